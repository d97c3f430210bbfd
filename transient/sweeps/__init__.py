"""Parameter sweeps on Dask: a base scene, parameter axes, the quantities to collect.

- :mod:`.spec` reads and validates a sweep file (axes, points, dotted scene keys) and resolves
  every run's scene before any work;
- :mod:`.execute` runs them: :func:`~.execute.run_one` on Dask workers (or in this process), the
  client and its local cluster, Ctrl-C handling;
- :mod:`.store` writes the one sweep file: each run in a result file's layout
  (:mod:`transient.results`), the sweep's axes, run index and status, and the summary table;
  run again, it mends the file, reusing every stored run whose resolved scene is unchanged.
"""
from .execute import Outcome, kernel_loads, run_one, run_sweep, worker_info
from .spec import (
                   DEFAULT_COLLECT,
                   METHODS,
                   QUANTITIES,
                   SPACINGS,
                   Axis,
                   RunSpec,
                   Sweep,
                   load_sweep,
                   set_key,
)
from .store import SweepStore, SweepTable, open_run, read_summary

__all__ = [
    "DEFAULT_COLLECT", "METHODS", "QUANTITIES", "SPACINGS", "Axis", "Outcome", "RunSpec",
    "Sweep", "SweepStore", "SweepTable", "kernel_loads", "load_sweep", "open_run",
    "read_summary", "run_one", "run_sweep", "set_key", "worker_info",
]
