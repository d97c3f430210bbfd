"""Runs with Wiebe combustion (``cases/gots_diesel_wiebe.toml``) and the governor's fuel command.

The cylinder pressure at fuel f is p = p_mot + f·(p_full − p_mot) (``transient.scene.Gas``):
the motored cycle (no fuel) and the full-load cycle (``fuel_mass``), both from
:func:`transient.forces.wiebe.wiebe_tables`. Checked here:

* a motored prescribed-speed run (fuel_mass = 0, or the governor at f = 0) does no net gas work
  over whole cycles, to 1e-9 of the compression work, when the intake and exhaust pressures are
  equal; with the scene's pressures it does the pumping loop's work, ``ncyl·WiebeCycle.work``, to
  1e-6 of the compression work (the trapezoidal W_gas column at 1440 samples per revolution);
* the full-load indicated work per cycle of a prescribed-speed run is ``ncyl·WiebeCycle.work``
  to 1e-6;
* in the governor's droop range the pressure applied (the ``p_k`` columns) is
  p_mot + f·(p_full − p_mot) of the tables evaluated in numpy, and M_gas is Σ (p_k − p0)·F_p·u_k;
* the interpolation in the fuel is exact for a constant γ and is not for γ(T) (the error the
  scene's comment and the Gas docstring quote);
* a scene at full fuel throughout runs on its full-load table alone, to rounding.

The compiled path against the reference path on this scene: ``test_reference_path.py``.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.forces.wiebe import wiebe_tables
from transient.run import integrate
from transient.scene import Friction, Governor, Initial, Output, Run, load_scene
from transient.scene.queries import gas_tables, wiebe_levels

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0
DEG = math.pi / 180.0
SAMPLES = 1440  # per revolution in the prescribed runs (0.25°)


def wiebe_scene(**gas):
    """The case with changed [gas] / [gas.wiebe] values (``wiebe={...}`` for the latter)."""
    scene = load_scene(CASES / "gots_diesel_wiebe.toml")
    w = replace(scene.gas.wiebe, **gas.pop("wiebe", {}))
    return replace(scene, gas=replace(scene.gas, wiebe=w, **gas))


def prescribed_run(scene, rpm, cycles=2, governor=False):
    """``cycles`` whole engine cycles at constant speed from φ = 0, no pairs, optionally the
    case's droop governor."""
    scene = replace(scene, run=Run(mode="prescribed-speed", speed=rpm * RPM,
                                   revolutions=2.0 * cycles),
                    initial=Initial(phi=0.0, omega=rpm * RPM), friction=Friction(),
                    output=Output(samples_per_rev=SAMPLES),
                    governor=scene.governor if governor else Governor())
    data = integrate(scene)
    tr = data.trajectory
    assert tr["phi"][-1] == pytest.approx(4 * math.pi * cycles, rel=1e-14)
    return scene, tr, tr["W_gas"][-1] / cycles


def compression_work(scene):
    """|∫p dV| of one cylinder from intake closing to the firing TDC on the motored cycle [J]."""
    mot = wiebe_levels(scene.mechanism, scene.gas)[0]
    return abs(float(mot.closed(np.array([2 * math.pi]))[1][0]))


# ----------------------------------------------------------------------------------------------
# Work per cycle at prescribed speed

@pytest.mark.parametrize("how", ["no fuel", "governor at f = 0"])
def test_motored_run_does_no_net_work(how):
    """With equal intake and exhaust pressures the motored cycle is closed (the compression and
    expansion isentropes coincide, the gas exchange is at one pressure): no net gas work."""
    if how == "no fuel":
        scene = wiebe_scene(p_intake=0.17e6, p_exhaust=0.17e6, wiebe={"fuel_mass": 0.0})
        rpm, governor = 2000.0, False
    else:
        scene = wiebe_scene(p_intake=0.17e6, p_exhaust=0.17e6)
        rpm, governor = 5000.0, True  # above speed_zero = 4600 rpm
    scene, tr, w_cycle = prescribed_run(scene, rpm, governor=governor)
    if governor:
        assert np.all(tr["fuel"] == 0.0)
    w_comp = scene.mechanism.n_cylinders * compression_work(scene)
    print(f"\n{how}: W_gas per cycle {w_cycle:.3e} J, compression work {w_comp:.2f} J, "
          f"ratio {abs(w_cycle) / w_comp:.2e}")
    assert w_comp > 1000.0  # 3 × 448 J
    assert abs(w_cycle) <= 1e-9 * w_comp


