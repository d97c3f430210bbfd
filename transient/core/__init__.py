"""Every numba-compiled function of transient (kinematics, reduced model, stepper).

Numba's on-disk cache checks only the file that defines a function (a hash of its contents), not
the kernels it calls from other files: after an edit to ``tables.py`` a cached ``model.gas_value``
would keep the old code. So the cache lives in a folder named by a hash of all the sources in
this package, unless the user sets ``NUMBA_CACHE_DIR`` (then that folder is used as it is).
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
    return cache_root() / "numba" / source_hash(Path(__file__).parent, "*.py")[:16]


if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = str(_cache_dir())
