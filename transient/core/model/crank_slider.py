"""Crank-slider kinematics and reduced inertia, exact (no truncated series).

Frame of one cylinder (Gots §1, Fig. 1): origin on the crank axis, ``y`` along the cylinder axis
toward the head, ``x`` to the side the crank moves at the top. The local crank angle ``alpha`` is
measured from the cylinder axis in the direction of rotation; the cylinder axis is offset by ``e``
toward positive ``x`` (Gots §1.4: "shifted to the right in the direction of rotation").

Crankpin  A = r (sin α, cos α);  piston pin  B = (e, r cos α + l cos β),  sin β = (r sin α − e)/l
(Gots (2), (13), (17) exact). β is positive when the rod leans in the direction of rotation.
"""
from __future__ import annotations

from math import asin, cos, sin, sqrt

import numpy as np

from ..jit import kernel

#: Layout of the parameter array ``mp`` of :func:`crank_slider_terms` (filled by
#: ``transient.mechanisms.crank_slider.CrankSlider.pack``).
R, L, E, M_PISTON, M_PIN, M_CRANKPIN, M_ROD, ROD_CG, I_ROD, M_CRANK, N_CYL = range(11)
#: mp[SIN0 + k], mp[SIN0 + n + k]: sine and cosine of the shaft angle φ_k at which cylinder k
#: (of n) has local angle 0 (its firing angle).
SIN0 = 11


@kernel
def slider(alpha, r, l, e):
    """Exact crank-slider kinematics at local crank angle ``alpha`` [rad].

    Returns
    -------
    s, ds, dds : float
        Piston travel from the true top dead centre [m] (Gots (1), (12)) and its first and second
        derivatives with respect to the crank angle [m/rad, m/rad²]; ``ds`` is positive toward the
        crank, so a piston force P (positive toward the crank, Gots §2.3) has generalized force P·ds.
    beta, dbeta, ddbeta : float
        Rod angle [rad] and its derivatives [1, 1/rad] (Gots (7)–(8), (17)–(19) at ω = 1).
    """
    sa, ca = sin(alpha), cos(alpha)
    sb, cb, db, ds = rod_and_piston(sa, ca, r, l, e)
    ddb, dds = rod_and_piston_second(sa, ca, r, l, sb, cb, db)
    s = sqrt((l + r) ** 2 - e * e) - (r * ca + l * cb)  # top dead centre minus the pin's height
    return s, ds, dds, asin(sb), db, ddb


@kernel(inline=True)
def rod_and_piston(sa, ca, r, l, e):
    """sin β, cos β, dβ/dα and the piston's ds/dα from sin α, cos α (Gots (2), (7), (12), (17))."""
    sb = (r * sa - e) / l
    cb = sqrt(1.0 - sb * sb)
    db = r * ca / (l * cb)
    return sb, cb, db, r * sa + l * sb * db


@kernel(inline=True)
def rod_and_piston_second(sa, ca, r, l, sb, cb, db):
    """d²β/dα² and d²s/dα² (Gots (8), (18)–(19) at ω = 1), from :func:`rod_and_piston`'s values."""
    ddb = (l * sb * db * db - r * sa) / (l * cb)
    return ddb, r * ca + l * cb * db * db + l * sb * ddb


@kernel
def cylinder_terms(alpha, mp):
    """Reduced inertia of one cylinder's moving parts (piston, rod, crank throw) and its derivative.

    Equations (19), (21) of the swash-plate paper applied to the crank-slider: J = Σ m |v|²/φ̇² +
    Σ I (β̇/φ̇)²; the rod is a rigid body (mass at its centre of mass G, inertia about G) and/or point
    masses at the pin and the crankpin (the two-mass model of Gots (20)).

    Returns ``(J, dJ, ds, dds)``: inertia [kg m²], dJ/dα [kg m²/rad], and the piston's transfer
    function and its derivative.
    """
    return cylinder_terms_sc(sin(alpha), cos(alpha), mp, True)


