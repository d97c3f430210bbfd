"""The ``scene-keys`` directive: every key of a scene file, as the scene reader reads it.

The reader tells what it asks of each key — type, unit, default, bounds, choices — and
:func:`transient.scene.keyref.collect` gathers that from every scene of ``cases/`` and each of
their variants; nothing here restates the reader. This renders it: a section per table (the
``[mechanism]`` tables one per mechanism type, as each mechanism reads its own), a row per key
with its meaning, its SI unit and unit suffixes, its default in the unit a scene usually writes
(``180°``, ``1 bar``), and what the reader allows, a bound that is another key's value by that
key's name; keys that only one choice of their table reads (``model = "wiebe"``) are grouped
under it. Each key has an anchor, and the role ``:key:`gas.wiebe.start``` (MyST
``{key}`gas.wiebe.start```) links to it; a reference to a key the reader does not read fails
the nitpicky build.
"""
from __future__ import annotations

import dataclasses
import re
import tomllib
import typing
from pathlib import Path

from docutils import nodes
from sphinx import addnodes
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

ROOT = Path(__file__).resolve().parents[2]
logger = logging.getLogger(__name__)

#: The std-domain object type of a scene key (``:key:`` role).
OBJTYPE = "scenekey"


def reference():
    """The key reference of every scene in ``cases/`` (:func:`transient.scene.keyref.collect`)."""
    from transient.scene.keyref import collect

    return collect((p.stem, tomllib.loads(p.read_text(encoding="utf-8")), p.parent)
                   for p in sorted((ROOT / "cases").glob("*.toml")))


def records() -> dict[str, type]:
    """Table path → the record class that holds it, from the type hints of
    :class:`transient.scene.Scene` down."""
    from transient.scene import Scene

    found: dict[str, type] = {}

    def walk(cls, prefix):
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            for arg in (hints[f.name], *typing.get_args(hints[f.name])):
                if dataclasses.is_dataclass(arg) and arg is not cls:
                    table = prefix + f.name + ("[]" if typing.get_origin(hints[f.name]) is tuple
                                               else "")
                    found[table] = arg
                    walk(arg, table + ".")
    walk(Scene, "")
    return found


def key_name(table, name: str) -> str:
    """The name a key is linked by: ``gas.wiebe.start``, ``gas.cylinders.fuel``,
    ``mechanism.crank-slider.rod.mass``."""
    path = table.path.replace("[]", "")
    if table.family:
        path = path.replace("mechanism", f"mechanism.{table.family}", 1)
    return f"{path}.{name}" if path else name


def anchor(name: str) -> str:
    return "key-" + re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")


def title(table) -> str:
    path = table.path
    return f"[[{path[:-2]}]]" if path.endswith("[]") else f"[{path}]"


