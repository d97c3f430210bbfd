"""``transient bench``: the work-precision record — error against run time over a tolerance
sweep, for transient's paths and for baselines, in one run on one machine.

For each benchmark scene (:data:`BENCH_SCENES`), over ``revolutions`` (1000):

* a reference solution: the compiled DOP853 in crank angle at rtol = atol = 1e-13, confirmed by
  the compiled DOP853 in time at the same tolerance (a different independent variable, state and
  error control); their difference is reported and bounds what the errors below can resolve;
* a sweep of rtol 1e-3 … 1e-12 (atol = rtol/1000, :data:`ATOL_PER_RTOL`) for transient's compiled
  paths (:data:`ADAPTIVE`: DOP853 and DOPRI5 in crank angle and in time, DOP853 with the tabulated
  reduced model), and a sweep of the step for the fixed-step DOP853 with tables (:data:`FIXED`,
  :data:`STEPS_PER_REV`), each timed as the median of ``repeat`` runs after a warm-up, the compile
  (or cache load) apart, integration loop only (``/solver wall_s``), writing one output sample per
  revolution (:data:`TIMED_SAMPLES_PER_REV`: the baselines are timed without dense output);
* baselines in the same run: ``scipy.integrate.solve_ivp`` RK45 and DOP853 with the plain-numpy
  right-hand side of :mod:`transient.reference` (breakpoints as terminal events, only the state
  kept), one run each (they take seconds to minutes), from loose to tight until a run is stopped
  at ``baseline_budget`` seconds; and, when the optional ``bench`` extra (CyRK) is installed, CyRK's
  compiled DOP853 (``nbsolve2_ivp``) with transient's own numba right-hand side as a C callback
  (governor branch and pair modes chosen inside each call, as a generic solver needs), timed like
  the compiled paths.

Errors after the run: the phase error ω_ref·|t_end − t_ref| [rad] at the final angle (CyRK, which
has no events, at the reference's final time: |φ − φ_ref|), the relative error of the final ω, and
the relative L2 error of ω(φ) over the last cycle (on the reference's samples; other paths'
samples interpolated by a cubic spline — solve_ivp's from its dense output, eight per step).
"""
from __future__ import annotations

import contextlib
import csv
import dataclasses as dc
import json
import math
import signal
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import SimulationError
from ..run import integrate
from ..scene import load_scene

_CASES = Path(__file__).resolve().parents[2] / "cases"
#: Benchmark scenes: the single-cylinder crank (equation (18) alone), the Gots diesel with
#: friction pairs and a governor, the 4-cylinder swash-plate engine.
BENCH_SCENES = {path.stem: path for path in (_CASES / "coasting_single.toml",
                                             _CASES / "gots_diesel_governed.toml",
                                             _CASES / "swash_plate_4cyl.toml")}
TOLERANCES = tuple(10.0 ** -k for k in range(3, 13))
#: atol of the sweep, for every method, relative to rtol. With atol = rtol the stepper's control
#: of the accumulating time (or angle) — scaled by its increment per step, ~1e-4 s — is set by
#: atol alone and the phase error stops falling with rtol (a plateau over decades of rtol on the
#: single cylinder); the other methods' states are large, where atol is moot.
ATOL_PER_RTOL = 1e-3
REF_RTOL = 1e-13
#: Each solve_ivp run is stopped after this long [s], and its tighter tolerances skipped (long
#: enough for RK45 to finish runs on every scene on a 2-core machine, which half of it is not).
BASELINE_BUDGET_S = 60.0
#: The accuracy at which speed is compared: final phase error after 1000 revolutions [rad].
TARGET_PHASE = 1e-6
SAMPLES_PER_REV = 72
#: Output of the timed runs of transient's paths: one sample per turn (in time, one per turn at
#: the final speed). The baselines are timed without dense output (CyRK keeps each step's state,
#: solve_ivp only the state), so transient is timed writing as little; the samples of the last
#: cycle for the L2 error come from an untimed rerun at SAMPLES_PER_REV (the same steps: the
#: output spacing only bounds the step at 256 samples, far from binding here).
TIMED_SAMPLES_PER_REV = 1

