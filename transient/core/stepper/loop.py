"""The compiled stepper: an embedded Runge–Kutta pair with dense output, driven segment by segment
between breakpoints, with state events located on the dense output (docs/theory.md, Steppers;
Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.6 and §II.10).

One loop for every method in :mod:`~transient.core.integrator.tableaus` (DOP853, DOPRI5, and
the Rosenbrock–W ROS34PW2 with the shaft line's Jacobian, a compile-time choice), passed as
data; adaptive, or with
fixed crank-angle steps (``cfg[C_FIXED_STEP] > 0``: no error control, for periodic steady runs).
While ω ≥ ω_lo it integrates in crank angle (dt/dφ = 1/ω) and stops exactly on every breakpoint,
so the right-hand side is smooth inside every step; below ω_lo (start from rest, stall, reversal)
it integrates in time, and a step that would cross a breakpoint is retaken so that it ends on it
(:mod:`~transient.core.stepper.breakpoints`). The events (:mod:`.events`) truncate the step
they fall in; acting on one changes the switches, the state or the independent variable
(:func:`_switch_at_event`).

Each turn of the loop in :func:`advance` is: the segment's end
(:func:`.breakpoints._segment_end`) and the step size (:func:`_step_size`), a step attempt
(:func:`_start_attempt`, the step, :func:`_judge_attempt`; with reaction friction, retaken at
once to end on a side force's change of side that its stages show where it fails the error
test, ``joint_friction``), its acceptance or rejection and the next step size, the retake for a
breakpoint crossed in time, the event location (:func:`.events._locate_events`), the output
samples inside the step (:func:`_emit_step_samples`), and either the step taken whole
(:func:`_take_step`) or the state moved to the event and the event acted on
(:func:`_move_to_event`, :func:`_record_event`, :func:`_switch_at_event`).

:func:`advance` runs until the run ends, an output buffer fills or a step budget is used, so that
the Python caller can stream results, show progress and react to Ctrl-C between chunks
(:mod:`~transient.core.stepper.io`).

One idea, the loop of a run: the steps, their retakes and the events acted on, in one module
because LLVM inlines its pieces into :func:`advance` and they share its bookkeeping; the
numerics of a step are the integrator's, locating an event is :mod:`.events`.

Every function here is a compile unit of its own (:func:`transient.core.jit.kernel`). The pieces of the loop,
and the helpers called once per step or per root-finding iteration that take the Model, are
inlined by LLVM (``kernel(inline=True)``) at each call site: a call that is not inlined copies
the Model's ~150 flattened words onto the stack. Calls that run rarely, or whose callee is too
large to copy at several sites (the dense output, the margins, the output row), stay calls. The
margins and the output row are inlined at one site each, into a small function: the margins
into the root finder, whose iterations evaluate them most (``rhs.margins_inline``), the output
row into the writing of the grid's samples (``outputs.output_row_inline``).

The kernels on a path from :func:`advance` to a feature that only some scenes use take the
argument ``extras`` (:func:`~transient.core.model.layout.extras_of`) and test it where the feature's code begins, so
that a plain scene's compile leaves that code out. The time-domain phase is in both variants: a
scene of either may need it at any point of a run (a start from rest, a load that slows the shaft
below the switch speed, a reversal).
"""
from __future__ import annotations

import numpy as np

from ..integrator.rk import accepted_size, dense_eval, error_norm, shrink, stiffness
from ..integrator.rosenbrock import is_w_method, method_step
from ..jit import compiled, kernel
from ..model import governor as gv
from ..model import stuck as st
from ..model.chain import AMBIGUOUS, NONE_CONSISTENT
from ..model.chain import LOCKED as LOCKED_STATUS
from ..model.forcing import (
    generator_branch,
    governor_branch,
    inertia,
    load_segment,
    moments,
    speed,
    speed_knot_segment,
    start_branch,
)
from ..model.layout import (
    KINETIC,
    N_SWITCHES,
    OMEGA,
    PHI,
    SW_DIRECTION,
    SW_MODES,
    WK_DEMAND,
    WK_G,
    WK_G_MIN,
    WK_SPEED,
    T,
    gov_index,
    line_dofs,
    n_margins,
    state_control,
)
from ..model.line_jacobian import line_band, model_jacobian
from ..model.rhs import (
    choose_modes,
    derivative,
    kink_in_attempt,
    margins_at,
    model_rhs,
    release,
    reset_kinks,
    watches_kinks,
)
from ..model.work import work_array
from .breakpoints import AHEAD, _aim_at_breakpoint, _at_breakpoint, _segment_end
from .events import (
    DEMAND_COMP,
    MAX_UNSEEN,
    N_MARGIN_SAMPLES,
    PAIR_COMP,
    _dense_once,
    _event_g,
    _locate_events,
    _root,
    _sleeve_stops,
)
from .io import (
    C_ATOL,
    C_CHUNK_STEPS,
    C_DPHI_OUT,
    C_DT_OUT,
    C_FIXED_STEP,
    C_PHI_END,
    C_RTOL,
    C_STIFF_SWITCH,
    C_T_END,
    C_W_HI,
    CHATTERING,
    EV_BREAKPOINT,
    EV_END,
    EV_GENERATOR,
    EV_GOVERNOR,
    EV_LOAD,
    EV_LOAD_KNOT,
    EV_PAIR_MODE,
    EV_RELEASED,
    EV_REVERSAL,
    EV_SLEEVE_FREE,
    EV_SLEEVE_STOP,
    EV_STARTER_CUTOUT,
    EV_STUCK,
    EV_TO_ANGLE,
    EV_TO_TIME,
    F_ERR_OLD,
    F_H,
    F_LAST_PHI,
    F_LAST_SWITCH,
    F_LAST_T,
    F_NEXT_OUT,
    F_PASSED_BP,
    F_REDO_LEVEL,
    F_SEL,
    FAIL_NONFINITE,
    FAIL_STEP,
    I_ANGLE_MODE,
    I_AT_EVENT,
    I_CHATTER_CODE,
    I_DIRECTION,
    I_F_VALID,
    I_FLIPPED,
    I_GEN_LOW,
    I_GOV_BRANCH,
    I_LOAD_SEG,
    I_LOAD_TABLE,
    I_MODES,
    I_NBAD,
    I_NCHATTER,
    I_NEV,
    I_NFEV,
    I_NONSTIFF,
    I_NOUT,
    I_NREDO,
    I_NREJECT,
    I_NSTEPS,
    I_NSTIFF_STEPS,
    I_NSWITCH,
    I_NTIES,
    I_NUNSEEN,
    I_REJECTED,
    I_SLEEVE,
    I_STARTED,
    I_STARTER_ON,
    I_STIFF,
    MAX_OUTPUT_INTERVALS,
    RUNNING,
    STALLED,
    STIFF,
    At,
    Chunk,
    Work,
    _carry,
    _emit_event,
    _emit_new_row,
    _emit_row,
    _emit_samples,
    _finish,
    _locked,
    _reset_output_grid,
    _retake,
)

