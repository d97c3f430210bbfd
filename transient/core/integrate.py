"""Compiled embedded Runge–Kutta stepper with dense output, driven segment by segment (DESIGN §2).

One loop for every pair in :mod:`.tableaus` (DOP853, DOPRI5), passed as data; adaptive, or with
fixed crank-angle steps (``cfg[C_FIXED_STEP] > 0``: no error control, for periodic steady runs).

The solver loop is compiled together with the right-hand side (``model.derivative``). While
ω ≥ ω_lo it integrates in crank angle (dt/dφ = 1/ω) and stops exactly on every breakpoint, so the
right-hand side is smooth inside every step; below ω_lo (start from rest, stall, reversal) it
integrates in time, and a step that would cross a breakpoint is retaken so that it ends on it.
On a breakpoint, cylinders starting their injection latch the governor's fuel command, and where
a pressure jumps the first stage of the next step is evaluated afresh (not carried over).
Switches between the two, starter cut-out, the governor characteristic's corners, the PI
governor's limits, the flyweight governor's stops, the corners of the load schedule and the
generator's minimum speed, speed reversals and the end of the run are state events located on
the dense output (Hairer, Nørsett & Wanner,
*Solving ODEs I*, §II.6 and §II.10).

:func:`advance` runs until the run ends, an output buffer fills or a step budget is used, so that
the Python caller can stream results, show progress and react to Ctrl-C between chunks.

Helpers called once per step or once per root-finding iteration that take the Model are inlined
(``inline="always"``: the step, the error norm, the stiffness test, the margin samples, the mode
settling, the event function, a pair's crossing), each at its one call site, or at a few where it
is small: a call that is not inlined copies the Model's ~150 flattened words onto the stack
(:mod:`.jit`). Under ``perf`` (``tools/profile_stepper.py``) those copies were 26 % of the
diesel's samples in numba's code and are now 13 %; the rest are calls that run rarely or whose
callee is too large to copy at several sites (the dense output, the margins, the output row).
The margins and the output row are inlined at one site each, into a small function: the margins
into the root finder, whose iterations (~7 a pair's mode switch) evaluate them most
(``model.margins_inline``), the output row into the writing of the grid's samples
(``model.output_row_inline``). That cost 30–38 s of cold compile for the row, none measurable
for the margins; the margins inlined into the step's samples too cost ~40 s more and were not
kept (README, *Calls that copy the Model*).
"""
from __future__ import annotations

import numpy as np

from .jit import compiled, kernel

from .chain import AMBIGUOUS, MAX_PAIRS, NONE_CONSISTENT
from .chain import LOCKED as LOCKED_STATUS
from . import cylinder as cyl
from . import governor as gv
from .model import (KINETIC, N_DYNAMIC, N_SWITCHES, OMEGA, PHI, SW_DIRECTION, SW_GENERATOR,
                    SW_GOVERNOR, SW_LOAD, SW_MODES, SW_SLEEVE, SW_STARTER, T, WK_DEMAND, WK_G,
                    WK_G_MIN, WK_SPEED, choose_modes, command, demand, derivative, generator_branch,
                    cyl_index, gov_index, governor_branch, inertia, is_pi, latch_index, load_segment,
                    margins_at, margins_inline, n_state, output_row, output_row_inline, speed,
                    start_branch, work_array)

# Step-size control as in SciPy's DOP853 and RK45 (error exponent −1/(q + 1), tab.exponent).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
PI_BETA = 0.04

# cfg[...] — settings (float64 array, filled by transient.simulate)
C_RTOL, C_ATOL, C_T_END, C_PHI_END, C_W_LO, C_W_HI, C_DPHI_OUT, C_DT_OUT = range(8)
C_MAX_STEP_PHI, C_MAX_STEP_T, C_CHUNK_STEPS, C_FIXED_STEP = range(8, 12)
N_CFG = 12
# fst[...] — float stepper state kept between chunks
F_H, F_SEL, F_NEXT_OUT, F_LAST_T, F_LAST_PHI, F_PASSED_BP, F_REDO_LEVEL, F_LAST_SWITCH = range(8)
F_ERR_OLD = 8  # the last accepted step's error norm (≥ 1e-4), for the PI step-size control
N_FST = 9
# fst[F_DERIV:F_DERIV + n]: the derivative at y that the last step carried over (FSAL), then the
# pairs' margins there; kept where a chunk ends with them valid (ist[I_F_VALID]). Chunks end where
# the output buffer fills: recomputed at each chunk's start (with the table piece ahead of the
# shaft, not the step's), they made the run depend on the samples per turn in the last bits.
F_DERIV = N_FST
# In time, a breakpoint counts as passed once a step has ended within this angle of it [rad]
# (a retaken step lands on it only to the accuracy of the dense output).
BP_LANDING = 1e-7
# ist[...] — integer stepper state kept between chunks
# ist[:N_SWITCHES] are the model's switches (starter, governor branch, pair modes, direction,
# load-schedule segment, generator branch, sleeve on a stop), passed on as ``sw``.
I_STARTER_ON, I_GOV_BRANCH, I_MODES, I_DIRECTION = SW_STARTER, SW_GOVERNOR, SW_MODES, SW_DIRECTION
I_LOAD_SEG, I_GEN_LOW, I_SLEEVE = SW_LOAD, SW_GENERATOR, SW_SLEEVE
(I_ANGLE_MODE, I_NFEV, I_NSTEPS, I_NREJECT, I_NOUT, I_NEV, I_STARTED, I_F_VALID,
 I_NREDO, I_NCHATTER, I_NSWITCH, I_NTIES, I_FLIPPED, I_CHATTER_CODE, I_AT_EVENT, I_STIFF,
 I_NONSTIFF) = range(N_SWITCHES, N_SWITCHES + 17)
# the last attempt was rejected by the error test; consecutive non-finite attempts; consecutive
# attempts retaken for a crossing that no sample found
I_REJECTED, I_NBAD, I_NUNSEEN = range(N_SWITCHES + 17, N_SWITCHES + 20)
N_IST = N_SWITCHES + 20
# Hairer's stiffness test (dop853.f, dopri5.f): this many accepted steps with hλ beyond the
# tableau's bound, not interrupted by as many as NONSTIFF_RESET within it, mean that stability,
# not accuracy, sets the step: the problem is stiff for an explicit method.
STIFF_COUNT, NONSTIFF_RESET = 15, 6
# State events closer together than this (rad in crank angle; × the output spacing in time) count
# as no progress; this many in a row is chattering, which is reported, never looped on.
CHATTER_GAP, CHATTER_COUNT = 1e-9, 50
# A step that starts within this (relative) of the level of the event just handled starts on it:
# the event has put it there, and rounding must not make it cross the level again at once.
ON_LEVEL = 1e-12

# advance() return codes
RUNNING, FINISHED, FAIL_NONFINITE, FAIL_STEP, STALLED, LOCKED, CHATTERING, STIFF = range(8)
# event codes written to the event buffer as (code, t, phi, omega)
(EV_BREAKPOINT, EV_TO_TIME, EV_TO_ANGLE, EV_STARTER_CUTOUT, EV_REVERSAL, EV_END, EV_GOVERNOR,
 EV_PAIR_MODE, EV_LOCKED, EV_LOAD, EV_GENERATOR, EV_SLEEVE_STOP, EV_SLEEVE_FREE,
 EV_INJECTION) = range(14)
EVENT_NAMES = ("breakpoint", "to_time_domain", "to_angle_domain", "starter_cutout",
               "speed_reversal", "end", "governor_corner", "pair_mode", "locked", "load_schedule",
               "generator_min_speed", "sleeve_stop", "sleeve_free", "injection")
