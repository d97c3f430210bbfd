"""Friction on the joints' reactions, whichever the mechanism: the one place that calls the
mechanism's solver (the Model's ``rx_prepare``, ``rx_solve``, ``rx_inverse``, chosen when the
stepper is compiled: :mod:`.joint_friction` for the crank-slider, :mod:`.articulated_friction`
for master and articulated rods, :mod:`.swash_friction` for the swash plate; ``NO_REACTIONS``
for a mechanism without one), for the right-hand side, the stuck mode, the inverse dynamics and
the output rows.
Every solver fills the same rows of ``wk`` for its callers: each piston's gas force (``R_P``,
filled by :func:`.forcing.moments`), the pairs' loss moments (``R_LOSS``), their η*, S
(``WK_ETA``, ``WK_S``) and each cylinder's share of the losses (``WK_CYL_LOSS``).

A scene with reaction pairs and tabulated kinematics is a crank-slider's (its ``Model.terms`` is
then the tables'): the scene check refuses the others.

A constant-η or mapped pair at the main bearings among reaction pairs
---------------------------------------------------------------------
The crank-slider's and the articulated mechanism's main bearings join the shaft (inertia J₀, the
moments M_shaft of load and starter) to the mechanism, whose throws put the torque T = Σ T_k on
it: their solvers close on the shaft's equation J₀ ε = M_shaft + T. Given constant efficiencies
there instead of friction on the reaction (the serial chain's pair of the same links, Antonyuk
et al. (22)–(25)), the shaft puts S = M_shaft − J₀ ε into the pair and the throws receive
η* S = −T, so the shaft's equation becomes

    (η* J₀) ε = η* M_shaft + T,

the same equation with J₀ and M_shaft times η*: each mode is one call of the mechanism's solver,
unchanged, and as exact as that is. Under the power-flow policy (the scene check allows no
other here) η* = η_fwd where S σ ≥ 0 and 1/η_bwd where S σ < 0. The residual
J₀ ε − M_shaft − T(ε)/η* increases strictly in ε for either η* (T falls with ε: the throws' and
the rods' inertia), and the two modes' residuals agree where T = 0, so exactly one mode is
consistent (the proof of ``transient.core.model.chain`` for one pair). Where no mode is held (a start,
a reversal, at rest: :data:`AUTO`) the forward solve is taken if its S σ ≥ 0, else the backward
one. While moving, the mode is held over each step as every chain pair's is, with the margin
S σ (forward) or −S σ (backward) watched at every stage (``rhs.mode_margins``), so that the
stepper switches it on a located event: φ̈ has a kink there, which no step straddles. The pair's
S, η* and loss (1 − η*) S are those of the chain's pair; its loss belongs to no cylinder (NaN per
cylinder), as a chain pair's. The swash plate's main bearing sits in the shaft's equation
itself, so there the scene check refuses the mix. So it does on an inner joint: a chain pair
between the throws and the rods loses a share of the power all cylinders pass together, which
among the joints' forces would have to be split over the cylinders' crankpins by an assumption
neither model makes.

A mapped pair there (``eta_table``) has η* = e(|S|) in each mode: the solve at η* gives S(η*),
and η* is the fixed point of η ↦ e(|S(η)|). Differentiating the shaft's equation,
dS/dη* = −J₀ S/(η* J₀ + |T′|), so the iteration contracts by less than |S e′(|S|)|/η*, which
the scene check's condition on maps keeps below 1 (``eta_table``, *Existence and uniqueness*);
each turn is a solve started from the last φ̈, and it stops when η* moves by at most
``eta_table.ROUNDING`` of itself (NaN after ``eta_table.MAX_ITER`` turns). A map of one point
stops at the first turn, on the constant pair's result bit for bit.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from . import eta_table as et
from . import joint_friction as jf
from .chain import LOCKED, UNIQUE
from .layout import RX_ETA_BWD, RX_ETA_FWD, WK_CYL_LOSS, WK_ETA, WK_RX, WK_S

#: Rows (offsets from ``layout.WK_RX``) every mechanism's solver shares: the gas force on each
#: piston, the angle its joints' directions are cached for, the pairs' loss moments
#: (``joint_friction.SHARED``).
R_P, R_SEL, R_LOSS = jf.R_P, jf.R_SEL, jf.R_LOSS


@kernel(inline=True)
def prepare(m, phi, w, sel, wk):
    """The mechanism's rows of the state (φ, ω) and of the step's angle ``sel``."""
    m.rx_prepare(m.mech, phi, w, sel, wk)


#: ``modes`` of :func:`acceleration`: the pair at the main bearings in its consistent mode, as at
#: a start, a reversal or at rest, where no mode is held.
AUTO = -1


@kernel(inline=True)
def coupled(m):
    """Whether a constant-η or mapped pair sits at the main bearings among the reaction pairs."""
    return m.rx_par[0, RX_ETA_FWD] != 0.0


@kernel(inline=True)
def acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, modes, wk):
    """φ̈ with the joints' friction, in direction σ, from the frictionless φ̈ = (M − ½J′ω²)/J
    (the rows of :func:`prepare` at the state); fills the pairs' η*, S, L. A constant-η or
    mapped pair at the main bearings passes power in the mode ``modes`` holds for it (bit k
    set: pair k backward), or in its consistent one (:data:`AUTO`; module docstring)."""
    eps0 = (M_gas + M_shaft - 0.5 * dJ * w * w) / J
    if not coupled(m):
        return _solve(m, m.J0, M_shaft, eps0, w, sigma, wk)
    if modes == AUTO or (modes >> m.rx_pair[0]) & 1 == 0:
        eps = _coupled_mode(m, False, M_shaft, eps0, w, sigma, wk)
        if modes != AUTO or wk[WK_S, m.rx_pair[0]] * sigma >= 0.0:
            return eps
    return _coupled_mode(m, True, M_shaft, eps0, w, sigma, wk)


@kernel(inline=True)
def _solve(m, J0, M_shaft, eps0, w, sigma, wk):
    """The mechanism's solver on the shaft's equation J₀ ε = M_shaft + T."""
    return m.rx_solve(m.mech, m.rx_par, m.rx_pair, J0, M_shaft, eps0, w, sigma, m.n_pairs, wk)


@kernel
def _coupled_mode(m, backward, M_shaft, eps0, w, sigma, wk):
    """φ̈ with the pair at the main bearings in one mode: at its constant η*, or at the η* its
    map gives at the S that the solve at that η* gives (a fixed point, module docstring); NaN if
    that does not settle."""
    if not m.eta_table:
        return _coupled_solve(m, _constant_eta(m, backward), M_shaft, eps0, w, sigma, wk)
    k = m.rx_pair[0]
    w_abs = abs(w)
    eps = eps0
    eta = et.transfer(m.et_speed, m.et_torque, m.et_size, m.et_eta, k, backward, w_abs,
                      M_shaft - m.J0 * eps0)[0]
    for _ in range(et.MAX_ITER):
        eps = _coupled_solve(m, eta, M_shaft, eps, w, sigma, wk)
        new = et.transfer(m.et_speed, m.et_torque, m.et_size, m.et_eta, k, backward, w_abs,
                          wk[WK_S, k])[0]
        if abs(new - eta) <= et.ROUNDING * eta:
            return eps
        eta = new
    return np.nan


@kernel(inline=True)
def _constant_eta(m, backward):
    """η* of a constant-η pair at the main bearings: η_fwd forward, 1/η_bwd backward."""
    return 1.0 / m.rx_par[0, RX_ETA_BWD] if backward else m.rx_par[0, RX_ETA_FWD]


@kernel(inline=True)
def _coupled_solve(m, eta, M_shaft, eps0, w, sigma, wk):
    """φ̈ with the pair at the main bearings passing η* = ``eta``: the solve with J₀ and M_shaft
    times η* (module docstring), then the pair's own terms (:func:`_couple`)."""
    eps = _solve(m, m.J0 * eta, M_shaft * eta, eps0, w, sigma, wk)
    _couple(m, eta, wk)
    return eps