#: transient's compiled paths in the sweep: label → solver settings. Adaptive ones sweep rtol.
ADAPTIVE: dict[str, dict[str, str | float]] = {
    "transient DOP853 (crank angle)": {"method": "dop853"},
    "transient DOP853 (time)": {"method": "dop853", "domain": "time"},
    "transient DOPRI5 (crank angle)": {"method": "dopri5"},
    "transient DOPRI5 (time)": {"method": "dopri5", "domain": "time"},
    "transient DOP853 tabulated (crank angle)": {"method": "dop853", "kinematics": "tabulated"},
}
#: The fixed-step path sweeps the step instead: 2π/N for these N (steps per revolution); its
#: tables are made to 1e-12 (``table_tolerance``), near the splines' floor.
FIXED: dict[str, dict[str, str | float]] = {
    "transient DOP853 fixed step, tabulated (crank angle)":
        {"method": "dop853", "kinematics": "tabulated", "table_tolerance": 1e-12}}
#: The fixed-step path's steps per revolution N (a step of 2π/N).
STEPS_PER_REV = (16, 32, 64, 128, 256, 512, 1024)
#: The label of the default path, against which the others' speed is stated.
DEFAULT = "transient DOP853 (crank angle)"

COLUMNS = ("scene", "method", "rtol", "step_rad", "wall_s", "compile_s", "repeats", "nfev",
           "nsteps", "nreject", "phase_err_rad", "omega_rel_err", "omega_l2_rel_err")


def _scene(base, method, rtol, revolutions, dt=0.0, samples=SAMPLES_PER_REV, **solver):
    """``base`` over ``revolutions`` with a method, rtol (atol = rtol·ATOL_PER_RTOL) and any other
    solver settings; output at ``samples`` per turn (or every ``dt`` in time)."""
    solver = dc.replace(base.solver, method=method, rtol=rtol, atol=rtol * ATOL_PER_RTOL,
                        **solver)
    return dc.replace(base, run=dc.replace(base.run, revolutions=revolutions, t_end=math.inf),
                      solver=solver, output=dc.replace(base.output, samples_per_rev=samples, dt=dt))


@dc.dataclass
class Reference:
    t_end: float
    omega_end: float
    phi_end: float
    phi_grid: np.ndarray  # the last cycle's samples
    omega_grid: np.ndarray
    confirm_phase: float = math.nan  # the second method's differences
    confirm_omega: float = math.nan


def _end_errors(ref: Reference, t_end, omega_end):
    """(phase [rad], relative final ω) of a run that ends at the reference's final angle."""
    return abs(ref.omega_end * (t_end - ref.t_end)), abs(omega_end / ref.omega_end - 1.0)


def _l2_error(ref: Reference, phi, omega) -> float:
    """Relative L2 error of ω(φ) over the last cycle, on the reference's samples."""
    window = phi >= ref.phi_grid[0] - 0.5
    p, w = phi[window], omega[window]
    keep = np.concatenate([[True], np.diff(p) > 0])
    w_run = CubicSpline(p[keep], w[keep])(ref.phi_grid) if keep.sum() >= 4 else np.nan
    return float(np.sqrt(np.mean((w_run - ref.omega_grid) ** 2)) / np.mean(ref.omega_grid))


def _errors(ref: Reference, t_end, omega_end, phi, omega):
    """(phase [rad], relative final ω, relative L2 of ω(φ) over the last cycle)."""
    return (*_end_errors(ref, t_end, omega_end), _l2_error(ref, phi, omega))


def _tail(traj, cycle):
    phi = traj["phi"]
    sel = phi >= phi[-1] - cycle - 1e-9
    return phi[sel], traj["omega"][sel]


def reference(base, revolutions) -> Reference:
    """Compiled DOP853 at 1e-13 in crank angle, confirmed in time."""
    cycle = base.mechanism.cycle
    data = integrate(_scene(base, "dop853", REF_RTOL, revolutions))
    tr = data.trajectory
    phi, w = _tail(tr, cycle)
    ref = Reference(tr["t"][-1], tr["omega"][-1], tr["phi"][-1], phi, w)
    check = integrate(_scene(base, "dop853", REF_RTOL, revolutions, dt=_dt(base, ref),
                             domain="time"), keep=False).trajectory
    ref.confirm_phase = abs(ref.omega_end * (check["t"][-1] - ref.t_end))
    ref.confirm_omega = abs(check["omega"][-1] / ref.omega_end - 1.0)
    return ref


