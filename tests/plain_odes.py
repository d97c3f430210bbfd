"""Plain ODEs with closed-form solutions, as kernels in the integrator's form (``rhs(ctx, y,
out)``, :mod:`transient.core.integrator.rk`), with their Jacobians in the W-method's form
(``jac(ctx, y, f0, band)``, :mod:`transient.core.integrator.rosenbrock`), for the tests that run
the integrator without any engine module (``tests/unit/test_integrator.py``,
``tests/unit/test_rosenbrock.py``). Imports nothing of transient but the
integrator's own layer: the test checks that running them leaves every engine module unimported.
"""
from __future__ import annotations

import math

import numpy as np

from transient.core.declare import BY_SIZE, NOT_CONTROLLED
from transient.core.integrator.rosenbrock import is_w_method, method_step
from transient.core.integrator.solve import solve
from transient.core.integrator.tableaus import TABLEAUS
from transient.core.jit import compiled, kernel


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


@kernel(inline=True)
def oscillator_jacobian(ctx, y, f0, band):
    """The oscillator's Jacobian [[0, 1], [−ω², 0]] times ``ctx[1]`` (1: exact; any other
    factor, a W-method's approximate matrix), in band storage (kb = 1); block from 0."""
    w = ctx[0]
    scale = ctx[1]
    band[0, 0] = 0.0
    band[0, 1] = 0.0
    band[0, 2] = scale
    band[1, 0] = -scale * w * w
    band[1, 1] = 0.0
    band[1, 2] = 0.0
    return 0


@kernel(inline=True)
def prothero_robinson(ctx, y, out):
    """Prothero & Robinson's stiff test, y′ = λ(y − sin x) + cos x, ``ctx`` = (λ,), x carried in
    component 1. Solution from y(0) = 0: sin x, whatever λ; with λ ≪ 0 every other solution
    falls onto it at the rate λ, which bounds an explicit method's step by stability."""
    lam = ctx[0]
    x = y[1]
    out[0] = lam * (y[0] - math.sin(x)) + math.cos(x)
    out[1] = 1.0


@kernel(inline=True)
def prothero_robinson_jacobian(ctx, y, f0, band):
    """∂f₀/∂y₀ = λ: the block is component 0 alone (kb = 0)."""
    band[0, 0] = ctx[0]
    return 0


@kernel(inline=True)
def linear(ctx, y, out):
    """y′ = L y, ``ctx`` = (L, A)."""
    L = ctx[0]
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(y.shape[0]):
            acc += L[i, j] * y[j]
        out[i] = acc


@kernel(inline=True)
def linear_matrix(ctx, y, f0, band):
    """The matrix A of ``ctx`` = (L, A) in the Jacobian's place, in full band storage."""
    A = ctx[1]
    n = A.shape[0]
    kb = (band.shape[1] - 1) // 2
    for i in range(n):
        for j in range(n):
            band[i, j - i + kb] = A[i, j]
    return 0


def oscillator_exact(x, w):
    return np.stack([np.cos(w * x), -w * np.sin(w * x)], axis=-1)


def rational_exact(x):
    return np.stack([x / (x + 10.0), 10.0 * x / (x + 10.0) ** 2], axis=-1)


def _jacobian_args(method, jac, rows: int, kb: int):
    """``(jac, band)`` for ``solve``: the Jacobian kernel and its band's storage for a
    W-method, (None, None) for an explicit pair."""
    if is_w_method(TABLEAUS[method]):
        return jac, np.zeros((rows, 2 * kb + 1))
    return None, None


