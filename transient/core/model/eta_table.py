r"""Pairs whose efficiencies are maps over speed and transmitted moment, solved exactly.

A pair with ``model = "table"`` has η_fwd(|ω|, |S|) and η_bwd(|ω|, |S|), S its moment out of the
shaft side reduced to φ (:mod:`.chain`), read bilinearly from a rectangular grid and held at the
grid's edges. With a mode held, pair k delivers h_k(S) = e_k(|S|)·S to its far side, e_k = η_fwd
forward and 1/η_bwd backward, so the chain's equations (:mod:`.chain`)

    S_0 = R_0 − J_0 a,   S_k = R_k − J_k a + h_{k−1}(S_{k−1}),   F(a) = R_n − J_n a + h_{n−1}(S_{n−1}) = 0

no longer give a in closed form: η depends on S and S on a. They are solved exactly at every
evaluation, never lagged from an earlier one.

Existence and uniqueness
------------------------
With x = |S|, h′_k(S) = e + x·de/dx: forward η_fwd + x ∂η_fwd/∂x, backward
(η_bwd − x ∂η_bwd/∂x)/η_bwd². The scene check requires both > 0 on the whole map
(``transient.scene.eta_map``; bilinear, they are linear in x in each cell and convex combinations
over the speed, so the grid's cell ends decide it, and held beyond the edges e' = 0). Then every
h_k is continuous and strictly increasing with h′ ≥ γ for some 0 < γ ≤ 1 (finitely many linear
pieces), so S_k(a) is continuous and strictly decreasing in a, and
F′(a) = −Σ_j J_j Π_{j≤i<n} h′_i ≤ −γⁿ Σ J_j < 0: F has exactly one root. The
same holds for the power-flow map g_k(S) = h_k(S) with the mode given by the sign of Sσ (the two
branches meet at S = 0 with value 0), so the power-flow-consistent mode vector is unique, as for
constant η; :func:`solve_auto` finds it directly, as the root of F with g_k in place of h_k.

The root lies in [−B, B], B = Σ_j c̄_j |R_j| / Σ_j c_j J_j, with c̄_j, c_j the largest and least
Π_{i<j} 1/e_i for e_i in [η_min,i, 1/η_min,i] (the acceleration of a chain with constant η* is
Σ c_j R_j / Σ c_j J_j, and the root is one, at the η* of its own S).

The solve
---------
Newton's method on F with the exact derivative, from the ideal chain's a, kept inside the
bracket [lo, hi] that every evaluation narrows (F is decreasing: F > 0 moves lo up, F < 0 hi
down), with a bisection where a Newton step would leave it. It stops when the correction is
within :data:`ROUNDING` (|a| + B): B/|F′| bounds the rounding of F's terms over its slope, so
this is the rounding level of a. Then η*_k = e_k(|S_k|) at the root, and a and S_k are computed
once more by :func:`.chain.chain_solve` with these η*: they satisfy the chain's equations with
those η* to rounding (so the losses (1 − η*_k) S_k ω close the work–energy balance as for
constant η), and a constant map gives the constant-η path's results bit for bit. After
:data:`MAX_ITER` evaluations without meeting the criterion (never, for a map the scene check
accepts), a is NaN: the run stops on a non-finite derivative with its time, angle and state.

All arrays are the Model's ``et_*`` fields, passed one by one (a call copies a whole Model).
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from .chain import chain_solve

#: Newton's stopping level, in units of |a| + B (module docstring): a few ulps.
ROUNDING = 4.0 * np.finfo(np.float64).eps
#: Evaluations of F before the solve gives up (Newton needs a handful; bisection of [−B, B] to
#: ROUNDING alone would need about 55).
MAX_ITER = 100

#: Directions of a pair's map (second index of ``et_eta``).
FORWARD, BACKWARD = 0, 1


@kernel(inline=True)
def _cell(axis, n, x):
    """(i, t, inside): the cell axis[i] ≤ x ≤ axis[i + 1] holding x (held to the axis' range),
    t the fraction of x across it, ``inside`` whether x lies strictly within the range (where the
    map has a slope in x)."""
    if n == 1 or x <= axis[0]:
        return 0, 0.0, False
    if x >= axis[n - 1]:
        return n - 2, 1.0, False
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if axis[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo, (x - axis[lo]) / (axis[lo + 1] - axis[lo]), True


@kernel(inline=True)
def lookup(speed, torque, size, eta, k, d, w_abs, x):
    """(η, ∂η/∂x) of pair k's map ``d`` (FORWARD, BACKWARD) at speed |ω| = ``w_abs`` and
    x = |S|: bilinear inside the grid, held at its edges (∂η/∂x = 0 there)."""
    nw, ns = size[k, 0], size[k, 1]
    i, u, _ = _cell(speed[k], nw, w_abs)
    j, v, inside = _cell(torque[k], ns, x)
    i1 = i + 1 if nw > 1 else i
    j1 = j + 1 if ns > 1 else j
    e00, e01 = eta[k, d, i, j], eta[k, d, i, j1]
    e10, e11 = eta[k, d, i1, j], eta[k, d, i1, j1]
    lo = e00 + v * (e01 - e00)
    hi = e10 + v * (e11 - e10)
    slope = 0.0
    if inside:
        slope = ((1.0 - u) * (e01 - e00) + u * (e11 - e10)) / (torque[k, j1] - torque[k, j])
    return lo + u * (hi - lo), slope


@kernel(inline=True)
def transfer(speed, torque, size, eta, k, backward, w_abs, s):
    """(e, h′): pair k's η* = e(|S|) (η_fwd, or 1/η_bwd ``backward``) at S = ``s`` and the slope
    of h(S) = e·S, e + |S| de/d|S|."""
    x = abs(s)
    if backward:
        eb, db = lookup(speed, torque, size, eta, k, BACKWARD, w_abs, x)
        e = 1.0 / eb
        return e, e - x * db * e * e
    ef, df = lookup(speed, torque, size, eta, k, FORWARD, w_abs, x)
    return ef, ef + x * df


@kernel(inline=True)
def _residual(J, dJ, M, w, sigma, mask, auto, speed, torque, size, eta, a, eta_out, S_out):
    """(F(a), F′(a)) of the chain (module docstring); fills S_k and η*_k at a. With ``auto`` the
    mode of pair k follows the sign of S_k σ (power flow), else bit k of ``mask``."""
    n = eta_out.shape[0]
    half_w2 = 0.5 * w * w
    w_abs = abs(w)
    prev = 0.0
    dprev = 0.0
    for k in range(n):
        s = M[k] - dJ[k] * half_w2 - J[k] * a + prev
        ds = dprev - J[k]
        backward = s * sigma < 0.0 if auto else ((mask >> k) & 1) == 1
        e, dh = transfer(speed, torque, size, eta, k, backward, w_abs, s)
        S_out[k] = s
        eta_out[k] = e
        prev = e * s
        dprev = dh * ds
    return M[n] - dJ[n] * half_w2 - J[n] * a + prev, dprev - J[n]


@kernel
def _solve(J, dJ, M, w, sigma, mask, auto, speed, torque, size, eta, eta_min, eta_out, S_out):
    """a of the chain with mapped efficiencies (module docstring); fills η*_k and S_k."""
    n = eta_out.shape[0]
    half_w2 = 0.5 * w * w
    # the bracket [−B, B] and the ideal chain's a, the start
    c_hi = 1.0
    c_lo = 1.0
    num = 0.0
    den = 0.0
    r_sum = 0.0
    j_sum = 0.0
    for j in range(n + 1):
        if j > 0:
            c_hi /= eta_min[j - 1]
            c_lo *= eta_min[j - 1]
        r = M[j] - dJ[j] * half_w2
        num += c_hi * abs(r)
        den += c_lo * J[j]
        r_sum += r
        j_sum += J[j]
    bound = num / den
    lo = -bound
    hi = bound
    a = min(max(r_sum / j_sum, lo), hi)
    done = False
    for _ in range(MAX_ITER):
        f, df = _residual(J, dJ, M, w, sigma, mask, auto, speed, torque, size, eta, a,
                          eta_out, S_out)
        if not (np.isfinite(f) and np.isfinite(df)):
            break
        if f == 0.0:
            done = True
            break
        if f > 0.0:
            lo = a
        else:
            hi = a
        nxt = a - f / df if df < 0.0 else np.nan
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        step = nxt - a
        a = nxt
        if abs(step) <= ROUNDING * (abs(a) + bound):
            _residual(J, dJ, M, w, sigma, mask, auto, speed, torque, size, eta, a, eta_out,
                      S_out)
            done = True
            break
    if not done:
        for k in range(n):
            eta_out[k] = np.nan
            S_out[k] = np.nan
        return np.nan
    # the chain once more at the η* of the root's own S (bit for bit the constant-η path for a
    # constant map)
    return chain_solve(J, dJ, M, eta_out, w, S_out)


@kernel
def solve_held(J, dJ, M, w, modes, speed, torque, size, eta, eta_min, eta_out, S_out):
    """φ̈ with pair k's mode held by bit k of ``modes`` (set: backward); fills η*_k and S_k.

    Shapes as :func:`.chain.chain_solve`; ``speed``, ``torque``, ``size``, ``eta``, ``eta_min``:
    the Model's ``et_*`` fields. NaN if the solve fails (module docstring).
    """
    return _solve(J, dJ, M, w, 1.0, modes, False, speed, torque, size, eta, eta_min, eta_out,
                  S_out)


@kernel
def solve_auto(J, dJ, M, w, sigma, speed, torque, size, eta, eta_min, eta_out, S_out):
    """φ̈ with every pair in the mode its transmitted power gives (S_k σ ≥ 0 forward), the unique
    power-flow-consistent solution (module docstring) for the direction σ = ±1."""
    return _solve(J, dJ, M, w, sigma, 0, True, speed, torque, size, eta, eta_min, eta_out, S_out)


@kernel
def invert(speed, torque, size, eta, eta_min, k, backward, w_abs, received):
    """(S, η*) with h_k(S) = e_k(|S|)·S = ``received``: the moment pair k must take out of its
    shaft side for its far side to receive ``received`` (inverse dynamics).

    x = |S| solves x·e(x) = |received|, increasing in x (module docstring), so sign S =
    sign received and x lies in [|received| η_min, |received|/η_min]; Newton's method kept in
    that bracket, stopping within :data:`ROUNDING` of its upper end. Then S = received/η* at
    the root's η* (bit for bit the constant-η path for a constant map); NaN if it fails.
    """
    t = abs(received)
    lo = t * eta_min[k]
    hi = t / eta_min[k]
    tol = ROUNDING * hi
    x = min(max(t, lo), hi)
    e = 1.0
    done = t == 0.0
    for _ in range(MAX_ITER):
        if done:
            break
        e, dh = transfer(speed, torque, size, eta, k, backward, w_abs, x)
        f = e * x - t
        if not (np.isfinite(f) and np.isfinite(dh)):
            break
        if f == 0.0:
            done = True
            break
        if f > 0.0:
            hi = x
        else:
            lo = x
        nxt = x - f / dh if dh > 0.0 else np.nan
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        step = nxt - x
        x = nxt
        if abs(step) <= tol:
            done = True
    if not done:
        return np.nan, np.nan
    e, _ = transfer(speed, torque, size, eta, k, backward, w_abs, x)
    return received / e, e
