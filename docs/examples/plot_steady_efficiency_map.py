"""
An efficiency map in steady state
=================================

The Gots diesel with friction in its main bearings and crankpins on a dynamometer: at each
speed and fuel the periodic steady state with the scene's own flywheel, the brake torque that
holds the mean speed solved for with the cycle (:mod:`transient.study.dynamometer`). A point
costs a handful of cycles, where a run settling to the same state would integrate hundreds.

With a real flywheel the crankshaft still speeds up and slows down within the cycle (δ ≠ 0),
and η_mech differs from the constant-speed study's, which is the limit of an infinite flywheel:
the check below makes the flywheel heavier and watches η_mech go to that limit.
"""
from pathlib import Path

import matplotlib.pyplot as plt

import transient
from transient.study.efficiency import efficiency_study, plot_map

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

scene = transient.load_scene(CASES / "gots_diesel_friction.toml")
rpm = [1000, 1500, 2000, 2500, 3000, 3500, 4000, 4500]
fuels = [1.0, 0.75, 0.5, 0.25]
rows = efficiency_study(scene, rpm, fuels, steady=True)
cycles = [r["cycles_integrated"] for r in rows]
print(f"{len(rows)} points, {sum(cycles)} cycles integrated ({min(cycles)}–{max(cycles)} a point)")

fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
plot_map(a1, rows)
plot_map(a2, rows, "delta", "δ = (ω_max − ω_min) / ω_mean")

# %%
# **Against the constant-speed study.** δ falls as the flywheel grows (as 1/J), and η_mech
# goes to the constant-speed study's value at every speed: the steady states and the inverse
# dynamics at a prescribed speed are computed by different routes, and meet in that limit.
J = scene.inertia.flywheel
plain = efficiency_study(scene, rpm, [1.0])
fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
for factor in (1, 4, 16):
    heavier = scene.replace(inertia={"flywheel": factor * J})
    held = efficiency_study(heavier, rpm, [1.0], steady=True)
    ax.plot(rpm, [r["eta_mech_work"] for r in held], "o-",
            label=f"steady, flywheel × {factor}")
    print(f"flywheel × {factor:2d}: δ at {rpm[0]} rpm {held[0]['delta']:.4f}, η_mech − "
          f"constant-speed η_mech at {rpm[-1]} rpm "
          f"{held[-1]['eta_mech_work'] - plain[-1]['eta_mech_work']:+.2e}")
ax.plot(rpm, [r["eta_mech_work"] for r in plain], "k--", label="constant speed (J → ∞)")
ax.set_xlabel("mean speed [rpm]")
ax.set_ylabel("η_mech = W_out / W_in")
ax.set_title(f"{scene.name}, full fuel")
ax.grid(True, alpha=0.3)
ax.legend()
plt.show()
