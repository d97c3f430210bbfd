"""Runs with a constant-η pair at the main bearings among reaction pairs (:mod:`transient.core.
reactions`, *A constant-η pair at the main bearings*), checked against what is written apart:

* **The chain of one pair**: with every reaction pair's coefficients zero, the mix is the serial
  chain of its one constant-η pair (Antonyuk et al. (22)–(25), ``transient.core.model.chain``), a
  model written apart from the joints' Newton–Euler: the same mode switches at the same angles,
  the same motion and the same loss, to the sum of the two runs' own errors (each measured
  against its run at a hundredth of the tolerance, ``tests/own_error.py``), for the
  crank-slider and the articulated mechanism; and at prescribed speeds (the efficiency study's inverse dynamics) the
  same η_mech and loss.
* **Work–energy balance** in a spin-up of ``cases/gots_diesel_mixed_friction.toml`` with every
  friction on: W_gas + W_load − Σ W_loss,k = ΔK to 1e-8 of the throughput (the bound of the
  reaction and constant-η balances), every loss ≥ 0 at every sample, the main bearings' η*
  exactly η_fwd where the shaft drives them and 1/η_bwd where the throws do, their loss in no
  cylinder.
* **At rest**: with the joints frictionless, the main bearings hold a drive s·G against the gas
  moment −G for η_bwd ≤ s ≤ 1/η_fwd (the chain's static reaction ratio of one pair): a drive
  ramp releases the shaft where it reaches either end, to 1e-8 of the drive.
* **The study**: η_mech falls with speed and with load, and every point closes its budget.
* **A mapped pair at the main bearings** (``eta_table``): a map of one point is the constant pair
  bit for bit; with the joints frictionless the mix is the chain of its one mapped pair (whose
  maps ``eta_table`` solves its own way), to the sum of their own errors, which the map's
  kinks inside steps make larger than the tolerance; with every friction on, the balance
  closes and every loss is ≥ 0.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import (
    check_release_at_holds,
    closure,
    constant_main_bearings,
    dense_spin_up,
    loss_is_share_of_transmitted,
    losses_nonnegative,
    with_main_bearings,
    without_friction,
)
from own_error import assert_agree

from transient.run import integrate, prescribed
from transient.scene import Friction, Initial, Load, Output, Pair, Run, Starter, load_scene
from transient.study.efficiency import efficiency_study, point_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = np.pi / 30.0


def mixed_case(**changes):
    return replace(load_scene(CASES / "gots_diesel_mixed_friction.toml"), **changes)


def radial_mixed(**changes):
    """The radial case's reaction pairs with its main bearings as a constant-η pair (the
    efficiencies of the diesel's case)."""
    base = load_scene(CASES / "radial_5cyl_reaction_friction.toml")
    return replace(constant_main_bearings(base), **changes)


def coupling(scene) -> Pair:
    return next(p for p in scene.friction.pairs if p.model != "reaction")


def mapped_main_bearings() -> Pair:
    """The main bearings' efficiency map of ``cases/gots_diesel_eta_map.toml``."""
    return load_scene(CASES / "gots_diesel_eta_map.toml").friction.pairs[0]


def frictionless_joints(scene):
    """``scene`` with its reaction pairs' coefficients all zero, the constant-η pair kept."""
    return replace(scene, friction=Friction("power-flow", without_friction(scene.friction.pairs)))


def one_pair_chain(scene):
    """``scene`` with its constant-η pair alone: the serial chain of one pair."""
    return replace(scene, friction=Friction("power-flow", (coupling(scene),)))


