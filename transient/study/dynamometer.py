"""An operating point on a dynamometer: the periodic steady state of a dynamic scene at a held
mean speed and fuel (docs/guide/steady.md, "Operating maps").

A dynamometer holds the engine's *mean* speed while the crankshaft still speeds up and slows
down within the cycle, against the real inertias. Here the engine runs at a fixed fuel (the
scene's governor left out, as the efficiency study holds it: a governor would set the fuel from
the speed) against a brake of constant torque T, the scene's own load taken off: the engine on
the bench. T is the one level at which the steady cycle's mean speed is the requested ω̄.

The unknowns are the periodic states at the cycle's start x (:class:`~transient.run.CycleMap`)
and T; the equations are the cycle map's Φ(x; T) − x = 0 and the cycle's time-mean speed
(the cycle over its duration: what a revolution counter reads) ω̄(x; T) − ω̄* = 0. Newton's
method on both at once, not an iteration on T around a shooting at each T: under a constant
brake torque the steady speed hangs on T by the slope of the friction and gas work against
speed alone, weak for an engine (the multiplier of the speed is close to 1), so the steady ω̄
moves far for a small change of T and an outer iteration would shoot many times; with T an
unknown beside x the system is well conditioned wherever the brake holds the speed, as the
dynamometer's controller makes it. T starts from the energy balance of a first cycle without a
brake (W_gas − losses = T·cycle in steady state); the derivative in T is then that first
cycle's secant, the one in x by differences (a cycle per state), and it is kept, updated by
Broyden's formula, while its steps converge. A point where T comes out negative has no steady
state under a brake: the fuel's work does not cover the friction at that speed (the bench
would have to motor the engine).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..analysis.efficiency import mechanical_efficiency
from ..analysis.irregularity import fluctuation
from ..errors import SimulationError
from ..results import Result
from ..run import CycleMap
from ..scene import Cylinder, Governor, Load, Output, Scene
from ..shooting import (
    MAX_HALVINGS,
    MAX_ITERATIONS,
    NOISE_FLOOR,
    STALLED_ITERATIONS,
    TOLERANCE,
    _speed_limited,
    cycles_from,
    refuse_nonperiodic,
)

#: A Broyden-updated derivative is kept while its step reduced the residual this much.
CHORD_RATE = 0.5


class NoOperatingPoint(SimulationError):
    """The point has no steady state under a brake (the fuel's work does not cover the friction
    at that speed, or a cycle stalled), or Newton found none: the message says which."""


@dataclass
class HeldPoint:
    """A dynamometer point: the requested time-mean speed ω̄ [rad/s] and fuel [1], the brake
    torque T [N m] that holds it, the scene on the bench with that brake, its steady cycle (a
    :class:`~transient.Result` of one cycle with its analysis), the residual at each iterate
    (in units of the solver's error weight) and the cycles integrated (the output cycle
    included)."""

    omega: float
    fuel: float
    brake_torque: float
    scene: Scene
    result: Result
    residuals: list[float]
    cycles: int


def bench_scene(scene, omega: float, fuel: float, samples_per_rev: int | None = None):
    """``scene`` on the bench: its governor left out, every cylinder at ``fuel`` times its own
    fuel factor (p = p_mot + fuel·φ_k·(p_full − p_mot), as the study's prescribed speed sets it),
    its load replaced by a brake of zero torque (set per cycle), starting at ``omega``."""
    gas = scene.gas
    if fuel != 1.0:
        given = {c.cylinder: c for c in gas.cylinders}
        cylinders = tuple(
            dataclasses.replace(given[k], fuel=given[k].fuel * fuel) if k in given
            else Cylinder(cylinder=k, fuel=fuel)
            for k in range(1, scene.mechanism.n_cylinders + 1))
        gas = dataclasses.replace(gas, cylinders=cylinders)
    output = scene.output if samples_per_rev is None else Output(samples_per_rev=samples_per_rev)
    return dataclasses.replace(scene, gas=gas, governor=Governor(), load=Load(), output=output,
                               initial=dataclasses.replace(scene.initial, omega=omega))


def held_point(scene, omega: float, fuel: float = 1.0, samples_per_rev: int | None = None
               ) -> HeldPoint:
    """The steady cycle of ``scene`` at the time-mean speed ``omega`` [rad/s] and ``fuel``
    held by a brake of constant torque (module docstring). Raises :class:`NoOperatingPoint`
    with the reason where there is none, a SceneError where the scene cannot be periodic."""
    bench = bench_scene(scene, omega, fuel, samples_per_rev)
    refuse_nonperiodic(bench)
    phi = CycleMap(bench)
    held = _solve(bench, phi, omega)
    x, T, residuals = held
    braked = dataclasses.replace(bench, load=Load(torque=T))
    analysis = {"brake_torque": (T, "N m"), "steady_residuals": (np.array(residuals), "1"),
                "steady_cycles_integrated": (phi.cycles + 1, "1")}
    result = cycles_from(braked, phi, x, analysis=analysis)
    return HeldPoint(omega, fuel, T, braked, result, residuals, phi.cycles + 1)


def _solve(scene, phi: CycleMap, omega: float) -> tuple[np.ndarray, float, list[float]]:
    """(x, T, residuals) of the held steady state, by Newton's method on (Φ(x; T) − x,
    ω̄(x; T) − ω̄*) in units of the solver's error weight."""
    sv = scene.solver
    base = phi.model
    free = np.flatnonzero(phi.free)
    x0 = phi.initial()
    target_weight = sv.atol + sv.rtol * omega
    failures: list[str] = []  # (what stopped the cycles that failed)

    def cycle(z):
        """G(z) and the cycle's net work, z = (x's free states, T); None where it failed."""
        x = x0.copy()
        x[free] = z[:-1]
        phi.model = base._replace(load_const=float(z[-1]))
        try:
            end = phi(x)
        except SimulationError as exc:
            failures.append(str(exc))
            return None, phi.net_work
        f = (end - x)[free] / (sv.atol + sv.rtol * np.abs(x[free]))
        g = (phi.cycle / phi.elapsed - omega) / target_weight
        return np.append(f, g), phi.net_work

    z = np.append(x0[free], 0.0)
    G, work = cycle(z)
    z1 = z.copy()
    z1[-1] = work / phi.cycle  # (in steady state W_gas − losses = T·cycle)
    G1, _ = cycle(z1) if G is not None else (None, None)
    if G is None or G1 is None:
        raise NoOperatingPoint(f"no steady state at {_rpm(omega)}: a first cycle from it, "
                               f"{'with' if G is not None else 'without'} a brake, failed: "
                               f"{failures[-1]}")
    rel = math.sqrt(max(sv.rtol, np.finfo(float).eps))
    J = _differences(cycle, z1, G1, rel, failures, skip=z.size - 1)
    J[:, -1] = (G1 - G) / (z1[-1] - z[-1])  # (the first two cycles' secant in T)
    z, G = z1, G1
    r = float(np.max(np.abs(G)))
    residuals = [r]
    best, since, fresh = (z, r), 0, True
    while r > TOLERANCE:
        if best[1] <= NOISE_FLOOR and since >= STALLED_ITERATIONS:
            z, r = best  # (the map's own noise holds the residual above the tolerance)
            residuals.append(r)
            break
        if len(residuals) > MAX_ITERATIONS:
            raise NoOperatingPoint(f"no convergence at {_rpm(omega)} in {MAX_ITERATIONS} "
                                   f"iterations; residuals {_shown(residuals)}")
        dz = np.linalg.solve(J, -G)
        x_step = np.zeros(x0.size)
        x_step[free] = dz[:-1]
        x_now = x0.copy()
        x_now[free] = z[:-1]
        lam = _speed_limited(x_now, x_step, phi.speed_at)
        step = None
        for _ in range(MAX_HALVINGS + 1 if fresh else 1):
            G_new, _ = cycle(z + lam * dz)
            if G_new is not None and np.max(np.abs(G_new)) < r:
                step = z + lam * dz, G_new
                break
            lam *= 0.5
        if step is None and fresh and best[1] <= NOISE_FLOOR:
            z, r = best  # (a fresh derivative's step reduces it no more: the map's noise)
            residuals.append(r)
            break
        if step is None:
            if fresh:
                raise NoOperatingPoint(f"Newton's step at {_rpm(omega)} reduces the residual "
                                       f"no more; residuals {_shown(residuals)}")
            # (the kept derivative's step failed: a fresh one)
            J, fresh = _differences(cycle, z, G, rel, failures), True
            continue
        z_new, G_new = step
        r_new = float(np.max(np.abs(G_new)))
        if r_new > CHORD_RATE * r:
            J, fresh = _differences(cycle, z_new, G_new, rel, failures), True
        else:  # (Broyden's rank-one update: the least change that meets the secant)
            dz_taken = z_new - z
            J = J + np.outer((G_new - G) - J @ dz_taken, dz_taken) / (dz_taken @ dz_taken)
            fresh = False
        z, G, r = z_new, G_new, r_new
        residuals.append(r)
        best, since = ((z, r), 0) if r < best[1] else (best, since + 1)
    phi.model = base
    T = float(z[-1])
    if T < 0.0:
        raise NoOperatingPoint(
            f"no steady state under a brake at {_rpm(omega)}: the brake would have to drive "
            f"the engine with {-T:.6g} N m (the fuel's work does not cover the friction at "
            f"this speed)")
    x = x0.copy()
    x[free] = z[:-1]
    return x, T, residuals


