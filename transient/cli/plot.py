"""``transient plot``: PNG figures of a result, or of several side by side."""
from __future__ import annotations

from .common import EXIT_OK, add_force, output_folder, pyplot, read_result, result_stem, save


def register(sub) -> None:
    pl = sub.add_parser("plot", help="write PNG figures of a result, or compare several")
    pl.add_argument("result", nargs="+", help="one result, or several to compare side by side")
    pl.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    add_force(pl)
    pl.set_defaults(func=cmd_plot)


def cmd_plot(args) -> int:
    plt = pyplot()

    from .. import plots
    from ..assemble import clearance_volume, gas_is_force, gas_table

    if len(args.result) > 1:
        return _plot_comparison(args)
    res = read_result(args.result[0])
    scene = res.scene()
    out = output_folder(args.output, res.path.parent)
    stem = result_stem(res.path)
    traj = res.trajectory
    written = []
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    plots.speed(a1, traj)
    plots.acceleration(a2, traj)
    a1.set_title(f"{scene.name}: speed and acceleration")
    written.append(save(fig, out / f"{stem}_speed.png", args.force, res))
    fig, ax = plt.subplots(figsize=(8, 4.5))
    plots.torques(ax, traj, scene.mechanism.cycle)
    ax.set_title(f"{scene.name}: moments over the last cycle")
    written.append(save(fig, out / f"{stem}_torques.png", args.force, res))
    if "load_change_1_t_s" in res.analysis:
        fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
        plots.load_response(axes, traj, scene.mechanism.cycle, res.analysis)
        axes[0].set_title(f"{scene.name}: load steps (ISO 8528-5 band around the new speed)")
        written.append(save(fig, out / f"{stem}_response.png", args.force, res))
    if scene.friction.pairs:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        plots.pair_power(ax, traj, [p.name for p in scene.friction.pairs], scene.mechanism.cycle)
        ax.set_title(f"{scene.name}: power through the non-ideal pairs ({scene.friction.policy})")
        written.append(save(fig, out / f"{stem}_pairs.png", args.force, res))
    if "fmep_1" in res.analysis:  # the friction budget of the steady cycles
        names = [p.name for p in scene.friction.pairs]
        fig, ax = plt.subplots(figsize=(5, 4.5))
        plots.friction_budget(ax, ["steady cycles"], [res.analysis[f"fmep_{k + 1}"][0]
                                                      for k in range(len(names))], names)
        ax.set_title(f"{scene.name}: FMEP per pair (η_mech = "
                     f"{res.analysis['eta_mech_work'][0]:.4f})")
        written.append(save(fig, out / f"{stem}_budget.png", args.force, res))
    table = gas_table(scene)
    if table is not None and not gas_is_force(scene):
        mech = scene.mechanism
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.5))
        plots.indicator_phi(a1, table)
        if scene.gas.model in ("mixed-cycle", "wiebe"):
            plots.indicator_pv(a2, table, mech.volume_function(clearance_volume(scene)))
        else:  # a table gives no clearance volume: plot against the swept part F_p·s
            plots.indicator_pv(a2, table, mech.volume_function(0.0), log=False)
            a2.set_xlabel("swept volume F_p·s [dm³]")
        a1.set_title(f"{scene.name}: indicator diagram")
        written.append(save(fig, out / f"{stem}_indicator.png", args.force, res))
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


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
        plots.speed(axes[0, j], res.trajectory)
        plots.acceleration(axes[1, j], res.trajectory)
        plots.piston_force(axes[2, j], res.trajectory, scene)
        axes[0, j].set_title(f"{scene.name}\n{scene.mechanism.n_cylinders} cylinder(s)", fontsize=9)
    path = out / ("compare_" + "_".join(result_stem(r.path) for r in results) + ".png")
    incomplete = next((r for r in results if not r.complete), None)
    print(f"wrote {save(fig, path, args.force, incomplete)}")
    return EXIT_OK
