"""Runs of the radial with friction on its joints' reactions
(:mod:`transient.core.articulated_friction`, ``cases/radial_5cyl_reaction_friction.toml``), checked
against what holds independently of the friction model:

* **Work–energy balance** in a spin-up with time as the independent variable throughout:
  W_gas + W_load − Σ W_loss,k = ΔK to 1e-8 of the energy throughput at rtol = atol = 1e-11 (the
  crank-slider's bound, ``test_reaction_friction_runs``), every pair's loss ≥ 0 at every sample,
  P_loss = (1 − η*) S ω.
* **No friction**: all coefficients zero, the losses are exactly zero and the motion is the
  scene's without pairs (solved as (18)) to ~ the solver's tolerance (bound 1e-6 of ω).
* **The case**: its steady budget closes and names the pair that loses most, the pistons.
* **Prescribed speed** (inverse dynamics): the drive torque and each pair's S and loss are the
  Newton–Euler reference's at every state checked, to rounding.
* **At rest** (the stuck mode, :mod:`transient.core.stuck`): without gas, the joints' friction
  holds a drive between M₋ and M₊, computed by the independent static Newton–Euler
  (:func:`transient.reference.articulated_joint_forces` at ω = φ̈ = 0 with the friction opposing
  σ = ±1); a drive ramping past M₊ (past M₋) releases the shaft forward (backward) at the instant
  it reaches it, to 1e-8 of M₊.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.efficiency import mechanical_efficiency
from transient.assemble import build_model
from transient.run import integrate, prescribed
from transient.reference import articulated_joint_forces
from transient.scene import Friction, Gas, Initial, Load, Output, Run, Starter, load_scene

from balances import (closure, dense_spin_up, loss_is_share_of_transmitted, losses_nonnegative,
                      without_friction)

CASES = Path(__file__).resolve().parents[2] / "cases"
CASE = CASES / "radial_5cyl_reaction_friction.toml"
N_PAIRS = 6


def reaction_case(**changes):
    return replace(load_scene(CASE), **changes)


@pytest.fixture(scope="module")
def spin_up():
    return dense_spin_up(reaction_case)


def test_the_work_energy_balance_closes_and_every_loss_is_a_loss(spin_up):
    scene, data = spin_up
    tr = data.trajectory
    residual = closure(scene, tr)
    losses = [float(tr[f"W_loss_{k}"][-1]) for k in range(1, N_PAIRS + 1)]
    print(f"balance: residual {residual:.1e}; losses {np.round(losses, 3)} J")
    assert residual <= 1e-8
    assert min(losses) > 1e-6 * float(np.max(np.abs(tr["W_gas"])))  # every pair loses
    losses_nonnegative(scene, tr)
    for k in range(1, N_PAIRS + 1):
        loss_is_share_of_transmitted(tr, k)


def test_without_friction_the_motion_is_the_ideal_one():
    base = reaction_case(run=Run(revolutions=20.0))
    zero = integrate(replace(base, friction=Friction("power-flow",
                                                     without_friction(base.friction.pairs))))
    ideal = integrate(replace(base, friction=Friction()))
    assert zero.complete and ideal.complete
    tr = zero.trajectory
    for k in range(1, N_PAIRS + 1):
        assert np.all(tr[f"P_loss_{k}"] == 0.0) and np.all(tr[f"W_loss_{k}"] == 0.0)
    phi = np.linspace(tr["phi"][0], tr["phi"][-1], 2001)
    w1 = np.interp(phi, tr["phi"], tr["omega"])
    w0 = np.interp(phi, ideal.trajectory["phi"], ideal.trajectory["omega"])
    print(f"max |Δω| / max ω = {np.max(np.abs(w1 - w0)) / np.max(w0):.1e}")
    assert np.max(np.abs(w1 - w0)) <= 1e-6 * np.max(w0)


def test_the_case_budget_closes_and_names_the_pistons():
    scene = load_scene(CASE)
    data = integrate(scene)
    assert data.complete, data.message
    eff = {k: v for k, (v, _) in mechanical_efficiency(scene, data.trajectory).items()}
    losses = [eff[f"W_loss_{k}_per_cycle"] for k in range(1, N_PAIRS + 1)]
    names = [p.name for p in scene.friction.pairs]
    print(dict(zip(names, np.round(losses, 3))), f"η_mech = {eff['eta_mech_work']:.4f}")
    assert names[int(np.argmax(losses))] == "pistons"
    assert min(losses) > 0.0
    assert abs(eff["energy_balance_residual"]) <= 1e-9
    assert 0.8 < eff["eta_mech_work"] < 1.0


def static_hold(scene, phi, P, sigma):
    """The drive on the shaft that the joints hold at rest at φ under the gas forces P with the
    friction opposing σ: −Σ T of the Newton–Euler reference at ω = φ̈ = 0."""
    model, _, _ = build_model(scene)
    ref = articulated_joint_forces(scene.mechanism, phi, 0.0, P, model.rx_par, sigma=sigma,
                                   epsilon=0.0)
    return -float(ref.throw_torque.sum())


def drive(d0, d1, t1):
    """A drive on the shaft from d0 at t = 0 to d1 at t1 [N m] (a schedule on a negative load)."""
    return Load(torque=-1.0, schedule_time=(0.0, t1), schedule_scale=(d0, d1))


@pytest.mark.parametrize("gas", [True, False])
def test_the_joints_release_the_radial_at_the_newton_euler_hold(gas):
    """With the gas (the pressures at rest depend on the angle only: the probe's) or without,
    where only the drive and the friction load the joints."""
    phi0 = 5.5
    base = reaction_case(starter=Starter(0.0, 1.0, 1.0), initial=Initial(phi0, 0.0),
                         output=Output(samples_per_rev=72, dt=1e-2))
    if not gas:
        base = replace(base, gas=Gas(model="none"))
    base = replace(base, solver=replace(base.solver, rtol=1e-10, atol=1e-10))
    mech = base.mechanism
    P = np.zeros(mech.n_cylinders)
    if gas:
        probe = integrate(replace(base, load=Load(), friction=Friction(), run=Run(t_end=1e-6)))
        P = np.array([(probe.trajectory[f"p_{k + 1}"][0] - base.gas.p0) * mech.piston_area
                      for k in range(mech.n_cylinders)])
        assert np.max(np.abs(P)) > 1e3
    hold_fwd, hold_bwd = static_hold(base, phi0, P, 1.0), static_hold(base, phi0, P, -1.0)
    print(f"gas forces {np.round(P)} N; holds {hold_fwd:.9g} N m forward, {hold_bwd:.9g} N m "
          f"backward")
    assert hold_bwd < hold_fwd
    mid = 0.5 * (hold_fwd + hold_bwd)
    width = hold_fwd - hold_bwd
    for target, sign in ((hold_fwd, 1.0), (hold_bwd, -1.0)):
        end = mid + sign * width  # reached at t = 1 s
        scene = replace(base, load=drive(mid, end, 1.0), run=Run(t_end=0.8))
        data = integrate(scene)
        assert data.complete, data.message
        ev, tr = data.events, data.trajectory
        t_rel = ev["released"][0, 0]
        t_star = (target - mid) / (end - mid)
        print(f"σ = {sign:+g}: release at {t_rel!r}, Newton–Euler {t_star!r}")
        assert ev["stuck"][0, 0] == 0.0 and ev["released"].shape[0] == 1
        assert abs(t_rel - t_star) * abs(end - mid) <= 1e-8 * abs(hold_fwd)
        held = tr["t"] <= t_rel
        assert np.all(tr["omega"][held] == 0.0) and np.all(tr["phi"][held] == phi0)
        after = tr["t"] > t_rel + 0.05
        assert np.all(sign * tr["omega"][after][:5] > 0.0)
        losses_nonnegative(scene, tr)


def test_prescribed_speed_drive_is_the_newton_euler_torque():
    """Inverse dynamics at 1500 rpm (the efficiency study's path): at every tenth sample the drive
    torque, each pair's S and its power lost are the reference's at that state (gas forces from
    the run's pressures, φ̈ = 0), to 1e-12 of the largest torque."""
    scene = reaction_case(run=Run(mode="prescribed-speed", speed=1500 * np.pi / 30.0,
                                  revolutions=2.0),
                          initial=Initial(0.3, 1500 * np.pi / 30.0))
    tr = prescribed(scene).trajectory
    model, _, _ = build_model(scene)
    mech = scene.mechanism
    worst = 0.0
    for i in range(0, tr["phi"].size, 10):
        P = np.array([(tr[f"p_{k + 1}"][i] - scene.gas.p0) * mech.piston_area
                      for k in range(mech.n_cylinders)])
        w = tr["omega"][i]
        ref = articulated_joint_forces(mech, tr["phi"][i], w, P, model.rx_par, epsilon=0.0)
        scale = np.abs(ref.throw_torque).sum() + abs(tr["M_load"][i])
        errs = [abs(tr["M_drive"][i] + tr["M_load"][i] + ref.throw_torque.sum()) / scale]
        for k in range(N_PAIRS):
            errs.append(abs(tr[f"S_{k + 1}"][i] - ref.S[k]) / scale)
            errs.append(abs(tr[f"P_loss_{k + 1}"][i] - ref.L[k] * w) / (scale * w))
        worst = max(worst, *errs)
        assert max(errs) <= 1e-12, (i, errs)
    print(f"largest relative difference {worst:.1e}")
