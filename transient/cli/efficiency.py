"""``transient efficiency``: η_mech against speed at steady speeds and loads, the friction
budget per pair and, over several speeds and loads, the η_mech map
(:mod:`transient.study.efficiency`)."""
from __future__ import annotations

import math
from pathlib import Path

from ..errors import SceneError, show_value
from .common import (
    EXIT_OK,
    MAX_POINTS,
    MAX_RPM,
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
    e.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    add_force(e)
    e.set_defaults(func=cmd_efficiency)


def cmd_efficiency(args) -> int:
    from ..scene import POLICIES, load_scene
    from ..scene.queries import part_load_refusal
    from ..study.efficiency import efficiency_study, plot_budget, plot_map, plot_study, write_csv

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
    out = output_folder(args.output, Path("results"))  # (before the study: -o is checked first)
    stem = Path(args.scene).stem
    names = [p.name for p in scene.friction.pairs]
    figures = ["efficiency"] + ["friction_budget"] * bool(names)
    figures += ["efficiency_map"] * (len(set(rpm)) > 1 and len(set(fuels)) > 1)
    for path in [out / f"{stem}_efficiency.csv"] + [out / f"{stem}_{f}.png" for f in figures]:
        check_output_file(path, args.force)  # refused before the study, not after it
    if scene.governor.model != "none":
        print(f"the scene's {scene.governor.model} governor is left out: each point holds its "
              f"speed and its fuel (--fuel)")
    rows = efficiency_study(scene, rpm, fuels, policies, args.samples_per_rev)
    with output_file(out / f"{stem}_efficiency.csv", args.force) as fh:
        write_csv(rows, fh)
    print(f"{'policy':>10} {'fuel':>5} {'rpm':>7} {'η_work':>9} {'η (30)':>9} {'imep':>7} "
          f"{'fmep':>6}  " + "  ".join(f"{n}: loss [J/cycle] (circulated), fmep" for n in names))
    for r in rows:
        pairs = "  ".join(f"{r[f'W_loss_{k + 1}_per_cycle']:10.4g} "
                          f"({r[f'W_circulated_{k + 1}_per_cycle']:.4g}) "
                          f"{r[f'fmep_{k + 1}'] / 1e3:6.4g}" for k in range(len(names)))
        print(f"{r['policy']:>10} {r['fuel']:5.3g} {r['rpm']:7.0f} {r['eta_mech_work']:9.5f} "
              f"{r.get('eta_mech_printed', math.nan):9.5f} {r['imep'] / 1e3:7.5g} "
              f"{r['fmep'] / 1e3:6.4g}  {pairs}")
    print("  (mean effective pressures in kPa: imep = W_in/V_d, fmep = Σ W_loss/V_d)")
    for r in rows:
        if r["note"]:
            print(f"  NaN at {r['rpm']:g} rpm, fuel {r['fuel']:g} ({r['policy']}): {r['note']}")
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    plot_study(a1, a2, rows, len(names), names)
    a1.set_title(f"{scene.name}: mechanical efficiency at constant speed")
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
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK
