"""Drive a run: the compiled stepper chunk by chunk (or the reference path), streaming to HDF5.

:func:`integrate` returns the run as :class:`~transient.results.RunData`;
:func:`transient.simulate`, the public entry,
returns a :class:`~transient.results.Result`, of a run kept in memory or written to a file.
Prescribed-speed runs (inverse dynamics) take :func:`prescribed`.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .assemble import build_model, initial_governor
from .core import stepper
from .core.integrator.tableaus import TABLEAUS
from .core.model import forcing, layout, work
from .core.model.inverse import inverse_dynamics
from .core.model.layout import n_outputs, n_state
from .core.model.shaft import line_parts
from .core.stepper import io as sio
from .core.stepper.loop import CHATTER_COUNT, STIFF_COUNT
from .errors import SceneError, SimulationError
from .outcome import FINISHED, RunStopped, Watch, code_status, failure_cause, judge, status_of
from .precompile import start_helper, stop_helper
from .prescribed_work import Motion, work_columns
from .results import NOT_RESUMABLE, Result, RunData, open_result, result_in_memory
from .scene.outputs import column_name, output_columns
from .scene.queries import part_load_refusal
from .scene.records import AUTO_METHODS, COMPILED_METHODS, runs_compiled
from .shaft import refuse_elastic_run
from .stopping import deferred

BUFFER_ROWS = 8192
EVENT_ROWS = 2048
#: The end-of-run summary reads back at most this many samples (the end of the run).
SUMMARY_SAMPLES = 500_000


def _config(scene) -> np.ndarray:
    sv, out, run = scene.solver, scene.output, scene.run
    cfg = np.zeros(sio.N_CFG)
    cfg[sio.C_RTOL] = sv.rtol
    cfg[sio.C_ATOL] = sv.atol
    cfg[sio.C_T_END] = run.t_end
    cfg[sio.C_PHI_END] = scene.initial.phi + 2.0 * math.pi * run.revolutions
    cfg[sio.C_W_LO] = sv.switch_speed
    cfg[sio.C_W_HI] = 1.5 * sv.switch_speed  # hysteresis: no chatter around the switch speed
    cfg[sio.C_DPHI_OUT] = 2.0 * math.pi / out.samples_per_rev
    cfg[sio.C_DT_OUT] = out.dt if out.dt > 0 else cfg[sio.C_DPHI_OUT] / cfg[sio.C_W_HI]
    cfg[sio.C_MAX_STEP_PHI] = sv.max_step
    cfg[sio.C_MAX_STEP_T] = sv.max_step / sv.switch_speed
    if sv.domain == "time":  # never to crank angle; steps bounded by the output spacing only
        cfg[sio.C_W_LO] = cfg[sio.C_W_HI] = math.inf
        cfg[sio.C_MAX_STEP_T] = math.inf
    cfg[sio.C_CHUNK_STEPS] = 20000
    cfg[sio.C_FIXED_STEP] = sv.fixed_step
    cfg[sio.C_STIFF_SWITCH] = float(sv.method == "auto")
    return cfg


def _initial_state(scene, model):
    y = np.zeros(n_state(model))
    y[0] = scene.initial.phi
    y[2] = scene.initial.omega
    governor, sleeve = initial_governor(scene, model)
    at = layout.STATE.offsets_for(model)
    y[at[layout.B_GOVERNOR]:at[layout.B_GOVERNOR] + governor.size] = governor
    # the shaft line's dofs at φ₀ and ω₀, untwisted (its speeds are states in time, where a run
    # starts; the stepper makes them energies where it turns to crank angle)
    y[at[layout.B_LINE] + 1:at[layout.B_LINE + 1]:2] = scene.initial.omega
    fst = np.zeros(sio.fst_size(model))
    fst[sio.F_PASSED_BP] = np.nan
    ist = np.zeros(sio.N_IST, dtype=np.int64)
    st = scene.starter
    ist[sio.I_STARTER_ON] = int(st.torque > 0 and scene.initial.omega < st.cutout_speed)
    ist[sio.I_SLEEVE] = sleeve
    return y, fst, ist


def _fraction_done(scene, y) -> float:
    run = scene.run
    f_t = y[1] / run.t_end if math.isfinite(run.t_end) else 0.0
    f_phi = ((y[0] - scene.initial.phi) / (2 * math.pi * run.revolutions)
             if math.isfinite(run.revolutions) else 0.0)
    return min(1.0, max(f_t, f_phi))


def _compile(model, tab, cfg, bp) -> float:
    """Compile (or load from the numba cache) the stepper, on a cold cache with a helper process
    compiling its callees (:mod:`.precompile`); return the seconds it took."""
    t0 = time.perf_counter()
    warm = cfg.copy()
    warm[sio.C_T_END] = 1e-6
    warm[sio.C_PHI_END] = 1e-6
    y = np.zeros(n_state(model))
    y[2] = 1.0
    helper = start_helper(model, tab)
    try:
        stepper.advance(model, layout.extras_of(model), tab, warm, bp, y,
                        np.zeros(sio.fst_size(model)), np.zeros(sio.N_IST, dtype=np.int64),
                        np.empty((1024, n_outputs(model))), np.empty((64, 4)),
                        stepper.buffers(model, tab, y.shape[0]))
    finally:
        stop_helper(helper)
    return time.perf_counter() - t0


def _events_by_name(rows, switching: bool) -> dict[str, np.ndarray]:
    """A chunk's events (rows of code, t, φ, ·) by name, each an (n, 2) array of (t, φ) in the
    order they occurred; the end of a run stopped to switch an inertia in is ``inertia_switch``.
    (Grouped by numpy: a diesel chunk holds thousands of pair switches and breakpoints.)"""
    codes = rows[:, 0].astype(np.int64)
    ev = {}
    for code in np.unique(codes):
        name = sio.EVENT_NAMES[code]
        ev["inertia_switch" if switching and name == "end" else name] = rows[codes == code, 1:3]
    return ev


#: The names of the events a compiled run can write (a result file makes their datasets first).
EVENT_NAMES = (*sio.EVENT_NAMES, "inertia_switch")


def run_compiled(scene, on_block: Callable[[dict, dict, tuple], None] | None = None,
                 progress: Callable[[float], None] | None = None, keep: bool = True,
                 start=None) -> RunData:
    """Integrate a dynamic scene with the compiled stepper (``scene.solver.method``: DOP853 or
    DOPRI5, adaptive or fixed-step); blocks go to ``on_block(block, events, state)`` as they
    come, ``state`` the stepper's after the block (the arguments of
    :meth:`transient.results.ResultWriter.block` after the events).

    With ``keep = False`` the trajectory is not kept in memory (only its last block), so that a
    long run streamed to a file needs bounded memory. A Ctrl-C between chunks ends the run with
    ``complete = False`` and what was computed so far. ``start``, a
    :class:`~transient.results.Checkpoint` of this scene's run, continues that run from it: the
    stepper carries nothing else from a block to the next, so the run goes on bit-identically.
    """
    model, bp, _ = build_model(scene)
    cfg = _config(scene)
    names = list(output_columns(scene))
    auto = _AutoMethod(scene, model)
    tab = TABLEAUS[auto.method]
    extras = layout.extras_of(model)
    compile_s = _compile(model, tab, cfg, bp)
    y, fst, ist = _initial_state(scene, model)
    outbuf = np.empty((BUFFER_ROWS, n_outputs(model)))
    evbuf = np.empty((EVENT_ROWS, 4))
    blocks: list[dict[str, np.ndarray]] = []
    events: dict[str, list[np.ndarray]] = {name: [] for name in sio.EVENT_NAMES}  # kept with keep
    status, message = sio.RUNNING, ""
    # An inertia switched in: the run stops at that time (as at its end), the shaft's inertia and
    # speed jump (switch_inertia), and the run goes on.
    switch_at = scene.load.inertia_time if 0.0 < scene.load.inertia and (
        scene.load.inertia_time < scene.run.t_end) else math.inf
    switched = False
    if start is not None:
        status, switched = _restore(start, y, fst, ist)
        if switched:
            model, switch_at = model._replace(J0=model.J0 + scene.load.inertia), math.inf
    run_cfg = cfg.copy()
    run_cfg[sio.C_T_END] = min(cfg[sio.C_T_END], switch_at)
    t0 = time.perf_counter()
    try:
        while status == sio.RUNNING:
            auto.mark(y, ist)
            status = stepper.advance(model, extras, tab, run_cfg, bp, y, fst, ist, outbuf, evbuf,
                                     stepper.buffers(model, tab, y.shape[0]))
            chosen = auto.after_chunk(status, run_cfg, y, fst, ist)
            if chosen is not None:  # (the state is as a chunk's end leaves it)
                tab, status = TABLEAUS[chosen], sio.RUNNING
                seconds = _compile(model, tab, cfg, bp)
                compile_s, t0 = compile_s + seconds, t0 + seconds  # (no compile in the wall time)
            switching = status == sio.FINISHED and y[layout.T] == switch_at
            block = {name: outbuf[: ist[sio.I_NOUT], j].copy() for j, name in enumerate(names)}
            ev = _events_by_name(evbuf[: ist[sio.I_NEV]], switching)
            ist[sio.I_NOUT] = 0
            ist[sio.I_NEV] = 0
            if switching:
                model = switch_inertia(model, scene.load.inertia, y, ist)
                run_cfg, switch_at, status, switched = cfg, math.inf, sio.RUNNING, True
            if keep or not blocks or block["t"].size:
                blocks = (blocks if keep else []) + [block]
            if keep:
                for k, v in ev.items():
                    events.setdefault(k, []).append(v)
            if on_block:
                on_block(block, ev, (np.concatenate([y, fst]), ist.copy(), switched, status))
            if progress:
                progress(_fraction_done(scene, y))
    except KeyboardInterrupt:
        message = "interrupted"
    wall = time.perf_counter() - t0
    filled = [b for b in blocks if b["t"].size]
    last = ({n: filled[-1][n][-1] for n in ("t", "phi", "omega")} if filled
            else {"t": 0.0, "phi": scene.initial.phi,
                  "omega": scene.initial.omega})
    where = (f"t = {last['t']:.9g} s, φ = {last['phi']:.9g} rad ({math.degrees(last['phi']):.6g}°), "
             f"ω = {last['omega']:.9g} rad/s")
    if message:
        message = f"interrupted; last sample at {where}"
    if status == sio.STALLED:
        how = "the shaft turned backwards" if y[2] < 0.0 else "the speed reached zero"
        message = (f"stalled: {how} at t = {y[1]:.9g} s, φ = {y[0]:.9g} rad "
                   f"({math.degrees(y[0]):.6g}°) before the {scene.run.revolutions:g} revolutions "
                   f"the run ends by; give run.t_end to follow the motion after a stall")
    at = f"t = {y[1]:.9g} s, φ = {y[0]:.9g} rad ({math.degrees(y[0]):.6g}°)"
    if status == sio.LOCKED:
        why = ("nothing in the scene changes them later, so the machine stays there"
               if math.isfinite(scene.run.t_end) else
               "the run ends by revolutions only; give run.t_end to follow it stuck until the "
               "drive exceeds the friction")
        if scene.shaft is not None:  # (a throw's chain: the line has no stuck state per throw)
            why = ("on a throw of the elastic line, whose throws cannot stay stuck in this "
                   "version")
        message = (f"locked: at rest at {at} the friction of the non-ideal pairs holds the "
                   f"applied moments in both directions ({why})")
    if status == sio.CHATTERING:
        event = sio.EVENT_NAMES[int(ist[sio.I_CHATTER_CODE])]
        message = (f"chattering: {CHATTER_COUNT} state events in a row ({event}) without "
                   f"progress at {at} (last sample {where})"
                   + (f"; the {scene.friction.policy!r} criterion has no consistent mode here (a "
                      f"sliding mode), the power-flow policy has one at every state"
                      if event == "pair_mode" and scene.friction.policy != "power-flow" else ""))
    if status == sio.STIFF:
        message = (f"stiff at {at}: in {STIFF_COUNT} steps the estimate h·λ of the "
                   f"dominant eigenvalue exceeded the stability bound {tab.stiff_bound:g} of "
                   f"{scene.solver.method} (Hairer's test), so stability, not accuracy, sets "
                   f"the step (a governor or actuator far faster than the engine?)")
    if status in (sio.FAIL_NONFINITE, sio.FAIL_STEP):
        cause = failure_cause(status == sio.FAIL_STEP, bool(np.all(np.isfinite(y))),
                              scene.solver.rtol, scene.solver.atol)
        message = (f"integration failed at t = {y[1]:.9g} s, φ = {y[0]:.9g} rad "
                   f"({math.degrees(y[0]):.6g}°) (last good sample {where}): {cause}")
    solver = {"method": scene.solver.method, "fixed_step": scene.solver.fixed_step,
              "rtol": scene.solver.rtol, "atol": scene.solver.atol,
              "nfev": int(ist[sio.I_NFEV]), "nsteps": int(ist[sio.I_NSTEPS]),
              "nreject": int(ist[sio.I_NREJECT]), "wall_s": wall, "compile_s": compile_s,
              "mode_switches": int(ist[sio.I_NSWITCH]), "mode_ties": int(ist[sio.I_NTIES]),
              **_kinematics_attrs(scene)}
    if auto.elastic_auto:  # (which methods ran, from where)
        solver["ran"] = auto.said
        solver["auto_trial_nfev"] = auto.trial_nfev
    held = int(ist[sio.I_NSTIFF_STEPS])
    if model.line[0, layout.LM_DOFS] > 0:
        solver["held_steps"] = held  # (by stability, after the stiffness test fired)
    if scene.solver.method != "auto" and held >= HINT_SHARE * ist[sio.I_NSTEPS] > 0:
        solver["stability_hint"] = stability_hint(scene, held, int(ist[sio.I_NSTEPS]))
    traj = {n: np.concatenate([b[n] for b in blocks] or [np.zeros(0)]) for n in names}
    return RunData(traj, {k: np.concatenate(v) for k, v in events.items() if v},
                   solver, complete=status == sio.FINISHED, message=message,
                   status=code_status(status))


class CycleMap:
    """One engine cycle of the compiled stepper, φ₀ → φ₀ + the mechanism's cycle, from a given
    state: the cycle map Φ of a periodic steady state (:mod:`transient.shooting`). The scene's
    settings, breakpoints and output grid are the run's (so that Φ is the map a run applies
    cycle after cycle, to the step), compiled once; each cycle starts the stepper afresh at φ₀,
    t = 0, with the works and losses zero and the switches chosen at the state as a run's start
    chooses them, so that Φ is a function of the periodic states alone
    (:func:`~transient.core.model.layout.periodic_states`). Its output rows are dropped, bar the
    last, whose speeds give the state at the cycle's end back in the start's form (the speeds,
    not the energies K = ½Jω² the stepper holds in crank angle).

    ``neutral_at``: the places in x of the twists nothing depends on (``_free_dofs``).
    ``start(x, t)``: the stepper's state (y, fst, ist) at the cycle's start with the periodic
    states ``x`` at time ``t`` (0 by default); ``__call__(x, t)``: the periodic states after one
    cycle (and ``elapsed``, its duration), or a
    :class:`~transient.errors.SimulationError` saying where the cycle failed. ``rows``: a list
    that collects the output rows of the cycles run while it is set (a long run's resolved
    cycles, :mod:`transient.longrun`)."""

    def __init__(self, scene) -> None:
        model, self.bp, _ = build_model(scene)
        self.model = model
        self.cfg = _config(scene)
        self.cfg[sio.C_T_END] = math.inf
        self.cfg[sio.C_STIFF_SWITCH] = 0.0  # (one method throughout: Φ must be one function)
        self.cycle = scene.mechanism.cycle
        self.cfg[sio.C_PHI_END] = scene.initial.phi + self.cycle
        self.tab = TABLEAUS[_AutoMethod(scene, model).method]
        self.extras = layout.extras_of(model)
        self.compile_s = _compile(model, self.tab, self.cfg, self.bp)
        self.y0, self.fst0, self.ist0 = _initial_state(scene, model)
        self.index = layout.periodic_states(model)
        at = self.offsets = layout.STATE.offsets_for(model)
        columns = list(output_columns(scene))
        # the periodic states that are speeds (the shaft's, each other line dof's), and the
        # output column that holds each at the cycle's end
        speeds = [(layout.OMEGA, columns.index("omega"))]
        if scene.shaft is not None:
            ref = int(model.line[0, layout.LM_REF])
            others = [name for d, (name, _, _) in enumerate(scene.shaft.line_dofs()) if d != ref]
            speeds += [(at[layout.B_LINE] + 2 * j + 1,
                        columns.index(f"omega_{column_name(name)}"))
                       for j, name in enumerate(others)]
        where = {int(i): k for k, i in enumerate(self.index)}
        self.speed_at = np.array([where[i] for i, _ in speeds], dtype=np.int64)
        self.speed_column = np.array([c for _, c in speeds], dtype=np.int64)
        self.neutral_at = np.array([where[at[layout.B_LINE] + 2 * j]
                                    for j in _free_dofs(model)], dtype=np.int64)
        self.free = np.ones(self.index.size, dtype=bool)  # the unknowns of the shooting
        self.free[self.neutral_at] = False
        self.outbuf = np.empty((BUFFER_ROWS, n_outputs(model)))
        self.evbuf = np.empty((EVENT_ROWS, 4))
        self.nfev = 0
        self.cycles = 0
        self.elapsed = math.nan  # the last cycle's duration [s]
        self.events: tuple[int, ...] = ()  # the last cycle's switching events (``_switches``)
        self.net_work = math.nan  # the last cycle's W_gas + W_load + W_starter − losses [J]
        # (up to where it stopped, if it failed)
        # a list to collect the cycles' output rows in (the columns of ``output_columns``),
        # or None to drop them
        self.rows: list[np.ndarray] | None = None

    def initial(self) -> np.ndarray:
        """The scene's initial state's periodic states."""
        return self.y0[self.index].copy()

    def state_names(self) -> list[str]:
        """The periodic states' names (the state's blocks, numbered within each)."""
        at = self.offsets
        names = []
        for k, b in enumerate(layout.STATE.blocks):
            if layout.PERIODIC[b.name]:
                n = at[k + 1] - at[k]
                names += [b.name] if n == 1 else [f"{b.name}[{j}]" for j in range(n)]
        return names

    def start(self, x: np.ndarray, t: float = 0.0):
        """The stepper's state at the cycle's start with the periodic states ``x``, at time
        ``t`` (a load schedule's place; the switches are chosen there as a run's start does)."""
        y, fst, ist = self.y0.copy(), self.fst0.copy(), self.ist0.copy()
        y[self.index] = x
        y[layout.T] = t
        return y, fst, ist

    def __call__(self, x: np.ndarray, t: float = 0.0) -> np.ndarray:
        if not x[self.speed_at[0]] >= self.cfg[sio.C_W_HI]:  # (also NaN)
            self.net_work = math.nan
            raise SimulationError(f"the cycle from ω = {x[self.speed_at[0]]:.9g} rad/s would "
                                  f"start in time, below 1.5 × solver.switch_speed")
        y, fst, ist = self.start(x, t)
        status = sio.RUNNING
        last = None
        events: list[int] = []
        while status == sio.RUNNING:
            status = stepper.advance(self.model, self.extras, self.tab, self.cfg, self.bp, y, fst,
                                     ist, self.outbuf, self.evbuf,
                                     stepper.buffers(self.model, self.tab, y.shape[0]))
            if ist[sio.I_NOUT]:
                last = self.outbuf[ist[sio.I_NOUT] - 1].copy()
                if self.rows is not None:
                    self.rows.append(self.outbuf[:ist[sio.I_NOUT]].copy())
            events += _switches(self.evbuf[:ist[sio.I_NEV], 0])
            ist[sio.I_NOUT] = ist[sio.I_NEV] = 0
        self.events = tuple(events)
        self.nfev += int(ist[sio.I_NFEV])
        self.cycles += 1
        self.elapsed = float(y[layout.T] - t)
        at = self.offsets
        self.net_work = float(y[layout.W_GAS] + y[layout.W_LOAD] + y[layout.W_STARTER]
                              - y[at[layout.B_LOSS]:at[layout.B_LOSS + 1]].sum()
                              - y[at[layout.B_LINE_LOSS]:at[layout.B_LINE_LOSS + 1]].sum())
        if status != sio.FINISHED:
            raise SimulationError(
                f"the cycle from ω = {x[self.speed_at[0]]:.9g} rad/s stopped "
                f"{_CYCLE_ENDS.get(status, 'failing')} at t = {y[layout.T]:.9g} s, "
                f"φ = {y[layout.PHI]:.9g} rad")
        if last is None:  # (the output grid puts a row at the cycle's end)
            raise SimulationError("the cycle wrote no output row at its end")
        out = y[self.index].copy()
        out[self.speed_at] = last[self.speed_column]
        return out


def _switches(codes: np.ndarray) -> list[int]:
    """The codes of the events that switch something (a pair's mode, the governor's branch, a
    load segment, …), in their order: a cycle's breakpoints and its end come every cycle alike,
    and say nothing of a change of regime."""
    return [int(c) for c in codes if c != sio.EV_BREAKPOINT and c != sio.EV_END]


def _free_dofs(model) -> list[int]:
    """The shaft line's dofs other than the reference (numbered as their states) that turn
    freely against it: no cylinder, not the load's, and only dampers to the rest (a damper's
    ring). Nothing depends on such a dof's twist, so any value of it repeats: a periodic
    state's neutral direction, multiplier 1."""
    n = layout.line_dofs(model)
    if n == 0:
        return []
    cylinders, _, elements = getattr(line_parts, "py_func", line_parts)(model.line)
    meta = model.line[0]
    others = [d for d in range(n) if d != int(meta[layout.LM_REF])]
    held = {int(c) for c in cylinders} | {int(meta[layout.LM_LOAD])}
    for e in elements:
        if e[layout.EL_K] != 0.0:
            held |= {int(e[layout.EL_I]), int(e[layout.EL_J])}
    return [j for j, d in enumerate(others) if d not in held]


