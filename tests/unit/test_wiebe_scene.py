"""``[gas] model = "wiebe"``: the scene keys, their validation, and the model they assemble.

A Wiebe scene has the cycle's pressures in ``[gas]`` (``compression_ratio``, ``p_a``,
``p_intake``, ``p_exhaust``, as the mixed cycle) and the combustion in ``[gas.wiebe]``, whose keys
are the ones :mod:`transient.forces.wiebe` names in its errors (``gas.wiebe.start_deg``, ...).
Invalid values reach the user as one line ``file: key: message`` with exit code 2, from
``load_scene`` (the tables are built there, before any run), and ``run`` writes nothing.
"""
from __future__ import annotations

import inspect
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.cli import main
from transient.errors import SceneError
from transient.forces.wiebe import WiebeCycle, wiebe_cycle
from transient.scene import Wiebe, load_scene, to_toml
from transient.scene.queries import gas_tables, wiebe_levels

CASES = Path(__file__).resolve().parents[2] / "cases"
WIEBE = CASES / "gots_diesel_wiebe.toml"
TEXT = WIEBE.read_text(encoding="utf-8")
DEG = math.pi / 180.0


def test_scene_keys_in_si():
    gas = load_scene(WIEBE).gas
    assert gas.model == "wiebe"
    assert (gas.p0, gas.compression_ratio, gas.p_a, gas.p_intake, gas.p_exhaust) == (
        0.1e6, 18.0, 0.1436e6, 0.165e6, 0.182e6)
    w = gas.wiebe
    assert w.start == pytest.approx(358 * DEG, rel=1e-15)
    assert w.duration == pytest.approx(50 * DEG, rel=1e-15)
    assert (w.a, w.m, w.fuel_mass, w.lhv, w.efficiency, w.gamma, w.gamma_slope, w.t_a) == (
        6.908, 0.5, 0.031e-3, 42.5e6, 1.0, 1.368, 0.0, 329.9)
    assert w.intake_closing is None and w.exhaust_opening is None


def test_defaults_are_wiebe_cycles():
    """The scene's defaults are :func:`wiebe_cycle`'s (written twice: the scene records do not import
    the module, which only Wiebe scenes need)."""
    params = inspect.signature(wiebe_cycle).parameters
    names = {"a": "a", "m": "m", "lhv": "lhv", "efficiency": "efficiency", "gamma": "gamma",
             "gamma_slope": "gamma_slope", "gamma_t_ref": "gamma_t_ref", "t_a": "t_a",
             "intake_closing": "intake_closing", "exhaust_opening": "exhaust_opening",
             "step": "step", "tolerance": "tolerance"}
    d = Wiebe()
    for field, param in names.items():
        assert getattr(d, field) == params[param].default, field


def test_optional_keys_and_round_trip(tmp_path):
    text = TEXT.replace("t_a = 329.9\n", "t_a = 329.9\nintake_closing_deg = 200\n"
                                         "exhaust_opening_deg = 520\nstep_deg = 0.25\n"
                                         "tolerance = 1e-9\ngamma_t_ref = 310\n")
    scene = load_scene(tmp_path / "s.toml", text=text)
    w = scene.gas.wiebe
    assert w.intake_closing == pytest.approx(200 * DEG) and w.exhaust_opening == pytest.approx(
        520 * DEG)
    assert (w.step, w.tolerance, w.gamma_t_ref) == (pytest.approx(0.25 * DEG), 1e-9, 310.0)
    again = load_scene(tmp_path / "r.toml", text=to_toml(scene))
    assert again == scene and to_toml(again) == to_toml(scene)
    full, mot = gas_tables(scene)
    assert full.intake_closing == pytest.approx(200 * DEG) and mot.fuel_mass == 0.0
    # Without the optional angles, the resolved scene leaves them out and reads None back.
    plain = load_scene(WIEBE)
    assert "intake_closing" not in to_toml(plain)
    assert load_scene(tmp_path / "p.toml", text=to_toml(plain)) == plain


