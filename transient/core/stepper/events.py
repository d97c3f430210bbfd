"""State events on a step: the event functions, their crossings located on the dense output
(Illinois root finding, sampling for crossings that come and go inside a step), which events are
watched in the current switches (:func:`~transient.core.stepper.events._event_spec`), and the search for a
step's earliest event (:func:`~transient.core.stepper.events._locate_events`).

The events are the switches between time and crank angle, starter cut-out, the governor
characteristic's corners, the PI governor's limits, the flyweight governor's stops, the corners of
the load schedule and the generator's minimum speed, speed reversals, the end of the run and the
pairs' mode switches (Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.6). Locating them is kept
apart from acting on them (:mod:`~transient.core.stepper`), because location only reads the step and its dense
output, while acting changes the state and the switches.
"""
from __future__ import annotations

import numpy as np

from ..declare import Layout
from ..integrator.rk import dense, dense_state
from ..integrator.roots import crosses, crossing_inside, fall_after_rise, root
from ..jit import kernel
from ..model import governor as gv
from ..model.forcing import demand, inertia, is_pi, speed
from ..model.layout import (
    LT_SPEED,
    OMEGA,
    PHI,
    SW_LOAD,
    SW_LOAD_TABLE,
    SW_SLEEVE,
    SW_STARTER,
    WK_DEMAND,
    WK_G,
    WK_G_MIN,
    T,
    gov_index,
    n_margins,
)
from ..model.rhs import margins_at, margins_inline, model_rhs
from .io import (
    C_PHI_END,
    C_T_END,
    C_W_HI,
    C_W_LO,
    EV_END,
    EV_GENERATOR,
    EV_GOVERNOR,
    EV_LOAD,
    EV_LOAD_KNOT,
    EV_PAIR_MODE,
    EV_REVERSAL,
    EV_SLEEVE_FREE,
    EV_SLEEVE_STOP,
    EV_STARTER_CUTOUT,
    EV_TO_ANGLE,
    EV_TO_TIME,
    I_AT_EVENT,
    I_NFEV,
)

# Event "components" at and above PAIR_COMP are the mode margins of the pairs (rhs.mode_margins);
# DEMAND_COMP is the PI governor's demand u (forcing.demand).
PAIR_COMP = 100
DEMAND_COMP = -1
# A step that starts within this (relative) of the level of the event just handled starts on it:
# the event has put it there, and rounding must not make it cross the level again at once.
ON_LEVEL = 1e-12


@kernel(inline=True)
def _event_g(m, extras, angle_mode, yv, comp, level, sel, sw, wk):
    """Event function: ω − level for the speed (K = ½Jω² in crank-angle mode), the mode margin of
    pair comp − PAIR_COMP, the PI demand u − level, else y[comp] − level."""
    if extras is not None and comp >= PAIR_COMP:
        margins_at(m, extras, angle_mode, yv, sel, sw, wk)
        return wk[WK_G, comp - PAIR_COMP]
    if comp == OMEGA or comp == DEMAND_COMP:
        J = inertia(m, yv[PHI], wk)
        w = speed(J, angle_mode, yv)
        if extras is not None and comp == DEMAND_COMP:
            return demand(m, w, yv) - level
        return w - level
    return yv[comp] - level


@kernel(inline=True)
def event_value(ctx, yv):
    """:func:`_event_g` in the integrator's form (:mod:`transient.core.integrator.roots`):
    ``ctx`` = (m, extras, angle_mode, comp, level, sel, sw, wk)."""
    return _event_g(ctx[0], ctx[1], ctx[2], yv, ctx[3], ctx[4], ctx[5], ctx[6], ctx[7])


@kernel(inline=True)
def _iterated_g(m, extras, angle_mode, yv, comp, level, sel, sw, wk):
    """:func:`_event_g` with a pair's margins inlined: the root finder's iterations evaluate
    them most, and there a call would copy the Model at every iteration. Only the full variant
    has pairs: a plain scene's root finder iterates :func:`event_value` itself (:func:`_root`),
    so that its compile has neither this nor :func:`iterated_value`."""
    if extras is not None and comp >= PAIR_COMP:
        margins_inline(m, extras, angle_mode, yv, sel, sw, wk)
        return wk[WK_G, comp - PAIR_COMP]
    return _event_g(m, extras, angle_mode, yv, comp, level, sel, sw, wk)


@kernel(inline=True)
def iterated_value(ctx, yv):
    """:func:`_iterated_g` in the integrator's form (``ctx`` as :func:`event_value`'s)."""
    return _iterated_g(ctx[0], ctx[1], ctx[2], yv, ctx[3], ctx[4], ctx[5], ctx[6], ctx[7])


