"""Long runs in a fraction of their cycles: multirevolution (envelope-following) steps on the
cycle map (docs/theory.md, "Multirevolution steps"; docs/guide/steady.md).

In crank angle the state at each cycle's start follows the cycle map, X_{n+1} = Φ(X_n), X the
periodic states and the time t (:class:`~transient.run.CycleMap`, started at the time it is
given). Where the inputs change slowly against a cycle (a heavy flywheel's spin-up, a load
programme over minutes) the sequence X_n lies on a smooth *envelope* X(n) through the nodes,
whose derivative at a node follows from the three resolved cycles after it (the third-order
one-sided difference of X_n … X_{n+3}):

    X′(n) ≈ F(X_n) = −11/6 X_n + 3 X_{n+1} − 3/2 X_{n+2} + 1/3 X_{n+3}.

The envelope is then integrated in n, the cycle number, by an embedded Runge–Kutta pair with
step control (scipy's RK45: a step of many cycles costs six F, eighteen resolved cycles), and
again at ten times the tolerance with the second-order difference: the difference of the two
is the error estimate (the looser one's error, its derivative's included, which bounds the
tighter one's where the method converges). It is the envelope's
error, not the stepper's: each cycle is integrated at the scene's tolerance, as a direct run's
is, and the two differ by about that a cycle, which a heavy flywheel's map adds up. A load schedule's corners are
crossed in resolved cycles (:data:`CORNER_CYCLES` on either side), so that a corner falls in
the cycle where the direct run has it; so are the run's last cycles where fewer are left than a
macro step saves, the first cycles, and those where the cycles' switching events change (a
pair's modes, a governor's limits: the envelope is not smooth there). A stiff envelope (a
multiplier well below 1) is integrated by BDF, implicit, from where an explicit step proves
too short.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import BDF, RK45
from scipy.optimize import brentq

from .errors import SceneError, SimulationError
from .run import CycleMap
from .scene.records import ENVELOPE_RTOL
from .shooting import refuse_nonperiodic

#: Weights of the one-sided difference of X_n … X_{n+3} for X′(n) (third order), and of
#: X_n … X_{n+2} (second order: the error estimate's integration, whose difference from the
#: run's then holds the derivative's error too, which no tolerance changes).
DIFFERENCE = (-11.0 / 6.0, 3.0, -1.5, 1.0 / 3.0)
DIFFERENCE_ESTIMATE = (-1.5, 2.0, -0.5)
#: Resolved cycles kept on either side of a schedule corner.
CORNER_CYCLES = 3
#: The share of the time to the next corner a macro segment spans at the present cycle's
#: period (the speed may rise and shorten it); the corner's event stops it if the speed falls.
CORNER_REACH = 0.9
#: Steps a macro segment takes before its step size, still below what a step costs in
#: cycles, says that the envelope is stiff.
STIFF_STEPS = 4
#: Fewer cycles left than this are integrated one by one (a macro step's stages cost more).
MIN_MACRO = 60
#: The envelope integrator's own relative tolerance, its least: the envelope's is put in its
#: absolute one, per state (``_Follower._macro``).
SOLVER_RTOL = 100 * np.finfo(float).eps
#: The time's error is held relative to this many cycles' duration: what places a corner in
#: its cycle to a small part of one over the run.
TIME_SCALE = 100.0
#: The second integration's tolerance, a multiple of the first's: their difference estimates
#: the second's error, which bounds the first's where the method converges.
ESTIMATE_RATIO = 10.0


@dataclass
class Envelope:
    """The run's state at every cycle start (the periodic states, then t): ``integrated`` says
    which cycles were integrated as the direct run would (the rest are the envelope's, from its
    dense output); ``error`` the estimate of each state's error at the last cycle (the
    difference of the integrations at rtol and at ten times it); the cycles integrated (the
    estimate's too) and their right-hand sides' evaluations."""

    names: list[str]
    states: np.ndarray
    integrated: np.ndarray
    error: np.ndarray
    cycles_integrated: int
    nfev: int

    def column(self, name: str) -> np.ndarray:
        """One state at every cycle start, cycle 0 to the last."""
        return self.states[:, self.names.index(name)]


def refuse(scene) -> None:
    """Raise :class:`~transient.errors.SceneError` for a scene the envelope cannot follow:
    shooting's refusals but a load schedule in time, whose corners are crossed cycle by cycle."""
    refuse_nonperiodic(scene, allowed=("load.schedule_time",))


class _Follower:
    """One integration of the envelope at one tolerance over a run of ``cycles`` cycles."""

    def __init__(self, phi: CycleMap, corners: np.ndarray, cycles: int, rtol: float,
                 atol: float, progress, difference=DIFFERENCE) -> None:
        self.phi, self.corners, self.cycles = phi, corners, cycles
        self.difference = np.asarray(difference)
        self.rtol, self.atol, self.progress = rtol, atol, progress
        width = phi.initial().size + 1
        self.states = np.full((cycles + 1, width), np.nan)
        # cycles to integrate one by one after a macro segment the envelope's stiffness held
        # short, doubled each time it recurs, and those of them left
        self.direct, self.direct_left = 0, 0
        # the envelope found stiff (its steps implicit from then on); a segment's first step
        self.implicit, self.first_step = False, None
        self.integrated = np.zeros(cycles + 1, dtype=bool)
        # called with (cycle reached, states, integrated) as the envelope advances: the states
        # of the cycles before the one reached are final
        self.watch: Callable[[int, np.ndarray, np.ndarray], None] | None = None
        # the switching events of the last resolved cycle, how many resolved cycles in a row
        # have had the same; each F's cycle number and whether its cycles switched otherwise,
        # since ``seen`` was emptied; the cycle up to which the envelope may go before a switch
        self.regime: tuple[int, ...] | None = None
        self.calm = 0
        self.seen: list[tuple[float, bool]] = []
        self.switch_near: int | None = None

    def cycle(self, X: np.ndarray) -> np.ndarray:
        """The state after one resolved cycle from ``X``."""
        end = self.phi(X[:-1], float(X[-1]))
        return np.append(end, X[-1] + self.phi.elapsed)

    def slope(self, n: float, X: np.ndarray) -> np.ndarray:
        """F(X): the envelope's derivative by the cycle number, from resolved cycles."""
        seq, other = [X], False
        for _ in self.difference[1:]:
            seq.append(self.cycle(seq[-1]))
            other |= self.phi.events != self.regime
        self.seen.append((n, other))
        return np.tensordot(self.difference, np.array(seq), axes=1)

    def resolve(self, n: int, X: np.ndarray) -> np.ndarray:
        """Cycle ``n`` integrated from ``X``: the state at cycle n + 1."""
        self.states[n], self.integrated[n] = X, True
        end = self.cycle(X)
        same = self.phi.events == self.regime
        self.regime, self.calm = self.phi.events, self.calm + 1 if same else 1
        return end

    def run(self) -> np.ndarray:
        n, X = 0, np.append(self.phi.initial(), 0.0)
        while n < self.cycles:
            if self.switch_near is not None and n >= self.switch_near:
                self.calm, self.switch_near = 0, None  # (resolved until the switches repeat)
            period = self.phi.cycle / abs(X[self.phi.speed_at[0]])
            corner = self._next_corner(X[-1])
            stop = self._reach(n, X[-1], corner, period)
            if self.switch_near is not None:
                stop = min(stop, self.switch_near)
            if (self._near_corner(X[-1], corner, period) or stop - n < MIN_MACRO
                    or self.direct_left > 0 or self.calm < CORNER_CYCLES):
                X, n = self.resolve(n, X), n + 1
                self.direct_left = max(self.direct_left - 1, 0)
            else:
                n, X = self._macro(n, X, stop, corner, period)
                self.direct_left = self.direct
            if self.progress is not None:
                self.progress(n, self.cycles, self.phi.cycles)
            if self.watch is not None:
                self.watch(n, self.states, self.integrated)
        self.states[self.cycles] = X
        return self.states

    def _near_corner(self, t: float, ahead: float | None, period: float) -> bool:
        """Within CORNER_CYCLES cycles (and one for the cycle that holds it) of a corner."""
        behind = self.corners[self.corners <= t]
        return bool((ahead is not None and ahead - t < (CORNER_CYCLES + 1) * period)
                    or (behind.size and t - behind[-1] < CORNER_CYCLES * period))

    def _next_corner(self, t: float) -> float | None:
        ahead = self.corners[self.corners > t]
        return float(ahead[0]) if ahead.size else None

    def _reach(self, n: int, t: float, corner: float | None, period: float) -> int:
        """Where a macro segment from cycle ``n`` may end: the run's end, or short of the next
        corner (no stage's cycles may reach it: they would see it)."""
        if corner is None:
            return self.cycles
        return min(self.cycles, n + int(CORNER_REACH * (corner - t) / period))

    def _macro(self, n: int, X: np.ndarray, stop: int, corner: float | None, period: float):
        """The envelope from cycle ``n`` to ``stop``, to the last whole cycle that ends
        CORNER_CYCLES cycles before the next corner, to before a step whose cycles switched
        otherwise (``_switched``), or to where the steps stay shorter than the cycles they
        integrate or a stage lands where no cycle runs (a speed too low, or reversed): the
        envelope is stiff, and the next segments are BDF's; if they were already, the next
        cycles are integrated one by one, twice as many each time it recurs. Its nodes are
        filled from each step's dense output."""
        # each state's error held to rtol of the largest size it has had (a governor's state
        # or a latched fuel may pass through zero), t's to rtol of TIME_SCALE cycles'
        # duration: relative to t itself, a long run's would grow with its length
        self.states[n], last, steps, stiff = X, n, 0, False
        begun = self.phi.cycles
        scale = np.nanmax(np.abs(self.states[:n + 1]), axis=0)
        scale[-1] = TIME_SCALE * period
        limit = None if corner is None else corner - CORNER_CYCLES * period
        self.seen = []
        try:  # (its first step's size is tried on the envelope too)
            rk = self._stepper(n, X, stop, self.atol + self.rtol * scale)
        except SimulationError:  # (a stage's state no cycle starts from: stiff, as below)
            rk, stiff = None, True
        switched = self._switched(n)
        while rk is not None and not switched and rk.status == "running":
            spent = self.phi.cycles
            self.seen = []
            try:
                rk.step()
            except SimulationError:
                stiff = True
                break
            switched = self._switched(rk.t_old)
            if switched:  # (none of the step kept: its cycles cross the switch)
                break
            steps += 1
            if rk.status == "failed":
                raise SimulationError(f"the envelope from cycle {n} failed at cycle "
                                      f"{rk.t:.6g}: {rk.message}")
            dense = rk.dense_output()
            reach, crossed = rk.t, limit is not None and rk.y[-1] >= limit
            if crossed:  # (where t reaches the limit, on this step's interpolant)
                reach = brentq(_time_past, rk.t_old, rk.t, args=(dense, limit))
            nodes = np.arange(last + 1, int(math.floor(reach + 1e-9)) + 1)
            if nodes.size:
                self.states[nodes] = dense(nodes).T
                last = int(nodes[-1])
            if rk.t == stop and not crossed:
                self.states[stop] = rk.y
            # (an explicit step held below what it costs once the controller has had steps to
            # grow it: the envelope is stiff; implicit steps that have covered fewer cycles
            # than they cost: no gain, where a step cut short by Newton's iteration on F's
            # rounding, at a size where that reaches the tolerance, grows again)
            short = (rk.t - n < self.phi.cycles - begun if self.implicit
                     else rk.h_abs < self.phi.cycles - spent)
            stiff = steps >= STIFF_STEPS and short
            if crossed or stiff:
                break
        if rk is not None:  # (the next segment's first step: this one's last)
            self.first_step = max(1.0, rk.h_abs)
        if stiff and not self.implicit:  # (BDF's steps from here on)
            self.implicit = True
        else:
            self.direct = max(2 * self.direct, MIN_MACRO // 2) if stiff else 0
        if last == n:  # (no whole cycle reached: integrate one)
            return n + 1, self.resolve(n, X)
        return last, self.states[last].copy()

    def _stepper(self, n: int, X: np.ndarray, stop: int, atol: np.ndarray):
        """The envelope's integrator from cycle ``n``: RK45, or BDF (its Jacobian by differences of
        F, a cycle map's evaluations per state) once the envelope has been found stiff."""
        first = None if self.first_step is None else min(self.first_step, stop - n)
        method = BDF if self.implicit else RK45
        return method(self.slope, n, X, stop, rtol=SOLVER_RTOL, atol=atol, first_step=first)

    def _switched(self, start: float) -> bool:
        """Whether a cycle of a step from ``start`` switched otherwise than the last resolved
        one (a governor reaching or leaving a limit, a pair's modes, a speed-table knot); if so
        ``switch_near`` is halfway from the last cycle whose F's cycles switched as before to
        the first whose did not (the switch lies between them: a step to there either sees it
        again, nearer, or leaves fewer cycles to resolve before it)."""
        other = [m for m, o in self.seen if o]
        if not other:
            return False
        same = max([m for m, o in self.seen if not o and m < min(other)], default=start)
        self.switch_near = int(math.floor(0.5 * (same + min(other))))
        return True


def _time_past(m: float, dense, limit: float) -> float:
    """How far the envelope's time at cycle ``m`` (on a step's interpolant) is past ``limit``."""
    return float(dense(m)[-1] - limit)


def multirevolution(scene, cycles: int, rtol: float = ENVELOPE_RTOL,
                    progress: Callable[[int, int, int], None] | None = None,
                    watch: Callable[[int, np.ndarray, np.ndarray], None] | None = None
                    ) -> Envelope:
    """Follow ``scene`` over ``cycles`` engine cycles on the envelope of its cycle map.

    Parameters
    ----------
    scene : Scene
        A dynamic scene of the compiled stepper in crank angle whose only input that changes
        with time is a load schedule in time (``load.schedule_time``).
    cycles : int
        The engine cycles to follow (≥ 1).
    rtol : float
        The envelope's relative tolerance (its absolute one the scene's ``solver.atol``).
    progress : callable, optional
        Called with (cycle reached, cycles, cycles integrated) as the envelope advances.
    watch : callable, optional
        Called with (cycle reached, states, integrated) as the envelope advances (the arrays
        of :class:`Envelope`, final before the cycle reached): what a long run's result
        writes as it goes (:mod:`transient.longrun`).

    Returns
    -------
    Envelope
        The state at every cycle start, which cycles were integrated, the error estimate.
    """
    if not (isinstance(cycles, int) and cycles >= 1):
        raise SceneError("cycles", f"{cycles!r}: a whole number of cycles ≥ 1")
    if not (isinstance(rtol, float) and 0.0 < rtol < 1.0):
        raise SceneError("rtol", f"{rtol!r}: the envelope's relative tolerance, in (0, 1)")
    refuse(scene)
    phi = CycleMap(scene)
    corners = np.unique(np.asarray(scene.load.schedule_time, dtype=float))
    atol = scene.solver.atol
    run = _Follower(phi, corners, cycles, rtol, atol, progress)
    run.watch = watch
    states = run.run()
    coarse = _Follower(phi, corners, cycles, rtol * ESTIMATE_RATIO, atol, None,
                       DIFFERENCE_ESTIMATE)
    coarse.run()
    return Envelope([*phi.state_names(), "t"], states, run.integrated,
                    np.abs(states[-1] - coarse.states[-1]), phi.cycles, phi.nfev)
