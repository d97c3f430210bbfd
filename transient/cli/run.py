"""``transient run``, ``check``, ``info`` and ``warmup``: simulate a scene, validate one, summarise
a result, compile the kernels ahead of a first run."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from ..errors import SceneError, SimulationError, escaped
from ..outcome import FINISHED
from .common import EXIT_FAILED, EXIT_OK, KERNELS_NOTICE, read_result


def register(sub) -> None:
    r = sub.add_parser("run", help="simulate a scene and write DIR/<scene stem>.h5")
    r.add_argument("scene")
    r.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    r.add_argument("--force", action="store_true", help="overwrite an existing result")
    r.add_argument("--resume", action="store_true",
                   help="continue the interrupted or killed run of this scene from its last "
                        "checkpoint (bit-identical to a run never stopped)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no summary")
    r.set_defaults(func=cmd_run)
    c = sub.add_parser("check", help="validate a scene only")
    c.add_argument("scene")
    c.set_defaults(func=cmd_check)
    i = sub.add_parser("info", help="summarise a result file")
    i.add_argument("result")
    i.add_argument("--source", action="store_true",
                   help="print the text of the scene file the run was read from, comments "
                        "included, as the result stores it (/scene/source)")
    i.set_defaults(func=cmd_info)
    w = sub.add_parser("warmup", help="compile the kernels ahead of a first run",
                       description="Compile (or load from the cache) every kernel a run needs, "
                                   "by running built-in scenes and the scenes given for a "
                                   "fraction of a revolution; one line per kernel compiled. "
                                   "The cache folder is $TRANSIENT_CACHE_DIR, else "
                                   "~/.cache/transient.")
    w.add_argument("scenes", nargs="*", metavar="scene",
                   help="scenes whose mechanisms' kinematics to compile too")
    w.set_defaults(func=cmd_warmup)


def cmd_check(args) -> int:
    from ..scene import load_scene
    from ..scene.queries import cycle_figures
    from ..scene.read import SweepNotScene

    try:
        scene = load_scene(args.scene)
    except SweepNotScene:
        return _check_sweep(args.scene)
    if scene.solver.multirevolution:  # (what `run` would refuse of it, refused here too)
        from ..longrun import refuse_long_run

        refuse_long_run(scene)
    pairs = scene.friction.pairs
    friction = (f", {len(pairs)} non-ideal pair(s) ({', '.join(p.name for p in pairs)}; "
                f"policy {scene.friction.policy})" if pairs else "")
    print(f"{args.scene}: ok ({scene.name}: {type(scene.mechanism).__name__}, "
          f"{scene.mechanism.n_cylinders} cylinder(s), gas {scene.gas.model}, "
          f"run {scene.run.mode}{friction})")
    _print_mechanism(scene.mechanism)
    _print_figures(cycle_figures(scene))
    return EXIT_OK


def _check_sweep(path: str) -> int:
    """``transient check`` of a sweep file: the file and every scene it resolves to
    (:func:`~transient.sweeps.load_sweep`), what it holds in one line."""
    from ..sweeps import load_sweep

    sweep = load_sweep(path)
    base = sweep.runs[0].scene
    axes = ", ".join(f"{a.key} ({len(a.values)} values)" for a in sweep.axes)
    print(f"{path}: ok (sweep {sweep.name}: {len(sweep.runs)} run(s), method {sweep.method}, "
          f"axes {axes}; base scene {base.name}: {type(base.mechanism).__name__}, "
          f"{base.mechanism.n_cylinders} cylinder(s)); run it with `transient sweep {path}`")
    return EXIT_OK


def _print_mechanism(mech) -> None:
    """What the mechanism's geometry implies, without a run (``scene.geometry()``), then its
    other figures a result stores (master and articulated rods: Semenov's series beside the
    exact values), each as ``name = value unit`` under the name and SI unit the API gives it."""
    figures = mech.geometry()
    figures.update(mech.analysis_summary())
    _print_figures(figures)


def _print_figures(figures: dict) -> None:
    """``name = value unit``, one a line."""
    for name, (value, unit) in figures.items():
        print(f"  {name} = {value:.9g} {unit}")


def cmd_run(args) -> int:
    from ..results import check_writable
    from ..run import simulate
    from ..scene import load_scene, runs_compiled

    scene = load_scene(args.scene)
    path = Path(args.output) / f"{Path(args.scene).stem}.h5"
    if args.resume and args.force:
        raise SceneError("--resume", "continues a run, --force replaces it: give one of them")
    if scene.solver.multirevolution:
        return _run_multirevolution(args, scene, path)
    if not args.resume:
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
    failed = None
    try:
        res = simulate(scene, path, force=args.force, resume=args.resume, progress=progress)
    except SimulationError as exc:
        if exc.result is None or not exc.result.complete:
            raise  # (one line: where it stopped, where the partial result is)
        res, failed = exc.result, exc  # ran to its end, but not as the scene describes
    finally:
        if bar:
            bar.close()
    if not args.quiet:
        print(f"wrote {path}")
        if res.status != FINISHED:
            print(f"  status: {res.message}")
        print_summary(res.analysis, res.solver, pair_names(scene))
    return said(res, failed)


def _run_multirevolution(args, scene, path: Path) -> int:
    """``transient run`` of a scene with ``solver.multirevolution``: its envelope followed and
    written (:func:`transient.longrun.run_multirevolution`), a bar of the cycles reached."""
    from ..longrun import refuse_long_run, run_multirevolution
    from ..results import check_writable

    if args.resume:
        raise SceneError("--resume", "a multirevolution run (solver.multirevolution) is not "
                                     "resumed; run it again with --force", file=args.scene)
    cycles = refuse_long_run(scene)  # (before any work or word of it)
    check_writable(path, args.force)
    bar = None
    if not args.quiet and sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=cycles, desc=f"{scene.name}: envelope ({KERNELS_NOTICE})",
                   unit="cycle", file=sys.stderr, leave=False)

    def progress(reached: int, total: int, integrated: int) -> None:
        if bar is not None:
            bar.set_description(f"{scene.name}: envelope, {integrated} cycle(s) integrated"
                                if reached < total else f"{scene.name}: the error estimate")
            bar.update(reached - bar.n)

    try:
        res = run_multirevolution(scene, path, force=args.force, progress=progress)
    finally:
        if bar:
            bar.close()
    if not args.quiet:
        print(f"wrote {path}")
        v = {k: val for k, (val, _) in res.analysis.items()}
        rpm = 30.0 / math.pi
        print(f"  end: t = {v['final_t']:.6g} s after {v['revolutions']:.6g} rev, "
              f"ω = {v['final_omega']:.6g} rad/s ({v['final_omega'] * rpm:.6g} rpm)")
        print_multirevolution(res.envelope, v)
    return EXIT_OK


def print_multirevolution(env, v: dict) -> None:
    """Which cycles a multirevolution result integrated and which it interpolated, the cycles
    it integrated in all and the envelope's error estimate (nothing for another result)."""
    if env is None:
        return
    done = env.integrated.size
    k = int(env.integrated.sum())
    print(f"  multirevolution: {done} of {env.cycles} cycle(s) followed"
          f"{'' if done == env.cycles else ' (the run stopped there)'}: {k} integrated "
          f"(cycles {cycle_ranges(np.flatnonzero(env.integrated))}), {done - k} interpolated "
          f"on the envelope; {v.get('multirev_cycles_integrated', '?')} cycle(s) integrated "
          f"in all, the error estimate's included")
    print(f"    resolved in the trajectory: {env.resolved.size} cycle(s) "
          f"({cycle_ranges(env.resolved)})")
    if np.isfinite(env.error).all():
        print(f"    envelope error estimate at the last cycle (envelope_rtol "
              f"{v.get('multirev_envelope_rtol', math.nan):.3g}): " + ", ".join(
                  f"{name} {err:.3g} {unit}" for name, err, unit in
                  zip(env.names, env.error, env.units)))
    else:
        print("    envelope error estimate: none (the run stopped before it)")


