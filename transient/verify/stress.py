"""The stress suite: hostile scenes, each run with a hard time bound, each checked against an
invariant or an expected diagnosis; the report ``results/stress.md``. One idea, kept in one
module: the catalogue's cases and the harness that bounds and judges them read each other's
fields throughout.

Every case ends in one of three ways, and the report says which:

* **pass** — the run did what the case expects: it completed and its invariant holds (the
  work–energy balance ½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load + W_starter − Σ W_loss,k closes to
  a tolerance tied to rtol, every stored value is finite, plus the case's own checks), or it
  stopped with the diagnosis the case expects (stalled, locked, …) naming time, angle and state;
* **FAIL** — anything else: a wrong answer, a non-finite value, an unexpected stop, an exception,
  or the time bound reached (the run is then killed: zero hangs);
* **known failure** — a FAIL the suite has found and that is written up but not yet fixed
  (``Case.known``): it stays in the report, marked, never hidden.

Scenes are built from the ``cases/*.toml`` files as dicts (:func:`base`), changed in code and
validated by :func:`transient.scene.read.scene_from_dict`, exactly as a scene file would be. A case
runs as ``transient run`` does (:func:`transient.simulate` into
``DIR/stress/<case>.h5``, read back with :func:`transient.open_result`), in a forked
child process that is killed when the case's time bound passes; the long runs stream through
:func:`transient.run.integrate` without keeping the trajectory.

``--quick`` runs the subset marked ``quick`` with shorter runs (the CI smoke test,
``tests/stress/test_stress_quick.py``); the full suite adds the 10⁶-revolution runs and the
longer versions. The property-based tests (``tests/stress/test_properties.py``) are the other
half of the stress testing; their full profile is ``TRANSIENT_STRESS_FULL=1 pytest tests/stress``.
"""
from __future__ import annotations

import copy
import datetime as _dt
import math
import multiprocessing
import resource
import time
import tomllib
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..scene import Scene

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0

#: Work–energy balance tolerance: C_BALANCE·rtol of the energy throughput (max K + max |W|).
#: In crank angle K is a state and the balance closes to rounding; in time the state is ω and
#: the balance collects the local errors of every step (≈ rtol each, with a systematic sign, so
#: that over 1000 revolutions the drift reaches the order of 10³·rtol in
#: tests/validation/test_energy.py).
C_BALANCE = 2000.0
#: Floor of the balance tolerance: rounding of K and of the work integrals (~1e-16 per step,
#: over up to 10⁶ steps).
BALANCE_FLOOR = 1e-10


# ------------------------------------------------------------------------------------------------
# Scenes as dicts


def base(name: str) -> dict:
    """``cases/<name>.toml`` parsed into a dict, to be changed with :func:`put`."""
    return tomllib.loads((CASES_DIR / f"{name}.toml").read_text(encoding="utf-8"))


def put(d: dict, section: str, **values) -> dict:
    """Set keys of ``d[section]`` (dotted for sub-tables: ``"mechanism.rod"``), replacing the
    same quantity written with a unit suffix (``omega_rpm`` for ``omega``). Returns ``d``."""
    from ..units import ALL_SUFFIXES

    table = d
    for part in section.split("."):
        table = table.setdefault(part, {})
    for key, value in values.items():
        plain = key
        head, _, suffix = key.rpartition("_")
        if suffix in ALL_SUFFIXES:
            plain = head
        for old in [k for k in table if k == plain or (k.startswith(plain + "_") and
                                                        k[len(plain) + 1:] in ALL_SUFFIXES)]:
            del table[old]
        table[key] = value
    return d


def scene_of(d: dict, name: str):
    """Validate a scene dict as ``transient run`` validates a file (``SceneError`` if invalid)."""
    from ..scene import scene_from_dict

    d = copy.deepcopy(d)
    d.setdefault("scene", {})["name"] = name
    return scene_from_dict(d, file=f"<stress:{name}>", base_dir=CASES_DIR)


# ------------------------------------------------------------------------------------------------
# Invariants


def balance_residual(tr: Mapping[str, np.ndarray], n_pairs: int) -> float:
    """Largest |ΔK − (W_gas + W_load + W_starter − Σ W_loss)| over the samples, relative to the
    energy throughput max K + max|W_gas| + max|W_load| + max|W_starter| (the measure of
    tests/validation/test_friction_runs.py)."""
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    works = tr["W_gas"] + tr["W_load"] + tr["W_starter"]
    lost = sum((tr[f"W_loss_{k + 1}"] for k in range(n_pairs)), np.zeros_like(K))
    scale = (K.max() + np.abs(tr["W_gas"]).max() + np.abs(tr["W_load"]).max()
             + np.abs(tr["W_starter"]).max())
    return float(np.max(np.abs(K - K[0] - (works - lost))) / scale)


def balance_tolerance(rtol: float) -> float:
    """max(C_BALANCE·rtol, BALANCE_FLOOR), and never looser than 1e-3."""
    return min(max(C_BALANCE * rtol, BALANCE_FLOOR), 1e-3)


def nonfinite(tr: Mapping[str, np.ndarray]) -> list[str]:
    """Trajectory columns holding a NaN or an infinity."""
    return [k for k, v in tr.items() if v.size and not np.all(np.isfinite(v))]


# ------------------------------------------------------------------------------------------------
# Cases


@dataclass
class Outcome:
    """What a case reports: one row of the table."""

    ok: bool = True  # every check held so far (the outcome is decided by run_case)
    outcome: str = ""  # "pass", "FAIL", "known failure"
    status: str = ""  # complete, a result's status (stalled, locked, …), timeout, error
    error: float = math.nan  # the invariant's error (the balance residual unless said otherwise)
    tolerance: float = math.nan
    steps: int = 0
    wall_s: float = 0.0
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Case:
    """One hostile scene (or a few). ``run(quick, ctx)`` fills an :class:`Outcome`; ``known``
    names a failure found and written up but not fixed (it is reported as such)."""

    name: str
    probes: str
    run: Callable[[bool, Context], Outcome]
    quick: bool = True
    time_limit: float = 60.0  # [s], quick and full alike unless full_time_limit is set
    full_time_limit: float | None = None
    known: str = ""


@dataclass
class Context:
    out: Path  # folder of the cases' result files
    deadline: float  # time.monotonic() at which a run is interrupted (soft bound)


class _Timeout(KeyboardInterrupt):
    """Raised from the progress callback after the soft deadline: the compiled driver treats it as
    an interrupt and returns the partial run (``run_compiled``)."""


@dataclass
class Run:
    """A scene run as ``transient run`` runs it, read back from its result file."""

    scene: Scene
    complete: bool
    message: str
    trajectory: Mapping[str, np.ndarray]
    events: dict  # name -> (n, 2) of (t, φ)
    solver: dict
    wall_s: float
    result_status: str  # the result's (transient.outcome.STATUSES)

    @property
    def status(self) -> str:
        """The result's status, ``complete`` for a run that did what its scene asks."""
        return "complete" if self.result_status == "finished" else self.result_status

    def count(self, event: str) -> int:
        return int(self.events.get(event, np.zeros((0, 2))).shape[0])


