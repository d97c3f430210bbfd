"""Load schedules and the generator load: the [load] keys, their validation, and
the compiled schedule and load moment against plain numpy.

* Parsing: SI values and unit suffixes, the resolved TOML round trip, and every validation error
  as one line ``file: key: message`` with exit code 2 (``transient check``).
* The schedule function s(x) of the kernel (``model.load_segment`` + ``model.load_scale``)
  against ``numpy.interp`` at many points and exactly on every corner: a step takes the value
  after it in the direction of motion (``numpy.interp`` is right-continuous at a repeated
  abscissa, checked here too; the falling side is ``numpy.interp`` of the mirrored table).
* The load moment of ``model.moments``: without a schedule and generator bit-for-bit the
  formula −(torque + linear·ω + fan·ω|ω|) of the scenes before schedules; with them
  −s·(… + P/max(ω, ω_min)).
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from scene_texts import SMALL, check_text

from transient.assemble import build_model
from transient.core.model import forcing, layout, work
from transient.scene import Load, load_scene, scene_from_dict, to_toml

# the small scene from 30°, with the default output
BASE = SMALL.replace("omega_rpm = 1000\n", "omega_rpm = 1000\nphi_deg = 30\n").replace(
    "\n[output]\nsamples_per_rev = 12\n", "")


def with_load(lines: str, extra: str = "") -> str:
    return BASE + "\n[load]\n" + lines + "\n" + extra


def scene_of(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    return load_scene(path)


# ------------------------------------------------------------------------------------------------
# Parsing


def test_default_load_has_no_schedule_and_no_generator(tmp_path):
    load = scene_of(tmp_path, BASE).load
    assert load == Load()
    assert (load.generator_power, load.schedule_time, load.schedule_revolutions,
            load.schedule_scale) == (0.0, (), (), ())


def test_keys_are_read_in_si(tmp_path):
    load = scene_of(tmp_path, with_load(
        "torque = 5\nlinear = 0.1\nfan = 1e-4\ngenerator_power = 20e3\n"
        "generator_min_speed_rpm = 600\nschedule_time = [0.5, 0.5, 1, 2]\n"
        "schedule_scale = [0, 1, 1, 0.25]")).load
    assert load == Load(5.0, 0.1, 1e-4, 20e3, 600 * math.pi / 30, (0.5, 0.5, 1.0, 2.0), (),
                        (0.0, 1.0, 1.0, 0.25))


@pytest.mark.parametrize("lines", [
    ("generator_power = 1e3\ngenerator_min_speed = 50\nschedule_time = [0, 0.1]\n"
     "schedule_scale = [1, 2]"),
    "fan = 1e-3\nschedule_revolutions = [1, 1, 2]\nschedule_scale = [0, 1, 0.5]",
    "torque = 3",
])
def test_resolved_toml_round_trips(tmp_path, lines):
    scene = scene_of(tmp_path, with_load(lines))
    again = load_scene(tmp_path / "resolved.toml", text=to_toml(scene))
    assert again == scene
    assert to_toml(again) == to_toml(scene)


def test_revolutions_are_angles_from_the_initial_angle(tmp_path):
    scene = scene_of(tmp_path, with_load("schedule_revolutions = [1, 2.5]\n"
                                         "schedule_scale = [1, 0]"))
    m = build_model(scene)[0]
    assert m.load_comp == layout.PHI
    phi0 = math.radians(30)
    assert m.load_x.tolist() == [phi0 + 2 * math.pi * 1.0, phi0 + 2 * math.pi * 2.5]
    assert m.load_s.tolist() == [1.0, 0.0]
    time = build_model(scene_of(tmp_path, with_load("schedule_time = [1, 2.5]\n"
                                                    "schedule_scale = [1, 0]")))[0]
    assert time.load_comp == layout.T and time.load_x.tolist() == [1.0, 2.5]


# ------------------------------------------------------------------------------------------------
# Validation: one line, exit 2, the key and what is wrong

ERRORS = [
    ("lengths-differ", "schedule_time = [0, 1]\nschedule_scale = [1]", "load.schedule_scale",
     "needs as many entries as 'schedule_time'; got 1 and 2"),
    ("decreasing", "schedule_time = [0, 2, 1]\nschedule_scale = [1, 1, 1]", "load.schedule_time",
     "must not decrease, but 1 follows 2 (entry 3)"),
    ("decreasing-revolutions", "schedule_revolutions = [3, 2]\nschedule_scale = [1, 1]",
     "load.schedule_revolutions", "must not decrease, but 2 follows 3"),
    ("three-equal", "schedule_time = [0, 1, 1, 1]\nschedule_scale = [1, 1, 2, 3]",
     "load.schedule_time", "1 appears three times in a row (entries 2 to 4); a step is two equal"),
    ("too-close", "schedule_time = [1, 1.0000000001]\nschedule_scale = [1, 2]",
     "load.schedule_time", "are closer than 1e-09 (relative); give equal entries for a step"),
    ("negative-scale", "schedule_time = [0, 1]\nschedule_scale = [1, -0.5]",
     "load.schedule_scale", "must be ≥ 0, got -0.5 (entry 2)"),
    ("time-and-revolutions",
     "schedule_time = [0, 1]\nschedule_revolutions = [0, 1]\nschedule_scale = [1, 2]",
     "load.schedule_revolutions",
     "given together with 'schedule_time'; a schedule runs against time or against revolutions"),
    ("scale-alone", "schedule_scale = [1, 2]", "load.schedule_scale",
     "has no abscissae; give 'schedule_time' [s] or 'schedule_revolutions'"),
    ("abscissae-alone", "schedule_revolutions = [1, 2]", "load.schedule_revolutions",
     "has no values; give 'schedule_scale'"),
    ("not-numbers", 'schedule_time = [0, "1"]\nschedule_scale = [1, 2]', "load.schedule_time",
     "must be a list of finite numbers"),
    ("not-a-list", "schedule_time = 1\nschedule_scale = [1]", "load.schedule_time",
     "must be a list of finite numbers"),
    ("time-suffix", "schedule_time_ms = [0, 1]\nschedule_scale = [1, 2]", "load.schedule_time_ms",
     "unknown unit suffix '_ms'; give 'schedule_time'"),
    ("negative-power", "generator_power = -1", "load.generator_power", "must be ≥ 0, got -1"),
    ("power-suffix", "generator_power_kW = 20", "load.generator_power_kW",
     "unknown unit suffix '_kW'; give 'generator_power'"),
    ("generator-without-min-speed", "generator_power = 1e3", "load.generator_min_speed",
     "is missing (required with a generator_power, else 0); give 'generator_min_speed' or "
     "'generator_min_speed_rpm'"),
    ("generator-min-speed-zero", "generator_power = 1e3\ngenerator_min_speed_rpm = 0",
     "load.generator_min_speed_rpm", "must be > 0 with a generator_power"),
    ("min-speed-negative", "generator_min_speed = -1", "load.generator_min_speed",
     "must be ≥ 0, got -1"),
    ("unknown-key", "schedule = [0, 1]", "load.schedule",
     ("unknown key; allowed here: fan, generator_min_speed, generator_power, inertia, "
      "inertia_time, linear, schedule_revolutions, schedule_scale, schedule_time, table, torque")),
]


@pytest.mark.parametrize("lines, key, fragment",
                         [pytest.param(t, k, f, id=i) for i, t, k, f in ERRORS])
def test_invalid_load_is_one_line_exit_2(tmp_path, capsys, lines, key, fragment):
    path, code, out, err = check_text(tmp_path, capsys, with_load(lines))
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith(f"{path}: {key}: "), err
    assert fragment in err, err


def test_valid_schedules_pass(tmp_path, capsys):
    """What the rules allow: a step at the first and at the last abscissa, one point, ramps."""
    for lines in ("schedule_time = [0, 0, 1, 2, 2]\nschedule_scale = [0, 1, 1, 3, 0]",
                  "schedule_revolutions = [-1, 5]\nschedule_scale = [0, 0]",
                  "schedule_time = [2]\nschedule_scale = [0.5]",
                  "schedule_time = []\nschedule_scale = []"):
        assert check_text(tmp_path, capsys, with_load(lines))[1] == 0, lines


# ------------------------------------------------------------------------------------------------
# The schedule function against numpy.interp

TABLES = {
    # steps at both ends, ramps up and down, a step between ramps, a flat stretch
    "steps-and-ramps": ([0.0, 0.0, 0.3, 0.5, 0.5, 0.9, 1.2, 1.2, 2.0],
                        [0.2, 1.0, 1.5, 1.5, 0.0, 2.0, 1.0, 0.4, 0.4]),
    "one-ramp": ([1.0, 3.0], [0.0, 1.0]),
    "one-step": ([2.0, 2.0], [1.0, 0.0]),
    "one-point": ([0.7], [0.3]),
    "negative-abscissae": ([-2.0, -1.0, -1.0, 4.0], [3.0, 1.0, 2.0, 0.0]),
}


def load_scene_small():
    return scene_from_dict(tomllib.loads(BASE), file="small.toml")


def schedule_model(x, s, comp):
    base = build_model(load_scene_small())[0]
    return base._replace(load_x=np.asarray(x, dtype=float), load_s=np.asarray(s, dtype=float),
                         load_comp=comp)


def kernel_scale(m, x, rising):
    y = np.zeros(layout.n_state(m))
    y[m.load_comp] = x
    return forcing.load_scale(m, y, forcing.load_segment(m, x, rising))


def test_numpy_interp_takes_the_value_after_a_repeated_abscissa():
    """The reference's own convention, so that the comparison below means what it says."""
    assert np.interp(1.0, [0, 1, 1, 2], [0, 0, 5, 5]) == 5.0
    assert np.interp(-1.0, [-2, -1, -1, 0], [5, 5, 0, 0]) == 0.0