def cycle_ranges(cycles, most: int = 8) -> str:
    """Cycle numbers as ranges, ``0–3, 7, 12–40``, the first ``most`` of them."""
    cycles = np.asarray(cycles, dtype=np.int64)
    if not cycles.size:
        return "none"
    breaks = np.flatnonzero(np.diff(cycles) != 1)
    starts = cycles[np.r_[0, breaks + 1]]
    ends = cycles[np.r_[breaks, cycles.size - 1]]
    shown = [f"{a}" if a == b else f"{a}–{b}" for a, b in zip(starts, ends)]
    return ", ".join(shown[:most]) + (f", … ({len(shown)} stretches)" if len(shown) > most
                                      else "")


def said(res, failed) -> int:
    """Warnings and a run that did not do what its scene describes, one line each on standard
    error; the exit code (1 for any status but finished)."""
    for warning in res.warnings:
        print(f"transient: warning: {warning}", file=sys.stderr)
    if failed is None:
        return EXIT_OK
    print(f"transient: {failed}", file=sys.stderr)
    return EXIT_FAILED


def print_summary(summary, solver, names=()) -> None:
    rpm = 30.0 / math.pi
    v = {k: val for k, (val, _) in summary.items()}
    print(f"  end: t = {v['final_t']:.6g} s after {v['revolutions']:.6g} rev, "
          f"ω = {v['final_omega']:.6g} rad/s ({v['final_omega'] * rpm:.6g} rpm)")
    _print_stops(v)
    if math.isfinite(v["mean_omega_last_cycle"]):
        print(f"  last cycle: mean ω = {v['mean_omega_last_cycle']:.6g} rad/s "
              f"({v['mean_omega_last_cycle'] * rpm:.6g} rpm), δ = {v['delta_last_cycle']:.4g}")
    else:
        print("  last cycle: none (the run holds no whole cycle turned forwards)")
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
    if "stuck_phases" in v:
        print(f"  stuck at rest, held by the pairs' friction: {v['stuck_phases']:.0f} time(s), "
              f"{v['stuck_time']:.6g} s in all (first at t = {v['stuck_first_t']:.9g} s, "
              f"φ = {v['stuck_first_phi']:.9g} rad)")
    _print_response(v)
    _print_efficiency(v, names)
    _print_thermodynamics(v)
    asked = [k for k, val in v.items() if np.ndim(val) > 0 and not k.startswith("steady_")]
    if asked:
        print(f"  stored {len(asked)} arrays the scene's [analysis] asks for (listed by "
              f"`transient info`)")
    print(f"  solver {solver.get('ran', solver['method'])}: {solver['nsteps']} steps, "
          f"{solver['nreject']} rejected, "
          f"{solver['nfev']} RHS calls, {solver['wall_s']:.3g} s (+ {solver['compile_s']:.3g} s "
          f"compile/cache load)")
    if solver.get("stiff_rerun"):
        print(f"  {solver['stiff_rerun']}")
    if solver.get("stability_hint"):
        print(f"  {solver['stability_hint']}")


