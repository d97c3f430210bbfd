"""The developer guide's pictures and tables, made in the build from the code they describe, so
that they cannot go stale:

* ``layer-diagram``: the layers of the import contracts in ``pyproject.toml``
  (``[tool.importlinter]``, which ``lint-imports`` checks), drawn with matplotlib: the packages
  top to bottom, the layers inside a package (``containers``) in its box, what a ``forbidden``
  contract keeps out of a package under its name, and any module of ``transient`` that no layer
  holds in a box of its own.
* ``layer-table``: each module of those layers with the first paragraph of its docstring.
* ``layout-table NAME``: the blocks of a declared layout (a
  :class:`transient.core.declare.Layout`, such as ``transient.core.model.layout.STATE``) with
  their offsets or size rules, from :meth:`~transient.core.declare.Layout.table`; or a
  table of (name, what it is) pairs, each numbered by its place (the stepper's events).
* ``namedtuple-fields NAME``: the fields of a namedtuple (the compiled ``Model``) with the
  comment each has beside it in its module's source; a field without one fails the build.
* ``module-members NAME``: every function and class defined in a module, private ones too,
  with the first paragraph of its docstring (the replacements of numba internals in
  ``transient.core.jit``).

Docstrings are read from the sources with :mod:`ast` (nothing is imported for them) and parsed
as reStructuredText, so that their cross-references resolve as on the API pages.
"""
from __future__ import annotations

import ast
import importlib
import io
import re
import tokenize
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.patches import FancyBboxPatch

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "transient"
OUT = Path("_generated") / "developer"


# --- the import contracts ---------------------------------------------------------------------

def contracts() -> list[dict]:
    """The import-linter contracts of ``pyproject.toml``, as written there."""
    with open(ROOT / "pyproject.toml", "rb") as f:
        return tomllib.load(f)["tool"]["importlinter"]["contracts"]


def _rows(layers: list[str]) -> list[list[str]]:
    """Each layer as its modules: ``a | b`` are independent siblings, ``a : b`` may import each
    other (import-linter's notations)."""
    return [[m.strip() for m in re.split(r"[|:]", layer)] for layer in layers]


def package_layers() -> list[list[str]]:
    """The layers of the contract over the whole package (no ``containers``), top first."""
    for c in contracts():
        if c["type"] == "layers" and not c.get("containers"):
            return _rows(c["layers"])
    raise RuntimeError("pyproject.toml has no layers contract over transient")


def inner_layers() -> dict[str, list[list[str]]]:
    """The layers inside a package (``containers``), by package, as full module names."""
    inner = {}
    for c in contracts():
        if c["type"] == "layers" and c.get("containers"):
            for pkg in c["containers"]:
                inner[pkg] = [[f"{pkg}.{m}" for m in row] for row in _rows(c["layers"])]
    return inner


def forbidden() -> dict[str, list[str]]:
    """What each ``forbidden`` contract keeps out of its source modules, by source module."""
    out = {}
    for c in contracts():
        if c["type"] == "forbidden":
            for src in c["source_modules"]:
                out.setdefault(src, []).extend(c["forbidden_modules"])
    return out


def unlayered() -> list[str]:
    """The modules and packages directly under ``transient`` that no layer names."""
    named = {m for row in package_layers() for m in row}
    found = {f"transient.{p.stem if p.is_file() else p.name}" for p in PACKAGE.iterdir()
             if (p.suffix == ".py" and not p.stem.startswith("__"))
             or (p.is_dir() and (p / "__init__.py").exists())}
    return sorted(found - named)


def _short(module: str) -> str:
    return module.removeprefix("transient.")


