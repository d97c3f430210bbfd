"""A governor far faster than the engine: detected by the stiffness test of the
compiled stepper and rerun by the implicit Radau method, with a message saying so.

The scene: the Gots PI generator set (``cases/gots_diesel_pi.toml``) with an actuator lag of
2 µs — the rack's eigenvalue −1/τ_A = −5·10⁵ 1/s against the engine's 33 ms cycle — through a
load step. The explicit DOP853 stops with ``stiff at t = …`` after 15 steps at hλ > 4
(``transient.core.integrator.tableaus``); ``integrate`` then runs the scene by scipy's Radau. Independent
check of that result: the compiled DOP853 with fixed crank-angle steps of 1e-3 rad, inside its
stability region (|hλ| = h/(τ_A ω) ≈ 1.2), where no stiffness test runs.
"""
from __future__ import annotations

import copy
import tomllib

import h5py
import numpy as np
import pytest
from conftest import CASES

from transient.run import integrate, run_compiled, simulate
from transient.scene import scene_from_dict


def stiff_scene(**solver):
    d = tomllib.loads((CASES / "gots_diesel_pi.toml").read_text(encoding="utf-8"))
    d["governor"]["actuator_time"] = 2e-6
    d["load"].update(schedule_time=[0.05, 0.05], schedule_scale=[0.0, 1.0])
    d["run"] = {"t_end": 0.1}
    d["solver"].update(solver)
    return scene_from_dict(copy.deepcopy(d), "stiff.toml")


@pytest.mark.slow
def test_stiffness_detected_and_rerun_by_radau(tmp_path):
    explicit = run_compiled(stiff_scene(), keep=True)
    assert not explicit.complete
    assert explicit.message.startswith("stiff at t = ") and "φ = " in explicit.message
    t_detect = explicit.trajectory["t"][-1]
    assert t_detect < 0.01  # within the first cycle: ~15 steps once the rack's mode is stiff

    data = simulate(stiff_scene(), tmp_path / "stiff.h5")
    assert data.complete
    assert data.solver["method"] == "scipy-Radau"
    assert data.solver["stiff_rerun"].startswith(explicit.message)
    assert data.solver["stiff_rerun"].endswith("rerun from the start with the implicit scipy-Radau")
    with h5py.File(tmp_path / "stiff.h5") as f:  # the file holds the Radau run alone
        t = f["trajectory/t"][()]
        assert f.attrs["complete"] and f["solver"].attrs["method"] == "scipy-Radau"
        assert t[0] == 0.0 and t[-1] == 0.1 and np.all(np.diff(t) >= 0.0)

    fixed = integrate(stiff_scene(fixed_step=1e-3))
    assert fixed.complete and "stiff_rerun" not in fixed.solver
    w_radau, w_fixed = data.trajectory["omega"][-1], fixed.trajectory["omega"][-1]
    rack = abs(data.trajectory["gov_rack"][-1] - fixed.trajectory["gov_rack"][-1])
    print(f"detected at t = {t_detect:.4g} s; Radau ω(0.1 s) = {w_radau:.10g}, fixed-step "
          f"{w_fixed:.10g} rad/s (relative {w_radau / w_fixed - 1:.2g}); rack {rack:.2g}; "
          f"Radau {data.solver['nsteps']} steps, explicit {data.solver['explicit_nsteps']}")
    assert abs(w_radau / w_fixed - 1.0) <= 1e-7
    assert rack <= 1e-6
