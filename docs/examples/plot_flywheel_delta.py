"""
Sizing a flywheel for a speed fluctuation δ
===========================================

How heavy a flywheel does the Gots diesel need for δ = (ω_max − ω_min)/ω_mean = 0.02 at its
operating point? First a loop in memory: the scene is read once into a dict, the flywheel is
varied, and each variant is validated and run without writing a file. Then
:func:`~transient.study.flywheel.flywheel_for_delta` finds the flywheel for the target directly
(Gots §2.8, refined by simulation).
"""
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt

import transient
from transient.analysis.irregularity import fluctuation
from transient.run import integrate
from transient.scene import scene_from_dict
from transient.study.flywheel import flywheel_for_delta

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

with open(CASES / "gots_diesel_spinup.toml", "rb") as fh:
    base = tomllib.load(fh)

flywheels = [0.05, 0.1, 0.2, 0.4]
deltas = []
for J in flywheels:
    data = {**base, "inertia": {**base.get("inertia", {}), "flywheel": J}}
    scene = scene_from_dict(data, file="gots_diesel_spinup.toml")
    run = integrate(scene)
    tr = run.trajectory
    deltas.append(fluctuation(tr["t"], tr["phi"], tr["omega"], scene.mechanism.cycle,
                              scene.initial.phi))
    print(f"flywheel {J:.2f} kg m²: δ of the last cycle {deltas[-1]:.4f}")

scene = transient.load_scene(CASES / "gots_diesel_spinup.toml")
sized = flywheel_for_delta(scene, 0.02)
print(f"flywheel for δ = 0.02: {sized.flywheel:.4f} kg m²")

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.plot(flywheels, deltas, "o-", label="runs in memory")
ax.axhline(0.02, color="0.5", lw=0.8, ls=":")
ax.plot([sized.flywheel], [0.02], "s", color="C3", label="flywheel_for_delta")
ax.set_xlabel("flywheel [kg m²]")
ax.set_ylabel("δ [1]")
ax.grid(True, alpha=0.3)
ax.legend()
plt.show()
