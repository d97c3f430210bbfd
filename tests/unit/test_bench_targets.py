"""The performance targets as ``transient bench`` measures them
(:mod:`transient.verify.targets`): the hand-written (18) it times transient against is the same
equation, and the verdicts read the record's rows as stated. (The harness end to end, on short
runs: ``tests/cli/test_cli.py::test_bench_quick_writes_a_consistent_record``.)"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from transient.scene import load_scene
from transient.verify import targets as bt
from transient.verify.bench import ADAPTIVE

CASES = Path(__file__).resolve().parents[2] / "cases"
FLAGS = ({}, {"layout": True}, {"layout": True, "loads": True},
         {"layout": True, "loads": True, "records": True})


@pytest.mark.parametrize("flags", FLAGS, ids=lambda f: "+".join(f) or "bare")
def test_hand_written_18_is_transients_right_hand_side(flags):
    """Gots (1)–(19) written out by hand for one rigid-rod cylinder give transient's dt/dφ and
    dK/dφ along 40 rad of crank angle (two implementations of the same kinematics, to 1e-13)."""
    base = load_scene(CASES / "coasting_single.toml")
    hand, transient = bt.hand_against_transient(base, range(0, 2000, 97), **flags)
    assert hand[:, 0] == pytest.approx(transient[:, 0], rel=1e-13)  # dt/dφ
    assert hand[:, 1] == pytest.approx(transient[:, 1], rel=1e-13, abs=1e-13)  # dK/dφ


@pytest.mark.parametrize("flags", FLAGS, ids=lambda f: "+".join(f) or "bare")
def test_hand_written_loop_counts_no_references(flags):
    """The hand-written loop runs without reference counting, as transient's kernels do. With it,
    once the load's branches are in, numba does not prune the incref and decref of the row
    ``states[i]`` at every call, a cost the rungs would charge to the load's terms."""
    base = load_scene(CASES / "coasting_single.toml")
    loop = bt.make_hand_loop(bt.make_hand_rhs(**flags))
    loop(*bt.hand_arguments(base))
    machine_code = "".join(loop.inspect_asm().values())
    assert "NRT_incref" not in machine_code and "NRT_decref" not in machine_code


def test_the_hand_written_kernel_refuses_another_mechanism():
    with pytest.raises(ValueError, match="one rigid-rod cylinder"):
        bt.hand_parameters(load_scene(CASES / "gots_diesel_governed.toml"))


def _row(scene, method, rtol, wall, phase, nsteps=None):
    """A record's row; by default each tighter rtol takes 10 % more steps than the one before."""
    steps = nsteps if nsteps is not None else round(1000 * 1.1 ** -math.log10(rtol))
    return {"scene": scene, "method": method, "rtol": rtol, "step_rad": 0.0, "wall_s": wall,
            "phase_err_rad": phase, "nsteps": steps}


DEFAULT = "transient DOP853 (crank angle)"
RK45 = "solve_ivp RK45 (numpy RHS)"
CYRK = "CyRK DOP853 (transient's compiled RHS)"


def test_speed_is_compared_at_1e_6_rad_or_at_the_baselines_best_error():
    rows = [_row("a", DEFAULT, 1e-6, 0.01, 1e-5), _row("a", DEFAULT, 1e-8, 0.02, 1e-7),
            _row("a", CYRK, 1e-8, 0.03, 1e-5), _row("a", CYRK, 1e-10, 0.05, 5e-7),
            _row("a", RK45, 1e-4, 10.0, 1e-3), _row("a", RK45, 1e-5, 9.0, 2e-3)]
    got = {s["baseline"]: s for s in bt.speed_at_equal_accuracy(rows)}
    assert got[CYRK]["ratio"] == pytest.approx(0.05 / 0.02)
    assert got[CYRK]["error_rad"] == 1e-6
    # RK45 never reaches 1e-6 rad and its errors give no trend: compared at its best, 1e-3 rad,
    # against the fastest default run at least as accurate (0.01 s)
    assert got[RK45]["error_rad"] == 1e-3 and got[RK45]["ratio"] == pytest.approx(1000.0)
    assert "not reached" in got[RK45]["how"]
    # a scene where RK45 finished no run within the budget: said so, not left out
    rows.append(_row("b", DEFAULT, 1e-8, 0.02, 1e-7))
    got = [s for s in bt.speed_at_equal_accuracy(rows) if s["scene"] == "b"]
    assert [(s["baseline"], s["how"]) for s in got] == [
        (RK45, "no run finished within the budget"), (CYRK, "no run finished within the budget")]
    assert {v for t, c, _, v in bt.verdicts(dict(_results(0.9, 0.29, 0, 0.02), speed=got))
            if t.startswith("≥")} == {"**not measured**"}
    # ≥ 300× at RK45's best error, 1e-3 rad, is not the target at 1e-6 rad: said so
    at_a = [s for s in bt.speed_at_equal_accuracy(rows) if s["scene"] == "a"]
    assert [v for t, c, _, v in bt.verdicts(dict(_results(0.9, 0.29, 0, 0.02), speed=at_a))
            if t.startswith("≥")] == ["met at the baseline's best error", "met"]


