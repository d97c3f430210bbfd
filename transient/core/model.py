"""The compiled reduced model: equation (18) of the swash-plate paper with variable ω,

    J(φ) φ̈ + ½ J′(φ) φ̇² = M(φ, φ̇, t),

assembled from a mechanism kernel (J, J′ and the piston transfer functions u_k), gas forces per
cylinder (angle-only pressure tables), loads and a starter. Everything here is numba-compiled and
unit-free (SI); the scene classes build a :data:`Model` with ``transient.assemble``.

State vector (named once, shared by the stepper, the results and the plots): see ``STATE``.
In time as independent variable the third component is ω; in crank angle it is the kinetic
energy K = ½ J(φ) ω², for which (18) is the work–energy law dK/dφ = M(φ, ω, t) and ω = √(2K/J).
That form is the same equation multiplied by ω, but an integration error in it is an error in
the energy budget only, never a spurious exchange between J(φ) and ω: coasting keeps K exactly.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from .jit import compiled, kernel

from .chain import LOCKED, UNIQUE, chain_solve, eta_star, modes_power_flow_into
from . import cylinder as cyl
from . import governor as gv
from .articulated import articulated_terms
from .crank_slider import crank_slider_terms
from .swash_plate import swash_terms
from .tabulated import tabulated_terms
from .tables import find_piece, table_eval, table_eval_pair

#: Names of the state components, in order (the third is K = ½Jω² in crank-angle mode). The first
#: three are the dynamics; then work integrals (quadratures that do not feed back): the work
#: of the gas forces, of the load and of the starter [J], then the energy lost in each non-ideal
#: pair k (``W_loss_<k+1>``). Integrated with the motion, the work–energy balance
#: ½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load + W_starter − Σ W_loss,k holds to the solver's accuracy.
#: After them the dynamic governor's states (:mod:`.governor`, from :func:`gov_index`), then, with
#: fuel latching, the fuel each cylinder took at its last injection (:func:`latch_index`; held
#: constant between injections: their derivative is zero and the stepper sets them), then, with
#: wall heat transfer, each cylinder's pressure in its closed part (:func:`cyl_index`,
#: :mod:`.cylinder`; the ``p_<k>`` columns show it there).
STATE = ("phi", "t", "omega", "W_gas", "W_load", "W_starter")
PHI, T, OMEGA, W_GAS, W_LOAD, W_STARTER = range(6)
KINETIC = OMEGA
N_DYNAMIC = 3
N_STATE_BASE = len(STATE)
W_LOSS0 = N_STATE_BASE  # y[W_LOSS0 + k]: energy lost in pair k

#: Discrete switches held constant over a step (an int array ``sw``): starter engaged (0/1), the
#: governor's branch (see :func:`governor_branch`), the modes of the non-ideal pairs (bit k set:
#: pair k backward, its far side drives), the direction of motion σ = ±1 that the pair modes
#: refer to (sign of ω; changed only at a speed reversal, where the modes are chosen afresh), the
#: segment of the load schedule (:func:`load_segment`) and the generator's low-speed branch
#: (:func:`generator_branch`), and the flyweight governor's sleeve, moving or on a stop
#: (``governor.FREE``, ``ON_LOW_STOP``, ``ON_HIGH_STOP``).
SW_STARTER, SW_GOVERNOR, SW_MODES, SW_DIRECTION, SW_LOAD, SW_GENERATOR, SW_SLEEVE = range(7)
N_SWITCHES = 7

#: Mechanism kinds (``Model.kind``); TABULATED: any, from its tables (``Model.kin_coef``).
CRANK_SLIDER, SWASH_PLATE, TABULATED, ARTICULATED = 0, 1, 2, 3

#: Mode-selection policies of the non-ideal pairs (``Model.policy``; ``transient.core.chain``).
POWER_FLOW, PAPER = 0, 1

#: Columns written for every output sample; then one gas column per cylinder, then
#: ``PAIR_OUTPUTS`` for each non-ideal pair, then the dynamic governor's states
#: (``governor.STATE_NAMES``) and, with fuel latching, the fuel latched by each cylinder.
OUTPUTS = ("t", "phi", "omega", "epsilon", "J", "dJ_dphi", "M_gas", "M_load", "M_starter", "fuel",
           "W_gas", "W_load", "W_starter")
OUTPUT_UNITS = ("s", "rad", "rad/s", "rad/s^2", "kg m^2", "kg m^2/rad", "N m", "N m", "N m", "1",
                "J", "J", "J")
N_OUT_FIXED = len(OUTPUTS)
COL_EPS, COL_J, COL_DJ = OUTPUTS.index("epsilon"), OUTPUTS.index("J"), OUTPUTS.index("dJ_dphi")
COL_M_GAS, COL_M_LOAD = OUTPUTS.index("M_gas"), OUTPUTS.index("M_load")
#: Per pair k: S_k, the moment it takes out of its shaft side (reduced to φ; the far side receives
#: η*_k S_k), η*_k in use, the power lost (1 − η*_k) S_k ω and the energy lost so far.
PAIR_OUTPUTS = ("S", "eta", "P_loss", "W_loss")
PAIR_OUTPUT_UNITS = ("N m", "1", "W", "J")

#: Rows of the work array ``wk`` (see :func:`work_array`): transfer functions u, u′ per cylinder;
#: per sub-chain J_k, J′_k, M_k; per pair η*_k, S_k, the mode margins g_k, their least value
#: over the right-hand sides evaluated since the stepper reset it, and η*, S of a trial mode
#: vector; the least and largest speed ω over those right-hand sides ([0], [1] of WK_SPEED), and
#: of the PI governor's demand u (WK_DEMAND); per cylinder the angle ``sel`` in its own cycle
#: and the gas table's piece there (WK_LOCAL, WK_PIECE), for the ``sel`` in WK_SEL[0]
#: (:func:`select_pieces`).
(WK_U, WK_DU, WK_J, WK_DJ, WK_M, WK_ETA, WK_S, WK_G, WK_G_MIN, WK_ETA_TRY, WK_S_TRY,
 WK_SPEED, WK_DEMAND, WK_LOCAL, WK_PIECE, WK_SEL, WK_SCRATCH) = range(17)
N_WK = WK_SCRATCH + 4  # four rows of scratch for chain.modes_power_flow_into

Model = namedtuple(
    "Model",
    [
        "kind",  # int: CRANK_SLIDER, SWASH_PLATE, ARTICULATED or TABULATED
        "mech",  # float64[:]: the mechanism's packed parameters
        "kin_coef",  # float64[1 + ncyl, n, 6]: the TABULATED kind's splines (transient.core.tabulated)
        "ncyl",  # int: number of cylinders (gas force points)
        "J0",  # float: constant inertia of shaft, flywheel and load [kg m²]
        "has_gas",  # bool
        "gas_phase",  # float64[ncyl]: shaft angle at which cylinder k is at local angle 0 [rad]
        "gas_scale",  # float64[ncyl]: force per unit table value (piston area [m²], or 1 for forces)
        "gas_offset",  # float: table value of zero force (crankcase pressure p0 [Pa], or 0)
        "period",  # float: cycle length in local angle [rad] (4π four-stroke, 2π two-stroke)
        "knots",  # float64[:], piecewise-cubic table (transient.core.tables)
        "coef",  # float64[:, 4], or [:, 8] with has_motored (full-load, then motored cubic)
        "piece_knot",  # int64[:]
        "has_motored",  # bool: coef pairs a motored curve; else it is the constant gas_offset
        "breakpoints",  # float64[:]: sorted shaft angles in [0, period) where a table has a corner
        "bp_jump",  # bool[:]: whether a cylinder's pressure jumps at each breakpoint
        "load_const",  # float: constant resisting torque [N m]
        "load_linear",  # float: c in −c·ω [N m s]
        "load_fan",  # float: K in −K·ω|ω| [N m s²]
        "load_x",  # float64[:]: corners of the load schedule, non-decreasing (empty: s ≡ 1)
        "load_s",  # float64[:]: the load's scale s at each corner (piecewise linear between)
        "load_comp",  # int: state component the corners are values of, T [s] or PHI [rad]
        "gen_power",  # float: generator power P in −s·P/max(ω, ω_min) [W] (0: none)
        "gen_min",  # float: ω_min, below it the generator's torque is held at −s·P/ω_min [rad/s]
        "starter_torque",  # float: starter stall torque [N m]
        "starter_noload",  # float: speed at which the starter characteristic reaches zero [rad/s]
        "starter_cutout",  # float: speed at which the starter disengages for good [rad/s]
        "gov_on",  # bool: a static droop governor scales the gas forces
        "gov_full",  # float: ω_a, full fuel at and below it [rad/s]
        "gov_zero",  # float: ω_1c, no fuel at and above it [rad/s]
        "gov_dyn",  # int: governor with states (transient.core.governor: NONE, PI, PID, FLYWEIGHT)
        "gov_par",  # float64[:]: its parameters (governor.P_* or governor.F_*)
        "latch",  # bool: each cylinder's fuel is latched at its start of injection
        "inj_angle",  # float: local angle of the start of injection [rad] (with latch)
        "woschni",  # bool: the closed part's pressures are states (wall heat transfer, .cylinder)
        "cyl_par",  # float64[cylinder.N_PAR]: their parameters (transient.core.cylinder)
        "n_pairs",  # int: number of non-ideal pairs (0: ideal constraints, equation (18))
        "eta_fwd",  # float64[n_pairs]: efficiency of pair k when its shaft side drives
        "eta_bwd",  # float64[n_pairs]: efficiency of pair k when its far side drives
        "policy",  # int: POWER_FLOW or PAPER
        "link_sub",  # int64[n_links]: sub-chain of each link (shaft first, gas-carrying link last)
        "link_J",  # float64[n_links]: constant reduced inertia of the middle links [kg m²]
    ],
)


@kernel(inline="always")
def gov_index(m):
    """Index of the dynamic governor's first state."""
    return N_STATE_BASE + m.n_pairs


