"""Breakpoints: the shaft angles where a pressure table has a corner or a jump, or a cylinder
starts its injection or closes its intake. The right-hand side is smooth only between them, so
the stepper ends a segment on each: in crank angle a step stops on the next one exactly; in time
a step that would cross one is retaken so that it ends on it (:func:`_aim_at_breakpoint`). On a
breakpoint the state may change (a cylinder latches its fuel, or starts its closed part at p_a)
and the derivative carried over from the last step may be stale (:func:`_at_breakpoint`).
"""
from __future__ import annotations

from ..integrator.breakpoints import count_below, next_breakpoint
from ..jit import kernel
from ..model import cylinder as cyl
from ..model.forcing import command, inertia, speed
from ..model.layout import OMEGA, PHI, cyl_index, latch_index
from .events import _crossing, _dense_once, _load_corner
from .io import (
    C_DPHI_OUT,
    C_DT_OUT,
    C_MAX_STEP_PHI,
    C_MAX_STEP_T,
    C_PHI_END,
    C_T_END,
    EV_INJECTION,
    F_PASSED_BP,
    F_REDO_LEVEL,
    I_ANGLE_MODE,
    I_NREDO,
    MAX_OUTPUT_INTERVALS,
    Segment,
    _emit_event,
    _retake,
)

# In time, a breakpoint counts as passed once a step has ended within this angle of it [rad]
# (a retaken step lands on it only to the accuracy of the dense output).
BP_LANDING = 1e-7


@kernel(inline=True)
def _segment_end(m, cfg, bp, angle_mode, ix, x, y, sw, fst):
    """Where the segment of the next step ends, and what bounds that step: a ``Segment`` of
    ``(x_end, up, down, h_max, tol_end, corner)``.

    ``x_end``: the next breakpoint (in crank angle), the end of the run, or a load-schedule corner
    on the independent variable before them (the step lands on it and its event is found there,
    θ = 1; one closer than ``tol_end`` is left to the event search, which finds it at once in the
    next step). ``up``, ``down``: the breakpoints above and below the shaft. ``tol_end``: a step
    that would end within rounding of ``x_end`` ends on it exactly, so that no later step of a
    few ulp is needed (:func:`~transient.core.integrator.breakpoints.next_breakpoint` treats
    such a point as reached).
    """
    here = y[PHI]
    if not angle_mode and abs(here - fst[F_PASSED_BP]) <= BP_LANDING:
        here = fst[F_PASSED_BP]  # just landed on it: look beyond it, both ways
    up = next_breakpoint(bp, m.period, here, True)
    down = next_breakpoint(bp, m.period, here, False)
    if angle_mode:
        x_end = min(up, cfg[C_PHI_END])
        h_max = min(cfg[C_MAX_STEP_PHI], MAX_OUTPUT_INTERVALS * cfg[C_DPHI_OUT])
    else:
        x_end = cfg[C_T_END]
        h_max = min(cfg[C_MAX_STEP_T], MAX_OUTPUT_INTERVALS * cfg[C_DT_OUT])
    tol_end = 1e-13 * max(1.0, abs(x))
    corner = _load_corner(m, ix, sw)
    if tol_end < corner - x and corner < x_end:
        x_end = corner
    return Segment(x_end, up, down, h_max, tol_end, corner)


@kernel(inline=True)
def _aim_at_breakpoint(tab, m, extras, at, y, work, fst, ist, seg, min_step):
    """In time, a step must not cross a breakpoint: one that does is retaken so that it ends
    there, at most four times in a row. Returns ``(retake, dense_ready)``: whether the step is
    to be computed again (``fst[F_H]`` set), and whether its dense output is in F."""
    if at.angle_mode:
        return False, False
    y_new, h = work.y_new, at.h
    if y_new[PHI] > seg.up or y_new[PHI] < seg.down:
        _dense_once(False, tab, m, extras, at, y, work, ist)
        level = seg.up if y_new[PHI] > seg.up else seg.down
        theta = _crossing(m, extras, at.angle_mode, work.F, y, y_new, PHI, level, at.sel, at.sw,
                          work.tmp, work.wk)
        fst[F_REDO_LEVEL] = level
        if theta * h > min_step and ist[I_NREDO] < 4:
            _retake(fst, ist, theta * h)
            ist[I_NREDO] += 1
            return True, True
        return False, True
    if 0 < ist[I_NREDO] < 4:
        # A retaken step lands on the breakpoint only to the accuracy of the dense output it was
        # aimed with (at loose tolerances, up to ~1e-3 rad short): lengthen it by the time the
        # rest of the angle takes at the speed reached (a secant step), rather than leaving a
        # sliver that the next step would cross and retake again.
        short = fst[F_REDO_LEVEL] - y_new[PHI]
        rest = short / y_new[OMEGA] if y_new[OMEGA] != 0.0 else -1.0
        if abs(short) > BP_LANDING and 0.0 < rest < h:
            _retake(fst, ist, h + rest)
            ist[I_NREDO] += 1
            return True, False
    return False, False


@kernel(inline=True)
def _on_angle(phi, angle, period):
    """Whether the shaft angle phi is on ``angle`` of the cycle (to BP_LANDING)."""
    d = (phi - angle) % period
    return min(d, period - d) <= BP_LANDING


@kernel
def _jumps_at(m, bp, phi):
    """Whether a pressure jumps at a breakpoint the shaft is on (``Model.bp_jump``): the
    derivative carried over from the step that ended there (FSAL) used the piece before it.
    Only the breakpoints near φ in its cycle (and across the cycle's ends) are looked at."""
    y = phi % m.period
    reach = 2.0 * BP_LANDING  # (wider than _on_angle's test, which decides)
    for shift in (-m.period, 0.0, m.period):
        c = y + shift
        j = count_below(bp, 0.0, c - reach, False)
        while j < bp.shape[0] and bp[j] <= c + reach:
            if m.bp_jump[j] and _on_angle(phi, bp[j], m.period):
                return True
            j += 1
    return False


@kernel
def _inject(m, extras, y, sw, evbuf, ist, wk):
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
            y[c + k] = command(m, extras, w, y, sw)
            hit = True
            _emit_event(m, evbuf, ist, EV_INJECTION, y, wk)
    return hit


@kernel
def _close_intake(m, y):
    """At a breakpoint: each cylinder whose pressure state restarts here (its intake closing;
    on an elastic line the middle of its open part, ``cylinder.RESTART``) is set to p_a
    (``m.woschni``, :mod:`~transient.core.model.cylinder`). Returns whether any did (the derivative at y changes)."""
    if not m.woschni:
        return False
    c = cyl_index(m)
    hit = False
    for k in range(m.ncyl):
        if _on_angle(y[PHI], m.gas_phase[k] + m.cyl_par[cyl.RESTART], m.period):
            y[c + k] = m.cyl_par[cyl.P_A]
            hit = True
    return hit


@kernel
def _at_breakpoint(m, extras, bp, y, sw, evbuf, ist, wk):
    """What a breakpoint does to the state (injections, intake closings); returns whether the
    derivative carried over from the last step (FSAL) is stale: the state changed, or a pressure
    jumps here."""
    injected = closed = False
    if extras is not None:
        injected = _inject(m, extras, y, sw, evbuf, ist, wk)
        closed = _close_intake(m, y)
    return injected or closed or _jumps_at(m, bp, y[PHI])
