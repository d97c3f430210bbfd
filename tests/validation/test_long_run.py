"""A long run on its envelope from a scene (``[solver] multirevolution = true``): the result file
against the :func:`~transient.multirev.multirevolution` call's envelope, its resolved cycles
against a direct run of the same scene, the per-cycle work against the kinetic energy's change
(the energy balance over a cycle that starts and ends at the same angle), ``transient run`` and
``transient info`` on it, its refusals (exit 2, one line), and a run killed or interrupted
(SIGKILL, SIGTERM) leaving a readable result marked incomplete that holds a prefix of the
envelope."""
from __future__ import annotations

import dataclasses
import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from terminal import terminal_run

import transient
from transient.cli import main
from transient.core.stepper import io as sio
from transient.longrun import RESOLVED_ALONG, run_multirevolution
from transient.multirev import multirevolution
from transient.results import Checkpoint, partial_path
from transient.run import CycleMap, simulate_from

REPO = Path(__file__).resolve().parents[2]
#: The stepper's tolerance (atol = rtol/100): the resolved cycles and the direct run's then
#: differ by the envelope's error, not the stepper's.
RTOL = 1e-10
#: The envelope's tolerance.
ENVELOPE_RTOL = 1e-7
#: The agreement of the envelope with the direct run in ω, relative (the method's acceptance,
#: which tests/validation/test_multirev.py checks cycle by cycle).
AGREE = 1e-6
#: Cycles of the test's long run: a spin-up from 1000 rpm, the load stepped up at 3 s and
#: down at 6 s (resolved cycles around each corner, interpolated stretches between).
CYCLES = 200
SCHEDULE = "schedule_time = [3.0, 3.0, 6.0, 6.0]\nschedule_scale = [1.0, 1.2, 1.2, 0.9]"


def scene_text(cycles: int = CYCLES, extra_solver: str = "", extra_run: str = "",
               schedule: str = SCHEDULE, extra: str = "") -> str:
    """The constant-η diesel of cases/gots_diesel_friction.toml with a flywheel ×30, run for
    ``cycles`` four-stroke cycles on its envelope."""
    text = (REPO / "cases" / "gots_diesel_friction.toml").read_text(encoding="utf-8")
    text = text.replace("flywheel = 0.15", "flywheel = 4.5")
    text = text.replace("revolutions = 600", f"revolutions = {2 * cycles}{extra_run}")
    text = text.replace("fan = 9.692e-4", f"fan = 9.692e-4\n{schedule}")
    text = text.replace("[solver]\nrtol = 1e-8\natol = 1e-10",
                        f"[solver]\nrtol = {RTOL:g}\natol = {RTOL * 1e-2:g}\nmultirevolution = "
                        f"true\nenvelope_rtol = {ENVELOPE_RTOL:g}{extra_solver}")
    text = text.replace("samples_per_rev = 72", "samples_per_rev = 36")
    assert "multirevolution" in text and "flywheel = 4.5" in text and "schedule" in text
    return text + extra