def run_scene(d: dict, name: str, ctx: Context) -> Run:
    """Run a scene dict as ``transient run`` would (:func:`transient.simulate` to
    ``ctx.out/<name>.h5``) and read the file back, complete or not."""
    from ..errors import SimulationError
    from ..results import open_result
    from ..run import simulate

    scene = scene_of(d, name)
    path = ctx.out / f"{name}.h5"

    def progress(_fraction):
        if time.monotonic() > ctx.deadline:
            raise _Timeout

    t0 = time.perf_counter()
    try:
        simulate(scene, path, force=True, progress=progress)
    except SimulationError:
        pass  # the file says what happened (complete = false, message)
    wall = time.perf_counter() - t0
    res = open_result(path)
    events = {k: np.column_stack([v["t"], v["phi"]]) for k, v in res.events.items()}
    return Run(scene, res.complete, str(res.attrs.get("message", "")), res.trajectory, events,
               res.solver, wall, res.status)


def _diagnosis_names_where(run: Run) -> bool:
    return "t = " in run.message and "φ = " in run.message


def check_run(run: Run, o: Outcome, expect: str = "complete",
              extra: Callable[[Run, Outcome], bool] | None = None) -> Outcome:
    """The common checks: the expected status (``"complete"`` or the diagnosis' first word, or
    several separated by ``|``), finite values, the balance within its tolerance, a diagnosis that
    names time and angle, and the case's ``extra`` checks (which append notes, return ok)."""
    o.status = run.status
    o.steps += int(run.solver.get("nsteps", 0))
    o.wall_s += run.wall_s
    ok = True
    if run.status not in expect.split("|"):
        ok = False
        o.notes.append(f"expected {expect}, got {run.status}: {run.message}")
    elif not run.complete:
        if not _diagnosis_names_where(run):
            ok = False
            o.notes.append(f"the diagnosis does not name time and angle: {run.message}")
        else:
            o.notes.append(f"diagnosis: {run.message.split('; partial result')[0]}")
    bad = nonfinite(run.trajectory)
    if bad:
        ok = False
        o.notes.append(f"non-finite values in {', '.join(bad)}")
    tr = run.trajectory
    if tr["t"].size >= 2 and not bad:
        err = balance_residual(tr, len(run.scene.friction.pairs))
        tol = balance_tolerance(run.scene.solver.rtol)
        o.error = err if not math.isfinite(o.error) else max(o.error, err)
        o.tolerance = tol if not math.isfinite(o.tolerance) else max(o.tolerance, tol)
        if not err <= tol:
            ok = False
            o.notes.append(f"work–energy balance {err:.3g} > {tol:.3g}")
    elif not bad:
        ok = False
        o.notes.append("fewer than two samples written")
    if extra is not None:
        ok = extra(run, o) and ok
    o.ok = o.ok and ok
    return o


def single(build: Callable[[bool], dict], expect: str = "complete",
           extra: Callable[[Run, Outcome], bool] | None = None, name: str = ""):
    """A case's ``run`` for one scene: ``build(quick)`` gives the scene dict."""
    def run(quick: bool, ctx: Context) -> Outcome:
        return check_run(run_scene(build(quick), name or "scene", ctx), Outcome(), expect, extra)
    return run


def several(builds: dict[str, Callable[[bool], dict]], expect: str = "complete",
            extra: Callable[[Run, Outcome], bool] | None = None):
    """A case's ``run`` for a few scenes; all must pass; the error is the largest."""
    def run(quick: bool, ctx: Context) -> Outcome:
        o = Outcome()
        for label, build in builds.items():
            r = run_scene(build(quick), label, ctx)
            n = len(o.notes)
            check_run(r, o, expect, extra)
            o.notes[n:] = [f"{label}: {s}" for s in o.notes[n:]]
        return o
    return run


# --- scene builders ------------------------------------------------------------------------------


def spinup(revs: float, **run) -> dict:
    """The Gots 3-cylinder diesel with flywheel (cases/gots_diesel_spinup.toml)."""
    return put(base("gots_diesel_spinup"), "run", revolutions=revs, **run)


def from_rest(quick: bool) -> dict:
    d = spinup(4 if quick else 40, t_end=2.0 if quick else 10.0)
    put(d, "starter", torque=300.0, noload_speed_rpm=600.0, cutout_speed_rpm=400.0)
    put(d, "initial", phi=0.0, omega=0.0)
    return put(d, "solver", rtol=1e-10, atol=1e-10)


def _from_rest_extra(run: Run, o: Outcome) -> bool:
    ok = run.count("to_angle_domain") == 1 and run.count("starter_cutout") == 1
    if not ok:
        o.notes.append(f"expected one switch to crank angle and one starter cut-out, got "
                       f"{run.count('to_angle_domain')} and {run.count('starter_cutout')}")
    return ok


#: A load torque well above what the Gots diesel carries (its mean indicated torque at full load
#: is ~190 N m: W_i ≈ 2.4 kJ per 720° cycle of 3 cylinders).
OVERLOAD = 600.0


def overload(quick: bool, t_end: float | None = None) -> dict:
    d = spinup(200)
    if t_end is not None:
        put(d, "run", t_end=t_end)
    put(d, "load", torque=OVERLOAD)
    return put(d, "output", dt=2e-4)


def _stall_extra(run: Run, o: Outcome) -> bool:
    w = run.trajectory["omega"]
    ok = abs(w[-1]) <= 1e-9 * abs(w[0]) and run.count("speed_reversal") >= 1
    if not ok:
        o.notes.append(f"stall: last ω = {w[-1]:.3g}, reversals {run.count('speed_reversal')}")
    return ok


def _reversal_extra(run: Run, o: Outcome) -> bool:
    w = run.trajectory["omega"]
    ok = w[-1] < -1.0 and run.count("speed_reversal") >= 1
    o.notes.append(f"ω from {w[0]:.4g} to {w[-1]:.4g} rad/s, {run.count('speed_reversal')} "
                   f"reversal(s)")
    return ok


def rocking(quick: bool) -> dict:
    """A starter too weak to push a cylinder through compression: the shaft rocks back and
    forth (tests/validation/test_friction_runs.py, without the pairs' losses)."""
    d = spinup(1000, t_end=1.0 if quick else 3.0)
    put(d, "starter", torque=20.0, noload_speed_rpm=600.0, cutout_speed_rpm=600.0)
    put(d, "initial", phi=0.5, omega=0.0)
    put(d, "solver", rtol=1e-10, atol=1e-10)
    return put(d, "output", dt=1e-4)


def _rocking_extra(run: Run, o: Outcome) -> bool:
    n = run.count("speed_reversal")
    o.notes.append(f"{n} speed reversals")
    return n >= 3


def long_rod_ratio(lam: float, domain: str = "auto"):
    def build(quick: bool) -> dict:
        d = spinup(10 if quick else 100)
        r = 47.0
        put(d, "mechanism", rod_length_mm=r / lam)
        put(d, "mechanism.rod", cg_from_pin_mm=0.725 * r / lam)
        return put(d, "solver", domain=domain)
    return build


def offset_near_limit(fraction: float, domain: str = "auto"):
    """The offset changes the stroke and moves the dead centres; a tabulated indicator diagram
    (:func:`firing_table`) keeps the gas force the same at every offset."""
    def build(quick: bool) -> dict:
        d = gas_table_scene(quick, *firing_table(), domain=domain)
        return put(d, "mechanism", offset_mm=fraction * (148.0 - 47.0))
    return build