def _print_stops(v: dict) -> None:
    """How often the speed went through zero over the whole run, and where first."""
    if "speed_reversals" in v:
        print(f"  speed through zero: {v['speed_reversals']:.0f} time(s), first at t = "
              f"{v['speed_reversal_first_t']:.9g} s, φ = {v['speed_reversal_first_phi']:.9g} rad")


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


def pair_names(scene) -> list[str]:
    """Each friction pair's label for the summary: its number and its name."""
    return [f"pair {k} ({p.name})" for k, p in enumerate(scene.friction.pairs, start=1)]


def _pair_flow(v: dict, s: str) -> str:
    """How the power went through the pair (or the pair in a throw) ``s`` per cycle."""
    return (f"circulated {v[f'W_circulated_{s}_per_cycle']:.6g} J/cycle, far side driving "
            f"{100 * v[f'backward_share_{s}']:.3g} % of the time, mode against the power "
            f"{100 * v[f'mode_against_power_share_{s}']:.3g} % of the time")


def _print_efficiency(v: dict, names=()) -> None:
    """η_mech in both forms and each pair's budget per cycle (``analysis.efficiency``), the
    pairs labelled by ``names`` (default: their numbers)."""
    if "eta_mech_work" not in v:
        return
    source = " from the load and drive into the gas" if v.get("driven") else ""
    print(f"  mechanical efficiency over {v['steady_cycles']:.0f} steady cycle(s): "
          f"η = W_out/W_in = {v['eta_mech_work']:.6f} (work ratio; W_in = "
          f"{v['W_in_per_cycle']:.6g} J/cycle{source}; energy balance residual "
          f"{v['energy_balance_residual']:.2e})")
    if "eta_mech_printed" in v and "W_loss_1_per_cycle" in v:
        # (30) approximates η by the time average of P_out/P_in. Without non-ideal pairs η is 1
        # by construction and the average measures only the power the inertia stores and returns
        # within the cycle, so the line is printed where pairs lose power.
        print(f"    (30) as printed, time average of P_out/P_in: {v['eta_mech_printed']:.6g} "
              f"(ill-posed where P_in crosses zero; {100 * v['eta_mech_printed_excluded']:.3g} % "
              f"of the time left out)")
    if "fmep" in v:
        print(f"    mean effective pressures (V_d = {v['displacement'] * 1e3:.6g} L): imep "
              f"{v['imep'] / 1e3:.6g} kPa, bmep {v['bmep'] / 1e3:.6g} kPa, fmep "
              f"{v['fmep'] / 1e3:.6g} kPa")
    k = 1
    label = dict(enumerate(names, start=1))
    while f"W_loss_{k}_per_cycle" in v:
        head = (f"    {label.get(k, f'pair {k}')}: loss {v[f'W_loss_{k}_per_cycle']:.6g} "
                f"J/cycle, fmep {v[f'fmep_{k}'] / 1e3:.6g} kPa "
                f"({100 * v[f'loss_share_{k}']:.4g} % of W_in)")
        if f"W_circulated_{k}_per_cycle" in v:
            print(f"{head}, {_pair_flow(v, str(k))}")
        else:  # an elastic line's pair, in each throw
            print(f"{head}; in each throw:")
            for key in (key for key in v if key.startswith(f"W_circulated_{k}_")):
                s = key[len("W_circulated_"):-len("_per_cycle")]  # "<k>_<station>"
                print(f"      {s[len(str(k)) + 1:]}: loss {v[f'W_loss_{s}_per_cycle']:.6g} "
                      f"J/cycle, {_pair_flow(v, s)}")
        k += 1
    if k > 2:
        most = max(range(1, k), key=lambda j: v[f"W_loss_{j}_per_cycle"])
        print(f"    {label.get(most, f'pair {most}')} loses most")
    c = 1
    while f"fmep_cyl{c}" in v:
        c += 1
    if c > 1:
        print("    fmep per cylinder, on its own swept volume: " + ", ".join(
            f"{j} {v[f'fmep_cyl{j}'] / 1e3:.6g} kPa" for j in range(1, c)))
    if "pair_mode_switches_per_cycle" in v:
        print(f"    pair mode switches: {v['pair_mode_switches_per_cycle']:.4g} per cycle")


