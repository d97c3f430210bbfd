"""Orders of the piston acceleration for every mechanism (module docstring of
:mod:`transient.analysis.orders`: which orders the geometry leaves out at constant speed).

* Radial engine (``cases/radial_5cyl.toml``, link pins at their cylinders' angles, ψ_i = δ_i):
  at constant ω no piston — master or slave — has an odd order ≥ 3 or a half order, to rounding
  (≤ 1e-13 of the first order); with the link pins moved off (ψ_i = δ_i + 10°) the slaves have a
  third order of 1e-4 of the first or more, the master still none.
* Swash plate (``cases/swash_plate_4cyl.toml``): the even orders are the rod's h²/(2ℓ): their
  amplitude times ℓ converges as ℓ grows (to 1e-4 from ℓ = 30 m to 300 m), while the odd orders
  keep their size; no half orders (the cycle is one turn).
* A run (varying ω) of the radial and of the swash plate: :func:`report_for_scene` reports each
  piston against the same engine at constant mean speed; the run adds the orders the constant
  speed lacks; ``[analysis] orders = ["W_2"]`` stores a slave piston's orders as its report
  computes them.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.orders import report_for_scene
from transient.analysis.pistons import piston_kinematics
from transient.run import integrate
from transient.scene import Initial, Output, Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
N = 1440  # grid points per cycle


def constant_speed_orders(mech):
    """Orders and |W|/|W₁| of every piston at constant ω (W ∝ s″) over one engine cycle."""
    phi = np.arange(N) * mech.cycle / N
    dds = piston_kinematics(mech, phi).dds
    amp = np.abs(np.fft.rfft(dds, axis=1))
    orders = np.arange(amp.shape[1]) * 2 * math.pi / mech.cycle
    first = amp[:, [int(round(mech.cycle / (2 * math.pi)))]]
    return orders, amp / first


def masks(orders, top=12.0):
    whole = np.abs(orders - np.round(orders)) < 1e-9
    odd = whole & (np.round(orders) % 2 == 1) & (orders >= 3) & (orders <= top)
    half = ~whole & (orders <= top)
    even = whole & (np.round(orders) % 2 == 0) & (orders >= 2) & (orders <= top)
    return odd, half, even


def test_radial_pistons_have_no_odd_or_half_orders_at_constant_speed():
    mech = load_scene(CASES / "radial_5cyl.toml").mechanism
    assert mech.link_angles == pytest.approx(mech.slave_banks, abs=1e-15)  # ψ_i = δ_i
    orders, rel = constant_speed_orders(mech)
    odd, half, even = masks(orders)
    assert rel[:, odd].max() <= 1e-13 and rel[:, half].max() <= 1e-13
    assert rel[:, orders == 2.0].min() > 0.1  # the second order is there, master and slaves
    moved = replace(mech, link_angles=tuple(d + math.radians(10.0) for d in mech.slave_banks))
    orders, rel = constant_speed_orders(moved)
    three = orders == 3.0
    assert rel[0, three] <= 1e-13  # the master is a crank-slider still
    assert rel[1:, three].min() >= 1e-4
    assert rel[:, half].max() <= 1e-13


def test_swash_plate_even_orders_are_the_rods():
    mech = load_scene(CASES / "swash_plate_4cyl.toml").mechanism
    scaled = {}
    for ell in (3.0, 30.0, 300.0):
        orders, rel = constant_speed_orders(replace(mech, rod_length=ell))
        odd, half, even = masks(orders)
        assert not half.any()
        scaled[ell] = rel[:, even] * ell, rel[:, odd]
    (e30, o30), (e300, o300) = scaled[30.0], scaled[300.0]
    assert e300 == pytest.approx(e30, rel=1e-4)  # the next term is O(h⁴/ℓ³): ≤ 1.1e-5 here
    assert o300 == pytest.approx(o30, rel=1e-5)
    assert o300[:, 0].min() > 0.1  # the Hooke joint's third order: kinematic


@pytest.mark.parametrize("case, run, omega", [("radial_5cyl.toml", Run(revolutions=12.0), 177.7),
                                              ("swash_plate_4cyl.toml", Run(t_end=1.0), 50.0)])
def test_report_for_every_piston_of_a_run(case, run, omega):
    """From about the case's steady speed (found by running it to its end), so that the orders
    the run adds are the speed ripple's, not a trend's leakage: the last cycle's W drifts by
    less than 1e-3 of its first order."""
    scene = load_scene(CASES / case)
    scene = replace(scene, run=run, output=Output(samples_per_rev=360),
                    initial=Initial(phi=0.0, omega=omega))
    data = integrate(scene)
    assert data.complete, data.message
    mech = scene.mechanism
    cuts = np.asarray(data.events.get("breakpoint", np.zeros((0, 2))))[:, 1]
    for k in range(1, mech.n_cylinders + 1):
        rep = report_for_scene(scene, data.trajectory, k, samples_per_cycle=N // 2, cycles=1,
                               cuts=cuts)
        odd, half, even = masks(rep.orders)
        # constant speed against the run: the speed's variation adds what the geometry lacks
        assert rep.delta[-1] > 1e-3
        assert abs(rep.drift[-1]) < 1e-3 * rep.first[-1]
        added = rep.relative_added[-1]
        if mech.name == "articulated":
            assert rep.relative_constant[-1][odd | half].max() <= 1e-12
            assert added[half].max() > 1e-5 and added[odd].max() > 1e-5
        else:
            assert added[even].max() > 1e-5
        assert rep.amplitude[-1][rep._k(1.0)] > 0.0
    with pytest.raises(ValueError, match="out of range"):
        report_for_scene(scene, data.trajectory, mech.n_cylinders + 1)


def test_stored_piston_orders_of_a_slave_match_its_report():
    """``[analysis] orders = ["W_2"]`` of a radial engine (a slave piston) stores what the
    odd-harmonic report computes for that piston, cycle by cycle."""
    from transient.analysis.requested import requested_analyses
    from transient.scene import Analysis

    scene = load_scene(CASES / "radial_5cyl.toml")
    scene = replace(scene, run=Run(revolutions=8.0), output=Output(samples_per_rev=360),
                    initial=Initial(phi=0.0, omega=177.7),
                    analysis=Analysis(orders=("W_2",), samples_per_cycle=720, detrend="none"))
    data = integrate(scene)
    stored = requested_analyses(scene, data.trajectory, data.events)
    cuts = np.asarray(data.events["breakpoint"])[:, 1]
    rep = report_for_scene(scene, data.trajectory, 2, samples_per_cycle=720, cuts=cuts)
    amp, unit = stored["orders_W_2_amplitude"]
    assert unit == "m/s^2" and amp.shape[0] == rep.amplitude.shape[0] == 4  # 8 rev
    k = amp.shape[1]
    assert amp == pytest.approx(rep.amplitude[:, :k], rel=1e-12, abs=1e-9 * rep.first.max())
