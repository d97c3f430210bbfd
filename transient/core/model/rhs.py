"""The right-hand side of the reduced model and what the non-ideal pairs add to it: the serial
chain's acceleration (:mod:`.chain`) from the sub-chains' inertias and moments, the pairs' mode
margins that the stepper watches, and the choice of the modes afresh at a start or a reversal.

:func:`derivative` is what the stepper integrates; it is inlined into each of its few call sites,
because a call would copy the Model's flattened fields at every stage. The margins come as an
inlined form for the root finder's iterations and as a call for the rare sites.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from . import eta_table as et
from . import governor as gv
from . import joint_friction as jf
from . import reactions as rx
from . import stuck as st
from .chain import LOCKED, UNIQUE, chain_solve, eta_star, modes_power_flow_into
from .forcing import command, cylinder_rates, governor_rates, moments
from .layout import (
    KINETIC,
    LINK_FIXED,
    LINK_PISTONS,
    N_SCRATCH,
    OMEGA,
    PHI,
    POWER_FLOW,
    SW_DIRECTION,
    SW_MODES,
    W_GAS,
    W_LOAD,
    W_LOSS0,
    W_STARTER,
    WK_DJ,
    WK_DU,
    WK_ETA,
    WK_G,
    WK_G_MIN,
    WK_J,
    WK_M,
    WK_S,
    WK_SCRATCH,
    WK_SPEED,
    WK_U,
    T,
)
from .shaft import LINE_MARGINS, LINE_MODES, LINE_RATES, NOT_A_LINE
from .swash_plate import link_terms as swash_link_terms


@kernel(inline=True)
def split_subchains(m, phi, J, dJ, M_gas, M_shaft, wk):
    """J_k, J′_k and M_k of every sub-chain of the machine into ``wk`` (docs/theory.md, The
    serial chain; :mod:`transient.core.model.chain`): :func:`split_chain` of its whole J(φ),
    its shaft link J0 and every cylinder."""
    split_chain(m, phi, J, dJ, M_gas, M_shaft, m.J0, 1.0, wk[WK_U, :m.ncyl],
                wk[WK_DU, :m.ncyl], wk)


@kernel(inline=True)
def split_chain(m, phi, J, dJ, M_gas, M_shaft, J_shaft, share, u, du, wk):
    """J_k, J′_k and M_k of every sub-chain of a chain into ``wk``: the machine's, or on an
    elastic line a throw's (:mod:`.line_pairs`), of inertia J(φ), J′(φ) with ``J_shaft`` on its
    shaft link, ``share`` of the constant links' inertias and the transfer functions ``u``,
    ``u′`` of its cylinders.

    Links in order (the mechanism's ``links``): the shaft (J0 with flywheel and load; load and
    starter act on it, ``M_shaft``), links of constant reduced inertia ``link_J`` (the crank),
    the link ``link_rest`` with what J(φ) holds beyond the others (the rods), and last the
    cylinders, whose gas forces (``M_gas``) do their work on the pistons through the pistons'
    pair with them. A link whose inertia varies with φ (the pistons, the swash plate's link 9)
    has it computed on its own only where a pair cuts it from ``link_rest`` (``link_own``);
    elsewhere it is in the rest. Links between ideal pairs share a sub-chain.
    """
    for k in range(m.n_pairs + 1):
        wk[WK_J, k] = 0.0
        wk[WK_DJ, k] = 0.0
        wk[WK_M, k] = 0.0
    last = m.link_sub.shape[0] - 1
    J_rest = J
    dJ_rest = dJ
    for i in range(last + 1):
        c = J_shaft if i == 0 else share * m.link_J[i]
        wk[WK_J, m.link_sub[i]] += c
        J_rest -= c
        if m.link_own[i] != LINK_FIXED:
            J_i, dJ_i = own_inertia(m.link_own[i], m.link_mass[i], m.mech, phi, u, du)
            wk[WK_J, m.link_sub[i]] += J_i
            wk[WK_DJ, m.link_sub[i]] += dJ_i
            J_rest -= J_i
            dJ_rest -= dJ_i
    wk[WK_M, m.link_sub[0]] += M_shaft
    wk[WK_J, m.link_sub[m.link_rest]] += J_rest
    wk[WK_DJ, m.link_sub[m.link_rest]] += dJ_rest
    wk[WK_M, m.link_sub[last]] += M_gas


@kernel
def own_inertia(law, mass, mech, phi, u, du):
    """J and dJ/dφ of a link by its law (``layout.LINK_*``): the pistons' m·Σ u_k² from the
    transfer functions u, u′ (``moments`` with dJ leaves them), or the swash plate's links 9 and
    crosses 13 from its parameters ``mech``."""
    if law == LINK_PISTONS:
        su2 = 0.0
        suu = 0.0
        for k in range(u.shape[0]):
            su2 += u[k] * u[k]
            suu += u[k] * du[k]
        return mass * su2, 2.0 * mass * suu
    return swash_link_terms(mech, phi)


@kernel(inline=True)
def pair_etas(m, modes, eta_out):
    """η*_k of (25) for the mode bit mask ``modes`` (bit k set: pair k backward)."""
    for k in range(m.n_pairs):
        eta_out[k] = eta_star(m.eta_fwd[k], m.eta_bwd[k], ((modes >> k) & 1) == 0)


@kernel(inline=True)
def acceleration(m, extras, phi, J, dJ, w, M_gas, M_load, M_starter, sw, wk):
    """φ̈ from (18) without non-ideal pairs, else from the serial chain (:func:`chain_acceleration`)
    or with the joints' reaction friction (:mod:`.reactions`)."""
    if extras is None or m.n_pairs == 0:
        return (M_gas + M_load + M_starter - 0.5 * dJ * w * w) / J
    return chain_acceleration(m, phi, J, dJ, w, M_gas, M_load + M_starter, sw, wk)


@kernel(inline=True)
def chain_acceleration(m, phi, J, dJ, w, M_gas, M_shaft, sw, wk):
    """φ̈ of the serial chain with the pair modes held in ``sw``; leaves the sub-chains' J, J′, M
    and the pairs' η*, S in the rows of ``wk``. With reaction friction the pairs are joints of
    one rigid chain: φ̈ and their η*, S and losses come from :mod:`.reactions`, in direction σ.
    Stuck at rest (``stuck``): φ̈ = 0, and the holding margin in ``wk[WK_G]``."""
    if sw[SW_DIRECTION] == st.STUCK:
        if not m.reaction:
            split_subchains(m, phi, J, dJ, M_gas, M_shaft, wk)
        return st.hold(m, J, M_gas, M_shaft, wk)
    if m.reaction:
        return rx.acceleration(m, J, dJ, w, M_gas, M_shaft, float(sw[SW_DIRECTION]),
                               sw[SW_MODES], wk)
    n = m.n_pairs
    split_subchains(m, phi, J, dJ, M_gas, M_shaft, wk)
    if m.eta_table:  # η* depends on S: solved with the modes held (``eta_table``)
        return et.solve_held(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1], wk[WK_M, : n + 1], w,
                             sw[SW_MODES], m.et_speed, m.et_torque, m.et_size, m.et_eta,
                             m.et_min, wk[WK_ETA, :n], wk[WK_S, :n])
    pair_etas(m, sw[SW_MODES], wk[WK_ETA])
    return chain_solve(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1], wk[WK_M, : n + 1], wk[WK_ETA, :n], w,
                       wk[WK_S, :n])


