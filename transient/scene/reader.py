"""The typed-key TOML reader: :class:`~transient.scene.reader.Section` takes keys off one
table, converts unit suffixes to SI and reports anything left over as an unknown key.

A quantity may be written in SI (``crank_radius = 0.047``) or with one unit suffix of its kind
(``crank_radius_mm = 47``, :data:`transient.units.SUFFIXES`). Every problem raises
:class:`transient.errors.SceneError` naming the key as the user wrote it, what is wrong and what
is allowed.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import SceneError, show_value
from ..units import ALL_SUFFIXES, SUFFIXES

#: The default of a required key: reading it when absent is an error (``None`` is a valid
#: default, so it cannot mark one).
MISSING = object()

#: TOML integers are unbounded; one past a float's range could not be compared or converted.
MAX_EXACT_INT = int(1.7976931348623157e308)


class Section:
    """One TOML table being read: takes keys off it, converts units, and reports what is left."""

    def __init__(self, data: Any, path: str) -> None:
        if not isinstance(data, dict):
            raise SceneError(path, f"must be a table, got {type(data).__name__}")
        self.data = dict(data)
        self.path = path
        self.known: list[str] = []
        self.kinds: dict[str, str | None] = {}
        self.written: dict[str, str] = {}  # base name -> the key as the user wrote it
        self.subs: dict[str, Section] = {}  # sub-tables read so far, for rename()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def _take(self, name: str, kind: str | None):
        """(value, SI factor, key as written) for a quantity given plain or with one unit suffix."""
        self.known.append(name)
        self.kinds[name] = kind
        found = []
        if name in self.data:
            found.append((name, 1.0))
        for suffix, factor in (SUFFIXES.get(kind, {}) if kind else {}).items():
            if f"{name}_{suffix}" in self.data:
                found.append((f"{name}_{suffix}", factor))
        if len(found) > 1:
            raise SceneError(self.key(found[1][0]),
                             f"given twice (also as {show_value(found[0][0])}); give one of them")
        if not found:
            self._check_suffixes(name)
            return MISSING, 1.0, name
        written, factor = found[0]
        self.written[name] = written
        return self.data.pop(written), factor, written

    def _check_suffixes(self, name: str) -> None:
        """A key ``name_<suffix>`` with a suffix this quantity does not take is an error here,
        not a 'missing key' later."""
        for key in self.data:
            base, _, suffix = key.rpartition("_")
            if base == name and _looks_like_unit(suffix):
                raise SceneError(self.key(key), self._suffix_problem(name, suffix))

    def _suffix_problem(self, name: str, suffix: str) -> str:
        hint = self._unit_hint(name, self.kinds.get(name))
        if suffix in ALL_SUFFIXES:
            return f"unit suffix '_{suffix}' does not fit this quantity; {hint}"
        return f"unknown unit suffix '_{suffix}'; {hint}"

    def number(self, name: str, kind: str | None = None, default: Any = MISSING, *,
               gt: float | None = None, ge: float | None = None, lt: float | None = None,
               le: float | None = None) -> float:
        value, factor, written = self._take(name, kind)
        if value is MISSING:
            if default is MISSING:
                raise SceneError(self.key(name), f"is missing; {self._unit_hint(name, kind)}")
            return default
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(self.key(written), f"must be a number, got {show_value(value)}")
        if isinstance(value, int) and abs(value) > MAX_EXACT_INT:
            raise SceneError(self.key(written), f"must be finite, got {show_value(value)} (beyond "
                                                f"a float's range)")
        if not math.isfinite(value):
            raise SceneError(self.key(written), f"must be finite, got {value}")
        self._check_range(written, value, gt, ge, lt, le, factor)
        return float(value) * factor

    def _check_range(self, written, value, gt, ge, lt, le, factor):
        # Bounds are given in SI; compare in the units the user wrote.
        for bound, ok, word in ((gt, lambda v, b: v > b, ">"), (ge, lambda v, b: v >= b, "≥"),
                                (lt, lambda v, b: v < b, "<"), (le, lambda v, b: v <= b, "≤")):
            if bound is not None and not ok(value * factor, bound):
                raise SceneError(self.key(written),
                                 f"must be {word} {bound / factor:g}, got {value:g}")

    def integer(self, name: str, default: Any = MISSING, *, ge: int | None = None,
                choices: tuple[int, ...] | None = None, le: int | None = None) -> int:
        value, _, written = self._take(name, None)
        if value is MISSING:
            if default is MISSING:
                raise SceneError(self.key(name), "is missing; give a whole number")
            return default
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(self.key(written), f"must be a whole number, got {show_value(value)}")
        if ge is not None and value < ge:
            raise SceneError(self.key(written), f"must be ≥ {ge}, got {show_value(value)}")
        if le is not None and value > le:
            raise SceneError(self.key(written), f"must be ≤ {le}, got {show_value(value)}")
        if choices is not None and value not in choices:
            raise SceneError(self.key(written),
                             f"must be one of {', '.join(map(str, choices))}, got "
                             f"{show_value(value)}")
        return value

    def flag(self, name: str, default: bool) -> bool:
        value, _, written = self._take(name, None)
        if value is MISSING:
            return default
        if not isinstance(value, bool):
            raise SceneError(self.key(written), f"must be true or false, got {show_value(value)}")
        return value

    def strings(self, name: str, default: Any = MISSING) -> tuple:
        value, _, written = self._take(name, None)
        if value is MISSING:
            if default is MISSING:
                raise SceneError(self.key(name), "is missing; give a list of strings")
            return default
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise SceneError(self.key(written),
                             f"must be a list of strings, got {show_value(value)}")
        return tuple(value)

    def string(self, name: str, default: Any = MISSING, *,
               choices: tuple[str, ...] | None = None) -> str:
        value, _, written = self._take(name, None)
        if value is MISSING:
            if default is MISSING:
                allowed = f"; allowed: {', '.join(choices)}" if choices else ""
                raise SceneError(self.key(name), f"is missing{allowed}")
            return default
        if not isinstance(value, str):
            raise SceneError(self.key(written), f"must be a string, got {show_value(value)}")
        if choices is not None and value not in choices:
            raise SceneError(self.key(written),
                             f"unknown value {show_value(value)}; allowed: "
                             f"{', '.join(map(repr, choices))}")
        return value

    def numbers(self, name: str, kind: str | None = None, default: Any = MISSING) -> tuple:
        value, factor, written = self._take(name, kind)
        if value is MISSING:
            if default is MISSING:
                raise SceneError(self.key(name), f"is missing; {self._unit_hint(name, kind)} list")
            return default
        if not isinstance(value, list) or not finite_numbers(value):
            raise SceneError(self.key(written), f"must be a list of finite numbers, got "
                                                f"{show_value(value)}")
        return tuple((np.asarray(value, dtype=float) * factor).tolist())

    def integers(self, name: str, default: Any = MISSING) -> tuple:
        value, _, written = self._take(name, None)
        if value is MISSING:
            if default is MISSING:
                raise SceneError(self.key(name), "is missing; give a list of whole numbers")
            return default
        if not isinstance(value, list) or not all(isinstance(v, int) and not isinstance(v, bool)
                                                  for v in value):
            raise SceneError(self.key(written), f"must be a list of whole numbers, got "
                                                f"{show_value(value)}")
        return tuple(value)

    def sub(self, name: str, required: bool = False) -> "Section":
        self.known.append(name)
        if name not in self.data:
            if required:
                raise SceneError(self.key(name), "is missing (a table)")
            child = Section({}, self.key(name))
        else:
            child = Section(self.data.pop(name), self.key(name))
        self.subs[name] = child
        return child

    def has(self, name: str, kind: str | None = None) -> bool:
        names = [name] + [f"{name}_{s}" for s in SUFFIXES.get(kind, {})] if kind else [name]
        return any(n in self.data for n in names)

    def finish(self) -> None:
        """Every key must have been read: anything left is unknown (or has a wrong unit suffix)."""
        for key in self.data:
            base, _, suffix = key.rpartition("_")
            if base in self.kinds and _looks_like_unit(suffix):
                raise SceneError(self.key(key), self._suffix_problem(base, suffix))
            raise SceneError(self.key(key), f"unknown key; allowed here: "
                                            f"{', '.join(sorted(set(self.known)))}")

    def rename(self, exc: SceneError) -> SceneError:
        """Re-key an error raised under a base name (``mechanism.firing``, or a suffixed form
        such as ``gas.phi_deg``) to the key the user actually wrote."""
        prefix = f"{self.path}." if self.path else ""
        if exc.key.startswith(prefix):
            name = exc.key[len(prefix):]
            head, dot, _ = name.partition(".")
            if dot and head in self.subs:  # a key of a sub-table (gas.wiebe.start_deg)
                return self.subs[head].rename(exc)
            base = name.rpartition("_")[0] if name.rpartition("_")[2] in ALL_SUFFIXES else name
            if base in self.written:
                exc.key = prefix + self.written[base]
        return exc

    @staticmethod
    def _unit_hint(name: str, kind: str | None) -> str:
        options = [name] + [f"{name}_{s}" for s in SUFFIXES.get(kind, {})] if kind else [name]
        return "give " + " or ".join(repr(o) for o in options) + (" (SI without a suffix)"
                                                                   if kind else "")


#: Suffixes that read as a unit: an unknown one is reported as a unit suffix, not an unknown key.
_UNIT_LIKE = {"in", "m", "cm", "km", "ft", "s", "ms", "min", "h", "rad", "rps", "hz", "pa", "kpa",
              "psi", "atm", "kg", "g", "lb", "n", "nm", "kw", "w", "k", "c", "l"}


def finite_number(v: Any) -> bool:
    """Whether ``v`` is a number (not a boolean) a float holds finitely."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    return abs(v) <= MAX_EXACT_INT if isinstance(v, int) else math.isfinite(v)


def finite_numbers(values: list) -> bool:
    """Whether every item of ``values`` is a :func:`finite_number`; a long table inline is
    checked in one pass of numpy, not number by number."""
    if not all(issubclass(k, (int, float)) and not issubclass(k, bool)
               for k in set(map(type, values))):
        return False
    try:
        return bool(np.all(np.isfinite(np.asarray(values, dtype=float))))
    except OverflowError:  # (an integer beyond a float's range)
        return False


def _looks_like_unit(suffix: str) -> bool:
    return suffix in ALL_SUFFIXES or suffix.lower() in _UNIT_LIKE
