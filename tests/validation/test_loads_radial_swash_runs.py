"""Loads of radial and swash-plate runs end to end: a run whose scene asks for
``[analysis] loads`` stores them under ``/analysis`` with units, they equal the loads of the stored
samples, and they balance the simulated shaft.

The shaft check is the run's own equation of motion, read from the result file: the torque the
mechanism passes to the shaft (Σ_rows r(R_T + T_rk) for the radial, ``loads_shaft_torque`` for the
swash plate), plus the recorded load moment ``M_load``, accelerates the constant inertias
(``[inertia]``) at the recorded ε. Both sides come from different code (the analysis' d'Alembert
forces; the compiled model's reduced equation (18)), so they agree only if the forces are right.

Scenes: ``cases/radial_5cyl.toml`` (4 revolutions: two 720° cycles) and
``cases/swash_plate_4cyl.toml`` (3 revolutions), output every 5° from φ0 = 0, which the analysis
grid (``samples_per_cycle`` = 144 resp. 72) hits exactly, so no interpolation separates the
stored loads from the samples.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.loads.articulated import articulated_loads_from_trajectory
from transient.analysis.loads.common import rod_split
from transient.analysis.loads.swash_plate import swash_loads_from_trajectory
from transient.cli import main
from transient.results import open_result
from transient.run import simulate
from transient.scene import Analysis, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"


def _run(tmp, name, revolutions, samples_per_cycle):
    """The scene shortened, with ``[analysis] loads = true`` set on the loaded scene.

    (Set after loading: ``transient.scene`` still refuses ``loads`` for mechanisms other than
    the crank-slider when it reads a file; see test_cli_run_stores_radial_loads.)
    """
    scene = load_scene(CASES / f"{name}.toml")
    scene = replace(scene, run=replace(scene.run, revolutions=revolutions, t_end=math.inf),
                    analysis=Analysis(loads=True, samples_per_cycle=samples_per_cycle))
    path = tmp / f"{name}.h5"
    simulate(scene, path)
    return scene, open_result(path)


@pytest.fixture(scope="module")
def radial(tmp_path_factory):
    return _run(tmp_path_factory.mktemp("radial"), "radial_5cyl", 4, 144)


@pytest.fixture(scope="module")
def swash(tmp_path_factory):
    return _run(tmp_path_factory.mktemp("swash"), "swash_plate_4cyl", 3, 72)


def _on_grid(res, grid):
    """The stored samples at the analysis grid's angles."""
    tr = res.trajectory
    idx = np.searchsorted(tr["phi"], grid - 1e-9)
    np.testing.assert_allclose(tr["phi"][idx], grid, rtol=0, atol=1e-9)
    return {k: v[idx] for k, v in tr.items()}


def test_radial_loads_are_stored_with_units_and_match_the_samples(radial):
    scene, res = radial
    a = res.analysis
    assert res.complete and "loads_skipped" not in a
    n, ns = scene.mechanism.n_cylinders, scene.mechanism.n_slaves
    shapes = {"loads_phi": ((144,), "rad"), "loads_P": ((n, 144), "N"),
              "loads_N": ((n, 144), "N"), "loads_S": ((n, 144), "N"),
              "loads_torque": ((n, 144), "N m"), "loads_K": ((1, 144), "N"),
              "loads_T": ((1, 144), "N"), "loads_R_K": ((1, 144), "N"),
              "loads_R_T": ((1, 144), "N"), "loads_R": ((1, 144), "N"),
              "loads_crankpin_R_max": ((1,), "N"), "loads_link_x": ((ns, 144), "N"),
              "loads_link_y": ((ns, 144), "N"), "loads_link_R_max": ((ns,), "N"),
              "loads_engine_torque": ((144,), "N m")}
    for name, (shape, unit) in shapes.items():
        assert np.shape(a[name][0]) == shape and a[name][1] == unit, name
    assert not [k for k in a if k.startswith(("loads_main", "loads_journal"))]
    samples = _on_grid(res, a["loads_phi"][0])
    ld = articulated_loads_from_trajectory(scene, samples)
    scale = np.abs(ld.R).max()
    dev = max(np.abs(getattr(ld, k) - a[f"loads_{k}"][0]).max()
              for k in ("P", "N", "S", "K", "T", "R_K", "R_T", "R", "link_x", "link_y")) / scale
    print(f"radial: stored loads vs the samples {dev:.1e} of |R|max "
          f"({scale / 1e3:.4g} kN, peak link-pin load {a['loads_link_R_max'][0].max() / 1e3:.4g} "
          f"kN)")
    assert dev <= 1e-9


