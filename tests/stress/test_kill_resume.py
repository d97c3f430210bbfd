"""Runs killed at random instants: the partial file opens, holds an exact prefix of the run that
was never stopped (so it is monotone and finite), says it is incomplete, and ``--resume`` ends in
a file bit-identical to that run's.

Each scene is run once uninterrupted in this process, then again and again in a child process
(``python -m transient run``) that is killed (SIGKILL, and SIGTERM for the interrupted path) at a
random instant after its partial file appears; each kill is followed by a resume in this process.
"""
from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from transient import load_scene, open_result
from transient.results import partial_path
from transient.run import simulate
from transient.scene import to_toml

REPO = Path(__file__).resolve().parents[2]
#: (case, its [run] changed to, kills): long enough for many blocks (about a second), short
#: enough for the suite; three scenes × 17 SIGKILLs = 51, with pairs switching modes, four
#: cylinders and a governor.
CASES = [("coasting_single", {"revolutions": 6_000}, 17),
         ("gots_diesel_friction", {"revolutions": 1_500}, 17),
         ("swash_plate_4cyl", {"t_end": 750.0}, 17)]
#: SIGTERMs per scene besides: a run ended as Ctrl-C ends it, resumed from its published file.
TERMS = 2


def _scene_file(tmp: Path, case: str, run: dict) -> Path:
    scene = load_scene(REPO / "cases" / f"{case}.toml")
    scene = dataclasses.replace(scene, run=dataclasses.replace(scene.run, **run))
    path = tmp / f"{case}.toml"
    path.write_text(to_toml(scene))
    return path


