"""The periodic steady state of a scene by shooting on the cycle map (docs/theory.md, "The cycle
map and shooting"; docs/guide/steady.md).

In crank angle the engine's right-hand side repeats over one cycle, so the periodic states at a
cycle's start (:func:`~transient.core.model.layout.periodic_states`) follow a map
x_{n+1} = Φ(x_n) (:class:`~transient.run.CycleMap`). A steady state is a fixed point,
F(x) = Φ(x) − x = 0, found here by Newton's method in the speeds' squares (where a cycle's work
is nearly linear) with the monodromy ∂Φ/∂x by finite differences (one cycle per periodic
state; kept and updated by Broyden's formula while it serves: with the speed alone, the
secant), damped by backtracking on ‖F‖ and falling back to direct cycles where a Newton step
does not reduce it (the map contracts). Its eigenvalues at
the solution, the multipliers, say how fast a disturbance of the steady cycle dies per cycle.
:func:`transient.steady` then runs the steady cycle(s) with output, a :class:`~transient.Result` like a
run's, with the convergence record and the multipliers in its analysis.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .core.stepper import io as sio
from .errors import SceneError, SimulationError
from .results import Checkpoint, Result, check_writable
from .run import CycleMap, simulate_from
from .scene.records import COMPILED_METHODS
from .shaft import refuse_elastic_run

#: Newton iterations (each a cycle for ‖F‖ and one per periodic state for the monodromy).
MAX_ITERATIONS = 30
#: Halvings of a Newton step that does not reduce ‖F‖ before direct cycles are taken instead.
MAX_HALVINGS = 4
#: Direct cycles x ← Φ(x) taken where a damped Newton step failed to reduce ‖F‖.
DIRECT_CYCLES = 3
#: ‖F‖ counts as converged at this multiple of the solver's own error weight atol + rtol·|x|:
#: the periodic states then repeat to the accuracy one step of the stepper keeps.
TOLERANCE = 1.0
#: Where Newton stalls for STALLED_ITERATIONS iterations, or a fresh monodromy's step fails,
#: with its best ‖F‖ at most NOISE_FLOOR (in the same units), that is the cycle map's own noise
#: (kinks and jumps located by retaken steps, a cycle's many steps' errors): the best iterate is
#: the solution, its residual the last recorded.
NOISE_FLOOR, STALLED_ITERATIONS = 1e3, 3
#: A monodromy is kept, updated by Broyden's rank-one formula, while its step reduced ‖F‖ at
#: least this much: a step on it costs one cycle, a fresh one a cycle per unknown more.
CHORD_RATE = 0.5
#: The most a Newton step may change a speed by, either way (``_speed_limited``).
SPEED_FACTOR = 4.0
#: A speed beyond which a scene runs away (no piston machine turns at 10⁴ rad/s, 95 000 rpm).
RUNAWAY_SPEED = 1e4


class NoSteadyState(SimulationError):
    """The scene has no periodic steady state that shooting finds (it accelerates or decelerates
    for ever, its steady state is unstable, or Newton did not converge); ``record`` is the
    :class:`Shooting` so far."""

    def __init__(self, message: str, record: Shooting) -> None:
        super().__init__(message)
        self.record = record


@dataclass
class Shooting:
    """The convergence record: the periodic states' names, the residual ‖F‖ (in units of the
    solver's error weight) at each iterate, the cycles integrated and their right-hand sides'
    evaluations, the solution ``x``, the multipliers (the monodromy's eigenvalues there, largest
    modulus first), the neutral twists left out of them (``CycleMap.neutral_at``), and the
    (speed, net work) of every cycle run."""

    names: list[str]
    residuals: list[float] = dataclasses.field(default_factory=list)
    cycles: int = 0
    nfev: int = 0
    x: np.ndarray | None = None
    multipliers: np.ndarray | None = None
    monodromy: np.ndarray | None = None
    neutral: list[str] = dataclasses.field(default_factory=list)
    seen: list[tuple[float, float]] = dataclasses.field(default_factory=list)

    def analysis(self) -> dict[str, tuple]:
        """The record as a result's analysis entries (name → (value, unit))."""
        mu = self.multipliers
        assert mu is not None, "the record of a shooting that found its state"
        return {"steady_state_t": (0.0, "s"),  # (the whole result is the steady cycle)
                "steady_iterations": (len(self.residuals) - 1, "1"),
                "steady_residuals": (np.array(self.residuals), "1"),
                "steady_cycles_integrated": (self.cycles, "1"),
                "steady_rhs_evaluations": (self.nfev, "1"),
                "steady_multiplier_max": (float(np.abs(mu).max()), "1"),
                "steady_multipliers_real": (mu.real.copy(), "1"),
                "steady_multipliers_imag": (mu.imag.copy(), "1"),
                **({"steady_neutral_states": (", ".join(self.neutral), "")}
                   if self.neutral else {})}