@kernel(inline=True)
def _couple(m, eta, wk):
    """The pair at the main bearings passing η* = ``eta``, from the moment −T the mechanism's
    solve left as its S (what the throws receive, η* S): its S, η*, loss (1 − η*) S, and no
    cylinder's share."""
    k = m.rx_pair[0]
    s = wk[WK_S, k] / eta
    wk[WK_S, k] = s
    wk[WK_ETA, k] = eta
    wk[WK_RX + R_LOSS, k] = (1.0 - eta) * s
    for i in range(m.ncyl):
        wk[WK_CYL_LOSS + k, i] = np.nan


@kernel(inline=True)
def mode_mask(m, sigma, wk):
    """The mode bits after a solve in the consistent mode: the pair at the main bearings'
    (backward where its S σ < 0), no other pair's."""
    if coupled(m) and wk[WK_S, m.rx_pair[0]] * sigma < 0.0:
        return 1 << m.rx_pair[0]
    return 0


@kernel
def inverse_drive(m, eps, w, sigma, M_shaft, wk):
    """The drive torque on the shaft for a prescribed φ̈ = ``eps``, with the joints' friction;
    with a constant-η or mapped pair at the main bearings, S with h(S) = η*(|S|) S = −T, its
    mode from the sign of the power it passes (forward where −T σ ≥ 0; module docstring)."""
    drive = m.rx_inverse(m, eps, w, sigma, M_shaft, wk)
    if not coupled(m):
        return drive
    k = m.rx_pair[0]
    T = m.J0 * eps - M_shaft - drive
    backward = T * sigma > 0.0
    if m.eta_table:
        eta = et.invert(m.et_speed, m.et_torque, m.et_size, m.et_eta, m.et_min, k, backward,
                        abs(w), -T)[1]
    else:
        eta = _constant_eta(m, backward)
    _couple(m, eta, wk)
    return m.J0 * eps - M_shaft + wk[WK_S, k]


