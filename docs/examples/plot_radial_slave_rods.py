"""
Slave-rod kinematics of a radial engine
=======================================

A five-cylinder radial with Semenov's dimensions: one master rod and four slave rods on link
pins. The slave pistons do not follow the crank-slider law: their strokes exceed 2r, their dead
centres lag their bank angles, and their second harmonic λ_i differs from cylinder to cylinder.
No simulation is needed: ``scene.geometry()`` gives each piston's exact stroke, dead centres and
λ_i (the names ``transient check`` prints), and the mechanism its kinematics and harmonics.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import transient
from transient.mechanisms import articulated

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

scene = transient.load_scene(CASES / "radial_5cyl.toml")
mech = scene.mechanism
geometry = scene.geometry()
for h in articulated.harmonics(mech):
    c = f"cyl_{h.cylinder}_"
    print(f"cylinder {h.cylinder} (bank {np.degrees(h.bank):5.1f}°): "
          f"TDC {np.degrees(geometry[c + 'tdc_after_bank'][0]):5.2f}° after its bank, "
          f"stroke − 2r = {1e3 * geometry[c + 'stroke_excess'][0]:6.3f} mm, "
          f"λ exact {geometry[c + 'lambda'][0]:.4f}, Semenov (61) {h.lam_semenov:.4f}")

phi = np.linspace(0.0, 2 * np.pi, 721)
table = mech.kinematics_table(phi)
fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, layout="constrained")
for k in range(1, mech.n_cylinders + 1):
    a1.plot(np.degrees(phi), 1e3 * table[f"u_{k}"], label=f"cylinder {k}")
a1.set_ylabel("u_k = dx/dφ [mm/rad]")
fig.legend(loc="outside lower center", ncol=mech.n_cylinders, fontsize=8)
a2.plot(np.degrees(phi), table["J"])
a2.set_ylabel("J(φ) [kg m²]")
a2.set_xlabel("φ [deg]")
for ax in (a1, a2):
    ax.grid(True, alpha=0.3)
fig.suptitle("Transfer functions and reduced inertia over one turn")
plt.show()