def refuse_nonperiodic(scene, allowed: Collection[str] = ()) -> None:
    """Raise :class:`~transient.errors.SceneError` for a scene that cannot be periodic by
    construction (something in it depends on time or on the cycle's number), before any work;
    the keys ``allowed`` are a caller's to follow."""
    refuse_elastic_run(scene)
    file = scene.source_file
    w_hi = 1.5 * scene.solver.switch_speed
    if scene.initial.omega < w_hi:
        raise SceneError("initial.omega", f"{scene.initial.omega:.6g} rad/s starts in time, below "
                                          f"1.5 × solver.switch_speed = {w_hi:.6g} rad/s; the "
                                          f"cycle map starts in crank angle: give a running "
                                          f"speed", file=file)
    why = _nonperiodic(scene, allowed)
    if why:
        key, what = why
        raise SceneError(key, f"{what}: the scene has no periodic steady state (shooting needs "
                              f"every input to repeat from cycle to cycle); `transient run` "
                              f"follows it in time", file=file)


def _nonperiodic(scene, allowed: Collection[str] = ()) -> tuple[str, str] | None:
    """(key, what) of the first thing in ``scene`` that makes it non-periodic, but those whose
    key is ``allowed`` (a caller that follows them), or None."""
    return next((why for why in _nonperiodic_parts(scene) if why[0] not in allowed), None)


def _nonperiodic_parts(scene) -> Iterator[tuple[str, str]]:
    """(key, what) of each thing in ``scene`` that makes it non-periodic, in the order they are
    told."""
    load, run = scene.load, scene.run
    if run.mode != "dynamic":
        yield "run.mode", f"{run.mode!r} prescribes the speed"
    if scene.solver.method not in COMPILED_METHODS:
        yield "solver.method", (f"{scene.solver.method!r} is a reference path; the cycle map "
                                f"is the compiled stepper's ({', '.join(COMPILED_METHODS)})")
    if scene.solver.domain == "time":
        yield "solver.domain", "\"time\" never turns to crank angle, the cycle map's variable"
    for key in ("load.schedule_time", "load.schedule_revolutions"):
        if getattr(load, key.split(".")[1]):
            yield key, "a load schedule changes the load from cycle to cycle"
    if load.table is not None and load.table.abscissa == "time":
        yield "load.table.time", "a load tabulated against time"
    if load.inertia > 0.0:
        yield "load.inertia", "an inertia switched in at load.inertia_time"
    st = scene.starter
    if st.torque > 0.0 and scene.initial.omega < st.cutout_speed:
        yield "starter.torque", (f"the starter is engaged until its cut-out speed "
                                 f"{st.cutout_speed:.6g} rad/s; start at or above it "
                                 f"(initial.omega) or without the starter")
    if scene.governor.model == "flyweight":
        yield "governor.model", ("\"flyweight\": its sleeve's stops are chosen once at the "
                                 "start, not per cycle, in this version")
    for c in scene.gas.cylinders:
        for key in ("misfire_cycles", "misfire_every", "misfire_rate"):
            if key in c.combustion_keys:
                yield f"gas.cylinders.{key}", (f"cylinder {c.cylinder} misfires in some cycles "
                                               f"and not in others")


