"""
Rigid or elastic: the orders of the speed of one engine
=======================================================

The in-line six of ``cases/inline6_damper.toml`` at 2600 rpm, near the speed at which its damped
first torsional mode meets the sixth order, run twice for twelve cycles: on its elastic shaft
line, each throw at its own angle, and as its rigid equivalent
(:func:`transient.shaft.line.rigid_equivalent`: the same inertias as one body, J(φ) the line's
with every station at one angle). A fan load holds both near that speed. The orders of the speed
over the last cycle are taken with the order machinery of ``transient orders``
(:func:`transient.analysis.torsion_run.line_orders`, each cycle's ramp removed).

On the rigid shaft every cylinder drives one body, and the six's excitations add up only in its
major orders 3, 6, 9, 12: the speed holds those (what is left of the others is the run still
settling to its speed, a thousandth of them). On the elastic line the throws drive the first
mode each at its own place along the shaft, and the minor orders add up in it too (their
relative excitation, ``transient modes``): the flywheel — the run's reference — carries the
orders 1.5 and 4.5 at a tenth of a radian per second and more, where the rigid shaft has next to
nothing, and the pulley at the front end, where the mode swings most, carries the sixth order at
twenty times the rigid model's. A rigid model gives the flywheel's mean speed and its major
orders; the elastic one gives what the front end and the damper see.
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import transient
from transient import plots
from transient.analysis.torsion_run import line_orders
from transient.shaft import rigid_equivalent

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
elastic = transient.load_scene(CASES / "inline6_damper.toml").replace(
    initial={"omega_rpm": 2600}, run={"revolutions": 24}, load={"fan": 5.5e-3})
rigid = rigid_equivalent(elastic)

speed_rigid = line_orders(rigid, transient.simulate(rigid).trajectory, ["omega"])
run = transient.simulate(elastic).trajectory
speed_elastic = line_orders(elastic, run, ["omega", "omega_pulley"])

orders = speed_rigid.orders
fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
bars = (("rigid shaft", speed_rigid.spectra["omega"], "0.45"),
        ("elastic: flywheel (reference)", speed_elastic.spectra["omega"], "C0"),
        ("elastic: pulley", speed_elastic.spectra["omega_pulley"], "C3"))
for k, (label, spectrum, colour) in enumerate(bars):
    plots.order_bars(ax, orders, spectrum.amplitude[-1], "ω amplitude [rad/s]", 12.0,
                     width=0.14, offset=(k - 1) * 0.15, label=label, log=True, color=colour)
ax.set_ylim(bottom=1e-4)
ax.set_xticks(np.arange(0.0, 12.5, 1.0))
ax.legend(fontsize=8)
ax.set_title(f"In-line six at {speed_elastic.omega_mean[-1] * 30 / math.pi:.0f} rpm: orders "
             f"of the speed over the last cycle", fontsize=10)
for q in (1.5, 3.0, 4.5, 6.0, 9.0):
    values = [abs(s.at(q)[-1]) for _, s, _ in bars]
    print(f"order {q:g}: rigid {values[0]:.3g}, flywheel {values[1]:.3g}, pulley {values[2]:.3g}"
          f" rad/s")
plt.show()
