"""What the stepper (:func:`~transient.core.stepper.advance`) and its Python caller exchange: the settings
``cfg``, the stepper's state kept between chunks (``fst``, ``ist``), the return codes, the event
codes and their names, and the writing of output rows and events into the caller's buffers.

The run is integrated in chunks so that the caller can stream results, show progress and react to
Ctrl-C between them; everything a chunk must hand to the next lives in ``fst`` and ``ist`` at the
indices named here, and where a chunk ends must change nothing in the run (:func:`_carry`). The
layouts are defined once here for the stepper's modules and for ``transient.simulate``, which
fills ``cfg`` and reads the counters.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel

from ..model.forcing import inertia, speed
from ..model.layout import (N_SWITCHES, PHI, SW_DIRECTION, SW_GENERATOR, SW_GOVERNOR, SW_LOAD,
                            SW_LOAD_TABLE, SW_MODES, SW_SLEEVE, SW_STARTER, T, n_state)
from ..model.outputs import output_row, output_row_inline
from ..integrator.rk import _dense_eval

# cfg[...] — settings (float64 array, filled by transient.simulate)
C_RTOL, C_ATOL, C_T_END, C_PHI_END, C_W_LO, C_W_HI, C_DPHI_OUT, C_DT_OUT = range(8)
C_MAX_STEP_PHI, C_MAX_STEP_T, C_CHUNK_STEPS, C_FIXED_STEP = range(8, 12)
N_CFG = 12
# fst[...] — float stepper state kept between chunks
F_H, F_SEL, F_NEXT_OUT, F_LAST_T, F_LAST_PHI, F_PASSED_BP, F_REDO_LEVEL, F_LAST_SWITCH = range(8)
F_ERR_OLD = 8  # the last accepted step's error norm (≥ 1e-4), for the PI step-size control
N_FST = 9
# fst[F_DERIV:F_DERIV + n]: the derivative at y that the last step carried over (FSAL), then the
# pairs' margins there; kept where a chunk ends with them valid (ist[I_F_VALID]). Recomputed at a
# chunk's start instead (with the table piece ahead of the shaft, not the step's), they would make
# the run depend in its last bits on where the output buffer fills, i.e. on the samples per turn.
F_DERIV = N_FST
# ist[...] — integer stepper state kept between chunks
# ist[:N_SWITCHES] are the model's switches (starter, governor branch, pair modes, direction,
# load-schedule segment, generator branch, sleeve on a stop, speed map's interval), passed on as
# ``sw``.
I_STARTER_ON, I_GOV_BRANCH, I_MODES, I_DIRECTION = SW_STARTER, SW_GOVERNOR, SW_MODES, SW_DIRECTION
I_LOAD_SEG, I_GEN_LOW, I_SLEEVE, I_LOAD_TABLE = SW_LOAD, SW_GENERATOR, SW_SLEEVE, SW_LOAD_TABLE
(I_ANGLE_MODE, I_NFEV, I_NSTEPS, I_NREJECT, I_NOUT, I_NEV, I_STARTED, I_F_VALID,
 I_NREDO, I_NCHATTER, I_NSWITCH, I_NTIES, I_FLIPPED, I_CHATTER_CODE, I_AT_EVENT, I_STIFF,
 I_NONSTIFF) = range(N_SWITCHES, N_SWITCHES + 17)
# the last attempt was rejected by the error test; consecutive non-finite attempts; consecutive
# attempts retaken for a crossing that no sample found
I_REJECTED, I_NBAD, I_NUNSEEN = range(N_SWITCHES + 17, N_SWITCHES + 20)
N_IST = N_SWITCHES + 20

#: Most intervals of an output grid one step may span (its samples fit the rows the stepper keeps
#: free in the output buffer).
MAX_OUTPUT_INTERVALS = 256.0

# advance() return codes
RUNNING, FINISHED, FAIL_NONFINITE, FAIL_STEP, STALLED, LOCKED, CHATTERING, STIFF = range(8)
# event codes written to the event buffer as (code, t, phi, omega)
(EV_BREAKPOINT, EV_TO_TIME, EV_TO_ANGLE, EV_STARTER_CUTOUT, EV_REVERSAL, EV_END, EV_GOVERNOR,
 EV_PAIR_MODE, EV_LOCKED, EV_LOAD, EV_GENERATOR, EV_SLEEVE_STOP, EV_SLEEVE_FREE,
 EV_INJECTION, EV_LOAD_KNOT, EV_STUCK, EV_RELEASED) = range(17)
EVENT_NAMES = ("breakpoint", "to_time_domain", "to_angle_domain", "starter_cutout",
               "speed_reversal", "end", "governor_corner", "pair_mode", "locked", "load_schedule",
               "generator_min_speed", "sleeve_stop", "sleeve_free", "injection", "load_table_speed",
               "stuck", "released")


@kernel
def fst_size(m):
    """Length of the float stepper state ``fst``: N_FST, then the carried derivative and margins."""
    return N_FST + n_state(m) + max(m.n_pairs, 1)


@kernel(inline=True)
def _retake(fst, ist, h):
    """The step attempt is computed again with size ``h``, counted as a rejection."""
    fst[F_H] = h
    ist[I_NREJECT] += 1


@kernel(inline=True)
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
        _dense_eval(F, y, (fst[F_NEXT_OUT] - x) / h, tmp)
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