@kernel(inline=True)
def cylinder_terms_sc(sa, ca, mp, with_dJ):
    """:func:`cylinder_terms` from sin α and cos α; without ``with_dJ`` only J and ds, dJ and dds
    NaN (the crank-angle right-hand side without pairs needs no dJ/dφ; README *Speed*, bare (18))."""
    r = mp[R]
    l = mp[L]
    sb, cb, db, ds = rod_and_piston(sa, ca, r, l, mp[E])
    # Rod centre of mass G = B + f (A − B), f = |BG|/l; B moves only along the axis (B' = (0, −ds)).
    f = mp[ROD_CG] / l
    gx1 = f * r * ca
    gy1 = (1.0 - f) * (-ds) - f * r * sa
    m_slide = mp[M_PISTON] + mp[M_PIN]
    m_rot = mp[M_CRANKPIN] + mp[M_CRANK]
    J = m_slide * ds * ds + m_rot * r * r + mp[M_ROD] * (gx1 * gx1 + gy1 * gy1) + mp[I_ROD] * db * db
    if not with_dJ:
        return J, np.nan, ds, np.nan
    ddb, dds = rod_and_piston_second(sa, ca, r, l, sb, cb, db)
    gx2 = -f * r * sa
    gy2 = (1.0 - f) * (-dds) - f * r * ca
    dJ = 2.0 * (m_slide * ds * dds + mp[M_ROD] * (gx1 * gx2 + gy1 * gy2) + mp[I_ROD] * db * ddb)
    return J, dJ, ds, dds


@kernel(inline=True)
def crank_slider_terms(mp, phi, u, du, with_dJ=True):
    """Reduced inertia J(φ), dJ/dφ of all cylinders; fills the piston transfer functions.

    ``u[k] = ds_k/dφ`` and ``du[k] = d²s_k/dφ²`` for cylinder k at local angle φ − φ_k. Without
    ``with_dJ``, dJ and ``du`` are NaN (:func:`cylinder_terms_sc`).
    The local angle's sine and cosine come from φ's by the angle-difference formulas: one sincos
    per call, not one per cylinder (3 sincos were 16 % of the diesel's samples under ``perf``).
    """
    n = np.int64(mp[N_CYL])
    sp = sin(phi)
    cp = cos(phi)
    J = 0.0
    dJ = 0.0
    for k in range(n):
        s0 = mp[SIN0 + k]
        c0 = mp[SIN0 + n + k]
        Jk, dJk, u[k], du[k] = cylinder_terms_sc(sp * c0 - cp * s0, cp * c0 + sp * s0, mp,
                                                   with_dJ)
        J += Jk
        dJ += dJk
    return J, dJ


#: The largest |d| for which :func:`turned` takes sin d and cos d from polynomials [rad].
NEAR = 1.0 / 16.0


@kernel(inline=True)
def turned(s, c, d):
    """sin(a + d) and cos(a + d) from s = sin a, c = cos a: by the sum formulas, with sin d and
    cos d from their Taylor polynomials where |d| ≤ :data:`NEAR` (the truncation, below
    d¹¹/11! and d¹⁰/10!, is about a thousandth of an ulp at most), else from ``sin``, ``cos``.
    Accurate to a few ulps of 1, as the sine of a large angle is; a call into the maths library
    costs more than the polynomials."""
    if abs(d) <= NEAR:
        d2 = d * d
        # (each coefficient a constant the compiler folds: a product, not a division)
        sd = d * (1.0 + d2 * (-1.0 / 6.0 + d2 * (1.0 / 120.0 + d2 * (-1.0 / 5040.0
                                                                      + d2 * (1.0 / 362880.0)))))
        cd = 1.0 + d2 * (-0.5 + d2 * (1.0 / 24.0 + d2 * (-1.0 / 720.0 + d2 * (1.0 / 40320.0))))
    else:
        sd = sin(d)
        cd = cos(d)
    return s * cd + c * sd, c * cd - s * sd


@kernel(inline=True)
def shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ):
    """``Model.shares`` of the crank-slider: each cylinder's own reduced inertia J_c, J′_c and
    transfer functions at ``angles[k]``, the angle of the station that carries it (theory (T1a)):
    on an elastic shaft line each throw turns at its own angle, so each cylinder takes its own
    sine and cosine — turned from the first cylinder's by the twist between them
    (:func:`turned`), one call of the maths library in all. Without ``with_dJ`` J′_c and u′
    are NaN (:func:`cylinder_terms_sc`)."""
    n = np.int64(mp[N_CYL])
    s_first = sin(angles[0])
    c_first = cos(angles[0])
    for k in range(n):
        sp, cp = turned(s_first, c_first, angles[k] - angles[0])
        s0 = mp[SIN0 + k]
        c0 = mp[SIN0 + n + k]
        Jc[k], dJc[k], u[k], du[k] = cylinder_terms_sc(sp * c0 - cp * s0, cp * c0 + sp * s0, mp,
                                                       with_dJ)


@kernel(inline=True)
def terms(mp, kin_coef, phi, u, du, with_dJ):
    """``Model.terms`` of the crank-slider: :func:`crank_slider_terms` (``kin_coef`` is the
    tabulated kernel's)."""
    return crank_slider_terms(mp, phi, u, du, with_dJ)