def _dt(base, ref: Reference) -> float:
    """Output spacing in time giving about SAMPLES_PER_REV samples per turn at the end."""
    return 2.0 * math.pi / (SAMPLES_PER_REV * abs(ref.omega_end))


def _row(name, method, rtol, wall, compile_s, repeats, solver, errors, step=0.0):
    return dict(zip(COLUMNS, (name, method, rtol, step, wall, compile_s, repeats,
                              solver.get("nfev", 0), solver.get("nsteps", 0),
                              solver.get("nreject", 0), *errors)))


def _compiled(name, base, ref, label, settings, rtol, revolutions, repeat, step=0.0):
    """One compiled path (``settings``: solver fields) at one rtol or fixed step [rad]."""
    time_domain = settings.get("domain") == "time"
    settings = dict(settings, fixed_step=step)
    sparse = SAMPLES_PER_REV / TIMED_SAMPLES_PER_REV
    scene = _scene(base, settings.pop("method"), rtol, revolutions,
                   _dt(base, ref) * sparse if time_domain else 0.0, TIMED_SAMPLES_PER_REV,
                   **settings)
    first = integrate(scene, keep=False)
    walls, data = [], None
    for _ in range(repeat):
        data = integrate(scene, keep=False)
        walls.append(data.solver["wall_s"])
    # The final state from the timed run; the last cycle's samples from an untimed rerun at
    # SAMPLES_PER_REV (in time with 8× denser output, so that the spline through them adds nothing
    # measurable; there the step bound, 256 output intervals, can bind, so steps may differ).
    end = data.trajectory
    dense = dc.replace(scene.output, samples_per_rev=SAMPLES_PER_REV,
                       dt=scene.output.dt / sparse / 8)
    full = integrate(dc.replace(scene, output=dense))
    if not time_domain and full.solver["nsteps"] != data.solver["nsteps"]:
        raise RuntimeError(f"{name} {label}: the rerun for the samples took "
                           f"{full.solver['nsteps']} steps, the timed run {data.solver['nsteps']}")
    tr = full.trajectory
    phase, w_err = _end_errors(ref, end["t"][-1], end["omega"][-1])
    l2 = _l2_error(ref, tr["phi"], tr["omega"])
    return _row(name, label, 0.0 if step else rtol, statistics.median(walls),
                first.solver["compile_s"], repeat, data.solver, (phase, w_err, l2), step)


#: Settings of the targets' timed runs (:mod:`.targets`): rtol 1e-8, atol 1e-11.
RUN_RTOL, RUN_ATOL = 1e-8, 1e-11


def timed_scene(base, revolutions=1000.0, samples_per_rev=1):
    """``base`` as the overhead and bare-scene runs time it (RUN_RTOL, RUN_ATOL)."""
    return dc.replace(base, run=dc.replace(base.run, revolutions=revolutions, t_end=math.inf),
                      solver=dc.replace(base.solver, rtol=RUN_RTOL, atol=RUN_ATOL),
                      output=dc.replace(base.output, samples_per_rev=samples_per_rev))


def median_walls(*scenes, repeat=5):
    """Median integration wall time of each scene, their runs alternating, after a warm-up each;
    with the solver's counts of each scene's last run."""
    walls, counts = [[] for _ in scenes], [None] * len(scenes)
    for i in range(repeat + 1):
        for k, scene in enumerate(scenes):
            counts[k] = integrate(scene, keep=False).solver
            if i:
                walls[k].append(counts[k]["wall_s"])
    return [statistics.median(w) for w in walls], walls, counts


class OverBudget(Exception):
    """A baseline run took longer than its budget and was stopped."""


