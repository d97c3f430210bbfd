"""What a run did, said: its status (the result's root attribute ``status``,
:data:`~transient.outcome.STATUSES`),
a one-line message with the time, angle and speed where it happened, and warnings; and the
watch over a run's blocks that stops a run exceeding its output budget or no longer advancing.

A run that integrated to its end can still have failed the scene: a shaft that stopped, or was
driven backwards by a load larger than the engine (``t_end`` lets the integration go on), or
ran away. Those are read off the blocks as they stream past (:class:`Watch`), since a long run
keeps only its last block in memory.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import SimulationError


#: Every status a run ends with, and what it means (README, "Result files"); a run the stepper
#: ends as ``stiff`` is run again by an implicit method and ends with one of these.
STATUSES = {
    "finished": "ran to its end as the scene describes",
    "interrupted": "stopped by Ctrl-C, SIGTERM or SIGHUP",
    "stalled": "the speed fell to zero and the shaft did not run again (it ends slower than "
               "the switch speed)",
    "reversed": "the shaft was driven backwards and turned backwards at the end (faster than "
                "the switch speed)",
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
#: A speed no piston machine reaches [rad/s] (about 955 000 rpm): beyond it a run ran away.
RUNAWAY_SPEED = 1e5
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
    """The status of the stepper's return code ``code`` (:mod:`transient.core.stepper_io`;
    RUNNING is left only by an interrupt). Imported here, so that the command line reads the
    statuses without loading the compiled core."""
    from .core import stepper_io as sio

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
        self.stop: tuple[float, float] | None = None  # (t, φ) where the speed first reached 0
        self.running = self.scene.initial.omega > 0.0
        self.fastest = abs(self.scene.initial.omega)
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
        t, phi, omega = block["t"], block["phi"], block["omega"]
        self.seen = True
        self._speeds(t, phi, omega, ev.get("speed_reversal"))
        if t.size:
            self.last = {k: float(v[-1]) for k, v in block.items()}
            for k, v in block.items():
                if k.startswith("P_loss_") and v.size:
                    low, high = self.loss_range.get(k, (math.inf, 0.0))
                    self.loss_range[k] = (min(low, float(v.min())),
                                          max(high, float(np.abs(v).max())))
        self.samples += t.size

    def _speeds(self, t, phi, omega, reversal) -> None:
        """Where the speed first reached zero, and the largest speed."""
        if omega.size:
            self.fastest = max(self.fastest, float(np.max(np.abs(omega))))
        if self.stop is None and reversal is not None and len(reversal) and self.running:
            self.stop = (float(reversal[0][0]), float(reversal[0][1]))
        if self.stop is None and omega.size:
            was = np.concatenate([[1.0 if self.running else 0.0], omega[:-1]])
            down = np.flatnonzero((was > 0.0) & (omega <= 0.0))
            if down.size:
                self.stop = (float(t[down[0]]), float(phi[down[0]]))
        self.running = self.running or bool(np.any(omega > 0.0))

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

    def verdict(self, status: str, message: str) -> tuple[str, str]:
        """The run's status and message, given those the integration ended with: a finished
        run that stopped, reversed or ran away, and a failure at a runaway speed, are said."""
        if status == "failed" and self.fastest > RUNAWAY_SPEED:
            return "runaway", f"runaway: the speed reached {self.fastest:.3g} rad/s; {message}"
        if status != FINISHED or not self.last:
            return status, message
        end = self._last_where()
        if self.fastest > RUNAWAY_SPEED:
            return "runaway", (f"runaway: the speed reached {self.fastest:.3g} rad/s (beyond "
                               f"{RUNAWAY_SPEED:g}); at the end {end}")
        omega, ws = self.last["omega"], self.scene.solver.switch_speed
        if omega <= -ws:  # (slower than the switch speed, either way, is rocking at rest)
            return "reversed", (f"reversed: the shaft was driven backwards{self._stopped()} "
                                f"and turned backwards at the end, {end}")
        if (self.stop is not None or omega < 0.0) and omega < ws:
            return "stalled", (f"stalled: the speed reached zero{self._stopped()} and the "
                               f"shaft did not run again; at the end {end}")
        return status, message

    def _stopped(self) -> str:
        if self.stop is None:
            return ""
        t, phi = self.stop
        return f" (it stopped at t = {t:.9g} s, φ = {phi:.9g} rad ({math.degrees(phi):.6g}°))"

    def warnings(self) -> list[str]:
        """What a finished run should not be read without: pairs that reported negative losses
        (policy ``"paper"``: criterion (25) can hold a mode against the power it transmits)."""
        out = []
        if self.scene.friction.policy != "paper":  # (the power-flow policy has none by design)
            return out
        for k, pair in enumerate(self.scene.friction.pairs):
            least, largest = self.loss_range.get(f"P_loss_{k + 1}", (0.0, 0.0))
            if least < -LOSS_ROUNDING * largest:
                out.append(f"pair {k + 1} ({pair.name}) reported negative losses (P_loss down to "
                           f"{least:.4g} W): under policy {self.scene.friction.policy!r} its "
                           f"mode can stand against the power it transmits; policy "
                           f"\"power-flow\" keeps every loss ≥ 0")
        return out


def judge(data, watch: Watch):
    """``data`` (a :class:`~transient.results.RunData`) with its status, message and warnings
    said (:meth:`Watch.verdict`); a run held whole in memory is taken in here."""
    if not watch.seen:
        watch.take(data.trajectory, data.events)
    status = data.status or (FINISHED if data.complete else status_in(data.message))
    data.status, data.message = watch.verdict(status, data.message)
    data.warnings = watch.warnings() if data.status == FINISHED else []
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
