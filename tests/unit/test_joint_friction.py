"""Friction on the crank-slider's joint reactions (:mod:`transient.core.model.joint_friction`) against
the Newton–Euler model written separately in numpy
(:func:`transient.reference.crank_slider_joint_forces`, eight linear equations per cylinder with
known joint moments).

The reference knows nothing of friction: its joint moments and the slider's axial force are
computed from its own joint forces by the friction laws written out again in numpy
(:func:`transient.reference.joints.crank_slider_friction_laws`), and iterated to a fixed point (plain
substitution; the friction changes the forces by a few per mille, so the
iteration contracts by about that factor each turn and 60 turns are far past rounding). Then, at
many states of three mechanisms (central two-mass, offset two-mass, offset rigid rod; speeds
both ways, accelerations to 1e5 rad/s², gas forces of both signs), the compiled solve must give
the same side force N, throw torque T, loss moments and transmitted moments per joint: exact
identities computed two ways, so to rounding (bound 1e-12 of the largest force, × r for moments).

The exact solve of the shaft's equation: at the compiled φ̈ the reference's throw torques leave
J₀ φ̈ − M_shaft − Σ T = 0 to rounding; with every coefficient zero the solve gives the reduced
model's φ̈ = (M − ½J′ω²)/J (Lagrange: J, J′ of :func:`transient.core.model.crank_slider.cylinder_terms`).

Where a step's stages see a side force change side, the step end the stepper aims at is the
root of N between the nearest stages of either side: exact for a linear N, checked against the
root put in by hand.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from engines import MECHS

from transient.assemble import build_model
from transient.core.model import crank_slider as core
from transient.core.model import joint_friction as jf
from transient.core.model.layout import (
    JOINT_CRANKPIN,
    JOINT_MAIN,
    JOINT_PIN,
    JOINT_SLIDER,
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
from transient.reference import crank_slider_friction, crank_slider_joint_signs
from transient.scene import load_scene, to_toml

RTOL = 1e-12


def coefficients(scale: float = 1.0) -> np.ndarray:
    """Per joint μ, radius, viscous, ring force, ring pressure share: larger than an engine's, so
    that the friction reaches the forces well beyond rounding."""
    jp = np.zeros((4, N_RX_PAR))
    jp[JOINT_MAIN, [RX_MU, RX_RADIUS, RX_VISCOUS]] = 0.05 * scale, 0.03, 0.02 * scale
    jp[JOINT_CRANKPIN, [RX_MU, RX_RADIUS, RX_VISCOUS]] = 0.04 * scale, 0.026, 0.01 * scale
    jp[JOINT_PIN, [RX_MU, RX_RADIUS, RX_VISCOUS]] = 0.08 * scale, 0.015, 0.005 * scale
    jp[JOINT_SLIDER, [RX_MU, RX_RING_FORCE, RX_RING_PRESSURE, RX_VISCOUS]] = (
        0.1 * scale, 200.0 * scale, 0.01 * scale, 5.0 * scale)
    return jp


def reference_friction(mech, jp, phi, w, eps, P):
    """The reference's forces with the friction laws applied to them, iterated to a fixed point
    (:func:`transient.reference.crank_slider_friction`), the joints' directions at φ itself:
    (forces, per-joint loss moments L, per-joint transmitted moments S), arrays over the
    cylinders."""
    return crank_slider_friction(mech, jp, phi, w, eps, P,
                                 crank_slider_joint_signs(mech, phi) * np.sign(w))


def compiled_cylinders(mech, jp, phi, w, eps, P):
    """N, T, and per joint (rows) the transmitted and loss moments of each cylinder (columns),
    from the compiled kernels at φ̈ = eps (sel = φ)."""
    mp = mech.pack()
    n = mech.n_cylinders
    wk = np.full((N_WK, max(n, 5)), np.nan)
    jf.prepare(mp, phi, w, phi, wk)
    wk[WK_RX + jf.R_P, :n] = P
    sigma = 1.0 if w > 0 else -1.0
    T = np.empty(n)
    terms = np.empty((8, n))
    for k in range(n):
        assert jf.solve_cylinder(mp, jp, wk, k, eps, w, sigma)
        terms[:, k] = jf.joint_terms(mp, jp, wk, k, eps, w, sigma, wk[WK_RX + jf.R_N, k])
        T[k] = -terms[0, k]  # the main bearing's S is what the shaft puts into the throw, −T
    return wk[WK_RX + jf.R_N, :n].copy(), T, terms[:4], terms[4:]


def states(seed: int, count: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (rng.uniform(0.0, 4 * math.pi), rng.choice([-1.0, 1.0]) * rng.uniform(20.0, 600.0),
               rng.uniform(-1e5, 1e5), rng.uniform(-5e3, 4e4, 3))


@pytest.mark.parametrize("name", list(MECHS))
def test_joint_reactions_and_losses_agree_with_newton_euler(name):
    mech = MECHS[name]
    jp = coefficients()
    worst = 0.0
    for phi, w, eps, P in states(11, 60):
        ref, loss, through = reference_friction(mech, jp, phi, w, eps, P)
        N, T, S, L = compiled_cylinders(mech, jp, phi, w, eps, P)
        f = max(np.max(np.abs(ref.crankpin)), np.max(np.abs(ref.main)), 1.0)
        m = f * mech.crank_radius
        errs = (np.max(np.abs(N - ref.N[:, 0])) / f,
                np.max(np.abs(T - ref.throw_torque[:, 0])) / m,
                np.max(np.abs(L - loss)) / m, np.max(np.abs(S - through)) / m)
        worst = max(worst, *errs)
        assert max(errs) <= RTOL, (phi, w, eps, errs)
        assert np.all(L * w >= 0.0)  # every joint dissipates
        assert np.max(np.abs(loss)) > 1e-3 * m  # the friction is far above rounding
    print(f"{name}: largest relative difference {worst:.1e}")


def shaft_terms(mech, P, phi, w):
    """Σ P s′, J and J′ of the cylinders (Lagrange, the compiled reduced model)."""
    mp = mech.pack()
    J = dJ = M = 0.0
    for k, a in enumerate(phi - np.asarray(mech.firing_angles)):
        Jk, dJk, ds, _ = core.cylinder_terms(a, mp)
        J, dJ, M = J + Jk, dJ + dJk, M + P[k] * ds
    return M, J, dJ


@pytest.mark.parametrize("name", ["two-mass", "offset-rigid"])
def test_the_solve_leaves_the_shaft_equation_at_rounding(name):
    """The compiled φ̈ satisfies the shaft's equation with the reference's throw torques at that
    φ̈ (friction iterated in the reference itself): the implicit equation's residual is rounding
    (bound 1e-12 of the sum of the magnitudes of its terms). Per pair the compiled η* = 1 − L/S."""
    mech = MECHS[name]
    jp = coefficients()
    J0, pair_of = 0.17, np.arange(4, dtype=np.int64)
    mp = mech.pack()
    worst = 0.0
    for phi, w, _, P in states(5, 40):
        M_shaft = -50.0 - 1e-3 * w * abs(w)
        M_gas, J, dJ = shaft_terms(mech, P, phi, w)
        wk = np.full((N_WK, 5), np.nan)
        jf.prepare(mp, phi, w, phi, wk)
        wk[WK_RX + jf.R_P, :3] = P
        eps0 = (M_gas + M_shaft - 0.5 * dJ * w * w) / (J + J0)
        eps = jf.solve(mp, jp, pair_of, J0, M_shaft, eps0, w, np.sign(w), 4, wk)
        ref, loss, through = reference_friction(mech, jp, phi, w, eps, P)
        T = ref.throw_torque[:, 0]
        residual = J0 * eps - M_shaft - T.sum()
        scale = J0 * abs(eps) + abs(M_shaft) + np.abs(T).sum()
        worst = max(worst, abs(residual) / scale)
        assert abs(residual) <= RTOL * scale, (phi, w, residual / scale)
        assert abs(eps - eps0) > 1e-4 * abs(eps0)  # the friction moves φ̈ far beyond rounding
        S, L = wk[WK_S, :4], wk[WK_RX + jf.R_LOSS, :4]
        m = np.max(np.abs(ref.crankpin)) * mech.crank_radius
        assert np.max(np.abs(S - through.sum(axis=1))) <= RTOL * m
        assert np.max(np.abs(L - loss.sum(axis=1))) <= RTOL * m
        assert np.array_equal(wk[WK_ETA, :4], 1.0 - L / S)
    print(f"{name}: largest residual {worst:.1e} of the terms")


@pytest.mark.parametrize("name", list(MECHS))
def test_without_friction_the_solve_is_the_reduced_model(name):
    """All coefficients zero: φ̈ = (Σ P s′ + M_shaft − ½J′ω²)/J of the Lagrange model, every loss
    exactly 0 and η* = 1 in every joint that transmits."""
    mech = MECHS[name]
    jp = np.zeros((4, N_RX_PAR))
    J0, pair_of = 0.17, np.arange(4, dtype=np.int64)
    mp = mech.pack()
    for phi, w, _, P in states(3, 40):
        M_shaft = -30.0
        M_gas, J, dJ = shaft_terms(mech, P, phi, w)
        wk = np.full((N_WK, 5), np.nan)
        jf.prepare(mp, phi, w, phi, wk)
        wk[WK_RX + jf.R_P, :3] = P
        lagrange = (M_gas + M_shaft - 0.5 * dJ * w * w) / (J + J0)
        eps = jf.solve(mp, jp, pair_of, J0, M_shaft, 0.0, w, np.sign(w), 4, wk)
        scale = (abs(M_gas) + abs(M_shaft) + abs(0.5 * dJ * w * w)) / (J + J0)
        assert abs(eps - lagrange) <= RTOL * scale, (phi, w, (eps - lagrange) / scale)
        assert np.all(wk[WK_RX + jf.R_LOSS, :4] == 0.0)
        assert np.all(wk[WK_ETA, :3] == 1.0)


CASE = Path(__file__).resolve().parents[2] / "cases" / "gots_diesel_reaction_friction.toml"


def test_reaction_pairs_survive_the_resolved_scene():
    scene = load_scene(CASE)
    back = load_scene("resolved.toml", text=to_toml(scene))
    assert back.friction == scene.friction
    assert [p.model for p in back.friction.pairs] == ["reaction"] * 4


def test_every_reversal_of_a_joint_is_a_breakpoint_where_the_derivative_jumps():
    """The pistons' speeds change sign at their dead centres, the rods' rates β̇ at local 90° and
    270° (both turns of the 4-stroke cycle): each is a breakpoint marked as a jump, so that no
    step straddles a friction force's reversal and none carries its derivative across one."""
    scene = load_scene(CASE)
    model, bp, _ = build_model(scene)
    mech = scene.mechanism
    want = np.mod(np.add.outer(np.asarray(mech.firing_angles),
                               np.arange(8) * math.pi / 2).ravel(), mech.cycle)
    for angle in want:
        gap = np.abs(bp - angle)
        i = int(np.argmin(np.minimum(gap, mech.cycle - gap)))
        assert min(gap[i], mech.cycle - gap[i]) <= 1e-12 * mech.cycle, angle
        assert model.bp_jump[i]
    assert model.reaction and list(model.rx_pair) == [0, 1, 2, 3] + [-1] * (N_JOINTS - 4)


