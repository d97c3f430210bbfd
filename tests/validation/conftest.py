"""Shared helpers of the validation tests: the scenes in ``cases/`` and an accurate quadrature
of output samples between known cut points (breakpoints, events; ``tests/sample_integrals.py``).
The published tables are read by ``tests/references``."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sample_integrals import sample_integral_impl

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"


@pytest.fixture(scope="session")
def sample_integral():
    """The function :func:`sample_integral_impl` (fixtures keep the test modules import-free)."""
    return sample_integral_impl


def table_end_events_impl(data, scene, tol: float = 1e-6):
    """The run's ``breakpoint`` events (rows of t, φ) where a cylinder's table starts its cycle
    (local angle 0 ≡ the cycle's end): the only corners of a smooth table's curve. Every other
    knot of a table from points is a breakpoint too, but the curve is C² there, so a quadrature
    of the samples needs no cut. ``tol`` [rad] covers a landing in time (to 1e-7 rad)."""
    from transient.assemble import gas_phases

    ev = np.asarray(data.events.get("breakpoint", np.zeros((0, 2)))).reshape(-1, 2)
    period = scene.mechanism.cycle
    d = np.mod(np.subtract.outer(ev[:, 1], gas_phases(scene)), period)
    return ev[np.any(np.minimum(d, period - d) <= tol, axis=1)]


@pytest.fixture(scope="session")
def table_end_events():
    """The function :func:`table_end_events_impl`."""
    return table_end_events_impl
