"""Swash-plate mechanism: Hooke-joint angle, joint and piston positions, reduced inertia.

Frame and motion (Antonyuk et al. §2, worked in the fixed frame with
the real motion, not the inverted one): ``Ox`` along shaft 1 toward plate 3, ``O`` where the shaft
axis meets the plate, the shaft turns by φ about ``Ox`` from ``Oy`` toward ``Oz``. At φ = 0 the plate
contains ``Oz`` and the line ``m = (−sin α, cos α, 0)`` (eq. (6) at argument 0), so its normal is
``n₀ = (cos α, sin α, 0)``; it turns with the shaft, n(φ) = (cos α, sin α cos φ, sin α sin φ) as in
(8). Link 9 turns on the plate about n by θ = φ₉,₀ (θ ≈ −φ: the Hooke joint holds it still), so

* its rotation is Q₉ = R_x(φ)·R_n₀(θ) and ω₉/φ̇ = w = i + θ′ n, eq. (8);
* joint B_k = R_x(φ)·R (cos β m + sin β e_z), β = ψ_k + θ: eq. (6) with the consistent argument
  ψ_k + φ₉,₀ (the printed ψ_k − φ₉,₀ is a misprint, see the reference);
* the piston joint D_k = (x_D, r₁ cos ψ_Dk, r₁ sin ψ_Dk) stays on its cylinder axis and
  x_D = x_B − √(ℓ² − (y_D − y_B)² − (z_D − z_B)²), eq. (10): pistons lie on the −x side of the plate,
  their gas force pushes them toward +x, so u_k = dx_D/dφ.

Hooke joint (anti-rotation cross 13). Its housing hinge ``a`` is fixed and perpendicular to ``Ox``;
its link-9 hinge ``c`` lies in the plate plane and is fixed in link 9, starting along n₀ × a. The
cross keeps a ⊥ c. With a = e_z (``hinge = "normal"``, perpendicular to the plane of the shaft axis
and n₀) this gives tan θ = −cos α tan φ, the printed (1); with a = e_y (``"in-plane"``, the text's
description) tan θ = −tan φ / cos α. The second is the first a quarter-turn on,
θ_in(φ) = θ_n(φ + π/2) + π/2, so both use one formula with a phase φ_h = 0 or π/2; written as
θ = −φ + atan2((1 − cos α) sin p cos p, cos²p + cos α sin²p), p = φ + φ_h, whose second argument is
positive: branch-free and continuous (unwrapped) for every φ. The cross turns about ``a`` at the
rate ω₉·a (ω₉ = rate about a + rate about c, a ⊥ c), so u₁₃ = θ′ sin α sin p.

All derivatives are exact: B′ = w × B, B″ = w′ × B + w × B′, and (10) is differentiated twice.
"""
from __future__ import annotations

from math import atan2, cos, sin, sqrt

import numpy as np

from ..jit import kernel

#: Layout of the parameter array ``mp``, filled by
#: ``transient.mechanisms.swash_plate.SwashPlate.pack``:
#: ALPHA swash angle α [rad] and its COS_A, SIN_A; JOINT_R R [m]; CYL_R r₁ [m]; ROD_L ℓ [m]; N_CYL
#: cylinders per half; HALVES 1 or 2; HINGE_PHASE φ_h [rad] (0 "normal", π/2 "in-plane"); M_PISTON
#: [kg]; M_ROD [kg]; ROD_CG distance D → centre of mass [m]; I_ROD rod inertia about its centre of
#: mass across its axis [kg m²] (a two-mass rod is packed as the rigid rod with I = m·cg·(ℓ − cg),
#: which is the same body); J_POLAR, J_DIAM link 9 about / across the plate normal [kg m²]; I_CROSS
#: cross 13 about its housing hinge [kg m²]. Then CYL_STRIDE entries per cylinder k from
#: CYL0 + CYL_STRIDE·k: Y_D, Z_D its axis (r₁ cos ψ_Dk, r₁ sin ψ_Dk) [m], eq. (5); COS_PSI, SIN_PSI
#: of the angle ψ_k of its joint on link 9.
(ALPHA, COS_A, SIN_A, JOINT_R, CYL_R, ROD_L, N_CYL, HALVES, HINGE_PHASE, M_PISTON, M_ROD, ROD_CG,
 I_ROD, J_POLAR, J_DIAM, I_CROSS) = range(16)
CYL0 = 16
Y_D, Z_D, COS_PSI, SIN_PSI = range(4)
CYL_STRIDE = 4


