"""What a run did, said: the watch over its blocks classifies a finished run (stalled, reversed,
runaway), stops a run that outgrows its output budget or no longer advances, and warns of
negative losses. Synthetic blocks: nothing is integrated here."""
from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from transient.errors import SimulationError
from transient.outcome import (
    IDLE_CHUNKS,
    STATUSES,
    RunStopped,
    Watch,
    code_status,
    failure_cause,
    status_in,
    status_of,
)


def scene(omega0=100.0, budget=4e9, policy="power-flow", pairs=(), revolutions=math.inf,
          t_end=math.inf, phi0=0.0, time=()):
    """The parts of a scene a watch reads."""
    return SimpleNamespace(initial=SimpleNamespace(phi=phi0, omega=omega0),
                           run=SimpleNamespace(max_output_bytes=budget, revolutions=revolutions,
                                               t_end=t_end, time=time),
                           solver=SimpleNamespace(switch_speed=WS, rtol=1e-8),
                           friction=SimpleNamespace(policy=policy, pairs=pairs), shaft=None)


#: The switch speed of the scenes above [rad/s] (10 rpm).
WS = math.pi / 3.0


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


def motion(t, omega, phi0=0.0):
    """A run's block and its speed_reversal events, written independently of the stepper: φ the
    trapezoidal integral of ω (exact for ω linear between the samples), each zero of ω (linear
    between the samples, with φ integrated up to it) an event."""
    t, omega = np.asarray(t, dtype=float), np.asarray(omega, dtype=float)
    phi = phi0 + np.concatenate([[0.0], np.cumsum(np.diff(t) * (omega[1:] + omega[:-1]) / 2)])
    events = []
    for i in np.flatnonzero(np.sign(omega[1:]) != np.sign(omega[:-1])):
        if omega[i + 1] == 0.0 and i + 2 < omega.size and np.sign(omega[i + 2]) == np.sign(
                omega[i]):
            continue  # (touching zero and going on is no passage)
        if omega[i] == 0.0:
            continue  # (counted at the sample where it arrived at zero)
        s = omega[i] / (omega[i] - omega[i + 1])  # ω = 0 at t_i + s·Δt
        dt = s * (t[i + 1] - t[i])
        events.append((t[i] + dt, phi[i] + omega[i] * dt / 2))
    return ({"t": t, "phi": phi, "omega": omega},
            {"speed_reversal": np.array(events).reshape(-1, 2)})


def judged(t, omega, status="finished", message="", **kw):
    """The verdict on one run of samples (t, ω) given to a watch of the scene ``kw``."""
    w = Watch(scene(**kw), columns=3)
    w.observe(*motion(t, omega, kw.get("phi0", 0.0)))
    return w.verdict(status, message)


def rocking(t_end, amplitude=20.0, period=0.1, n=4001):
    """A shaft swinging about φ = 0.1·amplitude·period/2π-ish: ω = A cos(2πt/T), no progress."""
    t = np.linspace(0.0, t_end, n)
    return t, amplitude * np.cos(2 * np.pi * t / period)


#: A start that runs 1.6 revolutions forwards (ω 100 → 0 in 0.2 s, 10 rad), then rocks.
def ran_then_rocks(t_end):
    t = np.linspace(0.0, t_end, 8001)
    omega = np.where(t < 0.2, 100.0 * (1 - t / 0.2), -20.0 * np.sin(2 * np.pi * (t - 0.2) / 0.1))
    return t, omega


def test_a_run_forward_to_its_revolutions_is_finished():
    t = np.linspace(0, 1, 101)
    status, message = judged(t, 20 * np.pi + 0 * t, revolutions=10.0)
    assert (status, message) == ("finished", "")


def test_a_run_forward_to_its_end_time_alone_is_finished():
    t = np.linspace(0, 1, 101)
    assert judged(t, 100 + 10 * t, t_end=1.0) == ("finished", "")


def test_reaching_t_end_before_the_revolutions_is_out_of_time():
    t = np.linspace(0, 1, 101)
    status, message = judged(t, 7 * np.pi + 0 * t, revolutions=10.0, t_end=1.0)
    assert status == "out-of-time"
    assert message.startswith("out of time: run.t_end = 1 s came after 3.5 of the 10 revolutions "
                              "the scene asks for; at the end t = 1 s, φ = 21.99")


