"""The typed-key TOML reader: :class:`~transient.scene.reader.Section` takes keys off one
table, converts unit suffixes to SI and reports anything left over as an unknown key.

A quantity may be written in SI (``crank_radius = 0.047``) or with one unit suffix of its kind
(``crank_radius_mm = 47``, :data:`transient.units.SUFFIXES`). Every problem raises
:class:`transient.errors.SceneError` naming the key as the user wrote it, what is wrong and what
is allowed.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import SceneError, show_value
from ..units import ALL_SUFFIXES, SUFFIXES, UNITS, Named, value_of

#: The default of a required key: reading it when absent is an error (``None`` is a valid
#: default, so it cannot mark one).
MISSING = object()


@dataclass(frozen=True)
class Key:
    """What the reader asks of one key, as it asks it: the table's ``path`` (``gas.wiebe``,
    ``friction.pairs[0]``), the key's ``name``, its ``type`` (the :class:`Section` method's
    name, or what a value the caller checks is), the quantity ``kind`` of a number
    (:data:`transient.units.UNITS`), its ``default`` (:data:`MISSING`: required), its
    ``bounds`` (``(">", 0.0)``, ``("≤", Named(…))``; ``or_zero``: 0 is allowed besides) and its
    ``choices``. A :func:`listening` callback hears each one before the key is read."""

    path: str
    name: str
    type: str
    kind: str | None = None
    default: Any = MISSING
    bounds: tuple[tuple[str, Any], ...] = ()
    choices: tuple | None = None
    or_zero: bool = False


_LISTENER: ContextVar[Callable[[Section, Key], None] | None] = ContextVar("scene_key_listener",
                                                                           default=None)


@contextmanager
def listening(callback: Callable[[Section, Key], None]) -> Iterator[None]:
    """Within the block, ``callback(section, key)`` hears every key any :class:`Section` asks
    for, before it is read (the key reference is built from this: :mod:`.keyref`)."""
    token = _LISTENER.set(callback)
    try:
        yield
    finally:
        _LISTENER.reset(token)


_COMPARE = {">": np.greater, "≥": np.greater_equal, "<": np.less, "≤": np.less_equal}


def _bounds(gt=None, ge=None, lt=None, le=None) -> tuple[tuple[str, Any], ...]:
    return tuple((word, b) for word, b in ((">", gt), ("≥", ge), ("<", lt), ("≤", le))
                 if b is not None)


def _why(default: Any) -> str:
    """Why a key is required, if its default says (a :class:`~transient.units.Named` one)."""
    return f" ({default.name})" if isinstance(default, Named) else ""


def _shown(bound: Any, factor: float = 1.0) -> str:
    """A bound in the units the user wrote, with its name if it has one."""
    value = value_of(bound)
    text = str(value) if isinstance(value, int) and factor == 1.0 else f"{value / factor:g}"
    if not isinstance(bound, Named) or bound.name.startswith(text):  # ("0 with a …")
        return bound.name if isinstance(bound, Named) else text
    return f"{bound.name} = {text}"


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

    def _ask(self, type_: str, name: str, kind: str | None = None, default: Any = MISSING,
             bounds: tuple = (), choices: tuple | None = None, or_zero: bool = False) -> None:
        """Tell a listener what is asked of key ``name`` (:func:`listening`)."""
        if type_ in ("number", "numbers") and kind not in UNITS:
            raise ValueError(f"{self.key(name)}: unknown quantity kind {kind!r}; one of "
                             f"{', '.join(map(repr, UNITS))}")
        listener = _LISTENER.get()
        if listener is not None:
            listener(self, Key(self.path, name, type_, kind, default, bounds, choices, or_zero))

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

    def number(self, name: str, kind: str, default: Any = MISSING, *, gt: Any = None,
               ge: Any = None, lt: Any = None, le: Any = None, or_zero: bool = False) -> float:
        """A number of quantity ``kind`` (:data:`transient.units.UNITS`) in SI; the bounds
        (plain or :class:`~transient.units.Named`) are in SI, and with ``or_zero`` 0 is allowed
        besides them (it turns something off)."""
        self._ask("number", name, kind, default, _bounds(gt, ge, lt, le), or_zero=or_zero)
        value, factor, written = self._take(name, kind)
        if value is MISSING:
            if value_of(default) is MISSING:
                raise SceneError(self.key(name), f"is missing{_why(default)}; "
                                                 f"{self._unit_hint(name, kind)}")
            return value_of(default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(self.key(written), f"must be a number, got {show_value(value)}")
        if isinstance(value, int) and abs(value) > MAX_EXACT_INT:
            raise SceneError(self.key(written), f"must be finite, got {show_value(value)} (beyond "
                                                f"a float's range)")
        if not math.isfinite(value):
            raise SceneError(self.key(written), f"must be finite, got {value}")
        if not (or_zero and value == 0):
            self._check_range(written, [value], _bounds(gt, ge, lt, le), factor, or_zero)
        return float(value) * factor

    def _check_range(self, written, values, bounds, factor, or_zero=False, entries=False):
        # Bounds are given in SI; compare in the units the user wrote.
        si = np.asarray(values, dtype=float) * factor
        for word, bound in bounds:
            bad = np.flatnonzero(~_COMPARE[word](si, value_of(bound)))
            if bad.size:
                i = int(bad[0])
                zero = "0 or " if or_zero else ""
                entry = f" (entry {i + 1})" if entries else ""
                raise SceneError(self.key(written), f"must be {zero}{word} "
                                                    f"{_shown(bound, factor)}, got "
                                                    f"{values[i]:g}{entry}")

    def integer(self, name: str, default: Any = MISSING, *, ge: Any = None,
                choices: tuple[int, ...] | None = None, le: Any = None) -> int:
        """A whole number; the bounds plain or :class:`~transient.units.Named`."""
        self._ask("integer", name, None, default, _bounds(ge=ge, le=le), choices)
        value, _, written = self._take(name, None)
        if value is MISSING:
            if value_of(default) is MISSING:
                raise SceneError(self.key(name), "is missing; give a whole number")
            return value_of(default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(self.key(written), f"must be a whole number, got {show_value(value)}")
        if ge is not None and value < value_of(ge):
            raise SceneError(self.key(written), f"must be ≥ {_shown(ge)}, got {show_value(value)}")
        if le is not None and value > value_of(le):
            raise SceneError(self.key(written), f"must be ≤ {_shown(le)}, got {show_value(value)}")
        if choices is not None and value not in choices:
            raise SceneError(self.key(written),
                             f"must be one of {', '.join(map(str, choices))}, got "
                             f"{show_value(value)}")
        return value

    def flag(self, name: str, default: bool) -> bool:
        self._ask("flag", name, default=default)
        value, _, written = self._take(name, None)
        if value is MISSING:
            return default
        if not isinstance(value, bool):
            raise SceneError(self.key(written), f"must be true or false, got {show_value(value)}")
        return value

    def strings(self, name: str, default: Any = MISSING) -> tuple:
        self._ask("strings", name, default=default)
        value, _, written = self._take(name, None)
        if value is MISSING:
            if value_of(default) is MISSING:
                raise SceneError(self.key(name), "is missing; give a list of strings")
            return value_of(default)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise SceneError(self.key(written),
                             f"must be a list of strings, got {show_value(value)}")
        return tuple(value)

    def string(self, name: str, default: Any = MISSING, *,
               choices: tuple[str, ...] | None = None) -> str:
        self._ask("string", name, default=default, choices=choices)
        value, _, written = self._take(name, None)
        if value is MISSING:
            if value_of(default) is MISSING:
                allowed = f"; allowed: {', '.join(choices)}" if choices else ""
                raise SceneError(self.key(name), f"is missing{allowed}")
            return value_of(default)
        if not isinstance(value, str):
            raise SceneError(self.key(written), f"must be a string, got {show_value(value)}")
        if choices is not None and value not in choices:
            raise SceneError(self.key(written),
                             f"unknown value {show_value(value)}; allowed: "
                             f"{', '.join(map(repr, choices))}")
        return value

    def numbers(self, name: str, kind: str, default: Any = MISSING, *, gt: Any = None,
                ge: Any = None, lt: Any = None, le: Any = None) -> tuple:
        """A list of numbers of quantity ``kind`` in SI, each within the bounds (as
        :meth:`number`'s)."""
        self._ask("numbers", name, kind, default, _bounds(gt, ge, lt, le))
        value, factor, written = self._take(name, kind)
        if value is MISSING:
            if value_of(default) is MISSING:
                raise SceneError(self.key(name), f"is missing{_why(default)}; "
                                                 f"{self._unit_hint(name, kind)} list")
            return value_of(default)
        if not isinstance(value, list) or not finite_numbers(value):
            raise SceneError(self.key(written), f"must be a list of finite numbers, got "
                                                f"{show_value(value)}")
        self._check_range(written, value, _bounds(gt, ge, lt, le), factor, entries=True)
        return tuple((np.asarray(value, dtype=float) * factor).tolist())

    def integers(self, name: str, default: Any = MISSING) -> tuple:
        self._ask("integers", name, default=default)
        value, _, written = self._take(name, None)
        if value is MISSING:
            if value_of(default) is MISSING:
                raise SceneError(self.key(name), "is missing; give a list of whole numbers")
            return value_of(default)
        if not isinstance(value, list) or not all(isinstance(v, int) and not isinstance(v, bool)
                                                  for v in value):
            raise SceneError(self.key(written), f"must be a list of whole numbers, got "
                                                f"{show_value(value)}")
        return tuple(value)

    def sub(self, name: str, required: bool = False) -> Section:
        self._ask("table", name, default=MISSING if required else None)
        self.known.append(name)
        if name not in self.data:
            if required:
                raise SceneError(self.key(name), "is missing (a table)")
            child = Section({}, self.key(name))
        else:
            child = Section(self.data.pop(name), self.key(name))
        self.subs[name] = child
        return child

    def tables(self, name: str) -> list[Section]:
        """The array of tables ``[[name]]`` under this table, a :class:`Section` each ([] if
        absent)."""
        self._ask("tables", name, default=())
        self.known.append(name)
        raw = self.data.pop(name, [])
        if not isinstance(raw, list):
            raise SceneError(self.key(name), f"must be an array of tables ([[{self.key(name)}]])")
        return [Section(item, f"{self.key(name)}[{i}]") for i, item in enumerate(raw)]

    def raw(self, name: str, what: str, required: bool = False) -> Any:
        """The value of ``name`` as the file gives it (:data:`MISSING` if absent), for a
        structure the typed methods do not read; the caller checks it. ``what`` says what it is
        (``"two link names"``), as the key reference shows it."""
        self._ask(what, name, default=MISSING if required else None)
        self.known.append(name)
        return self.data.pop(name, MISSING)

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
        suffixes = SUFFIXES.get(kind, {}) if kind else {}
        if not suffixes:  # (one unit: name it, unless the number has none)
            return f"give {name!r}" + (f" [{UNITS[kind]}]" if kind and kind != "1" else "")
        options = [name] + [f"{name}_{s}" for s in suffixes]
        return "give " + " or ".join(repr(o) for o in options) + " (SI without a suffix)"


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