class SceneKeys(SphinxDirective):
    """``.. scene-keys::``: the generated reference of every scene key."""

    def run(self):
        from transient.mechanisms import MECHANISMS

        ref = reference()
        for problem in ref.problems:
            logger.warning(f"scene-keys: {problem}", location=self.get_location())
        self.tables = ref.tables
        self.records = records()
        self.ids: set[str] = set()
        root = ref.tables[("", None)]
        out = [self.overview(root)]
        for row in root.rows:
            if row.name == "mechanism":
                section = self.section("[mechanism]", anchor("table mechanism"))
                section += self.paragraph(root.meaning("mechanism"))
                for family in MECHANISMS:
                    table = ref.tables.get(("mechanism", family))
                    if table is not None:
                        section += self.table_section(table, f'type = "{family}"')
                out.append(section)
            else:
                out.append(self.table_section(ref.tables[(row.name, None)]))
        return out

    # -- sections ----------------------------------------------------------------------------
    def section(self, text: str, node_id: str, literal: bool = True) -> nodes.section:
        section = nodes.section(ids=[node_id], names=[nodes.fully_normalize_name(node_id)])
        heading = nodes.title(text, "", nodes.literal(text, text)) if literal else \
            nodes.title(text, text)
        self.set_source_info(section)
        self.set_source_info(heading)
        section += heading
        self.state.document.note_explicit_target(section)
        return section

    def table_section(self, table, heading: str | None = None) -> nodes.section:
        """A table's section: its record, its keys (those of a choice grouped under it) and
        its sub-tables' sections."""
        family = f"-{table.family}" if table.family else ""
        section = self.section(heading or title(table), anchor(f"table {table.path}{family}"))
        record = self.record(table)
        if record is not None:
            section += record
        for caption, rows in self.groups(table):
            section += self.key_table(table, rows, caption)
        for row in table.rows:
            if row.key.type in ("table", "tables"):
                sub = self.tables.get((f"{table.path}.{row.name}" + ("[]" if row.key.type ==
                                                                      "tables" else ""),
                                       table.family))
                if sub is not None:
                    section += self.table_section(sub)
        return section

    def record(self, table):
        """"Read into :class:`Record`": where the table's keys go, whose docstring gives the
        equations behind them (None for a table no record class of its own holds)."""
        from transient.mechanisms import MECHANISMS

        if table.family is not None:
            cls = MECHANISMS[table.family] if table.path == "mechanism" else None
        else:
            cls = self.records.get(table.path)
        if cls is None:
            return None
        target = f"{cls.__module__}.{cls.__qualname__}"
        xref = addnodes.pending_xref("", refdomain="py", reftype="class", reftarget=target,
                                     refexplicit=False, refwarn=True)
        xref += nodes.literal(cls.__name__, cls.__name__, classes=["xref", "py", "py-class"])
        para = nodes.paragraph()
        para += nodes.Text("Read into ")
        para += xref
        para += nodes.Text(", whose docstring gives the equations behind the keys.")
        return para

    def overview(self, root) -> nodes.section:
        section = self.section("The tables", anchor("tables"), literal=False)
        body = []
        for row in root.rows:
            ref = nodes.reference("", "", internal=True, refid=anchor(f"table {row.name}"))
            ref += nodes.literal(f"[{row.name}]", f"[{row.name}]")
            body.append([[ref], self.inline(root.meaning(row.name)),
                         [nodes.Text("required" if row.required else "optional")]])
        section += self.grid(["table", "what it holds", "in a scene"], [20, 65, 15], body)
        return section

    # -- key tables --------------------------------------------------------------------------
    def groups(self, table):
        """(caption, rows): the keys always read, then those of each choice (or set of
        choices) of the table, in reading order."""
        every = table.variants
        out: dict[frozenset, list] = {}
        for row in table.rows:
            variants = frozenset(row.variants - {""})
            if "" in row.variants or variants == every:
                variants = frozenset()
            out.setdefault(variants, []).append(row)
        groups = sorted(out.items(), key=lambda kv: bool(kv[0]))  # (always first; stable)
        choices = {r.name: r.key.choices for r in table.rows if r.key.choices}
        return [(_when(v, choices), rows) for v, rows in groups]

    def key_table(self, table, rows, caption: str | None) -> nodes.table:
        body = [self.key_row(table, row) for row in rows]
        grid = self.grid(["key", "meaning", "unit", "default", "allowed"],
                         [17, 35, 15, 15, 18], body)
        if caption:
            heading = nodes.title(caption, "read when ", nodes.literal(caption, caption))
            self.set_source_info(heading)
            grid.insert(0, heading)
        return grid

    def key_row(self, table, row) -> list:
        from transient.scene.keyref import shown_value
        from transient.units import SHOWN, Named

        name = key_name(table, row.name)
        node_id = anchor(name)
        cell = []
        if node_id not in self.ids:  # (a key read two ways: the first row holds its anchor)
            self.ids.add(node_id)
            cell.append(nodes.target("", "", ids=[node_id]))
            std = self.env.get_domain("std")
            std.note_object(OBJTYPE, name, node_id, location=self.get_location())
        literal = nodes.literal(row.name, row.name)
        if row.key.type in ("table", "tables"):
            sub = f"{table.path}.{row.name}" + ("[]" if row.key.type == "tables" else "")
            family = f"-{table.family}" if table.family else ""
            ref = nodes.reference("", "", internal=True, refid=anchor(f"table {sub}{family}"))
            ref += literal
            cell.append(ref)
        else:
            cell.append(literal)
        unit = [nodes.Text(row.unit or "—")]
        for i, suffix in enumerate(row.suffixes):  # (the suffixes, each with its unit)
            kind = row.key.kind
            symbol = SHOWN[kind][1] if kind in SHOWN and SHOWN[kind][0] == suffix else suffix
            unit += [nodes.Text(", " if i else " (or "),
                     nodes.literal(f"_{suffix}", f"_{suffix}"), nodes.Text(f": {symbol}")]
        if row.suffixes:
            unit.append(nodes.Text(")"))
        given = row.key.default
        if isinstance(given, Named) and not _is_prose(given):
            default = [nodes.Text("= ")] + self.bound(table, given, row.key.kind)
        elif isinstance(given, Named) or given is None:
            default = [nodes.Text(shown_value(given, row.key.kind))]
        elif row.required:
            default = [nodes.emphasis("required", "required")]
        else:
            text = shown_value(given, row.key.kind)
            default = [nodes.literal(text, text)]
        return [cell, self.inline(table.meaning(row.name)), unit, default,
                self.allowed(table, row)]

    def allowed(self, table, row) -> list:
        """What the reader allows, in words: the bounds (another key's by its name, linked),
        the choices, or the kind of value."""
        from transient.scene.keyref import shown_value
        from transient.units import Named

        key = row.key
        if key.choices:
            out = []
            for i, c in enumerate(key.choices):
                out += ([nodes.Text(", ")] if i else []) + [
                    nodes.literal(shown_value(c, None), shown_value(c, None))]
            return out
        kind = key.kind if key.type in ("number", "numbers") else None
        parts = []  # (the plain bounds first, then those another key's value sets)
        for word, bound in sorted(key.bounds, key=lambda wb: isinstance(wb[1], Named)):
            parts.append([nodes.Text(f"{word} ")] + self.bound(table, bound, kind))
        text = {"number": "a number", "numbers": "a list of numbers", "integer": "a whole number",
                "integers": "a list of whole numbers", "flag": "true or false",
                "string": "text", "strings": "a list of texts", "table": "a table",
                "tables": "an array of tables"}.get(key.type, key.type)
        out = [nodes.Text(text)]
        if parts and key.type in ("number", "integer"):
            out = [nodes.Text("0 or ")] if key.or_zero else []
        elif parts:
            out.append(nodes.Text(", each "))
        for i, part in enumerate(parts):
            out += ([nodes.Text(", ")] if i else []) + part
        return out

    def bound(self, table, bound, kind) -> list:
        from transient.scene.keyref import shown_value
        from transient.units import Named

        if isinstance(bound, Named):
            other = self.key_of(table, bound.name)
            if other is not None:  # (another key, of this table or one it is in: link it)
                ref = nodes.reference("", "", internal=True, refid=anchor(other))
                ref += nodes.literal(bound.name, bound.name)
                return [ref]
            return [nodes.Text(bound.name)]
        return [nodes.Text(shown_value(bound, kind))]

    def key_of(self, table, name: str) -> str | None:
        """The linked name of key ``name`` (``rod_length``, ``mechanism.cylinders``) as seen
        from ``table``: a key of it or of a table it is in, else None."""
        from transient.mechanisms import MECHANISMS

        path = table.path
        while True:
            head, _, key = f"{path}.{name}".lstrip(".").rpartition(".")
            families = [None]
            if head.split(".")[0] == "mechanism":  # (its own type's, else the first that has it)
                families = [table.family] if table.family else list(MECHANISMS)
            for family in families:
                there = self.tables.get((head, family))
                if there is not None and any(r.name == key for r in there.rows):
                    return key_name(there, key)
            if not path:
                return None
            path = path.rpartition(".")[0]

    # -- nodes -------------------------------------------------------------------------------
    def inline(self, text: str) -> list:
        parsed, messages = self.state.inline_text(text, self.lineno)
        return parsed + messages

    def paragraph(self, text: str) -> nodes.paragraph:
        para = nodes.paragraph()
        para += self.inline(text)
        return para

    @staticmethod
    def grid(header: list[str], widths: list[int], body: list[list[list]]) -> nodes.table:
        table = nodes.table(classes=["scene-keys", "colwidths-given"])
        group = nodes.tgroup(cols=len(header))
        table += group
        for w in widths:
            group += nodes.colspec(colwidth=w)
        head = nodes.thead()
        group += head
        head += _row([[nodes.Text(h)] for h in header])
        tbody = nodes.tbody()
        group += tbody
        for cells in body:
            tbody += _row(cells)
        return table


