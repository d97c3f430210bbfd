"""Compiled look-up of periodic piecewise-cubic tables (cylinder pressure against crank angle).

A table describes one periodic curve over a cycle ``[0, P)``. The cycle is cut at **corners**
into **pieces**, and inside a piece the curve is a piecewise cubic on knots (C² for a cubic
spline, C¹ for pchip). A jump or a kink may sit only at a corner, so the integrator, which stops
on every corner (docs/theory.md, Events and
breakpoints), only ever steps across
smooth parts. The layout, shared by the right-hand side and by :mod:`transient.forces.gas`:

``knots``, float64[n + 1]
    Strictly increasing, ``knots[0] = 0`` and ``knots[n] = P``. Every corner is a knot.
``coef``, float64[n, 4]
    Local polynomial of knot interval ``i``: ``c0 + c1*d + c2*d**2 + c3*d**3`` with
    ``d = x - knots[i]``.
``piece_knot``, int64[m + 1]
    Knot index of each corner: piece ``j`` covers knot intervals ``piece_knot[j]`` to
    ``piece_knot[j + 1] - 1``. ``piece_knot[0] = 0`` and ``piece_knot[m] = n``.

The corners in angle are ``knots[piece_knot]``. Angles are in radians, values in SI (Pa).
The plain-numpy twin is :meth:`transient.forces.gas.PressureTable.evaluate`.

A **held curve** (a tabulated load, :func:`held_curve_value`) is one such cubic on increasing
knots that are not a cycle: below the first knot and above the last it keeps its end values.

A **paired** table holds two curves on the same knots and corners (the full-load and the motored
cylinder pressure, ``transient.assemble.paired_table``): ``coef`` is float64[n, 8], columns 0–3
the first curve's cubic and 4–7 the second's. :func:`table_eval` reads the first curve of it,
:func:`table_eval_pair` both, with one interval search.
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import kernel


@kernel
def find_piece(knots, piece_knot, x):
    """Index of the piece that contains the angle `x`.

    Parameters
    ----------
    knots : float64[n + 1]
        Knot angles [rad], ``knots[0] = 0``, ``knots[n] = P``.
    piece_knot : int64[m + 1]
        Knot index of each corner.
    x : float
        Angle [rad], expected in ``[0, P)``; no wrapping is done here.

    Returns
    -------
    int
        ``j`` in ``[0, m - 1]`` with ``corner[j] <= x < corner[j + 1]``. An `x` exactly on a
        corner belongs to the piece that starts there. Values below 0 give piece 0 and values
        at or above ``P`` give the last piece, so a caller that rounds just past the cycle end
        still gets a valid index.
    """
    # Largest j in [0, m-1] with knots[piece_knot[j]] <= x; bisection on the corners only.
    lo = 0
    hi = piece_knot.shape[0] - 2
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if knots[piece_knot[mid]] <= x:
            lo = mid
        else:
            hi = mid - 1
    return lo


@kernel(inline=True)
def find_piece_near(knots, piece_knot, x, held):
    """:func:`find_piece`'s piece for `x`, tried first in the piece ``held`` (a float: what
    the caller kept from its last search; a value that is no piece index, NaN or garbage, is
    skipped): two comparisons where `x` is still in it, which it is at most evaluations of a
    cylinder that a step's stages move by a fraction of a piece. The same piece as
    :func:`find_piece` for every `x` and ``held``, since the corners increase strictly."""
    if 0.0 <= held < piece_knot.shape[0] - 1:
        j = np.int64(held)
        if knots[piece_knot[j]] <= x < knots[piece_knot[j + 1]]:
            return j
    return find_piece(knots, piece_knot, x)


@kernel(inline=True)
def _interval(knots, piece_knot, piece, x):
    """The knot interval of ``piece`` that holds x (bisection). Only the piece's own intervals
    are searched: the same result as a global search clamped into the piece, and fewer
    comparisons."""
    return last_knot_at_or_below(knots, piece_knot[piece], piece_knot[piece + 1] - 1, x)


@kernel(inline=True)
def last_knot_at_or_below(knots, lo, hi, x):
    """The largest index i in [lo, hi] with knots[i] ≤ x (bisection; ``knots`` increasing,
    knots[lo] ≤ x assumed)."""
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if knots[mid] <= x:
            lo = mid
        else:
            hi = mid - 1
    return lo


@kernel
def table_eval(knots, coef, piece_knot, piece, x):
    """Value and slope of the table at `x`, using the polynomials of `piece` only.

    The knot interval is found by bisection and clamped into the intervals of `piece`. The
    integrator chooses `piece` from the midpoint of its step and stops on corners, so a step
    ending exactly on a corner evaluates the polynomial of the piece it lies in (the left limit
    of a jump), not the next piece. An `x` a hair outside the piece extrapolates the piece's end
    polynomial, which is what the stepper wants.

    Parameters
    ----------
    knots : float64[n + 1]
        Knot angles [rad].
    coef : float64[n, 4]
        Local cubic coefficients per knot interval (ascending powers of ``x - knots[i]``).
    piece_knot : int64[m + 1]
        Knot index of each corner.
    piece : int
        Piece to evaluate, in ``[0, m - 1]``.
    x : float
        Angle [rad], not wrapped.

    Returns
    -------
    value : float
        Table value (Pa for a pressure table).
    slope : float
        Derivative with respect to the angle (Pa/rad).
    """
    return _cubic(knots, coef, _interval(knots, piece_knot, piece, x), x)


@kernel(inline=True)
def _cubic(knots, coef, lo, x):
    """Value and slope at x of knot interval ``lo``'s cubic."""
    d = x - knots[lo]
    c0 = coef[lo, 0]
    c1 = coef[lo, 1]
    c2 = coef[lo, 2]
    c3 = coef[lo, 3]
    value = c0 + d * (c1 + d * (c2 + d * c3))
    slope = c1 + d * (2.0 * c2 + 3.0 * d * c3)
    return value, slope