@kernel(inline=True)
def derivative(m, extras, angle_mode, y, sel, sw, wk, out):
    """dy/dt = (ω, 1, ε, powers), or in crank angle dy/dφ = (1, 1/ω, dK/dφ, moments), y[2] = K.

    Inlined into its callers, because as a call, passing the Model (numba flattens it into ~130
    scalar arguments) would cost about as much as the right-hand side itself.

    In crank angle dK/dφ = Σ M − Σ (1 − η*_k) S_k, the work–energy law of the chain
    (``transient.core.model.chain``), so that the energy lost is exactly what the pairs account for.
    ``extras``: the kernels' variant for ``m`` (:func:`.layout.extras_of`), as for every kernel
    that reaches a feature only some scenes use. An elastic shaft line's state has its own
    derivative (``Model.line_model``, :mod:`.elastic`; in a rigid scene's Model a kernel that
    returns NOT_A_LINE, a constant the compiler folds: the rigid path tests nothing at run time).
    """
    if m.line_model(m, extras, LINE_RATES, angle_mode, y, sel, sw, wk, out) != NOT_A_LINE:
        return
    # (18) in crank angle is dK/dφ = M: without pairs no term needs dJ/dφ
    with_dJ = not angle_mode or (extras is not None and m.n_pairs > 0)
    J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, angle_mode, y, sel, sw, wk, with_dJ)
    # the speed's range over a step's stages: a speed event inside the step shows here
    wk[WK_SPEED, 0] = min(wk[WK_SPEED, 0], w)
    wk[WK_SPEED, 1] = max(wk[WK_SPEED, 1], w)
    M = M_gas + M_load + M_starter
    loss = 0.0  # Σ (1 − η*) S, the moment equivalent of the pairs' losses
    q = 1.0 if angle_mode else w  # work per unit of the independent variable
    if extras is None or m.n_pairs == 0:  # equation (18); no chain to solve
        a = (M - 0.5 * dJ * w * w) / J  # read in time mode only (in crank angle dJ may be NaN)
    else:
        a = chain_acceleration(m, y[PHI], J, dJ, w, M_gas, M_load + M_starter, sw, wk)
        mode_margins(m, sw, wk)  # watched at every stage: a mode switch inside a step shows here
        if m.reaction and angle_mode and rx.tracks_sides(m):  # a side force changing side
            jf.track_sides(m.ncyl, y[PHI], wk)  # in a step shows here
        for k in range(m.n_pairs):
            lk = rx.loss_moment(wk, k) if m.reaction else (1.0 - wk[WK_ETA, k]) * wk[WK_S, k]
            out[W_LOSS0 + k] = lk * q
            loss += lk
            wk[WK_G_MIN, k] = min(wk[WK_G_MIN, k], wk[WK_G, k])
    out[W_GAS] = M_gas * q
    out[W_LOAD] = M_load * q
    out[W_STARTER] = M_starter * q
    if extras is not None and (m.gov_dyn != gv.NONE or m.latch):
        governor_rates(m, w, y, 1.0 / w if angle_mode else 1.0, sw, wk, out)
    if extras is not None and m.woschni:
        cylinder_rates(m, angle_mode, y, sel, w, command(m, extras, w, y, sw), wk, out)
    if angle_mode:
        out[PHI] = 1.0
        out[T] = 1.0 / w
        out[KINETIC] = M - loss
    else:
        out[PHI] = w
        out[T] = 1.0
        out[OMEGA] = a


