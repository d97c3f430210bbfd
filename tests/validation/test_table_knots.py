"""Pressure tables from points, no corners declared: the run's error follows the tolerance.

A linear table is only C⁰ at its knots, pchip C¹ and the not-a-knot spline C²; a step across a
knot integrates a derivative jump that an order-8 method cannot follow. Every knot of a table
from points is therefore a breakpoint. Checked on one cylinder of the Gots diesel
(``cases/coasting_single.toml`` with a heavier shaft, no load): in crank angle the kinetic
energy gains exactly the gas work over each cycle, K(φ₀ + 4πN) − K(φ₀) = N·∮p dV, since J is
2π-periodic. The reference ∮p dV is independent of the stepper and of transient's own tables:
the interpolant is rebuilt with numpy/scipy (``np.interp``, ``PchipInterpolator``,
``CubicSpline`` not-a-knot) and integrated by parts, ∮p dV = −∮V p′ dx (p periodic and
continuous), with 16-point Gauss–Legendre on each knot interval, where V(x) is the mechanism's
volume function and p′ a polynomial of degree ≤ 2: exact to rounding.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import CubicSpline, PchipInterpolator

from transient.assemble import build_model
from transient.run import integrate
from transient.scene import Gas, Initial, Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
CYCLE = 4.0 * math.pi
CYCLES = 2
RTOL = 1e-10

#: A 4-stroke indicator diagram on uneven angles [deg] and pressures [bar]: intake, compression,
#: combustion peak after the firing TDC (360°), expansion, exhaust; periodic (p(0) = p(720)).
PHI_DEG = [0, 60, 120, 180, 240, 290, 320, 340, 350, 360, 365, 372, 380, 395, 420, 460, 500, 540,
           600, 660, 720]
P_BAR = [1.0, 1.0, 1.0, 1.0, 1.6, 3.5, 8.0, 16.0, 24.0, 35.0, 48.0, 55.0, 50.0, 38.0, 24.0,
         12.0, 6.0, 3.0, 1.2, 1.05, 1.0]


def scene_with_table(interpolation: str, rtol: float = RTOL):
    base = load_scene(CASES / "coasting_single.toml")
    gas = Gas(model="table", p0=1e5, phi=tuple(np.radians(PHI_DEG)),
              p=tuple(1e5 * np.array(P_BAR)), interpolation=interpolation)
    return replace(base, gas=gas, inertia=replace(base.inertia, shaft=0.5),
                   initial=Initial(0.0, 1000.0 * math.pi / 30.0),
                   run=Run(revolutions=2 * CYCLES),
                   solver=replace(base.solver, method="dop853", rtol=rtol, atol=1e-12))


def reference_slope(interpolation: str):
    """p′(x) of the interpolant, built apart from transient's tables."""
    x, p = np.radians(PHI_DEG), 1e5 * np.array(P_BAR)
    if interpolation == "linear":
        slopes = np.diff(p) / np.diff(x)
        return lambda z: slopes[np.clip(np.searchsorted(x, z, side="right") - 1, 0,
                                        slopes.size - 1)]
    interp = (PchipInterpolator(x, p) if interpolation == "pchip"
              else CubicSpline(x, p, bc_type="not-a-knot"))
    return interp.derivative()


def cycle_work(scene, interpolation: str) -> float:
    """∮p dV = −∮V p′ dx over one cycle, Gauss–Legendre on each knot interval [J]."""
    volume = scene.mechanism.volume_function(0.0)  # (V_c drops out: ∮p′ dx = 0)
    slope = reference_slope(interpolation)
    nodes, weights = np.polynomial.legendre.leggauss(16)
    x = np.radians(PHI_DEG)
    a, b = x[:-1, None], x[1:, None]
    z = 0.5 * (a + b) + 0.5 * (b - a) * nodes
    return float(-np.sum(0.5 * (b - a) * weights * volume(z) * slope(z)))


def energy_gain(data) -> float:
    """K(end) − K(start) from the output columns J and ω [J]."""
    tr = data.trajectory
    assert tr["phi"][-1] == pytest.approx(CYCLES * CYCLE, abs=1e-12)
    k = 0.5 * tr["J"] * tr["omega"] ** 2
    return float(k[-1] - k[0])


@pytest.mark.parametrize("interpolation", ["linear", "pchip", "spline"])
def test_energy_per_cycle_follows_the_tolerance(interpolation):
    scene = scene_with_table(interpolation)
    work = cycle_work(scene, interpolation)
    data = integrate(scene)
    gain = energy_gain(data) / CYCLES
    err = abs(gain - work) / abs(work)
    nfev = data.solver["nfev"]
    print(f"{interpolation}: W = {work:.6f} J per cycle, relative error {err:.2e} at rtol "
          f"{RTOL:g}, {nfev} right-hand sides")
    assert err <= 10 * RTOL
    # Every knot is a breakpoint: at least one DOP853 step per knot interval and cycle, and not
    # many more (each knot interval is smooth).
    knots = len(PHI_DEG) - 1
    assert nfev <= 12 * 12 * knots * CYCLES


def test_every_knot_is_a_breakpoint_of_every_cylinder():
    """A table from points without declared corners: its knots, shifted to each cylinder's phase,
    are the breakpoints (knots × cylinders, where they do not coincide)."""
    scene = load_scene(CASES / "gots_diesel_4400.toml")
    gas = Gas(model="table", p0=1e5, phi=tuple(np.radians(PHI_DEG)),
              p=tuple(1e5 * np.array(P_BAR)), interpolation="pchip")
    scene = replace(scene, gas=gas)
    model, bp, _ = build_model(scene)
    knots = np.radians(PHI_DEG[:-1])
    expect = np.unique(np.round(np.mod(np.add.outer(model.gas_phase, knots).ravel(), CYCLE), 9))
    np.testing.assert_allclose(bp, expect, atol=1e-9)
    assert bp.size > knots.size  # phases apart: the cylinders' knots do not all coincide
    assert not model.bp_jump.any()  # a continuous table jumps nowhere