def layer_figure():
    """The layer diagram: one row per layer, a box per independent module, the packages with
    inner layers drawn as a larger box holding them."""
    rows = package_layers()
    inner = inner_layers()
    banned = forbidden()
    extra = unlayered()
    width, row_h, gap = 6.0, 0.34, 0.1
    heights = [row_h if not any(m in inner for m in row)
               else 0.7 + row_h * len(inner[next(m for m in row if m in inner)]) for row in rows]
    total = sum(heights) + gap * (len(rows) - 1) + (row_h + 3 * gap if extra else 0.0)
    fig, ax = plt.subplots(figsize=(width + 0.9, total + 0.4))
    ax.set_xlim(-0.9, width)
    ax.set_ylim(-0.2 - (row_h + 3 * gap if extra else 0.0), sum(heights) + gap * (len(rows) - 1)
                + 0.2)
    ax.axis("off")
    y = sum(heights) + gap * (len(rows) - 1)
    for number, (row, h) in enumerate(zip(rows, heights), 1):
        y -= h
        ax.text(-0.1, y + h - row_h / 2, str(number), ha="right", va="center", fontsize=8,
                color="0.45")
        _draw_row(ax, row, 0.0, y, width, h, inner, banned)
        y -= gap
    top = sum(heights) + gap * (len(rows) - 1)
    ax.annotate("", xy=(-0.5, 0.0), xytext=(-0.5, top),
                arrowprops={"arrowstyle": "-|>", "color": "0.45", "lw": 1.2})
    ax.text(-0.7, top / 2, "imports point down only", rotation=90, ha="center", va="center",
            color="0.3", fontsize=9)
    if extra:
        y = -row_h - 2 * gap
        _box(ax, 0.0, y, width, row_h, "in no layer: " + ", ".join(map(_short, extra)),
             face="#fde2e2", edge="#b03030")
    return fig


def _draw_row(ax, row, x0, y0, w, h, inner, banned):
    n = len(row)
    pad = 0.05
    each = (w - pad * (n - 1)) / n
    size = min(_fitting(_short(m), each) for m in row)  # (one size along a row)
    for i, module in enumerate(row):
        x = x0 + i * (each + pad)
        if module in inner:
            _box(ax, x, y0, each, h, "", face="#e8eef7", edge="#34598a")
            note = _banned_note(banned.get(module, []))
            ax.text(x + 0.1, y0 + h - 0.17, _short(module), fontsize=10, weight="bold",
                    va="center", color="#1d3557")
            if note:
                ax.text(x + 0.1, y0 + h - 0.4, note, fontsize=7.5, va="center", color="0.25",
                        style="italic")
            sub = inner[module]
            sub_gap = 0.05
            sub_h = (h - 0.62) / len(sub) - sub_gap
            yy = y0 + h - 0.55
            for srow in sub:
                yy -= sub_h
                _draw_row(ax, srow, x + 0.2, yy, each - 0.4, sub_h, {}, {})
                yy -= sub_gap
        else:
            _box(ax, x, y0, each, h, _short(module), face="#f3f6fa", edge="#5b7aa6", size=size)


def _banned_note(modules: list[str]) -> str:
    """A forbidden contract's list in a few words: the package's own layers above it as one
    phrase, the other libraries by name."""
    own = [m for m in modules if m.startswith("transient.")]
    other = [m for m in modules if not m.startswith("transient.")]
    parts = (["nothing else of transient"] if own else []) + (
        [", ".join(other)] if other else [])
    return "imports " + "; no ".join(parts) if parts else ""


def _fitting(text: str, w: float) -> float:
    """The font size [pt] at which ``text`` in monospace fits a box ``w`` inches wide (9 at
    most)."""
    return min(9.0, 9.0 * (w - 0.08) / (len(text) * 0.09))


def _box(ax, x, y, w, h, text, face, edge, size=None):
    ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0,rounding_size=0.06",
                                facecolor=face, edgecolor=edge, lw=1.0))
    if text:
        size = size or _fitting(text, w)
        ax.text(x + w / 2, y + h / 2, text, ha="center", va="center", fontsize=size,
                family="monospace")


# --- docstrings --------------------------------------------------------------------------------

def _source(module: str) -> Path:
    path = ROOT.joinpath(*module.split("."))
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


def first_paragraph(module: str) -> str:
    """The first paragraph of ``module``'s docstring, read from its source."""
    doc = ast.get_docstring(ast.parse(_source(module).read_text()))
    if not doc:
        raise RuntimeError(f"{module} has no docstring: the developer guide shows what it holds "
                           "from it")
    return doc.split("\n\n")[0].replace("\n", " ")