@kernel(inline="always")
def latch_index(m):
    """Index of cylinder 0's latched fuel (with ``m.latch``)."""
    return N_STATE_BASE + m.n_pairs + gv.n_states(m.gov_dyn)


@kernel(inline="always")
def cyl_index(m):
    """Index of cylinder 0's pressure state (with ``m.woschni``), after the latched fuels."""
    return latch_index(m) + (m.ncyl if m.latch else 0)


@kernel
def n_state(m):
    """Length of the state vector of model ``m``."""
    return cyl_index(m) + (m.ncyl if m.woschni else 0)


@kernel
def n_outputs(m):
    """Columns of an output row of model ``m``."""
    return (N_OUT_FIXED + m.ncyl + len(PAIR_OUTPUTS) * m.n_pairs + gv.n_states(m.gov_dyn)
            + (m.ncyl if m.latch else 0))


@compiled
def work_array(m):
    """Scratch space of the right-hand side (rows ``WK_*``), allocated once per run."""
    wk = np.empty((N_WK, max(m.ncyl, m.n_pairs + 1, m.link_sub.shape[0], 2)))
    wk[WK_SEL, 0] = np.nan  # no pieces selected yet
    return wk


@kernel(inline="always")
def mechanism_terms(kind, mech, kin_coef, phi, u, du, with_dJ):
    """J(φ) and dJ/dφ of the mechanism's moving parts; fills ``u[k]``, ``du[k]`` per cylinder.
    Without ``with_dJ`` dJ and ``du`` may be left NaN (the exact crank-slider skips them)."""
    if kind == TABULATED:
        return tabulated_terms(kin_coef, phi, u, du)
    if kind == CRANK_SLIDER:
        return crank_slider_terms(mech, phi, u, du, with_dJ)
    if kind == ARTICULATED:
        return articulated_terms(mech, phi, u, du)
    return swash_terms(mech, phi, u, du)