#: How a cycle of :class:`CycleMap` that did not reach its end stopped, by the stepper's code.
_CYCLE_ENDS = {sio.STALLED: "stalled", sio.LOCKED: "locked", sio.CHATTERING: "chattering",
               sio.STIFF: "stiff", sio.FAIL_NONFINITE: "with non-finite values",
               sio.FAIL_STEP: "with a step below rounding"}


#: The share of an elastic run's explicit steps held by stability from which the run says so.
HINT_SHARE = 0.25
#: The steps of each method's trial in an ``"auto"`` run on an elastic line.
AUTO_TRIAL_STEPS = 400


def stability_hint(scene, held: int, steps: int) -> str:
    """What to do about an elastic run whose explicit steps the stiffness test found held by
    stability (``held`` of its ``steps``): the line's stiff sections, not accuracy, set them."""
    return (f"{held} of {steps} steps of {scene.solver.method} were held by stability, not "
            f"accuracy (Hairer's stiffness test: the shaft line's stiffest sections); "
            f"solver.method = \"auto\" tries ROS34PW2 from there and keeps the method that "
            f"advances further per derivative evaluation (\"ros34pw2\" runs it throughout)")


class _AutoMethod:
    """The compiled method of a run, and ``solver.method = "auto"``'s choice on an elastic
    line: DOP853 until Hairer's stiffness test finds its steps held by stability (the stepper
    then returns STIFF, the state left as a chunk's end leaves it, state S); then, from S, a
    trial of AUTO_TRIAL_STEPS steps of ROS34PW2, whose result is discarded (the stepper's state
    put back to S), and as many of DOP853, which the run keeps; the method that advanced the
    shaft further per evaluation of the derivative over its trial from S runs the rest, and
    the test is not run again. ``said``: which ran, from where; ``trial_nfev``: the evaluations
    of the discarded trial (not in the run's count)."""

    def __init__(self, scene, model) -> None:
        auto = scene.solver.method == "auto"
        self.elastic_auto = auto and model.line[0, layout.LM_DOFS] > 0
        self.choosing = self.elastic_auto
        self.method = AUTO_METHODS[0] if auto else scene.solver.method
        self.said = self.method
        self.trial_nfev = 0
        self.phase = ""  # "", then "implicit" and "explicit": the trials under way
        self.saved: tuple = ()  # S: y, fst, ist, and the chunk's steps
        self.implicit = 0.0  # the W-method's progress over its trial
        self.at = (0.0, 0)
        self.t = ""  # where the trials began

    def mark(self, y, ist) -> None:
        """A chunk starts at ``y``."""
        self.at = (float(y[layout.PHI]), int(ist[sio.I_NFEV]))

    def _progress(self, y, ist) -> float:
        """The shaft's angle per derivative evaluation over the chunk [rad]."""
        return (y[layout.PHI] - self.at[0]) / max(int(ist[sio.I_NFEV]) - self.at[1], 1)

    def after_chunk(self, status: int, cfg, y, fst, ist) -> str | None:
        """The method to go on with after a chunk that ended with ``status`` at ``y`` (the
        stepper's state ``fst``, ``ist``, put back to S after the W-method's trial; the
        settings ``cfg`` set for what follows), or None to go on as before."""
        if not self.choosing:
            return None
        explicit, implicit = AUTO_METHODS
        if not self.phase:
            if status != sio.STIFF:
                return None
            kept = ist.copy()
            kept[sio.I_NOUT] = kept[sio.I_NEV] = 0  # (what the chunk wrote is drained)
            self.saved = (y.copy(), fst.copy(), kept, cfg[sio.C_CHUNK_STEPS])
            cfg[sio.C_CHUNK_STEPS], cfg[sio.C_STIFF_SWITCH] = AUTO_TRIAL_STEPS, 0.0
            self.phase, self.t = "implicit", f"t = {y[layout.T]:.9g} s"
            return implicit
        if status != sio.RUNNING:  # (the run ended in a trial: as it ran)
            self.choosing = False
            if self.phase == "implicit":
                self.said = f"{explicit}, then {implicit} from {self.t}"
            return None
        if self.phase == "implicit":
            self.implicit = self._progress(y, ist)
            self.trial_nfev = int(ist[sio.I_NFEV]) - self.at[1]
            y[:], fst[:], ist[:] = self.saved[0], self.saved[1], self.saved[2]
            self.phase = "explicit"
            return explicit
        progress = self._progress(y, ist)
        cfg[sio.C_CHUNK_STEPS], self.choosing = self.saved[3], False
        rates = (f"{self.implicit:.3g} against {progress:.3g} rad per evaluation over "
                 f"{AUTO_TRIAL_STEPS} steps from {self.t}")
        if self.implicit > progress:
            self.said = (f"{explicit}, then {implicit} from t = {y[layout.T]:.9g} s "
                         f"({rates})")
            return implicit
        self.said = f"{explicit} ({implicit} tried: {rates})"
        return None


