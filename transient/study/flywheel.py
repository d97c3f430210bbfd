"""Flywheel sizing: the flywheel inertia that gives a target coefficient of speed irregularity δ
at a steady operating point (Gots §2.8), first in closed form, then refined by simulation.

**Closed form.** In crank angle, (18) is an energy balance: with K = ½J(φ)ω²,
dK/dφ = Jε + ½J′ω² = M_gas + M_load. Write J = J̄ + j(φ) (J̄ the cycle mean) and ω = ω_m(1 + u),
u small. To first order in u and j/J̄,

    J̄ ω_m² u(φ) = ∫(M_gas + M_load − ½J′ω_m²) dφ + const = E(φ) + const,

so the constant-inertia part J̄ sees the *engine torque* M_e = M_gas + M_load − ½J′ω_m² (the gas
torque plus the inertia torque of the mechanism at constant speed, less the load): exactly minus
the drive torque of an inverse-dynamics run at constant ω_m (:func:`transient.run.prescribed`,
M_drive = Jε + ½J′ω² − M at ε = 0; with non-ideal pairs their losses are in it too). In steady
state the mean of M_e over the cycle is zero (the load absorbs the mean indicated torque), the
excess work is ΔE_max = max E − min E over the cycle, and

    δ = (ω_max − ω_min)/ω_m ≈ ΔE_max / (J̄ ω_m²)    ⇒    J̄ = ΔE_max / (δ ω_m²)

(Gots §2.8). The flywheel is J̄ less the mean over the cycle of the rest (mechanism, shaft, load
inertias): J_fly = J̄ − (J̄_scene − J_fly,scene).

**Refinement.** The closed form neglects the products of u and j/J̄, the change of the load torque
with ω within the cycle, and the difference between the cycle-mean speed and ω_m. So the scene is
run (dynamic, its own gas model, load and solver) with the estimated flywheel to steady state,
δ is measured over the last cycle (:func:`~transient.analysis.irregularity.fluctuation`), and the
flywheel corrected by the secant method on log δ against log J̄ (a straight line of slope −1 in the
closed form; the first correction uses that slope) until |δ/δ_target − 1| ≤ ``rtol``.

Each run starts at the operating point's own speed at the initial angle (the closed-form
ω(φ₀) = √(2(K₀ + E(φ₀))/J(φ₀)), K₀ set so that the cycle-mean speed is ω_m), so that the start-up
transient is small; it runs for ``settle`` time constants τ = J̄/(−dM/dω) of the load–engine
balance (at least ``min_cycles`` cycles), and the δ of the last cycle is compared with the one
before it (``delta_change`` in each iteration, the steady-state check).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import brentq

from ..analysis.irregularity import cycle_boundaries, cycle_means
from ..outcome import FINISHED

#: Samples per revolution of the constant-speed (inverse-dynamics) analysis: the excess work is a
#: trapezoidal integral over them (0.05°; the gas torque has corners at valve events and firing).
PRESCRIBED_SAMPLES = 7200
#: Samples per revolution of the dynamic runs, on which ω_max and ω_min are read (0.5°: the
#: sampled extremum is within ~1e-5 of the amplitude of the 1.5th order of a 3-cylinder 4-stroke).
DYNAMIC_SAMPLES = 720


@dataclass(frozen=True)
class FlywheelIteration:
    """One simulation of the refinement: the flywheel inertia run [kg m²], the δ measured over the
    last cycle [1], the δ of the cycle before it (steady-state check) and the last cycle's mean
    speed [rad/s]."""

    flywheel: float
    delta: float
    delta_previous_cycle: float
    mean_speed: float

    @property
    def delta_change(self) -> float:
        """|δ(last cycle)/δ(cycle before) − 1|: how far from steady state the run ended."""
        return abs(self.delta / self.delta_previous_cycle - 1.0)


@dataclass(frozen=True)
class FlywheelResult:
    """What :func:`flywheel_for_delta` found.

    ``flywheel`` [kg m²]: the refined flywheel inertia (the last iteration's when not
    ``converged``); ``estimate``: the closed form of Gots §2.8, ΔE_max/(δ ω_m²) − J̄_rest;
    ``speed`` [rad/s]: the operating speed ω_m; ``excess_work`` [J]: ΔE_max at ω_m;
    ``inertia_rest`` [kg m²]: the cycle mean of J(φ) without the flywheel; ``load``: the load used
    (the scene's, or the one passed, with its constant torque offset when ``speed`` was given);
    ``iterations``: the simulations, the first with ``estimate``, the last with ``flywheel``.
    """

    delta_target: float
    flywheel: float
    estimate: float
    speed: float
    excess_work: float
    inertia_rest: float
    load: object
    iterations: tuple[FlywheelIteration, ...]
    converged: bool

    @property
    def delta(self) -> float:
        """δ measured with ``flywheel``."""
        return self.iterations[-1].delta

    def closed_form_delta(self, flywheel: float | None = None) -> float:
        """δ the closed form predicts with ``flywheel`` (default: the refined one),
        ΔE_max/((J̄_rest + J_fly) ω_m²)."""
        fly = self.flywheel if flywheel is None else flywheel
        return self.excess_work / ((self.inertia_rest + fly) * self.speed ** 2)


def _constant_speed(scene, speed: float, samples: int):
    """Inverse dynamics over one engine cycle at constant ``speed``: (φ, M_e, J) with
    M_e = −M_drive the engine torque on the constant-inertia part (module docstring)."""
    from ..run import prescribed
    from ..scene import Run

    cycle = scene.mechanism.cycle
    s = replace(scene, run=Run(mode="prescribed-speed", speed=speed,
                               revolutions=cycle / (2.0 * math.pi)),
                output=replace(scene.output, samples_per_rev=samples))
    tr = prescribed(s).trajectory
    phi = tr["phi"]
    if phi[-1] - phi[0] < cycle * (1.0 - 1e-9):
        raise ValueError(f"the constant-speed analysis at {speed:g} rad/s did not cover a cycle")
    return phi, -tr["M_drive"], tr["J"]


def _mean(phi, f) -> float:
    return float(np.trapezoid(f, phi) / (phi[-1] - phi[0]))


def _residual(scene, speed: float) -> float:
    """Cycle-mean engine torque at constant ``speed`` [N m]; > 0: the engine accelerates."""
    phi, m_e, _ = _constant_speed(scene, speed, 720)
    return _mean(phi, m_e)


def _operating_speed(scene, lo: float, hi: float) -> float:
    """The highest stable speed in [lo, hi] at which the cycle-mean torque balances."""
    grid = np.geomspace(lo, hi, 64)
    r = np.array([_residual(scene, w) for w in grid])
    stable = np.nonzero((r[:-1] > 0.0) & (r[1:] <= 0.0))[0]
    if stable.size == 0:
        raise ValueError(f"no steady operating point between {lo:g} and {hi:g} rad/s: the mean "
                         f"engine torque never falls through zero with rising speed against this "
                         f"load; give speed= (or a load that balances the engine)")
    i = stable[-1]
    return float(brentq(lambda w: _residual(scene, w), grid[i], grid[i + 1], xtol=1e-12,
                        rtol=1e-13))


def _excess_work(phi, m_e) -> tuple[float, np.ndarray]:
    """ΔE_max and E(φ) = ∫(M_e − mean M_e) dφ over the cycle."""
    E = cumulative_trapezoid(m_e - _mean(phi, m_e), phi, initial=0.0)
    return float(E.max() - E.min()), E


def _steady_run(scene, flywheel: float, speed: float, phi, E, J_scene, revolutions: float
                ) -> FlywheelIteration:
    """Run ``scene`` with ``flywheel`` from the closed-form speed at its initial angle; δ of the
    last two cycles."""
    from ..run import integrate
    from ..scene import Initial, Run

    cycle, phi0 = scene.mechanism.cycle, scene.initial.phi
    J = J_scene + (flywheel - scene.inertia.flywheel)
    # ½Jω² = K0 + E(φ): K0 such that the cycle mean of ω is ω_m (a few fixed-point steps).
    K0 = 0.5 * _mean(phi, J) * speed ** 2
    for _ in range(4):
        w = np.sqrt(2.0 * (K0 + E) / J)
        K0 *= (speed / _mean(phi, w)) ** 2
    w0 = float(np.sqrt(2.0 * (K0 + np.interp((phi0 - phi[0]) % cycle + phi[0], phi, E))
                       / np.interp((phi0 - phi[0]) % cycle + phi[0], phi, J)))
    s = replace(scene, inertia=replace(scene.inertia, flywheel=flywheel),
                initial=Initial(phi0, w0), run=Run(revolutions=revolutions),
                output=replace(scene.output, samples_per_rev=max(scene.output.samples_per_rev,
                                                                 DYNAMIC_SAMPLES)))
    data = integrate(s)
    if data.status != FINISHED:
        raise RuntimeError(f"the run with flywheel {flywheel:g} kg m² ended {data.status}: "
                           f"{data.message}")
    tr = data.trajectory
    t, ph, om = tr["t"], tr["phi"], tr["omega"]
    tb, _ = cycle_boundaries(t, ph, cycle, phi0)
    if tb.size < 3:
        raise RuntimeError("the run has fewer than two whole cycles")
    deltas = []
    for a, b in ((tb[-2], tb[-1]), (tb[-3], tb[-2])):
        sel = (t >= a) & (t <= b)
        deltas.append(float((om[sel].max() - om[sel].min()) * (b - a) / cycle))
    means, _ = cycle_means(t, ph, cycle, phi0)
    return FlywheelIteration(flywheel, deltas[0], deltas[1], float(means[-1]))


def flywheel_for_delta(scene, delta_target: float, speed: float | None = None, load=None, *,
                       rtol: float = 0.01, max_iter: int = 8, settle: float = 8.0,
                       min_cycles: int = 6, max_cycles: int = 5000,
                       speed_range: tuple[float, float] = (1.0, 3000.0)
                       ) -> FlywheelResult:
    """The flywheel inertia [kg m²] for which the steady motion of ``scene`` has the coefficient of
    speed irregularity ``delta_target`` = (ω_max − ω_min)/ω_mean over a cycle (Gots §2.8).

    The operating point is where the cycle-mean engine torque at constant speed balances the load
    (``scene.load``, or ``load``): ``speed=None`` takes the highest stable such speed within
    ``speed_range`` [rad/s]; a given ``speed`` [rad/s] offsets the load's constant torque so that
    it balances there (the load must still fall with speed faster than the engine torque, or the
    point is not stable). The starter is left out (the starter of a spin-up scene is cut out long
    before steady state).

    Closed-form estimate, then simulation runs refining it until
    |δ/δ_target − 1| ≤ ``rtol`` or ``max_iter`` runs (``converged`` says which; see the module
    docstring). ``settle``: length of each run in time constants of the speed balance, at least
    ``min_cycles`` and at most ``max_cycles`` engine cycles (more is a ValueError: the load holds
    the speed too loosely for a steady state to be reached).

    Raises ValueError for a δ_target outside (0, 0.5), a bad speed, a scheduled load, a scene that
    is not dynamic, no operating point, or a target that the scene meets without any flywheel.
    """
    from ..scene import Load, Starter

    if not (isinstance(delta_target, (int, float)) and 0.0 < delta_target < 0.5):
        raise ValueError(f"delta_target must be in (0, 0.5), got {delta_target!r}")
    if speed is not None and not (math.isfinite(speed) and speed > 0.0):
        raise ValueError(f"speed must be a finite positive angular speed [rad/s], got {speed!r}")
    if (not 0.0 < rtol < 0.5 or max_iter < 1 or settle <= 0.0
            or not 3 <= min_cycles <= max_cycles):
        raise ValueError("need 0 < rtol < 0.5, max_iter ≥ 1, settle > 0 and "
                         "3 ≤ min_cycles ≤ max_cycles")
    if scene.run.mode != "dynamic":
        raise ValueError("the scene must be a dynamic one (run.mode = 'dynamic'): the refinement "
                         "integrates it")
    if load is not None and not isinstance(load, Load):
        raise ValueError(f"load must be a transient.scene.Load, got {type(load).__name__}")
    load = scene.load if load is None else load
    if load.schedule_scale:
        raise ValueError("a scheduled load has no steady operating point: pass load= without a "
                         "schedule")
    base = replace(scene, load=load, starter=Starter())
    if speed is None:
        speed = _operating_speed(base, *speed_range)
    else:
        base = replace(base, load=replace(load, torque=load.torque + _residual(base, speed)))
    phi, m_e, J_scene = _constant_speed(base, speed, PRESCRIBED_SAMPLES)
    dE, E = _excess_work(phi, m_e)
    h = 1e-3 * speed
    slope = (_residual(base, speed + h) - _residual(base, speed - h)) / (2.0 * h)
    # Stable means the mean torque falls with speed by more than round-off: a relative change of
    # 1e-6 of the torque swing per relative change of speed at least.
    swing = float(m_e.max() - m_e.min())
    if not slope * speed < -1e-6 * swing:
        raise ValueError(f"the operating point at {speed:g} rad/s is not stable: the mean torque "
                         f"does not fall with speed (dM/dω = {slope:g} N m s); the load needs a "
                         f"speed-dependent part")
    J_rest = _mean(phi, J_scene) - base.inertia.flywheel
    J_total = dE / (delta_target * speed ** 2)
    estimate = J_total - J_rest
    if estimate <= 0.0:
        raise ValueError(f"δ without a flywheel is already ≈ {dE / (J_rest * speed ** 2):.4g} "
                         f"≤ δ_target = {delta_target:g}")

    cycle_time = base.mechanism.cycle / speed
    iterations: list[FlywheelIteration] = []
    prev: tuple[float, float] | None = None  # (x, y) of the previous iteration
    fly = estimate
    for _ in range(max_iter):
        tau = (J_rest + fly) / -slope
        cycles = max(min_cycles, math.ceil(settle * tau / cycle_time) + 2)
        if cycles > max_cycles:
            raise ValueError(f"reaching steady state would take {cycles} cycles (τ = {tau:.3g} s "
                             f"of the speed balance, dM/dω = {slope:g} N m s) > max_cycles = "
                             f"{max_cycles}")
        revs = cycles * base.mechanism.cycle / (2.0 * math.pi)
        it = _steady_run(base, fly, speed, phi, E, J_scene, revs)
        iterations.append(it)
        if abs(it.delta / delta_target - 1.0) <= rtol:
            return FlywheelResult(delta_target, fly, estimate, speed, dE, J_rest, base.load,
                                  tuple(iterations), True)
        x, y = math.log(J_rest + fly), math.log(it.delta)
        k = -1.0 if prev is None or x == prev[0] else (y - prev[1]) / (x - prev[0])
        if not k < 0.0:
            k = -1.0
        prev = x, y
        x_new = x + (math.log(delta_target) - y) / k
        fly = max(math.exp(x_new) - J_rest, 0.5 * fly)  # J_fly stays positive
    return FlywheelResult(delta_target, iterations[-1].flywheel, estimate, speed, dE, J_rest,
                          base.load, tuple(iterations), False)
