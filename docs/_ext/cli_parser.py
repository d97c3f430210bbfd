"""The ``transient`` command's own argument parser, for sphinx-argparse (docs/guide/cli.md).

Help strings are plain text; a ``|`` in them (``|R|``, an absolute value) would be read by reST
as a substitution reference, so it is escaped. Nothing else is changed."""
from __future__ import annotations

import argparse

from transient.cli import _parser


def _escape(parser: argparse.ArgumentParser) -> None:
    for text in ("description", "epilog"):
        if getattr(parser, text):
            setattr(parser, text, getattr(parser, text).replace("|", r"\|"))
    for action in parser._actions:
        if action.help:
            action.help = action.help.replace("|", r"\|")
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                if choice.help:
                    choice.help = choice.help.replace("|", r"\|")
            for sub in action.choices.values():
                _escape(sub)


def parser() -> argparse.ArgumentParser:
    p = _parser()
    _escape(p)
    return p