def _differences(cycle, z, G, rel: float, failures: list[str], skip: int | None = None
                 ) -> np.ndarray:
    """∂G/∂z by forward differences from G(z) = ``G``, a cycle per unknown but ``skip``, each
    step ``rel`` (√rtol: the rounding of a cycle) of the unknown's scale; a cycle that fails
    says why by the last of ``failures``."""
    J = np.zeros((z.size, z.size))
    for i in range(z.size):
        if i == skip:
            continue
        h = rel * max(abs(z[i]), 1e-3)
        up = z.copy()
        up[i] += h
        G_up, _ = cycle(up)
        if G_up is None:
            raise NoOperatingPoint(f"a cycle of the derivative by differences failed: "
                                   f"{failures[-1]}")
        J[:, i] = (G_up - G) / h
    return J


def _rpm(omega: float) -> str:
    return f"{omega * 30.0 / math.pi:.6g} rpm"


def _shown(residuals: list[float]) -> str:
    return ", ".join(f"{r:.3g}" for r in residuals)


def point_row(point: HeldPoint) -> dict:
    """η_mech and the friction budget of the point's steady cycle (as the study's prescribed
    point gives them), with δ, the brake torque and the cycles integrated."""
    res, scene = point.result, point.scene
    traj = res.trajectory
    phi0 = scene.initial.phi
    cycle = scene.mechanism.cycle
    eff = mechanical_efficiency(scene, dict(traj), window=(phi0, phi0 + cycle, 1))
    row = {k: v for k, (v, _) in eff.items()}
    t, ang, w = (np.asarray(traj[c]) for c in ("t", "phi", "omega"))
    row.update(delta=fluctuation(t, ang, w, cycle, phi0), brake_torque=point.brake_torque,
               rpm_mean=float(cycle / (t[-1] - t[0]) * 30.0 / math.pi),
               cycles_integrated=point.cycles)
    return row
