"""The elastic shaft line's Jacobian for the W-method (:mod:`transient.core.integrator.rosenbrock`;
theory, *Stiff lines: the W-method*, (T11)–(T12)): the part of ∂f/∂y that makes the line
stiff, its elements' stiffness and damping couplings of the twists and energies (speeds in time)
of the dofs other than the reference, in band storage over the line's block of the state.

What it leaves out (a W-method keeps its order with any matrix in J's place): the reference's
row and column (φ, t, K_ref: the rigid-body motion is not stiff), the dependence of the applied
moments on the state (gas, load, governor), in time the inertias' on the angles (J_d(θ_d); in
crank angle ω_d = √(2K_d/J_d(θ_d)) carries it, and it is kept), and the absolute damping's
coupling of different dofs (a rank-one term over the whole line, which would fill the band); its
diagonal is kept. So on a line without absolute damping it is exact entry for entry, but for a
cylinder's station's rate of energy (speed) against its own twist (the gas moment's and, in
time, the inertia's angle dependence) and the load's station's against its own speed
(``tests/unit/test_line_jacobian.py`` checks it against central differences of the compiled
derivative).

The band: dof d (d ≠ ref) holds the states 2p, 2p + 1 of the block, p its place among the
non-reference dofs; an element between places p and p′ couples states up to 2|p − p′| + 1
apart. :func:`line_band` gives the half-bandwidth kb over the element table; the line's own dof
order (stations, each followed by its dampers' rings, then the driven inertia;
:class:`transient.shaft.line.ShaftLine`) keeps it at 3 or 5 whatever the line's length, so a
factorisation is O(N).
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from .elastic import line_speeds
from .layout import (
    EL_C,
    EL_I,
    EL_J,
    EL_K,
    EL_R,
    LD_ABS,
    LD_GEAR,
    LD_WEIGHT,
    LM_DOFS,
    LM_REF,
    WK_LINE_DJ,
    WK_LINE_J,
    WK_LINE_OMEGA,
    line_dofs,
    line_index,
)
from .shaft import line_inertias, line_parts, twist_index


def line_band(line) -> tuple[int, int]:
    """(rows, kb) of the band of the Model's packed ``line``: the line's states (twice the dofs
    but the reference) and the half-bandwidth its elements need (at least 1: a dof's twist and
    energy), at most rows − 1 (a dense matrix in band storage)."""
    n = int(line[0, LM_DOFS])
    if n == 0:
        return 0, 0
    ref = int(line[0, LM_REF])
    elements = line_parts.py_func(line)[2]  # (the kernel's Python, on the Model's array)
    kb = 1
    for i, j in elements[:, [EL_I, EL_J]].astype(int):
        if i != ref and j != ref:
            kb = max(kb, 2 * abs(_place(i, ref) - _place(j, ref)) + 1)
    rows = 2 * (n - 1)
    return rows, min(kb, max(rows - 1, 0))


def _place(d: int, ref: int) -> int:
    return d if d < ref else d - 1


@kernel(inline=True)
def _add(band, kb, r, c, value):
    """J[r, c] += value, where the band holds it (an entry outside it is left out, which a
    W-method allows)."""
    if abs(c - r) <= kb:
        band[r, c - r + kb] += value


@kernel(inline=True)
def _speed_partials(angle_mode, J, dJ, w):
    """(∂ω/∂K, ∂ω/∂q) of a dof's speed through its states: ω = √(2K/J(φ + q)) in crank angle,
    (1/(Jω), −ωJ′/(2J)); the state itself in time, (1, 0)."""
    if angle_mode:
        return 1.0 / (J * w), -0.5 * w * dJ / J
    return 1.0, 0.0


@kernel(inline=True)
def line_jacobian(m, angle_mode, y, f0, wk, band):
    """The line's Jacobian at ``y`` into ``band`` (the derivative there ``f0``); returns the
    state index of the block's first component. In crank angle (T11), time (T12)."""
    lo = line_index(m)
    for r in range(band.shape[0]):
        for c in range(band.shape[1]):
            band[r, c] = 0.0
    if line_dofs(m) > 0:
        line_inertias(m, y, wk, True)
        line_speeds(m, angle_mode, y, wk)
        _own_terms(m, angle_mode, y, f0, wk, lo, band)
        _element_terms(m, angle_mode, wk, lo, band)
    return lo


@kernel(inline=True)
def _rate_factor(angle_mode, J, w, w_ref):
    """The factor from a torque on a dof to its energy's rate in crank angle, ω_d/ω_ref, or to
    its speed's in time, 1/J_d."""
    return w / w_ref if angle_mode else 1.0 / J


