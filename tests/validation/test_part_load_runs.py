"""A fuel below 1 scales the combustion, never the compression, for every gas model: runs against
what each model's motored cycle is, computed here apart from the library.

* Wiebe combustion (constant γ): a misfiring cycle's closed part is the adiabatic
  p_a·(V_ivc/V)^γ, so it peaks at p_a·ε^γ (intake closing at the BDC); the fired cylinders
  keep the full-load table to rounding.
* Wiebe with Woschni's wall heat: a cut-out cylinder's closed part at a held speed is the
  motored cycle of :mod:`transient.forces.woschni` (the numpy model, solve_ivp at rtol 1e-12)
  with wall heat and no fuel.
* A pressure table with its motored curve: a misfire follows the user's motored points, a
  weak cylinder p_mot + φ·(p − p_mot), both linear interpolations written out here.
* The mixed cycle under a droop governor: at the governor's fuel f every cylinder's pressure is
  p_mot + f·(p_full − p_mot) from the closed forms (gas guide, *Part load*), compression kept.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient import simulate
from transient.scene import Friction, Governor, load_scene, scene_from_dict
from transient.scene.queries import gas_tables

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0
EPS = np.finfo(float).eps


def columns(result):
    df = result.to_dataframe()
    return {c: df[c].to_numpy() for c in df.columns}


def assert_on_table_to_rounding(p, table, x, phi):
    """The stored p is ``table``'s at the local angles x to rounding: of the pressure, and of x
    (taken from the shaft angle φ) times the slope."""
    value, slope = table.evaluate(x)
    assert np.all(np.abs(p - value) <= 8 * EPS * (np.abs(value) + np.abs(phi * slope)))


def test_wiebe_misfire_is_the_adiabatic_compression(gots_cycle):
    """Cylinder 2 of the Wiebe diesel (γ = 1.368 constant, intake closing at the BDC) misfires in
    its cycle 3: over its closed part the stored pressure is p_a·(V_a/V)^γ to 1e-8, peaking at
    p_a·ε^γ at the firing TDC; cylinders 1 and 3 keep the full-load table to rounding."""
    base = load_scene(CASES / "gots_diesel_wiebe.toml")
    scene = replace(base.replace(gas={"cylinders": [{"cylinder": 2, "misfire_cycles": [3]}]},
                                 initial={"omega_rpm": 4000}, run={"revolutions": 8},
                                 output={"samples_per_rev": 720}), governor=Governor())
    w = scene.gas.wiebe
    assert w.gamma_slope == 0.0
    full, _ = gas_tables(scene)
    assert full.intake_closing == pytest.approx(math.pi, abs=1e-12)
    tr = columns(simulate(scene))
    phi = tr["phi"]
    tdc = np.radians([0.0, 240.0, 480.0])  # gas-exchange TDCs: firing_deg − 360°
    a = tdc[1] + 4 * math.pi  # cylinder 2's cycle 3 (cycle 1: in progress at φ0 = 0)
    closed = (phi > a + full.intake_closing + 1e-9) & (phi < a + full.exhaust_opening - 1e-9)
    x = phi[closed] - a
    g = gots_cycle
    adiabatic = g.P_A * (g.EPS * g.V_C / g.volume(x)) ** w.gamma
    err = np.max(np.abs(tr["p_2"][closed] / adiabatic - 1.0))
    print(f"\nWiebe misfire against the adiabatic compression: {err:.1e}")
    assert err <= 1e-8
    peak = gots_cycle.P_A * gots_cycle.EPS ** w.gamma
    assert tr["p_2"][closed].max() == pytest.approx(peak, rel=1e-8)
    for k in (0, 2):
        x = np.mod(phi - tdc[k], 4 * math.pi)
        away = np.min(np.abs(x[:, None] - full.corners[None, :]), axis=1) > 1e-6
        assert_on_table_to_rounding(tr[f"p_{k + 1}"][away], full, x[away], phi[away])


def test_woschni_cut_out_is_the_motored_cycle_with_wall_heat():
    """The Woschni diesel at a held 4400 rpm (a 10⁶ kg m² flywheel, no load, pairs or
    governor) with cylinder 2 cut out: over the closed part of its second cycle its pressure is
    transient.forces.woschni's closed cycle without fuel at that speed, to 1e-6 (the solvers'
    tolerances: rtol 1e-11 here, 1e-12 there), peaking where it does on the same samples."""
    from transient.forces.woschni import WoschniParameters, closed_cycle
    from transient.scene.queries import clearance_volume

    base = load_scene(CASES / "gots_diesel_woschni.toml")
    scene = replace(base.replace(gas={"cylinders": [{"cylinder": 2, "cut_out": True}]},
                                 load={"fan": 0.0}, inertia={"flywheel": 1e6},
                                 initial={"omega_rpm": 4400}, run={"revolutions": 6},
                                 solver={"rtol": 1e-11, "atol": 1e-11},
                                 output={"samples_per_rev": 1440}),
                    governor=Governor(), friction=Friction())
    tr = columns(simulate(scene))
    mech, gas = scene.mechanism, scene.gas
    w, h = gas.wiebe, gas.woschni
    ref = closed_cycle(mech.volume_function(clearance_volume(scene)), p_a=gas.p_a,
                       start=w.start, duration=w.duration, fuel_mass=0.0,
                       woschni=WoschniParameters(bore=mech.bore, stroke=mech.stroke(), c1=h.c1,
                                                 c2=h.c2, wall_temperature=h.wall_temperature),
                       omega=float(np.mean(tr["omega"])), a=w.a, m=w.m, lhv=w.lhv,
                       efficiency=w.efficiency, gamma=w.gamma, gamma_slope=w.gamma_slope,
                       gamma_t_ref=w.gamma_t_ref, t_a=w.t_a, strokes=mech.strokes)
    assert ref.heat_lost > 0.0  # the walls take heat: below the adiabatic motored cycle
    a = math.radians(240.0) + 4 * math.pi  # cylinder 2's second whole cycle
    phi = tr["phi"]
    closed = (phi > a + ref.start + 1e-9) & (phi < a + ref.end - 1e-9)
    expected = ref.pressure(phi[closed] - a)
    err = np.max(np.abs(tr["p_2"][closed] / expected - 1.0))
    print(f"\nWoschni cut-out against the motored closed cycle: {err:.1e}; peak "
          f"{tr['p_2'][closed].max() / 1e6:.4f} MPa against {ref.p_max / 1e6:.4f} MPa")
    assert err <= 1e-6
    # its peak is the motored one's on the same samples (0.25° apart; the continuous peak
    # lies between two of them, the wall's heat moving it before the TDC)
    assert tr["p_2"][closed].max() == pytest.approx(expected.max(), rel=1e-6)
    assert expected.max() <= ref.p_max < gas.p_a * 18.0 ** w.gamma  # below the adiabatic


def table_scene(motored=True, **changes):
    """The misfire case's four cylinders on a 4-stroke pressure table (linear, jumps at the
    firing TDC and at the exhaust opening) and, with ``motored``, its motored curve."""
    data = {"mechanism": {"type": "crank-slider", "crank_radius_mm": 47, "rod_length_mm": 148,
                          "bore_mm": 88, "piston_mass": 1.52, "crank_mass": 0.912, "strokes": 4,
                          "cylinders": 4, "firing_order": [1, 3, 4, 2],
                          "firing_deg": [360, 180, 540, 0],
                          "rod": {"model": "two-mass", "mass": 1.752, "cg_from_pin_mm": 107.3}},
            "gas": {"model": "table", "p0_MPa": 0.1, "interpolation": "linear",
                    "phi_deg": TABLE_PHI, "corners_deg": [360, 540], "p_bar": TABLE_P,
                    "cylinders": [{"cylinder": 2, "fuel": 0.5},
                                  {"cylinder": 3, "misfire_every": 2}]},
            "inertia": {"shaft": 0.02, "flywheel": 0.15}, "load": {"fan": 1e-3},
            "initial": {"omega_rpm": 2000}, "run": {"revolutions": 8},
            "output": {"samples_per_rev": 360}}
    if motored:
        data["gas"]["motored_p_bar"] = TABLE_MOTORED
    for key, value in changes.items():
        data[key].update(value)
    return scene_from_dict(data)


TABLE_PHI = [0, 180, 270, 360, 360, 450, 540, 540, 720]
TABLE_P = [1.6, 1.4, 8.0, 75.0, 105.0, 20.0, 5.7, 1.8, 1.8]
TABLE_MOTORED = [1.6, 1.4, 8.0, 75.0, 75.0, 8.0, 1.4, 1.8, 1.8]


def test_table_misfire_follows_the_users_motored_curve():
    """Cylinder 3 misfires in its even cycles onto the motored points, cylinder 2 burns half
    (p_mot + ½(p − p_mot)), cylinders 1 and 4 keep the full-load points: each against np.interp
    of the points (linear), away from the corners, to rounding; a misfire peaks at the motored
    75 bar at the firing TDC."""
    scene = table_scene()
    tr = columns(simulate(scene))
    phi = tr["phi"]
    tdc = np.radians([0.0, 540.0, 180.0, 360.0])  # gas-exchange TDCs
    P = 4 * math.pi
    points = np.radians(TABLE_PHI)
    full = lambda x: np.interp(x, points, np.array(TABLE_P) * 1e5)
    motored = lambda x: np.interp(x, points, np.array(TABLE_MOTORED) * 1e5)
    misfires = 0
    for k in range(4):
        x = np.mod(phi - tdc[k], P)
        # (np.interp takes the right value at a repeated angle; samples near one are left out)
        away = np.min(np.abs(x[:, None] - points[None, :]), axis=1) > 1e-6
        n = np.floor((phi - tdc[k]) / P) + (1 if tdc[k] == 0.0 else 2)  # its cycle number
        fuel = {1: 0.5, 2: np.where(n % 2 == 0, 0.0, 1.0)}.get(k, 1.0)
        expected = motored(x) + fuel * (full(x) - motored(x))
        p = tr[f"p_{k + 1}"]
        np.testing.assert_allclose(p[away], expected[away], rtol=1e-12, atol=0)
        if k == 2:
            for m in np.unique(n[(n % 2 == 0)]):
                a = tdc[k] + (m - 2) * P
                if a >= phi[0] and a + P <= phi[-1]:
                    inside = (phi > a) & (phi < a + P)
                    assert p[inside].max() == pytest.approx(75e5, rel=1e-12)
                    misfires += 1
    assert misfires >= 1


def test_governor_fuel_scales_the_combustion_of_the_mixed_cycle(gots_cycle):
    """The governed Gots diesel from 4300 rpm, on its droop line: every cylinder's stored
    pressure is the closed forms' p_mot + f·(p_full − p_mot) at the stored fuel command f (to
    2e-9 of p_z, the tables' interpolation), so that the compression stays whole at part fuel."""
    base = load_scene(CASES / "gots_diesel_governed.toml")
    scene = base.replace(initial={"omega_rpm": 4300}, run={"revolutions": 10},
                         output={"samples_per_rev": 360})
    tr = columns(simulate(scene))
    phi, fuel = tr["phi"], tr["fuel"]
    assert fuel.max() < 1.0 and fuel.min() < 0.6  # part fuel throughout
    worst = 0.0
    for k, tdc in enumerate(np.radians([0.0, 240.0, 480.0])):
        expected, near = gots_cycle.pressure(phi - tdc, fuel)
        err = np.max(np.abs(tr[f"p_{k + 1}"][~near] - expected[~near])) / gots_cycle.P_Z
        worst = max(worst, err)
        # the compression end is the motored one whatever the fuel
        x = np.mod(phi - tdc, 4 * math.pi)
        at_tdc = np.abs(x - 2 * math.pi) < 1e-9
        if at_tdc.any():
            left = tr[f"p_{k + 1}"][at_tdc]
            assert np.all((np.abs(left / gots_cycle.P_C - 1) < 1e-9)
                          | (left > gots_cycle.P_C))
    print(f"\ngoverned run against the closed forms at its fuel: {worst:.1e} of p_z")
    assert worst <= 2e-9
