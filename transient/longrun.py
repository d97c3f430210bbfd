"""A long run followed on its envelope (``[solver] multirevolution = true``; docs/guide/steady.md,
"Long runs: multirevolution steps"), written as a result.

:func:`transient.multirev.multirevolution` gives the state at every cycle start and which cycles
it integrated; :func:`transient.run_multirevolution` writes them as they come into a result of
the usual layout (:mod:`transient.results`) with an ``envelope`` group
(:data:`~transient.results.ENVELOPE`): every state at every cycle start, per cycle whether it
was integrated or interpolated, its mean speed Δφ/Δt, and δ and the net work where the file
holds the cycle's trajectory; the error estimate per state at the end. The trajectory holds the
*resolved* cycles: every cycle the envelope integrated (around a load schedule's corners, after
a stiff stretch, the run's last), the cycles at its macro segments' ends, the first and last
of each stretch it interpolated and :data:`~transient.longrun.RESOLVED_ALONG` cycles spread over the run, each
run with output from the envelope's state at its start (by a cycle map of its own, whose cycles
are not the envelope's cost; an integrated cycle is the very cycle the envelope took). Their t
and φ are the run's; their works and losses count from the cycle's start.

The file streams as a run's does (SWMR, a checkpoint after each block of resolved cycles), so
that a kill or an interrupt leaves it readable, marked incomplete, holding the envelope as far
as it went; such a run is not resumed (it starts afresh with ``--force``).
"""
from __future__ import annotations

import math
import re
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .analysis.irregularity import fluctuation
from .core.model import governor as gv
from .errors import SceneError, SimulationError
from .multirev import Envelope, multirevolution, refuse
from .outcome import RunStopped, status_of
from .results import (
    ENVELOPE_CYCLES,
    NOT_RESUMABLE,
    EnvelopeRecord,
    Result,
    ResultWriter,
    RunData,
    check_writable,
    open_result,
    result_in_memory,
)
from .run import CycleMap
from .scene import to_toml
from .scene.budget import VALUE_BYTES
from .scene.outputs import output_columns
from .scene.queries import governor_kind
from .stopping import deferred

#: Agreement with a whole number of cycles that a run's revolutions must reach (relative).
WHOLE = 1e-9
#: Cycles spread evenly over the run that are resolved besides (every cycles/RESOLVED_ALONG-th):
#: the trajectory's δ and work along a macro segment, not at its ends only.
RESOLVED_ALONG = 64
#: The [analysis] requests a multirevolution result cannot answer: they analyse a run's whole
#: trajectory, which it holds for its resolved cycles only.
TRAJECTORY_ANALYSES = ("loads", "orders", "irregularity", "thermodynamics")


def run_cycles(scene) -> int:
    """The engine cycles ``scene``'s run asks for: its ``revolutions``, a whole number of cycles,
    without ``t_end`` (an end in time no cycle start lands on); else a SceneError."""
    run, file = scene.run, scene.source_file
    per_cycle = scene.mechanism.cycle / (2.0 * math.pi)  # (revolutions a cycle)
    if math.isfinite(run.t_end):
        raise SceneError("run.t_end", f"{run.t_end:.9g} s: a multirevolution run (solver."
                                      f"multirevolution) ends after a whole number of cycles; "
                                      f"give run.revolutions alone, a multiple of {per_cycle:g}",
                         file=file)
    n = run.revolutions / per_cycle
    if not (math.isfinite(n) and round(n) >= 1 and abs(n - round(n)) <= WHOLE * n):
        raise SceneError("run.revolutions", f"{run.revolutions:.9g}: a multirevolution run "
                                            f"(solver.multirevolution) follows whole engine "
                                            f"cycles of {per_cycle:g} revolution(s); give a "
                                            f"multiple of {per_cycle:g}", file=file)
    return int(round(n))


def refuse_long_run(scene) -> int:
    """Everything a multirevolution run of ``scene`` cannot do, refused before any work (a
    SceneError naming the key); else the cycles it follows."""
    try:
        refuse(scene)
    except SceneError as exc:
        raise SceneError(exc.key, f"{exc.message} (the multirevolution method follows the cycle "
                                  f"map: set solver.multirevolution = false to integrate every "
                                  f"cycle)", file=exc.file or scene.source_file) from None
    for key in TRAJECTORY_ANALYSES:
        if getattr(scene.analysis, key):
            raise SceneError(f"analysis.{key}", "analyses a run's whole trajectory, which a "
                                                "multirevolution run (solver.multirevolution) "
                                                "holds for its resolved cycles only; drop it, or "
                                                "set solver.multirevolution = false",
                             file=scene.source_file)
    return run_cycles(scene)


