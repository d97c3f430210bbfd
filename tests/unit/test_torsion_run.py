"""The analyses of an elastic run's columns (:mod:`transient.analysis.torsion_run`) on synthetic
runs whose answers are known in closed form: the mean power c·ω²·A²/2 of a damper under a
sinusoidal relative motion, the integral of a known power, the compiled stepper's own loss rate
(the kernel the run integrates into W_line_loss) for the sum of the parts, twists and torques of
known orders on a run-up, and the peak of a resonance curve."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.torsion import Critical
from transient.analysis.torsion_run import (
    campbell_overlay,
    cumulative_heat,
    cycle_mean_power,
    damper_power_summary,
    line_cycles,
    line_elements,
    line_orders,
    line_powers,
    order_peaks,
    torque_column,
)
from transient.core.model import shaft as kernels
from transient.scene import load_scene
from transient.scene.outputs import column_name
from transient.shaft import ShaftLine

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"
SCENE = load_scene(CASE)
LINE = ShaftLine(SCENE)
NAMES = [column_name(n) for n in LINE.names]
CYCLE = 4.0 * math.pi


def _steady(omega: float, cycles: int, per_rev: int = 720):
    """Samples of a steady rotation at ``omega`` [rad/s] over ``cycles`` cycles, every
    360°/``per_rev``: t, φ and every dof's speed ω."""
    phi = np.linspace(0.0, cycles * CYCLE, 2 * cycles * per_rev + 1)
    t = phi / omega
    traj = {"t": t, "phi": phi, "omega": np.full(phi.size, omega)}
    traj.update({f"omega_{n}": np.full(phi.size, omega) for n in NAMES})
    return traj


def test_a_damper_under_a_sinusoidal_relative_motion_takes_c_omega2_A2_over_2():
    """The hub oscillating against the ring by δ = A sin(ω_v t), ω_v = 4.5 Ω (nine periods a
    cycle): the silicone's mean power over each cycle is c·ω_v²·A²/2 (c = 25 N m s/rad, the
    scene's), the summary's last-cycle figure too; the whole line's, from W_line_loss given
    in closed form, is the sum of the damper's, the first section's and the absolute
    damping's, each c·ω_v²·A²/2 with its own share of the motion."""
    Omega, A = 200.0, 1e-3
    w_v = 4.5 * Omega
    traj = _steady(Omega, 3)
    t = traj["t"]
    traj["omega_pulley"] = Omega + A * w_v * np.cos(w_v * t)
    c_damper = 25.0
    # the section pulley–throw 1: its damping ratio ζ = 0.01 at the first mode, c = 2ζk/ω₁
    c_section = 2 * 0.01 * 1.5e6 / LINE.omega_1
    # absolute damping of the throws (0.5 each), on their motion against ω̄, which the
    # pulley's share w_p/Σw of the inertia moves: each throw lags ω̄ by (w_p/Σw)·δ̇
    share = LINE.weights[NAMES.index("pulley")] / LINE.weights.sum()
    c_absolute = 6 * 0.5 * share ** 2
    c_all = c_damper + c_section + c_absolute
    traj["W_line_loss"] = c_all * A ** 2 * w_v ** 2 * (t / 2 + np.sin(2 * w_v * t) / (4 * w_v))

    powers = line_powers(LINE, traj)
    assert set(powers) == {"damper silicone at pulley", *(e.label for e in line_elements(LINE)
                                                          if e.kind == "section"),
                           *(f"absolute at throw {k}" for k in range(1, 7))}
    for k in range(2, 8):  # (the throws turn together: no power in the sections between them)
        label = next(p for p in powers if p.startswith(f"section {k} "))
        assert np.all(powers[label] == 0.0)
    speeds, mean = cycle_mean_power(SCENE, traj, powers["damper silicone at pulley"])
    np.testing.assert_allclose(speeds, Omega, rtol=1e-12)
    np.testing.assert_allclose(mean, c_damper * w_v ** 2 * A ** 2 / 2, rtol=1e-9)
    _, section = cycle_mean_power(SCENE, traj, powers["section 1 (pulley–throw 1)"])
    np.testing.assert_allclose(section, c_section * w_v ** 2 * A ** 2 / 2, rtol=1e-9)
    summary = damper_power_summary(SCENE, traj)
    assert set(summary) == {"pulley_damper_power_last_cycle", "line_loss_power_last_cycle"}
    assert summary["pulley_damper_power_last_cycle"] == (pytest.approx(
        c_damper * w_v ** 2 * A ** 2 / 2, rel=1e-9), "W")
    assert summary["line_loss_power_last_cycle"][0] == pytest.approx(
        c_all * w_v ** 2 * A ** 2 / 2, rel=1e-9)


