"""The ``transient`` command (DESIGN §4): run, check, info, plot, kinematics, bench, efficiency.

Exit codes: 0 success; 2 invalid input (one line, no traceback); 1 the simulation failed (the
partial result is kept and marked incomplete).
"""
from __future__ import annotations

import argparse
import gc
import math
import os
import sys
from pathlib import Path

import numpy as np

from .errors import SceneError, SimulationError, WriteFailed

EXIT_OK, EXIT_FAILED, EXIT_INVALID = 0, 1, 2


# The error of a result file whose writes failed: HDF5's deallocators must never run on it.
_BROKEN_WRITE: WriteFailed | None = None


def entry() -> None:
    """The ``transient`` command: :func:`main`, then exit with its code. After a failed write
    (:class:`~transient.errors.WriteFailed`) the process leaves by ``os._exit``, skipping the
    interpreter's teardown, in which HDF5 would retry the writes of the broken file and crash.

    Before exiting, every live object is frozen out of the garbage collector: the interpreter's
    final collections would otherwise walk numba's type system, a quarter of a second of a
    one-second run (measured, README *Start-up*). Files are closed by then; reference counting
    still tears the modules down."""
    code = main()
    gc.freeze()
    if _BROKEN_WRITE is not None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


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
        if isinstance(exc, WriteFailed):
            # (its traceback holds the broken file's objects: keep them from being freed)
            global _BROKEN_WRITE
            _BROKEN_WRITE = exc
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
    b.add_argument("--baseline-budget", type=float, default=None,
                   help="stop a baseline run after this long, and its tighter tolerances [s] "
                        "(default: transient.bench.BASELINE_BUDGET_S, 60 s)")
    b.add_argument("--quick", action="store_true",
                   help="a smoke test of the harness: 10 revolutions, 3 tolerances, one run each")
    b.add_argument("--report", action="store_true",
                   help="only rewrite work_precision.md, targets.md and the figures from the "
                        "record's CSV and JSON")
    b.add_argument("--targets", action="store_true",
                   help="only measure issue 5's other targets against the record (targets.md)")
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
    lo = sub.add_parser(
        "loads", help="crankpin, main-journal loads and running torques along a crank-slider "
                      "result, crankpin and link-pin loads along an articulated one (PNG + CSV "
                      "files; the result file is not changed)",
        description="Loads along the stored trajectory (transient.analysis.loads): polar "
                    "diagrams of the crankpin and of the most loaded main journal, |R| over the "
                    "last cycle, the wear diagram (Gots §2.6, ±60° rule), running torques; peak "
                    "values on standard output; the last cycle's loads as CSV. Results are "
                    "written as files into DIR, never into the HDF5 result (read only here).")
    lo.add_argument("result")
    lo.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    lo.add_argument("--cylinder", type=int, default=1,
                    help="cylinder (1-based, from the nose) whose crankpin is drawn (default 1)")
    lo.set_defaults(func=cmd_loads)
    od = sub.add_parser(
        "orders", help="order spectra of ω, M_gas and the piston acceleration (PNG + CSV "
                       "files; the result file is not changed)",
        description="Order spectra over the last whole cycle (transient.analysis.orders): ω, "
                    "the gas torque M_gas and, for a crank-slider, the piston acceleration of "
                    "cylinder 1 against the same engine at constant mean speed (odd-harmonic "
                    "report); δ of the last cycle; with two or more whole cycles, a run-up "
                    "waterfall and order tracks of ω against the cycle-mean speed. Results are "
                    "written as files into DIR, never into the HDF5 result (read only here).")
    od.add_argument("result")
    od.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    od.add_argument("--samples-per-cycle", type=int, default=720,
                    help="crank-angle grid points per engine cycle (default 720); orders up to "
                         "half of it per cycle")
    od.add_argument("--max-order", type=float, default=12.0,
                    help="highest order in the tables and figures (default 12)")
    od.add_argument("--detrend", choices=("auto", "ramp", "none"), default="auto",
                    help="remove each cycle's ramp from ω before its DFT (default auto: for a "
                         "spin-up, a run starting below 90 %% of its final speed)")
    od.set_defaults(func=cmd_orders)
    st = sub.add_parser(
        "stress", help="run the catalogue of hostile scenes → DIR/stress.md (issue 9)",
        description="Each case runs in a child process with a hard time bound and is checked "
                    "against the work–energy balance or its expected diagnosis "
                    "(transient.stress); result files go to DIR/stress/. Exit 1 if a case "
                    "fails (known failures are reported, not counted).")
    st.add_argument("--quick", action="store_true",
                    help="the CI subset with shorter runs (no 10⁶-revolution runs)")
    st.add_argument("--case", action="append", default=None,
                    help="run only this case (repeatable)")
    st.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    st.set_defaults(func=cmd_stress)
    sw = sub.add_parser(
        "sweep", help="run a parameter sweep on Dask → DIR/<stem>.h5 and <stem>_summary.csv",
        description="A base scene, parameter axes and quantities to collect (transient.sweep; "
                    "README, Sweeps). Every scene is validated before any work; an interrupted "
                    "sweep resumes where it stopped when the same command is run again.")
    sw.add_argument("sweep")
    sw.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    sw.add_argument("--scheduler", default=None,
                    help="tcp://host:port of a running Dask scheduler (default: a local cluster "
                         "of one process per core); 'serial' runs in this process without Dask")
    sw.add_argument("--workers", type=int, default=None,
                    help="processes of the local cluster (default: one per core)")
    sw.add_argument("--force", action="store_true",
                    help="replace an existing sweep file instead of resuming it")
    sw.add_argument("--retry-failed", action="store_true", help="run the failed runs again")
    sw.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no summary")
    sw.set_defaults(func=cmd_sweep)
    sp = sub.add_parser("sweep-plot", help="plot a sweep's summary: lines (one axis), heat maps "
                                           "(two-axis grid), scatter (otherwise)")
    sp.add_argument("result", help="a sweep file (DIR/<stem>.h5)")
    sp.add_argument("-o", "--output", default=None, help="folder (default: beside the file)")
    sp.add_argument("--quantity", action="append", default=None,
                    help="a collected quantity to plot (repeatable; default: all)")
    sp.set_defaults(func=cmd_sweep_plot)
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


