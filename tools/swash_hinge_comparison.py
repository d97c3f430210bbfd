"""What the hinge orientation of cross 13 changes: J(φ) of the moving parts and the governed
spin-up, for the 1- and 4-cylinder swash-plate scenes.
Rerun: ``.venv/bin/python tools/swash_hinge_comparison.py``.
"""
import dataclasses as dc
from pathlib import Path

import numpy as np

from transient.analysis.irregularity import cycle_means, fluctuation
from transient.run import integrate
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[1] / "cases"
phi = np.linspace(0, 2 * np.pi, 721)
for name in ("swash_plate_1cyl", "swash_plate_4cyl"):
    scene = load_scene(CASES / f"{name}.toml")
    for hinge in ("in-plane", "normal"):
        s = dc.replace(scene, mechanism=dc.replace(scene.mechanism, hinge=hinge))
        J = s.mechanism.kinematics_table(phi)["J"]
        tr = integrate(s).trajectory
        means, _ = cycle_means(tr["t"], tr["phi"], 2 * np.pi, 0.0)
        delta = fluctuation(tr["t"], tr["phi"], tr["omega"], 2 * np.pi, 0.0)
        print(f"{name} {hinge:8s}: J {J.min():.5f}…{J.max():.5f} kg m², last-turn mean ω "
              f"{means[-1]:.4f} rad/s, δ {delta:.4f}, {tr['phi'][-1] / (2 * np.pi):.3f} rev in "
              f"{tr['t'][-1]:g} s")
