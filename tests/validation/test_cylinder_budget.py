"""The friction budget per cylinder of reaction pairs (``P_loss_<k>_cyl<c>`` columns and the
``/analysis`` entries of :func:`transient.analysis.efficiency.mechanical_efficiency`), against
closed forms and a quadrature written here from other columns.

* **The columns**: at every sample each pair's per-cylinder losses sum to its ``P_loss_k``
  (rounding), and a pair on no cylinder-dependent quantity splits evenly.
* **Ring tension alone** (μ = 0, no gas-pressure term, no viscous term): the piston loses F·|v|,
  so each cylinder loses F times the piston's travel per cycle, 4 strokes of a four-stroke —
  its FMEP on its own swept volume is 4F/A_p, whatever the motion (1e-3: the per-cylinder
  shares come from the trapezoidal rule over the samples; the pair's total is exact).
* **A radial engine**: its slaves' strokes differ from the master's, so ring tension alone loses
  F times four of each cylinder's own strokes per cycle (from the mechanism's kinematics table).
* **Gas pressure behind the rings alone**, with cylinder 2 at half pressure: each cylinder loses
  c_p ∫ F_c⁺ |s′_c ω| dt, computed here from its ``p_c`` column and the piston's kinematics
  (:func:`transient.analysis.loads.crank_slider.slider_arrays`), and the weak cylinder the least.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.efficiency import mechanical_efficiency
from transient.analysis.loads.crank_slider import slider_arrays
from transient.run import integrate
from transient.scene import Cylinder, Friction, Output, Pair, Run, load_scene
from transient.scene.outputs import cylinder_loss_column

CASES = Path(__file__).resolve().parents[2] / "cases"
CASE = CASES / "gots_diesel_reaction_friction.toml"


def piston_rings(scene, cylinders=(), revolutions=12.0, **coefficients):
    """The reaction case with friction on the pistons only, ``coefficients`` of the slider, and
    ``cylinders`` as its [[gas.cylinders]], run 6 cycles sampled every half degree."""
    pair = Pair(between=("piston", "cylinder"), eta_forward=1.0, eta_backward=1.0,
                name="pistons", model="reaction", **coefficients)
    scene = replace(scene, friction=Friction("power-flow", (pair,)),
                    gas=replace(scene.gas, cylinders=tuple(cylinders)),
                    run=Run(revolutions=revolutions), output=Output(samples_per_rev=720))
    data = integrate(scene)
    assert data.complete, data.message
    return scene, data.trajectory


def whole_cycles(scene, tr, first=1, last=5):
    cyc = scene.mechanism.cycle
    return scene.initial.phi + first * cyc, scene.initial.phi + last * cyc, last - first


@pytest.fixture(scope="module")
def case():
    return load_scene(CASE)


def test_each_cylinders_losses_sum_to_the_pairs_at_every_sample(case):
    scene, tr = piston_rings(case, mu=0.03, ring_force=30.0, ring_pressure=0.0045)
    n = scene.mechanism.n_cylinders
    parts = np.array([tr[cylinder_loss_column(0, c)] for c in range(n)])
    total = tr["P_loss_1"]
    assert np.max(np.abs(parts.sum(axis=0) - total)) <= 1e-14 * np.max(np.abs(total))
    assert parts.min() >= -1e-9 * np.max(np.abs(parts))


def test_ring_tension_loses_its_force_over_four_strokes_per_cycle(case):
    F = 30.0
    scene, tr = piston_rings(case, ring_force=F)
    eff = {k: v for k, (v, _) in
           mechanical_efficiency(scene, tr, window=whole_cycles(scene, tr)).items()}
    mech = scene.mechanism
    expected = 4.0 * F / mech.piston_area  # 4 strokes of F over one cylinder's swept volume
    print({k: v for k, v in eff.items() if "cyl" in k})
    for c in range(mech.n_cylinders):
        assert eff[f"fmep_1_cyl{c + 1}"] == pytest.approx(expected, rel=1e-3)
        assert eff[f"fmep_cyl{c + 1}"] == eff[f"fmep_1_cyl{c + 1}"]
        assert eff[f"W_loss_1_cyl{c + 1}_per_cycle"] == pytest.approx(8.0 * mech.crank_radius
                                                                       * F, rel=1e-3)
    total = sum(eff[f"W_loss_1_cyl{c + 1}_per_cycle"] for c in range(mech.n_cylinders))
    assert total == pytest.approx(eff["W_loss_1_per_cycle"], rel=1e-14)
    assert abs(eff["cylinder_split_residual_1"]) < 1e-3


def test_a_cylinder_at_half_pressure_loses_half_as_much_on_its_rings(case):
    c_p = 0.0045
    scene, tr = piston_rings(case, cylinders=(Cylinder(cylinder=2, pressure=0.5),),
                             ring_pressure=c_p)
    a, b, n_cyc = whole_cycles(scene, tr)
    eff = {k: v for k, (v, _) in mechanical_efficiency(scene, tr, window=(a, b, n_cyc)).items()}
    mech = scene.mechanism
    sel = (tr["phi"] >= a - 1e-12) & (tr["phi"] <= b + 1e-12)
    t, phi, w = tr["t"][sel], tr["phi"][sel], tr["omega"][sel]
    p0 = scene.gas.p0
    lost = []
    for c in range(mech.n_cylinders):
        _, ds, *_ = slider_arrays(phi - mech.firing_angles[c], mech.crank_radius,
                                  mech.rod_length, mech.offset)
        force = np.maximum(mech.piston_area * (tr[f"p_{c + 1}"][sel] - p0), 0.0)
        lost.append(c_p * np.trapezoid(force * np.abs(ds * w), t) / n_cyc)
        print(c + 1, eff[f"W_loss_1_cyl{c + 1}_per_cycle"], lost[-1])
        assert eff[f"W_loss_1_cyl{c + 1}_per_cycle"] == pytest.approx(lost[-1], rel=2e-3)
    others = 0.5 * (lost[0] + lost[2])
    assert lost[1] / others == pytest.approx(0.5, rel=0.02)
    assert eff["fmep_cyl2"] / eff["fmep_cyl1"] == pytest.approx(0.5, rel=0.02)
    assert math.isfinite(eff["cylinder_split_residual_1"])


def test_a_radials_cylinders_lose_ring_tension_over_their_own_strokes():
    F = 50.0
    scene, tr = piston_rings(load_scene(CASES / "radial_5cyl_reaction_friction.toml"),
                             revolutions=5.0, ring_force=F)
    mech = scene.mechanism
    eff = {k: v for k, (v, _) in mechanical_efficiency(
        scene, tr, window=whole_cycles(scene, tr, 1, 2)).items()}
    s = mech.kinematics_table(np.linspace(0.0, 2.0 * np.pi, 20001))
    strokes = [np.ptp(s[f"s_{c + 1}"]) for c in range(mech.n_cylinders)]
    assert max(strokes) > min(strokes) * (1 + 1e-3)  # (the slaves' strokes are not the master's)
    print(strokes, [eff[f"W_loss_1_cyl{c + 1}_per_cycle"] for c in range(mech.n_cylinders)])
    for c, stroke in enumerate(strokes):
        assert eff[f"W_loss_1_cyl{c + 1}_per_cycle"] == pytest.approx(4.0 * F * stroke, rel=1e-3)


def test_a_swash_plates_pistons_split_and_its_bearings_do_not():
    """The swash plate's main and plate bearings carry every piston: their loss is the engine's
    (NaN per cylinder, no entries); its pistons' loss splits, each cylinder's share summing to the
    pair's at every sample and over the cycles."""
    scene = load_scene(CASES / "swash_plate_4cyl_reaction_friction.toml")
    scene = replace(scene, run=Run(revolutions=4.0), output=Output(samples_per_rev=720))
    data = integrate(scene)
    assert data.complete, data.message
    tr, n = data.trajectory, scene.mechanism.n_cylinders
    names = [p.name for p in scene.friction.pairs]
    k = names.index("pistons")
    parts = np.array([tr[cylinder_loss_column(k, c)] for c in range(n)])
    total = tr[f"P_loss_{k + 1}"]
    assert np.max(np.abs(parts.sum(axis=0) - total)) <= 1e-13 * np.max(np.abs(total))
    bearings = [j for j in range(len(names)) if j != k]
    assert bearings and all(np.isnan(tr[cylinder_loss_column(j, 0)]).all() for j in bearings)
    cyc = scene.mechanism.cycle
    eff = {key: v for key, (v, _) in mechanical_efficiency(
        scene, tr, window=(scene.initial.phi + cyc, scene.initial.phi + 3 * cyc, 2)).items()}
    split = [eff[f"W_loss_{k + 1}_cyl{c + 1}_per_cycle"] for c in range(n)]
    assert sum(split) == pytest.approx(eff[f"W_loss_{k + 1}_per_cycle"], rel=1e-13)
    assert all(f"fmep_{j + 1}_cyl1" not in eff for j in bearings)
    assert eff["fmep_cyl1"] == eff[f"fmep_{k + 1}_cyl1"]
