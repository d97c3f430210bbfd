"""What a run did, said: the watch over its blocks classifies a finished run (stalled, reversed,
runaway), stops a run that outgrows its output budget or no longer advances, and warns of
negative losses. Synthetic blocks: nothing is integrated here."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from transient.errors import SimulationError
from transient.outcome import (IDLE_CHUNKS, STATUSES, RunStopped, Watch, code_status,
                               failure_cause, status_in, status_of)


def scene(omega0=100.0, budget=4e9, policy="power-flow", pairs=()):
    """The parts of a scene a watch reads."""
    return SimpleNamespace(initial=SimpleNamespace(omega=omega0),
                           run=SimpleNamespace(max_output_bytes=budget),
                           solver=SimpleNamespace(switch_speed=math.pi / 3.0),
                           friction=SimpleNamespace(policy=policy, pairs=pairs))


def block(t, omega, **extra):
    t = np.asarray(t, dtype=float)
    omega = np.asarray(omega, dtype=float)
    return {"t": t, "phi": np.cumsum(np.abs(omega)) * 0.01, "omega": omega,
            **{k: np.asarray(v, dtype=float) for k, v in extra.items()}}


def watched(*blocks, **kw) -> Watch:
    w = Watch(scene(**kw), columns=3)
    for b in blocks:
        w.observe(b, {})
    return w


def test_a_run_forward_to_its_end_is_finished():
    w = watched(block([0, 1, 2], [100, 110, 120]))
    assert w.verdict("finished", "") == ("finished", "")


def test_a_shaft_driven_backwards_is_reversed_with_where_it_stopped():
    w = watched(block([0, 1], [100, 50]), block([2, 3], [-10, -2781.2]))
    status, message = w.verdict("finished", "")
    assert status == "reversed"
    assert message.startswith("reversed: the shaft was driven backwards (it stopped at t = 2 s, ")
    assert message.endswith("ω = -2781.2 rad/s (-26558.5 rpm)")


def test_the_reversal_event_gives_the_instant_of_the_stop():
    w = Watch(scene(), columns=3)
    w.observe(block([0, 1, 2], [100, 10, -5]), {"speed_reversal": np.array([[1.5, 0.75]])})
    assert w.verdict("finished", "")[1].startswith(
        "reversed: the shaft was driven backwards (it stopped at t = 1.5 s, φ = 0.75 rad")


def test_a_shaft_that_stopped_and_rocks_at_rest_is_stalled():
    w = watched(block([0, 1, 2, 3], [100, 0.0, -0.1, 0.05]))
    status, message = w.verdict("finished", "")
    assert status == "stalled"
    assert message.startswith("stalled: the speed reached zero (it stopped at t = 1 s, ")


def test_a_shaft_held_near_rest_by_friction_is_stalled_not_reversed():
    """Pairs of efficiency 0.01 brake the shaft to a creep backwards of a few µrad/s."""
    w = watched(block([0, 1, 2], [100, 0.0, -3.7e-6]))
    assert w.verdict("finished", "")[0] == "stalled"


def test_a_start_that_rocks_back_once_and_then_runs_is_finished():
    w = watched(block([0, 1, 2, 3], [0.0, 2.0, -0.5, 150.0]), omega0=0.0)
    assert w.verdict("finished", "")[0] == "finished"


def test_a_start_from_rest_is_not_a_stop():
    w = watched(block([0, 1, 2], [0.0, 0.0, 0.5]), omega0=0.0)
    assert w.stop is None


def test_runaway_is_said_for_a_finished_and_for_a_failed_run():
    w = watched(block([0, 1], [100, 2e5]))
    assert w.verdict("finished", "")[0] == "runaway"
    status, message = w.verdict("failed", "integration failed at t = 1 s")
    assert status == "runaway" and message == (
        "runaway: the speed reached 2e+05 rad/s; integration failed at t = 1 s")


def test_statuses_the_stepper_gave_are_kept():
    w = watched(block([0, 1], [100, 0]))
    assert w.verdict("locked", "locked: at rest") == ("locked", "locked: at rest")


def test_a_run_that_outgrows_its_budget_is_stopped_where_it_is():
    w = Watch(scene(budget=100.0), columns=3)  # 24 bytes a sample: 4 fit
    w.observe(block([0, 1, 2, 3], [100, 100, 100, 100]), {})
    with pytest.raises(RunStopped, match=r"^over budget: 5 samples, more than "
                                         r"run.max_output_bytes = 100 bytes allow; stopped at "
                                         r"t = 4 s, ") as info:
        w.observe(block([4], [100]), {})
    assert info.value.status == "over-budget" and isinstance(info.value, SimulationError)


def test_a_run_whose_blocks_stop_advancing_is_stopped():
    w = watched(block([0, 1], [100, 100]))
    empty = block([], [])
    for _ in range(IDLE_CHUNKS - 1):
        w.observe(empty, {})
    with pytest.raises(RunStopped, match=f"^no progress: {IDLE_CHUNKS} chunks of steps brought "
                                         f"no new sample or event; stopped after the last "
                                         f"sample, t = 1 s, ") as info:
        w.observe(empty, {})
    assert info.value.status == "no-progress"


def test_events_further_along_are_progress():
    w = watched(block([0, 1], [100, 100]))
    for k in range(3 * IDLE_CHUNKS):
        w.observe(block([], []), {"pair_mode": np.array([[1.0 + k, 2.0 + k]])})
    assert w.idle == 0


def test_a_restarted_run_is_watched_afresh():
    w = Watch(scene(), columns=3)
    watch_block = w.wrap(None)
    watch_block(block([0, 1], [100, -1]), {}, None)
    watch_block(None, None, None)
    assert w.stop is None and w.samples == 0 and not w.seen


def test_negative_losses_of_paper_pairs_are_a_warning():
    pairs = (SimpleNamespace(name="shaft-crank"),)
    b = block([0, 1, 2], [100, 100, 100], P_loss_1=[5.0, -2.5, 1.0])
    assert watched(b, pairs=pairs, policy="power-flow").warnings() == []
    assert watched(b, pairs=pairs, policy="paper").warnings() == [
        "pair 1 (shaft-crank) reported negative losses (P_loss down to -2.5 W): under policy "
        "'paper' its mode can stand against the power it transmits; policy \"power-flow\" keeps "
        "every loss ≥ 0"]
    rounding = block([0, 1], [100, 100], P_loss_1=[5.0, -1e-12])
    assert watched(rounding, pairs=pairs, policy="paper").warnings() == []


def test_statuses_from_codes_messages_and_exceptions():
    from transient.core import stepper_io as sio

    assert code_status(sio.FINISHED) == "finished" and code_status(sio.RUNNING) == "interrupted"
    assert code_status(sio.FAIL_STEP) == code_status(sio.FAIL_NONFINITE) == "failed"
    assert status_in("locked: at rest at t = 1 s") == "locked"
    assert status_in("integration failed at t = 1 s: x") == "failed"
    assert status_of(KeyboardInterrupt()) == "interrupted"
    assert status_of(RunStopped("no-progress", "no progress: …")) == "no-progress"
    assert status_of(SimulationError("stalled: the speed reached zero")) == "stalled"
    assert {code_status(c) for c in range(8)} - {"stiff"} <= set(STATUSES)


def test_a_failure_from_a_finite_state_names_the_tolerance():
    assert failure_cause(True, True, 1e-13, 1e-300) == (
        "the step size fell below 10 ulp (no step meets the tolerance rtol = 1e-13, "
        "atol = 1e-300 here)")
    assert "a non-finite value in the state" not in failure_cause(False, True, 1e-13, 1e-300)
    assert "atol = 1e-300, against which the error norm overflows" in failure_cause(
        False, True, 1e-13, 1e-300)
    assert failure_cause(False, False, 1e-8, 1e-10) == "a non-finite value in the state"
