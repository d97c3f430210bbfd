"""``transient loads`` and ``transient orders`` end to end: a short Gots spin-up is run
through ``transient.cli.main`` and both analyses are checked against independent calls of the
analysis functions; a swash-plate result is refused by ``loads`` (exit 2)."""
from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.analysis.irregularity import cycle_boundaries, fluctuation
from transient.analysis.loads.crank_slider import loads_from_trajectory
from transient.cli import main
from transient.results import open_result

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"


def _scene_text(name: str, old: str, new: str) -> str:
    text = (CASES / name).read_text()
    assert old in text, f"{name}: {old!r} not found"
    return text.replace(old, new)


@pytest.fixture(scope="module")
def spinup(tmp_path_factory):
    """The Gots spin-up (cases/gots_diesel_spinup.toml) for 8 revolutions: 4 whole cycles."""
    tmp = tmp_path_factory.mktemp("spinup")
    scene = tmp / "short_spinup.toml"
    scene.write_text(_scene_text("gots_diesel_spinup.toml", "revolutions = 1000",
                                 "revolutions = 8"))
    assert main(["run", str(scene), "-o", str(tmp), "-q"]) == 0
    path = tmp / "short_spinup.h5"
    assert path.is_file()
    return path


def _last_cycle_mask(res):
    scene = res.scene()
    traj = res.trajectory
    _, marks = cycle_boundaries(traj["t"], traj["phi"], scene.mechanism.cycle,
                                scene.initial.phi)
    tol = 1e-9 * scene.mechanism.cycle
    return (traj["phi"] >= marks[-2] - tol) & (traj["phi"] <= marks[-1] + tol)


