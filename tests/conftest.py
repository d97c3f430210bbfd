"""The order in which a parallel run of the suite (``make test``: pytest-xdist, ``--dist
worksteal``) hands the tests to its workers.

worksteal gives each worker an equal, contiguous share of the collection, in order, and a worker
that runs out takes the end of a busy one's share. On a cold numba cache the compiled stepper
takes minutes to compile; one worker compiles it and any other that
needs it meanwhile waits on its lock (``transient.core.jit``), then loads it. The unit tests
never run the stepper (runs belong in ``tests/validation``), so they go last: the last worker's
share is unit tests, which it runs while the first compiles. The stress tests go first, so that
their longest ones start early rather than end the run. A serial run keeps
pytest's own order.

The fixture ``ctrl_c`` makes SIGINT raise KeyboardInterrupt during a test that sends it, as in an
interactive Python: a suite started in the background inherits SIGINT ignored.
"""
from __future__ import annotations

import signal
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
PARALLEL_ORDER = ("stress", "validation", "cli", "unit")


def pytest_collection_modifyitems(config, items):
    if not hasattr(config, "workerinput"):  # (set in pytest-xdist's workers only)
        return

    def rank(item):
        folder = item.path.relative_to(TESTS).parts[0]
        return PARALLEL_ORDER.index(folder) if folder in PARALLEL_ORDER else len(PARALLEL_ORDER)

    items.sort(key=rank)  # (stable: each folder keeps pytest's order)


@pytest.fixture
def ctrl_c():
    kept = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, kept)
