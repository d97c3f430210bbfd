"""Every numba-compiled function of transient (kinematics, reduced model, stepper).

Numba's on-disk cache checks only the timestamp of the file that defines a function, not of the
kernels it calls from other files: after an edit to ``tables.py`` a cached ``model.gas_value``
would keep the old code. So the cache lives in a folder named by a hash of all the sources in
this package, unless the user sets ``NUMBA_CACHE_DIR`` (then that folder is used as it is).
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba


def _source_hash() -> str:
    h = hashlib.sha256()
    for path in sorted(Path(__file__).parent.glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _cache_dir() -> Path:
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    return base / "transient" / "numba" / _source_hash()


if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = str(_cache_dir())
