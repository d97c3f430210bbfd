"""
IMEP, BMEP, FMEP and the indicator diagram of a run
===================================================

The Gots diesel with Wiebe combustion, friction pairs and a droop governor, at half the case's
fan load: the governor settles it on its droop line at part fuel.
``[analysis] thermodynamics = true`` makes the run store, per cylinder and cycle, the indicated
work ∮p dV of the pressure it applied with the exact cylinder volume, and per cycle the brake and
friction mean effective pressures from the
load's work and the pairs' losses; over a cycle IMEP − BMEP − FMEP is the change of the kinetic
energy over the swept volume. The indicator diagram is drawn from the run's pressure: at part
fuel it lies well below the input table's full-load curve.
"""
import math
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt

import transient
from transient import plots
from transient.scene import scene_from_dict
from transient.scene.queries import gas_table

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

with open(CASES / "gots_diesel_wiebe.toml", "rb") as fh:
    data = tomllib.load(fh)
data["load"]["fan"] *= 0.5                  # half the load: part fuel on the droop line
data["initial"]["omega_rpm"] = 4400          # inside the droop range 4000 … 4600 rpm
data["run"]["revolutions"] = 20
data["output"] = {"samples_per_rev": 720}   # 0.5° samples: ∮p dV to ~1e-6
data["analysis"] = {"thermodynamics": True}
scene = scene_from_dict(data, file="gots_diesel_wiebe.toml")
result = transient.simulate(scene)

a = result.analysis
imep, bmep, fmep = (a[f"thermo_{n}"][0][-1] / 1e5 for n in ("imep_engine", "bmep", "fmep"))
print(f"last cycle at {a['thermo_cycle_omega_mean'][0][-1] * 30 / math.pi:.0f} rpm, fuel "
      f"{result.trajectory['fuel'][-1]:.3f}: IMEP {imep:.3f} bar, BMEP {bmep:.3f} bar, FMEP "
      f"{fmep:.3f} bar; balance residual {a['thermo_balance_residual'][0][-1]:.1e}")
print(f"MFB50 of cylinder 1: {math.degrees(a['thermo_mfb50'][0][0, -1]):.2f}° (local angle; "
      f"firing TDC at 360°)")

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
plots.run_indicator_phi(ax1, result, scene, cylinders=[1], table=gas_table(scene))
ax1.set_xlim(300, 480)
plots.run_indicator_pv(ax2, result, scene, cylinders=[1, 2, 3])
fig.suptitle("The run's pressure at part fuel against the full-load table")
plt.show()
