"""Adaptive Gauss–Kronrod quadrature of a vector-valued integrand over many intervals at once,
for the set-up and analysis code (the work integrals of a prescribed motion).

The 7-point Gauss rule and its 15-point Kronrod extension (Kronrod 1965; the constants of
QUADPACK's ``qk15``, Piessens et al., *QUADPACK*, 1983, §2.2.3): K15 integrates polynomials of
degree ≤ 22 exactly, G7 those of degree ≤ 13, and |K15 − G7| bounds the error of K15 from above
wherever the integrand is smooth on the interval (there K15's error is far smaller). An interval
whose estimate exceeds its share of the tolerance is halved, so that a corner or a jump inside
one is closed in on until the pieces around it meet the tolerance too; every node is inside its
interval, so an integrand evaluated at a node sees one side of a corner at an interval's end.

Not scipy.integrate: its ``quad`` takes one scalar integrand on one interval at a time, where
here thousands of intervals are evaluated in one call of a compiled kernel.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

# Kronrod abscissae on [0, 1] (descending; the odd-indexed ones are the Gauss points) and weights
_XK = np.array([0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                0.207784955007898467600689403773245, 0.0])
_WK = np.array([0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                0.204432940075298892414161999234649, 0.209482141084727828012999174891714])
_WG = np.array([0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                0.381830050505118944950369775488975, 0.417959183673469387755102040816327])

#: The 15 nodes on [−1, 1], ascending, and the K15 and G7 weights there (G7's are 0 off its
#: nodes).
NODES = np.concatenate([-_XK[:-1], _XK[::-1]])
KRONROD = np.concatenate([_WK[:-1], _WK[::-1]])
GAUSS = np.zeros(15)
GAUSS[1:15:2] = np.concatenate([_WG[:-1], _WG[::-1]])

#: Halvings of an interval at most: 2⁻⁴⁰ of it is below the rounding of its ends.
MAX_HALVINGS = 40


@dataclass(frozen=True)
class Integrals:
    """What :func:`integrals` returns.

    ``value``: (n_f, n) array, the integral of each component over each interval. ``pieces``:
    how many pieces the intervals ended in; ``evaluations``: the integrand's values taken;
    ``unresolved``: pieces whose estimate still exceeded their tolerance after
    :data:`MAX_HALVINGS` halvings, or whose integrand was not finite (their K15 value is in
    ``value`` all the same).
    """

    value: NDArray[np.float64]
    pieces: int
    evaluations: int
    unresolved: int


def integrals(f: Callable[[NDArray[np.float64]], NDArray[np.float64]], lo: ArrayLike,
              hi: ArrayLike, rtol: float, atol: float, batch: int = 4096) -> Integrals:
    """∫ f(x) dx over each interval [lo_i, hi_i] (lo ≤ hi), for every component of f.

    ``f`` maps abscissae (m,) to values (n_f, m). The sum of the error estimates |K15 − G7| of
    all pieces is kept below rtol·∫|f_j| + atol for each component j, ∫ over all the intervals
    together: each interval is integrated by K15, a piece whose estimate exceeds its share of
    that (rtol·∫|f_j| + atol·width/total width over the piece) is halved, until the pieces left
    over fit into what the others left of it (a jump inside a piece, whose error shrinks only
    as its width, needs that). So the error of each component, summed over any of the intervals,
    stays below rtol·∫|f_j| + atol where the estimate bounds the error (module docstring).
    ``batch``: the most intervals evaluated in one call of ``f`` (its memory).
    """
    lo = np.asarray(lo, dtype=np.float64).ravel()
    hi = np.asarray(hi, dtype=np.float64).ravel()
    if lo.shape != hi.shape or np.any(hi < lo):
        raise ValueError("lo and hi must be intervals of one shape with lo ≤ hi")
    total = float(np.sum(hi - lo))
    owner = np.nonzero(hi > lo)[0]
    a, b = lo[owner], hi[owner]
    value = spent = settled = None  # per component: the sums over the pieces accepted so far
    pieces = evaluations = unresolved = 0
    for level in range(MAX_HALVINGS + 1):
        if owner.size == 0:
            break
        k, g, mag = _rules(f, a, b, batch)
        if value is None:
            value = np.zeros((k.shape[0], lo.size))
            spent, settled = np.zeros(k.shape[0]), np.zeros(k.shape[0])
        evaluations += NODES.size * owner.size
        err = np.abs(k - g)
        done = np.all(err <= rtol * mag + atol * ((b - a) / total)[None, :], axis=0)
        budget = rtol * (settled + mag.sum(axis=1)) + atol
        # a non-finite piece is not halved: its values would not become finite by it
        bad = ~np.all(np.isfinite(k) & np.isfinite(g), axis=0)
        if level == MAX_HALVINGS or np.all(spent + err.sum(axis=1) <= budget):
            unresolved += int(np.count_nonzero(~done)) if level == MAX_HALVINGS else 0
            done[:] = True
        unresolved += int(np.count_nonzero(bad & ~done))
        done |= bad
        np.add.at(value.T, owner[done], k[:, done].T)
        spent += err[:, done].sum(axis=1)
        settled += mag[:, done].sum(axis=1)
        pieces += int(np.count_nonzero(done))
        mid = 0.5 * (a + b)
        owner = np.repeat(owner[~done], 2)
        a, b = (np.column_stack([a[~done], mid[~done]]).ravel(),
                np.column_stack([mid[~done], b[~done]]).ravel())
    if value is None:
        value = np.zeros((np.asarray(f(np.zeros(0))).shape[0], lo.size))
    return Integrals(value, pieces, evaluations, unresolved)


def _rules(f, a, b, batch):
    """K15, G7 and K15 of |f| on each interval [a_i, b_i]: three (n_f, n) arrays."""
    parts = []
    for s in range(0, a.size, batch):
        centre = 0.5 * (a[s:s + batch] + b[s:s + batch])
        half = 0.5 * (b[s:s + batch] - a[s:s + batch])
        x = centre[:, None] + half[:, None] * NODES[None, :]
        fx = np.asarray(f(x.ravel()), dtype=np.float64).reshape(-1, centre.size, NODES.size)
        parts.append((half * (fx @ KRONROD), half * (fx @ GAUSS), half * (np.abs(fx) @ KRONROD)))
    return tuple(np.concatenate(p, axis=1) for p in zip(*parts))
