"""Every scene of ``cases/`` through ``transient run`` gives its golden values
(``tests/data/golden``, written by ``tests/cli/golden.py``) within the tolerance its solver
settings allow: a change that alters a result fails here until the values are regenerated and
the diff reviewed; another CPU's rounding does not."""
from __future__ import annotations

import copy
import json
import math

import pytest
from golden import GOLDEN, capture, compare, run, scenes, tolerances, with_errors
from own_error import MOVE


@pytest.mark.parametrize("scene", scenes(), ids=lambda p: p.stem)
def test_run_gives_the_golden_values(scene, tmp_path):
    stored = GOLDEN / f"{scene.stem}.json"
    assert stored.is_file(), f"no golden values for {scene.name}: run tests/cli/golden.py"
    want = json.loads(stored.read_text())
    diffs = compare(capture(run(scene, tmp_path)), want)
    assert not diffs, f"{scene.name}:\n" + "\n".join(diffs)


def _base() -> dict:
    """A capture at rtol 1e-8 with its errors: a steady ω whose end moved 1e-6 at the tighter
    tolerance, a balance residual that is rounding noise, a percentage, a count."""
    values = {"solver": {"rtol": 1e-8, "atol": 1e-10}, "samples": 5,
              "end": {"t": 1.0, "phi": 2.0, "omega": 300.0}, "omega": [-100.0, 300.0],
              "analysis": {"energy_balance_residual": 3e-15, "overshoot_pct": 2e-11,
                           "W_out_per_cycle": 2000.0, "W_loss_1_per_cycle": 50.0,
                           "steady_cycles": 40.0, "steady_state_t": float("nan")},
              "units": {"energy_balance_residual": "1", "overshoot_pct": "%",
                        "W_out_per_cycle": "J", "W_loss_1_per_cycle": "J", "steady_cycles": "1",
                        "steady_state_t": "s"}}
    reference = copy.deepcopy(values)
    reference["end"]["omega"] += 1e-6
    reference["omega"][1] += 1e-6
    reference["analysis"]["energy_balance_residual"] = -1e-16
    reference["analysis"]["W_loss_1_per_cycle"] += 1e-5
    return with_errors(values, reference)


def _changed(where: str, key, by: float) -> dict:
    c = copy.deepcopy(_base())
    c.pop("error")
    c[where][key] = by if math.isnan(c[where][key]) else c[where][key] + by
    return c


def test_the_errors_are_the_distances_from_the_tighter_run():
    err = _base()["error"]
    assert err["end omega"] == pytest.approx(1e-6) and err["omega sample 1"] == err["end omega"]
    assert err["analysis energy_balance_residual"] == pytest.approx(3.1e-15)
    assert err["analysis steady_cycles"] == 0.0 and err["samples"] == 0
    assert err["analysis steady_state_t"] == 0.0  # (NaN in both)
    nan_once = copy.deepcopy(_base())
    nan_once["analysis"]["steady_state_t"] = 0.5
    with pytest.raises(ValueError, match="steady_state_t is 0.5, and nan at the tighter"):
        with_errors(nan_once, _base())


def test_each_value_is_held_to_its_error_and_the_solvers_floor():
    tol = tolerances(_base())
    # ω: ten times its error, plus rtol times the largest |ω| of the samples, plus atol
    assert tol["end omega"] == pytest.approx(MOVE * 1e-6 + 1e-8 * 300.0 + 1e-10)
    assert tol["omega sample 0"] == pytest.approx(1e-8 * 300.0 + 1e-10)  # (|ω| = 100 there)
    assert tol["end t"] == pytest.approx(1e-8 + 1e-10)
    # a residual that is rounding noise: held to rtol of the whole it is a fraction of
    assert tol["analysis energy_balance_residual"] == pytest.approx(1e-8, rel=1e-5)
    assert tol["analysis overshoot_pct"] == pytest.approx(1e-8 * 100.0)
    assert tol["analysis steady_cycles"] == pytest.approx(1e-8 * 40.0)  # (a count: itself)
    # a loss: its own error, or rtol of the largest energy of the run (the work it is part of)
    assert tol["analysis W_loss_1_per_cycle"] == pytest.approx(MOVE * 1e-5 + 2000e-8)
    assert tol["samples"] == 0.0


def test_compare_sees_a_change_beyond_the_tolerance_in_any_kept_value():
    """Equal captures agree; moves within each value's tolerance (another CPU's) are not named;
    a move beyond it — a real change, however small against the value — is, one line each."""
    base = _base()
    plain = copy.deepcopy(base)
    plain.pop("error")
    assert compare(plain, base) == []
    # (the residual is at rounding: a change of several times itself is within its floor)
    within = [("end", "omega", 5e-6), ("omega", 0, 2e-6), ("end", "t", 5e-9),
              ("analysis", "energy_balance_residual", -2e-14),
              ("analysis", "overshoot_pct", 5e-11), ("analysis", "W_loss_1_per_cycle", 5e-5)]
    for where, key, by in within:
        assert compare(_changed(where, key, by), base) == [], (where, key)
    beyond = [("end", "omega", 2e-5), ("omega", 0, 1e-5), ("end", "t", 1e-7),
              ("end", "phi", 1e-6), ("analysis", "energy_balance_residual", 1e-7),
              ("analysis", "overshoot_pct", 1e-5), ("analysis", "W_loss_1_per_cycle", 3e-4),
              ("analysis", "steady_cycles", 1.0), ("analysis", "steady_state_t", 0.5),
              ("samples", None, 1)]
    for where, key, by in beyond:
        changed = _changed(where, key, by) if key is not None else dict(plain, samples=6)
        diffs = compare(changed, base)
        assert len(diffs) == 1 and "against" in diffs[0], (where, key, diffs)
    # (a value off by 2e-5 at 300 rad/s is 7e-8 of it: within rtol 1e-6, beyond rtol 1e-8)
    loose = copy.deepcopy(base)
    loose["solver"]["rtol"] = 1e-6
    moved = _changed("end", "omega", 2e-5)
    moved["solver"]["rtol"] = 1e-6
    assert compare(moved, loose) == []


def test_compare_names_what_is_in_one_capture_only():
    base = _base()
    missing = copy.deepcopy(base)
    missing.pop("error")
    del missing["analysis"]["W_out_per_cycle"]
    del missing["units"]["W_out_per_cycle"]
    assert compare(missing, base) == ["analysis W_out_per_cycle: present in only one of them"]
    old_format = {k: v for k, v in base.items() if k not in ("solver", "units", "error")}
    assert compare(missing, old_format) == [
        "the golden values lack ['error', 'solver', 'units']: regenerate them "
        "(tests/cli/golden.py)"]
    other = copy.deepcopy(base)
    other.pop("error")
    other["solver"]["rtol"] = 1e-9
    other["units"]["W_loss_1_per_cycle"] = "kJ"
    assert compare(other, base) == [
        "solver: {'rtol': 1e-09, 'atol': 1e-10} against {'rtol': 1e-08, 'atol': 1e-10}",
        "unit of analysis W_loss_1_per_cycle: kJ against J"]
