"""Loads from data ([load.table]) and the interpolation of tables: the scene keys, their
validation, the curves against independent constructions, and the compiled load against its numpy
twin.

* Parsing: each abscissa inline with its unit suffix and from a CSV file, in SI; the resolved
  TOML round trip; ``[load] torque`` of either sign; every validation error one line
  ``file: key: message`` with exit code 2 (``transient check``).
* Curves: linear through the points; pchip's interior slopes against Fritsch–Carlson's
  weighted harmonic mean written out here (Fritsch & Butland's form, the one scipy uses); the
  periodic curve over the cycle C¹ across the cycle's end; values held beyond a speed or time
  table; no overshoot on data with a corner, where a cubic spline overshoots.
* The model: the angle table's points are breakpoints, a time table's knots load corners with
  the schedule's scale there; :func:`transient.core.model.forcing.table_load` equals the numpy twin
  :meth:`LoadCurve.evaluate` to rounding, and M_load of ``moments`` is −s·T(x).
"""
from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from scene_texts import SMALL, check_text

from transient.assemble import build_model, load_table_curve
from transient.core.model import forcing
from transient.core.model.layout import (
    LT_ANGLE,
    LT_NONE,
    LT_SPEED,
    LT_TIME,
    N_SWITCHES,
    PHI,
    SW_LOAD_TABLE,
    T,
    extras_of,
)
from transient.core.model.work import work_array
from transient.forces.load_table import interpolant, load_curve
from transient.scene import LoadTable, load_scene, to_toml

RPM = math.pi / 30.0