@kernel(inline="always")
def select_pieces(m, sel, wk):
    """Each cylinder's angle ``sel`` in its own cycle (WK_LOCAL) and the gas table's piece there
    (WK_PIECE). ``sel`` is one angle for a whole step, so they are computed when it changes and
    kept, not in each of a step's right-hand sides (numba's float modulo alone was 4.4 % of the
    diesel's samples under ``perf``)."""
    if wk[WK_SEL, 0] != sel:
        for k in range(m.ncyl):
            local_sel = (sel - m.gas_phase[k]) % m.period
            wk[WK_LOCAL, k] = local_sel
            wk[WK_PIECE, k] = find_piece(m.knots, m.piece_knot, local_sel)
        wk[WK_SEL, 0] = sel


@kernel(inline="always")
def gas_value(m, k, phi, sel, wk):
    """Full-load table value (pressure or force) of cylinder k at shaft angle ``phi``.

    ``sel`` is a shaft angle inside the current step: it picks the table piece, so that a step that
    ends exactly on a corner keeps using the piece it integrates over (DESIGN §2, breakpoints).
    The piece is the one :func:`select_pieces` left in ``wk`` for it.
    """
    local_sel = wk[WK_LOCAL, k]
    value, _ = table_eval(m.knots, m.coef, m.piece_knot, int(wk[WK_PIECE, k]),
                          local_sel + (phi - sel))
    return value


@kernel(inline="always")
def gas_pair(m, k, phi, sel, wk):
    """Full-load and motored table values of cylinder k at shaft angle ``phi`` (``m.has_motored``
    only: ``m.coef`` pairs the two curves on common knots); ``sel``, ``wk`` as in
    :func:`gas_value`."""
    local_sel = wk[WK_LOCAL, k]
    return table_eval_pair(m.knots, m.coef, m.piece_knot, int(wk[WK_PIECE, k]),
                           local_sel + (phi - sel))


@kernel(inline="always")
def applied_value(m, k, phi, sel, f, wk):
    """The pressure (or force) acting on piston k at fuel ``f``: p_mot + f·(p_full − p_mot).

    Without a motored table the motored curve is the constant ``gas_offset`` (p0), and at f = 1
    the value is the table's to the last bit.
    """
    if m.has_motored:
        p, p_mot = gas_pair(m, k, phi, sel, wk)
        return p_mot + f * (p - p_mot)
    p = gas_value(m, k, phi, sel, wk)
    if f == 1.0:
        return p
    return m.gas_offset + f * (p - m.gas_offset)


@kernel(inline="always")
def cylinder_value(m, k, y, sel, f, wk):
    """The pressure on piston k: its state in the closed part with wall heat transfer
    (``m.woschni``, :mod:`.cylinder`), else the table's at fuel ``f`` (:func:`applied_value`)."""
    if m.woschni:
        if cyl.closed_angle(m.cyl_par, wk[WK_LOCAL, k], m.period) >= 0.0:
            return y[cyl_index(m) + k]
    return applied_value(m, k, y[PHI], sel, f, wk)


