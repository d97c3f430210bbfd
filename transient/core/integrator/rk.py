"""The Runge–Kutta numerics: one step of an embedded pair, its error norm, the step-size factors,
Hairer's stiffness estimate and the dense output (Hairer, Nørsett & Wanner, *Solving ODEs I*,
§II.4–II.6 and §II.10; *Solving ODEs II*, §IV.2).

One set of functions for every pair in :mod:`.tableaus` (DOP853, DOPRI5), passed as data, and
for every ODE y′ = f(y), passed as a kernel: ``rhs(ctx, y, out)`` writes f(y) into ``out``, with
``ctx`` whatever the derivative needs besides the state (a tuple; the engine's is its Model, the
kernels' variant, the switches and the work array). A kernel passed as an argument is a constant
of the compile: each ``rhs`` compiles its own copy of these functions, with the derivative
inlined where it is inlined (:func:`transient.core.jit.kernel`), so passing it costs nothing at
run time. A non-autonomous problem carries its independent variable as a state component (the
engine's state holds both t and φ); ``ix`` names it, and a step sets it exactly to x + h.

The error control knows the state only through ``control`` (one code per component,
:data:`transient.core.declare.NOT_CONTROLLED` …), which the model declares with its state.
Nothing here knows of events, breakpoints or the engine's bookkeeping. The step, the error norm
and the stiffness estimate run once per step attempt and are inlined into it by LLVM.
"""
from __future__ import annotations

import numpy as np

from ..declare import BY_INCREMENT, NOT_CONTROLLED
from ..jit import kernel

# Step-size control as in SciPy's DOP853 and RK45 (error exponent −1/(q + 1), tab.exponent).
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
PI_BETA = 0.04
#: The least error norm kept for the PI control (a step of zero error would stop its damping).
ERR_OLD_FLOOR = 1e-4


@kernel(inline=True)
def error_norm(tab, K, h, y, y_new, rtol, atol, ix, control, e5, e3):
    """Error norm: DOP853's blend of its 5th- and 3rd-order estimators (Hairer), the RMS norm of
    the one estimator for a pair without a second (``tab.E3 = 0``, DOPRI5), over the components
    ``control`` controls, but the independent variable ``ix`` (which has no error). ``e5``,
    ``e3``: scratch of the state's length, where a state of :data:`STAGEWISE_FROM` components
    or more has the two estimators' combinations of K summed (:func:`combination`).

    A component that accumulates (``BY_INCREMENT``: t in crank angle, φ in time) is scaled by
    its increment over the step, not by its size: relative to |t| the allowed error would grow
    with the run's length and a long run would lose phase for nothing."""
    n = y.shape[0]
    m = tab.n_stages + 1
    stagewise = n >= STAGEWISE_FROM  # (else each component's sums where it is scaled)
    if stagewise:
        combination(tab.E5, K, m, e5)
        combination(tab.E3, K, m, e3)
    err5 = 0.0
    err3 = 0.0
    count = 0
    for i in range(n):
        c = control[i]
        if c == NOT_CONTROLLED or i == ix:
            continue
        count += 1
        if c == BY_INCREMENT:
            sc = atol + rtol * abs(y_new[i] - y[i])
        else:
            sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        if stagewise:
            e5_i = e5[i]
            e3_i = e3[i]
        else:
            e5_i = 0.0
            e3_i = 0.0
            for s in range(m):
                e5_i += K[s, i] * tab.E5[s]
                e3_i += K[s, i] * tab.E3[s]
        err5 += (e5_i / sc) ** 2
        err3 += (e3_i / sc) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / np.sqrt((err5 + 0.01 * err3) * count)


@kernel(inline=True)
def stiffness(tab, K, h, y, ix, control, rtol, atol):
    """Estimate of h·λ over the step (Hairer, *Solving ODEs II*, §IV.2): the last main stage and
    the FSAL stage both sit at the step's end, and ‖f(y₁) − f(y_s)‖/‖y₁ − y_s‖ estimates the
    dominant eigenvalue's modulus; y₁ − y_s = h Σ_j (A[ns, j] − A[ns−1, j]) K_j. Over the
    controlled components, each scaled by atol + rtol·|y| (a state that mixes joules with fuel
    fractions, unscaled, would hide a stiff governor state behind the kinetic energy)."""
    ns = tab.n_stages
    num = 0.0
    den = 0.0
    for i in range(y.shape[0]):
        if control[i] == NOT_CONTROLLED or i == ix:
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
def shrink(tab, err):
    """The factor on the step size after a step rejected with error norm ``err`` > 1."""
    return max(MIN_FACTOR, SAFETY * err ** -tab.exponent)