@pytest.mark.parametrize("t_end", [0.5, 0.525, 0.55, 0.575])  # ω > 0, = 0, < 0, = 0 at the end
@pytest.mark.parametrize("asked", [{"t_end": None}, {"revolutions": 30.0, "t_end": None}])
def test_rocking_never_started_whichever_way_the_shaft_turns_at_the_end(t_end, asked):
    """The reproducer's shape: a shaft that swings in compression, ω from −20 to +20 rad/s; the
    status does not depend on which way it turns at the end."""
    kw = {k: (t_end if v is None else v) for k, v in asked.items()}
    status, message = judged(*rocking(t_end), **kw)
    assert status == "not-started", message
    # (φ at most A·T/2π = 0.31831 rad, to the samples' trapezoidal rule)
    assert message.startswith("did not start: the shaft rocked and never turned a whole "
                              "revolution forwards (at most 0.3183")
    assert re.search(r"past its start at φ = 0 rad\); the speed went through zero 1[01] times, "
                     r"first at t = 0\.02(5|49999\d*) s, φ = 0\.3183", message), message


def test_a_shaft_that_ran_and_then_rocks_is_stalled_whichever_way_it_turns_at_the_end():
    for t_end in (0.5, 0.525, 0.55, 0.575):  # mid-swing both ways, and at the swings' ends
        status, message = judged(*ran_then_rocks(t_end), t_end=t_end)
        assert status == "stalled", (t_end, message)
        assert message.startswith("stalled: the speed reached zero and the shaft did not run "
                                  "again; the speed went through zero ")


def test_a_shaft_driven_backwards_past_where_it_swung_is_reversed():
    t = np.linspace(0.0, 1.0, 1001)
    status, message = judged(t, 100 - 300 * t, t_end=1.0)  # stops at 1/3 s, backwards after
    assert status == "reversed"
    assert message.startswith("reversed: the shaft was driven backwards; the speed went through "
                              "zero 1 time, first at t = 0.333333333 s, φ = 16.6666667 rad")
    assert message.endswith("ω = -200 rad/s (-1909.86 rpm)")


def test_a_shaft_given_a_backward_speed_is_reversed_from_the_start():
    t = np.linspace(0.0, 1.0, 11)
    status, message = judged(t, -50 - 10 * t, t_end=1.0, omega0=-50.0)
    assert status == "reversed"
    assert message.startswith("reversed: the shaft was driven backwards; it turned backwards "
                              "from the start; at the end it turned backwards, t = 1 s")


@pytest.mark.parametrize("asked", [{"t_end": 1.0}, {"t_end": 1.0, "revolutions": 10.0}])
def test_a_start_that_rocks_back_once_and_then_runs_is_finished_with_a_warning(asked):
    """From rest: forwards, back (ω = 20 sin(2πt/0.2)), then through to the end (10.2
    revolutions), past every angle reached before its last stop. A warning says where the
    shaft stopped; the first stop is at t = 0.1 s, φ = ∫ω dt = 0.4/π."""
    t = np.linspace(0.0, 1.0, 1001)
    omega = np.where(t < 0.2, 20 * np.sin(2 * np.pi * t / 0.2), 200 * (t - 0.2))
    w = Watch(scene(omega0=0.0, **asked), columns=3)
    w.observe(*motion(t, omega))
    assert w.verdict("finished", "") == ("finished", "")
    [warning] = w.warnings()
    assert warning.startswith("the shaft stopped on the way and ran again: the speed went "
                              "through zero 2 times, first at t = 0.1 s, φ = 1.273")
    assert ", last at t = 0.2 s, φ = " in warning
    summary = w.summary()
    assert summary["speed_reversals"] == (2.0, "1")
    assert summary["speed_reversal_first_t"] == (pytest.approx(0.1, abs=1e-12), "s")
    # (trapezoidal φ of the samples: O(h²) from the closed form 20·0.2/π)
    assert summary["speed_reversal_first_phi"] == (pytest.approx(4.0 / np.pi, rel=1e-4), "rad")


def test_a_start_that_has_not_yet_passed_its_furthest_angle_has_not_started():
    """Back, forwards again, but not yet past where it had stopped: a swing, not a start."""
    t = np.linspace(0.0, 0.3, 301)
    omega = np.where(t < 0.2, 20 * np.sin(2 * np.pi * t / 0.2), 200 * (t - 0.2))
    assert judged(t, omega, t_end=0.3, omega0=0.0)[0] == "not-started"