def _restore(start, y, fst, ist) -> tuple[int, bool]:
    """The stepper's state ``y``, ``fst``, ``ist`` set from the checkpoint ``start``; returns its
    return code and whether the extra inertia was in."""
    if start.floats.size != y.size + fst.size or start.ints.size != ist.size:
        raise SimulationError(f"the checkpoint holds a state of {start.floats.size} + "
                              f"{start.ints.size} numbers, this scene's stepper {y.size + fst.size}"
                              f" + {ist.size}: it was written by another version of transient")
    y[:] = start.floats[:y.size]
    fst[:] = start.floats[y.size:]
    ist[:] = start.ints
    return start.code, start.switched


def switch_inertia(model, extra: float, y, ist):
    """Couple the inertia ``extra`` [kg m²], at rest, to the shaft (an inelastic engagement):
    J(φ)ω is conserved, ω₊ = J ω₋/(J + J_x); the energy lost, ½Jω₋² − ½(J + J_x)ω₊², is taken
    from ``W_load``, so that the work–energy balance still closes. Updates the state ``y`` and
    the switches that depend on the speed, which jumped across their levels without an event
    (the governor's branch, the generator's, the speed map's interval); returns the model with
    the extra inertia on the shaft (``J0``)."""
    angle_mode = ist[sio.I_ANGLE_MODE] == 1
    J = forcing.inertia(model, y[layout.PHI], work.work_array(model))
    w = forcing.speed(J, angle_mode, y)
    w_new = J * w / (J + extra)
    y[layout.W_LOAD] -= 0.5 * J * w * w - 0.5 * (J + extra) * w_new * w_new
    if angle_mode:
        y[layout.KINETIC] = 0.5 * (J + extra) * w_new * w_new
    else:
        y[layout.OMEGA] = w_new
    ist[sio.I_GOV_BRANCH] = forcing.start_branch(model, layout.extras_of(model), w_new, y)
    ist[sio.I_GEN_LOW] = forcing.generator_branch(model, w_new, True)
    ist[sio.I_LOAD_TABLE] = forcing.speed_knot_segment(model, w_new, True)
    ist[sio.I_F_VALID] = 0  # the derivative the last chunk left is the old state's
    return model._replace(J0=model.J0 + extra)


