"""Friction on the joints' reactions, whichever the mechanism: the one place that picks the
mechanism's solver by ``Model.kind`` (:mod:`.joint_friction` for the crank-slider,
:mod:`.articulated_friction` for master and articulated rods, :mod:`.swash_friction` for the
swash plate), for the right-hand side, the stuck mode, the inverse dynamics and the output rows.
Every solver fills the same rows of ``wk`` for its callers: each piston's gas force (``R_P``,
filled by :func:`.forcing.moments`), the pairs' loss moments (``R_LOSS``), their η*, S
(``WK_ETA``, ``WK_S``) and each cylinder's share of the losses (``WK_CYL_LOSS``).

A scene with reaction pairs and tabulated kinematics keeps its mechanism's kind only if it is a
crank-slider (``Model.kind`` is then TABULATED): the scene check refuses the others.
"""
from __future__ import annotations

from .jit import kernel

from .chain import LOCKED, UNIQUE
from . import articulated_friction as af
from . import joint_friction as jf
from . import swash_friction as sf
from .layout import ARTICULATED, SWASH_PLATE, WK_RX

#: Rows (offsets from ``layout.WK_RX``) every mechanism's solver shares: the gas force on each
#: piston, the pairs' loss moments.
R_P, R_LOSS = jf.R_P, jf.R_LOSS


@kernel(inline=True)
def prepare(m, phi, w, sel, wk):
    """The mechanism's rows of the state (φ, ω) and of the step's angle ``sel``."""
    if m.kind == SWASH_PLATE:
        sf.prepare(m.mech, phi, w, sel, wk)
    elif m.kind == ARTICULATED:
        af.prepare(m.mech, phi, w, sel, wk)
    else:
        jf.prepare(m.mech, phi, w, sel, wk)


@kernel(inline=True)
def acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, wk):
    """φ̈ with the joints' friction, in direction σ, from the frictionless φ̈ = (M − ½J′ω²)/J
    (the rows of :func:`prepare` at the state); fills the pairs' η*, S, L."""
    eps0 = (M_gas + M_shaft - 0.5 * dJ * w * w) / J
    if m.kind == SWASH_PLATE:
        return sf.solve(m.mech, m.rx_par, m.rx_pair, m.J0, M_shaft, eps0, w, sigma, m.n_pairs,
                        wk)
    if m.kind == ARTICULATED:
        return af.solve(m.mech, m.rx_par, m.rx_pair, m.J0, M_shaft, eps0, w, sigma, m.n_pairs,
                        wk)
    return jf.solve(m.mech, m.rx_par, m.rx_pair, m.J0, M_shaft, eps0, w, sigma, m.n_pairs, wk)


@kernel
def inverse_drive(m, eps, w, sigma, M_shaft, wk):
    """The drive torque on the shaft for a prescribed φ̈ = ``eps``, with the joints' friction."""
    if m.kind == SWASH_PLATE:
        return sf.inverse_drive(m, eps, w, sigma, M_shaft, wk)
    if m.kind == ARTICULATED:
        return af.inverse_drive(m, eps, w, sigma, M_shaft, wk)
    return jf.inverse_drive(m, eps, w, sigma, M_shaft, wk)


@kernel(inline=True)
def loss_moment(wk, k):
    """The loss moment of pair k (its power lost over ω) after a solve."""
    return wk[WK_RX + R_LOSS, k]


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


@kernel(inline=True)
def tracks_sides(m):
    """Whether the stepper puts step ends where a side force changes side
    (``joint_friction.track_sides``): the crank-slider's solve leaves each cylinder's N in the row
    the tracking reads; the other mechanisms' solvers keep their side forces elsewhere."""
    return m.kind != SWASH_PLATE and m.kind != ARTICULATED
