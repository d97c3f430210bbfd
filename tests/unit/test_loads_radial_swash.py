"""Forces along a trajectory for the articulated (radial, V) and swash-plate mechanisms,
:mod:`transient.analysis.loads.articulated` and :mod:`transient.analysis.loads.swash_plate`.

Every check is independent of the force algebra it tests:

* **kinematics**: the velocities and accelerations the forces use against 6th-order finite
  differences in time along a synthetic motion with a strongly varying speed (ω ≈ 300…500 rad/s,
  ε up to ~1e5 rad/s²) of positions computed elsewhere (plain-numpy geometry of the articulated
  engine, the swash plate's compiled ``swash_points``), and the transfer functions against the
  kernels' u_k, u_k′;
* **virtual work**: Σ P_k ṡ_k against the crankpin's T r ω (radial) and Σ torque·ω (swash plate),
  and, for the whole engine, the torque passed to the shaft against Σ P_g u − J ε − ½ J′ ω² with
  the kernels' J, J′ — the kinetic energy the simulation integrates — on random ω, ε, gas forces;
* **Newton–Euler body by body** (pistons, slave rods, the master rod as rigid bodies with their
  own mass, centre of mass and inertia, no two-mass split): every force vector, not only its power;
* **degenerate cases**: the master cylinder alone and central articulation (fork-and-blade) reduce
  to :func:`transient.analysis.loads.crank_slider_loads`;
* the swash plate's torque at constant ω against the kernel's generalized force Σ P u_k.

Bounds: identities 1e-12 relative to the largest value (round-off of a few dozen operations);
finite differences 1e-8 (as ``test_loads.py``: truncation ~1e-16, round-off
~1e-10 with h = 2e-6 s; accelerations as differences of exact velocities).
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.loads import crank_slider as L
from transient.analysis.loads.articulated import articulated_loads, row_kinematics
from transient.analysis.loads.swash_plate import swash_kinematics, swash_loads
from transient.core.model import swash_plate as swash_core
from transient.core.model.articulated import articulated_terms
from transient.mechanisms import articulated as art
from transient.mechanisms import swash_plate as sp
from transient.mechanisms.crank_slider import CrankSlider
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RTOL = 1e-12
FD_RTOL = 1e-8
D6 = (np.array([-3, -2, -1, 1, 2, 3], dtype=float),
      np.array([-1.0, 9.0, -45.0, 45.0, -9.0, 1.0]) / 60.0)
H_T = 2e-6
T_GRID = np.linspace(0.0, 0.04, 801)
RNG_SEED = 20240607


def motion(t):
    """φ(t), ω(t), ε(t): 400 rad/s ± 25 % at 3 frequencies, so ε reaches ~1e5 rad/s²."""
    phi = 0.3 + 400.0 * t + 0.25 * np.sin(400.0 * t) + 0.05 * np.sin(1100.0 * t + 1.0)
    omega = 400.0 + 100.0 * np.cos(400.0 * t) + 55.0 * np.cos(1100.0 * t + 1.0)
    eps = -4.0e4 * np.sin(400.0 * t) - 6.05e4 * np.sin(1100.0 * t + 1.0)
    return phi, omega, eps


def d_dt(f):
    """d/dt of f(φ(t), ω(t)) on T_GRID by the 6th-order central stencil. Second derivatives are
    taken as d/dt of a velocity computed exactly (f = position′(φ)·ω), as test_loads.py does:
    a direct second difference would carry round-off ~1e-16·|f|/h² ≈ 1e-8 relative."""
    offsets, weights = D6
    out = 0.0
    for o, w in zip(offsets, weights):
        phi, omega, _ = motion(T_GRID + o * H_T)
        out = out + w * f(phi, omega)
    return out / H_T


def rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def random_state(n, cylinders, seed=RNG_SEED):
    """Random φ, ω (both signs), ε and gas forces of both signs."""
    rng = np.random.default_rng(seed)
    return (rng.uniform(-8.0, 8.0, n), rng.uniform(-400.0, 400.0, n),
            rng.uniform(-5e4, 5e4, n), rng.uniform(-2e4, 6e4, (cylinders, n)))


# ------------------------------------------------------------------------------------------------
# Articulated


def radial(banks_deg, psi_deg=None, **changes) -> art.Articulated:
    """Semenov's five-cylinder dimensions (as tests/unit/test_articulated.py), rigid rods."""
    banks = tuple(np.radians(banks_deg))
    psi = banks if psi_deg is None else tuple(np.radians(psi_deg))
    n = len(banks)
    return art.Articulated(**{
        "crank_radius": 0.095, "rod_length": 0.313, "bore": 0.146, "piston_mass": 2.18,
        "crank_mass": 2.0, "rod_model": "rigid", "rod_mass": 6.7, "rod_cg_from_pin": 0.235,
        "rod_inertia_cg": 0.06, "slave_banks": banks, "link_angles": psi,
        "link_radii": (0.075,) * n, "slave_lengths": (0.238,) * n, "slave_rod_model": "rigid",
        "slave_rod_mass": 1.34, "slave_rod_cg_from_pin": 0.131, "slave_rod_inertia_cg": 5e-3,
        **changes})


