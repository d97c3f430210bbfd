"""What a run did, said: its status (the result's root attribute ``status``,
:data:`~transient.outcome.STATUSES`),
a one-line message with the time, angle and speed where it happened, and warnings; and the
watch over a run's blocks that stops a run exceeding its output budget or no longer advancing.

A run that integrated to its end can still have failed the scene: a shaft that never started,
stopped, or was driven backwards by a load larger than the engine (``t_end`` lets the
integration go on), ran out of time before its revolutions, or ran away. Those are read off the
blocks as they stream past (:class:`Watch`), since a long run keeps only its last block in
memory: the speed's passages through zero (the ``speed_reversal`` events, which every path
records where ω crosses or reaches zero) bound the angles the shaft swung between, since φ is
monotone between two of them.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import SimulationError
from .scene.outputs import pair_columns
from .scene.records import RUNAWAY_SPEED

#: Every status a run ends with, and what it means (user guide, Result files: Statuses); a run
#: the stepper ends as ``stiff`` is run again by an implicit method and ends with one of these.
STATUSES = {
    "finished": "did what the scene asks: turned its run.revolutions; with run.t_end alone, "
                "followed the motion to t_end with the shaft running forwards at the end",
    "out-of-time": "reached run.t_end before the run.revolutions the scene asks for, the shaft "
                   "running forwards at the end (a prescribed speed table's end is its motion's "
                   "end, not this)",
    "not-started": "did not start: the shaft stopped, rocked or turned backwards before it had "
                   "ever turned a whole revolution forwards, and did not run again",
    "interrupted": "stopped by Ctrl-C, SIGTERM or SIGHUP",
    "stalled": "the shaft ran, then its speed reached zero and it did not run again (at rest, "
               "creeping or rocking, whichever way it turns at the end)",
    "reversed": "the shaft was driven backwards: at the end it turns backwards, faster than the "
                "switch speed, beyond every angle it had swung back to before",
    "locked": "at rest, the friction of the non-ideal pairs holds the machine and nothing can "
              "release it",
    "chattering": "pair modes or other switches flip without progress",
    "runaway": "the speed grew beyond RUNAWAY_SPEED",
    "no-progress": "steps stopped advancing time and angle",
    "over-budget": "the trajectory outgrew run.max_output_bytes",
    "failed": "the integration failed (a non-finite state, a step below 10 ulp, an error)",
}
#: The status of a run that did what its scene describes; every other one exits 1.
FINISHED = "finished"
#: How far past its starting angle the shaft must have turned forwards [rad] to have started: a
#: whole revolution, in which every piston passes its top dead centre.
STARTED = 2.0 * math.pi
#: Consecutive chunks of the stepper (each its chunk of step attempts) that bring no new sample
#: and no new event before a run is stopped as making no progress.
IDLE_CHUNKS = 50

#: A loss power below −LOSS_ROUNDING times the largest |P_loss| of its pair is negative, not
#: rounding.
LOSS_ROUNDING = 1e-9


class RunStopped(SimulationError):
    """A run stopped by its :class:`Watch`; ``status`` says why."""

    def __init__(self, status: str, message: str) -> None:
        super().__init__(message)
        self.status = status


def code_status(code: int) -> str:
    """The status of the stepper's return code ``code`` (:mod:`transient.core.stepper.io`;
    RUNNING is left only by an interrupt). Imported here, so that the command line reads the
    statuses without loading the compiled core."""
    from .core.stepper import io as sio

    return {sio.RUNNING: "interrupted", sio.FINISHED: FINISHED, sio.STALLED: "stalled",
            sio.LOCKED: "locked", sio.CHATTERING: "chattering", sio.STIFF: "stiff",
            sio.FAIL_NONFINITE: "failed", sio.FAIL_STEP: "failed"}[code]


def failure_cause(step: bool, finite: bool, rtol: float, atol: float) -> str:
    """Why the stepper gave up: the step fell below 10 ulp (``step``), or no attempt had a
    finite error estimate and state. From a finite state the tolerance is named as a cause, so
    that a tolerance no step can meet is not taken for a state gone non-finite."""
    tolerance = f"the tolerance rtol = {rtol:g}, atol = {atol:g}"
    if step:
        return f"the step size fell below 10 ulp (no step meets {tolerance} here)"
    if finite:
        return (f"from a finite state, 30 attempts at steps shrinking to 10⁻²¹ of the first had "
                f"a non-finite error estimate or new state (a force singular here, or "
                f"{tolerance}, against which the error norm overflows)")
    return "a non-finite value in the state"


def where(t: float, phi: float, omega: float) -> str:
    """A state as the messages give it: time, angle (also in degrees) and speed (also rpm)."""
    return (f"t = {t:.9g} s, φ = {phi:.9g} rad ({math.degrees(phi):.6g}°), ω = {omega:.9g} rad/s "
            f"({omega * 30.0 / math.pi:.6g} rpm)")


class Watch:
    """Follows a run's blocks (``observe``, as the run streams them) and says at the end what
    the run did (``verdict``). ``columns`` [1] counts the trajectory's columns, for the bytes."""

    def __init__(self, scene, columns: int) -> None:
        self.scene = scene
        self.row_bytes = 8 * columns
        self.reset()

    def reset(self) -> None:
        """Forget what was seen (a run started again from the beginning)."""
        self.samples = 0
        self.idle = 0
        self.reach = (-math.inf, -math.inf)  # the furthest (t, φ) a sample or event reached
        self.last: dict[str, float] = {}
        self.fastest = abs(self.scene.initial.omega)
        self.stops = 0  # passages of the speed through zero (speed_reversal events)
        self.first_stop: tuple[float, float] | None = None  # (t, φ)
        self.last_stop: tuple[float, float] | None = None
        self.stop_range = (math.inf, -math.inf)  # the least and largest φ at a stop
        self.loss_range: dict[str, tuple[float, float]] = {}  # P_loss_k: (least, largest |·|)
        self.seen = False

    def wrap(self, on_block):
        """``on_block`` with this watch in front: a block reaches it first, then the watch."""
        def watched(block, ev, state):
            if on_block:
                on_block(block, ev, state)
            if block is None:
                self.reset()
            else:
                self.observe(block, ev)
        return watched

    def observe(self, block: dict[str, np.ndarray], ev: dict[str, np.ndarray]) -> None:
        """Take in one block; raise :class:`RunStopped` when the run outgrew its budget or made
        no progress over :data:`IDLE_CHUNKS` blocks."""
        self.take(block, ev)
        self._progress(block["t"], block["phi"], ev)
        budget = self.scene.run.max_output_bytes
        if self.samples * self.row_bytes > budget:
            raise RunStopped("over-budget", f"over budget: {self.samples} samples, more than "
                                            f"run.max_output_bytes = {budget:.3g} bytes allow; "
                                            f"stopped at {self._last_where()}")
        if self.idle >= IDLE_CHUNKS:
            raise RunStopped("no-progress", f"no progress: {IDLE_CHUNKS} chunks of steps "
                                            f"brought no new sample or event; stopped after "
                                            f"the last sample, {self._last_where()}")

    def take(self, block: dict[str, np.ndarray], ev: dict[str, np.ndarray]) -> None:
        """Take in a block (or a whole run held in memory) without judging its progress."""
        t, omega = block["t"], block["omega"]
        self.seen = True
        if omega.size:
            self.fastest = max(self.fastest, float(np.max(np.abs(omega))))
        self._stops(ev.get("speed_reversal"))
        if t.size:
            self.last = {k: float(v[-1]) for k, v in block.items()}
            for k, v in block.items():
                if k.startswith("P_loss_") and v.size:
                    low, high = self.loss_range.get(k, (math.inf, 0.0))
                    self.loss_range[k] = (min(low, float(v.min())),
                                          max(high, float(np.abs(v).max())))
        self.samples += t.size

    def _stops(self, rows) -> None:
        """Count the speed's passages through zero and keep the angles they bound."""
        if rows is None or not len(rows):
            return
        rows = np.asarray(rows, dtype=float).reshape(-1, 2)
        self.stops += rows.shape[0]
        self.first_stop = self.first_stop or (float(rows[0, 0]), float(rows[0, 1]))
        self.last_stop = (float(rows[-1, 0]), float(rows[-1, 1]))
        low, high = self.stop_range
        self.stop_range = (min(low, float(rows[:, 1].min())), max(high, float(rows[:, 1].max())))

    def _progress(self, t, phi, ev) -> None:
        """Count the blocks in a row that reach no further than those before."""
        ts = [t[-1]] if t.size else []
        ps = [phi[-1]] if phi.size else []
        for rows in ev.values():
            if len(rows):
                ts.append(float(np.max(rows[:, 0])))
                ps.append(float(np.max(rows[:, 1])))
        reach = (max(ts, default=-math.inf), max(ps, default=-math.inf))
        if reach[0] > self.reach[0] or reach[1] > self.reach[1]:
            self.reach = (max(reach[0], self.reach[0]), max(reach[1], self.reach[1]))
            self.idle = 0
        else:
            self.idle += 1

    def _last_where(self) -> str:
        s = self.last
        return where(s["t"], s["phi"], s["omega"]) if s else "the start"

    def motion(self) -> str:
        """How the shaft moved, from where it stopped and where it ended: ``running`` (never
        stopped, or running again forwards past every angle it reached before its last stop),
        ``reversed`` (turning backwards past every angle it reached since its first stop),
        ``not-started`` (else, if it never turned :data:`STARTED` past its start) or
        ``stalled``. Between two stops φ is monotone, so the stops' angles and the start bound
        every angle reached before the last stop; a swing of a rocking shaft reaches no further
        than the one before it, driven motion does (a shaft turning backwards from the start
        stopped there)."""
        w, phi = self.last["omega"], self.last["phi"]
        ws, phi0 = self.scene.solver.switch_speed, self.scene.initial.phi
        if self.stops == 0 and w > 0.0:
            return "running"
        low, high = self.stop_range
        high = max(high, phi0)
        if self.stops == 0:  # (turning backwards from the start)
            low = phi0
        if w >= ws and phi > high:
            return "running"
        if w <= -ws and phi < low:
            return "reversed"
        return "not-started" if max(high, phi) - phi0 < STARTED else "stalled"

    def verdict(self, status: str, message: str) -> tuple[str, str]:
        """The run's status and message, given those the integration ended with: a run that
        ended by its end time before its revolutions, or did not start, stalled, reversed or ran
        away, is said, with the speed's passages through zero (:data:`STATUSES`)."""
        if status == "failed" and self.fastest > RUNAWAY_SPEED:
            return "runaway", f"runaway: the speed reached {self.fastest:.3g} rad/s; {message}"
        if status == "locked" and self.last:
            never = self._never_turned()
            return status, message + self._stops_said("; ") + (f"; it did not start: {never}"
                                                                if never else "")
        if status not in (FINISHED, "stalled") or not self.last:
            return status, message
        end = self._last_where()
        if self.fastest > RUNAWAY_SPEED:
            return "runaway", (f"runaway: the speed reached {self.fastest:.3g} rad/s (beyond "
                               f"{RUNAWAY_SPEED:g}); at the end {end}")
        reached = self._reached()
        motion = "running" if reached else self.motion()
        stops = self._stops_said("; ")
        if status == "stalled":  # (the stepper stopped a run that ends by revolutions only)
            if motion == "not-started":
                return motion, (f"did not start: {self._never_turned()}; "
                                f"{message.removeprefix('stalled: ')}")
            return status, message
        if motion == "running":
            run = self.scene.run
            if reached or not math.isfinite(run.revolutions) or (
                    run.time and self.last["t"] >= run.time[-1]):  # (a speed table's end)
                return status, message
            revs = (self.last["phi"] - self.scene.initial.phi) / (2.0 * math.pi)
            return "out-of-time", (f"out of time: run.t_end = {self.scene.run.t_end:g} s came "
                                   f"after {revs:.6g} of the {self.scene.run.revolutions:g} "
                                   f"revolutions the scene asks for{stops}; at the end {end}")
        if motion == "reversed":
            return motion, (f"reversed: the shaft was driven backwards{stops}; at the end it "
                            f"turned backwards, {end}")
        if motion == "not-started":
            return motion, f"did not start: {self._never_turned()}{stops}; at the end {end}"
        return motion, (f"stalled: the speed reached zero and the shaft did not run "
                        f"again{stops}; at the end {end}")

    def _reached(self) -> bool:
        """Whether the shaft turned the revolutions the scene asks for (the end is found to the
        solver's tolerance)."""
        target = self.scene.initial.phi + 2.0 * math.pi * self.scene.run.revolutions
        return (math.isfinite(target)
                and target - self.last["phi"] <= self.scene.solver.rtol * max(1.0, abs(target)))

    def _stops_said(self, lead: str) -> str:
        """The speed's passages through zero after ``lead``, for a message: how many, the first
        and the last ("" if none)."""
        first, last = self.first_stop, self.last_stop
        if first is None or last is None:  # (no passage: the first sets both)
            return (f"{lead}it turned backwards from the start"
                    if self.last.get("omega", 0.0) < 0.0 else "")
        t, phi = first
        text = (f"{lead}the speed went through zero {self.stops} time{'s' * (self.stops > 1)}, "
                f"first at t = {t:.9g} s, φ = {phi:.9g} rad ({math.degrees(phi):.6g}°)")
        if self.stops > 1:
            t, phi = last
            text += f", last at t = {t:.9g} s, φ = {phi:.9g} rad ({math.degrees(phi):.6g}°)"
        return text

    def _never_turned(self) -> str:
        """That the shaft never turned :data:`STARTED` forwards (rocking, if its speed went
        through zero twice or more), and how far it got; "" if it did."""
        phi0 = self.scene.initial.phi
        furthest = max(self.stop_range[1], phi0, self.last.get("phi", phi0)) - phi0
        if furthest >= STARTED:
            return ""
        return (f"the shaft {'rocked and ' * (self.stops > 1)}never turned a whole revolution "
                f"forwards (at most {furthest:.6g} rad, {math.degrees(furthest):.6g}°, past its "
                f"start at φ = {phi0:.9g} rad)")

    def warnings(self) -> list[str]:
        """What a finished run should not be read without: the speed's passages through zero
        (the shaft stopped on the way and ran again), and pairs that reported negative losses
        (policy ``"paper"``: criterion (25) can hold a mode against the power it transmits)."""
        out = []
        if self.stops:
            out.append(f"the shaft stopped on the way and ran again: {self._stops_said('')}")
        if self.scene.friction.policy != "paper":  # (the power-flow policy has none by design)
            return out
        for k, (pair, chains) in enumerate(zip(self.scene.friction.pairs,
                                               pair_columns(self.scene))):
            for s, _ in chains:  # (the pair itself; on an elastic line in each throw)
                least, largest = self.loss_range.get(f"P_loss_{s}", (0.0, 0.0))
                where = s[len(f"{k + 1}_"):]  # (the throw's station on an elastic line)
                if least < -LOSS_ROUNDING * largest:
                    out.append(f"pair {k + 1} ({pair.name}){f' at {where}' if where else ''} "
                               f"reported negative losses (P_loss down to {least:.4g} W): "
                               f"under policy {self.scene.friction.policy!r} its mode can "
                               f"stand against the power it transmits; policy \"power-flow\" "
                               f"keeps every loss ≥ 0")
        return out

    def summary(self) -> dict[str, tuple[float, str]]:
        """The speed's passages through zero over the whole run, for the end-of-run summary:
        ``speed_reversals`` [1] and the first one's ``speed_reversal_first_t`` [s] and
        ``speed_reversal_first_phi`` [rad]; nothing if the speed never went through zero."""
        if self.first_stop is None:  # (set at the first passage)
            return {}
        return {"speed_reversals": (float(self.stops), "1"),
                "speed_reversal_first_t": (self.first_stop[0], "s"),
                "speed_reversal_first_phi": (self.first_stop[1], "rad")}


def judge(data, watch: Watch):
    """``data`` (a :class:`~transient.results.RunData`) with its status, message and warnings
    said (:meth:`Watch.verdict`); a run held whole in memory is taken in here."""
    if not watch.seen:
        watch.take(data.trajectory, data.events)
    status = data.status or (FINISHED if data.complete else status_in(data.message))
    data.status, data.message = watch.verdict(status, data.message)
    data.warnings = watch.warnings() if data.status == FINISHED else []
    data.summary = watch.summary()
    return data


def status_in(message: str) -> str:
    """The status a failure's message opens with (``"locked: at rest …"``), else ``failed``."""
    head = message.partition(":")[0]
    return head if head in STATUSES else "failed"


def status_of(exc: BaseException) -> str:
    """The status of a run that ended by the exception ``exc``."""
    if isinstance(exc, RunStopped):
        return exc.status
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted"
    return status_in(str(exc))