def swash(quick: bool, **mech) -> dict:
    d = put(base("swash_plate_4cyl"), "run", t_end=1.0 if quick else 8.0)
    return put(d, "mechanism", **mech)


def swash_rod_at_reach(quick: bool) -> dict:
    """Rods 0.1 % longer than the lateral offset they must bridge over a turn."""
    from ..mechanisms.swash_plate import max_offset

    probe = scene_of(swash(quick), "probe").mechanism
    ell = 1.001 * max_offset(probe) * 1e3
    return put(swash(quick, rod_length_mm=ell), "mechanism.rod", cg_from_pin_mm=0.5 * ell)


def gas_table_scene(quick: bool, phi: list, p_bar: list, corners: list | None,
                    interpolation: str = "linear", domain: str = "auto") -> dict:
    """The Gots diesel with a tabulated indicator diagram (angles in radians, SI keys)."""
    d = spinup(10 if quick else 100)
    d["gas"] = {"model": "table", "p0_MPa": 0.1, "phi": phi, "p_bar": p_bar,
                "interpolation": interpolation}
    if corners:
        d["gas"]["corners"] = corners
    return put(d, "solver", domain=domain)


FOUR_PI = 4.0 * math.pi


def firing_table() -> tuple[list, list, list]:
    """A plain indicator diagram (angles [rad], p [bar], corners [rad]): 1 bar, a rise to 110 bar
    over 0.3 rad after the firing TDC (2π), expansion to 1 bar at 3π; every knot a corner."""
    x = 2.0 * math.pi
    phi = [0.0, x, x + 0.3, x + 0.6, 3.0 * math.pi, FOUR_PI]
    return phi, [1.0, 1.0, 110.0, 60.0, 1.0, 1.0], phi[1:-1]


def pressure_rise(rise: float, declared: bool, domain: str = "auto"):
    """1 bar → 120 bar over ``rise`` rad at the firing TDC (2π), then a linear expansion."""
    def build(quick: bool) -> dict:
        x = 2.0 * math.pi
        phi = [0.0, x, x + rise, x + 0.6, 3.0 * math.pi, FOUR_PI]
        p = [1.0, 1.0, 120.0, 40.0, 1.0, 1.0]
        return gas_table_scene(quick, phi, p, [x, x + rise] if declared else None, domain=domain)
    return build


def close_corners(gap: float, domain: str = "auto"):
    """A zig-zag of pressure corners ``gap`` rad apart (closer than one step) after TDC. (Table
    angles within 1e-9·cycle of each other are one angle to the scene reader.)"""
    def build(quick: bool) -> dict:
        x = 2.0 * math.pi
        corners = [x + k * gap for k in range(6)]
        phi = [0.0, *corners, x + 0.6, 3.0 * math.pi, FOUR_PI]
        p = [1.0, 1.0, 90.0, 60.0, 110.0, 80.0, 100.0, 40.0, 1.0, 1.0]
        return gas_table_scene(quick, phi, p, corners, domain=domain)
    return build


def load_steps(quick: bool) -> dict:
    """The Gots 4400 generator set with load steps, ramps 1e-8 s long, at odd times."""
    d = base("gots_diesel_load_steps")
    put(d, "load", schedule_time=[0.0123456789, 0.0123456789, 0.1, 0.1 + 1e-8, 0.2718281828,
                                  0.2718281828, 0.3, 0.3 + 3e-9],
        schedule_scale=[0.0, 1.0, 1.0, 0.25, 0.25, 1.0, 1.0, 0.5])
    return put(d, "run", t_end=0.5 if quick else 3.0)


def _load_steps_extra(run: Run, o: Outcome) -> bool:
    n = run.count("load_schedule")
    ok = n == 6
    o.notes.append(f"{n} load-schedule events (6 corners)")
    return ok


def friction(policy: str = "power-flow", eta: tuple[float, float] | None = None, **changes):
    """The Gots diesel with main bearings and crankpins non-ideal (gots_diesel_friction.toml)."""
    def build(quick: bool) -> dict:
        d = base("gots_diesel_friction")
        put(d, "friction", policy=policy)
        if eta is not None:
            for pair in d["friction"]["pairs"]:
                pair["eta_forward"], pair["eta_backward"] = eta
        put(d, "run", revolutions=10 if quick else 100)
        for section, values in changes.items():
            if section == "gas":
                d["gas"] = dict(values)  # a different model: its keys all change
            else:
                put(d, section, **values)
        return d
    return build


def _pairs_switch(run: Run, o: Outcome) -> bool:
    """Power-flow: many mode switches, every loss ≥ 0. The paper's criterion (25) looks at the
    applied moments only, so coasting it keeps its modes and its losses go negative where inertia
    drives: reported, not a failure."""
    n = run.count("pair_mode")
    tr = run.trajectory
    neg = [k + 1 for k in range(len(run.scene.friction.pairs))
           if tr[f"P_loss_{k + 1}"].min() < -1e-9 * np.abs(tr[f"P_loss_{k + 1}"]).max()]
    if run.scene.friction.policy == "paper":
        o.notes.append(f"{n} pair-mode switches" + (f"; negative loss in pair(s) {neg}, as "
                                                    f"criterion (25) allows" if neg else ""))
        return True
    o.notes.append(f"{n} pair-mode switches" + (f"; NEGATIVE loss in pair(s) {neg}" if neg else ""))
    return n > 10 and not neg


def locked_at_rest(quick: bool) -> dict:
    d = friction(eta=None)(quick)
    put(d, "starter", torque=20.0, noload_speed_rpm=600.0, cutout_speed_rpm=600.0)
    put(d, "initial", phi=0.5, omega=0.0)
    put(d, "run", t_end=3.0)
    del d["run"]["revolutions"]
    put(d, "solver", rtol=1e-10, atol=1e-10)
    return put(d, "output", dt=1e-4)


def backward_from_rest(quick: bool) -> dict:
    """The valid small scene of the scene tests with a 10 N m load and a 5 N m starter."""
    d = put(base("coasting_single"), "run", revolutions=2)
    put(d, "load", torque=10.0)
    return put(d, "starter", torque=5.0, noload_speed_rpm=300.0, cutout_speed_rpm=200.0,
               ) | {"initial": {"phi": 0.0, "omega": 0.0}}


def stiff_governor(quick: bool) -> dict:
    """The Gots PI generator set with an actuator lag of 2 µs, ~10⁴ times shorter than the
    engine's 33 ms cycle (and its firing interval), through a load step."""
    d = put(base("gots_diesel_pi"), "governor", actuator_time=2e-6)
    put(d, "load", schedule_time=[0.05, 0.05], schedule_scale=[0.0, 1.0])
    return put(d, "run", t_end=0.1 if quick else 0.3)


def _stiff_extra(run: Run, o: Outcome) -> bool:
    note = str(run.solver.get("stiff_rerun", ""))
    ok = note.startswith("stiff at t = ") and "scipy-Radau" in note and (
        run.solver.get("method") == "scipy-Radau")
    o.notes.append(note[:160] + ("…" if len(note) > 160 else "") if note else
                   "no stiffness detected, no implicit rerun")
    return ok


def _locked_extra(run: Run, o: Outcome) -> bool:
    ok = run.trajectory["omega"][-1] == 0.0 and run.count("locked") == 1
    if not ok:
        o.notes.append(f"locked: ω at the end {run.trajectory['omega'][-1]:.3g}, "
                       f"{run.count('locked')} locked event(s)")
    return ok


