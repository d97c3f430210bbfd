"""The reference of every scene key, collected from the reader as it reads.

Each :class:`~.reader.Section` tells a listener (:func:`~.reader.listening`) what it asks of a
key before reading it: its type, quantity kind, default, bounds and choices
(:class:`~.reader.Key`). :func:`collect` reads scenes through the reader with such a listener
and, to reach the keys that only some choice reads (``gas.model = "wiebe"``), reads each again
with every value of every choice key, a value within its bounds filled in for each required key
the variant lacks. What it gathers is what the reader asks, nothing restated; each key's one-line
meaning comes from the tables beside the reader (:mod:`~transient.scene.meanings`,
and each mechanism's ``key_meanings`` for the ``[mechanism]`` tables it reads itself). The
documentation renders it (``docs/_ext/scene_keys.py``); the tests hold it to the case files and
to what the reader enforces.
"""
from __future__ import annotations

import copy
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import SceneError
from ..mechanisms import MECHANISMS
from ..units import SHOWN, SUFFIXES, UNITS, Named, value_of
from .meanings import MEANINGS
from .read import scene_from_dict
from .reader import MISSING, Key, Section, listening

#: The choice keys whose value selects which other keys of their table the reader reads.
SELECTORS = ("model", "mode")
#: Reads that no case and no choice alone reach (the reader tests for a key's presence there,
#: or reads a file): table → what it is replaced with.
EXTRA_TABLES = (
    ("gas", {"model": "table", "phi_deg": [0.0, 720.0], "p_bar": [1.0, 1.0],
             "motored_p_bar": [1.0, 1.0], "corners_deg": [360.0]}),
    ("gas", {"model": "table", "file": "diagram.csv"}),
    ("gas", {"model": "table", "phi_deg": [0.0, 360.0], "force": [0.0, 1.0]}),
    ("run", {"mode": "prescribed-speed", "t_end": 1.0, "time": [0.0, 1.0],
             "speed_table_rpm": [1000, 1000]}),
    ("run", {"mode": "prescribed-speed", "t_end": 1.0, "speed_rpm": 1000}),
    ("load", {"table": {"speed_rpm": [0.0, 1000.0], "torque": [0.0, 1.0]}}),
    ("load", {"table": {"phi_deg": [0.0, 360.0], "torque": [0.0, 1.0]}}),
    ("load", {"table": {"time": [0.0, 1.0], "torque": [0.0, 1.0]}}),
    ("load", {"table": {"file": "water_brake_map.csv"}}),
    ("load", {"inertia": 0.1, "inertia_time": 0.5, "generator_power": 1.0,
              "generator_min_speed_rpm": 100, "schedule_revolutions": [0.0, 1.0],
              "schedule_scale": [1.0, 0.5]}),
    ("shaft", {"stations": [{"name": "a", "inertia": 0.1, "cylinders": [1]}, {"name": "b"}],
               "sections": [{"length_mm": 100.0, "diameter_mm": 60.0, "bore_mm": 20.0,
                             "shear_modulus_GPa": 80.0, "damping_ratio": 0.01}],
               "dampers": [{"station": "a", "model": "tuned", "inertia": 0.01,
                            "stiffness": 1e4, "damping": 1.0}],
               "coupling": {"stiffness": 1e4, "damping": 1.0, "gear_ratio": 2.0,
                            "driven_inertia": 0.5},
               "reference": "b", "load_at": "driven", "speed_range_rpm": [0.0, 1000.0]}),
    ("friction", {"pairs": [{"between": ["shaft", "crank"], "model": "table",
                             "speed": [0.0, 100.0], "torque": [0.0, 100.0],
                             "eta_forward": [[0.9, 0.9], [0.9, 0.9]],
                             "eta_backward": [[0.9, 0.9], [0.9, 0.9]]}]}),
)
#: Reads of one scene, each filling in at most this many required keys.
MAX_FILLS = 40


@dataclass
class Example:
    """A scene in which the reader read a key one way: the case it comes from, its parsed TOML
    (``data``, read relative to ``base_dir``), the path of the key's table in it
    (``friction.pairs[0]``), the values the bounds had there, whether a choice or a value
    was put into the case (``varied``) to reach the key and whether the key is given there."""

    case: str
    data: dict
    base_dir: Path
    path: str
    bounds: tuple[tuple[str, float | int], ...]
    varied: bool
    given: bool


@dataclass
class Row:
    """A key as the reader reads it one way (its spec), under which choices of its table; the
    quantity kinds it is read as (two for a key whose unit follows what else the table gives:
    a pair's ``viscous``)."""

    name: str
    key: Key
    contexts: set[tuple[str | None, str]] = field(default_factory=set)  # (mechanism, choice)
    example: Example | None = None
    kinds: list[str] = field(default_factory=list)

    @property
    def variants(self) -> set[str]:
        """The choices of its table under which it is read so ("": whatever the choice)."""
        return {variant for _, variant in self.contexts}

    @property
    def required(self) -> bool:
        return value_of(self.key.default) is MISSING

    @property
    def numeric(self) -> bool:
        return self.key.type in ("number", "numbers", "integer", "integers")

    @property
    def unit(self) -> str:
        """The SI unit of a number written without a suffix (``"1"``: dimensionless; a whole
        number counts), or "" for what is no number."""
        if self.key.type in ("number", "numbers"):
            return " or ".join(UNITS[k] for k in self.kinds)
        return "1" if self.key.type in ("integer", "integers") else ""

    @property
    def suffixes(self) -> dict[str, float]:
        return SUFFIXES.get(self.key.kind, {}) if self.key.kind else {}


