"""The work columns of prescribed-speed runs (transient.prescribed_work) against the work–energy
law and closed forms, at several tolerances and output spacings.

* **Balance.** The inverse dynamics makes the powers on the shaft add up to d(½J(φ)ω²)/dt at every
  instant, so W_drive + W_gas + W_load + W_starter − ΣW_loss,k must equal ΔK = ½J(φ)ω² − ½J(φ₀)ω₀²
  (J and ω from the samples, no quadrature) at every sample, to rtol·Σ∫|P_x|dt + atol per column
  (∫|P_x| by the trapezoid of the densest run's samples: a scale, not a result). Scenes: a
  forceless crank-slider whose J(φ) varies by ±12 %, the Gots diesel with its gas and fan load,
  with constant-η pairs and with reaction pairs; speed tables with corners (linear: ε jumps) and
  a pchip table; rtol 1e-6, 1e-9, 1e-12; 8, 72 and 720 samples per revolution.
* **Output spacing.** W_drive at the end is the same at every spacing, to twice that bound (the
  trapezoid over the samples gave 213.767 / 213.403 / 213.870 J for one ΔK = 213.827 J).
* **Fan load.** W_load = −K∫ω³dt, in closed form on each linear piece of the table,
  −K(ω_b⁴ − ω_a⁴)/(4s) (s its slope), at every sample.
* **Gas.** At constant speed over one 4-stroke cycle W_gas = Σ_k ∮(p_k − p0)dV_k = 3·W, W the
  closed-form loop work of the ideal mixed cycle (``MixedCycle.work``), and W_drive = −W_gas
  (ΔK = 0 over a cycle), to the tables' 1e-9 at every spacing (the trapezoid was 1.9e-3 off at
  72 samples per revolution: it cuts the pressure's corners).
"""
from __future__ import annotations

import math
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from transient.run import prescribed
from transient.scene import load_scene
from transient.scene.queries import gas_table

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0
TABLE = {"time": [0.0, 0.02, 0.05, 0.06], "speed_table_rpm": [1000, 2500, 2600, 2600],
         "revolutions": 1000}
SCENES = {
    "forceless": ("coasting_single.toml", {}),
    "gas-fan": ("gots_diesel_spinup.toml", {}),
    "gas-fan-pchip": ("gots_diesel_spinup.toml", {"interpolation": "pchip"}),
    "constant-eta-pairs": ("gots_diesel_friction.toml", {}),
    "reaction-pairs": ("gots_diesel_reaction_friction.toml", {}),
}
RTOLS = (1e-6, 1e-9, 1e-12)
SPACINGS = (8, 72, 720)
ATOL = 1e-12


@cache
def run(name: str, rtol: float, samples: int):
    case, run_keys = SCENES[name]
    scene = load_scene(CASES / case).replace(
        run={"mode": "prescribed-speed", **TABLE, **run_keys}, initial={"omega": 0.0},
        solver={"rtol": rtol, "atol": ATOL}, output={"samples_per_rev": samples})
    data = prescribed(scene)
    assert data.solver["quadrature_unresolved"] == 0
    assert (data.solver["rtol"], data.solver["atol"]) == (rtol, ATOL)
    return scene, data.trajectory


def work_names(scene):
    return ["W_drive", "W_gas", "W_load", "W_starter",
            *(f"W_loss_{k + 1}" for k in range(len(scene.friction.pairs)))]


def residual(scene, tr):
    """W_drive + W_gas + W_load + W_starter − ΣW_loss − ΔK at every sample [J]."""
    works = sum(tr[n] for n in work_names(scene) if not n.startswith("W_loss"))
    lost = sum(tr[n] for n in work_names(scene) if n.startswith("W_loss"))
    kinetic = 0.5 * tr["J"] * tr["omega"] ** 2
    return works - lost - (kinetic - kinetic[0])


def bound(name, rtol):
    """rtol·Σ∫|P_x|dt + atol per column, ∫|P_x| from the samples of the densest run."""
    scene, tr = run(name, 1e-12, SPACINGS[-1])
    w = tr["omega"]
    powers = [tr[c] * w for c in ("M_drive", "M_gas", "M_load", "M_starter")]
    powers += [tr[f"P_loss_{k + 1}"] for k in range(len(scene.friction.pairs))]
    magnitude = sum(np.trapezoid(np.abs(p), tr["t"]) for p in powers)
    return rtol * magnitude + len(powers) * ATOL, magnitude


