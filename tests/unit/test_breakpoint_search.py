"""The breakpoint search by bisection against a plain scan over every breakpoint.

A table from points makes every knot of every cylinder a breakpoint, so the stepper finds the
next one by bisection (:func:`transient.core.stepper.breakpoints.next_breakpoint`) and the jump flag of
the one it sits on near φ only (``_jumps_at``); both must answer what a scan of all of them
answers, to the bit, at and around breakpoints and across the cycle's ends.
"""
from __future__ import annotations

import math

import numpy as np

from transient.core.stepper.breakpoints import BP_LANDING, _jumps_at, next_breakpoint

PERIOD = 4.0 * math.pi


def scan_next(bp, period, phi, upward):
    """The breakpoint strictly above (below) φ by a scan over all of them."""
    tol = 1e-13 * max(1.0, abs(phi))
    k = np.floor(phi / period)
    cycles = (k, k + 1) if upward else (k, k - 1)
    for c in cycles:
        angles = c * period + bp  # (elementwise: the same rounding as the kernel's)
        hit = angles[angles > phi + tol] if upward else angles[angles < phi - tol]
        if hit.size:
            return hit[0] if upward else hit[-1]
    return math.inf if upward else -math.inf


def angles_to_try(bp, rng):
    """Random angles, the breakpoints themselves in several cycles, and a few ulp and tolerances
    either side of them."""
    on = np.concatenate([bp + c * PERIOD for c in (-3, 0, 1, 250)])
    near = np.concatenate([np.nextafter(on, np.inf), np.nextafter(on, -np.inf),
                           on + 2e-13 * np.maximum(1.0, np.abs(on)),
                           on - 2e-13 * np.maximum(1.0, np.abs(on))])
    return np.concatenate([rng.uniform(-3 * PERIOD, 300 * PERIOD, 400), on, near, [0.0, PERIOD]])


def test_next_breakpoint_is_the_scan():
    rng = np.random.default_rng(3)
    for n in (0, 1, 2, 7, 64, 1000):
        bp = np.sort(rng.uniform(0.0, PERIOD, n))
        if n > 2:
            bp[0] = 0.0  # a breakpoint on the cycle's start
        for phi in angles_to_try(bp, rng):
            for upward in (True, False):
                assert next_breakpoint(bp, PERIOD, phi, upward) == scan_next(bp, PERIOD, phi,
                                                                             upward)


def test_jump_flag_near_the_shaft_only():
    """The flag of any breakpoint the shaft is on (to BP_LANDING), across the cycle's ends, as a
    scan over all of them finds it."""
    rng = np.random.default_rng(5)
    bp = np.sort(np.concatenate([rng.uniform(0.0, PERIOD, 300), [0.0, PERIOD - 5e-8]]))
    jump = rng.random(bp.size) < 0.3
    jump[0] = jump[-1] = True
    for phi in angles_to_try(bp, rng):
        d = np.mod(phi - bp, PERIOD)
        on = np.minimum(d, PERIOD - d) <= BP_LANDING
        assert _jumps_at(bp, jump, PERIOD, phi) == bool(np.any(jump & on))
