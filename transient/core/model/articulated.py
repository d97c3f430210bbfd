"""Master and articulated rods (radial and V engines): exact kinematics and reduced inertia.

Frame of one row (Semenov's notation, §1–§2; his clockwise, left-handed frame is numerically
this one): origin O on the crank axis, x along the master cylinder from O toward its piston pin
B, y a quarter-turn on in the direction of rotation; the row's local crank angle α is measured
from x toward y (α = 0 at the master's TDC). Crankpin A = r(cos α, sin α); the master rod is
a central crank-slider, sin β = λ sin α (Semenov (31)), its axis A → B along e = (cos β, −sin β),
and n = (sin β, cos β) across it.

The master rod is a rigid body carrying the link pin of slave i at radius r_i and angle ψ_i from its
axis, toward n: A_i = A + a_i e + q_i n, a_i = r_i cos ψ_i, q_i = r_i sin ψ_i (Semenov (8)). Slave
cylinder i lies at bank angle δ_i, along d_i = (cos δ_i, sin δ_i), m_i = (−sin δ_i, cos δ_i). With
h = A_i·m_i the link pin's offset from that axis and c = √(l_i² − h²), the slave piston pin is

    B_i = X_i d_i,  X_i = A_i·d_i + c,                       (Semenov (40), (41): l_i sin β_i = −h)

and the slave rod's angle to its cylinder axis is β_i = −asin(h/l_i). The derivatives in α are exact:
e′ = −β′ n, so (a e + q n)′ = β′(v_y, −v_x) for v = a e + q n; c′ = −h h′/c, c″ = −(h′² + h h″ + c′²)/c;
β_i′ = −h′/c, β_i″ = −h″/c + h′c′/c². Central articulation (V engines, Semenov §3: the slave rod on
the crankpin) is r_i = 0: A_i = A, nothing else changes.

The master cylinder is exactly a centred crank-slider: its piston, rod and crank throw use
:func:`transient.core.model.crank_slider.cylinder_terms` on the same header of ``mp``.
"""
from __future__ import annotations

from math import cos, sin, sqrt

import numpy as np

from ..jit import kernel
from .crank_slider import L, R, cylinder_terms, slider

#: Layout of ``mp`` (filled by ``transient.mechanisms.articulated.Articulated.pack``). Slots 0–9
#: are the crank-slider header of the master cylinder (``transient.core.model.crank_slider``: R, L,
#: E = 0, masses of the master piston, the master rod and the crank throw); then N_ROWS, N_SLAVES
#: (slaves per row), and SLAVE_STRIDE entries per slave i from SLAVE0 + SLAVE_STRIDE·i: LINK_A a_i,
#: LINK_Q q_i [m]; COS_D, SIN_D of δ_i; SLAVE_L l_i [m]; SLAVE_PISTON [kg]; SLAVE_ROD mass [kg];
#: SLAVE_CG distance B_i → centre of mass [m]; SLAVE_I inertia about it [kg m²]. Then one entry per
#: row j at row0(mp) + j: the shaft angle at which row j is at α = 0.
N_ROWS, N_SLAVES = 10, 11
SLAVE0 = 12
LINK_A, LINK_Q, COS_D, SIN_D, SLAVE_L, SLAVE_PISTON, SLAVE_ROD, SLAVE_CG, SLAVE_I = range(9)
SLAVE_STRIDE = 9


@kernel
def row0(mp):
    """Index in ``mp`` of row 0's phase."""
    return SLAVE0 + SLAVE_STRIDE * np.int64(mp[N_SLAVES])


@kernel
def master_rod(alpha, r, l):
    """Crankpin A, its derivatives, and the master-rod angle β with β′, β″ at local angle α.

    Returns ``(ca, sa, cb, sb, db, ddb)``: cos α, sin α, cos β, sin β, dβ/dα, d²β/dα²
    (Semenov (31); derivatives as Gots (7)–(8) at ω = 1)."""
    _, _, _, beta, db, ddb = slider(alpha, r, l, 0.0)
    return cos(alpha), sin(alpha), cos(beta), sin(beta), db, ddb


@kernel
def slave(mp, i, r, ca, sa, cb, sb, db, ddb):
    """Slave i of a row whose crank and master rod are given (:func:`master_rod`).

    Returns
    -------
    X, X1, X2 : float
        Piston-pin position along the cylinder axis from O [m] and its derivatives in α.
    A1x, A1y, A2x, A2y : float
        First and second derivatives of the link pin A_i [m/rad, m/rad²] (row frame).
    t1, t2 : float
        β_i′ and β_i″, the slave rod's rate and its derivative (the rod turns by β_i relative to
        its fixed cylinder, so this is its angular velocity over φ̇).
    """
    k = SLAVE0 + SLAVE_STRIDE * i
    a = mp[k + LINK_A]
    q = mp[k + LINK_Q]
    # v = a e + q n on the master rod; v′ = β′(v_y, −v_x), v″ = β″(v_y, −v_x) − β′² v.
    vx = a * cb + q * sb
    vy = q * cb - a * sb
    Ax = r * ca + vx
    Ay = r * sa + vy
    A1x = -r * sa + db * vy
    A1y = r * ca - db * vx
    A2x = -r * ca + ddb * vy - db * db * vx
    A2y = -r * sa - ddb * vx - db * db * vy
    cd = mp[k + COS_D]
    sd = mp[k + SIN_D]
    li = mp[k + SLAVE_L]
    h = Ay * cd - Ax * sd
    h1 = A1y * cd - A1x * sd
    h2 = A2y * cd - A2x * sd
    c = sqrt(li * li - h * h)
    c1 = -h * h1 / c
    c2 = -(h1 * h1 + h * h2 + c1 * c1) / c
    X = Ax * cd + Ay * sd + c
    X1 = A1x * cd + A1y * sd + c1
    X2 = A2x * cd + A2y * sd + c2
    return X, X1, X2, A1x, A1y, A2x, A2y, -h1 / c, (h1 * c1 / c - h2) / c


