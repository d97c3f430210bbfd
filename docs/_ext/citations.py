"""A docstring that cites a work by its authors (``Gots §2.3``, ``Antonyuk et al., eq. (18)``)
links the first such mention to the work's entry on the references page (docs/references.bib):
the docstrings stay plain text for ``help()``, the pages link. Literals, roles and section
titles are left as they are."""
from __future__ import annotations

import re

from plain_docstrings import _QUOTED

#: How the docstrings name each work, longest first where one name contains another.
CITED = (
    (r"Patton, Nitschke & Heywood", "patton1989"),
    (r"Hairer, Nørsett & Wanner", "hairer1993"),
    (r"Hairer & Wanner", "hairer1996"),
    (r"Steele, Lea & Flood(?: 2014)?", "steele2014"),
    (r"Dormand & Prince(?: \(1980\))?", "dormand1980"),
    (r"Antonyuk et al\.?", "antonyuk2010"),
    (r"Gots\b", "gots2006"),
    (r"Semenov\b", "semenov1947"),
    (r"Heywood\b", "heywood1988"),
    (r"Woschni(?: \(?1967\)?)", "woschni1967"),
    (r"Kronrod 1965", "kronrod1965"),
    (r"Gustafsson\b", "gustafsson1991"),
    (r"Piessens et al\.?", "piessens1983"),
    (r"Shampine\b", "shampine1986"),
    (r"Annand\b", "annand1963"),
    (r"Brent\b", "brent1973"),
    (r"Vibe\b", "vibe1962"),
    (r"ISO 8528-5\b", "iso8528-5"),
)
_PATTERN = re.compile("|".join(f"(?P<k{i}>{p})" for i, (p, _) in enumerate(CITED)))
_UNDERLINE = re.compile(r"^\s*([-=~^\"'`#*+])\1+\s*$")


def _link(text: str, done: set[str]) -> str:
    def cite(m: re.Match) -> str:
        key = CITED[int(m.lastgroup[1:])][1]
        if key in done:
            return m.group(0)
        done.add(key)
        return f":cite:t:`{key}`"
    parts = _QUOTED.split(text)
    return "".join(part if i % 2 else _PATTERN.sub(cite, part) for i, part in enumerate(parts))


def link_citations(app, what, name, obj, options, lines) -> None:
    done: set[str] = set()
    for i, line in enumerate(lines):
        heading = i + 1 < len(lines) and _UNDERLINE.match(lines[i + 1]) and line.strip()
        if heading or _UNDERLINE.match(line) or line.lstrip().startswith((">>>", "...", "| ")):
            continue
        lines[i] = _link(line, done)


def setup(app):
    app.setup_extension("sphinxcontrib.bibtex")
    app.connect("autodoc-process-docstring", link_citations, priority=200)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