# Hairer's stiffness test (dop853.f, dopri5.f): this many accepted steps with hλ beyond the
# tableau's bound, not interrupted by as many as NONSTIFF_RESET within it, mean that stability,
# not accuracy, sets the step: the problem is stiff for an explicit method.
STIFF_COUNT, NONSTIFF_RESET = 15, 6
# State events closer together than this (rad in crank angle; × the output spacing in time) count
# as no progress; this many in a row is chattering, which is reported, never looped on.
CHATTER_GAP, CHATTER_COUNT = 1e-9, 50
# A rejected step whose stages show a side force changing side after this fraction of it is
# retaken to end there (reaction friction: the kink of μ|N|); nearer its start, shrunk as usual.
MIN_KINK_FRACTION = 0.05


def buffers(m, tab, n: int) -> Work:
    """The work arrays of one call of :func:`advance`, its last argument (a ``Work``): the
    stages ``K``, the dense output ``F``, the derivative ``f``, three states, the right-hand
    side's scratch ``wk``, the pairs' margins over a step ``gs`` and the state's error control
    ``control`` (:func:`~transient.core.model.layout.state_control`), and for a W-method the
    storage of its band over the shaft line's states (:func:`.line_jacobian.line_band`).
    Allocated by the caller, so that the stepper is one compile unit of its own, without
    reference counting; the work array by ``work_array``'s Python (compiled for a call from
    Python, once a run, it would cost a first run a compile of its own). ``n``: the length of
    the state."""
    band = None
    if is_w_method(tab):
        rows, kb = line_band(m.line)
        band = np.zeros((rows, 2 * kb + 1))
    return Work(np.empty((tab.n_ext, n)), np.empty((3 + tab.D.shape[0], n)), np.empty(n),
                np.empty(n), np.empty(n), np.empty(n), getattr(work_array, "py_func", work_array)(m),
                np.zeros((N_MARGIN_SAMPLES + 1, max(n_margins(m), 1))), state_control(m), band)


