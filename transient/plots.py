"""Plot helpers: each takes an ``ax`` and returns the artists; callers make and save figures.

Where a helper plots a run, ``traj`` is a :class:`~transient.results.Result` or its trajectory
(a mapping of column name to samples)."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

#: rpm per rad/s.
RPM = 30.0 / math.pi

#: A quantity over a run of more whole cycles than this is drawn cycle by cycle: each cycle's
#: mean as a line and its least to greatest value as a band. At a figure's width the pulses of
#: more cycles merge into a solid band (aliased where the pixels sample them) in which neither a
#: cycle nor a trend can be read.
CYCLE_VIEW_FROM = 20

#: Dash patterns of the cylinders' curves, cylinder k the k-th (cycled), with colour C(k−1):
#: curves that cross or lie on one another stay apart, in a grey print too.
DASHES = ("-", (0, (6, 2)), (0, (6, 2, 1.5, 2)), (0, (1.5, 1.5)), (0, (10, 2, 2, 2, 2, 2)),
          (0, (3, 1)), (0, (12, 3)), (0, (2, 1, 2, 4)))

#: Curves of an indicator diagram that keep within this fraction of the largest pressure (and
#: volume) drawn at every angle are drawn as one line labelled with each of them: at a
#: figure's height that is less than a line's width, so drawn apart they would only hide each
#: other.
COINCIDE = 2e-3

#: Events of a run that its figures over time mark, by their name in the result's ``/events``
#: (user guide, Results), in words. The others (breakpoints, governor corners, injections, a
#: load table's knots, the end) are corners the stepper steps onto, not happenings.
MARKED_EVENTS = {"load_schedule": "load step", "starter_cutout": "starter cut-out",
                 "speed_reversal": "speed through zero", "pair_mode": "friction mode switch",
                 "to_time_domain": "stepper to time steps",
                 "to_angle_domain": "stepper to angle steps",
                 "sleeve_stop": "governor sleeve at its stop",
                 "sleeve_free": "governor sleeve free", "stuck": "stuck by friction",
                 "released": "released", "locked": "locked",
                 "generator_min_speed": "generator below its least speed"}

#: An event kind more frequent than this per whole cycle is part of every cycle (a friction
#: pair's mode switches, say) rather than a happening: its rate is given in the legend, its
#: lines not drawn (they would fill the figure).
MARKED_PER_CYCLE = 0.5


def _columns(traj):
    """The trajectory of a Result, or ``traj`` itself."""
    return getattr(traj, "trajectory", traj)


def legend_outside(ax, handles=None, above=False, gap=0.01, **kwargs):
    """A legend to the right of ``ax`` (or ``above`` it, in one row, for panels stacked on
    one x axis that should keep one width), off its data: a legend inside an axes hides the
    curves it names wherever they pass under it; ``gap`` [axes width] between the axes and a
    legend at the right. Returns the legend."""
    kwargs.setdefault("fontsize", 8)
    if handles is not None:
        kwargs["handles"] = handles
    if above:
        kwargs.setdefault("ncol", len(handles if handles is not None else
                                      ax.get_legend_handles_labels()[0]))
        return ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.01), borderaxespad=0.0,
                         **kwargs)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.0 + gap, 1.0), borderaxespad=0.0,
                     **kwargs)


def cylinder_style(k: int, shift: int = 0) -> dict:
    """Colour and dash of cylinder ``k``'s (1-based) curves; ``shift`` moves the dash along for
    a further cycle of the same cylinder."""
    return {"color": f"C{(k - 1) % 10}", "ls": DASHES[(k - 1 + shift) % len(DASHES)]}


def _cycle_bounds(traj, scene):
    """Times at which the run's whole cycles begin and end (none without a ``scene``)."""
    if scene is None:
        return np.zeros(0)
    from .analysis.irregularity import cycle_boundaries

    return cycle_boundaries(traj["t"], traj["phi"], scene.mechanism.cycle, scene.initial.phi)[0]


def _time_means(traj, scene, column, bounds):
    """The time mean of ``column`` over each cycle between ``bounds``: exact for ω (Φ over the
    cycle's time) and ε (Δω over it), the trapezoidal rule on the samples otherwise."""
    t = traj["t"]
    if column == "omega":
        return scene.mechanism.cycle / np.diff(bounds)
    if column == "epsilon":
        return np.diff(np.interp(bounds, t, traj["omega"])) / np.diff(bounds)
    v = traj[column]
    area = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    return np.diff(np.interp(bounds, t, area)) / np.diff(bounds)


def _band(ax, traj, bounds, column, scale, color):
    """Each whole cycle's least to greatest ``column`` × ``scale`` between ``bounds`` as a
    band."""
    from .analysis.irregularity import cycle_extremes

    lo, hi = cycle_extremes(traj["t"], traj[column] * scale, bounds)
    return ax.fill_between(np.repeat(bounds, 2)[1:-1], np.repeat(lo, 2), np.repeat(hi, 2),
                           color=color, alpha=0.25, lw=0,
                           label="least to greatest in each cycle")


def _over_run(ax, traj, scene, column, scale, label, lw, color=None):
    """``column`` × ``scale`` against time: as sampled, or cycle by cycle for a run of more
    than :data:`CYCLE_VIEW_FROM` whole cycles (:func:`speed`). Returns the artists."""
    traj = _columns(traj)
    style = {"color": color} if color else {}
    bounds = _cycle_bounds(traj, scene)
    if bounds.size - 1 <= CYCLE_VIEW_FROM:
        return ax.plot(traj["t"], traj[column] * scale, lw=lw, label=label, **style)
    line = ax.plot(0.5 * (bounds[1:] + bounds[:-1]),
                   _time_means(traj, scene, column, bounds) * scale, lw=1.2,
                   label=f"{label + ': ' if label else ''}cycle mean", **style)[0]
    return [line, _band(ax, traj, bounds, column, scale, line.get_color())]


def speed(ax, traj, label=None, scene=None):
    """ω(t) [rpm]. With the run's ``scene``, a run of more than :data:`CYCLE_VIEW_FROM` whole
    cycles is drawn cycle by cycle: each cycle's mean speed (Φ over its time) as a line, its
    least to greatest speed as a band. Returns the artists."""
    artists = _over_run(ax, traj, scene, "omega", RPM, label, 1.0)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("ω [rpm]")
    ax.grid(True, alpha=0.3)
    return artists


def acceleration(ax, traj, label=None, scene=None):
    """ε(t) [rad/s²]; cycle by cycle as :func:`speed` (the cycle mean Δω over the cycle's
    time). Returns the artists."""
    artists = _over_run(ax, traj, scene, "epsilon", 1.0, label, 0.6)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("ε [rad/s²]")
    ax.grid(True, alpha=0.3)
    return artists


def run_events(res, scene) -> list[tuple[str, str, np.ndarray]]:
    """What happened in a run, for its figures over time: (kind, words, times [s]) of each
    misfiring cylinder (:func:`transient.analysis.thermo.misfires`) and of each event kind of
    :data:`MARKED_EVENTS` in the result ``res``, in that order."""
    from .analysis.thermo import misfires

    out = []
    found = misfires(scene, _columns(res))
    for k in sorted({m[0] for m in found}):
        out.append(("misfire", f"misfire of cylinder {k}",
                    np.array([m[2] for m in found if m[0] == k])))
    events = getattr(res, "events", {}) or {}
    for name, words in MARKED_EVENTS.items():
        if name in events and np.size(events[name]["t"]):
            out.append((name, words, np.asarray(events[name]["t"], dtype=float)))
    return out


