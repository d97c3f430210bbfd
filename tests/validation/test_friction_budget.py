"""The friction budget (:mod:`transient.analysis.efficiency`): each pair's loss per cycle and its
FMEP, the total, imep and bmep, checked against what holds independently of the analysis.

* **Work–energy balance** over a window of a spin-up (time as the independent variable, so φ̈
  comes from the chain solve and ΔK from the state ω): imep − fmep − bmep = ΔK/(C V_d), ΔK
  computed here from the J and ω columns. Relative to imep; the run is at rtol = atol = 1e-11,
  and the balance closes in ``test_friction_runs`` to 1e-8 of the energy throughput, so 1e-8
  of imep (a smaller quantity than the throughput, hence a stricter bound) leaves no room for
  a wrong term: ΔK alone is > 5 % of it.
* **The loss from the chain's quantities**: at every sample, from S_k, η*_k and ω alone, the loss
  is the share 1 − η of the power the driving side puts in, (1 − η_fwd)·S_k ω forward and
  (1 − η_bwd)·(−S_k ω/η_bwd) backward (to rounding), that driving power is ≥ 0 under the
  power-flow policy, and its quadrature between the mode switches and the cycle's corners
  equals the W_loss_k integrated with the motion (1e-7: the bound of the quadrature, see there).
* **Losses ≥ 0 at every sample** of the inverse dynamics (prescribed speed, the efficiency
  study's path) at every speed and load, both pairs.
* **η = η′ = 1**: the pairs lose nothing, every sample and every FMEP exactly 0, η_mech = 1
  (inverse dynamics), and a spin-up runs as the scene without pairs.
* **Closed form**: one pair with constant η through which the power flows one way (a
  four-cylinder two-stroke whose pistons always push, at 60 rpm): W_loss = (1 − η_bwd)·W_gas
  per cycle, fmep = (1 − η_bwd)·imep and η_mech = η_bwd (1e-9).
* **Displacement**: V_d = n·(π D²/4)·2r for the central Gots diesel; an offset engine's stroke
  from its piston positions at the dead centres.
* **Chen–Flynn**: the correlation in SI, and the Gots diesel's FMEP at rated speed of its order.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import dense_spin_up

from transient.analysis.efficiency import (
    chen_flynn_fmep,
    displacement,
    mean_piston_speed,
    mechanical_efficiency,
)
from transient.analysis.loads.crank_slider import slider_arrays
from transient.run import integrate, prescribed
from transient.scene import Friction, Gas, Initial, Output, Pair, Run, load_scene
from transient.scene.queries import gas_table
from transient.study.efficiency import point_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0


def gots_friction(**changes):
    return replace(load_scene(CASES / "gots_diesel_friction.toml"), **changes)


@pytest.fixture(scope="module")
def spin_up():
    """The Gots diesel with both pairs (power-flow) spinning up from 1000 rpm for 4 cycles, in
    time throughout, densely sampled."""
    return dense_spin_up(gots_friction)


def window(scene, tr, first: int, last: int):
    """(φ_a, φ_b, C, i, j): samples nearest the starts of cycles ``first`` and ``last``; C the
    cycles between them (not a whole number: the MEPs are per cycle of that length)."""
    cyc = scene.mechanism.cycle
    i = int(np.argmin(np.abs(tr["phi"] - (scene.initial.phi + first * cyc))))
    j = int(np.argmin(np.abs(tr["phi"] - (scene.initial.phi + last * cyc))))
    a, b = float(tr["phi"][i]), float(tr["phi"][j])
    return a, b, (b - a) / cyc, i, j


def test_mean_effective_pressures_close_the_work_energy_balance(spin_up):
    scene, data = spin_up
    tr = data.trajectory
    a, b, C, i, j = window(scene, tr, 1, 3)
    eff = {k: v for k, (v, _) in mechanical_efficiency(scene, tr, window=(a, b, C)).items()}
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    dK = K[j] - K[i]
    V = displacement(scene.mechanism)
    lhs = eff["imep"] - eff["fmep"] - eff["bmep"]
    residual = (lhs - dK / (C * V)) / eff["imep"]
    print(f"imep {eff['imep']:.6g} Pa, bmep {eff['bmep']:.6g}, fmep {eff['fmep']:.6g} "
          f"({eff['fmep_1']:.6g} + {eff['fmep_2']:.6g}), ΔK/(C V_d) {dK / (C * V):.6g}; "
          f"residual {residual:.2e}")
    assert dK > 0.05 * eff["W_in_per_cycle"] * C  # spinning up: the balance has a ΔK to match
    assert abs(residual) <= 1e-8
    assert eff["fmep"] == pytest.approx(eff["fmep_1"] + eff["fmep_2"], rel=1e-15)
    assert eff["fmep_1"] > 0 and eff["fmep_2"] > 0
    for k in (1, 2):
        assert eff[f"fmep_{k}"] * V == pytest.approx(eff[f"W_loss_{k}_per_cycle"], rel=1e-14)


def test_each_pair_loses_the_share_one_minus_eta_of_its_driving_power(spin_up, sample_integral):
    scene, data = spin_up
    tr = data.trajectory
    _, _, _, i, j = window(scene, tr, 1, 3)
    w = tr["omega"]
    modes = np.asarray(data.events["pair_mode"])
    # The loss has a corner at every breakpoint of the mixed cycle and at every mode switch, so
    # all are cuts of the quadrature; a switch within 3e-6 s (three samples) of a breakpoint
    # (near TDC the pairs switch microseconds from the cycle's corner) is merged with it: the
    # corner then left inside a segment costs ≲ Δ(dP/dt)·δ²/2 ≈ 1e6 W/s·(3e-6 s)²/2 ≈ 5e-6 J,
    # 1e-7 of the loss over the window's twenty of them.
    t_a, t_b = tr["t"][i], tr["t"][j]
    inner = np.concatenate([modes[:, 0], np.asarray(data.events["breakpoint"])[:, 0]])
    inner = inner[(inner > t_a + 3e-6) & (inner < t_b - 3e-6)]  # the window's ends are kept
    cuts = np.concatenate([[t_a, t_b], inner])
    for k, pair in enumerate(scene.friction.pairs, start=1):
        S, eta = tr[f"S_{k}"], tr[f"eta_{k}"]
        fwd, bwd = eta < 1.0, eta > 1.0
        assert fwd.sum() > 100 and bwd.sum() > 100  # both modes occur in the spin-up
        assert np.all(fwd | bwd)
        driving = np.where(fwd, S * w, -S * w / pair.eta_backward)
        share = np.where(fwd, 1.0 - pair.eta_forward, 1.0 - pair.eta_backward)
        loss = (1.0 - eta) * S * w
        scale = np.max(np.abs(loss))
        assert np.max(np.abs(loss - share * driving)) <= 1e-13 * scale
        assert np.max(np.abs(tr[f"P_loss_{k}"] - loss)) <= 1e-13 * scale
        assert driving.min() >= -1e-9 * np.max(np.abs(driving))  # power-flow: never against
        quad = sample_integral(tr["t"], loss, cuts, merge=3e-6)  # [s]: t < 1 s, so absolute
        state = tr[f"W_loss_{k}"][j] - tr[f"W_loss_{k}"][i]
        print(f"pair {k}: ∫(1 − η*)Sω dt = {quad:.10g} J, W_loss = {state:.10g} J, "
              f"{(quad - state) / state:.1e}")
        assert abs(quad - state) <= 1e-7 * state


@pytest.mark.parametrize("fuel", [1.0, 0.3])
def test_losses_are_nonnegative_at_every_sample_of_the_efficiency_study(fuel):
    """The inverse dynamics at constant speed, 500 … 5000 rpm: under power-flow every pair's
    loss is ≥ 0 at every sample (beyond rounding), the budget's balance closes per cycle and
    η_mech = 1 − fmep/imep."""
    scene = gots_friction()
    for rpm in (500.0, 2000.0, 5000.0):
        sc = point_scene(scene, rpm * RPM, "power-flow", 720)
        data = prescribed(sc, fuel)
        tr = data.trajectory
        eff = {k: v for k, (v, _) in mechanical_efficiency(sc, tr).items()}
        for k in (1, 2):
            P = tr[f"P_loss_{k}"]
            assert P.min() >= -1e-9 * np.abs(P).max(), (rpm, k, P.min())
            assert eff[f"fmep_{k}"] > 0
        assert abs(eff["imep"] - eff["fmep"] - eff["bmep"]) <= 1e-9 * eff["imep"]
        assert eff["eta_mech_work"] == pytest.approx(1 - eff["fmep"] / eff["imep"], rel=1e-12)


def test_ideal_pairs_lose_nothing():
    """η = η′ = 1 in both pairs: every loss sample and every FMEP is exactly zero and
    η_mech = 1 (to the trapezoidal drive work of the prescribed-speed path)."""
    base = gots_friction()
    ideal = tuple(replace(p, eta_forward=1.0, eta_backward=1.0) for p in base.friction.pairs)
    scene = replace(base, friction=Friction("power-flow", ideal))
    for rpm in (500.0, 4400.0):
        sc = point_scene(scene, rpm * RPM, "power-flow", 720)
        tr = prescribed(sc).trajectory
        eff = {k: v for k, (v, _) in mechanical_efficiency(sc, tr).items()}
        for k in (1, 2):
            assert np.all(tr[f"P_loss_{k}"] == 0.0) and np.all(tr[f"W_loss_{k}"] == 0.0)
            assert eff[f"fmep_{k}"] == 0.0
        assert eff["fmep"] == 0.0
        print(f"{rpm:g} rpm: η_mech − 1 = {eff['eta_mech_work'] - 1:.1e}")
        assert abs(eff["eta_mech_work"] - 1.0) <= 1e-9


def test_ideal_pairs_lose_nothing_in_a_dynamic_run():
    """The same in the compiled stepper's spin-up: every loss sample and W_loss exactly 0, the
    budget's FMEPs 0, and the motion that of the scene without pairs (the chain of two ideal
    pairs is (18) with the same J and M, solved another way: ω agrees to ~1e-8 at the case's
    rtol 1e-8; bound 1e-6)."""
    base = gots_friction(run=Run(revolutions=20.0))
    ideal = tuple(replace(p, eta_forward=1.0, eta_backward=1.0) for p in base.friction.pairs)
    with_pairs = integrate(replace(base, friction=Friction("power-flow", ideal)))
    without = integrate(replace(base, friction=Friction()))
    tr = with_pairs.trajectory
    for k in (1, 2):
        assert np.all(tr[f"P_loss_{k}"] == 0.0) and np.all(tr[f"W_loss_{k}"] == 0.0)
    phi = np.linspace(tr["phi"][0], tr["phi"][-1], 2001)
    w1 = np.interp(phi, tr["phi"], tr["omega"])
    w0 = np.interp(phi, without.trajectory["phi"], without.trajectory["omega"])
    print(f"max |Δω| / max ω = {np.max(np.abs(w1 - w0)) / np.max(w0):.1e}")
    assert np.max(np.abs(w1 - w0)) <= 1e-6 * np.max(w0)
    window = (tr["phi"][0] + 4 * base.mechanism.cycle, tr["phi"][-1],
              int(round((tr["phi"][-1] - tr["phi"][0]) / base.mechanism.cycle)) - 4)
    eff = {k: v for k, (v, _) in mechanical_efficiency(base, tr, window=window).items()}
    assert eff["fmep"] == 0.0 and eff["fmep_1"] == 0.0 and eff["fmep_2"] == 0.0


def one_way_engine(pair: Pair):
    """A four-cylinder two-stroke crank engine whose gas torque never changes sign (force pulses
    over the expansion half-turn, 90° apart, always one piston pushing) with the one pair
    ``pair``: at 60 rpm the inertia torque is too small to reverse the power through it."""
    base = gots_friction()
    mech = replace(base.mechanism, strokes=2, firing_angles=(0.0, math.pi / 2, math.pi,
                                                              3 * math.pi / 2),
                   bank_angles=(0.0,) * 4)
    gas = Gas(model="trapezoid", p0=0.0, amplitude=1000.0, ramp=math.radians(30),
              duration=math.pi)
    return replace(base, mechanism=mech, gas=gas, friction=Friction("power-flow", (pair,)),
                   run=Run(mode="prescribed-speed", speed=60 * RPM, revolutions=1.0),
                   initial=Initial(0.0, 60 * RPM), output=Output(samples_per_rev=1440))


@pytest.mark.parametrize("between", [("shaft", "crank"), ("crank", "rod")])
def test_one_pair_with_one_way_power_loses_one_minus_eta_of_it(between):
    scene = one_way_engine(Pair(between=between, eta_forward=0.97, eta_backward=0.95, name="p"))
    data = prescribed(scene)
    tr = data.trajectory
    assert np.all(tr["eta_1"] == 1 / 0.95)  # backward throughout: the pistons drive
    eff = {k: v for k, (v, _) in mechanical_efficiency(scene, tr).items()}
    W_gas = eff["W_in_per_cycle"]
    assert eff["W_loss_1_per_cycle"] == pytest.approx(0.05 * W_gas, rel=1e-9)
    assert eff["fmep_1"] == pytest.approx(0.05 * eff["imep"], rel=1e-9)
    assert eff["eta_mech_work"] == pytest.approx(0.95, rel=1e-9)


def test_displacement():
    mech = load_scene(CASES / "gots_diesel_friction.toml").mechanism
    expected = 3 * math.pi / 4 * 0.088**2 * 2 * 0.047
    assert displacement(mech) == pytest.approx(expected, rel=1e-14)
    offset = replace(mech, offset=0.012)
    tdc, bdc = offset.dead_centre_angles()
    s = slider_arrays(np.array([tdc, bdc]), offset.crank_radius, offset.rod_length, 0.012)[0]
    stroke = s[1] - s[0]
    assert stroke > 2 * offset.crank_radius  # an offset lengthens the stroke
    assert displacement(offset) == pytest.approx(3 * offset.piston_area * stroke, rel=1e-13)


def test_chen_flynn_in_si():
    """The correlation in SI against its usual units (bar, m/s): p_max = 100 bar, c_m = 10 m/s
    give 0.4 + 0.005·100 + 0.09·10 + 0.0009·100 = 1.89 bar; c_m = 2 S n."""
    assert chen_flynn_fmep(100e5, 10.0) == pytest.approx(1.89e5, rel=1e-14)
    mech = load_scene(CASES / "gots_diesel_friction.toml").mechanism
    assert mean_piston_speed(mech, 3000 * RPM) == pytest.approx(2 * 0.094 * 50.0, rel=1e-14)


def test_gots_diesel_fmep_has_the_order_of_chen_flynn_at_rated_speed():
    """A sanity check of the order of magnitude, not a fit: the Gots diesel at its rated
    4400 rpm and full fuel (inverse dynamics), the peak pressure of its cycle (p_z = 10.5 MPa)
    and c_m = 13.8 m/s. Its pairs are the main bearings and the crankpins only, while the
    correlation counts all the engine's friction (piston and rings, valve train, auxiliaries
    too), so the scene's FMEP must lie below the correlation's and, for efficiencies of a
    plausible size, within a factor of five of it."""
    scene = gots_friction()
    sc = point_scene(scene, 4400 * RPM, "power-flow", 720)
    eff = {k: v for k, (v, _) in mechanical_efficiency(sc, prescribed(sc).trajectory).items()}
    x = np.linspace(0.0, scene.mechanism.cycle, 200_001)
    p_max = float(np.max(gas_table(scene)(x)))
    assert p_max == pytest.approx(10.5e6, rel=1e-12)
    c_m = mean_piston_speed(scene.mechanism, 4400 * RPM)
    cf = chen_flynn_fmep(p_max, c_m)
    print(f"FMEP {eff['fmep'] / 1e5:.3f} bar (main bearings {eff['fmep_1'] / 1e5:.3f}, "
          f"crankpins {eff['fmep_2'] / 1e5:.3f}); Chen–Flynn {cf / 1e5:.3f} bar at p_max "
          f"{p_max / 1e5:.1f} bar, c_m {c_m:.2f} m/s; ratio {eff['fmep'] / cf:.2f}")
    assert 0.2 * cf <= eff["fmep"] <= cf