@compiled(nogil=True, _nrt=False)  # (nogil: the previous block is written meanwhile, simulate)
def advance(m, extras, tab, cfg, bp, y, fst, ist, outbuf, evbuf, work):
    """Integrate until the run ends, a buffer fills or the chunk's step budget is used.

    Parameters
    ----------
    m : Model
    extras : None or True
        The kernels' variant for ``m`` (:func:`~transient.core.model.layout.extras_of`): None
        compiles none of the features a plain scene does not use.
    tab : tableaus.Tableau or rosenbrock.WTableau
        The Runge–Kutta pair (DOP853, DOPRI5) or the W-method (ROS34PW2), whose step takes
        ``work.band``.
    cfg : float64[N_CFG]
        Settings, indices ``C_*`` (:mod:`~transient.core.stepper.io`, as the other layouts and
        codes).
    bp : float64[:]
        Sorted breakpoints in [0, m.period).
    y : float64[layout.n_state(m)]
        State, updated in place.
    fst, ist : float64[fst_size(m)], int64[N_IST]
        Stepper state kept between calls (zeros before the first call, except
        ``fst[F_PASSED_BP] = nan`` and ``ist[I_STARTER_ON]``).
    outbuf : float64[nbuf, layout.n_outputs(m)]
        Output samples; ``ist[I_NOUT]`` rows are filled (the caller resets it after draining).
    evbuf : float64[nev, 4]
        Events (code, t, φ, ω); ``ist[I_NEV]`` rows filled.
    work : io.Work
        Work arrays, fresh for each call (:func:`buffers`).

    Returns
    -------
    int
        RUNNING, FINISHED, FAIL_NONFINITE, FAIL_STEP, STALLED (the speed reached zero in a run
        that ends only by revolutions), LOCKED (at rest, the friction of the non-ideal pairs holds
        the applied moments and the machine cannot be stuck instead, :func:`_stick`),
        CHATTERING (pair modes switching without progress) or STIFF (Hairer's stiffness test
        fired).
    """
    io = Chunk(cfg, bp, fst, ist, outbuf, evbuf)
    K, f, y_new, tmp, wk, gs = work.K, work.f, work.y_new, work.tmp, work.wk, work.gs
    rtol = cfg[C_RTOL]
    atol = cfg[C_ATOL]
    # rows kept free: a step spans at most 256 intervals of its grid (in time, of each grid)
    margin = 600

    if ist[I_STARTED] == 0:
        status = _start_run(m, extras, io, y, wk)
        if status != RUNNING:
            return status
    # As the last chunk left them: its derivative and margins (F_DERIV), if valid, and the
    # counters of the retaken attempts; kept again where this chunk ends.
    if ist[I_F_VALID] == 1:
        _carry(fst, f, gs, n_margins(m), False)
    n_bad = ist[I_NBAD]  # consecutive non-finite step attempts
    n_unseen = ist[I_NUNSEEN]  # consecutive attempts retaken for a crossing no sample found
    rejected = ist[I_REJECTED] == 1  # the last attempt was rejected by the error test
    steps_here = 0
    while True:
        if (ist[I_NOUT] + margin >= outbuf.shape[0] or ist[I_NEV] + 8 >= evbuf.shape[0]
                or steps_here >= cfg[C_CHUNK_STEPS]):
            _leave_chunk(n_margins(m), f, gs, fst, ist, n_bad, n_unseen, rejected)
            return RUNNING
        angle_mode = ist[I_ANGLE_MODE] == 1
        sw = ist[:N_SWITCHES]
        ix = PHI if angle_mode else T
        x = y[ix]
        if not angle_mode and y[OMEGA] < 0.0 and not np.isfinite(cfg[C_T_END]):
            # A run that ends only by revolutions, turning backwards (from rest, or given a
            # negative speed), would never reach them: report it as a stall, with what was
            # computed, instead of integrating on.
            _emit_row(m, extras, y, fst[F_SEL], sw, outbuf, ist, fst, wk)
            return STALLED
        if ist[I_F_VALID] == 0:
            # The derivative and the pairs' margins afresh.
            ahead = _settle_at_restart(m, extras, angle_mode, y, sw, wk, gs, ist, evbuf)
            derivative(m, extras, angle_mode, y, ahead, sw, wk, f)
            _restarted(cfg, angle_mode, fst, ist)

        # The segment and the step size.
        seg = _segment_end(m, cfg, bp, angle_mode, ix, x, y, f, sw, fst)
        if seg.x_end - x <= seg.tol_end:
            return _finish(m, extras, y, fst[F_SEL], sw, outbuf, evbuf, ist, fst, wk)
        fixed = angle_mode and cfg[C_FIXED_STEP] > 0.0
        h, h_planned, at_segment_end = _step_size(cfg, fst, fixed, x, seg.x_end, seg.h_max,
                                                  seg.tol_end)
        min_step = 10.0 * (np.nextafter(abs(x), np.inf) - abs(x))
        if h < min_step:
            return FAIL_STEP
        if angle_mode:
            sel = x + 0.5 * h
        else:
            sel = y[PHI] + 0.5 * h * y[OMEGA]

        # The step attempt, its acceptance and the next step size. (The model's hooks for a kink
        # are the full variant's: a plain scene's compile leaves them out.)
        retakes_at_kinks = False
        if extras is not None:
            retakes_at_kinks = watches_kinks(m, extras, angle_mode) and not fixed
        on_corner = at_segment_end and seg.x_end == seg.corner
        cut = at_segment_end
        for attempt in range(2):
            if extras is not None and retakes_at_kinks:
                reset_kinks(m, extras, wk)
            _start_attempt(f, K, wk)
            method_step(tab, model_rhs, model_jacobian, (m, extras, angle_mode, sel, sw, wk), ix,
                        x, y, f, h, K, y_new, tmp, work.band)
            finite, err, seen = _judge_attempt(tab, m, ix, h, y, work, ist, rtol, atol, on_corner,
                                               seg.corner)
            if extras is None or attempt > 0 or not (retakes_at_kinks and finite and err > 1.0):
                break
            # A kink of the derivative inside the step (the model's hook: a side force changing
            # side, the kink of the pistons' μ|N|): the step is retaken at once to end where the
            # stages put it, so that the kink lies between two steps instead of inside a run of
            # rejected ones.
            x_kink = kink_in_attempt(m, extras, wk)
            if not x + MIN_KINK_FRACTION * h < x_kink < x + h:
                break
            ist[I_NREJECT] += 1
            ist[I_NREDO] = 0  # (as for a rejection: no longer ends where a retake aimed)
            h = x_kink - x
            sel = x + 0.5 * h
            at_segment_end = on_corner = False
            cut = True  # sized afterwards as a step cut short for a breakpoint
        if not finite:
            # A trial step may leave the physical region (K < 0 in a stage): shrink it; only a
            # non-finite value that persists at small steps is a failure.
            n_bad += 1
            if n_bad > 30:
                return FAIL_NONFINITE
            _retake(fst, ist, 0.2 * h)
            steps_here += 1
            continue
        n_bad = 0
        if fixed:
            err = 0.0  # every step is accepted; the step size alone sets the accuracy
        if err > 1.0:
            _retake(fst, ist, h * shrink(tab, err))
            ist[I_NREDO] = 0  # a shorter step no longer ends on the breakpoint it aimed at
            steps_here += 1
            rejected = True
            continue
        h_next, fst[F_ERR_OLD] = accepted_size(tab, err, fst[F_ERR_OLD], h, h_planned, cut,
                                               rejected)
        rejected = False
        # (a W-method's tableau has no stability bound to test)
        if (not fixed and tab.stiff_bound < np.inf
                and _stiff(tab, K, h, y, ix, work.control, rtol, atol, ist)):
            if line_dofs(m) == 0:
                # the run so far is kept; the state is the accepted step's start
                if fst[F_LAST_T] != y[T] or fst[F_LAST_PHI] != y[PHI]:
                    _emit_row(m, extras, y, fst[F_SEL], sw, outbuf, ist, fst, wk)
                return STIFF
            # An elastic line's stiff sections hold the step by stability: counted for the hint
            # to take the W-method, or (``solver.method = "auto"``) the caller goes on with it
            # from this step's start, which is left as a chunk's end leaves it.
            ist[I_NSTIFF_STEPS] += 1
            if cfg[C_STIFF_SWITCH] > 0.0:
                _leave_chunk(n_margins(m), f, gs, fst, ist, n_bad, n_unseen, rejected)
                return STIFF
        if not angle_mode and abs(y_new[PHI] - y[PHI]) > MAX_OUTPUT_INTERVALS * cfg[C_DPHI_OUT]:
            # (a step in time writes a sample at each crossing of the angle grid: no more of
            # them than a step in crank angle writes)
            _retake(fst, ist, 0.5 * h)
            steps_here += 1
            continue
        at = At(angle_mode, ix, x, h, sel, sw)
        retake, dense_ready = _aim_at_breakpoint(tab, m, extras, at, y, work, fst, ist, seg,
                                                 min_step)
        if retake:
            steps_here += 1
            continue
        redo_hit_breakpoint = ist[I_NREDO] > 0 or dense_ready
        ist[I_NREDO] = 0
        # (on an elastic line the breakpoints on each dof's own angle, in either domain)
        retake, dense_ready = m.line_retake(tab, m, extras, at, y, work, fst, ist, min_step,
                                            dense_ready)
        if retake:
            steps_here += 1
            continue

        # State events on this step: the earliest one truncates it.
        ev_code, ev_theta, ev_comp, ev_level, ev_rising, unseen, dense_ready = _locate_events(
            tab, m, extras, cfg, at, y, work, ist, seen, dense_ready)
        if unseen and ev_code < 0 and n_unseen < MAX_UNSEEN:
            _retake(fst, ist, 0.5 * h)  # computed again, shorter
            n_unseen += 1
            steps_here += 1
            continue
        n_unseen = 0
        x_stop = x + h if ev_code < 0 else x + ev_theta * h
        _emit_step_samples(tab, m, extras, io, at, x_stop, y, work, dense_ready)
        ist[I_NSTEPS] += 1
        steps_here += 1
        fst[F_H] = h_next
        fst[F_SEL] = sel
        if ev_code < 0:
            status = _take_step(tab, m, extras, io, at, seg, at_segment_end, redo_hit_breakpoint, y,
                                work)
            if status != RUNNING:
                return status
            continue

        # Truncate the step at the event, act on it and restart from there.
        if extras is not None and ev_code == EV_PAIR_MODE and ist[I_DIRECTION] == st.STUCK:
            ev_code = EV_RELEASED  # (the holding margin, in pair 0's slot, fell to zero)
        x_stop, on_breakpoint = _move_to_event(m, extras, at, seg, at_segment_end, x_stop,
                                               (ev_theta, ev_comp, ev_level), y, work, io)
        status = _record_event(m, extras, io, angle_mode, on_breakpoint, x_stop, ev_code, y, sel,
                               sw, wk)
        if status != RUNNING:
            return status
        _switch_at_event(m, extras, io, angle_mode, (ev_code, ev_comp, ev_level, ev_rising),
                         h_next, y, wk)


