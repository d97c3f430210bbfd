"""The sweep file keeps each run in a result file's layout: a run written by the sweep's store
and the same run written by the streaming result writer hold the same objects, attributes and
values; a run reads back as a Result; the summary round-trips; a part resumes; a file written
before the runs had that layout still resumes and summarises. No run is integrated here: the
runs are made up, so no kernel is compiled."""
from __future__ import annotations

import dataclasses
import json
import math
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient import results
from transient.sweeps import SweepStore, load_sweep, open_run, read_summary
from transient.sweeps.store import Stored, match_runs

CASES = Path(__file__).resolve().parents[2] / "cases"

SWEEP = f"""\
[sweep]
name = "small"
base = "{CASES / 'gots_diesel_friction.toml'}"
collect = ["mean_speed_rpm", "delta", "final_t"]
columns = ["t", "phi", "omega"]

[set]
"run.revolutions" = 12

[[axis]]
key = "load.torque"
values = [0.0, 400.0, 10.0]
"""
UNITS = {"t": "s", "phi": "rad", "omega": "rad/s", "epsilon": "rad/s^2"}


@pytest.fixture()
def sweep(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SWEEP)
    return load_sweep(path)


def _res(ok: bool, n: int = 5000, seed: int = 0) -> dict:
    """What run_one returns, made up: a complete run, or one that stopped with a message."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-4, 2e-4, n))
    return {"status": "finished" if ok else "failed", "complete": ok,
            "message": "" if ok else "stalled at t = 0.1 s",
            "trajectory": {"t": t, "phi": 300.0 * t, "omega": 300.0 + rng.normal(size=n)},
            "events": {"breakpoint": np.column_stack([t[::700], 300.0 * t[::700]]),
                       "steady": np.zeros((0, 2))},
            "solver": {"method": "dop853", "rtol": 1e-8, "nfev": 1234, "compile_s": 0.0},
            "summary": ({"mean_omega_last_cycle": (301.5, "rad/s"), "delta_last_cycle": (0.01, "1"),
                         "final_t": (float(t[-1]), "s"), "note": ("text", "")} if ok else {}),
            "units": UNITS, "worker": "host:1", "wall_s": 0.25}


def _tree(node: h5py.Group) -> dict:
    """Every object under ``node``: its attributes, and for a dataset its data and storage."""
    out = {}

    def visit(name, obj):
        entry = {"attrs": {k: v for k, v in obj.attrs.items() if k != "created"}}
        if isinstance(obj, h5py.Dataset):
            entry.update(data=obj[()], dtype=obj.dtype, chunks=obj.chunks, maxshape=obj.maxshape,
                         compression=obj.compression, opts=obj.compression_opts,
                         shuffle=obj.shuffle)
        out[name] = entry

    node.visititems(visit)
    return out


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    return a == b


@pytest.mark.parametrize("ok", [True, False])
def test_a_run_is_stored_as_a_result_file_stores_it(sweep, tmp_path, ok):
    spec, res = sweep.runs[0], _res(ok)
    store = SweepStore(tmp_path / "out" / "small.h5", sweep)
    store.write_run(spec, res)
    store.close(False)

    w = results.ResultWriter(tmp_path / "r.h5", spec.scene.name, spec.toml,
                             {c: UNITS[c] for c in res["trajectory"]}, list(res["events"]))
    for k in range(0, 5000, 1500):  # streamed in blocks, as a run writes it
        w.append({c: v[k:k + 1500] for c, v in res["trajectory"].items()})
    w.events(res["events"])
    w.finish(ok, res["message"], "finished" if ok else "failed", res["solver"], res["summary"])

    with h5py.File(tmp_path / "r.h5", "r") as f, \
            h5py.File(tmp_path / "out" / ".small.h5.part", "r") as s:
        g = s["runs/run_0000"]
        single, run = _tree(f), _tree(g)
        # (an incomplete streamed result keeps its checkpoints, to be resumed; a sweep's run is
        # written whole)
        single = {k: v for k, v in single.items() if not k.startswith("checkpoint")}
        assert run.keys() == single.keys()
        for name, entry in single.items():
            for key, value in entry.items():
                if key != "attrs":
                    assert _same(run[name][key], value), (name, key)
            assert all(_same(run[name]["attrs"][k], v) for k, v in entry["attrs"].items()), name
        header = dict(f.attrs)
        sweep_own = {"index", "params", "scene_toml", "worker", "wall_s", "status"}
        # a complete result file has no message; a run always says one (empty when ok)
        assert set(g.attrs) == set(header) | sweep_own | {"message"}
        for k, v in header.items():  # (a sweep's run says its status as ok or failed)
            assert k in ("created", "status") or _same(g.attrs[k], v), k
        assert g.attrs["message"] == res["message"]
        assert s.attrs["creator"] == f.attrs["creator"] and s.attrs["format"] == f.attrs["format"]
        # both files in the result files' HDF5 bounds: the 1.8 superblock (a killed writer's
        # file stays readable)
        assert s.id.get_create_plist().get_version()[0] == 0
        assert f.id.get_create_plist().get_version()[0] == 0


def test_a_run_reads_back_as_a_result(sweep, tmp_path):
    store = SweepStore(tmp_path / "small.h5", sweep)
    res = _res(True)
    store.write_run(sweep.runs[2], res)
    store.close(False)
    r = open_run(tmp_path / ".small.h5.part", 2)
    assert isinstance(r, results.Result) and r.complete
    assert r.attrs["creator"] == "transient" and r.attrs["scene"] == sweep.runs[2].scene.name
    for c, v in res["trajectory"].items():
        assert np.array_equal(r.trajectory[c], v) and r.units[c] == UNITS[c]
    assert np.array_equal(r.events["breakpoint"]["t"], res["events"]["breakpoint"][:, 0])
    assert "steady" not in r.events  # (events that occurred only)
    assert r.solver == res["solver"]
    assert r.analysis == res["summary"]
    assert r.scene() == sweep.runs[2].scene  # the stored scene is the run's
    with pytest.raises(KeyError, match="no finished run 1"):
        open_run(tmp_path / ".small.h5.part", 1)


def test_summary_round_trips_and_a_part_resumes(sweep, tmp_path):
    path = tmp_path / "small.h5"
    store = SweepStore(path, sweep)
    store.write_run(sweep.runs[0], _res(True))
    store.write_run(sweep.runs[1], _res(False))
    created = store.f["runs/run_0000"].attrs["created"]
    store.close(False)  # interrupted

    again = SweepStore(path, sweep)
    assert again.finished == {0, 1}
    again.write_run(sweep.runs[2], _res(True, seed=2))
    rows = again.write_summary(tmp_path / "small_summary.csv")
    assert again.close(True) == path
    assert [r["status"] for r in rows] == ["finished", "failed", "finished"]
    tab = read_summary(path)
    assert list(tab.columns["run"]) == [0, 1, 2]
    assert list(tab.columns["status"]) == ["finished", "failed", "finished"]
    assert tab.columns["mean_speed_rpm"][0] == pytest.approx(301.5 * 30 / math.pi, rel=1e-15)
    assert math.isnan(tab.columns["mean_speed_rpm"][1])
    assert tab.units["mean_speed_rpm"] == "rpm" and tab.units["final_t"] == "s"
    assert list(tab.columns["load.torque"]) == [0.0, 400.0, 10.0]
    assert tab.axes == [{"key": "load.torque", "group": "#0", "values": [0.0, 400.0, 10.0]}]
    with h5py.File(path, "r") as f:
        assert f.attrs["complete"] and f.attrs["kind"] == "sweep" and f.attrs["n_runs"] == 3
        assert f["runs/run_0000"].attrs["created"] == created  # kept, not rewritten


def test_a_file_in_the_earlier_layout_resumes(sweep, tmp_path):
    """Runs stored before they had a result's header and ``scene`` group (the scene only as the
    ``scene_toml`` attribute, columns neither chunked nor extendable) are kept on resuming and
    summarised with the new ones."""
    part = tmp_path / ".small.h5.part"
    res = _res(True)
    with h5py.File(part, "w") as f:
        f.attrs.update(creator="transient", version="0", format=1, created="2000-01-01T00:00:00",
                       kind="sweep", sweep="small", complete=False, n_runs=3)
        f.create_group("sweep").create_dataset("toml", data=sweep.text)
        f.create_group("analysis")
        g = f.create_group("runs").create_group("run_0000")
        g.attrs.update(index=0, params=json.dumps(sweep.runs[0].params),
                       scene_toml=sweep.runs[0].toml, message="", worker="w", wall_s=1.0,
                       created="2000-01-01T00:00:00")
        for c, v in res["trajectory"].items():
            g.create_dataset(f"trajectory/{c}", data=v).attrs["unit"] = UNITS[c]
        g.create_group("events")
        g.create_group("solver").attrs.update(res["solver"])
        for name, (value, unit) in res["summary"].items():
            g.create_dataset(f"analysis/{name}", data=value).attrs["unit"] = unit
        g.attrs["status"] = "finished"
    store = SweepStore(tmp_path / "small.h5", sweep)
    assert store.finished == {0}
    store.write_run(sweep.runs[1], _res(False))
    store.write_run(sweep.runs[2], _res(True, seed=3))
    rows = store.write_summary(tmp_path / "small_summary.csv")
    store.close(True)
    assert [r["status"] for r in rows] == ["finished", "failed", "finished"]
    assert rows[0]["mean_speed_rpm"] == pytest.approx(301.5 * 30 / math.pi, rel=1e-15)
    assert read_summary(tmp_path / "small.h5").columns["final_t"][0] == res["summary"]["final_t"][0]


# ------------------------------------------------------------------------------------------------
# Mending: runs reused by their resolved scene


def _sweep_of(tmp_path, values: str, name: str = "small"):
    """The sweep of SWEEP with the torque axis ``values``, in a file named small.toml (so that
    it writes small.h5) under a folder of its own."""
    folder = tmp_path / values.replace(" ", "").strip("[]")
    folder.mkdir(exist_ok=True)
    path = folder / "small.toml"
    path.write_text(SWEEP.replace("[0.0, 400.0, 10.0]", values)
                    .replace('name = "small"', f'name = "{name}"'))
    return load_sweep(path)


def _finished(out: Path, sweep) -> Path:
    """A finished sweep file of ``sweep``; the torque of 400 N m failed."""
    store = SweepStore(out / "small.h5", sweep)
    for spec in sweep.runs:
        store.write_run(spec, _res(spec.params["load.torque"] != 400.0, seed=spec.index))
    store.write_summary(out / "small_summary.csv")
    return store.close(True)


def _stored_runs(path: Path) -> dict[str, tuple[str, str]]:
    """Every finished run of a sweep file by where it is: (its scene, its ``created``)."""
    with h5py.File(path, "r") as f:
        return {f"{top}/{n}": (g.attrs["scene_toml"], g.attrs["created"])
                for top in ("runs", "unused") if top in f for n, g in f[top].items()
                if "status" in g.attrs}


def test_match_runs_prefers_ok_runs_in_place_and_retries_failed_ones(sweep):
    a, b, c = (s.toml for s in sweep.runs)
    targets = [f"runs/run_000{i}" for i in range(3)]
    stored = [Stored("unused/x", a, True, {}), Stored("runs/run_0000", a, True, {}),
              Stored("runs/run_0001", b, False, {}), Stored("unused/y", c, False, {}),
              Stored("unused/z", c, True, {})]
    got = match_runs(stored, sweep.runs, targets)
    assert {i: s.path for i, s in got.items()} == {0: "runs/run_0000", 1: "runs/run_0001",
                                                    2: "unused/z"}
    got = match_runs(stored, sweep.runs, targets, retry_failed=True)
    assert {i: s.path for i, s in got.items()} == {0: "runs/run_0000", 2: "unused/z"}
    # one stored run serves one run: a sweep holding a scene twice computes the second
    twice = (sweep.runs[0], dataclasses.replace(sweep.runs[0], index=1))
    assert list(match_runs(stored[1:2], twice, targets)) == [0]


def test_mending_reuses_moves_and_parks_runs(tmp_path):
    out = tmp_path / "out"
    path = _finished(out, _sweep_of(tmp_path, "[0.0, 400.0, 10.0]"))
    before = _stored_runs(path)
    mended = _sweep_of(tmp_path, "[10.0, 0.0, 5.0]")  # reordered, 400 dropped, 5 added
    store = SweepStore(path, mended)
    assert store.finished == {0, 1} and store.recomputed == set()
    assert not path.exists() and store.part.exists()  # mended as a part
    runs = {n: (g.attrs["scene_toml"], g.attrs["created"]) for n, g in store.f["runs"].items()}
    assert runs == {"run_0000": before["runs/run_0002"], "run_0001": before["runs/run_0000"]}
    assert [store.f[f"runs/run_000{i}"].attrs["index"] for i in (0, 1)] == [0, 1]
    assert json.loads(store.f["runs/run_0000"].attrs["params"]) == {"load.torque": 10.0}
    [parked] = store.f["unused"].values()
    assert (parked.attrs["scene_toml"], parked.attrs["created"]) == before["runs/run_0001"]
    assert "summary" not in store.f["analysis"] and not store.f.attrs["complete"]
    store.write_run(mended.runs[2], _res(True, seed=5))
    assert store.tidy() == 1  # the dropped point is kept
    rows = store.write_summary(out / "small_summary.csv")
    store.close(True)
    assert [r["load.torque"] for r in rows] == [10.0, 0.0, 5.0]
    tab = read_summary(path)
    assert tab.axes[0]["values"] == [10.0, 0.0, 5.0]
    with h5py.File(path, "r") as f:
        assert f.attrs["n_runs"] == 3 and f["sweep/toml"][()].decode() == mended.text
    # the dropped point again: reused from where it was kept; --prune deletes what is left over
    again = SweepStore(path, _sweep_of(tmp_path, "[0.0, 400.0, 10.0]"))
    assert again.finished == {0, 1, 2}
    assert again.f["runs/run_0001"].attrs["created"] == before["runs/run_0001"][1]
    assert again.tidy(prune=True) == 0 and len(again.f["unused"]) == 0
    again.close(True)


def test_changed_scenes_and_retried_failures_are_recomputed(tmp_path):
    out = tmp_path / "out"
    sweep = _sweep_of(tmp_path, "[0.0, 400.0, 10.0]")
    path = _finished(out, sweep)
    before = _stored_runs(path)
    store = SweepStore(path, sweep, retry_failed=True)
    assert store.finished == {0, 2} and store.recomputed == {1}
    assert list(store.f["runs"]) == ["run_0000", "run_0002"]  # the failed one parked, not lost
    store.write_run(sweep.runs[1], _res(False, seed=9))
    assert store.tidy() == 0  # (the retried run's old copy is gone once it is replaced)
    store.close(True)
    after = _stored_runs(path)
    assert after["runs/run_0000"] == before["runs/run_0000"]
    assert after["runs/run_0002"] == before["runs/run_0002"]
    assert set(after) == {"runs/run_0000", "runs/run_0001", "runs/run_0002"}
    # the same points with another constant change: every run is another scene, recomputed
    other = tmp_path / "other"
    other.mkdir()
    (other / "small.toml").write_text(SWEEP.replace('"run.revolutions" = 12',
                                                    '"run.revolutions" = 13'))
    store = SweepStore(path, load_sweep(other / "small.toml"))
    assert store.finished == set() and store.recomputed == {0, 1, 2}
    assert len(store.f["unused"]) == 3
    store.close(False)


def test_another_sweep_is_refused_unchanged(tmp_path):
    out = tmp_path / "out"
    path = _finished(out, _sweep_of(tmp_path, "[0.0, 400.0, 10.0]"))
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match="holds another sweep \\('small', not 'big'\\)"):
        SweepStore(path, _sweep_of(tmp_path, "[1.0]", name="big"))
    assert path.read_bytes() == before


class _Interrupt:
    """Raise KeyboardInterrupt before the ``at``-th change of an HDF5 file (a group moved or
    deleted, an attribute or a dataset written), as a Ctrl-C between two of them would."""

    PATCHED = ((h5py.Group, "move"), (h5py.Group, "__delitem__"),
               (h5py.AttributeManager, "__setitem__"), (h5py.Dataset, "__setitem__"))

    def __init__(self, monkeypatch, at: int) -> None:
        self.at, self.count = at, 0
        for cls, name in self.PATCHED:
            monkeypatch.setattr(cls, name, self._wrap(getattr(cls, name)))

    def _wrap(self, method):
        def changed(*args, **kwargs):
            self.count += 1
            if self.count == self.at:
                raise KeyboardInterrupt
            return method(*args, **kwargs)
        return changed


def test_interrupted_mending_loses_no_run(tmp_path, monkeypatch):
    """Interrupted before each change it makes in turn, mending leaves a file that the next
    mending completes: every run finished before is there once, reused or parked."""
    out = tmp_path / "out"
    template = tmp_path / "template.h5"
    shutil.copy(_finished(out, _sweep_of(tmp_path, "[0.0, 400.0, 10.0]")), template)
    before = sorted(_stored_runs(template).values())
    mended = _sweep_of(tmp_path, "[10.0, 0.0, 5.0]")
    at = 0
    while True:
        at += 1
        for p in out.iterdir():
            p.unlink()
        shutil.copy(template, out / "small.h5")
        store = None
        with monkeypatch.context() as m:
            trap = _Interrupt(m, at)
            try:
                store = SweepStore(out / "small.h5", mended)
                store.write_run(mended.runs[2], _res(True, seed=5))
                interrupted = False
            except KeyboardInterrupt:
                interrupted = True
                if store is not None:  # (as run_sweep does)
                    store.close(False)
        if not interrupted:
            store.close(False)
            break
        store = SweepStore(out / "small.h5", mended)
        done = store.finished
        assert done in ({0, 1}, {0, 1, 2}), at  # run 2 only if its status was written
        store.close(False)
        stored = _stored_runs(store.part)
        old = sorted(v for v in stored.values() if v[0] != mended.runs[2].toml)
        assert old == before, at  # each run finished before: there, once
        assert stored["runs/run_0000"] == _stored_runs(template)["runs/run_0002"], at
    assert at > 10 and trap.count == at - 1  # (every change was interrupted once)
