"""A/B wall time of the three benchmark scenes (1000 revolutions each as the scenes say): median
of 5 runs after a warm-up, with RHS calls, steps and rejected steps.

Compare two commits by running it once per checkout, alternately, e.g.
``git worktree add /tmp/old 705e2d5`` then ``PYTHONPATH=/tmp/old .venv/bin/python
scripts/ab_wall.py`` and ``.venv/bin/python scripts/ab_wall.py``, twice each.
"""
from __future__ import annotations

import statistics
from pathlib import Path

import transient
from transient.scene import load_scene
from transient.simulate import integrate

CASES = Path(__file__).resolve().parents[1] / "cases"

print(f"transient from {Path(transient.__file__).parent}")
for name in ("coasting_single", "gots_diesel_governed", "swash_plate_4cyl"):
    scene = load_scene(CASES / f"{name}.toml")
    integrate(scene, keep=False)
    runs = [integrate(scene, keep=False).solver for _ in range(5)]
    s = runs[0]
    print(f"{name:22s} {statistics.median(r['wall_s'] for r in runs):.4f} s  "
          f"{s['nfev']} RHS calls, {s['nsteps']} steps, {s['nreject']} rejected")
