"""Stepper overhead: wall time of a run against (RHS evaluations × cost of one compiled RHS
call), for the benchmark scenes and the Gots spin-up with and without friction pairs, at rtol 1e-8
over 1000 revolutions (issue 5's target: ≤ 30 %), writing 72 output samples per turn and writing
one (as ``transient bench`` times its runs).
The cost of one call is timed in a compiled loop over 2000 states along the run's last cycle (in
crank angle, as the run integrates; the gas table pieces picked once per CALLS_PER_STEP calls,
as once per step in the run), median of 7 rounds of 100 loops (``rhs_timing.py``): once
with the calls independent (the RHS's throughput) and once chained, each call's state depending on the previous result as a
step's stages do (its latency: the divisions, square root and sine of a call can no longer
overlap the next call's). For scenes with pairs it prints the cost of one mode-margin
evaluation as a call too: the stepper counts those among its RHS evaluations. Rerun:
``.venv/bin/python scripts/stepper_overhead.py`` (about 20 s).
"""
import dataclasses as dc
import statistics
from pathlib import Path

import numpy as np
from rhs_timing import margins_loop, per_call, rhs_chain, rhs_loop

from transient.assemble import build_model
from transient.bench import BENCH_SCENES
from transient.core import model as cm
from transient.scene import load_scene
from transient.simulate import integrate

CASES = Path(__file__).resolve().parents[1] / "cases"


SCENES = dict(BENCH_SCENES, gots_spinup=CASES / "gots_diesel_spinup.toml",
              gots_friction=CASES / "gots_diesel_friction.toml")


def timed(scene, samples_per_rev):
    """Median wall time of 5 runs after a warm-up, and the runs' RHS evaluations and steps."""
    scene = dc.replace(scene, output=dc.replace(scene.output, samples_per_rev=samples_per_rev))
    integrate(scene, keep=False)
    walls = []
    for _ in range(5):
        data = integrate(scene, keep=False)
        walls.append(data.solver["wall_s"])
    return statistics.median(walls), data.solver["nfev"], data.solver["nsteps"]


for name, path in SCENES.items():
    base = load_scene(path)
    scene = dc.replace(base, run=dc.replace(base.run, revolutions=1000.0, t_end=np.inf),
                       solver=dc.replace(base.solver, rtol=1e-8, atol=1e-11))
    runs = {n: timed(scene, n) for n in (72, 1)}
    model, _, _ = build_model(scene)
    tr = integrate(dc.replace(scene, run=dc.replace(scene.run, revolutions=50.0))).trajectory
    # 2000 states over the run's last cycle: CALLS_PER_STEP of them span ~0.08 rad, about a step
    phi = np.linspace(tr["phi"][-1] - model.period, tr["phi"][-1], 2000)
    states = np.zeros((phi.size, cm.n_state(model)))
    states[:, cm.PHI], states[:, cm.T] = phi, np.interp(phi, tr["phi"], tr["t"])
    states[:, cm.KINETIC] = np.interp(phi, tr["phi"], 0.5 * tr["J"] * tr["omega"] ** 2)
    out = np.empty(cm.n_state(model))
    sw = np.zeros(cm.N_SWITCHES, dtype=np.int64)
    sw[cm.SW_DIRECTION] = 1
    wk = cm.work_array(model)
    out[:] = 0.0
    call = per_call(rhs_loop, model, states, out, sw, wk)
    chained = per_call(rhs_chain, model, states, np.empty_like(out), out, sw, wk)
    if model.n_pairs:  # the margins, counted among the RHS evaluations, cost more as a call
        print(f"{name}: one mode-margin evaluation as a call "
              f"{per_call(margins_loop, model, states, out, sw, wk) * 1e6:.3f} µs")
    for n, (wall, nfev, nsteps) in runs.items():
        print(f"{name}, {n} samples/turn: {nfev} RHS evaluations, {nsteps} steps, {wall:.4g} s, "
              f"one call {call * 1e6:.3f} µs → RHS {nfev * call:.4g} s, stepper overhead "
              f"{wall / (nfev * call) - 1:+.0%} ({(wall - nfev * call) / nsteps * 1e6:.2f}"
              f" µs a step); one call chained {chained * 1e6:.3f} µs → overhead "
              f"{wall / (nfev * chained) - 1:+.0%}")
