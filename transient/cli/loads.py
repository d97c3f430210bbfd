"""``transient loads``: load diagrams of a stored run's last whole cycle as PNG and CSV files
(:mod:`transient.analysis.loads.diagrams`); the result file is only read."""
from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..mechanisms import MECHANISMS, PluginTable, provider, provides
from ..mechanisms.crank_slider import MAX_CYLINDERS
from .common import (
    EXIT_OK,
    add_force,
    output_folder,
    pyplot,
    read_result,
    result_stem,
    save,
    whole,
    write_columns,
)

#: The loads' names in the CSV where Gots' letter means something else in a result: Gots' S,
#: the force along the rod, is ``S_rod`` (a result's ``S_k`` is the moment pair k transmits).
CSV_NAMES = {"S": "S_rod"}


def register(sub) -> None:
    lo = sub.add_parser(
        "loads", help="bearing loads and running torques along a result (PNG + CSV)",
        description="Loads along the stored trajectory (transient.analysis.loads): polar "
                    "diagrams of the crankpin and of the most loaded main journal, |R| over the "
                    "last cycle, the wear diagram (Gots §2.6, ±60° rule), running torques; peak "
                    "values on standard output; the last cycle's loads as CSV. Results are "
                    "written as files into DIR, never into the HDF5 result (read only here).")
    lo.add_argument("result")
    lo.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    lo.add_argument("--cylinder", type=whole(1, MAX_CYLINDERS), default=1,
                    help="cylinder (1-based, from the nose) whose crankpin is drawn (default 1)")
    add_force(lo)
    lo.set_defaults(func=cmd_loads)


def _loads_scene(res):
    """The result's scene, or a one-line error (exit 2) if ``transient loads`` draws nothing for
    its mechanism (:data:`DRAWERS`)."""
    scene = res.scene()
    if provider(scene.mechanism, "drawers", DRAWERS) is None:
        drawn = " and ".join(name for name, cls in MECHANISMS.items()
                             if provides(cls, "drawers"))
        raise SceneError("mechanism.type", f"load diagrams are drawn for {drawn} engines, not "
                                           f"{type(scene.mechanism).__name__} (its forces are "
                                           f"stored by [analysis] loads = true)",
                         file=str(res.path))
    return scene


def _diagrams(compute, res, *args):
    """``compute(*args)``, a run shorter than a cycle being a one-line error (exit 2)."""
    from ..analysis.irregularity import NoWholeCycle

    try:
        return compute(*args)
    except NoWholeCycle as exc:
        raise SceneError("(trajectory)", str(exc), file=str(res.path)) from None


def cmd_loads(args) -> int:
    res = read_result(args.result)
    scene = _loads_scene(res)
    return provider(scene.mechanism, "drawers", DRAWERS)(args, res, scene)