@kernel(inline=True)
def _root(m, extras, angle_mode, F, y, comp, level, sel, sw, tmp, wk, a, b, ga, gb):
    """The root of event ``comp`` at ``level`` in the bracket θ ∈ [a, b] (values ga, gb) on the
    dense output (:func:`transient.core.integrator.roots.root`). Returns (θ, evaluations)."""
    if extras is None:  # (no pairs: the iterated form is the event function itself)
        return root(event_value, (m, extras, angle_mode, comp, level, sel, sw, wk), F, y, tmp,
                    a, b, ga, gb)
    return root(iterated_value, (m, extras, angle_mode, comp, level, sel, sw, wk), F, y, tmp, a,
                b, ga, gb)


@kernel
def _crossing(m, extras, angle_mode, F, y, y_new, comp, level, sel, sw, tmp, wk):
    """θ ∈ (0, 1] where the event function crosses zero on the dense output.

    The caller has checked that it changes sign between y and y_new. The bracket's right end is
    y_new itself, not the dense output at θ = 1, which can differ from it by rounding and then
    would not bracket a root that sits at the very end of the step.
    """
    ga = _event_g(m, extras, angle_mode, y, comp, level, sel, sw, wk)
    gb = _event_g(m, extras, angle_mode, y_new, comp, level, sel, sw, wk)
    return _root(m, extras, angle_mode, F, y, comp, level, sel, sw, tmp, wk, 0.0, 1.0, ga, gb)[0]


#: A pair's mode margin can fall through zero and come back within one step, unseen at the
#: step's ends. Every stage of the step evaluates it (``rhs.derivative`` keeps the least value);
#: when that dips to zero or below, the margin is sampled at these fractions of the step to find
#: the first crossing.
N_MARGIN_SAMPLES = 4


@kernel(inline=True)
def _sample_margins(m, extras, at, y, work):
    """Mode margins of all pairs at θ = j/N_MARGIN_SAMPLES, j = 1 … N − 1 (rows of ``gs``; row 0
    holds the step's start and row N its end already)."""
    for j in range(1, N_MARGIN_SAMPLES):
        dense_state(work.F, y, at.x, at.h, j / N_MARGIN_SAMPLES, at.ix, work.tmp)
        margins_at(m, extras, at.angle_mode, work.tmp, at.sel, at.sw, work.wk)
        for k in range(n_margins(m)):
            work.gs[j, k] = work.wk[WK_G, k]


#: Samples of the fine search for a crossing that a step's stages show and its coarse samples
#: miss (a pair's power reversing for a few degrees inside a long step); a crossing that these
#: miss too makes the step be retaken shorter, at most MAX_UNSEEN times in a row.
N_FINE_SAMPLES, MAX_UNSEEN = 64, 3


@kernel(inline=True)
def _crossing_inside(m, extras, at, y, work, comp, level, direction, ga, n_samples):
    """θ where the speed, the PI demand or a pair's margin (``comp``) first crosses ``level``
    (in ``direction``) inside a step whose ends are on the same side of it, sampled at
    θ = j/n_samples on the dense output; 2 if the samples see no crossing (it was only in a
    stage, or between samples). ``ga``: the event function at the step's start. Returns (θ,
    evaluations)."""
    ctx = (m, extras, at.angle_mode, comp, level, at.sel, at.sw, work.wk)
    if extras is None:  # (as in _root)
        return crossing_inside(event_value, event_value, ctx, work.F, y, at.x, at.h, at.ix,
                               direction, ga, work.tmp, n_samples)
    return crossing_inside(event_value, iterated_value, ctx, work.F, y, at.x, at.h, at.ix,
                           direction, ga, work.tmp, n_samples)


@kernel(inline=True)
def _pair_crossing(m, extras, at, y, work, k):
    """θ where pair k's margin first falls to zero within the step, or 2 if it does not; and the
    margin evaluations (right-hand sides) the root finding took.

    A margin that starts at 0 (an event has just switched this pair's mode) and is below it a
    sample on either fell at once — the power only touched zero there and turns back, and the
    switch is undone at the step's start (θ = 0) — or first rose for less than a sample's span
    (the power reversed for a few degrees): ``fall_after_rise`` tells which.
    """
    gs = work.gs
    if gs[0, k] == 0.0 and gs[1, k] < 0.0:
        return fall_after_rise(event_value, iterated_value,
                               (m, extras, at.angle_mode, PAIR_COMP + k, 0.0, at.sel, at.sw,
                                work.wk), work.F, y, at.x, at.h, at.ix, 1.0 / N_MARGIN_SAMPLES,
                               N_FINE_SAMPLES, work.tmp)
    for j in range(N_MARGIN_SAMPLES):
        if crosses(gs[j, k], gs[j + 1, k], -1):
            return _root(m, extras, at.angle_mode, work.F, y, PAIR_COMP + k, 0.0, at.sel, at.sw,
                         work.tmp, work.wk, j / N_MARGIN_SAMPLES, (j + 1) / N_MARGIN_SAMPLES,
                         gs[j, k], gs[j + 1, k])
    return 2.0, 0


