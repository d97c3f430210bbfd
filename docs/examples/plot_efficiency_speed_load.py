"""
Mechanical efficiency against speed and load
============================================

The Gots diesel with friction in its main bearings and crankpins, held at constant speeds as on
a dynamometer (one cycle of inverse dynamics through the chain of non-ideal pairs at each point),
at full and at half fuel. η_mech = W_out/W_in falls with speed, because the inertia torque makes
energy circulate through the pairs and back within every cycle, and it falls sooner at part load,
where the same circulation meets half the gas work.

The friction budget says where the loss goes: each pair's friction mean effective pressure
(its loss per cycle over the displacement), stacked at every speed.
"""
from pathlib import Path

import matplotlib.pyplot as plt

import transient
from transient.study.efficiency import efficiency_study, plot_budget

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

scene = transient.load_scene(CASES / "gots_diesel_friction.toml")
rpm = [500, 1000, 2000, 3000, 4000, 5000]
rows = efficiency_study(scene, rpm, fuels=(1.0, 0.5))

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
for fuel in (1.0, 0.5):
    eta = [r["eta_mech_work"] for r in rows if r["fuel"] == fuel]
    ax.plot(rpm, eta, "o-", label=f"fuel {fuel:g}")
    print(f"fuel {fuel:g}: η_mech = " + ", ".join(f"{e:.4f}" for e in eta))
ax.set_xlabel("speed [rpm]")
ax.set_ylabel("η_mech = W_out / W_in")
ax.grid(True, alpha=0.3)
ax.legend()
ax.set_title(scene.name)

# %%
# The budget at full fuel: the crankpins lose more than the main bearings (their efficiencies
# are the lower ones), and both grow with the energy that circulates at high speed.
names = [p.name for p in scene.friction.pairs]
fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
plot_budget(ax, rows, names)
ax.set_title(f"{scene.name}: FMEP per pair")
full = [r for r in rows if r["fuel"] == 1.0]
print("FMEP [kPa] at full fuel: " + ", ".join(f"{r['fmep'] / 1e3:.1f}" for r in full))
plt.show()
