"""What the stepper (:func:`~.loop.advance`) and its Python caller exchange: the settings
``cfg``, the stepper's state kept between chunks (``fst``, ``ist``), the return codes, the event
codes and their names, and the writing of output rows and events into the caller's buffers.

The run is integrated in chunks so that the caller can stream results, show progress and react to
Ctrl-C between them; everything a chunk must hand to the next lives in ``fst`` and ``ist`` at the
indices named here, and where a chunk ends must change nothing in the run (:func:`_carry`). The
layouts are defined once here for the stepper's modules and for ``transient.simulate``, which
fills ``cfg`` and reads the counters.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..declare import Block, Layout, Sized
from ..integrator.rk import dense_eval
from ..jit import kernel
from ..model.forcing import inertia, speed
from ..model.layout import (
    LM_DOFS,
    N_SWITCHES,
    PHI,
    STATE,
    SW_DIRECTION,
    SW_GENERATOR,
    SW_GOVERNOR,
    SW_LOAD,
    SW_LOAD_TABLE,
    SW_MODES,
    SW_SLEEVE,
    SW_STARTER,
    T,
    line_dofs,
    n_margins,
)
from ..model.outputs import output_row, output_row_inline

#: ``cfg``, the run's settings (float64, filled by ``transient.run``): the tolerances, the ends of
#: the run in time and in angle, the switch speeds from crank angle to time and back, the output
#: spacings in angle and in time, the largest steps in angle and in time, the steps a chunk may
#: take, the fixed step in angle (0: adaptive), and whether an elastic line's steps held by
#: stability end the chunk for the caller to go on with the W-method (1: ``solver.method =
#: "auto"``).
SETTINGS = Layout("settings", "rtol", "atol", "t_end", "phi_end", "w_lo", "w_hi", "dphi_out",
                  "dt_out", "max_step_phi", "max_step_t", "chunk_steps", "fixed_step",
                  "stiff_switch")
(C_RTOL, C_ATOL, C_T_END, C_PHI_END, C_W_LO, C_W_HI, C_DPHI_OUT, C_DT_OUT, C_MAX_STEP_PHI,
 C_MAX_STEP_T, C_CHUNK_STEPS, C_FIXED_STEP, C_STIFF_SWITCH) = SETTINGS
N_CFG = SETTINGS.size
#: ``fst``, the float state the stepper keeps between chunks: the next step's size, the angle
#: ``sel`` of the last step (it picks the table pieces), the next output sample on the grid, the
#: time and angle of the last row written, the breakpoint a step in time last landed on, the
#: level a retaken step aims at, where the last state event was (for chattering), the last
#: accepted step's error norm (≥ 1e-4, for the PI step-size control); then the derivative at y
#: that the last step carried over (FSAL), then the pairs' margins there (``F_DERIV``, kept where
#: a chunk ends with them valid, ``ist[I_F_VALID]``: recomputed at a chunk's start instead, with
#: the table piece ahead of the shaft, not the step's, they would make the run depend in its last
#: bits on where the output buffer fills, i.e. on the samples per turn); on an elastic line then
#: the size of the step a retake aims at a breakpoint on a dof's own angle with (0: none), the
#: retakes so aimed in a row, and per dof an angle and its next breakpoint above it
#: (:func:`line_fst`, ``breakpoints._next_up``).
FLOATS = Layout(
    "stepper floats", "h", "sel", "next_out", "last_t", "last_phi", "passed_bp", "redo_level",
    "last_switch", "err_old",
    Block("deriv", Sized(lambda m: STATE.offsets_for(m)[-1], "the state's length"),
          "the carried derivative"),
    Block("margins", Sized(lambda m: max(n_margins(m), 1),
                           "one per pair (per pair and throw on a line), at least one"),
          "the pairs' margins at y"),
    Block("line", Sized(lambda m: 2 + 2 * int(m.line[0, LM_DOFS]) if m.line[0, LM_DOFS] else 0,
                        "on an elastic line two, and two per dof"),
          "the step a retake aims at a dof's breakpoint with, the retakes in a row; per dof "
          "an angle and the next breakpoint above it"),
)
(F_H, F_SEL, F_NEXT_OUT, F_LAST_T, F_LAST_PHI, F_PASSED_BP, F_REDO_LEVEL, F_LAST_SWITCH,
 F_ERR_OLD) = (FLOATS.fixed_offset(n) for n in FLOATS.names[:9])
F_DERIV = FLOATS.fixed_offset("deriv")
N_FST = F_DERIV
#: ``ist``, the integer state the stepper keeps between chunks: first the model's switches
#: (``layout.SWITCHES``, passed on as ``sw = ist[:N_SWITCHES]``), then whether the independent
#: variable is the crank angle; the counters of right-hand sides, steps, rejections, output rows
#: and events written; whether the run has started and whether ``fst[F_DERIV:]`` is valid; the
#: retakes aimed at a breakpoint, the state events in a row without progress (chattering), the
#: pair-mode switches, the rounding ties of a mode choice, the pair an event has just flipped
#: (+1), the event that chattered, the event just acted on (+1), the stiffness test's counts;
#: whether the last attempt was rejected by the error test, the consecutive non-finite attempts,
#: the consecutive attempts retaken for a crossing that no sample found, and the steps of an
#: elastic line's run that the stiffness test found held by stability.
INTS = Layout(
    "stepper ints", Block("switches", N_SWITCHES, "the model's switches (layout.SWITCHES)"),
    "angle_mode", "nfev", "nsteps", "nreject", "nout", "nev", "started", "f_valid", "nredo",
    "nchatter", "nswitch", "nties", "flipped", "chatter_code", "at_event", "stiff", "nonstiff",
    "rejected", "nbad", "nunseen", "nstiff_steps",
)
(I_SWITCHES, I_ANGLE_MODE, I_NFEV, I_NSTEPS, I_NREJECT, I_NOUT, I_NEV, I_STARTED, I_F_VALID,
 I_NREDO, I_NCHATTER, I_NSWITCH, I_NTIES, I_FLIPPED, I_CHATTER_CODE, I_AT_EVENT, I_STIFF,
 I_NONSTIFF, I_REJECTED, I_NBAD, I_NUNSEEN, I_NSTIFF_STEPS) = INTS
N_IST = INTS.size
#: The switches in ``ist``, by their names in the stepper.
(I_STARTER_ON, I_GOV_BRANCH, I_MODES, I_DIRECTION, I_LOAD_SEG, I_GEN_LOW, I_SLEEVE,
 I_LOAD_TABLE) = (I_SWITCHES + sw for sw in (SW_STARTER, SW_GOVERNOR, SW_MODES, SW_DIRECTION,
                                             SW_LOAD, SW_GENERATOR, SW_SLEEVE, SW_LOAD_TABLE))
if I_SWITCHES != 0:  # (the stepper passes ist[:N_SWITCHES] on as the switches)
    raise AssertionError("the switches must lead the stepper's integer state")

#: The loop's arguments, bundled by what they are (numba passes a tuple to an inlined helper
#: for free, and flattened, as its fields, to one that is called). ``Chunk``: what
#: :func:`~transient.core.stepper.loop.advance` exchanges with its caller, the settings, the
#: breakpoints, the float and integer state kept between chunks, the output and event buffers.
#: ``Work``: the work arrays of one call (:func:`~transient.core.stepper.loop.buffers`), the
#: stages, the dense output's coefficients, the derivative at the state, the new state, the
#: state at an event, a scratch state, the right-hand side's work array, the pairs' margins
#: over a step, the error control of each state component (``layout.state_control``) and the
#: storage of a W-method's banded matrix (None for an explicit pair: its step compiles without).
#: ``At``: the step attempt at hand, whether crank angle is the independent
#: variable and its index in the state, the step's start and size, the angle ``sel`` that picks
#: the tables' pieces for it, the switches. ``Segment``: where the segment ends and what bounds
#: the step (:func:`~transient.core.stepper.breakpoints._segment_end`).
Chunk = namedtuple("Chunk", ["cfg", "bp", "fst", "ist", "outbuf", "evbuf"])
Work = namedtuple("Work", ["K", "F", "f", "y_new", "y_evt", "tmp", "wk", "gs", "control",
                           "band"])
At = namedtuple("At", ["angle_mode", "ix", "x", "h", "sel", "sw"])
Segment = namedtuple("Segment", ["x_end", "up", "down", "h_max", "tol_end", "corner"])

#: Most intervals of an output grid one step may span (its samples fit the rows the stepper keeps
#: free in the output buffer).
MAX_OUTPUT_INTERVALS = 256.0

#: What :func:`~transient.core.stepper.loop.advance` returns: the chunk ended with the run going
#: on, the run finished, or how it failed or stopped.
(RUNNING, FINISHED, FAIL_NONFINITE, FAIL_STEP, STALLED, LOCKED, CHATTERING,
 STIFF) = range(8)

#: Every event a run records, in one table: its name (the result file's, ``transient.run``) and
#: what it is. An event's code, written to the event buffer as (code, t, φ, ω) and kept in a
#: checkpoint's integer state (``I_AT_EVENT``, ``I_CHATTER_CODE``), is its place here: a new
#: event goes at the end. Which of them are state events watched on every step, and in what
#: order a tie between two at one instant is broken, is :data:`.events.WATCHED`.
EVENTS = (
    ("breakpoint", "the shaft on a breakpoint of the tables (a step ends there)"),
    ("to_time_domain", "the speed fell below the switch speed: time is the variable"),
    ("to_angle_domain", "the speed rose past 1.5 × the switch speed: crank angle is the variable"),
    ("starter_cutout", "the starter disengaged at its cut-out speed"),
    ("speed_reversal", "ω = 0 in time: the shaft turns back or stops"),
    ("end", "the run's end in time or in angle"),
    ("governor_corner", "a corner of the droop characteristic, or the PI demand at a limit"),
    ("pair_mode", "a non-ideal pair's mode switched (its margin fell to zero)"),
    ("locked", "at rest, held by the pairs' friction for good"),
    ("load_schedule", "a corner of the load schedule"),
    ("generator_min_speed", "the generator's minimum speed"),
    ("sleeve_stop", "the flyweight governor's sleeve reached a stop"),
    ("sleeve_free", "the sleeve left its stop"),
    ("injection", "a cylinder latched its fuel at its start of injection"),
    ("load_table_speed", "a knot of a load tabulated against speed"),
    ("stuck", "at rest, held by the pairs' friction until the drive exceeds it"),
    ("released", "the drive exceeded the friction holding it: moving again"),
)
EVENT_NAMES = tuple(name for name, _ in EVENTS)
(EV_BREAKPOINT, EV_TO_TIME, EV_TO_ANGLE, EV_STARTER_CUTOUT, EV_REVERSAL, EV_END, EV_GOVERNOR,
 EV_PAIR_MODE, EV_LOCKED, EV_LOAD, EV_GENERATOR, EV_SLEEVE_STOP, EV_SLEEVE_FREE,
 EV_INJECTION, EV_LOAD_KNOT, EV_STUCK, EV_RELEASED) = range(len(EVENTS))


def fst_size(m) -> int:
    """Length of the float stepper state ``fst`` of model ``m`` (:data:`FLOATS`)."""
    return FLOATS.offsets_for(m)[-1]


@kernel(inline=True)
def line_fst(m, fst):
    """Index in ``fst`` of an elastic line's block (:data:`FLOATS`): its last, two and two
    per dof."""
    return fst.shape[0] - 2 - 2 * line_dofs(m)


@kernel(inline=True)
def _retake(fst, ist, h):
    """The step attempt is computed again with size ``h``, counted as a rejection."""
    fst[F_H] = h
    ist[I_NREJECT] += 1


@kernel(inline=True)
def _carry(fst, f, gs, n_margins, keep):
    """The derivative ``f`` at the state and the pairs' margins there (``gs[0]``) into the stepper's
    state ``fst`` (``keep``) or back from it (F_DERIV): what a chunk leaves valid, the next takes
    up as it is, so that where chunks end changes nothing in the run."""
    n = f.shape[0]
    for i in range(n):
        if keep:
            fst[F_DERIV + i] = f[i]
        else:
            f[i] = fst[F_DERIV + i]
    for k in range(n_margins):
        if keep:
            fst[F_DERIV + n + k] = gs[0, k]
        else:
            gs[0, k] = fst[F_DERIV + n + k]


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
def _emit_row(m, extras, y, sel, sw, outbuf, ist, fst, wk):
    """One output row at state ``y`` (an event's): a call into ``outputs.output_row``."""
    output_row(m, extras, ist[I_ANGLE_MODE] == 1, y, sel, sw, wk, outbuf[ist[I_NOUT]])
    _count_row(y, ist, fst)


@kernel
def _emit_new_row(m, extras, y, sel, sw, outbuf, ist, fst, wk):
    """:func:`_emit_row` unless the last row is at the time of ``y`` already (a grid's sample
    that fell on an event): the trajectory's time never repeats."""
    if y[T] > fst[F_LAST_T]:
        _emit_row(m, extras, y, sel, sw, outbuf, ist, fst, wk)


@kernel(inline=True)
def _count_row(y, ist, fst):
    """The bookkeeping after a row is written at state ``y``."""
    ist[I_NOUT] += 1
    fst[F_LAST_T] = y[T]
    fst[F_LAST_PHI] = y[PHI]


@kernel
def _emit_samples(m, extras, F, y, x, h, x_stop, ix, d_out, sel, sw, outbuf, ist, fst, tmp, wk):
    """The output samples of the grid (spacing ``d_out``) up to ``x_stop`` inside the last step
    (from x, size h), from its dense output F. A call of its own, with the output row inlined,
    because every other arrangement copies the Model per sample: a call into the output row from
    the stepper's loop copies it (and the loop, with the step inlined, is the costliest place to
    copy it), and a call per sample through ``_emit_row`` copies it twice."""
    angle_mode = ist[I_ANGLE_MODE] == 1
    while fst[F_NEXT_OUT] <= x_stop:
        dense_eval(F, y, (fst[F_NEXT_OUT] - x) / h, tmp)
        tmp[ix] = fst[F_NEXT_OUT]
        output_row_inline(m, extras, angle_mode, tmp, sel, sw, wk, outbuf[ist[I_NOUT]])
        _count_row(tmp, ist, fst)
        fst[F_NEXT_OUT] = np.floor(fst[F_NEXT_OUT] / d_out + 0.5) * d_out + d_out


@kernel(inline=True)
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
def _locked(m, extras, y, sel, outbuf, evbuf, ist, fst, wk):
    """End a run at rest that the pairs' friction holds (``rhs.choose_modes``) where it cannot be
    stuck (``stepper._stick``): φ̈ = 0 from here, and nothing would ever release it, or the run
    has no end in time to wait for it."""
    _emit_event(m, evbuf, ist, EV_LOCKED, y, wk)
    if fst[F_LAST_T] != y[T] or fst[F_LAST_PHI] != y[PHI] or ist[I_NOUT] == 0:
        _emit_row(m, extras, y, sel, ist[:N_SWITCHES], outbuf, ist, fst, wk)
    return LOCKED


@kernel
def _finish(m, extras, y, sel, sw, outbuf, evbuf, ist, fst, wk):
    """Write the final state as the last sample (unless it already is one, possibly in an
    already drained buffer) and an end event."""
    if fst[F_LAST_T] != y[T] or fst[F_LAST_PHI] != y[PHI]:
        _emit_row(m, extras, y, sel, sw, outbuf, ist, fst, wk)
    if ist[I_NEV] == 0 or evbuf[ist[I_NEV] - 1, 0] != EV_END:
        _emit_event(m, evbuf, ist, EV_END, y, wk)
    return FINISHED