def state_units(scene, names: list[str]) -> list[str]:
    """The unit of each periodic state at a cycle start, as :class:`~transient.run.CycleMap`
    gives them (speeds, not energies), and of t."""
    governor = gv.STATE_UNITS[governor_kind(scene.governor)]
    fixed = {"omega": "rad/s", "latched": "1", "pressure": "Pa", "t": "s"}
    units = []
    for name in names:
        block, index = re.fullmatch(r"(\w+)(?:\[(\d+)\])?", name).groups()  # type: ignore[union-attr]
        index = int(index or 0)
        if block == "governor":
            units.append(governor[index])
        elif block == "line":  # (each dof's twist, then its speed)
            units.append("rad" if index % 2 == 0 else "rad/s")
        else:
            units.append(fixed[block])
    return units


class _Recorder:
    """Writes the envelope's cycles as they become final (:meth:`watch`), resolving the ones
    :func:`resolved_cycle` picks, those at the macro segments' ends and every ``every``-th,
    into the writer (a file) or memory."""

    def __init__(self, scene, cycles: int, out: CycleMap, writer: ResultWriter | None
                 ) -> None:
        self.scene, self.cycles, self.writer = scene, cycles, writer
        self.out = out  # (its own: the resolved cycles are no cost of the envelope)
        self.rows_of: list[np.ndarray] = []
        out.rows = self.rows_of
        self.names = [*out.state_names(), "t"]
        self.columns = list(output_columns(scene))
        self.phi_at = self.columns.index("phi")
        self.done = 0  # the cycles written
        # the cycle reached at the last watch, and the macro segments' ends (its nodes)
        self.reached, self.nodes = 0, {0}
        self.every = max(1, math.ceil(cycles / RESOLVED_ALONG))
        self.rows = 0  # the trajectory's rows written
        self.memory: dict[str, list] = {name: [] for name in (
            "states", *ENVELOPE_CYCLES, "resolved", "resolved_end", "trajectory")}
        self.datasets = None if writer is None else writer.envelope
        # the first cycle start: each cycle written adds the start of the next
        self._states(np.append(out.initial(), 0.0)[None, :])

    def watch(self, n: int, states: np.ndarray, integrated: np.ndarray) -> None:
        """The envelope reached cycle ``n``: the cycles before n − 1 are final, with the state
        that ends each and whether the next one was integrated; a jump of more than one cycle
        was a macro segment, whose ends are resolved."""
        if n - self.reached > 1:
            self.nodes.update((self.reached, n))
        self.reached = n
        self.write(n - 1, states, integrated)

    def write(self, upto: int, states: np.ndarray, integrated: np.ndarray) -> None:
        """Cycles ``done`` … ``upto`` − 1: their envelope rows, and the resolved ones'
        trajectories."""
        if upto <= self.done:
            return
        ks = np.arange(self.done, upto)
        t = states[:, -1]
        per_cycle = {"integrated": integrated[ks].astype(float),
                     "mean_omega": self.scene.mechanism.cycle / (t[ks + 1] - t[ks]),
                     "delta": np.full(ks.size, np.nan), "work": np.full(ks.size, np.nan)}
        blocks, resolved, ends = [], [], []
        for j, k in enumerate(ks):
            if not (k in self.nodes or k % self.every == 0
                    or resolved_cycle(int(k), integrated, self.cycles)):
                continue
            rows = self._cycle(int(k), states[k])
            c = self.columns.index
            per_cycle["delta"][j] = fluctuation(
                rows[:, c("t")], rows[:, self.phi_at], rows[:, c("omega")],
                self.scene.mechanism.cycle, rows[0, self.phi_at])
            per_cycle["work"][j] = self.out.net_work
            blocks.append(rows)
            self.rows += rows.shape[0]
            self._budget()
            resolved.append(int(k))
            ends.append(self.rows)
        self._store(states[ks + 1], per_cycle, blocks, resolved, ends)
        self.done = upto

    def _budget(self) -> None:
        """Stop the run (``over-budget``) where its resolved cycles outgrow
        ``run.max_output_bytes``, as a direct run's trajectory is stopped."""
        written = self.rows * len(self.columns) * VALUE_BYTES
        if written > self.scene.run.max_output_bytes:
            raise RunStopped("over-budget", f"over budget: {self.rows} samples of the resolved "
                                            f"cycles, more than run.max_output_bytes = "
                                            f"{self.scene.run.max_output_bytes:.6g} bytes allow")

    def _cycle(self, k: int, X: np.ndarray) -> np.ndarray:
        """Cycle ``k`` run with output from the envelope's state ``X`` at its start: its rows,
        φ the run's."""
        self.rows_of.clear()
        self.out(X[:-1], float(X[-1]))
        rows = np.concatenate(self.rows_of)
        rows[:, self.phi_at] += k * self.scene.mechanism.cycle
        return rows

    def _states(self, states: np.ndarray) -> None:
        """Cycle starts into memory and the file."""
        self.memory["states"].append(states)
        if self.writer is not None and self.datasets is not None:
            self.writer.extend([(self.datasets["states"], states)])

    def _store(self, ends_of, per_cycle, blocks, resolved, ends) -> None:
        """The cycles' rows into memory, or the file: the trajectory's block first, with its
        checkpoint, so that a resolved cycle is never listed without its rows; the state at
        each one's end (``ends_of``) last."""
        m = self.memory
        for name, values in per_cycle.items():
            m[name].append(values)
        m["resolved"] += resolved
        m["resolved_end"] += ends
        if self.writer is None:
            m["trajectory"] += blocks
            self._states(ends_of)
            return
        rows = np.concatenate(blocks) if blocks else np.zeros((0, len(self.columns)))
        self.writer.block({c: rows[:, j] for j, c in enumerate(self.columns)}, {},
                          np.zeros(0), np.zeros(0, np.int64), False, NOT_RESUMABLE)
        ds, writer = self.datasets, self.writer
        assert ds is not None, "a recorder with a writer has its datasets"
        writer.extend([*((ds[name], values) for name, values in per_cycle.items()),
                       (ds["resolved"], np.asarray(resolved, dtype=np.int64)),
                       (ds["resolved_end"], np.asarray(ends, dtype=np.int64))])
        self._states(ends_of)

    def finish(self, env: Envelope) -> None:
        """The cycles left and the error estimate."""
        self.write(self.cycles, env.states, env.integrated)
        if self.datasets is not None:
            self.datasets["error"][:] = env.error  # (flushed as the file is finished)

    def trajectory(self) -> dict[str, np.ndarray]:
        """The resolved cycles' rows kept in memory, by column."""
        blocks = self.memory["trajectory"]
        rows = np.concatenate(blocks) if blocks else np.zeros((0, len(self.columns)))
        return {c: rows[:, j] for j, c in enumerate(self.columns)}

    def record(self, error: np.ndarray) -> EnvelopeRecord:
        """What was written, as the result reads it back."""
        m = self.memory
        cat = {name: np.concatenate(m[name]) if m[name] else np.zeros(0)
               for name in ENVELOPE_CYCLES}
        return EnvelopeRecord(
            names=self.names, units=state_units(self.scene, self.names),
            states=np.concatenate(m["states"]), integrated=cat["integrated"].astype(bool),
            mean_omega=cat["mean_omega"], delta=cat["delta"], work=cat["work"],
            resolved=np.asarray(m["resolved"], dtype=np.int64),
            resolved_end=np.asarray(m["resolved_end"], dtype=np.int64), error=error,
            cycles=self.cycles)