#: ψ ≠ δ, unequal link radii (one central) and rods, two rows (crankpins 180° apart, turned 20°).
GENERAL = radial([72, 150, 220], [67, 155, 215], link_radii=(0.075, 0.06, 0.0),
                 slave_lengths=(0.238, 0.25, 0.313), row_banks=(0.0, math.radians(20.0)),
                 row_cranks=(0.0, math.pi))


def scene_mech(name):
    return load_scene(CASES / f"{name}.toml").mechanism


RADIALS = {"general": GENERAL, "radial_5cyl": scene_mech("radial_5cyl"),
           "radial_9cyl": scene_mech("radial_9cyl"),
           "v_twin_fork_blade": scene_mech("v_twin_fork_blade"),
           "5cyl two-mass rods": replace(scene_mech("radial_5cyl"), rod_model="two-mass",
                                         rod_inertia_cg=0.0)}


def radial_kernel(mech, phi):
    """J, dJ (n,) and u, du (n_cylinders, n) from the compiled articulated_terms."""
    mp = mech.pack()
    n = mech.n_cylinders
    u, du = np.empty((phi.size, n)), np.empty((phi.size, n))
    JdJ = np.array([articulated_terms(mp, p, u[j], du[j]) for j, p in enumerate(phi)])
    return JdJ[:, 0], JdJ[:, 1], u.T, du.T


def test_row_kinematics_against_the_kernel_transfer_functions():
    phi = np.linspace(-1.0, 13.0, 241)
    for name, mech in RADIALS.items():
        _, _, u, du = radial_kernel(mech, phi)
        ns = mech.n_slaves
        for j, phase in enumerate(mech.row_phases):
            kin = row_kinematics(mech, phi - phase)
            rows = slice(j * (1 + ns), (j + 1) * (1 + ns))
            assert rel(kin.ds, u[rows]) <= 1e-13, name
            assert rel(kin.dds, du[rows]) <= 1e-13, name


def _geometry(mech, phi):
    """s (toward the crank, from r + l), link pins (complex) and rod leans of row 1 from the
    plain-numpy positions of transient.mechanisms.articulated, independent of the kernels."""
    pos = art.positions(mech, phi)
    d = np.exp(1j * np.asarray(mech.slave_banks))[None, :]
    r, l = mech.crank_radius, mech.rod_length
    s = np.concatenate([(r + l - pos["B"].real)[None, :], (r + l - (pos["Bi"] / d).real).T])
    lean_slave = np.arcsin((pos["Ai"] / d).imag / np.asarray(mech.slave_lengths)).T
    lean_master = np.arcsin(-(pos["B"] - pos["A"]).imag / l)  # rod leans toward +y: B − A below
    return s, pos["Ai"].T, np.concatenate([lean_master[None, :], lean_slave])


