"""The sweep file: a base scene, parameter axes, the quantities to collect; every run's scene.

A **sweep file** (TOML; examples in ``cases/sweeps/``)::

    [sweep]
    name = "gots-eta"                      # default: the file's stem
    base = "../gots_diesel_friction.toml"  # relative to this file (or inline: a [base] table)
    method = "grid"                        # grid | list | random
    collect = ["mean_speed_rpm", "eta_mech"]
    columns = ["t", "phi", "omega"]        # trajectory columns to store (default all; [] none)
    steady = false                         # true: each run the scene's periodic steady state

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

Every resolved scene is validated here, before any work, so that a bad point stops the sweep
with one line instead of failing on a worker. With ``steady = true`` each run is the scene's
periodic steady state (:func:`transient.steady`: one steady cycle, found in a few cycles)
instead of its run from the initial state, and every scene must be periodic (refused here
otherwise, with the run and the key); its resolved TOML, which identifies a stored run when a
sweep is mended, then begins with :data:`STEADY_MARK`, so that a stored run of the other kind
is never taken for it.
"""
from __future__ import annotations

import copy
import dataclasses
import itertools
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import QUOTE_LIMIT, SceneError, clip, show_value
from ..scene.files import parse_toml, read_text
from ..scene.reader import finite_number
from ..units import ALL_SUFFIXES

METHODS = ("grid", "list", "random")
#: The first line of a steady run's resolved TOML (``sweep.steady``; the module docstring).
STEADY_MARK = "# the periodic steady state (sweep.steady = true)\n"
SPACINGS = ("linear", "log")
RPM = 30.0 / math.pi


def _has_load_step(scene) -> bool:
    """Whether the load schedule steps (two equal instants): the load-change quantities need one."""
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
    "fmep_kPa": ("fmep", 1e-3, "kPa", "friction mean effective pressure Σ W_loss/V_d, steady "
                 "cycles", lambda s: s.gas.model != "none"),
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
#: Most runs one sweep file may ask for: every run's scene is resolved and validated before any
#: work, so a grid of 10¹² points would never start; split a larger study into sweeps.
MAX_RUNS = 100_000
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_KEY_PART = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?$")


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
    steady: bool = False  # each run the scene's periodic steady state

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
        self.data, self.where, self.file = dict(data), where, file
        self.known: list[str] = []

    def error(self, key: str, message: str) -> SceneError:
        return SceneError(f"{self.where}.{key}" if self.where else key, message, file=self.file)

    def get(self, key: str, types: tuple, default: Any = None, what: str = "") -> Any:
        self.known.append(key)
        if key not in self.data:
            return default
        value = self.data.pop(key)
        if isinstance(value, bool) and bool not in types or not isinstance(value, types):
            raise self.error(key, f"must be {what}, got {show_value(value)}")
        return value

    def finish(self) -> None:
        for key in self.data:
            raise self.error(key, f"unknown key; allowed here: {', '.join(self.known)}")


