"""Speed fluctuation δ of the swash-plate example, 1 against 4 cylinders, at several steady speeds.

The governor is removed and the fan load sized so that the full-force mean gas torque (119.91 and
482.52 N m, see the scene files) balances it at each speed; δ over the last turn of a run started
at that speed. Rerun: ``.venv/bin/python tools/swash_smoothness_vs_speed.py``.
"""
import dataclasses as dc
from pathlib import Path

import numpy as np

from transient.analysis.irregularity import fluctuation
from transient.run import integrate
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[1] / "cases"
MEAN_TORQUE = {"swash_plate_1cyl": 119.91, "swash_plate_4cyl": 482.52}

print("rpm   δ(1 cyl)  δ(4 cyl)  ratio")
for rpm in (200, 300, 500, 800, 1200, 2000):
    w = rpm * np.pi / 30
    delta = []
    for name, torque in MEAN_TORQUE.items():
        s = load_scene(CASES / f"{name}.toml")
        s = dc.replace(s, governor=dc.replace(s.governor, model="none"),
                       load=dc.replace(s.load, fan=torque / w**2),
                       initial=dc.replace(s.initial, omega=w),
                       run=dc.replace(s.run, t_end=30.0 / (rpm / 60)))
        tr = integrate(s).trajectory
        delta.append(fluctuation(tr["t"], tr["phi"], tr["omega"], 2 * np.pi, 0.0))
    print(f"{rpm:4d}  {delta[0]:.4f}    {delta[1]:.4f}    {delta[0] / delta[1]:.2f}")