def solve_oscillator(method, rtol, w=2.0, x_end=3.0 * math.pi, n_out=50, event=False,
                     jacobian_scale=1.0):
    """The oscillator from (1, 0) over ``x_end`` at ``rtol`` (atol = rtol/1000), sampled at
    ``n_out`` abscissae; stopped at its first zero from above with ``event``. A W-method gets
    the Jacobian times ``jacobian_scale``."""
    x_out = np.linspace(0.0, x_end, n_out + 2)[1:-1]
    control = np.full(2, BY_SIZE, dtype=np.int64)
    return solve(TABLEAUS[method], oscillator, (w, jacobian_scale), 0.0, np.array([1.0, 0.0]),
                 x_end, 1e-3, rtol, rtol * 1e-3, control, -1, x_out,
                 position if event else None, -1,
                 *_jacobian_args(method, oscillator_jacobian, 2, 1)), x_out


def solve_prothero_robinson(method, rtol, lam, x_end=2.0):
    """Prothero–Robinson from y(0) = 0 over ``x_end`` at ``rtol`` (atol = rtol/1000), sampled at
    20 abscissae."""
    x_out = np.linspace(0.1, x_end - 0.1, 20)
    control = np.array([BY_SIZE, NOT_CONTROLLED], dtype=np.int64)
    return solve(TABLEAUS[method], prothero_robinson, (lam,), 0.0, np.zeros(2), x_end, 1e-3,
                 rtol, rtol * 1e-3, control, 1, x_out, None, 0,
                 *_jacobian_args(method, prothero_robinson_jacobian, 1, 0)), x_out


@compiled
def fixed_steps(tab, rhs, jac, ctx, y0, h, n, band):
    """``n`` steps of size h of the method ``tab`` from (0, y0), no error control: the final
    state (for an observed order of convergence)."""
    m = y0.shape[0]
    K = np.empty((tab.n_ext, m))
    y = y0.copy()
    y_new = np.empty(m)
    tmp = np.empty(m)
    f = np.empty(m)
    rhs(ctx, y, f)
    for k in range(n):
        for i in range(m):
            K[0, i] = f[i]
        method_step(tab, rhs, jac, ctx, -1, k * h, y, f, h, K, y_new, tmp, band)
        for i in range(m):
            y[i] = y_new[i]
            f[i] = K[tab.n_stages, i]
    return y


@compiled
def _one_step(tab, rhs, jac, ctx, y0, h, band):
    m = y0.shape[0]
    K = np.empty((tab.n_ext, m))
    y_new = np.empty(m)
    tmp = np.empty(m)
    f = np.empty(m)
    rhs(ctx, y0, f)
    K[0, :] = f
    method_step(tab, rhs, jac, ctx, -1, 0.0, y0, f, h, K, y_new, tmp, band)
    err = np.zeros(m)
    for s in range(tab.n_stages + 1):
        err += h * tab.E5[s] * K[s]
    return y_new, err


def linear_step(tab, L, A, y0, h):
    """One step of the W-method ``tab`` on y′ = L y with the matrix A in the Jacobian's place:
    (y₁, y₁ − ŷ₁)."""
    n = y0.shape[0]
    return _one_step(tab, linear, linear_matrix, (L, A), y0, h, np.zeros((n, 2 * n - 1)))


def oscillator_fixed(method, n, w=2.0, x_end=3.0 * math.pi, jacobian_scale=1.0):
    """The oscillator from (1, 0) over ``x_end`` in ``n`` equal steps."""
    jac, band = _jacobian_args(method, oscillator_jacobian, 2, 1)
    return fixed_steps(TABLEAUS[method], oscillator, jac, (w, jacobian_scale),
                       np.array([1.0, 0.0]), x_end / n, n, band)


def solve_rational(method, rtol, x_end=25.0):
    """SciPy's rational problem from x = 5 to ``x_end`` at ``rtol`` (atol = rtol/1000)."""
    x_out = np.linspace(5.5, x_end - 0.5, 20)
    control = np.array([BY_SIZE, BY_SIZE, NOT_CONTROLLED], dtype=np.int64)
    y0 = np.append(rational_exact(5.0), 5.0)
    return solve(TABLEAUS[method], rational, (0.0,), 5.0, y0, x_end, 1e-2, rtol, rtol * 1e-3,
                 control, 2, x_out, None, 0, None, None), x_out