def efficiency_sweep(quick: bool, ctx: Context) -> Outcome:
    """η from 0.3 to 1 on both pairs; η = 1 must give the ideal machine's run."""
    o = Outcome()
    etas = (0.3, 0.6, 1.0) if quick else (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)
    finals = {}
    for eta in etas:
        r = run_scene(friction(eta=(eta, eta))(quick), f"eta-{eta:g}", ctx)
        n = len(o.notes)
        check_run(r, o, "complete|stalled|not-started")  # low η may lose more than gas gives
        o.notes[n:] = [f"η = {eta:g}: {s}" for s in o.notes[n:]]
        finals[eta] = (r.trajectory["t"][-1], r.trajectory["omega"][-1])
    d = friction()(quick)
    del d["friction"]
    ideal = run_scene(d, "eta-ideal", ctx)
    check_run(ideal, o)
    rtol = ideal.scene.solver.rtol
    t1, w1 = finals[1.0]
    e = max(abs(t1 - ideal.trajectory["t"][-1]) / (rtol * abs(t1)),
            abs(w1 - ideal.trajectory["omega"][-1]) / (rtol * abs(w1)))
    o.notes.append(f"η = 1 against no pairs: |e| = {e:.3g} (in rtol)")
    w = [finals[eta][1] for eta in etas]
    o.notes.append("final ω: " + ", ".join(f"{v:.5g}" for v in w))
    if not (e <= 100 and all(a <= b for a, b in zip(w, w[1:]))):
        o.ok = False
        o.notes.append("η = 1 differs from the ideal machine, or ω does not grow with η")
    return o


def ladder_error(run: Run, ref: Run, x: str) -> float:
    """Largest error of ω and of t (or φ) at the samples both runs share (the output grid of
    ``x``, crank angle or time), relative to the largest |ω| and to the run's span of t (φ)."""
    a, b = run.trajectory, ref.trajectory
    common, i, j = np.intersect1d(a[x], b[x], return_indices=True)
    if common.size < 10:
        raise RuntimeError(f"only {common.size} samples in common on the {x} grid")
    y = "t" if x == "phi" else "phi"
    span = np.ptp(b[y])
    return float(max(np.max(np.abs(a["omega"][i] - b["omega"][j])) / np.max(np.abs(b["omega"])),
                     np.max(np.abs(a[y][i] - b[y][j])) / span))


#: In time the error is monotone in rtol only from here down. Above it, neither transient's DOP853
#: nor scipy's (``solve_ivp``, an independent code) is: at loose tolerances the steps are set by
#: the breakpoints (one or two per segment, at 1e-3 … 5e-5 alike), each segment keeps what DOP853
#: leaves over a steep compression, and these add up with signs that change with rtol (in
#: transient's errors and scipy's alike).
TIME_MONOTONE_FROM = 1e-6
#: Errors below this are the reference run's own noise (rtol 1e-13).
LADDER_FLOOR = 1e-12


def end_error(run: Run, ref: Run) -> float:
    """Error of the final state against the reference's (both end at the same angle): the larger
    of |Δt|/t and |Δω|/|ω|."""
    a, b = run.trajectory, ref.trajectory
    return max(abs(a["t"][-1] / b["t"][-1] - 1.0), abs(a["omega"][-1] / b["omega"][-1] - 1.0))


def _falls(rtols, errs, below=1.0) -> bool:
    """Whether the errors never rise as rtol tightens (among rtol ≤ ``below``; errors under
    LADDER_FLOOR are noise)."""
    errs = [e for r, e in zip(rtols, errs) if r <= below]
    return all(b <= a or b <= LADDER_FLOOR for a, b in zip(errs, errs[1:]))


def tolerance_ladder(quick: bool, ctx: Context) -> Outcome:
    """ω and t (φ) along the run against a run at rtol 1e-13, for rtol 1e-3 … 1e-12.

    In crank angle (the default path) the error must fall monotonically over the whole ladder.
    In time it must fall monotonically from TIME_MONOTONE_FROM down, and at every rtol the final
    state must be no worse than scipy's DOP853 (``solve_ivp``) makes it on the same scene, which
    shows what DOP853 itself does at the loose end.
    """
    o = Outcome()
    rtols = [10.0 ** -k for k in range(3, 10 if quick else 13)]
    for domain in ("auto", "time"):
        def build(rtol, domain=domain, **solver):
            d = put(spinup(10 if quick else 40), "output", dt=1e-4)  # the time-domain grid
            return put(d, "solver", rtol=rtol, atol=rtol * 1e-2, domain=domain, **solver)

        ref = run_scene(build(1e-13), f"ladder-{domain}-ref", ctx)
        o.steps += int(ref.solver.get("nsteps", 0))
        o.wall_s += ref.wall_s
        errs, worse = [], []
        for rtol in rtols:
            r = run_scene(build(rtol), f"ladder-{domain}-{rtol:.0e}", ctx)
            n = len(o.notes)
            check_run(r, o)
            o.notes[n:] = [f"{domain} rtol {rtol:.0e}: {s}" for s in o.notes[n:]]
            errs.append(ladder_error(r, ref, "phi" if domain == "auto" else "t"))
            if domain == "time":
                s = run_scene(build(rtol, method="scipy-DOP853"), f"ladder-scipy-{rtol:.0e}",
                              ctx)
                mine, theirs = end_error(r, ref), end_error(s, ref)
                if mine > max(theirs, LADDER_FLOOR):
                    worse.append(f"{rtol:.0e} ({mine:.1e} against {theirs:.1e})")
        ladder = " ".join(f"{e:.1e}" for e in errs)
        if domain == "auto":
            mono = _falls(rtols, errs)
            o.notes.append(f"crank angle: largest error of t, ω {ladder}"
                           + ("" if mono else " — NOT monotone"))
        else:
            falls = _falls(rtols, errs, TIME_MONOTONE_FROM)
            mono = falls and not worse
            against = ("final state no worse than scipy's DOP853 at every rtol" if not worse
                       else "worse than scipy's DOP853 at " + ", ".join(worse))
            o.notes.append(f"time: largest error of t, ω {ladder} (monotone from "
                           f"{TIME_MONOTONE_FROM:.0e} down{'' if falls else ': NOT'}); {against}")
        o.ok = o.ok and mono
    return o


