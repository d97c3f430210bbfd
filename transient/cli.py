"""The ``transient`` command (DESIGN §4): run, check, info, plot, kinematics, bench, efficiency.

Exit codes: 0 success; 2 invalid input (one line, no traceback); 1 the simulation failed (the
partial result is kept and marked incomplete).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from .errors import SceneError, SimulationError

EXIT_OK, EXIT_FAILED, EXIT_INVALID = 0, 1, 2


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except SceneError as exc:
        print(exc.line(), file=sys.stderr)
        return EXIT_INVALID
    except (FileExistsError, PermissionError, FileNotFoundError) as exc:
        print(str(exc), file=sys.stderr)
        return EXIT_INVALID
    except SimulationError as exc:
        print(f"transient: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        print("transient: interrupted", file=sys.stderr)
        return EXIT_FAILED


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="transient", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="simulate a scene and write DIR/<scene stem>.h5")
    r.add_argument("scene")
    r.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    r.add_argument("--force", action="store_true", help="overwrite an existing result")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no summary")
    r.set_defaults(func=cmd_run)
    c = sub.add_parser("check", help="validate a scene only")
    c.add_argument("scene")
    c.set_defaults(func=cmd_check)
    i = sub.add_parser("info", help="summarise a result file")
    i.add_argument("result")
    i.set_defaults(func=cmd_info)
    pl = sub.add_parser("plot", help="write PNG figures of a result, or compare several")
    pl.add_argument("result", nargs="+", help="one result, or several to compare side by side")
    pl.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    pl.set_defaults(func=cmd_plot)
    k = sub.add_parser("kinematics", help="tabulate positions, transfer functions, J and dJ/dφ")
    k.add_argument("scene")
    k.add_argument("-o", "--output", default=None, help="CSV file (default: standard output)")
    k.add_argument("--points", type=int, default=361, help="points over one cycle")
    k.add_argument("--plot", default=None, help="also write a PNG of the transfer functions and J")
    k.set_defaults(func=cmd_kinematics)
    b = sub.add_parser("bench", help="work-precision record: error against run time, transient "
                                     "against solve_ivp (and CyRK if installed)")
    b.add_argument("scenes", nargs="*", help="scene files (default: the three benchmark scenes)")
    b.add_argument("--revolutions", type=float, default=1000.0)
    b.add_argument("--repeat", type=int, default=5, help="timed runs per point (median)")
    b.add_argument("--no-baselines", action="store_true", help="transient's paths only")
    b.add_argument("--baseline-budget", type=float, default=30.0,
                   help="stop a baseline run after this long, and its tighter tolerances [s]")
    b.add_argument("--quick", action="store_true",
                   help="a smoke test of the harness: 10 revolutions, 3 tolerances, one run each")
    b.add_argument("--report", action="store_true",
                   help="only rewrite work_precision.md and the figures from the record's CSV")
    b.add_argument("-o", "--output", default="results/benchmarks", help="folder of the record")
    b.set_defaults(func=cmd_bench)
    e = sub.add_parser("efficiency", help="η_mech against speed at steady speeds and loads")
    e.add_argument("scene")
    e.add_argument("--rpm", default="500,1000,2000,3000,4000,5000",
                   help="speeds [rpm], comma-separated (default 500,1000,2000,3000,4000,5000)")
    e.add_argument("--fuel", default="1", help="gas-force fractions (loads), e.g. 1,0.5 "
                                                "(default 1, full load)")
    e.add_argument("--policies", default=None,
                   help="mode policies to compare, e.g. power-flow,paper (default: the scene's)")
    e.add_argument("--samples-per-rev", type=int, default=1440)
    e.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    e.set_defaults(func=cmd_efficiency)
    return p


def _number_list(text: str, option: str, low: float, high: float = math.inf) -> list[float]:
    """Comma-separated numbers in (low, high], or a one-line error (exit 2)."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SceneError(option, f"must be comma-separated numbers, got {text!r}") from None
    bad = [v for v in values if not (low < v <= high)]
    if not values or bad:
        raise SceneError(option, f"values must lie in ({low:g}, {high:g}], got {text!r}")
    return values