@contextlib.contextmanager
def budget(seconds: float):
    """Raise :class:`OverBudget` in the block after ``seconds``: a timer signal, not a check
    between segments, since one segment of a baseline can take arbitrarily long."""
    def stop(signum, frame):
        raise OverBudget

    previous = signal.signal(signal.SIGALRM, stop)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def _solve_ivp(name, base, ref, rtol, revolutions, method, seconds):
    """One solve_ivp run, or None if it was stopped after ``seconds``."""
    from ..reference import run_reference

    scene = _scene(base, f"scipy-{method}", rtol, revolutions)
    try:
        with budget(seconds):
            data = run_reference(scene, state_only=True, dense_tail=base.mechanism.cycle + 0.5)
    except OverBudget:
        return None
    except (ValueError, FloatingPointError, SimulationError) as exc:  # e.g. a stage overflowed
        return f"failed: {exc}"
    tr = data.trajectory
    return _row(name, f"solve_ivp {method} (numpy RHS)", rtol, data.solver["wall_s"], 0.0, 1,
                data.solver, _errors(ref, tr["t"][-1], tr["omega"][-1], tr["phi"], tr["omega"]))


def cyrk_available() -> bool:
    try:
        import CyRK  # noqa: F401
    except ImportError:
        return False
    return True


def _cyrk(name, base, ref, rtol, revolutions, repeat, rhs_cache):
    """CyRK's DOP853 on transient's compiled RHS (a C callback), over [0, t_ref]."""
    from CyRK import nbsolve2_ivp

    from ..assemble import build_model
    from ..core.model import layout, work
    from .cyrk_rhs import make_rhs

    model, _, _ = build_model(base)
    t0 = time.perf_counter()
    if name not in rhs_cache:
        rhs_cache[name] = make_rhs(model)
    rhs = rhs_cache[name]
    y0 = np.zeros(layout.n_state(model))
    y0[layout.PHI], y0[layout.OMEGA] = base.initial.phi, base.initial.omega
    args = work.work_array(model).ravel()  # (as allocated: no gas table piece selected yet)
    span = (0.0, ref.t_end)

    def solve(dense=False):
        return nbsolve2_ivp(rhs.address, span, y0, method="DOP853", rtol=rtol,
                            atol=rtol * ATOL_PER_RTOL,
                            args=args, dense_output=dense)

    sol = solve()
    sol.free()
    compile_s = time.perf_counter() - t0
    walls = []
    for _ in range(repeat):
        t1 = time.perf_counter()
        sol = solve()
        walls.append(time.perf_counter() - t1)
        ok, steps, y_end = sol.success, sol.steps_taken, sol.y[:, -1].copy()
        sol.free()
    if not ok:
        return None
    sol = solve(dense=True)  # the last cycle from its dense output (untimed)
    t_tail = np.linspace(ref.t_end - 1.5 * base.mechanism.cycle / abs(ref.omega_end), ref.t_end,
                         16 * SAMPLES_PER_REV)
    tail = sol.call_vectorize(t_tail)
    sol.free()
    phase = abs(y_end[layout.PHI] - ref.phi_end)
    w_err = _end_errors(ref, ref.t_end, y_end[layout.OMEGA])[1]
    l2 = _l2_error(ref, tail[layout.PHI], tail[layout.OMEGA])
    return _row(name, "CyRK DOP853 (transient's compiled RHS)", rtol, statistics.median(walls),
                compile_s, repeat, {"nfev": -1, "nsteps": steps, "nreject": -1},
                (phase, w_err, l2))


