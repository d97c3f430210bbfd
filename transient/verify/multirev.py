"""The multirevolution targets in ``transient bench``: a long slow spin-up with a load programme
followed on its envelope (:func:`transient.multirev.multirevolution`) against the direct run of
every cycle, both in the same run: cycles integrated, wall, the speed's error at every cycle
start and its estimate, and the cycle each schedule corner falls in.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from ..multirev import multirevolution
from ..run import simulate
from ..scene import load_scene
from .steady import cycle_starts, cycles_of

_CASE = Path(__file__).resolve().parents[2] / "cases" / "gots_diesel_friction.toml"
#: The long run's cycles, and the quick harness's.
CYCLES, QUICK_CYCLES = 100_000, 400
#: Its flywheel, a multiple of the case's: a spin-up from 1000 rpm over most of the run.
FLYWHEEL = 1000.0
#: The load programme: a step up at 600 s, held, then a ramp down to 2200 s [s, 1].
SCHEDULE = ((600.0, 600.0, 1500.0, 2200.0), (1.0, 1.2, 1.2, 0.7))
#: The stepper's tolerance (atol = rtol/100), tight enough that the direct run and the
#: envelope's cycles differ by less than the envelope's error, and the envelope's.
RTOL, ENVELOPE_RTOL = 1e-11, 1e-7
#: Targets: the cycles integrated, the wall, the agreement of ω, relative.
CYCLE_TARGET, WALL_TARGET, AGREE = 10.0, 5.0, 1e-6


def long_scene(flywheel: float = FLYWHEEL):
    """The constant-η diesel with its flywheel ×``flywheel`` and the load programme."""
    sc = load_scene(_CASE)
    return dataclasses.replace(
        sc, inertia=dataclasses.replace(sc.inertia, flywheel=sc.inertia.flywheel * flywheel),
        solver=dataclasses.replace(sc.solver, rtol=RTOL, atol=RTOL * 1e-2),
        output=dataclasses.replace(sc.output, samples_per_rev=4),
        load=dataclasses.replace(sc.load, schedule_time=SCHEDULE[0],
                                 schedule_scale=SCHEDULE[1]))


def measure(quick: bool = False) -> dict:
    """Both runs of the long case (``quick``: QUICK_CYCLES cycles, the harness only)."""
    n = QUICK_CYCLES if quick else CYCLES
    scene = long_scene(30.0 if quick else FLYWHEEL)
    simulate(cycles_of(scene, 2))  # (the stepper compiled before either is timed)
    t0 = time.perf_counter()
    env = multirevolution(scene, n, rtol=ENVELOPE_RTOL)
    env_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    direct = simulate(cycles_of(scene, n)).trajectory
    direct_s = time.perf_counter() - t0
    starts = cycle_starts(scene, direct, n)
    omega = np.asarray(direct["omega"])[starts]
    t = np.asarray(direct["t"])[starts]
    err = np.abs(env.column("omega") - omega) / omega
    corners = sorted({c for c in scene.load.schedule_time if c < t[-1]})
    on_cycle = [(int(np.searchsorted(t, c)) - 1, int(np.searchsorted(env.column("t"), c)) - 1)
                for c in corners]
    i_w, i_t = env.names.index("omega"), env.names.index("t")
    return {"cycles": n, "cycles_integrated": env.cycles_integrated,
            "resolved": int(env.integrated.sum()), "envelope_s": env_s, "direct_s": direct_s,
            "cycle_ratio": n / env.cycles_integrated, "wall_ratio": direct_s / env_s,
            "max_error": float(err.max()), "final_error": float(err[-1]),
            "estimate": float(env.error[i_w] / abs(env.column("omega")[-1])),
            "t_error": float(abs(env.column("t")[-1] - t[-1])),
            "t_estimate": float(env.error[i_t]),
            "omega_start": float(omega[0]), "omega_end": float(omega[-1]),
            "corners": [[float(c), d, e] for c, (d, e) in zip(corners, on_cycle)]}


def verdicts(r, missed) -> list[tuple[str, str, str, str]]:
    """(target, case, measured, verdict) of each multirevolution target; ``missed``: the
    targets' verdict of a value against a target (``targets._missed``)."""
    case = f"{r['cycles']} cycles, flywheel ×{FLYWHEEL:g}, load programme"
    bounded = r["estimate"] >= r["final_error"] and r["t_estimate"] >= r["t_error"]
    landed = all(d == e for _, d, e in r["corners"])
    return [
        (f"multirevolution: ≥ {CYCLE_TARGET:g}× fewer cycles integrated", case,
         f"{r['cycle_ratio']:.3g}× ({r['cycles_integrated']} of {r['cycles']}, the error "
         "estimate's included)", missed(r["cycle_ratio"], CYCLE_TARGET, larger_is_better=True)),
        (f"multirevolution: ≥ {WALL_TARGET:g}× less wall", case,
         f"{r['wall_ratio']:.3g}× ({r['envelope_s']:.3g} against {r['direct_s']:.3g} s)",
         missed(r["wall_ratio"], WALL_TARGET, larger_is_better=True)),
        (f"multirevolution: ω within {AGREE:g} of the direct run at every cycle start", case,
         f"largest {r['max_error']:.2e}, last {r['final_error']:.2e}",
         missed(r["max_error"], AGREE)),
        ("multirevolution: the error estimate bounds the error at the end", case,
         f"ω {r['final_error']:.2e} (estimate {r['estimate']:.2e}), t {r['t_error']:.2e} s "
         f"(estimate {r['t_estimate']:.2e} s)", "met" if bounded else "**missed**"),
        ("multirevolution: each schedule corner in the direct run's cycle", case,
         ", ".join(f"{c:g} s: cycle {d} and {e}" for c, d, e in r["corners"]) or "none reached",
         "met" if landed else "**missed**")]


def section(r) -> list[str]:
    """The record's section."""
    return ["", f"## Multirevolution (stepper rtol {RTOL:g}, envelope rtol {ENVELOPE_RTOL:g})",
            "", "| cycles | integrated | resolved as the run's | wall envelope [s] | "
            "wall direct [s] | ω start → end [rad/s] | largest error of ω | error of ω at the "
            "end (estimate) |", "|---|---|---|---|---|---|---|---|",
            f"| {r['cycles']} | {r['cycles_integrated']} | {r['resolved']} | "
            f"{r['envelope_s']:.3g} | {r['direct_s']:.3g} | {r['omega_start']:.4g} → "
            f"{r['omega_end']:.4g} | {r['max_error']:.2e} | {r['final_error']:.2e} "
            f"({r['estimate']:.2e}) |"]