# Event "components" at and above PAIR_COMP are the mode margins of the pairs (model.mode_margins);
# DEMAND_COMP is the PI governor's demand u (model.demand).
PAIR_COMP = 100
DEMAND_COMP = -1


@kernel(inline="always")
def _controlled(i, ix, g0, g1, c0):
    """Whether state component i is error-controlled: the dynamics' (but the independent
    variable ``ix``), the governor's y[g0:g1] and the cylinder pressures y[c0:]. The work
    integrals do not feed back (they follow the dynamics' steps) and the latched fuels are
    constant."""
    return i != ix and (i < N_DYNAMIC or g0 <= i < g1 or i >= c0)


@kernel(inline="always")
def _error_norm(tab, K, h, y, y_new, rtol, atol, ix, g0, g1, c0):
    """Error norm: DOP853's blend of its 5th- and 3rd-order estimators (Hairer), the RMS norm of
    the one estimator for a pair without a second (``tab.E3 = 0``, DOPRI5), over the components
    :func:`_controlled` names.

    The accumulating components (t in crank angle, φ in time) are scaled by their increment over
    the step, not by their size: relative to |t| the allowed error would grow with the run's length
    and a long run would lose phase for nothing. The independent variable ``ix`` has no error.
    """
    n = y.shape[0]
    err5 = 0.0
    err3 = 0.0
    for i in range(n):
        if not _controlled(i, ix, g0, g1, c0):
            continue
        if i == PHI or i == T:
            sc = atol + rtol * abs(y_new[i] - y[i])
        else:
            sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        e5 = 0.0
        e3 = 0.0
        for s in range(tab.n_stages + 1):
            e5 += K[s, i] * tab.E5[s]
            e3 += K[s, i] * tab.E3[s]
        err5 += (e5 / sc) ** 2
        err3 += (e3 / sc) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / np.sqrt((err5 + 0.01 * err3) * (N_DYNAMIC - 1 + g1 - g0 + n - c0))


@kernel(inline="always")
def _stiffness(tab, K, h, y, ix, g0, g1, c0, rtol, atol):
    """Estimate of h·λ over the step (Hairer, *Solving ODEs II*, §IV.2): the last main stage and
    the FSAL stage both sit at the step's end, and ‖f(y₁) − f(y_s)‖/‖y₁ − y_s‖ estimates the
    dominant eigenvalue's modulus; y₁ − y_s = h Σ_j (A[ns, j] − A[ns−1, j]) K_j. Over the
    dynamics' components and the governor's states, each scaled as in the error norm (the
    state mixes joules with fuel fractions: unscaled, a stiff governor state would be hidden
    behind the kinetic energy)."""
    ns = tab.n_stages
    num = 0.0
    den = 0.0
    for i in range(y.shape[0]):
        if not _controlled(i, ix, g0, g1, c0):
            continue
        sc = atol + rtol * abs(y[i])
        dy = 0.0
        for j in range(ns):
            dy += (tab.A[ns, j] - tab.A[ns - 1, j]) * K[j, i]
        num += ((K[ns, i] - K[ns - 1, i]) / sc) ** 2
        den += (h * dy / sc) ** 2
    if den == 0.0:
        return 0.0
    return abs(h) * np.sqrt(num / den)


@kernel(inline="always")
def _stiff(tab, K, h, y, ix, g0, g1, c0, rtol, atol, ist):
    """Count an accepted step in Hairer's stiffness test (``STIFF_COUNT``); True when stiff."""
    if _stiffness(tab, K, h, y, ix, g0, g1, c0, rtol, atol) > tab.stiff_bound:
        ist[I_NONSTIFF] = 0
        ist[I_STIFF] += 1
        return ist[I_STIFF] >= STIFF_COUNT
    ist[I_NONSTIFF] += 1
    if ist[I_NONSTIFF] >= NONSTIFF_RESET:
        ist[I_STIFF] = 0
    return False


@kernel(inline="always")
def _step(tab, m, angle_mode, x, y, f, h, sel, sw, K, y_new, tmp, wk):
    """One Runge–Kutta step of size h from (x, y) with f = y′; K[0] must hold f.

    Leaves the stages in K (K[tab.n_stages] = f(y_new)) and the new state in y_new.
    """
    n = y.shape[0]
    ns = tab.n_stages
    # Stage ns is the derivative at the new state (FSAL: row ns of A holds B). One call site, as
    # ``model.derivative`` is inlined wherever it is called.
    for s in range(1, ns + 1):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += tab.A[s, j] * K[j, i]
            tmp[i] = y[i] + h * acc
        if s == ns:
            # The independent variable advances exactly (exact stops on breakpoints).
            tmp[PHI if angle_mode else T] = x + h
            for i in range(n):
                y_new[i] = tmp[i]
        derivative(m, angle_mode, tmp, sel, sw, wk, K[s])


@kernel
def _dense(tab, m, angle_mode, y, y_new, h, sel, sw, K, F, tmp, wk):
    """Dense-output coefficients F (3 + tab.D rows × n) of the last step, after the extra stages
    (three for DOP853, none for DOPRI5; layout in :mod:`.tableaus`)."""
    n = y.shape[0]
    ns = tab.n_stages
    for s in range(ns + 1, tab.n_ext):
        a = tab.A[s]
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[j] * K[j, i]
            tmp[i] = y[i] + h * acc
        derivative(m, angle_mode, tmp, sel, sw, wk, K[s])
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[ns, i] + K[0, i])
        for r in range(tab.D.shape[0]):
            acc = 0.0
            for j in range(tab.n_ext):
                acc += tab.D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@kernel
def _dense_eval(F, y, theta, out):
    """State at fraction θ ∈ [0, 1] of the last step."""
    n = y.shape[0]
    for i in range(n):
        acc = 0.0
        for r in range(F.shape[0] - 1, -1, -1):
            acc += F[r, i]
            if r % 2 == 0:
                acc *= theta
            else:
                acc *= 1.0 - theta
        out[i] = y[i] + acc


@kernel(inline="always")
def _dense_state(F, y, x, h, theta, ix, out):
    """State at fraction θ of the last step (from x, size h), its independent variable ``ix``
    exactly x + θh."""
    _dense_eval(F, y, theta, out)
    out[ix] = x + theta * h


@kernel(inline="always")
def _event_g(m, angle_mode, yv, comp, level, sel, sw, wk):
    """Event function: ω − level for the speed (K = ½Jω² in crank-angle mode), the mode margin of
    pair comp − PAIR_COMP, the PI demand u − level, else y[comp] − level."""
    if comp >= PAIR_COMP:
        margins_at(m, angle_mode, yv, sel, sw, wk)
        return wk[WK_G, comp - PAIR_COMP]
    if comp == OMEGA or comp == DEMAND_COMP:
        J = inertia(m, yv[PHI], wk)
        w = speed(J, angle_mode, yv)
        return (w if comp == OMEGA else demand(m, w, yv)) - level
    return yv[comp] - level


@kernel
def _crossing(m, angle_mode, F, y, y_new, comp, level, sel, sw, tmp, wk):
    """θ ∈ (0, 1] where the event function crosses zero on the dense output.

    The caller has checked that it changes sign between y and y_new. The bracket's right end is
    y_new itself, not the dense output at θ = 1, which can differ from it by rounding and then
    would not bracket a root that sits at the very end of the step.
    """
    ga = _event_g(m, angle_mode, y, comp, level, sel, sw, wk)
    gb = _event_g(m, angle_mode, y_new, comp, level, sel, sw, wk)
    return _root(m, angle_mode, F, y, comp, level, sel, sw, tmp, wk, 0.0, 1.0, ga, gb)[0]


