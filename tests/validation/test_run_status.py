"""Every failure said, on real runs: a shaft driven backwards though ``t_end`` lets the run go on,
a run that outgrows its output budget, negative losses of the paper's criterion. The result's
``status``, the summary, one line on standard error and the exit code all say it."""
from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np

from transient.cli import main
from transient.results import open_result

CASES = Path(__file__).resolve().parents[2] / "cases"
COASTING = (CASES / "coasting_single.toml").read_text()
FRICTION = (CASES / "gots_diesel_friction.toml").read_text()


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
        r"transient: reversed: the shaft was driven backwards \(it stopped at t = \S+ s, "
        r"φ = \S+ rad \(\S+°\)\) and turned backwards at the end, t = 0\.3 s, φ = \S+ rad "
        r"\(\S+°\), ω = -\S+ rad/s \(-\S+ rpm\); result in \S+reversed\.h5 "
        r"\(status = reversed\)\n", err), err
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


def test_pairs_of_efficiency_near_zero_brake_the_engine_to_a_stall_exit_1(tmp_path, capsys):
    """η = 0.01 in both pairs: the engine cannot turn its own crank; with t_end the run goes on
    to its end, the shaft creeping at a few µrad/s around where it stopped."""
    text = FRICTION.replace("eta_forward = 0.985", "eta_forward = 0.01").replace(
        "eta_backward = 0.98\n", "eta_backward = 0.01\n").replace(
        "revolutions = 600", "revolutions = 20\nt_end = 2")
    scene = write(tmp_path, "braked", text)
    assert main(["run", str(scene), "-o", str(tmp_path), "-q"]) == 1
    err = capsys.readouterr().err
    assert re.fullmatch(r"transient: stalled: the speed reached zero \(it stopped at t = \S+ s, "
                        r"φ = \S+ rad \(\S+°\)\) and the shaft did not run again; at the end "
                        r"t = 2 s, φ = \S+ rad \(\S+°\), ω = \S+ rad/s \(\S+ rpm\); result in "
                        r"\S+braked\.h5 \(status = stalled\)\n", err), err
    res = open_result(tmp_path / "braked.h5")
    assert res.complete and res.status == "stalled"
    assert abs(res.trajectory["omega"][-1]) < 1e-3


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