def test_radial_velocities_and_accelerations_by_finite_differences():
    """ṡ, s̈ = s″ω² + s′ε of every piston, Ä_i of every link pin and β̈ of every rod."""
    mech = GENERAL
    phi, omega, eps = motion(T_GRID)
    kin = row_kinematics(mech, phi)
    s, _, beta = _geometry(mech, phi)
    assert rel(kin.s, s) <= 1e-13 and rel(kin.beta, beta) <= 1e-13  # (the master: two sources)
    w2 = omega**2
    geo = lambda k: lambda p, w: _geometry(mech, p)[k]
    rate = lambda name: lambda p, w: getattr(row_kinematics(mech, p), name) * w
    errors = {
        "v": rel(kin.ds * omega, d_dt(geo(0))),
        "a": rel(kin.dds * w2 + kin.ds * eps, d_dt(rate("ds"))),
        "A_link'": rel(kin.dA_link * omega, d_dt(geo(1))),
        "A_link''": rel(kin.ddA_link * w2 + kin.dA_link * eps, d_dt(rate("dA_link"))),
        "beta'": rel(kin.dbeta * omega, d_dt(geo(2))),
        "beta''": rel(kin.ddbeta * w2 + kin.dbeta * eps, d_dt(rate("dbeta"))),
    }
    without_eps = rel(kin.dds * w2, d_dt(rate("ds")))
    print("radial finite differences:", {k: f"{v:.1e}" for k, v in errors.items()},
          f"; s̈ without ε s′: {without_eps:.2f}")
    assert max(errors.values()) <= FD_RTOL
    assert without_eps > 0.05  # the ε term matters along this motion


@pytest.mark.parametrize("name", list(RADIALS))
def test_radial_virtual_work_row_by_row(name):
    """T r ω = Σ_k P_k ṡ_k + W_links per row; W_links = 0 with massless slave rods and a two-mass
    master (then exactly the crank-slider identity T r ω = P ds/dt)."""
    mech = RADIALS[name]
    phi, omega, eps, gas = random_state(500, mech.n_cylinders)
    ns = mech.n_slaves
    for m in (mech, replace(mech, rod_model="two-mass", rod_inertia_cg=0.0,
                            slave_rod_model="two-mass", slave_rod_mass=0.0,
                            slave_rod_inertia_cg=0.0)):
        ld = articulated_loads(m, phi, omega, eps, gas)
        pv = (ld.P * ld.v).reshape(m.rows, 1 + ns, -1).sum(axis=1)
        lhs = ld.T * ld.r * omega
        err = rel(lhs, pv + ld.link_power)
        share = float(np.max(np.abs(ld.link_power)) / np.max(np.abs(lhs)))
        print(f"{name} ({m.rod_model} master, slave rods {m.slave_rod_mass} kg): "
              f"T r ω vs Σ P ṡ + W_links {err:.1e}; W_links/|T r ω|max {share:.2e}")
        assert err <= RTOL
        if m.slave_rod_mass == 0.0:
            assert np.all(ld.link_power == 0.0)
        else:
            assert share > 1e-3  # the rod inertia terms are not negligible: the check has teeth


@pytest.mark.parametrize("name", list(RADIALS))
def test_radial_shaft_torque_against_the_kernel_inertia(name):
    """Σ_rows r (R_T + T_rk) = Σ_k P_g,k u_k − J ε − ½ J′ ω² with the kernel's u, J, J′: every
    inertia force of the analysis against the kinetic energy the simulation integrates."""
    mech = RADIALS[name]
    phi, omega, eps, gas = random_state(500, mech.n_cylinders, seed=7)
    ld = articulated_loads(mech, phi, omega, eps, gas)
    J, dJ, u, _ = radial_kernel(mech, phi)
    rhs = (gas * u).sum(axis=0) - J * eps - 0.5 * dJ * omega**2
    err = rel(ld.throw_torque.sum(axis=0), rhs)
    print(f"{name}: Σ r(R_T + T_rk) vs Σ P_g u − Jε − ½J′ω²: {err:.1e}")
    assert err <= RTOL
    assert rel(ld.u, u) <= 1e-13