@kernel
def _root(m, angle_mode, F, y, comp, level, sel, sw, tmp, wk, a, b, ga, gb):
    """Root of the event function in the bracket θ ∈ [a, b] (values ga, gb) on the dense output
    (Illinois method); b if the bracket holds no sign change. Returns (θ, evaluations).

    The θ returned is on the far side of the crossing (g there has gb's sign, or is 0): the
    state at the event has crossed. Two pairs whose margins fall through zero at the same angle
    (a massless link between them) then both see their crossing there, and a switch is never
    undone because rounding left the event a hair before its own root."""
    if gb == 0.0 or (ga > 0.0) == (gb > 0.0):
        return b, 0
    side = 0
    for i in range(100):
        if b - a < 1e-12:
            return b, i
        c = b - gb * (b - a) / (gb - ga)
        if not (a < c < b):
            c = 0.5 * (a + b)
        _dense_eval(F, y, c, tmp)
        if comp >= PAIR_COMP:  # most iterations: the margins inlined, no copy of the Model
            margins_inline(m, angle_mode, tmp, sel, sw, wk)
            gc = wk[WK_G, comp - PAIR_COMP]
        else:
            gc = _event_g(m, angle_mode, tmp, comp, level, sel, sw, wk)
        if gc == 0.0:
            return c, i + 1
        if (gc > 0.0) == (gb > 0.0):
            b, gb = c, gc
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            a, ga = c, gc
            if side == 1:
                gb *= 0.5
            side = 1
    return b, 100


#: A pair's mode margin can fall through zero and come back within one step, unseen at the
#: step's ends. Every stage of the step evaluates it (``model.derivative`` keeps the least value);
#: when that dips to zero or below, the margin is sampled at these fractions of the step to find
#: the first crossing.
N_MARGIN_SAMPLES = 4


@kernel(inline="always")
def _sample_margins(m, angle_mode, F, y, x, h, sel, sw, tmp, wk, gs):
    """Mode margins of all pairs at θ = j/N_MARGIN_SAMPLES, j = 1 … N − 1 (rows of ``gs``; row 0
    holds the step's start and row N its end already)."""
    ix = PHI if angle_mode else T
    for j in range(1, N_MARGIN_SAMPLES):
        _dense_state(F, y, x, h, j / N_MARGIN_SAMPLES, ix, tmp)
        margins_at(m, angle_mode, tmp, sel, sw, wk)
        for k in range(m.n_pairs):
            gs[j, k] = wk[WK_G, k]


#: Samples of the fine search for a crossing that a step's stages show and its coarse samples
#: miss (a pair's power reversing for a few degrees inside a long step); a crossing that these
#: miss too makes the step be retaken shorter, at most MAX_UNSEEN times in a row.
N_FINE_SAMPLES, MAX_UNSEEN = 64, 3


@kernel
def _crossing_inside(m, angle_mode, F, y, x, h, comp, level, direction, ga, sel, sw, tmp, wk,
                     n_samples):
    """θ where the speed, the PI demand or a pair's margin (``comp``) first crosses ``level``
    (in ``direction``) inside a step whose ends are on the same side of it, sampled at
    θ = j/n_samples on the dense output; 2 if the samples see no crossing (it was only in a
    stage, or between samples). Returns (θ, evaluations)."""
    ix = PHI if angle_mode else T
    g_prev = ga
    for j in range(1, n_samples + 1):
        theta = j / n_samples
        _dense_state(F, y, x, h, theta, ix, tmp)
        g = _event_g(m, angle_mode, tmp, comp, level, sel, sw, wk)
        if _crosses(g_prev, g, direction):
            root, evals = _root(m, angle_mode, F, y, comp, level, sel, sw, tmp, wk,
                                (j - 1) / n_samples, theta, g_prev, g)
            return root, j + evals
        g_prev = g
    return 2.0, n_samples


@kernel(inline="always")
def _pair_crossing(m, angle_mode, F, y, x, h, k, sel, sw, tmp, wk, gs):
    """θ where pair k's margin first falls to zero within the step, or 2 if it does not; and the
    margin evaluations (right-hand sides) the root finding took.

    A margin that starts at 0 (an event has just switched this pair's mode) and is below it a
    sample on either fell at once — the power only touched zero there and turns back, and the
    switch is undone at the step's start (θ = 0) — or first rose for less than a sample's span
    (the power reversed for a few degrees): :func:`_fall_after_rise` tells which.
    """
    if gs[0, k] == 0.0 and gs[1, k] < 0.0:
        return _fall_after_rise(m, angle_mode, F, y, x, h, k, 1.0 / N_MARGIN_SAMPLES, sel, sw,
                                tmp, wk)
    for j in range(N_MARGIN_SAMPLES):
        if _crosses(gs[j, k], gs[j + 1, k], -1):
            return _root(m, angle_mode, F, y, PAIR_COMP + k, 0.0, sel, sw, tmp, wk,
                         j / N_MARGIN_SAMPLES, (j + 1) / N_MARGIN_SAMPLES, gs[j, k], gs[j + 1, k])
    return 2.0, 0


@kernel
def _fall_after_rise(m, angle_mode, F, y, x, h, k, theta_end, sel, sw, tmp, wk):
    """For a margin that starts at 0 and is below it at ``theta_end``: θ where it falls to zero
    after rising above it (sampled at N_FINE_SAMPLES points up to ``theta_end``), or 0 if no
    sample rises above zero (it fell at once). Returns (θ, evaluations)."""
    ix = PHI if angle_mode else T
    rose = False
    g_prev = 0.0
    th_prev = 0.0
    for j in range(1, N_FINE_SAMPLES + 1):
        theta = theta_end * j / N_FINE_SAMPLES
        _dense_state(F, y, x, h, theta, ix, tmp)
        g = _event_g(m, angle_mode, tmp, PAIR_COMP + k, 0.0, sel, sw, wk)
        if rose and g <= 0.0:
            root, evals = _root(m, angle_mode, F, y, PAIR_COMP + k, 0.0, sel, sw, tmp, wk,
                                th_prev, theta, g_prev, g)
            return root, j + evals
        rose = rose or g > 0.0
        g_prev = g
        th_prev = theta
    return 0.0, N_FINE_SAMPLES


@kernel
def next_breakpoint(bp, period, phi, upward):
    """The breakpoint strictly above (``upward``) or below φ, as an absolute shaft angle."""
    tol = 1e-13 * max(1.0, abs(phi))
    k = np.floor(phi / period)
    if upward:
        for c in range(2):
            base = (k + c) * period
            for j in range(bp.shape[0]):
                v = base + bp[j]
                if v > phi + tol:
                    return v
        return np.inf
    for c in range(2):
        base = (k - c) * period
        for j in range(bp.shape[0] - 1, -1, -1):
            v = base + bp[j]
            if v < phi - tol:
                return v
    return -np.inf


FIRST_PAIR_EVENT = 14
N_EVENT_KINDS = FIRST_PAIR_EVENT + MAX_PAIRS


@kernel(inline="always")
def _load_corner(m, ix, sw):
    """The load schedule's next corner on the independent variable ``ix`` (``inf`` if the
    schedule runs against the other variable, or has no corner ahead)."""
    seg = sw[SW_LOAD]
    if m.load_comp != ix or seg >= m.load_x.shape[0]:
        return np.inf
    return m.load_x[seg]


