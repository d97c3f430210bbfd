"""``transient sweep`` on a real Dask cluster: the file, the summary, a failing run, resuming,
mending (a changed value, an added point, retried failures, an interrupted mending), never
overwriting another sweep, the sweep file's one-line errors, the summary plots.

One LocalCluster (2 worker processes, loopback only) serves the module through ``--scheduler``;
one test starts the default cluster of ``run_sweep`` itself. Every run is a few revolutions of
the Gots diesel (milliseconds of simulated work).
"""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest
from terminal import terminal_run

from transient.analysis.summary import summarize
from transient.cli import KERNELS_NOTICE, main
from transient.run import integrate
from transient.scene import load_scene
from transient.sweeps import kernel_loads, load_sweep, open_run, run_sweep

CASES = Path(__file__).resolve().parents[2] / "cases"

# 2 × 2 runs; a 400 N m torque stalls the engine: runs 1 and 3 fail on purpose.
SWEEP = f"""\
[sweep]
name = "small"
base = "{CASES / 'gots_diesel_friction.toml'}"
collect = ["mean_speed_rpm", "delta", "final_t"]
columns = ["t", "phi", "omega"]

[set]
"run.revolutions" = 12
"initial.omega_rpm" = 3000

[[axis]]
key = "load.fan"
values = [5e-4, 1e-3]

[[axis]]
key = "load.torque"
values = [0.0, 400.0]
"""


@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0") as c:
        yield c.scheduler_address


@pytest.fixture()
def sweep_file(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SWEEP)
    return path


def _groups(path):
    with h5py.File(path, "r") as f:
        return {n: dict(g.attrs) for n, g in f["runs"].items()}


