"""Breakpoints: the shaft angles where a pressure table has a corner or a jump, or a cylinder
starts its injection or closes its intake. The right-hand side is smooth only between them, so
the stepper ends a segment on each: in crank angle a step stops on the next one exactly; in time
a step that would cross one is retaken so that it ends on it (:func:`_aim_at_breakpoint`). On a
breakpoint the state may change (a cylinder latches its fuel, or starts its closed part at p_a)
and the derivative carried over from the last step may be stale (:func:`_at_breakpoint`).

On an elastic shaft line the breakpoints of a dof's cylinders are on that dof's own angle
θ_d = φ + q_d, which moves with the twist. They are reached as the time domain's are, by the
same retake: a step that crosses one (the event function θ_d − the breakpoint changes sign) is
retaken to end where its dense output puts the crossing (:func:`_aim_at_dof_breakpoints`); in
crank angle the next step is also aimed at the earliest of them, each predicted from its dof's
rate dθ_d/dφ = 1 + q′_d (:func:`_dof_segment_end`), the reference's exactly. What a breakpoint
does, it does where its own dof reaches it (:func:`_pass_dof_breakpoints`). The Model holds
these three kernels (``LINE_BREAKPOINTS``; a rigid shaft's, whose breakpoints are the shaft's,
``NO_LINE_BREAKPOINTS``, which do nothing), so that a rigid scene's stepper compiles none of
them.
"""
from __future__ import annotations

import numpy as np

from ..integrator.breakpoints import count_below, next_breakpoint, reached
from ..integrator.roots import root
from ..jit import kernel
from ..model import cylinder as cyl
from ..model.forcing import command, inertia, speed
from ..model.layout import LM_REF, OMEGA, PHI, cyl_index, latch_index, line_dofs, line_index
from ..model.shaft import angle_at, dof_angle, dof_breakpoints, line_parts, twist_at
from .events import _crossing, _dense_once, _load_corner
from .io import (
    C_DPHI_OUT,
    C_DT_OUT,
    C_MAX_STEP_PHI,
    C_MAX_STEP_T,
    C_PHI_END,
    C_T_END,
    EV_BREAKPOINT,
    EV_INJECTION,
    F_PASSED_BP,
    F_REDO_LEVEL,
    I_ANGLE_MODE,
    I_NREDO,
    I_NREJECT,
    MAX_OUTPUT_INTERVALS,
    Segment,
    _emit_event,
    _retake,
    line_fst,
)

# In time, a breakpoint counts as passed once a step has ended within this angle of it [rad]
# (a retaken step lands on it only to the accuracy of the dense output).
BP_LANDING = 1e-7
# A fresh derivative is taken this far ahead of the state in the direction of motion [rad], so
# that on a breakpoint it is the next piece's (``loop._settle_at_restart``).
AHEAD = 1e-9
# A breakpoint on a dof's own angle counts as reached by a step that ends this short of it
# [rad]: within the look ahead, so that the derivative after it is still the next piece's.
SHORT = 0.5 * AHEAD
# The retakes in a row aimed at a breakpoint at most; then the step crossing it is taken.
MAX_RETAKES = 4