def mark_events(axes, events, cycles: int):
    """Marks ``events`` (:func:`run_events`) on ``axes`` sharing t: a vertical line at each
    time, one style per kind, labelled once (on the first axes); a kind more frequent than
    :data:`MARKED_PER_CYCLE` per cycle over the run's ``cycles`` whole cycles is only named
    with its rate. Returns the handles for a legend."""
    from matplotlib.lines import Line2D

    styles: list[dict[str, Any]] = [
        {"color": "C3", "ls": "-", "lw": 0.8}, {"color": "k", "ls": ":", "lw": 1.0},
        {"color": "C4", "ls": "--", "lw": 0.8}, {"color": "C2", "ls": "-.", "lw": 0.8},
        {"color": "0.4", "ls": (0, (1, 3)), "lw": 1.0}]
    handles = []
    for j, (kind, words, times) in enumerate(events):
        if cycles and times.size > max(3.0, MARKED_PER_CYCLE * cycles):
            handles.append(Line2D([], [], ls="none",
                                  label=f"{words}: {times.size / cycles:.3g} per cycle "
                                        f"(not drawn)"))
            continue
        style = styles[0] if kind == "misfire" else styles[1 + j % (len(styles) - 1)]
        for ax in axes:
            for tk in times:
                ax.axvline(tk, alpha=0.7, zorder=1, **style)
        handles.append(Line2D([], [], label=f"{words} ({times.size})", **style))
    return handles


def speed_over_run(axes, res, scene):
    """The run's speed and acceleration over time (:func:`speed`, :func:`acceleration`) on two
    ``axes`` sharing t, its events marked (:func:`run_events`), the legend right of the
    speed's axes. Returns the artists."""
    a_w, a_e = axes
    artists = speed(a_w, res, scene=scene) + acceleration(a_e, res, scene=scene)
    cycles = max(_cycle_bounds(_columns(res), scene).size - 1, 0)
    handles = mark_events(axes, run_events(res, scene), cycles)
    a_w.set_xlabel("")
    if len(artists) > 2 or handles:
        legend_outside(a_w, handles=[a for a in artists[:2] if a.get_label()[0] != "_"]
                       + handles)
    return artists


def piston_force(ax, traj, scene, cylinder=1):
    """Gas force on one piston of ``cylinder`` against time [kN]: the table value times the
    pressure applied (the governor's fuel included) for force models, (p − p0)·F_p for pressure
    models."""
    traj = _columns(traj)
    from .scene.queries import gas_is_force

    value = traj[f"p_{cylinder}"]
    force = value if gas_is_force(scene) else (value - scene.gas.p0) * scene.mechanism.piston_area
    artists = ax.plot(traj["t"], force / 1e3, lw=0.6)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"P piston {cylinder} [kN]")
    ax.grid(True, alpha=0.3)
    return artists


def last_cycle(traj, cycle):
    """Boolean mask of the samples in the last whole cycle of crank angle."""
    traj = _columns(traj)
    phi = traj["phi"]
    return phi >= phi[-1] - cycle