@pytest.mark.parametrize("comp", [layout.T, layout.PHI], ids=["time", "angle"])
@pytest.mark.parametrize("name", list(TABLES))
def test_schedule_matches_numpy_interp(name, comp):
    xp, fp = (np.asarray(v) for v in TABLES[name])
    m = schedule_model(xp, fp, comp)
    rng = np.random.default_rng(7)
    x = np.concatenate([np.linspace(xp[0] - 1.0, xp[-1] + 1.0, 2001),
                        rng.uniform(xp[0] - 0.5, xp[-1] + 0.5, 500), xp,
                        np.nextafter(xp, np.inf), np.nextafter(xp, -np.inf)])
    rising = np.array([kernel_scale(m, v, True) for v in x])
    falling = np.array([kernel_scale(m, v, False) for v in x])
    up = np.interp(x, xp, fp)  # right-continuous: the value after a step, moving up
    down = np.interp(-x, -xp[::-1], fp[::-1])  # the value after a step, moving down
    # the two interpolate the same line from different ends: a few ulp of the scale
    tol = 8.0 * np.finfo(float).eps * max(1.0, float(np.max(fp)))
    assert np.max(np.abs(rising - up)) <= tol
    assert np.max(np.abs(falling - down)) <= tol
    # on the corners themselves exactly the table's values (no rounding through a ramp)
    for v in xp:
        assert kernel_scale(m, v, True) == np.interp(v, xp, fp)
        assert kernel_scale(m, v, False) == np.interp(-v, -xp[::-1], fp[::-1])


