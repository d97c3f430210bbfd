"""``transient bench`` and ``transient stress``: the work–precision record with its targets, and
the catalogue of hostile scenes (:mod:`transient.verify`)."""
from __future__ import annotations

from pathlib import Path

from ..errors import SceneError, show_value
from .common import EXIT_FAILED, EXIT_OK, add_force, real, whole

#: Bounds of the benchmark's options: a record of 10⁶ revolutions per run, or of 100 runs per
#: point, would take days on the benchmark scenes.
MAX_BENCH_REVOLUTIONS = 1e6
MAX_REPEAT = 100


def register_bench(sub) -> None:
    b = sub.add_parser("bench", help="work–precision record: error against run time, vs solve_ivp",
                       description="The work–precision record: error against run time, "
                                   "transient against solve_ivp (and CyRK if installed).")
    b.add_argument("scenes", nargs="*", help="scene files (default: the three benchmark scenes)")
    b.add_argument("--revolutions", type=real(gt=0.0, le=MAX_BENCH_REVOLUTIONS), default=1000.0,
                   help="revolutions of each timed run (default 1000)")
    b.add_argument("--repeat", type=whole(1, MAX_REPEAT), default=5,
                   help="timed runs per point (median; default 5)")
    b.add_argument("--no-baselines", action="store_true", help="transient's paths only")
    b.add_argument("--baseline-budget", type=real(gt=0.0), default=None,
                   help="stop a baseline run after this long, and its tighter tolerances [s] "
                        "(default: transient.verify.bench.BASELINE_BUDGET_S, 60 s)")
    b.add_argument("--quick", action="store_true",
                   help="a smoke test of the harness: 10 revolutions, 3 tolerances, one run each")
    b.add_argument("--report", action="store_true",
                   help="only rewrite work_precision.md, targets.md and the figures from the "
                        "record's CSV and JSON")
    b.add_argument("--targets", action="store_true",
                   help="only measure the benchmark's other targets against the record "
                        "(targets.md)")
    b.add_argument("-o", "--output", default="results/benchmarks", help="folder of the record")
    add_force(b)
    b.set_defaults(func=cmd_bench)


def register_stress(sub) -> None:
    st = sub.add_parser(
        "stress", help="run the catalogue of hostile scenes → DIR/stress.md",
        description="Each case runs in a child process with a hard time bound and is checked "
                    "against the work–energy balance or its expected diagnosis "
                    "(transient.verify.stress); result files go to DIR/stress/. Exit 1 if a case "
                    "fails (known failures are reported, not counted).")
    st.add_argument("--quick", action="store_true",
                    help="the CI subset with shorter runs (no 10⁶-revolution runs)")
    st.add_argument("--case", action="append", default=None,
                    help="run only this case (repeatable)")
    st.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    add_force(st)
    st.set_defaults(func=cmd_stress)


def cmd_stress(args) -> int:
    from ..results import check_writable
    from ..verify.stress import catalogue, run_stress

    names = [c.name for c in catalogue()]
    for name in args.case or ():
        if name not in names:
            raise SceneError("--case", f"unknown case {show_value(name)}; allowed: "
                                       f"{', '.join(names)}")
    out = Path(args.output)
    check_writable(out / "stress.md", force=args.force)  # before any work (exit 2)
    rows, path = run_stress(args.quick, out, only=args.case)
    failed = [case.name for case, o in rows if o.outcome == "FAIL"]
    print(f"wrote {path}" + (f"; FAILED: {', '.join(failed)}" if failed else ""))
    return EXIT_FAILED if failed else EXIT_OK


def cmd_bench(args) -> int:
    from ..scene import load_scene
    from ..verify.bench import BASELINE_BUDGET_S, BENCH_SCENES, rewrite_report, run_bench
    from ..verify.targets import rewrite_targets, run_targets

    if args.report or args.targets:
        if not (Path(args.output) / "work_precision.csv").is_file():
            flag = "--report" if args.report else "--targets"
            raise SceneError(f"bench {flag}", f"no work_precision.csv in {args.output}; run "
                                              f"transient bench first")
    if args.report:
        _refuse_to_replace(args, ["work_precision.md", *TARGETS])
        rewrite_report(Path(args.output), args.revolutions)
        also = ", targets.md" if rewrite_targets(args.output) else ""
        print(f"rewrote {Path(args.output) / 'work_precision.md'}{also} and figures")
        return EXIT_OK
    if args.targets:
        _refuse_to_replace(args, TARGETS)
        run_targets(args.output, args.quick)
        print(f"wrote {Path(args.output) / 'targets.md'} and targets.json")
        return EXIT_OK

    scenes = {Path(p).stem: p for p in args.scenes} if args.scenes else BENCH_SCENES
    for path in scenes.values():
        load_scene(path)  # an invalid scene fails here, before any work (exit 2)
    _refuse_to_replace(args, [*RECORD, *TARGETS, *(f"work_precision_{s}.png" for s in scenes)])
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


#: The files of a work–precision record, and of its targets (:mod:`transient.verify`).
RECORD = ("work_precision.csv", "work_precision.md", "work_precision_references.json")
TARGETS = ("targets.md", "targets.json")


def _refuse_to_replace(args, names) -> None:
    """Before any work: a record file already in ``-o`` is a one-line error (exit 2) unless
    ``--force``, so that a long benchmark never ends by replacing a record unasked."""
    from ..results import ResultExists

    if args.force:
        return
    for name in names:
        path = Path(args.output) / name
        if path.exists():
            raise ResultExists(f"{path}: exists; use --force to replace the record")