@kernel(inline=True)
def _leave_chunk(n_pairs, f, gs, fst, ist, n_bad, n_unseen, rejected):
    """What a chunk leaves for the next: the derivative and the margins at the state, and the
    counters of the retaken attempts, so that where a chunk ends changes nothing in the run."""
    _carry(fst, f, gs, n_pairs, True)
    ist[I_NBAD], ist[I_NUNSEEN], ist[I_REJECTED] = n_bad, n_unseen, rejected


@kernel(inline=True)
def _start_run(m, extras, io, y, wk):
    """The first chunk's start: the switches chosen at the initial state, the independent
    variable, the output grid and the first row. Returns RUNNING, or LOCKED where the pairs'
    friction holds the machine at rest."""
    cfg, fst, ist, outbuf, evbuf = io.cfg, io.fst, io.ist, io.outbuf, io.evbuf
    ist[I_STARTED] = 1
    fst[F_ERR_OLD] = 1e-4
    ist[I_GOV_BRANCH] = start_branch(m, extras, y[OMEGA], y)
    # (time only increases; the shaft angle as ω's sign says, forward from rest)
    ist[I_LOAD_SEG] = load_segment(m, y[m.load_comp], m.load_comp == T or y[OMEGA] >= 0.0)
    ist[I_GEN_LOW] = generator_branch(m, y[OMEGA], True)
    ist[I_LOAD_TABLE] = 0  # (the interval of a load tabulated against speed; none else)
    if extras is not None:
        ist[I_LOAD_TABLE] = speed_knot_segment(m, y[OMEGA], True)
        if ist[I_LOAD_TABLE] != speed_knot_segment(m, y[OMEGA], False):
            # On a speed map's knot the interval is the one the speed moves into (else the
            # knot it leaves by would not be watched): the sign of ε from the moments, the
            # pairs' losses left out (they do not change the sign of a net moment that decides
            # a tie).
            J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, False, y, y[PHI],
                                                         ist[:N_SWITCHES], wk, True)
            rising = M_gas + M_load + M_starter - 0.5 * dJ * w * w >= 0.0
            ist[I_LOAD_TABLE] = speed_knot_segment(m, y[OMEGA], rising)
    fst[F_LAST_SWITCH] = np.nan
    if (_start_modes(m, extras, y, y[PHI], ist, wk) == LOCKED_STATUS
            and not _stick(m, extras, cfg, y, evbuf, ist, wk)):
        return _locked(m, extras, y, y[PHI], outbuf, evbuf, ist, fst, wk)
    if y[OMEGA] >= cfg[C_W_HI]:
        _to_angle_mode(m, y, ist, wk)
    fst[F_SEL] = y[PHI]
    _reset_output_grid(cfg, ist, fst, y)
    _emit_row(m, extras, y, fst[F_SEL], ist[:N_SWITCHES], outbuf, ist, fst, wk)
    return RUNNING


