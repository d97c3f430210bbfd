"""The Examples of the public API's docstrings run as written: what the API pages show a user
(docs/api.rst) is what the code does. Each public name must have at least one."""
from __future__ import annotations

import doctest

import pytest

import transient

PUBLIC = [name for name in transient.__all__ if name not in ("errors", "__version__")]


def examples(name: str) -> list[doctest.DocTest]:
    """The doctests of ``transient.<name>`` and, for a class, of its methods."""
    obj = getattr(transient, name)
    found = doctest.DocTestFinder().find(obj, f"transient.{name}", module=False, globs={})
    return [test for test in found if test.examples]


@pytest.mark.parametrize("name", PUBLIC)
def test_every_public_name_has_examples_that_run(name):
    tests = examples(name)
    assert tests, f"transient.{name} has no Examples section"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report = []
    for test in tests:
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
    assert runner.tries >= 2