def shoot(scene, progress: Callable[[int, float, int], None] | None = None,
          cycle_map: CycleMap | None = None) -> tuple[Shooting, CycleMap]:
    """The periodic states of ``scene``'s steady cycle by Newton's method on Φ(x) − x, and the
    multipliers there; ``progress(iteration, residual, cycles)`` after each iterate. Raises
    :class:`NoSteadyState` with the reason where there is none, or where it is unstable."""
    refuse_nonperiodic(scene)
    phi = cycle_map or CycleMap(scene)
    sv = scene.solver
    rec = Shooting(phi.state_names())
    x = phi.initial()

    def weight(x):
        return sv.atol + sv.rtol * np.abs(x)

    def residual(x):
        """Φ(x) − x in units of the error weight, or None where the cycle failed."""
        try:
            end = phi(x)
        except SimulationError:
            end = None
        rec.seen.append((float(x[phi.speed_at[0]]), phi.net_work))
        if end is None:
            return None, None
        return end, float(np.max(np.abs(end - x) / weight(x)))

    end, r = residual(x)
    if end is None:
        raise _no_state(rec, phi, "the first cycle from the scene's initial state failed")
    rec.residuals.append(r)
    _said(progress, rec, phi)
    best, since = (x, end, r), 0
    to_z, from_z, slope = _energy_coordinates(phi.speed_at)
    Mz = None  # the monodromy in z, kept (Broyden-updated) while its steps reduce ‖F‖ fast
    while r > TOLERANCE:
        if best[2] <= NOISE_FLOOR and since >= STALLED_ITERATIONS:
            # the map's own noise (kinks located by step retakes, reaction friction's) holds
            # ‖F‖ above the tolerance: the best iterate, its residual recorded
            x, end, r = best
            rec.residuals.append(r)
            break
        if len(rec.residuals) > MAX_ITERATIONS:
            raise _no_state(rec, phi, f"no convergence in {MAX_ITERATIONS} iterations")
        fresh = Mz is None
        if Mz is None:
            M = _jacobian(phi, x, end - x, forward=True)
            Mz = slope(end)[:, None] * M / slope(x)[None, :]
        z, Fz = to_z(x), to_z(end) - to_z(x)
        dz = np.zeros_like(x)  # (a neutral twist stays as it is: any value repeats)
        dz[phi.free] = np.linalg.lstsq((Mz - np.eye(x.size))[:, phi.free], -Fz, rcond=None)[0]
        # (halving a step within the map's own noise finds nothing but noise)
        halvings = MAX_HALVINGS if fresh and r > NOISE_FLOOR else 0
        step = _damped(residual, z, dz, r, phi.speed_at, from_z, halvings)
        if step is None and not fresh:  # (the kept monodromy's step failed: a fresh one)
            Mz = None
            continue
        if step is None and best[2] <= NOISE_FLOOR:
            # a fresh monodromy's step reduces ‖F‖ no more: the map's own noise
            x, end, r = best
            rec.residuals.append(r)
            break
        if step is None:  # Newton failed to reduce ‖F‖: direct cycles (the map contracts)
            for _ in range(DIRECT_CYCLES):
                new_end, new_r = residual(end)
                if new_end is None:
                    raise _no_state(rec, phi, "a direct cycle failed")
                x, end, r = end, new_end, new_r
            Mz = None
        else:
            if step[2] > CHORD_RATE * r:
                Mz = None
            else:  # (with one unknown, the secant)
                Mz = _broyden(Mz, to_z(step[0]) - z, (to_z(step[1]) - to_z(step[0])) - Fz)
            x, end, r = step
        if x[phi.speed_at[0]] > RUNAWAY_SPEED:
            raise _no_state(rec, phi, f"the speed ran away past {RUNAWAY_SPEED:g} rad/s")
        rec.residuals.append(r)
        _said(progress, rec, phi)
        best, since = ((x, end, r), 0) if r < best[2] else (best, since + 1)
    rec.x = x
    M = _jacobian(phi, x, None, forward=False)
    free = phi.free
    rec.neutral = [n for n, f in zip(rec.names, free) if not f]
    rec.monodromy = M[np.ix_(free, free)]
    rec.cycles, rec.nfev = phi.cycles, phi.nfev
    mu = np.linalg.eigvals(rec.monodromy)
    rec.multipliers = mu[np.argsort(-np.abs(mu), kind="stable")]
    if np.abs(rec.multipliers[0]) >= 1.0:
        raise NoSteadyState(_unstable(rec, phi), rec)
    return rec, phi


def _broyden(M: np.ndarray, dx: np.ndarray, dF: np.ndarray) -> np.ndarray:
    """The monodromy ``M`` updated along the step ``dx`` that changed F by ``dF`` (Broyden's
    rank-one update of M − I: the least change that meets the secant condition)."""
    J = M - np.eye(M.shape[0])
    return M + np.outer(dF - J @ dx, dx) / (dx @ dx)


def _damped(residual, z, dz, r, speed_at, from_z, halvings: int):
    """The Newton step λ·dz from ``z`` (λ as :func:`_speed_limited` allows, halved up to
    ``halvings`` times) that reduces ‖F‖ below ``r``: (x, Φ(x), ‖F‖) there, or None."""
    lam = _speed_limited(z, dz, speed_at)
    for _ in range(halvings + 1):
        x = from_z(z + lam * dz)
        end, new_r = residual(x)
        if end is not None and new_r < r:
            return x, end, new_r
        lam *= 0.5
    return None


