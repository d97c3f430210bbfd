"""The elastic shaft line's speed targets, measured by ``transient bench --targets`` beside the
rigid ones (:mod:`transient.verify.targets`):

* **against the rigid model**: the in-line six with its damper (:data:`ELASTIC_SCENE`: eight
  stations and the damper's ring, nine degrees of freedom) run up from its initial speed costs at
  most :data:`RIGID_TARGET` times its rigid equivalent
  (:func:`transient.shaft.line.rigid_equivalent`) per cycle, both at the targets' tolerance
  (``targets.RUN_RTOL``, ``RUN_ATOL``); the steps and right-hand-side calls of each are kept,
  so that a miss says whether the steps or the calls cost it;
* **linear in the line's length**: a generated line of N equal stations and sections (the six's
  cylinders spread over all but the last, a flywheel last) for N = 3 … 30 — its highest natural
  frequency, which bounds an explicit step, does not grow with N — its wall per cycle fitted
  against N (slope, R²), met where it rises with N and the cost at 30 is at most 10× that at 3
  (as a + bN with a, b ≥ 0 is; a cost growing as N² would be 100×);
* **against scipy**: the same run-up by ``solve_ivp`` RK45, Radau and LSODA on the reference
  path's numpy right-hand side of the same equations (:mod:`transient.reference.torsion`), at
  equal final phase error against a tight compiled reference: the work-precision record's
  rows, compared as the rigid scenes' are (:func:`transient.verify.targets.elastic_against_scipy`),
  the fastest of the three against transient, at least :data:`SCIPY_TARGET` times.

A scene without ``[shaft]`` runs the rigid Model, whose line kernels are no-ops compiled out:
what it costs is the rigid targets' (stepper overhead, bare scene), not measured again here.
"""
from __future__ import annotations

import dataclasses as dc
import math
import time
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from ..reference.torsion import from_scene
from ..scene import load_scene
from ..scene.records import Station
from ..shaft import rigid_equivalent
from .bench import (
    _CASES,
    ADAPTIVE,
    ATOL_PER_RTOL,
    BASELINE_BUDGET_S,
    DEFAULT,
    OverBudget,
    _compiled,
    _row,
    budget,
    median_walls,
    reference,
    timed_scene,
)

#: The bench's elastic scene: eight stations (pulley, six throws, flywheel) and a viscous
#: damper's ring, nine degrees of freedom.
ELASTIC_SCENE = _CASES / "inline6_damper.toml"
#: The elastic run's cost per cycle at most this many times the rigid equivalent's.
RIGID_TARGET = 10.0
#: transient at least this many times faster than scipy's fastest on the numpy right-hand side.
SCIPY_TARGET = 100.0
SCIPY_METHODS = ("RK45", "Radau", "LSODA")
#: Station counts of the generated line.
STATIONS = (3, 5, 10, 20, 30)
#: The generated line: each station's own inertia, the flywheel's, each section's stiffness and
#: damping (the six's throws').
STATION_INERTIA, FLYWHEEL_INERTIA, SECTION_K, SECTION_C = 0.03, 0.5, 1.0e6, 10.0
#: The run-up timed against the rigid model and along the generated lines [revolutions], and the
#: one integrated against scipy (the numpy right-hand side takes seconds per revolution).
RUN_REVOLUTIONS, LINE_REVOLUTIONS, SCIPY_REVOLUTIONS = 200.0, 100.0, 20.0
SCIPY_TOLERANCES = tuple(10.0 ** -k for k in range(4, 11))


def _cycles(scene) -> float:
    """The engine cycles ``scene`` runs."""
    return scene.run.revolutions * 2.0 * math.pi / scene.mechanism.cycle


