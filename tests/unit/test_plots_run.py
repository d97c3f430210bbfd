"""The plot helpers of a run draw what they say: the colour-map waterfall holds each cycle's
amplitudes (clipped at four decades below the largest), the Campbell chart puts order ν at
frequency ν·n/60, the speed figure's δ is the summary's δ of the last cycle, and the cylinders'
torque curves add up to the gas torque drawn beside them. Runs in memory of the Gots friction
case (its kernel is shared with the thermodynamics tests)."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest

from transient import plots, simulate
from transient.analysis.irregularity import cycle_boundaries, fluctuation
from transient.scene import Initial, Output, Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_waterfall_and_campbell_hold_the_amplitudes():
    rng = np.random.default_rng(36)
    orders = np.arange(25) * 0.5
    amp = 10.0 ** rng.uniform(-7.0, 0.0, size=(5, orders.size))
    rpm = np.array([1000.0, 1500.0, 2000.0, 2500.0, 3000.0])
    fig, (a, b) = plt.subplots(1, 2)
    mesh = plots.order_waterfall(a, rpm, orders, amp, max_order=8.0)
    shown = (orders > 0) & (orders <= 8.0)
    top = amp[:, shown].max()
    assert np.asarray(mesh.get_array()).reshape(5, -1) == pytest.approx(
        np.maximum(amp[:, shown], 1e-4 * top), rel=1e-15)
    dots = plots.campbell(b, rpm, orders, amp, max_order=8.0)
    xy = dots.get_offsets()
    kept = amp[:, shown] >= 1e-4 * top
    speed = np.repeat(rpm[:, None], shown.sum(), axis=1)[kept]
    freq = (rpm[:, None] * orders[shown][None, :] / 60.0)[kept]
    assert np.asarray(xy[:, 0]) == pytest.approx(speed)
    assert np.asarray(xy[:, 1]) == pytest.approx(freq)
    plt.close(fig)


@pytest.fixture(scope="module")
def result():
    base = load_scene(CASES / "gots_diesel_friction.toml")
    scene = replace(base, initial=Initial(phi=0.0, omega=3900 * math.pi / 30),
                    run=Run(revolutions=6.0), output=Output(samples_per_rev=360))
    return scene, simulate(scene)


def test_speed_over_cycle_marks_the_summarys_delta(result):
    scene, res = result
    tr = res.trajectory
    fig, ax = plt.subplots()
    artists = plots.speed_over_cycle(ax, res, scene)
    marks = next(a for a in artists if a.get_label().startswith("δ"))
    delta = fluctuation(tr["t"], tr["phi"], tr["omega"], scene.mechanism.cycle, scene.initial.phi)
    assert marks.get_label().startswith(f"δ = {delta:.4g} ")
    # the marks are the last whole cycle's extremes (its samples; the run ends on its end)
    _, ends = cycle_boundaries(tr["t"], tr["phi"], scene.mechanism.cycle, scene.initial.phi)
    inside = (tr["phi"] >= ends[-2]) & (tr["phi"] <= ends[-1])
    np.testing.assert_allclose(marks.get_ydata(), [tr["omega"][inside].max() * 30.0 / math.pi,
                                                   tr["omega"][inside].min() * 30.0 / math.pi],
                               rtol=1e-15)
    plt.close(fig)


def test_cylinder_torque_curves_add_up_to_the_gas_torque(result):
    scene, res = result
    fig, ax = plt.subplots()
    lines = plots.cylinder_torque_curves(ax, res, scene)
    *cylinders, total = lines
    assert len(cylinders) == 3
    summed = sum(line.get_ydata() for line in cylinders)
    assert total.get_ydata() == pytest.approx(summed, rel=1e-15)
    sel = plots.last_cycle(res, scene.mechanism.cycle)
    gas = res.trajectory["M_gas"][sel]
    assert np.max(np.abs(summed - gas)) <= 1e-12 * np.max(np.abs(gas))
    with pytest.raises(ValueError, match="cylinder 4 is out of range"):
        plots.run_indicator_pv(ax, res, scene, cylinders=[4])
    plt.close(fig)
