"""Runs with loads from data on the compiled path, against the analytic loads the tables sample.

The scene is the single cylinder of ``cases/coasting_single.toml`` with no gas, so that the only
work is the load's: the work–energy balance ½J(φ)ω²|end − ½J(φ₀)ω₀² = W_load closes to the
solver's accuracy, and W_load (integrated with the motion) agrees with a quadrature of
M_load·ω over the samples.

* **Fan law from a table** (M(ω) = −Kω², tabulated every Δω, from a speed on a knot): the steps
  end on the knots the speed crosses (``load_table_speed`` events); linear interpolation is within
  Δω²/8·max|f″| = KΔω²/4 of Kω² (de Boor, ch. II (2.5)); the monotone cubic's error is bounded by
  the Hermite form with the curve's own knot slopes, Σ over the interval's ends of
  (4Δω/27)·|slope error| (f⁗ = 0 for a quadratic), computed from the table here.
* **A cosine over the cycle** (M(φ) = A cos(2φ)·… tabulated every 10°), linear: within
  Δφ²/8·max|f″|.
* **A trace in time**, linear: the knots are ``load_schedule`` events (the stepper stops on each).
* **A constant driving torque** (``torque < 0``): W_load = −torque·(φ_end − φ₀) exactly, and the
  shaft speeds up by it.
* **Prescribed speed through [1000, 3000, 3000] rpm**: ω never exceeds 3000 rpm, with either
  interpolation.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import load_table_curve
from transient.run import integrate, prescribed
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0


def coasting(load: dict, revolutions=12, run=None):
    """The coasting single cylinder from 1000 rpm with ``load`` as its [load] table."""
    base = load_scene(CASES / "coasting_single.toml")
    return base.replace(load=load, run=run or {"revolutions": revolutions},
                        output={"samples_per_rev": 360})


def finished(scene):
    data = integrate(scene)
    assert data.complete, data.message
    return data


def energy_closes(scene, tr):
    """½J(φ)ω² at the ends against W_load (no gas, no starter), to the solver's accuracy; and
    W_load against the trapezoidal quadrature of M_load·ω dt (to the samples' resolution)."""
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    dK = K[-1] - K[0]
    W = tr["W_load"][-1]
    assert abs(dK - W) <= 1e-8 * abs(W), (dK, W)
    P = tr["M_load"] * tr["omega"]
    quad = np.sum(np.diff(tr["t"]) * (P[1:] + P[:-1]) / 2.0)
    assert abs(quad - W) <= 1e-4 * abs(W), (quad, W)


@pytest.mark.parametrize("interpolation", ["linear", "pchip"])
def test_fan_law_from_a_table(interpolation):
    K = 2e-4  # N m s²: about 2.2 N m at 1000 rpm
    dw = 100.0 * RPM
    w_knots = np.arange(0.0, 1200.0 * RPM + dw / 2, dw)
    scene = coasting({"table": {"speed": list(w_knots), "torque": list(K * w_knots ** 2),
                                "interpolation": interpolation}})
    data = finished(scene)
    tr = data.trajectory
    w = tr["omega"]
    assert w[-1] < 0.9 * w[0]  # the load slowed the shaft down
    # the steps end on the knots the speed crosses (state events; the start is on a knot)
    ev = data.events["load_table_speed"]
    w_at = np.interp(ev[:, 1], tr["phi"], w)
    assert len(ev) >= 4 and w_at.min() < 800.5 * RPM
    assert np.all(np.min(np.abs(np.subtract.outer(w_at, w_knots)), axis=1) <= 1e-3 * dw)
    curve = load_table_curve(scene)
    # the applied load is the table's curve, to rounding
    np.testing.assert_allclose(-tr["M_load"], curve.evaluate(w), rtol=1e-12, atol=1e-14)
    error = np.abs(-tr["M_load"] - K * w ** 2)
    if interpolation == "linear":
        bound = K * dw ** 2 / 4.0
    else:
        slope_error = np.abs(np.append(curve.coef[:, 1], np.nan) - 2.0 * K * w_knots)
        i = np.searchsorted(w_knots, w) - 1
        bound = 4.0 * dw / 27.0 * (slope_error[i] + slope_error[i + 1])
    assert np.all(error <= bound * (1 + 1e-9) + 1e-13), float(np.max(error / bound))
    assert np.max(error) > 0.1 * np.max(bound)  # the table's error, not the formula's
    energy_closes(scene, tr)


def test_cosine_over_the_cycle_from_a_table():
    A, period = 0.8, 4.0 * math.pi  # N m over the 4-stroke cycle, two waves per cycle
    dphi = math.radians(10.0)
    phi = np.arange(0.0, period - dphi / 2, dphi)
    f = 1.5 + A * np.cos(2 * 2 * math.pi * phi / period)
    scene = coasting({"table": {"phi": list(phi), "torque": list(f)}})
    tr = finished(scene).trajectory
    exact = 1.5 + A * np.cos(2 * 2 * math.pi * tr["phi"] / period)
    bound = dphi ** 2 / 8.0 * A * (4 * math.pi / period) ** 2
    error = np.abs(-tr["M_load"] - exact)
    assert np.all(error <= bound * (1 + 1e-9)), float(np.max(error / bound))
    assert np.max(error) > 0.3 * bound
    energy_closes(scene, tr)


def test_trace_in_time_stops_on_its_knots():
    knots = [0.0, 0.02, 0.05, 0.09, 0.14]
    torque = [0.5, 3.0, -1.0, 2.0, 1.0]
    scene = coasting({"table": {"time": knots, "torque": torque}}, revolutions=15)
    data = finished(scene)
    tr = data.trajectory
    np.testing.assert_allclose(-tr["M_load"], np.interp(tr["t"], knots, torque), rtol=0,
                               atol=1e-12)
    events = data.events["load_schedule"][:, 0]
    inside = [k for k in knots[1:] if k < tr["t"][-1]]
    assert len(inside) >= 3
    np.testing.assert_allclose(events, inside, rtol=0, atol=1e-12)
    energy_closes(scene, tr)


def test_constant_driving_torque():
    torque = -2.0  # N m, driving
    scene = coasting({"torque": torque})
    tr = finished(scene).trajectory
    dphi = tr["phi"][-1] - tr["phi"][0]
    assert abs(tr["W_load"][-1] - (-torque) * dphi) <= 1e-9 * abs(torque * dphi)
    assert np.all(tr["M_load"] == -torque) and tr["omega"][-1] > tr["omega"][0]
    energy_closes(scene, tr)


@pytest.mark.parametrize("interpolation", ["linear", "pchip"])
def test_prescribed_speed_with_a_corner_does_not_overshoot(interpolation):
    base = load_scene(CASES / "coasting_single.toml")
    scene = base.replace(run={"mode": "prescribed-speed", "time": [0.0, 0.1, 0.2],
                              "speed_table_rpm": [1000, 3000, 3000], "revolutions": 1000,
                              "interpolation": interpolation}, initial={"omega": 0.0})
    data = prescribed(scene)
    w = data.trajectory["omega"] / RPM
    assert w.max() <= 3000.0 * (1 + 1e-12) and w.min() >= 1000.0 * (1 - 1e-12)
    assert np.all(np.abs(w[data.trajectory["t"] >= 0.1] - 3000.0) <= 3000.0 * 1e-12)
    # the angle is the integral of the speed: for the linear ramp ½(1000 + 3000) rpm·0.1 s
    t, phi = data.trajectory["t"], data.trajectory["phi"]
    if interpolation == "linear":
        at = np.argmin(np.abs(t - 0.1))
        ramp = 1000.0 * RPM * t[at] + 0.5 * (2000.0 * RPM / 0.1) * t[at] ** 2
        assert abs(phi[at] - phi[0] - ramp) <= 1e-9 * ramp, (phi[at], ramp)


TABLES = {
    "speed-pchip": {"speed_rpm": [0, 400, 800, 1200], "torque": [0.0, 0.4, 1.5, 3.2],
                    "interpolation": "pchip"},
    "angle-linear": {"phi_deg": [0, 90, 250, 400, 600], "torque": [1.0, 2.5, -0.5, 1.5, 0.2]},
    "time-linear": {"time": [0.0, 0.03, 0.06, 0.1], "torque": [0.5, 2.0, 1.0, 3.0]},
}


@pytest.mark.parametrize("name", list(TABLES))
def test_compiled_agrees_with_reference(name):
    """The compiled path against the reference path (numpy model with the curve's numpy twin,
    solve_ivp DOP853 with max_step 0.5°; angle knots are its segment ends, time knots its terminal
    events, speed knots only bounded by the small steps), final state
    e = (y − y_ref)/(atol + rtol·|y_ref|) ≤ 100 as ``test_reference_path.py``."""
    tol = {"rtol": 1e-10, "atol": 1e-10}
    comp = coasting({"table": TABLES[name]}, revolutions=5)
    comp = comp.replace(solver=tol)
    ref = comp.replace(solver={**tol, "method": "scipy-DOP853", "max_step_deg": 0.5})
    c, r = finished(comp).trajectory, finished(ref).trajectory
    assert c["phi"][-1] == pytest.approx(r["phi"][-1], rel=1e-15)
    for key in ("t", "omega"):
        e = (c[key][-1] - r[key][-1]) / (1e-10 + 1e-10 * abs(r[key][-1]))
        print(f"{name}: final e({key}) = {e:.3g}")
        assert abs(e) <= 100.0, (key, e)
    assert r["omega"][-1] < 0.99 * r["omega"][0]  # (the load did work)


def test_prescribed_speed_applies_the_table():
    """Inverse dynamics at a prescribed speed: M_load = −T(ω) at every sample."""
    base = load_scene(CASES / "coasting_single.toml")
    scene = base.replace(run={"mode": "prescribed-speed", "time": [0.0, 0.2],
                              "speed_table_rpm": [300, 1500], "revolutions": 1000},
                         load={"table": TABLES["speed-pchip"]}, initial={"omega": 0.0})
    tr = prescribed(scene).trajectory
    curve = load_table_curve(scene)
    np.testing.assert_allclose(tr["M_load"], -curve.evaluate(tr["omega"]), rtol=1e-13,
                               atol=1e-15)


def test_water_brake_case_reads_its_map_and_settles_where_the_map_meets_the_engine():
    """``cases/gots_diesel_water_brake.toml``: the absorber's torque read from its CSV. At every
    sample the load is minus the map interpolated linearly at ω (``numpy.interp`` on the CSV
    read here, not the kernels), the work–energy balance closes, and the steady speed is where
    the map's torque equals the engine's mean torque over the last cycle: within 0.1 %, as the
    speed swings by δ ≈ 2 % within a cycle, so the mean load is not exactly the map at the mean
    speed."""
    from transient import simulate

    scene = load_scene(CASES / "gots_diesel_water_brake.toml").replace(
        run={"revolutions": 240})
    lines = [x for x in (CASES / "water_brake_map.csv").read_text().splitlines()
             if not x.startswith("#")]
    assert lines[0] == "speed_rpm,torque"
    rpm, torque = np.loadtxt(lines[1:], delimiter=",", unpack=True)
    df = simulate(scene).to_dataframe()
    w, load = df["omega"].to_numpy(), df["M_load"].to_numpy()
    np.testing.assert_allclose(load, -np.interp(w / RPM, rpm, torque), rtol=1e-12, atol=1e-9)
    J = df["J"].to_numpy()
    kinetic = 0.5 * J * w ** 2
    balance = kinetic - kinetic[0] - (df["W_gas"] + df["W_load"]).to_numpy()
    assert np.max(np.abs(balance)) < 1e-8 * df["W_gas"].iloc[-1]
    cycle = scene.mechanism.cycle
    phi = df["phi"].to_numpy()
    last = phi >= phi[-1] - cycle
    gas_mean = (df["W_gas"].iloc[-1] - np.interp(phi[-1] - cycle, phi, df["W_gas"])) / cycle
    mean_speed = (phi[-1] - phi[last][0]) / (df["t"].iloc[-1] - df["t"][last].iloc[0])
    assert np.interp(mean_speed / RPM, rpm, torque) == pytest.approx(gas_mean, rel=1e-3)