def _dynamics_of_row(mech, ld, phi, omega, eps, j):
    """Newton–Euler residuals of row j's bodies as rigid bodies (no two-mass split), relative."""
    ns, r, l = mech.n_slaves, mech.crank_radius, mech.rod_length
    kin = row_kinematics(mech, phi - mech.row_phases[j])
    w2 = omega**2
    acc = lambda d1, d2: d2 * w2 + d1 * eps
    c0 = j * (1 + ns)
    scale = float(np.max(np.abs(ld.R)))
    res = []
    # Master piston at B (on x): the rod's force on it X0 from m_p a_B = X0 − P_g x̂ + N ŷ.
    a_B = -acc(kin.ds[0], kin.dds[0])
    X0 = mech.piston_mass * a_B + ld.P_g[c0] - 1j * ld.N[c0]
    A = kin.A
    a_A = (1j * eps - w2) * A
    B = r * np.cos(kin.alpha) + l * np.cos(kin.beta[0])
    slave_on_master = []
    for i in range(ns):
        k = c0 + 1 + i
        li, c = mech.slave_lengths[i], mech.slave_rod_cg_from_pin
        d = np.exp(1j * mech.slave_banks[i])
        a_Bi = -acc(kin.ds[1 + i], kin.dds[1 + i]) * d
        Bi = (r + l - kin.s[1 + i]) * d
        Ai = kin.A_link[i]
        a_Ai = acc(kin.dA_link[i], kin.ddA_link[i])
        X = mech.piston_mass * a_Bi + ld.P_g[k] * d - 1j * d * ld.N[k]  # rod → piston
        f = c / li
        G = Bi + f * (Ai - Bi)
        a_G = (1 - f) * a_Bi + f * a_Ai
        m = mech.slave_rod_mass
        I_G = (mech.slave_rod_inertia_cg if mech.slave_rod_model == "rigid"
               else m * c * (li - c))
        Y = m * a_G + X  # Newton: the master rod's force on the slave rod at A_i
        # The slave rod turns by −β (crank-slider sign) in the sense of rotation.
        euler = (np.conj(Bi - G) * (-X)).imag + (np.conj(Ai - G) * Y).imag \
            + I_G * acc(kin.dbeta[1 + i], kin.ddbeta[1 + i])
        res.append(np.max(np.abs(euler)) / (scale * li))
        link = ld.link_x[j * ns + i] + 1j * ld.link_y[j * ns + i]
        res.append(np.max(np.abs(-Y - link)) / scale)
        slave_on_master.append((Ai, -Y))
    # Master rod as a rigid body: mass m at G, I_G; crankpin force Z from Newton.
    m, lg = mech.rod_mass, mech.rod_cg_from_pin
    I_G = mech.rod_inertia_cg if mech.rod_model == "rigid" else m * lg * (l - lg)
    f = lg / l
    G = B + f * (A - B)
    a_G = (1 - f) * a_B + f * a_A
    Z = m * a_G + X0 - sum(F for _, F in slave_on_master)
    load = -Z  # the rod system's force on the crankpin, its own inertia included
    c_hat = np.exp(1j * kin.alpha)
    res.append(np.max(np.abs(-(np.conj(c_hat) * load).real - ld.R_K[j])) / scale)
    res.append(np.max(np.abs((np.conj(1j * c_hat) * load).real - ld.R_T[j])) / scale)
    euler = ((np.conj(B - G) * (-X0)).imag + (np.conj(A - G) * Z).imag
             + sum((np.conj(Ai - G) * F).imag for Ai, F in slave_on_master)
             + I_G * acc(kin.dbeta[0], kin.ddbeta[0]))
    res.append(np.max(np.abs(euler)) / (scale * l))
    return max(res)


@pytest.mark.parametrize("name", ["general", "radial_9cyl", "5cyl two-mass rods"])
def test_radial_newton_euler_body_by_body(name):
    """Pistons, slave rods and the master rod as rigid bodies (mass at G, inertia about G):
    Newton gives the link-pin loads and the crankpin load as vectors, Euler closes with the side
    forces N — independent of the two-mass split and of the virtual-work bookkeeping."""
    mech = RADIALS[name]
    phi, omega, eps, gas = random_state(400, mech.n_cylinders, seed=3)
    ld = articulated_loads(mech, phi, omega, eps, gas)
    worst = max(_dynamics_of_row(mech, ld, phi, omega, eps, j) for j in range(mech.rows))
    print(f"{name}: Newton–Euler residual {worst:.1e} of |R|max")
    assert worst <= RTOL


