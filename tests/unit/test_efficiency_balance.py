"""The work–energy balance's residual is relative to the energy the balance moves, so that a
machine where no gas or starter works (coasting against a brake, W_in = 0) reports rounding as
rounding, not divided by nothing."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from transient.analysis.efficiency import mechanical_efficiency
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_a_machine_coasting_against_a_brake_balances_relative_to_its_throughput():
    # J constant, a constant brake M: ω² = ω0² − 2Mφ/J exactly, K falls by M·Δφ, the load takes it
    scene = load_scene(CASES / "coasting_single.toml")
    J, M, w0 = 0.731, 2.3, 100.3
    phi = np.linspace(0.0, 4.0 * math.pi, 2001)
    omega = np.sqrt(w0 ** 2 - 2.0 * M * phi / J)
    t = J * (w0 - omega) / M
    zeros = np.zeros_like(phi)
    traj = {"t": t, "phi": phi, "omega": omega, "J": np.full_like(phi, J), "W_gas": zeros,
            "W_starter": zeros, "W_load": -M * phi, "M_gas": zeros, "M_starter": zeros,
            "M_load": np.full_like(phi, -M)}
    out = mechanical_efficiency(scene, traj, window=(0.0, 4.0 * math.pi, 1))
    assert out["W_in_per_cycle"][0] == 0.0
    assert math.isclose(out["W_out_per_cycle"][0], M * 4.0 * math.pi, rel_tol=1e-12)
    assert abs(out["energy_balance_residual"][0]) <= 1e-12
    assert math.isnan(out["eta_mech_work"][0])
