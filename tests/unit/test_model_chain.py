"""The serial chain inside the compiled model (``transient.core.model.rhs``): how a mechanism's links
become sub-chains, the right-hand side with held pair modes, the forward/inverse consistency of the
chain, and the choice of modes at a state."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core.model import forcing, inverse, layout, rhs, work
from transient.core.model.chain import LOCKED, UNIQUE
from transient.scene import Friction, Pair, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RNG = np.random.default_rng(20261122)


def gots(pairs=None, policy="power-flow"):
    base = load_scene(CASES / "gots_diesel_friction.toml")
    return replace(base, friction=Friction(policy, base.friction.pairs if pairs is None else pairs))


def state(model, phi, omega):
    y = np.zeros(layout.N_STATE_BASE + model.n_pairs)
    y[layout.PHI], y[layout.OMEGA] = phi, omega
    return y


def forward(model, phi, omega, modes):
    """φ̈, J, dJ and the per-sub-chain terms at a time-domain state with held ``modes``."""
    wk = work.work_array(model)
    sw = np.array([0, 0, modes, 1 if omega >= 0 else -1])
    y = state(model, phi, omega)
    J, dJ, w, Mg, Ml, Ms = forcing.moments(model, layout.extras_of(model), False, y, phi, sw, wk,
                                           True)
    a = rhs.acceleration(model, layout.extras_of(model), phi, J, dJ, w, Mg, Ml, Ms, sw, wk)
    return a, J, dJ, Mg + Ml + Ms, wk, sw, y


@pytest.mark.parametrize("links, expected", [
    ((("shaft", "crank"), ("crank", "rod")), [0, 1, 2, 2, 2]),
    ((("shaft", "crank"),), [0, 1, 1, 1, 1]),  # ideal crankpins: crank to cylinders one sub-chain
    ((("crank", "rod"),), [0, 0, 1, 1, 1]),  # ideal main bearings: shaft and crank one sub-chain
    ((("shaft", "crank"), ("crank", "rod"), ("rod", "piston"), ("piston", "cylinder")),
     [0, 1, 2, 3, 4]),
    ((("shaft", "crank"), ("rod", "piston")), [0, 1, 1, 2, 2]),  # a gap: ideal crankpins
])
def test_links_become_subchains_and_their_terms_add_up(links, expected):
    pairs = tuple(Pair(between=b, eta_forward=0.97, eta_backward=0.95) for b in links)
    model, _, _ = build_model(gots(pairs))
    assert list(model.link_sub) == expected
    mech = gots().mechanism
    assert model.link_J[1] == pytest.approx(3 * mech.crank_mass * mech.crank_radius ** 2)
    for phi in RNG.uniform(0, 4 * math.pi, 20):
        a, J, dJ, M, wk, _, _ = forward(model, phi, 300.0, 0)
        n = model.n_pairs
        assert np.sum(wk[layout.WK_J, :n + 1]) == pytest.approx(J, rel=1e-14)
        assert np.sum(wk[layout.WK_DJ, :n + 1]) == pytest.approx(dJ, rel=1e-14, abs=1e-15)
        assert np.sum(wk[layout.WK_M, :n + 1]) == pytest.approx(M, rel=1e-14, abs=1e-12)
        assert wk[layout.WK_J, 0] >= model.J0 and np.all(wk[layout.WK_J, :n + 1] >= 0)
        # only the cylinders alone (the frame, loaded by the gas) have no inertia
        assert np.all(wk[layout.WK_J, :n + 1][np.unique(model.link_sub[:-1])] > 0)


def test_ideal_pairs_reduce_to_equation_18_in_the_model():
    """η = 1 in both directions: the chain's φ̈ is (18)'s, for every mode vector."""
    ideal = tuple(Pair(between=p.between, eta_forward=1.0, eta_backward=1.0)
                  for p in gots().friction.pairs)
    with_pairs, _, _ = build_model(gots(ideal))
    without, _, _ = build_model(gots(()))
    for phi, omega in zip(RNG.uniform(0, 4 * math.pi, 20), RNG.uniform(-400, 400, 20)):
        ref = forward(without, phi, omega, 0)[0]
        for modes in range(4):
            assert forward(with_pairs, phi, omega, modes)[0] == pytest.approx(ref, rel=1e-13)


@pytest.mark.parametrize("policy", ["power-flow", "paper"])
def test_energy_form_equals_the_acceleration_form(policy):
    """In crank angle the RHS integrates dK/dφ = Σ M − Σ (1 − η*) S_k; it must equal
    J φ̈ + ½ J′ ω² with φ̈ from the chain (the two forms of the same equations)."""
    model, _, _ = build_model(gots(policy=policy))
    for phi, omega, modes in zip(RNG.uniform(0, 4 * math.pi, 30), RNG.uniform(50, 500, 30),
                                 RNG.integers(0, 4, 30)):
        a, J, dJ, M, wk, sw, y = forward(model, phi, omega, modes)
        y[layout.KINETIC] = 0.5 * J * omega ** 2
        out = np.empty_like(y)
        rhs.derivative(model, layout.extras_of(model), True, y, phi, sw, wk, out)
        assert out[layout.KINETIC] == pytest.approx(J * a + 0.5 * dJ * omega ** 2, rel=1e-12,
                                                    abs=1e-12 * abs(M))
        losses = out[layout.W_LOSS0:layout.W_LOSS0 + model.n_pairs]
        work = out[layout.W_GAS] + out[layout.W_LOAD] + out[layout.W_STARTER]
        assert work - losses.sum() == pytest.approx(out[layout.KINETIC], rel=1e-12,
                                                    abs=1e-12 * abs(M))


def test_inverse_chain_recovers_the_forward_motion():
    """Forward: φ̈ from the chain with the power-flow modes of the state. Inverse (the
    prescribed-speed path, solved from the far end): with that φ̈ the drive needed is zero, and
    the pair moments and modes are the same."""
    model, _, _ = build_model(gots())
    n = model.n_pairs
    for phi, omega in zip(RNG.uniform(0, 4 * math.pi, 40), RNG.uniform(-500, 500, 40)):
        wk = work.work_array(model)
        y = state(model, phi, omega)
        sw = np.zeros(layout.N_SWITCHES, dtype=np.int64)
        assert rhs.choose_modes(model, layout.extras_of(model), False, y, phi, sw, wk) == UNIQUE
        a, J, dJ, M, wk, _, _ = forward(model, phi, omega, sw[layout.SW_MODES])
        S, eta = wk[layout.WK_S, :n].copy(), wk[layout.WK_ETA, :n].copy()
        drive, n_ok = inverse.inverse_chain(model, a, omega, float(np.sign(omega)), wk)
        assert n_ok == 1
        scale = np.abs(wk[layout.WK_M, :n + 1]).sum() + J * abs(a) + abs(dJ) * omega ** 2
        assert abs(drive) <= 1e-12 * scale
        np.testing.assert_allclose(wk[layout.WK_S, :n], S, rtol=1e-10, atol=1e-12 * scale)
        np.testing.assert_array_equal(wk[layout.WK_ETA, :n], eta)


@pytest.mark.parametrize("policy", ["power-flow", "paper"])
def test_modes_chosen_at_a_state_follow_the_policy(policy):
    """power-flow: each pair's mode has the sign of the power it transmits (S_k ω); paper: the
    sign of the power of the moments on its shaft side (Σ_{j≤k} M_j) ω; margins ≥ 0 then."""
    model, _, _ = build_model(gots(policy=policy))
    n = model.n_pairs
    for phi, omega in zip(RNG.uniform(0, 4 * math.pi, 40), RNG.uniform(-500, 500, 40)):
        wk = work.work_array(model)
        y = state(model, phi, omega)
        sw = np.zeros(layout.N_SWITCHES, dtype=np.int64)
        rhs.choose_modes(model, layout.extras_of(model), False, y, phi, sw, wk)
        assert sw[layout.SW_DIRECTION] == np.sign(omega)
        _, _, _, _, wk, _, _ = forward(model, phi, omega, sw[layout.SW_MODES])
        rhs.mode_margins(model, sw, wk)
        upstream = np.cumsum(wk[layout.WK_M, :n])
        for k in range(n):
            backward = bool((sw[layout.SW_MODES] >> k) & 1)
            driver = wk[layout.WK_S, k] if policy == "power-flow" else upstream[k]
            assert backward == (driver * omega < 0), (k, driver, omega)
            assert wk[layout.WK_G, k] >= 0.0


def test_locked_at_rest_when_friction_holds_starter_against_compression():
    """At rest in a cylinder's compression, a starter torque whose ratio to the gas torque lies
    in [Π η_f, 1/Π η_b] = [0.9653, 1.0466] (the crank between the pairs carries no moment)
    cannot turn the engine: choose_modes reports LOCKED; with ideal pairs it moves."""
    base = gots()
    model, _, _ = build_model(base)
    phi = 1.5  # cylinder 3 compressing (its firing TDC at 120°)
    y = state(model, phi, 0.0)
    wk = work.work_array(model)
    sw = np.zeros(layout.N_SWITCHES, dtype=np.int64)
    _, _, _, Mg, _, _ = forcing.moments(model, layout.extras_of(model), False, y, phi, sw, wk, True)
    assert Mg < 0  # the gas resists forward motion here
    for ratio, locked in ((1.0, True), (1 / 0.9, False), (0.9, False)):
        m = model._replace(starter_torque=-Mg * ratio)
        sw = np.array([1, 0, 0, 1])
        status = rhs.choose_modes(m, layout.extras_of(m), False, y, phi, sw, wk)
        assert (status == LOCKED) == locked, ratio
        if not locked:
            assert sw[layout.SW_DIRECTION] == (1 if ratio > 1 else -1)
    ideal, _, _ = build_model(gots(()))
    ideal = ideal._replace(starter_torque=-Mg * 1.001)
    J, dJ, w, Mg2, Ml, Ms = forcing.moments(ideal, layout.extras_of(ideal), False, y, phi,
                                            np.array([1, 0, 0, 1]), wk, True)
    assert rhs.acceleration(ideal, layout.extras_of(ideal), phi, J, dJ, w, Mg2, Ml, Ms,
                            np.array([1, 0, 0, 1]), wk) > 0