@kernel(inline="always")
def cylinder_rates(m, angle_mode, y, sel, w, f, wk, out):
    """dp_k/dφ (crank angle) or dp_k/dt (time) of the cylinder pressure states (``m.woschni``):
    the first law with Wiebe's heat release and Woschni's wall heat (:mod:`.cylinder`); zero
    outside the closed part. dV/dφ = F_p·u_k from the row u of ``wk``, the cylinders' angles in
    their cycles from WK_LOCAL (both left by :func:`moments`)."""
    c = cyl_index(m)
    lc = latch_index(m)
    for k in range(m.ncyl):
        local_sel = wk[WK_LOCAL, k]
        x_sel = cyl.closed_angle(m.cyl_par, local_sel, m.period)
        if x_sel < 0.0:
            out[c + k] = 0.0
            continue
        shift = y[PHI] - sel  # the angles at y, continued from the step's piece
        f_k = y[lc + k] if m.latch else f
        A, B = cyl.pressure_rate(m.mech, m.cyl_par, x_sel + shift, x_sel, local_sel + shift,
                                 y[c + k], m.gas_scale[k] * wk[WK_U, k], w, f_k)
        out[c + k] = A - B / w if angle_mode else w * A - B


@kernel(inline="always")
def inertia(m, phi, wk):
    """Total reduced inertia J(φ), (19); fills the row u of ``wk``."""
    J, _ = mechanism_terms(m.kind, m.mech, m.kin_coef, phi, wk[WK_U], wk[WK_DU], False)
    return J + m.J0


@kernel(inline="always")
def speed(J, angle_mode, y):
    """ω from the state: y[2] itself in time mode, √(2K/J) in crank-angle mode (ω > 0 there)."""
    if angle_mode:
        return np.sqrt(2.0 * y[KINETIC] / J)
    return y[OMEGA]


@kernel
def governor_branch(m, w, rising):
    """Branch of the droop characteristic at speed w: 0 full fuel (ω ≤ ω_a), 1 the droop line,
    2 no fuel (ω ≥ ω₁c); on a corner, the branch the motion enters (``rising``: ω increasing)."""
    if w < m.gov_full or (w == m.gov_full and not rising):
        return 0
    if w > m.gov_zero or (w == m.gov_zero and rising):
        return 2
    return 1


@kernel(inline="always")
def fuel(m, w, branch):
    """Fuel command f of the static droop governor (Antonyuk §4): 1 below ω_a, falling linearly
    to 0 at ω_1c, 0 above; 1 without a governor. The cylinder pressure is p_mot + f·(p_full −
    p_mot) (:func:`applied_value`), i.e. f scales the gas force (p − p0)·F_p when the motored curve
    is p0. The branch is fixed for a whole step (a state event stops on each corner), so that the
    right-hand side is smooth inside every step."""
    if not m.gov_on or branch == 0:
        return 1.0
    if branch == 2:
        return 0.0
    return (m.gov_zero - w) / (m.gov_zero - m.gov_full)


@kernel(inline="always")
def command(m, w, y, sw):
    """The governor's fuel command at state ``y``: the rack of a dynamic governor (PI(D): its
    position state; flyweight: linked to the sleeve), else the droop characteristic (:func:`fuel`)."""
    if is_pi(m):
        return y[gov_index(m) + gv.PI_RACK]
    if m.gov_dyn == gv.FLYWEIGHT:
        return gv.rack_of_lift(m.gov_par, y[gov_index(m) + gv.FW_LIFT])
    return fuel(m, w, sw[SW_GOVERNOR])


@kernel(inline="always")
def is_pi(m):
    """Whether the governor is a PI(D) one (its demand's clipping is a switch, ``SW_GOVERNOR``)."""
    return m.gov_dyn == gv.PI or m.gov_dyn == gv.PID


@kernel(inline="always")
def demand(m, w, y):
    """The PI(D) governor's demand u at state y (before clipping)."""
    return gv.pi_demand(m.gov_dyn, m.gov_par, w, y, gov_index(m))[1]


@kernel
def start_branch(m, w, y):
    """``SW_GOVERNOR`` at the start of a run: the PI demand's clipping branch, or the droop
    characteristic's branch (:func:`governor_branch`)."""
    if is_pi(m):
        return gv.demand_branch(m.gov_par, demand(m, w, y), True)
    return governor_branch(m, w, True)


@kernel(inline="always")
def governor_rates(m, w, y, scale, sw, wk, out):
    """Derivatives of the dynamic governor's states (× ``scale``: 1/ω in crank angle) and zero
    for the latched fuels, into ``out``; the PI demand's range over a step into ``wk``."""
    g = gov_index(m)
    if is_pi(m):
        u = gv.pi_rates(m.gov_dyn, m.gov_par, w, y, g, sw[SW_GOVERNOR], scale, out)
        wk[WK_DEMAND, 0] = min(wk[WK_DEMAND, 0], u)
        wk[WK_DEMAND, 1] = max(wk[WK_DEMAND, 1], u)
    elif m.gov_dyn == gv.FLYWEIGHT:
        gv.flyweight_rates(m.gov_par, w, y, g, sw[SW_SLEEVE], scale, out)
    if m.latch:
        c = latch_index(m)
        for k in range(m.ncyl):
            out[c + k] = 0.0


@kernel
def load_segment(m, x, rising):
    """Segment of the load schedule at abscissa ``x`` (a time or a shaft angle, as ``m.load_comp``).

    Segment j lies between corners j − 1 and j (segment 0 before the first, n after the last,
    n corners): the number of corners below x, and on a corner the segment the motion enters
    (``rising``: x increasing), so that a step (two equal corners) takes its value after the
    step in the direction of motion. A step's empty segment is never the result.
    """
    j = 0
    n = m.load_x.shape[0]
    while j < n and (m.load_x[j] < x or (m.load_x[j] == x and rising)):
        j += 1
    return j


