"""``transient steady``: the periodic steady state of a scene by shooting on the cycle map
(:func:`transient.steady`), written as a result of its steady cycle(s)."""
from __future__ import annotations

import sys
from pathlib import Path

from .common import KERNELS_NOTICE, whole
from .run import pair_names, print_steady, print_summary, said


def register(sub) -> None:
    s = sub.add_parser("steady", help="find the periodic steady state and write its cycle(s)",
                       description="Newton's method on the cycle map Φ(x) − x over the states "
                                   "that repeat (speed, governor, latched fuels, pressures, "
                                   "shaft-line twists and speeds), then the steady cycle(s) "
                                   "written as a run's result, with the convergence record and "
                                   "the multipliers (docs/guide/steady.md). Refuses a scene "
                                   "that depends on time (exit 2) and one that has no stable "
                                   "periodic state (exit 1), saying why.")
    s.add_argument("scene")
    s.add_argument("-o", "--output", default=None,
                   help="the result file (default results/<scene stem>_steady.h5)")
    s.add_argument("--cycles", type=whole(1, 10_000), default=1,
                   help="steady cycles to write (default 1)")
    s.add_argument("--force", action="store_true", help="overwrite an existing result")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress, no summary")
    s.set_defaults(func=cmd_steady)


def cmd_steady(args) -> int:
    from ..results import check_writable
    from ..scene import load_scene
    from ..shooting import refuse_nonperiodic, steady

    scene = load_scene(args.scene)
    path = Path(args.output or Path("results") / f"{Path(args.scene).stem}_steady.h5")
    refuse_nonperiodic(scene)  # (before any work or word of it)
    check_writable(path, args.force)

    def progress(iteration: int, residual: float, cycles: int) -> None:
        if not args.quiet:
            print(f"  iteration {iteration}: ‖Φ(x) − x‖ = {residual:.3g} × (atol + rtol·|x|), "
                  f"{cycles} cycle(s) integrated", file=sys.stderr, flush=True)

    if not args.quiet:
        print(f"{scene.name}: shooting for the periodic steady state ({KERNELS_NOTICE})",
              file=sys.stderr, flush=True)
    res = steady(scene, path, cycles=args.cycles, force=args.force, progress=progress)
    if not args.quiet:
        print(f"wrote {path}")
        print_steady({k: v for k, (v, _) in res.analysis.items()})
        print_summary(res.analysis, res.solver, pair_names(scene))
    return said(res, None)
