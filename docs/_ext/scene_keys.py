"""The ``scene-keys`` directive: every key of a scene file, generated from the scene reader.

The key tables are not written by hand. The directive reads every scene in ``cases/`` (and, for
each of them, every value of each choice key such as ``gas.model``, so that every branch of the
reader runs) through :class:`transient.scene.reader.Section` with its methods wrapped, and
records what the reader asks for: the key, its type, the unit suffixes it takes, its default,
its allowed range or values, and under which choice of its table it is read. Each table's record
(the frozen dataclass of :mod:`transient.scene.records`, or the mechanism's class) follows with
its docstring. A field of a record that the reader never asked for is a build warning, so the
page cannot silently fall behind the reader.
"""
from __future__ import annotations

import copy
import dataclasses
import functools
import math
import re
import tomllib
import typing
from collections import defaultdict
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

ROOT = Path(__file__).resolve().parents[2]
logger = logging.getLogger(__name__)

#: The choice keys whose value selects which other keys of its table the reader reads.
SELECTORS = ("type", "model", "mode")

#: Branches that no scene in ``cases/`` takes and that a choice alone does not reach (the
#: reader tests for the presence of a key there): table → replacement table.
EXTRA_TABLES = (
    ("gas", {"model": "table", "phi_deg": [0.0, 720.0], "p_bar": [1.0, 1.0]}),
    ("gas", {"model": "table", "file": "diagram.csv"}),
    ("gas", {"model": "table", "phi_deg": [0.0, 360.0], "force": [0.0, 1.0]}),
    ("run", {"mode": "prescribed-speed", "t_end": 1.0, "time": [0.0, 1.0],
             "speed_table_rpm": [1000, 1000]}),
    ("load", {"table": {"speed_rpm": [0.0, 1000.0], "torque": [0.0, 1.0]}}),
    ("load", {"table": {"phi_deg": [0.0, 360.0], "torque": [0.0, 1.0]}}),
    ("load", {"table": {"time": [0.0, 1.0], "torque": [0.0, 1.0]}}),
    ("load", {"table": {"file": "load_map.csv"}}),
)

TYPES = {"number": "number", "numbers": "list of numbers", "integer": "whole number",
         "integers": "list of whole numbers", "flag": "true or false", "string": "string",
         "strings": "list of strings", "sub": "table"}
SI_UNIT = {"angle": "rad", "speed": "rad/s", "length": "m", "pressure": "Pa", "force": "N"}


class _Missing(Exception):
    """A required key is absent while exploring a branch: the recorder supplies a value."""


def _table(path: str) -> str:
    return re.sub(r"\[\d+\]", "[]", path)


class Recorder:
    """Wraps the reader's methods and collects, per table, what it asks for."""

    def __init__(self) -> None:
        from transient.scene import reader

        self.reader = reader
        # table -> key -> {"type", "kind", "defaults", "required", "bounds", "choices", "when"}
        self.keys: dict[str, dict[str, dict]] = defaultdict(dict)
        self.fill = False  # supply values for absent required keys (exploring branches)
        self.selectors: dict[str, dict[str, tuple]] = defaultdict(dict)

    def note(self, section, name, method, kind=None, default=None, required=False, bounds=(),
             choices=None):
        table = _table(section.path)
        entry = self.keys[table].setdefault(name, {
            "type": method, "kind": kind, "defaults": set(), "required": set(),
            "bounds": defaultdict(set), "choices": choices, "when": set()})
        variant = getattr(section, "_variant", None)
        if required:
            entry["required"].add(variant)
        elif method not in ("sub", "other"):
            entry["defaults"].add(_show_default(default))
        if method in ("number", "numbers", "integer"):
            entry["bounds"][variant].add(bounds)
        entry["when"].add(variant)
        if method == "string" and name in SELECTORS and choices:
            self.selectors[table][name] = choices

    def wrap(self):
        """Patch :class:`Section`; returns the function that restores it."""
        S = self.reader.Section
        MISSING = self.reader.MISSING
        saved = {name: getattr(S, name) for name in
                 ("number", "numbers", "integer", "integers", "flag", "string", "strings", "sub",
                  "finish")}
        rec = self

        def typed(method):
            original = saved[method]

            @functools.wraps(original)
            def call(self, name, *args, **kw):
                kind = None
                if method in ("number", "numbers"):
                    kind = kw.get("kind", args[0] if args else None)
                    default = kw.get("default", args[1] if len(args) > 1 else MISSING)
                elif method in ("integer", "integers", "flag", "string", "strings"):
                    default = kw.get("default", args[0] if args else MISSING)
                bounds = tuple((w, kw[k]) for k, w in (("gt", ">"), ("ge", "≥"), ("lt", "<"),
                                                       ("le", "≤")) if kw.get(k) is not None)
                choices = kw.get("choices")
                absent = not self.has(name, kind)
                rec.note(self, name, method, kind, default, default is MISSING, bounds, choices)
                if rec.fill and absent and default is MISSING:
                    self.known.append(name)
                    return _placeholder(method, bounds, choices)
                value = original(self, name, *args, **kw)
                if method == "string" and name in SELECTORS:
                    self._variant = f"{name} = {value}"
                return value
            return call

        def sub(self, name, required=False):
            rec.note(self, name, "sub")
            child = saved["sub"](self, name, required) if not (rec.fill and name not in self.data) \
                else saved["sub"](self, name, False)
            return child

        def finish(self):
            for name in self.known:
                if name not in rec.keys[_table(self.path)]:
                    rec.note(self, name, "other")
            return saved["finish"](self)

        for method in ("number", "numbers", "integer", "integers", "flag", "string", "strings"):
            setattr(S, method, typed(method))
        S.sub = sub
        S.finish = finish

        def restore():
            for name, fn in saved.items():
                setattr(S, name, fn)
        return restore

    def read(self, data: dict) -> None:
        from transient.errors import SceneError
        from transient.scene import read

        try:
            read.scene_from_dict(data, file="scene.toml", base_dir=ROOT / "cases")
        except (SceneError, ValueError, TypeError, ZeroDivisionError, IndexError):
            pass  # what was read before the error is recorded; that is all this needs