def stage_abscissae(x0, h):
    """The abscissae at which a DOP853 attempt from x0 of size h evaluates the right-hand side:
    its stages after the first (carried over) and the step's end."""
    from transient.core.integrator.tableaus import TABLEAUS

    tab = TABLEAUS["dop853"]
    return x0 + h * tab.A[1: tab.n_stages + 1].sum(axis=1)


def side_change_of(mech, x0, h, sides):
    """``jf.side_change`` after the stages of an attempt have seen N_k = sides[k](x)."""
    n = mech.n_cylinders
    wk = np.full((N_WK, max(n, 5)), np.nan)
    jf.reset_sides(n, wk)
    for x in stage_abscissae(x0, h):
        wk[WK_RX + jf.R_N, :n] = [side(x) for side in sides]
        jf.track_sides(n, x, wk)
    return jf.side_change(n, wk)


def test_a_side_force_changing_side_in_the_stages_puts_the_step_end_on_its_root():
    """Where a step's stages see a side force change side, the step is retaken to end at the
    root that they bracket (linear between the nearest stages of either side): exact for an N
    linear in the angle, whichever side it leaves, and the earliest of several cylinders'; a
    cylinder whose N keeps its side, or changes it twice (stages on the same side at both
    ends), puts no end."""
    mech = MECHS["two-mass"]
    assert mech.n_cylinders == 3
    x0, h = 2.0, 0.3
    a, b = x0 + 0.37 * h, x0 + 0.81 * h
    falls = lambda x: -4e3 * (x - a)  # positive, then negative
    rises = lambda x: 2e2 * (x - b)  # negative, then positive
    keeps = lambda x: 50.0 + x
    twice = lambda x: 1e3 * (x - x0 - 0.2 * h) * (x - x0 - 0.7 * h)
    for sides, root in (([falls, keeps, keeps], a), ([keeps, rises, keeps], b),
                        ([keeps, rises, falls], a), ([rises, keeps, falls], a)):
        got = side_change_of(mech, x0, h, sides)
        assert abs(got - root) <= 4 * np.finfo(float).eps * x0, (got, root)
    # a curved N: the root lies between the nearest stages of either side
    curved = lambda x: math.exp(3.0 * (x - a)) - 1.0
    c = stage_abscissae(x0, h)
    got = side_change_of(mech, x0, h, [keeps, curved, keeps])
    assert c[c < a].max() < got < c[c > a].min()
    assert side_change_of(mech, x0, h, [keeps, keeps, keeps]) == math.inf
    assert side_change_of(mech, x0, h, [twice, keeps, keeps]) == math.inf