def test_sweep_file_summary_and_failed_runs(sweep_file, tmp_path, cluster, capsys):
    out = tmp_path / "out"
    code = main(["sweep", str(sweep_file), "-o", str(out), "--scheduler", cluster])
    assert code == 1  # two runs failed (stalled), recorded; the others are there
    err = capsys.readouterr().err
    assert "2 of 4 runs failed" in err and len(err.strip().splitlines()) == 1
    path = out / "small.h5"
    with h5py.File(path, "r") as f:
        assert f.attrs["creator"] == "transient" and f.attrs["kind"] == "sweep"
        assert bool(f.attrs["complete"]) and f.attrs["n_runs"] == 4
        assert sorted(f["runs"]) == ["run_0000", "run_0001", "run_0002", "run_0003"]
        for name, g in f["runs"].items():
            params = json.loads(g.attrs["params"])
            scene = load_scene("stored", text=g.attrs["scene_toml"])
            assert scene.load.fan == params["load.fan"]
            assert scene.load.torque == params["load.torque"]
            assert sorted(g["trajectory"]) == ["omega", "phi", "t"]
            assert g["trajectory/omega"].attrs["unit"] == "rad/s"
            failing = params["load.torque"] == 400.0
            assert g.attrs["status"] == ("stalled" if failing else "finished"), name
            if failing:
                assert "stalled" in g.attrs["message"]
                assert g["trajectory/t"].size > 0  # the partial trajectory is kept
            else:
                assert g.attrs["message"] == "" and "mean_omega_last_cycle" in g["analysis"]
        table = f["analysis/summary"][()]
        units = json.loads(f["analysis/summary"].attrs["units"])
    assert units["mean_speed_rpm"] == "rpm" and units["final_t"] == "s"
    assert list(table["run"]) == [0, 1, 2, 3]
    assert [s.decode() for s in table["status"]] == ["finished", "stalled", "finished", "stalled"]
    assert np.isnan(table["mean_speed_rpm"][[1, 3]]).all()
    with open(out / "small_summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["status"] for r in rows] == ["finished", "stalled", "finished", "stalled"]
    assert "stalled" in rows[1]["message"]
    # a worker's result is the run as computed in this process
    spec = load_sweep(sweep_file).runs[2]
    data = integrate(spec.scene)
    mean = summarize(spec.scene, data.trajectory, data.events)["mean_omega_last_cycle"][0]
    assert float(rows[2]["mean_speed_rpm"]) == pytest.approx(mean * 30 / math.pi, rel=1e-12)


def test_resume_recomputes_nothing_finished(sweep_file, tmp_path, cluster):
    out = tmp_path / "out"
    sweep = load_sweep(sweep_file)

    def interrupt(spec, res, done, total):
        raise KeyboardInterrupt  # as a Ctrl-C after the first run is written

    with pytest.raises(KeyboardInterrupt):
        run_sweep(sweep, out, scheduler=cluster, on_result=interrupt)
    part = out / ".small.h5.part"
    assert part.is_file() and not (out / "small.h5").exists()
    first = _groups(part)
    assert len(first) == 1
    [(name, attrs)] = first.items()

    again = run_sweep(sweep, out, scheduler=cluster)
    assert again.reused == [attrs["index"]]
    assert sorted(again.computed) == sorted({0, 1, 2, 3} - {attrs["index"]})
    assert _groups(out / "small.h5")[name]["created"] == attrs["created"]  # not rewritten

    # a run lost from the finished file is the only one computed again
    with h5py.File(out / "small.h5", "r+") as f:
        del f["runs/run_0002"]
    before = _groups(out / "small.h5")
    third = run_sweep(sweep, out, scheduler=cluster)
    assert third.computed == [2] and third.reused == [0, 1, 3]
    after = _groups(out / "small.h5")
    assert all(after[n]["created"] == a["created"] for n, a in before.items())
    assert len(third.rows) == 4 and len(third.failed) == 2


def test_another_sweep_is_never_overwritten(sweep_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sweep", str(sweep_file), "-o", str(out), "--scheduler", "serial", "-q"]) == 1
    other = tmp_path / "other" / "small.toml"  # the same file name, another sweep
    other.parent.mkdir()
    other.write_text(SWEEP.replace('"small"', '"big"').replace("[5e-4, 1e-3]", "[5e-4, 2e-3]"))
    capsys.readouterr()
    assert main(["sweep", str(other), "-o", str(out), "--scheduler", "serial", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "holds another sweep ('small', not 'big')" in err and "--force" in err
    assert len(err.splitlines()) == 1
    with h5py.File(out / "small.h5", "r") as f:  # untouched
        assert json.loads(f["runs/run_0002"].attrs["params"])["load.fan"] == 1e-3
    assert main(["sweep", str(other), "-o", str(out), "--scheduler", "serial", "-q",
                 "--force"]) == 1
    with h5py.File(out / "small.h5", "r") as f:
        assert f.attrs["sweep"] == "big"
        assert json.loads(f["runs/run_0002"].attrs["params"])["load.fan"] == 2e-3


def _mark(path):
    """Mark every stored run with an attribute no run writes: a run computed again lacks it."""
    with h5py.File(path, "r+") as f:
        for g in f["runs"].values():
            g.attrs["mark"] = True


def _unused(path):
    """The ``created`` of each stored run the sweep no longer holds."""
    with h5py.File(path, "r") as f:
        return sorted(g.attrs["created"] for g in f["unused"].values())


def test_mending_after_changing_an_axis_value(sweep_file, tmp_path, capsys):
    out, path = tmp_path / "out", tmp_path / "out" / "small.h5"
    args = ["sweep", str(sweep_file), "-o", str(out), "--scheduler", "serial"]
    assert main(args) == 1  # (runs 1 and 3 fail on purpose, in every sweep below)
    _mark(path)
    before = _groups(path)
    sweep_file.write_text(SWEEP.replace("[5e-4, 1e-3]", "[5e-4, 2e-3]"))
    capsys.readouterr()
    assert main(args) == 1
    said = capsys.readouterr().out
    assert ("2 run(s) reused, 0 recomputed, 2 new, 2 failed; 2 stored run(s) no longer in the "
            "sweep kept in the file (--prune deletes them)") in said
    after = _groups(path)
    assert [n for n, a in after.items() if "mark" in a] == ["run_0000", "run_0001"]
    assert [after[n]["created"] for n in ("run_0000", "run_0001")] == [
        before[n]["created"] for n in ("run_0000", "run_0001")]
    assert [json.loads(a["params"])["load.fan"] for a in after.values()] == [5e-4, 5e-4, 2e-3,
                                                                            2e-3]
    assert _unused(path) == sorted(before[n]["created"] for n in ("run_0002", "run_0003"))
    with open(out / "small_summary.csv", newline="") as fh:
        assert [float(r["load.fan"]) for r in csv.DictReader(fh)] == [5e-4, 5e-4, 2e-3, 2e-3]

    sweep_file.write_text(SWEEP)  # back: every run reused, two from where they were kept
    assert main(args) == 1
    assert "4 run(s) reused, 0 recomputed, 0 new, 2 failed; 2 stored" in capsys.readouterr().out
    back = _groups(path)
    assert all(a["mark"] for a in back.values())
    assert {n: a["created"] for n, a in back.items()} == {
        n: a["created"] for n, a in before.items()}
    assert main(args + ["--prune"]) == 1
    said = capsys.readouterr().out
    assert "4 run(s) reused, 0 recomputed, 0 new, 2 failed\n" in said and "kept" not in said
    assert _unused(path) == [] and len(_groups(path)) == 4


def test_mending_after_adding_a_point(sweep_file, tmp_path):
    out = tmp_path / "out"
    first = run_sweep(load_sweep(sweep_file), out, scheduler="serial")
    _mark(first.path)
    before = _groups(first.path)
    omega = open_run(first.path, 3).trajectory["omega"]
    sweep_file.write_text(SWEEP.replace("[0.0, 400.0]", "[0.0, 10.0, 400.0]"))
    done = run_sweep(load_sweep(sweep_file), out, scheduler="serial")
    assert done.reused == [0, 2, 3, 5] and done.computed == [1, 4] and done.new == [1, 4]
    assert done.recomputed == [] and done.unused == 0
    after = _groups(done.path)
    for old, new in (("run_0000", "run_0000"), ("run_0001", "run_0002"),
                     ("run_0002", "run_0003"), ("run_0003", "run_0005")):  # moved, not rewritten
        assert after[new]["mark"] and after[new]["created"] == before[old]["created"], new
        assert after[new]["scene_toml"] == before[old]["scene_toml"], new
        assert after[new]["index"] == int(new[-1]), new
    assert "mark" not in after["run_0001"] and "mark" not in after["run_0004"]
    assert [r["status"] for r in done.rows] == ["finished", "finished", "stalled", "finished", "finished", "stalled"]
    assert [r["load.torque"] for r in done.rows] == [0.0, 10.0, 400.0] * 2
    assert np.array_equal(open_run(done.path, 5).trajectory["omega"], omega)


def test_retry_failed_recomputes_only_the_failed_runs(sweep_file, tmp_path, capsys):
    path = tmp_path / "out" / "small.h5"
    args = ["sweep", str(sweep_file), "-o", str(tmp_path / "out"), "--scheduler", "serial"]
    assert main(args) == 1
    _mark(path)
    before = _groups(path)
    capsys.readouterr()
    assert main(args + ["--retry-failed"]) == 1  # (they fail again)
    said = capsys.readouterr().out
    assert "2 run(s) reused, 2 recomputed, 0 new, 2 failed\n" in said and "kept" not in said
    after = _groups(path)
    assert sorted(n for n, a in after.items() if "mark" not in a) == ["run_0001", "run_0003"]
    assert after["run_0000"] == before["run_0000"] and after["run_0002"] == before["run_0002"]
    assert all("stalled" in after[n]["message"] for n in ("run_0001", "run_0003"))
    assert _unused(path) == []  # the failed runs' first copies went with their replacement


def test_interrupted_mending_keeps_every_finished_run(sweep_file, tmp_path):
    out, path = tmp_path / "out", tmp_path / "out" / "small.h5"
    run_sweep(load_sweep(sweep_file), out, scheduler="serial")
    _mark(path)
    created = sorted(a["created"] for a in _groups(path).values())
    sweep_file.write_text(SWEEP.replace("[0.0, 400.0]", "[0.0, 10.0, 400.0]"))
    mended = load_sweep(sweep_file)

    def interrupt(spec, res, done, total):
        raise KeyboardInterrupt  # as a Ctrl-C after the first new run is written

    with pytest.raises(KeyboardInterrupt):
        run_sweep(mended, out, scheduler="serial", on_result=interrupt)
    part = out / ".small.h5.part"
    assert part.is_file() and not path.exists()
    held = _groups(part)
    assert sorted(held) == ["run_0000", "run_0001", "run_0002", "run_0003", "run_0005"]
    assert sorted(a["created"] for a in held.values() if "mark" in a) == created
    with h5py.File(part, "r") as f:
        assert not f.attrs["complete"] and "summary" not in f["analysis"]
    done = run_sweep(mended, out, scheduler="serial")
    assert done.computed == [4] and done.reused == [0, 1, 2, 3, 5]
    assert {n: a["created"] for n, a in _groups(path).items() if n != "run_0004"} == {
        n: a["created"] for n, a in held.items()}


def test_sweep_in_a_terminal_says_kernels_load_until_the_first_run(sweep_file, tmp_path):
    """The progress bar names the kernels' loading (on a first run, their compiling, minutes)
    until the first run is back, then each run's status."""
    code, out, terminal = terminal_run(["sweep", str(sweep_file), "-o", str(tmp_path / "out"),
                                        "--scheduler", "serial"])
    assert code == 1, terminal  # (runs 1 and 3 fail on purpose)
    assert out.startswith(f"wrote {tmp_path / 'out' / 'small.h5'}"), out
    notice = terminal.find(KERNELS_NOTICE)
    status = terminal.find("run 0: finished", notice)
    assert 0 <= notice < status, terminal
    assert "run 3: stalled" in terminal[status:], terminal


def test_default_local_cluster(tmp_path):
    path = tmp_path / "ok.toml"
    path.write_text(SWEEP.replace("[0.0, 400.0]", "[0.0, 10.0]"))
    done = run_sweep(load_sweep(path), tmp_path / "out", workers=2)
    assert sorted(done.computed) == [0, 1, 2, 3] and not done.failed
    with h5py.File(done.path, "r") as f:
        assert 1 <= len({g.attrs["worker"] for g in f["runs"].values()}) <= 2


def test_workers_load_the_kernels_once(sweep_file, tmp_path, cluster):
    from dask.distributed import Client

    done = run_sweep(load_sweep(sweep_file), tmp_path / "out", scheduler=cluster)
    with h5py.File(done.path, "r") as f:
        workers = [g.attrs["worker"] for g in f["runs"].values()]
    assert len(workers) == 4 and len(set(workers)) <= 2  # some worker ran two runs or more
    with Client(cluster) as client:
        loads = client.run(kernel_loads)
    # (runs of earlier tests on this cluster count too: still one load per worker)
    assert all(v == {"signatures": 1, "loads": 1} for v in loads.values()), loads


BAD = [  # (a line of SWEEP, its replacement, the message)
    ('name = "small"', 'method = "spiral"', "sweep.method: unknown value 'spiral'; allowed: grid"),
    ('collect = ["mean_speed_rpm", "delta", "final_t"]', 'collect = ["speed_dip_pct"]',
     ("sweep.collect: 'speed_dip_pct' (ISO 8528-5 transient speed deviation after the first "
      "load step) cannot be measured in run 0: its scene has no load step")),
    ('columns = ["t", "phi", "omega"]', 'columns = ["omega", "nope"]',
     "sweep.columns: unknown column 'nope' in run 0; allowed: t, phi"),
    ('name = "small"', 'colect = ["delta"]', "sweep.colect: unknown key; allowed here: name"),
    ('"run.revolutions" = 12', '"run.revolutions" = -1',
     "run 0 (load.fan = 0.0005, load.torque = 0.0): scene run.revolutions: must be > 0"),
]


@pytest.mark.parametrize("old, new, message", BAD)
def test_sweep_file_errors_are_one_line(tmp_path, capsys, old, new, message):
    path = tmp_path / "bad.toml"
    path.write_text(SWEEP.replace(old, new))
    assert main(["sweep", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"{path}: ") and message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out").exists()  # no work started


@pytest.mark.parametrize("axis, message", [
    ('key = "load.linear"\nvalues = [-5.0]',
     ("run 0 (load.fan = 0.0005, load.torque = 0.0, load.linear = -5.0): scene load.linear: "
      "must be ≥ 0, got -5")),
    ('key = "load.torque"\nvalues = [1.0]',
     "axis[2].key: 'load.torque' sets the quantity of axis[1] ('load.torque') again"),
    ('key = "load.torq"\nvalues = [1.0]', "scene load.torq: unknown key; allowed here:"),
    ('key = "load..torque"\nvalues = [1.0]', "axis[2].key: 'load..torque' is not a scene key"),
    ('key = "load.torque"\nfrom = 1.0\nto = 2.0', "axis[2].num: is missing"),
])
def test_axis_errors_are_one_line(tmp_path, capsys, axis, message):
    path = tmp_path / "bad.toml"
    path.write_text(SWEEP + f"\n[[axis]]\n{axis}\n")
    assert main(["sweep", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_grid_groups_list_and_random(tmp_path):
    base = f'[sweep]\nbase = "{CASES / "gots_diesel_friction.toml"}"\n'
    path = tmp_path / "g.toml"
    path.write_text(base + '[[axis]]\nkey = "load.torque"\ngroup = "a"\nvalues = [1.0, 2.0]\n'
                           '[[axis]]\nkey = "initial.omega_rpm"\ngroup = "a"\n'
                           'from = 1000\nto = 2000\nnum = 2\n'
                           '[[axis]]\nkey = "load.fan"\nvalues = [1e-3, 2e-3, 3e-3]\n')
    runs = load_sweep(path).runs
    assert [r.params for r in runs[:4]] == [
        {"load.torque": 1.0, "initial.omega_rpm": 1000.0, "load.fan": 1e-3},
        {"load.torque": 1.0, "initial.omega_rpm": 1000.0, "load.fan": 2e-3},
        {"load.torque": 1.0, "initial.omega_rpm": 1000.0, "load.fan": 3e-3},
        {"load.torque": 2.0, "initial.omega_rpm": 2000.0, "load.fan": 1e-3}]
    assert runs[3].scene.initial.omega == pytest.approx(2000 * math.pi / 30)
    path.write_text(base + '[set]\nrun.revolutions = 7\n[set.initial]\nomega_rpm = 1200\n'
                    + '[[axis]]\nkey = "load.torque"\nvalues = [1.0]\n')
    [run] = load_sweep(path).runs  # [set] changes keys, never a whole table
    assert run.scene.run.revolutions == 7 and run.scene.initial.omega == pytest.approx(40 * math.pi)
    assert run.scene.run.t_end == math.inf and run.scene.initial.phi == 0.0
    path.write_text(base.replace("[sweep]", '[sweep]\nmethod = "random"\nsamples = 5\nseed = 7')
                    + '[[axis]]\nkey = "load.torque"\nlow = 1.0\nhigh = 2.0\n'
                      '[[axis]]\nkey = "friction.policy"\nvalues = ["paper", "power-flow"]\n')
    first, second = load_sweep(path).runs, load_sweep(path).runs
    assert len(first) == 5 and [r.params for r in first] == [r.params for r in second]
    assert all(1.0 <= r.scene.load.torque <= 2.0 for r in first)
    assert {r.scene.friction.policy for r in first} <= {"paper", "power-flow"}


def test_sweep_plot(sweep_file, tmp_path, capsys):
    out = tmp_path / "out"
    main(["sweep", str(sweep_file), "-o", str(out), "--scheduler", "serial", "-q"])
    assert main(["sweep-plot", str(out / "small.h5"), "--quantity", "mean_speed_rpm"]) == 0
    assert (out / "small_mean_speed_rpm.png").stat().st_size > 0
    line = sweep_file.with_name("line.toml")
    line.write_text(SWEEP.replace("[0.0, 400.0]", "[0.0]").replace('"small"', '"line"'))
    main(["sweep", str(line), "-o", str(out), "--scheduler", "serial", "-q"])
    assert main(["sweep-plot", str(out / "line.h5"), "-o", str(tmp_path / "png")]) == 0
    assert len(list((tmp_path / "png").glob("line_*.png"))) == 3
    capsys.readouterr()
    assert main(["sweep-plot", str(out / "small.h5"), "--quantity", "nope"]) == 2
    assert "'nope' is not in the summary" in capsys.readouterr().err


def test_steady_efficiency_points_on_the_cluster(tmp_path, cluster, capsys):
    """`transient efficiency --steady --scheduler ADDRESS` runs its points on the workers
    (map_tasks, as a sweep's runs) and writes the same table as in this process, row for row:
    the same points, the same state to the solver's rounding."""
    scene = CASES / "gots_diesel_friction.toml"
    argv = ["efficiency", str(scene), "--steady", "--rpm", "2000,4000", "--fuel", "1,0.5",
            "--samples-per-rev", "72"]
    tables = []
    for where in ("serial", cluster):
        out = tmp_path / where.replace(":", "_").replace("/", "_")
        assert main([*argv, "--scheduler", where, "-o", str(out)]) == 0
        with open(out / "gots_diesel_friction_steady_efficiency.csv") as fh:
            tables.append(list(csv.DictReader(fh)))
    capsys.readouterr()
    serial, cluster_rows = tables
    assert [(r["fuel"], r["rpm"]) for r in cluster_rows] == [(r["fuel"], r["rpm"])
                                                            for r in serial]
    for a, b in zip(serial, cluster_rows):
        for key in ("eta_mech_work", "fmep", "delta", "brake_torque", "rpm_mean"):
            assert float(b[key]) == pytest.approx(float(a[key]), rel=1e-9), key
