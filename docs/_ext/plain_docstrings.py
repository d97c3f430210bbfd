"""Docstrings written as plain text with math: ``|x|`` is an absolute value and a lone ``*``
a wildcard, not the substitution reference and emphasis reST would read. Both are escaped
before numpydoc and autodoc parse a docstring, except inside literals and roles."""
from __future__ import annotations

import re

# Backquoted spans (``literal``, :role:`text`, `text`) are left as they are.
_QUOTED = re.compile(r"(:[\w:.+-]+:`[^`]*`|``.*?``|`[^`]*`_{0,2})")


def _escape(text: str) -> str:
    out = []
    for i, part in enumerate(_QUOTED.split(text)):
        if i % 2:
            out.append(part)
            continue
        part = part.replace("|", r"\|")
        if part.count("*") % 2 or re.search(r"\w\*(?!\*)|\*\)", part):
            part = re.sub(r"(?<!\*)\*(?!\*)", r"\\*", part)
        out.append(part)
    return "".join(out)


def escape_docstring(app, what, name, obj, options, lines) -> None:
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        if stripped.startswith(("| ", "+-", ">>>", "...")) or stripped == "|":  # line blocks, grid
            continue  # tables, doctests
        bullet = re.match(r"\s*[*-] ", line)  # a list item's own marker stays
        head = bullet.group(0) if bullet else ""
        lines[i] = head + _escape(line[len(head):])


def setup(app):
    app.connect("autodoc-process-docstring", escape_docstring, priority=100)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
