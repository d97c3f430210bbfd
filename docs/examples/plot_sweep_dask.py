"""
A sweep on Dask: η_mech against the load
========================================

:func:`transient.sweep` runs a scene over parameter axes with the engine of
``transient sweep``: here the governed Gots diesel with its main bearings and crankpins as
non-ideal pairs (``cases/gots_diesel_governed.toml``, its fan load taken off) at four load
torques, 300 revolutions each (steady after a few dozen), on the Dask client it is
given. Without ``client`` it starts a local cluster of one worker process per core (in a script,
under ``if __name__ == "__main__":``, as any program that starts processes); here the cluster's
workers are threads, so that the example runs as it is anywhere. The table holds one row per
run: the axis value, the quantities collected, the run's status.
"""
from pathlib import Path

import matplotlib.pyplot as plt
from dask.distributed import Client, LocalCluster

import transient

CASES = Path(transient.__file__).resolve().parents[1] / "cases"
base = transient.load_scene(CASES / "gots_diesel_governed.toml")
base = base.replace(load={"fan": 0.0}, run={"revolutions": 300})

with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                  dashboard_address=None) as cluster, Client(cluster) as client:
    done = transient.sweep(base, {"load.torque": [40.0, 80.0, 120.0, 160.0]},
                           collect=["mean_speed_rpm", "eta_mech"], client=client)
df = done.to_dataframe()
print(df[["load.torque", "mean_speed_rpm", "eta_mech", "status"]])

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
ax.plot(df["load.torque"], df["eta_mech"], "o-")
ax.set_xlabel("load torque [N m]")
ax.set_ylabel("η_mech = W_out / W_in [1]")
ax.grid(True, alpha=0.3)
plt.show()
