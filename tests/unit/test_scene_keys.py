"""The scene-key reference (:mod:`transient.scene.keyref`, rendered on docs/guide/scene_keys) is
what the reader does: every key of every case file and sweep is in it with a meaning and a unit,
and each bound it lists is the one the reader enforces — a value just outside it is refused
naming the key, the value just inside accepted — checked by reading scenes, not by reading the
reference's own description of the reader."""
from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
import typing
from pathlib import Path

import pytest

from transient.errors import SceneError
from transient.scene import Scene, scene_from_dict
from transient.scene.keyref import collect, shown_value, table_at
from transient.scene.reader import Section
from transient.units import UNITS, Named, value_of

CASES = Path(__file__).resolve().parents[2] / "cases"
SCENES = [(p.stem, tomllib.loads(p.read_text(encoding="utf-8")), p.parent)
          for p in sorted(CASES.glob("*.toml"))]
REF = collect(SCENES)


def test_the_reader_reads_every_key_one_way_per_choice():
    """A default or bound that changes from scene to scene within one choice has a name
    (another key's), and every key read has a meaning."""
    assert REF.problems == []


def keys_of(table: dict, path: str = ""):
    """(table path, key as written) of every key of parsed TOML, arrays of tables as
    ``path[]``; a sub-table or array is a key of its parent too."""
    for key, value in table.items():
        yield path, key
        if isinstance(value, dict):
            yield from keys_of(value, f"{path}.{key}".lstrip("."))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                yield from keys_of(item, f"{path}.{key}[]".lstrip("."))


def rows_for(path: str, written: str, family: str | None):
    """The reference's rows of a key as written (``crank_radius_mm`` is ``crank_radius``
    with the suffix ``mm``, which its quantity must take)."""
    rows = REF.find(path, written, family)
    if rows:
        return rows
    base, _, suffix = written.rpartition("_")
    return [r for r in REF.find(path, base, family) if suffix in r.suffixes]


def sweep_keys():
    """(sweep, key) of each scene key a sweep of cases/sweeps sets or varies, with the
    mechanism type of its base scene."""
    for p in sorted((CASES / "sweeps").glob("*.toml")):
        sweep = tomllib.loads(p.read_text(encoding="utf-8"))
        base = tomllib.loads((p.parent / sweep["sweep"]["base"]).read_text(encoding="utf-8"))
        family = base["mechanism"]["type"]
        for key in [*sweep.get("set", {}), *(a["key"] for a in sweep.get("axis", []))]:
            yield p.stem, key, family


CASE_KEYS = sorted({(name, path, key, data["mechanism"]["type"])
                    for name, data, _ in SCENES for path, key in keys_of(data)})


@pytest.mark.parametrize("case, path, key, family", CASE_KEYS,
                         ids=[f"{c}:{p}.{k}".replace("[]", "") for c, p, k, _ in CASE_KEYS])
def test_every_key_of_every_case_has_a_meaning_and_a_unit(case, path, key, family):
    rows = rows_for(path, key, family)
    assert rows, f"{case}: [{path}] {key} is not on the key page"
    for row in rows:
        table = REF.tables[(path, family if path.split(".")[0] == "mechanism" else None)]
        assert len(table.meaning(row.name)) > 10
        if row.numeric:  # (a number has a unit; "1": dimensionless or a count)
            assert row.unit and all(k in UNITS for k in row.kinds if k)


@pytest.mark.parametrize("sweep, key, family", list(sweep_keys()),
                         ids=[f"{s}:{k}" for s, k, _ in sweep_keys()])
def test_every_key_a_sweep_sets_is_on_the_key_page(sweep, key, family):
    path, _, name = key.rpartition(".")
    rows = rows_for(path, name, family)
    assert rows and all(r.unit for r in rows if r.numeric), f"{sweep}: {key}"


def test_every_field_of_a_scene_record_is_a_key_the_reader_reads():
    """The records' fields (a field read from another key names it in its metadata) against
    the reference: no field the reader would silently never fill."""
    def walk(cls, path):
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            if f.name in ("mechanism", "source_file", "source_text"):
                continue
            nested = [a for a in (hints[f.name], *typing.get_args(hints[f.name]))
                      if dataclasses.is_dataclass(a)]
            table = "scene" if cls is Scene and not nested else path  # (name, description)
            yield table, f.metadata.get("key", f.name)
            for sub in nested:
                yield from walk(sub, f"{path}.{f.name}".lstrip(".")
                                + ("[]" if typing.get_origin(hints[f.name]) is tuple else ""))
    missing = [f"[{path}] {name}" for path, name in walk(Scene, "")
               if not REF.find(path, name)]
    assert missing == []


# ------------------------------------------------------------------------------------------------
# Each listed bound is the reader's


def bounds():
    for (path, family), table in REF.tables.items():
        for row in table.rows:
            if row.key.type not in ("number", "numbers", "integer") or row.example is None:
                continue
            for word, value in row.example.bounds:
                if math.isfinite(value):
                    name = f"[{path}{'/' + family if family else ''}] {row.name} {word} {value:g}"
                    yield pytest.param(row, word, value, id=name)