def test_tables_follow_the_scene():
    scene = load_scene(WIEBE)
    full, mot = gas_tables(scene)
    assert isinstance(full, WiebeCycle) and isinstance(mot, WiebeCycle)
    assert (full.fuel_mass, mot.fuel_mass) == (0.031e-3, 0.0)
    np.testing.assert_array_equal(full.knots, mot.knots)
    np.testing.assert_array_equal(full.piece_knot, mot.piece_knot)
    # The clearance volume follows from ε as for the mixed cycle: V_a/V_c = ε at the BDC.
    assert full.v_a / full.v_c == pytest.approx(18.0, rel=1e-12)
    assert full.v_h == pytest.approx(scene.mechanism.swept_volume(), rel=1e-12)
    assert gas_tables(scene)[0] is full  # built once per engine and cycle (cached)
    assert full.mean_pressure == pytest.approx(1.42e6, rel=2e-3)  # the scene's calibration


def test_model_of_a_wiebe_scene():
    scene = load_scene(WIEBE)
    model, bp, table = build_model(scene)
    full, mot = gas_tables(scene)
    assert model.has_motored and table is full
    # One paired table: the levels share knots and corners, so they are stacked as they are.
    np.testing.assert_array_equal(model.knots, full.knots)
    np.testing.assert_array_equal(model.piece_knot, full.piece_knot)
    np.testing.assert_array_equal(model.coef[:, :4], full.coef)
    np.testing.assert_array_equal(model.coef[:, 4:], mot.coef)
    # Corners 0, 180° (intake closing), 358°, 408° (combustion), 540° (exhaust opening) of
    # each of the 3 cylinders, all distinct.
    assert bp.size == 15
    local = np.sort(np.mod(bp[:, None] - model.gas_phase[None, :], model.period), axis=None)
    for c in np.array([0.0, 180.0, 358.0, 408.0, 540.0]) * DEG:
        assert np.count_nonzero(np.abs(local - c) < 1e-9) == 3


def test_motored_only_scene(tmp_path):
    """fuel_mass = 0: one cycle, the motored one, is both curves (the fuel does nothing)."""
    scene = load_scene(tmp_path / "s.toml", text=TEXT.replace("fuel_mass = 0.031e-3",
                                                               "fuel_mass = 0"))
    full, mot = gas_tables(scene)
    assert full is mot and mot.fuel_mass == 0.0
    model = build_model(scene)[0]
    assert model.has_motored
    np.testing.assert_array_equal(model.coef[:, :4], model.coef[:, 4:])


@pytest.mark.parametrize("name, motored", [("gots_diesel_4400", True), ("swash_plate_4cyl", False),
                                           ("coasting_single", False)])
def test_full_fuel_scenes_hold_one_table(name, motored):
    """Without a governor or a [[gas.cylinders]] entry that changes the combustion the fuel is 1
    throughout: the model holds the full-load table only and the kernels take the one-table path
    (no second look-up), whether or not the gas model has a motored curve (a force pulse's is
    zero force)."""
    scene = load_scene(CASES / f"{name}.toml")
    model = build_model(scene)[0]
    assert not model.has_motored
    assert (gas_tables(scene)[1] is not None) == motored
    assert model.coef.shape[1] == 4
    assert build_model(scene, part_load=True)[0].has_motored == motored


def test_governed_mixed_cycle_pairs_its_motored_cycle():
    scene = load_scene(CASES / "gots_diesel_governed.toml")
    model = build_model(scene)[0]
    full, motored = gas_tables(scene)
    assert model.has_motored and motored is full.motored
    # on the union of the knots (the full-load isobar is one interval, the motored curve's
    # polytrope there many), each cubic re-expanded about them: the same curves
    x = 0.5 * (model.knots[:-1] + model.knots[1:])
    for cols, table in ((slice(0, 4), full), (slice(4, 8), motored)):
        c = model.coef[:, cols]
        h = x - model.knots[:-1]
        paired = c[:, 0] + h * (c[:, 1] + h * (c[:, 2] + h * c[:, 3]))
        np.testing.assert_allclose(paired, table(x), rtol=1e-13)


# ----------------------------------------------------------------------------------------------
# Invalid scenes: one line, exit 2, the key as written.

def edit(old: str, new: str) -> str:
    """The case with one key line (or its start) replaced; comments are left alone."""
    assert TEXT.count(f"\n{old}") == 1, old
    return TEXT.replace(f"\n{old}", f"\n{new}")