def test_a_rise_of_the_error_is_found_above_the_references_floor_only():
    method = next(iter(ADAPTIVE))
    rows = [_row("a", method, r, 0.1, e) for r, e in
            ((1e-3, 1e-2), (1e-4, 3e-2), (1e-5, 1e-4), (1e-6, 1e-10), (1e-7, 2e-10))]
    got = {m["method"]: m for m in bt.error_monotone(rows, {"a": 1e-11})}[method]
    # 1e-4 rose ×3; the rise at 1e-7 is within 100× the floor (1e-9): not counted
    assert got["rises"] == [(1e-4, pytest.approx(3.0))]
    assert math.isfinite(got["slope"])


def test_a_plateau_on_the_same_steps_is_flat_and_a_rise_on_them_is_still_a_rise():
    """Where the breakpoints set the steps (the swash plate at loose rtol: one step per segment),
    tightening rtol changes neither the steps nor the error: flat, not a rise. An error that
    grows on the same steps (×1.8) is a rise all the same, and the slope leaves out the runs
    whose steps the tolerance did not set."""
    method = next(iter(ADAPTIVE))
    rows = [_row("a", method, r, 0.1, e, n) for r, e, n in
            ((1e-3, 5.650e-6, 12005), (1e-4, 5.652e-6, 12007), (1e-5, 1.0e-5, 12008),
             (1e-6, 2e-7, 24006), (1e-7, 2e-8, 36010), (1e-8, 2e-9, 48023))]
    got = bt.error_monotone(rows, {"a": 1e-13})[0]
    assert [r for r, _ in got["flat"]] == [1e-4]
    assert got["rises"] == [(1e-5, pytest.approx(1.0e-5 / 5.652e-6))]
    # the slope through rtol 1e-3, 1e-6, 1e-7, 1e-8 (1e-4 and 1e-5 took 1e-3's steps)
    x = np.log10([1e-3, 1e-6, 1e-7, 1e-8])
    assert got["slope"] == pytest.approx(np.polyfit(x, np.log10([5.65e-6, 2e-7, 2e-8, 2e-9]), 1)[0])
    line = next(v for t, c, v, _ in bt.verdicts(dict(_results(0.9, 0.29, 0, 0.02), monotone=[got]))
                if t.startswith("error falls"))
    assert "flat on the same steps at rtol 1e-04" in line and "rises: rtol 1e-05" in line


def _results(warm_s, overhead, change, iqr):
    return {"speed": [], "monotone": [],
            "overhead": [{"scene": "a", "samples_per_rev": 1, "overhead_chained": overhead}],
            "bare": {"hand_written_s": 1.0, "exact_s": 1.04, "tabulated_s": 1.2},
            "unused": {"change": change, "bare_iqr": iqr},
            "warm_start": {"scene": "a", "median_s": warm_s, "python_alone_s": 0.05},
            "scale": [{"revolutions": 1e3, "wall_per_1000_s": 1.0, "peak_mb": 100.0},
                      {"revolutions": 2e5, "wall_per_1000_s": 1.05, "peak_mb": 200.0},
                      {"revolutions": 1e6, "wall_per_1000_s": 1.12, "peak_mb": 201.0}]}