@pytest.mark.parametrize("make", [mixed_case, radial_mixed], ids=["crank-slider", "radial"])
def test_with_frictionless_joints_the_mix_is_the_chain_of_its_one_pair(make):
    """The two models take their own steps, so over 30 revolutions they agree to the sum of
    their own errors (``tests/own_error.py``), not to one step's tolerance."""
    base = make(run=Run(revolutions=30.0), output=Output(samples_per_rev=8))
    base = replace(base, solver=replace(base.solver, rtol=1e-10, atol=1e-12))
    scenes = frictionless_joints(base), one_pair_chain(base)
    mix, chain = (integrate(s) for s in scenes)
    assert mix.complete and chain.complete, (mix.message, chain.message)
    a, b = mix.trajectory, chain.trajectory
    switches_mix, switches_chain = mix.events["pair_mode"], chain.events["pair_mode"]
    print(f"{switches_mix.shape[0]} mode switches; final ω {a['omega'][-1]!r} against "
          f"{b['omega'][-1]!r}, W_loss_1 {a['W_loss_1'][-1]!r} against {b['W_loss_1'][-1]!r}")
    assert switches_mix.shape[0] == switches_chain.shape[0] > 50
    assert np.max(np.abs(switches_mix[:, 1] - switches_chain[:, 1])) <= 1e-6
    assert_agree(scenes[0], mix, scenes[1], chain, ("t", "omega", "W_loss_1"))
    assert np.allclose(a["eta_1"], b["eta_1"], rtol=0.0, atol=1e-15)  # the same modes
    for k in range(2, len(base.friction.pairs) + 1):
        assert np.all(a[f"W_loss_{k}"] == 0.0), k


@pytest.mark.parametrize("make", [mixed_case, radial_mixed], ids=["crank-slider", "radial"])
def test_at_prescribed_speeds_the_mix_is_the_chain_of_its_one_pair(make):
    base = frictionless_joints(make())
    for rpm, fuel in ((1500.0, 1.0), (3500.0, 0.4)):
        rows = [efficiency_study(sc, [rpm], [fuel], samples_per_rev=720)[0]
                for sc in (base, one_pair_chain(base))]
        print(f"{rpm} rpm, fuel {fuel}: η_mech {rows[0]['eta_mech_work']!r} against "
              f"{rows[1]['eta_mech_work']!r}")
        assert rows[0]["eta_mech_work"] == pytest.approx(rows[1]["eta_mech_work"], rel=1e-10)
        assert rows[0]["fmep_1"] == pytest.approx(rows[1]["fmep_1"], rel=1e-9)
        assert rows[0]["fmep_1"] > 0.0 and rows[0]["mode_against_power_share_1"] == 0.0


@pytest.fixture(scope="module")
def spin_up():
    return dense_spin_up(mixed_case)


def test_the_work_energy_balance_closes_with_losses_that_are_shares(spin_up):
    scene, data = spin_up
    tr = data.trajectory
    residual = closure(scene, tr)
    print(f"balance: residual {residual:.1e}; losses "
          f"{[round(float(tr[f'W_loss_{k}'][-1]), 3) for k in range(1, 5)]} J; "
          f"{data.events['pair_mode'].shape[0]} mode switches")
    assert residual <= 1e-8
    losses_nonnegative(scene, tr)
    for k in range(1, 5):
        assert tr[f"W_loss_{k}"][-1] > 0.0
        loss_is_share_of_transmitted(tr, k)
    main = coupling(scene)
    drives = tr["S_1"] * tr["omega"]
    assert np.all(tr["eta_1"][drives > 0.0] == main.eta_forward)
    assert np.all(tr["eta_1"][drives < 0.0] == 1.0 / main.eta_backward)
    assert np.any(drives > 0.0) and np.any(drives < 0.0)
    assert data.events["pair_mode"].shape[0] > 0
    for c in range(1, scene.mechanism.n_cylinders + 1):
        assert np.all(np.isnan(tr[f"P_loss_1_cyl{c}"]))
        assert np.all(np.isfinite(tr[f"P_loss_4_cyl{c}"]))


def test_the_main_bearings_release_the_shaft_at_their_reaction_ratio():
    """Gas resisting with −G at rest, joints frictionless: the main bearings hold a drive from
    η_bwd G to G/η_fwd (the static reaction ratio of one pair); a drive ramping past either
    end releases the shaft at the instant it reaches it."""
    base = frictionless_joints(mixed_case(starter=Starter(0.0, 1.0, 1.0),
                                          output=Output(samples_per_rev=72, dt=1e-2),
                                          initial=Initial(5.5, 0.0)))  # (a cylinder in
    base = replace(base, solver=replace(base.solver, rtol=1e-10, atol=1e-10))  # compression)
    probe = integrate(replace(base, load=Load(), friction=Friction(), run=Run(t_end=1e-6)))
    G = -float(probe.trajectory["M_gas"][0])
    assert G > 100.0
    main = coupling(base)
    check_release_at_holds(base, G / main.eta_forward, main.eta_backward * G)


