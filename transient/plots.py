"""Plot helpers: each takes an ``ax`` and returns the artists; callers make and save figures.

Where a helper plots a run, ``traj`` is a :class:`~transient.results.Result` or its trajectory
(a mapping of column name to samples)."""
from __future__ import annotations

import math

import numpy as np


def _columns(traj):
    """The trajectory of a Result, or ``traj`` itself."""
    return getattr(traj, "trajectory", traj)


def speed(ax, traj, label=None):
    """ω(t) [rpm]."""
    traj = _columns(traj)
    artists = ax.plot(traj["t"], traj["omega"] * 30.0 / math.pi, lw=1.0, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("ω [rpm]")
    ax.grid(True, alpha=0.3)
    return artists


def acceleration(ax, traj, label=None):
    """ε(t) [rad/s²]."""
    traj = _columns(traj)
    artists = ax.plot(traj["t"], traj["epsilon"], lw=0.6, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("ε [rad/s²]")
    ax.grid(True, alpha=0.3)
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
    ax.legend(fontsize=8)
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
    """(label "i of n", sample mask, start angle) of each of ``cylinder``'s own whole cycles asked
    for (indices as in a list: −1 the last); ValueError for an index the run does not hold."""
    from .analysis.thermo import own_cycles

    starts = own_cycles(scene, traj, cylinder)
    phi = traj["phi"]
    fuel = _cycle_fuel(scene)
    out = []
    for c in cycles:
        if not -starts.size <= c < starts.size:
            raise ValueError(f"cycle {c} is out of range: cylinder {cylinder} has "
                             f"{starts.size} whole cycle(s) in the run (allowed "
                             f"{-starts.size} … {starts.size - 1})")
        a = starts[c]
        note = fuel(cylinder, a + 0.5 * scene.mechanism.cycle)
        out.append((f"{c % starts.size + 1} of {starts.size}{note}",
                    (phi >= a) & (phi <= a + scene.mechanism.cycle), a))
    return out


def _cycle_fuel(scene):
    """``note(cylinder, φ)``: how the ``[[gas.cylinders]]`` entries set the fuel of the
    cylinder's cycle at the shaft angle φ, for a label: ", misfire", ", cut out", ", fuel 0.8"
    or ""."""
    if not scene.gas.cylinders:
        return lambda cylinder, phi: ""
    from .assemble import build_model
    from .core.model.variation import FUEL, cycle_fuel

    model = build_model(scene)[0]

    def note(cylinder, phi):
        f = cycle_fuel(model, cylinder - 1, phi)
        if f == 1.0:
            return ""
        if f != 0.0:
            return f", fuel {f:g}"
        return ", cut out" if model.var_par[cylinder - 1, FUEL] == 0.0 else ", misfire"
    return note


def run_indicator_phi(ax, traj, scene, cylinders=None, cycles=(-1,), table=None, motored=None):
    """The pressure the run applied [MPa] against each cylinder's own (local) angle [deg], over
    its whole cycles ``cycles`` (−1: the last), for ``cylinders`` (1-based; None: all).
    ``table``, ``motored``: the full-load and motored curves (each a
    :class:`~transient.forces.gas.PressureTable`, or None) drawn dashed and dotted for
    comparison: a misfiring cycle lies on the motored one. Returns the artists."""
    traj = _columns(traj)
    from .analysis.thermo import local_angle

    artists = []
    for k in _cylinders(scene, cylinders):
        for c, sel, a in _cycle_samples(traj, scene, k, cycles):
            artists += ax.plot(np.degrees(local_angle(scene, traj["phi"][sel], a)),
                               traj[f"p_{k}"][sel] / 1e6, lw=1.0, label=f"cylinder {k}, cycle {c}")
    x = local_angle(scene, np.linspace(0.0, scene.mechanism.cycle, 2881), 0.0)
    for curve, style, label in ((table, "--", "input table, full fuel"),
                                (motored, ":", "motored (no fuel)")):
        if curve is not None:
            artists += ax.plot(np.degrees(x), curve(x) / 1e6, lw=0.8, ls=style, color="0.4",
                               label=label)
    ax.set_xlabel("cylinder's own crank angle [deg]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return artists


def run_indicator_pv(ax, traj, scene, cylinders=None, cycles=(-1,), log=True):
    """p–V diagram of the run: the pressure applied [MPa] against the cylinder's exact volume
    [dm³] (:func:`transient.analysis.thermo.cylinder_volumes`; the swept part only where the gas
    model gives no clearance), log-log unless ``log`` is False. Returns the artists."""
    traj = _columns(traj)
    from .analysis.thermo import cylinder_volumes

    plot = ax.loglog if log else ax.plot
    artists = []
    for k in _cylinders(scene, cylinders):
        for c, sel, _ in _cycle_samples(traj, scene, k, cycles):
            V = cylinder_volumes(scene, traj["phi"][sel]).V[k - 1]
            artists += plot(V * 1e3, traj[f"p_{k}"][sel] / 1e6, lw=1.0,
                            label=f"cylinder {k}, cycle {c}")
    ax.set_xlabel("V [dm³]")
    ax.set_ylabel("p [MPa]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
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
        for c, _, a in _cycle_samples(traj, scene, k, cycles):
            got = heat_release_rate(scene, traj, k, a)
            if got is not None:
                artists += ax.plot(np.degrees(got[0]), got[1] * math.pi / 180.0, lw=1.0,
                                   label=f"cylinder {k}, cycle {c}")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("cylinder's own crank angle [deg]")
    ax.set_ylabel("dQ/dφ [J/deg]")
    ax.grid(True, alpha=0.3)
    if artists:
        ax.legend(fontsize=7)
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
    rpm = 30.0 / math.pi
    x = np.degrees(traj["phi"][sel] - a)
    w = traj["omega"][sel] * rpm
    mean = cycle / (tb[-1] - tb[-2]) * rpm
    artists = ax.plot(x, w, lw=1.2, label="ω")
    i, j = int(np.argmax(w)), int(np.argmin(w))
    artists.append(ax.axhline(mean, color="k", lw=0.6, ls="--", label="cycle mean"))
    artists += ax.plot([x[i], x[j]], [w[i], w[j]], "o", color="C3", ms=4)
    artists.append(ax.annotate("", xy=(x[i], w[j]), xytext=(x[i], w[i]),
                               arrowprops={"arrowstyle": "<->", "color": "C3", "lw": 0.8}))
    artists.append(ax.text(x[i], 0.5 * (w[i] + w[j]), f"  δ = {(w[i] - w[j]) / mean:.4g}",
                           color="C3", va="center", fontsize=9))
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("ω [rpm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
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
    artists = [ax.plot(x, m, lw=0.9, label=f"cylinder {k + 1}")[0]
               for k, m in enumerate(torques)]
    artists += ax.plot(x, torques.sum(axis=0), lw=1.6, color="k", label="sum (M_gas)")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("M [N m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
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
    a_m.legend(fontsize=8)
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


def pair_power(ax, traj, names, cycle):
    """Power each non-ideal pair transmits, S_k ω [kW] (> 0: the shaft side drives), and the
    power it loses, over the last cycle against the crank angle in that cycle."""
    traj = _columns(traj)
    sel = last_cycle(traj, cycle)
    phi = np.degrees(traj["phi"][sel] - traj["phi"][sel][0])
    w = traj["omega"][sel]
    artists = []
    for k, name in enumerate(names, start=1):
        line = ax.plot(phi, traj[f"S_{k}"][sel] * w / 1e3, lw=1.0, label=f"{name}: transmitted")[0]
        artists.append(line)
        artists += ax.plot(phi, traj[f"P_loss_{k}"][sel] / 1e3, lw=1.0, ls="--",
                           color=line.get_color(), label=f"{name}: lost")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel("power [kW]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
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
    ax.legend(fontsize=8)
    return artists


def load_response(axes, traj, cycle, analysis):
    """Speed (as run, and its one-cycle mean), fuel command and load torque against time, with
    each load step's ±band around its new steady speed (``analysis``: the run's ``/analysis``
    entries, name → (value, unit)). ``axes``: three axes sharing t. Returns the artists."""
    traj = _columns(traj)
    from .analysis.transient_response import cycle_mean_speed

    rpm = 30.0 / math.pi
    a_w, a_f, a_m = axes
    t = traj["t"]
    artists = a_w.plot(t, traj["omega"] * rpm, lw=0.5, color="0.6", label="ω")
    tm, wm = cycle_mean_speed(t, traj["phi"], cycle, traj["omega"])
    artists += a_w.plot(tm, wm * rpm, lw=1.2, color="C0", label="cycle mean")
    k = 1
    while f"load_change_{k}_t_s" in analysis:
        p = f"load_change_{k}_"
        t0, t1 = analysis[p + "t_s"][0], analysis[p + "t_end_s"][0]
        w_ss, band = analysis[p + "omega_after_rad_s"][0], analysis[p + "band_pct"][0] / 100.0
        w_ref = analysis[p + "omega_rated_rad_s"][0]
        artists.append(a_w.fill_between([t0, t1], (w_ss - band * w_ref) * rpm,
                                        (w_ss + band * w_ref) * rpm, color="C2", alpha=0.25,
                                        label="±band" if k == 1 else None))
        for ax in axes:
            artists.append(ax.axvline(t0, color="k", lw=0.6, ls=":"))
        if analysis[p + "recovered"][0]:
            artists.append(a_w.axvline(t0 + analysis[p + "recovery_s"][0], color="C2", lw=0.8))
        k += 1
    a_w.set_ylabel("ω [rpm]")
    a_w.legend(fontsize=8, loc="best")
    artists += a_f.plot(t, traj["fuel"], lw=1.0, color="C1")
    a_f.set_ylabel("fuel command [1]")
    artists += a_m.plot(t, -traj["M_load"], lw=1.0, color="C3")
    a_m.set_ylabel("load torque [N m]")
    a_m.set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return artists


def polar_load(ax, x, y, label=None, scale=1e-3):
    """Polar load diagram: the end points of a load vector (x, y) [N] drawn from the pole, in kN
    by default (``scale``). The caller picks the frame; the largest vector is drawn as an arrow.
    Returns the artists."""
    x = np.asarray(x) * scale
    y = np.asarray(y) * scale
    artists = ax.plot(x, y, lw=1.0, label=label)
    k = int(np.argmax(np.hypot(x, y)))
    artists.append(ax.annotate("", xy=(x[k], y[k]), xytext=(0.0, 0.0),
                               arrowprops={"arrowstyle": "->", "color": artists[0].get_color(),
                                           "lw": 0.8}))
    artists += ax.plot([0.0], [0.0], "k+", ms=8)
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.axvline(0.0, color="0.7", lw=0.5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    return artists


def crankpin_polar(ax, R_K, R_T, label=None):
    """Polar diagram of a crankpin load [N] in the crank frame, in kN: the crank pointing up (+y,
    outward), +x the direction of rotation, so the load R_T t̂ − R_K ĉ is drawn as (R_T, −R_K) —
    the frame of ``transient loads``. Takes a crank-slider's ``CylinderLoads`` rows or a radial
    row's master crankpin (``ArticulatedLoads.R_K[j]``, ``R_T[j]``). Returns the artists."""
    artists = polar_load(ax, R_T, -np.asarray(R_K), label=label)
    ax.set_xlabel("R_T [kN] (direction of rotation)")
    ax.set_ylabel("−R_K [kN] (crank outward)")
    return artists


def load_against_angle(ax, angle_deg, values, label=None, ylabel="|R| [kN]", scale=1e-3):
    """A load [N] (plotted in kN by default) against the crank angle [deg], with its mean as a
    dashed line. Returns the artists."""
    v = np.asarray(values) * scale
    artists = ax.plot(angle_deg, v, lw=1.0, label=label)
    artists.append(ax.axhline(float(np.mean(v)), color=artists[0].get_color(), lw=0.8, ls="--"))
    ax.set_xlabel("crank angle in the last cycle [deg]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return artists


def wear_diagram(ax, ray_deg, sums, label=None):
    """Conventional wear diagram: the journal as a unit circle and each ray's load sum plotted
    inward from it (Gots §2.6), scaled so that the largest sum reaches half the radius. ``ray_deg``
    are the ray directions in the frame of the matching polar diagram (counter-clockwise from its
    +x axis). Returns the artists."""
    th = np.radians(np.append(ray_deg, ray_deg[0]))
    s = np.append(sums, sums[0])
    top = float(np.max(s)) if np.max(s) > 0 else 1.0
    inner = 1.0 - 0.5 * s / top
    c = np.linspace(0.0, 2.0 * math.pi, 361)
    artists = ax.plot(np.cos(c), np.sin(c), color="k", lw=0.8)
    artists += ax.plot(inner * np.cos(th), inner * np.sin(th), lw=1.2, label=label)
    artists.append(ax.fill(np.concatenate([np.cos(th), inner[::-1] * np.cos(th[::-1])]),
                           np.concatenate([np.sin(th), inner[::-1] * np.sin(th[::-1])]),
                           alpha=0.3, lw=0, color=artists[-1].get_color())[0])
    for a in th[:-1]:
        ax.plot([0.0, math.cos(a)], [0.0, math.sin(a)], color="0.85", lw=0.4)
    k = int(np.argmin(sums))
    artists += ax.plot([math.cos(th[k])], [math.sin(th[k])], "v", color="C3",
                       label="least loaded ray")
    ax.set_aspect("equal")
    ax.set_xlim(-1.1, 1.1)
    ax.set_ylim(-1.1, 1.1)
    ax.set_xticks([])
    ax.set_yticks([])
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
    ax.legend(fontsize=7, ncol=2)
    return artists


def order_bars(ax, orders, amplitude, ylabel, max_order=12.0, width=0.35, offset=0.0,
               label=None, log=False):
    """Amplitude per engine order (order 0, the mean, left out) up to ``max_order`` as bars.
    Returns the artists."""
    orders = np.asarray(orders)
    sel = (orders > 0.0) & (orders <= max_order + 1e-9)
    artists = list(ax.bar(orders[sel] + offset, np.asarray(amplitude)[sel], width=width,
                          label=label, log=log))
    ax.set_xlabel("engine order [1/rev]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3, axis="y")
    return artists


def order_waterfall(ax, omega_mean_rpm, orders, amplitude, max_order=12.0, label=None):
    """Run-up waterfall as a colour map: the amplitude of each order (x) in each cycle, placed at
    the cycle's mean speed (y), on a logarithmic colour scale over four decades below the
    largest (weaker lines are drawn at its floor). ``amplitude``: (n_cycles, n_orders) in the
    unit of the signal, ``label`` names it on the colour bar. Returns the mesh."""
    from matplotlib.colors import LogNorm

    orders = np.asarray(orders)
    sel = (orders > 0.0) & (orders <= max_order + 1e-9)
    amp = np.asarray(amplitude, dtype=float)[:, sel]
    w = np.asarray(omega_mean_rpm, dtype=float)
    top = float(amp.max()) if amp.size and amp.max() > 0 else 1.0
    x = orders[sel]
    dx = x[1] - x[0] if x.size > 1 else 1.0
    x_edges = np.concatenate([x - dx / 2, [x[-1] + dx / 2]])
    # each cycle's band reaches halfway to its neighbours' speeds
    if w.size > 1:
        mid = 0.5 * (w[1:] + w[:-1])
        y_edges = np.concatenate([[w[0] - (mid[0] - w[0])], mid, [w[-1] + (w[-1] - mid[-1])]])
    else:
        y_edges = np.array([w[0] - 0.5, w[0] + 0.5]) if w.size else np.array([0.0, 1.0])
    order = np.argsort(w)
    if np.all(np.diff(w) > 0) or w.size < 2:
        mesh = ax.pcolormesh(x_edges, y_edges, np.maximum(amp, top * 1e-4),
                             norm=LogNorm(top * 1e-4, top), cmap="viridis", shading="flat")
    else:  # not monotonic in speed (a run-down or a load step): one row per cycle, speed labels
        mesh = ax.pcolormesh(x_edges, np.arange(w.size + 1), np.maximum(amp[order], top * 1e-4),
                             norm=LogNorm(top * 1e-4, top), cmap="viridis", shading="flat")
        ticks = np.linspace(0, w.size - 1, min(w.size, 8)).round().astype(int)
        ax.set_yticks(ticks + 0.5, [f"{w[order][i]:.0f}" for i in ticks])
    ax.figure.colorbar(mesh, ax=ax, label=label or "amplitude")
    ax.set_xlabel("engine order [1/rev]")
    ax.set_ylabel("cycle-mean speed [rpm]")
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


def order_tracks(ax, omega_mean_rpm, tracks, ylabel):
    """Campbell-style order tracks: the amplitude of each order in ``tracks`` (label → per-cycle
    amplitude) against the cycle-mean speed [rpm]. Returns the artists."""
    artists = [ax.plot(omega_mean_rpm, v, lw=1.0, marker=".", ms=3, label=k)[0]
               for k, v in tracks.items()]
    ax.set_xlabel("cycle-mean speed [rpm]")
    ax.set_ylabel(ylabel)
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
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
