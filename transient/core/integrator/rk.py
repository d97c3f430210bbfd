"""The Runge–Kutta numerics of the stepper: one step of an embedded pair, its error norm, the
step-size factors, Hairer's stiffness estimate and the dense output (Hairer, Nørsett & Wanner,
*Solving ODEs I*, §II.4–II.6 and §II.10; *Solving ODEs II*, §IV.2).

One set of functions for every pair in :mod:`.tableaus` (DOP853, DOPRI5), passed as data. They
know the state vector's layout only as far as the error control needs it (which components are
controlled and how the accumulating ones are scaled), and nothing of events or of the stepper's
bookkeeping, which :mod:`~transient.core.stepper` keeps. The step, the error norm and the stiffness estimate
run once per step attempt and are inlined into it by LLVM: as calls they would copy the Model's
flattened fields onto the stack (:func:`transient.core.jit.kernel`).
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel

from ..model.layout import N_DYNAMIC, PHI, T
from ..model.rhs import derivative

# Step-size control as in SciPy's DOP853 and RK45 (error exponent −1/(q + 1), tab.exponent).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
PI_BETA = 0.04


@kernel(inline=True)
def _controlled(i, ix, g0, g1, c0):
    """Whether state component i is error-controlled: the dynamics' (but the independent
    variable ``ix``), the governor's y[g0:g1] and the cylinder pressures y[c0:]. The work
    integrals do not feed back (they follow the dynamics' steps) and the latched fuels are
    constant."""
    return i != ix and (i < N_DYNAMIC or g0 <= i < g1 or i >= c0)


@kernel(inline=True)
def _error_norm(tab, K, h, y, y_new, rtol, atol, ix, g0, g1, c0):
    """Error norm: DOP853's blend of its 5th- and 3rd-order estimators (Hairer), the RMS norm of
    the one estimator for a pair without a second (``tab.E3 = 0``, DOPRI5), over the components
    :func:`_controlled` names.

    The accumulating components (t in crank angle, φ in time) are scaled by their increment over
    the step, not by their size: relative to |t| the allowed error would grow with the run's length
    and a long run would lose phase for nothing. The independent variable ``ix`` has no error.
    """
    n = y.shape[0]
    err5 = 0.0
    err3 = 0.0
    for i in range(n):
        if not _controlled(i, ix, g0, g1, c0):
            continue
        if i == PHI or i == T:
            sc = atol + rtol * abs(y_new[i] - y[i])
        else:
            sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        e5 = 0.0
        e3 = 0.0
        for s in range(tab.n_stages + 1):
            e5 += K[s, i] * tab.E5[s]
            e3 += K[s, i] * tab.E3[s]
        err5 += (e5 / sc) ** 2
        err3 += (e3 / sc) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / np.sqrt((err5 + 0.01 * err3) * (N_DYNAMIC - 1 + g1 - g0 + n - c0))


@kernel(inline=True)
def _stiffness(tab, K, h, y, ix, g0, g1, c0, rtol, atol):
    """Estimate of h·λ over the step (Hairer, *Solving ODEs II*, §IV.2): the last main stage and
    the FSAL stage both sit at the step's end, and ‖f(y₁) − f(y_s)‖/‖y₁ − y_s‖ estimates the
    dominant eigenvalue's modulus; y₁ − y_s = h Σ_j (A[ns, j] − A[ns−1, j]) K_j. Over the
    dynamics' components and the governor's states, each scaled as in the error norm (the
    state mixes joules with fuel fractions: unscaled, a stiff governor state would be hidden
    behind the kinetic energy)."""
    ns = tab.n_stages
    num = 0.0
    den = 0.0
    for i in range(y.shape[0]):
        if not _controlled(i, ix, g0, g1, c0):
            continue
        sc = atol + rtol * abs(y[i])
        dy = 0.0
        for j in range(ns):
            dy += (tab.A[ns, j] - tab.A[ns - 1, j]) * K[j, i]
        num += ((K[ns, i] - K[ns - 1, i]) / sc) ** 2
        den += (h * dy / sc) ** 2
    if den == 0.0:
        return 0.0
    return abs(h) * np.sqrt(num / den)


@kernel(inline=True)
def _shrink(tab, err):
    """The factor on the step size after a step rejected with error norm ``err`` > 1."""
    return max(MIN_FACTOR, SAFETY * err ** -tab.exponent)


@kernel(inline=True)
def _grow(tab, err, err_old, after_rejection):
    """The factor on the step size after a step accepted with error norm ``err``; ``err_old`` is
    the last accepted step's.

    PI control (Gustafsson; Hairer's DOPRI5 with β): the last accepted error damps the step
    size's response to an estimate that happens to be small. No growth right after a rejection
    (Hairer's DOPRI codes, SciPy): else the step size oscillates between growing past what the
    error allows and being cut back."""
    e = max(err, 1e-12)
    factor = min(MAX_FACTOR, SAFETY * e ** -(tab.exponent - 0.75 * PI_BETA) * err_old ** PI_BETA)
    if after_rejection:
        factor = min(factor, 1.0)
    return factor


@kernel(inline=True)
def _step(tab, m, extras, angle_mode, x, y, f, h, sel, sw, K, y_new, tmp, wk):
    """One Runge–Kutta step of size h from (x, y) with f = y′; K[0] must hold f.

    Leaves the stages in K (K[tab.n_stages] = f(y_new)) and the new state in y_new.
    """
    n = y.shape[0]
    ns = tab.n_stages
    # Stage ns is the derivative at the new state (FSAL: row ns of A holds B). One call site,
    # because ``rhs.derivative`` is inlined wherever it is called.
    for s in range(1, ns + 1):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += tab.A[s, j] * K[j, i]
            tmp[i] = y[i] + h * acc
        if s == ns:
            # The independent variable advances exactly (exact stops on breakpoints).
            tmp[PHI if angle_mode else T] = x + h
            for i in range(n):
                y_new[i] = tmp[i]
        derivative(m, extras, angle_mode, tmp, sel, sw, wk, K[s])


@kernel
def _dense(tab, m, extras, angle_mode, y, y_new, h, sel, sw, K, F, tmp, wk):
    """Dense-output coefficients F (3 + tab.D rows × n) of the last step, after the extra stages
    (three for DOP853, none for DOPRI5; layout in :mod:`.tableaus`)."""
    n = y.shape[0]
    ns = tab.n_stages
    for s in range(ns + 1, tab.n_ext):
        a = tab.A[s]
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[j] * K[j, i]
            tmp[i] = y[i] + h * acc
        derivative(m, extras, angle_mode, tmp, sel, sw, wk, K[s])
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[ns, i] + K[0, i])
        for r in range(tab.D.shape[0]):
            acc = 0.0
            for j in range(tab.n_ext):
                acc += tab.D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@kernel
def _dense_eval(F, y, theta, out):
    """State at fraction θ ∈ [0, 1] of the last step."""
    n = y.shape[0]
    for i in range(n):
        acc = 0.0
        for r in range(F.shape[0] - 1, -1, -1):
            acc += F[r, i]
            if r % 2 == 0:
                acc *= theta
            else:
                acc *= 1.0 - theta
        out[i] = y[i] + acc


@kernel(inline=True)
def _dense_state(F, y, x, h, theta, ix, out):
    """State at fraction θ of the last step (from x, size h), its independent variable ``ix``
    exactly x + θh."""
    _dense_eval(F, y, theta, out)
    out[ix] = x + theta * h
