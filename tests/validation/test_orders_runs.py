"""Order analysis of a real run, in crank angle and in time (transient.analysis.orders).

The Gots diesel spin-up (cases/gots_diesel_spinup.toml: 3 cylinders, mixed cycle, fan load,
flywheel) shortened to 20 revolutions (from 1000 rpm to ~3800 rpm) is integrated twice: in crank
angle (output every 5°, so the 144-point grid per 4π cycle lies on the samples: no interpolation)
and in time throughout (switch speed 10× the rated speed, output every 2e-5 s, ~0.1–0.45°: the
grid is reached by Hermite interpolation of ω with dω/dφ = ε/ω, of t with 1/ω, and by the spline
for ε, cut at the run's breakpoints, the corners of the pressure tables). The two are independent
solutions of (18), so their order spectra over the last whole cycle must agree to the solver's
tolerance: max |Δcoef|/ω̄ over all orders, largest at order 0 (the mean: the runs' global
error), within 10·rtol. Without the cuts at the breakpoints the time-domain resampling alone
would exceed that bound at rtol 1e-10.

The spin-up is not periodic: ω rises by 2.6 % of ω̄ over the last cycle, so δ (4.7 %) and the
orders of W there hold the trend's leakage too; the checks compare the two domains and the
constant-speed structure, not the size of the odd orders.
"""
from __future__ import annotations

import math
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.irregularity import fluctuation
from transient.analysis.orders import order_spectrum, report_for_scene, run_orders, to_angle_grid
from transient.run import integrate
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
REVS = 20
N = 144  # grid points per 4π cycle: 5°, the crank-angle run's output spacing
RATED = 4400.0 * math.pi / 30.0


@cache
def run(domain: str, rtol: float):
    base = load_scene(CASES / "gots_diesel_spinup.toml")
    solver = replace(base.solver, rtol=rtol, atol=1e-2 * rtol)
    output = base.output
    if domain == "time":
        solver = replace(solver, switch_speed=10.0 * RATED)
        output = replace(output, dt=2e-5)
    scene = replace(base, run=replace(base.run, revolutions=REVS), solver=solver, output=output)
    data = integrate(scene)
    assert data.complete
    assert data.trajectory["omega"].max() < RATED
    assert ("to_angle_domain" in data.events) is False
    return scene, data


def last_cycle(domain, rtol, name="omega", cuts=True):
    scene, data = run(domain, rtol)
    bp = data.events["breakpoint"][:, 1] if cuts else ()
    grid, cols = to_angle_grid(data.trajectory, [name], N, scene.mechanism.cycle,
                               phi0=scene.initial.phi, cycles=1, cuts=bp)
    return grid, cols[name], order_spectrum(cols[name], N, scene.mechanism.cycle)


@pytest.mark.parametrize("rtol", [1e-8, 1e-10])
def test_omega_spectra_agree_between_angle_and_time_domain(rtol):
    _, angle = run("angle", rtol)
    g_a, w_a, s_a = last_cycle("angle", rtol)
    g_t, w_t, s_t = last_cycle("time", rtol)
    _, _, s_nocut = last_cycle("time", rtol, cuts=False)
    # the crank-angle run's samples are the grid: taken as they are
    tr = angle.trajectory
    k = int(np.searchsorted(tr["phi"], g_a[0] - 1e-9))
    assert np.abs(tr["phi"][k:k + N] - g_a).max() <= 1e-12 * g_a[-1]
    assert np.array_equal(w_a, tr["omega"][k:k + N])
    assert np.array_equal(g_a, g_t)
    mean = s_a.mean[0]
    diff = np.abs(s_a.coef - s_t.coef)[0] / mean
    worst = int(np.argmax(diff))
    amp = s_a.amplitude[0] / mean
    print(f"rtol {rtol:g}: ω̄ = {mean:.6f} rad/s over φ = {g_a[0]:.4f}…{g_a[0] + 4 * math.pi:.4f}; "
          f"max |Δcoef|/ω̄ = {diff.max():.2e} (order {s_a.orders[worst]:g}), without the cuts "
          f"{np.abs(s_a.coef - s_nocut.coef).max() / mean:.2e}; orders 0.5…3 relative: "
          f"{np.round(amp[1:7], 6)}; grid values max diff {np.abs(w_a - w_t).max() / mean:.2e}")
    assert diff.max() <= 10.0 * rtol
    # the comparison has teeth: ω varies by percents within the cycle, over many orders
    assert amp[3] > 1e-3 and amp[1:20].min() > 1e-5