def _kinematics_attrs(scene) -> dict:
    """How J(φ) and u_k(φ) were evaluated: ``kinematics`` exact or tabulated, and for tables
    their size, estimated relative error and the tolerance they had to meet."""
    from .assemble import kinematics_table

    kin = kinematics_table(scene)
    if kin is None:
        return {"kinematics": "exact"}
    if kin.coef is None:
        return {"kinematics": "exact (no table reached the tolerance)",
                "table_tolerance": kin.target, "table_error": kin.error,
                "table_intervals": kin.intervals}
    return {"kinematics": "tabulated", "table_tolerance": kin.target, "table_error": kin.error,
            "table_intervals": kin.intervals}


def prescribed(scene, fuel: float = 1.0) -> RunData:
    """Inverse dynamics at a prescribed speed: the drive torque on the shaft that the chain needs
    (the textbook analysis at given ω). ``fuel`` sets the pressure between the motored and the
    full-load curve as the governor's command does, p = p_mot + fuel·(p_full − p_mot) (p_mot zero
    force for a force pulse): the tables' cubics are blended, so the ``p_<k>`` columns hold the
    pressure applied. A fuel below 1 for a model that cannot burn less (a table without its
    motored curve, a compressor: :func:`transient.scene.queries.part_load_refusal`) is a SceneError.
    The work columns are integrated over the motion to the scene's tolerance
    (:mod:`.prescribed_work`)."""
    why = part_load_refusal(scene) if fuel != 1.0 else None
    if why:
        raise SceneError("fuel", f"{fuel:g}: {why}")
    model, _, _ = build_model(scene, part_load=fuel != 1.0)
    coef = model.coef.copy()
    if model.has_motored:  # columns 0–3 full load, 4–7 motored (core.layout.Model)
        coef[:, :4] = coef[:, 4:] + fuel * (coef[:, :4] - coef[:, 4:])
    else:
        coef *= fuel
        coef[:, 0] += (1.0 - fuel) * model.gas_offset
    model = model._replace(coef=coef)
    run = scene.run
    phi0 = scene.initial.phi
    dphi = 2.0 * math.pi / scene.output.samples_per_rev
    motion = Motion.of(scene)
    if run.time:
        # ω(t) as the scene interpolates it (linear or monotone cubic: neither overshoots the
        # table's speeds); φ its exact integral, ε its derivative
        t_end = min(run.t_end, run.time[-1])
        n = int(math.ceil((motion.at(np.array([t_end]))[0][0] - phi0) / dphi)) + 1
        t = np.linspace(run.time[0], t_end, max(n, 2))
        phi, omega, eps = motion.at(t)
        stop = phi <= phi0 + 2 * math.pi * run.revolutions
        t, omega, eps, phi = t[stop], omega[stop], eps[stop], phi[stop]
    else:
        w = run.speed
        phi_end = phi0 + min(2 * math.pi * run.revolutions, w * run.t_end)
        phi = np.linspace(phi0, phi_end, int(round((phi_end - phi0) / dphi)) + 1)
        t = (phi - phi0) / w
        omega = np.full_like(phi, w)
        eps = np.zeros_like(phi)
    rows = np.empty((phi.size, n_outputs(model)))
    drive = np.empty(phi.size)
    n_ok = np.empty(phi.size, dtype=np.int64)
    t0 = time.perf_counter()
    inverse_dynamics(model, layout.extras_of(model), t[:1], phi[:1], omega[:1], eps[:1], rows[:1],
                     drive[:1], n_ok[:1])
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    inverse_dynamics(model, layout.extras_of(model), t, phi, omega, eps, rows, drive, n_ok)
    names = list(output_columns(scene))
    traj = {name: rows[:, j].copy() for j, name in enumerate(names) if name not in ("M_drive", "W_drive")}
    traj["M_drive"] = drive
    sv = scene.solver
    works, counts = work_columns(model, motion, t, phi, names, len(scene.friction.pairs),
                                 sv.rtol, sv.atol)
    traj.update(works)
    solver = {"method": "prescribed", "rtol": sv.rtol, "atol": sv.atol,
              "nfev": int(phi.size) + counts["quadrature_evaluations"], "nsteps": 0,
              "nreject": 0, "wall_s": time.perf_counter() - t0, "compile_s": compile_s,
              "ambiguous_samples": int(np.count_nonzero(n_ok > 1)),
              "inconsistent_samples": int(np.count_nonzero(n_ok == 0)), **counts}
    return RunData(traj, {}, solver)