def cmd_efficiency(args) -> int:
    from .scene import POLICIES, load_scene
    from .study import efficiency_study, plot_study, write_csv

    scene = load_scene(args.scene)
    rpm = _number_list(args.rpm, "--rpm", 0.0)
    fuels = _number_list(args.fuel, "--fuel", 0.0, 1.0)
    policies = tuple(args.policies.split(",")) if args.policies else None
    for p in policies or ():
        if p not in POLICIES:
            raise SceneError("--policies", f"unknown policy {p!r}; allowed: {', '.join(POLICIES)}")
    if scene.gas.model == "none":
        raise SceneError("gas.model", "an efficiency study needs gas forces (the input power)",
                         file=args.scene)
    if args.samples_per_rev < 36:
        raise SceneError("--samples-per-rev", f"must be ≥ 36, got {args.samples_per_rev}")
    rows = efficiency_study(scene, rpm, fuels, policies, args.samples_per_rev)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    stem = Path(args.scene).stem
    write_csv(rows, out / f"{stem}_efficiency.csv")
    names = [p.name for p in scene.friction.pairs]
    print(f"{'policy':>10} {'fuel':>5} {'rpm':>7} {'η_work':>9} {'η (30)':>9}  "
          + "  ".join(f"loss {n} [J/cycle] (circulated)" for n in names))
    for r in rows:
        pairs = "  ".join(f"{r[f'W_loss_{k + 1}_per_cycle']:10.4g} ({r[f'W_circulated_{k + 1}_per_cycle']:.4g})"
                          for k in range(len(names)))
        print(f"{r['policy']:>10} {r['fuel']:5.3g} {r['rpm']:7.0f} {r['eta_mech_work']:9.5f} "
              f"{r.get('eta_mech_printed', math.nan):9.5f}  {pairs}")
    plt = _pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    plot_study(a1, a2, rows, len(names), names)
    a1.set_title(f"{scene.name}: mechanical efficiency at constant speed")
    print(f"wrote {out / f'{stem}_efficiency.csv'}")
    print(f"wrote {_save(fig, out / f'{stem}_efficiency.png')}")
    return EXIT_OK


def cmd_bench(args) -> int:
    from .bench import BENCH_SCENES, rewrite_report, run_bench
    from .scene import load_scene

    if args.report:
        if not (Path(args.output) / "work_precision.csv").is_file():
            raise SceneError("bench --report", f"no work_precision.csv in {args.output}; run "
                                               f"transient bench first")
        rewrite_report(Path(args.output), args.revolutions)
        print(f"rewrote {Path(args.output) / 'work_precision.md'} and figures")
        return EXIT_OK

    scenes = {Path(p).stem: p for p in args.scenes} if args.scenes else BENCH_SCENES
    for path in scenes.values():
        load_scene(path)  # an invalid scene fails here, before any work (exit 2)
    if args.quick:
        run_bench(scenes, revolutions=10.0, tolerances=(1e-4, 1e-6, 1e-8), repeat=1,
                  baselines=not args.no_baselines, out=args.output, baseline_budget=5.0,
                  baseline_tolerances=(1e-4,), steps_per_rev=(32, 128))
    else:
        run_bench(scenes, args.revolutions, repeat=args.repeat, baselines=not args.no_baselines,
                  out=args.output, baseline_budget=args.baseline_budget,
                  baseline_tolerances=tuple(10.0 ** -k for k in range(3, 11)))
    print(f"wrote {Path(args.output) / 'work_precision.csv'}, work_precision.md and figures")
    return EXIT_OK


def cmd_check(args) -> int:
    from .scene import load_scene

    scene = load_scene(args.scene)
    pairs = scene.friction.pairs
    friction = (f", {len(pairs)} non-ideal pair(s) ({', '.join(p.name for p in pairs)}; "
                f"policy {scene.friction.policy})" if pairs else "")
    print(f"{args.scene}: ok ({scene.name}: {type(scene.mechanism).__name__}, "
          f"{scene.mechanism.n_cylinders} cylinder(s), gas {scene.gas.model}, "
          f"run {scene.run.mode}{friction})")
    return EXIT_OK


def cmd_run(args) -> int:
    from .results import check_writable
    from .scene import load_scene
    from .simulate import simulate

    scene = load_scene(args.scene)
    path = Path(args.output) / f"{Path(args.scene).stem}.h5"
    check_writable(path, args.force)
    bar = None
    if not args.quiet and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=1000, desc=scene.name, unit="‰", file=sys.stderr, leave=False)
    progress = (lambda f: bar.update(int(1000 * f) - bar.n)) if bar else None
    try:
        data = simulate(scene, path, force=args.force, progress=progress)
    finally:
        if bar:
            bar.close()
    if not args.quiet:
        print(f"wrote {path}")
        _print_summary(data.extra["summary"], data.solver)
    return EXIT_OK