@kernel(inline="always")
def load_scale(m, y, seg):
    """Scale s of the load at state ``y`` in schedule segment ``seg``: 1 without a schedule, the
    first (last) value before (after) the corners, linear between two of them.

    The segment is held for a whole step (a state event stops on each corner and moves it on),
    so that the right-hand side is smooth inside every step and a step changes s exactly at its
    event; inside a step the segment's line is extrapolated, as the governor's branch is.
    """
    n = m.load_x.shape[0]
    if n == 0:
        return 1.0
    if seg <= 0:
        return m.load_s[0]
    if seg >= n:
        return m.load_s[n - 1]
    x0 = m.load_x[seg - 1]
    s0 = m.load_s[seg - 1]
    return s0 + (m.load_s[seg] - s0) * (y[m.load_comp] - x0) / (m.load_x[seg] - x0)


@kernel
def generator_branch(m, w, rising):
    """1 while the generator's torque is held at −s·P/ω_min (ω < ω_min, or on it falling), else 0."""
    if w < m.gen_min or (w == m.gen_min and not rising):
        return 1
    return 0


@kernel(inline="always")
def moments(m, angle_mode, y, sel, sw, wk, with_dJ):
    """Reduced inertia, speed and moments at state ``y``.

    Returns ``(J, dJ, w, M_gas, M_load, M_starter)``, dJ possibly NaN without ``with_dJ``; the
    rows u, u′ of ``wk`` are left holding the transfer functions and, with gas, WK_LOCAL and
    WK_PIECE the cylinders' pieces at ``sel`` (:func:`select_pieces`), for :func:`cylinder_rates`
    and :func:`output_row`.

    Generalized forces follow (19): M = Σ P_q u_q + Σ M_k. The gas force of cylinder k is
    (p_k − p0)·F_p with p_k = p_mot + f·(p_full − p_mot) at the governor's fuel f
    (:func:`applied_value`). The load is M_load = −s·(torque + linear·ω + fan·ω|ω| +
    P/max(ω, ω_min)), s from the schedule's segment ``sw[SW_LOAD]`` and the max from the
    generator's branch ``sw[SW_GENERATOR]``. With fuel latching cylinder k burns the fuel it
    took at its last injection, else every cylinder the governor's command (:func:`command`).
    """
    phi = y[PHI]
    u = wk[WK_U]
    J, dJ = mechanism_terms(m.kind, m.mech, m.kin_coef, phi, u, wk[WK_DU], with_dJ)
    J += m.J0
    w = speed(J, angle_mode, y)
    M_gas = 0.0
    if m.has_gas:
        f = command(m, w, y, sw)
        select_pieces(m, sel, wk)
        if m.latch or m.has_motored:  # p = p_mot + f_k·(p_full − p_mot), per cylinder
            c = latch_index(m)
            for k in range(m.ncyl):
                f_k = y[c + k] if m.latch else f
                p_k = cylinder_value(m, k, y, sel, f_k, wk)
                M_gas += m.gas_scale[k] * (p_k - m.gas_offset) * u[k]
        else:  # the motored curve is p0: f·Σ(p − p0)F_p u, one multiplication
            for k in range(m.ncyl):
                M_gas += m.gas_scale[k] * (gas_value(m, k, phi, sel, wk) - m.gas_offset) * u[k]
            M_gas *= f
    # (with s = 1 exactly the formula without a schedule, to the last bit)
    s = load_scale(m, y, sw[SW_LOAD])
    M_load = -s * (m.load_const + m.load_linear * w + m.load_fan * w * abs(w))
    if m.gen_power != 0.0:
        # An electrical load of power s·P: M ω = −s·P. Below ω_min (a start from rest) the
        # torque is held at its value there, so that it stays finite; a state event switches
        # the branch at ω_min, as at the governor's corners, keeping each step smooth.
        w_gen = m.gen_min if sw[SW_GENERATOR] else w
        M_load -= s * m.gen_power / w_gen
    M_starter = 0.0
    if sw[SW_STARTER]:
        M_starter = m.starter_torque * (1.0 - w / m.starter_noload)
    return J, dJ, w, M_gas, M_load, M_starter


@kernel(inline="always")
def split_subchains(m, J, dJ, M_gas, M_shaft, wk):
    """J_k, J′_k and M_k of every sub-chain into ``wk`` (DESIGN §1, ``transient.core.chain``).

    Links in order: the shaft (J0 with flywheel and load; load and starter act on it), middle links
    of constant reduced inertia ``link_J`` (the crank), and the last link with the rest of the
    mechanism's inertia and the gas forces. Links between ideal pairs share a sub-chain.
    """
    for k in range(m.n_pairs + 1):
        wk[WK_J, k] = 0.0
        wk[WK_DJ, k] = 0.0
        wk[WK_M, k] = 0.0
    last = m.link_sub.shape[0] - 1
    J_rest = J
    for i in range(last):
        c = m.J0 if i == 0 else m.link_J[i]
        wk[WK_J, m.link_sub[i]] += c
        J_rest -= c
    wk[WK_M, m.link_sub[0]] += M_shaft
    wk[WK_J, m.link_sub[last]] += J_rest
    wk[WK_DJ, m.link_sub[last]] += dJ
    wk[WK_M, m.link_sub[last]] += M_gas


