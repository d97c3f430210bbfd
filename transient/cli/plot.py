"""``transient plot``: PNG figures of a result, or of several side by side."""
from __future__ import annotations

from ..errors import SceneError
from .common import EXIT_OK, add_force, output_folder, pyplot, read_result, result_stem, save


def register(sub) -> None:
    pl = sub.add_parser("plot", help="write PNG figures of a result, or compare several")
    pl.add_argument("result", nargs="+", help="one result, or several to compare side by side")
    pl.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    pl.add_argument("--cylinder", type=int, action="append", default=None, metavar="K",
                    help="cylinder (1-based) of the run's indicator diagrams; repeat for "
                         "several (default: all)")
    pl.add_argument("--cycles", type=int, nargs="+", default=None, metavar="C",
                    help="each cylinder's own whole cycles in those diagrams, counted from 0 "
                         "or from the end with −1 the last (default: −1)")
    add_force(pl)
    pl.set_defaults(func=cmd_plot)


def cmd_plot(args) -> int:
    if len(args.result) > 1:
        return _plot_comparison(args)
    res = read_result(args.result[0])
    scene = res.scene()
    out = output_folder(args.output, res.path.parent)
    stem = result_stem(res.path)
    held = _check_choices(args, scene, res)
    written = [save(fig, out / f"{stem}_{name}.png", args.force, res)
               for name, fig in figures(res, args.cylinder, args.cycles, held)]
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def figures(res, cylinders=None, cycles=None, held=None):
    """The figures ``transient plot`` writes of the result ``res``, as (name, figure) pairs in
    the order written (each saved as ``<stem>_<name>.png``): ``cylinders`` and ``cycles`` those
    of the indicator diagrams (None: all cylinders, the last cycle); ``held`` the whole cycles
    of their own those cylinders hold (as ``_check_choices`` counts them; None: counted here)."""
    plt = pyplot()

    import numpy as np

    from .. import plots
    from ..scene.queries import gas_is_force, gas_tables

    scene = res.scene()
    traj = res.trajectory
    cycles = cycles or [-1]
    if held is None:
        held = _held(scene, res, cylinders)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    plots.speed_over_run((a1, a2), res, scene)
    a1.set_title(f"{scene.name}: speed and acceleration")
    yield "speed", fig
    fig, ax = plt.subplots(figsize=(9, 4.5))
    plots.torques(ax, traj, scene.mechanism.cycle)
    ax.set_title(f"{scene.name}: moments over the last cycle")
    yield "torques", fig
    if "load_change_1_t_s" in res.analysis:
        fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
        plots.load_response(axes, traj, scene, res.analysis)
        axes[0].set_title(f"{scene.name}: load steps (ISO 8528-5 band around the new speed)")
        yield "response", fig
    if scene.friction.pairs:
        fig, ax = plt.subplots(figsize=(9, 4.5))
        plots.pair_power(ax, traj, pair_curves(scene), scene.mechanism.cycle)
        ax.set_title(f"{scene.name}: power through the non-ideal pairs ({scene.friction.policy})")
        yield "pairs", fig
    if "fmep_1" in res.analysis:  # the friction budget of the steady cycles
        names = [p.name for p in scene.friction.pairs]
        labels, suffixes = ["steady cycles"], [""]
        if "fmep_cyl1" in res.analysis:  # reaction pairs: each cylinder on its own volume too
            n = scene.mechanism.n_cylinders
            labels = ["engine"] + [f"cylinder {c + 1}" for c in range(n)]
            suffixes += [f"_cyl{c + 1}" for c in range(n)]
        fig, ax = plt.subplots(figsize=(5 + 0.8 * len(labels), 4.5))
        # (a pair every cylinder loads has no share per cylinder: the engine's bar alone)
        plots.friction_budget(ax, labels, [res.analysis.get(f"fmep_{k + 1}{s}", (0.0,))[0]
                                           for k in range(len(names)) for s in suffixes], names)
        ax.set_title(f"{scene.name}\nFMEP per pair (η_mech = "
                     f"{res.analysis['eta_mech_work'][0]:.4f})")
        yield "budget", fig
    whole = _has_whole_cycle(scene, traj)
    if whole:
        fig, ax = plt.subplots(figsize=(9, 4.5))
        plots.speed_over_cycle(ax, traj, scene)
        ax.set_title(f"{scene.name}: speed over the last cycle")
        yield "speed_cycle", fig
        fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
        plots.inertia_and_gas((a1, a2), traj, scene.mechanism.cycle)
        a1.set_title(f"{scene.name}: J(φ) and the inertia moment ½J′ω² beside the gas torque")
        yield "inertia", fig
    if whole and scene.gas.model != "none":
        fig, ax = plt.subplots(figsize=(9, 4.5))
        plots.cylinder_torque_curves(ax, traj, scene)
        ax.set_title(f"{scene.name}: each cylinder's gas torque over the last cycle")
        yield "cylinder_torques", fig
    table, motored = gas_tables(scene)
    if table is not None and not gas_is_force(scene) and held:
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5.5), layout="constrained")
        plots.run_indicator_phi(a1, traj, scene, cylinders, cycles, table=table,
                                motored=motored, legend=False)
        # a gas table gives no clearance volume: V is then the swept part F_p·s
        plots.run_indicator_pv(a2, traj, scene, cylinders, cycles,
                               log=scene.gas.model != "table", legend=False)
        if scene.gas.model == "table":
            a2.set_xlabel("swept volume F_p·s [dm³]")
        handles, labels = a1.get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=min(3, len(labels)),
                   fontsize=8)
        fig.suptitle(f"{scene.name}: indicator diagrams of the run")
        yield "indicator", fig
    if scene.gas.model == "wiebe" and held:
        fig, ax = plt.subplots(figsize=(9, 4.5))
        if plots.heat_release(ax, traj, scene, cylinders, cycles):
            ax.set_xlim(np.degrees(scene.gas.wiebe.start) - 20.0,
                        np.degrees(scene.gas.wiebe.start + scene.gas.wiebe.duration) + 30.0)
            ax.set_title(f"{scene.name}: apparent heat-release rate of the run")
            yield "heat_release", fig
        else:
            plt.close(fig)