def write_scene(folder: Path, text: str, name: str = "long") -> Path:
    path = folder / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The long run written by ``transient run``, the envelope of the call, a direct run."""
    folder = tmp_path_factory.mktemp("long")
    scene_file = write_scene(folder, scene_text())
    code = main(["run", str(scene_file), "-o", str(folder / "out"), "-q"])
    assert code == 0
    res = transient.open_result(folder / "out" / "long.h5")
    scene = transient.load_scene(scene_file)
    reached = [0]
    env = multirevolution(scene, CYCLES, ENVELOPE_RTOL,
                          watch=lambda n, states, integrated: reached.append(n))
    # the macro segments' ends: where the envelope advanced by more than a cycle at once
    env.nodes = {m for a, b in zip(reached, reached[1:]) if b - a > 1 for m in (a, b)}
    direct_scene = scene.replace(solver={"multirevolution": False})
    direct = transient.simulate(direct_scene).trajectory
    return scene, res, env, direct


def test_the_file_holds_the_envelope_of_the_call(written):
    scene, res, env, _ = written
    e = res.envelope
    assert res.complete and res.status == "finished"
    assert e.names == env.names and e.cycles == CYCLES
    assert e.states.shape == env.states.shape
    scale = np.abs(env.states).max(axis=0)
    assert np.all(np.abs(e.states - env.states) <= 1e-12 * scale)
    assert np.array_equal(e.integrated, env.integrated[:-1])
    assert 0 < e.integrated.sum() < CYCLES  # (both kinds in the run)
    assert np.allclose(e.error, env.error, rtol=1e-6, atol=0.0)
    a = res.analysis
    assert a["multirev_cycles_integrated"][0] == env.cycles_integrated
    assert a["multirev_cycles_interpolated"][0] == CYCLES - env.integrated[:-1].sum()
    assert a["final_omega"][0] == pytest.approx(env.column("omega")[-1], rel=1e-12)
    # the per-cycle mean speed is the cycle's angle over its duration
    t = env.column("t")
    assert np.allclose(e.mean_omega, scene.mechanism.cycle / np.diff(t), rtol=1e-12)


def test_resolved_cycles_are_the_integrated_ones_the_nodes_and_the_stretches_ends(written):
    _, res, env, _ = written
    e = res.envelope
    flags = env.integrated[:-1]
    every = math.ceil(CYCLES / RESOLVED_ALONG)
    expect = [k for k in range(CYCLES) if flags[k] or k in (0, CYCLES - 1)
              or flags[k - 1] or flags[k + 1] or k in env.nodes or k % every == 0]
    assert list(e.resolved) == expect
    assert e.resolved_end[-1] == res.trajectory["t"].size
    assert np.all(np.isfinite(e.delta[e.resolved])) and np.all(np.isfinite(e.work[e.resolved]))
    others = np.setdiff1d(np.arange(CYCLES), e.resolved)
    assert np.all(np.isnan(e.delta[others])) and np.all(np.isnan(e.work[others]))


def test_resolved_cycles_agree_with_the_direct_run(written):
    scene, res, env, direct = written
    e = res.envelope
    phi_d, w_d = np.asarray(direct["phi"]), np.asarray(direct["omega"])
    t_d = np.asarray(direct["t"])
    w_max = float(np.abs(w_d).max())
    for k in e.resolved:
        rows = e.rows(int(k))
        phi = np.asarray(res.trajectory["phi"][rows])
        w = np.asarray(res.trajectory["omega"][rows])
        t = np.asarray(res.trajectory["t"][rows])
        # the cycle's φ span is the run's, and each sample is on the direct run's grid
        assert phi[0] == pytest.approx(scene.initial.phi + k * scene.mechanism.cycle,
                                       abs=1e-9)
        assert phi[-1] == pytest.approx(phi[0] + scene.mechanism.cycle, abs=1e-9)
        at = np.searchsorted(phi_d, phi - 1e-9)
        assert np.allclose(phi_d[at], phi, rtol=0.0, atol=1e-9)
        # cycle 0 starts from the scene's own state: the direct run's to the stepper's tolerance
        tol = (100 * RTOL if k == 0 else AGREE) * w_max
        assert np.abs(w - w_d[at]).max() <= tol, (int(k), np.abs(w - w_d[at]).max())
        # t: the envelope's time error, which places each corner in its cycle (TIME_SCALE)
        assert np.abs(t - t_d[at]).max() <= (100 * RTOL if k == 0 else 1e-5), int(k)


def test_resolved_cycles_are_runs_from_the_envelope_s_state(written):
    # each resolved cycle against a run of that one cycle by transient's own run path
    # (simulate_from, its output written as any run's) from the envelope's state at its start:
    # every column to the stepper's tolerance
    scene, res, env, _ = written
    e = res.envelope
    one_scene = scene.replace(solver={"multirevolution": False})
    phi = CycleMap(one_scene)
    picks = {int(e.resolved[0]), int(np.flatnonzero(e.integrated)[0]), int(e.resolved[-1])}
    for k in sorted(picks):
        X = env.states[k]
        y, fst, ist = phi.start(X[:-1], float(X[-1]))
        start = Checkpoint(rows=0, events=0, switched=False, code=sio.RUNNING,
                           floats=np.concatenate([y, fst]), ints=ist)
        cycle = dataclasses.replace(
            one_scene, run=dataclasses.replace(one_scene.run, t_end=math.inf,
                                               revolutions=scene.mechanism.cycle / (2 * math.pi)),
            initial=dataclasses.replace(one_scene.initial,
                                        omega=float(X[env.names.index("omega")])))
        ran = simulate_from(cycle, start).trajectory
        rows = e.rows(k)
        for name in res.trajectory:
            ours = np.asarray(res.trajectory[name][rows], dtype=float)
            theirs = np.asarray(ran[name], dtype=float)
            if name == "phi":
                theirs = theirs + k * scene.mechanism.cycle
            assert ours.shape == theirs.shape, (k, name)
            scale = max(float(np.abs(theirs).max()), 1e-300)
            assert np.abs(ours - theirs).max() <= 100 * RTOL * scale, (k, name)


def test_an_integrated_cycle_ends_where_the_envelope_goes_on(written):
    _, res, env, _ = written
    e = res.envelope
    i_w = env.names.index("omega")
    for k in np.flatnonzero(e.integrated):
        rows = e.rows(int(k))
        end = float(res.trajectory["omega"][rows][-1])
        assert end == pytest.approx(env.states[k + 1, i_w], rel=1e-12)


def test_per_cycle_work_is_the_kinetic_energy_change(written):
    # W_gas + W_load − losses over a cycle = ½J(φ₀)(ω₁² − ω₀²), J the same at both ends
    _, res, env, _ = written
    e = res.envelope
    for k in e.resolved:
        rows = e.rows(int(k))
        J = float(res.trajectory["J"][rows][0])
        w = np.asarray(res.trajectory["omega"][rows])
        dK = 0.5 * J * (w[-1] ** 2 - w[0] ** 2)
        scale = 0.5 * J * w[0] ** 2
        assert e.work[k] == pytest.approx(dK, abs=100 * RTOL * scale), int(k)
        # δ: the cycle's peak-to-peak speed over its mean, the cycle over its own duration
        t = np.asarray(res.trajectory["t"][rows])
        mean = res.scene().mechanism.cycle / (t[-1] - t[0])
        assert e.delta[k] == pytest.approx(np.ptp(w) / mean, rel=1e-9), int(k)


def test_result_in_memory_is_the_file_s(written):
    scene, res, _, _ = written
    mem = run_multirevolution(scene)
    assert mem.path is None and mem.complete
    assert np.array_equal(mem.envelope.integrated, res.envelope.integrated)
    assert np.array_equal(mem.envelope.resolved, res.envelope.resolved)
    assert np.allclose(mem.envelope.states, res.envelope.states, rtol=1e-12, atol=0.0)
    assert np.allclose(mem.trajectory["omega"], res.trajectory["omega"], rtol=1e-12)


def test_info_says_which_cycles_and_the_error(written, capsys):
    _, res, env, _ = written
    code, out, err = run(capsys, "info", res.path)
    assert code == 0, err
    k = int(env.integrated[:-1].sum())
    assert f"{CYCLES} of {CYCLES} cycle(s) followed: {k} integrated" in out
    assert f"{CYCLES - k} interpolated on the envelope" in out
    assert f"{env.cycles_integrated} cycle(s) integrated in all" in out
    i_w = env.names.index("omega")
    assert f"omega {env.error[i_w]:.3g} rad/s" in out
    assert "envelope error estimate at the last cycle" in out
    first = int(np.flatnonzero(env.integrated)[0])
    assert f"(cycles {first}" in out


def test_nothing_overwritten_without_force(written, capsys, tmp_path):
    scene_file = write_scene(tmp_path, scene_text(cycles=4))
    out = tmp_path / "out"
    assert main(["run", str(scene_file), "-o", str(out), "-q"]) == 0
    before = (out / "long.h5").read_bytes()
    code, stdout, err = run(capsys, "run", scene_file, "-o", out, "-q")
    assert code == 2 and err.count("\n") == 1 and "--force" in err
    assert (out / "long.h5").read_bytes() == before
    code, _, err = run(capsys, "run", scene_file, "-o", out, "-q", "--force")
    assert code == 0, err
    code, _, err = run(capsys, "run", scene_file, "-o", out, "-q", "--resume")
    assert code == 2 and "--resume" in err and "--force" in err


REFUSED = {
    "load.schedule_revolutions": dict(schedule="schedule_revolutions = [0.0, 100.0]\n"
                                               "schedule_scale = [1.0, 1.2]"),
    "run.t_end": dict(extra_run="\nt_end = 5.0"),
    "run.revolutions": dict(cycles=100.25),
    "analysis.loads": dict(extra="\n[analysis]\nloads = true\n"),
    "solver.method": dict(extra_solver='\nmethod = "scipy-RK45"'),
    "starter.torque": dict(extra="\n[starter]\ntorque = 50.0\ncutout_speed = 200.0\n"
                                 "noload_speed = 300.0\n"),
}


@pytest.mark.parametrize("key", list(REFUSED))
def test_what_the_method_cannot_follow_is_refused_before_any_work(key, tmp_path, capsys):
    scene_file = write_scene(tmp_path, scene_text(**REFUSED[key]))
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "run", scene_file, "-o", out)
    assert code == 2, err
    assert stdout == "" and err.count("\n") == 1 and "Traceback" not in err
    assert str(scene_file) in err and key in err
    assert not out.exists() or not any(out.iterdir())  # (no work, no file)


@pytest.mark.parametrize("key", ["run.t_end", "analysis.loads"])
def test_check_refuses_what_run_would(key, tmp_path, capsys):
    scene_file = write_scene(tmp_path, scene_text(**REFUSED[key]))
    code, stdout, err = run(capsys, "check", scene_file)
    assert code == 2 and key in err and err.count("\n") == 1
    code, stdout, err = run(capsys, "check", write_scene(tmp_path, scene_text(), "good"))
    assert code == 0, err


def test_the_output_budget_counts_the_cycles_written(tmp_path, capsys):
    # a million cycles: a direct run's least output is refused, the envelope's is not
    many = scene_text(cycles=1_000_000)
    with pytest.raises(transient.SceneError, match="run.revolutions"):
        transient.load_scene(write_scene(tmp_path, many.replace("multirevolution = true",
                                                                "multirevolution = false")))
    assert transient.load_scene(write_scene(tmp_path, many)).solver.multirevolution
    # the resolved cycles outgrowing it stop the run, the result kept and marked
    small = scene_text(extra_run="\nmax_output_bytes = 200000")
    out = tmp_path / "out"
    code, _, err = run(capsys, "run", write_scene(tmp_path, small, "small"), "-o", out, "-q")
    assert code == 1 and "over budget" in err
    res = transient.open_result(out / "small.h5")
    assert not res.complete and res.status == "over-budget"
    # (written up to the cycles before the one that would outgrow it)
    assert 0 < res.trajectory["t"].size * len(res.trajectory) * 8 <= 200000
    assert 0 < res.envelope.integrated.size < CYCLES


def test_simulate_refuses_a_scene_that_asks_for_the_envelope(tmp_path):
    scene = transient.load_scene(write_scene(tmp_path, scene_text(cycles=4)))
    with pytest.raises(transient.SceneError, match="solver.multirevolution"):
        transient.simulate(scene)


def test_the_scene_keys_are_read_and_checked(tmp_path):
    scene = transient.load_scene(write_scene(tmp_path, scene_text(cycles=4)))
    assert scene.solver.multirevolution is True
    assert scene.solver.envelope_rtol == ENVELOPE_RTOL
    assert scene.replace(solver={"multirevolution": False}).solver.multirevolution is False
    bad = scene_text(cycles=4).replace(f"envelope_rtol = {ENVELOPE_RTOL:g}", "envelope_rtol = 2")
    with pytest.raises(transient.SceneError, match="envelope_rtol"):
        transient.load_scene(write_scene(tmp_path, bad, "bad"))
    bad = scene_text(cycles=4).replace("multirevolution = true", "multirevolution = 1")
    with pytest.raises(transient.SceneError, match="multirevolution"):
        transient.load_scene(write_scene(tmp_path, bad, "bad"))


def test_progress_on_a_terminal(tmp_path):
    scene_file = write_scene(tmp_path, scene_text(cycles=100))
    code, stdout, received = terminal_run(["run", str(scene_file), "-o", str(tmp_path / "o")])
    assert code == 0, received
    assert "cycle" in received and "envelope" in received
    assert "wrote" in stdout


#: A run long enough to be killed while it writes (its corners resolve many cycles).
KILLED_CYCLES = 3000
KILLED_SCHEDULE = ("schedule_time = [" + ", ".join(f"{t:g}, {t:g}" for t in range(3, 90, 3))
                   + "]\nschedule_scale = [" + ", ".join(
                       "1.0, 1.1" if i % 2 == 0 else "1.1, 1.0" for i in range(29)) + "]")


def _start(scene_file: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "transient", "run", str(scene_file), "-o",
                             str(out), "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _written_cycles(path: Path) -> int:
    """The cycles a partial file's envelope holds (0 if it cannot be read yet)."""
    try:
        with h5py.File(path, "r", swmr=True) as f:
            return int(f["envelope"]["integrated"].shape[0])
    except (OSError, KeyError):
        return 0


