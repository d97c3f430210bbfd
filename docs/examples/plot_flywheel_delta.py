"""
Sizing a flywheel for a speed fluctuation δ
===========================================

How heavy a flywheel does the Gots diesel need for δ = (ω_max − ω_min)/ω_mean = 0.02 at its
operating point? First a loop in memory: the flywheel is varied with ``scene.replace``, each
variant validated as a scene file is and run without writing a file. Then
:func:`~transient.study.flywheel.flywheel_for_delta` finds the flywheel for the target directly
(Gots §2.8, refined by simulation).
"""
from pathlib import Path

import matplotlib.pyplot as plt

import transient
from transient.study.flywheel import flywheel_for_delta

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
base = transient.load_scene(CASES / "gots_diesel_spinup.toml")

flywheels = [0.05, 0.1, 0.2, 0.4]
deltas = []
for J in flywheels:
    run = transient.simulate(base.replace(inertia={"flywheel": J}))
    deltas.append(run.summary()["delta_last_cycle"])
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