@pytest.mark.parametrize("name", list(SCENES))
def test_work_balances_to_the_tolerance_at_every_spacing(name):
    ends = {}
    _, reference = run(name, RTOLS[-1], SPACINGS[-1])
    for rtol in RTOLS:
        limit, magnitude = bound(name, rtol)
        for samples in SPACINGS:
            scene, tr = run(name, rtol, samples)
            res = np.abs(residual(scene, tr)).max()
            ends[rtol, samples] = tr["W_drive"][-1]
            print(f"{name} rtol {rtol:g}, {samples}/rev: max |balance| {res:.2e} J "
                  f"(bound {limit:.2e}; Σ∫|P| = {magnitude:.4g} J), W_drive {tr['W_drive'][-1]:.9f} J")
            assert res <= limit
            assert tr["t"][-1] == TABLE["time"][-1]
            # each column on its own converges with rtol (the balance closes on the sum of the
            # powers, which is smooth where the columns have corners)
            for work in work_names(scene):
                assert abs(tr[work][-1] - reference[work][-1]) <= limit + bound(name, RTOLS[-1])[0]
        spread = max(ends[rtol, s] for s in SPACINGS) - min(ends[rtol, s] for s in SPACINGS)
        assert spread <= 2.0 * limit
    # the bound has teeth: the trapezoid over the samples (the powers' corners between them)
    # misses it at the default spacing
    scene, tr = run(name, 1e-9, 72)
    trapezoid = dict(tr)
    for work, power in zip(work_names(scene), ("M_drive", "M_gas", "M_load", "M_starter")):
        trapezoid[work] = cumulative_trapezoid(tr[power] * tr["omega"], tr["t"], initial=0.0)
    for k in range(len(scene.friction.pairs)):
        trapezoid[f"W_loss_{k + 1}"] = cumulative_trapezoid(tr[f"P_loss_{k + 1}"], tr["t"],
                                                            initial=0.0)
    off = np.abs(residual(scene, trapezoid)).max()
    print(f"{name}: the trapezoid's max |balance| at 72/rev {off:.2e} J")
    assert off > 100.0 * bound(name, 1e-9)[0]


@pytest.mark.parametrize("samples", SPACINGS)
def test_fan_load_work_is_its_closed_form(samples):
    scene, tr = run("gas-fan", 1e-9, samples)
    K = scene.load.fan
    knots = np.array(TABLE["time"])
    speeds = np.array(TABLE["speed_table_rpm"]) * RPM
    t = tr["t"]

    def cube_integral(t_to):  # ∫ω³dt from knots[0] to each t_to, ω linear between the knots
        out = np.zeros_like(t_to)
        for a, b, wa, wb in zip(knots[:-1], knots[1:], speeds[:-1], speeds[1:]):
            s = (wb - wa) / (b - a)
            end = np.clip(t_to, a, b)
            w_end = wa + s * (end - a)
            out += (w_end ** 4 - wa ** 4) / (4 * s) if s != 0.0 else wa ** 3 * (end - a)
        return out

    exact = -K * cube_integral(t)
    limit = 1e-9 * K * cube_integral(t[-1:])[0] + ATOL
    err = np.abs(tr["W_load"] - exact).max()
    print(f"{samples}/rev: max |W_load − closed form| {err:.2e} J of {abs(exact[-1]):.6g} J")
    assert err <= limit


@pytest.mark.parametrize("samples", SPACINGS)
def test_gas_work_over_a_cycle_is_the_closed_form_loop(samples):
    scene = load_scene(CASES / "gots_diesel_4400.toml").replace(
        run={"revolutions": 2}, output={"samples_per_rev": samples})
    tr = prescribed(scene).trajectory
    loop = scene.mechanism.n_cylinders * gas_table(scene).work
    print(f"{samples}/rev: W_gas {tr['W_gas'][-1]:.9f} J, closed form {loop:.9f} J, "
          f"W_drive {tr['W_drive'][-1]:.9f} J")
    assert tr["phi"][-1] - tr["phi"][0] == pytest.approx(4.0 * math.pi, rel=1e-15)
    assert tr["W_gas"][-1] == pytest.approx(loop, rel=1e-9)
    assert tr["W_drive"][-1] == pytest.approx(-loop, rel=1e-9)