def _crank_slider_loads(args, res, scene) -> int:
    """``transient loads`` of a crank-slider engine: the chosen cylinder's crankpin (polar), the
    most loaded main journal, the wear diagram, running torques, and a CSV."""
    from ..analysis.loads.diagrams import crank_slider_diagrams

    mech = scene.mechanism
    n_cyl = mech.n_cylinders
    if not 1 <= args.cylinder <= n_cyl:
        raise SceneError("--cylinder", f"must be 1 … {n_cyl}, got {args.cylinder}")
    d = _diagrams(crank_slider_diagrams, res, scene, res.trajectory, args.cylinder)
    win, deg, loads = d.window.columns, d.window.angle_deg, d.loads
    k = args.cylinder - 1
    out = output_folder(args.output, res.path.parent)
    stem = result_stem(res.path)
    written = [save(fig, out / f"{stem}_{name}.png", args.force, res)
               for name, fig in crank_slider_figures(scene, d)]
    rays, sums = d.crankpin_wear

    cols = {"t_s": win["t"], "phi_rad": win["phi"], "cycle_angle_deg": deg,
            "omega_rad_s": win["omega"], "epsilon_rad_s2": win["epsilon"]}
    for j in range(n_cyl):
        for name in ("P_g", "P_j", "P", "N", "S", "K", "T", "R_K", "R_T", "R"):
            cols[f"{CSV_NAMES.get(name, name)}_{j + 1}_N"] = getattr(loads, name)[j]
        cols[f"M_{j + 1}_Nm"] = loads.torque[j]
    cols["M_engine_Nm"] = d.engine_torque
    for j in range(d.journal_torques.shape[0]):
        cols[f"M_journal_{j + 1}_Nm"] = d.journal_torques[j]
    for j in range(d.crankpin_torques.shape[0]):
        cols[f"M_crankpin_{j + 1}_Nm"] = d.crankpin_torques[j]
    for j in range(d.main_journals.x.shape[0]):
        cols[f"R_main_{j + 1}_N"] = d.main_journals.magnitude[j]
    csv = out / f"{stem}_loads.csv"
    write_columns(csv, cols, args.force)
    written.append(csv)

    area = loads.area
    start = d.window.start
    print(f"{res.path}: loads over the last cycle (φ = {start:.6g} … "
          f"{start + mech.cycle:.6g} rad, {d.window.samples} samples)")
    for j in range(n_cyl):
        i = int(np.argmax(loads.R[j]))
        print(f"  {_pin(mech, j)}: |R| max {loads.R[j][i] / 1e3:.6g} kN "
              f"({loads.R[j][i] / area / 1e6:.4g} MPa on the piston area) at "
              f"{deg[i]:.4g}° of the cycle, mean {np.mean(loads.R[j]) / 1e3:.6g} kN, "
              f"min {loads.R[j].min() / 1e3:.6g} kN")
    s, n = loads.S[k], loads.N[k]
    print(f"  cylinder {args.cylinder}: rod force S from {s.min() / 1e3:.6g} to "
          f"{s.max() / 1e3:.6g} kN (compression > 0), side force |N| max "
          f"{np.abs(n).max() / 1e3:.6g} kN, T from {loads.T[k].min() / 1e3:.6g} to "
          f"{loads.T[k].max() / 1e3:.6g} kN")
    m = d.engine_torque
    print(f"  engine torque Σ T r: mean {np.mean(m):.6g} N m (sample mean), from "
          f"{m.min():.6g} to {m.max():.6g} N m")
    for j in range(d.main_journals.x.shape[0]):
        print(f"  main journal {j + 1}: |R| max {d.main_journals.magnitude[j].max() / 1e3:.6g} kN")
    for j in range(1, d.journal_torques.shape[0]):
        print(f"  running torque journal {j + 1}: max |M| "
              f"{np.abs(d.journal_torques[j]).max():.6g} N m")
    for j in range(d.crankpin_torques.shape[0]):
        print(f"  running torque crankpin {j + 1}: max |M| "
              f"{np.abs(d.crankpin_torques[j]).max():.6g} N m")
    print(f"  wear diagram of {_pin(mech, k)}: least loaded ray at "
          f"{rays[np.argmin(sums)]:g}° (counter-clockwise from the direction of rotation, "
          f"crank up)")
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def crank_slider_figures(scene, d):
    """The figures ``transient loads`` draws of a crank-slider run's diagrams ``d``
    (:func:`~transient.analysis.loads.diagrams.crank_slider_diagrams`): (name, figure) pairs,
    each saved as ``<stem>_<name>.png``."""
    from .. import plots
    from ..analysis.loads.diagrams import dead_centres

    plt = pyplot()
    mech = scene.mechanism
    k, best, deg = d.cylinder - 1, d.most_loaded, d.window.angle_deg
    fig, axes = plt.subplots(1, 2, figsize=(13, 7), layout="constrained")
    plots.polar_load(axes[0], d.crankpin_x, d.crankpin_y, angle_deg=deg,
                     dead_centres=dead_centres(scene, d.window, d.cylinder), legend=False,
                     title=f"{_pin(mech, k)}, crank frame; TDCs of cylinder {d.cylinder}")
    axes[0].set_xlabel("R_T = T + T_rod [kN] (direction of rotation)")
    axes[0].set_ylabel("−R_K = −(K + K_rod) [kN] (crank outward)")
    plots.polar_load(axes[1], d.journal_x, d.journal_y, angle_deg=deg,
                     dead_centres=dead_centres(scene, d.window, 1), legend=False,
                     title=f"main journal {best + 1} (the most loaded), frame of crank 1 "
                           f"(split beam, (58)); TDCs of cylinder 1")
    axes[1].set_xlabel("R_x [kN] (along T₁, direction of rotation)")
    axes[1].set_ylabel("−R_y [kN] (crank 1 outward)")
    _polar_legend(fig, axes[0])
    fig.suptitle(f"{scene.name}: polar load diagrams over the last cycle (angles: crank angle "
                 f"in the cycle)")
    yield "loads_polar", fig

    fig, ax = plt.subplots(figsize=(9, 4.5))
    for j in range(mech.n_cylinders):
        plots.load_against_angle(ax, deg, d.loads.R[j], label=_pin(mech, j),
                                 style=plots.cylinder_style(j + 1))
    plots.legend_outside(ax)
    ax.set_title(f"{scene.name}: crankpin load |R| over the last cycle (dashed: mean)")
    yield "loads_crankpin", fig

    fig, axes = plt.subplots(1, 2, figsize=(12, 6.5), layout="constrained",
                             subplot_kw={"projection": "polar"})
    for ax, (rays, sums), words in (
            (axes[0], d.crankpin_wear, f"{_pin(mech, k)}: its crank frame, 0° the direction "
                                       f"of rotation, 90° the crank outward"),
            (axes[1], d.journal_wear, f"main journal {best + 1}: the frame of crank 1")):
        plots.wear_diagram(ax, rays, sums / d.wear_weight)
        ax.set_title(words, fontsize=9)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2,
               fontsize=8)
    fig.suptitle(f"{scene.name}: wear diagrams (Gots §2.6): each ray's load, the cycle mean of "
                 f"the loads within ±60° of it [kN], drawn inward from the rim", fontsize=10)
    yield "loads_wear", fig

    fig, ax = plt.subplots(figsize=(9, 4.5))
    plots.running_torque_curves(ax, deg, d.journal_torques, d.crankpin_torques)
    ax.set_title(f"{scene.name}: running torques over the last cycle (Gots §2.8)")
    yield "loads_running_torques", fig