@kernel(inline=True)
def grow(tab, err, err_old, after_rejection):
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
def accepted_size(tab, err, err_old, h, h_planned, cut, after_rejection):
    """``(h_next, err_old)``: the next step's size after a step of size h accepted with error
    norm ``err`` (the last accepted step's was ``err_old``), and the error to keep for the next
    step's PI control. A step ``cut`` short of the ``h_planned`` (to end on a breakpoint, say)
    says nothing against the step planned: unless it follows a rejection, the next is at least
    that, grown or shrunk by the same factor."""
    factor = grow(tab, err, err_old, after_rejection)
    h_next = h * factor
    if cut and not after_rejection:
        h_next = max(h_next, min(h_planned, h_planned * factor))
    return h_next, max(err, ERR_OLD_FLOOR)


@kernel(inline=True)
def step(tab, rhs, ctx, ix, x, y, f, h, K, y_new, tmp):
    """One Runge–Kutta step of size h from (x, y) with f = y′ = ``rhs(ctx, y)``; K[0] must hold f.

    Leaves the stages in K (K[tab.n_stages] = f(y_new)) and the new state in y_new; the
    independent variable, component ``ix`` (−1: none), exactly x + h there.
    """
    n = y.shape[0]
    ns = tab.n_stages
    # Stage ns is the derivative at the new state (FSAL: row ns of A holds B). One call site,
    # because the derivative is inlined wherever it is called.
    for s in range(1, ns + 1):
        stage_state(tab.A[s], K, s, y, h, tmp)
        if s == ns:
            # The independent variable advances exactly (exact stops on breakpoints).
            if ix >= 0:
                tmp[ix] = x + h
            for i in range(n):
                y_new[i] = tmp[i]
        rhs(ctx, tmp, K[s])


#: The least state size summed stage by stage (:func:`stage_state`); a smaller state is summed
#: component by component, which is faster where the state is less than a vector register or two.
STAGEWISE_FROM = 8


@kernel(inline=True)
def combination(w, K, m, out):
    """out = Σ_{s<m} w_s K_s, each component's sum in the order s = 0, 1, …: stage by stage
    over the whole state from :data:`STAGEWISE_FROM` components on, as :func:`stage_state`
    sums, for fewer component by component."""
    n = out.shape[0]
    if n < STAGEWISE_FROM:
        for i in range(n):
            acc = 0.0
            for s in range(m):
                acc += K[s, i] * w[s]
            out[i] = acc
        return
    w_0 = w[0]
    for i in range(n):
        out[i] = K[0, i] * w_0
    for s in range(1, m):
        w_s = w[s]
        for i in range(n):
            out[i] += K[s, i] * w_s


@kernel(inline=True)
def stage_state(a, K, s, y, h, out):
    """The state of stage s, y + h Σ_{j<s} a_j K_j, into ``out``. Each component's sum is taken
    in the order j = 0, 1, …: from :data:`STAGEWISE_FROM` components on stage by stage over the
    whole state (K's rows are contiguous, so the inner loops vectorise; the last stage's term
    and y in one pass), for fewer component by component (K read down its columns)."""
    n = y.shape[0]
    if n < STAGEWISE_FROM:
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[j] * K[j, i]
            out[i] = y[i] + h * acc
        return
    a_0 = a[0]
    for i in range(n):
        out[i] = a_0 * K[0, i]
    for j in range(1, s - 1):
        a_j = a[j]
        for i in range(n):
            out[i] += a_j * K[j, i]
    if s == 1:
        for i in range(n):
            out[i] = y[i] + h * out[i]
    else:
        a_j = a[s - 1]
        for i in range(n):
            out[i] = y[i] + h * (out[i] + a_j * K[s - 1, i])


@kernel
def dense(tab, rhs, ctx, y, y_new, h, K, F, tmp):
    """Dense-output coefficients F (3 + tab.D rows × n) of the last step, after the extra stages
    (three for DOP853, none for DOPRI5; layout in :mod:`.tableaus`)."""
    n = y.shape[0]
    ns = tab.n_stages
    for s in range(ns + 1, tab.n_ext):
        stage_state(tab.A[s], K, s, y, h, tmp)
        rhs(ctx, tmp, K[s])
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
def dense_eval(F, y, theta, out):
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
def dense_state(F, y, x, h, theta, ix, out):
    """State at fraction θ of the last step (from x, size h), its independent variable ``ix``
    exactly x + θh."""
    dense_eval(F, y, theta, out)
    if ix >= 0:
        out[ix] = x + theta * h
