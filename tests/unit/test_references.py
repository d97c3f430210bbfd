"""The references of ``tests/references`` are what they claim to be: every published table in
``tests/data`` is the file its README's checksum names, and every case names a test that exists
and calls it (the Validation page prints that name beside each comparison)."""
from __future__ import annotations

import ast
import hashlib
import re

import pytest
from references import DATA, KINDS, Comparison, Tolerance, load_all

TESTS = DATA.parent


def checksums() -> dict[str, str]:
    text = (DATA / "README.md").read_text(encoding="utf-8")
    block = text.split("## Checksums", 1)[1]
    return {name: digest for digest, name in re.findall(r"^([0-9a-f]{64})  (\S+)$", block, re.M)}


def test_every_table_is_the_file_its_checksum_names():
    sums = checksums()
    files = sorted(p.name for p in DATA.glob("*.csv"))
    assert files and sorted(sums) == files, "the README lists a checksum for each table"
    for name, digest in sums.items():
        assert hashlib.sha256((DATA / name).read_bytes()).hexdigest() == digest, name


@pytest.mark.parametrize("name", sorted(load_all()))
def test_each_case_names_the_test_that_asserts_it(name):
    """The named test function exists and calls ``<module>.<case>()`` in its body."""
    build = load_all()[name]
    path, _, function = build.test.partition("::")
    tree = ast.parse((TESTS / path).read_text(encoding="utf-8"))
    defs = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    assert function in defs, f"{build.test} does not exist"
    module, case = name.split(".")
    calls = {(c.func.value.id, c.func.attr) for c in ast.walk(defs[function])
             if isinstance(c, ast.Call) and isinstance(c.func, ast.Attribute)
             and isinstance(c.func.value, ast.Name)}
    assert (module, case) in calls, f"{build.test} does not call {name}()"


def test_a_tolerance_is_one_kind_of_bound():
    for bad in ({}, {"abs": 1.0, "rel": 1.0}, {"abs": 1.0, "low": 0.0}):
        with pytest.raises(ValueError):
            Tolerance(why="", **bad)


@pytest.mark.parametrize("tolerance,reference,computed,holds", [
    (Tolerance(abs=0.1, why=""), [1.0, 1.0], [1.05, 0.95], True),
    (Tolerance(abs=0.1, why=""), [1.0, 1.0], [1.05, 1.11], False),
    (Tolerance(rel=0.1, why=""), [10.0, 10.0], [10.9, 9.1], True),
    (Tolerance(rel=0.1, why=""), [10.0, 10.0], [11.1, 10.0], False),
    (Tolerance(low=3.0, why=""), None, 3.0, True),
    (Tolerance(low=3.0, why=""), None, 2.99, False),
    (Tolerance(low=1.0, high=2.0, why=""), None, [1.5, 2.01], False),
])
def test_a_comparison_holds_where_its_tolerance_does(tolerance, reference, computed, holds):
    c = Comparison("x", "s", KINDS[0], reference, computed, "m", tolerance)
    assert c.holds is holds
    if not holds:
        with pytest.raises(AssertionError, match="x \\(s\\)"):
            c.check()
