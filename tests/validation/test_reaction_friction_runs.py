"""Runs with friction on the joints' reactions (:mod:`transient.core.model.joint_friction`), checked
against what holds independently of the friction model:

* **Work–energy balance** in a spin-up of ``cases/gots_diesel_reaction_friction.toml`` with
  time as the independent variable throughout (φ̈ from the exact solve, ΔK from the state ω and
  J): W_gas + W_load − Σ W_loss,k = ΔK to 1e-8 of the energy throughput at rtol = atol = 1e-11
  (the bound of the constant-η balance in ``test_friction_budget``), every pair's loss ≥ 0 at
  every sample, and the main bearings', crankpins' and piston pins' η* < 1 where the shaft
  drives them, the pistons' η* = 0 (the wall takes no power).
* **No friction**: all coefficients zero, the losses are exactly zero and the motion is the
  scene's without pairs (solved as (18)) to ~ the solver's tolerance (bound 1e-6 of ω).
* **A constant share, in closed form**: a two-stroke whose gas force acts only while its piston
  moves toward the crank, with one pair, the pistons, whose only friction is the share c_p of the
  gas force (the rings' gas-pressure term): the friction force is −c_p P against a gas force P
  along the same path, so W_loss = c_p W_gas exactly, fmep = c_p imep and η_mech = 1 − c_p — the
  reaction model reduces to a constant efficiency 1 − c_p (bound 1e-12: the same quadrature of
  proportional integrands).
* **The diesel's budget at steady speeds** (inverse dynamics, the efficiency study's path):
  η_mech falls with speed at full fuel and with the load at a given speed, the pistons lose most
  at rated speed, the balance imep − fmep − bmep closes per cycle, the losses are ≥ 0 at every
  sample, and the total FMEP at 4400 rpm lies between a fifth of the Chen–Flynn correlation's and
  the correlation's (which counts the valve train and auxiliaries too): an order-of-magnitude
  check, not a fit.
* **At rest**: the rings' tension holds a starter torque up to Σ F_ring |s′_k| (the run ends
  *locked* at once) and lets 10 % more start the engine.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import (
    check_zero_friction_is_ideal,
    closure,
    dense_spin_up,
    loss_is_share_of_transmitted,
)

from transient.analysis.efficiency import chen_flynn_fmep, mean_piston_speed, mechanical_efficiency
from transient.analysis.loads.crank_slider import slider_arrays
from transient.run import integrate, prescribed
from transient.scene import Friction, Gas, Initial, Output, Pair, Run, Starter, load_scene
from transient.scene.queries import gas_table
from transient.study.efficiency import efficiency_study, point_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0
CASE = CASES / "gots_diesel_reaction_friction.toml"


def reaction_case(**changes):
    return replace(load_scene(CASE), **changes)


@pytest.fixture(scope="module")
def spin_up():
    return dense_spin_up(reaction_case)


def test_the_work_energy_balance_closes(spin_up):
    scene, data = spin_up
    tr = data.trajectory
    residual = closure(scene, tr)
    lost = sum(float(tr[f"W_loss_{k}"][-1]) for k in range(1, 5))
    print(f"balance: residual {residual:.1e}; losses "
          f"{[round(float(tr[f'W_loss_{k}'][-1]), 3) for k in range(1, 5)]} J")
    assert residual <= 1e-8
    assert lost > 1e-3 * float(np.max(np.abs(tr["W_gas"])))  # the friction is far above the bound


def test_losses_are_nonnegative_and_eta_means_what_it_says(spin_up):
    scene, data = spin_up
    tr = data.trajectory
    for k in range(1, 5):
        P = tr[f"P_loss_{k}"]
        # (≥ 0 beyond the rounding of a relative speed that vanishes on a breakpoint)
        assert P.min() >= -1e-12 * P.max(), (k, P.min())
        assert np.mean(P) > 0.0
        S, eta = tr[f"S_{k}"], tr[f"eta_{k}"]
        drive = S * tr["omega"] > 0.0
        loss_is_share_of_transmitted(tr, k)
        ok = np.isfinite(eta)
        if k < 4:
            assert np.all(eta[drive] < 1.0) and np.all(eta[~drive & ok] >= 1.0)
        else:
            assert np.all(eta[ok & (S != 0.0)] == 0.0)


def test_without_friction_the_motion_is_the_ideal_one():
    check_zero_friction_is_ideal(reaction_case(run=Run(revolutions=20.0)), "phi")


def kinks_case(mu_pistons=None, rtol=None):
    """60 revolutions of the reaction case, 4 samples a turn; the pistons' μ and the tolerance
    (atol = rtol/100) as given."""
    base = reaction_case(run=Run(revolutions=60.0), output=Output(samples_per_rev=4))
    if mu_pistons is not None:
        base = replace(base, friction=Friction("power-flow", tuple(
            replace(p, mu=mu_pistons) if p.name == "pistons" else p
            for p in base.friction.pairs)))
    if rtol is not None:
        base = replace(base, solver=replace(base.solver, rtol=rtol, atol=rtol / 100))
    return integrate(base)


def test_the_kinks_of_the_side_forces_cost_little_and_keep_the_tolerance():
    """Where a piston's side force changes side, μ·|N| has a kink (several per cylinder and
    cycle); a step rejected with one inside is retaken to end on it (``joint_friction``,
    *Directions and smoothness*). The evaluations of the spin-up stay within 20 % of the same
    scene without the pistons' μ, whose side forces then bend nothing (left to the error test
    alone, the kinks cost over 50 % more). The speed stays within 1e-5 of a run at rtol 1e-11
    (rtol 1e-8, 60 turns: the error the steps accumulate, about 250 rtol, with a factor 4 to
    spare)."""
    run = kinks_case()
    smooth = kinks_case(mu_pistons=0.0)
    tight = kinks_case(rtol=1e-11)
    ratio = run.solver["nfev"] / smooth.solver["nfev"]
    tr, ref = run.trajectory, tight.trajectory
    assert np.array_equal(tr["phi"], ref["phi"])  # the same angles sampled
    err = np.max(np.abs(tr["omega"] - ref["omega"]) / ref["omega"])
    print(f"nfev {run.solver['nfev']} against {smooth.solver['nfev']} ({ratio:.2f}), "
          f"max relative error of ω {err:.1e}")
    assert ratio <= 1.2
    assert err <= 1e-5


def test_a_gas_force_share_with_one_way_power_is_a_constant_efficiency():
    """The one-way engine of ``test_friction_budget``: four cylinders of a two-stroke, force
    pulses only over the expansion half-turn, at 60 rpm."""
    base = reaction_case()
    mech = replace(base.mechanism, strokes=2,
                   firing_angles=(0.0, math.pi / 2, math.pi, 3 * math.pi / 2),
                   bank_angles=(0.0,) * 4)
    gas = Gas(model="trapezoid", p0=0.0, amplitude=1000.0, ramp=math.radians(30),
              duration=math.pi)
    c_p = 0.04
    pair = Pair(between=("piston", "cylinder"), eta_forward=1.0, eta_backward=1.0, name="rings",
                model="reaction", ring_pressure=c_p)
    scene = replace(base, mechanism=mech, gas=gas, friction=Friction("power-flow", (pair,)),
                    run=Run(mode="prescribed-speed", speed=60 * RPM, revolutions=1.0),
                    initial=Initial(0.0, 60 * RPM), output=Output(samples_per_rev=1440))
    tr = prescribed(scene).trajectory
    eff = {k: v for k, (v, _) in mechanical_efficiency(scene, tr).items()}
    assert eff["W_loss_1_per_cycle"] == pytest.approx(c_p * eff["W_in_per_cycle"], rel=1e-12)
    assert eff["fmep_1"] == pytest.approx(c_p * eff["imep"], rel=1e-12)
    assert eff["eta_mech_work"] == pytest.approx(1.0 - c_p, rel=1e-12)


@pytest.fixture(scope="module")
def study():
    rows = efficiency_study(reaction_case(), [1000.0, 2000.0, 3000.0, 4400.0], [1.0, 0.6, 0.3],
                            samples_per_rev=720)
    return {(r["fuel"], r["rpm"]): r for r in rows}


def test_eta_mech_falls_with_speed_and_with_load(study):
    eta = {key: r["eta_mech_work"] for key, r in study.items()}
    for fuel in (1.0, 0.6, 0.3):
        line = [eta[(fuel, n)] for n in (1000.0, 2000.0, 3000.0, 4400.0)]
        print(f"fuel {fuel}: η_mech {np.round(line, 4)}")
        assert np.all(np.diff(line) < 0.0), (fuel, line)
    for n in (1000.0, 2000.0, 3000.0, 4400.0):
        assert eta[(1.0, n)] > eta[(0.6, n)] > eta[(0.3, n)], n


def test_every_point_closes_its_budget_with_nonnegative_losses(study):
    for key, r in study.items():
        assert abs(r["imep"] - r["fmep"] - r["bmep"]) <= 1e-9 * r["imep"], key
        assert r["eta_mech_work"] == pytest.approx(1 - r["fmep"] / r["imep"], rel=1e-12)
        assert all(r[f"fmep_{k}"] > 0.0 for k in range(1, 5))
        assert r["mode_against_power_share_1"] == 0.0
    sc = point_scene(reaction_case(), 4400 * RPM, "power-flow", 720)
    tr = prescribed(sc, 0.3).trajectory
    for k in range(1, 5):
        assert tr[f"P_loss_{k}"].min() >= -1e-12 * tr[f"P_loss_{k}"].max()


def test_the_pistons_lose_most_and_the_fmep_has_the_order_of_chen_flynn(study):
    scene = reaction_case()
    r = study[(1.0, 4400.0)]
    fmep = [r[f"fmep_{k}"] for k in range(1, 5)]
    names = [p.name for p in scene.friction.pairs]
    assert names[int(np.argmax(fmep))] == "pistons"
    x = np.linspace(0.0, scene.mechanism.cycle, 200_001)
    p_max = float(np.max(gas_table(scene)(x)))
    cf = chen_flynn_fmep(p_max, mean_piston_speed(scene.mechanism, 4400 * RPM))
    print("FMEP at 4400 rpm [bar]: " + ", ".join(f"{n} {f / 1e5:.3f}" for n, f in
                                                  zip(names, fmep))
          + f"; total {r['fmep'] / 1e5:.3f}; Chen–Flynn {cf / 1e5:.3f}; ratio {r['fmep'] / cf:.2f}")
    assert 0.2 * cf <= r["fmep"] <= cf


def ring_only(starter_torque: float, phi0: float):
    """The reaction case at rest, without gas, its pistons' only friction the rings' tension
    (every other coefficient zero), started by a constant starter torque."""
    base = reaction_case()
    pairs = tuple(replace(p, mu=0.0, viscous=0.0, ring_pressure=0.0) for p in
                  base.friction.pairs)
    return replace(base, gas=Gas(model="none"), friction=Friction("power-flow", pairs),
                   starter=Starter(starter_torque, 1e4, 1e4), initial=Initial(phi0, 0.0),
                   run=Run(t_end=0.05), output=Output(samples_per_rev=72, dt=1e-3))


@pytest.mark.parametrize("factor, moves", [(0.9, False), (1.1, True)])
def test_at_rest_the_rings_hold_a_starter_below_their_friction(factor, moves):
    """At rest the rings' tension friction F_ring acts against the incipient motion whatever
    the acceleration, so the shaft is held (the run ends *locked*, at t = 0, with its angle)
    exactly when the starter torque is at most Σ F_ring |s′_k(φ)|, the friction's moment on the
    shaft (s′ from the loads analysis' kinematics, written apart from the kernel's); 10 % above
    that it starts forward and the rings lose energy from the first sample."""
    scene = ring_only(1.0, 0.7)
    mech = scene.mechanism
    alpha = 0.7 - np.asarray(mech.firing_angles)
    s1 = slider_arrays(alpha, mech.crank_radius, mech.rod_length, mech.offset)[1]
    ring = scene.friction.pairs[-1].ring_force
    hold = ring * float(np.sum(np.abs(s1)))
    data = integrate(ring_only(factor * hold, 0.7))
    tr = data.trajectory
    if moves:
        assert data.complete, data.message
        assert tr["omega"][-1] > 0.0 and tr["W_loss_4"][-1] > 0.0
    else:
        assert not data.complete and data.message.startswith("locked"), data.message
        assert "locked" in data.events and tr["omega"][-1] == 0.0 and tr["t"][-1] == 0.0
