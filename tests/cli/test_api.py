"""The Python entry: ``transient.simulate`` in memory and to a file gives the same ``Result``;
a failed run raises with the run up to there; scenes are built, changed and written from code."""
from __future__ import annotations

import numpy as np
import pytest
from scene_texts import SMALL

import transient
from transient import Result, SimulationError, load_scene, open_result, simulate
from transient.scene import Scene


@pytest.fixture
def small(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return load_scene(path)


def test_in_memory_and_to_a_file_give_the_same_result(small, tmp_path):
    mem = simulate(small)
    disk = simulate(small, tmp_path / "small.h5")
    again = open_result(tmp_path / "small.h5")
    assert isinstance(mem, Result) and isinstance(disk, Result) and mem.path is None
    assert mem.complete and mem.status == disk.status == "finished" and mem.message == ""
    for res in (disk, again):
        assert sorted(res.trajectory) == sorted(mem.trajectory)
        for name, x in mem.trajectory.items():
            assert np.array_equal(res.trajectory[name], x), name
        assert res.units == mem.units
        assert sorted(res.events) == sorted(mem.events)
        for name, ev in mem.events.items():
            assert np.array_equal(res.events[name]["t"], ev["t"])
        np.testing.assert_equal(res.summary(), mem.summary())  # (NaN: not reached)
        assert {k: v for k, v in res.solver.items() if k not in ("wall_s", "compile_s")} == \
            {k: v for k, v in mem.solver.items() if k not in ("wall_s", "compile_s")}
    assert mem.scene() == small == disk.scene()
    assert mem.units["omega"] == "rad/s" and mem.summary()["final_omega"] == \
        mem.trajectory["omega"][-1]


def test_the_summary_and_a_dataframe(small):
    res = simulate(small)
    summary = res.summary()
    assert summary["revolutions"] == pytest.approx(2.0, rel=1e-12)
    assert all(np.ndim(v) == 0 for v in summary.values())
    df = res.to_dataframe()
    assert list(df.columns) == list(res.trajectory)
    assert np.array_equal(df["omega"].to_numpy(), res.trajectory["omega"])
    assert df.attrs["units"]["t"] == "s"


def test_a_failed_run_raises_with_the_run_up_to_there(small):
    stalls = small.replace(load={"torque": 5.0}, run={"revolutions": 50})  # (after 5 turns)
    with pytest.raises(SimulationError) as info:
        simulate(stalls)
    res = info.value.result
    assert isinstance(res, Result) and not res.complete and res.status == "stalled"
    assert str(info.value) == f"{res.message} (status = stalled)" and "t = " in res.message
    assert res.trajectory["t"].size > 0 and res.trajectory["omega"][0] > 0.0


def test_force_and_resume_need_a_file(small):
    with pytest.raises(transient.errors.SceneError, match="give its path"):
        simulate(small, force=True)


def test_scenes_from_code_vary_a_parameter_without_files(small):
    d = {"mechanism": {"type": "crank-slider", "crank_radius_mm": 47, "rod_length_mm": 148,
                       "bore_mm": 88, "piston_mass": 1.52, "crank_mass": 0.912,
                       "rod": {"model": "two-mass", "mass": 1.752, "cg_from_pin_mm": 107.3}},
         "inertia": {"shaft": 0.02}, "initial": {"omega_rpm": 1000}, "run": {"revolutions": 2},
         "solver": {"rtol": 1e-6, "atol": 1e-8}, "output": {"samples_per_rev": 12},
         "scene": {"name": "small"}}
    scene = Scene.from_dict(d)
    assert scene == small
    finals = [simulate(scene.replace(inertia={"flywheel": J})).trajectory["omega"]
              for J in (0.0, 0.1, 1.0)]
    # coasting without forces: more flywheel, less swing of ω about the same mean
    swings = [np.ptp(w) for w in finals]
    assert swings[0] > swings[1] > swings[2] > 0.0
    assert load_scene("text.toml", text=scene.to_toml()) == scene


def test_a_result_says_how_it_was_made_and_what_each_column_is(small, tmp_path):
    import re

    import h5py
    import numba

    simulate(small, tmp_path / "small.h5")
    with h5py.File(tmp_path / "small.h5") as f:
        a = f.attrs
        assert (a["numpy"], a["numba"], a["h5py"]) == (np.__version__, numba.__version__,
                                                       h5py.__version__)
        assert re.fullmatch(r"([0-9a-f]{40}(\+dirty)?)?", a["git_commit"])
        assert a["cpu"] and a["python"] and "command" in a
        for name, ds in f["trajectory"].items():
            assert ds.attrs["description"] and ds.attrs["unit"] is not None, name


def test_every_column_a_run_can_write_is_described():
    from transient.core.model import governor
    from transient.core.model.layout import OUTPUTS, PAIR_OUTPUTS
    from transient.scene.outputs import describe

    names = [*OUTPUTS, *(f"{c}_3" for c in PAIR_OUTPUTS), "p_2", "fuel_4", "M_drive", "W_drive",
             *(n for kind in governor.STATE_NAMES for n in kind)]
    for name in names:
        assert len(describe(name)) > 10, name
    assert "pair 3" in describe("S_3") and "cylinder 2" in describe("p_2")
    with pytest.raises(KeyError, match="no description"):
        describe("nonsense_1")


def test_plot_helpers_take_a_result(small):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from transient import plots

    res = simulate(small)
    fig, (a, b) = plt.subplots(2)
    (line,) = plots.speed(a, res)
    (same,) = plots.speed(b, res.trajectory)
    assert np.array_equal(line.get_ydata(), same.get_ydata())
    np.testing.assert_allclose(line.get_ydata(), res.trajectory["omega"] * 30.0 / np.pi,
                               rtol=1e-15)
    plt.close(fig)


def test_a_result_reads_its_columns_after_its_file_is_gone(small, tmp_path):
    """Columns are read when used, from the file opened when the result was: a temporary folder
    removed in between takes nothing away."""
    res = simulate(small, tmp_path / "gone.h5")
    (tmp_path / "gone.h5").unlink()
    assert res.trajectory["omega"].size > 0 and res.trajectory["t"][0] == 0.0
