"""The crank-slider's joint forces by Newton–Euler (:func:`transient.reference.crank_slider_joint_forces`,
eight linear equations per cylinder and sample, kinematics of its own) against

* the loads analysis (:mod:`transient.analysis.loads.crank_slider`, Gots' closed forms (34)–(41)
  after the two-mass split, plus the couple of a rigid rod): the wall force N, the rod force S,
  the crankpin load R_K, R_T, the throw's torque on the shaft, and, summed over the throws of an
  in-line engine, the main-journal loads of (58) (their sum is the shaft's bearing load);
* the reduced model (Lagrange): the throw torque equals P_g s′ − J ε − ½ J′ ω² with J, J′ of the
  compiled :func:`transient.core.model.crank_slider.cylinder_terms`;
* the power balance with known joint moments: for the same motion, the throw's torque on the
  shaft changes by the moments' power over ω.

Bounds: exact identities evaluated two ways, so round-off only — a few dozen operations and an
8×8 solve per sample; the forces agree to ~5e-16 of the largest crankpin load. Bound 1e-13 of
the largest force (torque: × r; power: of the largest power).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from engines import MECHS

from transient.analysis.loads import crank_slider as L
from transient.core.model import crank_slider as core
from transient.reference import crank_slider_joint_forces

RTOL = 1e-13


T = np.linspace(0.0, 0.04, 801)


def motion(t):
    """φ, ω, ε: 400 rad/s ± 25 % at two frequencies, so that ε (to ~1e5 rad/s²) matters."""
    phi = 0.3 + 400.0 * t + 0.25 * np.sin(400.0 * t) + 0.05 * np.sin(1100.0 * t + 1.0)
    omega = 400.0 + 100.0 * np.cos(400.0 * t) + 55.0 * np.cos(1100.0 * t + 1.0)
    eps = -4.0e4 * np.sin(400.0 * t) - 6.05e4 * np.sin(1100.0 * t + 1.0)
    return phi, omega, eps


def gas(mech, phi):
    """A smooth, sign-changing gas force per cylinder [N]."""
    alpha = phi[None, :] - np.asarray(mech.firing_angles)[:, None]
    return 2.0e4 * np.exp(np.cos(alpha / 2.0) * 3.0 - 3.0) - 3.0e3


def close(a, b, scale):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) <= RTOL * scale


@pytest.mark.parametrize("name", list(MECHS))
def test_joint_forces_equal_gots_forces(name):
    mech = MECHS[name]
    phi, omega, eps = motion(T)
    g = gas(mech, phi)
    ne = crank_slider_joint_forces(mech, phi, omega, eps, g)
    ld = L.crank_slider_loads(mech, phi, omega, eps, g)
    f = np.max(np.abs(ld.R))
    a = ld.alpha
    c_hat = np.array([np.sin(a), np.cos(a)])
    t_hat = np.array([np.cos(a), -np.sin(a)])
    assert close(ne.N, ld.N, f)
    assert close(ne.S, ld.S, f)
    assert close(-np.sum(ne.crankpin * c_hat, axis=0), ld.R_K, f)
    assert close(np.sum(ne.crankpin * t_hat, axis=0), ld.R_T, f)
    assert close(ne.throw_torque, ld.throw_torque, f * mech.crank_radius)
    # The throw's force on the main bearing: its crankpin load and its own d'Alembert force.
    k_sum, t_sum = ld.R_K + ld.K_crank, ld.R_T + ld.T_crank
    assert close(ne.main, -k_sum * c_hat + t_sum * t_hat, f)
    if name == "offset-rigid":  # the couple of a rigid rod reaches N: not the two-mass N
        two = L.crank_slider_loads(replace(mech, rod_model="two-mass"), phi, omega, eps, g)
        assert np.max(np.abs(two.N - ne.N)) > 1e-4 * f


def test_main_bearings_carry_the_journal_loads_of_58():
    """In-line: Σ over the throws of the Newton–Euler bearing force = Σ over the journals of
    (58)'s loads (the split beam divides each throw's load between two journals)."""
    mech = MECHS["two-mass"]
    phi, omega, eps = motion(T)
    g = gas(mech, phi)
    ne = crank_slider_joint_forces(mech, phi, omega, eps, g)
    ld = L.crank_slider_loads(mech, phi, omega, eps, g)
    mj = L.main_journal_loads(mech, ld, omega, eps)
    total = ne.main.sum(axis=1)  # all cylinders share cylinder 1's frame (in-line)
    f = np.max(mj.magnitude)
    assert close(total[0], mj.side.sum(axis=0), f)
    assert close(total[1], -mj.down.sum(axis=0), f)


@pytest.mark.parametrize("name", list(MECHS))
def test_throw_torque_is_the_lagrange_torque_of_the_reduced_model(name):
    """Virtual work: r(T + T_rш + T_rk) of Newton–Euler = P_g s′ − J ε − ½ J′ ω² per cylinder
    (the reduced model's generalized force, J and J′ from the compiled kernel)."""
    mech = MECHS[name]
    mp = mech.pack()
    phi, omega, eps = motion(T)
    g = gas(mech, phi)
    ne = crank_slider_joint_forces(mech, phi, omega, eps, g)
    alpha = phi[None, :] - np.asarray(mech.firing_angles)[:, None]
    for k in range(mech.n_cylinders):
        J, dJ, ds, _ = np.array([core.cylinder_terms(a, mp) for a in alpha[k]]).T
        lagrange = g[k] * ds - J * eps - 0.5 * dJ * omega**2
        assert close(ne.throw_torque[k], lagrange, np.max(np.abs(lagrange)))


@pytest.mark.parametrize("name", ["two-mass", "offset-rigid"])
def test_joint_moments_enter_by_their_power(name):
    """Known moments in the three joints (positive in the direction of rotation, on the outer
    body: M_O frame → throw, M_A throw → rod, M_B piston → rod): for the same motion, the
    kinetic energy and the gas power are the same, so the throw's torque on the shaft changes by
    the moments' power over ω: ΔT ω = M_O ω + M_A (ω_rod − ω) + M_B ω_rod, ω_rod = −β̇ the
    rod's speed in the direction of rotation (the rod turns by +β̇ about +z, against it)."""
    mech = MECHS[name]
    phi, omega, eps = motion(T)
    g = gas(mech, phi)
    rng = np.random.default_rng(7)
    moments = [rng.uniform(-30.0, 30.0, size=(3, T.size)) for _ in range(3)]
    plain = crank_slider_joint_forces(mech, phi, omega, eps, g)
    loaded = crank_slider_joint_forces(mech, phi, omega, eps, g, joint_moments=moments)
    alpha = phi[None, :] - np.asarray(mech.firing_angles)[:, None]
    db = L.slider_arrays(alpha, mech.crank_radius, mech.rod_length, mech.offset)[4]
    w_rod = -db * omega
    m_o, m_a, m_b = moments
    power = (m_o - m_a) * omega + (m_a + m_b) * w_rod
    assert close((loaded.throw_torque - plain.throw_torque) * omega, power,
                 np.max(np.abs(power)))
    assert np.max(np.abs(loaded.N - plain.N)) > 1.0  # the moments reach the forces too