def test_steps_differ_by_direction_exactly_on_the_corner():
    """The test above has teeth: on a step the two directions give the two values."""
    xp, fp = TABLES["steps-and-ramps"]
    m = schedule_model(xp, fp, layout.T)
    assert (kernel_scale(m, 0.5, True), kernel_scale(m, 0.5, False)) == (0.0, 1.5)
    assert (kernel_scale(m, 1.2, True), kernel_scale(m, 1.2, False)) == (0.4, 1.0)
    assert (kernel_scale(m, 0.0, True), kernel_scale(m, 0.0, False)) == (1.0, 0.2)


def test_segment_skips_a_step_empty_segment():
    """Two equal corners enclose no segment: the index lands past both, or before both."""
    m = schedule_model([1.0, 2.0, 2.0, 3.0], [0, 1, 2, 3], layout.T)
    assert [forcing.load_segment(m, x, True) for x in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0)] == \
        [0, 1, 1, 3, 3, 4, 4]
    assert [forcing.load_segment(m, x, False) for x in (1.0, 2.0, 3.0)] == [0, 1, 3]


# ------------------------------------------------------------------------------------------------
# The load moment


def moments_load(m, w, seg=0, gen_low=0, x=0.0):
    y = np.zeros(layout.n_state(m))
    y[layout.OMEGA] = w
    y[m.load_comp] = x
    sw = np.zeros(layout.N_SWITCHES, dtype=np.int64)
    sw[layout.SW_LOAD] = seg
    sw[layout.SW_GENERATOR] = gen_low
    return forcing.moments(m, layout.extras_of(m), False, y, 0.0, sw, work.work_array(m), True)[4]


