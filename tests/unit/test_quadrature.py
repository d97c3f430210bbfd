"""The adaptive Gauss–Kronrod quadrature (transient.quadrature) against closed forms.

* **The rule's constants** (typed in from QUADPACK's qk15): the 7 Gauss nodes and weights are
  numpy's Gauss–Legendre ones; the 15-point Kronrod rule integrates x^d exactly up to d = 22 and
  not d = 24, which fixes the Kronrod extension (it is unique); the Gauss rule up to d = 13.
* **Integrals** over many intervals at once of a smooth function, a corner and a jump inside an
  interval, against their antiderivatives: the error summed over the intervals stays below
  rtol·∫|f| + atol at every rtol, and a tighter rtol takes more pieces.
* A non-finite integrand is counted as unresolved and not halved forever; empty intervals give 0.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from transient.quadrature import GAUSS, KRONROD, MAX_HALVINGS, NODES, integrals


def test_the_rules_are_gauss_legendre_and_its_kronrod_extension():
    x, w = np.polynomial.legendre.leggauss(7)
    assert np.abs(NODES[1::2] - x).max() <= 1e-15
    assert np.abs(GAUSS[1::2] - w).max() <= 1e-15 and np.all(GAUSS[::2] == 0.0)
    assert np.all(np.diff(NODES) > 0) and np.all(NODES == -NODES[::-1])
    for d in range(26):
        exact = (1.0 - (-1.0) ** (d + 1)) / (d + 1)  # ∫_{-1}^{1} x^d dx
        k_err, g_err = abs(KRONROD @ NODES ** d - exact), abs(GAUSS @ NODES ** d - exact)
        assert (k_err <= 1e-15) == (d <= 22 or d % 2 == 1), (d, k_err)
        assert (g_err <= 1e-15) == (d <= 13 or d % 2 == 1), (d, g_err)


C_KINK, C_JUMP = 1.0 / math.e, 1.0 / math.pi  # inside an interval, on no dyadic point


def family(x):
    """sin(7x), |x − C_KINK|, a unit step at C_JUMP."""
    return np.vstack([np.sin(7.0 * x), np.abs(x - C_KINK), np.where(x >= C_JUMP, 1.0, 0.0)])


def antiderivative(x):
    x = np.asarray(x, dtype=float)
    return np.vstack([-np.cos(7.0 * x) / 7.0, 0.5 * (x - C_KINK) * np.abs(x - C_KINK),
                      np.maximum(x - C_JUMP, 0.0)])


@pytest.mark.parametrize("rtol", [1e-4, 1e-8, 1e-12])
def test_error_over_all_intervals_stays_within_the_tolerance(rtol):
    edges = np.linspace(0.0, 2.0, 5)  # four intervals of 0.5: sin(7x) is far from a polynomial
    q = integrals(family, edges[:-1], edges[1:], rtol, 1e-300)
    exact = np.diff(antiderivative(edges), axis=1)
    grid = np.linspace(0.0, 2.0, 200001)
    magnitude = np.trapezoid(np.abs(family(grid)), grid, axis=1)  # ∫|f|, to ~1e-9
    error = np.abs(q.value - exact).sum(axis=1)
    print(f"rtol {rtol:g}: error/(rtol·∫|f|) {error / (rtol * magnitude)}, {q.pieces} pieces")
    assert np.all(error <= rtol * magnitude)
    assert q.unresolved == 0 and q.evaluations == 15 * (2 * q.pieces - 4)  # a binary tree


def test_tighter_tolerance_takes_more_pieces():
    edges = np.linspace(0.0, 2.0, 5)
    pieces = [integrals(family, edges[:-1], edges[1:], r, 0.0).pieces for r in (1e-4, 1e-12)]
    assert pieces[1] > pieces[0] >= 4


def test_atol_alone_bounds_the_error():
    """With rtol = 0 the sum of the errors stays below atol (a function near zero)."""
    f = lambda x: 1e-3 * np.exp(x)[None, :]
    edges = np.array([0.0, 0.3, 1.7, 3.0])
    q = integrals(f, edges[:-1], edges[1:], 0.0, 1e-12)
    assert np.abs(q.value[0] - 1e-3 * np.diff(np.exp(edges))).sum() <= 1e-12


def test_non_finite_integrand_is_reported_not_halved_forever():
    f = lambda x: np.where(x > 0.25, np.nan, 1.0)[None, :]
    q = integrals(f, [0.0, 0.5], [0.5, 1.0], 1e-10, 0.0)
    assert q.unresolved >= 1 and q.pieces < 4 * MAX_HALVINGS
    assert np.all(np.isnan(q.value))


def test_empty_intervals_and_refusals():
    f = lambda x: np.vstack([x, x * x])
    q = integrals(f, [0.0, 1.0, 1.0], [1.0, 1.0, 2.0], 1e-10, 0.0)
    assert q.value.shape == (2, 3)
    np.testing.assert_allclose(q.value, [[0.5, 0.0, 1.5], [1 / 3, 0.0, 7 / 3]], rtol=1e-14)
    assert integrals(f, [2.0], [2.0], 1e-10, 0.0).value.shape == (2, 1)
    with pytest.raises(ValueError, match="lo ≤ hi"):
        integrals(f, [1.0], [0.0], 1e-10, 0.0)