def _polar_legend(fig, ax):
    """One legend below the polar diagrams, which share their marks, from ``ax``'s (the dead
    centres named without their angles, which differ from diagram to diagram)."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, [label.split(" (")[0] if "TDC" in label else label for label in labels],
               loc="outside lower center", ncol=len(labels), fontsize=8)


def _pin(mech, k: int) -> str:
    """Where cylinder k's (0-based) rod bears: its crankpin, or a crankpin two rods share."""
    if mech.cylinders_per_throw == 1:
        return f"crankpin {k + 1}"
    return f"rod {k + 1} on crankpin {mech.throw_of_cylinder()[k] + 1}"


def _radial_loads(args, res, scene) -> int:
    """``transient loads`` of an articulated engine: each row's master crankpin in its crank
    frame (polar), the crankpin and link-pin loads over the last cycle, and a CSV; main journals
    and running torques do not apply."""
    from ..analysis.loads.diagrams import articulated_diagrams

    mech = scene.mechanism
    d = _diagrams(articulated_diagrams, res, scene, res.trajectory)
    win, deg, loads = d.window.columns, d.window.angle_deg, d.loads
    rows, n_links = loads.R.shape[0], loads.link_x.shape[0]
    out = output_folder(args.output, res.path.parent)
    stem = result_stem(res.path)
    written = [save(fig, out / f"{stem}_{name}.png", args.force, res)
               for name, fig in articulated_figures(scene, d)]
    cols = {"t_s": win["t"], "phi_rad": win["phi"], "cycle_angle_deg": deg,
            "omega_rad_s": win["omega"], "epsilon_rad_s2": win["epsilon"]}
    for k in range(loads.P.shape[0]):
        for name in ("P_g", "P_j", "P", "N", "S", "torque"):
            cols[f"{CSV_NAMES.get(name, name)}_{k + 1}_{'Nm' if name == 'torque' else 'N'}"] = \
                getattr(loads, name)[k]
    for i in range(n_links):
        cols[f"link_x_{i + 1}_N"], cols[f"link_y_{i + 1}_N"] = loads.link_x[i], loads.link_y[i]
    for j in range(rows):
        for name in ("K", "T", "R_K", "R_T", "R"):
            cols[f"{name}_row{j + 1}_N"] = getattr(loads, name)[j]
    csv = out / f"{stem}_loads.csv"
    write_columns(csv, cols, args.force)
    written.append(csv)
    start = d.window.start
    print(f"{res.path}: loads over the last cycle (φ = {start:.6g} … "
          f"{start + mech.cycle:.6g} rad, {d.window.samples} samples)")
    for j in range(rows):
        i = int(np.argmax(loads.R[j]))
        print(f"  master crankpin, row {j + 1}: |R| max {loads.R[j][i] / 1e3:.6g} kN at "
              f"{deg[i]:.4g}° of the cycle, mean {np.mean(loads.R[j]) / 1e3:.6g} kN")
    for i in range(n_links):
        print(f"  link pin {i + 1}: |F| max {d.link_load[i].max() / 1e3:.6g} kN")
    for path in written:
        print(f"  wrote {path}")
    return EXIT_OK