def run_bench(scenes=None, revolutions=1000.0, tolerances=TOLERANCES, repeat=5,
              baselines=True, out="results/benchmarks", baseline_budget=BASELINE_BUDGET_S,
              baseline_tolerances=None, progress=print, steps_per_rev=STEPS_PER_REV
              ) -> list[dict]:
    """Measure every (scene, method, rtol); write ``work_precision.csv``, one figure per scene
    and ``work_precision.md`` into ``out``; return the rows."""
    scenes = scenes or BENCH_SCENES
    rows, refs = [], {}
    rhs_cache: dict[str, object] = {}  # each scene's right-hand side compiled for CyRK
    for name, path in scenes.items():
        base = load_scene(path)
        t0 = time.perf_counter()
        refs[name] = ref = reference(base, revolutions)
        progress(f"{name}: reference in {time.perf_counter() - t0:.1f} s (time-domain check: "
                 f"phase {ref.confirm_phase:.1e} rad, ω {ref.confirm_omega:.1e})")
        for label, settings in ADAPTIVE.items():
            for rtol in tolerances:
                rows.append(_compiled(name, base, ref, label, settings, rtol, revolutions,
                                      repeat))
                progress(_line(rows[-1]))
        for label, settings in FIXED.items():
            for n in steps_per_rev:
                rows.append(_compiled(name, base, ref, label, settings, base.solver.rtol,
                                      revolutions, repeat, step=2.0 * math.pi / n))
                progress(_line(rows[-1]))
        if baselines and cyrk_available():
            for rtol in tolerances:
                row = _cyrk(name, base, ref, rtol, revolutions, repeat, rhs_cache)
                if row:
                    rows.append(row)
                    progress(_line(rows[-1]))
        for method in ("RK45", "DOP853") if baselines else ():
            for rtol in baseline_tolerances or tolerances:
                row = _solve_ivp(name, base, ref, rtol, revolutions, method, baseline_budget)
                if row is None:
                    progress(f"  {name} | solve_ivp {method} | rtol {rtol:.0e} | stopped after "
                             f"{baseline_budget:g} s (budget)")
                    break
                if isinstance(row, str):  # a failed run: try the next, tighter tolerance
                    progress(f"  {name} | solve_ivp {method} | rtol {rtol:.0e} | {row}")
                    continue
                rows.append(row)
                progress(_line(rows[-1]))
        write_record(rows, refs, Path(out), revolutions)  # after every scene: nothing is lost
    return rows


def _line(r) -> str:
    how = (f"step {math.degrees(r['step_rad']):.3g}°" if r["step_rad"] else
           f"rtol {r['rtol']:.0e}")
    return (f"  {r['scene']} | {r['method']} | {how} | {r['wall_s']:.4g} s | "
            f"phase {r['phase_err_rad']:.2e} rad | ω {r['omega_rel_err']:.2e} | "
            f"L2 {r['omega_l2_rel_err']:.2e}")


#: How far a method's most accurate run may be from the target for a log-log extrapolation to it
#: [decades of phase error]: further, the runs are far from the asymptotic regime (a budgeted
#: solve_ivp stopped far from the target extrapolates to absurd times).
EXTRAPOLATE_DECADES = 2.0


def at_target(rows, scene, method, target=TARGET_PHASE):
    """(wall, how) to reach phase error ≤ target: the fastest run that does, else a log-log
    extrapolation through the two most accurate runs if the better is within
    EXTRAPOLATE_DECADES of the target (``how`` says which), else NaN."""
    runs = sorted((r for r in rows if r["scene"] == scene and r["method"] == method),
                  key=lambda r: r["phase_err_rad"])
    ok = [r["wall_s"] for r in runs if r["phase_err_rad"] <= target]
    if ok:
        return min(ok), "measured"
    good = [r for r in runs if r["phase_err_rad"] > 0 and math.isfinite(r["phase_err_rad"])]
    if len(good) < 2 or good[0]["phase_err_rad"] >= good[1]["phase_err_rad"]:
        return math.nan, "not reached"
    (e1, w1), (e2, w2) = ((r["phase_err_rad"], r["wall_s"]) for r in good[:2])
    if not w1 > w2 or e1 > target * 10.0 ** EXTRAPOLATE_DECADES:  # no trend to follow
        return math.nan, f"not reached (best {e1:.1e} rad)"
    slope = math.log(w1 / w2) / math.log(e1 / e2)
    return w1 * (target / e1) ** slope, f"extrapolated from {e1:.1e} rad"


def fastest_as_accurate(rows, scene, method, error):
    """(wall, run) of the fastest run of ``method`` whose phase error is ≤ ``error`` (measured
    runs only, no interpolation); (NaN, None) if none is."""
    ok = [r for r in rows if r["scene"] == scene and r["method"] == method
          and r["phase_err_rad"] <= error]
    if not ok:
        return math.nan, None
    best = min(ok, key=lambda r: r["wall_s"])
    return best["wall_s"], best