@kernel(inline="always")
def _event_spec(m, cfg, e, angle_mode, sw):
    """State event number e that applies now: (code, component, level, direction), code −1 if
    none. The component OMEGA means the speed (K = ½Jω² in crank angle); direction +1 rising,
    −1 falling, 0 either way.

    The load schedule's corners are levels of t or φ, watched one segment at a time: the corner
    above and, for corners in φ (the shaft may turn back in time mode), the one below. On the
    independent variable the segment also ends on the corner (see ``_advance``), so the event is
    found at the step's end exactly, as a breakpoint is in crank angle."""
    if e == 0 and sw[SW_STARTER] == 1:
        return EV_STARTER_CUTOUT, OMEGA, m.starter_cutout, 1
    if e == 1 and angle_mode:
        return EV_TO_TIME, OMEGA, cfg[C_W_LO], -1
    if e == 2 and not angle_mode:
        return EV_TO_ANGLE, OMEGA, cfg[C_W_HI], 1
    if e == 3 and not angle_mode:
        return EV_REVERSAL, OMEGA, 0.0, 0
    if e == 4:  # the end of the run by the variable that is not independent
        if angle_mode:
            return EV_END, T, cfg[C_T_END], 1
        return EV_END, PHI, cfg[C_PHI_END], 1
    if 5 <= e < 7 and m.gov_on:  # the droop characteristic's corners at ω_a and ω₁c
        return EV_GOVERNOR, OMEGA, m.gov_full if e == 5 else m.gov_zero, 0
    if 5 <= e < 7 and is_pi(m):  # the PI demand reaching its upper or lower limit
        return EV_GOVERNOR, DEMAND_COMP, m.gov_par[gv.P_FMAX if e == 5 else gv.P_FMIN], 0
    if e == 7 and sw[SW_LOAD] < m.load_x.shape[0]:  # the schedule's corner ahead
        return EV_LOAD, m.load_comp, m.load_x[sw[SW_LOAD]], 1
    if e == 8 and m.load_comp == PHI and sw[SW_LOAD] > 0:  # behind, reached turning back
        return EV_LOAD, PHI, m.load_x[sw[SW_LOAD] - 1], -1
    if e == 9 and m.gen_power != 0.0:  # the generator's minimum speed
        return EV_GENERATOR, OMEGA, m.gen_min, 0
    if 10 <= e < 14 and m.gov_dyn == gv.FLYWEIGHT:
        return _sleeve_event(m, e, sw)
    if e >= FIRST_PAIR_EVENT and e - FIRST_PAIR_EVENT < m.n_pairs:
        # the mode margin of pair e − FIRST_PAIR_EVENT falls to zero
        return EV_PAIR_MODE, PAIR_COMP + e - FIRST_PAIR_EVENT, 0.0, -1
    return -1, OMEGA, 0.0, 0


@kernel(inline="always")
def _sleeve_event(m, e, sw):
    """The flyweight governor's events (``_event_spec``, e = 10 … 13): a moving sleeve reaching
    its low or high stop; on a stop, the speed at which the net force turns away from it."""
    par = m.gov_par
    z = gov_index(m) + gv.FW_LIFT
    sleeve = sw[SW_SLEEVE]
    if e == 10 and sleeve == gv.FREE:
        return EV_SLEEVE_STOP, z, 0.0, -1
    if e == 11 and sleeve == gv.FREE:
        return EV_SLEEVE_STOP, z, par[gv.F_TRAVEL], 1
    if e == 12 and sleeve == gv.ON_LOW_STOP:
        return EV_SLEEVE_FREE, OMEGA, par[gv.F_W_LIFT], 1
    if e == 13 and sleeve == gv.ON_HIGH_STOP:
        return EV_SLEEVE_FREE, OMEGA, par[gv.F_W_TOP], -1
    return -1, OMEGA, 0.0, 0


@kernel
def _sleeve_stops(m, y, level, w):
    """The sleeve has reached a stop (lift ``level``): it stops there (ż = 0) unless the net force
    already pulls it away, so that it stays free (returns the new switch)."""
    g = gov_index(m)
    y[g + gv.FW_RATE] = 0.0
    low = level == 0.0
    force = gv.sleeve_force(m.gov_par, w, level, 0.0)
    if low and force <= 0.0:
        return gv.ON_LOW_STOP
    if not low and force >= 0.0:
        return gv.ON_HIGH_STOP
    return gv.FREE


@kernel(inline="always")
def _on_angle(phi, angle, period):
    """Whether the shaft angle phi is on ``angle`` of the cycle (to BP_LANDING)."""
    d = (phi - angle) % period
    return min(d, period - d) <= BP_LANDING


@kernel
def _jumps_at(m, bp, phi):
    """Whether a pressure jumps at the breakpoint the shaft is on (``Model.bp_jump``): the
    derivative carried over from the step that ended there (FSAL) used the piece before it."""
    for j in range(bp.shape[0]):
        if _on_angle(phi, bp[j], m.period):
            return m.bp_jump[j]
    return False


@kernel
def _inject(m, y, sw, evbuf, ist, wk):
    """At a breakpoint, moving forward: each cylinder whose start of injection this is latches the
    governor's command (``m.latch``). Returns whether any did (the derivative at y changes)."""
    if not m.latch:
        return False
    J = inertia(m, y[PHI], wk)
    w = speed(J, ist[I_ANGLE_MODE] == 1, y)
    if w <= 0.0:
        return False
    c = latch_index(m)
    hit = False
    for k in range(m.ncyl):
        if _on_angle(y[PHI], m.gas_phase[k] + m.inj_angle, m.period):
            y[c + k] = command(m, w, y, sw)
            hit = True
            _emit_event(m, evbuf, ist, EV_INJECTION, y, wk)
    return hit


@kernel
def _close_intake(m, y):
    """At a breakpoint: each cylinder whose intake closes here starts its closed part at p_a
    (``m.woschni``, :mod:`.cylinder`). Returns whether any did (the derivative at y changes)."""
    if not m.woschni:
        return False
    c = cyl_index(m)
    hit = False
    for k in range(m.ncyl):
        if _on_angle(y[PHI], m.gas_phase[k] + m.cyl_par[cyl.IVC], m.period):
            y[c + k] = m.cyl_par[cyl.P_A]
            hit = True
    return hit


@kernel
def _at_breakpoint(m, bp, y, sw, evbuf, ist, wk):
    """What a breakpoint does to the state (injections, intake closings); returns whether the
    derivative carried over from the last step (FSAL) is stale: the state changed, or a pressure
    jumps here."""
    injected = _inject(m, y, sw, evbuf, ist, wk)
    closed = _close_intake(m, y)
    return injected or closed or _jumps_at(m, bp, y[PHI])


@kernel(inline="always")
def _crosses(g0, g1, direction):
    """Whether g goes from g0 to g1 through zero in the given direction (reaching it counts)."""
    rising = g0 < 0.0 <= g1
    falling = g1 <= 0.0 < g0
    if direction > 0:
        return rising
    if direction < 0:
        return falling
    return rising or falling


@kernel
def _emit_event(m, evbuf, ist, code, y, wk):
    j = ist[I_NEV]
    if j < evbuf.shape[0]:
        J = inertia(m, y[PHI], wk)
        evbuf[j, 0] = code
        evbuf[j, 1] = y[T]
        evbuf[j, 2] = y[PHI]
        evbuf[j, 3] = speed(J, ist[I_ANGLE_MODE] == 1, y)
        ist[I_NEV] = j + 1


@kernel
def _emit_row(m, y, sel, sw, outbuf, ist, fst, wk):
    """One output row at state ``y`` (an event's): a call into ``model.output_row``."""
    output_row(m, ist[I_ANGLE_MODE] == 1, y, sel, sw, wk, outbuf[ist[I_NOUT]])
    _count_row(y, ist, fst)