#: The state events watched on every step (:func:`_event_spec`), each with its slots (the event
#: functions it may need at once: a corner above and one below, both stops of the sleeve), in
#: the order that breaks a tie between two events at one instant (the first slot wins); last
#: the pairs' mode margins, as many as the scene has (``layout.n_margins``), each in turn. The
#: events themselves, with their names and codes, are ``io.EVENTS``.
WATCHED = Layout(
    "watched events",
    ("starter_cutout", 1, "the speed rising to the starter's cut-out"),
    ("to_time", 1, "in crank angle, the speed falling to the switch speed"),
    ("to_angle", 1, "in time, the speed rising to 1.5 × the switch speed"),
    ("reversal", 1, "in time, ω = 0"),
    ("end", 1, "the run's end by the variable that is not independent"),
    ("governor", 2, "the droop characteristic's corners, or the PI demand's limits"),
    ("load_schedule", 2, "the schedule's corner ahead; in φ, the one behind"),
    ("generator", 1, "the generator's minimum speed"),
    ("sleeve", 4, "the sleeve reaching its low, its high stop; leaving the low, the high"),
    ("load_knot", 2, "a speed map's knot above ω, and the one below"),
    ("pair_mode", 1, "each pair's mode margin falling to zero, pair by pair (per pair and "
                     "throw on an elastic line)"),
)
(W_STARTER_CUTOUT, W_TO_TIME, W_TO_ANGLE, W_REVERSAL, W_END, W_GOVERNOR, W_LOAD_SCHEDULE,
 W_GENERATOR, W_SLEEVE, W_LOAD_KNOT, W_PAIR_MODE) = WATCHED
FIRST_PAIR_EVENT = W_PAIR_MODE
N_EVENT_KINDS = WATCHED.size


@kernel(inline=True)
def _load_corner(m, ix, sw):
    """The load schedule's next corner on the independent variable ``ix`` (``inf`` if the
    schedule runs against the other variable, or has no corner ahead)."""
    seg = sw[SW_LOAD]
    if m.load_comp != ix or seg >= m.load_x.shape[0]:
        return np.inf
    return m.load_x[seg]