@kernel(inline=True)
def _settle_at_restart(m, extras, angle_mode, y, sw, wk, gs, ist, evbuf):
    """Where the step before did not leave the derivative and the margins valid (a start, an
    event, a breakpoint that changes the state or where a pressure jumps): the pairs' margins
    ``gs[0]`` at the state, with the modes settled; returns the angle that picks the table pieces
    for the derivative there."""
    # (the table piece just ahead in the direction of motion: on a breakpoint, rounding of the
    # shaft angle must not pick the piece behind it)
    ahead = y[PHI] + (AHEAD if angle_mode or y[OMEGA] >= 0.0 else -AHEAD)
    if extras is not None and m.n_pairs > 0:
        _settle_modes(m, extras, angle_mode, y, ahead, sw, wk, gs, ist, evbuf)
        ist[I_NFEV] += 1
    return ahead


@kernel(inline=True)
def _restarted(cfg, angle_mode, fst, ist):
    """The derivative at the state is valid again; the first step's size if none is set."""
    ist[I_NFEV] += 1
    ist[I_F_VALID] = 1
    if fst[F_H] <= 0.0:
        # Initial step: a fixed fraction of a revolution (angle) or of the output spacing.
        fst[F_H] = 0.05 if angle_mode else 0.05 * cfg[C_DT_OUT]


@kernel(inline=True)
def _step_size(cfg, fst, fixed, x, x_end, h_max, tol_end):
    """The size of the next attempt, the size planned before a cut to the segment's end, and
    whether the attempt ends on the segment's end: ``(h, h_planned, at_segment_end)``."""
    h = cfg[C_FIXED_STEP] if fixed else min(fst[F_H], h_max)
    h_planned = h
    at_segment_end = False
    if x + h >= x_end - tol_end:
        h = x_end - x
        at_segment_end = True
    return h, h_planned, at_segment_end


@kernel(inline=True)
def _start_attempt(f, K, wk):
    """Before a step attempt: its first stage is the derivative carried over, and the ranges
    its stages record (the margins' least values, the speed's and the PI demand's ranges) are
    reset."""
    for i in range(f.shape[0]):
        K[0, i] = f[i]
    wk[WK_G_MIN, :] = np.inf
    wk[WK_SPEED, 0] = np.inf
    wk[WK_SPEED, 1] = -np.inf
    wk[WK_DEMAND, 0] = np.inf
    wk[WK_DEMAND, 1] = -np.inf


@kernel(inline=True)
def _judge_attempt(tab, m, ix, h, y, work, ist, rtol, atol, on_corner, corner):
    """After the step attempt of size h from y (stages in K, new state in y_new): ``(finite, err,
    seen)``, with the pairs' margins at y_new into ``gs[N_MARGIN_SAMPLES]``.

    ``err``: the error norm; ``finite``: it and y_new are finite; ``seen``: what the stages saw,
    (``dip``, ``w_lo``, ``w_hi``): whether some pair's margin reached zero in a stage
    (:func:`.events._locate_events` then samples them), and the speed's range over the stages,
    read before any dense output adds its own stages to it. ``on_corner``: the step ends on a
    load-schedule corner.
    """
    K, y_new, wk, gs = work.K, work.y_new, work.wk, work.gs
    n = y.shape[0]
    if on_corner:
        y_new[ix] = corner  # x + (corner − x) can miss it by an ulp: the event needs g = 0
    w_lo, w_hi = wk[WK_SPEED, 0], wk[WK_SPEED, 1]
    # (the step's last right-hand side is at y_new: WK_G holds the margins there)
    dip = False
    for k in range(n_margins(m)):
        gs[N_MARGIN_SAMPLES, k] = wk[WK_G, k]
        # a margin that starts at or above zero and dips below, or above and reaches it
        g_min = wk[WK_G_MIN, k]
        dip = dip or g_min < 0.0 <= gs[0, k] or g_min <= 0.0 < gs[0, k]
    ist[I_NFEV] += tab.n_stages
    # (tmp and y_evt are free until the step is taken: the estimators' scratch)
    err = error_norm(tab, K, h, y, y_new, rtol, atol, ix, work.control, work.tmp, work.y_evt)
    finite = np.isfinite(err)
    for i in range(n):
        finite = finite and np.isfinite(y_new[i])
    return finite, err, (dip, w_lo, w_hi)


@kernel(inline=True)
def _stiff(tab, K, h, y, ix, control, rtol, atol, ist):
    """Count an accepted step in Hairer's stiffness test (``STIFF_COUNT``); True when stiff."""
    if stiffness(tab, K, h, y, ix, control, rtol, atol) > tab.stiff_bound:
        ist[I_NONSTIFF] = 0
        ist[I_STIFF] += 1
        return ist[I_STIFF] >= STIFF_COUNT
    ist[I_NONSTIFF] += 1
    if ist[I_NONSTIFF] >= NONSTIFF_RESET:
        ist[I_STIFF] = 0
    return False