@pytest.mark.parametrize("rpm, governor", [(2000.0, False), (5000.0, True)])
def test_motored_run_does_the_pumping_work(rpm, governor):
    """With the scene's gas-exchange pressures the motored loop is the pumping loop,
    (p_intake − p_exhaust)·V_h per cylinder: −9.72 J (``WiebeCycle.work`` of the motored cycle)."""
    fuel = 0.031e-3 if governor else 0.0
    scene, _, w_cycle = prescribed_run(wiebe_scene(wiebe={"fuel_mass": fuel}), rpm,
                                       governor=governor)
    mot = wiebe_levels(scene.mechanism, scene.gas)[0]
    n = scene.mechanism.n_cylinders
    w_comp = n * compression_work(scene)
    assert mot.work == pytest.approx(-0.017e6 * mot.v_h, rel=1e-6)
    err = abs(w_cycle - n * mot.work) / w_comp
    print(f"\nmotored at {rpm:g} rpm: W_gas per cycle {w_cycle:.6f} J, ncyl·work "
          f"{n * mot.work:.6f} J, error {err:.2e} of the compression work")
    assert err <= 1e-6


def test_full_load_work_per_cycle():
    scene, tr, w_cycle = prescribed_run(wiebe_scene(), 2000.0)
    full = gas_tables(scene)[0]
    expected = scene.mechanism.n_cylinders * full.work
    rel = w_cycle / expected - 1
    print(f"\nfull load: W_gas per cycle {w_cycle:.6f} J, ncyl·WiebeCycle.work {expected:.6f} J, "
          f"relative error {rel:.2e}; p_i = {full.mean_pressure / 1e6:.4f} MPa")
    assert np.all(tr["fuel"] == 1.0)
    assert abs(rel) <= 1e-6


# ----------------------------------------------------------------------------------------------
# The applied pressure in the droop range

def expected_pressures(scene, phi):
    """p_mot + f·(p_full − p_mot) of each cylinder at shaft angles φ (numpy tables), per fuel f
    given later: returns (p_mot, p_full), shape (ncyl, n)."""
    full, mot = gas_tables(scene)
    model = build_model(scene)[0]
    local = np.mod(phi[None, :] - model.gas_phase[:, None], model.period)
    return mot(local), full(local), local


def off_corners(scene, phi):
    """Samples more than 1e-9 rad from every table corner in every cylinder: on a corner the
    kernel's and numpy's wrapping of the local angle may fall on either side of a jump."""
    _, _, local = expected_pressures(scene, phi)
    corners = gas_tables(scene)[0].corners
    near = np.min(np.abs(local[:, :, None] - corners[None, None, :]), axis=2)
    return np.all(near > 1e-9, axis=0)


def check_applied(scene, tr, keep):
    """The p_k columns and M_gas against the numpy tables and transfer functions at the samples
    ``keep``; returns the largest relative differences."""
    phi, f = tr["phi"][keep], tr["fuel"][keep]
    p_mot, p_full, _ = expected_pressures(scene, phi)
    p = p_mot + f[None, :] * (p_full - p_mot)
    n = scene.mechanism.n_cylinders
    cols = np.array([tr[f"p_{k + 1}"][keep] for k in range(n)])
    scale = gas_tables(scene)[0].p_max
    e_p = float(np.max(np.abs(cols - p))) / scale
    kin = scene.mechanism.kinematics_table(phi)
    u = np.array([kin[f"u_{k + 1}"] for k in range(n)])
    m_gas = np.sum((cols - scene.gas.p0) * scene.mechanism.piston_area * u, axis=0)
    m_scale = scale * scene.mechanism.piston_area * scene.mechanism.crank_radius
    e_m = float(np.max(np.abs(tr["M_gas"][keep] - m_gas))) / m_scale
    return e_p, e_m