@kernel(inline=True)
def _event_spec(m, extras, cfg, e, angle_mode, sw):
    """State event number e that applies now: (code, component, level, direction), code −1 if
    none. The component OMEGA means the speed (K = ½Jω² in crank angle); direction +1 rising,
    −1 falling, 0 either way.

    The load schedule's corners are levels of t or φ, watched one segment at a time: the corner
    above and, for corners in φ (the shaft may turn back in time mode), the one below. On the
    independent variable the segment also ends on the corner (``breakpoints._segment_end``), so
    the event is found at the step's end exactly, as a breakpoint is in crank angle."""
    if e == W_STARTER_CUTOUT and sw[SW_STARTER] == 1:
        return EV_STARTER_CUTOUT, OMEGA, m.starter_cutout, 1
    if e == W_TO_TIME and angle_mode:
        return EV_TO_TIME, OMEGA, cfg[C_W_LO], -1
    if e == W_TO_ANGLE and not angle_mode:
        return EV_TO_ANGLE, OMEGA, cfg[C_W_HI], 1
    if e == W_REVERSAL and not angle_mode:
        return EV_REVERSAL, OMEGA, 0.0, 0
    if e == W_END:  # the end of the run by the variable that is not independent
        if angle_mode:
            return EV_END, T, cfg[C_T_END], 1
        return EV_END, PHI, cfg[C_PHI_END], 1
    if W_GOVERNOR <= e < W_GOVERNOR + 2 and m.gov_on:  # the droop characteristic's corners
        return EV_GOVERNOR, OMEGA, m.gov_full if e == W_GOVERNOR else m.gov_zero, 0
    if extras is not None and W_GOVERNOR <= e < W_GOVERNOR + 2 and is_pi(m):  # PI demand limits
        return EV_GOVERNOR, DEMAND_COMP, m.gov_par[gv.P_FMAX if e == W_GOVERNOR else gv.P_FMIN], 0
    if e == W_LOAD_SCHEDULE and sw[SW_LOAD] < m.load_x.shape[0]:  # the schedule's corner ahead
        return EV_LOAD, m.load_comp, m.load_x[sw[SW_LOAD]], 1
    if e == W_LOAD_SCHEDULE + 1 and m.load_comp == PHI and sw[SW_LOAD] > 0:  # behind, reached
        return EV_LOAD, PHI, m.load_x[sw[SW_LOAD] - 1], -1  # turning back
    if e == W_GENERATOR and m.gen_power != 0.0:  # the generator's minimum speed
        return EV_GENERATOR, OMEGA, m.gen_min, 0
    if extras is not None and W_SLEEVE <= e < W_SLEEVE + 4 and m.gov_dyn == gv.FLYWEIGHT:
        return _sleeve_event(m, e - W_SLEEVE, sw)
    if (extras is not None and e == W_LOAD_KNOT and m.lt_kind == LT_SPEED
            and sw[SW_LOAD_TABLE] < m.lt_x.shape[0]):
        return EV_LOAD_KNOT, OMEGA, m.lt_x[sw[SW_LOAD_TABLE]], 1  # a speed map's knot above ω
    if (extras is not None and e == W_LOAD_KNOT + 1 and m.lt_kind == LT_SPEED
            and sw[SW_LOAD_TABLE] > 0):
        return EV_LOAD_KNOT, OMEGA, m.lt_x[sw[SW_LOAD_TABLE] - 1], -1  # and the one below
    return -1, OMEGA, 0.0, 0


@kernel(inline=True)
def _sleeve_event(m, s, sw):
    """The flyweight governor's events (``_event_spec``, slot ``s`` of the sleeve's four): a
    moving sleeve reaching its low or high stop; on a stop, the speed at which the net force
    turns away from it."""
    par = m.gov_par
    z = gov_index(m) + gv.FW_LIFT
    sleeve = sw[SW_SLEEVE]
    if s == 0 and sleeve == gv.FREE:
        return EV_SLEEVE_STOP, z, 0.0, -1
    if s == 1 and sleeve == gv.FREE:
        return EV_SLEEVE_STOP, z, par[gv.F_TRAVEL], 1
    if s == 2 and sleeve == gv.ON_LOW_STOP:
        return EV_SLEEVE_FREE, OMEGA, par[gv.F_W_LIFT], 1
    if s == 3 and sleeve == gv.ON_HIGH_STOP:
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


@kernel(inline=True)
def _dense_once(ready, tab, m, extras, at, y, work, ist):
    """The last step's dense output into F, unless ``ready`` (it costs the pair's extra stages,
    so a step computes it only when an event or an output sample needs it); returns True."""
    if not ready:
        dense(tab, model_rhs, (m, extras, at.angle_mode, at.sel, at.sw, work.wk), y, work.y_new,
              at.h, work.K, work.F, work.tmp)
        ist[I_NFEV] += tab.n_ext - tab.n_stages - 1  # the dense output's extra stages
    return True


@kernel(inline=True)
def _locate_events(tab, m, extras, cfg, at, y, work, ist, seen, dense_ready):
    """The earliest state event in the last step (``at``; accepted, not yet taken):
    ``(code, θ, component, level, rising, unseen, dense_ready)``, code −1 if there is none.

    ``rising``: the event function crosses from below. ``unseen``: a pair's margin dipped below
    zero in the step's stages only, which no sample found (the caller retakes the step shorter).
    ``seen``: what the step's stages saw, (``dip``, ``w_lo``, ``w_hi``): whether some pair's
    margin reached zero, the speed's range; ``gs[0]`` and ``gs[N_MARGIN_SAMPLES]`` hold the
    margins at the step's ends.
    """
    dip, w_lo, w_hi = seen
    ev_code = -1
    ev_theta = 2.0
    unseen = False
    ev_comp = 0
    ev_level = 0.0
    ev_rising = True
    # ω at both ends: in crank angle the derivative holds dt/dφ = 1/ω.
    w0 = 1.0 / work.f[T] if at.angle_mode else y[OMEGA]
    w1 = 1.0 / work.K[tab.n_stages, T] if at.angle_mode else work.y_new[OMEGA]
    if extras is not None and dip:
        dense_ready = _dense_once(dense_ready, tab, m, extras, at, y, work, ist)
        _sample_margins(m, extras, at, y, work)
        ist[I_NFEV] += N_MARGIN_SAMPLES - 1
    for e in range(FIRST_PAIR_EVENT):
        code, comp, level, direction = _event_spec(m, extras, cfg, e, at.angle_mode, at.sw)
        if code < 0:
            continue
        theta, rising, dense_ready = _level_event(tab, m, extras, at, y, work,
                                                  (code, comp, level, direction),
                                                  (w0, w1, w_lo, w_hi), ist, dense_ready)
        if theta < ev_theta:
            ev_theta, ev_code, ev_comp, ev_level = theta, code, comp, level
            ev_rising = rising
    # (the plain variant watches no pair)
    if extras is not None and dip:
        for k in range(n_margins(m)):  # each mode margin falling to zero
            theta, only_stages = _pair_event(m, extras, at, y, work, k, ist)
            unseen = unseen or only_stages
            if theta < ev_theta:
                ev_theta, ev_code, ev_comp, ev_level = theta, EV_PAIR_MODE, PAIR_COMP + k, 0.0
    return ev_code, ev_theta, ev_comp, ev_level, ev_rising, unseen, dense_ready