def load_sweep(source: str | Path) -> Sweep:
    """Read and validate a sweep file and every scene it resolves to. Raises SceneError."""
    path = Path(source)
    file = str(path)
    text = read_text(path, "sweep")
    data = parse_toml(text, file)
    root = _Table(data, "", file)
    head = _Table(root.get("sweep", (dict,), None, "a table") or {}, "sweep", file)
    name = head.get("name", (str,), path.stem, "a string")
    if not name.isprintable():  # (it labels the progress bar and the sweep's files, as a scene's)
        raise head.error("name", f"holds a control character ({show_value(name)}); give "
                                 f"printable text")
    base_path = head.get("base", (str,), None, "a scene file path (string)")
    inline = root.get("base", (dict,), None, "a table holding the whole base scene")
    if (base_path is None) == (inline is None):
        raise head.error("base", "give the base scene either as a file (sweep.base = \"x.toml\") "
                                 "or inline as a [base] table, exactly one of them")
    method = head.get("method", (str,), "grid", "a string")
    if method not in METHODS:
        raise head.error("method", f"unknown value {show_value(method)}; allowed: "
                                   f"{', '.join(METHODS)}")
    samples = head.get("samples", (int,), None, "a whole number ≥ 1")
    seed = head.get("seed", (int,), None, "a whole number")
    if samples is not None and samples > MAX_RUNS:
        raise head.error("samples", f"must be ≤ {MAX_RUNS} (runs of one sweep), got {samples}")
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
        raise head.error("columns", f"must be a list of strings, got {show_value(columns)}")
    steady = head.get("steady", (bool,), False, "true or false")
    head.finish()
    changes = _flatten(root.get("set", (dict,), {}, "a table of dotted scene keys and values"))
    for key in changes:
        _check_key(key, SceneError(f"set.{key}", "", file=file))
    draws = None if samples is None or seed is None else (samples, seed)  # (method "random")
    axes = tuple(_axis(_Table(a, f"axis[{i}]", file), draws, i)
                 for i, a in enumerate(_axis_list(root, file)))
    root.finish()
    _check_distinct(axes, file)
    if inline is not None:
        base, base_file, base_dir = inline, f"{file}:[base]", path.parent
    else:
        base_file = path.parent / base_path
        base, base_dir = _read_base(base_file, base_path, file), base_file.parent
    sweep = Sweep(name, path, text, method, axes, collect,
                  None if columns is None else tuple(columns), (), steady)
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
            raise head.error("collect", f"{show_value(n)} is not a quantity name; give names "
                                        f"such as {', '.join(QUANTITIES)}, or any /analysis "
                                        f"entry")
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
    texts = key.split(".")
    parts = [m for m in map(_KEY_PART.match, texts) if m is not None]
    if not key or len(parts) < len(texts):
        err.message = (f"{show_value(key)} is not a scene key; give dotted TOML keys such as "
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
            raise SceneError(f"axis[{i}].key", f"{show_value(a.key)} sets the quantity of "
                                               f"axis[{j}] ({show_value(axes[j].key)}) again; "
                                               f"give each quantity one axis", file=file)


def _axis(t: _Table, draws: tuple[int, int] | None, i: int) -> Axis:
    """Axis ``i`` of the table ``t``; ``draws``, (samples, seed) of method ``"random"``, else
    None."""
    key = t.get("key", (str,), None, "a dotted scene key (string)")
    if key is None:
        raise t.error("key", "is missing; give the dotted scene key this axis sets, e.g. "
                             "'load.torque'")
    _check_key(key, t.error("key", ""))
    group = t.get("group", (str,), f"#{i}", "a string")
    values = t.get("values", (list,), None, "a list of values")
    lo_hi = {k: t.get(k, (int, float), None, "a number")
             for k in (("low", "high") if draws is not None else ("from", "to"))}
    num = t.get("num", (int,), None, "a whole number ≥ 2") if draws is None else None
    spacing = t.get("spacing", (str,), "linear", "a string")
    t.finish()
    for k, v in lo_hi.items():
        if v is not None and not finite_number(v):
            raise t.error(k, f"must be finite, got {show_value(v)}")
    if spacing not in SPACINGS:
        raise t.error("spacing", f"unknown value {show_value(spacing)}; allowed: "
                                 f"{', '.join(SPACINGS)}")
    given = [k for k, v in lo_hi.items() if v is not None] + (["num"] if num is not None else [])
    if values is not None and given:
        raise t.error(given[0], "given together with 'values'; give a list of values or a range, "
                                "not both")
    if values is not None:
        if not values or not all(isinstance(v, (int, float, str, bool)) for v in values):
            raise t.error("values", f"must be a non-empty list of numbers, strings or booleans, "
                                    f"got {show_value(values)}")
        if draws is not None:  # draw from the list
            samples, seed = draws
            picks = np.random.default_rng([seed, i]).integers(0, len(values), samples)
            values = [values[k] for k in picks]
        return Axis(key, tuple(values), group)
    need = list(lo_hi) + ([] if draws is not None else ["num"])
    missing = [k for k in need if k not in given]
    if missing:
        raise t.error(missing[0], f"is missing; give 'values' = [...] or {', '.join(need)}")
    a, b = lo_hi.values()
    if spacing == "log" and not (a > 0 and b > 0):
        raise t.error(need[0], f"spacing = \"log\" needs positive bounds, got {a:g} and {b:g}")
    if draws is not None:
        if not a < b:
            raise t.error("high", f"must be > low ({a:g}), got {b:g}")
        return Axis(key, _draw(a, b, spacing, *draws, i), group)
    if num is None or not 2 <= num <= MAX_RUNS:  # (None: refused as missing above)
        raise t.error("num", f"must be 2 … {MAX_RUNS} (runs of one sweep), got {num}")
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
            what = "method = \"list\"" if moving else f"group {show_value(g[0].group)}"
            raise SceneError(f"axis ({g[0].key})",
                             f"the axes of {what} move together and need equally many values; "
                             f"got {', '.join(f'{a.key}: {len(a.values)}' for a in g)}",
                             file=str(sweep.path))
    if moving is not None:
        yield from (dict(zip((a.key for a in moving), row))
                    for row in zip(*(a.values for a in moving)))
        return
    runs = math.prod(len(g[0].values) for g in groups)
    if runs > MAX_RUNS:
        raise SceneError("axis", f"the grid has {runs} points, more than the {MAX_RUNS} runs of "
                                 f"one sweep; split it into sweeps or give fewer values",
                         file=str(sweep.path))
    for combo in itertools.product(*(range(len(g[0].values)) for g in groups)):
        yield {a.key: a.values[k] for g, k in zip(groups, combo) for a in g}


def _read_base(path: Path, written: str, sweep_file: str) -> dict:
    """The base scene at ``path`` parsed (as ``written`` in the sweep file, which its errors
    quote)."""
    try:
        return parse_toml(read_text(path, "scene"), str(path))
    except SceneError as exc:  # (the sweep file's key names which file could not be read)
        raise SceneError("sweep.base", f"the base scene {show_value(written)}: {exc.message}",
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
            raise SceneError(key, f"{show_value(name)} is a value in the base scene, not a table")
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
    from ..scene import scene_from_dict, to_toml
    from ..shooting import refuse_nonperiodic

    data = copy.deepcopy(base)
    shown = ", ".join(f"{clip(k)} = {show_value(v)}" for k, v in params.items())
    try:
        for key, value in itertools.chain(changes.items(), params.items()):
            set_key(data, key, value)
        scene = scene_from_dict(data, file=base_file, base_dir=base_dir)
        if sweep.steady:
            refuse_nonperiodic(scene)
    except SceneError as exc:
        raise SceneError(f"run {i} ({shown})", f"scene {clip(exc.key, 4 * QUOTE_LIMIT)}: "
                                               f"{exc.message}",
                         file=str(sweep.path)) from None
    return RunSpec(i, params, scene, STEADY_MARK * sweep.steady + to_toml(scene))


def _check_columns(sweep: Sweep, runs: tuple[RunSpec, ...]) -> None:
    """Collected short names must be measurable, stored columns must exist, in every scene."""
    from ..scene.outputs import output_columns

    for spec in runs:
        for q in sweep.collect:
            check = QUANTITIES.get(q, (None,) * 5)[4]
            if check is not None and not check(spec.scene):
                what = "gas forces" if q in ("eta_mech", "fmep_kPa") else "load step"
                raise SceneError("sweep.collect", f"{show_value(q)} ({QUANTITIES[q][3]}) cannot "
                                                  f"be measured in run {spec.index}: its scene "
                                                  f"has no {what}",
                                 file=str(sweep.path))
        have = output_columns(spec.scene)
        for c in sweep.columns or ():
            if c not in have:
                raise SceneError("sweep.columns", f"unknown column {show_value(c)} in run "
                                                  f"{spec.index}; allowed: {', '.join(have)}",
                                 file=str(sweep.path))
