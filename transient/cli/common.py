"""What the command modules share: exit codes, option checks, reading a result, figures and CSV.

Heavy modules (matplotlib, the result reader) are imported inside the helpers, so that a command
that does not need them starts without them.
"""
from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

import numpy as np

from ..errors import QUOTE_LIMIT, SceneError, clip, show_value
from ..scene.files import not_a_regular_file
from ..scene.records import MAX_SAMPLES_PER_REV

EXIT_OK, EXIT_FAILED, EXIT_INVALID = 0, 1, 2

#: The progress bar's words until a compiled run's first block (``run``) or a sweep's first
#: finished run (``sweep``): the kernels load from numba's cache, or, on a first run (an empty
#: cache), compile, which takes a while; so a first run does not look hung.
KERNELS_NOTICE = "loading the kernels; a first run compiles them (transient warmup: ahead)"


#: Most points of a grid over one cycle an option may ask for, as many as a scene may write per
#: revolution: every point is computed and written.
MAX_POINTS = MAX_SAMPLES_PER_REV
#: Highest shaft speed an option may give [rpm]: beyond it no piston machine runs, and the
#: inertia forces (∝ ω²) would overflow long before.
MAX_RPM = 1e6
#: Most processes of a local Dask cluster (``sweep --workers``): more would only fork the machine
#: to a halt.
MAX_WORKERS = 256


class OptionParser(argparse.ArgumentParser):
    """argparse whose errors are one line, ``option: what is wrong, what is allowed``, raised as a
    :class:`~transient.errors.SceneError` for :func:`transient.cli.main` to print (exit 2) as it
    prints a scene's, instead of a usage block; a value it quotes is cut to a token's length."""

    def error(self, message: str):
        """Raise argparse's complaint ``message`` as the one-line error (never returns)."""
        message = re.sub(r"'([^']*)'", lambda m: show_value(m.group(1)), message)
        head, _, rest = message.partition(": ")
        if head.startswith("argument ") and rest:
            raise SceneError(head.removeprefix("argument "), rest)
        if head == "unrecognized arguments":
            message = f"{head}: {clip(rest, 2 * QUOTE_LIMIT)}"
        raise SceneError(self.prog, f"{message}; see '{self.prog} --help'")


def whole(low: int, high: int):
    """An option's type: a whole number in [low, high]; argparse names the option in the error."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number {low} … {high}, got "
                                             f"{show_value(text)}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be {low} … {high}, got {value}")
        return value
    return parse


def real(gt: float, le: float = math.inf):
    """An option's type: a finite number in (gt, le]; argparse names the option in the error."""
    allowed = f"> {gt:g}" + (f" and ≤ {le:g}" if le < math.inf else "")
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number {allowed}, got "
                                             f"{show_value(text)}") from None
        if not (math.isfinite(value) and gt < value <= le):
            raise argparse.ArgumentTypeError(f"must be finite and {allowed}, got {value:g}")
        return value
    return parse


def number_list(text: str, option: str, low: float, high: float = math.inf) -> list[float]:
    """Comma-separated finite numbers in (low, high], or a one-line error (exit 2)."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SceneError(option, f"must be comma-separated numbers, got "
                                 f"{show_value(text)}") from None
    bad = [v for v in values if not (low < v <= high and math.isfinite(v))]
    if not values or bad:
        raise SceneError(option, f"values must be finite and lie in ({low:g}, {high:g}], "
                                 f"got {show_value(text)}")
    return values


def read_result(path):
    """The result file at ``path``; a missing file or one that is not a transient result is a
    one-line error (exit 2), not a traceback."""
    from ..results import open_result

    check_result_path(path, "result file")
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
    how = "stopped while running (killed?)" if res.status == "running" else res.status
    return (f"an incomplete run ({how}): covers t ≤ {t[-1]:.6g} s only" if t.size
            else f"an incomplete run ({how}): no samples")


def check_result_path(path, what: str) -> None:
    """A file transient wrote (``what``: "result file", "sweep file") must be there and be a
    regular file; else a one-line error (exit 2) saying what it is."""
    kind = not_a_regular_file(Path(path))
    if kind:
        raise SceneError("(file)", f"is {kind}, not a {what}; give the .h5 file transient wrote",
                         file=str(path))
    if not Path(path).is_file():
        raise FileNotFoundError(f"{path}: no such {what}")


def output_folder(option: str | None, default: Path) -> Path:
    """The folder given by ``-o`` (else ``default``), created if missing."""
    from ..results import NotWritable

    out = Path(option) if option else default
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # a file in the way, a read-only file system, …
        raise NotWritable(f"{out}: cannot create the output folder ({exc.strerror or exc}); "
                          f"give a writable folder") from None
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

    return io.TextIOWrapper(_created(path, force), encoding="utf-8", newline="")


def check_output_file(path, force: bool) -> None:
    """Before any work, what :func:`output_file` would refuse: a folder at the name, a file
    there without ``force``, a folder that is not there."""
    from ..results import NotWritable, ResultExists

    path = Path(path)
    if path.is_dir():
        raise NotWritable(f"{path}: is a folder; give a file name")
    if path.exists() and not force:
        raise ResultExists(f"{path}: exists; use --force to replace it")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{path}: cannot create the file (no folder {path.parent}); "
                                f"give a path in an existing folder")


def _created(path, force: bool):
    """``create_exclusive(path)``; a name in a folder that is not there is a one-line error."""
    from ..results import create_exclusive

    try:
        return create_exclusive(Path(path), replace=force)
    except (FileNotFoundError, NotADirectoryError) as exc:
        raise FileNotFoundError(f"{path}: cannot create the file ({exc.strerror}); give a path "
                                f"in an existing folder") from None


#: Resolution of the PNG figures [dots per inch]: twice the 100 of a figure on a plain screen,
#: so that a figure stays sharp on a high-density screen and when zoomed into.
DPI = 200


def lay_out(fig) -> None:
    """The figure's titles wrapped within it (the suptitle among its texts), its axes laid out
    around their labels and legends unless a layout engine does that."""
    for text in [ax.title for ax in fig.axes] + list(fig.texts):
        text.set_wrap(True)
    if fig.get_layout_engine() is None:
        fig.tight_layout()


def save(fig, path, force: bool, source=None):
    """Write ``fig`` as a PNG at ``path`` (as :func:`output_file` creates files) and close it
    (a long command draws many); returns ``path``. A figure of an incomplete result ``source``
    says so across its top."""
    lay_out(fig)
    if source is not None and not source.complete:
        if fig.get_layout_engine() is None:
            fig.subplots_adjust(top=0.9)
        fig.text(0.5, 0.995, incomplete_note(source), ha="center", va="top", color="crimson",
                 fontsize="medium", fontweight="bold")
    with _created(path, force) as fh:
        fig.savefig(fh, format="png", dpi=DPI)
    pyplot().close(fig)
    return path


def write_columns(path, cols: dict, force: bool) -> None:
    """A CSV of equal-length columns, named by the keys (12 significant digits), created as
    :func:`output_file` creates files."""
    with output_file(path, force) as fh:
        np.savetxt(fh, np.column_stack(list(cols.values())), delimiter=",",
                   header=",".join(cols), comments="", fmt="%.12g")
