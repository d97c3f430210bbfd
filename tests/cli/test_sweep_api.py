"""Sweeps from code (``transient.sweep``): the engine of ``transient sweep`` on a scene
held in memory; its runs are the runs ``simulate`` gives."""
from __future__ import annotations

import numpy as np
import pytest
from scene_texts import SMALL

from transient import SceneError, load_scene, simulate, sweep


@pytest.fixture
def small():
    return load_scene("small.toml", text=SMALL)


def test_a_sweep_from_code_runs_what_simulate_runs(small):
    flywheels = [0.0, 0.1, 1.0]
    done = sweep(small, {"inertia.flywheel": flywheels}, collect=["delta", "final_speed_rpm"],
                 scheduler="serial")
    df = done.to_dataframe()
    assert list(df["inertia.flywheel"]) == flywheels and list(df["status"]) == ["finished"] * 3
    assert df.attrs["units"]["delta"] == "1"
    assert np.all(np.diff(df["delta"]) < 0)  # more flywheel, less swing
    for i, J in enumerate(flywheels):
        alone = simulate(small.replace(inertia={"flywheel": J}))
        run = done.run(i)
        assert np.array_equal(run.trajectory["omega"], alone.trajectory["omega"])
        assert df["delta"][i] == alone.summary()["delta_last_cycle"]
    assert done.computed == [0, 1, 2] and done.reused == []


def test_a_sweep_in_a_folder_is_mended_when_run_again(small, tmp_path):
    first = sweep(small, {"load.torque": [0.0, 1.0]}, output=tmp_path, scheduler="serial")
    again = sweep(small, {"load.torque": [0.0, 1.0, 2.0]}, output=tmp_path, scheduler="serial")
    assert first.path == again.path == tmp_path / "small.sweep.h5"
    assert sorted(again.computed) == [2] and sorted(again.reused) == [0, 1]
    assert (tmp_path / "small.sweep.toml").is_file()


def test_axes_must_be_given_as_a_dict_of_values(small):
    with pytest.raises(SceneError, match="give a dict of dotted scene keys"):
        sweep(small, [("load.torque", [1.0])], scheduler="serial")
    with pytest.raises(SceneError, match=r"axes\['load.torque'\]: values must be numbers"):
        sweep(small, {"load.torque": [{"a": 1}]}, scheduler="serial")


def test_a_sweep_on_a_given_dask_client(small):
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        before = cluster.scheduler.transition_counter
        done = sweep(small, {"inertia.flywheel": [0.0, 0.5]}, client=client)
        moved = cluster.scheduler.transition_counter - before
    assert list(done.to_dataframe()["status"]) == ["finished", "finished"]
    assert moved >= 2 * 3  # each run's task went through that scheduler (at least 3 states)


def test_a_nan_in_a_sweep_comes_with_its_reason(tmp_path):
    """The Gots diesel with friction for 1, 8 and 600 revolutions: 1 holds no whole cycle (a
    cycle is 2 revolutions), 8 no steady state, 600 runs into it. η_mech is NaN in the first
    two, δ and the mean speed in the first; each row's note says why, as the run's own summary
    shows, and the CSV carries it."""
    from pathlib import Path

    base = load_scene(Path(__file__).resolve().parents[2] / "cases" / "gots_diesel_friction.toml")
    done = sweep(base, {"run.revolutions": [1.0, 8.0, 600.0]},
                 collect=["mean_speed_rpm", "delta", "eta_mech"], scheduler="serial",
                 output=tmp_path)
    df = done.to_dataframe()
    assert list(df["status"]) == ["finished"] * 3
    assert np.isnan(df["eta_mech"][:2]).all() and np.isfinite(df["eta_mech"][2])
    no_cycle = ("the run holds no whole cycle turned forwards (1 revolutions from its start)")
    assert df["note"][0] == (f"mean_speed_rpm: {no_cycle}; delta: {no_cycle}; eta_mech: "
                             f"{no_cycle}")
    assert df["note"][1] == ("eta_mech: no steady cycles to take it over: no steady state: the "
                             "cycle-mean speed still changed by 1e-4 or more from cycle to cycle")
    assert df["note"][2] == ""
    first, second, third = (done.run(i).analysis for i in range(3))
    assert "eta_mech_work" not in first and np.isnan(first["mean_omega_last_cycle"][0])
    assert "eta_mech_work" not in second and np.isnan(second["steady_state_t"][0])
    assert df["eta_mech"][2] == third["eta_mech_work"][0]
    csv = (tmp_path / "gots-diesel-friction.sweep_summary.csv").read_text().splitlines()
    assert csv[0].endswith(",note,message") and no_cycle in csv[1] and "steady" in csv[2]


def test_a_run_that_did_not_finish_says_so_in_the_note(small):
    done = sweep(small, {"load.torque": [0.0, 500.0]}, collect=["final_speed_rpm"],
                 scheduler="serial")
    df = done.to_dataframe()
    assert list(df["status"]) == ["finished", "not-started"]
    assert list(df["note"]) == ["", "not collected: the run ended not-started (its message says "
                                    "how)"]
    assert df["message"][1].startswith("did not start: the shaft never turned a whole revolution")
