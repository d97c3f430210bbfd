"""Tabulated reduced model: J(φ) and the piston transfer functions u_k(φ) as periodic quintic
splines on a uniform grid (docs/theory.md, Tabulation; built by :mod:`transient.tabulate`).

The angle-only terms of the reduced model are smooth and 2π-periodic. Evaluated exactly they
cost a few trigonometric functions, square roots and an arcsine per cylinder; from a table they
cost an index and a degree-5 polynomial per function. dJ/dφ and u′_k are the derivatives of the
same polynomials, so the tabulated model is itself a consistent mechanism: coasting conserves
½J_tab(φ)ω² exactly as the exact model conserves ½J(φ)ω².

Layout: ``coef[f, i, p]`` is the coefficient of ``(φ − i·h)**p`` on interval i of function f,
f = 0 for J (without the constant inertias), f = 1 + k for u_k; h = 2π/n.
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import kernel

TWO_PI = 2.0 * math.pi


@kernel(inline=True)
def _poly5(c, x):
    """Value and derivative of c[0] + c[1]x + … + c[5]x⁵ (Horner)."""
    v = c[5]
    d = 5.0 * c[5]
    v = v * x + c[4]
    d = d * x + 4.0 * c[4]
    v = v * x + c[3]
    d = d * x + 3.0 * c[3]
    v = v * x + c[2]
    d = d * x + 2.0 * c[2]
    v = v * x + c[1]
    d = d * x + c[1]
    v = v * x + c[0]
    return v, d


@kernel
def tabulated_terms(coef, phi, u, du):
    """J(φ), dJ/dφ of the mechanism from its tables; fills ``u[k]``, ``du[k]`` per cylinder.

    ``du`` is the derivative of the spline of u_k (no table of its own)."""
    n = coef.shape[1]
    h = TWO_PI / n
    x = phi - TWO_PI * math.floor(phi / TWO_PI)
    i = np.int64(x / h)
    if i >= n:  # x within rounding of 2π
        i = n - 1
    x -= i * h
    J, dJ = _poly5(coef[0, i], x)
    for k in range(coef.shape[0] - 1):
        u[k], du[k] = _poly5(coef[1 + k, i], x)
    return J, dJ


@kernel(inline=True)
def shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ):
    """``Model.shares`` of tabulated kinematics: the tables hold the mechanism's J(φ) whole, so
    every cylinder rides one station, whose angle is ``angles[0]``; the first cylinder's share
    is the whole J, the others' nothing."""
    Jc[0], dJc[0] = tabulated_terms(kin_coef, angles[0], u, du)
    for k in range(1, kin_coef.shape[0] - 1):
        Jc[k] = 0.0
        dJc[k] = 0.0


@kernel(inline=True)
def terms(mp, kin_coef, phi, u, du, with_dJ):
    """``Model.terms`` of tabulated kinematics, any mechanism's: :func:`tabulated_terms` (``mp``
    is the mechanism's own parameters, for its reaction solver)."""
    return tabulated_terms(kin_coef, phi, u, du)
