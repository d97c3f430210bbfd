"""The compiled elastic shaft line's equations (:mod:`transient.core.model.shaft`) against the
reference path's separately written line (:class:`transient.reference.torsion.TorsionModel`):
the inertias, torques, accelerations and dissipated power of every degree of freedom — stations
with the cylinders they carry, damper rings (viscous and tuned), a driven inertia beyond a geared
coupling — at random states, and the crank-angle rates from the reference's time derivatives."""
from __future__ import annotations

import numpy as np
import pytest
from engines import inline_six_line, inline_six_mech

from transient.core.model import shaft
from transient.reference.torsion import CrankSliderCylinders, PressurePulse, TorsionModel

LINE = inline_six_line()
RINGS, COUPLING = LINE.rings, LINE.coupling
#: Rounding of sums of torques of the stiffness's size times twists.
RTOL = 1e-12


def _reference():
    mech = inline_six_mech()
    line = LINE
    load = lambda th, w, t: -40.0 - 0.01 * w * w
    pulse = PressurePulse(peak=8e6, at=np.radians(10.0), width=np.radians(30.0), cycle=4 * np.pi)
    return mech, TorsionModel(line, CrankSliderCylinders(mech, pulse), driven_load=load), load


def _compiled_line(model):
    """The reference line as the compiled kernels take it: one array of degrees of freedom
    (stations, rings, the driven inertia), an element table, absolute damping per one."""
    line = model.line
    n, rings = line.n, line.rings
    driven = n + len(rings)
    J_own = np.concatenate([line.inertia, [r.inertia for r in rings], [COUPLING.driven_inertia]])
    rows = [(i, i + 1, k, c, 1.0) for i, (k, c) in enumerate(zip(line.stiffness, line.damping))]
    rows += [(r.station, n + j, r.stiffness, r.damping, 1.0) for j, r in enumerate(rings)]
    rows += [(COUPLING.station, driven, COUPLING.stiffness, COUPLING.damping, COUPLING.ratio)]
    absolute = np.concatenate([line.absolute, np.zeros(len(rings) + 1)])
    return J_own, np.array(rows, dtype=float), absolute, driven


def _gear(driven, n_dof):
    """Each dof's ratio to the stations' speed: the driven inertia turns 1/i as fast."""
    gear = np.ones(n_dof)
    gear[driven] = COUPLING.ratio  # (its twist q = i θ_d − φ)
    return gear


def test_the_lines_accelerations_and_losses_are_the_references():
    mech, model, load = _reference()
    J_own, elements, absolute, driven = _compiled_line(model)
    carrier = np.asarray(model.line.station_of_cylinder, dtype=np.int64)
    rng = np.random.default_rng(5)
    n_dof = J_own.size
    for _ in range(20):
        y = model.initial_state(rng.uniform(0, 4 * np.pi), rng.uniform(50.0, 300.0))
        y[: model.i_works] += rng.normal(0.0, 1e-3, model.i_works) * np.where(
            np.arange(model.i_works) % 2 == 0, 1.0, 1e3)  # (twists of mrad, speeds of rad/s)
        th, w, rth, rw, thd, wd = model.split(y)
        theta = np.concatenate([th, rth, [thd]])
        omega = np.concatenate([w, rw, [wd]])
        t = 0.01
        acc_ref, ring_ref, driven_ref, _, dissipated = model.accelerations(t, y)

        n_cyl = mech.n_cylinders
        Jc, dJc, u, du = (np.zeros(n_cyl) for _ in range(4))
        mech.shares_kernel(mech.pack(), np.zeros((1, 1, 6)), theta[carrier], Jc, dJc, u, du,
                           True)
        J, dJ = np.zeros(n_dof), np.zeros(n_dof)
        shaft.line_inertia(carrier, J_own, Jc, dJc, J, dJ)
        M = np.zeros(n_dof)
        M[: model.line.n] = model.gas_moments(th, w, t)
        M[driven] = load(thd, wd, t)
        T = np.zeros(n_dof)
        taken = shaft.line_torques(elements, absolute, model.weights, _gear(driven, n_dof),
                                   theta, omega, T)
        acc = np.zeros(n_dof)
        shaft.line_accelerations(J, dJ, M, T, omega, acc)

        want = np.concatenate([acc_ref, ring_ref, [driven_ref]])
        scale = np.abs(T).max() / J.min()
        np.testing.assert_allclose(acc, want, rtol=0, atol=RTOL * scale)
        assert taken == pytest.approx(sum(dissipated[:4]), rel=RTOL)


