"""``transient sweep`` and ``transient sweep-plot``: parameter sweeps on Dask and figures of their
summaries (:mod:`transient.sweeps`)."""
from __future__ import annotations

import sys
from typing import Any

import numpy as np

from ..errors import SceneError, show_value
from .common import (
    EXIT_FAILED,
    EXIT_OK,
    KERNELS_NOTICE,
    MAX_WORKERS,
    add_force,
    check_result_path,
    output_folder,
    pyplot,
    save,
    whole,
)


def register(sub) -> None:
    sw = sub.add_parser(
        "sweep", help="run a parameter sweep on Dask → DIR/<stem>.h5 + summary CSV",
        description="A base scene, parameter axes and quantities to collect (transient.sweeps). "
                    "Every scene is validated before any work. Run again, the command mends "
                    "its file: a stored run whose resolved scene is unchanged is reused, "
                    "changed and new points are computed (an interrupted sweep resumes).")
    sw.add_argument("sweep")
    sw.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    sw.add_argument("--scheduler", default=None,
                    help="tcp://host:port of a running Dask scheduler (default: a local cluster "
                         "of one process per core); 'serial' runs in this process without Dask")
    sw.add_argument("--workers", type=whole(1, MAX_WORKERS), default=None,
                    help="processes of the local cluster (default: one per core)")
    sw.add_argument("--force", action="store_true",
                    help="replace an existing sweep file instead of mending it")
    sw.add_argument("--retry-failed", action="store_true",
                    help="compute the failed runs again (the others are reused)")
    sw.add_argument("--prune", action="store_true",
                    help="delete the stored runs the sweep no longer holds (kept by default)")
    sw.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no summary")
    sw.set_defaults(func=cmd_sweep)
    sp = sub.add_parser("sweep-plot", help="plot a sweep's summary: lines, heat maps or scatter",
                        description="Plot a sweep's summary: lines (one axis), heat maps "
                                    "(two-axis grid), scatter (otherwise).")
    sp.add_argument("result", help="a sweep file (DIR/<stem>.h5)")
    sp.add_argument("-o", "--output", default=None, help="folder (default: beside the file)")
    sp.add_argument("--quantity", action="append", default=None,
                    help="a collected quantity to plot (repeatable; default: all)")
    add_force(sp)
    sp.set_defaults(func=cmd_sweep_plot)


def cmd_sweep(args) -> int:
    from ..scene import runs_compiled
    from ..sweeps import load_sweep, run_sweep

    sweep = load_sweep(args.sweep)  # every scene validated here, before any work (exit 2)
    s = args.scheduler
    if s is not None and s != "serial" and "://" not in s:
        raise SceneError("--scheduler", f"{show_value(s)} is not an address; give "
                                        f"tcp://host:port of a running Dask scheduler, or "
                                        f"'serial'")
    if args.workers is not None and s is not None:
        raise SceneError("--workers", "is for the local cluster only; leave it out with "
                                      "--scheduler")
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
        out = run_sweep(sweep, args.output, args.scheduler, args.workers, force=args.force,
                        retry_failed=args.retry_failed, on_result=on_result, prune=args.prune)
    except KeyboardInterrupt:
        # (not main's generic line: the finished runs are kept, and saying so tells how to resume)
        print(f"transient: interrupted; the finished runs are kept in {args.output}/."
              f"{sweep.path.stem}.h5.part: run the same command again to resume",
              file=sys.stderr)
        return EXIT_FAILED
    finally:
        if bar is not None:
            bar.close()
    if not args.quiet:
        print(f"wrote {out.path} and {out.csv}: {_counts(out)}")
        for r in out.failed:
            print(f"  run {r['run']} failed: {r['message']}")
        for r in out.rows:
            if r["note"] and r not in out.failed:
                print(f"  run {r['run']}: NaN: {r['note']}")
    if out.failed:
        print(f"transient: {len(out.failed)} of {len(sweep.runs)} runs failed (recorded in "
              f"{out.path}; --retry-failed runs them again)", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def _counts(out) -> str:
    """What the sweep did with each run, and the stored runs it no longer holds."""
    text = (f"{len(out.reused)} run(s) reused, {len(out.recomputed)} recomputed, "
            f"{len(out.new)} new, {len(out.failed)} failed")
    if out.unused:
        text += (f"; {out.unused} stored run(s) no longer in the sweep kept in the file "
                 f"(--prune deletes them)")
    return text


def cmd_sweep_plot(args) -> int:
    from .. import plots
    from ..sweeps.store import finished, read_summary

    check_result_path(args.result, "sweep file")
    try:
        tab = read_summary(args.result)
    except (OSError, ValueError, KeyError) as exc:
        raise SceneError("(file)", f"not a readable transient sweep file: {exc}",
                         file=str(args.result)) from None
    quantities = args.quantity or tab.collect
    for q in quantities:
        if q not in tab.columns or q in ("run", "status", "note", "message"):
            raise SceneError("--quantity", f"{show_value(q)} is not in the summary; allowed: "
                                           f"{', '.join(tab.collect)}", file=str(args.result))
    out = output_folder(args.output, tab.path.parent)
    plt = pyplot()
    dims: list[dict[str, Any]] = []  # one coordinate per grid dimension: each group's first axis
    for a in tab.axes:
        if all(d["group"] != a["group"] for d in dims):
            dims.append(a)
    failed = np.array([not finished(str(status)) for status in tab.columns["status"]])
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
        written.append(save(fig, out / f"{tab.path.stem.lstrip('.')}_{q}.png", args.force))
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK


def _axis_label(axis: dict, tab) -> str:
    """An axis key and the other keys of its group (they move together)."""
    others = [a["key"] for a in tab.axes if a["group"] == axis["group"] and a is not axis]
    if len(others) > 1:  # (a long label would not fit beside the plot)
        return f"{axis['key']} (+ {len(others)} keys of its group)"
    return axis["key"] + (f" (with {others[0]})" if others else "")