def _placeholder(method, bounds, choices):
    if choices:
        return choices[0]
    low = max([b for w, b in bounds if w in (">", "≥")], default=0.0)
    value = low + 1.0
    for w, b in bounds:
        if w in ("<", "≤") and value >= b:
            value = (low + b) / 2.0
    return {"number": value, "numbers": (0.0, value), "integer": max(1, int(value)),
            "integers": (1,), "flag": False, "string": "x", "strings": ()}[method]


def _show_default(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "∞" if math.isinf(value) else f"{value:.6g}"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, tuple):
        return "[" + ", ".join(_show_default(v) for v in value) + "]"
    return str(value)


def record_keys() -> Recorder:
    """Read every scene of ``cases/`` and each of its choice variants through the recorder."""
    from transient.scene import read

    rec = Recorder()
    restore = rec.wrap()
    checks = {name: getattr(read, name) for name in
              ("check_consistency", "check_gas_table", "check_analysis")}
    try:
        for name in checks:  # (the checks across tables build gas tables: not needed here)
            setattr(read, name, lambda *a, **k: None)
        scenes = [tomllib.loads(p.read_text(encoding="utf-8"))
                  for p in sorted((ROOT / "cases").glob("*.toml"))]
        for data in scenes:
            rec.read(data)
        rec.fill = True
        for data in scenes:
            for table, selectors in list(rec.selectors.items()):
                for key, choices in selectors.items():
                    for choice in choices:
                        rec.read(_with(data, table, key, choice))
            for table, replacement in EXTRA_TABLES:
                variant = copy.deepcopy(data)
                variant[table] = replacement
                rec.read(variant)
    finally:
        for name, fn in checks.items():
            setattr(read, name, fn)
        restore()
    return rec


def _with(data: dict, table: str, key: str, value) -> dict:
    variant = copy.deepcopy(data)
    node = variant
    for part in [p for p in table.split(".") if p]:
        part = part.replace("[]", "")
        node = node.setdefault(part, {})
        if isinstance(node, list):
            if not node:
                return variant
            node = node[0]
    node[key] = value
    return variant


def records() -> dict[str, list[type]]:
    """Table → the record classes that hold it, found from the type hints of
    :class:`transient.scene.Scene` down."""
    from transient.mechanisms import MECHANISMS
    from transient.scene import Scene

    found: dict[str, list[type]] = {"scene": [Scene], "mechanism": list(MECHANISMS.values())}

    def walk(cls, prefix):
        for f in dataclasses.fields(cls):
            hint = typing.get_type_hints(cls)[f.name]
            for arg in (hint, *typing.get_args(hint)):
                if dataclasses.is_dataclass(arg) and arg is not cls:
                    table = f"{prefix}{f.name}" + ("[]" if typing.get_origin(hint) is tuple
                                                   else "")
                    found[table] = [arg]
                    walk(arg, table + ".")
    walk(Scene, "")
    found.pop("mechanism.rod", None)
    return found


def _variants(variants: set) -> str:
    """``{"type = a", "type = b"}`` → ``type = a, b``."""
    by_key = defaultdict(list)
    for v in sorted(variants):
        key, _, value = v.partition(" = ")
        by_key[key].append(value)
    return "; ".join(f"{key} = {', '.join(values)}" for key, values in by_key.items())


def _when(entry: dict, all_variants: set) -> str:
    variants = {v for v in entry["when"] if v}
    if not variants or variants == all_variants:
        return ""
    return _variants(variants)


