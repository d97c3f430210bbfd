"""A linearly implicit Rosenbrock–W method for stiff problems: ROS34PW2 (Rang & Angermann, *BIT*
45 (2005) 761–787), one banded LU factorisation per step attempt (docs/theory.md, *The elastic
shaft line*, *Stiff lines: the W-method*).

A Rosenbrock method solves, per stage, a linear system with W = I − hγJ in place of the Newton
iterations of an implicit Runge–Kutta method; a **W-method** keeps its order with any matrix in
place of the Jacobian J (Hairer & Wanner, *Solving ODEs II*, §IV.7, Table 7.3's conditions with
J and the matrix told apart), so a model may give only the part of J that makes it stiff (the
shaft line's couplings, :mod:`transient.core.model.line_jacobian`). ROS34PW2 has 4 stages, order
3 for any such matrix, an embedded order-2 solution for the error estimate, and is L-stable and
stiffly accurate (its last stage is the solution: a very stiff component is damped, not echoed).
Its coefficients are the paper's (α, Γ, b, b̂), as PETSc registers them (``TSROSWRA34PW2``);
``tests/unit/test_rosenbrock.py`` checks them against the order conditions.

The step in the form of Hairer & Wanner's ``ros4.f`` (their (7.4′)), with u_i = Σ_{j≤i} γ_ij k_j:

    (I − hγJ) u_i / h = γ f(y + Σ_{j<i} a_ij u_j) + γ Σ_{j<i} c_ij u_j / h,
    y₁ = y + Σ m_j u_j,   a = αΓ⁻¹,  C = diag(1/γ) − Γ⁻¹,  m = bΓ⁻¹,

which needs no product of J with a vector. The tableau (:class:`WTableau`) has the fields the
explicit pairs' shared kernels read (:mod:`.rk`), laid out so that they serve it unchanged: the
stage array K holds f(y) in row 0, u_i/h in rows 1 … 4 and f(y₁) in row 5 (``n_stages`` = 5, the
FSAL row); the error estimate h Σ (m_j − m̂_j) u_j/h is ``E5`` over those rows; with no ``D``
rows the dense output is the cubic Hermite interpolant of y, y₁, f(y), f(y₁), third order like
the method; ``stiff_bound`` is infinite (Hairer's stiffness test is for explicit pairs). A
step attempt costs s = 4 evaluations of the derivative (the first stage's is f(y), carried
over) and the Jacobian's, which a count of evaluations by ``n_stages`` takes for a fifth.

The model's part, passed as kernels like the derivative: ``jac(ctx, y, f0, band)`` writes its
J over one block of the state, components ``lo … lo + nb − 1`` (nb the rows of ``band``), in
band storage — J[r, c] at ``band[r, c − r + kb]``, kb = (columns − 1)/2 — and returns ``lo``;
outside the block W is the identity. The LU factorisation without pivoting (W is close to I for
small h, and I plus a positive semi-definite form for an elastic line) costs O(nb·kb²): O(N) in
the line's length.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import kernel
from .rk import step

#: The least |pivot| of W = I − hγJ's factorisation (W is I plus hγ times the line's
#: couplings): one smaller means hγ J has an eigenvalue near 1, the step far too long for the
#: linearisation, and the attempt is retaken shorter as a non-finite one is.
MIN_PIVOT = 1e-6

WTableau = namedtuple("WTableau", ["gamma", "a", "c", "m", "A", "E5", "E3", "D", "n_stages",
                                   "n_ext", "exponent", "order", "stiff_bound"])


def ros34pw2_coefficients() -> tuple:
    """(γ, α, Γ, b, b̂) of ROS34PW2 (Rang & Angermann 2005; Γ with γ on its diagonal)."""
    g = 4.3586652150845900e-01
    alpha = np.array([[0.0, 0.0, 0.0, 0.0],
                      [8.7173304301691801e-01, 0.0, 0.0, 0.0],
                      [8.4457060015369423e-01, -1.1299064236484185e-01, 0.0, 0.0],
                      [0.0, 0.0, 1.0, 0.0]])
    Gamma = np.array([[g, 0.0, 0.0, 0.0],
                      [-8.7173304301691801e-01, g, 0.0, 0.0],
                      [-9.0338057013044082e-01, 5.4180672388095326e-02, g, 0.0],
                      [2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01,
                       g]])
    b = np.array([2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351020e+00, g])
    b_hat = np.array([3.7810903145819369e-01, -9.6042292212423178e-02, 0.5,
                      2.1793326075422950e-01])
    return g, alpha, Gamma, b, b_hat


def w_tableau(gamma, alpha, Gamma, b, b_hat, order: int) -> WTableau:
    """The stepper's tableau of a W-method given as (γ, α, Γ, b, b̂), in the transformed form
    (a, C, m) of the module's docstring; ``order`` the method's, its estimate's one less."""
    s = b.shape[0]
    inv = np.linalg.inv(Gamma)
    a = alpha @ inv
    c = np.diag(1.0 / np.diag(Gamma)) - inv
    m = b @ inv
    m_hat = b_hat @ inv
    n_stages, n_ext = s + 1, s + 2
    E5 = np.zeros(n_stages + 1)
    E5[1:s + 1] = m - m_hat
    return WTableau(gamma=float(gamma), a=a, c=c, m=m, A=np.zeros((n_ext, n_ext)), E5=E5,
                    E3=np.zeros(n_stages + 1), D=np.zeros((0, n_ext)), n_stages=n_stages,
                    n_ext=n_ext, exponent=1.0 / order, order=order, stiff_bound=np.inf)