@kernel(inline="always")
def pair_etas(m, modes, eta_out):
    """η*_k of (25) for the mode bit mask ``modes`` (bit k set: pair k backward)."""
    for k in range(m.n_pairs):
        eta_out[k] = eta_star(m.eta_fwd[k], m.eta_bwd[k], ((modes >> k) & 1) == 0)


@kernel(inline="always")
def acceleration(m, J, dJ, w, M_gas, M_load, M_starter, sw, wk):
    """φ̈ from (18) without non-ideal pairs, else from the serial chain (:func:`chain_acceleration`)."""
    if m.n_pairs == 0:
        return (M_gas + M_load + M_starter - 0.5 * dJ * w * w) / J
    return chain_acceleration(m, J, dJ, w, M_gas, M_load + M_starter, sw, wk)


@kernel(inline="always")
def chain_acceleration(m, J, dJ, w, M_gas, M_shaft, sw, wk):
    """φ̈ of the serial chain with the pair modes held in ``sw``; leaves the sub-chains' J, J′, M
    and the pairs' η*, S in the rows of ``wk``."""
    n = m.n_pairs
    split_subchains(m, J, dJ, M_gas, M_shaft, wk)
    pair_etas(m, sw[SW_MODES], wk[WK_ETA])
    return chain_solve(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1], wk[WK_M, : n + 1], wk[WK_ETA, :n], w,
                       wk[WK_S, :n])


@kernel(inline="always")
def derivative(m, angle_mode, y, sel, sw, wk, out):
    """dy/dt = (ω, 1, ε, powers), or in crank angle dy/dφ = (1, 1/ω, dK/dφ, moments), y[2] = K.

    Inlined into its callers: as a call, passing the Model (numba flattens it into ~130 scalar
    arguments) cost ~40 ns of a ~75 ns right-hand side (``tools/handwritten_kernel.py``).

    In crank angle dK/dφ = Σ M − Σ (1 − η*_k) S_k, the work–energy law of the chain
    (``transient.core.chain``), so that the energy lost is exactly what the pairs account for.
    """
    # (18) in crank angle is dK/dφ = M: without pairs no term needs dJ/dφ
    with_dJ = not angle_mode or m.n_pairs > 0
    J, dJ, w, M_gas, M_load, M_starter = moments(m, angle_mode, y, sel, sw, wk, with_dJ)
    # the speed's range over a step's stages: a speed event inside the step shows here
    wk[WK_SPEED, 0] = min(wk[WK_SPEED, 0], w)
    wk[WK_SPEED, 1] = max(wk[WK_SPEED, 1], w)
    M = M_gas + M_load + M_starter
    loss = 0.0  # Σ (1 − η*) S, the moment equivalent of the pairs' losses
    q = 1.0 if angle_mode else w  # work per unit of the independent variable
    if m.n_pairs == 0:  # equation (18); no chain to solve (a scene without pairs pays nothing)
        a = (M - 0.5 * dJ * w * w) / J  # read in time mode only (in crank angle dJ may be NaN)
    else:
        a = chain_acceleration(m, J, dJ, w, M_gas, M_load + M_starter, sw, wk)
        mode_margins(m, sw, wk)  # watched at every stage: a mode switch inside a step shows here
        for k in range(m.n_pairs):
            lk = (1.0 - wk[WK_ETA, k]) * wk[WK_S, k]
            out[W_LOSS0 + k] = lk * q
            loss += lk
            wk[WK_G_MIN, k] = min(wk[WK_G_MIN, k], wk[WK_G, k])
    out[W_GAS] = M_gas * q
    out[W_LOAD] = M_load * q
    out[W_STARTER] = M_starter * q
    if m.gov_dyn != gv.NONE or m.latch:
        governor_rates(m, w, y, 1.0 / w if angle_mode else 1.0, sw, wk, out)
    if m.woschni:
        cylinder_rates(m, angle_mode, y, sel, w, command(m, w, y, sw), wk, out)
    if angle_mode:
        out[PHI] = 1.0
        out[T] = 1.0 / w
        out[KINETIC] = M - loss
    else:
        out[PHI] = w
        out[T] = 1.0
        out[OMEGA] = a


@kernel(inline="always")
def mode_margins(m, sw, wk):
    """How far each pair's held mode is from switching, into ``wk[WK_G]`` (after
    :func:`acceleration`); a mode switch is due where a margin falls to zero.

    ``power-flow``: the power the pair transmits must have the mode's sign, S_k σ ≥ 0 forward,
    S_k σ < 0 backward. ``paper``: criterion (25) on the moments of everything on the shaft side,
    (Σ_{j≤k} M_j) σ ≥ 0 forward (``transient.core.chain.modes_paper``).
    """
    sigma = sw[SW_DIRECTION]
    upstream = 0.0
    for k in range(m.n_pairs):
        upstream += wk[WK_M, k]
        v = wk[WK_S, k] if m.policy == POWER_FLOW else upstream
        if (sw[SW_MODES] >> k) & 1:
            wk[WK_G, k] = -v * sigma
        else:
            wk[WK_G, k] = v * sigma