def test_verdicts_say_met_or_missed_against_each_target():
    met = {t: v for t, _, _, v in bt.verdicts(_results(0.9, 0.29, -0.01, 0.02))}
    assert met["warm start ≤ 1 s"] == "met"
    assert met["stepper overhead ≤ 30% (chained calls, 1 sample per turn)"] == "met"
    assert [v for t, c, _, v in bt.verdicts(_results(0.9, 0.29, -0.01, 0.02))
            if t.startswith("bare scene")] == ["met", "**missed**"]  # +4 %, +20 %
    assert next(v for t, _, _, v in bt.verdicts(_results(0.9, 0.29, -0.01, 0.02))
                if t.startswith("peak memory")) == "met"  # +1 MB of 200 from 2e5 on
    grown = _results(0.9, 0.29, -0.01, 0.02)
    grown["scale"][-1]["peak_mb"] = 203.0  # +3 MB: 1.5 %
    assert next(v for t, _, _, v in bt.verdicts(grown) if t.startswith("peak memory")) \
        == "**missed**"
    assert next(v for t, _, _, v in bt.verdicts(_results(0.9, 0.29, -0.01, 0.02))
                if t.startswith("wall per revolution")) == "**missed**"  # +12 %
    missed = {t: v for t, _, _, v in bt.verdicts(_results(1.1, 0.31, 0.03, 0.02))}
    assert missed["warm start ≤ 1 s"] == "**missed**"
    assert missed["stepper overhead ≤ 30% (chained calls, 1 sample per turn)"] == "**missed**"
    assert missed["unused options change nothing measurable (within the bare runs' IQR)"] \
        == "**missed**"


def test_the_record_extrapolates_to_1e_6_rad_only_from_near_it():
    """A log-log line through the two most accurate runs, if the better is within two decades
    of 1e-6 rad (4e-5 → 1e-6 rad at the slope of 1e-4 → 4e-5: wall ×2 per ×0.4 of error);
    from 0.65 rad, no estimate."""
    from transient.verify.bench import at_target

    near = [_row("a", RK45, 1e-8, 10.0, 4e-5), _row("a", RK45, 1e-7, 5.0, 1e-4)]
    wall, how = at_target(near, "a", RK45)
    assert how == "extrapolated from 4.0e-05 rad"
    assert wall == pytest.approx(10.0 * 2.0 ** (math.log(1e-6 / 4e-5) / math.log(0.4)))
    far = [_row("a", RK45, 1e-8, 10.0, 0.65), _row("a", RK45, 1e-7, 5.0, 10.0)]
    wall, how = at_target(far, "a", RK45)
    assert math.isnan(wall) and how == "not reached (best 6.5e-01 rad)"


def test_the_models_left_out_copy_matches_the_sources(tmp_path):
    """Every pattern of the build without the friction models matches the compiled core as often
    as :data:`transient.verify.models_out.LEFT_OUT` says, and the copy leaves no test of a
    reaction pair, a map or the stuck mode in the hot path; the rest of the package is copied
    unchanged."""
    import re

    from transient.verify import models_out

    copy = models_out.left_out_copy(tmp_path) / "transient"
    for name in {f for f, *_ in models_out.LEFT_OUT}:
        text = (copy / "core" / name).read_text(encoding="utf-8")
        assert not re.search(r"(?<!False and )\bm\.(reaction|eta_table)\b", text), name
        assert "== st.STUCK" not in text, name
    original = models_out.PACKAGE / "core" / "model" / "chain.py"
    assert (copy / "core" / "model" / "chain.py").read_text(encoding="utf-8") == original.read_text(
        encoding="utf-8")



# -- the elastic shaft line's targets (transient.verify.torsion)