@pytest.mark.parametrize("rod", ["two-mass", "rigid"])
def test_master_cylinder_alone_is_the_crank_slider(rod):
    """No slaves: every force equals crank_slider_loads of the master's crank-slider."""
    mech = replace(scene_mech("radial_5cyl"), slave_banks=(), link_angles=(), link_radii=(),
                   slave_lengths=(), rod_model=rod)
    mech.validate()
    phi, omega, eps = motion(T_GRID)
    gas = 3e4 * np.cos(phi / 2.0) ** 8
    a = articulated_loads(mech, phi, omega, eps, gas)
    c = L.crank_slider_loads(mech.master(), phi, omega, eps, gas)
    worst = max(rel(getattr(a, k), getattr(c, k)) for k in
                ("P", "P_j", "N", "S", "beta", "v", "K", "T", "K_rod", "T_rod", "R_K", "R_T", "R",
                 "throw_torque"))
    print(f"master alone ({rod} rod) vs crank_slider_loads: {worst:.1e}")
    assert worst <= RTOL
    assert rel(a.engine_torque, c.engine_torque) <= RTOL
    # The cylinder's share P u leaves out the rigid rod's couple power, which T r holds (loads.py:
    # T r ω = P ds/dt + C β̇); that power is W_links here.
    assert rel(a.torque + a.link_power / omega, c.torque) <= RTOL
    assert (rod == "rigid") == (rel(a.torque, c.torque) > 1e-3)


@pytest.mark.parametrize("rods", ["two-mass", "rigid"])
def test_central_articulation_is_two_crank_sliders(rods):
    """Fork-and-blade (link radius 0): the slave is a crank-slider on the same crankpin turned by
    δ — its P, N, S equal crank_slider_loads', and the crankpin load is the sum of the two
    crank-sliders' loads (each with its own rod's rotating mass)."""
    mech = scene_mech("v_twin_fork_blade")
    if rods == "rigid":
        mech = replace(mech, rod_model="rigid", rod_inertia_cg=4e-3, slave_rod_model="rigid",
                       slave_rod_inertia_cg=3e-3)
    (delta,) = mech.slave_banks
    slave = CrankSlider(crank_radius=mech.crank_radius, rod_length=mech.slave_lengths[0],
                        offset=0.0, bore=mech.bore, piston_mass=mech.piston_mass, crank_mass=0.0,
                        rod_model=mech.slave_rod_model, rod_mass=mech.slave_rod_mass,
                        rod_cg_from_pin=mech.slave_rod_cg_from_pin,
                        rod_inertia_cg=mech.slave_rod_inertia_cg, strokes=mech.strokes,
                        firing_angles=(delta,), bank_angles=(delta,))
    phi, omega, eps = motion(T_GRID)
    gas = np.vstack([3e4 * np.cos(phi / 2.0) ** 8, 2e4 * np.sin(phi / 2.0) ** 6])
    a = articulated_loads(mech, phi, omega, eps, gas)
    m = L.crank_slider_loads(mech.master(), phi, omega, eps, gas[0])
    s = L.crank_slider_loads(slave, phi, omega, eps, gas[1])
    errors = [rel(a.P[1], s.P[0]), rel(a.N[1], s.N[0]), rel(a.S[1], s.S[0]),
              rel(a.beta[1], s.beta[0]), rel(a.N[0], m.N[0]),
              rel(a.R_K[0], m.R_K[0] + s.R_K[0]), rel(a.R_T[0], m.R_T[0] + s.R_T[0])]
    print(f"fork-and-blade ({rods}) vs two crank-sliders: {max(errors):.1e}")
    assert max(errors) <= RTOL