def equal_error_lines(rows, scene) -> list[str]:
    """Markdown rows: each baseline's most accurate run against the fastest run of each transient
    path at least as accurate (speed at equal error where the baseline cannot reach 1e-6 rad)."""
    lines = []
    transient = sorted({r["method"] for r in rows if r["scene"] == scene
                        and r["method"].startswith("transient")})
    for base in sorted({r["method"] for r in rows if r["scene"] == scene
                        and not r["method"].startswith("transient")}):
        runs = [r for r in rows if r["scene"] == scene and r["method"] == base
                and math.isfinite(r["phase_err_rad"])]
        if not runs:
            continue
        b = min(runs, key=lambda r: r["phase_err_rad"])
        for m in transient:
            wall, r = fastest_as_accurate(rows, scene, m, b["phase_err_rad"])
            if r is not None:
                lines.append(f"| {base} | {b['phase_err_rad']:.2g} | {b['wall_s']:.4g} | {m} | "
                             f"{r['phase_err_rad']:.2g} | {wall:.4g} | {b['wall_s'] / wall:.3g} |")
    return lines


#: Two runs of an adaptive path whose step counts are within this fraction of each other took the
#: same steps: the tolerance did not set them (the breakpoints and the maximum step did), and
#: errors within this fraction of each other are the same error (a plateau, not a rise).
SAME_STEPS = 0.01


def loose_to_tight(rows, scene, method):
    """The runs of one path on one scene, from the loosest rtol (or the longest fixed step)."""
    return sorted((r for r in rows if r["scene"] == scene and r["method"] == method),
                  key=lambda r: -(r["step_rad"] or r["rtol"]))


def on_plateau(prev, run) -> bool:
    """Whether ``run`` took the steps of the looser ``prev`` (within ``SAME_STEPS``): tightening
    the tolerance from there changed neither the steps nor, then, what sets the error."""
    return prev is not None and run["nsteps"] <= (1.0 + SAME_STEPS) * prev["nsteps"] \
        and run["step_rad"] == 0.0


def order_slope(rows, scene, method, floor):
    """Least-squares slope of log(phase error) against log(rtol) — or against log(step) for a
    fixed-step path — over the runs whose error is above 100× ``floor`` (the reference's own
    uncertainty) and whose steps the tolerance set (not :func:`on_plateau`: on the swash plate,
    rtol 1e-3 … 1e-6 all take one step per breakpoint segment and give one error, which would
    flatten the slope without saying anything of the method's order)."""
    runs = loose_to_tight(rows, scene, method)
    pts = [(math.log10(r["step_rad"] or r["rtol"]), math.log10(r["phase_err_rad"]))
           for prev, r in zip([None] + runs, runs)
           if r["phase_err_rad"] > 100 * floor and not on_plateau(prev, r)]
    if len(pts) < 3:
        return math.nan
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


def _merge_earlier(rows, refs, out: Path):
    """Rows and references of scenes measured by an earlier run into ``out`` and not by this one
    (``transient bench SCENE…`` updates the record scene by scene)."""
    csv_path, ref_path = out / "work_precision.csv", out / "work_precision_references.json"
    if not (csv_path.is_file() and ref_path.is_file()):
        return rows, refs
    earlier = json.loads(ref_path.read_text())
    keep = {name: Reference(phi_grid=np.zeros(0), omega_grid=np.zeros(0), **r)
            for name, r in earlier.items() if name not in refs}
    with open(csv_path, newline="") as fh:
        old = [{k: (r.get(k, "0") if k in ("scene", "method") else float(r.get(k) or 0.0))
                for k in COLUMNS} for r in csv.DictReader(fh) if r["scene"] in keep]
    return old + rows, {**keep, **refs}


