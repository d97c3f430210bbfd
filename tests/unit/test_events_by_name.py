"""run._events_by_name: a chunk's event rows grouped by name with numpy, against the
row-by-row grouping it replaced (the events' order within a name kept)."""
import numpy as np

from transient.core.stepper import io as sio
from transient.run import _events_by_name


def grouped_row_by_row(rows, switching):
    ev = {}
    for code, t, phi, _ in rows:
        name = sio.EVENT_NAMES[int(code)]
        ev.setdefault("inertia_switch" if switching and name == "end" else name,
                      []).append((t, phi))
    return ev


def test_grouping_matches_the_row_by_row_loop():
    rng = np.random.default_rng(1)
    n = 500
    rows = np.column_stack([rng.integers(0, len(sio.EVENT_NAMES), n), np.arange(n) * 1e-3,
                            rng.normal(size=n), rng.normal(size=n)])
    for switching in (False, True):
        got, want = _events_by_name(rows, switching), grouped_row_by_row(rows, switching)
        assert set(got) == set(want)
        for name, pairs in want.items():
            np.testing.assert_array_equal(got[name], np.array(pairs))
    assert "inertia_switch" in _events_by_name(rows, True)
    assert _events_by_name(rows[:0], False) == {}