def integrate(scene, on_block=None, progress=None, keep=True, start=None, before=()) -> RunData:
    """Run a scene by the method it names (compiled, reference or prescribed); see run_compiled
    for ``keep`` and ``start``, and ``before`` the (block, events) the run continued from
    ``start`` wrote before it. The run comes back judged (:func:`transient.outcome.judge`) over
    all of it; a run that outgrows its output budget or stops advancing raises
    :class:`~transient.outcome.RunStopped` after its blocks so far went to ``on_block``."""
    refuse_elastic_run(scene)
    watch = Watch(scene, len(output_columns(scene)))
    for block, events in before:
        watch.take(block, events)
    if scene.run.mode == "prescribed-speed":
        data = prescribed(scene)
    elif scene.solver.method in COMPILED_METHODS:
        data = run_compiled(scene, watch.wrap(on_block), progress, keep, start)
        if data.message.startswith("stiff") and scene.shaft is None:  # (the implicit path
            # has no elastic line: an elastic run found stiff stays failed, as it says)
            data = _implicit_rerun(scene, data, watch.wrap(on_block), progress)
    else:
        from .reference import run_reference

        data = run_reference(scene, on_block, progress)
    return judge(data, watch)


def _implicit_rerun(scene, stiff: RunData, on_block, progress) -> RunData:
    """A stiff scene again from the start by the reference path's implicit Radau method
    (solve_ivp), which stability does not bound; the result says so (``solver.stiff_rerun``)."""
    import dataclasses

    from .reference import run_reference

    note = f"{stiff.message}; rerun from the start with the implicit scipy-Radau"
    radau = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver,
                                                                  method="scipy-Radau"))
    if on_block:  # (what the explicit run streamed is superseded: start the file afresh)
        on_block(None, None, None)
    data = run_reference(radau, None, progress)
    data.solver["stiff_rerun"] = note
    data.solver["explicit_nsteps"] = stiff.solver["nsteps"]
    return data


