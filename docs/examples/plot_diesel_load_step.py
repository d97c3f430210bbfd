"""
A diesel generator set under a load step (ISO 8528-5)
=====================================================

The governed three-cylinder Gots diesel, with friction in its main bearings and crankpins,
drives a 70 kW generator: the load is accepted at once at 1 s and rejected at 2 s. For each step
the run's summary gives the ISO 8528-5 measures of the speed's response, computed on the
cycle-mean speed so that the firing fluctuation is not taken for a deviation.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import transient
from transient import plots

CASES = Path(transient.__file__).resolve().parents[1] / "cases"

scene = transient.load_scene(CASES / "gots_diesel_load_steps.toml")
with tempfile.TemporaryDirectory() as tmp:
    transient.simulate(scene, Path(tmp) / "load_steps.h5")
    res = transient.open_result(Path(tmp) / "load_steps.h5")

for k in (1, 2):
    p = f"load_change_{k}_"
    print(f"step {k}: deviation {res.analysis[p + 'dev_max_pct'][0]:+.2f} %, "
          f"recovery {res.analysis[p + 'recovery_s'][0]:.3f} s, "
          f"steady change {res.analysis[p + 'droop_pct'][0]:+.2f} %")

fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True, layout="constrained")
plots.load_response(axes, res.trajectory, scene, res.analysis)
axes[0].set_title("Load acceptance and rejection")
plt.show()