def _first_paragraph_as_code(doc: str) -> str:
    """A docstring's first paragraph, its cross-references as code: most name private objects
    (which have no page), read out of their class's or module's context."""
    para = doc.split("\n\n")[0].replace("\n", " ")
    return re.sub(r":\w+:`~?([^`]*)`", r"``\1``", para)


def members(module: str) -> list[tuple[str, str, str]]:
    """(kind, name, first paragraph of its docstring) of each function and class defined at the
    top of ``module``'s source, in source order."""
    tree = ast.parse(_source(module).read_text())
    out = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            doc = ast.get_docstring(node) or ""
            out.append(("class" if isinstance(node, ast.ClassDef) else "function", node.name,
                        _first_paragraph_as_code(doc)))
    return out


def namedtuple_comments(module: str, name: str) -> list[tuple[str, str]]:
    """(field, its comment) of the namedtuple ``name`` in ``module``'s source, in order; a
    comment line of its own inside the field list is a ("", comment) row, a comment continued
    on the next line joins its field's."""
    text = _source(module).read_text()
    call = next(node.value for node in ast.parse(text).body
                if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == name for t in node.targets))
    fields = call.args[1]
    first, last = fields.lineno, fields.end_lineno
    comments = {tok.start[0]: tok.string.lstrip("#").strip()
                for tok in tokenize.generate_tokens(io.StringIO(text).readline)
                if tok.type == tokenize.COMMENT and first <= tok.start[0] <= last}
    by_line = {e.lineno: e.value for e in fields.elts}
    rows: list[list[str]] = []
    for line in range(first, last + 1):
        if line in by_line:
            rows.append([by_line[line], comments.get(line, "")])
        elif line in comments:
            raw = text.splitlines()[line - 1].strip()
            if raw.startswith("#   ") and rows and rows[-1][0]:  # (continues the field's)
                rows[-1][1] += " " + comments[line]
            elif rows and not rows[-1][0] and not raw.startswith("#   "):
                rows[-1][1] += " " + comments[line]  # (a group comment of several lines)
            else:
                rows.append(["", comments[line]])
    return [(f, c) for f, c in rows]


def _object(dotted: str):
    module, _, attr = dotted.rpartition(".")
    return getattr(importlib.import_module(module), attr)


# --- Sphinx ------------------------------------------------------------------------------------