@kernel(inline=True)
def _own_terms(m, angle_mode, y, f0, wk, lo, band):
    """Each dof's own block: its twist's rate, the absolute damping's diagonal and the
    dependence of the rate of its energy on its own speed (after
    :func:`~transient.core.model.elastic.line_speeds`)."""
    n = line_dofs(m)
    kb = (band.shape[1] - 1) // 2
    dofs = line_parts(m.line)[1]
    ref = np.int64(m.line[0, LM_REF])
    J, dJ, w = wk[WK_LINE_J, :n], wk[WK_LINE_DJ, :n], wk[WK_LINE_OMEGA, :n]
    total = 0.0
    absolute = 0.0
    for d in range(n):
        total += dofs[d, LD_WEIGHT]
        absolute += dofs[d, LD_ABS]
    for d in range(n):
        if d == ref:
            continue
        r = twist_index(m, d) - lo
        g = dofs[d, LD_GEAR]
        dw, dwq = _speed_partials(angle_mode, J[d], dJ[d], w[d])
        # the twist's rate g_d ω_d/ω_ref − 1 (g_d ω_d − ω_ref in time)
        if angle_mode:
            band[r, kb] = g * dwq / w[ref]
            band[r, kb + 1] = g * dw / w[ref]
        else:
            band[r, kb + 1] = g
        # the absolute damping's diagonal (T3): ∂A_d/∂ω_d
        share = dofs[d, LD_WEIGHT] / total
        a = dofs[d, LD_ABS]
        dA = g * g * (-a + 2.0 * a * share - share * share * absolute)
        factor = _rate_factor(angle_mode, J[d], w[d], w[ref])
        band[r + 1, kb - 1] = factor * dA * dwq
        band[r + 1, kb] = factor * dA * dw
        if angle_mode:
            # (M_d + T_d)·∂(ω_d/ω_ref)/∂y = (dK_d/dφ)/ω_d · ∂ω_d/∂y
            rate = f0[lo + r + 1] / w[d]
            band[r + 1, kb - 1] += rate * dwq
            band[r + 1, kb] += rate * dw
        else:
            # −½J′_d ω_d²/J_d, its ω_d-derivative
            band[r + 1, kb] -= dJ[d] * w[d] / J[d]


@kernel(inline=True)
def _element_terms(m, angle_mode, wk, lo, band):
    """The elements' couplings: T_i −= τ and T_j += rτ with τ = k(θ_i − rθ_j) + c(ω_i − rω_j),
    so ∂T_a/∂θ_b = −s_a s_b k and ∂T_a/∂ω_b = −s_a s_b c (s_i = 1, s_j = −r), into the energy
    (speed) rows of a and b against the states of a and b (after
    :func:`~transient.core.model.elastic.line_speeds`)."""
    n = line_dofs(m)
    kb = (band.shape[1] - 1) // 2
    elements = line_parts(m.line)[2]
    ref = np.int64(m.line[0, LM_REF])
    J, dJ, w = wk[WK_LINE_J, :n], wk[WK_LINE_DJ, :n], wk[WK_LINE_OMEGA, :n]
    for e in range(elements.shape[0]):
        i = np.int64(elements[e, EL_I])
        j = np.int64(elements[e, EL_J])
        ratio = elements[e, EL_R]
        k = elements[e, EL_K]
        c = elements[e, EL_C]
        for side_a in range(2):
            a = i if side_a == 0 else j
            if a == ref:
                continue
            sa = 1.0 if side_a == 0 else -ratio
            ra = twist_index(m, a) - lo + 1
            factor = _rate_factor(angle_mode, J[a], w[a], w[ref])
            for side_b in range(2):
                b = i if side_b == 0 else j
                if b == ref:
                    continue
                sb = 1.0 if side_b == 0 else -ratio
                cb = twist_index(m, b) - lo
                dw, dwq = _speed_partials(angle_mode, J[b], dJ[b], w[b])
                _add(band, kb, ra, cb, -factor * sa * sb * (k + c * dwq))
                _add(band, kb, ra, cb + 1, -factor * sa * sb * c * dw)


@kernel(inline=True)
def model_jacobian(ctx, y, f0, band):
    """The model's Jacobian in the W-method's form (``jac(ctx, y, f0, band)``, ctx as the
    derivative's, :func:`.rhs.model_rhs`): the shaft line's."""
    m, extras, angle_mode, sel, sw, wk = ctx
    return line_jacobian(m, angle_mode, y, f0, wk, band)