def test_the_crank_angle_rates_are_the_time_rates_over_the_references_speed():
    mech, model, load = _reference()
    J_own, elements, absolute, driven = _compiled_line(model)
    carrier = np.asarray(model.line.station_of_cylinder, dtype=np.int64)
    n_dof = J_own.size
    ref = 7  # the flywheel
    gear = _gear(driven, n_dof)
    rng = np.random.default_rng(9)
    y = model.initial_state(1.3, 180.0)
    y[: model.i_works] += rng.normal(0.0, 1e-3, model.i_works)
    th, w, rth, rw, thd, wd = model.split(y)
    theta = np.concatenate([th, rth, [thd]])
    omega = np.concatenate([w, rw, [wd]])
    acc_ref, ring_ref, driven_ref, _, _ = model.accelerations(0.0, y)
    acc_want = np.concatenate([acc_ref, ring_ref, [driven_ref]])
    J_all = np.concatenate([model.station_inertia(th)[0], [r.inertia for r in RINGS],
                            [COUPLING.driven_inertia]])
    dJ_all = np.concatenate([model.station_inertia(th)[1], np.zeros(len(RINGS) + 1)])
    # d(½Jω²)/dt = J ω ω̇ + ½ J′ ω³, and d/dφ = (d/dt)/ω_ref
    dK_want = (J_all * omega * acc_want + 0.5 * dJ_all * omega ** 3) / omega[ref]
    dq_want = gear * omega / omega[ref] - 1.0

    Jc, dJc, u, du = (np.zeros(mech.n_cylinders) for _ in range(4))
    mech.shares_kernel(mech.pack(), np.zeros((1, 1, 6)), theta[carrier], Jc, dJc, u, du, True)
    M = np.zeros(n_dof)
    M[: model.line.n] = model.gas_moments(th, w, 0.0)
    M[driven] = load(thd, wd, 0.0)
    T = np.zeros(n_dof)
    shaft.line_torques(elements, absolute, model.weights, gear, theta, omega, T)
    dq, dK = np.zeros(n_dof), np.zeros(n_dof)
    shaft.line_angle_rates(ref, gear, M, T, omega, dq, dK)
    np.testing.assert_allclose(dq, dq_want, rtol=0, atol=1e-15)
    np.testing.assert_allclose(dK, dK_want, rtol=0, atol=RTOL * np.abs(T).max())


def test_absolute_damping_acts_on_the_motion_relative_to_the_rigid_rotation():
    """The absolute damping's torques sum to zero (it never brakes the line as a whole), vanish
    on a rigid rotation, and take Σ a_d (ω_d − ω̄)², ω̄ the inertia-weighted mean speed."""
    rng = np.random.default_rng(3)
    n = 9
    weights = rng.uniform(0.01, 1.0, n)
    absolute = rng.uniform(0.0, 2.0, n)
    gear = np.ones(n)
    no_elements = np.zeros((0, shaft.N_ELEMENT))
    theta = rng.normal(0.0, 1e-3, n)
    T = np.zeros(n)
    assert shaft.line_torques(no_elements, absolute, weights, gear, theta, np.full(n, 300.0),
                              T) == 0.0
    np.testing.assert_allclose(T, 0.0, atol=1e-12)
    omega = 300.0 + rng.normal(0.0, 5.0, n)
    taken = shaft.line_torques(no_elements, absolute, weights, gear, theta, omega, T)
    mean = weights @ omega / weights.sum()
    assert abs(T.sum()) <= 1e-12 * np.abs(T).max()
    assert taken == pytest.approx(np.sum(absolute * (omega - mean) ** 2), rel=1e-12)
    assert -T @ omega == pytest.approx(taken, rel=1e-9)