def setup(app):
    from docutils import nodes
    from docutils.parsers.rst import Parser
    from docutils.utils import new_document
    from sphinx.util.docutils import SphinxDirective

    def rst(directive, text: str, module: str | None = None) -> list:
        """``text`` parsed as reStructuredText in the directive's document (roles resolve), as
        in ``module``'s docstring where given (its relative references)."""
        doc = new_document(directive.env.docname, directive.state.document.settings)
        context = directive.env.ref_context
        before = context.get("py:module")
        context["py:module"] = module
        try:
            Parser().parse(text, doc)
        finally:
            context["py:module"] = before
        return list(doc.children)

    def table(header: list[str], rows: list[list], widths: list[int]):
        """A table of ``rows``, each cell a string (as literal text when it names code) or a
        list of nodes."""
        tgroup = nodes.tgroup(cols=len(header))
        for w in widths:
            tgroup += nodes.colspec(colwidth=w)
        head = nodes.thead()
        head += nodes.row("", *[nodes.entry("", nodes.paragraph(text=h)) for h in header])
        tgroup += head
        body = nodes.tbody()
        for row in rows:
            cells = []
            for cell in row:
                if isinstance(cell, list):
                    cells.append(nodes.entry("", *cell))
                else:
                    cells.append(nodes.entry("", nodes.paragraph("", "", nodes.Text(cell))))
            body += nodes.row("", *cells)
        tgroup += body
        t = nodes.table(classes=["developer-table"])
        t += tgroup
        return t

    def code(text: str):
        return [nodes.paragraph("", "", nodes.literal(text, text))] if text else []

    class LayerDiagram(SphinxDirective):
        """The layers of the import contracts (``layer_figure``), the body its caption."""

        has_content = True

        def run(self):
            from PIL import Image

            out = Path(self.env.srcdir) / OUT
            out.mkdir(parents=True, exist_ok=True)
            fig = layer_figure()
            fig.savefig(out / "layers.png", dpi=200, bbox_inches="tight")
            plt.close(fig)
            with Image.open(out / "layers.png") as image:
                width = image.size[0] // 2
            self.env.note_dependency(str(ROOT / "pyproject.toml"))
            figure = nodes.figure(classes=["guide-figure"])
            figure += nodes.image(uri="/" + (OUT / "layers.png").as_posix(),
                                  alt="The layers of transient's import contracts",
                                  width=f"{min(width, 900)}px")
            if self.content:
                parsed = nodes.container()
                self.state.nested_parse(self.content, self.content_offset, parsed)
                figure += nodes.caption("", "", *parsed[0].children)
            return [figure]

    class LayerTable(SphinxDirective):
        """Every module of the layers, top first, with the first paragraph of its docstring."""

        def run(self):
            rows = []
            inner = inner_layers()
            for i, row in enumerate(package_layers(), 1):
                for j, module in enumerate(row):
                    rows.append([str(i) if j == 0 else "", rst(self, f":mod:`{module}`"),
                                 rst(self, first_paragraph(module), module)])
                    for k, srow in enumerate(inner.get(module, []), 1):
                        for sub in srow:
                            rows.append([f"{i}.{k}", rst(self, f":mod:`{sub}`"),
                                         rst(self, first_paragraph(sub), sub)])
            return [table(["layer", "module", "what it holds (its docstring)"], rows,
                          [8, 24, 68])]

    class LayoutTable(SphinxDirective):
        """``layout-table DOTTED.NAME``: a Layout's blocks."""

        required_arguments = 1

        def run(self):
            layout = _object(self.arguments[0])
            if not hasattr(layout, "table"):  # (a table of (name, doc) pairs: codes by place)
                rows = [[code(str(i)), code(name), doc] for i, (name, doc) in enumerate(layout)]
                return [table(["code", "name", "what it is"], rows, [8, 22, 70])]
            rows = [[code(name), code(where), doc] for name, where, doc in layout.table()]
            return [table(["block", "offset (or size, per scene)", "what it holds"], rows,
                          [18, 22, 60])]

    class NamedtupleFields(SphinxDirective):
        """``namedtuple-fields DOTTED.NAME``: its fields with their source comments."""

        required_arguments = 1

        def run(self):
            module, _, name = self.arguments[0].rpartition(".")
            rows = namedtuple_comments(module, name)
            fields = [f for f, _ in rows if f]
            declared = list(_object(self.arguments[0])._fields)
            if fields != declared:
                raise self.error(f"{self.arguments[0]}: the source's fields {fields} are not "
                                 f"the namedtuple's {declared}")
            missing = [f for f, c in rows if f and not c]
            if missing:
                raise self.error(f"{self.arguments[0]}: fields without a comment: {missing}")
            return [table(["field", "what it holds"],
                          [[code(f), c] if f else [[], [nodes.paragraph(
                              "", "", nodes.emphasis(c, c))]] for f, c in rows], [22, 78])]

    class ModuleMembers(SphinxDirective):
        """``module-members DOTTED.NAME``: its functions and classes, private ones too."""

        required_arguments = 1

        def run(self):
            rows = [[kind, code(name), rst(self, doc) if doc else []]
                    for kind, name, doc in members(self.arguments[0])]
            return [table(["", "name", "what it does (its docstring's first paragraph)"], rows,
                          [10, 30, 60])]

    app.add_directive("layer-diagram", LayerDiagram)
    app.add_directive("layer-table", LayerTable)
    app.add_directive("layout-table", LayoutTable)
    app.add_directive("namedtuple-fields", NamedtupleFields)
    app.add_directive("module-members", ModuleMembers)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
