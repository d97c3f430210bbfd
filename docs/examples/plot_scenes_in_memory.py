"""
Scenes from code, runs in memory, a DataFrame
=============================================

A notebook's way of working: a scene built from a dict (no file), one parameter varied in a
loop with ``scene.replace`` (each variant validated exactly as a scene file is), every run kept
in memory, their summaries in a pandas DataFrame and ω(t) of each in one figure. Here a single
cylinder of the Gots diesel coasts from 1000 rpm with flywheels of four sizes: the larger the
flywheel, the smaller the swing of ω about its mean (δ).
"""
import matplotlib.pyplot as plt
import pandas as pd

import transient

scene = transient.Scene.from_dict({
    "scene": {"name": "coasting"},
    "mechanism": {"type": "crank-slider", "crank_radius_mm": 47, "rod_length_mm": 148,
                  "bore_mm": 88, "piston_mass": 1.52, "crank_mass": 0.912,
                  "rod": {"model": "two-mass", "mass": 1.752, "cg_from_pin_mm": 107.3}},
    "inertia": {"shaft": 0.02},
    "initial": {"omega_rpm": 1000},
    "run": {"revolutions": 5},
    "output": {"samples_per_rev": 180},
})

runs = {J: transient.simulate(scene.replace(inertia={"flywheel": J}))
        for J in (0.0, 0.02, 0.1, 0.5)}
table = pd.DataFrame([{"flywheel [kg m²]": J, **run.summary()} for J, run in runs.items()])
print(table[["flywheel [kg m²]", "mean_omega_last_cycle", "delta_last_cycle"]])

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for J, run in runs.items():
    df = run.to_dataframe()
    ax.plot(df["t"], df["omega"] * 30 / 3.141592653589793, lw=1.0, label=f"flywheel {J} kg m²")
ax.set_xlabel("t [s]")
ax.set_ylabel("ω [rpm]")
ax.grid(True, alpha=0.3)
ax.legend()
plt.show()
