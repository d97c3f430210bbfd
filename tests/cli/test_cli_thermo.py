"""``[analysis] thermodynamics`` and the run's own diagrams end to end: ``transient run`` prints
the last cycle's mean effective pressures, ``transient info`` repeats them, ``transient plot``
draws the run's indicator diagrams, the speed over the last cycle, each cylinder's torque and
J(φ) beside the gas torque, and refuses a cylinder or cycle the result does not hold (exit 2,
one line). The values themselves: tests/validation/test_thermo_runs.py."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from transient.analysis.pistons import cylinder_torques
from transient.cli import main
from transient.results import open_result

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture(scope="module")
def friction_result(tmp_path_factory):
    """The friction case near its steady speed, 12 revolutions, thermodynamics asked for."""
    tmp = tmp_path_factory.mktemp("thermo")
    text = (CASES / "gots_diesel_friction.toml").read_text()
    assert "revolutions = 600" in text and "omega_rpm = 1000" in text
    text = text.replace("revolutions = 600", "revolutions = 12").replace(
        "omega_rpm = 1000", "omega_rpm = 3900") + "\n[analysis]\nthermodynamics = true\n"
    scene = tmp / "fr.toml"
    scene.write_text(text)
    return tmp, scene


def test_run_and_info_print_the_mean_effective_pressures(friction_result, capsys):
    tmp, scene = friction_result
    assert main(["run", str(scene), "-o", str(tmp), "--force"]) == 0
    out = capsys.readouterr().out
    res = open_result(tmp / "fr.h5")
    a = res.analysis
    line = next(x for x in out.splitlines() if "IMEP" in x)
    assert f"IMEP {a['thermo_last_imep_engine'][0] / 1e5:.5g} bar" in line
    assert f"BMEP {a['thermo_last_bmep'][0] / 1e5:.5g} bar" in line
    assert f"FMEP {a['thermo_last_fmep'][0] / 1e5:.5g} bar" in line
    # 12 revolutions from φ0 = 0: six cycles
    assert a["thermo_imep"][1] == "Pa" and a["thermo_imep"][0].shape == (3, 6)
    assert main(["info", str(tmp / "fr.h5")]) == 0
    assert line in capsys.readouterr().out


def test_cylinder_torques_add_up_to_the_gas_torque(friction_result):
    tmp, scene = friction_result
    if not (tmp / "fr.h5").exists():
        assert main(["run", str(scene), "-o", str(tmp), "-q"]) == 0
    res = open_result(tmp / "fr.h5")
    m = cylinder_torques(res.scene(), res.trajectory)
    gas = res.trajectory["M_gas"]
    assert m.shape == (3, gas.size)
    assert np.max(np.abs(m.sum(axis=0) - gas)) <= 1e-12 * np.max(np.abs(gas))


def test_plot_draws_the_runs_diagrams_and_checks_its_choices(friction_result, capsys):
    tmp, scene = friction_result
    if not (tmp / "fr.h5").exists():
        assert main(["run", str(scene), "-o", str(tmp), "-q"]) == 0
    capsys.readouterr()
    figures = tmp / "figures"
    assert main(["plot", str(tmp / "fr.h5"), "-o", str(figures), "--cylinder", "2",
                 "--cycles", "0", "-1"]) == 0
    names = {Path(x.removeprefix("wrote ")).name for x in capsys.readouterr().out.splitlines()}
    assert {"fr_speed_cycle.png", "fr_inertia.png", "fr_cylinder_torques.png",
            "fr_indicator.png"} <= names
    for option, value, says in (("--cylinder", "4", "allowed: 1 … 3"),
                                ("--cycles", "5", "allowed -5 … 4")):
        code = main(["plot", str(tmp / "fr.h5"), "-o", str(figures), "--force", option, value])
        err = capsys.readouterr().err
        assert code == 2 and len(err.splitlines()) == 1, err
        assert err.startswith(f"{tmp / 'fr.h5'}: {option}: ") and says in err


def test_check_refuses_thermodynamics_without_a_pressure(tmp_path, capsys):
    text = (CASES / "swash_plate_1cyl.toml").read_text()
    assert 'model = "trapezoid"' in text
    scene = tmp_path / "force.toml"
    scene.write_text(text + "\n[analysis]\nthermodynamics = true\n")
    assert main(["check", str(scene)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1
    assert "analysis.thermodynamics: gas model 'trapezoid' applies no cylinder pressure" in err


def test_cylinder_torque_orders_add_up_to_the_gas_torques(friction_result, capsys):
    """The spectra of the cylinders' torques (``transient orders``) add up, order by order as
    complex coefficients, to the spectrum of M_gas: the DFT is linear and the torques add up to
    M_gas at every grid point."""
    from transient.analysis.orders import run_orders

    tmp, scene = friction_result
    if not (tmp / "fr.h5").exists():
        assert main(["run", str(scene), "-o", str(tmp), "-q"]) == 0
    res = open_result(tmp / "fr.h5")
    cuts = res.events["breakpoint"]["phi"]
    ro = run_orders(res.scene(), res.trajectory, 720, cuts=cuts, piston_cylinder=2)
    total = ro.cylinder_torques.coef.sum(axis=0)
    scale = np.abs(ro.gas_torque.coef[-1]).max()
    assert np.max(np.abs(total - ro.gas_torque.coef[-1])) <= 1e-9 * scale
    assert main(["orders", str(tmp / "fr.h5"), "-o", str(tmp / "orders"), "--cylinder", "2"]) == 0
    out = capsys.readouterr().out
    assert "piston acceleration W of cylinder 2" in out and "cylinder 3 torque" in out
    code = main(["orders", str(tmp / "fr.h5"), "-o", str(tmp / "orders"), "--cylinder", "0"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.splitlines()) == 1 and "allowed: 1 … 3" in err


def test_plot_without_a_whole_cycle_of_a_cylinder_draws_no_indicator(tmp_path, capsys):
    """Two revolutions from φ = 0: one engine cycle, which holds a whole cycle of its own only
    for cylinder 1 (its gas phase is 0); the others' diagrams are left out, not failed on."""
    text = (CASES / "gots_diesel_friction.toml").read_text()
    scene = tmp_path / "short.toml"
    scene.write_text(text.replace("revolutions = 600", "revolutions = 2").replace(
        "omega_rpm = 1000", "omega_rpm = 3900"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "short.h5")]) == 0
    names = [Path(x.removeprefix("wrote ")).name for x in capsys.readouterr().out.splitlines()]
    assert "short_speed_cycle.png" in names and "short_indicator.png" not in names
    assert main(["plot", str(tmp_path / "short.h5"), "--cylinder", "1", "--force"]) == 0
    assert "short_indicator.png" in capsys.readouterr().out
    assert main(["plot", str(tmp_path / "short.h5"), "--cylinder", "2", "--cycles", "-1",
                 "--force"]) == 2
    assert "--cycles: cycle -1 is not held" in capsys.readouterr().err


def test_plot_draws_the_heat_release_of_a_wiebe_run(tmp_path, capsys):
    """The Wiebe case near its droop line, 4 revolutions at 0.5°: the heat-release figure is
    written (its curve: tests/validation/test_thermo_runs.py), and not for the mixed cycle."""
    text = (CASES / "gots_diesel_wiebe.toml").read_text()
    assert "revolutions = 1000" in text and "samples_per_rev = 72" in text
    scene = tmp_path / "wb.toml"
    scene.write_text(text.replace("revolutions = 1000", "revolutions = 4").replace(
        "omega_rpm = 1000", "omega_rpm = 4300").replace("samples_per_rev = 72",
                                                        "samples_per_rev = 720"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "wb.h5"), "--cylinder", "1"]) == 0
    assert "wb_heat_release.png" in capsys.readouterr().out
    data = (tmp_path / "wb_heat_release.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000