@dataclass
class Table:
    """One TOML table as the reader reads it: its path (``gas.cylinders[]`` for an array of
    tables), the mechanism type it belongs to (``[mechanism]`` and its sub-tables, which each
    mechanism reads itself; else None), its rows in reading order and its choices' variants."""

    path: str
    family: str | None
    rows: list[Row] = field(default_factory=list)

    @property
    def variants(self) -> set[str]:
        return set().union(*(r.variants for r in self.rows)) - {""}

    def meaning(self, name: str) -> str:
        """The key's one-line meaning, from the table the reader's side keeps."""
        if self.family is not None:
            own = MECHANISMS[self.family].key_meanings.get(self.path, {})
            if name in own:
                return own[name]
        return MEANINGS.get(self.path, {}).get(name, "")


@dataclass
class Reference:
    """Every table and key the reader read (:func:`collect`), and what is inconsistent:
    a key read within one choice with two defaults or bounds that differ without a name
    (:class:`~transient.units.Named`), or a key without a meaning."""

    tables: dict[tuple[str, str | None], Table]
    problems: list[str]

    def find(self, path: str, name: str, family: str | None = None) -> list[Row]:
        """The rows of key ``name`` of table ``path`` (``gas.cylinders[]``)."""
        table = self.tables.get((path, family if path.split(".")[0] == "mechanism" else None))
        return [r for r in table.rows if r.name == name] if table else []


def table_path(path: str) -> str:
    """``friction.pairs[1]`` → ``friction.pairs[]``: an array's entries are one table."""
    return re.sub(r"\[\d+\]", "[]", path)


class Recorder:
    """Listens to the reader (:func:`~.reader.listening`) and gathers the :class:`Reference`."""

    def __init__(self) -> None:
        self.tables: dict[tuple[str, str | None], Table] = {}
        self.selectors: dict[str, dict[str, tuple]] = {}  # path → choice key → its choices
        self._read: tuple[str, dict, Path, bool] | None = None
        self._family: str | None = None
        self._variant: dict[str, str] = {}  # path → the choice read in it
        self.missing: tuple[str, Key] | None = None  # the last required key heard absent

    def hear(self, section: Section, key: Key) -> None:
        path = table_path(section.path)
        if section.path == "mechanism" and key.name == "type":
            self._family = section.data.get("type")
        family = self._family if path.split(".")[0] == "mechanism" else None
        if key.name in SELECTORS and key.choices:
            self.selectors.setdefault(section.path, {})[key.name] = key.choices
            chosen = section.data.get(key.name, value_of(key.default))
            self._variant[section.path] = f'{key.name} = "{chosen}"'
        table = self.tables.setdefault((path, family), Table(path, family))
        variant = self._variant.get(section.path, "") if key.name not in SELECTORS else ""
        spec = _spec(key)
        row = next((r for r in table.rows if r.name == key.name and _spec(r.key) == spec), None)
        if row is None:
            row = Row(key.name, key)
            table.rows.append(row)
        row.contexts.add((self._family, variant))
        if key.kind is not None and key.kind not in row.kinds:  # (a number's: others have none)
            row.kinds.append(key.kind)
        if self._read is None:
            raise RuntimeError("a key heard outside Recorder.read")
        case, data, base_dir, varied = self._read
        bounds = tuple((w, value_of(b) if isinstance(value_of(b), int) else float(value_of(b)))
                       for w, b in key.bounds)
        absent = not section.has(key.name, key.kind)
        example = Example(case, data, base_dir, section.path, bounds, varied, not absent)
        if row.example is None or _rank(example) > _rank(row.example):
            row.example = example
        self.missing = (section.path, key) if absent and value_of(key.default) is MISSING \
            else None

    def read(self, case: str, data: dict, base_dir: Path, varied: bool = False) -> None:
        """Read one scene, filling in (if ``varied``) each required key it lacks."""
        data = copy.deepcopy(data)
        for _ in range(MAX_FILLS):
            self._read, self._family, self._variant = (case, copy.deepcopy(data), base_dir,
                                                       varied), None, {}
            self.missing = None
            try:
                scene_from_dict(data, file=f"{case}.toml", base_dir=base_dir)
                return
            except SceneError as exc:
                if not varied or self.missing is None:
                    return
                path, key = self.missing
                if exc.key != (f"{path}.{key.name}" if path else key.name):
                    return  # (refused for another reason: what was read is recorded)
                value = _placeholder(key)
                if value is None:
                    return
                table_at(data, path)[key.name] = value

    def reference(self) -> Reference:
        problems = []
        for table in self.tables.values():
            by_variant: dict[tuple, list[Row]] = {}
            for row in table.rows:
                for family, v in row.contexts:
                    by_variant.setdefault((row.name, v, family), []).append(row)
                if not table.meaning(row.name):
                    problems.append(f"[{table.path}] {row.name}"
                                    + (f" ({table.family})" if table.family else "")
                                    + ": no meaning")
            for (name, v, _), rows in by_variant.items():
                if len(rows) > 1:
                    problems.append(f"[{table.path}] {name}" + (f" ({v})" if v else "")
                                    + ": read with a default, bounds or type that differ "
                                      "from scene to scene without a name: "
                                    + "; ".join(repr(_spec(r.key)) for r in rows))
        return Reference(self.tables, problems)


