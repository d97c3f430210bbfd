"""A/B wall time of the benchmark scenes (as the scenes say), and of the PI-governed diesel (the
kernels' full variant without friction): median of 5 runs after a warm-up, with the time spent
inside the compiled stepper (``stepper.advance``, steadier than the wall, which adds the
blocks' handling), RHS calls, steps and rejected steps.

Compare two commits by running it once per checkout, alternately, e.g.
``git worktree add /tmp/old <commit>`` then ``PYTHONPATH=/tmp/old .venv/bin/python
tools/ab_wall.py`` and ``.venv/bin/python tools/ab_wall.py``, twice each.

``--bench`` times instead the scenes at the settings of ``stepper_overhead.py`` (1000
revolutions, rtol 1e-8, atol 1e-11), writing 72 and then one sample per turn, median of 9, with
the Gots spin-up as a fourth scene.
"""
from __future__ import annotations

import dataclasses as dc
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import transient
import transient.run
from transient.run import integrate
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[1] / "cases"


_advance = transient.run.stepper.advance
_inside = [0.0]


def _timed_advance(*args):
    t0 = time.perf_counter()
    try:
        return _advance(*args)
    finally:
        _inside[0] += time.perf_counter() - t0


transient.run.stepper.advance = _timed_advance


def median_run(scene, repeats):
    """(median wall, median time inside the stepper, the first run's solver statistics)."""
    integrate(scene, keep=False)
    runs, inside = [], []
    for _ in range(repeats):
        _inside[0] = 0.0
        runs.append(integrate(scene, keep=False).solver)
        inside.append(_inside[0])
    return statistics.median(r["wall_s"] for r in runs), statistics.median(inside), runs[0]


print(f"transient from {Path(transient.__file__).parent}")
if "--bench" in sys.argv[1:]:
    for name in ("coasting_single", "gots_diesel_governed", "swash_plate_4cyl",
                 "gots_diesel_spinup"):
        base = load_scene(CASES / f"{name}.toml")
        for samples in (72, 1):
            scene = dc.replace(base, run=dc.replace(base.run, revolutions=1000.0, t_end=np.inf),
                               solver=dc.replace(base.solver, rtol=1e-8, atol=1e-11),
                               output=dc.replace(base.output, samples_per_rev=samples))
            wall, inside, s = median_run(scene, 9)
            print(f"{name:22s} {samples:2d} samples/turn {wall:.4f} s (stepper {inside:.4f} s)  "
                  f"{s['nfev']} RHS calls, {s['nsteps']} steps, {s['nreject']} rejected")
else:
    for name in ("coasting_single", "gots_diesel_governed", "gots_diesel_pi", "swash_plate_4cyl"):
        wall, inside, s = median_run(load_scene(CASES / f"{name}.toml"), 5)
        print(f"{name:22s} {wall:.4f} s (stepper {inside:.4f} s)  "
              f"{s['nfev']} RHS calls, {s['nsteps']} steps, {s['nreject']} rejected")
