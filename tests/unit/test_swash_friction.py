"""Friction on the swash plate's joint reactions (:mod:`transient.core.model.swash_friction`) against
the Newton–Euler model written separately in numpy
(:func:`transient.reference.swash_plate_reactions`: every body's equations one linear system,
the kinematics from positions and rotation matrices;
:func:`transient.reference.swash_plate_friction` closes the friction laws, written out again
there, by ``scipy.optimize.fsolve``).

* Without friction the reference's torque on the plates equals the reduced model's
  J ε + ½J′ω² − Σ P u (Lagrange, :func:`transient.core.model.swash_plate.swash_terms`, written apart
  from both), and the compiled solve's φ̈ is (M − ½J′ω²)/J: bound 1e-12 of the terms.
* With friction, at many states of five mechanisms (both hinges, a rigid rod, two halves with an
  anisotropic link 9, five cylinders; speeds both ways, gas forces of both signs), the compiled
  φ̈, pistons' friction forces and per pair S and L equal the reference's: bound 1e-12 of the
  scale (φ̈'s frictionless size, the largest joint force, × R for moments), as for the
  crank-slider: both solve the same exact equations, fsolve to ~1e-14 of its scaled unknowns
  (the largest difference seen is 2e-14).
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core.model import swash_friction as sf
from transient.core.model import swash_plate as core
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
from transient.mechanisms.swash_plate import antonyuk_example, dead_centres
from transient.reference import swash_plate_friction, swash_plate_motion, swash_plate_reactions
from transient.scene import load_scene, to_toml

CASE = Path(__file__).resolve().parents[2] / "cases" / "swash_plate_4cyl_reaction_friction.toml"

MECHS = {
    "in-plane": antonyuk_example(),
    "normal": antonyuk_example(hinge="normal"),
    "rigid-rod": antonyuk_example(rod_model="rigid", rod_inertia_cg=0.02, rod_cg_from_pin=0.1),
    "two-halves": antonyuk_example(halves=2, link_polar_inertia=0.5, link_diametral_inertia=0.2),
    "five": antonyuk_example(cylinders=5, bore=0.08, hinge="normal", link_polar_inertia=0.1,
                             link_diametral_inertia=0.4),
}

#: Larger than an engine's, so that the friction reaches the forces well beyond rounding:
#: (μ, r, c) of the journals, (μ, F_ring, c_p, c) of the pistons.
COEFFICIENTS = dict(main=(0.05, 0.04, 0.05), plate=(0.04, 0.1, 0.03),
                    pistons=(0.1, 200.0, 0.01, 5.0))
PAIR_OF = np.array([0, 1, -1, -1, 2], dtype=np.int64)  # main, plate, (ball joints), pistons


def packed(co) -> np.ndarray:
    jp = np.zeros((N_JOINTS, N_RX_PAR))
    jp[sf.J_MAIN, [RX_MU, RX_RADIUS, RX_VISCOUS]] = co["main"]
    jp[sf.J_PLATE, [RX_MU, RX_RADIUS, RX_VISCOUS]] = co["plate"]
    jp[sf.J_SLIDER, [RX_MU, RX_RING_FORCE, RX_RING_PRESSURE, RX_VISCOUS]] = co["pistons"]
    return jp


def states(seed: int, count: int, z: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (rng.uniform(0.0, 4 * math.pi), rng.choice([-1.0, 1.0]) * rng.uniform(20.0, 300.0),
               rng.uniform(-2e3, 2e4, z))


def reduced(mech, phi, w, P, J0, M_shaft):
    """Σ P u, J, J′ and the frictionless φ̈ of the reduced model (18)."""
    z = mech.cylinders
    u, du = np.empty(z), np.empty(z)
    J, dJ = core.swash_terms(mech.pack(), phi, u, du)
    M_gas = float(P @ u)
    return M_gas, J, dJ, (M_gas + M_shaft - 0.5 * dJ * w * w) / (J + J0)


def compiled(mech, jp, phi, w, P, J0, M_shaft, eps0):
    z = mech.cylinders
    wk = np.full((N_WK, max(z, 5)), np.nan)
    sf.prepare(mech.pack(), phi, w, phi, wk)
    wk[WK_RX + sf.R_P, :z] = P
    eps = sf.solve(mech.pack(), jp, PAIR_OF, J0, M_shaft, eps0, w, np.sign(w), 3, wk)
    return eps, wk


@pytest.mark.parametrize("name", list(MECHS))
def test_without_friction_newton_euler_is_the_reduced_model(name):
    """The reference's torque the plates put into link 9 at a prescribed φ̈ is what the reduced
    model asks of the shaft, J ε + ½J′ω² − Σ P u; the Hooke constraint a·c = 0 holds; the
    compiled solve with every coefficient zero gives the reduced φ̈, no loss and η* = 1."""
    mech = MECHS[name]
    rng = np.random.default_rng(7)
    worst = 0.0
    for phi, w, P in states(3, 40, mech.cylinders):
        eps = rng.uniform(-3e3, 3e3)
        M_gas, J, dJ, _ = reduced(mech, phi, w, P, 0.0, 0.0)
        ref = swash_plate_reactions(mech, phi, w, eps, P)
        want = J * eps + 0.5 * dJ * w * w - M_gas
        scale = abs(J * eps) + abs(0.5 * dJ * w * w) + abs(M_gas)
        worst = max(worst, abs(ref.through[1] - want) / scale)
        assert abs(ref.through[1] - want) <= 1e-12 * scale, (phi, w, eps)
        assert abs(swash_plate_motion(mech, phi, w, eps)["hooke"]) <= 1e-14
        M_shaft = -100.0
        _, _, _, lagrange = reduced(mech, phi, w, P, 1.0, M_shaft)
        a, wk = compiled(mech, np.zeros((N_JOINTS, N_RX_PAR)), phi, w, P, 1.0, M_shaft, 0.0)
        assert abs(a - lagrange) <= 1e-12 * (abs(M_gas) + abs(M_shaft) + abs(0.5 * dJ * w * w)) / (
            J + 1.0)
        assert np.all(wk[WK_RX + sf.R_LOSS, :3] == 0.0)
        assert wk[WK_ETA, 0] == 1.0 and wk[WK_ETA, 1] == 1.0
    print(f"{name}: largest relative difference {worst:.1e}")


@pytest.mark.parametrize("name", list(MECHS))
def test_joint_reactions_and_losses_agree_with_newton_euler(name):
    mech = MECHS[name]
    jp = packed(COEFFICIENTS)
    J0, M_shaft = 1.0, -100.0
    worst = 0.0
    for phi, w, P in states(11, 12, mech.cylinders):
        _, _, _, eps0 = reduced(mech, phi, w, P, J0, M_shaft)
        eps, wk = compiled(mech, jp, phi, w, P, J0, M_shaft, eps0)
        ref = swash_plate_friction(mech, COEFFICIENTS, phi, w, P, J0, M_shaft)
        f = max(np.max(np.abs(ref.B)), np.max(np.abs(ref.plate)))
        m = f * mech.joint_radius
        z = mech.cylinders
        errs = (abs(eps - ref.epsilon) / abs(eps0),
                np.max(np.abs(wk[WK_RX + sf.S_F, :z] - ref.f)) / f,
                np.max(np.abs(wk[WK_S, :3] - ref.through)) / m,
                np.max(np.abs(wk[WK_RX + sf.R_LOSS, :3] - ref.loss)) / m)
        worst = max(worst, *errs)
        assert max(errs) <= 1e-12, (phi, w, errs)
        assert np.all(ref.loss * w >= 0.0)  # every joint dissipates
        assert np.min(np.abs(ref.loss)) > 1e-4 * m  # each friction far above rounding
        assert abs(eps - eps0) > 1e-3 * abs(eps0)  # and it moves φ̈
        S, L = wk[WK_S, :3], wk[WK_RX + sf.R_LOSS, :3]
        assert np.array_equal(wk[WK_ETA, :3], 1.0 - L / S)
    print(f"{name}: largest relative difference {worst:.1e}")


def test_inverse_dynamics_gives_the_newton_euler_drive():
    """At a prescribed φ̈ (the efficiency study's path, ``reactions.inverse_drive``) the drive the
    shaft needs and the pairs' S, L equal the reference's with its friction closed at that φ̈."""
    scene = load_scene(CASE)
    pairs = tuple(replace(p, mu=mu, radius=r, viscous=c) for p, (mu, r, c) in
                  zip(scene.friction.pairs[:2], (COEFFICIENTS["main"], COEFFICIENTS["plate"])))
    mu, ring, share, c = COEFFICIENTS["pistons"]
    pairs += (replace(scene.friction.pairs[2], mu=mu, ring_force=ring, ring_pressure=share,
                      viscous=c),)
    scene = replace(scene, friction=replace(scene.friction, pairs=pairs))
    model, _, _ = build_model(scene)
    mech = scene.mechanism
    rng = np.random.default_rng(5)
    for phi, w, P in states(13, 12, mech.cylinders):
        eps = rng.uniform(-3e3, 3e3)
        M_shaft = -100.0
        wk = np.full((N_WK, 5), np.nan)
        sf.prepare(model.mech, phi, w, phi, wk)
        wk[WK_RX + sf.R_P, :4] = P
        drive = sf.inverse_drive(model, eps, w, np.sign(w), M_shaft, wk)
        ref = swash_plate_friction(mech, COEFFICIENTS, phi, w, P, model.J0, M_shaft, epsilon=eps)
        want = ref.through[0] + model.J0 * eps - M_shaft
        m = max(np.max(np.abs(ref.B)), np.max(np.abs(ref.plate))) * mech.joint_radius
        assert abs(drive - want) <= 1e-12 * m, (phi, w, eps, drive, want)
        assert np.max(np.abs(wk[WK_S, :3] - ref.through)) <= 1e-12 * m
        assert np.max(np.abs(wk[WK_RX + sf.R_LOSS, :3] - ref.loss)) <= 1e-12 * m
        assert np.min(np.abs(ref.loss)) > 1e-4 * m


def test_reaction_pairs_survive_the_resolved_scene_and_report_per_joint():
    scene = load_scene(CASE)
    back = load_scene("resolved.toml", text=to_toml(scene))
    assert back.friction == scene.friction
    model, _, _ = build_model(scene)
    assert model.reaction and list(model.rx_pair) == [0, 1, -1, -1, 2] + [-1] * (N_JOINTS - 5)
    assert model.rx_par[sf.J_PLATE, RX_RADIUS] == 0.070


def test_every_dead_centre_is_a_breakpoint_where_the_derivative_jumps():
    """A piston's speed changes sign at its dead centres (roots of x_D′, found by bisection in
    :func:`dead_centres`): each is a breakpoint marked as a jump, so that no step straddles a
    reversal of the pistons' friction; the bearings turn one way throughout."""
    scene = load_scene(CASE)
    model, bp, _ = build_model(scene)
    inner, outer = dead_centres(scene.mechanism)
    for angle in np.mod(np.concatenate([inner, outer]), 2 * math.pi):
        gap = np.abs(bp - angle)
        i = int(np.argmin(np.minimum(gap, 2 * math.pi - gap)))
        assert min(gap[i], 2 * math.pi - gap[i]) <= 1e-9, angle
        assert model.bp_jump[i]
    q = [core.hooke(scene.mechanism.pack(), p)[1] for p in np.linspace(0.0, 2 * math.pi, 721)]
    assert max(q) < 0.0  # θ′ < 0: link 9 turns on the plate against the shaft throughout
