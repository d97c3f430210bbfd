"""The stepper under the numba fallback: with a numba release other than the checked one,
``transient.core.jit`` compiles with plain ``njit(cache=True)`` instead of its replacements of
numba internals (``tests/unit/test_numba_internals.py`` checks that switch on toy kernels). Here
a real scene — the Gots diesel spinning up under its gas forces — runs through the fallback in a
process that believes another numba is installed, and its trajectory must agree with the same
scene run normally.

The two builds round differently (numba's reference counting and inliner against LLVM's), so
the adaptive steps may part; the runs are compared as two paths of the same physics, to the sum
of their own errors plus one step's tolerance (``tests/own_error.py``), never bit for bit.
"""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from own_error import assert_agree

from transient.core import CACHE_DIR_VARIABLE, cache_root
from transient.run import integrate
from transient.scene import load_scene

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "cases" / "gots_diesel_spinup.toml"
REVOLUTIONS = 6.0
COLUMNS = ("phi", "omega")

#: Runs the scene in a process where numba reports another release, so that transient.core.jit
#: falls back at import; writes the trajectory's columns to the .npz named.
FALLBACK_RUN = """
import sys
from dataclasses import replace

import numba
import numpy as np

numba.__version__ = "0.0.0"  # as if another release were installed
from transient.core import jit
from transient.run import integrate
from transient.scene import load_scene

assert not jit.REPLACEMENTS_ON
scene = load_scene(sys.argv[1])
scene = replace(scene, run=replace(scene.run, revolutions=float(sys.argv[2])))
data = integrate(scene)
assert data.complete, data.message
np.savez(sys.argv[3], **{c: data.trajectory[c] for c in sys.argv[4:]})
"""


def _scene():
    scene = load_scene(SCENE)
    return replace(scene, run=replace(scene.run, revolutions=REVOLUTIONS))


# the long tier: the fallback compiles the whole stepper again with plain njit, in its own cache
@pytest.mark.slow
@pytest.mark.stress
def test_the_stepper_under_the_fallback_agrees_with_the_normal_build(tmp_path):
    # numba's own cache for the fallback's kernels, beside (not among) the replacements' cache
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_root() / "numba-fallback"),
           CACHE_DIR_VARIABLE: str(cache_root())}
    out = tmp_path / "fallback.npz"
    done = subprocess.run([sys.executable, "-W", "ignore::RuntimeWarning", "-c", FALLBACK_RUN,
                           str(SCENE), str(REVOLUTIONS), str(out), *COLUMNS],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=3600)
    assert done.returncode == 0, done.stderr
    with np.load(out) as saved:
        fallback = SimpleNamespace(trajectory={c: saved[c] for c in COLUMNS})
    scene = _scene()
    normal = integrate(scene)
    assert normal.complete, normal.message
    assert_agree(scene, normal, scene, fallback, COLUMNS)
