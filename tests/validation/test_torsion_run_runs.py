"""The analyses of an elastic run (:mod:`transient.analysis.torsion_run`) on runs of the in-line
six of ``cases/inline6_damper.toml``, against what the run holds independently of them: the
heats of the damping parts against the stepper's own ``W_line_loss`` (the state it integrates at
its tolerance), the summary's last-cycle powers against that column's slope, and a run-up's order
amplitude against the critical speed of the modal analysis."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import transient
from transient.analysis.summary import summarize
from transient.analysis.torsion import critical_speeds, engine_orders, modal_analysis
from transient.analysis.torsion_run import line_losses, line_orders, order_peaks
from transient.shaft import ShaftLine

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"


@pytest.fixture(scope="module")
def dense():
    """Two cycles from 2600 rpm (near the first mode's sixth-order critical), sampled every
    0.5°."""
    scene = transient.load_scene(CASE).replace(
        initial={"omega_rpm": 2600}, run={"revolutions": 4}, output={"samples_per_rev": 720})
    return scene, transient.simulate(scene)


def test_the_heats_add_up_to_the_lines_loss(dense):
    """Σ of the parts' heats is W_line_loss to QUADRATURE of it at 0.5° samples, and the
    difference falls at least eightfold with samples twice as dense (the quadrature's error,
    not the run's): the parts are all the loss there is."""
    scene, res = dense
    line = ShaftLine(scene)
    tr = res.trajectory
    losses = line_losses(line, tr)
    assert set(losses.parts) >= {"damper silicone at pulley", "absolute at throw 1"}
    assert abs(losses.residual) <= 1e-6
    coarse = line_losses(line, {k: v[::2] for k, v in tr.items()})
    assert abs(losses.residual) <= abs(coarse.residual) / 8 + 10 * scene.solver.rtol
    # every part takes power, the damper most
    taken = losses.heat[:, -1]
    assert np.all(taken > 0.0)
    assert losses.parts[int(np.argmax(taken))] == "damper silicone at pulley"


def test_the_summary_holds_the_dampers_power_over_the_last_cycle(dense):
    """The summary's line loss over the last cycle is W_line_loss's slope over it, and the
    damper's power is the largest part of it."""
    scene, res = dense
    tr = res.trajectory
    summary = summarize(scene, tr, res.events)
    power, unit = summary["pulley_damper_power_last_cycle"]
    total, _ = summary["line_loss_power_last_cycle"]
    assert unit == "W" and 0.0 < power < total
    cycle = 4 * math.pi
    last = (tr["phi"] >= tr["phi"][-1] - cycle - 1e-9)
    t = tr["t"][last]
    slope = (tr["W_line_loss"][last][-1] - tr["W_line_loss"][last][0]) / (t[-1] - t[0])
    assert total == pytest.approx(slope, rel=1e-9)
    assert res.summary()["pulley_damper_power_last_cycle"] == pytest.approx(power, rel=1e-12)


def test_a_run_up_peaks_at_its_critical_speeds():
    """The six without its damper run up slowly (a constant load a little below the engine's
    torque) through the first mode's criticals of the orders 9, 7.5 and 6: each order's
    amplitude in the flywheel section's torque peaks within the mode's frozen band (as a speed
    of that order), widened by the run's sweep over one cycle below and, above, by that and the
    resonance's build-up over 1/(ζω_n) (ζ the damped mode's), and stands out of its track."""
    scene = transient.load_scene(CASE).replace(
        initial={"omega_rpm": 1500}, run={"revolutions": 130}, load={"fan": None, "torque": 370},
        shaft={"dampers": None})
    line = ShaftLine(scene)
    modal = modal_analysis(line)
    first = modal.modes[0]
    damped = min(modal.damped, key=lambda d: abs(d.omega_n / (2 * math.pi) - first.f))
    res = transient.simulate(scene)
    column = "torque_throw_6_flywheel"
    lo = line_orders(scene, res.trajectory, [column], 720)
    rpm = lo.omega_mean * 30 / math.pi
    orders = (9.0, 7.5, 6.0)
    criticals = [c for c in critical_speeds(modal, engine_orders(scene.mechanism.cycle, 12.0),
                                            (rpm[0], rpm[-1])) if c.mode == 1]
    for peak in order_peaks(lo, column, orders, criticals):
        assert peak.mode == 1
        band = 60.0 * np.array(first.band) / peak.order
        i = int(np.argmin(np.abs(rpm - peak.critical)))
        sweep = float(np.diff(rpm)[min(i, rpm.size - 2)])
        per_second = sweep / (lo.cycle_start[1] - lo.cycle_start[0]) * (peak.rpm * math.pi / 30)
        build_up = per_second / (damped.zeta * damped.omega_n)
        assert band[0] - sweep <= peak.rpm <= band[1] + sweep + build_up, (peak, band, sweep,
                                                                            build_up)
        assert peak.amplitude > 3 * np.median(lo.track(column, peak.order)), peak
