"""``transient --help`` lists every command with a one-line help and an example, and each
command's own help ends with its example; every example is a command line the parser accepts,
naming case files that exist."""
from __future__ import annotations

import argparse
import shlex
from pathlib import Path

import pytest

from transient.cli import EXAMPLES, _parser

ROOT = Path(__file__).resolve().parents[2]


def commands() -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_every_command_has_one_example_in_the_listed_order():
    assert list(EXAMPLES) == list(commands())
    assert len(EXAMPLES) == 15


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_each_example_parses_as_its_command(name):
    assert len(EXAMPLES[name]) <= 70  # (a command's help, 80 columns wide, keeps it on one line)
    argv = shlex.split(EXAMPLES[name])
    assert argv[0] == "transient"
    args = _parser().parse_args(argv[1:])
    assert args.command == name
    for word in argv[1:]:
        if word.startswith("cases/"):
            assert (ROOT / word).is_file(), word


def test_the_help_lists_each_command_on_one_line_and_ends_with_the_examples(monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")  # (argparse wraps to the terminal's width)
    text = _parser().format_help()
    help_of = {c.dest: c.help for c in next(
        a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))._choices_actions}
    for name, parser in commands().items():
        assert "\n" not in help_of[name] and len(help_of[name]) <= 64, name
        assert any(line.strip().endswith(help_of[name]) for line in text.splitlines()), name
        assert EXAMPLES[name] in text
        assert parser.format_help().rstrip().endswith(f"example: {EXAMPLES[name]}")
    assert "DESIGN" not in text