class _WriteBehind:
    """Writes a block in a second thread while the stepper computes the next one: the compiled
    ``advance`` runs without the GIL (``nogil``), and compressing a block costs a sizeable part
    of computing it at dense output. One write at a time, so the file takes the blocks in the
    run's order and memory stays bounded; a write's exception is raised in the caller by
    :meth:`wait`."""

    def __init__(self) -> None:
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="transient-write")
        self._pending: Future | None = None

    def start(self, fn, *args) -> None:
        """Begin ``fn(*args)`` after the write in progress has ended."""
        with deferred():
            self._wait()
            self._pending = self._pool.submit(fn, *args)

    def wait(self) -> None:
        """Wait for the write in progress, raising what it raised. A stop signal meanwhile acts
        once the wait is over: raised inside the futures' locks, it could leave one of them held
        and the writing thread blocked on it for ever."""
        with deferred():
            self._wait()

    def _wait(self) -> None:
        if self._pending is not None:
            pending, self._pending = self._pending, None
            pending.result()

    def settle(self) -> None:
        """Wait for the write in progress, ignoring its failure (the run has failed already,
        and the writer remembers a broken write)."""
        try:
            self.wait()
        except Exception:
            pass

    def shutdown(self) -> None:
        self.settle()
        self._pool.shutdown(wait=True)