@pytest.fixture(scope="module")
def study():
    rows = efficiency_study(mixed_case(), [1000.0, 2500.0, 4400.0], [1.0, 0.5],
                            samples_per_rev=720)
    return {(r["fuel"], r["rpm"]): r for r in rows}


def test_eta_mech_falls_with_speed_and_load_and_every_point_closes(study):
    eta = {key: r["eta_mech_work"] for key, r in study.items()}
    for fuel in (1.0, 0.5):
        line = [eta[(fuel, n)] for n in (1000.0, 2500.0, 4400.0)]
        print(f"fuel {fuel}: η_mech {np.round(line, 4)}")
        assert np.all(np.diff(line) < 0.0), (fuel, line)
    for n in (1000.0, 2500.0, 4400.0):
        assert eta[(1.0, n)] > eta[(0.5, n)], n
    for key, r in study.items():
        assert abs(r["imep"] - r["fmep"] - r["bmep"]) <= 1e-9 * r["imep"], key
        assert all(r[f"fmep_{k}"] > 0.0 for k in range(1, 5))
        assert r["mode_against_power_share_1"] == 0.0
    tr = prescribed(point_scene(mixed_case(), 4400 * RPM, "power-flow", 720), 0.5).trajectory
    for k in range(1, 5):
        assert tr[f"P_loss_{k}"].min() >= -1e-12 * tr[f"P_loss_{k}"].max(), k


def test_a_mapped_pair_at_the_main_bearings():
    """The one-point map is the constant pair bit for bit (one process, one CPU: the same
    arithmetic). The mix and the chain of a mapped pair meet the map's kinks inside their own
    steps, so they agree to the sum of their own errors (``tests/own_error.py``)."""
    base = mixed_case(run=Run(revolutions=30.0), output=Output(samples_per_rev=8))
    base = replace(base, solver=replace(base.solver, rtol=1e-10, atol=1e-12))
    main, mapped = coupling(base), mapped_main_bearings()
    assert mapped.model == "table" and len(mapped.speed) > 1 and len(mapped.torque) > 1
    one_point = replace(mapped, speed=(0.0,), torque=(0.0,),
                        eta_forward_map=((main.eta_forward,),),
                        eta_backward_map=((main.eta_backward,),))
    a, b = integrate(base), integrate(with_main_bearings(base, one_point))
    assert all(np.array_equal(a.trajectory[k], b.trajectory[k], equal_nan=True)
               for k in a.trajectory)

    scenes = (frictionless_joints(with_main_bearings(base, mapped)),
              one_pair_chain(with_main_bearings(base, mapped)))
    mix, chain = (integrate(s) for s in scenes)
    x, y = mix.trajectory, chain.trajectory
    print(f"{mix.events['pair_mode'].shape[0]} mode switches; final ω {x['omega'][-1]!r} against "
          f"{y['omega'][-1]!r}; W_loss_1 {x['W_loss_1'][-1]!r} against {y['W_loss_1'][-1]!r}")
    assert mix.events["pair_mode"].shape[0] == chain.events["pair_mode"].shape[0] > 50
    assert_agree(scenes[0], mix, scenes[1], chain, ("omega", "W_loss_1", "eta_1"))

    full = with_main_bearings(mixed_case(run=Run(revolutions=60.0)), mapped)
    tr = integrate(full).trajectory
    assert closure(full, tr) <= 1e-8
    losses_nonnegative(full, tr)
    rows = [efficiency_study(sc, [3000.0], [0.6], samples_per_rev=720)[0]
            for sc in (frictionless_joints(full), one_pair_chain(full))]
    assert rows[0]["eta_mech_work"] == pytest.approx(rows[1]["eta_mech_work"], rel=1e-10)