def torques(ax, traj, cycle):
    """Moments over the last cycle against the crank angle in that cycle [deg]."""
    traj = _columns(traj)
    sel = last_cycle(traj, cycle)
    phi = np.degrees(traj["phi"][sel] - traj["phi"][sel][0])
    inertia = -0.5 * traj["dJ_dphi"][sel] * traj["omega"][sel] ** 2
    series = {"gas": traj["M_gas"][sel], "load": traj["M_load"][sel],
              "inertia −½J′ω²": inertia}
    if np.any(traj["M_starter"][sel]):
        series["starter"] = traj["M_starter"][sel]
    if "M_drive" in traj:
        series["drive (required)"] = traj["M_drive"][sel]
    artists = [ax.plot(phi, v, lw=1.0, label=k)[0] for k, v in series.items()]
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("M [N m]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    return artists


def indicator_phi(ax, table):
    """Indicator diagram p(φ) over the local cycle angle [deg], absolute pressure [MPa]."""
    x = np.linspace(0.0, table.period, 2881)
    artists = ax.plot(np.degrees(x), table(x) / 1e6, lw=1.0)
    for c in table.corners[1:-1]:
        ax.axvline(math.degrees(c), color="0.8", lw=0.5)
    ax.set_xlabel("local crank angle [deg]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, alpha=0.3)
    return artists


def indicator_pv(ax, table, volume, log=True):
    """Indicator diagram p(V), V [dm³], p [MPa]; log-log unless ``log`` is False."""
    x = np.linspace(0.0, table.period, 2881)
    plot = ax.loglog if log else ax.plot
    artists = plot(volume(x) * 1e3, table(x) / 1e6, lw=1.0)
    ax.set_xlabel("V [dm³]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, which="both", alpha=0.3)
    return artists


def _cylinders(scene, cylinders):
    """Cylinder numbers (1-based) to draw: all for None; ValueError for one out of range."""
    n = scene.mechanism.n_cylinders
    picked = list(range(1, n + 1)) if cylinders is None else [int(c) for c in cylinders]
    bad = [c for c in picked if not 1 <= c <= n]
    if bad:
        raise ValueError(f"cylinder {bad[0]} is out of range; allowed: 1 … {n}")
    return picked


def _cycle_samples(traj, scene, cylinder, cycles):
    """(cycle number, note, sample mask, start angle) of each of ``cylinder``'s own whole
    cycles asked for (indices as in a list: −1 the last), numbered as ``[[gas.cylinders]]``
    counts them (:func:`transient.analysis.thermo.own_cycle_numbers`), the note saying how its
    fuel was set: ", misfire", ", cut out", ", fuel 0.8" or "". ValueError for an index the run
    does not hold."""
    from .analysis.thermo import cycle_fuel_of, own_cycle_numbers, own_cycles

    starts = own_cycles(scene, traj, cylinder)
    numbers = own_cycle_numbers(scene, cylinder, starts)
    phi = traj["phi"]
    fuel = cycle_fuel_of(scene)
    out = []
    for c in cycles:
        if not -starts.size <= c < starts.size:
            raise ValueError(f"cycle {c} is out of range: cylinder {cylinder} has "
                             f"{starts.size} whole cycle(s) in the run (allowed "
                             f"{-starts.size} … {starts.size - 1})")
        a = starts[c]
        f, cut = fuel(cylinder, a + 0.5 * scene.mechanism.cycle)
        note = ("" if f == 1.0 else f", fuel {f:g}" if f != 0.0 else
                ", cut out" if cut else ", misfire")
        tol = 1e-9 * scene.mechanism.cycle  # (a sample on the cycle's end up to rounding)
        out.append((int(numbers[c]), note,
                    (phi >= a - tol) & (phi <= a + scene.mechanism.cycle + tol), a))
    return out


def _indicator_curves(traj, scene, cylinders, cycles, volume=False):
    """The run's indicator curves, those that coincide (:data:`COINCIDE`) merged: a list of
    (label, style, x, p [MPa]) with x the local angle [deg], or the volume [dm³] if
    ``volume``."""
    from .analysis.thermo import cylinder_volumes, local_angle

    curves = []  # (members, style, x, p, values on a common grid, largest sample step there)
    grid = np.linspace(0.0, 1.0, 1441)
    for k in _cylinders(scene, cylinders):
        for j, (n, note, sel, a) in enumerate(_cycle_samples(traj, scene, k, cycles)):
            local = local_angle(scene, traj["phi"][sel], a)
            p = traj[f"p_{k}"][sel] / 1e6
            x = (cylinder_volumes(scene, traj["phi"][sel]).V[k - 1] * 1e3 if volume
                 else np.degrees(local))
            u = (local - local[0]) / scene.mechanism.cycle
            key = [np.interp(grid, u, p)] + ([np.interp(grid, u, x)] if volume else [])
            curves.append(([(k, n, note)], cylinder_style(k, j), x, p, key,
                           float(np.max(np.diff(u)))))
    scale = [max(np.max(np.abs(c[4][i])) for c in curves) for i in range(1 + volume)]
    reach = math.ceil(max(c[5] for c in curves) * (grid.size - 1))
    merged = []
    for c in curves:
        for m in merged:
            if all(_near(u, v, COINCIDE * s, reach) and _near(v, u, COINCIDE * s, reach)
                   for u, v, s in zip(c[4], m[4], scale)):
                m[0].extend(c[0])
                break
        else:
            merged.append(c)
    return [(_curve_label(m[0]), m[1], m[2], m[3]) for m in merged]


def _near(u, v, tol, reach):
    """Whether ``u`` keeps within ``tol`` of what ``v`` spans over each grid point and the
    ``reach`` points either side (a sample spacing): a jump that the two curves' samples
    straddle differently is no difference."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    lo = minimum_filter1d(v, 2 * reach + 1, mode="wrap")
    hi = maximum_filter1d(v, 2 * reach + 1, mode="wrap")
    return bool(np.all((u >= lo - tol) & (u <= hi + tol)))


def _curve_label(members):
    """``cylinder 3, cycle 100, misfire``; ``cylinders 1, 4, cycle 100`` for curves that
    coincide in the same cycle with the same fuel."""
    ks = [m[0] for m in members]
    if len({(m[1], m[2]) for m in members}) == 1:
        n, note = members[0][1], members[0][2]
        who = f"cylinder {ks[0]}" if len(ks) == 1 else "cylinders " + ", ".join(map(str, ks))
        return f"{who}, cycle {n}{note}"
    return "; ".join(f"cylinder {k}, cycle {n}{note}" for k, n, note in members)


def _log_ticks(axis):
    """Plain-number ticks on a logarithmic ``axis`` (1, 2, 5 per decade, or more where it
    spans less than one), the minor ones unlabelled: no 3×10⁻² labels running into each other."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    lo, hi = sorted(axis.get_view_interval())
    span = math.log10(hi / lo) if lo > 0 else 2.0
    subs = (1.0, 2.0, 5.0) if span > 1.0 else (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0)
    axis.set_major_locator(LogLocator(base=10.0, subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def run_indicator_phi(ax, traj, scene, cylinders=None, cycles=(-1,), table=None, motored=None,
                      legend=True):
    """The pressure the run applied [MPa] against each cylinder's own (local) angle [deg], over
    its whole cycles ``cycles`` (−1: the last), for ``cylinders`` (1-based; None: all), each
    cylinder in its own colour and dash (:func:`cylinder_style`), curves that coincide drawn
    once and labelled with every cylinder (:data:`COINCIDE`), a cycle numbered as
    ``[[gas.cylinders]]`` counts it and named a misfire, cut out or part fuel where it is one.
    ``table``, ``motored``: the full-load and motored curves (each a
    :class:`~transient.forces.gas.PressureTable`, or None) drawn thin grey dashed and dotted for
    comparison: a misfiring cycle lies on the motored one. ``legend``: one right of the axes.
    Returns the artists."""
    traj = _columns(traj)
    from .analysis.thermo import local_angle

    artists = []
    for label, style, x, p in _indicator_curves(traj, scene, cylinders, cycles):
        artists += ax.plot(x, p, lw=1.2, label=label, **style)
    x = local_angle(scene, np.linspace(0.0, scene.mechanism.cycle, 2881), 0.0)
    for curve, style, label in ((table, "--", "input table, full fuel"),
                                (motored, ":", "motored (no fuel)")):
        if curve is not None:
            artists += ax.plot(np.degrees(x), curve(x) / 1e6, lw=0.8, ls=style, color="0.4",
                               label=label)
    ax.set_xlabel("cylinder's own crank angle [deg]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, alpha=0.3)
    if legend:
        legend_outside(ax)
    return artists


def run_indicator_pv(ax, traj, scene, cylinders=None, cycles=(-1,), log=True, legend=True):
    """p–V diagram of the run: the pressure applied [MPa] against the cylinder's exact volume
    [dm³] (:func:`transient.analysis.thermo.cylinder_volumes`; the swept part only where the gas
    model gives no clearance), log-log with plain-number ticks unless ``log`` is False; styles,
    merged curves and labels as :func:`run_indicator_phi`. Returns the artists."""
    traj = _columns(traj)
    plot = ax.loglog if log else ax.plot
    artists = []
    for label, style, x, p in _indicator_curves(traj, scene, cylinders, cycles, volume=True):
        artists += plot(x, p, lw=1.2, label=label, **style)
    ax.set_xlabel("V [dm³]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, which="both", alpha=0.3)
    if log:
        _log_ticks(ax.xaxis)
        _log_ticks(ax.yaxis)
    if legend:
        legend_outside(ax)
    return artists


def heat_release(ax, traj, scene, cylinders=None, cycles=(-1,)):
    """Apparent heat-release rate dQ/dφ [J/deg] of the run's pressure over the closed part of
    each cylinder's own cycles ``cycles``, against its local angle [deg]
    (:func:`transient.analysis.thermo.heat_release_rate`; Wiebe combustion with constant γ).
    Returns the artists (none where the run does not hold a closed part)."""
    traj = _columns(traj)
    from .analysis.thermo import heat_release_rate

    artists = []
    for k in _cylinders(scene, cylinders):
        for j, (n, note, _, a) in enumerate(_cycle_samples(traj, scene, k, cycles)):
            got = heat_release_rate(scene, traj, k, a)
            if got is not None:
                artists += ax.plot(np.degrees(got[0]), got[1] * math.pi / 180.0, lw=1.2,
                                   label=f"cylinder {k}, cycle {n}{note}",
                                   **cylinder_style(k, j))
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("cylinder's own crank angle [deg]")
    ax.set_ylabel("dQ/dφ [J/deg]")
    ax.grid(True, alpha=0.3)
    if artists:
        legend_outside(ax)
    return artists


def speed_over_cycle(ax, traj, scene):
    """ω(φ) [rpm] over the last whole cycle against the angle in it [deg], with its mean, its
    extremes and δ = (ω_max − ω_min)/ω_mean (Gots §2.8) marked. Returns the artists."""
    traj = _columns(traj)
    from .analysis.irregularity import cycle_boundaries

    cycle = scene.mechanism.cycle
    tb, marks = cycle_boundaries(traj["t"], traj["phi"], cycle, scene.initial.phi)
    if marks.size < 2:
        raise ValueError("the run holds no whole cycle")
    a, b = marks[-2], marks[-1]
    sel = (traj["phi"] >= a) & (traj["phi"] <= b)
    x = np.degrees(traj["phi"][sel] - a)
    w = traj["omega"][sel] * RPM
    mean = cycle / (tb[-1] - tb[-2]) * RPM
    artists = ax.plot(x, w, lw=1.2, label="ω")
    i, j = int(np.argmax(w)), int(np.argmin(w))
    artists.append(ax.axhline(mean, color="k", lw=0.6, ls="--", label="cycle mean"))
    artists += ax.plot([x[i], x[j]], [w[i], w[j]], "o", color="C3", ms=4,
                       label=f"δ = {(w[i] - w[j]) / mean:.4g} = (ω_max − ω_min)/ω_mean")
    artists.append(ax.annotate("", xy=(x[i], w[j]), xytext=(x[i], w[i]),
                               arrowprops={"arrowstyle": "<->", "color": "C3", "lw": 0.8}))
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("ω [rpm]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    return artists


def cylinder_torque_curves(ax, traj, scene):
    """Each cylinder's gas torque and their sum M_gas [N m] over the last whole cycle against
    the angle in it [deg] (:func:`transient.analysis.pistons.cylinder_torques`). Returns the
    artists."""
    traj = _columns(traj)
    from .analysis.pistons import cylinder_torques

    sel = last_cycle(traj, scene.mechanism.cycle)
    part = {k: np.asarray(traj[k])[sel] for k in traj if k == "phi" or k.startswith("p_")}
    x = np.degrees(part["phi"] - part["phi"][0])
    torques = cylinder_torques(scene, part)
    artists = [ax.plot(x, m, lw=1.0, label=f"cylinder {k + 1}", **cylinder_style(k + 1))[0]
               for k, m in enumerate(torques)]
    artists += ax.plot(x, torques.sum(axis=0), lw=1.6, color="k", label="sum (M_gas)")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("M [N m]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    return artists


def inertia_and_gas(axes, traj, cycle):
    """Over the last cycle against the angle in it [deg]: J(φ) [kg m²] on ``axes[0]``, and on
    ``axes[1]`` the inertia moment ½J′(φ)ω² beside the gas and load moments [N m] — the terms
    of (18), J φ̈ = M − ½J′φ̇², whose balance sets ε. Returns the artists."""
    traj = _columns(traj)
    sel = last_cycle(traj, cycle)
    x = np.degrees(traj["phi"][sel] - traj["phi"][sel][0])
    a_j, a_m = axes
    artists = a_j.plot(x, traj["J"][sel], lw=1.2, color="C4")
    a_j.set_ylabel("J [kg m²]")
    artists += a_m.plot(x, 0.5 * traj["dJ_dphi"][sel] * traj["omega"][sel] ** 2, lw=1.2,
                        color="C4", label="½J′ω²")
    artists += a_m.plot(x, traj["M_gas"][sel], lw=1.0, color="C0", label="M_gas")
    artists += a_m.plot(x, traj["M_load"][sel], lw=1.0, color="C3", label="M_load")
    a_m.axhline(0.0, color="0.6", lw=0.5)
    a_m.set_ylabel("M [N m]")
    a_m.set_xlabel("crank angle in the last cycle [deg]")
    legend_outside(a_m)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return artists


def transfer_functions(ax, table):
    """Transfer functions of a kinematics table against the shaft angle: u₉,₁ and u₁₃,₁ of a
    swash plate (the paper's Fig. 4), the piston ones u_k [m/rad] on a second axis."""
    phi = table["phi_deg"]
    artists = [ax.plot(phi, table[k], lw=1.2, label=k)[0] for k in ("u9", "u13") if k in table]
    pistons = [k for k in table if k.startswith("u_")]
    other = ax.twinx() if artists else ax
    artists += [other.plot(phi, table[k], lw=0.8, ls="--", color=f"C{j + 2}", label=k)[0]
                for j, k in enumerate(pistons)]
    if artists and other is not ax:
        other.set_ylabel("piston u [m/rad]")
    ax.set_ylabel("u₉,₁, u₁₃,₁ [1]" if other is not ax else "u [m/rad]")
    ax.grid(True, alpha=0.3)
    ax.legend(handles=artists, fontsize=7, ncol=4)
    return artists


def reduced_inertia(ax, table):
    """J(φ) and dJ/dφ of the moving parts from a kinematics table."""
    phi = table["phi_deg"]
    a = ax.plot(phi, table["J"], lw=1.2, label="J")
    other = ax.twinx()
    b = other.plot(phi, table["dJ_dphi"], lw=0.8, color="C3", label="dJ/dφ")
    ax.set_xlabel("shaft angle [deg]")
    ax.set_ylabel("J [kg m²]")
    other.set_ylabel("dJ/dφ [kg m²/rad]")
    ax.grid(True, alpha=0.3)
    ax.legend(handles=a + b, fontsize=8)
    return a + b


def pair_power(ax, traj, pairs, cycle):
    """Power each non-ideal pair transmits, S_k ω [kW] (> 0: the shaft side drives), and the
    power it loses, over the last cycle against the crank angle in that cycle. ``pairs``:
    (label, columns' suffix, speed column) of each (on an elastic line of each pair in each
    throw, :func:`transient.scene.outputs.pair_columns`)."""
    traj = _columns(traj)
    sel = last_cycle(traj, cycle)
    phi = np.degrees(traj["phi"][sel] - traj["phi"][sel][0])
    artists = []
    for name, s, speed in pairs:
        line = ax.plot(phi, traj[f"S_{s}"][sel] * traj[speed][sel] / 1e3, lw=1.0,
                       label=f"{name}: transmitted")[0]
        artists.append(line)
        artists += ax.plot(phi, traj[f"P_loss_{s}"][sel] / 1e3, lw=1.0, ls="--",
                           color=line.get_color(), label=f"{name}: lost")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("power [kW]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    return artists


def friction_budget(ax, labels, fmep, names):
    """The friction budget as stacked bars: at each of ``labels`` (operating points, or one run)
    the FMEP of each pair [kPa], ``fmep`` of shape (len(names), len(labels)) [Pa], the total on
    top. Returns the bars."""
    fmep = np.asarray(fmep, float).reshape(len(names), len(labels)) / 1e3
    x = np.arange(len(labels))
    bottom = np.zeros(len(labels))
    artists = []
    for name, row in zip(names, fmep):
        artists.append(ax.bar(x, row, 0.6, bottom=bottom, label=name))
        bottom = bottom + row
    for xi, total in zip(x, bottom):
        ax.annotate(f"{total:.4g}", (xi, total), ha="center", va="bottom", fontsize=8)
    ax.set_xticks(x, [str(v) for v in labels])
    ax.set_ylabel("FMEP [kPa]")
    ax.grid(True, axis="y", alpha=0.3)
    ax.margins(y=0.1)  # (room for the totals above the bars)
    legend_outside(ax)
    return artists


def load_response(axes, traj, scene, analysis):
    """Speed (as run, and its mean over the cycle before each instant), fuel command and load
    torque against time, each cycle by cycle for a long run (:func:`speed`), with each load
    step's ±band around its new steady speed (``analysis``: the run's ``/analysis`` entries,
    name → (value, unit)). ``axes``: three axes sharing t. Returns the artists."""
    traj = _columns(traj)
    from .analysis.transient_response import cycle_mean_speed

    a_w, a_f, a_m = axes
    t = traj["t"]
    bounds = _cycle_bounds(traj, scene)
    artists = ([_band(a_w, traj, bounds, "omega", RPM, "0.5")]
               if bounds.size - 1 > CYCLE_VIEW_FROM else
               a_w.plot(t, traj["omega"] * RPM, lw=0.5, color="0.6", label="ω"))
    tm, wm = cycle_mean_speed(t, traj["phi"], scene.mechanism.cycle, traj["omega"])
    artists += a_w.plot(tm, wm * RPM, lw=1.2, color="C0", label="mean over the cycle before")
    k = 1
    while f"load_change_{k}_t_s" in analysis:
        p = f"load_change_{k}_"
        t0, t1 = analysis[p + "t_s"][0], analysis[p + "t_end_s"][0]
        w_ss, half = analysis[p + "omega_after_rad_s"][0], analysis[p + "band_pct"][0] / 100.0
        w_ref = analysis[p + "omega_rated_rad_s"][0]
        artists.append(a_w.fill_between([t0, t1], (w_ss - half * w_ref) * RPM,
                                        (w_ss + half * w_ref) * RPM, color="C2", alpha=0.25,
                                        label=f"±{half * 100:g} % band" if k == 1 else None))
        for ax in axes:
            artists.append(ax.axvline(t0, color="k", lw=0.8, ls=":",
                                      label="load step" if k == 1 and ax is a_w else None))
        if analysis[p + "recovered"][0]:
            artists.append(a_w.axvline(t0 + analysis[p + "recovery_s"][0], color="C2", lw=0.8,
                                       label="back in the band" if k == 1 else None))
        k += 1
    a_w.set_ylabel("ω [rpm]")
    legend_outside(a_w)
    artists += _over_run(a_f, traj, scene, "fuel", 1.0, None, 1.0, color="C1")
    a_f.set_ylabel("fuel command [1]")
    artists += _over_run(a_m, traj, scene, "M_load", -1.0, None, 1.0, color="C3")
    a_m.set_ylabel("load torque [N m]")
    a_m.set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return artists


def polar_load(ax, x, y, label=None, scale=1e-3, angle_deg=None, dead_centres=None,
               legend=True, title=None):
    """Polar load diagram: the end points of a load vector (x, y) [N] drawn from the pole (+),
    in kN by default (``scale``). The caller picks the frame. The largest vector is drawn as an
    arrow, its size (and angle) given in the title. ``angle_deg``: the crank angle of each point
    [deg], increasing; given, the curve is marked every 30° of it (labelled every 90°, every
    120° over a 720° cycle), and ``dead_centres`` (words → angle [deg], e.g. the firing TDC) as
    stars on the curve. ``legend``: one right of the axes; ``title``: the axes', above the
    largest load's line. Returns the artists."""
    x = np.asarray(x, dtype=float) * scale
    y = np.asarray(y, dtype=float) * scale
    artists = ax.plot(x, y, lw=1.0, label=label or "load over the cycle")
    colour = artists[0].get_color()
    k = int(np.argmax(np.hypot(x, y)))
    artists.append(ax.annotate("", xy=(x[k], y[k]), xytext=(0.0, 0.0),
                               arrowprops={"arrowstyle": "->", "color": colour, "lw": 0.8}))
    where = f" at {angle_deg[k]:.0f}°" if angle_deg is not None else ""
    peak = f"largest: {math.hypot(x[k], y[k]):.3g} kN{where} (arrow)"
    ax.set_title(f"{title}\n{peak}" if title else peak, fontsize=9)
    artists += ax.plot([0.0], [0.0], "k+", ms=9, label="pole (zero load)")
    if angle_deg is not None:
        artists += _angle_marks(ax, np.asarray(angle_deg, dtype=float), x, y, colour,
                                dead_centres or {})
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.axvline(0.0, color="0.7", lw=0.5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    if legend:
        legend_outside(ax)
    return artists


def _angle_marks(ax, angle, x, y, colour, dead_centres) -> list:
    """Dots every 30° of ``angle`` along the curve (x, y), labelled every 90° (120° over a 720°
    cycle; marks that fall on one spot share a label), and a star at each dead centre."""
    every = 120.0 if angle[-1] - angle[0] > 400.0 else 90.0
    at = np.arange(math.ceil(angle[0] / 30.0) * 30.0, angle[-1] - 1e-6, 30.0)  # (end = start)
    mx, my = np.interp(at, angle, x), np.interp(at, angle, y)
    artists = ax.plot(mx, my, "o", ms=2.5, color=colour, label="every 30° of crank angle")
    near = 0.04 * max(np.ptp(x), np.ptp(y), 1e-300)
    spots: list[list] = []  # [x, y, angles]
    for a, u, v in zip(at, mx, my):
        if abs(a / every - round(a / every)) < 1e-9:
            spot = next((s for s in spots if math.hypot(s[0] - u, s[1] - v) < near), None)
            if spot is None:
                spots.append([u, v, [a]])
            else:
                spot[2].append(a)
    for u, v, angles in spots:
        artists.append(ax.annotate(", ".join(f"{a:.0f}" for a in angles) + "°", (u, v),
                                   xytext=(4, 3), textcoords="offset points", fontsize=7,
                                   color="0.25"))
    for (words, a), marker in zip(dead_centres.items(), ("*", "P", "X", "D")):
        artists += ax.plot([np.interp(a, angle, x)], [np.interp(a, angle, y)], marker, ms=9,
                           color="k", mfc="gold", label=f"{words} ({a:.0f}°)")
    return artists


def crankpin_polar(ax, R_K, R_T, label=None, angle_deg=None, dead_centres=None, legend=True,
                   title=None):
    """Polar diagram of a crankpin load [N] in the crank frame, in kN: the crank pointing up (+y,
    outward), +x the direction of rotation, so the load R_T t̂ − R_K ĉ is drawn as (R_T, −R_K) —
    the frame of ``transient loads``; angle marks as :func:`polar_load`. Takes a
    crank-slider's ``CylinderLoads`` rows or a radial row's master crankpin
    (``ArticulatedLoads.R_K[j]``, ``R_T[j]``). Returns the artists."""
    artists = polar_load(ax, R_T, -np.asarray(R_K), label=label, angle_deg=angle_deg,
                         dead_centres=dead_centres, legend=legend, title=title)
    ax.set_xlabel("R_T [kN] (direction of rotation)")
    ax.set_ylabel("−R_K [kN] (crank outward)")
    return artists


def load_against_angle(ax, angle_deg, values, label=None, ylabel="|R| [kN]", scale=1e-3,
                       style=None):
    """A load [N] (plotted in kN by default) against the crank angle [deg], with its mean as a
    dashed line. Returns the artists."""
    v = np.asarray(values) * scale
    artists = ax.plot(angle_deg, v, lw=1.0, label=label, **(style or {}))
    artists.append(ax.axhline(float(np.mean(v)), color=artists[0].get_color(), lw=0.8, ls="--"))
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return artists


def wear_diagram(ax, ray_deg, load, label=None, scale=1e-3):
    """Conventional wear diagram (Gots §2.6) on a polar ``ax``: the journal's rim is each ray's
    zero and its load is drawn inward from it on the radial axis, in kN by default
    (``scale``); ``load`` [N] per ray, e.g. the cycle-mean load within ±60° of it
    (:class:`~transient.analysis.loads.diagrams.CrankSliderDiagrams`). ``ray_deg``: the rays'
    directions in the frame of the matching polar diagram, counter-clockwise from its +x axis
    (the direction of rotation; 90° the crank outward). The least loaded ray, where an oil hole
    belongs, is marked. Returns the artists."""
    from matplotlib.ticker import FuncFormatter

    th = np.radians(np.append(ray_deg, ray_deg[0]))
    v = np.append(load, load[0]) * scale
    top = float(np.max(v)) if np.max(v) > 0 else 1.0
    artists = ax.plot(th, v, lw=1.2, label=label or "load of each ray")
    artists.append(ax.fill_between(th, 0.0, v, alpha=0.3, lw=0, color=artists[0].get_color()))
    k = int(np.argmin(load))
    artists += ax.plot([th[k]], [0.0], "v", color="C3", ms=8, clip_on=False,
                       label="least loaded ray")
    artists.append(ax.annotate(f"{ray_deg[k]:.0f}°", (th[k], 0.0), xytext=(0, -12),
                               textcoords="offset points", color="C3", fontsize=8,
                               ha="center", va="top"))
    ax.set_ylim(1.6 * top, 0.0)  # the rim is zero load, the load grows inward
    ax.set_rlabel_position(100.0)
    ax.set_thetagrids(np.arange(0, 360, 30), fontsize=8)
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g} kN"))
    ax.tick_params(axis="y", labelsize=7)
    ax.grid(True, alpha=0.4)
    return artists


def running_torque_curves(ax, angle_deg, journals, crankpins):
    """Running torques [N m] against the crank angle [deg]: each main journal after the first
    (solid; the last carries the engine torque) and each crankpin (dashed). Returns the artists."""
    artists = []
    for j in range(1, journals.shape[0]):
        artists += ax.plot(angle_deg, journals[j], lw=1.0, label=f"journal {j + 1}")
    for k in range(crankpins.shape[0]):
        artists += ax.plot(angle_deg, crankpins[k], lw=0.8, ls="--", label=f"crankpin {k + 1}")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("running torque [N m]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
    return artists


def order_bars(ax, orders, amplitude, ylabel, max_order=12.0, width=0.35, offset=0.0,
               label=None, log=False, floor=0.0, **style):
    """Amplitude per engine order (order 0, the mean, left out) up to ``max_order`` as bars;
    amplitudes below ``floor`` (the noise floor of the data, :func:`noise_floor`) are not
    content and are not drawn. Returns the artists."""
    orders = np.asarray(orders)
    amplitude = np.asarray(amplitude)
    sel = (orders > 0.0) & (orders <= max_order + 1e-9) & (amplitude >= floor)
    artists = list(ax.bar(orders[sel] + offset, amplitude[sel], width=width, label=label,
                          log=log, **style))
    ax.set_xlabel("engine order [1/rev]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3, axis="y")
    return artists


def noise_floor(ax, level, words, color="0.3"):
    """A horizontal line at the noise floor ``level`` of a logarithmic panel, labelled
    ``words`` (what sets it): below it the data hold rounding or solver error, not content.
    Returns the line."""
    return ax.axhline(level, color=color, lw=0.9, ls=(0, (4, 2)), label=words, zorder=0.5)


def _order_columns(orders, amplitude, max_order):
    """The orders 0 < ν ≤ ``max_order``, their columns of ``amplitude`` and their cell edges."""
    orders = np.asarray(orders)
    sel = (orders > 0.0) & (orders <= max_order + 1e-9)
    x = orders[sel]
    dx = x[1] - x[0] if x.size > 1 else 1.0
    return x, np.asarray(amplitude, dtype=float)[:, sel], np.concatenate([x - dx / 2,
                                                                         [x[-1] + dx / 2]])


def _log_colours(amp):
    """A logarithmic colour scale over four decades below the largest amplitude, and the
    amplitudes raised to its floor."""
    from matplotlib.colors import LogNorm

    top = float(amp.max()) if amp.size and amp.max() > 0 else 1.0
    return LogNorm(top * 1e-4, top), np.maximum(amp, top * 1e-4)


def order_waterfall(ax, omega_mean_rpm, orders, amplitude, max_order=12.0, label=None):
    """Run-up waterfall as a colour map: the amplitude of each order (x) in each cycle, at the
    cycle's mean speed on a linear speed axis (y), each cycle's band reaching halfway to the
    speeds of the cycles next to it in speed (the steady cycles at the end of a spin-up are a
    thin band at the top); logarithmic colours over four decades below the largest (weaker
    lines at its floor). ``amplitude``: (n_cycles, n_orders) in the unit of the signal,
    ``label`` names it on the colour bar. For a run-up (:func:`transient.analysis.orders.is_run_up`);
    :func:`order_waterfall_cycles` for a steady run. Returns the mesh."""
    _, amp, x_edges = _order_columns(orders, amplitude, max_order)
    w = np.asarray(omega_mean_rpm, dtype=float)
    order = np.argsort(w, kind="stable")
    w, amp = w[order], amp[order]
    if w.size > 1 and w[-1] > w[0]:
        mid = 0.5 * (w[1:] + w[:-1])
        y_edges = np.concatenate([[w[0] - (mid[0] - w[0])], mid, [w[-1] + (w[-1] - mid[-1])]])
    else:
        y_edges = np.linspace(w[0] - 0.5, w[0] + 0.5, w.size + 1) if w.size else np.ones(2)
    norm, shown = _log_colours(amp)
    mesh = ax.pcolormesh(x_edges, y_edges, shown, norm=norm, cmap="viridis", shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label=label or "amplitude")
    ax.set_xlabel("engine order [1/rev]")
    ax.set_ylabel("cycle-mean speed [rpm]")
    return mesh


def order_waterfall_cycles(ax, cycle_numbers, orders, amplitude, max_order=12.0, label=None):
    """Waterfall of a steady run as a colour map: the amplitude of each order (x) in each whole
    cycle, one row per cycle in the order they ran (y), logarithmic colours as
    :func:`order_waterfall`. Returns the mesh."""
    _, amp, x_edges = _order_columns(orders, amplitude, max_order)
    n = np.asarray(cycle_numbers, dtype=float)
    norm, shown = _log_colours(amp)
    mesh = ax.pcolormesh(x_edges, np.append(n - 0.5, n[-1] + 0.5), shown, norm=norm,
                         cmap="viridis", shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label=label or "amplitude")
    ax.set_xlabel("engine order [1/rev]")
    ax.set_ylabel("cycle of the run")
    return mesh


def campbell(ax, omega_mean_rpm, orders, amplitude, max_order=12.0, label=None):
    """Campbell chart: each cycle's orders as points at (cycle-mean speed [rpm], frequency
    ν·n/60 [Hz]), their colour and size the amplitude (logarithmic, four decades), over the
    order lines ν = 1, 2, … (grey rays). ``amplitude``: (n_cycles, n_orders). Returns the
    scatter."""
    from matplotlib.colors import LogNorm

    orders = np.asarray(orders)
    sel = (orders > 0.0) & (orders <= max_order + 1e-9)
    amp = np.asarray(amplitude, dtype=float)[:, sel]
    w = np.asarray(omega_mean_rpm, dtype=float)
    top = float(amp.max()) if amp.size and amp.max() > 0 else 1.0
    speed = np.repeat(w[:, None], sel.sum(), axis=1)
    freq = speed * orders[sel][None, :] / 60.0
    floor = top * 1e-4
    shown = np.maximum(amp, floor)
    size = 4.0 + 60.0 * (np.log10(shown / floor) / 4.0)
    keep = amp >= floor
    dots = ax.scatter(speed[keep], freq[keep], c=shown[keep], s=size[keep], cmap="viridis",
                      norm=LogNorm(floor, top), edgecolors="none")
    span = np.array([0.0, float(w.max()) * 1.05 if w.size else 1.0])
    for nu in range(1, int(max_order) + 1):
        ax.plot(span, span * nu / 60.0, color="0.8", lw=0.6, zorder=0)
        ax.annotate(f"{nu}", (span[1], span[1] * nu / 60.0), fontsize=6, color="0.5")
    ax.figure.colorbar(dots, ax=ax, label=label or "amplitude")
    low = float(w.min()) if w.size else 0.0
    ax.set_xlim(max(0.0, low - 0.1 * max(float(np.ptp(w)) if w.size else 0.0, low)),
                span[1] * 1.04)
    ax.set_xlabel("cycle-mean speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    ax.grid(True, alpha=0.3)
    return dots


def order_tracks(ax, x, tracks, ylabel, xlabel="cycle-mean speed [rpm]", floor=None):
    """Order tracks: the amplitude of each order in ``tracks`` (label → per-cycle amplitude)
    against ``x`` (each cycle's mean speed [rpm], or its number), on a logarithmic axis,
    joined in the order of x (a run-down or an uneven sweep draws no polygon). ``floor``:
    (level, words), the data's noise floor (:func:`noise_floor`), below which a track is not
    drawn, itself drawn where the tracks come within a decade of it. Returns the
    artists."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    artists = []
    for k, (name, v) in enumerate(tracks.items()):
        v = np.asarray(v, dtype=float)[order]
        if floor is not None:
            v = np.where(v >= floor[0], v, np.nan)
        artists += ax.plot(x[order], v, lw=1.0, marker="." if x.size <= 60 else None, ms=3,
                           label=name, ls=DASHES[k % len(DASHES)])
    shown = np.concatenate([np.asarray(v, dtype=float) for v in tracks.values()])
    if floor is not None and np.nanmin(shown, initial=np.inf) < 10.0 * floor[0]:
        artists.append(noise_floor(ax, *floor))  # (drawn only where the data come near it)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    legend_outside(ax)
    return artists


def sweep_line(ax, x, y, failed, xlabel, ylabel):
    """A quantity of a one-axis sweep against the axis; failed runs as crosses on the axis
    line (they have no value). Returns the artists."""
    x, y, failed = np.asarray(x, float), np.asarray(y, float), np.asarray(failed, bool)
    order = np.argsort(x)
    artists = ax.plot(x[order], y[order], marker="o", ms=4, lw=1.0)
    if failed.any():
        artists += ax.plot(x[failed], np.full(failed.sum(), np.nanmin(y) if np.isfinite(y).any()
                                              else 0.0), "rx", ms=8, label="failed run")
        ax.legend(fontsize=8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return artists


def sweep_heatmap(ax, x, y, z, xlabel, ylabel, zlabel):
    """A quantity of a two-axis grid sweep as a heat map: ``z`` of shape (len(y), len(x)), NaN
    (failed or not measured) left blank; each cell is labelled with its value. Returns the
    mesh."""
    z = np.ma.masked_invalid(np.asarray(z, float))
    mesh = ax.pcolormesh(np.arange(len(x) + 1), np.arange(len(y) + 1), z, cmap="viridis",
                         shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label=zlabel)
    ax.set_xticks(np.arange(len(x)) + 0.5, [f"{v:.4g}" for v in x], rotation=45)
    ax.set_yticks(np.arange(len(y)) + 0.5, [f"{v:.4g}" for v in y])
    if z.size <= 100:
        for (i, j), v in np.ndenumerate(z.filled(np.nan)):
            ax.text(j + 0.5, i + 0.5, "–" if np.isnan(v) else f"{v:.4g}", ha="center",
                    va="center", fontsize=7)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    return mesh


def sweep_scatter(ax, x, y, c, xlabel, ylabel, clabel=None):
    """Runs as points (x, y), coloured by ``c`` if given (random or list sweeps). Returns the
    artists."""
    if c is None:
        artists = ax.plot(x, y, "o", ms=4)
    else:
        artists = ax.scatter(x, y, c=c, s=20, cmap="viridis")
        ax.figure.colorbar(artists, ax=ax, label=clabel)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return artists


#: How the Campbell diagram draws an engine order of each kind
#: (:data:`transient.analysis.torsion.ORDER_KINDS`): the major orders bold, the other integer
#: orders dashed, the half orders dotted, so that a grey print tells them apart too.
ORDER_STYLES = {"major": dict(color="C3", lw=1.5, ls="-"),
                "integer": dict(color="0.3", lw=0.8, ls=(0, (5, 2))),
                "half": dict(color="0.55", lw=0.8, ls=(0, (1.5, 1.5)))}


def modal_campbell(ax, modal, orders, speed_range, criticals, run_orders=None, run_label=None,
                   run_largest=None):
    """The Campbell diagram of a shaft line: natural frequency [Hz] against shaft speed [rpm].

    ``modal`` (:class:`transient.analysis.torsion.Modal`): each elastic mode below the highest
    order's line as a line at its cycle-mean frequency, its frozen-angle band shaded; ``orders``
    [1/rev] as lines f = q·n/60, styled by kind (:data:`ORDER_STYLES`) and labelled outside
    the right edge, where they leave the axes; ``criticals``
    (:class:`transient.analysis.torsion.Critical`) marked, their size growing with their
    relative excitation; ``speed_range`` (lo, hi) [rpm] the x axis.
    ``run_orders``: a run's order amplitudes per cycle, (cycle-mean speeds [rpm], orders
    [1/rev], amplitudes (n_cycles, n_orders)) as
    :func:`transient.analysis.torsion_run.campbell_overlay` gives them, drawn on the orders'
    lines at (n, q·n/60), a marker per cycle and order, its area and colour (logarithmic, a
    colour bar under the axes) the amplitude; ``run_label`` names the amplitude and its unit on
    the colour bar, ``run_largest`` is the top of its scale (default: the largest drawn; give
    one to compare the diagrams of several runs); None draws none. Returns the legend's
    handles."""
    from matplotlib.lines import Line2D

    from .analysis.torsion import order_kind

    lo, hi = speed_range
    top = 1.05 * max(orders) * hi / 60.0
    rpm = np.array([lo, hi])
    handles = []
    for mode in modal.modes:
        if mode.band[0] > top:
            continue
        color = f"C{(mode.number - 1) % 10}"
        ax.axhspan(*mode.band, color=color, alpha=0.18, lw=0)
        handles.append(ax.axhline(mode.f, color=color, lw=1.2,
                                  label=f"mode {mode.number}: {mode.f:.4g} Hz "
                                        f"(band {mode.band[0]:.4g}–{mode.band[1]:.4g})"))
    firing = modal.line.scene.mechanism.firing_angles
    for q in orders:
        kind = order_kind(q, firing)
        ax.plot(rpm, q * rpm / 60.0, **ORDER_STYLES[kind])
        # (labelled outside the right spine, where the line leaves the axes: inside they
        # would sit on the modes' bands and the critical speeds near that edge)
        ax.annotate(f"{q:g}", (1.0, q * hi / 60.0), xycoords=("axes fraction", "data"),
                    xytext=(2, 0), textcoords="offset points", fontsize=6, ha="left",
                    va="center", color=ORDER_STYLES[kind]["color"], annotation_clip=False)
    handles += [Line2D([], [], **ORDER_STYLES[k], label=f"{k} orders") for k in ORDER_STYLES]
    if criticals:
        x = [c.rpm for c in criticals]
        y = [c.rpm * c.order / 60.0 for c in criticals]
        size = [12.0 + 48.0 * c.excitation for c in criticals]
        handles.append(ax.scatter(x, y, s=size, facecolor="none", edgecolor="k", lw=0.9,
                                  zorder=3, label="critical speeds (size: relative excitation)"))
    if run_orders is not None:
        handles.append(_run_overlay(ax, *run_orders, label=run_label, largest=run_largest))
    ax.set_xlim(lo, hi)
    ax.set_ylim(0.0, top)
    ax.set_xlabel("shaft speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax, handles=handles, gap=ORDER_LABELS)
    return handles


#: Room [axes width] right of a Campbell diagram for the orders' labels, between its spine
#: and its legend.
ORDER_LABELS = 0.05

#: Decades of amplitude below the largest that a run's overlay on the Campbell diagram shows:
#: weaker orders are the run's noise and the other orders' leakage, and would cover the lines.
OVERLAY_DECADES = 2.0


def _run_overlay(ax, speeds, run_q, amplitude, label=None, largest=None):
    """A run's order amplitudes on a Campbell diagram: a marker at (cycle-mean speed [rpm],
    q·n/60 [Hz]) for each cycle and order, its area ∝ the amplitude and its colour the
    amplitude on a logarithmic scale up to ``largest`` (default the largest amplitude; a colour
    bar under the axes, ``label`` on it), the largest drawn last (on top); amplitudes
    :data:`OVERLAY_DECADES` below the top left out. Returns a handle for the legend."""
    from matplotlib.colors import LogNorm
    from matplotlib.lines import Line2D

    speeds, run_q = np.asarray(speeds, dtype=float), np.asarray(run_q, dtype=float)
    amp = np.abs(np.asarray(amplitude, dtype=float)).reshape(speeds.size, run_q.size)
    if largest is None:
        largest = float(amp.max()) if amp.size and amp.max() > 0 else 1.0
    floor = largest * 10.0 ** -OVERLAY_DECADES
    x = np.repeat(speeds[:, None], run_q.size, axis=1)
    y = x * run_q[None, :] / 60.0
    keep = amp >= floor
    order = np.argsort(amp[keep], kind="stable")
    shown = np.minimum(amp[keep][order], largest)
    dots = ax.scatter(x[keep][order], y[keep][order], s=2.0 + 50.0 * shown / largest,
                      c=shown, cmap="plasma", norm=LogNorm(floor, largest),
                      lw=0, alpha=0.85, zorder=2.5)
    ax.figure.colorbar(dots, ax=ax, orientation="horizontal", location="bottom", fraction=0.05,
                       pad=0.08, aspect=40, label=label or "run's order amplitude")
    return Line2D([], [], marker="o", ls="", color=dots.cmap(0.7),
                  label="the run's order amplitudes (area, colour)")


def cycle_curves(ax, x, curves, ylabel, xlabel="cycle-mean speed [rpm]"):
    """Quantities of a run cycle by cycle (``curves``: label → one value per cycle) against
    ``x`` (each cycle's mean speed [rpm], or its number), joined in the order of x, each in its
    own dash pattern (:data:`DASHES`); the legend right of the axes. Returns the artists."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    artists = []
    for k, (name, v) in enumerate(curves.items()):
        artists += ax.plot(x[order], np.asarray(v, dtype=float)[order], lw=1.0,
                           marker="." if x.size <= 60 else None, ms=3, label=name,
                           ls=DASHES[k % len(DASHES)], color=f"C{k % 10}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if artists:
        legend_outside(ax)
    return artists


def torsional_response(axes, res, criticals, leading: int = 6):
    """The steady forced response of a shaft line against mean speed [rpm], on two axes.

    ``res`` (:class:`transient.analysis.torsional_response.ForcedResponse`). Top: each
    element's vibratory torque over all the orders, half the synthesised peak-to-peak (an
    amplitude, comparable with one order's). Bottom: the most loaded element's, with the sum of
    its orders' amplitudes (the classical bound) and its ``leading`` largest orders, styled by
    kind (:data:`ORDER_STYLES`' colours cycled within a kind). ``criticals``
    (:class:`transient.analysis.torsion.Critical`) marked on both as vertical lines, labelled
    order/mode on the top axes. Returns the index of the most loaded element."""
    from .analysis.torsion import order_kind
    from .analysis.torsional_response import leading_orders

    top, bottom = axes
    rpm = res.rpm
    half = 0.5 * res.torque_pp
    for e, label in enumerate(res.elements):
        top.plot(rpm, half[:, e], lw=1.1, label=label)
    worst = int(np.argmax(half.max(axis=0)))
    bottom.plot(rpm, half[:, worst], color="k", lw=1.6, label="all orders (½ peak-to-peak)")
    bottom.plot(rpm, res.torque_sum[:, worst], color="k", lw=0.9, ls="--",
                label="sum of the orders' amplitudes")
    firing = res.line.scene.mechanism.firing_angles
    for n, j in enumerate(leading_orders(res, worst, leading)):
        q = float(res.orders[j])
        kind = order_kind(q, firing)
        bottom.plot(rpm, np.abs(res.torque[:, j, worst]), color=f"C{n}", lw=1.0,
                    ls=ORDER_STYLES[kind]["ls"] if kind != "major" else "-",
                    label=f"order {q:g} ({kind})")
    for ax in axes:
        for c in criticals:
            ax.axvline(c.rpm, color="0.6", lw=0.6, ls=":", zorder=0)
        ax.set_xlim(float(rpm[0]), float(rpm[-1]))
        ax.set_ylim(bottom=0.0)
        ax.set_ylabel("vibratory torque [N m]")
        ax.grid(True, alpha=0.3)
    for c in criticals:
        top.annotate(f"{c.order:g}/{c.mode}", (c.rpm, 1.0), xycoords=("data", "axes fraction"),
                     fontsize=6, rotation=90, ha="right", va="top", color="0.4")
    top.set_title("vibratory torque amplitude of each element, all orders (½ peak-to-peak); "
                  "critical speeds dotted, labelled order/mode", fontsize=9)
    bottom.set_title(f"{res.elements[worst]}: all orders and the leading orders", fontsize=9)
    bottom.set_xlabel("mean shaft speed [rpm]")
    legend_outside(top)
    legend_outside(bottom)
    return worst


#: Line styles of the speeds where instability regions may open, by kind
#: (:class:`transient.analysis.floquet.Resonance`).
RESONANCE_STYLES = {"principal": dict(color="C3", ls="--"), "second": dict(color="C1", ls=":"),
                    "combination": dict(color="C2", ls="-.")}


def floquet_chart(ax, res, resonances=()):
    """The parametric stability of a shaft line against mean speed [rpm]: the twist's largest
    growth per revolution, g·ln|μ|max in e-folds (``res``,
    :class:`transient.analysis.floquet.Floquet`), the unstable speeds shaded, and the speeds
    where regions may open (``resonances``, :class:`~transient.analysis.floquet.Resonance`)
    as vertical lines labelled with their condition (principal dashed, second dotted,
    combination dash-dotted)."""
    rpm, growth = res.rpm, res.growth_per_rev
    ax.plot(rpm, growth, color="k", lw=1.2, label="growth per revolution, g·ln|μ|max")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.fill_between(rpm, 0.0, 1.0, where=res.unstable, transform=ax.get_xaxis_transform(),
                    color="C3", alpha=0.15, lw=0, label="parametrically unstable")
    seen = set()
    for r in resonances:
        style = RESONANCE_STYLES[r.kind]
        ax.axvline(r.rpm, lw=0.7, zorder=0, label=None if r.kind in seen else
                   f"{r.kind} resonance, hΩ = (ω_i + ω_j)/k", **style)
        seen.add(r.kind)
        ax.annotate(r.label, (r.rpm, 1.0), xycoords=("data", "axes fraction"), fontsize=6,
                    rotation=90, ha="right", va="top", color=style["color"])
    ax.set_xlim(float(rpm[0]), float(rpm[-1]))
    ax.set_xlabel("mean shaft speed [rpm]")
    ax.set_ylabel("twist growth per revolution [e-folds]")
    ax.grid(True, alpha=0.3)
    legend_outside(ax)
