"""Multirevolution steps on the cycle map (transient.multirev) against the direct run of the
same scene, cycle by cycle: the envelope's states at every cycle start, its error estimate
against the error measured, and a load schedule's corners and the switches of a pair's modes or
a governor's limits falling in the same cycles."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import transient
from transient.errors import SceneError
from transient.multirev import CORNER_CYCLES, MIN_MACRO, multirevolution
from transient.run import CycleMap
from transient.verify.steady import cycle_starts, cycles_of

CASE = "cases/gots_diesel_friction.toml"
#: The scene's stepper tolerance: so tight that the two runs differ by the envelope's error
#: (the map's own, the stepper's, which the direct run shares, is no part of the estimate).
RTOL = 1e-12
#: The acceptance's agreement in ω, relative.
AGREE = 1e-6
CYCLES = 4000
GOVERNED = "cases/gots_diesel_pi.toml"


def _scene(flywheel: float, omega: float | None = None, schedule=None, case=CASE):
    sc = transient.load_scene(case)
    sc = dataclasses.replace(
        sc, inertia=dataclasses.replace(sc.inertia, flywheel=flywheel * sc.inertia.flywheel),
        solver=dataclasses.replace(sc.solver, rtol=RTOL, atol=RTOL * 1e-2),
        output=dataclasses.replace(sc.output, samples_per_rev=4))
    if omega is not None:
        sc = dataclasses.replace(sc, initial=dataclasses.replace(sc.initial, omega=omega))
    if schedule is not None:
        sc = dataclasses.replace(sc, load=dataclasses.replace(
            sc.load, schedule_time=schedule[0], schedule_scale=schedule[1]))
    return sc


#: The diesel with a flywheel ×100 near its running speed, its load stepped up at 5 s, ramped
#: and stepped down at 60 s and 90 s: an envelope that changes slowly between the corners;
#: with a flywheel ×300 from 1000 rpm, a spin-up to its running speed over the run, in which
#: the pairs' modes start switching more often in a cycle; and the PI-governed diesel with a
#: flywheel ×10 and its load switched on and off, the governor's rack on its lower limit for
#: a while after: a stiff envelope (its latched fuels' multipliers are zero).
SCENES = {"load programme": dict(flywheel=100.0, omega=440.0,
                                 schedule=((5.0, 60.0, 90.0), (1.0, 1.25, 0.8))),
          "spin-up": dict(flywheel=300.0, omega=104.71975511965977, schedule=((), ())),
          "governed": dict(flywheel=10.0, case=GOVERNED)}
#: Those whose envelope is stiff: besides, cycles resolved where implicit steps gain nothing.
STIFF = {"governed"}


@pytest.fixture(scope="module", params=list(SCENES))
def both(request):
    scene = _scene(**SCENES[request.param])
    env = multirevolution(scene, CYCLES)
    run = transient.simulate(cycles_of(scene, CYCLES))
    starts = cycle_starts(scene, run.trajectory, CYCLES)
    t = np.asarray(run.trajectory["t"])[starts]
    return (scene, env, np.asarray(run.trajectory["omega"])[starts], t, _switches(run, t),
            request.param)


def _switches(run, t) -> np.ndarray:
    """The cycles whose switching events (their kinds, how many of each) differ from the
    cycle's before them, in the direct run; an event on a cycle's start, which either cycle
    may hold, left out."""
    cycles = t.size - 1
    counts = []
    for kind in set(run.events) - {"breakpoint", "end"}:
        at = run.events[kind]["t"]
        n = np.searchsorted(t, at, side="right") - 1
        inside = (n < cycles) & (np.abs(at - t[np.round(n)]) > 1e-9 * (t[1] - t[0]))
        inside &= np.abs(at - t[np.minimum(n + 1, cycles)]) > 1e-9 * (t[1] - t[0])
        counts.append(np.bincount(n[inside], minlength=cycles))
    return np.nonzero(np.any(np.diff(np.array(counts), axis=1) != 0, axis=0))[0] + 1


def test_envelope_follows_the_direct_run_cycle_by_cycle(both):
    scene, env, omega, t, switches, _ = both
    err = np.abs(env.column("omega") - omega) / omega
    assert err.max() <= AGREE, (err.max(), int(err.argmax()))
    assert env.cycles_integrated < CYCLES  # (both integrations, the estimate's included)
    # a resolved cycle is one cycle of the map from its start, to the stepper's tolerance
    # (the state it starts from is the envelope's, within the envelope's error)
    phi = CycleMap(scene)
    resolved = np.nonzero(env.integrated[:-1])[0]
    for n in resolved[np.linspace(0, resolved.size - 1, 8).astype(int)]:
        start = env.states[n]
        end = phi(start[:-1], float(start[-1]))
        assert end[0] == pytest.approx(env.states[n + 1, 0], rel=100 * RTOL), n
        assert start[-1] + phi.elapsed == pytest.approx(env.states[n + 1, -1], rel=100 * RTOL)


def test_cycles_are_resolved_at_the_start_corners_and_switches_only(both):
    scene, env, omega, t, switches, case = both
    resolved = np.nonzero(env.integrated)[0]
    assert np.all(env.integrated[:CORNER_CYCLES])
    assert np.all(env.integrated[switches]), switches[~env.integrated[switches]]
    corners = np.searchsorted(t, scene.load.schedule_time, side="right") - 1
    marks = np.concatenate(([0], corners, switches))
    # (a stretch shorter than a macro segment's least is resolved whole)
    near = np.abs(resolved[:, None] - marks[None, :]).min(axis=1) <= MIN_MACRO + CORNER_CYCLES
    assert np.all(near) or case in STIFF, resolved[~near]


def test_error_estimate_bounds_the_measured_error(both):
    _, env, omega, t, _, _ = both
    # (the estimate is the envelope's error: the cycles' own, at the stepper's tolerance, is
    # all that is left where the run has settled, as the governed one has)
    floor = 10 * RTOL
    measured_omega = abs(env.column("omega")[-1] - omega[-1])
    measured_t = abs(env.column("t")[-1] - t[-1])
    assert measured_omega <= env.error[env.names.index("omega")] + floor * omega[-1]
    assert measured_t <= env.error[env.names.index("t")] + floor * t[-1]


def test_schedule_corners_fall_in_the_direct_run_cycles(both):
    scene, env, omega, t, _, _ = both
    for corner in scene.load.schedule_time:
        ours = int(np.searchsorted(env.column("t"), corner)) - 1
        theirs = int(np.searchsorted(t, corner)) - 1
        assert ours == theirs, (corner, ours, theirs)
        assert env.integrated[ours]  # (the cycle holding a corner is integrated)


def test_refuses_what_the_envelope_cannot_follow():
    sc = transient.load_scene(CASE)
    with pytest.raises(SceneError, match="cycles"):
        multirevolution(sc, 0)
    with pytest.raises(SceneError, match="rtol"):
        multirevolution(sc, 10, rtol=2.0)
    started = dataclasses.replace(sc, starter=dataclasses.replace(
        sc.starter, torque=50.0, cutout_speed=2 * sc.initial.omega))
    with pytest.raises(SceneError, match="starter"):
        multirevolution(started, 10)
    revs = dataclasses.replace(sc, load=dataclasses.replace(
        sc.load, schedule_revolutions=(0.0, 100.0), schedule_scale=(1.0, 1.2)))
    with pytest.raises(SceneError, match="schedule_revolutions"):
        multirevolution(revs, 10)