def million_revolutions(driven: bool):
    """10⁶ revolutions streamed (the trajectory is not kept): energy drift and phase drift of
    the coasting single cylinder (against the time the exact J(φ) gives), or the work–energy
    balance of the driven Gots diesel; peak memory of the process."""
    def run(quick: bool, ctx: Context) -> Outcome:
        from ..run import integrate

        revs = 1e6
        if driven:
            d = spinup(revs)
            put(d, "output", samples_per_rev=4)
        else:
            d = put(base("coasting_single"), "run", revolutions=revs)
            put(d, "output", samples_per_rev=4)
        scene = scene_of(d, "million")
        n_pairs = len(scene.friction.pairs)
        stats = {"drift": 0.0, "bal": 0.0, "scale": 0.0, "n": 0, "bad": 0}
        first: dict[str, float] = {}  # the kinetic energy K0 at the first sample

        def on_block(block, _ev, _state):
            if not block["t"].size:
                return
            K = 0.5 * block["J"] * block["omega"] ** 2
            K0 = first.setdefault("K0", float(K[0]))
            works = block["W_gas"] + block["W_load"] + block["W_starter"]
            lost = sum((block[f"W_loss_{k + 1}"] for k in range(n_pairs)), np.zeros_like(K))
            stats["drift"] = max(stats["drift"], float(np.max(np.abs(K / K0 - 1))))
            stats["bal"] = max(stats["bal"], float(np.max(np.abs(K - K0 - (works - lost)))))
            stats["scale"] = max(stats["scale"], float(K.max() + np.abs(block["W_gas"]).max() +
                                                       np.abs(block["W_load"]).max()))
            stats["n"] += block["t"].size
            stats["bad"] += int(sum(np.count_nonzero(~np.isfinite(v)) for v in block.values()))

        def progress(_f):
            if time.monotonic() > ctx.deadline:
                raise _Timeout

        rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        t0 = time.perf_counter()
        data = integrate(scene, on_block=on_block, progress=progress, keep=False)
        o = Outcome(status="complete" if data.complete else data.message.split(":")[0],
                    steps=int(data.solver["nsteps"]), wall_s=time.perf_counter() - t0)
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        tr = data.trajectory  # the last block only
        ok = data.complete and stats["bad"] == 0
        if not data.complete:
            o.notes.append(data.message)
        o.notes.append(f"{stats['n']} samples streamed; peak RSS {rss / 1024:.0f} MB "
                       f"(+{(rss - rss0) / 1024:.0f} MB during the run)")
        if driven:
            o.error = stats["bal"] / stats["scale"]
            o.tolerance = balance_tolerance(scene.solver.rtol)
        else:
            t_exact = revs * _coast_period(scene)
            phase = tr["t"][-1] / t_exact - 1.0
            o.error, o.tolerance = stats["drift"], 1e-8
            o.notes.append(f"energy drift max |K/K₀ − 1| = {stats['drift']:.2e}; phase: t(end) "
                           f"/ t_exact − 1 = {phase:.2e}")
            ok = ok and abs(phase) <= 1e-8
        ok = ok and o.error <= o.tolerance
        o.ok = ok
        return o
    return run


def _coast_period(scene) -> float:
    """Time to coast one revolution: ∫₀^{2π} √(J(φ)/(2K₀)) dφ (single cylinder, 2π-periodic J)."""
    from scipy.integrate import quad

    mech = scene.mechanism

    def J(p):
        return float(mech.kinematics_table(np.array([p]))["J"][0]) + scene.inertia.total

    K0 = 0.5 * J(scene.initial.phi) * scene.initial.omega ** 2
    value, _ = quad(lambda p: math.sqrt(J(p) / (2.0 * K0)), 0.0, 2.0 * math.pi, epsabs=0.0,
                    epsrel=1e-13, limit=400)
    return value


#: Runaway inputs: (section, keys) that would write or step without bound, each refused before
#: any work with a one-line error naming the key.
RUNAWAY_INPUTS = [("run", "t_end", 1e30), ("run", "revolutions", 1e30),
                  ("solver", "switch_speed_rpm", 1e30), ("solver", "max_step_deg", 1e-9),
                  ("solver", "fixed_step_deg", 1e-12), ("initial", "phi", 1e20),
                  ("solver", "rtol", 1e-16)]


def runaway(quick: bool, ctx: Context) -> Outcome:
    """Inputs that would run without bound are refused before any work, naming their key; and a
    run that outgrows its output budget all the same is stopped where it is, the partial result
    kept readable and marked (``over-budget``)."""
    from ..errors import SceneError

    o = Outcome(status="complete", error=0.0, tolerance=0.0)
    for section, key, value in RUNAWAY_INPUTS:
        d = put(base("coasting_single"), section, **{key: value})
        if key == "t_end":
            del d["run"]["revolutions"]  # (which would end the run first)
        try:
            scene_of(d, "runaway")
            o.ok = False
            o.notes.append(f"{section}.{key} = {value:g} was accepted")
        except SceneError as exc:
            if exc.key != f"{section}.{key}" or "\n" in str(exc):
                o.ok = False
                o.notes.append(f"{section}.{key}: the error names {exc.key!r}: {exc}")
        o.steps += 1
    d = put(put(base("coasting_single"), "run", t_end=100.0, max_output_bytes=3e5),
            "solver", rtol=1e-6)
    d["run"].pop("revolutions", None)
    run = run_scene(d, "runaway-budget", ctx)
    t = run.trajectory["t"]
    kept = t.size > 0 and bool(np.all(np.diff(t) > 0)) and not nonfinite(run.trajectory)
    if run.complete or not run.message.startswith("over budget") or not kept:
        o.ok = False
        o.notes.append(f"over budget: complete {run.complete}, {t.size} samples kept "
                       f"(monotone and finite: {kept}): {run.message}")
    o.notes.append(f"{len(RUNAWAY_INPUTS)} runaway inputs refused; a run over its budget stopped "
                   f"after {t.size} samples")
    return o


