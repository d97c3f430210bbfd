"""Runs with the tabulated reduced model against the same runs with the exact kernels, the
energy law for the tabulated mechanism itself, and the fall-back to the exact kernels when no
table reaches the tolerance asked for."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model, kinematics_table
from transient.run import integrate
from transient.scene import Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"


def pair(stem, revs, rtol, **solver):
    base = load_scene(CASES / f"{stem}.toml")
    base = replace(base, run=replace(base.run, revolutions=revs, t_end=math.inf))
    exact = replace(base, solver=replace(base.solver, rtol=rtol, atol=rtol * 1e-3, **solver))
    tab = replace(exact, solver=replace(exact.solver, kinematics="tabulated"))
    return integrate(exact), integrate(tab)


@pytest.mark.parametrize("stem", ["coasting_single", "gots_diesel_governed", "swash_plate_4cyl"])
def test_tabulated_run_agrees_with_exact(stem):
    """100 revolutions at rtol 1e-10 (tables to 1e-12): final time and ω agree to 1e-9
    (both runs' own errors are ~rtol). Measured: see -s."""
    exact, tab = pair(stem, 100, 1e-10)
    assert tab.solver["kinematics"] == "tabulated" and tab.solver["table_error"] <= 1e-12
    dt = abs(tab.trajectory["t"][-1] / exact.trajectory["t"][-1] - 1)
    dw = abs(tab.trajectory["omega"][-1] / exact.trajectory["omega"][-1] - 1)
    print(f"{stem}: {tab.solver['table_intervals']} intervals, Δt/t {dt:.1e}, Δω/ω {dw:.1e}")
    assert dt <= 1e-9 and dw <= 1e-9


def test_tabulated_coasting_in_time_conserves_its_energy():
    """In time the stepper integrates (18) with the tables' J and J′; as J′ is the derivative of
    the tabulated J, ½J_tab ω² is a first integral: its drift over 200 revolutions at rtol 1e-10
    stays at the level of the exact model's (test_energy: ≤ 3000 rtol)."""
    base = load_scene(CASES / "coasting_single.toml")
    scene = replace(base, run=Run(revolutions=200),
                    solver=replace(base.solver, rtol=1e-10, atol=1e-12, kinematics="tabulated",
                                   switch_speed=2 * base.initial.omega))
    data = integrate(scene)
    tr = data.trajectory
    assert data.solver["kinematics"] == "tabulated" and "to_angle_domain" not in data.events
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    drift = np.max(np.abs(K / K[0] - 1))
    print(f"time domain, tabulated: |ΔK/K|max {drift:.2e}")
    assert drift <= 3000 * 1e-10


def test_unreachable_tolerance_falls_back_to_exact():
    """A tolerance below what the splines reach (~1e-13): no table, the exact kernel, and the run
    says so; the result is the exact run's."""
    base = load_scene(CASES / "coasting_single.toml")
    base = replace(base, run=replace(base.run, revolutions=5))
    scene = replace(base, solver=replace(base.solver, kinematics="tabulated",
                                         table_tolerance=1e-15))
    assert kinematics_table(scene).coef is None
    model, _, _ = build_model(scene)
    assert model.terms is scene.mechanism.kernel
    data, exact = integrate(scene), integrate(base)
    assert data.solver["kinematics"].startswith("exact (no table")
    assert data.solver["table_error"] > 1e-15
    np.testing.assert_array_equal(data.trajectory["omega"], exact.trajectory["omega"])