def _row(cells: list[list]) -> nodes.row:
    row = nodes.row()
    for content in cells:
        entry = nodes.entry()
        para = nodes.paragraph()
        para += content
        entry += para
        row += entry
    return row


def _when(variants: frozenset, choices: dict[str, tuple]) -> str | None:
    """``{'model = "a"', 'model = "b"'}`` → ``model = "a" or "b"``; all choices of the key but
    one or a few → ``model ≠ "none"``, ``model not "none" nor "compressor"``."""
    if not variants:
        return None
    by_key: dict[str, list[str]] = {}
    for v in sorted(variants):
        key, _, value = v.partition(" = ")
        by_key.setdefault(key, []).append(value)
    out = []
    for key, values in by_key.items():
        others = [f'"{c}"' for c in choices.get(key, ()) if f'"{c}"' not in values]
        if len(others) == 1 and len(values) > 1:
            out.append(f"{key} ≠ {others[0]}")
        elif others and len(others) < len(values):
            out.append(f"{key} not {' nor '.join(others)}")
        else:
            out.append(f"{key} = {' or '.join(values)}")
    return "; ".join(out)


def _is_prose(named) -> bool:
    """Whether a named default or bound is words rather than another key's name."""
    return not re.fullmatch(r"[a-z_][a-z0-9_.]*", named.name)


def setup(app):
    app.add_object_type(OBJTYPE, "key", objname="scene key",
                        indextemplate="pair: %s; scene key")
    app.add_directive("scene-keys", SceneKeys)
    app.add_css_file("scene_keys.css")
    return {"parallel_read_safe": True, "parallel_write_safe": True}