def cmd_stress(args) -> int:
    from .results import check_writable
    from .stress import catalogue, run_stress

    names = [c.name for c in catalogue()]
    for name in args.case or ():
        if name not in names:
            raise SceneError("--case", f"unknown case {name!r}; allowed: {', '.join(names)}")
    out = Path(args.output)
    check_writable(out / "stress.md", force=True)  # before any work (exit 2)
    rows, path = run_stress(args.quick, out, only=args.case)
    failed = [case.name for case, o in rows if o.outcome == "FAIL"]
    print(f"wrote {path}" + (f"; FAILED: {', '.join(failed)}" if failed else ""))
    return EXIT_FAILED if failed else EXIT_OK


def cmd_bench(args) -> int:
    from .bench import BASELINE_BUDGET_S, BENCH_SCENES, rewrite_report, run_bench
    from .bench_targets import rewrite_targets, run_targets
    from .scene import load_scene

    if args.report or args.targets:
        if not (Path(args.output) / "work_precision.csv").is_file():
            flag = "--report" if args.report else "--targets"
            raise SceneError(f"bench {flag}", f"no work_precision.csv in {args.output}; run "
                                              f"transient bench first")
    if args.report:
        rewrite_report(Path(args.output), args.revolutions)
        also = ", targets.md" if rewrite_targets(args.output) else ""
        print(f"rewrote {Path(args.output) / 'work_precision.md'}{also} and figures")
        return EXIT_OK
    if args.targets:
        run_targets(args.output, args.quick)
        print(f"wrote {Path(args.output) / 'targets.md'} and targets.json")
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
                  out=args.output, baseline_budget=args.baseline_budget or BASELINE_BUDGET_S,
                  baseline_tolerances=tuple(10.0 ** -k for k in range(3, 11)))
    run_targets(args.output, args.quick)
    print(f"wrote {Path(args.output) / 'work_precision.csv'}, work_precision.md, figures, "
          f"targets.md and targets.json")
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


#: The progress bar's words until a compiled run's first block (cmd_run) or a sweep's first
#: finished run (cmd_sweep): the kernels load from numba's cache, or, on a first run (an empty
#: cache), compile, which takes minutes (README, Start-up); so a first run does not look hung.
KERNELS_NOTICE = "loading the kernels; a first run compiles them, minutes"


def cmd_run(args) -> int:
    from .results import check_writable
    from .scene import load_scene, runs_compiled
    from .simulate import simulate

    scene = load_scene(args.scene)
    path = Path(args.output) / f"{Path(args.scene).stem}.h5"
    check_writable(path, args.force)
    bar = None
    if not args.quiet and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=1000, desc=f"{scene.name} ({KERNELS_NOTICE})" if runs_compiled(scene)
                   else scene.name, unit="‰", file=sys.stderr, leave=False)
    progress = None
    if bar:
        def progress(fraction):
            if KERNELS_NOTICE in bar.desc:
                bar.set_description(scene.name)  # (shown at once, however short the run)
            bar.update(int(1000 * fraction) - bar.n)
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
    asked = [k for k, val in v.items() if np.ndim(val) > 0]
    if asked:
        print(f"  stored {len(asked)} arrays the scene's [analysis] asks for (listed by "
              f"`transient info`)")
    print(f"  solver {solver['method']}: {solver['nsteps']} steps, {solver['nreject']} rejected, "
          f"{solver['nfev']} RHS calls, {solver['wall_s']:.3g} s (+ {solver['compile_s']:.3g} s "
          f"compile/cache load)")
    if solver.get("stiff_rerun"):
        print(f"  {solver['stiff_rerun']}")


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
        if s.get("stiff_rerun"):
            print(f"  {s['stiff_rerun']}")
    values = {k: v for k, (v, _) in res.analysis.items()}
    _print_response(values)
    _print_efficiency(values)
    arrays = []
    for k, (v, unit) in res.analysis.items():
        if np.ndim(v) > 0:  # the scene's [analysis] (analysis.requested): listed, not dumped
            arrays.append(f"{k} {'×'.join(map(str, np.shape(v)))} [{unit}]")
        else:
            print(f"  {k} = {v:.9g} {unit}" if isinstance(v, (int, float, np.number))
                  else f"  {k} = {v} {unit}")
    if arrays:
        print(f"  analyses asked for by the scene ([analysis]; {len(arrays)} arrays): "
              + ", ".join(arrays))
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