def print_steady(v: dict) -> None:
    """The shooting's record of a steady result (:func:`transient.steady`): its iterations,
    the cycles it integrated, the residuals and the multipliers."""
    if "steady_iterations" not in v:
        return
    mu = [complex(r, i) if i else r for r, i in zip(np.atleast_1d(v["steady_multipliers_real"]),
                                                    np.atleast_1d(v["steady_multipliers_imag"]))]
    print(f"  periodic steady state by shooting: {v['steady_iterations']} Newton iteration(s), "
          f"{v['steady_cycles_integrated']} cycle(s) integrated; residuals ‖Φ(x) − x‖/(atol + "
          f"rtol·|x|) " + ", ".join(f"{r:.3g}" for r in np.atleast_1d(v["steady_residuals"])))
    print("    multipliers (per cycle): " + ", ".join(f"{m:.6g}" for m in mu))


def _print_thermodynamics(v: dict) -> None:
    """The last whole cycle's mean effective pressures and powers (``analysis.thermo``)."""
    if "thermo_last_imep_engine" not in v:
        return
    print(f"  last cycle: IMEP {v['thermo_last_imep_engine'] / 1e5:.5g} bar, BMEP "
          f"{v['thermo_last_bmep'] / 1e5:.5g} bar, FMEP {v['thermo_last_fmep'] / 1e5:.5g} bar; "
          f"indicated {v['thermo_last_P_indicated_engine'] / 1e3:.5g} kW, brake "
          f"{v['thermo_last_P_brake'] / 1e3:.5g} kW, friction "
          f"{v['thermo_last_P_friction'] / 1e3:.5g} kW; peak pressure "
          f"{v['thermo_last_p_max'] / 1e6:.5g} MPa")
    # ∮p dV is a quadrature of the stored samples: how well it closes the energy balance says
    # whether the output spacing is fine enough for the digits above
    print(f"    IMEP − BMEP − FMEP closes the cycle's energy balance to "
          f"{abs(v['thermo_last_balance_residual']):.1e} of the indicated work (finer "
          f"[output] samples_per_rev make it smaller)")