def with_value(row, value) -> tuple[dict, str]:
    """The row's example scene with its key set to ``value`` (SI, written without a suffix;
    a list key: its first entry), and the key's full name."""
    ex = row.example
    data = copy.deepcopy(ex.data)
    table = table_at(data, ex.path)
    current = case_value(row)
    for spelling in [row.name] + [f"{row.name}_{s}" for s in row.suffixes]:
        table.pop(spelling, None)
    if row.key.type == "numbers":
        value = [value] + list(current or [value])[1:]
    table[row.name] = value
    return data, f"{ex.path}.{row.name}".lstrip(".")


def case_value(row):
    """The key's value in its example scene, in SI (a list for a list key), or its default
    there; None if it has neither."""
    table = table_at(copy.deepcopy(row.example.data), row.example.path)
    for spelling, factor in [(row.name, 1.0)] + [(f"{row.name}_{s}", f)
                                                 for s, f in row.suffixes.items()]:
        if spelling in table:
            v = table[spelling]
            return [x * factor for x in v] if isinstance(v, list) else v * factor
    default = value_of(row.key.default)
    return default if isinstance(default, (int, float, list, tuple)) else None


def read(data, row):
    return scene_from_dict(data, file=f"{row.example.case}.toml", base_dir=row.example.base_dir)


#: How far inside a bound, as a share of the way to the case's own value, a scene is tried
#: after the nearest value (a float, or whole number, next to the bound): values degenerate
#: enough (a swash angle of 5e-324 rad) fail checks of the whole scene that are no bound of
#: the key.
INSIDE = (1e-9, 1e-6, 1e-3)


def inside_values(row, word: str, value):
    """The value next to the bound on its inside, then values :data:`INSIDE` of the way
    from the bound to the case's own value."""
    lower = word in (">", "≥")
    if row.key.type == "integer":
        yield int(value)
        return
    yield value if word in ("≥", "≤") else math.nextafter(value, math.inf if lower else
                                                          -math.inf)
    own = case_value(row)
    own = own[0] if isinstance(own, (list, tuple)) and own else own
    if isinstance(own, (int, float)) and math.isfinite(own) and (own > value) == lower:
        for share in INSIDE:
            yield value + share * (own - value)


def outside_value(row, word: str, value):
    """The value next to the bound on its outside: the next whole number, or the bound itself
    or the float next to it (the bound is exact)."""
    lower = word in (">", "≥")
    if row.key.type == "integer":
        return int(value) + (-1 if lower else 1)
    if word in (">", "<"):
        return value
    return math.nextafter(value, -math.inf if lower else math.inf)


@pytest.mark.parametrize("row, word, value", list(bounds()))
def test_each_listed_bound_is_the_one_the_reader_enforces(row, word, value):
    """Just outside: refused, naming the key, by its bound. Just inside: read, or refused
    naming another key (a constraint of that key, which this value enters: a firing order
    that no longer fits the crank) or by another listed bound of this one; any other refusal
    naming this key is allowed only nearest the bound (a check of the whole scene on a
    degenerate value), until a value a share :data:`INSIDE` of the way in is read."""
    data, key = with_value(row, outside_value(row, word, value))
    with pytest.raises(SceneError) as refused:
        read(data, row)
    assert refused.value.key == key and refused.value.message.startswith("must be")
    errors = []
    for inside in inside_values(row, word, value):
        data, key = with_value(row, inside)
        try:
            read(data, row)
            return
        except SceneError as exc:
            assert not (exc.key == key and exc.message.startswith(f"must be {word} ")), \
                exc.message
            if exc.key != key or exc.message.startswith("must be"):
                return  # (another key's constraint, or another listed bound of this one)
            errors.append(f"{inside!r}: {exc}")
    pytest.fail(f"refused however near inside the bound {word} {value}: " + "; ".join(errors))


# ------------------------------------------------------------------------------------------------
# Defaults and bounds as a scene writes them


@pytest.mark.parametrize("value, kind, shown", [
    (math.pi, "angle", "180°"),
    (math.radians(0.125), "angle", "0.125°"),
    (-math.pi / 6.0, "angle", "−30°"),
    (math.pi / 3.0, "speed", "10 rpm"),
    (1.0e5, "pressure", "1 bar"),
    (0.047, "length", "47 mm"),
    (0.0, "angle", "0"),
    (1e-10, "1", "10⁻¹⁰"),
    (42.5e6, "specific energy", "4.25 × 10⁷ J/kg"),
    (450.0, "temperature", "450 K"),
    (math.inf, "time", "not set"),
    (None, "angle", "not set"),
    (Named(2 ** 63 - 1, "2⁶³ − 1"), None, "2⁶³ − 1"),
    ((), "angle", "none"),
    ("pchip", None, '"pchip"'),
    (True, None, "true"),
])
def test_defaults_are_shown_in_the_unit_a_scene_writes(value, kind, shown):
    assert shown_value(value, kind) == shown


def test_a_number_without_a_known_unit_is_refused_where_it_is_read():
    """Every number the reader takes names its quantity kind, so that its unit is known where
    it is read (:data:`transient.units.UNITS`): a call without one is a programming error,
    raised before the key is read."""
    with pytest.raises(ValueError, match="unknown quantity kind 'furlongs'"):
        Section({"x": 1.0}, "t").number("x", "furlongs")
    with pytest.raises(ValueError, match="unknown quantity kind None"):
        Section({"x": [1.0]}, "t").numbers("x", None)
    with pytest.raises(TypeError):
        Section({"x": 1.0}, "t").number("x")  # (no kind)