@kernel
def slave_inertia(mp, i, X1, X2, A1x, A1y, A2x, A2y, t1, t2):
    """J and dJ/dα of slave i's piston and rod: m_p X′² + m |G′|² + I β_i′², G = B_i + f(A_i − B_i)."""
    k = SLAVE0 + SLAVE_STRIDE * i
    cd = mp[k + COS_D]
    sd = mp[k + SIN_D]
    f = mp[k + SLAVE_CG] / mp[k + SLAVE_L]
    g1x = (1.0 - f) * X1 * cd + f * A1x
    g1y = (1.0 - f) * X1 * sd + f * A1y
    g2x = (1.0 - f) * X2 * cd + f * A2x
    g2y = (1.0 - f) * X2 * sd + f * A2y
    mp_ = mp[k + SLAVE_PISTON]
    mr = mp[k + SLAVE_ROD]
    mi = mp[k + SLAVE_I]
    J = mp_ * X1 * X1 + mr * (g1x * g1x + g1y * g1y) + mi * t1 * t1
    dJ = 2.0 * (mp_ * X1 * X2 + mr * (g1x * g2x + g1y * g2y) + mi * t1 * t2)
    return J, dJ


@kernel
def articulated_terms(mp, phi, u, du):
    """Reduced inertia J(φ), dJ/dφ of every row's crank throw, rods and pistons; fills u, u′.

    Equations (19), (21) of the swash-plate paper: J = Σ m |v|²/φ̇² + Σ I (ω/φ̇)². Cylinder
    k = j(1 + z′) (master of row j) and k = j(1 + z′) + 1 + i (slave i), z′ slaves per row:
    ``u[k]`` = ds_k/dφ with s_k the travel from the outer dead centre toward the crank (so a gas
    force P, positive toward the crank, does P·u[k]), ``du[k]`` = d²s_k/dφ².
    """
    j0 = row0(mp)
    J = 0.0
    dJ = 0.0
    for j in range(np.int64(mp[N_ROWS])):
        Jj, dJj = row_terms(mp, j, phi - mp[j0 + j], u, du)
        J += Jj
        dJ += dJj
    return J, dJ


@kernel(inline=True)
def row_terms(mp, j, alpha, u, du):
    """J and dJ/dα of row j (its crank throw, master rod and piston, slaves) at its local angle
    α; fills the row's u, u′ (:func:`articulated_terms`)."""
    r = mp[R]
    l = mp[L]
    ns = np.int64(mp[N_SLAVES])
    base = j * (1 + ns)
    # Master piston, master rod (as a body: its centre of mass and β′) and the crank throw.
    J, dJ, u[base], du[base] = cylinder_terms(alpha, mp)
    ca, sa, cb, sb, db, ddb = master_rod(alpha, r, l)
    for i in range(ns):
        X, X1, X2, A1x, A1y, A2x, A2y, t1, t2 = slave(mp, i, r, ca, sa, cb, sb, db, ddb)
        Js, dJs = slave_inertia(mp, i, X1, X2, A1x, A1y, A2x, A2y, t1, t2)
        J += Js
        dJ += dJs
        u[base + 1 + i] = -X1
        du[base + 1 + i] = -X2
    return J, dJ


@kernel(inline=True)
def shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ):
    """``Model.shares`` of master and articulated rods: a row's master and slaves move with its
    crank throw, so they ride one station, whose angle is that of the row's master,
    ``angles[j(1 + z′)]``; the master's share is the whole row's J, the slaves' nothing."""
    ns = np.int64(mp[N_SLAVES])
    j0 = row0(mp)
    for j in range(np.int64(mp[N_ROWS])):
        base = j * (1 + ns)
        Jc[base], dJc[base] = row_terms(mp, j, angles[base] - mp[j0 + j], u, du)
        for i in range(ns):
            Jc[base + 1 + i] = 0.0
            dJc[base + 1 + i] = 0.0


@kernel
def axial_positions(mp, alpha, x, dx, ddx):
    """Piston-pin positions X_k along their cylinder axes from O [m] and dX/dα, d²X/dα² of one
    row at local angle α: k = 0 the master, k = 1 + i slave i (arrays of length 1 + z′)."""
    r = mp[R]
    l = mp[L]
    s, ds, dds, _, _, _ = slider(alpha, r, l, 0.0)
    x[0] = r + l - s
    dx[0] = -ds
    ddx[0] = -dds
    ca, sa, cb, sb, db, ddb = master_rod(alpha, r, l)
    for i in range(np.int64(mp[N_SLAVES])):
        x[1 + i], dx[1 + i], ddx[1 + i], _, _, _, _, _, _ = slave(mp, i, r, ca, sa, cb, sb, db,
                                                                  ddb)


@kernel(inline=True)
def terms(mp, kin_coef, phi, u, du, with_dJ):
    """``Model.terms`` of master and articulated rods: :func:`articulated_terms` (``kin_coef`` is the
    tabulated kernel's)."""
    return articulated_terms(mp, phi, u, du)
