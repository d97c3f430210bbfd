"""Parameter sweeps on Dask (issue 10): a base scene, parameter axes, the quantities to collect.

A **sweep file** (TOML; examples in ``cases/sweeps/``)::

    [sweep]
    name = "gots-eta"                      # default: the file's stem
    base = "../gots_diesel_friction.toml"  # relative to this file (or inline: a [base] table)
    method = "grid"                        # grid | list | random
    collect = ["mean_speed_rpm", "eta_mech"]
    columns = ["t", "phi", "omega"]        # trajectory columns to store (default all; [] none)

    [set]                                  # constant changes to the base scene
    "run.revolutions" = 200

    [[axis]]
    key = "load.torque"                    # a dotted scene key, unit suffix allowed
    values = [50.0, 100.0, 150.0]          # or from/to/num (+ spacing = "log"); random: low/high

Keys address the scene's TOML tables (``mechanism.rod.mass``, ``friction.pairs[1].eta_forward``);
a key with a unit suffix replaces the quantity however the base wrote it
(``governor.speed_full_rpm`` replaces ``speed_full = 45.0``). ``grid`` runs every combination of
the axes; axes that share a ``group`` move together (equal lengths). ``list`` runs the axes' i-th
values together. ``random`` draws ``samples`` points with ``seed``, uniformly in [low, high]
(log-uniform with ``spacing = "log"``) or from ``values``.

**Running.** Every resolved scene is validated before any work. Workers (Dask processes, one
thread each) run :func:`run_one` and return arrays; only the client writes, into one HDF5 file
``DIR/<stem>.h5`` (layout in :class:`SweepStore`), run by run as results arrive, so an interrupted
sweep resumes from what is there. The summary table goes to ``/analysis/summary`` and
``DIR/<stem>_summary.csv``.
"""
from __future__ import annotations

import contextlib
import copy
import csv
import dataclasses
import datetime as _dt
import itertools
import json
import math
import os
import re
import signal
import socket
import sys
import threading
import time
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from . import __version__
from .errors import SceneError
from .units import ALL_SUFFIXES

METHODS = ("grid", "list", "random")
SPACINGS = ("linear", "log")
RPM = 30.0 / math.pi


def _has_load_step(scene) -> bool:
    x = scene.load.schedule_time or scene.load.schedule_revolutions
    return any(a == b for a, b in itertools.pairwise(x))


#: Short names of common quantities: name -> (summary entry of /analysis, factor, unit, what it
#: is, a check of the scene that it can be measured, or None). Any other name is taken as an
#: /analysis entry as it is (e.g. "load_change_2_recovery_s", "steady_state_t").
QUANTITIES: dict[str, tuple[str, float, str, str, Callable | None]] = {
    "mean_speed_rpm": ("mean_omega_last_cycle", RPM, "rpm",
                       "cycle-mean speed over the last whole cycle", None),
    "final_speed_rpm": ("final_omega", RPM, "rpm", "speed at the end of the run", None),
    "delta": ("delta_last_cycle", 1.0, "1",
              "speed non-uniformity δ = (ω_max − ω_min)/ω_mean over the last cycle", None),
    "eta_mech": ("eta_mech_work", 1.0, "1", "mechanical efficiency W_out/W_in, steady cycles",
                 lambda s: s.gas.model != "none"),
    "speed_dip_pct": ("load_change_1_dev_max_pct", 1.0, "%",
                      "ISO 8528-5 transient speed deviation after the first load step",
                      _has_load_step),
    "recovery_time_s": ("load_change_1_recovery_s", 1.0, "s",
                        "ISO 8528-5 recovery time (±1 %) after the first load step",
                        _has_load_step),
    "droop_pct": ("load_change_1_droop_pct", 1.0, "%", "steady speed change at the first load step",
                  _has_load_step),
    "spin_up_t90_s": ("spin_up_t90_s", 1.0, "s", "time to 90 % of the final speed", None),
}
DEFAULT_COLLECT = ("mean_speed_rpm", "delta")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_KEY_PART = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?$")


# ------------------------------------------------------------------------------------------------
# The sweep file


