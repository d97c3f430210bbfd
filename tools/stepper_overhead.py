"""Stepper overhead: wall time of a run against (RHS evaluations × cost of one compiled RHS
call), for the benchmark scenes and the Gots spin-up with and without friction pairs, at rtol 1e-8
over 1000 revolutions (the target: ≤ 30 %), writing 72 output samples per turn and writing
one (as ``transient bench`` times its runs). The measurement is
``transient.verify.targets.stepper_overhead`` (``transient bench`` records it for the three
benchmark scenes in ``targets.md``): the cost of one call timed in a compiled loop over 2000
states along the run's last cycle, once with the calls independent (the RHS's throughput) and
once chained (its latency, as a step's stages are). For scenes with pairs it prints the cost of
one mode-margin evaluation as a call too: the stepper counts those among its RHS evaluations.
Rerun: ``.venv/bin/python tools/stepper_overhead.py``.
"""
from pathlib import Path

from transient.core.jit import kernel
from transient.core.model import layout, rhs
from transient.scene import load_scene
from transient.verify.bench import BENCH_SCENES
from transient.verify.targets import (
    CALLS_PER_STEP,
    per_call,
    rhs_arguments,
    stepper_overhead,
    timed_scene,
)

CASES = Path(__file__).resolve().parents[1] / "cases"
SCENES = dict(BENCH_SCENES, gots_spinup=CASES / "gots_diesel_spinup.toml",
              gots_friction=CASES / "gots_diesel_friction.toml")


@kernel
def margins_loop(m, states, y, out, sw, wk):
    """The mode margins at every state as the stepper evaluates them outside its root finder: a
    call to ``rhs.margins_at`` (not inlined; it passes the Model by value). ``y``, ``out``
    unused (the arguments of ``rhs_loop``)."""
    acc = 0.0
    for i in range(states.shape[0]):
        sel = states[i - i % CALLS_PER_STEP, layout.PHI]
        rhs.margins_at(m, True, states[i], sel, sw, wk)
        acc += wk[layout.WK_G, 0]
    return acc


for name, path in SCENES.items():
    for o in stepper_overhead(name, path, samples=(72, 1)):
        print(f"{name}, {o['samples_per_rev']} samples/turn: {o['nfev']} RHS evaluations, "
              f"{o['nsteps']} steps, {o['wall_s']:.4g} s, one call "
              f"{o['call_independent_s'] * 1e6:.3f} µs → overhead "
              f"{o['overhead_independent']:+.0%} "
              f"({(o['wall_s'] - o['nfev'] * o['call_independent_s']) / o['nsteps'] * 1e6:.2f} µs"
              f" a step); one call chained {o['call_chained_s'] * 1e6:.3f} µs → overhead "
              f"{o['overhead_chained']:+.0%}")
    args = rhs_arguments(timed_scene(load_scene(path)))
    if args[0].n_pairs:  # the margins, counted among the RHS evaluations, cost more as a call
        print(f"{name}: one mode-margin evaluation as a call "
              f"{per_call(margins_loop, *args) * 1e6:.3f} µs")