@pytest.mark.slow  # (a run of KILLED_CYCLES cycles in a child process, twice, and in this one)
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_killed_run_keeps_what_it_computed(sig, tmp_path):
    scene_file = write_scene(tmp_path, scene_text(cycles=KILLED_CYCLES,
                                                  schedule=KILLED_SCHEDULE))
    out = tmp_path / "out"
    proc = _start(scene_file, out)
    part = partial_path(out / "long.h5")
    deadline = time.monotonic() + 300
    while _written_cycles(part) < 50 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    proc.send_signal(sig)
    code = proc.wait()
    assert code != 0
    path = part if sig == signal.SIGKILL else out / "long.h5"
    res = transient.open_result(path)
    assert not res.complete
    assert res.status == ("running" if sig == signal.SIGKILL else "interrupted")
    if sig == signal.SIGKILL:
        assert "multirevolution" in res.message and "--force" in res.message
    e = res.envelope
    n = e.integrated.size
    assert 50 <= n < KILLED_CYCLES and e.states.shape[0] == n + 1
    assert np.all(np.isnan(e.error)) or sig == signal.SIGTERM
    # a prefix of the envelope a run never stopped computes, and its resolved cycles' rows
    scene = transient.load_scene(scene_file)
    whole = multirevolution(scene, KILLED_CYCLES, ENVELOPE_RTOL)
    scale = np.abs(whole.states).max(axis=0)
    assert np.all(np.abs(e.states - whole.states[:n + 1]) <= 1e-12 * scale)
    assert np.array_equal(e.integrated, whole.integrated[:n])
    assert e.resolved.size and e.resolved_end[-1] <= res.trajectory["t"].size
    assert np.all(np.isfinite(np.asarray(res.trajectory["omega"])))
    # and without --force the kept result is not replaced
    code = subprocess.run([sys.executable, "-m", "transient", "run", str(scene_file), "-o",
                           str(out), "-q"], capture_output=True).returncode
    assert code == 2
    assert math.isfinite(float(e.mean_omega[-1]))