@dataclass(frozen=True)
class Axis:
    """One swept scene key and its values (numbers, or strings and booleans for ``values``)."""

    key: str
    values: tuple
    group: str


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: its index, the axis values, the validated scene and its resolved TOML."""

    index: int
    params: dict[str, Any]
    scene: Any
    toml: str


@dataclass(frozen=True)
class Sweep:
    """A validated sweep file and its runs."""

    name: str
    path: Path
    text: str
    method: str
    axes: tuple[Axis, ...]
    collect: tuple[str, ...]
    columns: tuple[str, ...] | None  # None: every trajectory column
    runs: tuple[RunSpec, ...]

    @property
    def groups(self) -> list[list[Axis]]:
        """Axes by group, in the order of first appearance (a grid's dimensions)."""
        out: dict[str, list[Axis]] = {}
        for a in self.axes:
            out.setdefault(a.group, []).append(a)
        return list(out.values())


class _Table:
    """A table of the sweep file: takes keys off it, reports unknown ones (as scene.Section)."""

    def __init__(self, data: Any, where: str, file: str) -> None:
        if not isinstance(data, dict):
            raise SceneError(where, f"must be a table, got {type(data).__name__}", file=file)
        self.data, self.where, self.file, self.known = dict(data), where, file, []

    def error(self, key: str, message: str) -> SceneError:
        return SceneError(f"{self.where}.{key}" if self.where else key, message, file=self.file)

    def get(self, key: str, types: tuple, default: Any = None, what: str = "") -> Any:
        self.known.append(key)
        if key not in self.data:
            return default
        value = self.data.pop(key)
        if isinstance(value, bool) and bool not in types or not isinstance(value, types):
            raise self.error(key, f"must be {what}, got {value!r}")
        return value

    def finish(self) -> None:
        for key in self.data:
            raise self.error(key, f"unknown key; allowed here: {', '.join(self.known)}")


def load_sweep(source: str | Path) -> Sweep:
    """Read and validate a sweep file and every scene it resolves to. Raises SceneError."""
    path = Path(source)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except OSError as exc:
        raise SceneError("(file)", f"cannot read: {exc.strerror}", file=file) from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SceneError("(syntax)", f"not valid TOML (UTF-8): {exc}", file=file) from None
    root = _Table(data, "", file)
    head = _Table(root.get("sweep", (dict,), None, "a table") or {}, "sweep", file)
    name = head.get("name", (str,), path.stem, "a string")
    base_path = head.get("base", (str,), None, "a scene file path (string)")
    inline = root.get("base", (dict,), None, "a table holding the whole base scene")
    if (base_path is None) == (inline is None):
        raise head.error("base", "give the base scene either as a file (sweep.base = \"x.toml\") "
                                 "or inline as a [base] table, exactly one of them")
    method = head.get("method", (str,), "grid", "a string")
    if method not in METHODS:
        raise head.error("method", f"unknown value {method!r}; allowed: {', '.join(METHODS)}")
    samples = head.get("samples", (int,), None, "a whole number ≥ 1")
    seed = head.get("seed", (int,), None, "a whole number")
    if method == "random" and (samples is None or samples < 1 or seed is None):
        raise head.error("samples" if samples is None or samples < 1 else "seed",
                         "method = \"random\" needs samples (≥ 1) and seed (a whole number)")
    if method != "random" and (samples is not None or seed is not None):
        raise head.error("samples" if samples is not None else "seed",
                         f"only for method = \"random\", not {method!r}")
    collect = _collect(head, head.get("collect", (list,), list(DEFAULT_COLLECT),
                                      "a list of quantity names"))
    columns = head.get("columns", (list,), None, "a list of trajectory column names")
    if columns is not None and not all(isinstance(c, str) for c in columns):
        raise head.error("columns", f"must be a list of strings, got {columns!r}")
    head.finish()
    changes = _flatten(root.get("set", (dict,), {}, "a table of dotted scene keys and values"))
    for key in changes:
        _check_key(key, SceneError(f"set.{key}", "", file=file))
    axes = tuple(_axis(_Table(a, f"axis[{i}]", file), method, samples, seed, i)
                 for i, a in enumerate(_axis_list(root, file)))
    root.finish()
    _check_distinct(axes, file)
    if inline is not None:
        base, base_file, base_dir = inline, f"{file}:[base]", path.parent
    else:
        base_file = path.parent / base_path
        base, base_dir = _read_base(base_file, file), base_file.parent
    sweep = Sweep(name, path, text, method, axes, collect,
                  None if columns is None else tuple(columns), ())
    runs = tuple(_resolve(sweep, base, changes, params, i, str(base_file), base_dir)
                 for i, params in enumerate(_points(sweep)))
    _check_columns(sweep, runs)
    return dataclasses.replace(sweep, runs=runs)


def _flatten(table: dict, prefix: str = "") -> dict[str, Any]:
    """``[set]`` as dotted keys: ``"run.t_end" = 2``, ``run.t_end = 2`` and ``[set.run]``
    ``t_end = 2`` all mean the same change (not a replacement of the whole ``[run]`` table)."""
    out = {}
    for key, value in table.items():
        if isinstance(value, dict):
            out.update(_flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def _collect(head: _Table, names: list) -> tuple[str, ...]:
    for n in names:
        if not isinstance(n, str) or not _NAME.match(n):
            raise head.error("collect", f"{n!r} is not a quantity name; give names such as "
                                        f"{', '.join(QUANTITIES)}, or any /analysis entry")
    if len(set(names)) != len(names):
        raise head.error("collect", "names must not repeat")
    return tuple(names)


def _axis_list(root: _Table, file: str) -> list:
    axes = root.get("axis", (list,), None, "an array of tables [[axis]]")
    if not axes:
        raise SceneError("axis", "is missing; give at least one [[axis]] with a key and its "
                                 "values", file=file)
    return axes


def _check_key(key: str, err: SceneError) -> list[tuple[str, int | None]]:
    """The parts of a dotted scene key, name and optional [index] each; err if malformed."""
    parts = [_KEY_PART.match(p) for p in key.split(".")]
    if not key or not all(parts):
        err.message = (f"{key!r} is not a scene key; give dotted TOML keys such as "
                       f"'load.torque' or 'friction.pairs[0].eta_forward'")
        err.args = (err.line(),)
        raise err
    return [(m.group(1), None if m.group(2) is None else int(m.group(2))) for m in parts]


def _quantity_key(key: str) -> str:
    """A key without the unit suffix of its last part: the quantity it sets."""
    head, _, leaf = key.rpartition(".")
    stem, _, suffix = leaf.rpartition("_")
    return f"{head}.{stem}" if suffix in ALL_SUFFIXES else key


def _check_distinct(axes: tuple[Axis, ...], file: str) -> None:
    seen: dict[str, int] = {}
    for i, a in enumerate(axes):
        j = seen.setdefault(_quantity_key(a.key), i)
        if j != i:
            raise SceneError(f"axis[{i}].key", f"{a.key!r} sets the quantity of axis[{j}] "
                                               f"({axes[j].key!r}) again; give each quantity one "
                                               f"axis", file=file)


def _axis(t: _Table, method: str, samples: int | None, seed: int | None, i: int) -> Axis:
    key = t.get("key", (str,), None, "a dotted scene key (string)")
    if key is None:
        raise t.error("key", "is missing; give the dotted scene key this axis sets, e.g. "
                             "'load.torque'")
    _check_key(key, t.error("key", ""))
    group = t.get("group", (str,), f"#{i}", "a string")
    values = t.get("values", (list,), None, "a list of values")
    lo_hi = {k: t.get(k, (int, float), None, "a number")
             for k in (("low", "high") if method == "random" else ("from", "to"))}
    num = t.get("num", (int,), None, "a whole number ≥ 2") if method != "random" else None
    spacing = t.get("spacing", (str,), "linear", "a string")
    t.finish()
    if spacing not in SPACINGS:
        raise t.error("spacing", f"unknown value {spacing!r}; allowed: {', '.join(SPACINGS)}")
    given = [k for k, v in lo_hi.items() if v is not None] + (["num"] if num is not None else [])
    if values is not None and given:
        raise t.error(given[0], "given together with 'values'; give a list of values or a range, "
                                "not both")
    if values is not None:
        if not values or not all(isinstance(v, (int, float, str, bool)) for v in values):
            raise t.error("values", f"must be a non-empty list of numbers, strings or booleans, "
                                    f"got {values!r}")
        if method == "random":  # draw from the list
            picks = np.random.default_rng([seed, i]).integers(0, len(values), samples)
            values = [values[k] for k in picks]
        return Axis(key, tuple(values), group)
    need = list(lo_hi) + ([] if method == "random" else ["num"])
    missing = [k for k in need if k not in given]
    if missing:
        raise t.error(missing[0], f"is missing; give 'values' = [...] or {', '.join(need)}")
    a, b = lo_hi.values()
    if spacing == "log" and not (a > 0 and b > 0):
        raise t.error(need[0], f"spacing = \"log\" needs positive bounds, got {a:g} and {b:g}")
    if method == "random":
        if not a < b:
            raise t.error("high", f"must be > low ({a:g}), got {b:g}")
        return Axis(key, _draw(a, b, spacing, samples, seed, i), group)
    if num < 2:
        raise t.error("num", f"must be ≥ 2, got {num}")
    grid = np.geomspace(a, b, num) if spacing == "log" else np.linspace(a, b, num)
    return Axis(key, tuple(float(v) for v in grid), group)


def _draw(a: float, b: float, spacing: str, samples: int, seed: int, i: int) -> tuple:
    """``samples`` random values in [a, b]; axis i has its own stream of the seed, so adding an
    axis does not change the draws of the others."""
    rng = np.random.default_rng([seed, i])
    if spacing == "log":
        return tuple(float(v) for v in np.exp(rng.uniform(math.log(a), math.log(b), samples)))
    return tuple(float(v) for v in rng.uniform(a, b, samples))


def _points(sweep: Sweep) -> Iterator[dict[str, Any]]:
    """The axis values of each run, in run order."""
    axes = sweep.axes
    if sweep.method == "random":  # every axis holds its `samples` draws
        yield from (dict(zip((a.key for a in axes), row)) for row in zip(*(a.values for a in axes)))
        return
    groups = ([[a] for a in axes] if sweep.method == "list" else
              [[a for a in axes if a.group == g] for g in dict.fromkeys(a.group for a in axes)])
    moving = [a for g in groups for a in g] if sweep.method == "list" else None
    for g in (groups if moving is None else [moving]):
        lengths = {len(a.values) for a in g}
        if len(lengths) > 1:
            what = "method = \"list\"" if moving else f"group {g[0].group!r}"
            raise SceneError(f"axis ({g[0].key})",
                             f"the axes of {what} move together and need equally many values; "
                             f"got {', '.join(f'{a.key}: {len(a.values)}' for a in g)}",
                             file=str(sweep.path))
    if moving is not None:
        yield from (dict(zip((a.key for a in moving), row))
                    for row in zip(*(a.values for a in moving)))
        return
    for combo in itertools.product(*(range(len(g[0].values)) for g in groups)):
        yield {a.key: a.values[k] for g, k in zip(groups, combo) for a in g}


def _read_base(path: Path, sweep_file: str) -> dict:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SceneError("sweep.base", f"cannot read the base scene {str(path)!r}: "
                                       f"{exc.strerror}", file=sweep_file) from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SceneError("sweep.base", f"the base scene {str(path)!r} is not valid TOML: {exc}",
                         file=sweep_file) from None


def set_key(data: dict, key: str, value: Any) -> None:
    """Set a dotted scene key in parsed TOML, creating tables on the way. A leaf written with a
    unit suffix (or without) replaces every other spelling of the same quantity, so that an axis
    ``governor.speed_full_rpm`` overrides ``speed_full = 45.0`` of the base."""
    parts = _check_key(key, SceneError(key, ""))
    node = data
    for name, index in parts[:-1]:
        node = node.setdefault(name, {})
        if index is not None:
            if not isinstance(node, list) or index >= len(node):
                raise SceneError(key, f"{name}[{index}]: the base scene has no such entry "
                                      f"(an array of tables, indexed from 0)")
            node = node[index]
        if not isinstance(node, dict):
            raise SceneError(key, f"{name!r} is a value in the base scene, not a table")
    leaf, index = parts[-1]
    if index is not None:
        raise SceneError(key, "the last part must name a value, not an array entry")
    stem = leaf.rpartition("_")[0] if leaf.rpartition("_")[2] in ALL_SUFFIXES else leaf
    for spelling in [stem] + [f"{stem}_{s}" for s in ALL_SUFFIXES]:
        node.pop(spelling, None)
    node[leaf] = value


def _resolve(sweep: Sweep, base: dict, changes: dict, params: dict, i: int, base_file: str,
             base_dir: Path) -> RunSpec:
    """Run i's scene: the base with the constant changes and the axis values, validated."""
    from .scene import scene_from_dict, to_toml

    data = copy.deepcopy(base)
    shown = ", ".join(f"{k} = {v!r}" for k, v in params.items())
    try:
        for key, value in itertools.chain(changes.items(), params.items()):
            set_key(data, key, value)
        scene = scene_from_dict(data, file=base_file, base_dir=base_dir)
    except SceneError as exc:
        raise SceneError(f"run {i} ({shown})", f"scene {exc.key}: {exc.message}",
                         file=str(sweep.path)) from None
    return RunSpec(i, params, scene, to_toml(scene))


def _check_columns(sweep: Sweep, runs: tuple[RunSpec, ...]) -> None:
    """Collected short names must be measurable, stored columns must exist, in every scene."""
    from .simulate import output_columns

    for spec in runs:
        for q in sweep.collect:
            check = QUANTITIES.get(q, (None,) * 5)[4]
            if check is not None and not check(spec.scene):
                what = "gas forces" if q == "eta_mech" else "load step"
                raise SceneError("sweep.collect", f"{q!r} ({QUANTITIES[q][3]}) cannot be measured "
                                                  f"in run {spec.index}: its scene has no {what}",
                                 file=str(sweep.path))
        have = output_columns(spec.scene)
        for c in sweep.columns or ():
            if c not in have:
                raise SceneError("sweep.columns", f"unknown column {c!r} in run {spec.index}; "
                                                  f"allowed: {', '.join(have)}",
                                 file=str(sweep.path))


# ------------------------------------------------------------------------------------------------
# A worker's part: one run, arrays back to the client


def run_one(scene, columns: tuple[str, ...] | None) -> dict[str, Any]:
    """Integrate one scene and summarise it (on a worker); never raises: a failure comes back
    as ``status = "failed"`` with its message (and the partial trajectory, if any).

    The imports stay in this process (a Dask worker runs many tasks), so numba loads each kernel
    once per worker, from its on-disk cache; ``compile_s`` shows it (≈ 0 after the first run).
    """
    from .analysis.irregularity import summarize
    from .simulate import integrate, output_columns

    t0 = time.perf_counter()
    out: dict[str, Any] = {"status": "failed", "message": "", "trajectory": {}, "events": {},
                           "solver": {}, "summary": {}, "units": output_columns(scene),
                           "worker": f"{socket.gethostname()}:{os.getpid()}"}
    try:
        data = integrate(scene, keep=True)
        out["solver"] = data.solver
        out["events"] = data.events
        keep = data.trajectory if columns is None else {c: data.trajectory[c] for c in columns}
        out["trajectory"] = keep
        if data.complete:
            out["summary"] = summarize(scene, data.trajectory, data.events)
            out["status"] = "ok"
        out["message"] = data.message
    except Exception as exc:  # noqa: BLE001 (this run failed: say so, the sweep goes on)
        out["message"] = f"{type(exc).__name__}: {exc}"
    out["wall_s"] = time.perf_counter() - t0
    return out


def worker_info() -> dict[str, str]:
    """Run on every worker before the sweep: imports the simulator once (and so tells at once
    if a cluster's workers cannot), and reports the version they run."""
    from . import simulate  # noqa: F401  (the import is the point)

    return {"version": __version__, "python": sys.version.split()[0]}


def kernel_loads() -> dict[str, int]:
    """How often this process compiled or loaded the stepper from numba's cache (its signatures
    and cache hits + misses): 1 after any number of runs of one kind of scene."""
    from .core import stepper

    st = stepper.advance.stats
    return {"signatures": len(stepper.advance.signatures),
            "loads": sum(st.cache_hits.values()) + sum(st.cache_misses.values())}


# ------------------------------------------------------------------------------------------------
# The client's part: the one writer of the sweep file


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


class SweepStore:
    """The sweep file (HDF5), written by the client only.

    Layout: root attributes as a result file (``creator``, ``version``, ``format``, ``created``,
    ``complete``) plus ``kind = "sweep"``, ``sweep`` (its name) and ``n_runs``; ``/sweep/toml``
    the sweep file; ``/sweep`` attributes ``method``, ``axes`` and ``collect`` (JSON);
    ``/runs/run_<i>`` one group per run with attributes ``index``, ``params`` (JSON),
    ``scene_toml`` (the resolved scene), ``status`` (``ok`` or ``failed``, written last: a group
    without it is unfinished), ``message``, ``worker``, ``wall_s``, and sub-groups
    ``trajectory/<col>`` (with ``unit``), ``events/<name>/{t,phi}``, ``solver`` (attributes) and
    ``analysis/<name>`` (the run's summary, with ``unit``); ``/analysis/summary`` the table of
    collected quantities (attribute ``units``, JSON).

    While the sweep runs the file is ``.<name>.h5.part``; it is renamed when every run is done.
    An existing file of the same sweep is resumed (finished runs are kept); one of another sweep
    is never overwritten without ``force``.
    """

    def __init__(self, path: Path, sweep: Sweep, force: bool = False) -> None:
        self.path, self.sweep = Path(path), sweep
        self.part = self.path.with_name(f".{self.path.name}.part")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if not os.access(self.path.parent, os.W_OK):
            raise PermissionError(f"{self.path.parent}: folder is not writable")
        if force:
            for p in (self.path, self.part, self.path.with_name(f"{self.path.stem}_summary.csv")):
                p.unlink(missing_ok=True)
        found = next((p for p in (self.part, self.path) if p.exists()), None)
        if found is None:
            self.f = self._create(self.part)
        else:
            self._check(found)  # raises, changing nothing, if it is another sweep
            os.replace(found, self.part)  # a finished file being resumed is a part again
            self.f = h5py.File(self.part, "r+")
        self.finished = self._prepare()

    def _check(self, path: Path) -> None:
        """An existing file must hold this sweep: every stored run's scene equal to ours."""
        other = (f"{path}: exists and holds another sweep ({{}}); use --force to replace it or "
                 f"-o another folder")
        try:
            with h5py.File(path, "r") as f:
                if f.attrs.get("kind") != "sweep" or int(f.attrs.get("n_runs", -1)) != len(
                        self.sweep.runs):
                    raise FileExistsError(other.format(f"not {len(self.sweep.runs)} runs"))
                for name, g in f["runs"].items():
                    i = int(g.attrs.get("index", -1))
                    same = (0 <= i < len(self.sweep.runs)
                            and g.attrs["scene_toml"] == self.sweep.runs[i].toml)
                    if "status" in g.attrs and not same:
                        raise FileExistsError(other.format(f"the scene of {name} differs from "
                                                           f"run {i} of {self.sweep.path}"))
        except OSError as exc:
            if isinstance(exc, FileExistsError):
                raise
            raise SceneError("(file)", f"cannot open to resume: {exc}; use --force to start "
                                       f"afresh", file=str(path)) from None

    def _create(self, path: Path) -> h5py.File:
        f = h5py.File(path, "w")
        f.attrs.update(creator="transient", version=__version__, format=1, created=_now(),
                       kind="sweep", sweep=self.sweep.name, complete=False,
                       n_runs=len(self.sweep.runs))
        f.create_group("sweep").create_dataset("toml", data=self.sweep.text)
        f.create_group("runs")
        f.create_group("analysis")
        return f

    def _prepare(self) -> set[int]:
        """Indices of the finished runs; groups left half-written by an interrupt are removed
        (they run again). The sweep's text and axes are (re)written: a resumed sweep may collect
        other quantities."""
        runs = self.f["runs"]
        for name in [n for n, g in runs.items() if "status" not in g.attrs]:
            del runs[name]
        done = {int(g.attrs["index"]) for g in runs.values()}
        g = self.f["sweep"]
        del g["toml"]
        g.create_dataset("toml", data=self.sweep.text)
        g.attrs.update(method=self.sweep.method, collect=json.dumps(self.sweep.collect),
                       axes=json.dumps([{"key": a.key, "group": a.group, "values": list(a.values)}
                                        for a in self.sweep.axes]))
        self.f.flush()
        return done

    def group_name(self, index: int) -> str:
        return f"run_{index:0{max(4, len(str(len(self.sweep.runs) - 1)))}d}"

    def drop_failed(self) -> None:
        """Forget the failed runs so that they run again (``--retry-failed``)."""
        for spec in self.sweep.runs:
            name = self.group_name(spec.index)
            if spec.index in self.finished and self.f["runs"][name].attrs["status"] != "ok":
                del self.f["runs"][name]
                self.finished.discard(spec.index)

    def write_run(self, spec: RunSpec, res: dict[str, Any]) -> None:
        """One run's group; ``status`` is written last and flushed, marking it finished."""
        runs = self.f["runs"]
        name = self.group_name(spec.index)
        if name in runs:
            del runs[name]
        g = runs.create_group(name)
        g.attrs.update(index=spec.index, params=json.dumps(spec.params), scene_toml=spec.toml,
                       message=res["message"], worker=res["worker"], wall_s=res["wall_s"],
                       created=_now())
        tr = g.create_group("trajectory")
        for col, values in res["trajectory"].items():
            values = np.asarray(values, dtype=float)
            opts = ({"compression": "gzip", "compression_opts": 1, "shuffle": True}
                    if values.size else {})  # (an empty dataset cannot be chunked)
            ds = tr.create_dataset(col, data=values, **opts)
            ds.attrs["unit"] = res["units"].get(col, "")
        ev = g.create_group("events")
        for ename, rows in res["events"].items():
            rows = np.asarray(rows, dtype=float).reshape(-1, 2)
            e = ev.create_group(ename)
            e.create_dataset("t", data=rows[:, 0]).attrs["unit"] = "s"
            e.create_dataset("phi", data=rows[:, 1]).attrs["unit"] = "rad"
        g.create_group("solver").attrs.update(res["solver"])
        an = g.create_group("analysis")
        for qname, (value, unit) in res["summary"].items():
            an.create_dataset(qname, data=value).attrs["unit"] = unit
        g.attrs["status"] = res["status"]
        self.f.flush()
        self.finished.add(spec.index)

    def summary(self) -> tuple[list[dict[str, Any]], dict[str, str]]:
        """The summary rows (run order) and the units of their columns, from the stored runs."""
        units = {"run": "", "status": "", **{a.key: _suffix_unit(a.key) for a in self.sweep.axes},
                 **{q: "" for q in self.sweep.collect}}
        rows = []
        for spec in self.sweep.runs:
            g = self.f["runs"].get(self.group_name(spec.index))
            if g is None or "status" not in g.attrs:
                continue
            row = {"run": spec.index, "status": str(g.attrs["status"]), **spec.params}
            for q in self.sweep.collect:
                value, unit = _quantity(g["analysis"], q)
                row[q] = value if row["status"] == "ok" else math.nan
                units[q] = units[q] or unit
            row["wall_s"] = float(g.attrs["wall_s"])
            row["compile_s"] = float(g["solver"].attrs.get("compile_s", math.nan))
            row["message"] = str(g.attrs["message"])
            rows.append(row)
        units.update(wall_s="s", compile_s="s", message="")
        return rows, units

    def write_summary(self, csv_path: Path) -> list[dict[str, Any]]:
        """``/analysis/summary`` and the CSV beside the file; returns the rows."""
        rows, units = self.summary()
        names = list(units)
        an = self.f["analysis"]
        if "summary" in an:
            del an["summary"]
        table = np.zeros(len(rows), dtype=[(n, _column_dtype(n, rows)) for n in names])
        for n in names:
            table[n] = [r.get(n, math.nan) for r in rows]
        ds = an.create_dataset("summary", data=table)
        ds.attrs["units"] = json.dumps(units)
        self.f.flush()
        with open(csv_path, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(names)
            w.writerows([[_csv(r.get(n, "")) for n in names] for r in rows])
        return rows

    def close(self, complete: bool) -> Path:
        """Close; a complete sweep gets its final name, an incomplete one stays a part."""
        if not self.f.id.valid:
            return self.part
        self.f.attrs["complete"] = bool(complete)
        self.f.close()
        if complete:
            os.replace(self.part, self.path)
            return self.path
        return self.part


def _suffix_unit(key: str) -> str:
    """The unit an axis key names by its suffix (``_rpm``, ``_deg`` …); "" for SI."""
    suffix = key.rpartition("_")[2]
    return suffix if suffix in ALL_SUFFIXES else ""


def _quantity(analysis, name: str) -> tuple[float, str]:
    """A collected quantity from a run's /analysis (a short name of QUANTITIES, or as stored)."""
    entry, factor, unit = QUANTITIES[name][:3] if name in QUANTITIES else (name, 1.0, None)
    if entry not in analysis:
        return math.nan, unit or ""
    return float(analysis[entry][()]) * factor, unit or str(analysis[entry].attrs.get("unit", ""))


def _column_dtype(name: str, rows: list[dict]) -> Any:
    values = [r.get(name) for r in rows]
    if name == "run":
        return "<i8"
    if any(isinstance(v, str) for v in values):
        return h5py.string_dtype()
    return "<f8"


def _csv(value: Any) -> Any:
    return repr(value) if isinstance(value, float) else value


# ------------------------------------------------------------------------------------------------
# Running a sweep


@dataclass
class Outcome:
    """What a sweep did: the file, the runs computed now, those found finished, and the rows."""

    path: Path
    csv: Path
    computed: list[int]
    skipped: list[int]
    rows: list[dict[str, Any]]

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [r for r in self.rows if r["status"] != "ok"]


def run_sweep(sweep: Sweep, out_dir: str | Path = "results", scheduler: str | None = None,
              workers: int | None = None, force: bool = False, retry_failed: bool = False,
              on_result: Callable[[RunSpec, dict, int, int], None] | None = None) -> Outcome:
    """Run the sweep's unfinished runs and write the file and the summary (module docstring).

    ``scheduler``: None for a LocalCluster of ``workers`` processes (default one per core), a
    ``tcp://host:port`` address of a running Dask scheduler, or ``"serial"`` (this process, no
    Dask: debugging and the benchmark's baseline). ``on_result(spec, result, done, total)`` is
    called after each run is written (the progress bar). On KeyboardInterrupt the file keeps the
    finished runs (``complete = false``) and the interrupt goes on.
    """
    out_dir = Path(out_dir)
    stem = sweep.path.stem
    store = SweepStore(out_dir / f"{stem}.h5", sweep, force)
    if retry_failed:
        store.drop_failed()
    skipped = sorted(store.finished)
    todo = [s for s in sweep.runs if s.index not in store.finished]
    computed: list[int] = []
    try:
        # closing(): an interrupt here shuts the cluster down at once, not when the generator
        # is collected
        with contextlib.closing(_execute(todo, sweep.columns, scheduler, workers)) as results:
            for spec, res in results:
                store.write_run(spec, res)
                computed.append(spec.index)
                if on_result:
                    on_result(spec, res, len(store.finished), len(sweep.runs))
    except BaseException:
        store.close(False)
        raise
    csv_path = out_dir / f"{stem}_summary.csv"
    rows = store.write_summary(csv_path)
    path = store.close(True)
    return Outcome(path, csv_path, computed, skipped, rows)


def _execute(todo: list[RunSpec], columns, scheduler: str | None, workers: int | None
             ) -> Iterator[tuple[RunSpec, dict]]:
    """(spec, result) of each run as it finishes."""
    if not todo:
        return
    if scheduler == "serial":
        for spec in todo:
            yield spec, run_one(spec.scene, columns)
        return
    from dask.distributed import as_completed

    with _client(scheduler, workers) as client:
        futures = {client.submit(run_one, s.scene, columns, pure=False,
                                 key=f"transient-run-{s.index}-{os.urandom(4).hex()}"): s
                   for s in todo}
        try:
            for fut in as_completed(futures):
                spec = futures.pop(fut)
                try:
                    res = fut.result()
                except Exception as exc:  # noqa: BLE001 (a lost worker or task: this run only)
                    res = _lost(exc)
                fut.release()
                yield spec, res
        finally:
            client.cancel(list(futures))


def _lost(exc: BaseException) -> dict[str, Any]:
    return {"status": "failed", "message": f"{type(exc).__name__} (on the cluster): {exc}",
            "trajectory": {}, "events": {}, "solver": {}, "summary": {}, "units": {},
            "worker": "?", "wall_s": math.nan}


@contextlib.contextmanager
def _sigint_ignored():
    """SIGINT ignored while processes are started (they keep ignoring it: Python installs no
    KeyboardInterrupt handler where SIGINT is ignored at start), so that a Ctrl-C reaches the
    client alone, which stops the cluster in order; the main thread only (signals need it)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class _client:
    """A Dask client: on a new LocalCluster (one single-threaded process per core, loopback
    only) or connected to ``address``; checks that the workers can import transient."""

    def __init__(self, address: str | None, workers: int | None) -> None:
        self.address, self.workers = address, workers
        self.cluster = self.client = None

    def __enter__(self):
        import logging

        from dask.distributed import Client, LocalCluster

        if self.address is None:
            # Processes, not threads: the runs hold the GIL in Python between compiled chunks.
            # Loopback only; the scheduler's HTTP server (always started) on a free port.
            with _sigint_ignored():  # Ctrl-C is the client's to handle: the workers inherit this
                self.cluster = LocalCluster(n_workers=self.workers or os.cpu_count() or 1,
                                            threads_per_worker=1, processes=True,
                                            host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                            silence_logs=logging.ERROR)
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(self.address, timeout="10s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise SceneError("--scheduler", f"cannot connect to {self.address!r}: {exc}; "
                                                f"give tcp://host:port of a running Dask "
                                                f"scheduler") from None
        try:
            info = self.client.run(worker_info)
        except Exception as exc:  # noqa: BLE001 (whatever the workers raise, said in one line)
            self.__exit__(None, None, None)
            raise SceneError("--scheduler", f"the workers cannot import transient ({exc}); "
                                            f"install it in the workers' environment") from None
        other = {w: i["version"] for w, i in info.items() if i["version"] != __version__}
        if other:
            print(f"transient sweep: warning: workers run other versions of transient: {other}",
                  file=sys.stderr)
        return self.client

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


# ------------------------------------------------------------------------------------------------
# Reading a sweep file back (plots)


@dataclass
class SweepTable:
    """The summary of a sweep file: columns by name, their units, the axes and the method."""

    path: Path
    name: str
    method: str
    axes: list[dict[str, Any]]
    collect: list[str]
    columns: dict[str, np.ndarray]
    units: dict[str, str]


def read_summary(path: str | Path) -> SweepTable:
    """``/analysis/summary`` of a sweep file (complete or a ``.part``)."""
    path = Path(path)
    with h5py.File(path, "r") as f:
        if f.attrs.get("kind") != "sweep":
            raise ValueError("not a transient sweep file")
        if "summary" not in f["analysis"]:
            raise ValueError("no summary yet (the sweep did not finish; rerun it to resume)")
        ds = f["analysis/summary"]
        table = ds[()]
        cols = {n: (np.array([v.decode() if isinstance(v, bytes) else v for v in table[n]])
                    if table.dtype[n].kind == "O" else table[n]) for n in table.dtype.names}
        s = f["sweep"].attrs
        return SweepTable(path, str(f.attrs["sweep"]), str(s["method"]), json.loads(s["axes"]),
                          json.loads(s["collect"]), cols, json.loads(ds.attrs["units"]))