def resolved_cycle(k: int, integrated: np.ndarray, cycles: int) -> bool:
    """Whether a long run's result holds cycle ``k``'s trajectory: an integrated cycle, or the
    first or last of a stretch the envelope interpolated."""
    return bool(integrated[k] or k == 0 or integrated[k - 1] or k == cycles - 1
                or integrated[k + 1])


def run_multirevolution(scene, path: str | Path | None = None, *, force: bool = False,
                        progress: Callable[[int, int, int], None] | None = None) -> Result:
    """Follow ``scene``'s run on the envelope of its cycle map
    (:func:`~transient.multirev.multirevolution`, ``[solver] multirevolution = true``) and
    write it as a result.

    Parameters
    ----------
    scene : Scene
        A dynamic scene of the compiled stepper whose only input that changes with time is a
        load schedule in time, run for a whole number of cycles (``run.revolutions``).
    path : str or Path, optional
        The result file; none keeps the result in memory.
    force : bool
        Replace an existing result at ``path``.
    progress : callable, optional
        Called with (cycle reached, cycles, cycles integrated) as the envelope advances.

    Returns
    -------
    Result
        Its ``envelope`` (:class:`~transient.results.EnvelopeRecord`): every state at every cycle
        start, which cycles were integrated, the error estimate; its trajectory the resolved
        cycles (``envelope.resolved``, each one's rows ``envelope.rows(cycle)``).

    Raises
    ------
    transient.SceneError
        What the envelope cannot follow, a run that is not a whole number of cycles, an
        analysis of the whole trajectory asked for; a result at ``path`` without ``force``:
        before any work.
    transient.SimulationError
        A cycle or the envelope failed, or the run was interrupted; its ``result`` holds what
        was computed (marked incomplete).

    Examples
    --------
    A single cylinder, unfired, with a heavy shaft (2 kg m²), driven by a constant 20 N m
    against a load of 0.1 N m s/rad: it spins up from 1000 rpm towards 200 rad/s over 500
    cycles, which the envelope follows in macro steps; its end agrees with the direct run's
    within the error estimate.

    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 2.0},
    ...     "load": {"torque": -20.0, "linear": 0.1},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 1000},
    ...     "solver": {"rtol": 1e-10, "atol": 1e-12,
    ...                "multirevolution": True}})
    >>> res = transient.run_multirevolution(scene)
    >>> e = res.envelope
    >>> e.cycles, e.states.shape  # every cycle start: its periodic state (ω), and t
    (500, (501, 2))
    >>> direct = transient.simulate(scene.replace(solver={"multirevolution": False}))
    >>> w_end = direct.trajectory["omega"][-1]
    >>> bool(abs(e.column("omega")[-1] - w_end) <= e.error[e.names.index("omega")])
    True
    """
    cycles = refuse_long_run(scene)
    rtol = scene.solver.envelope_rtol
    path = None if path is None else Path(path)
    if path is not None:
        check_writable(path, force)
    out = CycleMap(scene)
    names = [*out.state_names(), "t"]
    writer = None if path is None else ResultWriter(
        path, scene.name, to_toml(scene), output_columns(scene), force=force,
        scene_source=(scene.source_file, scene.source_text),
        envelope=(names, state_units(scene, names), cycles))
    t0 = time.perf_counter()
    recorder = None
    try:
        recorder = _Recorder(scene, cycles, out, writer)
        env = multirevolution(scene, cycles, rtol, progress, recorder.watch)
        recorder.finish(env)
    except BaseException as exc:
        message = "interrupted" if isinstance(exc, KeyboardInterrupt) else (
            str(exc) if isinstance(exc, SimulationError) else f"{type(exc).__name__}: {exc}")
        if writer is not None:  # (published marked incomplete, whatever stopped it)
            with deferred():
                writer.finish(False, message=message, status=status_of(exc))
        if isinstance(exc, (SimulationError, KeyboardInterrupt)):
            raise _stopped(scene, writer, recorder, message, exc) from None
        raise
    solver = {"method": scene.solver.method, "ran": f"multirevolution ({scene.solver.method})",
              "rtol": scene.solver.rtol, "atol": scene.solver.atol, "envelope_rtol": rtol,
              "nfev": env.nfev + recorder.out.nfev, "wall_s": time.perf_counter() - t0}
    analysis = _analysis(scene, env, recorder)
    if writer is None:
        data = RunData(trajectory=recorder.trajectory(), events={}, solver=solver,
                       status="finished")
        res = result_in_memory(scene.name, to_toml(scene), data, output_columns(scene),
                               analysis, (scene.source_file, scene.source_text))
        res.envelope = recorder.record(env.error)
        return res
    with deferred():  # (a stop while the file takes its name would leave neither)
        writer.finish(True, solver=solver, analysis=analysis)
    return open_result(writer.path)