def _start(scene_file: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "transient", "run", str(scene_file), "-o",
                             str(out), "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _wait_for(path: Path, proc: subprocess.Popen) -> bool:
    """Whether ``path`` appeared while ``proc`` still ran."""
    while proc.poll() is None:
        if path.exists():
            return True
        time.sleep(0.01)
    return False


def _child_span(scene_file: Path, out: Path, case: str) -> float:
    """Wall time [s] from a child's partial file appearing to the child's exit, the run left
    to finish: its kernels' load and its integration."""
    proc = _start(scene_file, out)
    if not _wait_for(partial_path(out / f"{case}.h5"), proc):
        pytest.fail(f"{case}: the run ended before its partial file appeared: "
                    f"{proc.stderr.read().decode()}")
    t0 = time.perf_counter()
    assert proc.wait() == 0, proc.stderr.read().decode()
    return time.perf_counter() - t0


def _same(a, b, what: str) -> None:
    assert sorted(a.trajectory) == sorted(b.trajectory)
    for name, x in a.trajectory.items():
        assert np.array_equal(x, b.trajectory[name]), f"{what}: column {name} differs"
    assert sorted(a.events) == sorted(b.events), what
    for name, ev in a.events.items():
        for col in ("t", "phi"):
            assert np.array_equal(ev[col], b.events[name][col]), f"{what}: event {name} differs"


def _check_prefix(part, full, what: str) -> None:
    """``part`` holds the first samples of ``full`` exactly: monotone and finite as it is."""
    assert not part.complete, what
    n = part.trajectory["t"].size
    for name, x in part.trajectory.items():
        assert np.array_equal(x, full.trajectory[name][:n]), f"{what}: column {name} differs"
    for name, ev in part.events.items():
        k = ev["t"].size
        assert np.array_equal(ev["t"], full.events[name]["t"][:k]), f"{what}: event {name}"
    t = part.trajectory["t"]
    assert np.all(np.diff(t) > 0) and np.all(np.isfinite(t)), what


@pytest.mark.slow
@pytest.mark.stress
@pytest.mark.parametrize("case, run, kills", CASES)
def test_killed_runs_keep_a_prefix_and_resume_bit_identically(tmp_path, case, run, kills):
    scene_file = _scene_file(tmp_path, case, run)
    scene = load_scene(scene_file)
    full = simulate(scene, tmp_path / "full" / f"{case}.h5")
    # A child loads the kernels after its partial file appears, then integrates: kills land
    # over both. How long that takes is measured on a child left to finish, on the machine as
    # loaded now (another test may be compiling beside this one), not assumed.
    span = _child_span(scene_file, tmp_path / "probe", case) + 0.5
    rng = np.random.default_rng(sum(map(ord, case)))
    killed = terms = resumed_from_middle = 0
    for k in range(4 * (kills + TERMS)):  # (some runs finish before their kill)
        if killed == kills and terms == TERMS:
            break
        sig = signal.SIGKILL if killed < kills else signal.SIGTERM
        out = tmp_path / f"run{k}"
        result = out / f"{case}.h5"
        proc = _start(scene_file, out)
        if not _wait_for(partial_path(result), proc):
            pytest.fail(f"{case}: the run ended before its partial file appeared: "
                        f"{proc.stderr.read().decode()}")
        time.sleep(rng.uniform(0.0, span))
        proc.send_signal(sig)
        rc = proc.wait()
        what = f"{case}, kill {k} ({sig.name}, rc {rc})"
        if result.exists() and open_result(result).complete:
            continue  # it finished first: nothing to check
        killed += sig == signal.SIGKILL
        terms += sig == signal.SIGTERM
        left = partial_path(result) if sig == signal.SIGKILL else result
        if not left.exists():
            pytest.fail(f"{what}: it left no {left.name}: {proc.stderr.read().decode()}")
        part = open_result(left)
        _check_prefix(part, full, what)
        assert part.attrs["status"] == ("running" if sig == signal.SIGKILL else "interrupted")
        resumed_from_middle += 0 < part.trajectory["t"].size
        simulate(scene, result, resume=True)
        assert not partial_path(result).exists()
        _same(open_result(result), full, what)
    assert (killed, terms) == (kills, TERMS)  # every one landed while the run ran
    assert resumed_from_middle >= kills // 2  # most after some blocks, not before the first


def test_a_stop_while_the_last_block_is_written_still_finishes_the_file(tmp_path, monkeypatch,
                                                                        ctrl_c):
    """A stop signal that arrives after the run, while the last block's write behind it ends,
    acts once the file is whole: complete, under its name, and the stop still stops the command
    (before, the stop skipped the file's last step and left only the partial file)."""
    import transient.run as run

    real_shutdown = run._WriteBehind.shutdown
    stopped = []

    def shutdown(self):
        if not stopped:  # (the first: the end of a run that went well)
            stopped.append(True)
            os.kill(os.getpid(), signal.SIGINT)
        return real_shutdown(self)

    monkeypatch.setattr(run._WriteBehind, "shutdown", shutdown)
    scene = load_scene(REPO / "cases" / "coasting_single.toml").replace(run={"revolutions": 4})
    result = tmp_path / "coasting_single.h5"
    with pytest.raises(KeyboardInterrupt):
        simulate(scene, result)
    assert stopped and open_result(result).complete
    assert not partial_path(result).exists()


def test_a_stop_during_the_last_write_waits_until_the_file_is_whole(tmp_path, monkeypatch,
                                                                    ctrl_c):
    """A stop signal that arrives while the result file's last step moves the run into its layout
    acts once that step is done: the file is whole and complete, and the stop still stops the
    command (the signal comes from inside that step here, so it cannot land anywhere else)."""
    from transient.results import ResultWriter

    real_finish = ResultWriter.finish

    def finish(self, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)  # (Python's handler: KeyboardInterrupt)
        return real_finish(self, *args, **kwargs)

    monkeypatch.setattr(ResultWriter, "finish", finish)
    scene = load_scene(REPO / "cases" / "coasting_single.toml").replace(run={"revolutions": 4})
    result = tmp_path / "coasting_single.h5"
    with pytest.raises(KeyboardInterrupt):
        simulate(scene, result)
    assert open_result(result).complete
    assert not partial_path(result).exists()


#: A child that runs ``transient run`` and sends itself SIGTERM from inside llvmlite's object-cache
#: callback, through which numba loads a cached kernel, once the partial file exists: where the
#: random kills above landed now and then, and where an exception crashed the process (SIGSEGV).
_STOP_IN_KERNEL_LOAD = """
import os, signal, sys
from pathlib import Path
from llvmlite.binding import executionengine

partial, argv = Path(sys.argv[1]), sys.argv[2:]
real = executionengine.ExecutionEngine._raw_object_cache_getbuffer
sent = []

def getbuffer(self, data):
    if not sent and partial.exists():
        sent.append(True)
        os.kill(os.getpid(), signal.SIGTERM)
    return real(self, data)

executionengine._getbuffer_c_hook = executionengine._ObjectCacheGetBufferFunc(getbuffer)
from transient.cli import main
code = main(argv)
print("sent" if sent else "never sent", file=sys.stderr)
sys.exit(code)
"""


def test_a_stop_while_a_kernel_loads_interrupts_the_run_after_the_load(tmp_path):
    """A SIGTERM inside numba's kernel loading (an LLVM callback into Python) waits until the
    load is done, then interrupts the run as anywhere else: exit 1, the result under its name,
    marked interrupted (an exception raised there crashed the process and left only the partial
    file)."""
    # (a run far longer than the stop's wait, so that the stop lands in it)
    scene_file = _scene_file(tmp_path, "coasting_single", {"revolutions": 100_000})
    out = tmp_path / "out"
    result = out / "coasting_single.h5"
    proc = subprocess.run([sys.executable, "-c", _STOP_IN_KERNEL_LOAD, str(partial_path(result)),
                           "run", str(scene_file), "-o", str(out), "-q"],
                          capture_output=True, text=True, cwd=REPO)
    assert "never sent" not in proc.stderr, "no kernel was loaded after the partial file appeared"
    assert proc.returncode == 1, proc.stderr
    res = open_result(result)
    assert not res.complete and res.status == "interrupted", proc.stderr
