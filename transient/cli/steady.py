"""``transient steady``: the periodic steady state of a scene by shooting on the cycle map
(:func:`transient.steady`), written as a result of its steady cycle(s)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from .common import EXIT_OK, KERNELS_NOTICE, whole
from .run import _print_summary, _said, pair_names


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
    from ..scene import load_scene
    from ..shooting import steady

    scene = load_scene(args.scene)
    path = Path(args.output or Path("results") / f"{Path(args.scene).stem}_steady.h5")

    def progress(iteration: int, residual: float, cycles: int) -> None:
        if not args.quiet:
            print(f"  iteration {iteration}: ‖Φ(x) − x‖ = {residual:.3g} × (atol + rtol·|x|), "
                  f"{cycles} cycle(s) integrated", file=sys.stderr, flush=True)

    if not args.quiet:
        print(f"{scene.name}: shooting for the periodic steady state ({KERNELS_NOTICE})",
              file=sys.stderr, flush=True)
    res = steady(scene, path, cycles=args.cycles, force=args.force, progress=progress)
    if not args.quiet:
        a = {k: v for k, (v, _) in res.analysis.items()}
        print(f"wrote {path}")
        print(f"  steady after {a['steady_iterations']} Newton iteration(s), "
              f"{a['steady_cycles_integrated']} cycle(s) integrated; multipliers "
              + ", ".join(f"{complex(r, i):.6g}" if i else f"{r:.6g}"
                          for r, i in zip(np.atleast_1d(a["steady_multipliers_real"]),
                                          np.atleast_1d(a["steady_multipliers_imag"]))))
        _print_summary(res.analysis, res.solver, pair_names(scene))
    return _said(res, None)