@kernel(inline=True)
def model_rhs(ctx, y, out):
    """:func:`derivative` in the integrator's form (``rhs(ctx, y, out)``,
    :mod:`transient.core.integrator.rk`), with ``ctx`` = (m, extras, angle_mode, sel, sw, wk).
    It hands each on as an argument: ``extras`` must reach the kernels as one for their branches
    on it to be pruned (:func:`.layout.extras_of`)."""
    derivative(ctx[0], ctx[1], ctx[2], y, ctx[3], ctx[4], ctx[5], out)


@kernel(inline=True)
def watches_kinks(m, extras, angle_mode):
    """Whether the derivative records, over a step attempt's stages, where it has a kink that a
    step should end on rather than straddle (:func:`kink_in_attempt`): the crank-slider's side
    forces changing side under reaction friction (the kink of μ|N|, ``joint_friction``), in
    crank angle. The stepper's hook into the model for retaking a rejected step at a kink."""
    return extras is not None and m.reaction and rx.tracks_sides(m) and angle_mode


@kernel(inline=True)
def reset_kinks(m, extras, wk):
    """Before a step attempt where :func:`watches_kinks`: no stage has seen a kink yet."""
    if extras is not None:
        jf.reset_sides(m.ncyl, wk)


@kernel(inline=True)
def kink_in_attempt(m, extras, wk):
    """The earliest abscissa where the last attempt's stages show a kink (where
    :func:`watches_kinks`), or ∞."""
    if extras is not None:
        return jf.side_change(m.ncyl, wk)
    return np.inf