@kernel(inline="always")
def _count_row(y, ist, fst):
    """The bookkeeping after a row is written at state ``y``."""
    ist[I_NOUT] += 1
    fst[F_LAST_T] = y[T]
    fst[F_LAST_PHI] = y[PHI]


@kernel
def _emit_samples(m, F, y, x, h, x_stop, ix, d_out, sel, sw, outbuf, ist, fst, tmp, wk):
    """The output samples of the grid (spacing ``d_out``) up to ``x_stop`` inside the last step
    (from x, size h), from its dense output F. A call of its own, with the output row inlined:
    from the stepper's loop, once the step was inlined there, each sample's call into the output
    row copied the Model at three times the cost (``perf``), and the coasting cylinder's runs at
    72 samples per turn were 10 % slower; from here a call per sample still copied it twice
    (through ``_emit_row``), and inlining only ``_emit_row`` made those runs 17–22 % slower
    (README, *Calls that copy the Model*)."""
    angle_mode = ist[I_ANGLE_MODE] == 1
    while fst[F_NEXT_OUT] <= x_stop:
        _dense_eval(F, y, (fst[F_NEXT_OUT] - x) / h, tmp)
        tmp[ix] = fst[F_NEXT_OUT]
        output_row_inline(m, angle_mode, tmp, sel, sw, wk, outbuf[ist[I_NOUT]])
        _count_row(tmp, ist, fst)
        fst[F_NEXT_OUT] = np.floor(fst[F_NEXT_OUT] / d_out + 0.5) * d_out + d_out


@kernel(inline="always")
def _out_spacing(cfg, angle_mode):
    return cfg[C_DPHI_OUT] if angle_mode else cfg[C_DT_OUT]


@kernel
def _reset_output_grid(cfg, ist, fst, y):
    """Next output sample: the first grid point of the current mode's grid beyond the state."""
    angle_mode = ist[I_ANGLE_MODE] == 1
    x = y[PHI] if angle_mode else y[T]
    d = _out_spacing(cfg, angle_mode)
    j = np.floor(x / d) + 1.0
    fst[F_NEXT_OUT] = j * d


@kernel
def fst_size(m):
    """Length of the float stepper state ``fst``: N_FST, then the carried derivative and margins."""
    return N_FST + n_state(m) + max(m.n_pairs, 1)


@compiled(nogil=True)  # (nogil: the previous block is written meanwhile, simulate)
def advance(m, tab, cfg, bp, y, fst, ist, outbuf, evbuf):
    """Integrate until the run ends, a buffer fills or the chunk's step budget is used.

    Parameters
    ----------
    m : Model
    tab : tableaus.Tableau
        The Runge–Kutta pair (DOP853, DOPRI5).
    cfg : float64[N_CFG]
        Settings, indices ``C_*``.
    bp : float64[:]
        Sorted breakpoints in [0, m.period).
    y : float64[model.n_state(m)]
        State, updated in place.
    fst, ist : float64[fst_size(m)], int64[N_IST]
        Stepper state kept between calls (zeros before the first call, except
        ``fst[F_PASSED_BP] = nan`` and ``ist[I_STARTER_ON]``).
    outbuf : float64[nbuf, model.n_outputs(m)]
        Output samples; ``ist[I_NOUT]`` rows are filled (the caller resets it after draining).
    evbuf : float64[nev, 4]
        Events (code, t, φ, ω); ``ist[I_NEV]`` rows filled.

    Returns
    -------
    int
        RUNNING, FINISHED, FAIL_NONFINITE, FAIL_STEP, STALLED (the speed reached zero in a run
        that ends only by revolutions), LOCKED (at rest, the friction of the non-ideal pairs holds
        the applied moments) or CHATTERING (pair modes switching without progress).
    """
    n = n_state(m)
    K = np.empty((tab.n_ext, n))
    F = np.empty((3 + tab.D.shape[0], n))
    gs = np.zeros((N_MARGIN_SAMPLES + 1, max(m.n_pairs, 1)))  # pair mode margins over a step
    return _advance(m, tab, cfg, bp, y, fst, ist, outbuf, evbuf, K, F, np.empty(n), np.empty(n),
                    np.empty(n), np.empty(n), work_array(m), gs)


