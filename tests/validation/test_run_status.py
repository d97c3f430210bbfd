"""Every failure said, on real runs: a start that rocks in compression and never runs (the status
does not depend on which way the shaft turns at the end), a shaft driven backwards though
``t_end`` lets the run go on, an engine that ran and then stalled, a run out of time before its
revolutions, a shaft that stopped on the way and ran again, a run that outgrows its output
budget, negative losses of the paper's criterion. The result's ``status``, the summary, one line
on standard error and the exit code all say it."""
from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.cli import main
from transient.results import open_result

CASES = Path(__file__).resolve().parents[2] / "cases"
COASTING = (CASES / "coasting_single.toml").read_text()
FRICTION = (CASES / "gots_diesel_friction.toml").read_text()
SPINUP = (CASES / "gots_diesel_spinup.toml").read_text()
REACTION = (CASES / "gots_diesel_reaction_friction.toml").read_text()
#: A number as the messages print it, and a place with its degrees.
NUM = r"-?[\d.]+(e[-+]\d+)?"
AT = rf"t = {NUM} s, φ = {NUM} rad \({NUM}°\)"
#: How a rocking start that never ran opens its line on standard error.
ROCKED = (r"transient: did not start: the shaft rocked and never turned a whole revolution "
          r"forwards \(at most ")


def write(tmp_path, name: str, text: str) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_load_larger_than_the_engine_drives_it_backwards_exit_1(tmp_path, capsys):
    """With t_end the integration follows the shaft through the stop and backwards; the run
    is complete but did not do what the scene describes."""
    text = COASTING.replace("[initial]", "[load]\ntorque = 50.0\n\n[initial]").replace(
        "revolutions = 1000", "revolutions = 1000\nt_end = 0.3")
    scene = write(tmp_path, "reversed", text)
    assert main(["run", str(scene), "-o", str(tmp_path)]) == 1
    out, err = capsys.readouterr()
    assert re.fullmatch(
        rf"transient: reversed: the shaft was driven backwards; the speed went through zero 1 "
        rf"time, first at {AT}; at the end it turned backwards, t = 0\.3 s, φ = {NUM} rad "
        rf"\({NUM}°\), ω = -{NUM} rad/s \(-{NUM} rpm\); result in \S+reversed\.h5 "
        rf"\(status = reversed\)\n", err), err
    assert "  status: reversed: the shaft was driven backwards" in out
    res = open_result(tmp_path / "reversed.h5")
    assert res.complete and res.status == "reversed"
    assert res.trajectory["omega"][-1] < 0.0 and res.events["speed_reversal"]["t"].size == 1
    assert main(["info", str(tmp_path / "reversed.h5")]) == 0
    assert "status = reversed" in capsys.readouterr().out