def simulate(scene, path: str | Path | None = None, *, force: bool = False, resume: bool = False,
             progress: Callable[[float], None] | None = None) -> Result:
    """Run ``scene``: in memory without ``path``, streamed to the result file ``path`` with it
    (see :mod:`transient.results`); the :class:`~transient.results.Result` is the same either
    way (a file's columns are read when first used).

    Parameters
    ----------
    scene : Scene
        A scene from :func:`transient.load_scene` or :meth:`Scene.from_dict
        <transient.Scene.from_dict>`.
    path : str or Path, optional
        The result file; none keeps the run in memory.
    force : bool
        Replace an existing result (and a partial one) at ``path``.
    resume : bool
        Continue the run that an interrupt or a kill stopped, from the last checkpoint of its
        partial file (or of its incomplete result), bit-identically to a run never stopped.
    progress : callable, optional
        Called with the fraction done (0 … 1) after each block.

    Returns
    -------
    Result
        The finished run: its trajectory, events, solver statistics and analyses.

    Raises
    ------
    transient.SimulationError
        The run failed or was interrupted; its ``result`` holds the run up to there (written
        to ``path``, marked incomplete, when one was given).
    transient.SceneError
        ``force`` or ``resume`` without a ``path``; a result at ``path`` without ``force``.

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> res = transient.simulate(scene)
    >>> res.status
    'finished'
    >>> res.units["omega"], res.summary()["revolutions"]
    ('rad/s', 2.0)
    >>> import math
    >>> omega0 = res.trajectory["omega"][0]  # [rad/s]
    >>> math.isclose(omega0, 1000 * 2 * math.pi / 60)
    True
    """
    if scene.solver.multirevolution:  # (what the scene asks is the envelope, not every cycle)
        raise SceneError("solver.multirevolution", "true: transient.run_multirevolution(scene) "
                                                   "(as `transient run`) follows the run on its "
                                                   "envelope; simulate integrates every cycle: "
                                                   "set it false for that",
                         file=scene.source_file)
    return simulate_from(scene, None, path, force=force, resume=resume, progress=progress)


