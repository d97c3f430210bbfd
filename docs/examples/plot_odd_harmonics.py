"""
Odd harmonics of the piston acceleration when ω varies
======================================================

At a constant speed the piston acceleration W = ω²s″(φ) of a crank-slider holds only the orders
1, 2, 4, 6 … of the crank angle. With the speed fluctuating within the cycle, W = ω²s″ + εs′
gains the products of those orders with the speed ripple's. The three-cylinder Gots diesel fires
every 240°, so its ripple is of order 1.5 and W gains orders such as 0.5, 2.5, 3.5 and 5. Here the
engine runs to steady speed in memory with a light flywheel, and the last cycle's spectrum of W
is set against the same engine turning at that cycle's mean speed.
"""
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import transient
from transient.analysis.orders import report_for_scene
from transient.run import integrate
from transient.scene import scene_from_dict

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

with open(CASES / "gots_diesel_spinup.toml", "rb") as fh:
    data = tomllib.load(fh)
data["inertia"]["flywheel"] = 0.05                 # kg m²: a light flywheel, a larger δ
scene = scene_from_dict(data, file="gots_diesel_spinup.toml")
run = integrate(scene)

report = report_for_scene(scene, run.trajectory, cylinder=1, cycles=1)
keep = report.orders <= 8
orders = report.orders[keep]
varying = report.relative[-1][keep]
constant = report.relative_constant[-1][keep]
print(f"δ of the last cycle: {report.delta[-1]:.4f}")
added = np.where(constant < 1e-9, varying, 0.0)  # orders absent at constant speed
for i in np.argsort(added)[::-1][:4]:
    print(f"order {orders[i]:g}: {varying[i]:.2e} of the first order "
          f"(constant speed: {constant[i]:.1e})")

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ax.bar(orders - 0.1, varying, width=0.2, label="with the run's ω(φ)")
ax.bar(orders + 0.1, constant, width=0.2, label="at constant mean speed")
ax.set_yscale("log")
ax.set_ylim(1e-6, 2.0)
ax.set_xlabel("order [1/rev]")
ax.set_ylabel("|W_k| / |W_1|")
ax.grid(True, alpha=0.3)
ax.legend()
ax.set_title("Piston acceleration, cylinder 1, last cycle")
plt.show()