def test_the_parts_add_up_to_the_loss_rate_the_stepper_integrates():
    """At random speeds of every dof, Σ of the parts' powers is what the compiled kernel
    :func:`transient.core.model.shaft.line_torques` returns as the power the line takes (the
    rate of W_line_loss in the run)."""
    rng = np.random.default_rng(7)
    rows = LINE.element_rows()
    absolute, gear = LINE.absolute, np.ones(LINE.n)
    for _ in range(5):
        omega = 300.0 + rng.normal(0.0, 3.0, LINE.n)
        theta = rng.normal(0.0, 1e-3, LINE.n)
        taken = kernels.line_torques(rows, absolute, LINE.weights, gear, theta, omega,
                                     np.zeros(LINE.n))
        traj = {f"omega_{n}": np.array([w]) for n, w in zip(NAMES, omega)}
        total = sum(float(p[0]) for p in line_powers(LINE, traj).values())
        assert total == pytest.approx(taken, rel=1e-12)


def test_the_heat_integrates_a_known_power_and_a_repeated_sample_adds_nothing():
    """Q(t) of P = 1 + sin²(ωt) on an uneven grid (spaced as a run-up's samples in time)
    against 3t/2 − sin(2ωt)/(4ω), converging at fourth order as the grid is refined; a
    sample written twice (an event's) changes nothing."""
    w = 50.0
    exact = lambda t: 1.5 * t - np.sin(2 * w * t) / (4 * w)
    errors = []
    for n in (200, 400, 800):
        s = np.linspace(0.0, 1.0, n + 1)
        t = (s + 0.5 * s ** 2) / 1.5
        q = cumulative_heat(t, 1.0 + np.sin(w * t) ** 2)
        errors.append(np.max(np.abs(q - exact(t))))
        repeated = np.insert(t, 50, t[50])
        q2 = cumulative_heat(repeated, 1.0 + np.sin(w * repeated) ** 2)
        assert q2[50] == q2[51]
        np.testing.assert_allclose(np.delete(q2, 50), q, rtol=0, atol=2 * errors[-1])
    assert errors[1] < errors[0] / 12 and errors[2] < errors[1] / 12
    assert errors[-1] < 1e-6
    with pytest.raises(ValueError, match="non-decreasing"):
        cumulative_heat(np.array([0.0, 2.0, 1.0]), np.ones(3))


def _run_up(per_rev: int = 360, cycles: int = 12):
    """A run-up of the line's reference at ε = const from 150 to about 400 rad/s, sampled
    uniformly in angle: t, φ, ω, ε and every dof's speed (all ω but where a test sets it)."""
    w0, eps = 150.0, 700.0
    phi = np.linspace(0.0, cycles * CYCLE, 2 * cycles * per_rev + 1)
    omega = np.sqrt(w0 ** 2 + 2 * eps * phi)
    t = (omega - w0) / eps
    traj = {"t": t, "phi": phi, "omega": omega, "epsilon": np.full(phi.size, eps)}
    traj.update({f"omega_{n}": omega.copy() for n in NAMES})
    return traj


def test_the_orders_of_a_twist_on_a_run_up_are_its_known_orders():
    """A twist θ_d − φ = a·cos(4.5φ) + b·sin(6φ + 0.3) + m(φ) with a mean m growing along the
    run, sampled 250 times a revolution (off the grid: interpolated, with the derivative its
    speed column gives, ω_d = ω·(1 + dq/dφ)): each cycle's order 4.5 is a and order 6 is b, the
    ramp keeps the mean's trend out of them, and order 3 (absent) stays below 1e-6 of them."""
    traj = _run_up(per_rev=250)
    phi, omega = traj["phi"], traj["omega"]
    a, b, slope = 1e-3, 5e-4, 2e-3 / 75.0
    q = a * np.cos(4.5 * phi) + b * np.sin(6 * phi + 0.3) + slope * phi
    dq = -4.5 * a * np.sin(4.5 * phi) + 6 * b * np.cos(6 * phi + 0.3) + slope
    traj["twist_throw_6"] = q
    traj["omega_throw_6"] = omega * (1.0 + dq)
    lo = line_orders(SCENE, traj, ["twist_throw_6"], 720, detrend="ramp")
    assert lo.cycle_start.size == 12 and lo.detrend == "ramp"
    np.testing.assert_allclose(lo.track("twist_throw_6", 4.5), a, rtol=1e-6)
    np.testing.assert_allclose(lo.track("twist_throw_6", 6.0), b, rtol=1e-6)
    assert np.all(lo.track("twist_throw_6", 3.0) < 1e-6 * b)
    # without the ramp the trend leaks into every order, as slope·Φ/(πk) (k = 2q)
    raw = line_orders(SCENE, traj, ["twist_throw_6"], 720, detrend="none")
    np.testing.assert_allclose(raw.track("twist_throw_6", 3.0), slope * CYCLE / (6 * math.pi),
                               rtol=1e-2)
    # each cycle's mean speed, as the overlay draws it at (n, q·n/60)
    speeds, qs, amp = campbell_overlay(lo, "twist_throw_6", [4.5, 6.0])
    tb = np.interp(CYCLE * np.arange(13), phi, traj["t"])
    np.testing.assert_allclose(speeds, CYCLE / np.diff(tb) * 30 / math.pi, rtol=1e-9)
    assert amp.shape == (12, 2) and np.array_equal(qs, [4.5, 6.0])
    np.testing.assert_array_equal(amp[:, 1], lo.track("twist_throw_6", 6.0))


