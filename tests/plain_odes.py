"""Plain ODEs with closed-form solutions, as kernels in the integrator's form (``rhs(ctx, y,
out)``, :mod:`transient.core.integrator.rk`), for the tests that run the integrator without any
engine module (``tests/unit/test_integrator.py``). Imports nothing of transient but the
integrator's own layer: the test checks that running them leaves every engine module unimported.
"""
from __future__ import annotations

import math

import numpy as np

from transient.core.declare import BY_SIZE, NOT_CONTROLLED
from transient.core.integrator.solve import solve
from transient.core.integrator.tableaus import TABLEAUS
from transient.core.jit import kernel


@kernel(inline=True)
def oscillator(ctx, y, out):
    """y″ = −ω²y as (y, y′): ``ctx`` = (ω,). Solution from (1, 0): (cos ωx, −ω sin ωx)."""
    w = ctx[0]
    out[0] = y[1]
    out[1] = -w * w * y[0]


@kernel(inline=True)
def position(ctx, y):
    """The oscillator's position, an event function (zero at ωx = π/2 + kπ)."""
    return y[0]


@kernel(inline=True)
def rational(ctx, y, out):
    """SciPy's rational test problem (``scipy/integrate/_ivp/tests/test_ivp.py``,
    ``fun_rational``), non-autonomous: the state carries x in component 2. Solution:
    (x/(x + 10), 10x/(x + 10)²)."""
    x = y[2]
    out[0] = y[1] / x
    out[1] = y[1] * (y[0] + 2.0 * y[1] - 1.0) / (x * (y[0] - 1.0))
    out[2] = 1.0


def oscillator_exact(x, w):
    return np.stack([np.cos(w * x), -w * np.sin(w * x)], axis=-1)


def rational_exact(x):
    return np.stack([x / (x + 10.0), 10.0 * x / (x + 10.0) ** 2], axis=-1)


def solve_oscillator(method, rtol, w=2.0, x_end=3.0 * math.pi, n_out=50, event=False):
    """The oscillator from (1, 0) over ``x_end`` at ``rtol`` (atol = rtol/1000), sampled at
    ``n_out`` abscissae; stopped at its first zero from above with ``event``."""
    x_out = np.linspace(0.0, x_end, n_out + 2)[1:-1]
    control = np.full(2, BY_SIZE, dtype=np.int64)
    return solve(TABLEAUS[method], oscillator, (w,), 0.0, np.array([1.0, 0.0]), x_end, 1e-3,
                 rtol, rtol * 1e-3, control, -1, x_out, position if event else None, -1), x_out


def solve_rational(method, rtol, x_end=25.0):
    """SciPy's rational problem from x = 5 to ``x_end`` at ``rtol`` (atol = rtol/1000)."""
    x_out = np.linspace(5.5, x_end - 0.5, 20)
    control = np.array([BY_SIZE, BY_SIZE, NOT_CONTROLLED], dtype=np.int64)
    y0 = np.append(rational_exact(5.0), 5.0)
    return solve(TABLEAUS[method], rational, (0.0,), 5.0, y0, x_end, 1e-2, rtol, rtol * 1e-3,
                 control, 2, x_out, None, 0), x_out