@pytest.mark.parametrize("n", [3, 10, 30])
def test_the_generated_line_has_n_stations_and_a_spectrum_bounded_in_n(n):
    """N stations (the six's cylinders each on one of the first N − 1, in order; the flywheel
    last, the reference and where the load acts), N − 1 equal sections, no damper; its highest
    natural frequency within Gershgorin's bound 2√(k/J_min), which does not grow with N, and
    near it from N = 10 on (an explicit step's stability limit: the same along the lines)."""
    from transient.analysis.torsion import natural_modes
    from transient.shaft import ShaftLine
    from transient.verify import torsion as vt

    scene = vt.generated_line(load_scene(vt.ELASTIC_SCENE), n)
    shaft = scene.shaft
    assert len(shaft.stations) == n and len(shaft.sections) == n - 1 and not shaft.dampers
    carried = [c for st in shaft.stations for c in st.cylinders]
    assert carried == list(range(1, 7))
    assert shaft.reference == shaft.load_at == shaft.stations[-1].name == "flywheel"
    line = ShaftLine(scene)
    omega, _ = natural_modes(line.K, line.mean_inertia(), line.rigid_modes)
    bound = 2.0 * math.sqrt(vt.SECTION_K / vt.STATION_INERTIA)
    assert omega[-1] <= bound
    if n >= 10:
        assert omega[-1] >= 0.8 * bound


def _torsion_results(rigid_ratio, r2, cost_ratio, scipy_ratios):
    each = [{"scene": "six", "baseline": f"solve_ivp {m} (numpy RHS)", "error_rad": 1e-6,
             "how": "measured", "baseline_s": r, "transient_s": 1.0, "ratio": r, "target": 100.0}
            for m, r in scipy_ratios.items()]
    return {"rigid": {"scene": "six", "stations": 8, "dofs": 9, "cycles": 100.0,
                      "elastic_s": rigid_ratio * 1e-3, "rigid_s": 1e-3, "ratio": rigid_ratio,
                      "elastic_steps": 400.0, "rigid_steps": 50.0, "elastic_call_s": 2e-7,
                      "rigid_call_s": 1e-7},
            "scaling": {"stations": [3, 30], "wall_per_cycle_s": [1e-3, cost_ratio * 1e-3],
                        "steps_per_cycle": [400.0, 400.0], "slope_s": 1e-5, "intercept_s": 0.0,
                        "r2": r2, "ratio": cost_ratio, "span": 10.0},
            "rows": [], "scipy": bt.elastic_against_scipy([]) if not each else
            {"each": each, "best": min(each, key=lambda s: s["ratio"])}}


def test_the_elastic_verdicts_say_met_or_missed():
    """≤ 10× the rigid run per cycle; linear in N (rising, and at most N₃₀/N₃ = 10× the cost
    at 3, whatever the noise makes of R²); ≥ 100× the fastest scipy method; the rigid scenes'
    cost left to the rigid rows."""
    from transient.verify import torsion as vt

    def verdicts(res):
        return [v for _, _, _, v in vt.verdicts(res, bt._missed)]

    assert verdicts(_torsion_results(8.0, 0.99, 9.0, {"RK45": 300.0, "LSODA": 150.0})) == [
        "met", "met", "met", "covered by the rigid targets"]
    assert verdicts(_torsion_results(12.0, 0.99, 12.0, {"RK45": 300.0, "LSODA": 50.0})) == [
        "**missed**", "**missed**", "**missed**", "covered by the rigid targets"]
    assert verdicts(_torsion_results(8.0, 0.9, 5.0, {}))[1:3] == ["met", "**not measured**"]
    line = vt.verdicts(_torsion_results(8.0, 0.99, 9.0, {"RK45": 300.0, "LSODA": 150.0}),
                       bt._missed)[2][2]
    assert line.startswith("150× solve_ivp LSODA (numpy RHS)")  # (the fastest of them)


def test_the_scipy_comparison_takes_the_fastest_method_at_equal_error():
    """The record's rows through the rigid scenes' comparison: each method at 1e-6 rad against
    transient's default path there; the best of them the one of least ratio."""
    rows = [_row("six", DEFAULT, 1e-8, 0.01, 1e-7), _row("six", DEFAULT, 1e-6, 0.005, 1e-5),
            _row("six", "solve_ivp RK45 (numpy RHS)", 1e-8, 20.0, 5e-7),
            _row("six", "solve_ivp LSODA (numpy RHS)", 1e-8, 3.0, 8e-7),
            _row("six", "solve_ivp Radau (numpy RHS)", 1e-8, 9.0, 2e-7)]
    got = bt.elastic_against_scipy(rows)
    assert len(got["each"]) == 3
    assert got["best"]["baseline"] == "solve_ivp LSODA (numpy RHS)"
    assert got["best"]["ratio"] == pytest.approx(3.0 / 0.01)
