"""
A long run on its envelope: a slow spin-up under a load programme
=================================================================

The Gots diesel with a flywheel a hundred times its own spins up from 1000 rpm over thousands
of cycles while its load is stepped up and then down. With ``[solver] multirevolution = true``
the run follows the states at the cycle starts on their smooth envelope, in macro steps of many
cycles, and integrates cycle by cycle only around the load steps and at the end (user guide,
*Long runs from a scene*). The result holds the speed at every cycle start, which cycles were
integrated, the envelope's error estimate, and the trajectories of the resolved cycles.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import transient

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
CYCLES = 3000

scene = transient.load_scene(CASES / "gots_diesel_friction.toml").replace(
    inertia={"flywheel": 15.0},
    load={"schedule_time": [40.0, 40.0, 80.0, 80.0], "schedule_scale": [1.0, 1.3, 1.3, 0.9]},
    run={"revolutions": 2 * CYCLES},
    solver={"rtol": 1e-10, "atol": 1e-12, "multirevolution": True, "envelope_rtol": 1e-7},
    output={"samples_per_rev": 36})

with tempfile.TemporaryDirectory() as tmp:
    res = transient.run_multirevolution(scene, Path(tmp) / "long.h5")
    e = res.envelope
    t, omega = e.column("t"), e.column("omega")
    traj = {name: np.asarray(res.trajectory[name]) for name in ("t", "omega")}

a = res.analysis
print(f"{CYCLES} cycles: {int(e.integrated.sum())} integrated, "
      f"{int((~e.integrated).sum())} interpolated; "
      f"{a['multirev_cycles_integrated'][0]} cycles integrated in all")
print(f"final speed {omega[-1]:.4f} rad/s, its error estimate "
      f"{e.error[e.names.index('omega')]:.2g} rad/s")

# %%
# The speed at every cycle start (the envelope), the resolved cycles' trajectories over it and
# the integrated cycles' starts marked: a macro step covers hundreds of cycles between the load
# steps, and each step is crossed cycle by cycle.
fig, (ax, zoom) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
for axis in (ax, zoom):
    axis.plot(t, omega, "-", color="0.6", lw=1, label="envelope (every cycle start)")
    axis.plot(traj["t"], traj["omega"], ".", ms=1.5, color="C0", label="resolved cycles")
    starts = np.flatnonzero(e.integrated)
    axis.plot(t[starts], omega[starts], "x", ms=4, color="C3", label="integrated cycles")
    for corner in sorted(set(scene.load.schedule_time)):
        axis.axvline(corner, color="0.8", lw=0.8, ls="--")
    axis.set_xlabel("t [s]")
    axis.set_ylabel("ω [rad/s]")
    axis.grid(True, alpha=0.3)
ax.set_title(f"{scene.name}: {CYCLES} cycles on the envelope")
ax.legend(loc="lower right", fontsize=8)
corner = 40.0
near = (t > corner - 0.6) & (t < corner + 0.6)
zoom.set_xlim(corner - 0.6, corner + 0.6)
zoom.set_ylim(omega[near].min() - 2.0, omega[near].max() + 2.0)
zoom.set_title("around the load step at 40 s")

# %%
# Per cycle: the mean speed of every cycle (its angle over its duration) and the speed
# fluctuation δ of the resolved ones.
fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
n = np.arange(CYCLES)
ax.plot(n, e.mean_omega, "-", color="C0", label="cycle-mean ω")
ax.set_xlabel("cycle")
ax.set_ylabel("cycle-mean ω [rad/s]")
ax2 = ax.twinx()
ax2.plot(n[e.resolved], e.delta[e.resolved], "o", ms=2, color="C1", label="δ (resolved)")
ax2.set_ylabel("δ")
ax.grid(True, alpha=0.3)
plt.show()
