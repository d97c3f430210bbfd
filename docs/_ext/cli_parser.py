"""The ``transient`` command's own argument parser, for sphinx-argparse (docs/guide/cli.md).

Help strings are plain text; a ``|`` in them (``|R|``, an absolute value) would be read by reST
as a substitution reference and ``tcp://host:port`` as a link, so both are escaped. The examples
that end ``transient --help`` (a plain text table there) become a table of the commands under the
description, at the top of the page, and each command's example a literal."""
from __future__ import annotations

import argparse

from transient.cli import EXAMPLES, _parser


def _plain(text: str) -> str:
    return text.replace("|", r"\|").replace("://", r"\://")


def _escape(parser: argparse.ArgumentParser) -> None:
    for text in ("description", "epilog"):
        if getattr(parser, text):
            setattr(parser, text, _plain(getattr(parser, text)))
    for action in parser._actions:
        if action.help:
            action.help = _plain(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                if choice.help:
                    choice.help = _plain(choice.help)
            for sub in action.choices.values():
                _escape(sub)


def _with_examples(p: argparse.ArgumentParser) -> None:
    sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
    rows = [".. list-table:: The commands, one example each", "   :header-rows: 1",
            "   :widths: 12 40 48", "", "   * - command", "     - what it does", "     - example"]
    for choice in sub._choices_actions:
        name = choice.dest
        rows += [f"   * - ``{name}``", f"     - {choice.help}", f"     - ``{EXAMPLES[name]}``"]
        sub.choices[name].epilog = f"Example: ``{EXAMPLES[name]}``"
    p.description = f"{p.description}\n\n" + "\n".join(rows)
    p.epilog = None


def parser() -> argparse.ArgumentParser:
    p = _parser()
    _escape(p)
    _with_examples(p)
    return p