def collect(scenes: Iterable[tuple[str, dict, Path]]) -> Reference:
    """The :class:`Reference` of what the reader asks of every key it reads in ``scenes``
    (name, parsed TOML, folder its files are relative to), and in each variant of them: every
    value of each choice key met, and :data:`EXTRA_TABLES`."""
    scenes = list(scenes)
    rec = Recorder()
    with listening(rec.hear):
        for case, data, base_dir in scenes:
            rec.selectors.clear()
            rec.read(case, data, base_dir)
            for path, choices in list(rec.selectors.items()):
                for name, values in choices.items():
                    for value in values:
                        variant = copy.deepcopy(data)
                        table_at(variant, path)[name] = value
                        rec.read(case, variant, base_dir, varied=True)
            for table, replacement in EXTRA_TABLES:
                variant = copy.deepcopy(data)
                variant[table] = copy.deepcopy(replacement)
                rec.read(case, variant, base_dir, varied=True)
    return rec.reference()


def _rank(example: Example) -> tuple[bool, bool, bool]:
    """How good an example is (the larger the better): a case as it is rather than varied,
    the key given in it, and every bound finite (testable)."""
    return (not example.varied, example.given, all(math.isfinite(v) for _, v in example.bounds))


def _spec(key: Key) -> tuple:
    """What a row shows of a :class:`~.reader.Key` but its kind: a
    :class:`~transient.units.Named` default or bound by its name, a plain one by its value."""
    def shown(x):
        return ("named", x.name) if isinstance(x, Named) else ("value", _hashable(x))
    return (key.type, shown(key.default), tuple((w, shown(b)) for w, b in key.bounds),
            key.choices, key.or_zero)


def _hashable(x: Any) -> Any:
    if x is MISSING:
        return "required"
    if isinstance(x, (list, tuple)):
        return tuple(_hashable(v) for v in x)
    if isinstance(x, float) and math.isnan(x):
        return "nan"
    return x


def table_at(data: dict, path: str) -> dict:
    """The dict of the table at ``path`` (``friction.pairs[0]``) in parsed TOML, made if
    absent."""
    node = data
    for part in [p for p in path.split(".") if p]:
        name, _, index = part.partition("[")
        node = node.setdefault(name, [] if index else {})
        if index:
            node = node[int(index[:-1])]
    return node


def _placeholder(key: Key) -> Any:
    """A value of the key's type within its bounds and choices, or None if there is none."""
    if key.choices:
        return key.choices[0]
    lows = [value_of(b) for w, b in key.bounds if w in (">", "≥")]
    highs = [value_of(b) for w, b in key.bounds if w in ("<", "≤")]
    low = max(lows, default=None)
    high = min(highs, default=None)
    if low is not None and high is not None:
        value = (low + high) / 2.0
    elif low is not None:
        value = low + max(1.0, abs(low))
    elif high is not None:
        value = high - max(1.0, abs(high)) / 2.0
    else:
        value = 1.0
    return {"number": value, "numbers": [value, value], "integer": max(1, math.ceil(value)),
            "integers": [1], "flag": False, "string": "x", "strings": [], "table": {},
            "tables": []}.get(key.type)


def shown_value(value: Any, kind: str | None) -> str:
    """A default or bound as a scene writes it: an angle in degrees, a speed in rpm, a length
    in mm, a pressure in bar (:data:`transient.units.SHOWN`), else in SI with its unit."""
    if isinstance(value, Named):
        return value.name
    if value is None:
        return "not set"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(shown_value(v, kind) for v in value) + "]" if value else "none"
    if isinstance(value, int):
        return str(value).replace("-", "−")
    if math.isinf(value):
        return "not set"
    if kind in SHOWN:
        suffix, symbol = SHOWN[kind]
        number = _number(value / SUFFIXES[kind][suffix])
        return number + ("°" if symbol == "°" else f" {symbol}") if value != 0.0 else "0"
    unit = UNITS.get(kind, "1") if kind else "1"
    return _number(value) + (f" {unit}" if unit not in ("1", "") and value != 0.0 else "")


def _number(x: float) -> str:
    """``1e-10`` as 10⁻¹⁰, ``-30`` as −30, others as ``:.6g`` gives them."""
    text = f"{x:.6g}".replace("-", "−")
    if "e" in text:
        mantissa, exponent = text.split("e")
        power = str(int(exponent.replace("−", "-"))).translate(
            str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
        return f"10{power}" if mantissa == "1" else f"{mantissa} × 10{power}"
    return text