@kernel
def _advance(m, tab, cfg, bp, y, fst, ist, outbuf, evbuf, K, F, f, y_new, y_evt, tmp, wk, gs):
    """:func:`advance` in buffers allocated by it, compiled as a kernel (no reference counting,
    :mod:`.jit`): the stepper loop passes arrays to its helpers at every step."""
    n = y.shape[0]
    n_extra = tab.n_ext - tab.n_stages - 1  # the dense output's extra stages
    rtol = cfg[C_RTOL]
    atol = cfg[C_ATOL]
    margin = 300  # rows kept free: a step never spans more than 256 output intervals
    g0 = gov_index(m)  # the governor's states y[g0:g1] are error-controlled with the dynamics,
    g1 = g0 + gv.n_states(m.gov_dyn)
    c0 = cyl_index(m)  # and so are the cylinder pressures y[c0:]

    if ist[I_STARTED] == 0:
        ist[I_STARTED] = 1
        fst[F_ERR_OLD] = 1e-4
        ist[I_GOV_BRANCH] = start_branch(m, y[OMEGA], y)
        # (time only increases; the shaft angle as ω's sign says, forward from rest)
        ist[I_LOAD_SEG] = load_segment(m, y[m.load_comp], m.load_comp == T or y[OMEGA] >= 0.0)
        ist[I_GEN_LOW] = generator_branch(m, y[OMEGA], True)
        fst[F_LAST_SWITCH] = np.nan
        if _start_modes(m, y, y[PHI], ist, wk) == LOCKED_STATUS:
            return _locked(m, y, y[PHI], outbuf, evbuf, ist, fst, wk)
        if y[OMEGA] >= cfg[C_W_HI]:
            _to_angle_mode(m, y, ist, wk)
        fst[F_SEL] = y[PHI]
        _reset_output_grid(cfg, ist, fst, y)
        _emit_row(m, y, fst[F_SEL], ist[:N_SWITCHES], outbuf, ist, fst, wk)

    # As the last chunk left them: its derivative and margins (F_DERIV), if valid, and the
    # counters of the retaken attempts; kept again where this chunk ends.
    if ist[I_F_VALID] == 1:
        _carry(fst, f, gs, m.n_pairs, False)
    n_bad = ist[I_NBAD]  # consecutive non-finite step attempts
    n_unseen = ist[I_NUNSEEN]  # consecutive attempts retaken for a crossing no sample found
    rejected = ist[I_REJECTED] == 1  # the last attempt was rejected by the error test
    steps_here = 0
    while True:
        if (ist[I_NOUT] + margin >= outbuf.shape[0] or ist[I_NEV] + 8 >= evbuf.shape[0]
                or steps_here >= cfg[C_CHUNK_STEPS]):
            _carry(fst, f, gs, m.n_pairs, True)
            ist[I_NBAD], ist[I_NUNSEEN], ist[I_REJECTED] = n_bad, n_unseen, rejected
            return RUNNING
        angle_mode = ist[I_ANGLE_MODE] == 1
        sw = ist[:N_SWITCHES]
        ix = PHI if angle_mode else T
        x = y[ix]
        if not angle_mode and y[OMEGA] < 0.0 and not np.isfinite(cfg[C_T_END]):
            # A run that ends only by revolutions, turning backwards (from rest, or given a
            # negative speed), would never reach them: report it as a stall, with what was
            # computed, instead of integrating on.
            _emit_row(m, y, fst[F_SEL], sw, outbuf, ist, fst, wk)
            return STALLED
        if ist[I_F_VALID] == 0:
            # (the table piece just ahead in the direction of motion: on a breakpoint, rounding
            # of the shaft angle must not pick the piece behind it)
            ahead = y[PHI] + (1e-9 if angle_mode or y[OMEGA] >= 0.0 else -1e-9)
            if m.n_pairs > 0:
                _settle_modes(m, angle_mode, y, ahead, sw, wk, gs, ist, evbuf)
                ist[I_NFEV] += 1
            derivative(m, angle_mode, y, ahead, sw, wk, f)
            ist[I_NFEV] += 1
            ist[I_F_VALID] = 1
            if fst[F_H] <= 0.0:
                # Initial step: a fixed fraction of a revolution (angle) or of the output spacing.
                fst[F_H] = 0.05 if angle_mode else 0.05 * cfg[C_DT_OUT]
        # Where this segment ends: the next breakpoint or the end of the run.
        here = y[PHI]
        if not angle_mode and abs(here - fst[F_PASSED_BP]) <= BP_LANDING:
            here = fst[F_PASSED_BP]  # just landed on it: look beyond it, both ways
        up = next_breakpoint(bp, m.period, here, True)
        down = next_breakpoint(bp, m.period, here, False)
        if angle_mode:
            x_end = min(up, cfg[C_PHI_END])
            h_max = min(cfg[C_MAX_STEP_PHI], 256.0 * cfg[C_DPHI_OUT])
        else:
            x_end = cfg[C_T_END]
            h_max = min(cfg[C_MAX_STEP_T], 256.0 * cfg[C_DT_OUT])
        # A step that would end within rounding of the segment's end ends on it exactly, so that
        # no later step of a few ulp is needed (next_breakpoint treats such a point as reached).
        tol_end = 1e-13 * max(1.0, abs(x))
        if x_end - x <= tol_end:
            return _finish(m, y, fst[F_SEL], sw, outbuf, evbuf, ist, fst, wk)
        # A load-schedule corner on the independent variable (t in time, φ in crank angle) ends
        # the segment too: the step lands on it and its event is found there (θ = 1). One closer
        # than tol_end is left to the event search, which finds it at once in the next step.
        corner = _load_corner(m, ix, sw)
        if tol_end < corner - x and corner < x_end:
            x_end = corner
        fixed = angle_mode and cfg[C_FIXED_STEP] > 0.0
        h = cfg[C_FIXED_STEP] if fixed else min(fst[F_H], h_max)
        h_planned = h  # before a cut to the segment's end
        at_segment_end = False
        if x + h >= x_end - tol_end:
            h = x_end - x
            at_segment_end = True
        min_step = 10.0 * (np.nextafter(abs(x), np.inf) - abs(x))
        if h < min_step:
            return FAIL_STEP
        if angle_mode:
            sel = x + 0.5 * h
        else:
            sel = y[PHI] + 0.5 * h * y[OMEGA]
        for i in range(n):
            K[0, i] = f[i]
        wk[WK_G_MIN, :] = np.inf
        wk[WK_SPEED, 0] = np.inf
        wk[WK_SPEED, 1] = -np.inf
        wk[WK_DEMAND, 0] = np.inf
        wk[WK_DEMAND, 1] = -np.inf
        _step(tab, m, angle_mode, x, y, f, h, sel, sw, K, y_new, tmp, wk)
        if at_segment_end and x_end == corner:
            y_new[ix] = corner  # x + (corner − x) can miss it by an ulp: the event needs g = 0
        w_lo, w_hi = wk[WK_SPEED, 0], wk[WK_SPEED, 1]
        # (the step's last right-hand side is at y_new: WK_G holds the margins there)
        dip = False
        for k in range(m.n_pairs):
            gs[N_MARGIN_SAMPLES, k] = wk[WK_G, k]
            # a margin that starts at or above zero and dips below, or above and reaches it
            g_min = wk[WK_G_MIN, k]
            dip = dip or g_min < 0.0 <= gs[0, k] or g_min <= 0.0 < gs[0, k]
        ist[I_NFEV] += tab.n_stages
        err = _error_norm(tab, K, h, y, y_new, rtol, atol, ix, g0, g1, c0)
        finite = np.isfinite(err)
        for i in range(n):
            finite = finite and np.isfinite(y_new[i])
        if not finite:
            # A trial step may leave the physical region (K < 0 in a stage): shrink it; only a
            # non-finite value that persists at small steps is a failure.
            n_bad += 1
            if n_bad > 30:
                return FAIL_NONFINITE
            fst[F_H] = 0.2 * h
            ist[I_NREJECT] += 1
            steps_here += 1
            continue
        n_bad = 0
        if fixed:
            err = 0.0  # every step is accepted; the step size alone sets the accuracy
        if err > 1.0:
            fst[F_H] = h * max(MIN_FACTOR, SAFETY * err ** -tab.exponent)
            ist[I_NREDO] = 0  # a shorter step no longer ends on the breakpoint it aimed at
            ist[I_NREJECT] += 1
            steps_here += 1
            rejected = True
            continue
        # PI control (Gustafsson; Hairer's DOPRI5 with β): the last accepted error damps the
        # step size's response to an estimate that happens to be small.
        e = max(err, 1e-12)
        factor = min(MAX_FACTOR, SAFETY * e ** -(tab.exponent - 0.75 * PI_BETA)
                     * fst[F_ERR_OLD] ** PI_BETA)
        fst[F_ERR_OLD] = max(err, 1e-4)
        after_rejection = rejected
        rejected = False
        if after_rejection:
            # No growth right after a rejection (Hairer's DOPRI codes, SciPy): else the step
            # size oscillates between growing past what the error allows and being cut back.
            factor = min(factor, 1.0)
        h_next = h * factor
        if not fixed and _stiff(tab, K, h, y, ix, g0, g1, c0, rtol, atol, ist):
            # the run so far is kept; the state is the accepted step's start
            if fst[F_LAST_T] != y[T] or fst[F_LAST_PHI] != y[PHI]:
                _emit_row(m, y, fst[F_SEL], sw, outbuf, ist, fst, wk)
            return STIFF
        if at_segment_end and not after_rejection:
            # a step cut short to end on a breakpoint says nothing against the step planned
            h_next = max(h_next, min(h_planned, h_planned * factor))
        dense_ready = False
        # In time, a step must not cross a breakpoint: retake it so that it ends there.
        if not angle_mode and (y_new[PHI] > up or y_new[PHI] < down):
            _dense(tab, m, angle_mode, y, y_new, h, sel, sw, K, F, tmp, wk)
            ist[I_NFEV] += n_extra
            level = up if y_new[PHI] > up else down
            theta = _crossing(m, angle_mode, F, y, y_new, PHI, level, sel, sw, tmp, wk)
            fst[F_REDO_LEVEL] = level
            if theta * h > min_step and ist[I_NREDO] < 4:
                # (counted as a rejection: the step is computed again, shorter)
                fst[F_H] = theta * h
                ist[I_NREDO] += 1
                ist[I_NREJECT] += 1
                steps_here += 1
                continue
            dense_ready = True
        elif not angle_mode and 0 < ist[I_NREDO] < 4:
            # A retaken step lands on the breakpoint only to the accuracy of the dense output
            # it was aimed with (at loose tolerances, up to ~1e-3 rad short): lengthen it by the
            # time the rest of the angle takes at the speed reached (a secant step), rather than
            # leaving a sliver that the next step would cross and retake again.
            short = fst[F_REDO_LEVEL] - y_new[PHI]
            rest = short / y_new[OMEGA] if y_new[OMEGA] != 0.0 else -1.0
            if abs(short) > BP_LANDING and 0.0 < rest < h:
                fst[F_H] = h + rest
                ist[I_NREDO] += 1
                ist[I_NREJECT] += 1
                steps_here += 1
                continue
        redo_hit_breakpoint = ist[I_NREDO] > 0 or dense_ready
        ist[I_NREDO] = 0
        # State events on this step: the earliest one truncates it.
        ev_code = -1
        ev_theta = 2.0
        unseen = False  # a pair's margin dipped below zero in the stages only
        ev_comp = 0
        ev_level = 0.0
        ev_rising = True
        # ω at both ends: in crank angle the derivative holds dt/dφ = 1/ω.
        w0 = 1.0 / f[T] if angle_mode else y[OMEGA]
        w1 = 1.0 / K[tab.n_stages, T] if angle_mode else y_new[OMEGA]
        if dip:
            if not dense_ready:
                _dense(tab, m, angle_mode, y, y_new, h, sel, sw, K, F, tmp, wk)
                ist[I_NFEV] += n_extra
                dense_ready = True
            _sample_margins(m, angle_mode, F, y, x, h, sel, sw, tmp, wk, gs)
            ist[I_NFEV] += N_MARGIN_SAMPLES - 1
        for e in range(N_EVENT_KINDS):
            code, comp, level, direction = _event_spec(m, cfg, e, angle_mode, sw)
            if code < 0:
                continue
            if comp >= PAIR_COMP:
                if not dip:
                    continue
                k = comp - PAIR_COMP
                theta, evals = _pair_crossing(m, angle_mode, F, y, x, h, k, sel, sw, tmp, wk, gs)
                ist[I_NFEV] += evals
                if theta > 1.0 and wk[WK_G_MIN, k] < 0.0 <= gs[0, k]:
                    # the stages saw the margin fall below zero, the samples did not
                    theta, evals = _crossing_inside(m, angle_mode, F, y, x, h, comp, 0.0, -1,
                                                    gs[0, k], sel, sw, tmp, wk, N_FINE_SAMPLES)
                    ist[I_NFEV] += evals
                    unseen = unseen or theta > 1.0
                if theta < ev_theta:
                    ev_theta, ev_code, ev_comp, ev_level = theta, code, comp, level
                continue
            if comp == DEMAND_COMP:
                ga = _event_g(m, angle_mode, y, comp, level, sel, sw, wk)
                gb = _event_g(m, angle_mode, y_new, comp, level, sel, sw, wk)
            else:
                ga = (w0 if comp == OMEGA else y[comp]) - level
                gb = (w1 if comp == OMEGA else y_new[comp]) - level
            if code == ist[I_AT_EVENT] - 1 and abs(ga) <= ON_LEVEL * max(1.0, abs(level)):
                ga = 0.0
            ends = _crosses(ga, gb, direction)
            # The speed (the PI demand) can pass a level and come back within one step (its
            # fluctuation within a cycle about a governor corner): the stages' range shows it.
            inside = not ends and ((comp == OMEGA and w_lo < level < w_hi) or (
                comp == DEMAND_COMP and wk[WK_DEMAND, 0] < level < wk[WK_DEMAND, 1]))
            if ends or inside:
                if not dense_ready:
                    _dense(tab, m, angle_mode, y, y_new, h, sel, sw, K, F, tmp, wk)
                    ist[I_NFEV] += n_extra
                    dense_ready = True
                if ends:
                    theta = _crossing(m, angle_mode, F, y, y_new, comp, level, sel, sw, tmp, wk)
                else:
                    for n_samples in (N_MARGIN_SAMPLES, N_FINE_SAMPLES):  # coarse, then fine
                        theta, evals = _crossing_inside(m, angle_mode, F, y, x, h, comp, level,
                                                        direction, ga, sel, sw, tmp, wk,
                                                        n_samples)
                        ist[I_NFEV] += evals
                        if theta <= 1.0:
                            break
                if theta < ev_theta:
                    ev_theta, ev_code, ev_comp, ev_level = theta, code, comp, level
                    # the crossing's direction: from below (an 'inside' crossing is the first
                    # one away from the step's start, so this holds for it too)
                    ev_rising = ga < 0.0 or (ga == 0.0 and gb > 0.0)
        if unseen and ev_code < 0 and n_unseen < MAX_UNSEEN:
            fst[F_H] = 0.5 * h  # (counted as a rejection: the step is computed again, shorter)
            n_unseen += 1
            ist[I_NREJECT] += 1
            steps_here += 1
            continue
        n_unseen = 0
        x_stop = x + h if ev_code < 0 else x + ev_theta * h
        # Output samples inside the step (dense output), then the step's end state.
        if fst[F_NEXT_OUT] <= x_stop:
            if not dense_ready:
                _dense(tab, m, angle_mode, y, y_new, h, sel, sw, K, F, tmp, wk)
                ist[I_NFEV] += n_extra
                dense_ready = True
            _emit_samples(m, F, y, x, h, x_stop, ix, _out_spacing(cfg, angle_mode), sel, sw,
                          outbuf, ist, fst, tmp, wk)
        ist[I_NSTEPS] += 1
        steps_here += 1
        fst[F_H] = h_next
        fst[F_SEL] = sel
        if ev_code < 0:
            ist[I_AT_EVENT] = 0
            for i in range(n):
                y[i] = y_new[i]
                f[i] = K[tab.n_stages, i]
            for k in range(gs.shape[1]):
                gs[0, k] = gs[N_MARGIN_SAMPLES, k]
                if gs[0, k] < 0.0:
                    # A margin that the step's end leaves below zero (a root on the step's end,
                    # by rounding on its far side) would never be seen falling: the next step
                    # settles the modes first (_settle_modes).
                    ist[I_F_VALID] = 0
            if angle_mode and at_segment_end and x_end == up:
                _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
                if _at_breakpoint(m, bp, y, sw, evbuf, ist, wk):
                    ist[I_F_VALID] = 0
            elif redo_hit_breakpoint:
                fst[F_PASSED_BP] = fst[F_REDO_LEVEL]
                _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
                if _at_breakpoint(m, bp, y, sw, evbuf, ist, wk):
                    ist[I_F_VALID] = 0
            if angle_mode and at_segment_end and x_end == cfg[C_PHI_END]:
                return _finish(m, y, sel, sw, outbuf, evbuf, ist, fst, wk)
            if not angle_mode and at_segment_end and x_end == cfg[C_T_END]:
                return _finish(m, y, sel, sw, outbuf, evbuf, ist, fst, wk)
            continue
        # Truncate the step at the event, act on it and restart from there.
        _dense_eval(F, y, ev_theta, y_evt)
        # An event within rounding of the breakpoint the step ends on (a pair whose power changes
        # sign at a pressure corner, a load corner there) is on it: the state goes exactly there
        # and both are recorded (else the next step would take the breakpoint as passed, unseen).
        on_breakpoint = angle_mode and at_segment_end and x_end == up and x_end - x_stop <= tol_end
        if on_breakpoint:
            x_stop = x_end
        y_evt[ix] = x_stop
        if ev_comp >= PAIR_COMP:
            pass  # the margin is zero here to the root finder's accuracy; nothing to put on a level
        elif ev_comp == DEMAND_COMP:
            # the demand onto the limit exactly, by its integrator (a shift of the root finder's
            # accuracy), so that the next step starts on the level and does not cross it again
            y_evt[gov_index(m) + gv.PI_INTEGRAL] -= _event_g(m, angle_mode, y_evt, ev_comp,
                                                             ev_level, sel, sw, wk)
        elif ev_comp != OMEGA:
            y_evt[ev_comp] = ev_level
        elif angle_mode:  # put the speed exactly on the level: K = ½ J ω²
            J = inertia(m, y_evt[PHI], wk)
            y_evt[KINETIC] = 0.5 * J * ev_level * ev_level
        else:
            y_evt[OMEGA] = ev_level
        for i in range(n):
            y[i] = y_evt[i]
        ist[I_F_VALID] = 0
        if on_breakpoint:
            _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
            _at_breakpoint(m, bp, y, sw, evbuf, ist, wk)
        _emit_event(m, evbuf, ist, ev_code, y, wk)
        if ev_code == EV_END:
            return _finish(m, y, sel, sw, outbuf, evbuf, ist, fst, wk)
        if ev_code == EV_REVERSAL and not np.isfinite(cfg[C_T_END]):
            # A run that ends only by revolutions would never end once the shaft stops: report
            # the stall (with what was computed) instead of integrating on.
            _emit_row(m, y, sel, sw, outbuf, ist, fst, wk)
            return STALLED
        if ev_code == EV_REVERSAL and m.n_pairs > 0:
            # At rest the pairs may hold the applied moments; else the modes start afresh.
            if _start_modes(m, y, sel, ist, wk) == LOCKED_STATUS:
                return _locked(m, y, sel, outbuf, evbuf, ist, fst, wk)
        gap = CHATTER_GAP * (1.0 if angle_mode else cfg[C_DT_OUT])
        ist[I_NCHATTER] = ist[I_NCHATTER] + 1 if abs(x_stop - fst[F_LAST_SWITCH]) < gap else 0
        fst[F_LAST_SWITCH] = x_stop
        if ist[I_NCHATTER] >= CHATTER_COUNT:
            ist[I_CHATTER_CODE] = ev_code
            _emit_row(m, y, sel, sw, outbuf, ist, fst, wk)
            return CHATTERING
        ist[I_AT_EVENT] = ev_code + 1
        if ev_code == EV_PAIR_MODE:
            ist[I_MODES] ^= 1 << (ev_comp - PAIR_COMP)
            ist[I_NSWITCH] += 1
            ist[I_FLIPPED] = ev_comp - PAIR_COMP + 1
        elif ev_code == EV_STARTER_CUTOUT:
            ist[I_STARTER_ON] = 0
        elif ev_code == EV_GOVERNOR and ev_comp == DEMAND_COMP:
            ist[I_GOV_BRANCH] = gv.demand_branch(m.gov_par, ev_level, ev_rising)
        elif ev_code == EV_GOVERNOR:
            ist[I_GOV_BRANCH] = governor_branch(m, ev_level, ev_rising)
        elif ev_code == EV_LOAD:
            # past the corner (and past its twin, for a step) in the direction of motion
            ist[I_LOAD_SEG] = load_segment(m, ev_level, ev_rising)
        elif ev_code == EV_GENERATOR:
            ist[I_GEN_LOW] = generator_branch(m, ev_level, ev_rising)
        elif ev_code == EV_SLEEVE_STOP:
            J = inertia(m, y[PHI], wk)
            ist[I_SLEEVE] = _sleeve_stops(m, y, ev_level, speed(J, angle_mode, y))
        elif ev_code == EV_SLEEVE_FREE:
            ist[I_SLEEVE] = gv.FREE
        elif ev_code == EV_TO_TIME:
            _to_time_mode(m, y, ist, wk)
            fst[F_H] = h_next / ev_level
            _reset_output_grid(cfg, ist, fst, y)
        elif ev_code == EV_TO_ANGLE:
            _to_angle_mode(m, y, ist, wk)
            fst[F_H] = h_next * ev_level
            _reset_output_grid(cfg, ist, fst, y)


