"""The load diagrams' analysis (:mod:`transient.analysis.wear`, :mod:`transient.analysis.loads.diagrams`,
:func:`transient.analysis.irregularity.last_cycle_window`) against hand computations:

* wear rays on a few load vectors whose sums are written out by hand, and on the Gots 36-ray
  diagram of a load fixed in one direction (13 rays see it, the others none);
* the angle weights integrate a linear function exactly on any mesh (the trapezoidal rule), and
  agree with ``numpy.trapezoid`` on a smooth one;
* the last cycle's window on runs whose cycle marks fall on known samples, with φ0 ≠ 0 and after
  a reversal;
* the diagrams of the Gots engine on a synthetic constant-speed run: the crankpin's frame, the
  most loaded journal and both wear diagrams against a loop over rays and samples.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.irregularity import NoWholeCycle, last_cycle_window
from transient.analysis.loads.crank_slider import loads_from_trajectory, main_journal_loads
from transient.analysis.wear import WEAR_HALF_ARC_DEG, angle_weights, wear_rays

CASES = Path(__file__).resolve().parents[2] / "cases"


# ------------------------------------------------------------------------------------------------
# Wear rays


def test_wear_rays_by_hand():
    """Four rays (0°, 90°, 180°, 270°), ±60°: each load counted by the rays within 60° of it, a
    load exactly 60° from a ray (−60°) counted by it."""
    direction = np.radians([0.0, 45.0, 200.0, -60.0])
    magnitude = np.array([10.0, 4.0, 3.0, 5.0])
    weight = np.array([1.0, 2.0, 1.0, 0.5])
    rays, sums = wear_rays(direction, magnitude, weight, n_rays=4)
    np.testing.assert_array_equal(rays, [0.0, 90.0, 180.0, 270.0])
    # ray 0°: 10·1 (0°) + 4·2 (45°) + 5·0.5 (60° away); 90°: 4·2 (45° away); 180°: 3 (20° away);
    # 270°: 5·0.5 (30° away). 200° is 70° from 270°, 45° is 135° from 180°: not counted.
    np.testing.assert_allclose(sums, [20.5, 8.0, 3.0, 2.5], rtol=1e-15)


def test_wear_rays_wrap_around_and_arc():
    """A load at 350° wears rays 290° … 50° (through 0°), its ends included; a narrower arc
    takes fewer rays."""
    rays, sums = wear_rays(np.radians([350.0]), np.array([2.0]), np.array([1.0]), n_rays=36)
    expected = {290, 300, 310, 320, 330, 340, 350, 0, 10, 20, 30, 40, 50}
    np.testing.assert_array_equal(sums, [2.0 if int(r) in expected else 0.0 for r in rays])
    _, narrow = wear_rays(np.radians([350.0]), np.array([2.0]), np.array([1.0]), n_rays=36,
                          half_arc_deg=15.0)
    assert set(np.round(rays[narrow > 0]).astype(int)) == {340, 350, 0}


def test_gots_diagram_of_a_fixed_load():
    """36 rays (every 10°), a load of 7 kN at 10° on 50 equal steps: the 13 rays from −50° to 70°
    each sum 50 × 7 kN; with the default arc of ±60°."""
    assert WEAR_HALF_ARC_DEG == 60.0
    n = 50
    rays, sums = wear_rays(np.full(n, math.radians(10.0)), np.full(n, 7e3), np.ones(n))
    seen = [(r - 10.0 + 180.0) % 360.0 - 180.0 for r in rays]
    for r, s, d in zip(rays, sums, seen):
        assert s == pytest.approx(n * 7e3 if abs(d) <= 60.0 else 0.0, rel=1e-14), r
    assert np.count_nonzero(sums) == 13


# ------------------------------------------------------------------------------------------------
# Angle weights


def test_angle_weights_on_equal_steps():
    np.testing.assert_allclose(angle_weights(np.linspace(0.0, 2.0, 5)),
                               [0.5, 1.0, 1.0, 1.0, 0.5], rtol=1e-15)
    np.testing.assert_array_equal(angle_weights(np.array([3.0])), [1.0])


def test_angle_weights_integrate_a_line_exactly():
    """Σ w f · (mean step) is the trapezoidal rule: exact for f = 3φ + 2 on a random mesh, and
    the trapezoidal rule (numpy's) for a smooth f."""
    rng = np.random.default_rng(31)
    phi = np.sort(rng.uniform(1.0, 7.0, 200))
    phi[0], phi[-1] = 1.0, 7.0
    w = angle_weights(phi)
    assert w.sum() == pytest.approx(phi.size - 1, rel=1e-14)
    mean_step = (phi[-1] - phi[0]) / (phi.size - 1)
    exact = 1.5 * (7.0 ** 2 - 1.0 ** 2) + 2.0 * (7.0 - 1.0)
    assert np.sum(w * (3.0 * phi + 2.0)) * mean_step == pytest.approx(exact, rel=1e-13)
    f = np.sin(phi) * np.exp(0.1 * phi)
    assert np.sum(w * f) * mean_step == pytest.approx(np.trapezoid(f, phi), rel=1e-12)


def test_angle_weights_do_not_count_a_cluster_twice():
    """Extra samples close together (around a breakpoint) share the angle they stand for: a ray's
    sum times the mean step is the angle its load covers, 0.45 rad of load 1 toward 0° (samples
    0 … 0.4 and half the step beyond) with or without a cluster of samples inside it, while the
    unweighted count grows with the cluster."""
    equal = np.linspace(0.0, 1.0, 11)
    clustered = np.sort(np.concatenate([equal, [0.25 - 1e-6, 0.25, 0.25 + 1e-6]]))
    for phi in (equal, clustered):
        direction = np.where(phi < 0.45, 0.0, np.pi)
        mean_step = (phi[-1] - phi[0]) / (phi.size - 1)
        _, sums = wear_rays(direction, np.ones(phi.size), angle_weights(phi), n_rays=4)
        assert sums[0] * mean_step == pytest.approx(0.45, rel=1e-12)
        assert sums[2] * mean_step == pytest.approx(0.55, rel=1e-12)
        _, count = wear_rays(direction, np.ones(phi.size), np.ones(phi.size), n_rays=4)
        assert count[0] == (5 if phi is equal else 8)


# ------------------------------------------------------------------------------------------------
# The last whole cycle


CYCLE = 4.0 * math.pi


def _run(phi, omega=100.0):
    return phi / omega, phi


def test_last_cycle_window_marks_on_samples():
    """2.5 cycles at 8 steps per cycle from φ0 = 0: the last whole cycle is samples 8 … 16."""
    t, phi = _run(np.arange(21) * (CYCLE / 8))
    mask, start = last_cycle_window(t, phi, CYCLE, 0.0)
    np.testing.assert_array_equal(np.nonzero(mask)[0], np.arange(8, 17))
    assert start == pytest.approx(CYCLE, rel=1e-15)


def test_last_cycle_window_from_phi0():
    """Cycles counted from φ0 = 0.3 rad: the last whole one is [0.3 + Φ, 0.3 + 2Φ]."""
    t, phi = _run(np.linspace(0.0, 2.5 * CYCLE, 1001))
    mask, start = last_cycle_window(t, phi, CYCLE, 0.3)
    assert start == pytest.approx(0.3 + CYCLE, rel=1e-15)
    inside = (phi >= 0.3 + CYCLE) & (phi <= 0.3 + 2 * CYCLE)
    np.testing.assert_array_equal(mask, inside)


def test_last_cycle_window_after_a_reversal():
    """Up to 1.2 Φ, back to 0.9 Φ, up to 2.3 Φ: the window [Φ, 2Φ] holds only the samples after
    the backward motion, though the first pass crossed 1.0 … 1.2 Φ too."""
    phi = np.concatenate([np.linspace(0.0, 1.2, 121), np.linspace(1.19, 0.9, 30),
                          np.linspace(0.91, 2.3, 140)]) * CYCLE
    t = np.arange(phi.size) * 1e-3
    mask, start = last_cycle_window(t, phi, CYCLE, 0.0)
    assert start == pytest.approx(CYCLE, rel=1e-15)
    after = np.arange(phi.size) >= 151
    np.testing.assert_array_equal(mask, after & (phi >= CYCLE * (1 - 1e-9))
                                  & (phi <= 2 * CYCLE * (1 + 1e-9)))
    assert not mask[:151].any() and mask.sum() == 101


def test_no_whole_cycle():
    t, phi = _run(np.linspace(0.0, 0.9 * CYCLE, 50))
    with pytest.raises(NoWholeCycle, match="the run holds no whole cycle of 720°"):
        last_cycle_window(t, phi, CYCLE, 0.0)
    assert issubclass(NoWholeCycle, ValueError)


# ------------------------------------------------------------------------------------------------
# The diagrams of a crank-slider engine


def _wear_by_hand(direction, magnitude, weight, n_rays=36, half_arc=60.0):
    sums = []
    for i in range(n_rays):
        ray = i * 360.0 / n_rays
        total = 0.0
        for d, m, w in zip(direction, magnitude, weight):
            off = abs(math.degrees(d) - ray) % 360.0
            if min(off, 360.0 - off) <= half_arc + 1e-9:
                total += m * w
        sums.append(total)
    return np.array(sums)


@pytest.fixture(scope="module")
def gots():
    """The Gots diesel (3 cylinders in line) turning at 300 rad/s for 2.3 cycles, 4 samples per
    degree: the last whole cycle is [Φ, 2Φ]."""
    from transient.scene import load_scene

    scene = load_scene(CASES / "gots_diesel_4400.toml")
    phi = np.linspace(0.0, 2.3 * CYCLE, round(2.3 * 720 * 4) + 1)
    traj = {"t": phi / 300.0, "phi": phi, "omega": np.full_like(phi, 300.0),
            "epsilon": np.zeros_like(phi)}
    return scene, traj


def test_crank_slider_diagrams(gots):
    from transient.analysis.loads.diagrams import crank_slider_diagrams

    scene, traj = gots
    assert scene.mechanism.cycle == pytest.approx(CYCLE) and scene.initial.phi == 0.0
    d = crank_slider_diagrams(scene, traj, cylinder=2)
    phi = traj["phi"]
    mask = (phi >= CYCLE * (1 - 1e-12)) & (phi <= 2 * CYCLE * (1 + 1e-12))
    assert d.window.samples == mask.sum() == 720 * 4 + 1
    np.testing.assert_array_equal(d.window.columns["phi"], phi[mask])
    np.testing.assert_allclose(d.window.angle_deg, np.degrees(phi[mask] - CYCLE), atol=1e-9)
    # the forces of the whole run, cut afterwards: the window does not change them
    full = loads_from_trajectory(scene, traj)
    np.testing.assert_allclose(d.crankpin_x, full.R_T[1][mask], rtol=1e-13, atol=1e-9)
    np.testing.assert_allclose(d.crankpin_y, -full.R_K[1][mask], rtol=1e-13, atol=1e-9)
    np.testing.assert_allclose(d.engine_torque, full.torque.sum(axis=0)[mask], rtol=1e-12,
                               atol=1e-9)
    # equal steps: weights ½ at the ends, 1 inside
    w = np.ones(mask.sum())
    w[[0, -1]] = 0.5
    rays, sums = d.crankpin_wear
    np.testing.assert_allclose(sums, _wear_by_hand(np.arctan2(d.crankpin_y, d.crankpin_x),
                                                   full.R[1][mask], w), rtol=1e-12)
    # running torques and main journals, the most loaded one by its peak
    mj = main_journal_loads(scene.mechanism, full, traj["omega"], traj["epsilon"])
    peaks = [np.hypot(mj.x[j][mask], mj.y[j][mask]).max() for j in range(mj.x.shape[0])]
    assert d.most_loaded == int(np.argmax(peaks))
    j = d.most_loaded
    np.testing.assert_allclose(d.journal_x, mj.x[j][mask], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(d.journal_y, -mj.y[j][mask], rtol=1e-12, atol=1e-9)
    _, sums_j = d.journal_wear
    np.testing.assert_allclose(
        sums_j, _wear_by_hand(np.arctan2(-mj.y[j][mask], mj.x[j][mask]),
                              np.hypot(mj.x[j][mask], mj.y[j][mask]), w), rtol=1e-12)
    assert d.journal_torques.shape == (4, mask.sum())
    # the last journal carries every throw's torque
    np.testing.assert_allclose(d.journal_torques[-1], full.throw_torque.sum(axis=0)[mask],
                               rtol=1e-12, atol=1e-9)


def test_crank_slider_diagrams_of_a_v_engine(gots):
    """Bank angles that differ (a throw per cylinder): main journals and running torques too,
    the journals those of :func:`main_journal_loads` (``tests/unit/test_v_engines.py`` checks
    them against an independent computation)."""
    from transient.analysis.loads.diagrams import crank_slider_diagrams

    scene, traj = gots
    v = replace(scene, mechanism=replace(scene.mechanism, bank_angles=(0.0, 0.5, 0.0)))
    d = crank_slider_diagrams(v, traj, cylinder=1)
    mj = main_journal_loads(v.mechanism, d.loads, d.window.columns["omega"],
                            d.window.columns["epsilon"])
    np.testing.assert_array_equal(d.main_journals.x, mj.x)
    assert d.journal_torques.shape == (4, d.window.samples)
    assert d.crankpin_wear[1].shape == (36,) and d.journal_wear[1].shape == (36,)


def test_crank_slider_diagrams_refuse(gots):
    from transient.analysis.loads.diagrams import crank_slider_diagrams

    scene, traj = gots
    with pytest.raises(ValueError, match="cylinder must be 1 … 3, got 4"):
        crank_slider_diagrams(scene, traj, cylinder=4)
    short = {k: v[:100] for k, v in traj.items()}
    with pytest.raises(NoWholeCycle):
        crank_slider_diagrams(scene, short)
