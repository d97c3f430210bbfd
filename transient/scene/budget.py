"""Bounded work: what a run will write and how many steps its limits imply, estimated from the
scene before any integration and held against the run's budgets (``[run] max_output_bytes``,
``max_steps``), so that a mistyped end, spacing or limit is one line instead of a full disk or a
run that never ends.

The estimates are lower bounds wherever the speed the run will reach is unknown: a dynamic run in
crank angle turns at least at the switch speed ω_s, and in time below 1.5 ω_s (the stepper's
hysteresis), so it writes at least ``min(ω_s·n/(2π), 1/Δt)`` samples a second and
``min(n, 2π/(1.5 ω_s Δt))`` a revolution (n samples a revolution, Δt the time-domain spacing);
a refusal on these bounds is never wrong. The steps are counted at the least speed of the crank
angle domain, the resolution of the shaft angle at the largest angle the run reaches.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from .records import MIN_OUTPUT_DT, Scene

#: Bytes of one stored value (float64, before compression).
VALUE_BYTES = 8
#: The smallest ``rtol`` a double can honour: a step's round-off is a few ε, and the error
#: estimate of an embedded pair cannot resolve less; scipy's ``solve_ivp`` raises rtol to the
#: same 100 ε.
RTOL_MIN = 100.0 * float(np.finfo(float).eps)
#: An angle increment (output spacing, step limit) must span this many units in the last place
#: of the shaft angle: coarser, samples and steps stop advancing (φ + Δφ = φ).
ANGLE_RESOLUTION_ULPS = 1e4
#: Arrays of the order analysis per signal and cycle, besides the signal itself (its grid, t, ω).
ORDERS_GRID_ARRAYS = 3
#: Arrays of the loads analysis per cylinder over its grid (forces, pin loads, torques).
LOADS_GRID_ARRAYS = 20


@dataclass(frozen=True)
class Work:
    """What a run will do, estimated before it starts: ``samples`` written [1], ``bytes`` of
    trajectory [bytes], ``steps`` its step limits imply [1], ``analysis_bytes`` of the
    ``[analysis]`` grid [bytes], and the largest shaft angle it reaches ``phi_max`` [rad]."""

    samples: float
    bytes: float
    steps: float
    analysis_bytes: float
    phi_max: float


def time_spacing(scene: Scene) -> float:
    """The time-domain sample spacing [s]: ``output.dt``, or the angle spacing at 1.5 ω_s (the
    speed above which the run returns to crank angle)."""
    if scene.output.dt > 0.0:
        return scene.output.dt
    return angle_spacing(scene) / (1.5 * scene.solver.switch_speed)


def angle_spacing(scene: Scene) -> float:
    """The crank-angle sample spacing [rad]."""
    return 2.0 * math.pi / scene.output.samples_per_rev


def estimate(scene: Scene) -> Work:
    """The work of a run of ``scene`` (:class:`Work`)."""
    from .outputs import output_columns

    run = scene.run
    turns = _revolutions(scene)
    if run.mode == "prescribed-speed":
        samples = 2.0 + turns * scene.output.samples_per_rev
        steps = samples
    else:
        # (a multirevolution run integrates and writes some of its cycles only: at least its
        # first and its last)
        counted = min(turns, scene.mechanism.cycle / math.pi) if (
            scene.solver.multirevolution) else turns
        per_s, per_rev = _sample_rates(scene)
        samples = 1.0 + min(_times(run.t_end, per_s), _times(counted, per_rev))
        steps = _steps(scene, counted)
    phi_end = abs(scene.initial.phi) + 2.0 * math.pi * turns
    return Work(samples=samples, bytes=samples * len(output_columns(scene)) * VALUE_BYTES,
                steps=steps, analysis_bytes=_analysis_bytes(scene),
                phi_max=phi_end if math.isfinite(phi_end) else abs(scene.initial.phi))


def _times(a: float, b: float) -> float:
    """a·b, where an unset bound (inf) times a rate of 0 stays unbounded (inf)."""
    return math.inf if math.isinf(a) else a * b


def _revolutions(scene: Scene) -> float:
    """The revolutions the run ends by: ``run.revolutions``, or for a prescribed speed the
    fewer of those and what the speed turns by ``t_end`` (inf: ends by time only)."""
    run = scene.run
    if run.mode != "prescribed-speed":
        return run.revolutions
    if run.time:
        t = np.asarray(run.time)
        w = np.asarray(run.speed_table)
        keep = t <= run.t_end
        angle = float(np.sum(np.diff(t[keep]) * (w[keep][1:] + w[keep][:-1]) / 2.0))
    else:
        angle = run.speed * run.t_end
    return min(run.revolutions, angle / (2.0 * math.pi))


def _sample_rates(scene: Scene) -> tuple[float, float]:
    """Least samples a second and a revolution of a dynamic run (module docstring)."""
    spr, ws = scene.output.samples_per_rev, scene.solver.switch_speed
    dt = time_spacing(scene)
    if scene.solver.domain == "time":  # (no speed bounds the time domain's angle per sample)
        return 1.0 / dt, 0.0
    return min(ws * spr / (2.0 * math.pi), 1.0 / dt), min(spr, 2.0 * math.pi / (1.5 * ws * dt))


def _steps(scene: Scene, turns: float) -> float:
    """Least steps the limits imply (``max_step``, ``fixed_step``) in the crank-angle domain
    over ``turns`` revolutions."""
    sv, run = scene.solver, scene.run
    if sv.domain == "time":
        return 0.0
    h = sv.fixed_step if sv.fixed_step > 0.0 else sv.max_step
    angle = min(2.0 * math.pi * turns, _times(run.t_end, sv.switch_speed))
    return angle / h


def _analysis_bytes(scene: Scene) -> float:
    """Bytes of the ``[analysis]`` grid over one cycle (the least any run holds)."""
    a = scene.analysis
    arrays = (len(a.orders) + ORDERS_GRID_ARRAYS if a.orders else 0) + (
        LOADS_GRID_ARRAYS * scene.mechanism.n_cylinders if a.loads else 0)
    return float(a.samples_per_cycle) * arrays * VALUE_BYTES


def check_work(scene: Scene) -> None:
    """Refuse, naming the key, a scene whose run cannot be done within its budgets or cannot
    advance: an unreachable tolerance, a time-domain spacing below
    :data:`~transient.scene.records.MIN_OUTPUT_DT`, output
    or an analysis grid beyond ``run.max_output_bytes``, steps beyond ``run.max_steps``, angle
    increments the shaft angle cannot resolve."""
    sv, run = scene.solver, scene.run
    if sv.rtol < RTOL_MIN and run.mode == "dynamic":
        raise SceneError("solver.rtol", f"{sv.rtol:g} is below what double precision can "
                                        f"deliver (100 ε = {RTOL_MIN:.3g}: round-off alone "
                                        f"exceeds it); give rtol ≥ {RTOL_MIN:.3g}")
    if run.mode == "dynamic":
        _check_time_spacing(scene)
    work = estimate(scene)
    budget = run.max_output_bytes
    if work.bytes > budget:
        raise SceneError(_output_key(scene), f"the run would write at least {work.samples:.3g} "
                                             f"samples, {_size(work.bytes)} (run.max_output_bytes "
                                             f"= {_size(budget)}); shorten the run, sample it "
                                             f"more coarsely or raise run.max_output_bytes")
    if work.analysis_bytes > budget:
        raise SceneError("analysis.samples_per_cycle",
                         f"{scene.analysis.samples_per_cycle} samples a cycle need at least "
                         f"{_size(work.analysis_bytes)} for the analysis grid (run.max_output_bytes "
                         f"= {_size(budget)}); give fewer samples_per_cycle")
    if work.steps > run.max_steps:
        key = "solver.fixed_step" if sv.fixed_step > 0.0 else "solver.max_step"
        raise SceneError(key, f"implies at least {work.steps:.3g} steps (run.max_steps = "
                              f"{run.max_steps:.3g}); give a larger step or raise run.max_steps")
    _check_resolution(scene, work.phi_max)


def _output_key(scene: Scene) -> str:
    """The key that sets how long a run is: the end the estimate counted by."""
    run = scene.run
    if math.isfinite(run.revolutions) and run.mode == "dynamic":
        return "run.revolutions"
    return "run.t_end" if math.isfinite(run.t_end) else "run.revolutions"


def _check_time_spacing(scene: Scene) -> None:
    """The time-domain spacing a switch speed implies is held to the bound of ``output.dt``."""
    if scene.output.dt > 0.0:
        return
    dt = time_spacing(scene)
    if dt < MIN_OUTPUT_DT:
        most = angle_spacing(scene) / (1.5 * MIN_OUTPUT_DT)
        raise SceneError("solver.switch_speed", f"makes the time-domain sample spacing "
                                                f"Δφ/(1.5 ω_s) = {dt:.3g} s, below "
                                                f"{MIN_OUTPUT_DT:g} s; give switch_speed ≤ "
                                                f"{most:.3g} rad/s, or output.dt")


def _check_resolution(scene: Scene, phi_max: float) -> None:
    """Every angle increment spans :data:`ANGLE_RESOLUTION_ULPS` of the largest shaft angle."""
    sv = scene.solver
    increments = {"output.samples_per_rev": angle_spacing(scene), "solver.max_step": sv.max_step}
    if sv.fixed_step > 0.0:
        increments["solver.fixed_step"] = sv.fixed_step
    key, smallest = min(increments.items(), key=lambda kv: kv[1])
    if ANGLE_RESOLUTION_ULPS * _ulp(abs(scene.initial.phi)) > smallest:
        most = smallest / ANGLE_RESOLUTION_ULPS / np.finfo(float).eps
        raise SceneError("initial.phi", f"{scene.initial.phi:g} rad: a double there resolves "
                                        f"only {_ulp(scene.initial.phi):.3g} rad, too coarse for "
                                        f"the increment {smallest:.3g} rad of {key} (the run "
                                        f"would not advance); give |phi| ≤ {most:.3g} rad")
    if ANGLE_RESOLUTION_ULPS * _ulp(phi_max) > smallest:
        raise SceneError(key, f"{smallest:.3g} rad is finer than the shaft angle resolves at "
                              f"φ = {phi_max:.3g} rad ({_ulp(phi_max):.3g} rad), where the run "
                              f"ends (the run would not advance); give a coarser value or a "
                              f"shorter run")


def _ulp(x: float) -> float:
    """The spacing of doubles at ``x``."""
    return float(np.spacing(abs(x)))


def _size(n: float) -> str:
    """A byte count in words, e.g. ``4 GB``."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.3g} bytes"