def _analysis(scene, env: Envelope, recorder: _Recorder) -> dict[str, tuple]:
    """The run's end and the envelope's record, as a result's analysis entries."""
    i_w = env.names.index("omega")
    return {"final_t": (float(env.states[-1, -1]), "s"),
            "final_omega": (float(env.states[-1, i_w]), "rad/s"),
            "revolutions": (scene.run.revolutions, "rev"),
            "multirev_cycles": (recorder.cycles, "1"),
            "multirev_cycles_interpolated": (int((~env.integrated[:-1]).sum()), "1"),
            "multirev_cycles_integrated": (env.cycles_integrated, "1"),
            "multirev_rhs_evaluations": (env.nfev, "1"),
            "multirev_cycles_resolved": (recorder.out.cycles, "1"),
            "multirev_envelope_rtol": (scene.solver.envelope_rtol, "1"),
            "multirev_error_omega": (float(env.error[i_w]), "rad/s"),
            "multirev_error_t": (float(env.error[-1]), "s")}


def _stopped(scene, writer: ResultWriter | None, recorder: _Recorder | None, message: str,
             exc: BaseException) -> SimulationError:
    """The error of a run that failed or was interrupted, carrying what it computed: the file
    it published marked incomplete, or what it kept in memory."""
    if writer is not None:
        res = open_result(writer.path)
        where = f"partial result kept in {writer.path} (complete = false)"
    else:
        data = RunData(trajectory=recorder.trajectory() if recorder else {}, events={},
                       solver={}, complete=False, message=message, status=status_of(exc))
        res = result_in_memory(scene.name, to_toml(scene), data, output_columns(scene), {},
                               (scene.source_file, scene.source_text))
        if recorder is not None:
            res.envelope = recorder.record(np.full(len(recorder.names), np.nan))
        where = "the result so far in its .result"
    err = SimulationError(f"{message}; {where}")
    err.result = res
    return err
