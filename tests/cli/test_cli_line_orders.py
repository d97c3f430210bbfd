"""``transient orders`` of an elastic run: the shaft line's tables and figures besides the orders
of ω, its summary on standard output, the column asked for checked before any work, nothing
overwritten without --force, and a rigid run's --line-column refused."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import transient
from transient.analysis.torsion_run import line_cycles, line_elements
from transient.cli import main
from transient.shaft import ShaftLine, rigid_equivalent

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"
FILES = ("campbell_run.png", "line_cycles.png", "line_cycles.csv", "line_orders.csv")


@pytest.fixture(scope="module")
def elastic(tmp_path_factory):
    """The case over five cycles from 2000 rpm, written as a result file."""
    scene = transient.load_scene(CASE).replace(initial={"omega_rpm": 2000},
                                               run={"revolutions": 10})
    path = tmp_path_factory.mktemp("elastic") / "six.h5"
    transient.simulate(scene, path)
    return path


def test_an_elastic_run_gets_its_lines_tables_and_figures(elastic, tmp_path, capsys):
    """The four files beside those of ω; the table's peak-to-peak per cycle is the analysis's
    (the torque on the grid), its power columns the damping parts', and standard output names
    the default column (the element the first mode twists most) and the heats' check."""
    assert main(["orders", str(elastic), "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    names = {p.name for p in tmp_path.iterdir()}
    assert {f"six_{end}" for end in FILES} <= names
    assert "heats of the damping parts" in out and "strongest orders up to 12" in out
    assert "damper silicone at pulley: mean power at most" in out
    assert "samples per period of the first mode" in out
    res = transient.open_result(elastic)
    scene = res.scene()
    line = ShaftLine(scene)
    cuts = res.events["breakpoint"]["phi"]  # (as transient orders takes them)
    lc = line_cycles(scene, res.trajectory, [e.torque for e in line_elements(line)], 720,
                     cuts=cuts)
    with open(tmp_path / "six_line_cycles.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == lc.cycle_start.size == 5
    i = lc.index("torque_throw_6_flywheel")
    np.testing.assert_allclose([float(r["torque_throw_6_flywheel_peak_to_peak_Nm"]) for r in rows],
                               lc.peak_to_peak[i], rtol=1e-11)
    assert float(rows[-1]["power_damper_silicone_at_pulley_W"]) > 0.0
    with open(tmp_path / "six_line_orders.csv", encoding="utf-8") as fh:
        header = next(csv.reader(fh))
    assert header[:2] == ["cycle", "cycle_omega_mean_rpm"]
    assert all(h.endswith("_Nm") for h in header[2:]) and len(header) == 2 + 24


def test_the_column_is_checked_before_any_work_and_nothing_is_overwritten(elastic, tmp_path,
                                                                         capsys):
    assert main(["orders", str(elastic), "-o", str(tmp_path), "--line-column", "twist_x"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--line-column" in err[0] and "twist_throw_1" in err[0]
    assert not any(tmp_path.iterdir())
    kept = tmp_path / "six_line_orders.csv"
    kept.write_text("mine", encoding="utf-8")
    assert main(["orders", str(elastic), "-o", str(tmp_path),
                 "--line-column", "twist_pulley"]) == 2
    assert "exists; use --force" in capsys.readouterr().err
    assert kept.read_text(encoding="utf-8") == "mine" and len(list(tmp_path.iterdir())) == 1
    assert main(["orders", str(elastic), "-o", str(tmp_path), "--line-column", "twist_pulley",
                 "--force"]) == 0
    out = capsys.readouterr().out
    assert "twist_pulley, strongest orders" in out
    with open(kept, encoding="utf-8") as fh:
        assert next(csv.reader(fh))[2].endswith("_rad")


def test_a_rigid_run_refuses_the_line_column(tmp_path, capsys):
    scene = rigid_equivalent(transient.load_scene(CASE)).replace(
        run={"revolutions": 4})
    path = tmp_path / "rigid.h5"
    transient.simulate(scene, path)
    assert main(["orders", str(path), "-o", str(tmp_path),
                 "--line-column", "torque_throw_6_flywheel"]) == 2
    err = capsys.readouterr().err
    assert "no elastic shaft line" in err
    assert main(["orders", str(path), "-o", str(tmp_path / "out")]) == 0
    assert not any(p.name.endswith(FILES) for p in (tmp_path / "out").iterdir())