def _print_summary(summary, solver) -> None:
    rpm = 30.0 / math.pi
    v = {k: val for k, (val, _) in summary.items()}
    print(f"  end: t = {v['final_t']:.6g} s after {v['revolutions']:.6g} rev, "
          f"ω = {v['final_omega']:.6g} rad/s ({v['final_omega'] * rpm:.6g} rpm)")
    print(f"  last cycle: mean ω = {v['mean_omega_last_cycle']:.6g} rad/s "
          f"({v['mean_omega_last_cycle'] * rpm:.6g} rpm), δ = {v['delta_last_cycle']:.4g}")
    ss = v.get("steady_state_t")
    if ss is not None:
        print("  steady state: " + (f"reached at t = {ss:.6g} s" if math.isfinite(ss) else
                                    "not reached (cycle-mean speed still changing by ≥ 1e-4)"))
    if "M_gas_swing_last_cycle" in v:
        print(f"  last cycle: peak |ε| = {v['epsilon_peak_last_cycle']:.4g} rad/s², swing of the "
              f"gas torque {v['M_gas_swing_last_cycle']:.4g} N m against the inertia torque "
              f"½J′ω² {v['M_inertia_swing_last_cycle']:.4g} N m")
    if "mean_drive_torque_last_cycle" in v:
        print(f"  mean drive torque required over the last cycle: "
              f"{v['mean_drive_torque_last_cycle']:.6g} N m")
    _print_response(v)
    _print_efficiency(v)
    print(f"  solver {solver['method']}: {solver['nsteps']} steps, {solver['nreject']} rejected, "
          f"{solver['nfev']} RHS calls, {solver['wall_s']:.3g} s (+ {solver['compile_s']:.3g} s "
          f"compile/cache load)")


def _print_response(v: dict) -> None:
    """ISO 8528-5 measures of each load step and of a spin-up (``analysis.transient_response``)."""
    rpm = 30.0 / math.pi
    k = 1
    while f"load_change_{k}_t_s" in v:
        p = f"load_change_{k}_"
        rec = (f"recovered into ±{v[p + 'band_pct']:.3g} % after {v[p + 'recovery_s']:.4g} s"
               if v[p + "recovered"] else "not recovered by the end of its segment")
        print(f"  load step {k} at t = {v[p + 't_s']:.6g} s: cycle-mean speed "
              f"{v[p + 'omega_before_rad_s'] * rpm:.6g} → {v[p + 'omega_after_rad_s'] * rpm:.6g} "
              f"rpm, transient deviation {v[p + 'dev_max_pct']:+.4g} %, {rec}, steady change "
              f"(droop) {v[p + 'droop_pct']:+.4g} %"
              + ("" if v[p + "settled"] else " (not settled: segment too short)"))
        k += 1
    if "spin_up_t90_s" in v:
        print(f"  spin-up: 90 % of the final {v['spin_up_omega_final_rad_s'] * rpm:.6g} rpm after "
              f"{v['spin_up_t90_s']:.4g} s, in ±1 % after {v['spin_up_settling_s']:.4g} s, "
              f"overshoot {v['spin_up_overshoot_pct']:.3g} %")


def _print_efficiency(v: dict) -> None:
    """η_mech in both forms and each pair's budget per cycle (``analysis.efficiency``)."""
    if "eta_mech_work" not in v:
        return
    print(f"  mechanical efficiency over {v['steady_cycles']:.0f} steady cycle(s): "
          f"η = W_out/W_in = {v['eta_mech_work']:.6f} (work ratio; W_in = "
          f"{v['W_in_per_cycle']:.6g} J/cycle; energy balance residual "
          f"{v['energy_balance_residual']:.2e})")
    if "eta_mech_printed" in v:
        print(f"    (30) as printed, time average of P_out/P_in: {v['eta_mech_printed']:.6g} "
              f"(ill-posed where P_in crosses zero; {100 * v['eta_mech_printed_excluded']:.3g} % "
              f"of the time left out)")
    k = 1
    while f"W_loss_{k}_per_cycle" in v:
        print(f"    pair {k}: loss {v[f'W_loss_{k}_per_cycle']:.6g} J/cycle "
              f"({100 * v[f'loss_share_{k}']:.4g} % of W_in), circulated "
              f"{v[f'W_circulated_{k}_per_cycle']:.6g} J/cycle, far side driving "
              f"{100 * v[f'backward_share_{k}']:.3g} % of the time, mode against the power "
              f"{100 * v[f'mode_against_power_share_{k}']:.3g} % of the time")
        k += 1
    if "pair_mode_switches_per_cycle" in v:
        print(f"    pair mode switches: {v['pair_mode_switches_per_cycle']:.4g} per cycle")