@kernel(inline=True)
def _emit_step_samples(tab, m, extras, io, at, x_stop, y, work, dense_ready):
    """The output samples inside the step, up to ``x_stop`` (its end, or its event), from the
    dense output: in crank angle the angle grid's; in time the time grid's and the angle grid's
    crossings (:func:`_emit_time_samples`)."""
    cfg, fst, ist, outbuf = io.cfg, io.fst, io.ist, io.outbuf
    F, tmp, wk = work.F, work.tmp, work.wk
    x, h = at.x, at.h
    if at.angle_mode:
        if fst[F_NEXT_OUT] <= x_stop:
            _dense_once(dense_ready, tab, m, extras, at, y, work, ist)
            _emit_samples(m, extras, F, y, x, h, x_stop, at.ix, cfg[C_DPHI_OUT], at.sel, at.sw,
                          outbuf, ist, fst, tmp, wk)
        return
    whole = x_stop == x + h
    if whole and fst[F_NEXT_OUT] > x_stop and not _crosses_level(
            fst[F_LAST_PHI], y[PHI], work.y_new[PHI], cfg[C_DPHI_OUT]):
        return  # (most steps in time: nothing to write, no dense output needed)
    _dense_once(dense_ready, tab, m, extras, at, y, work, ist)
    if whole:
        phi_stop = work.y_new[PHI]
    else:
        dense_eval(F, y, (x_stop - x) / h, tmp)
        phi_stop = tmp[PHI]
    _emit_time_samples(m, extras, F, y, x, h, x_stop, phi_stop, cfg, at.sel, at.sw, outbuf, ist,
                       fst, tmp, wk)


@kernel(inline=True)
def _next_level(last, d, dphi):
    """The first multiple of the angle spacing ``dphi`` beyond the angle ``last`` in the
    direction ``d`` (±1), at least a millionth of the spacing beyond it (``last`` may be a
    multiple computed another way, an ulp off)."""
    k = np.floor(last / dphi) if d > 0.0 else np.ceil(last / dphi)
    level = (k + d) * dphi
    if d * (level - last) <= 1e-6 * dphi:
        level = (k + 2.0 * d) * dphi
    return level


@kernel(inline=True)
def _crosses_level(last, a, b, dphi):
    """Whether the shaft, turning from ``a`` to ``b``, crosses the next multiple of ``dphi``
    beyond the last sample's angle ``last``."""
    d = 1.0 if b >= a else -1.0
    return d * (b - _next_level(last, d, dphi)) >= 0.0


@kernel
def _emit_time_samples(m, extras, F, y, x, h, x_stop, phi_stop, cfg, sel, sw, outbuf, ist, fst, tmp,
                       wk):
    """The time domain's samples inside the last step (from time x, size h) up to ``x_stop``
    (where the shaft is at ``phi_stop``), in time order: the time grid's (spacing
    ``cfg[C_DT_OUT]``), and one wherever the shaft angle crosses a multiple of the angle spacing
    ``cfg[C_DPHI_OUT]``, either way. So a shaft that turns fast in time (backwards, rocking,
    ``domain = "time"``) is sampled at least as densely in angle as one turning forwards in
    crank angle. Inside a step φ is monotone: a reversal is an event, which ends a step."""
    dt, dphi = cfg[C_DT_OUT], cfg[C_DPHI_OUT]
    theta_stop = (x_stop - x) / h
    d = 1.0 if phi_stop >= y[PHI] else -1.0
    level = _next_level(fst[F_LAST_PHI], d, dphi)
    while d * (phi_stop - level) >= 0.0:
        g0 = y[PHI] - level
        if d * g0 < 0.0:  # (a level on the step's start by rounding was passed with it)
            theta = _root(m, extras, False, F, y, PHI, level, sel, sw, tmp, wk, 0.0, theta_stop,
                          g0, phi_stop - level)[0]
            t = x + theta * h
            _emit_samples(m, extras, F, y, x, h, t, T, dt, sel, sw, outbuf, ist, fst, tmp, wk)
            if t > fst[F_LAST_T]:  # (else the time grid's sample is at this instant)
                dense_eval(F, y, theta, tmp)
                tmp[T] = t
                tmp[PHI] = level
                _emit_row(m, extras, tmp, sel, sw, outbuf, ist, fst, wk)
        level = _next_level(level, d, dphi)
    _emit_samples(m, extras, F, y, x, h, x_stop, T, dt, sel, sw, outbuf, ist, fst, tmp, wk)


@kernel(inline=True)
def _take_step(tab, m, extras, io, at, seg, at_segment_end, redo_hit_breakpoint, y, work):
    """The accepted step, without an event in it, becomes the state (with its derivative and
    margins carried over); a breakpoint it ends on acts. Returns RUNNING, or FINISHED where the
    run ends with it."""
    cfg, bp, fst, ist, outbuf, evbuf = io
    y_new, f, K, gs, wk = work.y_new, work.f, work.K, work.gs, work.wk
    angle_mode, sel, sw = at.angle_mode, at.sel, at.sw
    n = y.shape[0]
    ist[I_AT_EVENT] = 0
    stale = m.line_passed(m, extras, y, y_new, sw, evbuf, ist, wk, fst)
    for i in range(n):
        y[i] = y_new[i]
        f[i] = K[tab.n_stages, i]
    for k in range(gs.shape[1]):
        gs[0, k] = gs[N_MARGIN_SAMPLES, k]
        if gs[0, k] < 0.0:
            # A margin that the step's end leaves below zero (a root on the step's end, by
            # rounding on its far side) would never be seen falling: the next step settles the
            # modes first (_settle_modes).
            ist[I_F_VALID] = 0
    if stale:  # (a breakpoint on a dof's own angle changed the state, or a pressure jumps there)
        ist[I_F_VALID] = 0
    if angle_mode and at_segment_end and seg.x_end == seg.up:
        _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
        if _at_breakpoint(m, extras, bp, y, sw, evbuf, ist, wk):
            ist[I_F_VALID] = 0
    elif redo_hit_breakpoint:
        fst[F_PASSED_BP] = fst[F_REDO_LEVEL]
        _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
        if _at_breakpoint(m, extras, bp, y, sw, evbuf, ist, wk):
            ist[I_F_VALID] = 0
    if angle_mode and at_segment_end and seg.x_end == cfg[C_PHI_END]:
        return _finish(m, extras, y, sel, sw, outbuf, evbuf, ist, fst, wk)
    if not angle_mode and at_segment_end and seg.x_end == cfg[C_T_END]:
        return _finish(m, extras, y, sel, sw, outbuf, evbuf, ist, fst, wk)
    return RUNNING