@kernel(inline="always")
def margins_inline(m, angle_mode, y, sel, sw, wk):
    """Mode margins at state ``y`` (see :func:`mode_margins`), in ``wk[WK_G]``; inlined into the
    stepper's root finder, whose iterations evaluate them most: there a call would copy the Model
    at every iteration."""
    J, dJ, w, M_gas, M_load, M_starter = moments(m, angle_mode, y, sel, sw, wk, True)
    acceleration(m, J, dJ, w, M_gas, M_load, M_starter, sw, wk)
    mode_margins(m, sw, wk)


@kernel
def margins_at(m, angle_mode, y, sel, sw, wk):
    """:func:`margins_inline` as a call: one compiled copy of the model's terms for the sites
    that evaluate the margins rarely."""
    margins_inline(m, angle_mode, y, sel, sw, wk)


@kernel
def choose_modes(m, angle_mode, y, sel, sw, wk):
    """Choose σ and the pair modes afresh at state ``y`` (start of a run, speed reversal).

    With ω ≠ 0, σ = sign ω; ``power-flow`` takes the unique consistent mode vector
    (``chain.modes_power_flow``), ``paper`` criterion (25). At rest, the incipient motion decides:
    σ is the direction the chain starts to move in; if the pairs' friction holds the applied
    moments in both directions the chain is locked. Sets ``sw[SW_DIRECTION]`` and
    ``sw[SW_MODES]``. Returns the status of ``chain.modes_power_flow``: UNIQUE, LOCKED, or (a
    rounding tie S_k ≈ 0, resolved by its documented rule) AMBIGUOUS or NONE_CONSISTENT.
    """
    J, dJ, w, M_gas, M_load, M_starter = moments(m, angle_mode, y, sel, sw, wk, True)
    n = m.n_pairs
    if n == 0:
        sw[SW_DIRECTION] = -1 if w < 0.0 else 1
        sw[SW_MODES] = 0
        return UNIQUE
    split_subchains(m, J, dJ, M_gas, M_load + M_starter, wk)
    a, status, _ = modes_power_flow_into(wk[WK_J, : n + 1], wk[WK_DJ, : n + 1],
                                         wk[WK_M, : n + 1], m.eta_fwd, m.eta_bwd, w,
                                         wk[WK_ETA, :n], wk[WK_S, :n],
                                         wk[WK_SCRATCH: WK_SCRATCH + 4, :n])
    if status == LOCKED:
        return status
    if w != 0.0:
        sw[SW_DIRECTION] = 1 if w > 0.0 else -1
    else:
        sw[SW_DIRECTION] = 1 if a > 0.0 else -1
    modes = 0
    upstream = 0.0
    for k in range(n):
        upstream += wk[WK_M, k]
        if m.policy == POWER_FLOW:
            backward = wk[WK_ETA, k] != m.eta_fwd[k]
        else:
            backward = upstream * sw[SW_DIRECTION] < 0.0
        if backward:
            modes |= 1 << k
    sw[SW_MODES] = modes
    return status


@kernel
def output_row(m, angle_mode, y, sel, sw, wk, row):
    """:func:`output_row_inline` as a call: one compiled copy of the model's terms for the
    output rows written at events."""
    output_row_inline(m, angle_mode, y, sel, sw, wk, row)


@kernel(inline="always")
def output_row_inline(m, angle_mode, y, sel, sw, wk, row):
    """Fill one output sample: columns ``OUTPUTS``, the gas value applied to each cylinder
    (p_mot + f·(p_full − p_mot), see :func:`applied_value`), ``PAIR_OUTPUTS`` of each pair, the
    dynamic governor's states and the latched fuels. Inlined where the stepper writes the grid's
    samples (``integrate._emit_samples``): there a call would copy the Model for every sample."""
    J, dJ, w, M_gas, M_load, M_starter = moments(m, angle_mode, y, sel, sw, wk, True)
    row[0] = y[T]
    row[1] = y[PHI]
    row[2] = w
    row[3] = acceleration(m, J, dJ, w, M_gas, M_load, M_starter, sw, wk)
    row[4] = J
    row[5] = dJ
    row[6] = M_gas
    row[7] = M_load
    row[8] = M_starter
    f = command(m, w, y, sw)
    row[9] = f
    row[10] = y[W_GAS]
    row[11] = y[W_LOAD]
    row[12] = y[W_STARTER]
    c = latch_index(m)
    for k in range(m.ncyl):  # the pressure (force) applied, at the cylinder's fuel
        f_k = y[c + k] if m.latch else f
        row[N_OUT_FIXED + k] = cylinder_value(m, k, y, sel, f_k, wk) if m.has_gas else 0.0
    pair_rows(m, w, y[W_LOSS0: W_LOSS0 + m.n_pairs], wk, row[N_OUT_FIXED + m.ncyl:])
    j = N_OUT_FIXED + m.ncyl + len(PAIR_OUTPUTS) * m.n_pairs
    for i in range(gov_index(m), cyl_index(m)):  # governor states, latched fuels
        row[j] = y[i]
        j += 1