def kill_and_resume(quick: bool, ctx: Context) -> Outcome:
    """The governed diesel with friction pairs run by ``transient run`` in child processes, each
    killed (SIGKILL) at a random instant and resumed in this one: the partial file must hold an
    exact prefix of the run never stopped, and the resumed file that run, bit for bit."""
    import signal
    import subprocess
    import sys

    from ..results import open_result, partial_path
    from ..run import simulate
    from ..scene import to_toml

    scene = scene_of(put(base("gots_diesel_friction"), "run",
                         revolutions=3000 if quick else 10000), "kill-and-resume")
    scene_file = ctx.out / "kill-and-resume.toml"
    scene_file.write_text(to_toml(scene), encoding="utf-8")
    whole = simulate(scene, ctx.out / "kill-and-resume-whole.h5", force=True)
    span = whole.solver["wall_s"] + 0.2  # (a child loads the kernels first; no compile here)
    o, rng = Outcome(status="complete", error=0.0, tolerance=0.0), np.random.default_rng(1)
    kills = 3 if quick else 20
    for k in range(4 * kills):  # (a run may finish before its kill: another is started)
        if o.steps == kills:
            break
        out = ctx.out / f"kill-and-resume-{k}"
        result = out / "kill-and-resume.h5"
        for stale in (result, partial_path(result)):
            stale.unlink(missing_ok=True)
        proc = subprocess.Popen([sys.executable, "-m", "transient", "run", str(scene_file), "-o",
                                 str(out), "-q"], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        while proc.poll() is None and not partial_path(result).exists():
            time.sleep(0.01)
        time.sleep(rng.uniform(0.0, span))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        if result.exists():
            continue  # it had finished
        part = open_result(partial_path(result))
        n = part.trajectory["t"].size
        prefix = all(np.array_equal(v, whole.trajectory[c][:n]) for c, v in part.trajectory.items())
        simulate(scene, result, resume=True)
        again = open_result(result)
        same = all(np.array_equal(v, again.trajectory[c]) for c, v in whole.trajectory.items())
        o.steps += 1
        if not (prefix and same and not part.complete):
            o.ok = False
            o.notes.append(f"kill {k} after {n} samples: prefix {prefix}, resumed identical {same}")
    o.notes.append(f"{o.steps} runs killed and resumed")
    return o


# --- the cases a user tries -------------------------------------------------------------------
# Each must end without a traceback and with the status that says what happened; a run that did
# not do what its scene asked never ends ``finished``.


def inline_six(quick: bool) -> dict:
    """The Gots cylinder as an in-line six (firing order 1-5-3-6-2-4, 120° apart), its fan load
    doubled for twice the cylinders, spinning up from 1000 rpm."""
    d = spinup(10 if quick else 200)
    put(d, "mechanism", cylinders=6, firing_order=[1, 5, 3, 6, 2, 4])
    del d["mechanism"]["firing_deg"]  # (the order spreads them evenly)
    return put(d, "load", fan=2 * 9.692e-4)


def v8(quick: bool) -> dict:
    """The cross-plane V8 (cases/v8_cross_plane.toml: two cylinders on each of four throws, side
    by side, crank_mass per throw), spinning up from 1500 rpm."""
    return put(base("v8_cross_plane"), "run", revolutions=10 if quick else 200)


def _v8_journals(run: Run, o: Outcome) -> bool:
    """The loads analysis gives the V8 its five main journals (four throws), finite and loaded."""
    from ..analysis.requested import stored_loads

    cuts = run.events.get("breakpoint", np.zeros((0, 2)))[:, 1]
    x = np.asarray(stored_loads(run.scene, run.trajectory, cuts)["loads_main_x"][0])
    ok = x.shape[0] == 5 and bool(np.all(np.isfinite(x))) and float(np.max(np.abs(x))) > 0.0
    if not ok:
        o.notes.append(f"main journals: {x.shape[0]} of 5, finite {np.all(np.isfinite(x))}")
    return ok


def two_stroke(quick: bool) -> dict:
    """The Gots engine as a two-stroke (firing 120° apart over a 360° cycle), scavenged to p_a
    at bottom dead centre: no gas-exchange pressures (a scene that gives them is refused)."""
    d = spinup(10 if quick else 200)
    put(d, "mechanism", strokes=2, firing_deg=[0, 120, 240])
    for key in ("p_intake_MPa", "p_exhaust_MPa"):
        del d["gas"][key]
    return d


def _refuses_exchange_pressures(run: Run, o: Outcome) -> bool:
    """The same two-stroke with p_intake given is refused, naming the key."""
    from ..errors import SceneError

    d = two_stroke(True)
    put(d, "gas", p_intake_MPa=0.165)
    try:
        scene_of(d, "two-stroke-p-intake")
    except SceneError as exc:
        return exc.key == "gas.p_intake_MPa"
    o.notes.append("a two-stroke scene with p_intake was accepted")
    return False


def weak_starter(t_end: float):
    """A 5 N m starter from rest on the reaction-friction diesel, 30 revolutions asked by
    ``t_end``: far too weak to push a cylinder through compression, it rocks the crank in the
    first one (by 0.5 s it turns backwards at the end; by 2 s the pairs hold it at rest)."""
    def build(quick: bool) -> dict:
        d = put(base("gots_diesel_reaction_friction"), "run", revolutions=30, t_end=t_end)
        put(d, "starter", torque=5.0, noload_speed_rpm=600.0, cutout_speed_rpm=400.0)
        return put(d, "initial", phi=0.0, omega=0.0)
    return build


def light_flywheel(t_end: float):
    """The spin-up scene without its flywheel (a 0.001 kg m² shaft), asked for 30 revolutions:
    the compression stops the crank within the first turn and it rocks until ``t_end``."""
    def build(quick: bool) -> dict:
        d = spinup(30, t_end=t_end)
        return put(d, "inertia", flywheel=0.0, shaft=0.001)
    return build


def _did_not_start(run: Run, o: Outcome) -> bool:
    """A run whose shaft never completed what its scene asked: it must not end ``finished``,
    and its message must say that it did not start, whichever way the shaft turns at the end;
    each reversal is a sample at rest (the time-domain output rule)."""
    rev = run.events.get("speed_reversal", np.zeros((0, 2)))
    tr = run.trajectory
    at_rest = all(np.any((tr["t"] == t) & (tr["omega"] == 0.0)) for t, _ in rev)
    o.notes.append(f"status {run.result_status}, {len(rev)} reversal(s); {run.message[:160]}")
    ok = run.result_status != "finished" and "did not start" in run.message and at_rest
    if not ok:
        o.notes.append("expected a status other than finished, saying it did not start"
                       + ("" if at_rest else "; a reversal is not a sample at rest"))
    return ok


def failed_starts(builds: dict[str, Callable[[bool], dict]]):
    """A case's ``run`` for scenes whose shaft never completes what they ask: the verdict is
    ``_did_not_start``'s, whatever status the run ends with (the common checks still hold:
    finite values, the balance, a diagnosis naming time and angle)."""
    def run(quick: bool, ctx: Context) -> Outcome:
        o = Outcome()
        for label, build in builds.items():
            r = run_scene(build(quick), label, ctx)
            n = len(o.notes)
            check_run(r, o, r.status, _did_not_start)
            o.notes[n:] = [f"{label}: {x}" for x in o.notes[n:]]
        return o
    return run


#: The revolutions of the load steps of :func:`load_steps_at_revolutions` (quick, full).
STEP_REVOLUTIONS = {True: (20.0, 50.0, 80.0), False: (60.0, 200.0, 300.0)}


def load_steps_at_revolutions(quick: bool) -> dict:
    """The Gots generator set taking its full load at one revolution count and shedding half
    of it at another, the run ending by revolutions."""
    on, off, end = STEP_REVOLUTIONS[quick]
    d = base("gots_diesel_load_steps")
    del d["load"]["schedule_time"]
    put(d, "load", schedule_revolutions=[on, on, off, off], schedule_scale=[0.0, 1.0, 1.0, 0.5])
    d["run"] = {"revolutions": end}
    return d


def _steps_at_their_revolutions(run: Run, o: Outcome) -> bool:
    """One event per step, each at φ₀ + 2π·(its revolution count) to rounding."""
    quick = run.scene.run.revolutions == STEP_REVOLUTIONS[True][2]
    on, off, _ = STEP_REVOLUTIONS[quick]
    phi0 = run.scene.initial.phi
    got = run.events.get("load_schedule", np.zeros((0, 2)))[:, 1]
    want = phi0 + 2.0 * math.pi * np.array([on, off])
    ok = got.size == 2 and bool(np.all(np.abs(got - want) <= 1e-9 * want))
    o.notes.append(f"load steps at φ = {', '.join(f'{g:.12g}' for g in got)} rad (want "
                   f"{', '.join(f'{w:.12g}' for w in want)})")
    return ok and run.result_status == "finished"


SWEEP_SCRIPT = """\
import transient

def main():
    base = transient.load_scene({scene!r}).replace(run={{"revolutions": 2}})
    done = transient.sweep(base, {{"load.torque": [0.0, 5.0]}}, output={out!r}, workers=2)
    print(*done.table.columns["status"])

{call}
"""


def sweep_from_script(quick: bool, ctx: Context) -> Outcome:
    """The guide's sweep from code as a script on a local cluster: under the ``__main__`` guard
    it runs (both runs finished); without it, it fails in one line saying to add the guard,
    before Dask starts a worker (no traceback from inside Dask)."""
    import subprocess
    import sys

    o = Outcome(status="complete", error=0.0, tolerance=0.0)
    for guarded in (True, False):
        folder = ctx.out / f"sweep-script-{'guarded' if guarded else 'plain'}"
        folder.mkdir(parents=True, exist_ok=True)
        script = folder / "study.py"
        script.write_text(SWEEP_SCRIPT.format(
            scene=str(CASES_DIR / "coasting_single.toml"), out=str(folder),
            call='if __name__ == "__main__":\n    main()' if guarded else "main()"),
            encoding="utf-8")
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                              timeout=max(10.0, ctx.deadline - time.monotonic()))
        o.wall_s += time.perf_counter() - t0
        last = (proc.stderr.strip().splitlines() or [""])[-1]
        if guarded:
            ok = proc.returncode == 0 and proc.stdout.split() == ["finished", "finished"]
            o.notes.append(f"guarded: exit {proc.returncode}, statuses {proc.stdout.split()}")
        else:
            ok = (proc.returncode == 1 and "UnguardedMain" in last
                  and 'if __name__ == "__main__":' in last and "distributed" not in proc.stderr)
            o.notes.append(f"unguarded: exit {proc.returncode}: {last[:200]}")
        o.steps += 1
        o.ok = o.ok and ok
    return o