@kernel(inline=True)
def loss_moment(wk, k):
    """The loss moment of pair k (its power lost over ω) after a solve."""
    return wk[WK_RX + R_LOSS, k]


@kernel(inline=True)
def choose_direction(m, J, dJ, w, M_gas, M_shaft, wk):
    """``(σ, φ̈, status)`` at a start or a reversal: σ = sign ω while moving; at rest the
    incipient motion decides, as for the chain (``transient.core.model.chain``): with the friction
    opposing σ = +1, φ̈ > 0 starts forward; else with it opposing σ = −1, φ̈ < 0 starts backward;
    else the joints' friction holds the applied moments (LOCKED, φ̈ = 0)."""
    if w != 0.0:
        sigma = 1.0 if w > 0.0 else -1.0
        return sigma, acceleration(m, J, dJ, w, M_gas, M_shaft, sigma, AUTO, wk), UNIQUE
    a = acceleration(m, J, dJ, w, M_gas, M_shaft, 1.0, AUTO, wk)
    if a > 0.0:
        return 1.0, a, UNIQUE
    a = acceleration(m, J, dJ, w, M_gas, M_shaft, -1.0, AUTO, wk)
    if a < 0.0:
        return -1.0, a, UNIQUE
    return 1.0, 0.0, LOCKED


@kernel(inline=True)
def tracks_sides(m):
    """Whether the stepper puts step ends where a side force changes side
    (``joint_friction.track_sides``): the crank-slider's solve leaves each cylinder's N in the row
    the tracking reads; the other mechanisms' solvers keep their side forces elsewhere."""
    return m.rx_sides


@kernel(inline=True)
def no_prepare(mp, phi, w, sel, wk):
    """``Model.rx_prepare`` of a mechanism without reaction friction: never called (the scene
    check refuses reaction pairs for it, so ``Model.reaction`` is False)."""


@kernel(inline=True)
def no_solve(mp, jp, pair_of, J0, M_shaft, eps0, w, sigma, n_pairs, wk):
    """``Model.rx_solve`` of a mechanism without reaction friction: never called; NaN, which
    the stepper reports, were it ever."""
    return np.nan


@kernel(inline=True)
def no_inverse(m, eps, w, sigma, M_shaft, wk):
    """``Model.rx_inverse`` of a mechanism without reaction friction: never called; NaN."""
    return np.nan


#: The reaction kernels (prepare, solve, inverse_drive) of a mechanism without reaction friction.
NO_REACTIONS = (no_prepare, no_solve, no_inverse)