def ros34pw2() -> WTableau:
    return w_tableau(*ros34pw2_coefficients(), order=3)


def is_w_method(tab) -> bool:
    """Whether ``tab`` is a W-method's tableau (its stepper takes a Jacobian and a band)."""
    return isinstance(tab, WTableau)


@kernel(inline=True)
def band_factor(band, hg):
    """W = I − hg·J in place of J (band storage), then its LU factorisation without pivoting,
    in place (L's unit diagonal implied). Returns False if a pivot is below MIN_PIVOT."""
    nb = band.shape[0]
    kb = (band.shape[1] - 1) // 2
    for i in range(nb):
        for d in range(band.shape[1]):
            band[i, d] *= -hg
        band[i, kb] += 1.0
    for k in range(nb):
        p = band[k, kb]
        if not abs(p) >= MIN_PIVOT:
            return False
        for i in range(k + 1, min(nb, k + kb + 1)):
            lik = band[i, k - i + kb] / p
            band[i, k - i + kb] = lik
            if lik != 0.0:
                for j in range(k + 1, min(nb, k + kb + 1)):
                    band[i, j - i + kb] -= lik * band[k, j - k + kb]
    return True


@kernel(inline=True)
def band_solve(band, lo, v):
    """v[lo : lo + nb] ← W⁻¹ v[lo : lo + nb] with W's LU from :func:`band_factor`."""
    nb = band.shape[0]
    kb = (band.shape[1] - 1) // 2
    for i in range(nb):
        acc = v[lo + i]
        for j in range(max(0, i - kb), i):
            acc -= band[i, j - i + kb] * v[lo + j]
        v[lo + i] = acc
    for i in range(nb - 1, -1, -1):
        acc = v[lo + i]
        for j in range(i + 1, min(nb, i + kb + 1)):
            acc -= band[i, j - i + kb] * v[lo + j]
        v[lo + i] = acc / band[i, kb]


@kernel(inline=True)
def w_step(tab, rhs, jac, ctx, ix, x, y, h, K, y_new, tmp, band):
    """One step of the W-method ``tab`` of size h from (x, y); K[0] must hold f(y).

    Leaves u_i/h in K[1 … s], the new state in y_new (its independent variable ``ix`` exactly
    x + h) and f(y_new) in K[s + 1]. A pivot of W below MIN_PIVOT leaves y_new non-finite, and
    the stages undone: the caller retakes the step shorter."""
    n = y.shape[0]
    s = tab.m.shape[0]
    lo = jac(ctx, y, K[0], band)
    if not band_factor(band, h * tab.gamma):
        for c in range(n):
            y_new[c] = np.nan
        return
    for c in range(n):  # the first stage is at y: f(y) is K[0]
        K[1, c] = tab.gamma * K[0, c]
    band_solve(band, lo, K[1])
    # Stage i's point, then (i = s) the new state; one call site of the derivative, which is
    # inlined wherever it is called.
    for i in range(1, s + 1):
        for c in range(n):
            acc = 0.0
            for j in range(i):
                acc += (tab.a[i, j] if i < s else tab.m[j]) * K[j + 1, c]
            tmp[c] = y[c] + h * acc
        if i == s:
            if ix >= 0:
                tmp[ix] = x + h
            for c in range(n):
                y_new[c] = tmp[c]
        rhs(ctx, tmp, K[i + 1])
        if i < s:
            for c in range(n):
                acc = K[i + 1, c]
                for j in range(i):
                    acc += tab.c[i, j] * K[j + 1, c]
                K[i + 1, c] = tab.gamma * acc
            band_solve(band, lo, K[i + 1])


@kernel(inline=True)
def method_step(tab, rhs, jac, ctx, ix, x, y, f, h, K, y_new, tmp, band):
    """One step attempt of the method ``tab``: the explicit pair's (:func:`.rk.step`) where
    ``band`` is None, the W-method's (:func:`w_step`, with the Jacobian kernel ``jac`` and the
    band's storage) else. A branch on an argument typed None is pruned before typing, so an
    explicit pair's caller compiles nothing of the W-method."""
    if band is None:
        step(tab, rhs, ctx, ix, x, y, f, h, K, y_new, tmp)
    else:
        w_step(tab, rhs, jac, ctx, ix, x, y, h, K, y_new, tmp, band)
