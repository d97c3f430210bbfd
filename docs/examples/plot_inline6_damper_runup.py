"""
An in-line six run up through its critical speeds, with and without its damper
==============================================================================

``cases/inline6_damper.toml`` is an in-line six diesel on an elastic crankshaft: a pulley with a
viscous (silicone) damper at the front end, six throws, a flywheel. Its first torsional mode
meets the engine orders 9, 7.5 and 6 between 1500 and 3400 rpm at the critical speeds that
``transient modes`` lists; 9 and 6 are major orders of the six, in which every cylinder excites
the mode in phase. Here the engine runs up at full load through them twice, slowly (a constant
load a little below its torque), each throw at its own angle: as the case has it, and with the
damper taken out.

The first figure shows, cycle by cycle against the cycle's mean speed, the vibratory torque
(half the peak-to-peak over the cycle) in the section at the flywheel and in the one at the
front end, beside the steady forced response at constant inertias (``transient modes
--response``): the run-up follows it, its resonances a little later and lower, having passed
them before they built up fully. Below, the mean power the damper's silicone takes over each
cycle, the heat flow it is sized by. The second figure shows each line's Campbell diagram with
the run's own order amplitudes of the flywheel section's torque
(:func:`transient.analysis.torsion_run.campbell_overlay`).
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import transient
from transient import plots
from transient.analysis.torsion import critical_speeds, engine_orders, modal_analysis
from transient.analysis.torsion_run import (
    campbell_overlay,
    cycle_mean_power,
    line_cycles,
    line_elements,
    line_orders,
    line_powers,
    order_peaks,
)
from transient.analysis.torsional_response import forced_response
from transient.shaft import ShaftLine

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
RPM = 30.0 / math.pi
# a constant load a little below the engine's mean torque: a slow run-up, about 25 rpm a cycle
damped = transient.load_scene(CASES / "inline6_damper.toml").replace(
    initial={"omega_rpm": 1500}, run={"revolutions": 130}, load={"fan": None, "torque": 370})
bare = damped.replace(shaft={"dampers": None})
REAR, FRONT = "torque_throw_6_flywheel", "torque_pulley_throw_1"

runs = {}
for name, scene in (("with the damper", damped), ("without the damper", bare)):
    line = ShaftLine(scene)
    result = transient.simulate(scene)
    traj = result.trajectory
    runs[name] = (scene, line, traj, line_cycles(scene, traj, [REAR, FRONT]),
                  line_orders(scene, traj, [REAR]))

fig, axes = plt.subplots(3, 1, figsize=(8, 9.5), sharex=True, layout="constrained")
for (name, (scene, line, traj, cycles, _)), colour in zip(runs.items(), ("C0", "C3")):
    rpm = cycles.omega_mean * RPM
    steady = forced_response(line, np.linspace(rpm.min(), rpm.max(), 240) / RPM)
    labels = {e.torque: e.label for e in line_elements(line)}
    for ax, column in zip(axes[:2], (REAR, FRONT)):
        ax.plot(rpm, 0.5 * cycles.peak_to_peak[cycles.index(column)], "o-", ms=2.5, lw=1.0,
                color=colour, label=f"run-up, {name}")
        e = steady.elements.index(labels[column])
        ax.plot(steady.rpm, 0.5 * steady.torque_pp[:, e], color=colour, lw=0.8, ls="--",
                label=f"steady response, {name}")
        ax.set_title(labels[column], fontsize=9)
    if name == "with the damper":
        power = line_powers(line, traj)["damper silicone at pulley"]
        speeds, mean = cycle_mean_power(scene, traj, power)
        axes[2].plot(speeds * RPM, mean, "o-", ms=2.5, lw=1.0, color=colour)
        k = int(np.argmax(mean))
        print(f"damper: largest mean power over a cycle {mean[k]:.4g} W at "
              f"{speeds[k] * RPM:.0f} rpm")
for ax in axes[:2]:
    ax.set_ylabel("vibratory torque,\n½ peak-to-peak [N m]")
    ax.grid(True, alpha=0.3)
fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2,
           fontsize=8)
axes[2].set_ylabel("damper's mean power\nover the cycle [W]")
axes[2].set_xlabel("cycle-mean speed [rpm]")
axes[2].grid(True, alpha=0.3)
fig.suptitle("In-line six run up at full load through the first mode's criticals of the "
             "orders 9, 7.5 and 6", fontsize=10)
plt.show()

# %%
# The Campbell diagram of each line (its natural frequencies with their frozen-angle bands,
# the engine orders, the critical speeds as circles) and the run's own order amplitudes of
# the flywheel section's torque, a marker per cycle and order, on one scale for both runs.
# The undamped modes of the two lines are the same (a viscous ring with no damping turns
# freely); without the damper the resonances stand at the critical speeds and are narrow,
# with it they are lower, wider and several times smaller: the silicone couples the ring's
# inertia to the pulley and takes the vibration's energy.
orders = engine_orders(damped.mechanism.cycle, 12.0)
overlays = {name: campbell_overlay(run[4], REAR, orders) for name, run in runs.items()}
largest = max(float(amp.max()) for _, _, amp in overlays.values())
fig, axes = plt.subplots(2, 1, figsize=(9, 11), layout="constrained")
for ax, (name, (_, line, _, _, orders_of_run)) in zip(axes, runs.items()):
    modal = modal_analysis(line)
    speed_range = (1400.0, 3600.0)
    criticals = critical_speeds(modal, orders, speed_range)
    plots.modal_campbell(ax, modal, orders, speed_range, criticals, run_orders=overlays[name],
                         run_label="order amplitude of the flywheel section's torque [N m]",
                         run_largest=largest)
    ax.set_title(name, fontsize=10)
    for peak in order_peaks(orders_of_run, REAR, [6.0], criticals):
        print(f"{name}: order 6 peaks at {peak.amplitude:.4g} N m at {peak.rpm:.0f} rpm; "
              f"critical speed {peak.critical:.0f} rpm (mode {peak.mode})")
plt.show()
