"""Steady efficiency map against direct runs: an 8 speeds × 4 fuels map of
``cases/gots_diesel_friction.toml`` on a dynamometer (``transient efficiency --steady``, one
process) and, for every point, a direct run of the same bench scene (the same brake torque)
from the same initial state (the point's speed at the cycle's start) until it has settled to
the same accuracy.

Under a constant brake η_mech of a cycle is fixed by the brake torque and the fuel (W_out/W_in,
both set), so a direct run's η_mech agrees long before its speed has settled: it is then the
η_mech of another speed. So a direct run counts as settled, as a value of the map at the
requested speed, from the first cycle after which every cycle's η_mech is within ``--accuracy``
of the steady point's and its time-mean speed ω̄ close enough that the map's own slope
|∂η/∂ln ω̄| (differences between the steady map's neighbouring speeds at the same fuel) times
|ω̄/ω̄* − 1| is within ``--accuracy`` too; up to ``--max-cycles`` (a point whose constant-brake
equilibrium is unstable, or decays more slowly, never settles: reported so).

Measured in one process, each round the map (serial) and then the direct runs, each of exactly
its settling cycles, timed: walls, cycles integrated. Median of ``--repeat`` rounds.

Rerun: ``.venv/bin/python tools/steady_map_wall.py [--repeat K] [--max-cycles N]``
(TRANSIENT_CACHE_DIR as for any run).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import time
from pathlib import Path

import numpy as np

import transient
from transient.analysis.irregularity import cycle_boundaries
from transient.scene import Load
from transient.study.dynamometer import bench_scene
from transient.study.efficiency import efficiency_study

CASE = Path(__file__).resolve().parents[1] / "cases" / "gots_diesel_friction.toml"
RPM = (1000.0, 1500.0, 2000.0, 2500.0, 3000.0, 3500.0, 4000.0, 4500.0)
FUELS = (1.0, 0.75, 0.5, 0.25)
SAMPLES = 72


def direct(scene, row, cycles: int, samples: int):
    """The bench scene of ``row``'s point under its brake torque, run ``cycles`` cycles from
    the point's initial state."""
    omega = row["rpm"] * math.pi / 30.0
    bench = bench_scene(scene, omega, row["fuel"], samples)
    run = dataclasses.replace(bench.run, t_end=math.inf,
                              revolutions=cycles * scene.mechanism.cycle / (2 * math.pi))
    return dataclasses.replace(bench, run=run, load=Load(torque=row["brake_torque"]))


def slopes(rows) -> dict:
    """|∂η/∂ln ω̄| at each held point, by differences between the map's neighbouring speeds at
    the same fuel (one-sided at the ends)."""
    out = {}
    for fuel in {r["fuel"] for r in rows}:
        line = sorted((r["rpm"], r["eta_mech_work"]) for r in rows
                      if r["fuel"] == fuel and "brake_torque" in r)
        n, eta = np.log([p[0] for p in line]), np.array([p[1] for p in line])
        for (rpm, _), g in zip(line, np.gradient(eta, n)):
            out[(rpm, fuel)] = abs(float(g))
    return out


def settling(scene, row, max_cycles: int, accuracy: float, slope: float
             ) -> tuple[int | None, float]:
    """(The cycles a direct run needs to settle, None if it does not in ``max_cycles``; the
    last cycle's relative speed error)."""
    sc = direct(scene, row, max_cycles, 2)  # (a sample on every cycle's start: exact marks)
    try:
        traj = transient.simulate(sc).trajectory
    except transient.SimulationError as exc:  # (a speed that fell away until it stalled)
        print(f"    direct run at {row['rpm']:g} rpm, fuel {row['fuel']:g}: {exc}")
        return None, math.nan
    t, phi = np.asarray(traj["t"]), np.asarray(traj["phi"])
    cycle = scene.mechanism.cycle
    tb, marks = cycle_boundaries(t, phi, cycle, scene.initial.phi)
    w_gas = np.interp(marks, phi, np.asarray(traj["W_gas"]))
    w_load = np.interp(marks, phi, np.asarray(traj["W_load"]))
    eta = -np.diff(w_load) / np.diff(w_gas)
    speed = cycle / np.diff(tb) * 30.0 / math.pi
    ok = ((np.abs(eta - row["eta_mech_work"]) <= accuracy)
          & (slope * np.abs(speed / row["rpm"] - 1.0) <= accuracy))
    last_error = float(speed[-1] / row["rpm"] - 1.0)
    if ok.size < max_cycles or not ok[-1]:
        return None, last_error
    bad = np.flatnonzero(~ok)
    return (int(bad[-1]) + 2 if bad.size else 1), last_error


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--max-cycles", type=int, default=20000)
    ap.add_argument("--accuracy", type=float, default=1e-6)
    args = ap.parse_args()
    scene = transient.load_scene(CASE)
    print(f"solver rtol {scene.solver.rtol:g}, atol {scene.solver.atol:g}; "
          f"{len(RPM)} speeds × {len(FUELS)} fuels")
    efficiency_study(scene, RPM[:1], FUELS[:1], samples_per_rev=SAMPLES, steady=True)  # (warm)
    rows = efficiency_study(scene, RPM, FUELS, samples_per_rev=SAMPLES, steady=True)
    held = [r for r in rows if "brake_torque" in r]
    for r in rows:
        if r["note"]:
            print(f"  {r['rpm']:g} rpm, fuel {r['fuel']:g}: {r['note']}")
    need = {}
    slope = slopes(held)
    for r in held:
        n, err = settling(scene, r, args.max_cycles, args.accuracy, slope[(r["rpm"], r["fuel"])])
        need[(r["rpm"], r["fuel"])] = n
        print(f"  {r['rpm']:6g} rpm fuel {r['fuel']:4g}: steady {r['cycles_integrated']:3d} cycles,"
              f" η {r['eta_mech_work']:.8f}, |∂η/∂ln ω̄| {slope[(r['rpm'], r['fuel'])]:.3g},"
              f" δ {r['delta']:.4f}; direct "
              + (f"{n} cycles" if n else f"not settled in {args.max_cycles} cycles "
                                         f"(speed error {err:.3g} at the end)"))
    settled = [r for r in held if need[(r["rpm"], r["fuel"])]]
    walls_map, walls_direct = [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        efficiency_study(scene, RPM, FUELS, samples_per_rev=SAMPLES, steady=True)
        walls_map.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        for r in settled:
            transient.simulate(direct(scene, r, need[(r["rpm"], r["fuel"])], SAMPLES))
        walls_direct.append(time.perf_counter() - t0)
    steady_cycles = sum(r["cycles_integrated"] for r in held)
    steady_settled = sum(r["cycles_integrated"] for r in settled)
    direct_cycles = sum(need[(r["rpm"], r["fuel"])] for r in settled)
    print(f"steady map: {len(held)} points held, {len(rows) - len(held)} without a steady "
          f"state; {steady_cycles} cycles integrated; wall median "
          f"{statistics.median(walls_map):.3f} s ({', '.join(f'{w:.3f}' for w in walls_map)})")
    print(f"direct runs: {len(settled)} of {len(held)} points settle within "
          f"{args.max_cycles} cycles; those need {direct_cycles} cycles (the steady map "
          f"{steady_settled} for the same points); wall median "
          f"{statistics.median(walls_direct):.3f} s "
          f"({', '.join(f'{w:.3f}' for w in walls_direct)})")


if __name__ == "__main__":
    main()