@kernel(inline="always")
def _carry(fst, f, gs, n_pairs, keep):
    """The derivative ``f`` at the state and the pairs' margins there (``gs[0]``) into the stepper's
    state ``fst`` (``keep``) or back from it (F_DERIV): what a chunk leaves valid, the next takes
    up as it is, so that where chunks end changes nothing in the run."""
    n = f.shape[0]
    for i in range(n):
        if keep:
            fst[F_DERIV + i] = f[i]
        else:
            f[i] = fst[F_DERIV + i]
    for k in range(n_pairs):
        if keep:
            fst[F_DERIV + n + k] = gs[0, k]
        else:
            gs[0, k] = fst[F_DERIV + n + k]


@kernel
def _to_angle_mode(m, y, ist, wk):
    """Crank angle becomes the independent variable; the third state becomes K = ½ J ω²."""
    J = inertia(m, y[PHI], wk)
    y[KINETIC] = 0.5 * J * y[OMEGA] * y[OMEGA]
    ist[I_ANGLE_MODE] = 1


@kernel
def _to_time_mode(m, y, ist, wk):
    """Time becomes the independent variable; the third state becomes ω."""
    J = inertia(m, y[PHI], wk)
    y[OMEGA] = speed(J, True, y)
    ist[I_ANGLE_MODE] = 0


