"""Friction on the joints' reactions, by mechanism: the one place that picks the solver of
``Model.kind`` (:mod:`.joint_friction` for the crank-slider, :mod:`.articulated_friction` for
master and articulated rods), for the right-hand side, the stuck mode, the inverse dynamics and
the outputs. Each mechanism's module has the same functions; these branch and call them.

A scene with reaction pairs and tabulated kinematics keeps its mechanism's kind only if it is a
crank-slider (``Model.kind`` is then TABULATED): the scene check refuses the others.
"""
from __future__ import annotations

from .jit import kernel

from . import articulated_friction as af
from . import joint_friction as jf
from .chain import LOCKED, UNIQUE
from .layout import ARTICULATED, WK_RX


@kernel(inline=True)
def prepare(m, phi, w, sel, wk):
    """The state's rows for the solve (and the joints' directions at ``sel``)."""
    if m.kind == ARTICULATED:
        af.prepare(m.mech, phi, w, sel, wk)
    else:
        jf.prepare(m.mech, phi, w, sel, wk)


@kernel(inline=True)
def acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, wk):
    """φ̈ with the joints' friction in direction σ, and the pairs' η*, S, L into ``wk``."""
    if m.kind == ARTICULATED:
        return af.reaction_acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, wk)
    return jf.reaction_acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, wk)


@kernel
def inverse_drive(m, eps, w, sigma, M_shaft, wk):
    """The drive torque on the shaft for a prescribed motion, with the joints' friction."""
    if m.kind == ARTICULATED:
        return af.inverse_drive(m, eps, w, sigma, M_shaft, wk)
    return jf.inverse_drive(m, eps, w, sigma, M_shaft, wk)


@kernel(inline=True)
def loss_moment(wk, k):
    """The loss moment of pair k (its power lost over ω) after the solve (both mechanisms keep
    it in the same row)."""
    return wk[WK_RX + jf.R_LOSS, k]


@kernel(inline=True)
def choose_direction(m, J, dJ, w, M_gas, M_shaft, wk):
    """``(σ, φ̈, status)`` at a start or a reversal: σ = sign ω while moving; at rest the
    incipient motion decides, as for the chain (``transient.core.chain``): with the friction
    opposing σ = +1, φ̈ > 0 starts forward; else with it opposing σ = −1, φ̈ < 0 starts backward;
    else the joints' friction holds the applied moments (LOCKED, φ̈ = 0)."""
    if w != 0.0:
        sigma = 1.0 if w > 0.0 else -1.0
        return sigma, acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, wk), UNIQUE
    a = acceleration(m, J, dJ, w, M_gas, M_shaft, 1.0, wk)
    if a > 0.0:
        return 1.0, a, UNIQUE
    a = acceleration(m, J, dJ, w, M_gas, M_shaft, -1.0, wk)
    if a < 0.0:
        return -1.0, a, UNIQUE
    return 1.0, 0.0, LOCKED
