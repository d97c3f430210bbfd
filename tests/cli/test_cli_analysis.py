"""The scene's ``[analysis]`` table end to end: ``transient run`` stores what it asks
for under ``/analysis`` with units, ``transient info`` lists it, a scene that asks for nothing
gets nothing new, and a run too short for a whole cycle says so instead of failing.

The stored values are checked against independent computations on the stored trajectory: the
spin-up's output samples (72 per revolution from φ0) coincide with the analysis grid
(``samples_per_cycle = 144``), so no interpolation separates the two.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.irregularity import cycle_boundaries, fluctuation
from transient.analysis.loads.crank_slider import loads_from_trajectory
from transient.cli import main
from transient.results import open_result
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
ANALYSIS = """
[analysis]
loads = true
orders = ["omega", "M_gas", "W_1"]
irregularity = true
max_order = 6
samples_per_cycle = 144
"""


def _run(tmp, name, text, capsys):
    scene = tmp / f"{name}.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "-o", str(tmp), "-q"]) == 0
    capsys.readouterr()
    return tmp / f"{name}.h5"


@pytest.fixture(scope="module")
def spinup(tmp_path_factory):
    """The Gots spin-up for 8 revolutions (4 whole cycles) with every analysis asked for."""
    tmp = tmp_path_factory.mktemp("analysis")
    text = (CASES / "gots_diesel_spinup.toml").read_text()
    assert "revolutions = 1000" in text
    scene = tmp / "asked.toml"
    scene.write_text(text.replace("revolutions = 1000", "revolutions = 8") + ANALYSIS)
    assert main(["run", str(scene), "-o", str(tmp), "-q"]) == 0
    return open_result(tmp / "asked.h5")


def test_stored_with_units_and_round_trip(spinup):
    a = spinup.analysis
    units = {"irregularity_cycle_delta": "1", "irregularity_cycle_omega_mean": "rad/s",
             "orders_order": "1/rev", "orders_omega_amplitude": "rad/s",
             "orders_M_gas_amplitude": "N m", "orders_W_1_amplitude": "m/s^2",
             "orders_omega_phase": "rad", "loads_phi": "rad", "loads_T": "N", "loads_R": "N",
             "loads_engine_torque": "N m", "loads_journal_torque": "N m", "loads_main_x": "N"}
    for name, unit in units.items():
        assert a[name][1] == unit, name
    assert a["orders_detrend"][0] == "ramp"  # a spin-up from 1000 rpm: detrended by default
    assert a["orders_omega_amplitude"][0].shape == (4, 13)  # 4 cycles, orders 0 … 6 by ½
    assert a["loads_T"][0].shape == (3, 144)
    assert a["loads_main_x"][0].shape == (4, 144)
    scene = spinup.scene()  # /scene/toml reads back with its [analysis]
    assert scene.analysis.orders == ("omega", "M_gas", "W_1")
    assert scene.analysis.loads and scene.analysis.samples_per_cycle == 144


def test_irregularity_and_loads_agree_with_the_trajectory(spinup):
    a = {k: v for k, (v, _) in spinup.analysis.items()}
    tr = spinup.trajectory
    scene = spinup.scene()
    cycle = scene.mechanism.cycle
    tb, _ = cycle_boundaries(tr["t"], tr["phi"], cycle, scene.initial.phi)
    np.testing.assert_allclose(a["irregularity_cycle_omega_mean"], cycle / np.diff(tb),
                               rtol=1e-12)
    assert a["irregularity_cycle_delta"][-1] == pytest.approx(
        fluctuation(tr["t"], tr["phi"], tr["omega"], cycle, scene.initial.phi), rel=1e-12)
    assert a["irregularity_cycle_delta"][-1] == pytest.approx(a["delta_last_cycle"], rel=1e-12)
    # the orders' cycle means come from t resampled onto the grid: the same cycles
    np.testing.assert_allclose(a["orders_cycle_omega_mean"], a["irregularity_cycle_omega_mean"],
                               rtol=1e-9)
    # loads over the last cycle = the loads of the stored samples at the same angles
    phi = tr["phi"]
    idx = np.searchsorted(phi, a["loads_phi"] - 1e-9)
    np.testing.assert_allclose(phi[idx], a["loads_phi"], rtol=0, atol=1e-9)
    ld = loads_from_trajectory(scene, {k: v[idx] for k, v in tr.items()})
    scale = np.abs(ld.T).max()
    dev = max(np.abs(ld.T - a["loads_T"]).max(), np.abs(ld.R - a["loads_R"]).max()) / scale
    dev_m = np.abs(ld.engine_torque - a["loads_engine_torque"]).max() / scale / ld.r
    print(f"stored loads vs the samples: {dev:.1e} (T, R), {dev_m:.1e} (torque), relative")
    assert dev <= 1e-9 and dev_m <= 1e-9
    # the last journal carries every throw's r(T + T_rш + T_rk): ≠ Σ T r while ε ≠ 0 (§2.8)
    np.testing.assert_allclose(a["loads_journal_torque"][-1], ld.throw_torque.sum(axis=0),
                               rtol=0, atol=1e-9 * scale * ld.r)
    assert np.abs(a["loads_journal_torque"][-1] - a["loads_engine_torque"]).max() > 1.0


def test_piston_acceleration_orders(spinup):
    """W_1's first order → r ω̄² (Gots (6): the first-order term rω² cos φ; the exact
    kinematics add ~0.4 %) as the spin-up's share ε s′ fades cycle by cycle."""
    a = {k: v for k, (v, _) in spinup.analysis.items()}
    mech = spinup.scene().mechanism
    k1 = int(np.nonzero(np.isclose(a["orders_order"], 1.0))[0][0])
    ratio = a["orders_W_1_amplitude"][:, k1] / (mech.crank_radius
                                                 * a["orders_cycle_omega_mean"] ** 2)
    print(f"|W_1, order 1| / (r ω̄²) per cycle: {np.round(ratio, 4)}")
    assert np.all(np.diff(ratio) < 0)
    assert abs(ratio[-1] - 1.0) < 0.01


def test_info_lists_the_stored_analyses(spinup, capsys):
    assert main(["info", str(spinup.path)]) == 0
    out = capsys.readouterr().out
    assert "analyses asked for by the scene ([analysis];" in out
    assert "orders_omega_amplitude 4×13 [rad/s]" in out
    assert "loads_main_x 4×144 [N]" in out


def test_not_asked_nothing_stored(tmp_path, capsys):
    text = (CASES / "coasting_single.toml").read_text()
    path = _run(tmp_path, "plain", text, capsys)
    res = open_result(path)
    prefixes = ("loads_", "orders_", "irregularity_")
    assert not [k for k in res.analysis if k.startswith(prefixes)]
    assert "[analysis]" not in res.scene_toml
    assert not res.scene().analysis.requested


def test_too_short_run_is_skipped_not_failed(tmp_path, capsys):
    text = (CASES / "coasting_single.toml").read_text()
    scene = load_scene(CASES / "coasting_single.toml")
    short = "\n[analysis]\nirregularity = true\n"
    revs = scene.mechanism.cycle / (2 * math.pi) / 2  # half a cycle
    text = re.sub(r"(?m)^revolutions\s*=.*$", f"revolutions = {revs}", text)
    path = _run(tmp_path, "short", text + short, capsys)
    res = open_result(path)
    assert res.complete
    assert "no whole cycle" in res.analysis["irregularity_skipped"][0]