def _nontrivial_png(path: Path) -> None:
    assert path.is_file(), path
    assert path.stat().st_size > 10_000, path
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    header = path.read_text().splitlines()[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert data.shape[1] == len(header)
    return {name: data[:, j] for j, name in enumerate(header)}


def test_loads_files_and_peak(spinup, tmp_path, capsys):
    with h5py.File(spinup, "r") as f:
        before = sorted(f["analysis"])
    out = tmp_path / "loads"
    assert main(["loads", str(spinup), "-o", str(out), "--cylinder", "2"]) == 0
    printed = capsys.readouterr().out
    stem = spinup.stem
    for name in ("polar", "crankpin", "wear", "running_torques"):
        _nontrivial_png(out / f"{stem}_loads_{name}.png")
    csv = _read_csv(out / f"{stem}_loads.csv")

    # Independent recomputation over the same window: the last whole cycle from φ0.
    res = open_result(spinup)
    scene = res.scene()
    loads = loads_from_trajectory(scene, res.trajectory)
    mask = _last_cycle_mask(res)
    assert csv["phi_rad"].size == mask.sum() > 100
    np.testing.assert_allclose(csv["phi_rad"], res.trajectory["phi"][mask], rtol=1e-11)
    for k in range(scene.mechanism.n_cylinders):
        peak = loads.R[k][mask].max()
        assert csv[f"R_{k + 1}_N"].max() == pytest.approx(peak, rel=1e-10)
        assert f"crankpin {k + 1}: |R| max {peak / 1e3:.6g} kN" in printed
    assert 3e4 < loads.R[1][mask].max() < 1e5  # tens of kN: the Gots diesel at full fuel
    # the engine torque column is Σ T r over the cylinders
    total = sum(csv[f"M_{k + 1}_Nm"] for k in range(scene.mechanism.n_cylinders))
    np.testing.assert_allclose(csv["M_engine_Nm"], total, rtol=1e-9, atol=1e-6)
    assert "main journal 2: |R| max" in printed and "kN" in printed and "N m" in printed
    # the result file is read only: nothing was added under /analysis
    with h5py.File(spinup, "r") as f:
        assert sorted(f["analysis"]) == before


def test_loads_bad_cylinder(spinup, tmp_path, capsys):
    assert main(["loads", str(spinup), "-o", str(tmp_path), "--cylinder", "4"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--cylinder" in err and len(err.splitlines()) == 1


def test_orders_files_and_delta(spinup, tmp_path, capsys):
    out = tmp_path / "orders"
    assert main(["orders", str(spinup), "-o", str(out), "--samples-per-cycle", "720"]) == 0
    printed = capsys.readouterr().out
    stem = spinup.stem
    _nontrivial_png(out / f"{stem}_orders.png")
    # four cycles: fewer inside the sweep than a run-up figure needs (RUN_UP_CYCLES)
    _nontrivial_png(out / f"{stem}_orders_cycles.png")
    assert not (out / f"{stem}_orders_runup.png").exists()
    csv = _read_csv(out / f"{stem}_orders.csv")
    assert csv["order"].size == 361  # N/2 + 1 orders, half orders of a 4-stroke cycle
    assert csv["order"][1] == pytest.approx(0.5)
    assert csv["omega_amplitude_rad_s"][1:].max() > 0.0
    assert csv["M_gas_amplitude_Nm"][1:].max() > 0.0
    # the odd-harmonic table: first-order W relative to itself is 1
    k1 = int(np.argmin(np.abs(csv["order"] - 1.0)))
    assert csv["W_1_relative"][k1] == pytest.approx(1.0)
    assert "odd>=3" in printed and "fractional" in printed
    runup = _read_csv(out / f"{stem}_orders_runup.csv")
    assert runup["cycle"].size == 4
    assert np.all(np.diff(runup["cycle_omega_mean_rad_s"]) > 0)  # spinning up

    res = open_result(spinup)
    scene = res.scene()
    traj = res.trajectory
    delta = fluctuation(traj["t"], traj["phi"], traj["omega"], scene.mechanism.cycle,
                        scene.initial.phi)
    m = re.search(r"δ = ([0-9.eE+-]+)", printed)
    assert m, printed
    assert float(m.group(1)) == pytest.approx(delta, rel=1e-10)
    assert delta == pytest.approx(res.analysis["delta_last_cycle"][0], rel=1e-12)


def test_loads_refuses_swash_plate(tmp_path, capsys):
    scene = tmp_path / "short_swash.toml"
    scene.write_text(_scene_text("swash_plate_1cyl.toml", "t_end = 8.0", "t_end = 0.3"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    result = tmp_path / "short_swash.h5"
    capsys.readouterr()
    assert main(["loads", str(result), "-o", str(tmp_path / "loads")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "crank-slider" in err
    assert not (tmp_path / "loads").exists()


def test_loads_of_a_radial_engine(tmp_path, capsys):
    """An articulated result: the polar diagram of the master crankpin, the load curves and a
    CSV whose crankpin load is the analysis function's on the stored samples of the last cycle."""
    from transient.analysis.loads.articulated import articulated_loads_from_trajectory

    scene = tmp_path / "short_radial.toml"
    scene.write_text(_scene_text("radial_5cyl.toml", "revolutions = 300", "revolutions = 6"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    result = tmp_path / "short_radial.h5"
    capsys.readouterr()
    out = tmp_path / "loads"
    assert main(["loads", str(result), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    for name in ("polar", "crankpin"):
        _nontrivial_png(out / f"short_radial_loads_{name}.png")
    csv = _read_csv(out / "short_radial_loads.csv")
    res = open_result(result)
    mask = _last_cycle_mask(res)
    win = {k: v[mask] for k, v in res.trajectory.items()}
    loads = articulated_loads_from_trajectory(res.scene(), win)
    # (the CSV holds 12 significant digits)
    np.testing.assert_allclose(csv["phi_rad"], win["phi"], rtol=1e-11)
    np.testing.assert_allclose(csv["R_row1_N"], loads.R[0], rtol=1e-10)
    np.testing.assert_allclose(csv["link_x_4_N"], loads.link_x[3], rtol=1e-10,
                               atol=1e-10 * np.abs(loads.link_x[3]).max())
    peak = re.search(r"row 1: \|R\| max ([0-9.eE+-]+) kN", printed)
    assert peak and float(peak.group(1)) == pytest.approx(loads.R[0].max() / 1e3, rel=1e-6)


def test_the_loads_csv_names_no_quantity_as_a_result_names_another(tmp_path, capsys):
    """One vocabulary: a loads CSV column is a result column's name only for the same quantity
    (Gots' rod force S is S_rod, not a result's pair moment S_k)."""
    from pathlib import Path

    import transient

    case = Path(__file__).resolve().parents[2] / "cases" / "gots_diesel_friction.toml"
    scene = transient.load_scene(case).replace(run={"revolutions": 3})
    res = transient.simulate(scene, tmp_path / "r.h5")
    assert main(["loads", str(tmp_path / "r.h5"), "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    header = (tmp_path / "r_loads.csv").read_text().splitlines()[0].split(",")
    assert "S_rod_1_N" in header and "S_1" in res.trajectory
    units = {"s": "s", "rad": "rad", "rad_s": "rad/s", "rad_s2": "rad/s^2", "N": "N", "Nm": "N m"}
    for column in header:
        for suffix, unit in units.items():
            name = column.removesuffix(f"_{suffix}")
            if name != column and name in res.units:
                assert res.units[name] == unit, column


#: Orders-CSV columns that no result stores (each is explained in the orders section of the
#: user guide): a run-up row's cycle number and the odd-harmonic report's comparisons with the
#: same engine at constant speed. Every other column is a stored quantity's name.
ORDERS_ONLY_IN_CSV = {"cycle", "W_1_amplitude_constant_m_s2", "W_1_relative",
                      "W_1_relative_constant", "W_1_relative_added"}

#: Each cylinder's gas torque spectrum (the run stores M_gas only, their sum).
PER_CYLINDER_TORQUE = re.compile(r"M_cylinder_\d+_(amplitude_Nm|phase_rad)")

#: Unit suffixes of CSV column names → the unit strings of result files.
CSV_UNITS = {"s": "s", "rad": "rad", "rad_s": "rad/s", "rad_s2": "rad/s^2", "N": "N", "Nm": "N m",
             "m_s2": "m/s^2"}


def _without_unit(column: str) -> tuple[str, str | None]:
    for suffix in sorted(CSV_UNITS, key=len, reverse=True):
        if column.endswith(f"_{suffix}"):
            return column.removesuffix(f"_{suffix}"), CSV_UNITS[suffix]
    return column, None


def test_the_orders_csvs_name_each_quantity_as_a_result_does(tmp_path, capsys):
    """One vocabulary: an orders-CSV column named as a trajectory column has its unit, and one
    named as a stored analysis ``orders_<name>`` (the scene's ``[analysis] orders``, same grid
    and orders) is that quantity: the same unit and the same values (last cycle for the
    per-order table, every cycle for the run-up table, to the CSV's 12 digits)."""
    import transient

    case = CASES / "gots_diesel_spinup.toml"
    scene = transient.load_scene(case).replace(
        run={"revolutions": 8},
        analysis={"orders": ["omega", "M_gas", "W_1"], "samples_per_cycle": 720,
                  "max_order": 12.0})
    res = transient.simulate(scene, tmp_path / "r.h5")
    assert main(["orders", str(tmp_path / "r.h5"), "-o", str(tmp_path),
                 "--samples-per-cycle", "720", "--max-order", "12"]) == 0
    capsys.readouterr()
    stored = res.analysis
    orders = stored["orders_order"][0]
    k = orders.size
    matched = set()
    for csv_name, per_order in (("r_orders.csv", True), ("r_orders_runup.csv", False)):
        csv = _read_csv(tmp_path / csv_name)
        for column, values in csv.items():
            name, unit = _without_unit(column)
            if name in res.units:
                assert res.units[name] == unit, column
            order = re.fullmatch(r"(\w+)_order_([0-9.]+)", name)
            if order:  # a run-up column: one order's amplitude over the cycles
                signal, nu = order.group(1), float(order.group(2))
                value, stored_unit = stored[f"orders_{signal}_amplitude"]
                value = value[:, int(np.argmin(np.abs(orders - nu)))]
            elif f"orders_{name}" in stored:
                value, stored_unit = stored[f"orders_{name}"]
                value = value[-1] if per_order and np.ndim(value) == 2 else value
            else:
                assert column in ORDERS_ONLY_IN_CSV or PER_CYLINDER_TORQUE.fullmatch(column), \
                    column
                continue
            matched.add(column)
            assert (unit or "1/rev") == stored_unit, column
            got = values[:k] if per_order else values
            np.testing.assert_allclose(got, value, rtol=1e-10,
                                       atol=1e-10 * np.abs(value).max(), err_msg=column)
    assert {"omega_amplitude_rad_s", "M_gas_amplitude_Nm", "W_1_amplitude_m_s2",
            "cycle_omega_mean_rad_s", "omega_order_1_rad_s"} <= matched
