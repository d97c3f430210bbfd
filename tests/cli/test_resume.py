"""``transient run --resume``: what it continues and what it refuses (one line, exit 2), and how
a figure of an incomplete result says so. Killed runs resumed bit-identically:
``tests/stress/test_kill_resume.py``."""
from __future__ import annotations

import h5py
import matplotlib
import numpy as np
import pytest
from scene_texts import SMALL

from transient.cli import main
from transient.cli.common import incomplete_note, result_stem, save
from transient.results import _checkpoint_datasets, open_result

matplotlib.use("Agg")


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def small(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL, encoding="utf-8")
    return path


def _interrupted(path):
    """Mark the finished result at ``path`` as a run interrupted before its first block."""
    with h5py.File(path, "r+") as f:
        f.attrs.update(complete=False, status="interrupted")
        _checkpoint_datasets(f, [])  # (and none in them)


def test_resume_and_force_together_are_refused(tmp_path, small, capsys):
    code, out, err = run(capsys, "run", small, "-o", tmp_path / "out", "--resume", "--force")
    assert code == 2 and out == ""
    assert err == ("--resume: continues a run, --force replaces it: give one of them\n")


def test_nothing_to_resume_is_one_line(tmp_path, small, capsys):
    code, out, err = run(capsys, "run", small, "-o", tmp_path / "out", "--resume", "-q")
    assert code == 2 and out == ""
    assert err == (f"{tmp_path / 'out' / 'small.h5'}: no partial or incomplete result to "
                   f"resume; run without --resume\n")


def test_a_complete_result_is_not_resumed(tmp_path, small, capsys):
    assert run(capsys, "run", small, "-o", tmp_path, "-q")[0] == 0
    code, _, err = run(capsys, "run", small, "-o", tmp_path, "--resume", "-q")
    assert code == 2 and err == f"{tmp_path / 'small.h5'}: the run is complete; nothing to resume\n"


def test_an_unreadable_partial_file_is_one_line(tmp_path, small, capsys):
    part = tmp_path / ".small.h5.part"
    part.write_bytes(b"not HDF5")
    code, _, err = run(capsys, "run", small, "-o", tmp_path, "--resume", "-q")
    assert code == 2 and err.count("\n") == 1
    assert err.startswith(f"{part}: not a readable result (") and "--force" in err
    assert part.read_bytes() == b"not HDF5"  # left as it was


def test_a_changed_scene_is_not_resumed(tmp_path, small, capsys):
    assert run(capsys, "run", small, "-o", tmp_path, "-q")[0] == 0
    _interrupted(tmp_path / "small.h5")
    small.write_text(SMALL.replace("shaft = 0.02", "shaft = 0.03"), encoding="utf-8")
    code, _, err = run(capsys, "run", small, "-o", tmp_path, "--resume", "-q")
    assert code == 2 and err == (f"{tmp_path / 'small.h5'}: written from another scene (its "
                                 f"/scene/toml differs); resume with the same scene, or use "
                                 f"--force to start afresh\n")


def test_a_run_stopped_before_its_first_block_starts_afresh(tmp_path, small, capsys):
    assert run(capsys, "run", small, "-o", tmp_path / "whole", "-q")[0] == 0
    assert run(capsys, "run", small, "-o", tmp_path, "-q")[0] == 0
    _interrupted(tmp_path / "small.h5")
    assert open_result(tmp_path / "small.h5").trajectory["t"].size == 0  # nothing checkpointed
    code, _, err = run(capsys, "run", small, "-o", tmp_path, "--resume", "-q")
    assert code == 0, err
    again, whole = open_result(tmp_path / "small.h5"), open_result(tmp_path / "whole/small.h5")
    assert again.complete and again.attrs["status"] == "finished"
    assert all((again.trajectory[c] == v).all() for c, v in whole.trajectory.items())


def test_a_run_that_failed_is_not_resumed(tmp_path, small, capsys):
    assert run(capsys, "run", small, "-o", tmp_path, "-q")[0] == 0
    with h5py.File(tmp_path / "small.h5", "r+") as f:
        f.attrs.update(complete=False, status="stalled")
    code, _, err = run(capsys, "run", small, "-o", tmp_path, "--resume", "-q")
    assert code == 2 and err == (f"{tmp_path / 'small.h5'}: the run ended stalled; resuming "
                                 f"would end the same way (resume continues interrupted or "
                                 f"killed runs)\n")


def test_figures_and_output_of_an_incomplete_result_say_so(tmp_path, small, capsys):
    assert run(capsys, "run", small, "-o", tmp_path, "-q")[0] == 0
    with h5py.File(tmp_path / "small.h5", "r+") as f:
        f.attrs.update(complete=False, status="interrupted")
    code, out, err = run(capsys, "plot", tmp_path / "small.h5", "-o", tmp_path)
    res = open_result(tmp_path / "small.h5")
    note = incomplete_note(res)
    assert code == 0 and err == f"warning: {tmp_path / 'small.h5'}: {note}\n"
    assert note.startswith("an incomplete run (interrupted): covers t ≤ ")
    import matplotlib.pyplot as plt

    fig = plt.figure()
    save(fig, tmp_path / "f.png", False, res)
    assert [t.get_text() for t in fig.texts] == [note]
    fig = plt.figure()
    res.attrs["complete"] = True
    save(fig, tmp_path / "g.png", False, res)
    assert fig.texts == []


def test_the_partial_file_of_a_killed_run_names_its_figures_as_the_result():
    assert result_stem(".engine.h5.part") == "engine"
    assert result_stem("dir/engine.h5") == "engine"


def test_a_run_killed_while_finishing_resumes_to_the_same_file(tmp_path, small, monkeypatch):
    """Killed after its last block, before its file got its name: the partial file holds the
    whole run, and --resume only finishes it (no block computed again, no event twice)."""
    from transient import load_scene, simulate
    from transient.results import ResultWriter, partial_path

    scene = load_scene(small)
    whole = simulate(scene, tmp_path / "whole.h5")
    with monkeypatch.context() as m:
        m.setattr(ResultWriter, "finish", lambda self, *a, **k: self.f.close())  # the "kill"
        with pytest.raises(FileNotFoundError):
            simulate(scene, tmp_path / "small.h5")
    part = partial_path(tmp_path / "small.h5")
    assert part.is_file() and not (tmp_path / "small.h5").exists()
    assert open_result(part).trajectory["t"].size == whole.trajectory["t"].size
    again = simulate(scene, tmp_path / "small.h5", resume=True)
    assert again.complete and not part.exists()
    for name, x in whole.trajectory.items():
        assert np.array_equal(again.trajectory[name], x), name
    assert {k: v["t"].size for k, v in again.events.items()} == \
        {k: v["t"].size for k, v in whole.events.items()}
    assert again.solver["nsteps"] == whole.solver["nsteps"]
