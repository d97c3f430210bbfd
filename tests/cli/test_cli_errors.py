"""Errors become exit codes in one place, ``transient.cli.main``, whichever command raises them:
invalid input → 2 with one line on standard error, a failed simulation or an interrupt → 1.
No simulation runs here: a command is replaced by one that raises, or given a missing file."""
from __future__ import annotations

import pytest

import transient.cli as cli
from transient.cli import main
from transient.errors import SceneError, SimulationError, WriteFailed


def _raising(exc):
    def command(args):
        raise exc
    return command


@pytest.mark.parametrize("exc, code, line", [
    (SceneError("run.t_end", "must be > 0, got -1", file="a.toml"), 2,
     "a.toml: run.t_end: must be > 0, got -1"),
    (FileExistsError("results/a.h5 exists; --force replaces it"), 2,
     "results/a.h5 exists; --force replaces it"),
    (PermissionError("results: not writable"), 2, "results: not writable"),
    (FileNotFoundError("a.h5: no such result file"), 2, "a.h5: no such result file"),
    (SimulationError("step size underflow at t = 0.1 s"), 1,
     "transient: step size underflow at t = 0.1 s"),
    (KeyboardInterrupt(), 1, "transient: interrupted"),
])
def test_errors_become_exit_codes(monkeypatch, capsys, exc, code, line):
    monkeypatch.setattr(cli.run, "cmd_check", _raising(exc))
    assert main(["check", "a.toml"]) == code
    captured = capsys.readouterr()
    assert captured.err == line + "\n" and captured.out == ""


def test_a_failed_write_is_remembered_for_the_exit(monkeypatch, capsys):
    """``entry`` leaves by ``os._exit`` after a failed write: ``main`` keeps the error for it."""
    exc = WriteFailed("disk full at t = 0.2 s")
    monkeypatch.setattr(cli.loads, "cmd_loads", _raising(exc))
    monkeypatch.setattr(cli, "_BROKEN_WRITE", None)
    assert main(["loads", "a.h5"]) == 1
    assert capsys.readouterr().err == "transient: disk full at t = 0.2 s\n"
    assert cli._BROKEN_WRITE is exc


@pytest.mark.parametrize("argv", [
    ["check", "{missing}.toml"], ["run", "{missing}.toml", "-o", "{tmp}"],
    ["kinematics", "{missing}.toml"], ["efficiency", "{missing}.toml", "-o", "{tmp}"],
    ["info", "{missing}.h5"], ["plot", "{missing}.h5"], ["loads", "{missing}.h5"],
    ["orders", "{missing}.h5"], ["sweep", "{missing}.toml", "-o", "{tmp}"],
    ["sweep-plot", "{missing}.h5"],
])
def test_every_command_reports_a_missing_file_in_one_line(tmp_path, capsys, argv):
    missing = tmp_path / "missing"
    argv = [a.format(missing=missing, tmp=tmp_path / "out") for a in argv]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert len(captured.err.splitlines()) == 1 and str(missing) in captured.err
    assert "Traceback" not in captured.err
    assert not (tmp_path / "out").exists()


def test_a_reader_that_stops_reading_ends_the_command_without_a_traceback(tmp_path):
    """``transient info … | head -1``: the command ends as ``cat`` ends when its reader closes
    the pipe (exit 128 + SIGPIPE), with nothing on standard error."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import transient

    scene = transient.load_scene(Path(__file__).resolve().parents[2] / "cases"
                                 / "coasting_single.toml").replace(run={"revolutions": 5})
    transient.simulate(scene, tmp_path / "r.h5")
    command = [sys.executable, "-c", "from transient.cli import entry; entry()", "info",
               str(tmp_path / "r.h5")]
    read, write = os.pipe()
    os.close(read)  # (the reader gone before the first line: every write meets a closed pipe)
    try:
        done = subprocess.run(command, stdout=write, stderr=subprocess.PIPE, timeout=120)
    finally:
        os.close(write)
    assert (done.returncode, done.stderr.decode()) == (cli.EXIT_BROKEN_PIPE, "")