@kernel(inline="always")
def _settle_modes(m, angle_mode, y, sel, sw, wk, gs, ist, evbuf):
    """The pair margins at the start of a step, into ``gs[0]``. The pair whose mode an event has
    just switched sits on its level (margin 0). Any other pair already past its level here (two
    pairs switching within the event location's accuracy) is switched now, so that no step starts
    with a mode against its criterion: the stepper watches a margin only while it is positive."""
    margins_at(m, angle_mode, y, sel, sw, wk)
    flipped = ist[I_FLIPPED] - 1
    ist[I_FLIPPED] = 0
    changed = False
    for k in range(m.n_pairs):
        if k != flipped and wk[WK_G, k] < 0.0:
            sw[SW_MODES] ^= 1 << k
            ist[I_NSWITCH] += 1
            changed = True
            _emit_event(m, evbuf, ist, EV_PAIR_MODE, y, wk)
    if changed:
        margins_at(m, angle_mode, y, sel, sw, wk)
        ist[I_NFEV] += 1
    for k in range(m.n_pairs):
        gs[0, k] = 0.0 if k == flipped else wk[WK_G, k]


@kernel
def _start_modes(m, y, sel, ist, wk):
    """Choose σ and the pair modes afresh (start, speed reversal; time domain); a rounding tie
    that the kernel had to resolve by its rule is counted (``I_NTIES``)."""
    status = choose_modes(m, False, y, sel, ist[:N_SWITCHES], wk)
    if status == AMBIGUOUS or status == NONE_CONSISTENT:
        ist[I_NTIES] += 1
    return status


@kernel
def _locked(m, y, sel, outbuf, evbuf, ist, fst, wk):
    """End a run at rest that the pairs' friction holds (``model.choose_modes``): φ̈ = 0 from here,
    and nothing in the model depends on time explicitly, so the machine stays where it is."""
    _emit_event(m, evbuf, ist, EV_LOCKED, y, wk)
    if fst[F_LAST_T] != y[T] or fst[F_LAST_PHI] != y[PHI] or ist[I_NOUT] == 0:
        _emit_row(m, y, sel, ist[:N_SWITCHES], outbuf, ist, fst, wk)
    return LOCKED


@kernel
def _finish(m, y, sel, sw, outbuf, evbuf, ist, fst, wk):
    """Write the final state as the last sample (unless it already is one, possibly in an
    already drained buffer) and an end event."""
    if fst[F_LAST_T] != y[T] or fst[F_LAST_PHI] != y[PHI]:
        _emit_row(m, y, sel, sw, outbuf, ist, fst, wk)
    if ist[I_NEV] == 0 or evbuf[ist[I_NEV] - 1, 0] != EV_END:
        _emit_event(m, evbuf, ist, EV_END, y, wk)
    return FINISHED