def test_a_shaft_held_near_rest_by_friction_is_stalled_not_reversed():
    """Pairs of efficiency 0.01 brake the shaft to a creep backwards of a few µrad/s."""
    t = np.linspace(0.0, 2.0, 2001)
    omega = np.where(t < 1.0, 100 * (1 - t), -3.7e-6)
    status, message = judged(t, omega, t_end=2.0)
    assert status == "stalled", message


def test_the_steppers_stall_within_the_first_revolution_did_not_start():
    """A run that ends by revolutions only is stopped by the stepper where the speed reaches
    zero; within the first revolution that is a start that failed."""
    t = np.linspace(0.0, 0.1, 101)
    stall = ("stalled: the speed reached zero at t = 0.1 s, φ = 5 rad (286.479°) before the 30 "
             "revolutions the run ends by; give run.t_end to follow the motion after a stall")
    status, message = judged(t, 100 * (1 - t / 0.1), "stalled", stall, revolutions=30.0)
    assert status == "not-started"
    assert message == ("did not start: the shaft never turned a whole revolution forwards (at "
                       "most 5 rad, 286.479°, past its start at φ = 0 rad); the speed reached "
                       "zero at t = 0.1 s, φ = 5 rad (286.479°) before the 30 revolutions the "
                       "run ends by; give run.t_end to follow the motion after a stall")
    t = np.linspace(0.0, 0.2, 101)
    assert judged(t, 100 * (1 - t / 0.2), "stalled", stall, revolutions=30.0) == ("stalled",
                                                                                  stall)


def test_a_prescribed_speed_run_ended_by_t_end_before_its_revolutions_is_out_of_time():
    """…unless the end is its speed table's: the prescribed motion ends there."""
    t = np.linspace(0.0, 0.5, 51)
    assert judged(t, 20 * np.pi + 0 * t, revolutions=10.0, t_end=0.5)[0] == "out-of-time"
    assert judged(t, 20 * np.pi + 0 * t, revolutions=5.0, t_end=0.5)[0] == "finished"
    assert judged(t, 20 * np.pi + 0 * t, revolutions=10.0, t_end=0.5,
                  time=(0.0, 0.5))[0] == "finished"
    assert judged(t, 20 * np.pi + 0 * t, revolutions=10.0, t_end=0.5,
                  time=(0.0, 0.8))[0] == "out-of-time"


def test_a_locked_start_says_it_did_not_start():
    t = np.linspace(0.0, 0.3, 301)
    status, message = judged(t, 20 * np.sin(2 * np.pi * t / 0.2) * (t < 0.2), "locked",
                             "locked: at rest at t = 0.3 s", t_end=1.0, omega0=0.0)
    assert status == "locked"
    assert message.startswith("locked: at rest at t = 0.3 s; the speed went through zero 2 "
                              "times, first at t = 0.1 s")
    assert "; it did not start: the shaft rocked and never turned a whole revolution" in message


def test_a_resumed_watch_that_took_the_run_before_says_the_same():
    """The blocks before a checkpoint, taken in again, then the rest: the same verdict and
    summary as one watch over the whole run."""
    t, omega = rocking(0.55)
    whole = judged(t, omega, t_end=0.55)
    run, events = motion(t, omega)
    cut = np.searchsorted(t, 0.3)
    w = Watch(scene(t_end=0.55), columns=3)
    early = events["speed_reversal"][:, 0] < t[cut]
    reversals = events["speed_reversal"]
    w.take({k: v[:cut] for k, v in run.items()}, {"speed_reversal": reversals[early]})
    w.observe({k: v[cut:] for k, v in run.items()}, {"speed_reversal": reversals[~early]})
    assert w.verdict("finished", "") == whole
    assert w.summary()["speed_reversals"] == (11.0, "1")


def test_every_status_said_is_documented():
    assert {"finished", "out-of-time", "not-started", "stalled", "reversed"} <= set(STATUSES)


def test_runaway_is_said_for_a_finished_and_for_a_failed_run():
    w = watched(block([0, 1], [100, 2e5]))
    assert w.verdict("finished", "")[0] == "runaway"
    status, message = w.verdict("failed", "integration failed at t = 1 s")
    assert status == "runaway" and message == (
        "runaway: the speed reached 2e+05 rad/s; integration failed at t = 1 s")


def test_statuses_the_stepper_gave_are_kept():
    w = watched(block([0, 1], [1000, 0]))  # (10 rad: started)
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
    assert w.stops == 0 and w.samples == 0 and not w.seen


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
    from transient.core.stepper import io as sio

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
