"""A plain adaptive driver of the integrator's kernels for an ODE y′ = f(y): steps of an embedded
pair (:mod:`.rk`) or of the W-method (:mod:`.rosenbrock`) under its error norm and PI step-size
control, the dense output at requested
abscissae, and one optional terminal event located on it (:mod:`~transient.core.integrator.roots`).

It is the integrator on its own, with nothing of the engine: the tests run it on closed-form
problems (a harmonic oscillator, SciPy's rational test problem), so that the numerics the
engine's stepper (:func:`transient.core.stepper.loop.advance`) is built from are checked apart
from any model. The stepper drives the same kernels, with the engine's segments between
breakpoints, its events and its output grid around them.
"""
from __future__ import annotations

import numpy as np

from ..jit import compiled
from .rk import accepted_size, dense, dense_state, error_norm, shrink
from .roots import crosses, root
from .rosenbrock import method_step

#: Consecutive step attempts with a non-finite result before the solve gives up.
MAX_NONFINITE = 30


@compiled
def solve(tab, rhs, ctx, x0, y0, x_end, h0, rtol, atol, control, ix, x_out, g, direction, jac,
          band):
    """Integrate y′ = ``rhs(ctx, y)`` from (x0, y0) towards x_end > x0 with the pair ``tab``,
    starting with the step ``h0``; the error control of each component as ``control`` says
    (:data:`transient.core.declare.BY_SIZE` …), the independent variable component ``ix`` (−1:
    the state does not hold it).

    ``x_out``: increasing abscissae where the dense output is sampled. ``g``: an event function
    ``g(ctx, y)``, or None; the solve stops where it first crosses zero in ``direction`` (+1
    rising, −1 falling, 0 either). ``jac``, ``band``: a W-method's Jacobian kernel and the
    storage of its band (:mod:`.rosenbrock`), None and None for an explicit pair.

    Returns ``(x, y, y_out, n_out, n_steps, n_rejected, n_rhs, status)``: where the solve
    stopped and the state there, the samples (rows of ``y_out``; the first ``n_out`` are
    filled), the steps accepted and rejected, the derivative's evaluations, and ``status`` 0 at
    x_end, 1 at the event, −1 after MAX_NONFINITE non-finite attempts in a row.
    """
    n = y0.shape[0]
    ns = tab.n_stages
    K = np.empty((tab.n_ext, n))
    F = np.empty((3 + tab.D.shape[0], n))
    y = y0.copy()
    y_new = np.empty(n)
    tmp = np.empty(n)
    f = np.empty(n)
    e5 = np.empty(n)
    e3 = np.empty(n)
    y_out = np.full((x_out.shape[0], n), np.nan)
    rhs(ctx, y, f)
    n_rhs = 1
    x = x0
    h = h0
    err_old = 1e-4
    rejected = False
    n_steps = n_rejected = n_bad = j = 0
    status = 0
    while x < x_end:
        h_planned = h
        cut = x + h >= x_end
        if cut:
            h = x_end - x
        for i in range(n):
            K[0, i] = f[i]
        method_step(tab, rhs, jac, ctx, ix, x, y, f, h, K, y_new, tmp, band)
        n_rhs += ns
        err = error_norm(tab, K, h, y, y_new, rtol, atol, ix, control, e5, e3)
        if not (np.isfinite(err) and np.all(np.isfinite(y_new))):
            n_bad += 1
            if n_bad > MAX_NONFINITE:
                status = -1
                break
            h = 0.2 * h
            continue
        n_bad = 0
        if err > 1.0:
            h = h * shrink(tab, err)
            rejected = True
            n_rejected += 1
            continue
        h_next, err_old = accepted_size(tab, err, err_old, h, h_planned, cut, rejected)
        rejected = False
        n_steps += 1
        dense_ready = False
        hit = False
        theta = 1.0
        if g is not None:
            ga = g(ctx, y)
            gb = g(ctx, y_new)
            hit = crosses(ga, gb, direction)
            if hit:
                dense(tab, rhs, ctx, y, y_new, h, K, F, tmp)
                n_rhs += tab.n_ext - ns - 1
                dense_ready = True
                theta = root(g, ctx, F, y, tmp, 0.0, 1.0, ga, gb)[0]
        x_stop = x + theta * h
        while j < x_out.shape[0] and x_out[j] <= x_stop:
            if not dense_ready:
                dense(tab, rhs, ctx, y, y_new, h, K, F, tmp)
                n_rhs += tab.n_ext - ns - 1
                dense_ready = True
            dense_state(F, y, x, h, (x_out[j] - x) / h, ix, y_out[j])
            j += 1
        if hit:
            dense_state(F, y, x, h, theta, ix, tmp)
            for i in range(n):
                y[i] = tmp[i]
            x = x_stop
            status = 1
            break
        for i in range(n):
            y[i] = y_new[i]
            f[i] = K[ns, i]
        x = x_end if cut else x + h
        h = h_next
    return x, y, y_out, j, n_steps, n_rejected, n_rhs, status