def scene_of(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return load_scene(path)


def with_load(lines: str) -> str:
    return SMALL + "\n[load]\n" + lines + "\n"


# ------------------------------------------------------------------------------------------------
# Parsing


def test_inline_tables_are_read_in_si(tmp_path):
    speed = scene_of(tmp_path, with_load(
        "[load.table]\nspeed_rpm = [0, 1000, 2000]\ntorque = [0, 5, 20]\n"
        "interpolation = \"pchip\"")).load.table
    assert speed == LoadTable((0.0, 5.0, 20.0), speed=(0.0, 1000 * RPM, 2000 * RPM),
                              interpolation="pchip")
    angle = scene_of(tmp_path, with_load(
        "[load.table]\nphi_deg = [0, 360, 720]\ntorque = [1, -1, 1]")).load.table
    # (a point at the cycle's end repeating the one at 0 is dropped: the curve is periodic)
    assert angle == LoadTable((1.0, -1.0), phi=(0.0, 2.0 * math.pi))
    trace = scene_of(tmp_path, with_load("[load.table]\ntime = [0, 0.1]\ntorque = [2, 3]")).load
    assert trace.table == LoadTable((2.0, 3.0), time=(0.0, 0.1))


def test_csv_table_is_read_in_si(tmp_path):
    (tmp_path / "fan.csv").write_text("# a fan map\nspeed_rpm,torque\n0,0\n1000,5\n2000,20\n",
                                      encoding="utf-8")
    table = scene_of(tmp_path, with_load("[load.table]\nfile = \"fan.csv\"")).load.table
    assert table == LoadTable((0.0, 5.0, 20.0), speed=(0.0, 1000 * RPM, 2000 * RPM))
    (tmp_path / "valve.csv").write_text("phi_deg,torque\n0,1\n180,2\n", encoding="utf-8")
    table = scene_of(tmp_path, with_load("[load.table]\nfile = \"valve.csv\"\n"
                                         "interpolation = \"pchip\"")).load.table
    assert table == LoadTable((1.0, 2.0), phi=(0.0, math.pi), interpolation="pchip")


@pytest.mark.parametrize("lines", [
    "torque = -3.5",
    "torque = 2\n[load.table]\nspeed_rpm = [0, 1000, 2000]\ntorque = [0, 5, -20]\n"
    "interpolation = \"pchip\"",
    "[load.table]\nphi_deg = [0, 90, 400]\ntorque = [1, -1, 0.5]",
    "schedule_time = [0.05, 0.2]\nschedule_scale = [1, 0.5]\n"
    "[load.table]\ntime = [0, 0.1, 0.3]\ntorque = [2, 3, -1]",
])
def test_resolved_toml_round_trips(tmp_path, lines):
    scene = scene_of(tmp_path, with_load(lines))
    text = to_toml(scene)
    tomllib.loads(text)
    assert load_scene(tmp_path / "r.toml", text=text) == scene


ERRORS = [
    ("not-increasing", "[load.table]\nspeed_rpm = [0, 2000, 1000]\ntorque = [0, 1, 2]",
     "load.table.speed_rpm", "must increase strictly, but entry 3"),
    ("repeated", "[load.table]\ntime = [0, 1, 1]\ntorque = [0, 1, 2]",
     "load.table.time", "must increase strictly"),
    ("lengths", "[load.table]\ntime = [0, 1, 2]\ntorque = [0, 1]",
     "load.table.torque", "needs one value per entry of load.table.time; got 2 and 3"),
    ("one-point", "[load.table]\ntime = [0]\ntorque = [0]",
     "load.table.time", "needs at least 2 points, got 1"),
    ("no-abscissa", "[load.table]\ntorque = [0, 1]",
     "load.table.torque", "needs exactly one abscissa of 'speed', 'phi', 'time'"),
    ("two-abscissae", "[load.table]\ntime = [0, 1]\nspeed = [0, 1]\ntorque = [0, 1]",
     "load.table.time", "got 'speed' and 'time'"),
    ("not-finite", "[load.table]\ntime = [0, 1]\ntorque = [0, nan]",
     "load.table.torque", "must be a list of finite numbers"),
    ("interpolation", "[load.table]\ntime = [0, 1]\ntorque = [0, 1]\ninterpolation = \"spline\"",
     "load.table.interpolation", "allowed: 'linear', 'pchip'"),
    ("angle-beyond-cycle", "[load.table]\nphi_deg = [0, 800]\ntorque = [0, 1]",
     "load.table.phi_deg", "angles must lie within one cycle, 0 to 720°"),
    ("end-not-periodic", "[load.table]\nphi_deg = [0, 180, 720]\ntorque = [0, 1, 2]",
     "load.table.phi_deg", "is the point at 0° again; give it with the same torque"),
    ("time-with-revolutions", "schedule_revolutions = [1, 2]\nschedule_scale = [1, 0]\n"
     "[load.table]\ntime = [0, 1]\ntorque = [0, 1]",
     "load.table.time", "a load in time with a schedule in revolutions"),
    ("unit-suffix", "[load.table]\ntime_ms = [0, 1]\ntorque = [0, 1]",
     "load.table.time_ms", "unit suffix"),
    ("linear-negative", "linear = -1", "load.linear", "must be ≥ 0"),
]


@pytest.mark.parametrize("lines, key, fragment",
                         [pytest.param(t, k, f, id=i) for i, t, k, f in ERRORS])
def test_invalid_table_is_one_line_exit_2(tmp_path, capsys, lines, key, fragment):
    path, code, out, err = check_text(tmp_path, capsys, with_load(lines))
    assert code == 2 and out == "", err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith(f"{path}: {key}: "), err
    assert fragment in err, err


CSV_ERRORS = [
    ("speed_rpm,torque\n0,0\n1000,5\n900,20\n", "fan.csv, column speed_rpm: must increase"),
    ("speed_rpm,moment\n0,0\n1000,5\n", "needs an abscissa column (speed, speed_rpm, phi, "
                                        "phi_deg, time) and a torque column (torque)"),
    ("speed_rpm,torque\n0,0\n1000,inf\n", "line 3, column torque: 'inf' is not finite"),
    ("speed_rpm,torque\n0,0\n1000\n", "line 3 has 1 field(s)"),
]


@pytest.mark.parametrize("csv, fragment", CSV_ERRORS)
def test_invalid_csv_is_one_line_exit_2(tmp_path, capsys, csv, fragment):
    (tmp_path / "fan.csv").write_text(csv, encoding="utf-8")
    path, code, out, err = check_text(tmp_path, capsys, with_load("[load.table]\nfile = \"fan.csv\""))
    assert code == 2 and out == "", err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith(f"{path}: load.table.file: "), err
    assert fragment in err, err


def test_missing_csv_names_the_key(tmp_path, capsys):
    path, code, _, err = check_text(tmp_path, capsys, with_load("[load.table]\nfile = \"no.csv\""))
    assert code == 2 and err.startswith(f"{path}: load.table.file: no such file 'no.csv'"), err


# ------------------------------------------------------------------------------------------------
# Curves


def fritsch_butland_slopes(x, y):
    """Interior slopes of the monotone cubic, written out: 0 where the secants δ change sign or
    one is 0, else the weighted harmonic mean (w1 + w2)/(w1/δ₋ + w2/δ₊), w1 = 2h₊ + h₋,
    w2 = h₊ + 2h₋ (Fritsch & Butland 1984; scipy's PchipInterpolator)."""
    h, d = np.diff(x), np.diff(y) / np.diff(x)
    out = np.zeros(x.size - 2)
    for k in range(1, x.size - 1):
        dm, dp, hm, hp = d[k - 1], d[k], h[k - 1], h[k]
        if dm * dp > 0.0:
            w1, w2 = 2.0 * hp + hm, hp + 2.0 * hm
            out[k - 1] = (w1 + w2) / (w1 / dm + w2 / dp)
    return out


def test_linear_curve_is_the_broken_line():
    rng = np.random.default_rng(5)
    x = np.cumsum(rng.uniform(0.1, 1.0, 12))
    y = rng.normal(size=12)
    curve = load_curve("time", x, y, "linear")
    q = np.linspace(x[0], x[-1], 1001)
    assert np.max(np.abs(curve.evaluate(q) - np.interp(q, x, y))) <= 1e-13
    # beyond the ends the end values hold
    assert curve.evaluate(x[0] - 5.0) == y[0] and abs(curve.evaluate(x[-1] + 5.0) - y[-1]) < 1e-13


def test_pchip_slopes_are_fritsch_carlson():
    rng = np.random.default_rng(7)
    x = np.cumsum(rng.uniform(0.1, 1.0, 15))
    y = np.cumsum(rng.normal(size=15))
    curve = load_curve("speed", x, y, "pchip")
    slopes = curve.coef[1:, 1]  # the slope at each interior knot (the interval it starts)
    np.testing.assert_allclose(slopes, fritsch_butland_slopes(x, y), rtol=1e-12, atol=1e-14)
    # it passes through the points and is C¹
    assert np.max(np.abs(curve.coef[:, 0] - y[:-1])) <= 1e-14
    h = np.diff(x)
    c = curve.coef
    end_value = c[:, 0] + h * (c[:, 1] + h * (c[:, 2] + h * c[:, 3]))
    end_slope = c[:, 1] + h * (2.0 * c[:, 2] + 3.0 * h * c[:, 3])
    np.testing.assert_allclose(end_value, y[1:], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(end_slope[:-1], slopes, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("interpolation", ["linear", "pchip"])
def test_angle_curve_is_periodic(interpolation):
    """Over the cycle: through the points, continuous (pchip: C¹) across the cycle's end, one
    period later the same, and pchip's slopes those of the periodic data (every point interior)."""
    period = 4.0 * math.pi
    x = np.radians([0.0, 60.0, 200.0, 330.0, 500.0, 650.0])
    y = np.array([1.0, 3.0, -2.0, 0.5, 4.0, 2.0])
    curve = load_curve("angle", x, y, interpolation, period)
    np.testing.assert_allclose(curve.evaluate(x), y, rtol=0, atol=1e-13)
    np.testing.assert_allclose(curve.evaluate(x + 3 * period), y, rtol=0, atol=1e-12)
    eps = 1e-7
    left, right = curve.evaluate(period - eps), curve.evaluate(eps)
    assert abs(left - right) < 1e-5
    np.testing.assert_array_equal(curve.corners, x)
    if interpolation == "pchip":
        xe = np.concatenate([x[-1:] - period, x, x[:1] + period])
        ye = np.concatenate([y[-1:], y, y[:1]])
        slopes = fritsch_butland_slopes(xe, ye)  # at x[0] … x[-1]
        fd = (curve.evaluate(x + 1e-7) - curve.evaluate(x - 1e-7)) / 2e-7
        np.testing.assert_allclose(fd, slopes, rtol=1e-5, atol=1e-6)


def test_monotone_cubic_does_not_overshoot_a_corner():
    """A ramp into a plateau, [1000, 3000, 3000]: pchip stays within the data (no value above
    3000 nor below 1000), where the cubic spline through the same points overshoots to about
    3250 (the hazard the data carry)."""
    from scipy.interpolate import CubicSpline

    t, w = [0.0, 1.0, 2.0], [1000.0, 3000.0, 3000.0]
    q = np.linspace(0.0, 2.0, 20001)
    spline = CubicSpline(t, w)(q)
    assert spline.max() > 3200.0
    for kind in ("linear", "pchip"):
        v = interpolant(t, w, kind)(q)
        assert v.max() <= 3000.0 * (1 + 1e-15) and v.min() >= 1000.0 * (1 - 1e-15), kind


# ------------------------------------------------------------------------------------------------
# The model


def test_scene_without_table_has_none(tmp_path):
    model, _, _ = build_model(scene_of(tmp_path, with_load("torque = 1")))
    assert model.lt_kind == LT_NONE and load_table_curve(scene_of(tmp_path, SMALL)) is None


def test_angle_points_are_breakpoints(tmp_path):
    scene = scene_of(tmp_path, with_load("[load.table]\nphi_deg = [10, 95, 200, 300]\n"
                                         "torque = [1, 2, 0, 1]"))
    model, bp, _ = build_model(scene)
    assert model.lt_kind == LT_ANGLE
    np.testing.assert_allclose(bp, np.radians([10, 95, 200, 300]), rtol=0, atol=1e-15)
    assert not model.bp_jump.any()


def test_time_knots_are_load_corners_with_the_schedule_scale(tmp_path):
    scene = scene_of(tmp_path, with_load(
        "schedule_time = [0.05, 0.05, 0.25]\nschedule_scale = [1, 0.5, 0.1]\n"
        "[load.table]\ntime = [0, 0.05, 0.15, 0.3]\ntorque = [2, 3, -1, 0]"))
    model, _, _ = build_model(scene)
    assert model.lt_kind == LT_TIME and model.load_comp == T
    np.testing.assert_allclose(model.load_x, [0.0, 0.05, 0.05, 0.15, 0.25, 0.3])
    np.testing.assert_allclose(model.load_s, [1.0, 1.0, 0.5, 0.3, 0.1, 0.1], rtol=1e-14)
    alone = build_model(scene_of(tmp_path, with_load("[load.table]\ntime = [0, 0.1]\n"
                                                     "torque = [2, 3]")))[0]
    np.testing.assert_array_equal(alone.load_x, [0.0, 0.1])
    np.testing.assert_array_equal(alone.load_s, [1.0, 1.0])


@pytest.mark.parametrize("table, kind", [
    ("speed_rpm = [200, 900, 1400, 2500]\ntorque = [-1, 3, 2, 8]", LT_SPEED),
    ("phi_deg = [20, 140, 200, 310]\ntorque = [1, -2, 0.5, 3]", LT_ANGLE),
    ("time = [0.01, 0.05, 0.2]\ntorque = [4, -1, 2]", LT_TIME),
])
@pytest.mark.parametrize("interpolation", ["linear", "pchip"])
def test_kernel_equals_numpy_twin(tmp_path, table, kind, interpolation):
    scene = scene_of(tmp_path, with_load(f"torque = 0.5\n[load.table]\n{table}\n"
                                         f"interpolation = \"{interpolation}\""))
    model, _, _ = build_model(scene)
    curve = load_table_curve(scene)
    assert model.lt_kind == kind
    rng = np.random.default_rng(11)
    wk = work_array(model)
    sw = np.zeros(N_SWITCHES, dtype=np.int64)
    for _ in range(200):
        y = np.zeros(12)
        y[PHI] = rng.uniform(-30.0, 30.0)
        y[T] = rng.uniform(-0.05, 0.3)
        w = rng.uniform(-50.0, 300.0)
        x = {LT_SPEED: w, LT_ANGLE: y[PHI], LT_TIME: y[T]}[kind]
        expect = float(curve.evaluate(x))
        got = forcing.table_load(model, w, y)
        assert abs(got - expect) <= 1e-12 * max(1.0, abs(expect)), (x, got, expect)
        # M_load of the model in time mode (y[2] = ω): −(torque + T(x)), no schedule
        y[2] = w
        sw[SW_LOAD_TABLE] = forcing.speed_knot_segment(model, w, True)
        M_load = forcing.moments(model, extras_of(model), False, y, y[PHI], sw, wk, True)[4]
        assert abs(M_load + 0.5 + expect) <= 1e-12 * max(1.0, abs(expect))