def write_record(rows, refs, out: Path, revolutions) -> None:
    out.mkdir(parents=True, exist_ok=True)
    rows, refs = _merge_earlier(rows, refs, out)
    (out / "work_precision_references.json").write_text(json.dumps(
        {name: {k: getattr(r, k) for k in ("t_end", "omega_end", "phi_end", "confirm_phase",
                                            "confirm_omega")} for name, r in refs.items()},
        indent=1) + "\n")
    with open(out / "work_precision.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    _figures(rows, out)
    lines = [f"# Work-precision record ({revolutions:g} revolutions)", "",
             "Written by `transient bench` (see its docstring for what is measured). Compiled "
             "paths and CyRK: median of the runs after a warm-up, compile apart; solve_ivp: one "
             f"run. Speed compared at a final phase error ≤ {TARGET_PHASE:g} rad. Output while "
             f"timed: transient {TIMED_SAMPLES_PER_REV} sample per revolution, CyRK the state at "
             "each step, solve_ivp the state (no dense output for any); the last cycle's samples "
             "for the L2 error come from untimed reruns.", ""]
    for scene, ref in refs.items():
        lines += [f"## {scene}", "",
                  f"Reference: DOP853 in crank angle at rtol = atol = {REF_RTOL:g}; the same in "
                  f"time differs by {ref.confirm_phase:.1e} rad in phase and "
                  f"{ref.confirm_omega:.1e} in final ω.", "",
                  "| method | wall at ≤ 1e-6 rad [s] | how | × transient (crank angle) | "
                  "slope of log(error) against log(rtol), fixed step: log(step) |",
                  "|---|---|---|---|---|"]
        methods = sorted({r["method"] for r in rows if r["scene"] == scene})
        base_wall, _ = at_target(rows, scene, DEFAULT)
        for m in methods:
            wall, how = at_target(rows, scene, m)
            lines.append(f"| {m} | {wall:.4g} | {how} | {wall / base_wall:.3g} | "
                         f"{order_slope(rows, scene, m, ref.confirm_phase):.2f} |")
        lines += ["", "At equal error: each baseline's most accurate run against the fastest run "
                      "of each transient path that is at least as accurate.", "",
                  "| baseline | its phase error [rad] | its wall [s] | transient path | "
                  "phase error [rad] | wall [s] | baseline / transient |",
                  "|---|---|---|---|---|---|---|", *equal_error_lines(rows, scene), ""]
    (out / "work_precision.md").write_text("\n".join(lines) + "\n", encoding="utf-8")


def read_record(out: Path) -> tuple[list[dict], dict[str, Reference]]:
    """The rows and references of the record in ``out`` (references without their samples)."""
    return _merge_earlier([], {}, Path(out))


def rewrite_report(out: Path, revolutions: float = 1000.0) -> None:
    """Rewrite ``work_precision.md`` and the figures from the record's CSV and references (after
    a change to the report, without measuring again)."""
    rows, refs = read_record(Path(out))
    write_record(rows, refs, Path(out), revolutions)


def _figures(rows, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for scene in sorted({r["scene"] for r in rows}):
        fig, axes = plt.subplots(1, 2, figsize=(12, 5.6))
        for m in sorted({r["method"] for r in rows if r["scene"] == scene}):
            sel = sorted((r for r in rows if r["scene"] == scene and r["method"] == m),
                         key=lambda r: -(r["step_rad"] or r["rtol"]))
            for ax, key in zip(axes, ("phase_err_rad", "omega_l2_rel_err")):
                ax.loglog([r["wall_s"] for r in sel], [max(r[key], 1e-17) for r in sel], "o-",
                          label=m, ms=4)
        for ax, label in zip(axes, ("final phase error [rad]", "L2 error of ω(φ), last cycle")):
            ax.set_xlabel("wall time [s]")
            ax.set_ylabel(label)
            ax.grid(True, which="both", alpha=0.3)
        axes[0].axhline(TARGET_PHASE, color="k", lw=0.6, ls=":")
        # one legend below both panels: inside an axes it hid the slow baselines' points
        handles, labels = axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
        fig.suptitle(f"{scene}: work-precision")
        fig.tight_layout(rect=(0, 0.1, 1, 1))
        fig.savefig(out / f"work_precision_{scene}.png", dpi=110)
        plt.close(fig)
