"""The compiled run of an elastic shaft line (``[shaft]``, :mod:`transient.core.model.elastic`)
checked against what is independent of it: the reference path's separately written line
(:func:`transient.reference.torsion.from_scene`, integrated by scipy) on the same scene, the
energy balance (T4) written out from the output columns with the stations' inertias of
:class:`transient.shaft.ShaftLine` (numpy, not the kernels), and the rigid model's run of the
rigid equivalent as the sections stiffen (T6)."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from elastic_checks import line_balance

import transient
from transient.analysis.efficiency import mechanical_efficiency
from transient.reference.torsion import from_scene, integrate
from transient.scene import load_scene
from transient.scene.outputs import column_name
from transient.shaft import ShaftLine, rigid_equivalent

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"
CYCLE = 4.0 * math.pi


def _case(revolutions: float = 4.0, rtol: float = 1e-8, **shaft):
    """The in-line six of the case over ``revolutions`` at ``rtol`` (atol 1e-2 of it)."""
    sc = load_scene(CASE)
    return dataclasses.replace(
        sc, run=dataclasses.replace(sc.run, revolutions=revolutions),
        solver=dataclasses.replace(sc.solver, rtol=rtol, atol=1e-2 * rtol),
        shaft=dataclasses.replace(sc.shaft, **shaft))


@pytest.fixture(scope="module")
def two_cycles():
    scene = _case()
    return scene, transient.simulate(scene)


def test_the_run_is_the_reference_lines(two_cycles):
    """Over two cycles from 800 rpm: the reference station's ω(t) within 10·rtol of its
    largest, and the torque in the middle section within 1000·rtol of its largest (a twist of
    a milliradian carries the angles' error times k, 1e6 N m/rad), against scipy's DOP853 at
    rtol 1e-10 on the reference's own equations (its absolute damping and element torques
    written apart from the kernels')."""
    scene, res = two_cycles
    tr = res.trajectory
    model, ref = from_scene(scene)
    sol = integrate(model, model.initial_state(scene.initial.phi, scene.initial.omega),
                    tr["t"][-1], rtol=1e-10, atol=1e-10, dense_output=True)
    y = sol.sol(tr["t"])
    n = model.line.n
    rtol = scene.solver.rtol
    omega = tr["omega"]
    assert np.max(np.abs(y[n + ref] - omega)) <= 10 * rtol * np.max(omega)
    # the section between throws 3 and 4 (stations 3 and 4) transmits −S_3 as the compiled
    # element (throw 3, throw 4) reports it: S_i = k Δθ + c Δω with Δ = station i+1 − i
    S = (model.line.stiffness[3] * (y[4] - y[3]) + model.line.damping[3] * (y[n + 4] - y[n + 3]))
    torque = tr["torque_throw_3_throw_4"]
    assert np.max(np.abs(torque)) > 100.0  # (the gas loads twist it)
    assert np.max(np.abs(-S - torque)) <= 1000 * rtol * np.max(np.abs(torque))


def test_the_energy_balance_holds_to_the_solvers_tolerance(two_cycles):
    """(T4) within 1e2·rtol of the gas work at every sample; the column ``E_line`` is the
    line's energy written out here, and the efficiency analysis closes its balance with it."""
    scene, res = two_cycles
    tr = res.trajectory
    balance, energy = line_balance(scene, tr)
    # the kernels' own sum of it (J_d from the mechanism's compiled shares)
    np.testing.assert_allclose(tr["E_line"], energy, rtol=1e-12)
    assert tr["W_line_loss"][-1] > 0.0 and np.all(np.diff(tr["W_line_loss"]) >= 0.0)
    assert np.max(np.abs(balance)) <= 1e2 * scene.solver.rtol * np.max(np.abs(tr["W_gas"]))
    # the reference's columns are its dof's
    line = ShaftLine(scene)
    ref = line.station_dof[line.shaft.station_index(line.shaft.reference)]
    name = column_name(line.dofs[ref].name)
    np.testing.assert_array_equal(tr["omega"], tr[f"omega_{name}"])
    assert np.all(tr[f"twist_{name}"] == 0.0)
    budget = mechanical_efficiency(scene, tr, window=(tr["phi"][0], tr["phi"][-1], 2))
    assert abs(budget["energy_balance_residual"][0]) <= 1e2 * scene.solver.rtol


def test_a_start_from_rest_switches_every_dof_to_crank_angle():
    """From rest on a starter at the flywheel: in time every dof's speed is a state, past the
    switch speed its energy (the stepper's conversion of each K_d ↔ ω_d); the balance (T4),
    with the starter's work, holds across the switch."""
    sc = _case()
    scene = dataclasses.replace(
        sc, initial=dataclasses.replace(sc.initial, omega=0.0),
        run=dataclasses.replace(sc.run, revolutions=3.0),
        starter=dataclasses.replace(sc.starter, torque=300.0, noload_speed=20 * math.pi,
                                    cutout_speed=40 * math.pi / 3))
    res = transient.simulate(scene)
    tr = res.trajectory
    assert tr["omega"][0] == 0.0 and tr["omega"][-1] > 2.0 * scene.solver.switch_speed
    assert res.events["to_angle_domain"]["t"].size >= 1 and tr["W_starter"][-1] > 0.0
    balance, _ = line_balance(scene, tr)
    assert np.max(np.abs(balance)) <= 1e2 * scene.solver.rtol * np.max(np.abs(tr["W_gas"]))


def test_the_rigid_limit():
    """Sections 10, 100 and 1000 times as stiff (no damper: a viscous ring slips and is no part
    of the rigid inertia): the reference's ω(φ) over two cycles approaches the rigid
    equivalent's run, the error falling by more than 7 × per decade of stiffness (as 1/k,
    theory (T6))."""
    base = _case(rtol=1e-10, dampers=())
    rigid = transient.simulate(rigid_equivalent(base)).trajectory
    errors = []
    for factor in (10.0, 100.0, 1000.0):
        sections = tuple(dataclasses.replace(s, stiffness=factor * s.stiffness)
                         for s in base.shaft.sections)
        run = transient.simulate(dataclasses.replace(
            base, shaft=dataclasses.replace(base.shaft, sections=sections))).trajectory
        np.testing.assert_allclose(run["phi"], rigid["phi"], rtol=1e-12)  # (the same grid)
        errors.append(np.max(np.abs(run["omega"] - rigid["omega"])))
    assert errors[0] > 7.0 * errors[1] > 49.0 * errors[2], errors
    assert errors[2] < 1e-5 * np.max(rigid["omega"])
