"""Breakpoints: sorted abscissae in one period where the right-hand side has a corner or a jump,
repeated every period (the engine's shaft angles of its tables' corners). A step must not
straddle one: the caller ends a step on the next one (:func:`next_breakpoint`), or retakes a
step that crossed one so that it ends there.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel


@kernel(inline=True)
def reached(level, phi, upward):
    """Whether φ has reached the breakpoint at ``level`` (the shaft angle it is at) moving up
    (``upward``) or down: it is within the search's tolerance of φ or behind it, so that
    :func:`next_breakpoint` from φ looks beyond it."""
    tol = 1e-13 * max(1.0, abs(phi))
    return level <= phi + tol if upward else level >= phi - tol


@kernel
def next_breakpoint(bp, period, phi, upward):
    """The breakpoint strictly above (``upward``) or below φ, as an absolute shaft angle (the
    first not :func:`reached` from φ); by bisection, as a table from points makes every knot of
    every cylinder a breakpoint."""
    tol = 1e-13 * max(1.0, abs(phi))
    k = np.floor(phi / period)
    n = bp.shape[0]
    if upward:
        for c in range(2):
            base = (k + c) * period
            j = count_below(bp, base, phi + tol, True)
            if j < n:
                return base + bp[j]
        return np.inf
    for c in range(2):
        base = (k - c) * period
        j = count_below(bp, base, phi - tol, False) - 1
        if j >= 0:
            return base + bp[j]
    return -np.inf


@kernel(inline=True)
def count_below(bp, base, level, inclusive):
    """How many of the angles ``base + bp[j]`` lie below ``level`` (or on it, ``inclusive``).
    They are a leading run of j: bp is sorted and rounded addition is monotone, so bisection
    finds what a scan from j = 0 would."""
    lo = 0
    hi = bp.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        v = base + bp[mid]
        if v < level or (inclusive and v == level):
            lo = mid + 1
        else:
            hi = mid
    return lo
