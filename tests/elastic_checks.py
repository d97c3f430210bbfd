"""Checks of elastic shaft-line runs that the tests share (on ``pythonpath``, pyproject): the
energy balance (T4) written out from a run's columns, and the run against the reference path's
separately written line (:func:`transient.reference.torsion.from_scene`, scipy)."""
from __future__ import annotations

import numpy as np

from transient.reference.torsion import from_scene, integrate
from transient.scene.outputs import column_name
from transient.shaft import ShaftLine


def line_balance(scene, tr):
    """(T4) at every sample: Σ ½J_d(θ_d)ω_d² + Σ ½kδ² − its start − (W_gas + W_load +
    W_starter − W_line_loss), the kinetic energy from the columns' angles and speeds with
    ShaftLine's station inertias (numpy, not the kernels), the potential from its element
    table; and that energy, to hold the column ``E_line`` against."""
    line = ShaftLine(scene)
    names = [column_name(d.name) for d in line.dofs]
    theta = np.array([tr["phi"] + tr[f"twist_{d}"] for d in names])
    omega = np.array([tr[f"omega_{d}"] for d in names])
    J = np.repeat(line.own_inertia[:, None], theta.shape[1], axis=1)
    for i in range(theta.shape[1]):
        J[line.station_dof, i] = line.station_inertia(theta[line.station_dof, i])[0]
    kinetic = 0.5 * np.sum(J * omega ** 2, axis=0)
    rows = line.element_rows()
    a, b = rows[:, 0].astype(int), rows[:, 1].astype(int)
    potential = 0.5 * np.sum(rows[:, 2, None] * (theta[a] - theta[b]) ** 2, axis=0)
    energy = kinetic + potential
    balance = (energy - energy[0] - tr["W_gas"] - tr["W_load"] - tr["W_starter"]
               + tr["W_line_loss"])
    return balance, energy


def reference_run(scene, tr):
    """The reference model of ``scene`` (and its reference station) and its state at the run's
    sample times, integrated by scipy's DOP853 at rtol 1e-10."""
    model, ref = from_scene(scene)
    sol = integrate(model, model.initial_state(scene.initial.phi, scene.initial.omega),
                    tr["t"][-1], rtol=1e-10, atol=1e-10, dense_output=True)
    return model, ref, sol.sol(tr["t"])


def check_against_reference(scene, tr, section: int = 3, omega_rel: float = 10.0):
    """The reference station's ω(t) within ``omega_rel``·rtol of its largest, and the torque
    in section ``section`` (between stations ``section`` and ``section + 1``) within
    100·``omega_rel``·rtol of its largest (a twist of a milliradian carries the angles' error
    times k, 1e6 N m/rad), against :func:`reference_run`; returns (model, ref, y) for further
    checks."""
    model, ref, y = reference_run(scene, tr)
    n = model.line.n
    rtol = scene.solver.rtol
    omega = tr["omega"]
    assert np.max(np.abs(y[n + ref] - omega)) <= omega_rel * rtol * np.max(omega)
    i = section
    S = (model.line.stiffness[i] * (y[i + 1] - y[i])
         + model.line.damping[i] * (y[n + i + 1] - y[n + i]))
    names = [column_name(st.name) for st in scene.shaft.stations]
    torque = tr[f"torque_{names[i]}_{names[i + 1]}"]
    assert np.max(np.abs(torque)) > 100.0  # (the gas loads twist it)
    assert np.max(np.abs(-S - torque)) <= 100 * omega_rel * rtol * np.max(np.abs(torque))
    return model, ref, y
