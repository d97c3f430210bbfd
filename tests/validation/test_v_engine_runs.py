"""A V8 with two rods on each crankpin through the whole model (``cases/v8_cross_plane.toml``:
cross-plane crank, side-by-side rods, crank mass per throw).

* The run's J(φ) is the model written here: the sum over the cylinders of one crank-slider's J
  (the numpy twin of a single cylinder without crank mass) at each cylinder's local angle from
  the published crank, plus the constant inertias and m_k r² once per throw.
* Work–energy: ½J(φ)ω² with that J changes by W_gas + W_load (the run's work integrals): to
  rounding in crank angle, where the kinetic energy is the state, and to C·rtol in time; the gas
  torque is Σ (p_c − p0) F_p u_c with the pistons' u_c of the same model.
* ``transient run`` stores, and ``transient loads`` prints and writes, the five main journals
  and the running torques of the four throws, the journals those of
  :func:`transient.analysis.loads.crank_slider.main_journal_loads` on the stored grid
  (``tests/unit/test_v_engines.py`` checks that function against Newton–Euler).
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.cli import main
from transient.mechanisms.twins import CrankSliderNumpy
from transient.results import open_result
from transient.run import integrate
from transient.scene import Run, load_scene

CASE = Path(__file__).resolve().parents[2] / "cases" / "v8_cross_plane.toml"
C_DRIFT = 3000.0  # as tests/validation/test_energy.py: time-domain drift ≤ C·rtol


BANKS = np.radians([45.0, -45.0] * 4)
PINS = np.radians(np.repeat([0.0, 90.0, 270.0, 180.0], 2))


def independent_terms(scene):
    """φ ↦ (J, u_c) of the whole machine: Σ_c J_cylinder(φ + θ_c − δ_c) + 4 m_k r² + the
    constants and each piston's ds/dφ, the crank as the case's comments publish it (banks ±45°,
    throws 0°, 90°, 270°, 180°), each cylinder the numpy twin of a single cylinder."""
    mech = scene.mechanism
    single = CrankSliderNumpy(replace(mech, crank_mass=0.0, firing_angles=(0.0,),
                                      bank_angles=(0.0,), rod_arrangement="single",
                                      rod_spacing=0.0, journal_spacing=0.0))
    constant = 4 * mech.crank_mass * mech.crank_radius**2 + scene.inertia.total

    def terms(phi):
        parts = [single.terms(phi + PINS[c] - BANKS[c]) for c in range(8)]
        return sum(p[0] for p in parts) + constant, np.array([p[2][0] for p in parts])
    return terms


@pytest.mark.parametrize("domain", ["auto", "time"])
def test_v8_run_keeps_the_work_energy_balance_with_its_own_inertia(domain):
    """20 revolutions from 1500 rpm, in crank angle (where ½J(φ)ω² is the state) and in time
    throughout (where the balance is a result: its drift ≤ C·rtol, C as
    ``tests/validation/test_energy.py``); the gas torque is Σ (p_c − p0) F_p u_c."""
    scene = load_scene(CASE)
    solver = replace(scene.solver, domain=domain)
    data = integrate(replace(scene, run=Run(revolutions=20), solver=solver))
    tr = data.trajectory
    assert data.complete, data.message
    terms = independent_terms(scene)
    J, u = map(np.array, zip(*(terms(p) for p in tr["phi"])))
    assert np.max(np.abs(tr["J"] - J)) <= 1e-12 * J.max()
    p = np.array([tr[f"p_{c + 1}"] for c in range(8)])
    gas = np.sum((p - scene.gas.p0) * scene.mechanism.piston_area * u.T, axis=0)
    assert np.max(np.abs(tr["M_gas"] - gas)) <= 1e-12 * np.max(np.abs(gas))
    K = 0.5 * J * tr["omega"] ** 2
    works = tr["W_gas"] + tr["W_load"] + tr["W_starter"]
    total = abs(tr["W_gas"][-1]) + abs(tr["W_load"][-1])
    residual = np.max(np.abs(K - K[0] - works)) / total
    print(f"V8, 20 revolutions, domain {domain}: ω {tr['omega'][0]:.1f} → "
          f"{tr['omega'][-1]:.1f} rad/s, max |ΔK − W| / (|W_gas| + |W_load|) = {residual:.1e}")
    assert tr["omega"][-1] > 1.3 * tr["omega"][0]  # it did spin up: the works are not small
    assert residual <= (1e-12 if domain == "auto" else C_DRIFT * scene.solver.rtol)


def test_v8_loads_of_the_main_journals(tmp_path, capsys):
    """``transient run`` stores, ``transient loads`` prints and writes, the five journals and the
    four throws' running torques; the last journal carries the engine's every throw torque."""
    assert main(["run", str(CASE), "-o", str(tmp_path), "-q"]) == 0
    result = tmp_path / "v8_cross_plane.h5"
    a = open_result(result).analysis
    n = a["loads_phi"][0].size
    assert a["loads_main_x"][0].shape == a["loads_main_y"][0].shape == (5, n)
    assert a["loads_main_R_max"][0].shape == (5,)
    journals, pins = a["loads_journal_torque"][0], a["loads_crankpin_torque"][0]
    assert journals.shape == (5, n) and pins.shape == (4, n)
    assert np.all(journals[0] == 0.0)
    # the mean of the last journal's torque is the engine's mean torque (ε averages out)
    assert math.isclose(journals[-1].mean(), a["loads_engine_torque"][0].mean(), rel_tol=1e-3)
    capsys.readouterr()
    assert main(["loads", str(result), "-o", str(tmp_path / "loads")]) == 0
    out = capsys.readouterr().out
    for j in range(1, 6):
        assert f"  main journal {j}: |R| max" in out
    assert "  rod 8 on crankpin 4: |R| max" in out and "running torque crankpin 4" in out
    assert "in-line engines only" not in out
    header = (tmp_path / "loads" / "v8_cross_plane_loads.csv").read_text().splitlines()[0]
    assert "R_main_5_N" in header and "M_crankpin_4_Nm" in header and "M_crankpin_5" not in header
