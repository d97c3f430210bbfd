"""Roots of scalar functions of one variable, for the set-up code (dead centres, the mixed
cycle's isobar).

Not scipy.optimize: importing it (and with it scipy.linalg) would be a large part of a warm
``transient run``'s start, and these roots are few.
"""
from __future__ import annotations

from collections.abc import Callable


def bisect_root(g: Callable[[float], float], a: float, b: float) -> float:
    """The x in [a, b] where g changes sign (g(a) and g(b) of opposite signs, a zero counting as
    positive), by bisection until the bracket cannot shrink: to the last bit, g(x) with g(b)'s
    sign and g one ulp towards a with g(a)'s, to within rounding of g."""
    a_negative = g(a) < 0.0
    while True:
        c = 0.5 * (a + b)
        if not min(a, b) < c < max(a, b):
            return b
        if (g(c) < 0.0) == a_negative:
            a = c
        else:
            b = c