def test_droop_range_prescribed_speed():
    """At 4300 rpm the droop line gives f = (4600 − 4300)/600 = 0.5: the pressure is halfway
    between the motored and the full-load cycle, and so is the work (exactly, for a constant γ)."""
    scene, tr, w_cycle = prescribed_run(wiebe_scene(), 4300.0, governor=True)
    g = scene.governor
    f = (g.speed_zero - 4300 * RPM) / (g.speed_zero - g.speed_full)
    assert f == pytest.approx(0.5, rel=1e-14)
    np.testing.assert_array_equal(tr["fuel"], f)
    keep = off_corners(scene, tr["phi"])
    assert np.count_nonzero(keep) > 0.99 * keep.size
    e_p, e_m = check_applied(scene, tr, keep)
    full, mot = gas_tables(scene)
    n = scene.mechanism.n_cylinders
    w_expected = n * (mot.work + f * (full.work - mot.work))
    print(f"\nf = {f:.15g}: max |p_k − (p_mot + f(p_full − p_mot))| = {e_p:.2e} p_max, M_gas "
          f"{e_m:.2e}; W per cycle {w_cycle:.4f} J against {w_expected:.4f} J")
    assert e_p <= 1e-14 and e_m <= 1e-12
    assert abs(w_cycle / w_expected - 1) <= 1e-6


def test_droop_range_dynamic_run():
    """A dynamic run inside the droop range (from 4300 rpm, f = 0.5, settling near 4070 rpm): the
    fuel follows the speed sample by sample and the p_k columns are the interpolated pressures
    (away from table corners, where a sample may take the piece of the step that ends there)."""
    scene = wiebe_scene()
    scene = replace(scene, initial=Initial(phi=0.0, omega=4300 * RPM),
                    run=replace(scene.run, revolutions=20.0),
                    output=Output(samples_per_rev=720))
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    g = scene.governor
    droop = (tr["omega"] > g.speed_full) & (tr["omega"] < g.speed_zero)
    assert np.count_nonzero(droop) > 0.9 * tr["phi"].size
    f_line = (g.speed_zero - tr["omega"][droop]) / (g.speed_zero - g.speed_full)
    np.testing.assert_allclose(tr["fuel"][droop], f_line, rtol=0, atol=1e-14)
    assert np.ptp(tr["fuel"]) > 0.3  # from 0.5 to full fuel (the speed dips below 4000 rpm)
    model = build_model(scene)[0]
    keep = off_corners(scene, tr["phi"])
    assert np.count_nonzero(keep) > 0.98 * tr["phi"].size  # 15 of 1440 samples a cycle are corners
    e_p, e_m = check_applied(scene, tr, keep)
    print(f"\ndynamic, fuel {tr['fuel'].min():.3f}–{tr['fuel'].max():.3f}: max |p_k − p| = "
          f"{e_p:.2e} p_max, M_gas {e_m:.2e}")
    assert e_p <= 1e-14 and e_m <= 1e-12
    assert model.has_motored


def test_case_spins_up_onto_the_droop_line():
    """The whole case: from 1000 rpm to steady running on the droop line (the full-load torque
    balances the fan near 4270 rpm, above the 4000 rpm corner)."""
    scene = load_scene(CASES / "gots_diesel_wiebe.toml")
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    last = tr["phi"] >= tr["phi"][-1] - scene.mechanism.cycle
    mean_rpm = scene.mechanism.cycle / np.ptp(tr["t"][last]) / RPM
    fuel = np.mean(tr["fuel"][last])
    print(f"\nsteady: last-cycle mean {mean_rpm:.1f} rpm, mean fuel {fuel:.4f}, "
          f"{data.solver['nsteps']} steps")
    assert 4000.0 < mean_rpm < 4270.0
    assert 0.5 < fuel < 1.0 and tr["fuel"][last].min() < 1.0
    assert np.all(np.isfinite(tr["p_1"])) and tr["p_1"].max() < 13e6


# ----------------------------------------------------------------------------------------------
# The interpolation in the fuel: exact for a constant γ, approximate for γ(T)