def _write_columns(path, cols: dict) -> None:
    """A CSV of equal-length columns, named by the keys (12 significant digits)."""
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols),
               comments="", fmt="%.12g")


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


# ------------------------------------------------------------------------------------------------
# transient loads / transient orders: analyses of a stored result, written as CSV and PNG files
# (the result file stays as it is).

#: Half-width of the arc each load vector "wears" in the conventional wear diagram (Gots §2.6,
#: reference/gots-crank-dynamics.md §7: wear ∝ force, each force acting over ±60° of arc).
WEAR_HALF_ARC_DEG = 60.0


def _loads_scene(res):
    """The result's scene, or a one-line error (exit 2) if ``transient loads`` draws nothing for
    its mechanism: crank-slider and articulated engines only."""
    from .mechanisms.articulated import Articulated
    from .mechanisms.crank_slider import CrankSlider

    scene = res.scene()
    if not isinstance(scene.mechanism, (CrankSlider, Articulated)):
        raise SceneError("mechanism.type", f"load diagrams are drawn for crank-slider and "
                                           f"articulated engines, not "
                                           f"{type(scene.mechanism).__name__} (its forces are "
                                           f"stored by [analysis] loads = true)",
                         file=str(res.path))
    return scene


def _radial_loads(args, res, scene) -> int:
    """``transient loads`` of an articulated engine: each row's master crankpin in its crank
    frame (polar), the crankpin and link-pin loads over the last cycle, and a CSV
    (``transient.analysis.loads.articulated``; main journals and running torques do not apply)."""
    from . import plots
    from .analysis.loads.articulated import articulated_loads_from_trajectory

    mech = scene.mechanism
    traj = res.trajectory
    mask, start = _last_cycle_window(scene, traj, res.path)
    win = {k: v[mask] for k, v in traj.items()}
    loads = articulated_loads_from_trajectory(scene, win)
    deg = np.degrees(win["phi"] - start)
    rows, n_links = loads.R.shape[0], loads.link_x.shape[0]
    out = Path(args.output) if args.output else res.path.parent
    out.mkdir(parents=True, exist_ok=True)
    stem = res.path.stem
    plt = _pyplot()
    written = []
    fig, axes = plt.subplots(1, rows, figsize=(6 * rows, 5.5), squeeze=False)
    for j in range(rows):
        plots.crankpin_polar(axes[0, j], loads.R_K[j], loads.R_T[j])
        axes[0, j].set_title(f"master crankpin of row {j + 1}, crank frame", fontsize=9)
    fig.suptitle(f"{scene.name}: polar load diagram over the last cycle")
    written.append(_save(fig, out / f"{stem}_loads_polar.png"))
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for j in range(rows):
        plots.load_against_angle(ax, deg, loads.R[j], label=f"crankpin, row {j + 1}")
    for i in range(n_links):
        plots.load_against_angle(ax, deg, np.hypot(loads.link_x[i], loads.link_y[i]),
                                 label=f"link pin {i + 1}")
    ax.legend(fontsize=8)
    ax.set_title(f"{scene.name}: crankpin and link-pin loads over the last cycle (dashed: mean)")
    written.append(_save(fig, out / f"{stem}_loads_crankpin.png"))
    cols = {"t_s": win["t"], "phi_rad": win["phi"], "cycle_angle_deg": deg,
            "omega_rad_s": win["omega"], "epsilon_rad_s2": win["epsilon"]}
    for k in range(loads.P.shape[0]):
        for name in ("P_g", "P_j", "P", "N", "S", "torque"):
            cols[f"{name}_{k + 1}_{'Nm' if name == 'torque' else 'N'}"] = getattr(loads, name)[k]
    for i in range(n_links):
        cols[f"link_x_{i + 1}_N"], cols[f"link_y_{i + 1}_N"] = loads.link_x[i], loads.link_y[i]
    for j in range(rows):
        for name in ("K", "T", "R_K", "R_T", "R"):
            cols[f"{name}_row{j + 1}_N"] = getattr(loads, name)[j]
    csv = out / f"{stem}_loads.csv"
    _write_columns(csv, cols)
    written.append(csv)
    print(f"{res.path}: loads over the last cycle (φ = {start:.6g} … "
          f"{start + mech.cycle:.6g} rad, {int(mask.sum())} samples)")
    for j in range(rows):
        i = int(np.argmax(loads.R[j]))
        print(f"  master crankpin, row {j + 1}: |R| max {loads.R[j][i] / 1e3:.6g} kN at "
              f"{deg[i]:.4g}° of the cycle, mean {np.mean(loads.R[j]) / 1e3:.6g} kN")
    for i in range(n_links):
        print(f"  link pin {i + 1}: |F| max "
              f"{np.hypot(loads.link_x[i], loads.link_y[i]).max() / 1e3:.6g} kN")
    for path in written:
        print(f"  wrote {path}")
    return EXIT_OK