def cmd_info(args) -> int:
    res = read_result(args.result)
    file, text = res.scene_source
    if args.source:
        if not text:
            raise SceneError("--source", "the result stores no scene file (its scene was built "
                                         "in code, or the file predates the record); its "
                                         "resolved scene is /scene/toml", file=str(res.path))
        print(text, end="" if text.endswith("\n") else "\n")
        return EXIT_OK
    a = res.attrs
    print(f"{res.path}: scene {a['scene']!r}, transient {a['version']}, format {a['format']}, "
          f"created {a['created']}, complete = {bool(a['complete'])}, status = {res.status}")
    if a.get("message"):
        print(f"  message: {a['message']}")
    for warning in res.warnings:
        print(f"  warning: {warning}")
    n = res.trajectory["t"].size
    print(f"  trajectory: {n} samples; " + ", ".join(f"{k} [{u}]" for k, u in res.units.items()))
    for name, ev in res.events.items():
        print(f"  events {name}: {ev['t'].size}")
    s = res.solver
    if s and res.envelope is not None:
        print(f"  solver {s.get('ran')}: rtol {s.get('rtol')}, atol {s.get('atol')}, envelope "
              f"rtol {s.get('envelope_rtol')}, {s.get('nfev')} RHS calls, wall "
              f"{s.get('wall_s', 0):.3g} s")
    elif s:
        print(f"  solver {s.get('ran', s.get('method'))}: rtol {s.get('rtol')}, "
              f"atol {s.get('atol')}, "
              f"{s.get('nsteps')} steps, {s.get('nreject')} rejected, {s.get('nfev')} RHS calls, "
              f"wall {s.get('wall_s', 0):.3g} s, compile {s.get('compile_s', 0):.3g} s")
        for note in ("stiff_rerun", "stability_hint"):
            if s.get(note):
                print(f"  {s[note]}")
    _print_provenance(a)
    if text:
        print(f"  scene file: {escaped(file)} ({len(text.splitlines())} lines, comments "
              f"included, stored in /scene/source: `transient info --source` prints them)")
    values = {k: v for k, (v, _) in res.analysis.items()}
    _print_stops(values)
    _print_response(values)
    # (the pairs' names are in the resolved scene, read only when there are pairs)
    _print_efficiency(values, pair_names(res.scene()) if "fmep_1" in values else ())
    _print_thermodynamics(values)
    print_steady(values)
    print_multirevolution(res.envelope, values)
    arrays = []
    for k, (v, unit) in res.analysis.items():
        if k.startswith("steady_") and np.ndim(v) > 0 or k.startswith("multirev_"):
            continue  # (print_steady's, print_multirevolution's)
        if np.ndim(v) > 0:  # the scene's [analysis] (analysis.requested): listed, not dumped
            arrays.append(f"{k} {'×'.join(map(str, np.shape(v)))} [{unit}]")
        else:
            print(f"  {k} = {v:.9g} {unit}" if isinstance(v, (int, float, np.number))
                  else f"  {k} = {v} {unit}")
    if arrays:
        print(f"  analyses asked for by the scene ([analysis]; {len(arrays)} arrays): "
              + ", ".join(arrays))
    return EXIT_OK


#: The versions a result records (``results.provenance``), in the order ``info`` prints them.
_VERSIONS = ("python", "numpy", "scipy", "numba", "h5py", "hdf5", "dask", "distributed",
             "matplotlib", "pandas")


def _print_provenance(attrs) -> None:
    """How the result was made: the command, the CPU, the git commit, the versions (those the
    file records: older files record fewer)."""
    commit = f" at git {attrs['git_commit']}" if attrs.get("git_commit") else ""
    print(f"  made by `{escaped(str(attrs.get('command', '')))}` on {attrs.get('cpu', '?')}"
          f"{commit}")
    versions = [f"{name} {attrs[name]}" for name in _VERSIONS if name in attrs]
    if versions:
        print(f"  versions: {', '.join(versions)}")


def cmd_warmup(args) -> int:
    from numba import config

    from ..scene import load_scene
    from ..warmup import warm_up

    scenes = [load_scene(path) for path in args.scenes]  # (every scene valid before any work)

    def report(kernel) -> None:
        print(f"{'  ' * kernel.depth}compiled {kernel.name} in {kernel.wall_s:.2f} s", flush=True)

    cache = config.CACHE_DIR  # type: ignore[attr-defined]  # (numba sets it at import)
    print(f"kernels in {cache}", flush=True)
    compiled = warm_up(scenes, report)
    print(f"{len(compiled)} kernel(s) compiled" if compiled else "all kernels were cached")
    return EXIT_OK
