"""Runs of the swash plate with friction on its joints' reactions
(:mod:`transient.core.model.swash_friction`), checked against what holds independently of it:

* **Work–energy balance** in a spin-up of ``cases/swash_plate_4cyl_reaction_friction.toml`` in
  time throughout at rtol = atol = 1e-11 (``tests/balances.py``), as given and with the mirror
  half (opposed pistons, whose axial forces cancel at the main bearing): ΔK = W_gas + W_load −
  Σ W_loss to 1e-8 of the energies, every pair's loss ≥ 0 at every sample, P_loss = (1 − η*) S ω.
* **No friction**: every coefficient zero, the losses are exactly zero and the motion is the
  ideal scene's (solved as (18)) to ~ the solver's tolerance (bound 1e-6 of ω).
* **The case's budget**: ``transient run`` of the case names the pistons as the pair that loses
  most, and their loss per cycle is at least the rings' tension alone, F_ring times the path of
  every piston (two strokes per turn, :func:`transient.mechanisms.swash_plate.stroke`): a closed
  form lower bound the skirt's, gas-pressure and viscous terms add to.
* **At rest** (the stuck mode): with the rings' tension the only friction and no gas, the shaft
  is held by any starter torque up to F_ring Σ_k |x_D′(φ)| (x_D′ from the reference's kinematics,
  :func:`transient.reference.swash_plate_motion`); 10 % below it the run ends *locked* at once,
  10 % above it the engine starts and the rings lose energy.
"""
from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import (
    check_zero_friction_is_ideal,
    closure,
    dense_spin_up,
    loss_is_share_of_transmitted,
    losses_nonnegative,
)

from transient.mechanisms.swash_plate import stroke
from transient.reference import swash_plate_motion
from transient.run import integrate
from transient.scene import Friction, Gas, Governor, Initial, Load, Output, Run, Starter, load_scene

CASE = Path(__file__).resolve().parents[2] / "cases" / "swash_plate_4cyl_reaction_friction.toml"


def reaction_case(**changes):
    return replace(load_scene(CASE), **changes)


@pytest.mark.parametrize("halves", [1, 2])
def test_the_work_energy_balance_closes_with_nonnegative_losses(halves):
    def make(**changes):
        base = load_scene(CASE)
        return replace(base, mechanism=replace(base.mechanism, halves=halves), **changes)

    scene, data = dense_spin_up(make)
    tr = data.trajectory
    res = closure(scene, tr)
    losses = [float(tr[f"W_loss_{k}"][-1]) for k in range(1, 4)]
    print(f"balance: residual {res:.1e} of the energies; losses {np.round(losses, 3)} J")
    assert res <= 1e-8
    assert min(losses) > 1e-5 * float(np.max(np.abs(tr["W_gas"])))  # 1000× the bound
    losses_nonnegative(scene, tr)
    for k in range(1, 4):
        loss_is_share_of_transmitted(tr, k)


def test_without_friction_the_motion_is_the_ideal_one():
    check_zero_friction_is_ideal(reaction_case(run=Run(t_end=1.0)), "t")


def test_the_case_names_the_pistons_as_losing_most(tmp_path):
    run = subprocess.run([sys.executable, "-m", "transient", "run", str(CASE), "-o",
                          str(tmp_path)], capture_output=True, text=True, timeout=1200)
    assert run.returncode == 0, run.stderr
    out = run.stdout
    print(out)
    assert "(pistons) loses most" in out
    line = next(s for s in out.splitlines() if "(pistons): loss" in s)
    loss = float(line.split("loss ")[1].split(" J/cycle")[0])
    scene = load_scene(CASE)
    mech = scene.mechanism
    rings = scene.friction.pairs[-1].ring_force * mech.halves * 2.0 * float(np.sum(stroke(mech)))
    print(f"pistons {loss:.4g} J/cycle, of which the rings' tension {rings:.4g} J/cycle")
    assert rings < loss < 3.0 * rings


def rings_only(starter_torque: float, phi0: float):
    """The case at rest, without gas, the pistons' ring tension the only friction, started by a
    constant starter torque."""
    base = reaction_case()
    pairs = tuple(replace(p, mu=0.0, viscous=0.0, ring_pressure=0.0) for p in
                  base.friction.pairs)
    return replace(base, gas=Gas(model="none"), governor=Governor(),
                   friction=Friction("power-flow", pairs), load=Load(),
                   starter=Starter(starter_torque, 1e4, 1e4), initial=Initial(phi0, 0.0),
                   run=Run(t_end=0.05), output=Output(samples_per_rev=72, dt=1e-3))


def test_at_rest_the_rings_hold_a_starter_below_their_friction():
    phi0 = 0.7
    scene = rings_only(1.0, phi0)
    mech = scene.mechanism
    xd1 = swash_plate_motion(mech, phi0, 1.0, 0.0)["xd1"]
    hold = scene.friction.pairs[-1].ring_force * mech.halves * float(np.sum(np.abs(xd1)))
    held = integrate(rings_only(0.9 * hold, phi0))
    assert not held.complete and held.message.startswith("locked"), held.message
    assert held.trajectory["omega"][-1] == 0.0 and held.trajectory["t"][-1] == 0.0
    start = rings_only(1.1 * hold, phi0)
    moves = integrate(start)
    assert moves.complete, moves.message
    tr = moves.trajectory
    assert tr["omega"][-1] > 0.0 and tr["W_loss_3"][-1] > 0.0
    losses_nonnegative(start, tr)