def catalogue() -> list[Case]:
    """Every case, in report order."""
    return [
        Case("start-from-rest", "starter from ω = 0: time domain, switch to crank angle, cut-out",
             single(from_rest, extra=_from_rest_extra, name="start-from-rest")),
        Case("stall-overload", f"load torque {OVERLOAD:g} N m, about 3× what the engine carries; "
                               f"the run ends by revolutions",
             single(overload, "not-started", _stall_extra, "stall-overload")),
        Case("reversal-by-load", "the same overload with an end time: the load drives the shaft "
                                 "backwards through the gas cycle",
             single(lambda q: overload(q, t_end=0.4), "reversed", _reversal_extra,
                    "reversal-by-load")),
        Case("through-zero-rocking", "weak starter against compression: ω through zero many "
                                     "times",
             single(rocking, "not-started", _rocking_extra, "through-zero-rocking")),
        Case("lambda-0.9", "λ = r/l = 0.9 (crank angle and time domain); λ = 0.75",
             several({"lambda-0.9": long_rod_ratio(0.9), "lambda-0.9-time":
                      long_rod_ratio(0.9, "time"), "lambda-0.75": long_rod_ratio(0.75)})),
        Case("offset-near-limit", "offset e = 0.999·(l − r) and 0.99·(l − r): the rod almost "
                                  "perpendicular to the cylinder",
             several({"offset-0.999": offset_near_limit(0.999), "offset-0.99-time":
                      offset_near_limit(0.99, "time"), "offset-neg-0.999":
                      offset_near_limit(-0.999)})),
        Case("swash-40deg", "swash-plate angle 40° (and 30°)",
             several({"swash-40": lambda q: swash(q, swash_deg=40.0),
                      "swash-30": lambda q: swash(q, swash_deg=30.0)})),
        Case("swash-rod-reach", "swash-plate rods 0.1 % longer than the offset they bridge",
             single(swash_rod_at_reach, name="swash-rod-reach")),
        Case("pressure-rise-1e-6", "1 → 120 bar over 1e-6 rad, declared corners (crank angle, "
                                   "time) and undeclared (every knot a breakpoint all the "
                                   "same)",
             several({"rise-1e-6": pressure_rise(1e-6, True),
                      "rise-1e-6-time": pressure_rise(1e-6, True, "time"),
                      "rise-1e-6-undeclared": pressure_rise(1e-6, False)})),
        Case("close-breakpoints", "six pressure corners 1e-4 rad and 3e-8 rad apart (a step is "
                                  "~0.1 rad); crank angle and time",
             several({"corners-1e-4": close_corners(1e-4), "corners-3e-8": close_corners(3e-8),
                      "corners-1e-4-time": close_corners(1e-4, "time"),
                      "corners-3e-8-time": close_corners(3e-8, "time")})),
        Case("load-steps-odd-times", "load steps and 1e-8 s ramps at arbitrary times under a "
                                     "droop governor",
             single(load_steps, extra=_load_steps_extra, name="load-steps-odd-times")),
        Case("pair-power-around-zero", "coasting with friction pairs: inertia makes the power "
                                       "through each pair oscillate around zero (power-flow; "
                                       "paper's criterion may chatter)",
             several({"oscillating-power-flow": friction(gas={"model": "none"},
                                                         initial={"omega_rpm": 3000}),
                      "oscillating-paper": friction("paper", gas={"model": "none"},
                                                    initial={"omega_rpm": 3000})},
                     "complete|chattering", _pairs_switch)),
        Case("locked-at-rest", "weak starter, non-ideal pairs: the swings die out and the pairs "
                               "hold the shaft (diagnosis: locked)",
             single(locked_at_rest, "locked", _locked_extra, "locked-at-rest")),
        Case("near-self-braking", "η = 0.05 in both pairs: almost self-braking, gas drives "
                                  "backward through them",
             several({"self-braking-0.05": friction(eta=(0.05, 0.05)),
                      "self-braking-0.05-rest": friction(
                          eta=(0.05, 0.05), starter={"torque": 500.0, "noload_speed_rpm": 600.0,
                                                     "cutout_speed_rpm": 400.0},
                          initial={"omega": 0.0}, run={"t_end": 2.0})},
                     "complete|stalled|not-started|locked")),
        Case("efficiency-0.3-to-1", "η from 0.3 to 1 on both pairs; η = 1 equals no pairs",
             efficiency_sweep),
        Case("tolerance-ladder", "rtol 1e-3 … 1e-12 (quick: … 1e-9): the largest error of t and "
                                 "ω along the run falls monotonically (in time: from 1e-6 "
                                 "down, and the end state is no worse than scipy's DOP853 at "
                                 "every rtol)", tolerance_ladder, time_limit=180.0),
        Case("stiff-governor", "a PI governor whose actuator (2 µs) is ~10⁴× faster than the "
                               "engine: detected by the stiffness test, rerun by Radau",
             single(stiff_governor, extra=_stiff_extra, name="stiff-governor"), time_limit=120.0),
        Case("backward-revolutions-only", "starter weaker than a constant load, from rest, the "
                                          "run ending by revolutions only: the shaft turns "
                                          "backwards and can never reach them",
             single(backward_from_rest, "not-started|locked", name="backward-revolutions-only"),
             time_limit=10.0),
        Case("runaway", "inputs that would run without bound (t_end, revolutions 1e30, …) "
                        "refused naming their key; a run over its output budget stopped, kept",
             runaway, time_limit=60.0),
        Case("kill-and-resume", "runs killed (SIGKILL) at random instants, then --resume: "
                                "a prefix of the run kept, the resumed run bit-identical",
             kill_and_resume, time_limit=120.0, full_time_limit=600.0),
        Case("in-line-six", "the Gots cylinder as an in-line six (1-5-3-6-2-4), spinning up",
             single(inline_six, name="in-line-six")),
        Case("v8", "the cross-plane V8, two cylinders on each of four throws, spinning up; "
                   "its five main journals loaded",
             single(v8, extra=_v8_journals, name="v8")),
        Case("two-stroke", "the Gots engine as a two-stroke; the same scene with p_intake is "
                           "refused, naming the key",
             single(two_stroke, extra=_refuses_exchange_pressures, name="two-stroke")),
        Case("weak-starter-from-rest", "a 5 N m starter from rest on the reaction-friction "
                                       "diesel, t_end 0.5 s and 2 s: it rocks the crank (then "
                                       "is held at rest) and must say it did not start",
             failed_starts({"weak-starter-0.5s": weak_starter(0.5),
                            "weak-starter-2s": weak_starter(2.0)})),
        Case("light-flywheel", "no flywheel, a 0.001 kg m² shaft, 30 revolutions asked by "
                               "t_end 0.5 s and 2 s: the crank rocks in compression and the "
                               "run must say it did not start, whichever way it turns at the "
                               "end",
             failed_starts({"light-flywheel-0.5s": light_flywheel(0.5),
                            "light-flywheel-2s": light_flywheel(2.0)})),
        Case("load-steps-at-revolutions", "full load taken at one revolution count and half "
                                          "shed at another under a droop governor; the steps "
                                          "land there",
             single(load_steps_at_revolutions, extra=_steps_at_their_revolutions,
                    name="load-steps-at-revolutions")),
        Case("sweep-from-script", "the guide's sweep from code run as a script on a local "
                                  "cluster, with and without the __main__ guard",
             sweep_from_script, time_limit=180.0),
        Case("million-revolutions-coasting", "10⁶ revolutions coasting: energy drift, phase "
                                             "drift, memory", million_revolutions(False),
             quick=False, time_limit=900.0),
        Case("million-revolutions-driven", "10⁶ revolutions of the driven Gots diesel: "
                                           "work–energy balance, memory",
             million_revolutions(True), quick=False, time_limit=1800.0),
    ]