@kernel
def hooke(mp, phi):
    """Link 9 and cross 13 at shaft angle φ [rad], from the Hooke constraint a ⊥ c.

    Returns
    -------
    theta, dtheta, ddtheta : float
        θ = φ₉,₀ [rad] (unwrapped: θ(φ + 2π) = θ(φ) − 2π), dθ/dφ = −cos α / (1 − sin²α sin²p)
        (eq. (4) at phase 0) and d²θ/dφ², p = φ + φ_h. The spin of link 9 about the plate normal is
        ω₉·n/φ̇ = cos α + θ′; across the normal it is always sin α, so u₉,₁ = √((cos α + θ′)² + sin²α).
    u13, du13 : float
        u₁₃,₁ = ω₉·a/φ̇ = θ′ sin α sin p, the rate of cross 13 about its housing hinge, and d/dφ.
    """
    p = phi + mp[HINGE_PHASE]
    s = sin(p)
    c = cos(p)
    ca = mp[COS_A]
    sa = mp[SIN_A]
    # tan(θ + φ) from tan θ = −cos α tan p; the denominator is > 0, so atan2 never changes branch.
    theta = -phi + atan2((1.0 - ca) * s * c, c * c + ca * s * s)
    d = 1.0 - sa * sa * s * s
    d1 = -ca / d
    d2 = -2.0 * ca * sa * sa * s * c / (d * d)
    return theta, d1, d2, d1 * sa * s, sa * (d2 * s + d1 * c)


@kernel
def joint_b(mp, k, c_phi, s_phi, c_theta, s_theta):
    """Centre (x, y, z) [m] of joint B_k on link 9, given cos/sin of the shaft angle φ and of θ."""
    r = mp[JOINT_R]
    i = CYL0 + CYL_STRIDE * k
    # β = ψ_k + θ: eq. (6) with the consistent argument gives B_k in the plate's frame at φ = 0 ...
    cb = mp[i + COS_PSI] * c_theta - mp[i + SIN_PSI] * s_theta
    sb = mp[i + SIN_PSI] * c_theta + mp[i + COS_PSI] * s_theta
    py = r * cb * mp[COS_A]
    pz = r * sb
    # ... and the plate turns with the shaft by φ about Ox.
    return -r * cb * mp[SIN_A], c_phi * py - s_phi * pz, s_phi * py + c_phi * pz


@kernel
def swash_points(mp, phi, theta, pts):
    """Positions of the joints of half 1 at the shaft angles ``phi``.

    Parameters
    ----------
    mp : float64[:]
        Packed parameters.
    phi : float64[n]
        Shaft angles [rad].
    theta : float64[n]
        Output: θ = φ₉,₀ [rad] (unwrapped).
    pts : float64[n, N_CYL, 6]
        Output: ``pts[j, k, :3]`` = B_k, ``pts[j, k, 3:]`` = D_k [m]; x_D is NaN where a rod is too
        short to reach its cylinder axis.
    """
    ell = mp[ROD_L]
    for j in range(phi.shape[0]):
        th = hooke(mp, phi[j])[0]
        theta[j] = th
        for k in range(np.int64(mp[N_CYL])):
            bx, by, bz = joint_b(mp, k, cos(phi[j]), sin(phi[j]), cos(th), sin(th))
            yd = mp[CYL0 + CYL_STRIDE * k + Y_D]
            zd = mp[CYL0 + CYL_STRIDE * k + Z_D]
            pts[j, k, 0] = bx
            pts[j, k, 1] = by
            pts[j, k, 2] = bz
            pts[j, k, 3] = bx - sqrt(ell * ell - (yd - by) ** 2 - (zd - bz) ** 2)  # eq. (10)
            pts[j, k, 4] = yd
            pts[j, k, 5] = zd


@kernel
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@kernel(inline=True)  # (on every evaluation: its unused results must cost nothing)
def link_motion(mp, phi):
    """Link 9's motion per unit shaft rate at angle φ: cos/sin of φ and θ, the plate normal n,
    w = ω₉/φ̇ = i + θ′ n and w′ = θ″ n + θ′ (i × n), eq. (8), and :func:`hooke`'s θ′, θ″, u₁₃, u₁₃′."""
    ca = mp[COS_A]
    sa = mp[SIN_A]
    theta, d1, d2, u13, du13 = hooke(mp, phi)
    c_phi = cos(phi)
    s_phi = sin(phi)
    n = (ca, sa * c_phi, sa * s_phi)
    w = (1.0 + d1 * n[0], d1 * n[1], d1 * n[2])
    dw = (d2 * n[0], d2 * n[1] - d1 * n[2], d2 * n[2] + d1 * n[1])
    return c_phi, s_phi, cos(theta), sin(theta), n, w, dw, d1, d2, u13, du13


@kernel(inline=True)
def rod_motion(mp, k, c_phi, s_phi, c_theta, s_theta, w, dw):
    """Joint B_k, its rod and piston per unit shaft rate: B, B′ = w × B, B″ = w′ × B + w × B′; the
    rod's direction e = (B − D)/ℓ, e′, e″; x_D′, x_D″ (d/dφ) of its piston.

    Eq. (10): x_D = x_B − s, s = √(ℓ² − 2q), q = ½ |lateral offset|², so s′ = −q′/s and
    s″ = −(q″ + s′²)/s; D moves along x only, so e′ = (B′ − x_D′ x̂)/ℓ."""
    ell = mp[ROD_L]
    b = joint_b(mp, k, c_phi, s_phi, c_theta, s_theta)
    b1 = _cross(w, b)
    t1 = _cross(dw, b)
    t2 = _cross(w, b1)
    b2 = (t1[0] + t2[0], t1[1] + t2[1], t1[2] + t2[2])
    dy = mp[CYL0 + CYL_STRIDE * k + Y_D] - b[1]
    dz = mp[CYL0 + CYL_STRIDE * k + Z_D] - b[2]
    s = sqrt(ell * ell - dy * dy - dz * dz)
    q1 = -(dy * b1[1] + dz * b1[2])
    q2 = b1[1] * b1[1] + b1[2] * b1[2] - (dy * b2[1] + dz * b2[2])
    s1 = -q1 / s
    s2 = -(q2 + s1 * s1) / s
    x1 = b1[0] - s1
    x2 = b2[0] - s2
    e = (s / ell, -dy / ell, -dz / ell)
    e1 = ((b1[0] - x1) / ell, b1[1] / ell, b1[2] / ell)
    e2 = ((b2[0] - x2) / ell, b2[1] / ell, b2[2] / ell)
    return b, b1, b2, x1, x2, e, e1, e2