def test_default_load_moment_is_the_formula_bit_for_bit():
    """Scenes without schedule and generator: the model holds no schedule (s ≡ 1) and P = 0, and
    M_load is −(torque + linear·ω + fan·ω|ω|) to the last bit, as before schedules existed."""
    scene = load_scene_small()
    scene = replace(scene, load=Load(torque=7.3, linear=0.0123, fan=3.7e-4))
    m = build_model(scene)[0]
    assert m.load_x.size == 0 and m.load_s.size == 0 and m.gen_power == 0.0
    for w in (0.0, 1e-3, 0.7, 104.72, 523.6, -3.1, -250.0):
        expected = -(7.3 + 0.0123 * w + 3.7e-4 * w * abs(w))
        for seg in (0, 1, 5):  # no schedule: the segment index is irrelevant
            assert moments_load(m, w, seg) == expected


def test_generator_moment():
    """M ω = −s·P above ω_min (to rounding), −s·P/ω_min on the low branch; s from the schedule."""
    scene = replace(load_scene_small(), load=Load(torque=2.0, generator_power=15e3,
                                                  generator_min_speed=50.0,
                                                  schedule_time=(1.0, 2.0),
                                                  schedule_scale=(0.5, 1.5)))
    m = build_model(scene)[0]
    for w in (50.0, 60.0, 300.0, 1000.0):
        M = moments_load(m, w, seg=0)  # s = 0.5 before the first corner
        assert M * w == pytest.approx(-0.5 * (2.0 * w + 15e3), rel=1e-15, abs=0)
    for w in (0.0, 10.0, 49.9, -20.0):
        assert moments_load(m, w, seg=0, gen_low=1) == -0.5 * (2.0 + 15e3 / 50.0)
    # mid-ramp: s = 0.5 + (1.5 − 0.5)·0.25
    assert moments_load(m, 100.0, seg=1, x=1.25) == pytest.approx(-0.75 * (2.0 + 150.0),
                                                                  rel=1e-15)
    branch = forcing.generator_branch
    assert branch(m, 49.0, True) == 1 and branch(m, 51.0, False) == 0
    assert branch(m, 50.0, True) == 0 and branch(m, 50.0, False) == 1


@pytest.mark.parametrize("abscissa", ["time", "revolutions"])
def test_prescribed_speed_follows_the_schedule(abscissa):
    """Inverse dynamics (``model.inverse_dynamics``) at a constant 100 rad/s: every sample's load
    is −s·(torque + P/ω) with s from ``numpy.interp`` of the schedule at the sample's t (or
    revolutions since the start), a step taking its value after (the motion is forward)."""
    xp, fp = [0.01, 0.01, 0.03, 0.05], [1.0, 2.0, 3.0, 0.5]
    if abscissa == "time":
        sched = {"schedule_time": tuple(xp), "schedule_scale": tuple(fp)}
    else:  # the same corners in revolutions: at 100 rad/s, t = 2π·rev/100
        xp = [100.0 * x / (2 * math.pi) for x in xp]
        sched = {"schedule_revolutions": tuple(xp), "schedule_scale": tuple(fp)}
    base = load_scene_small()
    scene = replace(base, load=Load(torque=1.0, generator_power=100.0, generator_min_speed=10.0,
                                    **sched),
                    run=replace(base.run, mode="prescribed-speed", speed=100.0, revolutions=1.5))
    from transient.run import integrate

    tr = integrate(scene).trajectory
    x = tr["t"] if abscissa == "time" else (tr["phi"] - scene.initial.phi) / (2 * math.pi)
    s = np.interp(x, xp, fp)
    assert np.ptp(s) > 2.0  # samples on every stretch of the schedule
    np.testing.assert_allclose(tr["M_load"], -s * (1.0 + 100.0 / 100.0), rtol=1e-13, atol=0)