def test_report_of_the_spinup_in_both_domains():
    """The odd-harmonic report of cylinder 1 over the last whole cycle, both domains (rtol 1e-10):
    δ equals irregularity.fluctuation in crank angle (same samples), and δ, the relative odd
    orders of W and its first order agree between the domains to 1e-8; at constant ω̄ the odd
    orders ≥ 3 and the half orders vanish (< 1e-12 of the first), in the run they do not."""
    reports = {}
    for domain in ("angle", "time"):
        scene, data = run(domain, 1e-10)
        reports[domain] = report_for_scene(scene, data.trajectory, samples_per_cycle=N, cycles=1,
                                           cuts=data.events["breakpoint"][:, 1])
    a, t = reports["angle"], reports["time"]
    scene, data = run("angle", 1e-10)
    tr = data.trajectory
    delta_irr = fluctuation(tr["t"], tr["phi"], tr["omega"], scene.mechanism.cycle,
                            scene.initial.phi)
    rel_a, rel_t = a.relative[-1], t.relative[-1]
    odd, frac = a.odd, a.fractional
    print(f"δ = {a.delta[-1]:.6e} (angle), {t.delta[-1]:.6e} (time), irregularity "
          f"{delta_irr:.6e}; ω̄ = {a.omega_mean[-1]:.6f}; first order {a.first[-1]:.3f} m/s²; "
          f"odd 3, 5, 7, 9 relative {rel_a[[6, 10, 14, 18]]}; largest half order "
          f"{rel_a[frac].max():.2e}; drift of W {a.drift[-1]:.3e} m/s²; "
          f"max |Δrelative| {np.abs(rel_a - rel_t).max():.2e}")
    for key, value in a.summary().items():
        print(f"  {key} = {value[0]:.6g} {value[1]}")
    assert a.delta[-1] == pytest.approx(delta_irr, rel=1e-12)
    assert t.delta[-1] == pytest.approx(a.delta[-1], rel=1e-8)
    assert t.first[-1] == pytest.approx(a.first[-1], rel=1e-8)
    assert np.abs(rel_a - rel_t).max() <= 1e-8
    assert a.relative_constant[-1][odd | frac].max() <= 1e-12
    assert rel_a[odd].max() > 1e-3 and rel_a[frac].max() > 1e-3


TIGHT = {"rtol": 1e-12, "atol": 1e-12}
#: Steady runs whose ω has period π, so no odd order (and for the 4-stroke no half order): a
#: 4-cylinder in-line 4-stroke (throws 0°, 180°, 180°, 0°, firing every 180°: the misfire case
#: with every cylinder alike); an opposed 2-stroke twin with fork-and-blade rods of one kind
#: (the V-twin case opened to 180°: each piston a crank-slider half a turn from the other);
#: the 4-cylinder swash plate (J and its 4 pulses repeat every half turn). Each spins up
#: (ω₀ below 90 % of its final speed), so the default detrend is the ramp, and runs until its
#: cycles repeat to rounding at rtol 1e-12 (at 1e-8 the steps' own asymmetry leaves odd orders
#: near 1e-8 of the largest).
STEADY = {
    "crank-slider": lambda: load_scene(CASES / "diesel_4cyl_misfire.toml").replace(
        gas={"cylinders": []}, initial={"omega_rpm": 4000}, run={"revolutions": 400},
        solver=TIGHT),
    "articulated": lambda: load_scene(CASES / "v_twin_fork_blade.toml").replace(
        mechanism={"bank_deg": [180], "strokes": 2,
                   "slave_rod": {"mass": 0.75, "cg_from_pin_mm": 133}},
        gas={"p_intake": None, "p_exhaust": None},  # (a 2-stroke has no gas exchange strokes)
        inertia={"flywheel": 0.04}, initial={"omega_rpm": 3000}, run={"revolutions": 200},
        solver=TIGHT),
    "swash-plate": lambda: load_scene(CASES / "swash_plate_4cyl.toml").replace(
        run={"t_end": 3.0}, solver=TIGHT),
}


@pytest.mark.parametrize("mechanism", list(STEADY))
def test_no_odd_orders_where_the_geometry_has_none(mechanism):
    """``run_orders`` as ``transient orders`` calls it (the run's breakpoints as cuts, default
    detrend): the odd orders of ω and of M_gas over the last cycle at rounding level, ≤ 1e-10
    of the largest order, and no half orders. The cycle's end falls on a breakpoint, where the
    output sample lies an ulp off it: taken from the wrong side, it gave odd orders of 1e-6
    (swash plate) to 1e-3 (twin) of the largest."""
    scene = STEADY[mechanism]()
    data = integrate(scene)
    assert data.complete
    tr = data.trajectory
    cuts = data.events["breakpoint"][:, 1]
    ro = run_orders(scene, tr, 720, cuts=cuts)
    assert ro.detrend == "ramp"
    end = ro.cycle_start[-1] + scene.mechanism.cycle
    assert np.abs(cuts - end).min() <= 1e-12 * end  # the cycle's end is a breakpoint
    orders = ro.orders
    whole = np.abs(orders - np.round(orders)) <= 1e-9
    odd = whole & (np.round(orders) % 2 == 1)
    for label, spec in (("omega", ro.omega), ("M_gas", ro.gas_torque)):
        amp = spec.amplitude[-1]
        largest = amp[1:].max()
        print(f"{mechanism} {label}: largest order {largest:.4g}, odd ≤ {amp[odd].max():.2e}, "
              f"half ≤ {amp[~whole].max(initial=0.0):.2e}")
        assert amp[odd].max() <= 1e-10 * largest
        assert amp[~whole].max(initial=0.0) <= 1e-10 * largest