def _last_cycle_window(scene, traj, path):
    """Mask of the samples of the last whole cycle counted from ``scene.initial.phi`` (as
    ``analysis.irregularity`` counts cycles), its end marks included, and its start angle."""
    from .analysis.irregularity import cycle_boundaries

    cycle = scene.mechanism.cycle
    _, marks = cycle_boundaries(traj["t"], traj["phi"], cycle, scene.initial.phi)
    if marks.size < 2:
        raise SceneError("(trajectory)", f"the run holds no whole cycle of "
                                         f"{math.degrees(cycle):g}°", file=str(path))
    a, b = marks[-2], marks[-1]
    tol = 1e-9 * cycle
    phi = traj["phi"]
    # after the last backward motion only (a run that reversed passes these angles twice)
    back = np.nonzero(np.diff(phi) < 0)[0]
    start = back[-1] + 1 if back.size else 0
    mask = (phi >= a - tol) & (phi <= b + tol)
    mask[:start] = False
    return mask, a


def wear_rays(direction: np.ndarray, magnitude: np.ndarray, weight: np.ndarray,
              n_rays: int = 36, half_arc_deg: float = WEAR_HALF_ARC_DEG
              ) -> tuple[np.ndarray, np.ndarray]:
    """The conventional wear diagram's ray sums (Gots §2.6, Table 14;
    reference/gots-crank-dynamics.md §7): for each of ``n_rays`` equally spaced directions, the
    sum of the magnitudes of the load vectors whose direction lies within ±``half_arc_deg`` of
    it. Gots draws 12 (or 18) rays over samples at equal crank-angle steps; here each sample
    counts with ``weight`` (the crank angle it stands for over the mean step: 1 for equal
    steps), so that extra samples at breakpoints do not count twice.

    Returns (ray angles [deg], sums [unit of ``magnitude``]).
    """
    rays = np.arange(n_rays) * (360.0 / n_rays)
    d = np.degrees(direction)[None, :] - rays[:, None]
    d = (d + 180.0) % 360.0 - 180.0
    inside = np.abs(d) <= half_arc_deg + 1e-9
    return rays, (inside * (magnitude * weight)[None, :]).sum(axis=1)


def _angle_weights(phi: np.ndarray) -> np.ndarray:
    """Crank angle each sample stands for (half the intervals on either side) over the mean."""
    if phi.size < 2:
        return np.ones_like(phi)
    gaps = np.diff(phi)
    w = np.zeros_like(phi)
    w[:-1] += 0.5 * gaps
    w[1:] += 0.5 * gaps
    return w / (w.sum() / (phi.size - 1))