@kernel(inline=True)
def _move_to_event(m, extras, at, seg, at_segment_end, x_stop, crossing, y, work, io):
    """The state at the event (``crossing``: its θ in the step, its component and level; the
    independent variable ``x_stop``), put exactly on the event's level, becomes the state
    (what a breakpoint on a dof's own angle that it reaches does, done).
    Returns ``(x_stop, on_breakpoint)``: an event within rounding of the breakpoint the step ends on (a pair whose
    power changes sign at a pressure corner, a load corner there) is on it, and the state goes
    exactly there, so that both are recorded (else the next step would take the breakpoint as
    passed, unseen)."""
    ev_theta, ev_comp, ev_level = crossing
    angle_mode, sel, sw, wk, y_evt = at.angle_mode, at.sel, at.sw, work.wk, work.y_evt
    fst, ist, evbuf = io.fst, io.ist, io.evbuf
    dense_eval(work.F, y, ev_theta, y_evt)
    ends_on_breakpoint = at_segment_end and seg.x_end == seg.up
    on_breakpoint = angle_mode and ends_on_breakpoint and seg.x_end - x_stop <= seg.tol_end
    if on_breakpoint:
        x_stop = seg.x_end
    y_evt[at.ix] = x_stop
    if ev_comp >= PAIR_COMP:
        pass  # the margin is zero here to the root finder's accuracy; nothing to put on a level
    elif extras is not None and ev_comp == DEMAND_COMP:
        # the demand onto the limit exactly, by its integrator (a shift of the root finder's
        # accuracy), so that the next step starts on the level and does not cross it again
        y_evt[gov_index(m) + gv.PI_INTEGRAL] -= _event_g(m, extras, angle_mode, y_evt, ev_comp,
                                                         ev_level, sel, sw, wk)
    elif ev_comp != OMEGA:
        y_evt[ev_comp] = ev_level
    elif angle_mode:  # put the speed exactly on the level: K = ½ J ω²
        J = inertia(m, y_evt[PHI], wk)
        y_evt[KINETIC] = 0.5 * J * ev_level * ev_level
    else:
        y_evt[OMEGA] = ev_level
    m.line_passed(m, extras, y, y_evt, sw, evbuf, ist, wk, fst)  # (the derivative anew)
    for i in range(y.shape[0]):
        y[i] = y_evt[i]
    ist[I_F_VALID] = 0
    return x_stop, on_breakpoint


@kernel(inline=True)
def _record_event(m, extras, io, angle_mode, on_breakpoint, x_stop, ev_code, y, sel, sw, wk):
    """The event (and a breakpoint it sits on) into the event buffer, and the ends of a run it
    may bring: the end, a stall, the pairs locking at rest, chattering. Returns RUNNING, or the
    code the run ends with."""
    cfg, bp, fst, ist, outbuf, evbuf = io
    if on_breakpoint:
        _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
        _at_breakpoint(m, extras, bp, y, sw, evbuf, ist, wk)
    _emit_event(m, evbuf, ist, ev_code, y, wk)
    if ev_code == EV_END:
        return _finish(m, extras, y, sel, sw, outbuf, evbuf, ist, fst, wk)
    if ev_code == EV_REVERSAL:
        # The turning point (ω = 0) as a sample: the grids' samples rarely fall on it.
        _emit_new_row(m, extras, y, sel, sw, outbuf, ist, fst, wk)
        if not np.isfinite(cfg[C_T_END]):
            # A run that ends only by revolutions would never end once the shaft stops: report
            # the stall (with what was computed) instead of integrating on.
            return STALLED
    if extras is not None and ev_code == EV_REVERSAL and m.n_pairs > 0:
        # At rest the pairs may hold the applied moments; else the modes start afresh.
        if (_start_modes(m, extras, y, sel, ist, wk) == LOCKED_STATUS
                and not _stick(m, extras, cfg, y, evbuf, ist, wk)):
            return _locked(m, extras, y, sel, outbuf, evbuf, ist, fst, wk)
    if extras is not None and ev_code == EV_RELEASED:
        release(m, extras, y, sel, sw, wk)
    gap = CHATTER_GAP * (1.0 if angle_mode else cfg[C_DT_OUT])
    ist[I_NCHATTER] = ist[I_NCHATTER] + 1 if abs(x_stop - fst[F_LAST_SWITCH]) < gap else 0
    fst[F_LAST_SWITCH] = x_stop
    if ist[I_NCHATTER] >= CHATTER_COUNT:
        ist[I_CHATTER_CODE] = ev_code
        _emit_new_row(m, extras, y, sel, sw, outbuf, ist, fst, wk)
        return CHATTERING
    ist[I_AT_EVENT] = ev_code + 1
    return RUNNING