def test_an_elements_torque_cycle_by_cycle_and_its_vibratory_part():
    """A torque T = M + s·φ + B cos(6φ) sampled 250 times a revolution: on the grid of 720
    points a cycle, each cycle's mean, peak-to-peak and vibratory part (T less the mean) are
    those of the function itself on that grid (the grid's mean of the cosine is 0)."""
    traj = _run_up(per_rev=250, cycles=4)
    phi = traj["phi"]
    M, s, B = 300.0, 4.0, 120.0
    exact = lambda x: M + s * x + B * np.cos(6 * x)
    column = "torque_throw_6_flywheel"
    traj[column] = exact(phi)
    lc = line_cycles(SCENE, traj, [column], 720)
    i = lc.index(column)
    grid = lc.cycle_start[:, None] + CYCLE / 720 * np.arange(720)[None, :]
    np.testing.assert_allclose(lc.cycle_start, CYCLE * np.arange(4), rtol=0, atol=1e-12)
    # (the spline's error: (5/384)·h⁴·6⁴·B = 7e-6·B at most, at 250 samples a revolution)
    np.testing.assert_allclose(lc.mean[i], M + s * grid.mean(axis=1), rtol=0, atol=1e-5 * B)
    np.testing.assert_allclose(lc.peak_to_peak[i], np.ptp(exact(grid), axis=1), rtol=1e-5)
    vibratory = exact(grid) - exact(grid).mean(axis=1)[:, None]
    np.testing.assert_allclose(lc.vibratory[i], vibratory, rtol=0, atol=1e-5 * B)
    with pytest.raises(KeyError, match="not among"):
        lc.index("torque_pulley_throw_1")


def test_the_order_peak_is_where_the_resonance_curve_peaks_with_its_nearest_critical():
    """Order 6 of a torque shaped as a resonance over the speed: the peak found is in the cycle
    whose mean speed is nearest the resonance's, paired with the order's critical nearest to
    it (not the other order's, nor the farther one); an order without a critical has none."""
    traj = _run_up(per_rev=360, cycles=20)
    phi = traj["phi"]
    rpm = traj["omega"] * 30 / math.pi
    resonance = 3300.0
    column = "torque_throw_6_flywheel"
    traj[column] = 100.0 / np.hypot(1 - (rpm / resonance) ** 2, 0.05) * np.cos(6 * phi)
    lo = line_orders(SCENE, traj, [column], 720, detrend="none")
    mean_rpm = lo.omega_mean * 30 / math.pi
    assert mean_rpm.min() < resonance < mean_rpm.max()
    criticals = [Critical(1, 6.0, "major", 3250.0, 1.0), Critical(2, 6.0, "major", 9000.0, 1.0),
                 Critical(1, 4.5, "half", 3300.0, 0.5)]
    (peak,) = order_peaks(lo, column, [6.0], criticals)
    assert peak.rpm == mean_rpm[np.argmin(np.abs(mean_rpm - resonance))]
    assert (peak.critical, peak.mode) == (3250.0, 1)
    (none,) = order_peaks(lo, column, [3.0], criticals)
    assert math.isnan(none.critical) and none.mode == 0


def test_the_elements_are_the_runs_torque_columns():
    """The elements in the order of the run's torque columns (the scene's
    ``line_elements``), with their stiffness and damping as the line's K and C hold them."""
    names = [f"torque_{column_name(a)}_{column_name(b)}" for a, b in SCENE.shaft.line_elements()]
    elements = line_elements(LINE)
    assert [e.torque for e in elements] == names
    assert [e.kind for e in elements] == ["section"] * 7 + ["damper"]
    damper = elements[-1]
    assert (damper.k, damper.c) == (0.0, 25.0)
    assert damper.omega_a == "omega_pulley" and damper.omega_b == "omega_pulley_damper"
    C = np.zeros((LINE.n, LINE.n))
    for e in elements:
        a, b = NAMES.index(e.omega_a[6:]), NAMES.index(e.omega_b[6:])
        C[np.ix_([a, b], [a, b])] += e.c * np.array([[1, -1], [-1, 1]])
    P = np.eye(LINE.n) - np.outer(np.ones(LINE.n), LINE.weights) / LINE.weights.sum()
    np.testing.assert_allclose(C + P.T @ np.diag(LINE.absolute) @ P, LINE.C, rtol=1e-12,
                               atol=1e-12)
    assert torque_column(LINE, "section 7 (throw 6–flywheel)") == "torque_throw_6_flywheel"
    with pytest.raises(KeyError):
        torque_column(LINE, "section 9")
