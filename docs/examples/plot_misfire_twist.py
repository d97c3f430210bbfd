"""
The twist at a misfire: the section torques and their half orders
=================================================================

The in-line six of ``cases/inline6_damper.toml`` at about 2000 rpm on its elastic crankshaft,
run twice for six cycles from the same start: firing normally, and with cylinder 3 misfiring in
every cycle (``[[gas.cylinders]]``, ``misfire_every = 1``). A fan load holds each run at that
speed; for the misfiring engine it takes five sixths of the torque, so that both last cycles,
the ones shown, run at nearly the same mean speed.

Each throw's gas torque acts at that throw, so a section carries the torques of the throws
ahead of it (towards the front end) less what it takes to accelerate them. Cylinder 3's missing
combustion therefore unloads the sections behind throw 3, down to the flywheel, by about its
mean torque, and hardly those ahead of it (the mean torques printed below: the drop is about a sixth of
the firing engine's mean gas torque). In the cycle the sections behind throw 3 lose the peak
that follows cylinder 3's firing TDC. The misfire repeats once per cycle, once per two
revolutions: the torque it takes away is periodic over 720°, and its spectrum holds every
multiple of half an order — the half orders ½, 1, 1½ …, which the six's equal firing every 120°
does not excite (its cylinders' excitations add up in the orders 3, 6, 9 … and cancel in the
others). The flywheel section's torque and the flywheel's speed take them on.
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import transient
from transient import plots
from transient.analysis.torsion import critical_speeds, modal_analysis
from transient.analysis.torsion_run import line_cycles, line_orders
from transient.shaft import ShaftLine

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
RPM = 30.0 / math.pi
FAN = 9.2e-3  # [N m s²]: the full engine's torque at about 2000 rpm
firing = transient.load_scene(CASES / "inline6_damper.toml").replace(
    initial={"omega_rpm": 2000}, run={"revolutions": 12}, load={"fan": FAN})
n_cyl = firing.mechanism.n_cylinders
misfiring = firing.replace(gas={"cylinders": [{"cylinder": 3, "misfire_every": 1}]},
                           load={"fan": FAN * (n_cyl - 1) / n_cyl})

SECTIONS = {"torque_throw_2_throw_3": "throw 2 – throw 3 (ahead of the misfire)",
            "torque_throw_3_throw_4": "throw 3 – throw 4 (behind it)",
            "torque_throw_6_flywheel": "throw 6 – flywheel"}
COLUMNS = [*SECTIONS, "omega", "M_gas"]
runs = {}
for name, scene in (("firing", firing), ("cylinder 3 misfires", misfiring)):
    traj = transient.simulate(scene).trajectory
    runs[name] = (line_cycles(scene, traj, COLUMNS), line_orders(scene, traj, COLUMNS))
    print(f"{name}: last cycle's mean speed {runs[name][0].omega_mean[-1] * RPM:.0f} rpm")

# the crank angle in the cycle, from the cycle's start, and cylinder 3's firing TDC in it
cycles_fired = runs["firing"][0]
samples = cycles_fired.values.shape[2]
angle = np.arange(samples) * 720.0 / samples
tdc_3 = math.degrees(
    (firing.mechanism.firing_angles[2] - cycles_fired.cycle_start[-1]) % firing.mechanism.cycle)

fig, axes = plt.subplots(len(SECTIONS), 1, figsize=(8, 8), sharex=True, layout="constrained")
for ax, (column, label) in zip(axes, SECTIONS.items()):
    for (name, (cycles, _)), style in zip(runs.items(), ({"color": "0.5", "lw": 1.0},
                                                           {"color": "C3", "lw": 1.2})):
        torque = cycles.values[cycles.index(column), -1]
        ax.plot(angle, torque, label=name, **style)
    ax.axvline(tdc_3, color="k", ls=":", lw=0.8)
    ax.set_title(label, fontsize=9)
    ax.set_ylabel("section torque [N m]")
    ax.grid(True, alpha=0.3)
    means = [cycles.mean[cycles.index(column), -1] for cycles, _ in runs.values()]
    print(f"{label}: mean torque {means[0]:.1f} N m firing, {means[1]:.1f} N m misfiring "
          f"(drop {means[0] - means[1]:.1f} N m)")
axes[0].legend(fontsize=8, loc="upper right")
axes[0].annotate("cylinder 3's firing TDC", (tdc_3, 1.0), xycoords=("data", "axes fraction"),
                 xytext=(4, -12), textcoords="offset points", fontsize=8)
axes[-1].set_xlabel("crank angle in the last cycle [°]")
axes[-1].set_xticks(np.arange(0, 721, 120))
axes[-1].set_xlim(0, 720)
fig.suptitle("Section torques over the last cycle, firing and with cylinder 3 misfiring",
             fontsize=10)
# the mean drop behind the misfire against cylinder 3's share of the mean gas torque
gas = [cycles.mean[cycles.index("M_gas"), -1] for cycles, _ in runs.values()]
print(f"mean gas torque {gas[0]:.1f} N m firing, {gas[1]:.1f} N m misfiring: "
      f"drop {gas[0] - gas[1]:.1f} N m, a sixth of the firing engine's {gas[0] / n_cyl:.1f} N m")
plt.show()

# %%
# The orders of the last cycle, of the flywheel section's torque and of the flywheel's speed
# (the run's reference), each cycle's ramp removed. Firing, the orders ½, 1, 2 … are at the
# level of the run's settling, hundreds of times below the major orders; only 1.5, 4.5, 7.5 …
# are there already, the minor orders that the elastic line lets in (each throw drives the
# first mode at its own place along the shaft, see the rigid-versus-elastic example), 7.5 the
# strongest of them, its critical speed with the first mode near (printed below). With the
# misfire the half orders stand, the low ones within a few times of the major orders, in the
# torque as in the speed. Far below the first torsional mode (its frequency printed below), at
# the orders ½ and 1 the line moves as one body: the missing gas torque's order accelerates
# the whole line, and the flywheel section carries the flywheel's share of that acceleration,
# its share of the line's inertia (printed below with the ratio of the section's order to the
# gas torque's in the misfiring run).
fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True, layout="constrained")
panels = (("torque_throw_6_flywheel", "flywheel section's torque\namplitude [N m]"),
          ("omega", "flywheel speed ω\namplitude [rad/s]"))
for ax, (column, ylabel) in zip(axes, panels):
    for k, ((name, (_, orders)), colour) in enumerate(zip(runs.items(), ("0.5", "C3"))):
        plots.order_bars(ax, orders.orders, orders.spectra[column].amplitude[-1], ylabel, 12.0,
                         width=0.2, offset=(k - 0.5) * 0.21, label=name, log=True, color=colour)
    ax.set_xlabel("")
axes[-1].set_xlabel("engine order [1/rev]")
axes[-1].set_xticks(np.arange(0.0, 12.5, 1.0))
axes[-1].set_xticks(np.arange(0.5, 12.0, 1.0), minor=True)
axes[0].legend(fontsize=8)
fig.suptitle("Orders over the last cycle: a misfire every cycle brings in the half orders",
             fontsize=10)

line = ShaftLine(firing)
modal = modal_analysis(line)
print(f"first torsional mode {line.omega_1 / (2 * math.pi):.0f} Hz; order 0.5 at this speed "
      f"{0.5 * runs['firing'][0].omega_mean[-1] / (2 * math.pi):.1f} Hz")
for c in critical_speeds(modal, [7.5], (1000.0, 4000.0)):
    print(f"order 7.5 meets mode {c.mode} at {c.rpm:.0f} rpm")
share = line.weights[line.names.index("flywheel")] / line.weights.sum()
print(f"flywheel's share of the line's mean inertia: {share:.3f}")
for q in (0.5, 1.0, 2.0, 1.5, 4.5, 3.0, 6.0):
    torque, speed = ([abs(o.spectra[c].at(q)[-1]) for _, o in runs.values()]
                     for c in ("torque_throw_6_flywheel", "omega"))
    print(f"order {q:g}: flywheel section {torque[0]:.3g} → {torque[1]:.3g} N m, "
          f"ω {speed[0]:.3g} → {speed[1]:.3g} rad/s (firing → misfiring)")
for q in (0.5, 1.0):
    spectra = runs["cylinder 3 misfires"][1].spectra
    ratio = abs(spectra["torque_throw_6_flywheel"].at(q)[-1]) / abs(spectra["M_gas"].at(q)[-1])
    print(f"order {q:g}, misfiring: flywheel section's torque / gas torque = {ratio:.3f}")
plt.show()
