"""Runs with efficiency maps (``model = "table"``, ``cases/gots_diesel_eta_map.toml``): a constant
map is the constant-η run bit for bit; the work–energy balance closes and no loss is negative;
every sample's η* is the map's value at that sample's own |ω| and |S| (solved at the instant,
not lagged), read by scipy's interpolator; the efficiency study (inverse dynamics) agrees with
the dynamic solve's relation between S and η*."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import closure, losses_nonnegative
from scipy.interpolate import RegularGridInterpolator

from transient.run import integrate, prescribed
from transient.scene import Friction, Gas, Initial, Load, Output, Run, Starter, load_scene
from transient.study.efficiency import efficiency_study

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0


def constant_map(pair):
    """``pair`` as a table pair whose map is its two constants on a 2 × 3 grid."""
    return replace(pair, model="table", eta_forward=1.0, eta_backward=1.0,
                   speed=(0.0, 600.0), torque=(0.0, 10.0, 100.0),
                   eta_forward_map=((pair.eta_forward,) * 3,) * 2,
                   eta_backward_map=((pair.eta_backward,) * 3,) * 2)


def map_scene(**changes):
    return replace(load_scene(CASES / "gots_diesel_eta_map.toml"), **changes)


@pytest.mark.parametrize("policy", ["power-flow", "paper"])
@pytest.mark.parametrize("mode", ["dynamic", "prescribed"])
def test_a_constant_map_runs_bit_for_bit_as_constant_eta(mode, policy):
    """gots_diesel_friction with each pair's constants as a map: the same trajectory to the last
    bit (the solve ends in the constant-η chain at the map's η*, which is the constant exactly)."""
    base = load_scene(CASES / "gots_diesel_friction.toml")
    base = replace(base, run=Run(revolutions=30.0),
                   friction=Friction(policy, base.friction.pairs))
    mapped = replace(base, friction=Friction(policy,
                                             tuple(constant_map(p) for p in base.friction.pairs)))
    if mode == "dynamic":
        a, b = integrate(base), integrate(mapped)
        assert a.complete and b.complete
        if policy == "power-flow":  # (the paper's criterion keeps both pairs backward here)
            assert a.events["pair_mode"].shape[0] > 10
        assert a.events.keys() == b.events.keys()
        for name in a.events:
            assert np.array_equal(a.events[name], b.events[name]), name
    else:
        a, b = (prescribed(replace(s, run=Run(mode="prescribed-speed", speed=3000 * RPM,
                                              revolutions=2.0)), 0.7) for s in (base, mapped))
    assert a.trajectory.keys() == b.trajectory.keys()
    for name in a.trajectory:
        assert np.array_equal(a.trajectory[name], b.trajectory[name], equal_nan=True), name


def scipy_eta(pair, backward, w_abs, x):
    """η* of a table pair by scipy: the point held to the grid, bilinear inside."""
    w, s = np.array(pair.speed), np.array(pair.torque)
    pts = np.column_stack([np.clip(w_abs, w[0], w[-1]), np.clip(x, s[0], s[-1])])
    fwd = RegularGridInterpolator((w, s), np.array(pair.eta_forward_map))(pts)
    bwd = RegularGridInterpolator((w, s), np.array(pair.eta_backward_map))(pts)
    return np.where(backward, 1.0 / bwd, fwd)


def check_samples(scene, tr):
    """Every sample's η*_1 is the map's at its own |ω| and |S_1|, in the mode its power gives."""
    pair = scene.friction.pairs[0]
    S, w = tr["S_1"], tr["omega"]
    sigma = np.where(w >= 0.0, 1.0, -1.0)  # (at rest: the incipient motion's, forward here)
    want = scipy_eta(pair, S * sigma < 0.0, np.abs(w), np.abs(S))
    np.testing.assert_allclose(tr["eta_1"], want, rtol=1e-12)


def checked_run(scene):
    """The run's trajectory, complete, its balance closed to 1e-8, every loss ≥ 0 and every η*
    the map's at its own sample (:func:`check_samples`)."""
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    assert closure(scene, tr) <= 1e-8
    losses_nonnegative(scene, tr)
    check_samples(scene, tr)
    return tr


def test_gots_map_balance_losses_and_eta_at_every_sample():
    """The case over 60 revolutions in crank angle: balance ≤ 1e-8, losses ≥ 0, η* from the map
    at each sample's own state, and η* really varies (forward and backward, over the grid)."""
    scene = map_scene(run=Run(revolutions=60.0))
    tr = checked_run(scene)
    fwd = tr["eta_1"][tr["eta_1"] < 1.0]
    bwd = tr["eta_1"][tr["eta_1"] > 1.0]
    assert fwd.size and bwd.size and np.ptp(fwd) > 5e-3 and np.ptp(1.0 / bwd) > 5e-3


def test_gots_map_in_time_from_rest_and_coasting():
    """Time as independent variable (a switch speed above every ω): a start from rest with a
    starter and a coast-down without gas, where φ̈ itself comes from the solve; the balance
    ≤ 1e-8 and losses ≥ 0 throughout."""
    base = map_scene()
    common = dict(solver=replace(base.solver, rtol=1e-11, atol=1e-11, switch_speed=1e4),
                  output=Output(samples_per_rev=72, dt=2e-4))
    start = map_scene(starter=Starter(300.0, 600 * RPM, 400 * RPM), initial=Initial(0.0, 0.0),
                      run=Run(revolutions=5.0, t_end=1.0), **common)
    coast = map_scene(run=Run(t_end=0.3), gas=Gas(), load=Load(fan=5e-3), **common)
    for scene in (start, coast):
        tr = checked_run(scene)
        assert tr["W_loss_1"][-1] > 0


def test_efficiency_study_with_the_map():
    """The study's inverse dynamics: η* at each sample from the map at its own S, losses ≥ 0,
    and η_mech falling with speed at full and at half load (the map's drag grows with speed)."""
    scene = map_scene()
    sc = replace(scene, run=Run(mode="prescribed-speed", speed=4000 * RPM, revolutions=2.0),
                 initial=Initial(0.0, 4000 * RPM))
    data = prescribed(sc, 1.0)
    check_samples(sc, data.trajectory)
    losses_nonnegative(sc, data.trajectory)
    rows = efficiency_study(scene, [1000, 5000], fuels=(1.0, 0.5), samples_per_rev=360)
    eta = {(r["fuel"], r["rpm"]): r["eta_mech_work"] for r in rows}
    for fuel in (1.0, 0.5):
        assert eta[(fuel, 5000)] < eta[(fuel, 1000)]
    assert all(r["inconsistent_samples"] == 0 for r in rows)
