"""The steady state's targets in ``transient bench``: per case, the engine cycles (and wall)
shooting integrates for the periodic steady state (:func:`transient.steady`, the written cycle
included) against the cycles a direct run from the same initial state needs to settle to the
same accuracy, both measured in the same run.

*Settled* is where every later cycle's start speed is within :data:`SETTLED` of the direct
run's last (relative), or within its own scatter where that is larger (reaction friction's
jumps, located by retaken steps, keep the cycle map noisy at rtol 1e-12); the shooting's
steady cycle agrees with that run's last cycle to the same 1e-9
(``tests/validation/test_steady.py``). The direct run's wall up to that cycle is its wall per
cycle times the cycles.
"""
from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from ..run import simulate
from ..scene import load_scene
from ..shooting import steady

_CASES = Path(__file__).resolve().parents[2] / "cases"
#: The acceptance's cases: constant-η pairs, reaction friction, a droop and a PI governor, the
#: swash plate.
CASES = {"constant-eta": "gots_diesel_friction",
         "reaction-friction": "gots_diesel_reaction_friction",
         "droop governor": "gots_diesel_governed",
         "PI governor": "gots_diesel_pi",
         "swash-plate": "swash_plate_4cyl_friction"}
#: The tolerance both runs take (atol = rtol/100): the acceptance's, where the direct run
#: settles to rounding.
RTOL = 1e-12
#: How close to its last a cycle's start speed must be, relative, for the direct run to count
#: as settled: the acceptance's agreement of the steady cycle with the settled run.
SETTLED = 1e-9
#: The direct run's cycles past the count the multiplier predicts for settling to rounding.
MARGIN_CYCLES = 10
#: Target: shooting integrates at least this many times fewer cycles.
TARGET = 10.0


def bench_scene(name: str, rtol: float = RTOL):
    """The case ``name`` at ``rtol`` as both runs take it: nothing that depends on time (the PI
    case's load programme held at its full load)."""
    scene = load_scene(_CASES / f"{name}.toml")
    if scene.load.schedule_time:
        scene = dataclasses.replace(scene, load=dataclasses.replace(
            scene.load, schedule_time=(), schedule_scale=()))
    solver = dataclasses.replace(scene.solver, rtol=rtol, atol=rtol * 1e-2)
    return dataclasses.replace(scene, solver=solver)


def cycles_of(scene, n: float):
    """``scene`` run for ``n`` engine cycles from its initial state."""
    run = dataclasses.replace(scene.run, revolutions=n * scene.mechanism.cycle / (2 * math.pi),
                              t_end=math.inf)
    return dataclasses.replace(scene, run=run)


def cycle_starts(scene, trajectory, n: int) -> np.ndarray:
    """The rows of a direct run's samples at its ``n`` + 1 cycle starts."""
    phi = np.asarray(trajectory["phi"])
    return np.searchsorted(phi, scene.initial.phi + scene.mechanism.cycle * np.arange(n + 1)
                           - 1e-9)


def settled_at(speeds: np.ndarray, floor: float = SETTLED, scatter_cycles: int = 6) -> int:
    """The first cycle from which every cycle start speed is within ``floor`` of the last, or of
    the last ``scatter_cycles`` cycles' own scatter where that is larger."""
    change = np.abs(speeds - speeds[-1]) / abs(speeds[-1])
    floor = max(floor, float(np.abs(np.diff(speeds[-scatter_cycles - 1:])).max()
                             / abs(speeds[-1])))
    outside = np.flatnonzero(change > floor)
    return int(outside[-1]) + 1 if outside.size else 0


def measure_case(label: str, name: str) -> dict:
    """One case's shooting and direct run, in the same minutes."""
    scene = bench_scene(name)
    simulate(cycles_of(scene, 1))  # (the stepper compiled before either is timed)
    t0 = time.perf_counter()
    res = steady(scene)
    shooting_s = time.perf_counter() - t0
    a = res.analysis
    mu = float(a["steady_multiplier_max"][0])
    shot = int(a["steady_cycles_integrated"][0]) + 1  # (and the cycle written)
    n = max(int(math.ceil(math.log(1e-15) / math.log(max(mu, 1e-3)))), 20) + MARGIN_CYCLES
    t0 = time.perf_counter()
    direct = simulate(cycles_of(scene, n))
    direct_s = time.perf_counter() - t0
    speeds = np.asarray(direct.trajectory["omega"])[cycle_starts(scene, direct.trajectory, n)]
    settled = settled_at(speeds)
    per_cycle = direct_s / n
    return {"case": label, "scene": name, "multiplier": mu, "iterations":
            int(a["steady_iterations"][0]), "shooting_cycles": shot,
            "shooting_s": shooting_s, "direct_cycles": settled, "direct_s": settled * per_cycle,
            "cycle_ratio": settled / shot, "wall_ratio": settled * per_cycle / shooting_s,
            "speed_difference": float(abs(res.trajectory["omega"][0] - speeds[-1])
                                     / abs(speeds[-1]))}


def measure(quick: bool = False, progress=print) -> list[dict]:
    """Every case (``quick``: the first only)."""
    rows = []
    for label, name in list(CASES.items())[:1 if quick else None]:
        rows.append(measure_case(label, name))
        progress(f"targets: steady state, {label}")
    return rows


def verdicts(rows, missed) -> list[tuple[str, str, str, str]]:
    """(target, case, measured, verdict) per case; ``missed``: the targets' verdict of a value
    against a target (``targets._missed``)."""
    return [(f"steady state in ≥ {TARGET:g}× fewer cycles than the direct run settles in",
             f"{r['case']} ({r['scene']}, largest multiplier {r['multiplier']:.3g})",
             f"{r['cycle_ratio']:.2f}× ({r['shooting_cycles']} against {r['direct_cycles']} "
             f"cycles; wall {r['wall_ratio']:.2f}×)",
             missed(r["cycle_ratio"], TARGET, larger_is_better=True)) for r in rows]


def section(rows) -> list[str]:
    """The record's section: each case's figures."""
    lines = ["", f"## Steady state against a settling direct run (rtol {RTOL:g}, settled to "
             f"{SETTLED:g} of the speed)", "",
             "| case | largest multiplier | Newton iterations | cycles (shooting, the written one included) "
             "| cycles (direct, to settle) | wall shooting [s] | wall direct [s] | "
             "steady start speed against the settled run |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['multiplier']:.4g} | {r['iterations']} | "
                     f"{r['shooting_cycles']} | {r['direct_cycles']} | {r['shooting_s']:.3g} | "
                     f"{r['direct_s']:.3g} | {r['speed_difference']:.2e} |")
    return lines