def test_two_mass_slave_rod_is_a_two_force_member():
    """With a two-mass slave rod, the link-pin load less the link-pin mass's inertia lies along
    the rod (û from the numpy geometry), and its component there is S."""
    mech = replace(GENERAL, slave_rod_model="two-mass", slave_rod_inertia_cg=0.0)
    phi, omega, eps, gas = random_state(300, mech.n_cylinders, seed=11)
    ld = articulated_loads(mech, phi, omega, eps, gas)
    kin = row_kinematics(mech, phi)
    pos = art.positions(mech, phi)
    ns = mech.n_slaves
    for i in range(ns):
        li, c = mech.slave_lengths[i], mech.slave_rod_cg_from_pin
        m2 = mech.slave_rod_mass * c / li
        u_hat = (pos["Ai"][:, i] - pos["Bi"][:, i]) / li
        a_link = kin.ddA_link[i] * omega**2 + kin.dA_link[i] * eps
        rod = ld.link_x[i] + 1j * ld.link_y[i] + m2 * a_link
        scale = np.max(np.abs(rod))
        assert np.max(np.abs((np.conj(u_hat) * rod).imag)) <= RTOL * scale
        assert rel((np.conj(u_hat) * rod).real, ld.S[1 + i]) <= RTOL


# ------------------------------------------------------------------------------------------------
# Swash plate


SWASH = {
    "example": {},
    "two halves, rigid": {"halves": 2, "rod_model": "rigid", "rod_inertia_cg": 0.008,
                          "link_polar_inertia": 0.4, "link_diametral_inertia": 0.25},
    "two halves, 5 cyl, normal hinge": {"halves": 2, "cylinders": 5, "rod_cg_from_pin": 0.2,
                                        "hinge": "normal", "swash_angle": math.radians(30.0)},
}


def swash_kernel(g, phi):
    """J, dJ (n,) and u, du (z, n) from the compiled swash_terms."""
    mp = g.pack()
    u, du = np.empty((phi.size, g.cylinders)), np.empty((phi.size, g.cylinders))
    JdJ = np.array([swash_core.swash_terms(mp, p, u[j], du[j]) for j, p in enumerate(phi)])
    return JdJ[:, 0], JdJ[:, 1], u.T, du.T


def _joints(g, phi):
    """B (z, n, 3), x_D (z, n) and e (z, n, 3) from the compiled swash_points."""
    mp = g.pack()
    phi = np.ascontiguousarray(phi)
    theta, pts = np.empty(phi.size), np.empty((phi.size, g.cylinders, 6))
    swash_core.swash_points(mp, phi, theta, pts)
    B, D = pts[..., :3].transpose(1, 0, 2), pts[..., 3:].transpose(1, 0, 2)
    return B, D[..., 0], (B - D) / g.rod_length


@pytest.mark.parametrize("case", list(SWASH))
def test_swash_kinematics_against_the_kernel(case):
    """x_D′, x_D″ (× halves) = the kernel's u, u′; link 9's and the cross's J, J′ = the kernel's
    with pistons and rods massless."""
    g = sp.antonyuk_example(**SWASH[case])
    phi = np.linspace(-1.0, 7.5, 173)
    kin = swash_kinematics(g, phi)
    _, _, u, du = swash_kernel(g, phi)
    assert rel(g.halves * kin.dx, u) <= 1e-13
    assert rel(g.halves * kin.ddx, du) <= 1e-13
    J0, dJ0, _, _ = swash_kernel(replace(g, piston_mass=0.0, rod_mass=0.0, rod_inertia_cg=0.0),
                                 phi)
    assert rel(kin.J_link, J0) <= 1e-14 and rel(kin.dJ_link, dJ0) <= 1e-13