@kernel(inline=True)
def _switch_at_event(m, extras, io, angle_mode, event, h_next, y, wk):
    """What the event switches: a pair's mode, the starter, the governor's branch, the load
    schedule's segment, the generator's branch, the speed map's interval, the sleeve on or off a
    stop, or the independent variable (with the next step's size converted by ω = level and the
    output grid of the new variable). ``event``: (code, component, level, rising)."""
    ev_code, ev_comp, ev_level, ev_rising = event
    cfg, fst, ist = io.cfg, io.fst, io.ist
    if ev_code == EV_PAIR_MODE:
        ist[I_MODES] ^= 1 << (ev_comp - PAIR_COMP)
        ist[I_NSWITCH] += 1
        ist[I_FLIPPED] = ev_comp - PAIR_COMP + 1
    elif ev_code == EV_STARTER_CUTOUT:
        ist[I_STARTER_ON] = 0
    elif extras is not None and ev_code == EV_GOVERNOR and ev_comp == DEMAND_COMP:
        ist[I_GOV_BRANCH] = gv.demand_branch(m.gov_par, ev_level, ev_rising)
    elif ev_code == EV_GOVERNOR:
        ist[I_GOV_BRANCH] = governor_branch(m, ev_level, ev_rising)
    elif ev_code == EV_LOAD:
        # past the corner (and past its twin, for a step) in the direction of motion
        ist[I_LOAD_SEG] = load_segment(m, ev_level, ev_rising)
    elif ev_code == EV_GENERATOR:
        ist[I_GEN_LOW] = generator_branch(m, ev_level, ev_rising)
    elif extras is not None and ev_code == EV_LOAD_KNOT:
        ist[I_LOAD_TABLE] = speed_knot_segment(m, ev_level, ev_rising)
    elif extras is not None and ev_code == EV_SLEEVE_STOP:
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


@kernel
def _to_angle_mode(m, y, ist, wk):
    """Crank angle becomes the independent variable; the third state becomes K = ½ J ω², and
    on an elastic shaft line each dof's speed its K_d (``Model.line_switch``,
    :func:`~transient.core.model.shaft.line_mode`)."""
    J = inertia(m, y[PHI], wk)
    y[KINETIC] = 0.5 * J * y[OMEGA] * y[OMEGA]
    m.line_switch(m, y, True, wk)  # an elastic shaft line's other dofs alike
    ist[I_ANGLE_MODE] = 1


@kernel
def _to_time_mode(m, y, ist, wk):
    """Time becomes the independent variable; the third state becomes ω, and each shaft-line
    dof's K_d its ω_d."""
    J = inertia(m, y[PHI], wk)
    y[OMEGA] = speed(J, True, y)
    m.line_switch(m, y, False, wk)
    ist[I_ANGLE_MODE] = 0


@kernel(inline=True)
def _settle_modes(m, extras, angle_mode, y, sel, sw, wk, gs, ist, evbuf):
    """The pair margins at the start of a step, into ``gs[0]``. The pair whose mode an event has
    just switched sits on its level (margin 0). Any other pair already past its level here (two
    pairs switching within the event location's accuracy) is switched now, so that no step starts
    with a mode against its criterion: the stepper watches a margin only while it is positive."""
    margins_at(m, extras, angle_mode, y, sel, sw, wk)
    if sw[SW_DIRECTION] == st.STUCK and wk[WK_G, 0] < 0.0:
        # stuck, and a jump of the drive (a load step at a corner in time) releases it here
        _emit_event(m, evbuf, ist, EV_RELEASED, y, wk)
        release(m, extras, y, sel, sw, wk)
        margins_at(m, extras, angle_mode, y, sel, sw, wk)
        ist[I_NFEV] += 2
    flipped = ist[I_FLIPPED] - 1
    ist[I_FLIPPED] = 0
    changed = False
    for k in range(n_margins(m)):
        if k != flipped and wk[WK_G, k] < 0.0:
            sw[SW_MODES] ^= 1 << k
            ist[I_NSWITCH] += 1
            changed = True
            _emit_event(m, evbuf, ist, EV_PAIR_MODE, y, wk)
    if changed:
        margins_at(m, extras, angle_mode, y, sel, sw, wk)
        ist[I_NFEV] += 1
    for k in range(n_margins(m)):
        gs[0, k] = 0.0 if k == flipped else wk[WK_G, k]


@kernel
def _stick(m, extras, cfg, y, evbuf, ist, wk):
    """At rest with the pairs holding the applied moments: the machine is stuck (``stuck``) if
    the run ends by time and something can still change the moments, so that the drive may come
    to exceed the friction; returns False where the run is to end *locked* instead (nothing
    would ever release it, or no end in time would end the wait; on an elastic line, whose
    throws have no stuck state of their own)."""
    if (extras is not None and np.isfinite(cfg[C_T_END]) and line_dofs(m) == 0
            and st.can_change(m, y, ist[:N_SWITCHES])):
        ist[I_DIRECTION] = st.STUCK
        ist[I_MODES] = 0
        _emit_event(m, evbuf, ist, EV_STUCK, y, wk)
        return True
    return False


@kernel
def _start_modes(m, extras, y, sel, ist, wk):
    """Choose σ and the pair modes afresh (start, speed reversal; time domain); a rounding tie
    that the kernel had to resolve by its rule is counted (``I_NTIES``)."""
    status = choose_modes(m, extras, False, y, sel, ist[:N_SWITCHES], wk)
    if status == AMBIGUOUS or status == NONE_CONSISTENT:
        ist[I_NTIES] += 1
    return status
