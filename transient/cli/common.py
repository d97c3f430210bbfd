"""What the command modules share: exit codes, option checks, reading a result, figures and CSV.

Heavy modules (matplotlib, the result reader) are imported inside the helpers, so that a command
that does not need them starts without them.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from ..errors import SceneError

EXIT_OK, EXIT_FAILED, EXIT_INVALID = 0, 1, 2

#: The progress bar's words until a compiled run's first block (``run``) or a sweep's first
#: finished run (``sweep``): the kernels load from numba's cache, or, on a first run (an empty
#: cache), compile, which takes minutes; so a first run does not look hung.
KERNELS_NOTICE = "loading the kernels; a first run compiles them, minutes"


def number_list(text: str, option: str, low: float, high: float = math.inf) -> list[float]:
    """Comma-separated finite numbers in (low, high], or a one-line error (exit 2)."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SceneError(option, f"must be comma-separated numbers, got {text!r}") from None
    bad = [v for v in values if not (low < v <= high and math.isfinite(v))]
    if not values or bad:
        raise SceneError(option, f"values must be finite and lie in ({low:g}, {high:g}], "
                                 f"got {text!r}")
    return values


def read_result(path):
    """The result file at ``path``; a missing file or one that is not a transient result is a
    one-line error (exit 2), not a traceback."""
    from ..results import open_result

    if not Path(path).is_file():
        raise FileNotFoundError(f"{path}: no such result file")
    try:
        res = open_result(path)
    except (OSError, ValueError) as exc:
        raise SceneError("(file)", f"not a readable transient result: {exc}", file=str(path)) from None
    if not res.complete:
        print(f"warning: {path}: {incomplete_note(res)}", file=sys.stderr)
    return res


def result_stem(path: Path) -> str:
    """The name a result's figures and tables start with: its file's stem, also for the partial
    file of a killed run (``.NAME.h5.part`` → ``NAME``)."""
    name = Path(path).name
    if name.startswith(".") and name.endswith(".h5.part"):
        name = name[1:-len(".part")]
    return Path(name).stem


def incomplete_note(res) -> str:
    """What a figure or a table of the incomplete result ``res`` covers, in one line."""
    t = res.trajectory["t"]
    status = str(res.attrs.get("status", "failed"))
    how = "stopped while running (killed?)" if status == "running" else status
    return (f"an incomplete run ({how}): covers t ≤ {t[-1]:.6g} s only" if t.size
            else f"an incomplete run ({how}): no samples")


def output_folder(option: str | None, default: Path) -> Path:
    """The folder given by ``-o`` (else ``default``), created if missing."""
    out = Path(option) if option else default
    out.mkdir(parents=True, exist_ok=True)
    return out


def pyplot():
    """matplotlib's pyplot on the file-only Agg backend (the CLI never opens windows)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def add_force(parser) -> None:
    """The ``--force`` option of a command that writes files."""
    parser.add_argument("--force", action="store_true",
                        help="replace files that exist (default: refuse, exit 2)")


def output_file(path, force: bool):
    """``path`` opened for writing text, created by this call: an existing file is a one-line
    error (exit 2) unless ``force``, and a link planted at the name is never followed."""
    import io

    from ..results import create_exclusive

    return io.TextIOWrapper(create_exclusive(Path(path), replace=force), encoding="utf-8",
                            newline="")


def save(fig, path, force: bool, source=None):
    """Write ``fig`` as a PNG at ``path`` (as :func:`output_file` creates files) and close it
    (a long command draws many); returns ``path``. A figure of an incomplete result ``source``
    says so across its top."""
    from ..results import create_exclusive

    fig.tight_layout()
    if source is not None and not source.complete:
        fig.subplots_adjust(top=0.9)
        fig.text(0.5, 0.995, incomplete_note(source), ha="center", va="top", color="crimson",
                 fontsize="medium", fontweight="bold")
    with create_exclusive(Path(path), replace=force) as fh:
        fig.savefig(fh, format="png", dpi=110)
    pyplot().close(fig)
    return path


def write_columns(path, cols: dict, force: bool) -> None:
    """A CSV of equal-length columns, named by the keys (12 significant digits), created as
    :func:`output_file` creates files."""
    with output_file(path, force) as fh:
        np.savetxt(fh, np.column_stack(list(cols.values())), delimiter=",",
                   header=",".join(cols), comments="", fmt="%.12g")