def test_swash_velocities_and_accelerations_by_finite_differences():
    g = sp.antonyuk_example(**SWASH["two halves, 5 cyl, normal hinge"])
    phi, omega, eps = motion(T_GRID)
    kin = swash_kinematics(g, phi)
    _, x, e = _joints(g, phi)
    assert rel(kin.x, x) <= 1e-15 and rel(kin.e, e) <= 1e-15
    w, w2, ep = omega[:, None], omega[:, None] ** 2, eps[:, None]
    geo = lambda k: lambda p, _: _joints(g, p)[k]
    rate = lambda name, k=None: lambda p, w_: (
        getattr(swash_kinematics(g, p), name) * (w_ if k is None else w_[:, None]))
    errors = {
        "B'": rel(kin.dB * w, d_dt(geo(0))),
        "B''": rel(kin.ddB * w2 + kin.dB * ep, d_dt(rate("dB", 1))),
        "x'": rel(kin.dx * omega, d_dt(geo(1))),
        "x''": rel(kin.ddx * omega**2 + kin.dx * eps, d_dt(rate("dx"))),
        "e'": rel(kin.de * w, d_dt(geo(2))),
        "e''": rel(kin.dde * w2 + kin.de * ep, d_dt(rate("de", 1))),
    }
    print("swash finite differences:", {k: f"{v:.1e}" for k, v in errors.items()})
    assert max(errors.values()) <= FD_RTOL


@pytest.mark.parametrize("case", list(SWASH))
def test_swash_virtual_work(case):
    """torque·ω = halves·(P ẋ_D − ΔI ė·ë) per cylinder; with two-mass rods Σ torque·ω = Σ P ẋ."""
    g = sp.antonyuk_example(**SWASH[case])
    phi, omega, eps, gas = random_state(500, g.cylinders, seed=5)
    ld = swash_loads(g, phi, omega, eps, gas)
    lhs = ld.torque * omega
    err = rel(lhs, g.halves * ld.P * ld.v + ld.rod_power)
    err_sum = rel(ld.engine_torque * omega, (g.halves * ld.P * ld.v + ld.rod_power).sum(axis=0))
    print(f"{case}: torque ω vs halves P ẋ + rod power {err:.1e} (sum {err_sum:.1e})")
    assert err <= RTOL and err_sum <= RTOL
    if g.rod_model == "two-mass":
        assert np.all(ld.rod_power == 0.0)
    else:
        assert np.max(np.abs(ld.rod_power)) > 1e-6 * np.max(np.abs(lhs))


@pytest.mark.parametrize("case", list(SWASH))
def test_swash_torque_is_the_kernel_generalized_force_at_constant_speed(case):
    """ε = 0: Σ torque = Σ_k P_k u_k with P = P_g − m_j x″ω² from the kernel's u_k, u_k′
    (M_П of Antonyuk (19)), and the shaft torque = Σ P_g u_k − ½J′ω² (eq. (18) at constant ω)."""
    g = sp.antonyuk_example(**SWASH[case])
    phi = np.linspace(0.0, 2.0 * math.pi, 361)
    omega = 90.0
    gas = np.random.default_rng(9).uniform(-2e3, 2e4, (g.cylinders, phi.size))
    ld = swash_loads(g, phi, omega, 0.0, gas)
    _, dJ, u, du = swash_kernel(g, phi)
    m_j = g.piston_mass + g.rod_mass * (g.rod_length - g.rod_cg_from_pin) / g.rod_length
    P = gas - m_j * du / g.halves * omega**2
    e_gen = rel(ld.engine_torque - ld.rod_power.sum(axis=0) / omega, (P * u).sum(axis=0))
    e_shaft = rel(ld.shaft_torque, (gas * u).sum(axis=0) - 0.5 * dJ * omega**2)
    print(f"{case}: Σ torque vs Σ P u_k {e_gen:.1e}; shaft torque vs Σ P_g u − ½J′ω² "
          f"{e_shaft:.1e}")
    assert e_gen <= RTOL and e_shaft <= RTOL


@pytest.mark.parametrize("case", list(SWASH))
def test_swash_shaft_torque_against_the_kernel_inertia(case):
    """Random ω, ε: shaft_torque = Σ P_g u − J ε − ½ J′ ω² with the kernel's J, J′."""
    g = sp.antonyuk_example(**SWASH[case])
    phi, omega, eps, gas = random_state(500, g.cylinders, seed=13)
    ld = swash_loads(g, phi, omega, eps, gas)
    J, dJ, u, _ = swash_kernel(g, phi)
    err = rel(ld.shaft_torque, (gas * u).sum(axis=0) - J * eps - 0.5 * dJ * omega**2)
    print(f"{case}: shaft torque vs Σ P_g u − Jε − ½J′ω²: {err:.1e}")
    assert err <= RTOL


