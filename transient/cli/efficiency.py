"""``transient efficiency``: η_mech against speed at steady speeds and loads
(:mod:`transient.study.efficiency`)."""
from __future__ import annotations

import math
from pathlib import Path

from ..errors import SceneError, show_value
from .common import (EXIT_OK, MAX_POINTS, MAX_RPM, add_force, number_list, output_file,
                     output_folder, pyplot, save, whole)


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
    from ..study.efficiency import efficiency_study, plot_study, write_csv

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
    out = output_folder(args.output, Path("results"))  # (before the study: -o is checked first)
    stem = Path(args.scene).stem
    rows = efficiency_study(scene, rpm, fuels, policies, args.samples_per_rev)
    with output_file(out / f"{stem}_efficiency.csv", args.force) as fh:
        write_csv(rows, fh)
    names = [p.name for p in scene.friction.pairs]
    print(f"{'policy':>10} {'fuel':>5} {'rpm':>7} {'η_work':>9} {'η (30)':>9}  "
          + "  ".join(f"loss {n} [J/cycle] (circulated)" for n in names))
    for r in rows:
        pairs = "  ".join(f"{r[f'W_loss_{k + 1}_per_cycle']:10.4g} ({r[f'W_circulated_{k + 1}_per_cycle']:.4g})"
                          for k in range(len(names)))
        print(f"{r['policy']:>10} {r['fuel']:5.3g} {r['rpm']:7.0f} {r['eta_mech_work']:9.5f} "
              f"{r.get('eta_mech_printed', math.nan):9.5f}  {pairs}")
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    plot_study(a1, a2, rows, len(names), names)
    a1.set_title(f"{scene.name}: mechanical efficiency at constant speed")
    print(f"wrote {out / f'{stem}_efficiency.csv'}")
    print(f"wrote {save(fig, out / f'{stem}_efficiency.png', args.force)}")
    return EXIT_OK
