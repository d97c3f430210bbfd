"""Sweeps from code: :func:`transient.sweep` runs a scene over parameter axes with the engine of
``transient sweep``, from a sweep file it writes beside its results, ``<name>.sweep.toml``
(validated, stored and mended exactly as a sweep file given to the command is), into
``<name>.sweep.h5`` and ``<name>.sweep_summary.csv``.
"""
from __future__ import annotations

import re
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import SceneError
from ..results import create_exclusive
from ..tomlout import toml_value
from .execute import run_sweep
from .spec import DEFAULT_COLLECT, load_sweep
from .store import SweepTable, open_run, read_summary


@dataclass
class SweepResult:
    """A finished sweep: its summary table (one row per run: the axes' values, the collected
    quantities, the run's status) and each run's whole :class:`~transient.results.Result`.

    Without an output folder the sweep's file lives in a temporary folder as long as this
    object does."""

    path: Path
    table: SweepTable
    computed: list[int]
    reused: list[int]
    _tmp: Any = field(default=None, repr=False)

    def to_dataframe(self):
        """The summary table as a pandas DataFrame (the ``pandas`` extra), units in
        ``df.attrs["units"]``."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: pip install 'transient[pandas]'") \
                from None
        df = pd.DataFrame(self.table.columns)
        df.attrs["units"] = dict(self.table.units)
        return df

    def run(self, index: int):
        """Run ``index``'s result (its trajectory read when used)."""
        return open_run(self.path, index)


def sweep(base, axes: dict[str, Sequence], *, collect: Sequence[str] = DEFAULT_COLLECT,
          method: str = "grid", name: str | None = None, columns: Sequence[str] | None = None,
          output: str | Path | None = None, client=None, scheduler: str | None = None,
          workers: int | None = None, force: bool = False,
          progress: Callable[[int, int], None] | None = None,
          steady: bool = False) -> SweepResult:
    """Run ``base`` (a :class:`~transient.Scene`) over ``axes`` and collect quantities of
    every run, as ``transient sweep`` does.

    Parameters
    ----------
    base : Scene
        The scene every run starts from.
    axes : dict
        Dotted scene key → values, e.g. ``{"load.torque": [50, 100], "inertia.flywheel":
        [0.1, 0.2]}``; unit suffixes allowed (``"initial.omega_rpm"``).
    collect : sequence of str
        Quantities of each run for the table (:data:`transient.sweeps.spec.QUANTITIES` or any
        ``/analysis`` entry).
    method : {"grid", "list"}
        ``"grid"``: every combination of the axes; ``"list"``: their i-th values together.
    name : str, optional
        The sweep's name (its file's stem; a sweep of the same name in ``output`` is mended:
        unchanged runs reused). Default: the base scene's name.
    columns : sequence of str, optional
        Trajectory columns to keep of each run (default all).
    output : str or Path, optional
        Folder of the sweep file and its summary CSV; default a temporary folder.
    client, scheduler, workers : Client, str, int, optional
        A :class:`distributed.Client` to run on, or a scheduler's address, or ``"serial"``;
        default a local cluster of ``workers`` processes (one per core).
    force : bool
        Replace a sweep file of another sweep of this name.
    progress : callable, optional
        Called with (runs done, runs in all) after each run.
    steady : bool
        Each run the scene's periodic steady state (:func:`transient.steady`, one cycle) in
        place of its run from the initial state; every scene must be periodic.

    Returns
    -------
    SweepResult
        The summary table (one row per run) and each run's result.

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> axes = {"inertia.flywheel": [0.0, 0.5]}
    >>> swept = transient.sweep(scene, axes, scheduler="serial")
    >>> columns = swept.table.columns
    >>> columns["inertia.flywheel"].tolist()
    [0.0, 0.5]
    >>> columns["status"].tolist()
    ['finished', 'finished']
    >>> swept.run(1).scene().inertia.flywheel
    0.5
    """
    if not isinstance(axes, dict) or not axes:
        raise SceneError("axes", "give a dict of dotted scene keys and their values, e.g. "
                                 "{'load.torque': [50, 100]}")
    tmp = None
    if output is None:
        tmp = tempfile.TemporaryDirectory(prefix="transient-sweep-")
        output = tmp.name
    folder = Path(output)
    folder.mkdir(parents=True, exist_ok=True)
    name = name or base.name
    spec_file = folder / f"{name}.sweep.toml"  # (the sweep's own definition: rewritten each time)
    with create_exclusive(spec_file, replace=True) as fh:
        fh.write(sweep_toml(base, axes, collect, method, name, columns, steady).encode("utf-8"))
    spec = load_sweep(spec_file)
    if client is not None:
        scheduler = client.scheduler.address
    done = run_sweep(spec, folder, scheduler, workers, force,
                     on_result=(lambda _s, _r, n, total: progress(n, total)) if progress else None)
    return SweepResult(done.path, read_summary(done.path), done.computed, done.reused, tmp)


def sweep_toml(base, axes: dict[str, Sequence], collect: Sequence[str], method: str, name: str,
               columns: Sequence[str] | None, steady: bool = False) -> str:
    """The sweep file of a sweep from code: the base scene inline (its resolved TOML under
    ``[base]``), one ``[[axis]]`` per key."""
    head = [f"name = {toml_value(name)}", f"method = {toml_value(method)}",
            f"collect = {toml_value(list(collect))}"]
    if columns is not None:
        head.append(f"columns = {toml_value(list(columns))}")
    if steady:
        head.append("steady = true")
    lines = ["[sweep]", *head, ""]
    for key, values in axes.items():
        try:
            written = toml_value(list(values))
        except TypeError as exc:
            raise SceneError(f"axes[{key!r}]", f"values must be numbers, strings or booleans "
                                               f"({exc})") from None
        lines += ["[[axis]]", f"key = {toml_value(str(key))}", f"values = {written}", ""]
    scene = re.sub(r"^\[(\[?)", r"[\1base.", base.to_toml(), flags=re.MULTILINE)
    return "\n".join(lines) + "\n" + scene