@kernel(inline=True)
def link_inertia(mp, d1, d2, u13, du13):
    """J and dJ/dφ of link 9 and cross 13 of one half from :func:`hooke`'s θ′, θ″, u₁₃, u₁₃′:
    link 9 (ω·n)² J_p + (φ̇ sin α)² J_d, the reference's form of (15)–(17), cross 13 about its
    hinge a."""
    sa = mp[SIN_A]
    wn = mp[COS_A] + d1
    J = mp[J_POLAR] * wn * wn + mp[J_DIAM] * sa * sa + mp[I_CROSS] * u13 * u13
    dJ = 2.0 * (mp[J_POLAR] * wn * d2 + mp[I_CROSS] * u13 * du13)
    return J, dJ


@kernel
def link_terms(mp, phi):
    """J and dJ/dφ of the links 9 and crosses 13 of every half: the chain's link ``link``, whose
    inertia a pair on either side of it separates from the rods' (``rhs.split_subchains``)."""
    _, d1, d2, u13, du13 = hooke(mp, phi)
    J, dJ = link_inertia(mp, d1, d2, u13, du13)
    return mp[HALVES] * J, mp[HALVES] * dJ


@kernel
def swash_terms(mp, phi, u, du):
    """Reduced inertia of the moving parts except shaft and plates, eqs. (19), (21).

    J = Σ m |v|²/φ̇² + Σ ω·I·ω/φ̇² over link 9 (polar/diametral inertia about the plate normal; its
    centre stays at O), cross 13 (rotation about its housing hinge), the rods (centre of mass and
    rotation across the rod axis; spin about the axis of a slender rod is ignored) and the pistons;
    times 2 with the mirror half, whose kinetic energy equals that of half 1.

    Parameters
    ----------
    mp : float64[:]
        Packed parameters (layout: module constants).
    phi : float
        Shaft angle [rad].
    u, du : float64[N_CYL]
        Output: ``u[k]`` = d(displacement toward the plate)/dφ [m/rad] summed over the pistons of
        cylinder k (1 or 2), so a gas force F ≥ 0 on each piston does the generalized force F·u[k];
        ``du[k]`` = du[k]/dφ [m/rad²].

    Returns
    -------
    J, dJ : float
        J(φ) [kg m²] and dJ/dφ [kg m²/rad].
    """
    cg = mp[ROD_CG]
    c_phi, s_phi, c_theta, s_theta, n, w, dw, d1, d2, u13, du13 = link_motion(mp, phi)
    J, dJ = link_inertia(mp, d1, d2, u13, du13)
    halves = mp[HALVES]
    for k in range(np.int64(mp[N_CYL])):
        _, _, _, x1, x2, _, e1, e2 = rod_motion(mp, k, c_phi, s_phi, c_theta, s_theta, w, dw)
        # The rod's centre of mass G = D + cg·e; D moves along x only.
        g1x, g2x = x1 + cg * e1[0], x2 + cg * e2[0]
        e11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]
        e12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]
        G11 = g1x * g1x + cg * cg * (e1[1] * e1[1] + e1[2] * e1[2])
        G12 = g1x * g2x + cg * cg * (e1[1] * e2[1] + e1[2] * e2[2])
        J += mp[M_PISTON] * x1 * x1 + mp[M_ROD] * G11 + mp[I_ROD] * e11
        dJ += 2.0 * (mp[M_PISTON] * x1 * x2 + mp[M_ROD] * G12 + mp[I_ROD] * e12)
        u[k] = halves * x1
        du[k] = halves * x2
    return halves * J, halves * dJ


@kernel(inline=True)
def shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ):
    """``Model.shares`` of the swash plate: its plate, links, rods and pistons move together, so
    they ride one station, whose angle is ``angles[0]``; the first cylinder's share is the whole
    J, the others' nothing."""
    Jc[0], dJc[0] = swash_terms(mp, angles[0], u, du)
    for k in range(1, np.int64(mp[N_CYL])):
        Jc[k] = 0.0
        dJc[k] = 0.0


@kernel(inline=True)
def terms(mp, kin_coef, phi, u, du, with_dJ):
    """``Model.terms`` of the swash plate: :func:`swash_terms` (``kin_coef`` is the
    tabulated kernel's)."""
    return swash_terms(mp, phi, u, du)