def test_radial_crankpin_torque_drives_the_shaft(radial):
    """Σ r(R_T + T_rk) + M_load = (I_shaft + I_flywheel) ε at every stored angle."""
    scene, res = radial
    a = {k: v for k, (v, _) in res.analysis.items()}
    s = _on_grid(res, a["loads_phi"])
    mech = scene.mechanism
    r = mech.crank_radius
    _, m2, _ = rod_split(mech.master())
    # R_T = T + T_rш and T_rk = −m_k r ε: the stored R_T plus the throw's own inertia.
    to_shaft = r * (a["loads_R_T"].sum(axis=0) - mech.rows * mech.crank_mass * r * s["epsilon"])
    inertia = scene.inertia.shaft + scene.inertia.flywheel
    lhs = to_shaft + s["M_load"]
    rhs = inertia * s["epsilon"]
    scale = np.abs(to_shaft).max()
    err = np.abs(lhs - rhs).max() / scale
    print(f"radial: shaft balance {err:.1e} of |torque to the shaft|max ({scale:.4g} N m); "
          f"|ε|max {np.abs(s['epsilon']).max():.4g} rad/s²")
    assert err <= 1e-9
    # The master rod's rotating mass matters here: R_T ≠ T when ε ≠ 0.
    assert np.abs(a["loads_R_T"] - a["loads_T"]).max() == pytest.approx(
        m2 * r * np.abs(s["epsilon"]).max(), rel=1e-9)


def test_swash_loads_are_stored_and_drive_the_shaft(swash):
    scene, res = swash
    a = res.analysis
    assert res.complete and "loads_skipped" not in a
    z = scene.mechanism.cylinders
    for name, shape, unit in (("loads_P", (z, 72), "N"), ("loads_S", (z, 72), "N"),
                              ("loads_N_radial", (z, 72), "N"),
                              ("loads_N_tangential", (z, 72), "N"),
                              ("loads_torque", (z, 72), "N m"),
                              ("loads_engine_torque", (72,), "N m"),
                              ("loads_shaft_torque", (72,), "N m")):
        assert np.shape(a[name][0]) == shape and a[name][1] == unit, name
    assert not [k for k in a if k.startswith(("loads_K", "loads_R", "loads_main"))]
    v = {k: val for k, (val, _) in a.items()}
    s = _on_grid(res, v["loads_phi"])
    ld = swash_loads_from_trajectory(scene, s)
    scale = np.abs(ld.S).max()
    dev = max(np.abs(getattr(ld, k) - v[f"loads_{k}"]).max()
              for k in ("P", "S", "N_radial", "N_tangential")) / scale
    dev_m = np.abs(ld.shaft_torque - v["loads_shaft_torque"]).max() / np.abs(ld.shaft_torque).max()
    lhs = v["loads_shaft_torque"] + s["M_load"]
    rhs = scene.inertia.shaft * s["epsilon"]
    err = np.abs(lhs - rhs).max() / np.abs(v["loads_shaft_torque"]).max()
    print(f"swash: stored vs samples {dev:.1e} (forces), {dev_m:.1e} (shaft torque); shaft "
          f"balance {err:.1e}; |ε|max {np.abs(s['epsilon']).max():.4g} rad/s²")
    assert dev <= 1e-9 and dev_m <= 1e-9 and err <= 1e-9


def test_cli_run_stores_radial_loads(tmp_path, capsys):
    """``transient run`` on a short radial scene asking for loads writes the datasets."""
    text = (CASES / "radial_5cyl.toml").read_text()
    assert "revolutions = 300" in text
    text = text.replace("revolutions = 300", "revolutions = 4")
    text += "\n[analysis]\nloads = true\nsamples_per_cycle = 144\n"
    scene = tmp_path / "radial.toml"
    scene.write_text(text)
    code = main(["run", str(scene), "-o", str(tmp_path), "-q"])
    _, err = capsys.readouterr()
    assert code == 0, err
    a = open_result(tmp_path / "radial.h5").analysis
    assert a["loads_R"][0].shape == (1, 144) and a["loads_link_x"][0].shape == (4, 144)