@kernel(inline=True)
def mode_margins(m, sw, wk):
    """How far each pair's held mode is from switching, into ``wk[WK_G]`` (after
    :func:`acceleration`); a mode switch is due where a margin falls to zero.

    ``power-flow``: the power the pair transmits must have the mode's sign, S_k σ ≥ 0 forward,
    S_k σ < 0 backward. ``paper``: criterion (25) on the moments of everything on the shaft side,
    (Σ_{j≤k} M_j) σ ≥ 0 forward (``transient.core.model.chain.modes_paper``).
    """
    sigma = sw[SW_DIRECTION]
    if sigma == st.STUCK:  # the holding margin, left by chain_acceleration
        return
    if m.reaction:  # no modes: the joints' directions change on breakpoints only, but for
        for k in range(m.n_pairs):  # a constant-η or mapped pair at the main bearings
            wk[WK_G, k] = 1.0
        if rx.coupled(m):
            k = m.rx_pair[0]
            v = wk[WK_S, k] * sigma
            wk[WK_G, k] = -v if (sw[SW_MODES] >> k) & 1 else v
        return
    upstream = 0.0
    for k in range(m.n_pairs):
        upstream += wk[WK_M, k]
        v = wk[WK_S, k] if m.policy == POWER_FLOW else upstream
        if (sw[SW_MODES] >> k) & 1:
            wk[WK_G, k] = -v * sigma
        else:
            wk[WK_G, k] = v * sigma


@kernel(inline=True)
def margins_inline(m, extras, angle_mode, y, sel, sw, wk):
    """Mode margins at state ``y`` (see :func:`mode_margins`), in ``wk[WK_G]``; inlined into the
    stepper's root finder, whose iterations evaluate them most: there a call would copy the Model
    at every iteration."""
    if m.line_model(m, extras, LINE_MARGINS, angle_mode, y, sel, sw, wk, wk[WK_G]) != NOT_A_LINE:
        return  # (an elastic line's chains, one per throw)
    J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, angle_mode, y, sel, sw, wk, True)
    acceleration(m, extras, y[PHI], J, dJ, w, M_gas, M_load, M_starter, sw, wk)
    mode_margins(m, sw, wk)


@kernel
def margins_at(m, extras, angle_mode, y, sel, sw, wk):
    """:func:`margins_inline` as a call: one compiled copy of the model's terms for the sites
    that evaluate the margins rarely."""
    margins_inline(m, extras, angle_mode, y, sel, sw, wk)


@kernel
def choose_modes(m, extras, angle_mode, y, sel, sw, wk):
    """Choose σ and the pair modes afresh at state ``y`` (start of a run, speed reversal).

    With ω ≠ 0, σ = sign ω; ``power-flow`` takes the unique consistent mode vector
    (``chain.modes_power_flow``), ``paper`` criterion (25). At rest, the incipient motion decides:
    σ is the direction the chain starts to move in; if the pairs' friction holds the applied
    moments in both directions the chain is locked. Sets ``sw[SW_DIRECTION]`` and
    ``sw[SW_MODES]``. Returns the status of ``chain.modes_power_flow``: UNIQUE, LOCKED, or (a
    rounding tie S_k ≈ 0, resolved by its documented rule) AMBIGUOUS or NONE_CONSISTENT. On an
    elastic line each throw's chain chooses its own (``Model.line_model``, :mod:`.line_pairs`).
    """
    if extras is not None and m.n_pairs > 0:
        status = m.line_model(m, extras, LINE_MODES, angle_mode, y, sel, sw, wk, wk[WK_G])
        if status != NOT_A_LINE:
            return status
    J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, angle_mode, y, sel, sw, wk, True)
    n = m.n_pairs
    if extras is None or n == 0:
        sw[SW_DIRECTION] = -1 if w < 0.0 else 1
        sw[SW_MODES] = 0
        return UNIQUE
    if m.reaction:
        sigma, _, status = rx.choose_direction(m, J, dJ, w, M_gas, M_load + M_starter, wk)
        sw[SW_DIRECTION] = 1 if sigma > 0.0 else -1
        sw[SW_MODES] = rx.mode_mask(m, sigma, wk)
        return status
    split_subchains(m, y[PHI], J, dJ, M_gas, M_load + M_starter, wk)
    if m.eta_table:
        a, status = table_modes(m, w, wk, wk[WK_ETA, :n], wk[WK_S, :n])
    else:
        a, status, _ = modes_power_flow_into(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1],
                                             wk[WK_M, : n + 1], m.eta_fwd, m.eta_bwd, w,
                                             wk[WK_ETA, :n], wk[WK_S, :n],
                                             wk[WK_SCRATCH: WK_SCRATCH + N_SCRATCH, :n])
    if status == LOCKED:
        return status
    if w != 0.0:
        sw[SW_DIRECTION] = 1 if w > 0.0 else -1
    else:
        sw[SW_DIRECTION] = 1 if a > 0.0 else -1
    sw[SW_MODES] = mode_mask(m, sw[SW_DIRECTION], wk[WK_ETA, :n], wk[WK_S, :n], wk)
    return status