BAD = [
    ("negative-fuel", edit("fuel_mass = 0.031e-3", "fuel_mass = -0.031e-3"),
     "gas.wiebe.fuel_mass", "must be ≥ 0, got -3.1e-05"),
    ("zero-duration", edit("duration_deg = 50", "duration_deg = 0"),
     "gas.wiebe.duration_deg", "must be > 0, got 0"),
    ("negative-duration", edit("duration_deg = 50", "duration_deg = -5"),
     "gas.wiebe.duration_deg", "must be > 0, got -5"),
    ("combustion-past-exhaust-opening", edit("duration_deg = 50", "duration_deg = 200"),
     "gas.wiebe.duration_deg", "ends at 558°, after the exhaust opening at 540°"),
    ("start-outside-closed-part", edit("start_deg = 358", "start_deg = 100"),
     "gas.wiebe.start_deg", "combustion starts at 100°, outside the closed part"),
    ("start-in-radians-outside", edit("start_deg = 358", "start = 1.0"),
     "gas.wiebe.start", "outside the closed part"),
    ("missing-start", edit("start_deg = 358\n", ""),
     "gas.wiebe.start", "is missing; give 'start' or 'start_deg'"),
    ("missing-fuel", edit("fuel_mass = 0.031e-3\n", ""),
     "gas.wiebe.fuel_mass", "is missing"),
    ("missing-wiebe-table", edit("[gas.wiebe]\n", "[combustion]\n"),
     "gas.wiebe", "is missing (a table)"),
    ("unknown-wiebe-key", edit("a = 6.908", "a = 6.908\nwoschni = 1"),
     "gas.wiebe.woschni", ("unknown key; allowed here: a, duration, efficiency, exhaust_opening, "
                           "fuel_mass, gamma, gamma_slope, gamma_t_ref, intake_closing, lhv, m")),
    ("misfit-suffix", edit("duration_deg = 50", "duration_rpm = 50"),
     "gas.wiebe.duration_rpm", "unit suffix '_rpm' does not fit this quantity"),
    ("a-zero", edit("a = 6.908", "a = 0"), "gas.wiebe.a", "must be > 0, got 0"),
    ("m-below-minus-1", edit("m = 0.5", "m = -1"), "gas.wiebe.m", "must be > -1, got -1"),
    ("efficiency-above-1", edit("efficiency = 1.0", "efficiency = 1.1"),
     "gas.wiebe.efficiency", "must be ≤ 1, got 1.1"),
    ("lhv-negative", edit("lhv = 42.5e6", "lhv = -1"), "gas.wiebe.lhv", "must be > 0"),
    ("gamma-1", edit("gamma = 1.368", "gamma = 1"), "gas.wiebe.gamma", "must be > 1, got 1"),
    ("gamma-of-t-below-1", edit("gamma_slope = 0.0", "gamma_slope = -0.02"),
     "gas.wiebe.gamma_slope", "it must be > 1 there"),
    ("t-a-zero", edit("t_a = 329.9", "t_a = 0"), "gas.wiebe.t_a", "must be > 0, got 0"),
    ("intake-closing-after-firing-tdc",
     edit("t_a = 329.9", "t_a = 329.9\nintake_closing_deg = 400"),
     "gas.wiebe.intake_closing_deg", "intake closes at 400°; it must be after 0°"),
    ("exhaust-opening-before-firing-tdc",
     edit("t_a = 329.9", "t_a = 329.9\nexhaust_opening_deg = 300"),
     "gas.wiebe.exhaust_opening_deg", "exhaust opens at 300°; it must be after 360°"),
    ("tolerance-too-large", edit("t_a = 329.9", "t_a = 329.9\ntolerance = 0.1"),
     "gas.wiebe.tolerance", "must be ≤ 0.001, got 0.1"),
    ("step-zero", edit("t_a = 329.9", "t_a = 329.9\nstep_deg = 0"),
     "gas.wiebe.step_deg", "must be ≥ 0.000572958, got 0"),
    ("compression-ratio-1", edit("compression_ratio = 18", "compression_ratio = 1"),
     "gas.compression_ratio", "must be > 1, got 1"),
    ("p-a-negative", edit("p_a_MPa = 0.1436", "p_a_MPa = -0.1"),
     "gas.p_a_MPa", "must be > 0, got -0.1"),
    ("four-stroke-without-intake-pressure", edit("p_intake_MPa = 0.165\n", ""),
     "gas.p_intake", "is missing"),
    ("negative-exhaust-pressure", edit("p_exhaust_MPa = 0.182", "p_exhaust_MPa = -0.182"),
     "gas.p_exhaust_MPa", "must be ≥ 0, got -0.182"),
]