@kernel
def table_eval_pair(knots, coef, piece_knot, piece, x):
    """Values of both curves of a paired table (``coef`` float64[n, 8]) at `x`, using the
    polynomials of `piece` only, as :func:`table_eval` (which this is, twice on one interval).

    Returns
    -------
    first, second : float
        The curves of columns 0–3 and 4–7 (full-load and motored pressure) [Pa].
    """
    return _cubic_pair(knots, coef, _interval(knots, piece_knot, piece, x), x)


@kernel(inline=True)
def _cubic_pair(knots, coef, lo, x):
    """Both curves' values at x on knot interval ``lo`` of a paired table."""
    d = x - knots[lo]
    first = coef[lo, 0] + d * (coef[lo, 1] + d * (coef[lo, 2] + d * coef[lo, 3]))
    second = coef[lo, 4] + d * (coef[lo, 5] + d * (coef[lo, 6] + d * coef[lo, 7]))
    return first, second


#: How many knot intervals :func:`interval_near` walks from the kept one before it bisects.
NEAR_STEPS = 4


@kernel(inline=True)
def interval_near(knots, piece_knot, piece, x, held):
    """:func:`_interval`'s knot interval of ``piece`` for x — the largest i of the piece's with
    knots[i] ≤ x, its first where none is — walked to from ``held`` (a float: the interval the
    caller kept from its last search; one outside the piece, NaN or garbage, is skipped) in at
    most :data:`NEAR_STEPS` steps, else found by bisection. A cylinder's successive evaluations
    lie a few intervals apart, where a bisection over a piece of a thousand knots takes ten
    data-dependent branches; the interval is the same either way, the only one whose ends
    bracket x (the piece's first and last open below and above)."""
    lo = piece_knot[piece]
    hi = piece_knot[piece + 1] - 1
    if lo <= held <= hi:
        i = np.int64(held)
        for _ in range(NEAR_STEPS):
            if i > lo and x < knots[i]:
                i -= 1
            elif i < hi and knots[i + 1] <= x:
                i += 1
            else:
                return i
    return last_knot_at_or_below(knots, lo, hi, x)


@kernel(inline=True)
def table_eval_near(knots, coef, piece_knot, piece, x, held):
    """:func:`table_eval`'s value at x, its interval searched from ``held``
    (:func:`interval_near`); returns (value, the interval)."""
    i = interval_near(knots, piece_knot, piece, x, held)
    return _cubic(knots, coef, i, x)[0], i


@kernel(inline=True)
def table_eval_pair_near(knots, coef, piece_knot, piece, x, held):
    """:func:`table_eval_pair`'s values at x, the interval searched from ``held``
    (:func:`interval_near`); returns (first, second, the interval)."""
    i = interval_near(knots, piece_knot, piece, x, held)
    first, second = _cubic_pair(knots, coef, i, x)
    return first, second, i


@kernel
def wrap_angle(x, period):
    """`x` reduced into ``[0, period)``.

    Parameters
    ----------
    x : float
        Angle [rad], any value (the shaft angle is unwrapped).
    period : float
        Cycle length [rad], ``4*pi`` for a 4-stroke and ``2*pi`` for a 2-stroke.

    Returns
    -------
    float
        ``x mod period`` in ``[0, period)``.
    """
    y = x - period * math.floor(x / period)
    # floor() can leave y == period when x is a hair below a multiple of the period.
    if y >= period:
        y -= period
    if y < 0.0:
        y = 0.0
    return y


@kernel(inline=True)
def wrap_near(x, period):
    """:func:`wrap_angle`'s x in ``[0, period)``, x itself where it is in it already: two
    comparisons, not a division, for an angle that a small shift has moved from one already
    reduced (a cylinder's angle at a throw's twist from its angle at the reference's)."""
    if 0.0 <= x < period:
        return x
    return wrap_angle(x, period)


@kernel
def table_value(knots, coef, piece_knot, x):
    """Table value at any angle `x`: wrap into the cycle, find the piece, evaluate.

    Parameters
    ----------
    knots, coef, piece_knot
        The table arrays (see the module docstring).
    x : float
        Angle [rad], any value; it is wrapped modulo ``knots[-1]``.

    Returns
    -------
    float
        Value at `x`. At a jump this is the right limit (a corner belongs to the piece that
        starts there).
    """
    y = wrap_angle(x, knots[knots.shape[0] - 1])
    piece = find_piece(knots, piece_knot, y)
    value, _ = table_eval(knots, coef, piece_knot, piece, y)
    return value


@kernel(inline=True)
def held_curve_value(x_knots, coef, x):
    """Value at ``x`` of the piecewise cubic on ``x_knots`` (float64[n + 1], increasing; ``coef``
    float64[n, 4] as above), its end values held outside ``[x_knots[0], x_knots[n]]``: a load
    map or trace says nothing beyond its range, and a held value stays bounded where an
    extrapolated cubic would not."""
    n = coef.shape[0]
    if x <= x_knots[0]:
        return coef[0, 0]
    if x >= x_knots[n]:
        d = x_knots[n] - x_knots[n - 1]
        return coef[n - 1, 0] + d * (coef[n - 1, 1] + d * (coef[n - 1, 2] + d * coef[n - 1, 3]))
    lo = last_knot_at_or_below(x_knots, 0, n - 1, x)
    d = x - x_knots[lo]
    return coef[lo, 0] + d * (coef[lo, 1] + d * (coef[lo, 2] + d * coef[lo, 3]))
