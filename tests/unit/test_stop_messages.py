"""The message of a compiled run the stepper stopped as stiff or chattering: it names the
stepper loop's own thresholds and where the run stopped. The stepper is replaced by a stub that
returns the status at once (and the helper compile is skipped): nothing is compiled or
integrated, so the message is built from the initial state."""
from __future__ import annotations

import pytest

import transient.run as sim
from transient.core import stepper
from transient.core.stepper import io as sio
from transient.core.stepper import loop
from transient.scene import scene_from_dict

SCENE = {
    "mechanism": {"type": "crank-slider", "crank_radius_mm": 47, "rod_length_mm": 148,
                  "bore_mm": 88, "piston_mass": 1.52, "crank_mass": 0.912,
                  "rod": {"model": "two-mass", "mass": 1.752, "cg_from_pin_mm": 107.3}},
    "inertia": {"shaft": 0.02},
    "initial": {"omega_rpm": 1000},
    "run": {"revolutions": 2},
}


def stopped_run(monkeypatch, status: int, chatter_event: int = 0):
    """``run_compiled`` of :data:`SCENE` with a stepper that stops at once with ``status``."""
    def advance(m, extras, tab, cfg, bp, y, fst, ist, outbuf, evbuf, work):
        ist[sio.I_CHATTER_CODE] = chatter_event
        return status

    monkeypatch.setattr(stepper, "advance", advance)
    monkeypatch.setattr(sim, "start_helper", lambda model, tab: None)
    return sim.run_compiled(scene_from_dict(SCENE, file="stop.toml"))


def test_a_stiff_run_names_the_stiffness_test_count(monkeypatch):
    data = stopped_run(monkeypatch, sio.STIFF)
    assert not data.complete
    assert data.message.startswith("stiff at t = 0 s, φ = 0 rad")
    assert f"in {loop.STIFF_COUNT} steps" in data.message


@pytest.mark.parametrize("event", ["pair_mode", "locked"])
def test_a_chattering_run_names_its_event_and_count(monkeypatch, event):
    data = stopped_run(monkeypatch, sio.CHATTERING, sio.EVENT_NAMES.index(event))
    assert not data.complete
    assert data.message.startswith(
        f"chattering: {loop.CHATTER_COUNT} state events in a row ({event}) without progress "
        f"at t = 0 s")