def simulate_from(scene, start, path: str | Path | None = None, *, force: bool = False,
                  resume: bool = False, progress: Callable[[float], None] | None = None,
                  analysis: dict[str, tuple] | None = None, periodic: bool = False) -> Result:
    """:func:`transient.simulate` from the stepper's state ``start`` (a
    :class:`~transient.results.Checkpoint`; None: the scene's initial state), with ``analysis``
    (name → (value, unit)) stored beside the run's own; a ``periodic`` run (steady cycles) is
    summarised as steady from its start."""
    refuse_elastic_run(scene)  # (before any file is made)
    if path is None:
        if force or resume:
            raise SceneError("path", "force and resume apply to a result file: give its path")
        return _in_memory(scene, progress, start, analysis or {}, periodic)
    try:
        _write(scene, Path(path), force, resume, progress, start, analysis or {}, periodic)
    except RunStopped as exc:  # (written as far as it went)
        raise _with_result(exc, open_result(path), path) from None
    res = open_result(path)
    if res.status != FINISHED:
        raise _with_result(SimulationError(res.message), res, path)
    return res


def _with_result(exc: SimulationError, res: Result, path: str | Path) -> SimulationError:
    """``exc`` carrying the result ``res``, its message saying where the result is."""
    exc.args = (f"{exc}; result in {path} (status = {res.status})" if res.complete else
                f"{exc}; partial result kept in {path} (complete = false)",)
    exc.result = res
    return exc


def _in_memory(scene, progress, start, analysis, periodic=False) -> Result:
    """A run kept in memory, with its summary, as a Result."""
    from .analysis.summary import summarize
    from .scene import to_toml

    data = integrate(scene, progress=progress, start=start)
    summary = {**(summarize(scene, data.trajectory, data.events, periodic)
                  if data.trajectory["t"].size else {}), **data.summary, **analysis}
    res = result_in_memory(scene.name, to_toml(scene), data, output_columns(scene), summary,
                           (scene.source_file, scene.source_text))
    if res.status != FINISHED:
        raise SimulationError(f"{data.message} (status = {res.status})", res)
    return res


def _write(scene, path: Path, force: bool, resume: bool, progress, start, analysis,
           periodic=False) -> None:
    """Stream a run into the result file ``path`` (:class:`~transient.results.ResultWriter`),
    its summary from the end of the run."""
    from .analysis.summary import summarize
    from .results import ResultWriter
    from .scene import to_toml

    streamed = runs_compiled(scene)
    if resume and not streamed:
        raise SceneError("solver.method", f"{scene.solver.method!r}: only runs of the compiled "
                         f"stepper (DOP853, DOPRI5) can be resumed; run it again with --force")
    writer = ResultWriter(path, scene.name, to_toml(scene), output_columns(scene),
                          EVENT_NAMES, force=force, resume=resume,
                          scene_source=(scene.source_file, scene.source_text))
    writes = _WriteBehind()
    data = None
    try:
        def on_block(block, ev, state):
            writes.wait()
            if block is None:  # the run starts again (a stiff scene, by an implicit method)
                writer.restart()
                return
            writes.start(writer.block, block, ev, *state)

        data = integrate(scene, on_block=on_block, progress=progress, keep=False,
                         start=writer.checkpoint or start, before=writer.written_blocks())
        writes.wait()
        if not streamed or "stiff_rerun" in data.solver:  # written whole, not resumable
            writer.block(data.trajectory, data.events, np.zeros(0), np.zeros(0, np.int64), False,
                         NOT_RESUMABLE)
        # The summary looks at the end of the run: its last SUMMARY_SAMPLES samples, so that
        # memory stays bounded however long the run (steady state, efficiency are found there).
        tail = writer.read_trajectory(last=SUMMARY_SAMPLES)
        events = writer.read_events(t_from=tail["t"][0] if tail["t"].size else -math.inf)
        summary = {**(summarize(scene, tail, events, periodic) if tail["t"].size else {}),
                   **data.summary, **analysis}
    except BaseException as exc:
        writes.settle()
        msg = data.message if data is not None and data.message else (
            str(exc) if isinstance(exc, SimulationError) else f"{type(exc).__name__}: {exc}")
        with deferred():
            writes.shutdown()
            writer.finish(False, msg, status_of(exc), data.solver if data is not None else None)
        raise
    # (the write-behind's end inside the deferral too: a stop there would skip the finish)
    with deferred():
        writes.shutdown()
        writer.finish(data.complete, data.message, data.status, data.solver, summary,
                      data.warnings)
