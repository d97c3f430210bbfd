"""Every numba-compiled function of transient, in three subpackages that follow the data flow:

- :mod:`~transient.core.integrator`: the numerics of an ODE, knowing nothing of engines:
  Runge–Kutta pairs and their tableaus, the step, its error norm and size control, the dense
  output, the location of an event function's crossings, the search of sorted breakpoints. It
  takes the model's derivative (and its event functions) as arguments.
- :mod:`~transient.core.model`: the reduced model of the machine: the
  :data:`~transient.core.model.layout.Model` tuple and the declared layout of its state, the
  mechanisms' kernels, the forcing, the serial chain and the friction solvers, the governor, the
  cylinder, the right-hand side and the output row.
- :mod:`~transient.core.stepper`: the run's loop, composing the two: the steps in crank angle or
  time between breakpoints, the engine's events and what they switch, the output grid, and what
  the loop and its Python caller exchange between chunks.

``pyproject.toml`` holds the contracts: the integrator imports nothing of the model or the
stepper, the model nothing of the stepper or the integrator; :mod:`.jit` (the compile decorators)
is below all three.

Numba's on-disk cache checks only the file that defines a function (a hash of its contents), not
the kernels it calls from other files: after an edit to ``tables.py`` a cached ``model.gas_value``
would keep the old code. So the cache lives in a folder named by a hash of all the sources in
this package and its subpackages, unless the user sets ``NUMBA_CACHE_DIR`` (then that folder is
used as it is).
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba


def source_hash(root: Path, pattern: str) -> str:
    """SHA-256 of the names (relative to ``root``) and contents of the files ``pattern`` matches
    under ``root``: the version of the code that a cache's contents come from."""
    h = hashlib.sha256()
    for path in sorted(root.glob(pattern)):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


#: The environment variable naming transient's cache folder (a shared file system's folder lets
#: the nodes of a cluster compile once per CPU model).
CACHE_DIR_VARIABLE = "TRANSIENT_CACHE_DIR"


def cache_root() -> Path:
    """``$TRANSIENT_CACHE_DIR``, else ``$XDG_CACHE_HOME/transient`` (``~/.cache/transient`` when
    unset or empty), where transient keeps what it computes once: numba's kernels here, the Wiebe
    cycles' tables (:mod:`transient.forces.wiebe_cache`)."""
    if os.environ.get(CACHE_DIR_VARIABLE):
        return Path(os.environ[CACHE_DIR_VARIABLE]).expanduser()
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "transient"


def _cache_dir() -> Path:
    return cache_root() / "numba" / source_hash(Path(__file__).parent, "**/*.py")[:16]


if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = str(_cache_dir())
