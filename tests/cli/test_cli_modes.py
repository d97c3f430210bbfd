"""``transient modes``: the modes table and critical speeds on standard output, the Campbell
diagram (and with --csv the tables) written, nothing overwritten without --force, and every
mistake one line with exit 2."""
from __future__ import annotations

import csv
from pathlib import Path

import pytest

from transient.cli import main

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"


def test_modes_prints_the_table_and_writes_the_figure_and_tables(tmp_path, capsys):
    assert main(["modes", str(CASE), "-o", str(tmp_path), "--csv"]) == 0
    out = capsys.readouterr().out
    assert "2 rigid mode(s) at 0 Hz" in out and "critical speeds from 800 to 4400 rpm" in out
    names = {p.name for p in tmp_path.iterdir()}
    assert names == {"inline6_damper_campbell.png", "inline6_damper_modes.csv",
                     "inline6_damper_criticals.csv", "inline6_damper_damped_criticals.csv"}
    assert (tmp_path / "inline6_damper_campbell.png").read_bytes()[:4] == b"\x89PNG"
    with open(tmp_path / "inline6_damper_criticals.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert rows and all(800 <= float(r["rpm"]) <= 4400 for r in rows)
    # each critical is its mode's frequency over its order (the modes table's f)
    with open(tmp_path / "inline6_damper_modes.csv", encoding="utf-8") as fh:
        f = {int(float(r["mode"])): float(r["f_Hz"]) for r in csv.DictReader(fh)}
    for r in rows:
        assert float(r["rpm"]) == pytest.approx(60 * f[int(float(r["mode"]))]
                                                / float(r["order"]), rel=1e-10)
    # the damped line's: each its damped mode's f_n over its order, below the undamped one's
    with open(tmp_path / "inline6_damper_damped_criticals.csv", encoding="utf-8") as fh:
        damped = list(csv.DictReader(fh))
    f_n = [float(r.split()[0]) for r in
           out[out.index("damped: "):out.index("critical speeds")].splitlines()[1:]]
    assert damped and f_n
    for r in damped:
        assert float(r["rpm"]) == pytest.approx(60 * f_n[int(float(r["mode"])) - 1]
                                                / float(r["order"]), rel=1e-3)  # (4 digits)
    first = {float(r["order"]): float(r["rpm"]) for r in damped if float(r["mode"]) == 1}
    assert first and all(rpm < 60 * f[1] / q for q, rpm in first.items())


def test_nothing_is_overwritten_without_force(tmp_path, capsys):
    figure = tmp_path / "inline6_damper_campbell.png"
    figure.write_bytes(b"mine")
    assert main(["modes", str(CASE), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exists; use --force" in err[0]
    assert figure.read_bytes() == b"mine"
    assert main(["modes", str(CASE), "-o", str(tmp_path), "--force"]) == 0
    assert figure.read_bytes()[:4] == b"\x89PNG"


def test_speed_range_and_orders_from_the_options(tmp_path, capsys):
    assert main(["modes", str(CASE), "-o", str(tmp_path), "--speed-range", "2600,2700",
                 "--max-order", "6"]) == 0
    out = capsys.readouterr().out
    table = out[out.index("critical speeds"):out.index("critical speeds of the damped")]
    rows = [line.split() for line in table.splitlines()[2:] if line.strip()]
    assert [(r[1], r[2], r[3]) for r in rows] == [("1", "6", "major")]
    # (the damper lowers the first mode: its order 6 critical falls below 2600 rpm)
    damped = out[out.index("critical speeds of the damped"):].splitlines()
    assert damped[1].strip() == "none"


@pytest.mark.parametrize("args, words", [
    (["--speed-range", "3000,1000"], "--speed-range: give two speeds LO,HI"),
    (["--speed-range", "x"], "--speed-range: must be comma-separated numbers"),
    (["--max-order", "0"], "max-order"),
    (["--speeds", "50"], "--speeds: sets the speeds of the forced response and the stability "
                         "chart; add --response or --floquet"),
    (["--floquet", "--speeds", "1"], "speeds"),
    (["--response", "--speeds", "1"], "speeds"),
])
def test_bad_options_are_one_line(tmp_path, capsys, args, words):
    assert main(["modes", str(CASE), "-o", str(tmp_path), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]
    assert list(tmp_path.iterdir()) == []


def test_a_scene_without_a_shaft_line_is_refused(tmp_path, capsys):
    rigid = CASE.parent / "gots_diesel_spinup.toml"
    assert main(["modes", str(rigid), "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "shaft: the scene has no [shaft] table" in err


def test_the_campbell_diagram_takes_a_runs_order_spectra():
    """The overlay draws one marker per cycle and order, on that order's line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from transient import plots
    from transient.analysis.torsion import critical_speeds, engine_orders, modal_analysis
    from transient.scene import load_scene
    from transient.shaft import ShaftLine

    scene = load_scene(CASE)
    modal = modal_analysis(ShaftLine(scene), band_samples=8)
    orders = engine_orders(scene.mechanism.cycle, 6)
    fig, ax = plt.subplots()
    speeds, run_q = np.array([1000.0, 2000.0]), np.array([3.0, 4.5])
    before = len(ax.collections)
    handles = plots.modal_campbell(ax, modal, orders, (800.0, 4400.0),
                                   critical_speeds(modal, orders, (800.0, 4400.0)),
                                   run_orders=(speeds, run_q, np.array([[1.0, 2.0], [3.0, 4.0]])))
    dots = ax.collections[-1].get_offsets()
    assert len(ax.collections) > before and len(dots) == 4
    assert np.allclose(dots[:, 1], dots[:, 0] * np.array([3.0, 4.5, 3.0, 4.5]) / 60.0)
    assert handles[-1].get_label() == "the run's order amplitudes (area, colour)"
    # the colour bar under the axes names the amplitude
    assert fig.axes[-1].get_label() == "<colorbar>"
    plt.close(fig)


def test_the_response_writes_its_table_and_figure(tmp_path, capsys):
    """--response: the table's peak-to-peak per element is the synthesised signal's, at most
    twice the sum of the orders' amplitudes; a second run without --force overwrites
    nothing."""
    args = ["modes", str(CASE), "-o", str(tmp_path), "--response", "--speeds", "41",
            "--max-order", "6"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "steady forced response at" in out and "dissipates at most" in out
    table = tmp_path / "inline6_damper_response.csv"
    figure = tmp_path / "inline6_damper_response.png"
    assert figure.read_bytes()[:4] == b"\x89PNG"
    with open(table, encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) >= 41 and float(rows[0]["rpm"]) == 800.0
    name = "section 4 (throw 3–throw 4)"
    for r in rows:
        assert 0.0 < float(r[f"{name} peak-to-peak [N m]"]) <= 2.0 * float(
            r[f"{name} sum of orders [N m]"]) * (1 + 1e-12)
        assert float(r["damper silicone at pulley power [W]"]) > 0.0
    before = table.read_bytes()
    assert main(args) == 2
    assert "exists; use --force" in capsys.readouterr().err
    assert table.read_bytes() == before


def test_the_response_refuses_a_misfiring_scene_before_writing(tmp_path, capsys):
    scene = tmp_path / "misfire.toml"
    scene.write_text(CASE.read_text() + "\n[[gas.cylinders]]\ncylinder = 2\nmisfire_every = 5\n")
    out = tmp_path / "out"
    assert main(["modes", str(scene), "-o", str(out), "--response"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gas.cylinders[0].misfire_every" in err[0]
    assert list(out.iterdir()) == []


def test_the_floquet_chart_writes_its_table_and_figure(tmp_path, capsys):
    """--floquet: a row per speed with |μ|max the largest of the multipliers' moduli and the
    growth per revolution ln|μ|max (a crank-slider's inertias repeat every revolution); the
    six's damped line stable at every speed (its inertia varies by a few per cent); a second
    run without --force overwrites nothing."""
    import math

    args = ["modes", str(CASE), "-o", str(tmp_path), "--floquet", "--speeds", "13"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "parametric stability at 13 speeds from" in out and "stable at every speed" in out
    table = tmp_path / "inline6_damper_floquet.csv"
    assert (tmp_path / "inline6_damper_floquet.png").read_bytes()[:4] == b"\x89PNG"
    with open(table, encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 13 and float(rows[0]["rpm"]) == 800.0
    for r in rows:
        moduli = [float(v) for k, v in r.items() if k.startswith("mu_abs_")]
        assert float(r["mu_max"]) == max(moduli) < 1.0
        assert float(r["growth_per_rev"]) == pytest.approx(math.log(float(r["mu_max"])),
                                                           rel=1e-9)
        assert r["unstable"] == "0"
    before = table.read_bytes()
    assert main(args) == 2
    assert "exists; use --force" in capsys.readouterr().err
    assert table.read_bytes() == before