# ------------------------------------------------------------------------------------------------
# Running the catalogue


def _child(case: Case, quick: bool, out: str, soft: float, conn) -> None:
    try:
        o = case.run(quick, Context(Path(out), time.monotonic() + soft))
    except BaseException as exc:
        o = Outcome(ok=False, status="error", notes=[f"{type(exc).__name__}: {exc}".splitlines()[0],
                                           traceback.format_exc().splitlines()[-1]])
    conn.send(o)
    conn.close()


def warm_up() -> float:
    """Compile (or load from numba's cache) the kernels of both mechanisms, with and without
    pairs, in this process, so that the forked cases inherit them and their time bounds measure
    integration, not compilation. Returns the seconds it took."""
    from ..run import integrate

    t0 = time.perf_counter()
    for d in (put(base("coasting_single"), "run", revolutions=0.01),
              put(base("gots_diesel_friction"), "run", revolutions=0.01),
              put(put(base("swash_plate_4cyl"), "run", t_end=1e-3), "solver", method="dop853"),
              put(base("swash_plate_4cyl_friction"), "run", t_end=1e-3)):
        integrate(scene_of(d, "warm-up"))
    return time.perf_counter() - t0


def run_case(case: Case, quick: bool, out: Path) -> Outcome:
    """Run one case in a forked child, killed at its time limit (no case can hang the suite).
    A soft deadline at 80 % of the limit interrupts a run between chunks, keeping its partial
    result and diagnosis."""
    limit = case.time_limit if quick or case.full_time_limit is None else case.full_time_limit
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    t0 = time.perf_counter()
    p = ctx.Process(target=_child, args=(case, quick, str(out), 0.8 * limit, send), daemon=True)
    p.start()
    send.close()
    o = None
    if recv.poll(limit):
        try:
            o = recv.recv()
        except EOFError:
            o = None
    p.join(5.0)
    if p.is_alive():
        p.kill()
        p.join()
    wall = time.perf_counter() - t0
    if o is None:
        o = Outcome(ok=False, status="timeout" if wall >= limit else "crashed",
                    notes=[f"no result within {limit:g} s (killed)" if wall >= limit else
                           f"the process died (exit code {p.exitcode})"])
    o.wall_s = wall
    if o.status == "interrupted":
        o.notes.append(f"interrupted at the soft time bound ({0.8 * limit:g} s)")
    o.outcome = "pass" if o.ok and o.status not in ("timeout", "crashed", "error") else (
        "known failure" if case.known else "FAIL")
    if o.outcome != "pass":
        if case.known:
            o.notes.append(f"known: {case.known}")
    return o


def _fmt(x: float) -> str:
    return "—" if not math.isfinite(x) else f"{x:.2e}"


def report(rows: list[tuple[Case, Outcome]], quick: bool, wall: float, compile_s: float) -> str:
    counts = {k: sum(o.outcome == k for _, o in rows) for k in ("pass", "FAIL", "known failure")}
    lines = [
        "# Stress suite" + (" (quick)" if quick else ""),
        "",
        f"`transient stress{' --quick' if quick else ''}`, {_dt.datetime.now().isoformat(timespec='seconds')}, "
        f"{len(rows)} cases in {wall:.1f} s ({compile_s:.1f} s of it compiling or loading the "
        f"kernels before the first case): {counts['pass']} pass, {counts['FAIL']} FAIL, "
        f"{counts['known failure']} known failure(s). What each case probes and checks: "
        f"`transient/stress.py`.",
        "",
        f"Invariant: the work–energy balance ½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load + W_starter − "
        f"Σ W_loss over every stored sample, relative to the energy throughput; tolerance "
        f"max({C_BALANCE:g}·rtol, {BALANCE_FLOOR:g}) (the largest over a case's runs), unless "
        f"the notes say otherwise. Expected diagnoses (stalled, locked, chattering) must name "
        f"time and angle. Steps: accepted steps over all runs of the case. Wall: the case's "
        f"whole time, child process and result files included.",
        "",
        "| case | what it probes | outcome | status | invariant error (tolerance) | steps | "
        "wall [s] | notes |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for case, o in rows:
        notes = "; ".join(o.notes).replace("|", "\\|").replace("\n", " ")
        outcome = {"pass": "pass", "FAIL": "**FAIL**", "known failure": "**known failure**"}[
            o.outcome]
        lines.append(f"| {case.name} | {case.probes} | {outcome} | {o.status} | "
                     f"{_fmt(o.error)} ({_fmt(o.tolerance)}) | {o.steps} | {o.wall_s:.1f} | "
                     f"{notes} |")
    lines += [""]
    return "\n".join(lines)


def run_stress(quick: bool, out: str | Path = "results", only: list[str] | None = None,
               echo: Callable[[str], None] | None = print) -> tuple[list[tuple[Case, Outcome]],
                                                                   Path]:
    """Run the catalogue (``only``: these case names) and write ``out/stress.md``; the result
    files go to ``out/stress/``. Returns the rows and the report's path."""
    out = Path(out)
    files = out / "stress"
    files.mkdir(parents=True, exist_ok=True)
    cases = [c for c in catalogue() if (c.quick or not quick) and (not only or c.name in only)]
    rows = []
    t0 = time.perf_counter()
    compile_s = warm_up()
    if echo:
        echo(f"compiled or loaded the kernels in {compile_s:.1f} s")
    for case in cases:
        o = run_case(case, quick, files)
        rows.append((case, o))
        if echo:
            echo(f"{case.name:32s} {o.outcome:14s} {o.status:12s} err {_fmt(o.error)} "
                 f"({_fmt(o.tolerance)}) {o.wall_s:6.1f} s")
    path = out / "stress.md"
    path.write_text(report(rows, quick, time.perf_counter() - t0, compile_s), encoding="utf-8")
    return rows, path
