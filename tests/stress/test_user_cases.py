"""The stress suite's cases a user would try (``transient.verify.stress``: an in-line six, a
V8, a two-stroke, a weak starter from rest, a light flywheel, load steps at revolution counts, a
sweep from a script), each run as ``transient stress`` runs it — a forked child with a time
bound — and each must pass: no traceback, and the status that says what happened. A run whose
shaft never did what its scene asked must not end ``finished`` and must say it did not start."""
from __future__ import annotations

import pytest

from transient.verify.stress import catalogue, run_case, warm_up

USER_CASES = ("in-line-six", "v8", "two-stroke", "weak-starter-from-rest", "light-flywheel",
              "load-steps-at-revolutions", "sweep-from-script")


@pytest.fixture(scope="module")
def warm():
    warm_up()  # (in this process, so that the forked cases load the kernels, not compile them)


@pytest.mark.slow
@pytest.mark.parametrize("name", USER_CASES)
def test_a_case_a_user_tries_passes(tmp_path, warm, name):
    case = next(c for c in catalogue() if c.name == name)
    assert case.quick and not case.known
    o = run_case(case, True, tmp_path)
    assert o.outcome == "pass", f"{o.status}: " + "; ".join(o.notes)


def test_the_catalogue_holds_the_cases_a_user_tries():
    names = [c.name for c in catalogue()]
    assert set(USER_CASES) <= set(names) and len(set(names)) == len(names)