@kernel(inline=True)
def _pair_event(m, extras, at, y, work, k, ist):
    """θ where pair k's margin first falls to zero in the step (2 if it does not), and whether
    only the stages saw it fall below zero (the samples, coarse and fine, did not)."""
    theta, evals = _pair_crossing(m, extras, at, y, work, k)
    ist[I_NFEV] += evals
    only_stages = False
    if theta > 1.0 and work.wk[WK_G_MIN, k] < 0.0 <= work.gs[0, k]:
        # the stages saw the margin fall below zero, the samples did not
        theta, evals = _crossing_inside(m, extras, at, y, work, PAIR_COMP + k, 0.0, -1,
                                        work.gs[0, k], N_FINE_SAMPLES)
        ist[I_NFEV] += evals
        only_stages = theta > 1.0
    return theta, only_stages


@kernel(inline=True)
def _level_event(tab, m, extras, at, y, work, spec, speeds, ist, dense_ready):
    """θ where the speed, the PI demand or the state ``comp`` first crosses ``level`` (in
    ``direction``) in the step, 2 if it does not; whether it crosses from below; ``dense_ready``.
    ``spec``: the event, (code, comp, level, direction) as :func:`_event_spec` gives it;
    ``speeds``: the speed at the step's ends and its range over the stages, (w0, w1, w_lo,
    w_hi)."""
    code, comp, level, direction = spec
    w0, w1, w_lo, w_hi = speeds
    wk = work.wk
    if extras is not None and comp == DEMAND_COMP:
        ga = _event_g(m, extras, at.angle_mode, y, comp, level, at.sel, at.sw, wk)
        gb = _event_g(m, extras, at.angle_mode, work.y_new, comp, level, at.sel, at.sw, wk)
    else:
        ga = (w0 if comp == OMEGA else y[comp]) - level
        gb = (w1 if comp == OMEGA else work.y_new[comp]) - level
    if code == ist[I_AT_EVENT] - 1 and abs(ga) <= ON_LEVEL * max(1.0, abs(level)):
        ga = 0.0
    ends = crosses(ga, gb, direction)
    # The speed (the PI demand) can pass a level and come back within one step (its
    # fluctuation within a cycle about a governor corner): the stages' range shows it.
    inside = not ends and ((comp == OMEGA and w_lo < level < w_hi) or (
        extras is not None and comp == DEMAND_COMP
        and wk[WK_DEMAND, 0] < level < wk[WK_DEMAND, 1]))
    theta = 2.0
    rising = True
    if ends or inside:
        dense_ready = _dense_once(dense_ready, tab, m, extras, at, y, work, ist)
        if ends:
            theta = _crossing(m, extras, at.angle_mode, work.F, y, work.y_new, comp, level, at.sel,
                              at.sw, work.tmp, wk)
        else:
            for n_samples in (N_MARGIN_SAMPLES, N_FINE_SAMPLES):  # coarse, then fine
                theta, evals = _crossing_inside(m, extras, at, y, work, comp, level, direction, ga,
                                                n_samples)
                ist[I_NFEV] += evals
                if theta <= 1.0:
                    break
        # the crossing's direction: from below (an 'inside' crossing is the first one away from
        # the step's start, so this holds for it too)
        rising = ga < 0.0 or (ga == 0.0 and gb > 0.0)
    return theta, rising, dense_ready