@kernel
def release(m, extras, y, sel, sw, wk):
    """A stuck machine starts to move (its holding margin has fallen to zero, ``stuck``): σ the
    direction whose margin crossed, the modes chosen afresh for it; time domain, ω = 0."""
    J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, False, y, sel, sw, wk, True)
    if not m.reaction:
        split_subchains(m, y[PHI], J, dJ, M_gas, M_load + M_starter, wk)
    sigma = st.release_direction(m, J, M_gas, M_load + M_starter, wk)
    sw[SW_DIRECTION] = 1 if sigma > 0.0 else -1
    sw[SW_MODES] = (rx.mode_mask(m, sigma, wk) if m.reaction
                    else mode_mask(m, sw[SW_DIRECTION], wk[WK_ETA], wk[WK_S], wk))


@kernel
def mode_mask(m, sigma, eta, S, wk):
    """The pairs' mode bits (bit k set: pair k backward) in direction σ from the η* and S that
    the chain's solve left in ``eta``, ``S`` (its sub-chains in ``wk``): ``power-flow`` its
    modes, ``paper`` criterion (25)."""
    n = m.n_pairs
    modes = 0
    upstream = 0.0
    for k in range(n):
        upstream += wk[WK_M, k]
        if m.policy == POWER_FLOW and m.eta_table:
            backward = S[k] * sigma < 0.0
        elif m.policy == POWER_FLOW:
            backward = eta[k] != m.eta_fwd[k]
        else:
            backward = upstream * sigma < 0.0
        if backward:
            modes |= 1 << k
    return modes


@kernel
def table_modes(m, w, wk, eta, S):
    """(φ̈, status) with mapped efficiencies and every pair's mode given by its transmitted power
    (``eta_table.solve_auto``, unique for ω ≠ 0); at rest the incipient motion decides, as in
    ``chain.modes_power_flow``: σ = +1 if it accelerates forward, σ = −1 if backward, else
    locked. The sub-chains from the rows of ``wk``; fills η*, S into ``eta``, ``S``."""
    n = m.n_pairs
    J, dJ, M = wk[WK_J, : n + 1], wk[WK_DJ, : n + 1], wk[WK_M, : n + 1]
    sigma = -1.0 if w < 0.0 else 1.0
    a = et.solve_auto(J, dJ, M, w, sigma, m.et_speed, m.et_torque, m.et_size, m.et_eta,
                      m.et_min, eta, S)
    if w != 0.0 or a > 0.0:
        return a, UNIQUE
    a = et.solve_auto(J, dJ, M, w, -1.0, m.et_speed, m.et_torque, m.et_size, m.et_eta,
                      m.et_min, eta, S)
    if a < 0.0:
        return a, UNIQUE
    for k in range(n):  # held by the pairs' friction (``chain.modes_power_flow``)
        eta[k] = np.nan
        S[k] = np.nan
    S[0] = wk[WK_M, 0]
    return 0.0, LOCKED
