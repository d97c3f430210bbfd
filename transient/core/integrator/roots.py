"""Where an event function crosses zero inside the last step, on its dense output (Hairer,
Nørsett & Wanner, *Solving ODEs I*, §II.6): the Illinois method on a bracket, and sampling for a
crossing that comes and goes inside a step (both ends on one side).

The event function is passed as a kernel, ``g(ctx, y)``, the value at the state y (a tuple
``ctx`` holds what else it needs: the event's level, the model), as the derivative is to
:mod:`.rk`; which events a problem has, and what acting on one does, is the caller's.
"""
from __future__ import annotations

from ..jit import kernel
from .rk import dense_eval, dense_state

#: Iterations of the Illinois method at most, and the bracket's width in θ that ends them.
MAX_ITER, THETA_TOL = 100, 1e-12


@kernel
def root(g, ctx, F, y, tmp, a, b, ga, gb):
    """Root of the event function ``g(ctx, ·)`` in the bracket θ ∈ [a, b] (values ga, gb) on
    the dense output F of the last step from y (Illinois method); b if the bracket holds no sign
    change. Returns (θ, evaluations).

    The θ returned is on the far side of the crossing (g there has gb's sign, or is 0): the
    state at the event has crossed. Two functions that fall through zero at the same θ then both
    see their crossing there, and a switch is never undone because rounding left the event a
    hair before its own root."""
    if gb == 0.0 or (ga > 0.0) == (gb > 0.0):
        return b, 0
    side = 0
    for i in range(MAX_ITER):
        if b - a < THETA_TOL:
            return b, i
        c = b - gb * (b - a) / (gb - ga)
        if not (a < c < b):
            c = 0.5 * (a + b)
        dense_eval(F, y, c, tmp)
        gc = g(ctx, tmp)
        if gc == 0.0:
            return c, i + 1
        if (gc > 0.0) == (gb > 0.0):
            b, gb = c, gc
            if side == -1:
                ga *= 0.5
            side = -1
        else:
            a, ga = c, gc
            if side == 1:
                gb *= 0.5
            side = 1
    return b, MAX_ITER


@kernel(inline=True)
def crosses(g0, g1, direction):
    """Whether g goes from g0 to g1 through zero in the given direction (+1 rising, −1 falling,
    0 either; reaching zero counts)."""
    rising = g0 < 0.0 <= g1
    falling = g1 <= 0.0 < g0
    if direction > 0:
        return rising
    if direction < 0:
        return falling
    return rising or falling


@kernel
def crossing_inside(g, g_iterated, ctx, F, y, x, h, ix, direction, ga, tmp, n_samples):
    """θ where ``g(ctx, ·)`` first crosses zero (in ``direction``) inside a step whose ends are
    on the same side of it, sampled at θ = j/n_samples on the dense output (the independent
    variable, component ``ix``, exact at each), the crossing then located by :func:`root` with
    ``g_iterated`` (the same function, in a form cheaper to iterate, or ``g`` itself); 2 if the
    samples see no crossing (it was only in a stage, or between samples). ``ga``: g at the
    step's start. Returns (θ, evaluations)."""
    g_prev = ga
    for j in range(1, n_samples + 1):
        theta = j / n_samples
        dense_state(F, y, x, h, theta, ix, tmp)
        gj = g(ctx, tmp)
        if crosses(g_prev, gj, direction):
            found, evals = root(g_iterated, ctx, F, y, tmp, (j - 1) / n_samples, theta, g_prev,
                                gj)
            return found, j + evals
        g_prev = gj
    return 2.0, n_samples


@kernel
def fall_after_rise(g, g_iterated, ctx, F, y, x, h, ix, theta_end, n_samples, tmp):
    """For a function ``g(ctx, ·)`` that starts at 0 and is below it at ``theta_end``: θ where it
    falls to zero after rising above it (sampled at ``n_samples`` points up to ``theta_end``,
    located by :func:`root` with ``g_iterated``), or 0 if no sample rises above zero (it fell at
    once). Returns (θ, evaluations)."""
    rose = False
    g_prev = 0.0
    th_prev = 0.0
    for j in range(1, n_samples + 1):
        theta = theta_end * j / n_samples
        dense_state(F, y, x, h, theta, ix, tmp)
        gj = g(ctx, tmp)
        if rose and gj <= 0.0:
            found, evals = root(g_iterated, ctx, F, y, tmp, th_prev, theta, g_prev, gj)
            return found, j + evals
        rose = rose or gj > 0.0
        g_prev = gj
        th_prev = theta
    return 0.0, n_samples