def _energy_coordinates(speed_at):
    """The unknowns Newton steps in: each speed ω as ω|ω|, every other state as it is; and
    the derivative of that change, per state.

    The work of a cycle is what moves the speed: the gas's and friction's change little with
    the speed, a fan's is ∝ ω², so F in ω² (the kinetic energy's measure) is close to linear
    and Newton's step from far away lands close; in ω it is not. A fixed point is one in either
    coordinate, and so are the multipliers (the two monodromies are similar there)."""
    def to_z(x):
        z = x.copy()
        z[speed_at] = x[speed_at] * np.abs(x[speed_at])
        return z

    def from_z(z):
        x = z.copy()
        x[speed_at] = np.sign(z[speed_at]) * np.sqrt(np.abs(z[speed_at]))
        return x

    def slope(x):
        d = np.ones_like(x)
        d[speed_at] = 2.0 * np.abs(x[speed_at])
        return d

    return to_z, from_z, slope


def _said(progress, rec: Shooting, phi: CycleMap) -> None:
    if progress is not None:
        progress(len(rec.residuals) - 1, rec.residuals[-1], phi.cycles)


def _jacobian(phi: CycleMap, x, fx, forward: bool) -> np.ndarray:
    """∂Φ/∂x by differences: forward from Φ(x) = x + ``fx`` (one cycle a state; for Newton's
    step) or central (two; for the multipliers), each state's step sized to the rounding of the
    cycle (√rtol forward, rtol^⅓ central, of the state's scale); a neutral twist's column is
    the unit one, without a cycle."""
    rtol = max(phi.cfg[sio.C_RTOL], np.finfo(float).eps)
    rel = math.sqrt(rtol) if forward else rtol ** (1.0 / 3.0)
    M = np.eye(x.size)  # (a neutral twist's column: carried over as it is)
    for i in np.flatnonzero(phi.free):
        h = rel * max(abs(x[i]), 1e-3)
        up = x.copy()
        up[i] += h
        if forward:
            M[:, i] = (phi(up) - (x + fx)) / h
        else:
            down = x.copy()
            down[i] -= h
            M[:, i] = (phi(up) - phi(down)) / (2.0 * h)
    return M


def _speed_limited(z, dz, speed_at) -> float:
    """The largest λ ≤ 1 with which the step λ·dz changes no speed by more than a factor
    SPEED_FACTOR (its z = ω|ω| by its square) either way: a Newton step from far away must not
    reverse the shaft, nor leave for speeds where nothing was seen."""
    grow, shrink = SPEED_FACTOR ** 2 - 1.0, 1.0 - SPEED_FACTOR ** -2
    lam = 1.0
    for i in speed_at:
        if dz[i] > grow * z[i]:
            lam = min(lam, grow * z[i] / dz[i])
        elif dz[i] < -shrink * z[i]:
            lam = min(lam, -shrink * z[i] / dz[i])
    return lam


def _no_state(rec: Shooting, phi: CycleMap, what: str) -> NoSteadyState:
    """The refusal where Newton found no steady state: a scene that accelerates (decelerates)
    for ever, the cycle's net work one sign at every speed seen; else what went wrong, with the
    residuals."""
    rec.cycles = phi.cycles
    if rec.seen:
        seen = [(w, e) for w, e in rec.seen if math.isfinite(e)]
        speeds = [w for w, _ in seen] or [math.nan]
        works = [e for _, e in seen] or [math.nan]
        # one sign at every state seen, and the speed gone that way (with a governor the work
        # depends on its states too: a speed gone against the work's sign is no runaway)
        if all(e > 0 for e in works) and speeds[-1] >= speeds[0] or (
                all(e < 0 for e in works) and speeds[-1] <= speeds[0]):
            how = "accelerates" if works[0] > 0 else "decelerates"
            return NoSteadyState(
                f"no periodic steady state: the scene {how} for ever ({what}); the cycle's net "
                f"work is {'positive' if works[0] > 0 else 'negative'} at every speed seen, "
                f"{min(speeds):.6g} to {max(speeds):.6g} rad/s ({min(works):.6g} to "
                f"{max(works):.6g} J per cycle); give it a load that balances, or follow it "
                f"with `transient run`", rec)
    shown = ", ".join(f"{r:.3g}" for r in rec.residuals)
    return NoSteadyState(f"no periodic steady state found: {what}; residuals ‖Φ(x) − x‖ in "
                         f"units of atol + rtol·|x|: {shown} ({phi.cycles} cycles integrated); "
                         f"`transient run` follows the scene in time", rec)