@kernel(inline="always")
def pair_rows(m, w, w_loss, wk, out):
    """``PAIR_OUTPUTS`` of each pair from the rows η*, S of ``wk``; ``w_loss``: energy lost so far."""
    np_ = len(PAIR_OUTPUTS)
    for k in range(m.n_pairs):
        out[np_ * k] = wk[WK_S, k]
        out[np_ * k + 1] = wk[WK_ETA, k]
        out[np_ * k + 2] = (1.0 - wk[WK_ETA, k]) * wk[WK_S, k] * w
        out[np_ * k + 3] = w_loss[k]


@kernel
def inverse_chain(m, a, w, sigma, wk):
    """Drive torque on the shaft and pair moments for a prescribed motion (φ̈ = a, φ̇ = w).

    With a known, the sub-chain equations J_k a = R_k + η*_{k−1} S_{k−1} − S_k
    (``transient.core.chain``) are solved from the far end: η*_{n−1} S_{n−1} = J_n a − R_n, …,
    and the drive M_drive = J_0 a − R_0 + S_0. Every mode vector is tried (bit k: pair k backward)
    and the first consistent one kept: for ``power-flow`` S_k σ must have the mode's sign (always
    exactly one vector, because η* > 0 keeps the sign of η* S_k), for ``paper`` the criterion (25)
    with the drive counted among the shaft-side moments; if none is consistent, the one violating
    least. Needs the rows J, J′, M of ``wk``; fills η*, S. Returns ``(M_drive, n_consistent)``.
    """
    n = m.n_pairs
    half_w2 = 0.5 * w * w
    eta, S = wk[WK_ETA_TRY], wk[WK_S_TRY]
    best = np.nan
    best_viol = np.inf
    n_ok = 0
    for mask in range(1 << n):
        pair_etas(m, mask, eta)
        for k in range(n, 0, -1):  # η*_{k−1} S_{k−1}, the moment arriving from the far side
            carried = wk[WK_J, k] * a - (wk[WK_M, k] - wk[WK_DJ, k] * half_w2)
            if k < n:
                carried += S[k]
            S[k - 1] = carried / eta[k - 1]
        drive = wk[WK_J, 0] * a - (wk[WK_M, 0] - wk[WK_DJ, 0] * half_w2) + S[0]
        ok = True
        viol = 0.0
        upstream = drive
        for k in range(n):
            upstream += wk[WK_M, k]
            v = (S[k] if m.policy == POWER_FLOW else upstream) * sigma
            if (mask >> k) & 1:
                ok = ok and v < 0.0
                viol += max(0.0, v)
            else:
                ok = ok and v >= 0.0
                viol += max(0.0, -v)
        if ok:
            n_ok += 1
        if (ok and n_ok == 1) or (n_ok == 0 and viol < best_viol):
            best, best_viol = drive, viol
            for k in range(n):
                wk[WK_ETA, k] = eta[k]
                wk[WK_S, k] = S[k]
    return best, n_ok


@compiled
def inverse_dynamics(m, t, phi, omega, eps, rows, M_drive, n_consistent):
    """Prescribed motion: the drive torque on the shaft that the chain needs [N m].

    Without pairs M_drive = J ε + ½ J′ ω² − M, from (18); with pairs see :func:`inverse_chain`.
    Fills ``rows`` (one output row per sample, ``epsilon`` being the prescribed one; the work
    columns are left zero, integrated by the caller), ``M_drive`` and ``n_consistent`` (the number
    of consistent mode vectors per sample, 1 unless a policy is ambiguous there). The starter is
    off, ``sel`` is the sample angle itself and a load-schedule corner takes its value after.
    """
    wk = work_array(m)
    y = np.zeros(n_state(m))
    sw = np.zeros(N_SWITCHES, dtype=np.int64)
    n = m.n_pairs
    for i in range(t.shape[0]):
        y[PHI] = phi[i]
        y[T] = t[i]
        y[OMEGA] = omega[i]
        sw[SW_GOVERNOR] = governor_branch(m, omega[i], eps[i] >= 0.0)
        sw[SW_LOAD] = load_segment(m, y[m.load_comp], True)  # t and φ increase here (ω > 0)
        sw[SW_GENERATOR] = generator_branch(m, omega[i], eps[i] >= 0.0)
        if m.latch:  # (a static governor only) at a prescribed speed each cylinder latches it
            for k in range(m.ncyl):
                y[latch_index(m) + k] = fuel(m, omega[i], sw[SW_GOVERNOR])
        J, dJ, w, M_gas, M_load, M_starter = moments(m, False, y, phi[i], sw, wk, True)
        output_row(m, False, y, phi[i], sw, wk, rows[i])
        rows[i, COL_EPS] = eps[i]
        if n == 0:
            M_drive[i] = J * eps[i] + 0.5 * dJ * w * w - (M_gas + M_load)
            n_consistent[i] = 1
            continue
        split_subchains(m, J, dJ, M_gas, M_load, wk)
        sigma = 1.0 if w > 0.0 or (w == 0.0 and eps[i] >= 0.0) else -1.0
        M_drive[i], n_consistent[i] = inverse_chain(m, eps[i], w, sigma, wk)
        pair_rows(m, w, y[W_LOSS0: W_LOSS0 + n], wk, rows[i, N_OUT_FIXED + m.ncyl:])
