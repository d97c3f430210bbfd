"""A shaft that stops in a run that ends only by revolutions is reported as a stall, or as a start
that failed if it never turned a whole revolution (exit 1, the partial result kept and marked
incomplete), never integrated forever."""
from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import h5py
import numpy as np
import pytest

from transient.cli import main
from transient.run import integrate
from transient.scene import load_scene

CASE = Path(__file__).resolve().parents[2] / "cases" / "coasting_single.toml"


def test_stall_is_reported_with_time_angle_and_state(tmp_path, capsys):
    """10 N m against the coasting cylinder: it turns about 2.2 revolutions, then stops."""
    text = CASE.read_text().replace("[initial]", "[load]\ntorque = 10.0\n\n[initial]")
    scene = tmp_path / "stall.toml"
    scene.write_text(text)
    code = main(["run", str(scene), "-o", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 1
    assert err.startswith("transient: stalled: the speed reached zero at t = ") and "φ = " in err
    with h5py.File(tmp_path / "stall.h5") as f:
        assert not f.attrs["complete"] and f.attrs["status"] == "stalled"
        assert "stalled" in f.attrs["message"]
        omega = f["trajectory/omega"][()]
        assert omega[0] > 100 and abs(omega[-1]) < 1e-9  # computed up to the stop, kept
        assert f["trajectory/phi"][-1] > 2 * np.pi
        assert f["events/speed_reversal/t"].size == 1


@pytest.mark.parametrize("torque, status", [(10.0, "stalled"), (50.0, "not-started")])
def test_reference_path_reports_the_stall_too(tmp_path, torque, status):
    """solve_ivp's run stops at the same stall, said the same way (within its first revolution
    with 50 N m: the shaft did not start)."""
    text = CASE.read_text().replace("[initial]", f"[load]\ntorque = {torque}\n\n[initial]")
    scene = load_scene(tmp_path / "stall.toml", text=text)
    compiled = integrate(scene)
    scene = dc.replace(scene, solver=dc.replace(scene.solver, method="scipy-DOP853", rtol=1e-8))
    reference = integrate(scene)
    for data in (compiled, reference):
        assert not data.complete and data.status == status, data.message
        assert "the speed reached zero at t = " in data.message
    [(t_c, phi_c)], [(t_r, phi_r)] = (compiled.events["speed_reversal"],
                                      reference.events["speed_reversal"])
    assert abs(t_r - t_c) <= 1e-6 * t_c and abs(phi_r - phi_c) <= 1e-6 * phi_c


@pytest.mark.parametrize("start", ["backwards", "from rest"])
def test_backward_motion_in_a_revolutions_run_did_not_start(tmp_path, start):
    """A shaft that turns backwards never reaches its revolutions: given a negative speed, or
    started from rest by a starter weaker than the load (else the run would integrate on without
    end, its file growing). Reported as a start that failed, the partial run kept."""
    text = CASE.read_text().replace("[initial]", "[load]\ntorque = 10.0\n\n[initial]")
    text = text.replace("omega_rpm = 1000", "omega_rpm = -100" if start == "backwards" else
                        "omega_rpm = 0")
    if start == "from rest":
        text += "\n[starter]\ntorque = 5.0\nnoload_speed_rpm = 300\ncutout_speed_rpm = 200\n"
    scene = load_scene(tmp_path / "back.toml", text=text)
    data = integrate(scene)
    assert not data.complete and data.status == "not-started"
    assert data.message.startswith("did not start: the shaft never turned a whole revolution "
                                   "forwards (at most 0 rad, 0°, past its start at φ = 0 rad); "
                                   "the shaft turned backwards at t = ")
    assert data.trajectory["omega"][-1] < 0.0 and data.trajectory["t"].size >= 1