@kernel(inline=True)
def _segment_end(m, cfg, bp, angle_mode, ix, x, y, f, sw, fst):
    """Where the segment of the next step ends, and what bounds that step: a ``Segment`` of
    ``(x_end, up, down, h_max, tol_end, corner)``.

    ``x_end``: the next breakpoint (in crank angle; on an elastic line one on a dof's own angle,
    :func:`_dof_segment_end`, with the derivative ``f`` at y), the end of the run, or a
    load-schedule corner on the independent variable before them (the step lands on it and its
    event is found there, θ = 1; one closer than ``tol_end`` is left to the event search, which
    finds it at once in the next step). ``up``, ``down``: the breakpoints above and below the shaft. ``tol_end``: a step
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
    x_end = m.line_segment_end(m, fst, f, angle_mode, x, y, x_end, tol_end)
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
        if theta * h > min_step and ist[I_NREDO] < MAX_RETAKES:
            _retake(fst, ist, theta * h)
            ist[I_NREDO] += 1
            return True, True
        return False, True
    if 0 < ist[I_NREDO] < MAX_RETAKES:
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
def _jumps_at(bp, jumps, period, phi):
    """Whether a pressure jumps at a breakpoint of ``bp`` (sorted angles of the cycle, ``jumps``
    their flags: ``Model.bp_jump``) the angle phi is on: the derivative carried over from the
    step that ended there (FSAL) used the piece before it. Only the breakpoints near φ in its
    cycle (and across the cycle's ends) are looked at."""
    y = phi % period
    reach = 2.0 * BP_LANDING  # (wider than _on_angle's test, which decides)
    for shift in (-period, 0.0, period):
        c = y + shift
        j = count_below(bp, 0.0, c - reach, False)
        while j < bp.shape[0] and bp[j] <= c + reach:
            if jumps[j] and _on_angle(phi, bp[j], period):
                return True
            j += 1
    return False


@kernel
def _cylinder_on(m, extras, k, angle, forward, y, sw, evbuf, ist, wk):
    """Cylinder k on a breakpoint at ``angle`` of its own (the shaft's; on an elastic line its
    station's): its start of injection, moving ``forward``, latches the governor's command
    (``m.latch``), its intake closing starts its closed part at p_a (``m.woschni``,
    :mod:`~transient.core.model.cylinder`). Returns whether either did (the derivative at y
    changes)."""
    hit = False
    if m.latch and forward and _on_angle(angle, m.gas_phase[k] + m.inj_angle, m.period):
        w = speed(inertia(m, y[PHI], wk), ist[I_ANGLE_MODE] == 1, y)  # (the reference's)
        y[latch_index(m) + k] = command(m, extras, w, y, sw)
        _emit_event(m, evbuf, ist, EV_INJECTION, y, wk)
        hit = True
    if m.woschni and _on_angle(angle, m.gas_phase[k] + m.cyl_par[cyl.IVC], m.period):
        y[cyl_index(m) + k] = m.cyl_par[cyl.P_A]
        hit = True
    return hit


@kernel
def _at_breakpoint(m, extras, bp, y, sw, evbuf, ist, wk):
    """What a breakpoint of the shaft does to the state (injections, intake closings,
    :func:`_cylinder_on`); returns whether the derivative carried over from the last step (FSAL)
    is stale: the state changed, or a pressure jumps here."""
    changed = False
    if extras is not None:
        forward = not m.latch or speed(inertia(m, y[PHI], wk), ist[I_ANGLE_MODE] == 1, y) > 0.0
        for k in range(m.ncyl):
            changed = _cylinder_on(m, extras, k, y[PHI], forward, y, sw, evbuf, ist, wk) or changed
    return changed or _jumps_at(bp, m.bp_jump, m.period, y[PHI])


# -- an elastic line's breakpoints, each dof's own on its angle (the Model's line_segment_end,
# line_retake, line_passed)


@kernel(inline=True)
def _next_dof_breakpoint(m, d, theta, upward):
    """The breakpoint of dof d's own next beyond its angle θ by more than SHORT (absolute, on
    its angle): one a step ended within SHORT of is behind it, reached
    (:func:`_pass_dof_breakpoints`). Upward, the one kept in ``fst`` (:func:`_next_up`) is
    the same, found without a search."""
    bps = dof_breakpoints(m, d)[0]
    if upward:
        return next_breakpoint(bps, m.period, theta + SHORT, True)
    return next_breakpoint(bps, m.period, theta - SHORT, False)


@kernel(inline=True)
def _next_up(m, fst, block, d, theta):
    """:func:`_next_dof_breakpoint` upward, kept in ``fst`` with the angle it was found from
    (its pair in the elastic line's block, from index ``block``, :func:`.io.line_fst`): still
    the next at any angle from there up to where it is reached, so that a step searches only
    past a breakpoint. Found afresh where θ is below that angle (zeros, before the first
    search, or a dof turning back in time) or has reached it."""
    i = block + 2 + 2 * d
    if theta < fst[i] or reached(fst[i + 1], theta + SHORT, True):
        fst[i] = theta
        fst[i + 1] = _next_dof_breakpoint(m, d, theta, True)
    return fst[i + 1]


@kernel(inline=True)
def _dof_segment_end(m, fst, f, angle_mode, x, y, x_end, tol_end):
    """``Model.line_segment_end``: where the next step must end for a breakpoint on a dof's own
    angle, if sooner than ``x_end``: where a retake aims (:func:`_aim_at_dof_breakpoints`), else
    in crank angle the earliest of the dofs' next breakpoints, each where its angle's rate at y,
    dθ_d/dφ = 1 + q′_d (``f``, the derivative there), puts it, the reference's (θ = φ) exactly.
    A step so aimed that ends short of the breakpoint leaves a short step to the next segment,
    one that crosses it is retaken. At least twice ``tol_end`` ahead of x: a segment that ends
    within it of x is the run's end."""
    least = x + 2.0 * tol_end
    block = line_fst(m, fst)
    aim = fst[block]
    if aim > 0.0:
        return min(x_end, max(x + aim, least))
    if angle_mode:
        ref, first = np.int64(m.line[0, LM_REF]), line_index(m)  # (read once for every dof)
        for d in range(line_dofs(m)):
            theta = angle_at(y, d, first, ref)
            level = _next_up(m, fst, block, d, theta)
            if d == ref:
                x_end = min(x_end, level)
            else:
                rate = 1.0 + f[twist_at(first, ref, d)]
                if rate > 0.0 and level < np.inf:
                    x_end = min(x_end, max(x + (level - theta) / rate, least))
    return x_end


@kernel(inline=True)
def _dof_angle_value(ctx, yv):
    """The event function of a breakpoint on dof d's own angle, θ_d − level, with ``ctx`` =
    (m, d, level), in the integrator's form (:mod:`transient.core.integrator.roots`)."""
    return dof_angle(ctx[0], yv, ctx[1]) - ctx[2]


@kernel(inline=True)
def _aim_at_dof_breakpoints(tab, m, extras, at, y, work, fst, ist, min_step, dense_ready):
    """``Model.line_retake``, after a step the error test accepted: one that crossed a
    breakpoint on a dof's own angle by more than BP_LANDING is retaken to end where the earliest
    such crossing is on its dense output (the next segment ends there,
    :func:`_dof_segment_end`), at most MAX_RETAKES times in a row. Returns ``(retake,
    dense_ready)``."""
    y_new = work.y_new
    theta = 2.0
    block = line_fst(m, fst)
    ref, first = np.int64(m.line[0, LM_REF]), line_index(m)  # (read once for every dof)
    for d in range(line_dofs(m)):
        a = angle_at(y, d, first, ref)
        b = angle_at(y_new, d, first, ref)
        if b == a:
            continue
        level = (_next_up(m, fst, block, d, a) if b > a
                 else _next_dof_breakpoint(m, d, a, False))
        if (b - level if b > a else level - b) > BP_LANDING:
            dense_ready = _dense_once(dense_ready, tab, m, extras, at, y, work, ist)
            found = root(_dof_angle_value, (m, d, level), work.F, y, work.tmp, 0.0, 1.0,
                         a - level, b - level)[0]
            theta = min(theta, found)
    if theta <= 1.0 and theta * at.h > min_step and fst[block + 1] < MAX_RETAKES:
        fst[block] = theta * at.h
        fst[block + 1] += 1.0
        ist[I_NREJECT] += 1
        return True, dense_ready
    fst[block] = 0.0
    fst[block + 1] = 0.0
    return False, dense_ready


@kernel(inline=True)
def _pass_dof_breakpoints(m, extras, y, y_to, sw, evbuf, ist, wk, fst):
    """``Model.line_passed``, where the state moves from y to ``y_to`` (a step taken, or the
    state moved to an event in it): each breakpoint on a dof's own angle the move reached (to
    within SHORT) acts on ``y_to`` (:func:`_at_dof_breakpoint`). Returns whether the derivative
    at ``y_to`` is stale."""
    stale = False
    block = line_fst(m, fst)
    ref, first = np.int64(m.line[0, LM_REF]), line_index(m)  # (read once for every dof)
    for d in range(line_dofs(m)):
        a = angle_at(y, d, first, ref)
        b = angle_at(y_to, d, first, ref)
        if b == a:
            continue
        up = b > a
        level = _next_up(m, fst, block, d, a) if up else _next_dof_breakpoint(m, d, a, False)
        while reached(level, b + SHORT if up else b - SHORT, up):
            stale = _at_dof_breakpoint(m, extras, d, level, up, y_to, sw, evbuf, ist, wk) or stale
            level = next_breakpoint(dof_breakpoints(m, d)[0], m.period, level, up)
    return stale


@kernel
def _at_dof_breakpoint(m, extras, d, level, rising, y, sw, evbuf, ist, wk):
    """Dof d on its breakpoint ``level`` (its angle reaching it rising, or falling), recorded:
    each cylinder it carries acts there on its own angle (:func:`_cylinder_on`). Returns whether
    the derivative at y is stale: the state changed, or a pressure jumps here."""
    _emit_event(m, evbuf, ist, EV_BREAKPOINT, y, wk)
    bps, first = dof_breakpoints(m, d)
    stale = _jumps_at(bps, m.bp_jump[first:first + bps.shape[0]], m.period, level)
    if extras is not None:
        carrier = line_parts(m.line)[0]
        for k in range(m.ncyl):
            if np.int64(carrier[k]) == d:
                stale = _cylinder_on(m, extras, k, level, rising, y, sw, evbuf, ist, wk) or stale
    return stale


# -- a rigid shaft's: no dofs, nothing to do (the stepper's bp are the shaft's)


@kernel(inline=True)
def no_segment_end(m, fst, f, angle_mode, x, y, x_end, tol_end):
    """``Model.line_segment_end`` of a rigid shaft: ``x_end``."""
    return x_end


@kernel(inline=True)
def no_retake(tab, m, extras, at, y, work, fst, ist, min_step, dense_ready):
    """``Model.line_retake`` of a rigid shaft: no retake."""
    return False, dense_ready


@kernel(inline=True)
def no_passed(m, extras, y, y_to, sw, evbuf, ist, wk, fst):
    """``Model.line_passed`` of a rigid shaft: the derivative stays valid."""
    return False


#: The Model's kernels of the breakpoints on each dof's own angle, on an elastic line
#: (``line_segment_end``, ``line_retake``, ``line_passed``), and on a rigid shaft.
LINE_BREAKPOINTS = (_dof_segment_end, _aim_at_dof_breakpoints, _pass_dof_breakpoints)
NO_LINE_BREAKPOINTS = (no_segment_end, no_retake, no_passed)
