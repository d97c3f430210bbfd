"""Every scene of ``cases/`` through ``transient run`` gives its golden values
(``tests/data/golden``, written by ``tests/cli/golden.py``): a change that alters a result fails
here until the values are regenerated and the diff reviewed."""
from __future__ import annotations

import json

import pytest

from golden import GOLDEN, capture, compare, run, scenes


@pytest.mark.parametrize("scene", scenes(), ids=lambda p: p.stem)
def test_run_gives_the_golden_values(scene, tmp_path):
    stored = GOLDEN / f"{scene.stem}.json"
    assert stored.is_file(), f"no golden values for {scene.name}: run tests/cli/golden.py"
    want = json.loads(stored.read_text())
    diffs = compare(capture(run(scene, tmp_path)), want)
    assert not diffs, f"{scene.name}:\n" + "\n".join(diffs)


def test_compare_sees_a_change_in_any_kept_value():
    """The comparison itself: equal captures agree; a change beyond the tolerance in each kind of
    value is named, one within it is not."""
    base = {"samples": 5, "end": {"t": 1.0, "phi": 2.0, "omega": 3.0}, "omega": [3.0, 3.5],
            "analysis": {"delta_last_cycle": 0.01, "steady_state_t": float("nan")}}
    assert compare(base, json.loads(json.dumps(base))) == []
    near = json.loads(json.dumps(base))
    near["end"]["omega"] *= 1 + 1e-12
    assert compare(near, base) == []
    for path, value in ((("end", "t"), 1.0 + 1e-6), (("omega", 1), 3.6),
                        (("analysis", "delta_last_cycle"), 0.0101),
                        (("analysis", "steady_state_t"), 0.5)):
        changed = json.loads(json.dumps(base))
        changed[path[0]][path[1]] = value
        assert len(compare(changed, base)) == 1, path
    fewer = dict(base, samples=4)
    assert compare(fewer, base) == ["samples: 4 against 5"]
    missing = json.loads(json.dumps(base))
    del missing["analysis"]["delta_last_cycle"]
    assert compare(missing, base) == ["analysis delta_last_cycle: present in only one of them"]
