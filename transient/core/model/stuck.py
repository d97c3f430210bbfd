r"""The stuck mode: a machine at rest that the non-ideal pairs' friction holds, released when the
drive exceeds what the friction can hold in one direction (as the Modelica Standard Library's
``Rotational.Components.LossyGear`` sticks: Pelchen, Schweiger & Otter, "Modeling and simulating
the efficiency of gearboxes and of planetary gearboxes", 2nd International Modelica Conference,
2002, pp. 257–266: a gear's stuck and rolling modes).

At ω = 0 the friction's direction is that of the incipient motion (``transient.core.model.chain``, *At
rest*): with the friction opposing σ = +1 the chain's acceleration is a₊, opposing σ = −1 it is
a₋. If a₊ > 0 the machine starts forward, if a₋ < 0 backward; if a₊ ≤ 0 ≤ a₋ the pairs hold the
applied moments. While they hold, the machine is *stuck*: φ is fixed, ω = φ̈ = 0, time goes on,
no power flows (the work integrals and the losses stay constant), and the governor's and the
cylinders' states keep their own dynamics. The switch ``sw[SW_DIRECTION]`` is :data:`STUCK` then
(±1 while moving).

What releases it is the *holding margin*

    g = min(−a₊, a₋) ≥ 0 while stuck,

the acceleration by which the weaker of the two directions is held. a_σ is a continuous function
of the applied moments: for constant-η pairs it is the root of the chain's residual F(a), which
is continuous and strictly decreasing in a (``chain``, the proof of uniqueness, with σ in place of
ω), and so it is with efficiency maps under the scene check's requirement on them
(``eta_table``); for reaction pairs it is the solution of the joints' equations
(``reactions.acceleration``) at ω = 0, where every friction term is a magnitude that varies
continuously with the forces. So g falls through zero at the instant the drive exceeds the
holding moment in one direction, and the stepper locates that instant as it locates a pair's
mode switch (a margin falling to zero, to the
root finder's accuracy on the dense output); the pair margins' slot 0 carries g, the others a
constant 1 that never falls. At the release the direction is the one whose margin crossed (the
lower of −a₊, a₋) and the modes are chosen afresh for it.

No rule against chattering is needed: the machine leaves rest only where g < 0, i.e.
a_σ σ > 0, so it moves away, and it sticks again only after its speed has come back to zero,
which takes a time of its own (a speed reversal); entering and leaving at one instant happens only
where g is exactly zero there, and is then one stuck and one released event.

A machine held at rest is stuck only where the run ends by time and something can still change
the moments (:func:`can_change`); elsewhere nothing could release it and the run ends *locked*
(``stepper._stick``).
"""
from __future__ import annotations

from ..jit import kernel
from . import eta_table as et
from . import governor as gv
from . import reactions as rx
from .chain import _best_candidate
from .layout import LT_TIME, SW_LOAD, WK_DJ, WK_ETA, WK_G, WK_J, WK_M, WK_RX, WK_S, WK_SCRATCH, T

#: ``sw[SW_DIRECTION]`` while the machine is stuck (±1 while it moves).
STUCK = 0


@kernel
def incipient(m, J, M_gas, M_shaft, sigma, wk):
    """φ̈ at ω = 0 with the pairs' friction opposing an incipient motion ``sigma``: for constant-η
    pairs (or mapped ones, ``eta_table.solve_auto``) the chain solved with the modes consistent
    with σ (the sub-chains' rows of ``wk`` split already, ``rhs.split_subchains``; their η*, S
    left in ``wk``), for reaction pairs the joints' solve (``reactions.acceleration``, the rows
    of ``prepare`` at the state)."""
    if m.reaction:
        return rx.acceleration(m, J, 0.0, 0.0, M_gas, M_shaft, sigma, rx.AUTO, wk)
    n = m.n_pairs
    if m.eta_table:
        return et.solve_auto(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1], wk[WK_M, : n + 1], 0.0,
                             sigma, m.et_speed, m.et_torque, m.et_size, m.et_eta, m.et_min,
                             wk[WK_ETA, :n], wk[WK_S, :n])
    a, _ = _best_candidate(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1], wk[WK_M, : n + 1], m.eta_fwd,
                           m.eta_bwd, 0.0, sigma, wk[WK_ETA, :n], wk[WK_S, :n],
                           wk[WK_SCRATCH, :n], wk[WK_SCRATCH + 1, :n])
    return a


@kernel
def hold(m, J, M_gas, M_shaft, wk):
    """φ̈ = 0 while stuck; the holding margin g = min(−a₊, a₋) into ``wk[WK_G, 0]`` (the other
    pairs' slots 1), and the pairs' S = 0, η* = 1, loss 0: no power passes while nothing moves."""
    a_fwd = incipient(m, J, M_gas, M_shaft, 1.0, wk)
    a_bwd = incipient(m, J, M_gas, M_shaft, -1.0, wk)
    wk[WK_G, 0] = min(-a_fwd, a_bwd)
    for k in range(m.n_pairs):
        if k > 0:
            wk[WK_G, k] = 1.0
        wk[WK_S, k] = 0.0
        wk[WK_ETA, k] = 1.0
        if m.reaction:
            wk[WK_RX + rx.R_LOSS, k] = 0.0
    return 0.0


@kernel
def release_direction(m, J, M_gas, M_shaft, wk):
    """σ = ±1 that a stuck machine starts in: the direction whose margin is the lower (−a₊ against
    a₋), with the chain's η*, S for it left in ``wk``."""
    a_fwd = incipient(m, J, M_gas, M_shaft, 1.0, wk)
    a_bwd = incipient(m, J, M_gas, M_shaft, -1.0, wk)
    if -a_fwd <= a_bwd:
        incipient(m, J, M_gas, M_shaft, 1.0, wk)
        return 1.0
    return -1.0


@kernel
def can_change(m, y, sw):
    """Whether anything can still change the moments on a machine at rest, so that being stuck
    may end: a load schedule in time with a corner ahead, a load tabulated against time before
    its last knot, a governor with states or cylinder pressures as states (the starter's torque
    and every other term depend on the speed and the angle only)."""
    return ((m.load_comp == T and sw[SW_LOAD] < m.load_x.shape[0])
            or (m.lt_kind == LT_TIME and y[T] < m.lt_x[m.lt_x.shape[0] - 1])
            or m.gov_dyn != gv.NONE or m.woschni)