def articulated_figures(scene, d):
    """The figures ``transient loads`` draws of an articulated run's diagrams ``d``
    (:func:`~transient.analysis.loads.diagrams.articulated_diagrams`): (name, figure)
    pairs."""
    from .. import plots
    from ..analysis.loads.diagrams import dead_centres

    plt = pyplot()
    loads, deg = d.loads, d.window.angle_deg
    rows, n_links = loads.R.shape[0], loads.link_x.shape[0]
    per_row = scene.mechanism.n_cylinders // rows
    fig, axes = plt.subplots(1, rows, figsize=(7.5 * rows, 6.5), squeeze=False,
                             layout="constrained")
    for j in range(rows):
        plots.crankpin_polar(axes[0, j], loads.R_K[j], loads.R_T[j], angle_deg=deg,
                             dead_centres=dead_centres(scene, d.window, j * per_row + 1),
                             legend=False,
                             title=f"master crankpin of row {j + 1}, crank frame; TDCs of its "
                                   f"master cylinder {j * per_row + 1}")
    _polar_legend(fig, axes[0, 0])
    fig.suptitle(f"{scene.name}: polar load diagram over the last cycle (angles: crank angle "
                 f"in the cycle)")
    yield "loads_polar", fig
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for j in range(rows):
        plots.load_against_angle(ax, deg, loads.R[j], label=f"crankpin, row {j + 1}",
                                 style={"color": "k", "ls": plots.DASHES[j % len(plots.DASHES)]})
    for i in range(n_links):
        plots.load_against_angle(ax, deg, d.link_load[i], label=f"link pin {i + 1}",
                                 style=plots.cylinder_style(i + 1))
    plots.legend_outside(ax)
    ax.set_title(f"{scene.name}: crankpin and link-pin loads over the last cycle (dashed: mean)")
    yield "loads_crankpin", fig


#: What ``transient loads`` draws (capability ``"drawers"``), by the mechanism's name in
#: :data:`transient.mechanisms.MECHANISMS`; other mechanisms store their forces through
#: ``[analysis] loads = true`` instead.
#: A mechanism's own module ``transient.cli.loads_<name>`` may hold it as ``draw``.
DRAWERS = PluginTable({"crank-slider": _crank_slider_loads, "articulated": _radial_loads},
                      "transient.cli.loads_{}", "draw")