def cmd_loads(args) -> int:
    from .analysis.loads.crank_slider import (
        loads_from_trajectory,
        main_journal_loads,
        running_torques,
    )

    from .mechanisms.articulated import Articulated

    res = _open(args.result)
    scene = _loads_scene(res)
    if isinstance(scene.mechanism, Articulated):
        return _radial_loads(args, res, scene)
    mech = scene.mechanism
    n_cyl = mech.n_cylinders
    if not 1 <= args.cylinder <= n_cyl:
        raise SceneError("--cylinder", f"must be 1 … {n_cyl}, got {args.cylinder}")
    traj = res.trajectory
    mask, start = _last_cycle_window(scene, traj, res.path)
    win = {k: v[mask] for k, v in traj.items()}
    loads = loads_from_trajectory(scene, win)
    k = args.cylinder - 1
    deg = np.degrees(win["phi"] - start)
    inline = n_cyl == 1 or np.ptp(np.asarray(mech.bank_angles, dtype=float)) <= 1e-12
    journals = crankpins = mj = None
    if inline:
        journals, crankpins = running_torques(mech, loads)
        mj = main_journal_loads(mech, loads, win["omega"], win["epsilon"])

    out = Path(args.output) if args.output else res.path.parent
    out.mkdir(parents=True, exist_ok=True)
    stem = res.path.stem
    plt = _pyplot()

    from . import plots

    written = []
    # Frame of the pictures: crank k pointing up (+y, outward along ĉ), +x the direction of
    # rotation at the crankpin (t̂); the load on the crankpin is R_T t̂ − R_K ĉ.
    px, py = loads.R_T[k], -loads.R_K[k]
    best = None
    ncols = 2 if inline else 1
    fig, axes = plt.subplots(1, ncols, figsize=(6 * ncols, 5.5), squeeze=False)
    plots.polar_load(axes[0, 0], px, py)
    axes[0, 0].set_xlabel("R_T = T + T_rш [kN] (direction of rotation)")
    axes[0, 0].set_ylabel("−R_K = −(K + K_rш) [kN] (crank outward)")
    axes[0, 0].set_title(f"crankpin {args.cylinder}, crank frame", fontsize=9)
    if inline:
        best = int(np.argmax(mj.magnitude.max(axis=1)))
        plots.polar_load(axes[0, 1], mj.x[best], -mj.y[best])
        axes[0, 1].set_xlabel("R_x [kN] (along T₁, direction of rotation)")
        axes[0, 1].set_ylabel("−R_y [kN] (crank 1 outward)")
        axes[0, 1].set_title(f"main journal {best + 1} (the most loaded), frame of crank 1 "
                             f"(split beam, (58))", fontsize=9)
    fig.suptitle(f"{scene.name}: polar load diagrams over the last cycle")
    written.append(_save(fig, out / f"{stem}_loads_polar.png"))

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for j in range(n_cyl):
        plots.load_against_angle(ax, deg, loads.R[j], label=f"crankpin {j + 1}")
    ax.legend(fontsize=8)
    ax.set_title(f"{scene.name}: crankpin load |R| over the last cycle (dashed: mean)")
    written.append(_save(fig, out / f"{stem}_loads_crankpin.png"))

    weight = _angle_weights(win["phi"])
    rays, sums = wear_rays(np.arctan2(py, px), loads.R[k], weight)
    fig, axes = plt.subplots(1, ncols, figsize=(5.5 * ncols, 5.5), squeeze=False)
    plots.wear_diagram(axes[0, 0], rays, sums)
    axes[0, 0].set_title(f"crankpin {args.cylinder} (frame of its polar diagram)", fontsize=9)
    if inline:
        rays_j, sums_j = wear_rays(np.arctan2(-mj.y[best], mj.x[best]), mj.magnitude[best],
                                   weight)
        plots.wear_diagram(axes[0, 1], rays_j, sums_j)
        axes[0, 1].set_title(f"main journal {best + 1} (frame of crank 1)", fontsize=9)
    fig.suptitle(f"{scene.name}: wear diagrams (Gots §2.6: each load wears ±60° around its "
                 f"direction)", fontsize=10)
    written.append(_save(fig, out / f"{stem}_loads_wear.png"))

    if inline:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        plots.running_torque_curves(ax, deg, journals, crankpins)
        ax.set_title(f"{scene.name}: running torques over the last cycle (Gots §2.8)")
        written.append(_save(fig, out / f"{stem}_loads_running_torques.png"))

    # CSV of the last cycle: every cylinder's forces, the engine torque, running torques and
    # main-journal loads.
    cols = {"t_s": win["t"], "phi_rad": win["phi"], "cycle_angle_deg": deg,
            "omega_rad_s": win["omega"], "epsilon_rad_s2": win["epsilon"]}
    for j in range(n_cyl):
        for name in ("P_g", "P_j", "P", "N", "S", "K", "T", "R_K", "R_T", "R"):
            cols[f"{name}_{j + 1}_N"] = getattr(loads, name)[j]
        cols[f"M_{j + 1}_Nm"] = loads.torque[j]
    cols["M_engine_Nm"] = loads.engine_torque
    if inline:
        for j in range(journals.shape[0]):
            cols[f"M_journal_{j + 1}_Nm"] = journals[j]
        for j in range(crankpins.shape[0]):
            cols[f"M_crankpin_{j + 1}_Nm"] = crankpins[j]
        for j in range(mj.x.shape[0]):
            cols[f"R_main_{j + 1}_N"] = mj.magnitude[j]
    csv = out / f"{stem}_loads.csv"
    _write_columns(csv, cols)
    written.append(csv)

    area = loads.area
    print(f"{res.path}: loads over the last cycle (φ = {start:.6g} … "
          f"{start + mech.cycle:.6g} rad, {int(mask.sum())} samples)")
    for j in range(n_cyl):
        i = int(np.argmax(loads.R[j]))
        print(f"  crankpin {j + 1}: |R| max {loads.R[j][i] / 1e3:.6g} kN "
              f"({loads.R[j][i] / area / 1e6:.4g} MPa on the piston area) at "
              f"{deg[i]:.4g}° of the cycle, mean {np.mean(loads.R[j]) / 1e3:.6g} kN, "
              f"min {loads.R[j].min() / 1e3:.6g} kN")
    s, n = loads.S[k], loads.N[k]
    print(f"  cylinder {args.cylinder}: rod force S from {s.min() / 1e3:.6g} to "
          f"{s.max() / 1e3:.6g} kN (compression > 0), side force |N| max "
          f"{np.abs(n).max() / 1e3:.6g} kN, T from {loads.T[k].min() / 1e3:.6g} to "
          f"{loads.T[k].max() / 1e3:.6g} kN")
    m = loads.engine_torque
    print(f"  engine torque Σ T r: mean {np.mean(m):.6g} N m (sample mean), from "
          f"{m.min():.6g} to {m.max():.6g} N m")
    if inline:
        for j in range(mj.x.shape[0]):
            print(f"  main journal {j + 1}: |R| max {mj.magnitude[j].max() / 1e3:.6g} kN")
        for j in range(1, journals.shape[0]):
            print(f"  running torque journal {j + 1}: max |M| {np.abs(journals[j]).max():.6g} "
                  f"N m")
        for j in range(crankpins.shape[0]):
            print(f"  running torque crankpin {j + 1}: max |M| "
                  f"{np.abs(crankpins[j]).max():.6g} N m")
    else:
        print("  main journals and running torques: in-line engines only (skipped)")
    print(f"  wear diagram of crankpin {args.cylinder}: least loaded ray at "
          f"{rays[np.argmin(sums)]:g}° (counter-clockwise from the direction of rotation, "
          f"crank up)")
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def cmd_orders(args) -> int:
    from .analysis.irregularity import cycle_means, fluctuation
    from .analysis.orders import (cycle_spectra, order_spectrum, report_for_scene,
                                  resolve_detrend, to_angle_grid)
    from .mechanisms.crank_slider import CrankSlider

    res = _open(args.result)
    scene = res.scene()
    mech = scene.mechanism
    n = args.samples_per_cycle
    if n < 16:
        raise SceneError("--samples-per-cycle", f"must be ≥ 16, got {n}")
    if not args.max_order > 0:
        raise SceneError("--max-order", f"must be > 0, got {args.max_order:g}")
    traj = res.trajectory
    cycle, phi0 = mech.cycle, scene.initial.phi
    cuts = res.events.get("breakpoint", {}).get("phi", np.zeros(0))
    # a spin-up's trend would leak into every order of each cycle: detrended by default
    detrend = resolve_detrend(args.detrend, scene.initial.omega, float(traj["omega"][-1]))
    try:
        starts, spec_w = cycle_spectra(traj, "omega", n, cycle, phi0=phi0, cuts=cuts,
                                       detrend=detrend)
    except ValueError as exc:
        raise SceneError("(trajectory)", str(exc), file=str(res.path)) from None
    n_cyc = starts.size
    spec_m = None
    if "M_gas" in traj and scene.gas.model != "none":
        _, cm = to_angle_grid(traj, ("M_gas",), n, cycle, phi0=phi0, cycles=1, cuts=cuts)
        spec_m = order_spectrum(cm["M_gas"], n, cycle)
    rep = None
    if isinstance(mech, CrankSlider):
        rep = report_for_scene(scene, traj, 1, samples_per_cycle=n, cycles=1, cuts=cuts)
    t, phi, omega = traj["t"], traj["phi"], traj["omega"]
    delta = fluctuation(t, phi, omega, cycle, phi0)
    means, _ = cycle_means(t, phi, cycle, phi0)
    means = means[-n_cyc:]
    rpm = 30.0 / math.pi
    orders = spec_w.orders
    top = args.max_order
    shown = (orders > 0.0) & (orders <= top + 1e-9)

    out = Path(args.output) if args.output else res.path.parent
    out.mkdir(parents=True, exist_ok=True)
    stem = res.path.stem
    written = []
    cols_csv = {"order": orders, "omega_amplitude_rad_s": spec_w.amplitude[-1],
                "omega_phase_rad": spec_w.phase[-1]}
    if spec_m is not None:
        cols_csv["M_gas_amplitude_Nm"] = spec_m.amplitude[-1]
        cols_csv["M_gas_phase_rad"] = spec_m.phase[-1]
    if rep is not None:
        cols_csv["W_amplitude_m_s2"] = rep.amplitude[-1]
        cols_csv["W_amplitude_constant_m_s2"] = rep.amplitude_constant[-1]
        cols_csv["W_relative"] = rep.relative[-1]
        cols_csv["W_relative_constant"] = rep.relative_constant[-1]
        cols_csv["W_relative_added"] = rep.relative_added[-1]
    csv = out / f"{stem}_orders.csv"
    _write_columns(csv, cols_csv)
    written.append(csv)

    plt = _pyplot()

    from . import plots

    rows = 1 + (spec_m is not None) + (rep is not None)
    fig, axes = plt.subplots(rows, 1, figsize=(9, 3.2 * rows), squeeze=False)
    axes = axes[:, 0]
    plots.order_bars(axes[0], orders, spec_w.amplitude[-1], "ω amplitude [rad/s]", top)
    axes[0].set_title(f"{scene.name}: orders over the last cycle (mean ω "
                      f"{means[-1] * rpm:.5g} rpm, δ = {delta:.4g}"
                      f"{', detrended' if detrend == 'ramp' else ''})", fontsize=10)
    i = 1
    if spec_m is not None:
        plots.order_bars(axes[i], orders, spec_m.amplitude[-1], "M_gas amplitude [N m]", top)
        i += 1
    if rep is not None:
        plots.order_bars(axes[i], orders, rep.relative[-1], "W / W₁ (cylinder 1)", top,
                         width=0.2, offset=-0.1, label="run", log=True)
        plots.order_bars(axes[i], orders, rep.relative_constant[-1], "W / W₁ (cylinder 1)", top,
                         width=0.2, offset=0.1, label="constant ω̄", log=True)
        axes[i].legend(fontsize=8)
    written.append(_save(fig, out / f"{stem}_orders.png"))

    if n_cyc >= 2:
        amp = spec_w.amplitude
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5))
        pick = np.unique(np.linspace(0, n_cyc - 1, min(n_cyc, 60)).round().astype(int))
        plots.order_waterfall(a1, means[pick] * rpm, orders, amp[pick], top)
        a1.set_title(f"ω spectrum per cycle ({pick.size} of {n_cyc} cycles)", fontsize=9)
        # the strongest orders of the last cycle, and the firing-frequency ones
        strongest = np.argsort(amp[-1][shown])[::-1][:6]
        ks = np.nonzero(shown)[0][strongest]
        tracks = {f"order {orders[j]:g}": amp[:, j] for j in sorted(ks)}
        plots.order_tracks(a2, means * rpm, tracks, "ω amplitude [rad/s]")
        a2.set_title("order tracks of ω against the cycle-mean speed", fontsize=9)
        fig.suptitle(f"{scene.name}: run-up orders of ω")
        written.append(_save(fig, out / f"{stem}_orders_runup.png"))
        sel = np.nonzero(shown)[0]
        run = {"cycle": np.arange(1, n_cyc + 1), "cycle_start_rad": starts,
               "omega_mean_rad_s": means}
        run.update({f"omega_order_{orders[j]:g}_rad_s": amp[:, j] for j in sel})
        csv = out / f"{stem}_orders_runup.csv"
        _write_columns(csv, run)
        written.append(csv)

    print(f"{res.path}: orders over the last whole cycle (φ = {starts[-1]:.6g} … "
          f"{starts[-1] + cycle:.6g} rad, {n} points; {n_cyc} whole cycle(s); ω spectra "
          f"{'detrended (ramp)' if detrend == 'ramp' else 'not detrended'})")
    print(f"  δ = {delta:.12g} (last cycle, (ω_max − ω_min)/ω_mean), cycle-mean ω = "
          f"{means[-1]:.6g} rad/s ({means[-1] * rpm:.6g} rpm)")
    strongest = np.nonzero(shown)[0][np.argsort(spec_w.amplitude[-1][shown])[::-1][:6]]
    print("  ω, strongest orders: " + ", ".join(
        f"{orders[j]:g}: {spec_w.amplitude[-1][j]:.4g} rad/s" for j in strongest))
    if spec_m is not None:
        strongest = np.nonzero(shown)[0][np.argsort(spec_m.amplitude[-1][shown])[::-1][:6]]
        print(f"  M_gas (mean {spec_m.mean[-1]:.6g} N m), strongest orders: " + ", ".join(
            f"{orders[j]:g}: {spec_m.amplitude[-1][j]:.4g} N m" for j in strongest))
    if rep is not None:
        print(f"  piston acceleration W of cylinder 1, relative to its first order "
              f"(|W₁| = {rep.first[-1]:.6g} m/s²), against the same engine at constant "
              f"ω̄ = {rep.omega_mean[-1]:.6g} rad/s:")
        print(f"  {'order':>6} {'|W| [m/s²]':>12} {'rel. run':>10} {'rel. ω̄':>10} "
              f"{'added':>10}  kind")
        for r in rep.table(-1, max_order=top):
            print(f"  {r['order']:6g} {r['amplitude']:12.5g} {r['relative']:10.3e} "
                  f"{r['relative_constant']:10.3e} {r['relative_added']:10.3e}  {r['kind']}")
        if rep.drift[-1] and abs(rep.drift[-1]) > 1e-6 * rep.first[-1]:
            print(f"  (the cycle is not periodic: W drifts by {rep.drift[-1]:.3g} m/s² across "
                  f"it, which leaks into every order)")
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