def _unstable(rec: Shooting, phi: CycleMap) -> str:
    """Which periodic state an unstable multiplier moves most, and the multipliers."""
    M, x, mu = rec.monodromy, rec.x, rec.multipliers
    assert M is not None and x is not None and mu is not None, "a shooting's final record"
    w, v = np.linalg.eig(M)
    k = int(np.argmax(np.abs(w)))
    # (each component relative to its state's size: a speed and a rack position compared)
    worst = rec.names[int(np.argmax(np.abs(v[:, k]) / np.maximum(np.abs(x), 1e-3)))]
    shown = ", ".join(f"{m:.6g}" for m in mu)
    return (f"the periodic steady state at ω = {x[phi.speed_at[0]]:.9g} rad/s is unstable: "
            f"the multiplier {mu[0]:.6g} (|μ| = {abs(mu[0]):.6g} ≥ 1) "
            f"grows a disturbance each cycle, mostly of {worst} (a governor that hunts?); "
            f"multipliers {shown}; `transient run` follows the motion")


def steady(scene, path: str | Path | None = None, *, cycles: int = 1, force: bool = False,
           progress: Callable[[int, float, int], None] | None = None) -> Result:
    """The periodic steady state of ``scene``: its steady cycle(s) as a
    :class:`~transient.Result`, every column and analysis a run has, t, the works and the
    losses from zero at the cycle's start (φ₀, the scene's initial angle).

    Parameters
    ----------
    scene : Scene
        A dynamic scene of the compiled stepper with nothing in it that depends on time.
    path : str or Path, optional
        The result file; none keeps the result in memory.
    cycles : int
        The steady cycles to write (≥ 1).
    force : bool
        Replace an existing result at ``path``.
    progress : callable, optional
        Called with (iteration, residual, cycles integrated) after each Newton iterate.

    Returns
    -------
    Result
        The steady cycle(s); ``analysis`` holds the convergence record (``steady_residuals``
        per iteration, in units of the solver's error weight atol + rtol·|x|,
        ``steady_cycles_integrated``) and the multipliers (``steady_multipliers_real``,
        ``_imag``, largest modulus first; ``steady_multiplier_max``).

    Raises
    ------
    transient.SceneError
        A scene that cannot be periodic (a load schedule, a starter engaged, prescribed speed,
        …), before any work; ``cycles`` < 1; a result at ``path`` without ``force``.
    NoSteadyState
        The scene accelerates or decelerates for ever, its steady state is unstable, or Newton
        did not converge: the message says which (a :class:`transient.SimulationError`).

    Examples
    --------
    A single cylinder, unfired, driven by a constant 20 N m against a load of 0.1 N m s/rad:
    the cycle's work balance puts the angle-mean speed at 20/0.1 = 200 rad/s (the scene's
    ``[run]`` end is the direct run's; the steady result holds the cycles asked for).

    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.05},
    ...     "load": {"torque": -20.0, "linear": 0.1},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> res = transient.steady(scene)
    >>> import numpy as np
    >>> phi, omega = res.trajectory["phi"], res.trajectory["omega"]
    >>> round(float(np.trapezoid(omega, phi) / (phi[-1] - phi[0])), 4)
    200.0
    >>> bool(abs(res.analysis["steady_multiplier_max"][0]) < 1)
    True
    """
    if not (isinstance(cycles, int) and cycles >= 1):
        raise SceneError("cycles", f"{cycles!r}: a whole number of cycles ≥ 1")
    refuse_nonperiodic(scene)
    if path is not None:
        check_writable(Path(path), force)
    rec, phi = shoot(scene, progress)
    assert rec.x is not None, "shoot returns the state it found"
    return cycles_from(scene, phi, rec.x, cycles, path, force, rec.analysis())


def cycles_from(scene, phi: CycleMap, x: np.ndarray, cycles: int = 1,
                path: str | Path | None = None, force: bool = False,
                analysis: dict[str, tuple] | None = None) -> Result:
    """``cycles`` cycles of ``scene`` run with output from the periodic states ``x`` at its
    cycle start (``phi``'s), a :class:`~transient.Result` with ``analysis`` beside its own."""
    y, fst, ist = phi.start(x)
    start = Checkpoint(rows=0, events=0, switched=False, code=sio.RUNNING,
                       floats=np.concatenate([y, fst]), ints=ist)
    run = dataclasses.replace(scene.run, t_end=math.inf,
                              revolutions=cycles * phi.cycle / (2.0 * math.pi))
    initial = dataclasses.replace(scene.initial, omega=float(x[phi.speed_at[0]]))
    cycle_scene = dataclasses.replace(scene, run=run, initial=initial)
    return simulate_from(cycle_scene, start, path, force=force, analysis=analysis,
                         periodic=True)
