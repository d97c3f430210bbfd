"""``transient efficiency``: η_mech against speed at steady speeds and loads, the friction
budget per pair and, over several speeds and loads, the η_mech map
(:mod:`transient.study.efficiency`); with ``--steady`` each point the periodic steady state
on a dynamometer with the scene's inertias (:mod:`transient.study.dynamometer`); the points on
Dask workers as a sweep's runs."""
from __future__ import annotations

import math
import sys
from pathlib import Path

from ..errors import SceneError, show_value
from .common import (
    EXIT_OK,
    KERNELS_NOTICE,
    MAX_POINTS,
    MAX_RPM,
    MAX_WORKERS,
    add_force,
    check_output_file,
    number_list,
    output_file,
    output_folder,
    pyplot,
    save,
    whole,
)


def register(sub) -> None:
    e = sub.add_parser("efficiency", help="η_mech against speed at steady speeds and loads")
    e.add_argument("scene")
    e.add_argument("--rpm", default="500,1000,2000,3000,4000,5000",
                   help="speeds [rpm], comma-separated (default 500,1000,2000,3000,4000,5000)")
    e.add_argument("--fuel", default="1", help="gas-force fractions (loads), e.g. 1,0.5 "
                                                "(default 1, full load)")
    e.add_argument("--policies", default=None,
                   help="mode policies to compare, e.g. power-flow,paper (default: the scene's)")
    e.add_argument("--samples-per-rev", type=whole(36, MAX_POINTS), default=1440,
                   help="crank-angle samples per revolution of each steady run (default 1440)")
    e.add_argument("--steady", action="store_true",
                   help="each point the periodic steady state with the scene's inertias (δ ≠ 0): "
                        "the fuel held, the mean speed held by a brake of constant torque "
                        "solved for (default: one cycle at a prescribed constant speed)")
    e.add_argument("--scheduler", default=None,
                   help="tcp://host:port of a running Dask scheduler; 'serial' (the default) "
                        "runs the points in this process, 'local' on a local cluster")
    e.add_argument("--workers", type=whole(1, MAX_WORKERS), default=None,
                   help="processes of the local cluster (default: one per core)")
    e.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    add_force(e)
    e.set_defaults(func=cmd_efficiency)


