"""The integrator on its own (:mod:`transient.core.integrator`), on plain ODEs with closed-form
solutions (``tests/plain_odes.py``): the harmonic oscillator and SciPy's rational test problem,
with both pairs, against their exact solutions at tolerances that follow rtol; an event located
on the dense output against the exact zero; and, in a fresh process, with no module of the engine
(the model, the stepper, the scene, the mechanisms …) imported at all.

The bounds are multiples of rtol on the solutions' scale (the oscillator's amplitude 2, the
rational problem's below 1): an adaptive pair's global error over a few periods is a small multiple
of its local tolerance (measured 0.6–3.3·rtol for these settings), so a bound of 10·rtol fails for
a wrong tableau, a wrong error norm or a wrong dense output, and holds on any CPU.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import plain_odes as po
import pytest

TESTS = Path(__file__).resolve().parents[1]
METHODS = ("dop853", "dopri5")


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_the_oscillator_follows_its_closed_form(method, rtol):
    (x, y, y_out, n_out, n_steps, _, n_rhs, status), x_out = po.solve_oscillator(method, rtol)
    assert status == 0 and x == 3.0 * math.pi and n_out == x_out.size
    scale = 2.0  # (the amplitude of y′)
    assert np.max(np.abs(y - po.oscillator_exact(x, 2.0))) <= 10.0 * rtol * scale
    assert np.max(np.abs(y_out - po.oscillator_exact(x_out, 2.0))) <= 10.0 * rtol * scale
    assert n_rhs >= n_steps * (6 if method == "dopri5" else 11)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_scipys_rational_problem_follows_its_closed_form(method, rtol):
    """Non-autonomous: the state carries x (component 2, not error-controlled), which each step
    sets exactly (the run ends on x_end to the last bit)."""
    (x, y, y_out, n_out, *_, status), x_out = po.solve_rational(method, rtol)
    assert status == 0 and x == 25.0 and y[2] == 25.0 and n_out == x_out.size
    assert np.max(np.abs(y[:2] - po.rational_exact(x))) <= 10.0 * rtol
    assert np.max(np.abs(y_out[:, :2] - po.rational_exact(x_out))) <= 10.0 * rtol
    assert np.array_equal(y_out[:, 2], x_out)  # (dense_state puts x exactly)


@pytest.mark.parametrize("method", METHODS)
def test_the_error_follows_the_tolerance(method):
    """Tightening rtol by 10⁴ cuts the error by at least 10³: the error control works as a
    control, not as a bound that happens to hold."""
    errors = []
    for rtol in (1e-6, 1e-10):
        (x, y, *_), _ = po.solve_oscillator(method, rtol)
        errors.append(np.max(np.abs(y - po.oscillator_exact(x, 2.0))))
    assert errors[1] < errors[0] / 1e3


@pytest.mark.parametrize("method", METHODS)
def test_an_event_is_located_on_the_dense_output(method):
    """The oscillator's position first falls through zero at ωx = π/2 (ω = 2): the solve stops
    there, to the root finder's and the dense output's accuracy."""
    (x, y, _, _, _, _, _, status), _ = po.solve_oscillator(method, 1e-10, event=True)
    assert status == 1
    assert abs(x - math.pi / 4.0) <= 1e-9
    assert abs(y[0]) <= 1e-9 and abs(y[1] + 2.0) <= 1e-8


ALONE = """
import json, sys
import numpy as np
import plain_odes as po
(x, y, y_out, n_out, *_), x_out = po.solve_oscillator("dop853", 1e-8)
err = max(np.max(np.abs(y - po.oscillator_exact(x, 2.0))),
          np.max(np.abs(y_out - po.oscillator_exact(x_out, 2.0))))
print(json.dumps({"error": float(err), "modules": sorted(m for m in sys.modules
                                                         if m.split(".")[0] == "transient")}))
"""

#: What the integrator may import of transient: the package's top level (its errors and
#: version), the core's own (the compile decorators, the layouts' declaration) and itself.
ALLOWED = ("transient", "transient.errors", "transient.version", "transient.core",
           "transient.core.jit", "transient.core.declare")


def test_the_integrator_runs_without_any_engine_module():
    run = subprocess.run([sys.executable, "-c", ALONE], capture_output=True, text=True,
                         timeout=600, env={**os.environ, "PYTHONPATH": str(TESTS)})
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout.splitlines()[-1])
    engine = [m for m in out["modules"]
              if m not in ALLOWED and not m.startswith("transient.core.integrator")]
    assert engine == [], engine
    assert "transient.core.integrator.solve" in out["modules"]
    assert out["error"] <= 10.0 * 1e-8 * 2.0