@pytest.mark.parametrize("command", ["check", "run"])
@pytest.mark.parametrize("text, key, fragment", [pytest.param(t, k, f, id=i) for i, t, k, f in BAD])
def test_invalid_wiebe_scene_is_one_line_exit_2(tmp_path, capsys, command, text, key, fragment):
    scene = tmp_path / "bad.toml"
    scene.write_text(text, encoding="utf-8")
    out_dir = tmp_path / "out"
    argv = ["check", str(scene)] if command == "check" else ["run", str(scene), "-o", str(out_dir)]
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"{scene}: {key}: "), lines[0]
    assert fragment in lines[0][len(f"{scene}: {key}: "):], lines[0]
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_errors_come_from_load_scene(tmp_path):
    """The table is built (and so checked) by load_scene itself, not first by a run."""
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "bad.toml", text=edit("duration_deg = 50", "duration_deg = 200"))
    assert info.value.key == "gas.wiebe.duration_deg"
    assert str(info.value).startswith(f"{tmp_path / 'bad.toml'}: gas.wiebe.duration_deg: ")


def test_two_stroke_needs_no_gas_exchange_pressures(tmp_path):
    """A 2-stroke is scavenged to p_a at exhaust opening: p_intake and p_exhaust are not needed,
    the firing TDC is at 0 and the combustion may start before it (-2° is 358°)."""
    text = (edit("strokes = 4", "strokes = 2").replace("p_intake_MPa = 0.165\n", "")
            .replace("p_exhaust_MPa = 0.182\n", "").replace("firing_deg = [360, 600, 120]",
                                                           "firing_deg = [0, 120, 240]"))
    scene = load_scene(tmp_path / "two.toml", text=text)
    full = gas_tables(scene)[0]
    assert full.strokes == 2 and full.period == pytest.approx(2 * math.pi)
    assert full.combustion_start == pytest.approx(358 * DEG)
    assert load_scene(tmp_path / "r.toml", text=to_toml(scene)) == scene


def test_wiebe_levels_is_cached_per_engine_and_cycle():
    scene = load_scene(WIEBE)
    before = wiebe_levels.cache_info().hits
    other = replace(scene, run=replace(scene.run, revolutions=3.0))
    assert gas_tables(other)[0] is gas_tables(scene)[0]
    assert wiebe_levels.cache_info().hits >= before + 2


def test_paired_table_on_different_knots():
    """Two curves with different knots and corners go onto the union of both, each re-expanded
    exactly; the compiled pair look-up agrees with each table's numpy evaluation."""
    from transient.assemble import paired_table
    from transient.core.model.tables import find_piece, table_eval, table_eval_pair
    from transient.forces.gas import table_from_points

    period = 4 * math.pi
    a = table_from_points(np.radians([0, 100, 180, 360, 360, 500, 720]),
                          np.array([1.0, 1.2, 1.5, 60.0, 40.0, 3.0, 1.0]) * 1e5, period,
                          corners=np.radians([180, 360]), interpolation="spline")
    b = table_from_points(np.radians([0, 90, 250, 360, 450, 720]),
                          np.array([1.1, 1.3, 4.0, 20.0, 5.0, 1.1]) * 1e5, period,
                          corners=np.radians([250]), interpolation="pchip")
    knots, coef, piece_knot = paired_table(a, b)
    assert coef.shape == (knots.size - 1, 8)
    np.testing.assert_allclose(knots[piece_knot], np.union1d(a.corners, b.corners), rtol=0,
                               atol=1e-15)
    assert set(np.round(a.knots, 12)) | set(np.round(b.knots, 12)) == set(np.round(knots, 12))
    rng = np.random.default_rng(6)
    x = rng.uniform(0, period, 2000)
    corners = knots[piece_knot]
    x = x[np.min(np.abs(x[:, None] - corners[None, :]), axis=1) > 1e-9]
    for xi in x:
        j = find_piece(knots, piece_knot, xi)
        first, second = table_eval_pair(knots, coef, piece_knot, j, xi)
        assert first == table_eval(knots, coef, piece_knot, j, xi)[0]
        assert first == pytest.approx(float(a(xi)), rel=1e-13, abs=1e-9)
        assert second == pytest.approx(float(b(xi)), rel=1e-13, abs=1e-9)
