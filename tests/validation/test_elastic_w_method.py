"""The elastic shaft line run by the Rosenbrock–W method (``solver.method = "ros34pw2"``,
:mod:`transient.core.integrator.rosenbrock` with the line's Jacobian,
:mod:`transient.core.model.line_jacobian`), against what is independent of it: DOP853's run of
the same scene at a tolerance 100 times tighter, the energy balance (T4) written out from the
output columns (``elastic_checks.line_balance``, numpy), the sample grid and the switch from time
to crank angle where DOP853 puts them; and, on the same line with a stiff front end, the hint an
explicit run gives where stability holds its step."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from elastic_checks import line_balance
from test_elastic_runs import _case

import transient
from transient.errors import SceneError
from transient.scene import load_scene
from transient.scene.checks import check_consistency


def _with(scene, **solver):
    return dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, **solver))


def _stiff_front(scene, factor: float = 33.1):
    """The pulley's section ``factor`` times as stiff: the highest mode rises (the hub on its
    section), the others hardly move; 33.1 puts f_max/f_1 at 40 (``tools/shaft_w_method.py``
    finds the factor)."""
    sections = (dataclasses.replace(scene.shaft.sections[0],
                                    stiffness=factor * scene.shaft.sections[0].stiffness),
                *scene.shaft.sections[1:])
    return dataclasses.replace(scene, shaft=dataclasses.replace(scene.shaft, sections=sections))


@pytest.fixture(scope="module")
def runs():
    """Two cycles from 800 rpm by the W-method at rtol 1e-7, and by DOP853 at 1e-9."""
    scene = _with(_case(rtol=1e-7), method="ros34pw2")
    tight = _with(_case(rtol=1e-9), method="dop853")
    return scene, transient.simulate(scene), transient.simulate(tight)


def test_the_w_method_follows_dop853(runs):
    """On the same sample grid (the angle grid's samples land where DOP853's do), the
    reference's ω within 30·rtol of its largest and a section's torque within 1000·rtol of its
    largest (as for DOP853 against the reference path: a twist's error times k)."""
    scene, res, tight = runs
    a, b = res.trajectory, tight.trajectory
    assert res.solver["method"] == "ros34pw2" and res.status == "finished"
    np.testing.assert_allclose(a["phi"], b["phi"], rtol=1e-12)
    rtol = scene.solver.rtol
    assert np.max(np.abs(a["omega"] - b["omega"])) <= 30 * rtol * np.max(b["omega"])
    torque = b["torque_throw_3_throw_4"]
    assert np.max(np.abs(a["torque_throw_3_throw_4"] - torque)) <= 1000 * rtol * np.max(
        np.abs(torque))
    assert "stability_hint" not in tight.solver  # (at 1e-9 DOP853 is held by accuracy)


def test_the_energy_balance_holds_with_the_w_method(runs):
    """(T4) within 1e2·rtol of the gas work at every sample, as for DOP853."""
    scene, res, _ = runs
    tr = res.trajectory
    balance, energy = line_balance(scene, tr)
    np.testing.assert_allclose(tr["E_line"], energy, rtol=1e-12)
    assert tr["W_line_loss"][-1] > 0.0 and np.all(np.diff(tr["W_line_loss"]) >= 0.0)
    assert np.max(np.abs(balance)) <= 1e2 * scene.solver.rtol * np.max(np.abs(tr["W_gas"]))


def test_a_start_from_rest_switches_to_crank_angle_where_dop853_does():
    """From rest on a starter: in time the Jacobian is the time form's (T12); the switch to crank
    angle (a speed event located on the cubic Hermite dense output) at DOP853's instant to the
    tolerance, and the balance across it."""
    sc = _case(revolutions=2.0, rtol=1e-8)
    scene = dataclasses.replace(
        sc, initial=dataclasses.replace(sc.initial, omega=0.0),
        starter=dataclasses.replace(sc.starter, torque=300.0, noload_speed=20 * math.pi,
                                    cutout_speed=40 * math.pi / 3))
    w = transient.simulate(_with(scene, method="ros34pw2"))
    d = transient.simulate(_with(scene, rtol=1e-10, atol=1e-12))
    tw = w.events["to_angle_domain"]["t"]
    td = d.events["to_angle_domain"]["t"]
    assert tw.size == td.size >= 1
    # (the event's time: the speed's error over the run from rest, relative, times its time)
    assert np.max(np.abs(tw - td)) <= 10 * scene.solver.rtol * td[-1]
    balance, _ = line_balance(scene, w.trajectory)
    assert np.max(np.abs(balance)) <= 1e2 * scene.solver.rtol * np.max(
        np.abs(w.trajectory["W_gas"]))


def test_a_stiff_front_end_holds_dop853_by_stability_and_says_so():
    """The pulley's section 33 times as stiff (f_max/f_1 = 40): at rtol 1e-6 most of DOP853's
    steps are held by stability (the stiffness test counts them and the result says so), the
    W-method's are not: it needs fewer evaluations of the derivative for the run, and agrees
    with DOP853; ``"auto"``, having tried both from where the test fired, hands the run over to
    it and lands its samples on the same grid."""
    scene = _stiff_front(_case(revolutions=4.0, rtol=1e-6))
    d = transient.simulate(scene)
    w = transient.simulate(_with(scene, method="ros34pw2"))
    assert '"auto"' in d.solver.get("stability_hint", "")
    assert "stability_hint" not in w.solver
    assert w.solver["nfev"] < d.solver["nfev"]
    a, b = w.trajectory, d.trajectory
    assert np.max(np.abs(a["omega"] - b["omega"])) <= 100 * 1e-6 * np.max(b["omega"])
    auto = transient.simulate(_with(scene, method="auto"))
    assert auto.solver["ran"].startswith("dop853, then ros34pw2 from t = ")
    assert auto.status == "finished" and "stability_hint" not in auto.solver
    np.testing.assert_allclose(auto.trajectory["phi"], b["phi"], rtol=1e-12)
    assert np.max(np.abs(auto.trajectory["omega"] - b["omega"])) <= 100 * 1e-6 * np.max(
        b["omega"])


def test_auto_keeps_dop853_where_the_w_method_does_not_pay():
    """The case's own line at rtol 1e-6: DOP853's stiffness test fires on some steps, the
    W-method's trial advances less per evaluation (it must resolve the first mode at order
    3) than DOP853's from the same state, and DOP853 runs on; its result is DOP853's to the
    tolerance."""
    scene = _case(revolutions=4.0, rtol=1e-6)
    d = transient.simulate(scene)
    auto = transient.simulate(_with(scene, method="auto"))
    assert auto.solver["ran"].startswith("dop853 (ros34pw2 tried: ")
    assert auto.solver["auto_trial_nfev"] > 0 and auto.status == "finished"
    np.testing.assert_allclose(auto.trajectory["phi"], d.trajectory["phi"], rtol=1e-12)
    assert np.max(np.abs(auto.trajectory["omega"] - d.trajectory["omega"])) <= 100 * 1e-6 * (
        np.max(d.trajectory["omega"]))


def test_the_w_method_needs_a_shaft_line():
    """A rigid scene has no line to take the Jacobian of: refused, the key named."""
    scene = load_scene(Path(__file__).resolve().parents[2] / "cases" / "coasting_single.toml")
    with pytest.raises(SceneError, match="shaft"):
        check_consistency(_with(scene, method="ros34pw2"))