def pair_curves(scene) -> list[tuple[str, str, str]]:
    """(label, columns' suffix, speed column) of each pair's power curves: the pair's name, on
    an elastic line with the station of each throw it acts in."""
    from ..scene.outputs import pair_columns

    line = scene.shaft is not None
    return [(f"{p.name} at {st}" if line else p.name, s, speed)
            for p, chains in zip(scene.friction.pairs, pair_columns(scene))
            for st, (s, speed) in zip(scene.shaft.throws if line else [""], chains)]


def _has_whole_cycle(scene, traj) -> bool:
    from ..analysis.irregularity import cycle_boundaries

    return cycle_boundaries(traj["t"], traj["phi"], scene.mechanism.cycle,
                            scene.initial.phi)[1].size >= 2


def _check_choices(args, scene, res) -> int:
    """--cylinder and --cycles within what the result holds, before any figure is drawn; returns
    how many whole cycles of their own the cylinders drawn hold (0: no indicator diagram)."""
    n = scene.mechanism.n_cylinders
    for k in args.cylinder or ():
        if not 1 <= k <= n:
            raise SceneError("--cylinder", f"cylinder {k} is out of range; allowed: 1 … {n}",
                             file=str(res.path))
    held = _held(scene, res, args.cylinder)
    if args.cycles is not None:  # (by default the last cycle, or none if there is none)
        for c in args.cycles:
            if not -held <= c < held:
                raise SceneError("--cycles", f"cycle {c} is not held: the run has {held} whole "
                                             f"cycle(s) of the cylinders drawn; allowed "
                                             f"{-held} … {held - 1}", file=str(res.path))
    return held


def _held(scene, res, cylinders) -> int:
    """How many whole cycles of their own ``cylinders`` (None: all) hold, the fewest of them."""
    from ..analysis.thermo import own_cycles

    return min(own_cycles(scene, res.trajectory, k).size
               for k in (cylinders or range(1, scene.mechanism.n_cylinders + 1)))


def _plot_comparison(args) -> int:
    """The swash-plate paper's Fig. 5 as one figure: ω(t), ε(t) and the force on piston 1 of
    each result, one column per result, shared axes."""
    plt = pyplot()

    from .. import plots

    results = [read_result(p) for p in args.result]
    out = output_folder(args.output, results[0].path.parent)
    n = len(results)
    fig, axes = plt.subplots(3, n, figsize=(5 * n, 8), sharex=True, sharey="row", squeeze=False)
    for j, res in enumerate(results):
        scene = res.scene()
        plots.speed(axes[0, j], res.trajectory, scene=scene)
        plots.acceleration(axes[1, j], res.trajectory, scene=scene)
        plots.piston_force(axes[2, j], res.trajectory, scene)
        axes[0, j].set_title(f"{scene.name}\n{scene.mechanism.n_cylinders} cylinder(s)", fontsize=9)
    path = out / ("compare_" + "_".join(result_stem(r.path) for r in results) + ".png")
    incomplete = next((r for r in results if not r.complete), None)
    print(f"wrote {save(fig, path, args.force, incomplete)}")
    return EXIT_OK
