"""Multirevolution steps on the cycle map (transient.multirev) against the direct run of the
same scene, cycle by cycle: the envelope's states at every cycle start, its error estimate
against the error measured, and a load schedule's corners falling in the same cycles."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import transient
from transient.errors import SceneError
from transient.multirev import multirevolution
from transient.verify.steady import cycle_starts, cycles_of

CASE = "cases/gots_diesel_friction.toml"
#: The scene's stepper tolerance: so tight that the two runs differ by the envelope's error
#: (the map's own, the stepper's, which the direct run shares, is no part of the estimate).
RTOL = 1e-12
#: The acceptance's agreement in ω, relative.
AGREE = 1e-6
CYCLES = 4000


def _scene(flywheel: float, omega: float, schedule=((), ())):
    sc = transient.load_scene(CASE)
    return dataclasses.replace(
        sc, inertia=dataclasses.replace(sc.inertia, flywheel=flywheel * sc.inertia.flywheel),
        initial=dataclasses.replace(sc.initial, omega=omega),
        solver=dataclasses.replace(sc.solver, rtol=RTOL, atol=RTOL * 1e-2),
        output=dataclasses.replace(sc.output, samples_per_rev=4),
        load=dataclasses.replace(sc.load, schedule_time=schedule[0],
                                 schedule_scale=schedule[1]))


#: The diesel with a flywheel ×100 near its running speed, its load stepped up at 5 s, ramped
#: and stepped down at 60 s and 90 s: an envelope that changes slowly between the corners; and
#: with a flywheel ×300 from 1000 rpm, a spin-up to its running speed over the run.
SCENES = {"load programme": (100.0, 440.0, ((5.0, 60.0, 90.0), (1.0, 1.25, 0.8))),
          "spin-up": (300.0, 104.71975511965977)}


@pytest.fixture(scope="module", params=list(SCENES))
def both(request):
    scene = _scene(*SCENES[request.param])
    env = multirevolution(scene, CYCLES)
    direct = transient.simulate(cycles_of(scene, CYCLES)).trajectory
    starts = cycle_starts(scene, direct, CYCLES)
    return scene, env, np.asarray(direct["omega"])[starts], np.asarray(direct["t"])[starts]


def test_envelope_follows_the_direct_run_cycle_by_cycle(both):
    scene, env, omega, t = both
    err = np.abs(env.column("omega") - omega) / omega
    assert err.max() <= AGREE, (err.max(), int(err.argmax()))
    assert env.cycles_integrated < CYCLES  # (both integrations, the estimate's included)
    # the resolved cycles are the direct run's to the stepper's tolerance
    resolved = env.integrated
    assert resolved.any() == bool(scene.load.schedule_time)  # (at the corners only)
    assert np.all(np.abs(env.column("omega")[resolved] - omega[resolved])
                  <= 1e-8 * omega.max())


def test_error_estimate_bounds_the_measured_error(both):
    _, env, omega, t = both
    measured_omega = abs(env.column("omega")[-1] - omega[-1])
    measured_t = abs(env.column("t")[-1] - t[-1])
    assert measured_omega <= env.error[env.names.index("omega")], measured_omega
    assert measured_t <= env.error[env.names.index("t")], measured_t


def test_schedule_corners_fall_in_the_direct_run_cycles(both):
    scene, env, omega, t = both
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