def interpolation_error(scene, fuel, fractions, **gamma):
    """max |p_mot + f(p_full − p_mot) − p(f·fuel)| over the cycle / full-load p_max, and the work
    error at each f, for the scene's engine and cycle with the given γ."""
    mech, gas = scene.mechanism, scene.gas
    w = gas.wiebe
    levels = sorted({0.0, fuel, *(f * fuel for f in fractions)})
    tabs = wiebe_tables(mech.volume_function(mech.swept_volume() / (gas.compression_ratio - 1)),
                        levels, p_a=gas.p_a, start=w.start, duration=w.duration, a=w.a, m=w.m,
                        lhv=w.lhv, t_a=w.t_a, p_intake=gas.p_intake, p_exhaust=gas.p_exhaust,
                        **gamma)
    mot, full = tabs[0], tabs[-1]
    x = mot.interior_points(4)
    out = []
    for f in fractions:
        part = tabs[levels.index(f * fuel)]
        e = np.max(np.abs(mot(x) + f * (full(x) - mot(x)) - part(x))) / full.p_max
        w_err = (mot.work + f * (full.work - mot.work)) / part.work - 1
        out.append((f, float(e), float(w_err)))
    return out


def test_fuel_interpolation_exact_for_constant_gamma():
    scene = load_scene(CASES / "gots_diesel_wiebe.toml")
    w = scene.gas.wiebe
    res = interpolation_error(scene, w.fuel_mass, [0.25, 0.5, 0.75], gamma=w.gamma)
    print("\nconstant γ: " + ", ".join(f"f {f}: {e:.1e} of p_max, work {we:.1e}"
                                       for f, e, we in res))
    for _, e, we in res:
        assert e <= 1e-10 and abs(we) <= 1e-9


def test_fuel_interpolation_error_for_gamma_of_t():
    """γ(T) = 1.38 − 1e-4·(T − 300 K) (air-like, as ``test_wiebe_cycle.py``): the numbers quoted
    by ``transient.scene.Gas`` and the scene's comment: 1.1 % of p_max at f = 0.5 between 0 and
    0.02 g; between 0 and 0.031 g 2.1 % (f = 0.5), work 7.6 % low at f = 0.25."""
    scene = load_scene(CASES / "gots_diesel_wiebe.toml")
    gamma = {"gamma": 1.38, "gamma_slope": -1e-4, "gamma_t_ref": 300.0}
    small = interpolation_error(scene, 0.02e-3, [0.5], **gamma)
    whole = interpolation_error(scene, scene.gas.wiebe.fuel_mass, [0.25, 0.5, 0.75], **gamma)
    print(f"\nγ(T), 0–0.02 g: f 0.5: {small[0][1]:.4f} of p_max; 0–0.031 g: "
          + ", ".join(f"f {f}: {e:.4f} of p_max, work {we:+.4f}" for f, e, we in whole))
    assert small[0][1] == pytest.approx(0.011, abs=0.001)
    assert whole[1][1] == pytest.approx(0.021, abs=0.001)
    assert whole[0][2] == pytest.approx(-0.076, abs=0.002)


# ----------------------------------------------------------------------------------------------
# Scenes at full fuel throughout: one table

def test_full_fuel_mixed_cycle_runs_on_its_table_alone():
    """gots_diesel_governed.toml without its governor burns full fuel throughout: the model holds
    the full-load table alone (the mixed cycle's motored cycle is not paired, so the kernels
    take their one-table path) and the p_k columns are that table's values to rounding, of the
    pressure and of its local angle taken from the shaft's (times the slope). Under the
    governor the motored cycle is paired: tests/validation/test_part_load_runs.py."""
    scene = load_scene(CASES / "gots_diesel_governed.toml")
    scene = replace(scene, governor=Governor(), run=replace(scene.run, revolutions=20.0))
    model = build_model(scene)[0]
    assert not model.has_motored and gas_tables(scene)[1] is not None
    tr = integrate(scene).trajectory
    assert np.all(tr["fuel"] == 1.0)
    table = gas_tables(scene)[0]
    for k in range(3):
        local = np.mod(tr["phi"] - model.gas_phase[k], model.period)
        off = np.min(np.abs(local[:, None] - table.corners[None, :]), axis=1) > 1e-9
        value, slope = table.evaluate(local[off])
        bound = 8 * np.finfo(float).eps * (np.abs(value) + np.abs(tr["phi"][off] * slope))
        assert np.all(np.abs(tr[f"p_{k + 1}"][off] - value) <= bound)
