"""Radial and V engines with articulated rods through the whole model: coasting keeps ½J(φ)ω²,
driven runs keep the work–energy balance, the tabulated kinematics and the CLI agree.

Scenes: ``cases/radial_5cyl.toml`` (Semenov's dimensions), ``radial_9cyl.toml`` (link radii by
Semenov (7)), ``v_twin_fork_blade.toml`` (central articulation), shortened; and a two-row variant
of the five-cylinder radial (crankpins 180° apart, rows staggered by 36°).
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.cli import main
from transient.run import integrate
from transient.scene import Gas, Initial, Load, Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
SCENES = ("radial_5cyl", "radial_9cyl", "v_twin_fork_blade")
C_DRIFT = 3000.0  # as tests/validation/test_energy.py: time-domain drift ≤ C·rtol


def coasting(name="radial_5cyl", rows=1, revs=100, **solver):
    """The scene without gas, load or flywheel (J(φ) varies by several per cent), from 1500 rpm."""
    scene = load_scene(CASES / f"{name}.toml")
    mech = scene.mechanism
    if rows == 2:
        mech = replace(mech, row_banks=(0.0, math.radians(36.0)), row_cranks=(0.0, math.pi))
    return replace(scene, mechanism=mech, gas=Gas(model="none"), load=Load(),
                   inertia=replace(scene.inertia, flywheel=0.0),
                   initial=Initial(0.0, 1500 * math.pi / 30), run=Run(revolutions=revs),
                   solver=replace(scene.solver, rtol=1e-10, atol=1e-12, **solver))


@pytest.mark.parametrize("name,rows", [("radial_5cyl", 1), ("radial_5cyl", 2),
                                       ("radial_9cyl", 1), ("v_twin_fork_blade", 1)])
def test_coasting_keeps_kinetic_energy(name, rows):
    """Crank angle: K = ½J(φ)ω² constant to 1e-9 over 100 revolutions (it is the state), while ω
    varies by > 0.5 % (the test has teeth only if J(φ) does)."""
    data = integrate(coasting(name, rows))
    tr = data.trajectory
    assert data.complete
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    drift = np.max(np.abs(K / K[0] - 1.0))
    swing = tr["omega"].max() / tr["omega"].min() - 1.0
    print(f"{name} ×{rows} rows: ω swing {swing:.3%}, |ΔK/K|max {drift:.2e}")
    assert swing > 0.005
    assert drift <= 1e-9


def test_coasting_in_time_domain_drift_is_bounded_by_rtol():
    """Time domain, (18) with its ½J′ω² term: the energy drift ≤ C·rtol (C as test_energy.py) and
    falls ≥ 10× from rtol 1e-8 to 1e-10."""
    drifts = {}
    for rtol in (1e-8, 1e-10):
        scene = coasting(revs=50)
        scene = replace(scene, solver=replace(scene.solver, rtol=rtol, domain="time"))
        tr = integrate(scene).trajectory
        K = 0.5 * tr["J"] * tr["omega"] ** 2
        drifts[rtol] = float(np.max(np.abs(K / K[0] - 1.0)))
        print(f"rtol {rtol:g}: |ΔK/K|max {drifts[rtol]:.2e} ({drifts[rtol] / rtol:.0f} rtol)")
        assert drifts[rtol] <= C_DRIFT * rtol
    assert drifts[1e-10] <= 0.1 * drifts[1e-8]


@pytest.mark.parametrize("name", SCENES)
def test_driven_run_keeps_the_work_energy_balance(name):
    """The scene itself for 20 revolutions (10 four-stroke cycles, gas on every cylinder, the
    propeller load): K(end) − K(0) = W_gas + W_load to 1e-8 of |W_gas| + |W_load|."""
    scene = load_scene(CASES / f"{name}.toml")
    data = integrate(replace(scene, run=Run(revolutions=20)))
    tr = data.trajectory
    assert data.complete
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    works = tr["W_gas"][-1] + tr["W_load"][-1] + tr["W_starter"][-1]
    total = abs(tr["W_gas"][-1]) + abs(tr["W_load"][-1])
    residual = (K[-1] - K[0] - works) / total
    print(f"{name}: ΔK {K[-1] - K[0]:.6g} J, W_gas {tr['W_gas'][-1]:.6g} J, residual {residual:.2e}")
    assert tr["W_gas"][-1] > 0.1 * total
    assert abs(residual) <= 1e-8


def test_tabulated_kinematics_agree_with_exact():
    """The tabulated reduced model (quintic splines of J and u_k) reaches the same state: final ω
    and t to 1e-6 relative after 20 revolutions of the nine-cylinder radial."""
    scene = replace(load_scene(CASES / "radial_9cyl.toml"), run=Run(revolutions=20))
    exact = integrate(scene).trajectory
    tab = integrate(replace(scene, solver=replace(scene.solver, kinematics="tabulated")))
    assert tab.solver["kinematics"] == "tabulated"
    for key in ("omega", "t"):
        assert tab.trajectory[key][-1] == pytest.approx(exact[key][-1], rel=1e-6)


def test_cli_run_and_info_report_the_harmonics(tmp_path, capsys):
    """``transient run`` on the V-twin (shortened copy) exits 0, and ``transient info`` lists the
    slave's figures: central articulation has λ_2 = the master's 2nd harmonic and no stroke
    excess."""
    text = (CASES / "v_twin_fork_blade.toml").read_text().replace("revolutions = 300",
                                                                 "revolutions = 10")
    scene = tmp_path / "vtwin.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "vtwin.h5")]) == 0
    out = capsys.readouterr().out
    lines = {ln.split(" = ")[0].strip(): ln.split(" = ")[1] for ln in out.splitlines()
             if ln.strip().startswith("cyl_2_")}
    print(lines)
    assert {"cyl_2_lambda", "cyl_2_lambda_semenov", "cyl_2_stroke_excess", "cyl_2_S3",
            "cyl_2_S3_semenov", "cyl_2_series_error_W", "cyl_2_tdc_after_bank"} <= set(lines)
    assert abs(float(lines["cyl_2_stroke_excess"].split()[0])) < 1e-15
    assert abs(float(lines["cyl_2_tdc_after_bank"].split()[0])) < 1e-12