# ------------------------------------------------------------------------------------------------
# transient sweep / sweep-plot (transient.sweep): parameter sweeps on Dask and their summaries


def cmd_sweep(args) -> int:
    from .scene import runs_compiled
    from .sweep import load_sweep, run_sweep

    sweep = load_sweep(args.sweep)  # every scene validated here, before any work (exit 2)
    s = args.scheduler
    if s is not None and s != "serial" and "://" not in s:
        raise SceneError("--scheduler", f"{s!r} is not an address; give tcp://host:port of a "
                                        f"running Dask scheduler, or 'serial'")
    if args.workers is not None and (args.workers < 1 or s is not None):
        raise SceneError("--workers", "must be ≥ 1, and only for the local cluster (no "
                                      "--scheduler)")
    bar = None
    if not args.quiet and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=len(sweep.runs), desc=sweep.name, unit="run", file=sys.stderr)
        if any(runs_compiled(spec.scene) for spec in sweep.runs):
            bar.set_postfix_str(KERNELS_NOTICE)  # (replaced by the first run's status)

    def on_result(spec, res, done, total):
        if bar is not None:
            bar.n = done
            bar.set_postfix_str(f"run {spec.index}: {res['status']}", refresh=True)

    try:
        out = run_sweep(sweep, args.output, args.scheduler, args.workers, args.force,
                        args.retry_failed, on_result)
    except KeyboardInterrupt:
        print(f"transient: interrupted; the finished runs are kept in {args.output}/."
              f"{sweep.path.stem}.h5.part: run the same command again to resume",
              file=sys.stderr)
        return EXIT_FAILED
    finally:
        if bar is not None:
            bar.close()
    if not args.quiet:
        print(f"wrote {out.path} and {out.csv}: {len(out.computed)} run(s) computed, "
              f"{len(out.skipped)} found finished, {len(out.failed)} failed")
        for r in out.failed:
            print(f"  run {r['run']} failed: {r['message']}")
    if out.failed:
        print(f"transient: {len(out.failed)} of {len(sweep.runs)} runs failed (recorded in "
              f"{out.path}; --retry-failed runs them again)", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def cmd_sweep_plot(args) -> int:
    from . import plots
    from .sweep import read_summary

    if not Path(args.result).is_file():
        raise FileNotFoundError(f"{args.result}: no such sweep file")
    try:
        tab = read_summary(args.result)
    except (OSError, ValueError, KeyError) as exc:
        raise SceneError("(file)", f"not a readable transient sweep file: {exc}",
                         file=str(args.result)) from None
    quantities = args.quantity or tab.collect
    for q in quantities:
        if q not in tab.columns or q in ("run", "status", "message"):
            raise SceneError("--quantity", f"{q!r} is not in the summary; allowed: "
                                           f"{', '.join(tab.collect)}", file=str(args.result))
    out = Path(args.output) if args.output else tab.path.parent
    out.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    dims = []  # one coordinate per grid dimension: the first axis of each group
    for a in tab.axes:
        if all(d["group"] != a["group"] for d in dims):
            dims.append(a)
    failed = tab.columns["status"] != "ok"
    written = []
    for q in quantities:
        label = f"{q} [{tab.units.get(q, '')}]"
        fig, ax = plt.subplots(figsize=(7, 5))
        if tab.method == "grid" and len(dims) == 2:
            x, y = dims[1]["values"], dims[0]["values"]  # runs are in row-major order
            plots.sweep_heatmap(ax, x, y, tab.columns[q].reshape(len(y), len(x)),
                                _axis_label(dims[1], tab), _axis_label(dims[0], tab), label)
        elif len(tab.axes) == 1 or (tab.method == "grid" and len(dims) == 1):
            key = dims[0]["key"]
            plots.sweep_line(ax, tab.columns[key], tab.columns[q], failed,
                             _axis_label(dims[0], tab), label)
        else:
            a, b = tab.axes[0], tab.axes[1]
            plots.sweep_scatter(ax, tab.columns[a["key"]], tab.columns[b["key"]], tab.columns[q],
                                _axis_label(a, tab), _axis_label(b, tab), label)
        ax.set_title(f"{tab.name}: {q}", fontsize=10)
        written.append(_save(fig, out / f"{tab.path.stem.lstrip('.')}_{q}.png"))
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def _axis_label(axis: dict, tab) -> str:
    """An axis key and the other keys of its group (they move together)."""
    others = [a["key"] for a in tab.axes if a["group"] == axis["group"] and a is not axis]
    if len(others) > 1:  # (a long label would not fit beside the plot)
        return f"{axis['key']} (+ {len(others)} keys of its group)"
    return axis["key"] + (f" (with {others[0]})" if others else "")
