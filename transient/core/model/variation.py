"""Per-cylinder variation: each cylinder's fuel factor in the cycle it is in, with its misfires
(``[[gas.cylinders]]``, :class:`transient.scene.records.Cylinder`).

A cylinder's cycles begin at its own angle ``Model.var_par[k, START]`` (cycle 1 the one in
progress at the initial angle) and repeat every ``Model.period``; the factor is constant over a
cycle and changes only on a cycle's first angle, which is a breakpoint, so that the right-hand
side stays smooth inside every step. The factor of a step is taken at its ``sel``, as the gas
table's piece is (:func:`transient.core.model.forcing.select_pieces`).

Random misfires come from a counter-based generator: the draw of cylinder k in cycle n is a
hash of (seed, k, n), the SplitMix64 finaliser (Steele, Lea & Flood 2014, "Fast splittable
pseudorandom number generators", OOPSLA, Fig. 3, ``mix64``), so that it needs no state, is the
same on every machine and in every run, and a resumed run draws what the uninterrupted one did.
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import kernel

#: Columns of ``Model.var_par`` (filled by ``transient.assemble.variation_fields``), per
#: cylinder: fuel factor φ_k (0: cut out) [1], pressure factor β_k on p − p0 [1], the shaft
#: angle where its cycle 1 begins [rad], the probability that a cycle misfires [1], the
#: combustion offset δ_k [rad].
FUEL, PRESSURE, START, RATE, SHIFT = range(5)
N_VAR_PAR = 5
#: Columns of ``Model.var_int``: cycles n with n % period == 0 misfire (0: none), the seed of
#: the draws, then the cycles that misfire, padded with 0.
EVERY, SEED, CYCLES = range(3)

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)


@kernel(inline=True)
def _mix64(z):
    """SplitMix64's output function of one uint64 (wrapping arithmetic)."""
    z = z + _GOLDEN
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@kernel
def misfire_draw(seed, k, n):
    """A uniform number in [0, 1) for cylinder ``k`` (from 0) in its cycle ``n`` (≥ 1) under
    ``seed`` (≥ 0): the top 53 bits of mix64(mix64(mix64(seed) ^ k) ^ n)."""
    h = _mix64(_mix64(_mix64(np.uint64(seed)) ^ np.uint64(k)) ^ np.uint64(n))
    return np.float64(h >> _S11) * (1.0 / 9007199254740992.0)


@kernel(inline=True)
def cycle_number(m, k, sel):
    """The cycle of cylinder k that the shaft angle ``sel`` lies in (1: the one in progress at
    the initial angle; a cycle includes its first angle)."""
    return np.int64(math.floor((sel - m.var_par[k, START]) / m.period)) + 1


@kernel(inline=True)
def cycle_fuel(m, k, sel):
    """Fuel factor of cylinder k in the cycle ``sel`` lies in: its factor φ_k, or 0 in a
    misfiring cycle (a listed one, a multiple of its misfire period, or a draw below its
    rate)."""
    f = m.var_par[k, FUEL]
    if f == 0.0:
        return f
    n = cycle_number(m, k, sel)
    if n < 1:  # (before the start: turned backwards past it; no schedule there)
        return f
    every = m.var_int[k, EVERY]
    if every > 0 and n % every == 0:
        return 0.0
    for j in range(CYCLES, m.var_int.shape[1]):
        if m.var_int[k, j] == n:
            return 0.0
    rate = m.var_par[k, RATE]
    if rate > 0.0 and misfire_draw(m.var_int[k, SEED], k, n) < rate:
        return 0.0
    return f