@pytest.mark.parametrize("case", list(SWASH))
def test_swash_newton_euler_of_piston_and_rod(case):
    """The piston (m_p at D) and the rod as one rigid body (mass at G, transverse inertia I_G;
    slender: d/dt of its angular momentum is I_G e × ë) under the gas force, the side force and
    the joint force F_B: Newton and Euler hold; the side force has no x component."""
    g = sp.antonyuk_example(**SWASH[case])
    phi, omega, eps, gas = random_state(400, g.cylinders, seed=17)
    ld = swash_loads(g, phi, omega, eps, gas)
    kin = swash_kinematics(g, phi)
    w2, ep = omega[:, None] ** 2, eps[:, None]
    ell, c, m = g.rod_length, g.rod_cg_from_pin, g.rod_mass
    I_G = g.rod_inertia_cg if g.rod_model == "rigid" else m * c * (ell - c)
    psi = np.asarray(g.bank_angles)[:, None]
    side = np.stack([np.zeros_like(ld.N_radial),
                     ld.N_radial * np.cos(psi) - ld.N_tangential * np.sin(psi),
                     ld.N_radial * np.sin(psi) + ld.N_tangential * np.cos(psi)], axis=-1)
    a_D = np.zeros_like(kin.B)
    a_D[..., 0] = kin.ddx * omega**2 + kin.dx * eps
    a_B = kin.ddB * w2 + kin.dB * ep
    F_B = np.stack([ld.joint_x, ld.joint_y, ld.joint_z], axis=-1)
    gas_vec = np.zeros_like(kin.B)
    gas_vec[..., 0] = ld.P_g
    X = g.piston_mass * a_D - gas_vec - side  # the rod's force on the piston
    f = c / ell
    a_G = (1 - f) * a_D + f * a_B
    newton = -X - F_B - m * a_G  # forces on the rod: −X at D, −F_B at B
    D = kin.B - ell * kin.e
    G = D + c * kin.e
    e_acc = kin.dde * w2 + kin.de * ep
    euler = (np.cross(D - G, -X) + np.cross(kin.B - G, -F_B)
             - I_G * np.cross(kin.e, e_acc))
    scale = np.max(np.abs(F_B))
    res = (np.max(np.abs(newton)) / scale, np.max(np.abs(euler)) / (scale * ell))
    # (not arccos(e_x): ill-conditioned at small tilts)
    tilt = np.arctan2(np.hypot(kin.e[..., 1], kin.e[..., 2]), kin.e[..., 0])
    print(f"{case}: Newton {res[0]:.1e}, Euler {res[1]:.1e}; rod tilt ≤ "
          f"{np.degrees(tilt.max()):.2f}°")
    assert max(res) <= RTOL
    if g.rod_model == "two-mass":  # S = P/cos(tilt), |N| = |P| tan(tilt) (Gots (34), (35))
        assert rel(ld.S, ld.P / np.cos(tilt)) <= RTOL
        assert rel(ld.N, np.abs(ld.P) * np.tan(tilt)) <= RTOL


# ------------------------------------------------------------------------------------------------
# Plot


def test_crankpin_polar_draws_the_crank_frame():
    """plots.crankpin_polar draws (R_T, −R_K) in kN for a radial row's master crankpin."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from transient import plots

    mech = RADIALS["radial_5cyl"]
    phi, omega, eps = motion(T_GRID)
    ld = articulated_loads(mech, phi, omega, eps, 3e4 * np.cos(phi / 2.0) ** 8)
    fig, ax = plt.subplots()
    artists = plots.crankpin_polar(ax, ld.R_K[0], ld.R_T[0])
    x, y = artists[0].get_data()
    plt.close(fig)
    np.testing.assert_allclose(x, ld.R_T[0] / 1e3, rtol=0, atol=1e-12)
    np.testing.assert_allclose(y, -ld.R_K[0] / 1e3, rtol=0, atol=1e-12)