def cmd_info(args) -> int:

    res = _open(args.result)
    a = res.attrs
    print(f"{res.path}: scene {a['scene']!r}, transient {a['version']}, format {a['format']}, "
          f"created {a['created']}, complete = {bool(a['complete'])}")
    if a.get("message"):
        print(f"  message: {a['message']}")
    n = res.trajectory["t"].size
    print(f"  trajectory: {n} samples; " + ", ".join(f"{k} [{u}]" for k, u in res.units.items()))
    for name, ev in res.events.items():
        print(f"  events {name}: {ev['t'].size}")
    s = res.solver
    if s:
        print(f"  solver {s.get('method')}: rtol {s.get('rtol')}, atol {s.get('atol')}, "
              f"{s.get('nsteps')} steps, {s.get('nreject')} rejected, {s.get('nfev')} RHS calls, "
              f"wall {s.get('wall_s', 0):.3g} s, compile {s.get('compile_s', 0):.3g} s")
    _print_efficiency({k: v for k, (v, _) in res.analysis.items()})
    for k, (v, unit) in res.analysis.items():
        print(f"  {k} = {v:.9g} {unit}" if np.ndim(v) == 0 and isinstance(v, (int, float, np.number))
              else f"  {k} = {v} {unit}")
    return EXIT_OK


def _open(path):
    from .results import open_result

    if not Path(path).is_file():
        raise FileNotFoundError(f"{path}: no such result file")
    try:
        return open_result(path)
    except (OSError, ValueError) as exc:
        raise SceneError("(file)", f"not a readable transient result: {exc}", file=str(path)) from None


def cmd_plot(args) -> int:
    plt = _pyplot()

    from . import plots
    from .assemble import clearance_volume, gas_is_force, gas_table

    if len(args.result) > 1:
        return _plot_comparison(args)
    res = _open(args.result[0])
    scene = res.scene()
    out = Path(args.output) if args.output else res.path.parent
    out.mkdir(parents=True, exist_ok=True)
    stem = res.path.stem
    traj = res.trajectory
    written = []
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    plots.speed(a1, traj)
    plots.acceleration(a2, traj)
    a1.set_title(f"{scene.name}: speed and acceleration")
    written.append(_save(fig, out / f"{stem}_speed.png"))
    fig, ax = plt.subplots(figsize=(8, 4.5))
    plots.torques(ax, traj, scene.mechanism.cycle)
    ax.set_title(f"{scene.name}: moments over the last cycle")
    written.append(_save(fig, out / f"{stem}_torques.png"))
    if "load_change_1_t_s" in res.analysis:
        fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
        plots.load_response(axes, traj, scene.mechanism.cycle, res.analysis)
        axes[0].set_title(f"{scene.name}: load steps (ISO 8528-5 band around the new speed)")
        written.append(_save(fig, out / f"{stem}_response.png"))
    if scene.friction.pairs:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        plots.pair_power(ax, traj, [p.name for p in scene.friction.pairs], scene.mechanism.cycle)
        ax.set_title(f"{scene.name}: power through the non-ideal pairs ({scene.friction.policy})")
        written.append(_save(fig, out / f"{stem}_pairs.png"))
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
        written.append(_save(fig, out / f"{stem}_indicator.png"))
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def _plot_comparison(args) -> int:
    """The swash-plate paper's Fig. 5 as one figure: ω(t), ε(t) and the force on piston 1 of
    each result, one column per result, shared axes."""
    plt = _pyplot()

    from . import plots

    results = [_open(p) for p in args.result]
    out = Path(args.output) if args.output else results[0].path.parent
    out.mkdir(parents=True, exist_ok=True)
    n = len(results)
    fig, axes = plt.subplots(3, n, figsize=(5 * n, 8), sharex=True, sharey="row", squeeze=False)
    for j, res in enumerate(results):
        scene = res.scene()
        plots.speed(axes[0, j], res.trajectory)
        plots.acceleration(axes[1, j], res.trajectory)
        plots.piston_force(axes[2, j], res.trajectory, scene)
        axes[0, j].set_title(f"{scene.name}\n{scene.mechanism.n_cylinders} cylinder(s)", fontsize=9)
    path = out / ("compare_" + "_".join(r.path.stem for r in results) + ".png")
    print(f"wrote {_save(fig, path)}")
    return EXIT_OK


def _pyplot():
    """matplotlib's pyplot on the file-only Agg backend (the CLI never opens windows)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)
    return path


def cmd_kinematics(args) -> int:
    from .scene import load_scene

    scene = load_scene(args.scene)
    mech = scene.mechanism
    phi = np.linspace(0.0, mech.cycle, args.points)
    table = mech.kinematics_table(phi)
    header = ",".join(table)
    data = np.column_stack(list(table.values()))
    if args.output:
        np.savetxt(args.output, data, delimiter=",", header=header, comments="", fmt="%.12g")
        print(f"wrote {args.output}")
    else:
        np.savetxt(sys.stdout, data, delimiter=",", header=header, comments="", fmt="%.12g")
    if args.plot:
        plt = _pyplot()

        from . import plots

        fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        plots.transfer_functions(a1, table)
        plots.reduced_inertia(a2, table)
        a1.set_title(f"{scene.name}: transfer functions and reduced inertia")
        print(f"wrote {_save(fig, Path(args.plot))}", file=sys.stderr if not args.output else sys.stdout)
    return EXIT_OK