def against_rigid(revolutions=RUN_REVOLUTIONS, repeat=5) -> dict:
    """The elastic scene's run-up and its rigid equivalent's, both at the targets' tolerance:
    median integration wall per cycle of alternating runs, steps and calls per cycle."""
    elastic = timed_scene(load_scene(ELASTIC_SCENE), revolutions)
    rigid = rigid_equivalent(elastic)
    (w_e, w_r), _, (c_e, c_r) = median_walls(elastic, rigid, repeat=repeat)
    cycles = _cycles(elastic)
    return {"scene": ELASTIC_SCENE.stem, "dofs": len(elastic.shaft.line_dofs()),
            "stations": len(elastic.shaft.stations), "cycles": cycles,
            "elastic_s": w_e / cycles, "rigid_s": w_r / cycles, "ratio": w_e / w_r,
            "elastic_steps": c_e["nsteps"] / cycles, "rigid_steps": c_r["nsteps"] / cycles,
            "elastic_call_s": w_e / c_e["nfev"], "rigid_call_s": w_r / c_r["nfev"]}


def generated_line(base, n: int):
    """``base`` (a crank-slider scene with ``[shaft]``) on a line of ``n`` ≥ 2 stations: n − 1
    equal ones carrying the cylinders spread in order (cylinder c on station ⌊c (n−1)/z⌋ of
    z), then a flywheel, joined by equal sections."""
    z = base.mechanism.n_cylinders
    cylinders: list[list[int]] = [[] for _ in range(n - 1)]
    for c in range(z):
        cylinders[c * (n - 1) // z].append(c + 1)
    stations = [Station(f"s{i + 1}", STATION_INERTIA, 0.0, tuple(cyl))
                for i, cyl in enumerate(cylinders)]
    stations.append(Station("flywheel", FLYWHEEL_INERTIA))
    section = dc.replace(base.shaft.sections[1], stiffness=SECTION_K, damping=SECTION_C,
                         loss_factor=0.0, damping_ratio=0.0)
    shaft = dc.replace(base.shaft, stations=tuple(stations), sections=(section,) * (n - 1),
                       dampers=(), coupling=None, reference="flywheel", load_at="flywheel")
    return dc.replace(base, shaft=shaft)


def stations_scaling(counts=STATIONS, revolutions=LINE_REVOLUTIONS, repeat=5) -> dict:
    """Wall per cycle of the generated line at each station count (medians of alternating
    runs), the least-squares line through them against N, its R², and the cost at the largest
    N over that at the smallest."""
    base = timed_scene(load_scene(ELASTIC_SCENE), revolutions)
    scenes = [generated_line(base, n) for n in counts]
    walls, _, counts_ = median_walls(*scenes, repeat=repeat)
    per_cycle = np.array(walls) / _cycles(base)
    n = np.asarray(counts, dtype=float)
    slope, intercept = np.polyfit(n, per_cycle, 1)
    fit = slope * n + intercept
    r2 = 1.0 - float(np.sum((per_cycle - fit) ** 2) / np.sum((per_cycle - per_cycle.mean()) ** 2))
    return {"stations": list(counts), "wall_per_cycle_s": per_cycle.tolist(),
            "steps_per_cycle": [c["nsteps"] / _cycles(base) for c in counts_],
            "slope_s": float(slope), "intercept_s": float(intercept), "r2": r2,
            "ratio": float(per_cycle[-1] / per_cycle[0]), "span": float(n[-1] / n[0])}


def _numpy_run(name, base, ref, rtol, method, seconds):
    """One ``solve_ivp`` run of the reference path's numpy line to the reference's final time,
    or None if stopped after ``seconds``; its phase error the reference station's angle there
    against the reference's final angle. The motion's states only: the work integrals feed
    nothing back (and, as a viscous ring's angle, would be columns of zeros in an implicit
    method's Jacobian: :func:`_difference_jacobian`)."""
    model, at = from_scene(base)
    y0 = model.initial_state(base.initial.phi, base.initial.omega)
    works = np.zeros(model.size - model.i_works)

    def motion(t, y):
        return model.rhs(t, np.concatenate([y, works]))[:model.i_works]

    jac = {"jac": _difference_jacobian(motion)} if method in ("Radau", "BDF") else {}
    try:
        with budget(seconds):
            t0 = time.perf_counter()
            sol = solve_ivp(motion, (0.0, ref.t_end), y0[:model.i_works], method=method,
                            rtol=rtol, atol=rtol * ATOL_PER_RTOL, **jac)
            wall = time.perf_counter() - t0
    except OverBudget:
        return None
    except (ValueError, FloatingPointError, np.linalg.LinAlgError) as exc:
        return f"failed: {exc}"
    if sol.status != 0:
        return f"failed: {sol.message}"
    y = sol.y[:, -1]
    errors = (abs(y[at] - ref.phi_end), abs(y[model.line.n + at] / ref.omega_end - 1.0),
              math.nan)
    return _row(name, f"solve_ivp {method} (numpy RHS)", rtol, wall, 0.0, 1,
                {"nfev": model.nfev, "nsteps": sol.t.size - 1, "nreject": 0}, errors)


def _difference_jacobian(fun):
    """Forward differences of ``fun`` at steps √ε·max(|y|, 1): the Jacobian scipy's Radau would
    form, without its adaptive step, which grows tenfold at every evaluation in a column of
    zeros (a viscous damper's ring angle, on which no force depends) until it overflows."""
    def jac(t, y):
        f0 = fun(t, y)
        h = math.sqrt(np.finfo(float).eps) * np.maximum(np.abs(y), 1.0)
        out = np.empty((f0.size, y.size))
        for j in range(y.size):
            step = y.copy()
            step[j] += h[j]
            out[:, j] = (fun(t, step) - f0) / h[j]
        return out
    return jac


def scipy_rows(revolutions=SCIPY_REVOLUTIONS, tolerances=SCIPY_TOLERANCES, repeat=3,
               seconds=BASELINE_BUDGET_S, methods=SCIPY_METHODS, progress=print) -> list[dict]:
    """The work-precision rows of the elastic scene's run-up (:data:`ELASTIC_SCENE` over
    ``revolutions``): transient's default path at each rtol, and each scipy method from loose to
    tight until a run exceeds ``seconds``; the errors against :func:`.bench.reference`."""
    base = load_scene(ELASTIC_SCENE)
    base = dc.replace(base, run=dc.replace(base.run, revolutions=revolutions, t_end=math.inf))
    name = f"{ELASTIC_SCENE.stem} (elastic)"
    ref = reference(base, revolutions)
    rows = [_compiled(name, base, ref, DEFAULT, ADAPTIVE[DEFAULT], rtol, revolutions, repeat)
            for rtol in tolerances]
    for method in methods:
        for rtol in tolerances:
            row = _numpy_run(name, base, ref, rtol, method, seconds)
            if row is None:
                progress(f"targets: {name} solve_ivp {method} at rtol {rtol:.0e} stopped after "
                         f"{seconds:g} s")
                break
            if isinstance(row, str):
                progress(f"targets: {name} solve_ivp {method} at rtol {rtol:.0e} {row}")
                continue
            rows.append(row)
    progress(f"targets: {name} against scipy ({len(rows)} runs; reference confirmed in time to "
             f"{ref.confirm_phase:.1e} rad)")
    return rows


def measure(quick=False, progress=print) -> dict:
    """Every elastic target's measurement (``quick``: the harness on tiny runs); the scipy
    rows' comparison is the targets' (:func:`.targets.elastic_against_scipy`)."""
    res: dict[str, Any]
    if quick:
        res = {"rigid": against_rigid(revolutions=4.0, repeat=1),
               "scaling": stations_scaling(counts=(3, 4), revolutions=2.0, repeat=1)}
        rows = scipy_rows(revolutions=1.0, tolerances=(1e-5, 1e-6), repeat=1, seconds=30.0,
                          methods=("RK45",), progress=progress)
    else:
        res = {"rigid": against_rigid()}
        progress("targets: elastic against rigid")
        res["scaling"] = stations_scaling()
        progress("targets: elastic line's length")
        rows = scipy_rows(progress=progress)
    res["rows"] = rows
    return res


def verdicts(res, missed) -> list[tuple[str, str, str, str]]:
    """(target, case, measured, verdict) of each elastic target; ``missed``: the targets'
    verdict of a value against a target (``targets._missed``)."""
    r, s, sp = res["rigid"], res["scaling"], res["scipy"]
    lines = [(f"elastic run-up ≤ {RIGID_TARGET:g}× its rigid equivalent per cycle (equal "
              "tolerance)", f"{r['scene']} ({r['stations']} stations, {r['dofs']} dofs)",
              f"{r['ratio']:.2f}× ({r['elastic_s'] * 1e3:.3g} against {r['rigid_s'] * 1e3:.3g} "
              f"ms per cycle; {r['elastic_steps']:.0f} against {r['rigid_steps']:.0f} steps per "
              f"cycle, {r['elastic_call_s'] / r['rigid_call_s']:.2f}× per RHS call)",
              missed(r["ratio"], RIGID_TARGET))]
    # (a cost a + bN, a, b ≥ 0, grows at most as N does; a quadratic term would pass it)
    linear = s["slope_s"] > 0.0 and s["ratio"] <= s["span"]
    lines.append((f"cost per cycle linear in the stations, {s['stations'][0]} to "
                  f"{s['stations'][-1]}", "generated line (equal stations, flywheel last)",
                  f"{s['slope_s'] * 1e6:.3g} µs per station per cycle, R² {s['r2']:.3f}; "
                  f"{s['ratio']:.2f}× the cost at {s['stations'][0]} (linear: ≤ "
                  f"{s['span']:g}×)", "met" if linear else "**missed**"))
    b = sp["best"]
    if b is None:
        lines.append((f"≥ {SCIPY_TARGET:g}× scipy's best of {'/'.join(SCIPY_METHODS)} (numpy "
                      "RHS), equal error", ELASTIC_SCENE.stem, "no scipy run to compare",
                      "**not measured**"))
    else:
        verdict = missed(b["ratio"], SCIPY_TARGET, larger_is_better=True)
        lines.append((f"≥ {SCIPY_TARGET:g}× scipy's best of {'/'.join(SCIPY_METHODS)} (numpy "
                      "RHS), equal error", b["scene"],
                      f"{b['ratio']:.3g}× {b['baseline']} at {b['error_rad']:.1e} rad "
                      f"({b['how']})", verdict))
    lines.append(("a scene without [shaft] pays nothing for the torsional model", "rigid scenes",
                  "the rigid rows above (stepper overhead, bare scene): a rigid Model's line "
                  "kernels are no-ops, compiled out", "covered by the rigid targets"))
    return lines


def section(res) -> list[str]:
    """targets.md's section of the elastic measurements."""
    r, s = res["rigid"], res["scaling"]
    md = ["", "## Elastic shaft line", "",
          f"Run-up of `{r['scene']}.toml` over {r['cycles']:g} cycles at the targets' tolerance, "
          f"against its rigid equivalent: {r['elastic_s'] * 1e3:.4g} against "
          f"{r['rigid_s'] * 1e3:.4g} ms per cycle, {r['elastic_steps']:.0f} against "
          f"{r['rigid_steps']:.0f} steps per cycle, {r['elastic_call_s'] * 1e6:.3g} against "
          f"{r['rigid_call_s'] * 1e6:.3g} µs of wall per RHS call (the stepper's share "
          "included).", "",
          "| stations | wall per cycle [ms] | steps per cycle |", "|---|---|---|",
          *(f"| {n} | {w * 1e3:.4g} | {k:.0f} |" for n, w, k in
            zip(s["stations"], s["wall_per_cycle_s"], s["steps_per_cycle"])), "",
          "Against scipy on the numpy right-hand side (phase error at the reference's final "
          "time; transient at each rtol, scipy from loose to tight within the budget):", "",
          "| method | rtol | wall [s] | RHS calls | steps | phase error [rad] |",
          "|---|---|---|---|---|---|",
          *(f"| {row['method']} | {row['rtol']:.0e} | {row['wall_s']:.4g} | {row['nfev']:.0f} | "
            f"{row['nsteps']:.0f} | {row['phase_err_rad']:.2e} |" for row in res["rows"])]
    return md