def cmd_efficiency(args) -> int:
    from ..scene import POLICIES, load_scene
    from ..scene.queries import part_load_refusal
    from ..study.efficiency import plot_budget, plot_map, plot_study, write_csv

    scene = load_scene(args.scene)
    rpm = number_list(args.rpm, "--rpm", 0.0, MAX_RPM)
    fuels = number_list(args.fuel, "--fuel", 0.0, 1.0)
    policies = tuple(args.policies.split(",")) if args.policies else None
    for p in policies or ():
        if p not in POLICIES:
            raise SceneError("--policies", f"unknown policy {show_value(p)}; allowed: "
                                           f"{', '.join(POLICIES)}")
    if scene.gas.model == "none":
        raise SceneError("gas.model", "an efficiency study needs gas forces (the input power)",
                         file=args.scene)
    why = part_load_refusal(scene)
    if why and any(f != 1.0 for f in fuels):
        raise SceneError("--fuel", why, file=args.scene)
    scheduler = _scheduler(args)
    if args.steady:
        _check_steady(scene, rpm, args.scene)
    out = output_folder(args.output, Path("results"))  # (before the study: -o is checked first)
    stem = Path(args.scene).stem + "_steady" * args.steady
    names = [p.name for p in scene.friction.pairs]
    figures = ["efficiency"] + ["friction_budget"] * bool(names)
    figures += ["efficiency_map", "delta_map"][:1 + args.steady] * (len(set(rpm)) > 1
                                                                   and len(set(fuels)) > 1)
    for path in [out / f"{stem}_efficiency.csv"] + [out / f"{stem}_{f}.png" for f in figures]:
        check_output_file(path, args.force)  # refused before the study, not after it
    if scene.governor.model != "none":
        print(f"the scene's {scene.governor.model} governor is left out: each point holds its "
              f"speed and its fuel (--fuel)")
    rows = _study(scene, rpm, fuels, policies, args, scheduler)
    with output_file(out / f"{stem}_efficiency.csv", args.force) as fh:
        write_csv(rows, fh)
    steady = f" {'δ':>8} {'brake':>8}" if args.steady else ""
    print(f"{'policy':>10} {'fuel':>5} {'rpm':>7} {'η_work':>9} {'η (30)':>9} {'imep':>7} "
          f"{'fmep':>6}{steady}  "
          + "  ".join(f"{n}: loss [J/cycle] (circulated), fmep" for n in names))
    for r in rows:
        def v(key, r=r):  # (NaN where a point has no value)
            return r.get(key, math.nan)

        pairs = "  ".join(f"{v(f'W_loss_{k + 1}_per_cycle'):10.4g} "
                          f"({v(f'W_circulated_{k + 1}_per_cycle'):.4g}) "
                          f"{v(f'fmep_{k + 1}') / 1e3:6.4g}" for k in range(len(names)))
        steady = f" {v('delta'):8.5f} {v('brake_torque'):8.4g}" if args.steady else ""
        print(f"{r['policy']:>10} {r['fuel']:5.3g} {r['rpm']:7.0f} {v('eta_mech_work'):9.5f} "
              f"{v('eta_mech_printed'):9.5f} {v('imep') / 1e3:7.5g} "
              f"{v('fmep') / 1e3:6.4g}{steady}  {pairs}")
    print("  (mean effective pressures in kPa: imep = W_in/V_d, fmep = Σ W_loss/V_d"
          + ("; δ the cyclic irregularity, brake the torque [N m] that holds the mean speed)"
             if args.steady else ")"))
    for r in rows:
        if r["note"]:
            print(f"  NaN at {r['rpm']:g} rpm, fuel {r['fuel']:g} ({r['policy']}): {r['note']}")
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    plot_study(a1, a2, rows, len(names), names)
    a1.set_title(f"{scene.name}: mechanical efficiency "
                 + ("in steady state on a dynamometer" if args.steady else "at constant speed"))
    written = [out / f"{stem}_efficiency.csv", save(fig, out / f"{stem}_efficiency.png",
                                                    args.force)]
    if "friction_budget" in figures:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        plot_budget(ax, rows, names)
        ax.set_title(f"{scene.name}: friction budget per pair")
        written.append(save(fig, out / f"{stem}_friction_budget.png", args.force))
    if "efficiency_map" in figures:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        plot_map(ax, rows)
        written.append(save(fig, out / f"{stem}_efficiency_map.png", args.force))
    if "delta_map" in figures:
        fig, ax = plt.subplots(figsize=(8, 4.5))
        plot_map(ax, rows, "delta", "δ = (ω_max − ω_min) / ω_mean")
        written.append(save(fig, out / f"{stem}_delta_map.png", args.force))
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def _scheduler(args) -> str | None:
    """The study's points' scheduler for :func:`~transient.sweeps.execute.map_tasks` (None: a
    local cluster), checked before any work."""
    s = args.scheduler or "serial"
    if s not in ("serial", "local") and "://" not in s:
        raise SceneError("--scheduler", f"{show_value(s)} is not an address; give "
                                        f"tcp://host:port of a running Dask scheduler, 'local' "
                                        f"or 'serial'")
    if args.workers is not None and s != "local":
        raise SceneError("--workers", "is for the local cluster only: give it with "
                                      "--scheduler local")
    return None if s == "local" else s


def _check_steady(scene, rpm, file) -> None:
    """Refuse, before any work, a steady study whose points cannot be periodic: a speed below
    the cycle map's crank-angle range, or what in the scene changes from cycle to cycle."""
    from ..shooting import refuse_nonperiodic
    from ..study.dynamometer import bench_scene

    w_hi = 1.5 * scene.solver.switch_speed
    if min(rpm) * math.pi / 30.0 < w_hi:
        raise SceneError("--rpm", f"{min(rpm):g} rpm is below 1.5 × solver.switch_speed = "
                                  f"{w_hi * 30.0 / math.pi:.6g} rpm, where the steady cycle "
                                  f"starts in time; --steady needs running speeds", file=file)
    refuse_nonperiodic(bench_scene(scene, min(rpm) * math.pi / 30.0, 1.0))


def _study(scene, rpm, fuels, policies, args, scheduler) -> list[dict]:
    """The study's rows, the points on ``scheduler``'s workers, with a progress bar on a
    terminal."""
    from functools import partial

    from ..study.efficiency import efficiency_study
    from ..sweeps.execute import check_main_guarded, map_tasks

    if scheduler is None:
        check_main_guarded()
    bar = None
    if sys.stderr.isatty():
        from tqdm import tqdm

        bar = tqdm(total=len(rpm) * len(fuels) * len(policies or (0,)), unit="point",
                   desc="efficiency", file=sys.stderr)
        bar.set_postfix_str(KERNELS_NOTICE)

    def progress(share):
        if bar is not None:
            bar.n = round(share * bar.total)
            bar.set_postfix_str("", refresh=True)

    try:
        return efficiency_study(scene, rpm, fuels, policies, args.samples_per_rev, progress,
                                steady=args.steady,
                                run_points=partial(map_tasks, scheduler=scheduler,
                                                   workers=args.workers))
    finally:
        if bar is not None:
            bar.close()