def _bounds(seen: set, unit: str) -> str:
    """The bounds one variant of a table reads a key with; a bound whose value differs between
    scenes is another key's value (``cutout_speed`` ≤ ``noload_speed``)."""
    sets = [set(b) for b in seen]
    common = set.intersection(*sets)
    order = {w: i for i, w in enumerate((">", "≥", "<", "≤"))}
    text = [f"{w} {b:g}" + (f" {unit}" if unit else "")
            for w, b in sorted(common, key=lambda wb: order[wb[0]])]
    text += [f"{w} another key" for w in sorted({w for s in sets for w, _ in s - common},
                                                 key=order.get)]
    return ", ".join(text)


def _allowed(entry: dict) -> str:
    if entry["choices"]:
        return ", ".join(f"``{c!r}``".replace("'", '"') for c in entry["choices"])
    unit = SI_UNIT.get(entry["kind"], "")
    by_text = defaultdict(set)
    for variant, seen in entry["bounds"].items():
        by_text[_bounds(seen, unit)].add(variant)
    if len(by_text) == 1:
        return next(iter(by_text))
    return "; ".join(f"{text} ({_variants(v) if None not in v else 'otherwise'})"
                     for text, v in by_text.items() if text)


def _default(entry: dict) -> str:
    if entry["type"] in ("sub", "other"):
        return "required" if entry["required"] else ""
    required = entry["required"]
    if required and (None in required or not entry["defaults"]):
        return "required"
    if len(entry["defaults"]) > 1:
        text = "from other keys"
    else:
        value = next(iter(entry["defaults"]), "")
        unit = SI_UNIT.get(entry["kind"], "")
        text = f"``{value}``" + (f" {unit}" if unit and value not in ("none", "∞", "[]") else "")
    if required:
        text += f"; required when {_variants(required)}"
    return text


def _key_forms(name: str, entry: dict) -> str:
    from transient.units import SUFFIXES

    forms = [name] + [f"{name}_{s}" for s in SUFFIXES.get(entry["kind"], {})]
    return " or ".join(f"``{f}``" for f in forms)


def _type(entry: dict, name: str, classes: list[type]) -> str:
    text = TYPES.get(entry["type"])
    if text is None:
        for cls in classes:
            hint = typing.get_type_hints(cls).get(name) if dataclasses.is_dataclass(cls) else None
            if hint is not None:
                text = "array of tables" if name in ("pairs", "cylinders") else _hint(hint)
        text = text or "value"
    if entry["kind"]:
        text += f" [{SI_UNIT[entry['kind']]}]"
    return text


def _hint(hint) -> str:
    if typing.get_origin(hint) is tuple:
        args = typing.get_args(hint)
        return f"list of {len(args)} {'strings' if args[0] is str else 'values'}"
    return getattr(hint, "__name__", str(hint))


def render(rec: Recorder) -> list[str]:
    """The reST of the whole reference: one section per table, in reading order."""
    classes = records()
    lines = []
    for table, keys in rec.keys.items():
        if not table:
            continue
        title = f"``[{table.replace('[]', '')}]``" if not table.endswith("[]") \
            else f"``[[{table[:-2]}]]``"
        lines += [title, "-" * len(title), ""]
        variants = set().union(*(e["when"] for e in keys.values())) - {None}
        lines += [".. list-table::", "   :header-rows: 1", "   :widths: 28 16 14 24 18", "",
                  "   * - key", "     - type", "     - default", "     - allowed",
                  "     - read when"]
        for name, entry in keys.items():
            kind = entry["type"]
            key = f"``[{table}.{name}]``" if kind == "sub" else _key_forms(name, entry)
            cells = [key, _type(entry, name, classes.get(table, [])), _default(entry),
                     _allowed(entry), _when(entry, variants)]
            lines.append(f"   * - {cells[0]}")
            lines += [f"     - {c}" for c in cells[1:]]
        lines.append("")
        for cls in classes.get(table, []):
            lines += [f".. autoclass:: {cls.__module__}.{cls.__qualname__}", "   :no-index:",
                      "   :no-members:", ""]
        _check_fields(table, keys, classes.get(table, []))
    return lines


def _check_fields(table: str, keys: dict, classes: list[type]) -> None:
    """Every field of a scene record must be a key the reader reads, its own name or the key
    its metadata names (mechanisms name theirs after the geometry, not the key, so they are left
    out)."""
    if table in ("mechanism", "scene"):
        return
    for cls in classes:
        for f in dataclasses.fields(cls):
            if f.metadata.get("key", f.name) not in keys:
                logger.warning(f"scene-keys: {cls.__name__}.{f.name} is no key the reader of "
                               f"[{table}] reads in any scene or branch")


class SceneKeys(SphinxDirective):
    """``.. scene-keys::``: the generated reference of every scene key."""

    def run(self):
        rec = record_keys()
        container = nodes.section()
        container.document = self.state.document
        self.state.nested_parse(StringList(render(rec), source="scene-keys"), self.content_offset,
                                container, match_titles=True)
        return container.children


def setup(app):
    app.add_directive("scene-keys", SceneKeys)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
