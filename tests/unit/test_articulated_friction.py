"""Friction on the articulated mechanism's joint reactions
(:mod:`transient.core.model.articulated_friction`) against the Newton–Euler model written separately in
numpy (:func:`transient.reference.articulated_joint_forces`: its own loop-closure kinematics, every
body's equations of a row as one linear system with φ̈ among the unknowns, the friction iterated
to a fixed point).

* At many states of four mechanisms (Semenov's five-cylinder radial with ψ_i = δ_i; the same with
  the link pins off the cylinder axes and rigid slave rods; a two-row radial; the fork-and-blade
  V-twin, central articulation), speeds both ways, gas forces of both signs and coefficients
  larger than an engine's, the compiled solve gives the same φ̈, side forces, big-end and
  main-bearing forces and per joint the transmitted and loss moments: the same equations solved
  two ways, so to rounding (bound 1e-12 of the largest force, of φ̈'s terms, × r for moments).
* Without friction the reference's shaft torque at a prescribed φ̈ is the reduced model's
  Σ T = M_gas − J(φ)φ̈ − ½J′(φ)φ̇² (Lagrange, the kernel's J of
  :func:`transient.core.model.articulated.articulated_terms`): an invariant between two models written
  apart, at many angles.
* The breakpoints: no joint's relative rate changes sign between two of them.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core.model import articulated as core
from transient.core.model import articulated_friction as af
from transient.core.model.joint_friction import R_LOSS, R_P
from transient.core.model.layout import (
    N_JOINTS,
    N_RX_PAR,
    RX_MU,
    RX_RADIUS,
    RX_RING_FORCE,
    RX_RING_PRESSURE,
    RX_VISCOUS,
    WK_ETA,
    WK_RX,
    WK_S,
)
from transient.core.model.work import N_WK
from transient.mechanisms.articulated import _slave_rates
from transient.reference import articulated_joint_forces
from transient.scene import load_scene, to_toml

CASES = Path(__file__).resolve().parents[2] / "cases"
RTOL = 1e-12

RADIAL = load_scene(CASES / "radial_5cyl.toml").mechanism
MECHS = {
    "radial": RADIAL,
    "off-axis-rigid": replace(RADIAL, link_angles=tuple(d - math.radians(5.0)
                                                        for d in RADIAL.slave_banks),
                              slave_rod_model="rigid", slave_rod_inertia_cg=0.012),
    "two-rows": replace(RADIAL, row_banks=(0.0, math.radians(36.0)),
                        row_cranks=(0.0, math.pi)),
    "v-twin": load_scene(CASES / "v_twin_fork_blade.toml").mechanism,
}


def coefficients(scale: float = 1.0) -> np.ndarray:
    """Per joint μ, radius, viscous, ring force, ring share: larger than an engine's, so that the
    friction reaches the forces far beyond rounding (rows ``af.J_*``)."""
    jp = np.zeros((N_JOINTS, N_RX_PAR))
    for j, (mu, rad, visc) in zip(range(5), ((0.05, 0.04, 0.02), (0.04, 0.035, 0.01),
                                             (0.06, 0.015, 0.004), (0.08, 0.02, 0.005),
                                             (0.07, 0.018, 0.003))):
        jp[j, [RX_MU, RX_RADIUS, RX_VISCOUS]] = mu * scale, rad, visc * scale
    jp[af.J_SLIDER, [RX_MU, RX_RING_FORCE, RX_RING_PRESSURE, RX_VISCOUS]] = (
        0.1 * scale, 200.0 * scale, 0.01 * scale, 5.0 * scale)
    return jp


def states(seed: int, count: int, n: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (rng.uniform(0.0, 4 * math.pi), rng.choice([-1.0, 1.0]) * rng.uniform(20.0, 400.0),
               rng.uniform(-5e3, 4e4, n))


def compiled(mech, jp, phi, w, P, J0, M_shaft):
    """φ̈ from the compiled solve and its work rows (sel = φ, σ = sign ω)."""
    mp = mech.pack()
    n = mech.n_cylinders
    wk = np.full((N_WK, max(n, N_JOINTS + 1)), np.nan)
    af.prepare(mp, phi, w, phi, wk)
    wk[WK_RX + R_P, :n] = P
    eps = af.solve(mp, jp, np.arange(N_JOINTS, dtype=np.int64), J0, M_shaft, 0.0, w,
                   np.sign(w), N_JOINTS, wk)
    return eps, wk


def lagrange(mech, P, phi, w):
    """M_gas, J, J′ of the reduced model (the kernel's Lagrange terms)."""
    n = mech.n_cylinders
    u, du = np.empty(n), np.empty(n)
    J, dJ = core.articulated_terms(mech.pack(), phi, u, du)
    return float(np.dot(P, u)), J, dJ


@pytest.mark.parametrize("name", list(MECHS))
def test_the_solve_agrees_with_newton_euler(name):
    mech = MECHS[name]
    jp = coefficients()
    n, rows, ns = mech.n_cylinders, mech.rows, mech.n_slaves
    J0 = 6.15
    worst = 0.0
    largest = np.zeros(N_JOINTS)
    for phi, w, P in states(7, 25, n):
        M_shaft = -300.0 - 0.03 * w * abs(w)
        eps, wk = compiled(mech, jp, phi, w, P, J0, M_shaft)
        ref = articulated_joint_forces(mech, phi, w, P, jp, J0=J0, M_shaft=M_shaft)
        f = max(np.abs(ref.big_end).max(), np.abs(ref.main).max(), 1.0)
        m = f * mech.crank_radius
        M_gas, J, dJ = lagrange(mech, P, phi, w)
        e_scale = (abs(M_gas) + abs(M_shaft) + abs(0.5 * dJ * w * w) + m) / (J + J0)
        masters = np.arange(rows) * (1 + ns)
        errs = (abs(eps - ref.epsilon) / e_scale,
                np.max(np.abs(wk[WK_RX + af.A_N, :n] - ref.N)) / f,
                np.max(np.abs(wk[WK_RX + af.A_FX, :n] - ref.big_end[0])) / f,
                np.max(np.abs(wk[WK_RX + af.A_FY, :n] - ref.big_end[1])) / f,
                np.max(np.abs(wk[WK_RX + af.A_FOX, masters] - ref.main[0])) / f,
                np.max(np.abs(wk[WK_RX + af.A_FOY, masters] - ref.main[1])) / f,
                np.max(np.abs(wk[WK_S, :N_JOINTS] - ref.S)) / m,
                np.max(np.abs(wk[WK_RX + R_LOSS, :N_JOINTS] - ref.L)) / m)
        worst = max(worst, *errs)
        assert max(errs) <= RTOL, (phi, w, errs)
        L = wk[WK_RX + R_LOSS, :N_JOINTS]
        assert np.all(L * w >= 0.0)  # every joint dissipates
        largest = np.maximum(largest, np.abs(ref.L) / m)
        assert abs(eps - (M_gas + M_shaft - 0.5 * dJ * w * w) / (J + J0)) > 1e-3 * e_scale
        np.testing.assert_array_equal(wk[WK_ETA, :N_JOINTS], 1.0 - L / wk[WK_S, :N_JOINTS])
    assert np.all(largest > 1e-3)  # each joint's friction far above rounding
    print(f"{name}: largest relative difference {worst:.1e}")


@pytest.mark.parametrize("name", list(MECHS))
def test_without_friction_newton_euler_is_the_reduced_model(name):
    """Σ T of the reference at a prescribed φ̈ = M_gas − Jφ̈ − ½J′φ̇² of the kernel's J, J′; the
    compiled solve with every coefficient 0 gives the reduced model's φ̈, losses exactly 0."""
    mech = MECHS[name]
    zero = np.zeros((N_JOINTS, N_RX_PAR))
    rng = np.random.default_rng(3)
    worst = 0.0
    for phi, w, P in states(5, 40, mech.n_cylinders):
        eps = rng.uniform(-2e3, 2e3)
        ref = articulated_joint_forces(mech, phi, w, P, zero, epsilon=eps)
        M_gas, J, dJ = lagrange(mech, P, phi, w)
        want = M_gas - J * eps - 0.5 * dJ * w * w
        scale = abs(M_gas) + abs(J * eps) + abs(0.5 * dJ * w * w)
        worst = max(worst, abs(ref.throw_torque.sum() - want) / scale)
        assert abs(ref.throw_torque.sum() - want) <= RTOL * scale, (phi, w, eps)
        a, wk = compiled(mech, zero, phi, w, P, 0.4, -30.0)
        lag = (M_gas - 30.0 - 0.5 * dJ * w * w) / (J + 0.4)
        assert abs(a - lag) <= RTOL * (abs(M_gas) + 30.0 + abs(0.5 * dJ * w * w)) / (J + 0.4)
        assert np.all(wk[WK_RX + R_LOSS, :N_JOINTS] == 0.0)
    print(f"{name}: largest relative difference {worst:.1e}")


def test_no_joint_reverses_between_breakpoints():
    """Between two consecutive breakpoints of the reaction case every slave's X′, β_i′ and
    β_i′ + β′ and the master's X₀′ ∝ −(sin α + …) and β′ ∝ cos α keep their signs (sampled at 40
    points per interval), and each breakpoint is marked as a jump of the derivative."""
    scene = load_scene(CASES / "radial_5cyl_reaction_friction.toml")
    mech = scene.mechanism
    model, bp, _ = build_model(scene)
    reversal = set(np.round(np.mod(np.add.outer(np.asarray(mech.row_phases),
                                                mech.row_reversals()), 2 * np.pi), 9).ravel())
    ends = np.append(bp, bp[0] + mech.cycle)
    for a, b in zip(ends[:-1], ends[1:]):
        x = np.linspace(a, b, 42)[1:-1]
        rates = np.array([_slave_rates(mech, t) for t in x])
        master = np.array([[-math.sin(t), math.cos(t)] for t in x])
        for series in (rates.reshape(len(x), -1), master):
            assert np.all(np.abs(np.diff(np.sign(series), axis=0)) == 0), (a, b)
    for angle in reversal:
        gap = np.abs(np.mod(bp, 2 * np.pi) - angle)
        i = int(np.argmin(np.minimum(gap, 2 * np.pi - gap)))
        assert min(gap[i], 2 * np.pi - gap[i]) <= 1e-9 and model.bp_jump[i]
    assert model.reaction and list(model.rx_pair) == list(range(N_JOINTS))
    assert len(reversal) > 4 * (1 + mech.n_slaves)  # the slaves' own reversals are there


def test_reaction_pairs_survive_the_resolved_scene():
    scene = load_scene(CASES / "radial_5cyl_reaction_friction.toml")
    back = load_scene("resolved.toml", text=to_toml(scene))
    assert back.friction == scene.friction
    assert [p.between for p in back.friction.pairs] == list(scene.mechanism.reaction_joints)