def test_a_finished_run_says_so(tmp_path, capsys):
    scene = write(tmp_path, "coast", COASTING.replace("revolutions = 1000", "revolutions = 3"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    assert capsys.readouterr().err == ""
    assert open_result(tmp_path / "coast.h5").status == "finished"


def test_a_run_beyond_its_output_budget_is_stopped_and_kept(tmp_path, capsys):
    """The estimate counts a time-bounded run at the switch speed; at 1000 rpm it writes far
    more, and the watch stops it at its first block past the budget."""
    text = COASTING.replace("revolutions = 1000", "t_end = 100\nmax_output_bytes = 3e5").replace(
        "rtol = 1e-10", "rtol = 1e-6")
    scene = write(tmp_path, "budget", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    err = capsys.readouterr().err
    assert re.fullmatch(r"transient: over budget: \d+ samples, more than run.max_output_bytes "
                        r"= 3e\+05 bytes allow; stopped at t = \S+ s, φ = \S+ rad \(\S+°\), "
                        r"ω = \S+ rad/s \(\S+ rpm\); partial result kept in \S+budget\.h5 "
                        r"\(complete = false\)\n", err), err
    with h5py.File(tmp_path / "budget.h5") as f:
        assert not f.attrs["complete"] and f.attrs["status"] == "over-budget"
        assert f["trajectory/t"].size > 0 and np.all(np.diff(f["trajectory/t"][()]) > 0)


def test_pairs_of_efficiency_near_zero_brake_the_engine_before_it_starts_exit_1(tmp_path,
                                                                               capsys):
    """η = 0.01 in both pairs: the engine cannot turn its own crank; from 1000 rpm it stops in
    its first compression and, with t_end, the run goes on to its end, the shaft rocking and then
    creeping at a few µrad/s around where it stopped: it did not start."""
    text = FRICTION.replace("eta_forward = 0.985", "eta_forward = 0.01").replace(
        "eta_backward = 0.98\n", "eta_backward = 0.01\n").replace(
        "revolutions = 600", "revolutions = 20\nt_end = 2")
    scene = write(tmp_path, "braked", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    err = capsys.readouterr().err
    assert re.fullmatch(rf"{ROCKED}{NUM} rad, {NUM}°, past its start at "
                        rf"φ = 0 rad\); the speed went through zero \d+ times, first at {AT}, "
                        rf"last at {AT}; at the end t = 2 s, φ = {NUM} rad \({NUM}°\), "
                        rf"ω = {NUM} rad/s \({NUM} rpm\); result in \S+braked\.h5 \(status = "
                        rf"not-started\)\n", err), err
    res = open_result(tmp_path / "braked.h5")
    assert res.complete and res.status == "not-started"
    assert abs(res.trajectory["omega"][-1]) < 1e-3


def light(t_end: float) -> str:
    """The Gots diesel of gots_diesel_spinup.toml with no flywheel and a crankshaft of 0.001
    kg m²: from 1000 rpm its kinetic energy (5.5 J) cannot carry a piston through compression."""
    return SPINUP.replace("shaft = 0.02\nflywheel = 0.15", "shaft = 0.001\nflywheel = 0").replace(
        "revolutions = 1000", f"revolutions = 30\nt_end = {t_end}")


@pytest.mark.parametrize("t_end", [0.5, 2.0])
def test_a_light_crank_rocking_in_compression_did_not_start_exit_1(tmp_path, capsys, t_end):
    """The shaft swings in its first compression (ω between about −66 and +112 rad/s) to the
    end: at t = 0.5 s it happens to turn forwards, at 2 s backwards; either way the run did not
    start, and the summary, the result and ``transient info`` say how often the speed went
    through zero and where first. The swings stay within the first revolution: the largest
    angle the samples reach is below 2π."""
    scene = write(tmp_path, "light", light(t_end))
    assert main(["run", str(scene), "-o", str(tmp_path)]) == 1
    out, err = capsys.readouterr()
    assert err.startswith("transient: did not start: the shaft rocked and never turned a whole "
                          "revolution forwards (at most 1.51"), err
    assert err.endswith("(status = not-started)\n")
    res = open_result(tmp_path / "light.h5")
    tr, reversals = res.trajectory, res.events["speed_reversal"]
    assert res.complete and res.status == "not-started"
    assert tr["phi"].max() < 2 * np.pi and tr["omega"].min() < -60 and tr["omega"].max() > 100
    assert (tr["omega"][-1] > 0) == (t_end == 0.5)  # (the end's direction differs)
    n = reversals["t"].size
    assert n >= 10 and res.analysis["speed_reversals"] == (float(n), "1")
    assert res.analysis["speed_reversal_first_t"] == (reversals["t"][0], "s")
    assert (f"  speed through zero: {n} time(s), first at t = {reversals['t'][0]:.9g} s, "
            f"φ = {reversals['phi'][0]:.9g} rad\n") in out
    # every swing turns where ω = 0: the samples' φ stays within the reversals' angles
    assert reversals["phi"].max() >= tr["phi"].max() - 1e-9
    assert main(["info", str(tmp_path / "light.h5")]) == 0
    info = capsys.readouterr().out
    assert "status = not-started" in info and "  message: did not start: " in info
    assert f"  speed_reversals = {n} 1\n" in info and "  speed through zero: " in info


def test_a_weak_starter_on_the_reaction_friction_diesel_did_not_start_exit_1(tmp_path, capsys):
    """5 N m of starter from rest against the compression of the Gots diesel with friction on
    its joints: the shaft moves 61° forwards, rocks, the swings die out (8 passages of the speed
    through zero in 0.8 s); with a longer t_end the pairs lock it, and that says so too."""
    text = REACTION.replace("[initial]\nomega_rpm = 1000", "[starter]\ntorque = 5.0\n"
                            "noload_speed_rpm = 600\ncutout_speed_rpm = 400\n\n[initial]\n"
                            "omega = 0.0").replace("revolutions = 600", "revolutions = 600\n"
                                                   "t_end = 0.8")
    scene = write(tmp_path, "weak", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    err = capsys.readouterr().err
    assert re.fullmatch(rf"{ROCKED}1\.069\d* rad, 61\.2\d*°, past its "
                        rf"start at φ = 0 rad\); the speed went through zero 8 times, first at "
                        rf"{AT}, last at {AT}; at the end t = 0\.8 s, .*\(status = "
                        rf"not-started\)\n", err), err
    write(tmp_path, "weak", text.replace("t_end = 0.8", "t_end = 2.0"))
    assert main(["run", str(tmp_path / "weak.toml"), "-o", str(tmp_path), "-q", "--force"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("transient: locked: at rest at t = ")
    assert re.search(r"; the speed went through zero \d+ times, .*; it did not start: the shaft "
                     r"rocked and never turned a whole revolution forwards", err), err


def test_a_run_out_of_time_before_its_revolutions_exit_1(tmp_path, capsys):
    """Coasting from 1000 rpm for 0.05 s turns about 0.8 of the 1000 revolutions asked."""
    scene = write(tmp_path, "short", COASTING.replace("revolutions = 1000",
                                                      "revolutions = 1000\nt_end = 0.05"))
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    err = capsys.readouterr().err
    res = open_result(tmp_path / "short.h5")
    revs = (res.trajectory["phi"][-1] - res.trajectory["phi"][0]) / (2 * np.pi)
    assert 0.75 < revs < 0.85 and res.complete and res.status == "out-of-time"
    assert err.startswith(f"transient: out of time: run.t_end = 0.05 s came after {revs:.6g} of "
                          f"the 1000 revolutions the scene asks for; at the end t = 0.05 s, ")


@pytest.mark.parametrize("run", ["t_end = 0.5", "revolutions = 5\nt_end = 0.5"])
def test_a_shaft_that_stops_on_the_way_and_runs_again_finishes_with_a_warning(tmp_path, capsys,
                                                                              run):
    """Given −50 rad/s and a motor's 20 N m forwards, the shaft stops, turns forwards and runs
    on past its start: it did what the scene asks (exit 0), and a warning says where it
    stopped."""
    text = COASTING.replace("[initial]", "[load]\ntorque = -20.0\n\n[initial]").replace(
        "omega_rpm = 1000", "omega = -50.0").replace("revolutions = 1000", run)
    scene = write(tmp_path, "back", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    err = capsys.readouterr().err
    res = open_result(tmp_path / "back.h5")
    [(t, phi)] = np.column_stack([res.events["speed_reversal"]["t"],
                                  res.events["speed_reversal"]["phi"]])
    assert err == (f"transient: warning: the shaft stopped on the way and ran again: the speed "
                   f"went through zero 1 time, first at t = {t:.9g} s, φ = {phi:.9g} rad "
                   f"({np.degrees(phi):.6g}°)\n")
    assert res.status == "finished" and res.warnings == [err.split("warning: ")[1].strip()]
    assert phi < 0 < res.trajectory["phi"][-1]


@pytest.mark.parametrize("run, status", [("t_end = 1.0", "stalled"),
                                         ("revolutions = 200", "stalled")])
def test_an_engine_that_ran_and_is_stalled_by_a_load_step_exit_1(tmp_path, capsys, run, status):
    """The spin-up diesel at 1000 rpm; at 0.3 s (about 6 revolutions) its fan load grows 400
    times: the speed falls to zero and the shaft rocks in compression to the end (t_end), or the
    run stops there (revolutions only)."""
    text = SPINUP.replace("fan = 9.692e-4", "fan = 9.692e-4\nschedule_time = [0.3, 0.3]\n"
                          "schedule_scale = [1.0, 400.0]").replace("revolutions = 1000", run)
    scene = write(tmp_path, "step", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("transient: stalled: the speed reached zero"), err
    res = open_result(tmp_path / "step.h5")
    assert res.status == status and res.trajectory["phi"].max() > 2 * np.pi


def test_a_prescribed_speed_run_out_of_time_exit_1(tmp_path, capsys):
    """600 rpm prescribed for 0.5 s: 5 of the 10 revolutions asked."""
    text = SPINUP.replace("[initial]\nomega_rpm = 1000", "[initial]\nomega_rpm = 600").replace(
        "revolutions = 1000", 'mode = "prescribed-speed"\nspeed_rpm = 600\nrevolutions = 10\n'
                              't_end = 0.5')
    scene = write(tmp_path, "held", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    assert capsys.readouterr().err.startswith("transient: out of time: run.t_end = 0.5 s came "
                                              "after 5 of the 10 revolutions")
    assert open_result(tmp_path / "held.h5").status == "out-of-time"


def test_a_resumed_run_is_judged_over_all_of_it(tmp_path):
    """The light crank interrupted after a few blocks and resumed: the passages through zero
    before the interrupt count, as in a run never stopped."""
    from transient import load_scene, simulate
    from transient.errors import SimulationError

    scene = load_scene(write(tmp_path, "light", light(1.0) + "dt = 2e-5\n"))
    with pytest.raises(SimulationError) as whole:
        simulate(scene, tmp_path / "whole.h5")
    blocks = []

    def stop_after_three(_fraction):
        blocks.append(1)
        if len(blocks) == 3:
            raise KeyboardInterrupt

    with pytest.raises(SimulationError, match="interrupted"):
        simulate(scene, tmp_path / "light.h5", progress=stop_after_three)
    assert open_result(tmp_path / "light.h5").status == "interrupted"
    with pytest.raises(SimulationError) as again:
        simulate(scene, tmp_path / "light.h5", resume=True)
    a, b = whole.value.result, again.value.result
    assert a.status == b.status == "not-started" and a.message == b.message
    assert a.analysis["speed_reversals"] == b.analysis["speed_reversals"]


def test_negative_losses_of_the_papers_criterion_are_a_warning(tmp_path, capsys):
    """The Gots diesel with policy "paper": both pairs report negative losses (their modes stand
    against the power); the run did what the scene asked, exit 0, with a warning per pair."""
    text = FRICTION.replace('policy = "power-flow"', 'policy = "paper"').replace(
        "revolutions = 600", "revolutions = 5")
    scene = write(tmp_path, "paper", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 0
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" (P_loss")[0] for line in lines] == [
        "transient: warning: pair 1 (main bearings) reported negative losses",
        "transient: warning: pair 2 (crankpins) reported negative losses"]
    res = open_result(tmp_path / "paper.h5")
    assert res.status == "finished"
    assert res.attrs["warnings"].count("reported negative losses") == 2


def test_the_reference_path_records_the_same_passages_through_zero(tmp_path):
    """solve_ivp's run of the light crank (no friction chain: its zeros of ω are recorded as
    they pass) finds the compiled run's passages through zero, and the same status."""
    import dataclasses as dc

    from transient import load_scene
    from transient.run import integrate

    scene = load_scene(write(tmp_path, "light", light(0.5)))
    compiled = integrate(scene)
    reference = integrate(dc.replace(scene, solver=dc.replace(scene.solver,
                                                              method="scipy-DOP853")))
    a, b = compiled.events["speed_reversal"], reference.events["speed_reversal"]
    assert compiled.status == reference.status == "not-started"
    assert a.shape == b.shape and a.shape[0] >= 10
    # (both located to rtol = 1e-8 of swings 40 ms long)
    assert np.max(np.abs(a - b)) <= 1e-6, np.max(np.abs(a - b))
