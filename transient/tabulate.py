"""Build the tabulated reduced model of a scene (:mod:`transient.core.model.tabulated`), with an
estimate of its error against the exact mechanism kernel.

The grid is refined (doubling the number of intervals) until the largest relative deviation of
the tables from the exact kernel — J, dJ/dφ and every u_k, each relative to its largest magnitude
over the cycle, checked at the quarter points of every interval, where the interpolation error of
a spline is largest — is at most the scene's ``table_tolerance``. If even
:data:`MAX_INTERVALS` do not reach it, the exact kernel is used and the summary says why.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly, make_interp_spline

#: Table sizes tried: 64, 128, … intervals per revolution.
MIN_INTERVALS, MAX_INTERVALS = 64, 1 << 15
#: The tables' error bound as a fraction of the scene's rtol (``solver.table_tolerance`` = 0).
FRACTION_OF_RTOL = 0.01
#: Below this the estimate measures the kernel's own rounding, not the tables.
ERROR_FLOOR = 1e-14


@dataclass(frozen=True)
class KinematicsTable:
    """Spline coefficients (``coef``, layout in :mod:`transient.core.model.tabulated`; None when the
    target was not reached), the intervals per revolution and the estimated relative error."""

    coef: NDArray[np.float64] | None
    intervals: int
    error: float
    target: float


def exact_terms(kernel, mech: NDArray[np.float64], ncyl: int, phi: NDArray[np.float64]
                ) -> NDArray[np.float64]:
    """Rows J, dJ, u_1 … u_n, u′_1 … u′_n of the exact kernel (a mechanism's ``kernel``, with its
    packed parameters ``mech``) at the angles ``phi``."""
    out = np.empty((2 + 2 * ncyl, phi.size))
    u, du = np.empty(ncyl), np.empty(ncyl)
    no_table = np.zeros((1, 1, 6))
    for j, p in enumerate(phi):
        out[0, j], out[1, j] = kernel(mech, no_table, p, u, du, True)
        out[2: 2 + ncyl, j] = u
        out[2 + ncyl:, j] = du
    return out


def _fit(values: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Quintic periodic spline coefficients (ascending powers), shape (n, 6), of samples at
    φ_i = 2π i/n (i = 0 … n)."""
    x = np.linspace(0.0, 2.0 * math.pi, n + 1)
    pp = PPoly.from_spline(make_interp_spline(x, values, k=5, bc_type="periodic"))
    first = int(np.argmin(np.abs(pp.x - 0.0)))
    return pp.c[::-1, first: first + n].T.copy()


def _tables(terms: NDArray[np.float64], ncyl: int, n: int) -> NDArray[np.float64]:
    rows = [terms[0]] + [terms[2 + k] for k in range(ncyl)]
    return np.stack([_fit(r, n) for r in rows])


def _error(coef, kernel, mech, ncyl, scale) -> float:
    """Largest relative deviation from the exact kernel at the quarter points of every interval."""
    from .core.model.tabulated import tabulated_terms

    n = coef.shape[1]
    h = 2.0 * math.pi / n
    phi = (np.arange(n)[:, None] * h + np.array([0.25, 0.5, 0.75]) * h).ravel()
    exact = exact_terms(kernel, mech, ncyl, phi)
    u, du = np.empty(ncyl), np.empty(ncyl)
    worst = 0.0
    for j, p in enumerate(phi):
        J, dJ = tabulated_terms(coef, p, u, du)
        got = np.concatenate(([J, dJ], u, du))
        worst = max(worst, float(np.max(np.abs(got - exact[:, j]) / scale)))
    return worst


def build_table(kernel, mech: NDArray[np.float64], ncyl: int, target: float) -> KinematicsTable:
    """The smallest table (64 · 2^j intervals) whose estimated relative error ≤ ``target``; if
    refining stops paying (the error falls less than 2× per doubling: the spline fit's rounding,
    ~1e-13, is reached) or MAX_INTERVALS does not reach it, a table with ``coef = None``."""
    probe = exact_terms(kernel, mech, ncyl, np.linspace(0.0, 2.0 * math.pi, 4097))
    if np.max(np.abs(probe[:, -1] - probe[:, 0])) > 1e-12 * np.max(np.abs(probe)):
        raise ValueError("the mechanism's kinematics is not 2π-periodic")
    # Relative to each function's largest magnitude (a function that vanishes: absolute).
    peak = np.max(np.abs(probe), axis=1)
    scale = np.where(peak > 0.0, peak, 1.0)
    target = max(target, ERROR_FLOOR)
    n, best, best_n = MIN_INTERVALS, math.inf, 0
    while n <= MAX_INTERVALS:
        x = np.linspace(0.0, 2.0 * math.pi, n + 1)
        coef = _tables(exact_terms(kernel, mech, ncyl, x), ncyl, n)
        err = _error(coef, kernel, mech, ncyl, scale)
        if err <= target:
            return KinematicsTable(coef, n, err, target)
        if err > 0.5 * best:
            break
        best, best_n = err, n
        n *= 2
    return KinematicsTable(None, best_n, best, target)
