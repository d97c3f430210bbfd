"""Forces along a trajectory, :mod:`transient.analysis.loads.crank_slider` (Gots
§2.3–§2.8): identities that hold exactly, so the bounds are round-off bounds.

* the vectorised kinematics against the compiled :func:`transient.core.model.crank_slider.slider`;
* **the ε term**: P_j = −m_j d²s/dt² against a finite difference of the piston velocity
  ds/dt = s′(φ(t)) φ̇(t) along a synthetic motion with a strongly varying speed;
* **force balance** in Gots' convention: S cos β = P, N = P tan β = S sin β, K = S cos(α+β),
  T = S sin(α+β) (34)–(37), and the crankpin/big-end vectors rebuilt in the cylinder's x–y frame;
* **virtual work**: T r ω = P ds/dt, and for the whole cylinder
  r(T + T_rш + T_rk) = P_g s′ − J ε − ½ J′ ω² with J, J′ of the compiled reduced inertia
  (two-mass and rigid rods);
* main journals: (58) written out as printed, the shaft's force balance and the block frame;
  running torques.

Finite differences: 6th-order central stencil in time with h = 2e-6 s on a motion with
ω ≈ 300…500 rad/s (h ω ≈ 1e-3 rad): truncation ~h⁶ f⁽⁷⁾/140 ≈ 1e-16 relative, round-off
~ε|v|/h ≈ 1e-10 relative, so 1e-8 leaves a factor 100.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from engines import MECHS, gots_mech

from transient.analysis.loads import crank_slider as L
from transient.analysis.loads.common import gas_forces, rod_split
from transient.core.model import crank_slider as core

RTOL = 1e-12  # exact identities: round-off of a few dozen operations
FD_RTOL = 1e-8  # see module docstring
D6 = (np.array([-3, -2, -1, 1, 2, 3], dtype=float),
      np.array([-1.0, 9.0, -45.0, 45.0, -9.0, 1.0]) / 60.0)


def motion(t):
    """φ(t), ω(t), ε(t): 400 rad/s ± 25 % at 3 frequencies, so ε reaches ~1e5 rad/s²."""
    phi = 0.3 + 400.0 * t + 0.25 * np.sin(400.0 * t) + 0.05 * np.sin(1100.0 * t + 1.0)
    omega = 400.0 + 100.0 * np.cos(400.0 * t) + 55.0 * np.cos(1100.0 * t + 1.0)
    eps = -4.0e4 * np.sin(400.0 * t) - 6.05e4 * np.sin(1100.0 * t + 1.0)
    return phi, omega, eps


T_GRID = np.linspace(0.0, 0.04, 1201)  # ~3 revolutions, φ and α off the dead centres too


def gas(mech, phi):
    """A smooth, sign-changing synthetic gas force per cylinder [N]."""
    alpha = phi[None, :] - np.asarray(mech.firing_angles)[:, None]
    return 2.0e4 * np.exp(np.cos(alpha / 2.0) * 3.0 - 3.0) - 3.0e3


def rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("e", [0.0, 0.012])
def test_slider_arrays_match_the_kernel(e):
    alpha = np.linspace(-2.0, 14.0, 301)
    got = np.array(L.slider_arrays(alpha, 0.047, 0.11, e))
    ref = np.array([core.slider(a, 0.047, 0.11, e) for a in alpha]).T
    for k in range(6):
        assert rel(got[k], ref[k]) <= 1e-13, k


@pytest.mark.parametrize("name", list(MECHS))
def test_inertia_force_has_the_epsilon_term(name):
    """P_j = −m_j d/dt(s′(φ)φ̇), the derivative taken numerically from velocities only."""
    mech = MECHS[name]
    m1, _, _ = rod_split(mech)
    m_j = mech.piston_mass + m1
    phi, omega, eps = motion(T_GRID)
    loads = L.crank_slider_loads(mech, phi, omega, eps)
    h = 2e-6
    offsets, weights = D6
    fd = np.zeros_like(loads.P_j)
    for o, wgt in zip(offsets, weights):
        p_o, w_o, _ = motion(T_GRID + o * h)
        v_o = L.crank_slider_loads(mech, p_o, w_o, 0.0).v  # v = s′(φ) ω, no ε involved
        fd += wgt * v_o
    p_j_fd = -m_j * fd / h
    err = rel(loads.P_j, p_j_fd)
    # The constant-speed textbook form −m_j s″ω² misses m_j s′ε; here that is a large share.
    no_eps = L.crank_slider_loads(mech, phi, omega, 0.0).P_j
    miss = rel(no_eps, p_j_fd)
    print(f"{name}: P_j vs finite difference {err:.1e}; without the ε term {miss:.2f}")
    assert err <= FD_RTOL
    assert miss > 0.1


@pytest.mark.parametrize("name", ["two-mass", "offset-two-mass"])
def test_force_balance_in_gots_convention(name):
    """(34)–(37): S cos β = P, N = P tan β = S sin β, K = S cos(α+β), T = S sin(α+β)."""
    mech = MECHS[name]
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    assert rel(ld.P, ld.P_g + ld.P_j) <= RTOL
    assert rel(ld.S * np.cos(ld.beta), ld.P) <= RTOL
    assert rel(ld.N, ld.P * np.tan(ld.beta)) <= RTOL
    assert rel(ld.S * np.sin(ld.beta), ld.N) <= RTOL
    assert rel(ld.S * np.cos(ld.alpha + ld.beta), ld.K) <= RTOL
    assert rel(ld.S * np.sin(ld.alpha + ld.beta), ld.T) <= RTOL
    assert rel(np.hypot(ld.K, ld.T), np.abs(ld.S)) <= RTOL


@pytest.mark.parametrize("name", list(MECHS))
def test_crankpin_and_big_end_as_vectors(name):
    """Rebuild the loads in the cylinder's x–y frame (y to the head): the rod pushes the crankpin
    with S û plus the rigid rod's H x̂; the rod's m₂ at A adds −m₂ a_A, a_A = −ω²A + ε r t̂."""
    mech = MECHS[name]
    r = mech.crank_radius
    _, m2, _ = rod_split(mech)
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    a, b = ld.alpha, ld.beta
    c_hat = np.array([np.sin(a), np.cos(a)])
    t_hat = np.array([np.cos(a), -np.sin(a)])
    u_hat = np.array([np.sin(b), -np.cos(b)])
    n_hat = np.array([np.cos(b), np.sin(b)])
    # Piston: −P ŷ from gas and inertia, the rod's −(S û + H x̂)... solved for the wall force N x̂:
    # x: N − S sin β − H = 0 → H = N − P tan β (0 for the two-mass rod).
    h = ld.N - ld.P * np.tan(b)
    rod_on_pin = ld.P / np.cos(b) * u_hat + np.array([h, np.zeros_like(h)])
    inertia_m2 = m2 * (omega**2 * r * c_hat - eps * r * t_hat)
    load = rod_on_pin + inertia_m2
    assert rel(-np.sum(rod_on_pin * c_hat, axis=0), ld.K) <= RTOL
    assert rel(np.sum(rod_on_pin * t_hat, axis=0), ld.T) <= RTOL
    assert rel(np.sum(rod_on_pin * u_hat, axis=0), ld.S) <= RTOL
    assert rel(ld.K_rod, -m2 * r * omega**2 + 0 * a) <= RTOL
    assert rel(ld.T_rod, -m2 * r * eps + 0 * a) <= RTOL
    assert rel(-np.sum(load * c_hat, axis=0), ld.R_K) <= RTOL
    assert rel(np.sum(load * t_hat, axis=0), ld.R_T) <= RTOL
    assert rel(np.hypot(*load), ld.R) <= RTOL
    assert rel(np.sum(load * u_hat, axis=0), ld.R_axial) <= RTOL
    assert rel(np.sum(load * n_hat, axis=0), ld.R_normal) <= RTOL
    if name == "two-mass":
        # The book's scalar |R| = √(S² + K_rш²) (40)/(41) is not the vector sum (a misprint).
        book = np.hypot(ld.S, ld.K_rod)
        assert rel(book, ld.R) > 0.1


@pytest.mark.parametrize("name", list(MECHS))
def test_newton_euler_of_piston_and_rod(name):
    """Independent of the two-mass split: the piston (m_p at B) and the rod as one rigid body
    (mass m at G, I_G; the two-mass rod is the one with I_G = m l₁(l − l₁)) under the gas force,
    the wall force N x̂ and the crankpin load R satisfy Newton and Euler.

    Frame x–y (y to the head). Rod on the crankpin: R = R_K(−ĉ) + R_T t̂ (includes m₂'s inertia),
    so the crankpin acts on the rod with −R; the piston gets −P_g ŷ + N x̂ and the rod's
    F_pin→piston. Accelerations: a_B = −(s″ω² + s′ε) ŷ, a_A = −ω²A + ε r t̂,
    a_G = (1 − f) a_B + f a_A (f = l₁/l), β̈ = β″ω² + β′ε counter-clockwise.
    """
    mech = MECHS[name]
    r, l, l1, m = mech.crank_radius, mech.rod_length, mech.rod_cg_from_pin, mech.rod_mass
    i_g = mech.rod_inertia_cg if mech.rod_model == "rigid" else m * l1 * (l - l1)
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    a = ld.alpha
    _, ds, dds, b, db, ddb = L.slider_arrays(a, r, l, mech.offset)
    zero = np.zeros_like(a)
    c_hat = np.array([np.sin(a), np.cos(a)])
    t_hat = np.array([np.cos(a), -np.sin(a)])
    pos_a = r * c_hat
    pos_b = pos_a - l * np.array([np.sin(b), -np.cos(b)])
    f = l1 / l
    pos_g = (1 - f) * pos_b + f * pos_a
    acc_b = np.array([zero, -(dds * omega**2 + ds * eps)])
    acc_a = -omega**2 * pos_a + eps * r * t_hat
    acc_g = (1 - f) * acc_b + f * acc_a
    beta_acc = ddb * omega**2 + db * eps
    load = -ld.R_K * c_hat + ld.R_T * t_hat  # rod → crankpin
    # Piston: −P_g ŷ + N x̂ + F_rod→piston = m_p a_B, so the piston acts on the rod with −F.
    f_rod_on_piston = mech.piston_mass * acc_b - np.array([ld.N, -ld.P_g])
    f_on_rod = -load - f_rod_on_piston  # from the crankpin and from the pin
    scale = np.max(np.abs(ld.R))
    newton = f_on_rod - m * acc_g
    assert np.max(np.abs(newton)) <= RTOL * scale * 10

    def cross(p, q):
        return p[0] * q[1] - p[1] * q[0]

    euler = cross(pos_a - pos_g, -load) + cross(pos_b - pos_g, -f_rod_on_piston) - i_g * beta_acc
    assert np.max(np.abs(euler)) <= RTOL * scale * l * 10


@pytest.mark.parametrize("name", ["two-mass", "offset-two-mass"])
def test_torque_power_equals_piston_power(name):
    """T r ω = P ds/dt (virtual work of the two-force rod) to 1e-12."""
    mech = MECHS[name]
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    err = rel(ld.torque * omega, ld.P * ld.v)
    print(f"{name}: |T r ω − P v| / max|P v| = {err:.1e}")
    assert err <= RTOL


@pytest.mark.parametrize("name", list(MECHS))
def test_torque_equals_the_reduced_model(name):
    """r(T + T_rш + T_rk) = P_g s′ − J ε − ½ J′ ω² per cylinder, J and J′ from the compiled
    :func:`transient.core.model.crank_slider.cylinder_terms` (Lagrange; rigid rod: the couple ΔI β̈)."""
    mech = MECHS[name]
    mp = mech.pack()
    phi, omega, eps = motion(T_GRID)
    g = gas(mech, phi)
    ld = L.crank_slider_loads(mech, phi, omega, eps, g)
    for k in range(mech.n_cylinders):
        terms = np.array([core.cylinder_terms(a, mp) for a in ld.alpha[k]]).T
        J, dJ, ds = terms[0], terms[1], terms[2]
        lagrange = g[k] * ds - J * eps - 0.5 * dJ * omega**2
        err = rel(ld.throw_torque[k], lagrange)
        assert err <= RTOL, (k, err)
    if name == "offset-rigid":  # the couple is not negligible here
        two_mass = L.crank_slider_loads(replace(mech, rod_model="two-mass"), phi, omega, eps, g)
        assert rel(two_mass.throw_torque, ld.throw_torque) > 1e-3


def test_rigid_rod_virtual_work():
    """T r ω = P ds/dt + C β̇, C = −ΔI β̈ the couple the two-mass split misses."""
    mech = MECHS["offset-rigid"]
    _, _, d_inertia = rod_split(mech)
    assert abs(d_inertia) > 1e-4
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    _, _, _, _, db, ddb = L.slider_arrays(ld.alpha, mech.crank_radius, mech.rod_length,
                                          mech.offset)
    couple = -d_inertia * (ddb * omega**2 + db * eps)
    assert rel(ld.torque * omega, ld.P * ld.v + couple * db * omega) <= RTOL


def test_constant_speed_reduces_to_gots():
    """ε = 0: P_j = −m_j r ω² [cos(α+β)/cos β + λ cos²α/cos³β] (exact form of Gots (6)), no
    tangential inertia, throw torque = cylinder torque."""
    mech = gots_mech()
    w = 460.77
    phi = np.radians(np.arange(0.0, 720.0, 5.0))
    ld = L.crank_slider_loads(mech, phi, w, 0.0)
    m1, m2, _ = rod_split(mech)
    lam = mech.lam
    a = ld.alpha
    b = np.arcsin(lam * np.sin(a))
    j = mech.crank_radius * w**2 * (np.cos(a + b) / np.cos(b) + lam * np.cos(a)**2 / np.cos(b)**3)
    assert rel(ld.P_j, -(mech.piston_mass + m1) * j) <= RTOL
    assert np.all(ld.T_rod == 0.0) and np.all(ld.T_crank == 0.0)
    np.testing.assert_array_equal(ld.throw_torque, ld.torque)
    assert np.allclose(ld.K_rod, -m2 * mech.crank_radius * w**2, rtol=1e-15, atol=0)


def test_main_journals_tabular_method():
    """(58) as printed for the journal between throws i and i + 1; the shaft's force balance
    (the journals carry the throws' loads); the block frame; a counterweight."""
    mech = gots_mech()
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    cw_mass, cw_angle = 0.7, math.radians(200.0)
    mj = L.main_journal_loads(mech, ld, omega, eps, cw_mass, cw_angle)
    np.testing.assert_allclose(np.degrees(mj.gamma), [0.0, 120.0, 240.0], atol=1e-12)
    r = mech.crank_radius
    # Throw loads K_Σ, T_Σ, counterweight written out (ρ at angle δ ahead of the crank).
    k_cw = -cw_mass * r * (omega**2 * math.cos(cw_angle) + eps * math.sin(cw_angle))
    t_cw = cw_mass * r * (omega**2 * math.sin(cw_angle) - eps * math.cos(cw_angle))
    K = ld.K + ld.K_rod - mech.crank_mass * r * omega**2 + k_cw
    T = ld.T + ld.T_rod - mech.crank_mass * r * eps + t_cw
    g = mj.gamma
    for j in range(4):  # journal j + 1 between throws j and j + 1 (absent ones are zero)
        rx = np.zeros_like(phi)
        ry = np.zeros_like(phi)
        for i in (j - 1, j):
            if 0 <= i < 3:
                rx += (T[i] / 2) * np.cos(g[i]) - (K[i] / 2) * np.sin(g[i])
                ry += (T[i] / 2) * np.sin(g[i]) + (K[i] / 2) * np.cos(g[i])
        assert rel(mj.x[j], rx) <= RTOL
        assert rel(mj.y[j], ry) <= RTOL
    # Block frame (cylinder 1's x, y to the head): each throw's load is K_Σ(−ĉ_i) + T_Σ t̂_i.
    a = ld.alpha
    fx = np.sum(-K * np.sin(a) + T * np.cos(a), axis=0)
    fy = np.sum(-K * np.cos(a) - T * np.sin(a), axis=0)
    assert rel(mj.side.sum(axis=0), fx) <= RTOL
    assert rel(mj.down.sum(axis=0), -fy) <= RTOL
    assert rel(mj.magnitude, np.hypot(mj.x, mj.y)) <= RTOL


def test_running_torques():
    mech = gots_mech()
    phi, omega, eps = motion(T_GRID)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas(mech, phi))
    journals, pins = L.running_torques(mech, ld)
    assert np.all(journals[0] == 0.0)
    r = mech.crank_radius
    throw = (ld.T + ld.T_rod + ld.T_crank) * r
    assert rel(journals[-1], throw.sum(axis=0)) <= RTOL
    assert rel(pins[1], throw[0] + 0.5 * throw[1]) <= RTOL
    j2, p2 = L.running_torques(mech, ld, include_rotating=False)
    assert rel(j2[-1], ld.engine_torque) <= RTOL
    assert rel(p2[2], ld.torque[0] + ld.torque[1] + 0.5 * ld.torque[2]) <= RTOL


def test_gas_forces_and_trajectory():
    """Gas forces read from the scene's tables at φ − gas_phases, and from a trajectory's p_k."""
    from transient.scene import load_scene
    from transient.scene.queries import gas_phases, gas_table, gas_tables

    scene = load_scene(Path(__file__).resolve().parents[2] / "cases" / "gots_diesel_4400.toml")
    mech = scene.mechanism
    phi = np.linspace(0.01, 4 * math.pi, 97)
    table = gas_table(scene)
    p = np.array([table(phi - ph) for ph in gas_phases(scene)])
    expected = (p - scene.gas.p0) * mech.piston_area
    got = gas_forces(scene, phi)
    assert rel(got, expected) <= RTOL
    # at half fuel half the combustion: midway between the full-load and the motored cycle
    motored = gas_tables(scene)[1]
    p_mot = np.array([motored(phi - ph) for ph in gas_phases(scene)])
    half = gas_forces(scene, phi, fuel=0.5)
    assert rel(half, (0.5 * (p + p_mot) - scene.gas.p0) * mech.piston_area) <= RTOL
    traj = {"phi": phi, "omega": np.full_like(phi, 300.0), "epsilon": np.full_like(phi, 50.0)}
    traj.update({f"p_{k + 1}": p[k] for k in range(3)})
    a = L.loads_from_trajectory(scene, traj)
    b = L.crank_slider_loads(mech, phi, 300.0, 50.0, expected)
    np.testing.assert_allclose(a.T, b.T, rtol=0, atol=1e-9 * np.max(np.abs(b.T)))
    c = L.loads_from_trajectory(scene, {k: traj[k] for k in ("phi", "omega", "epsilon")})
    np.testing.assert_allclose(c.T, b.T, rtol=0, atol=1e-9 * np.max(np.abs(b.T)))
