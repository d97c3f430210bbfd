r"""Friction on the reactions of the articulated mechanism's joints (radial and V engines), solved
exactly with the motion, as :mod:`.joint_friction` does for the crank-slider.

The friction laws are that module's: a journal or pin loses μ·r·|R| + c·q, opposing its relative
angular speed q; a piston in its cylinder μ·|N| + F_ring + c_p·P⁺ + c·v, opposing its speed v.
The joints of a row (:mod:`transient.core.model.articulated`; ``transient.mechanisms.articulated`` names
them for
the scene): the main bearing (frame – throw), the master crankpin (throw – master rod), the link
pins (master rod – slave rod i; with central articulation, r_i = 0, the slave rod sits on the
crankpin, which then carries it through the master rod's big end), the master and the slave
piston pins (rod – piston) and the pistons in their cylinders.

The reactions by Newton–Euler
-----------------------------
In the row frame of :mod:`transient.core.model.articulated` (x along the master cylinder, rotation
positive, so every
moment below is about z in the direction of rotation; a × b = a_x b_y − a_y b_x). Every point p
of the row moves as p(α), α = φ − φ_j, so its acceleration is p″ω² + p′ε, affine in ε = φ̈:
A, A′, A″ the crankpin, B = X₀ x̂ the master piston pin (X₀′ = −s′, Semenov (31) through the
crank-slider's relations), A_i = A + a_i e + q_i n the link pins (Semenov (8)), B_i = X_i d_i the
slave piston pins (Semenov (40)–(41)); the master rod turns at θ₀′ = −β′, slave rod i at β_i′
(:func:`.articulated.slave`). Cylinder k has its axis d_k (d₀ = x̂), m_k = ẑ × d_k across it, the
side force N_k m_k of the wall on its piston and the gas force −P_k d_k. With F_Bk the rod's force
on piston k, F_Ai the master rod's on slave rod i at A_i, F_A the throw's on the master rod at A,
F_O the frame's on the throw, and the friction moments M (on the outer body of each joint: M_A
on the master rod from the throw, M_B0 on it from its piston, M_Li on slave rod i from the master
rod, M_Bi on slave rod i from its piston, M_O on the throw from the frame):

    F_Bk = (m_p a_Xk + P_k − F_sk) d_k − N_k m_k                (piston k, along and across)
    F_Ai = F_Bi + D_i,  F_A = F_B0 + D₀ + Σ_i F_Ai,  F_O = F_A + m_k a_A     (Newton)
    g_i = (A_i − B_i) × F_Ai + M_Li + M_Bi − H_i = 0                 (slave rod i about B_i)
    g₀ = (A − B) × F_A − Σ_i [(A_i − B) × F_Ai + M_Li] + M_A + M_B0 − H₀ = 0   (master rod about B)
    T = −A × F_A + M_O − M_A − m_k r² ε                             (throw about O)

with F_sk the slider's friction along d_k, D the rods' masses times their accelerations
(the master rod's point masses at B and A and its rigid part at G; each slave rod rigid) and H
their rates of angular momentum about the piston pin (Σ (p − B) × m a_p + I θ̈). T is the
throw's torque on the shaft and the shaft obeys J₀ ε = M_shaft + Σ_rows T. Without friction T
summed over the rows is M_gas − J(φ)ε − ½J′ω² with J the mechanism's part of the reduced
inertia, the reduced model's (Lagrange: ``tests/unit/test_articulated_friction.py`` checks it).
``transient.reference.articulated_joint_forces`` solves the same bodies as one linear system
per state, its kinematics by its own loop-closure analysis: the independent check.

The exact solve
---------------
The unknowns are ε and every piston's side force N_k; the equations the rods' g_k and the shaft's.
g_i depends on N_i and ε only, g₀ on N₀, every N_i of its row and ε, T on all of them: per row
the Jacobian is an arrowhead. Newton's method eliminates it in closed form: with
r_i = g_i/∂g_i/∂N_i and q_i = (∂g_i/∂ε)/(∂g_i/∂N_i), δN_i = −r_i − q_i δε; then
δN₀ = −r₀ − q₀ δε with r₀ = (g₀ − Σ ∂g₀/∂N_i r_i)/∂g₀/∂N₀, q₀ = (∂g₀/∂ε − Σ ∂g₀/∂N_i q_i)/∂g₀/∂N₀,
and the shaft's equation H = J₀ ε − M_shaft − Σ T linearized in δε alone gives
δε = −(H + Σ_k ∂T/∂N_k r_k)/(J₀ − Σ (∂T/∂ε − Σ_k ∂T/∂N_k q_k)). The derivatives are exact (the
functions are smooth but for the |·| of the forces and of N). It starts from the frictionless
φ̈ and, at that φ̈, the side forces without the terms in |·| (then the rods' equations are
linear in the N_k: one elimination solves them), and stops as :func:`.joint_friction.solve`
does, when the corrections are below :data:`.joint_friction.TOL` of the forces' scales; NaN if
it has not converged after :data:`.joint_friction.MAX_ITER` (the run then stops reporting the
non-finite derivative). Nothing is lagged: the solve is a function of the state alone.

Directions
----------
The relative rates (per ω) are: the throw's 1; the master rod's on the throw θ₀′ − 1 = −β′ − 1,
never 0 (|β′| ≤ λ/√(1 − λ²) < 1); the master pin's θ₀′ = −β′, zero at α = 90°, 270°; the link
pin's β_i′ + β′; the slave pin's β_i′; the pistons' X_k′. Their signs are taken at the step's
angle ``sel`` (cached) times σ, and every angle where one changes sign is a breakpoint
(``Articulated.reaction_reversals``, ``transient.assemble.reaction_breakpoints``), so no friction
force reverses inside a step.

Outputs per pair, summed over the joints of every row that it names: S the moment the shaft
side puts into the joint (the power F·v of the inner body's force at the joint's point plus the
moment times the inner body's rate, over ω; the shaft into the throws for the main bearings),
L the loss moment (−M q over ω for a journal, −F_s X′ for a slider) and η* = 1 − L/S, exactly as
:func:`.joint_friction._pair_terms`.

Shapes: ``jp`` = ``Model.rx_par`` float64[N_JOINTS, N_RX_PAR] (rows ``J_*`` below); the rows
``WK_RX + A_*`` of ``wk`` hold one value per cylinder (the master's column k₀ = j(1 + z′) also
the row's crankpin and throw), the gas force row ``WK_RX + joint_friction.R_P`` and per pair the
loss ``WK_RX + joint_friction.R_LOSS`` as the crank-slider's.
"""
from __future__ import annotations

import numpy as np

from ..declare import Layout
from ..jit import kernel
from .articulated import (
    COS_D,
    LINK_A,
    LINK_Q,
    N_ROWS,
    N_SLAVES,
    SIN_D,
    SLAVE0,
    SLAVE_CG,
    SLAVE_I,
    SLAVE_L,
    SLAVE_PISTON,
    SLAVE_ROD,
    SLAVE_STRIDE,
    master_rod,
    row0,
    slave,
)
from .crank_slider import I_ROD, M_CRANK, M_CRANKPIN, M_PIN, M_PISTON, M_ROD, ROD_CG, L, R
from .joint_friction import (
    MAX_ITER,
    R_LOSS,
    R_P,
    SHARED,
    TOL,
    _norm,
    _slope,
    clear_pairs,
    newton_step,
    pair_efficiencies,
)
from .layout import (
    RX_MU,
    RX_RADIUS,
    RX_RING_FORCE,
    RX_RING_PRESSURE,
    RX_VISCOUS,
    WK_CYL_LOSS,
    WK_RX,
    WK_S,
)

#: The joints (rows of ``Model.rx_par``): main bearing, master crankpin, link pins, master piston
#: pin, slave piston pins, pistons in their cylinders.
J_MAIN, J_CRANKPIN, J_LINK, J_MASTER_PIN, J_SLAVE_PIN, J_SLIDER = range(6)
N_JOINTS = 6

#: The articulated mechanism's own rows, after the rows every solver shares
#: (``joint_friction.SHARED``; offsets from ``layout.WK_RX``), per cylinder k: the rod from the piston pin to its
#: other end (A − B, A_i − B_i), the piston's rate X′, the rod's rate θ′, per acceleration its
#: part at ε = 0 and its slope in ε (the piston along its axis, D_x, D_y, H), the signs at ``sel``
#: per unit σ of the slider's, the piston pin's and the big end's (crankpin or link pin) relative
#: rate, N's iterate, the Newton parts r_k, q_k; per slave the link pin's offset A_i − A and
#: velocity A_i′, and the force F_Ai with its derivatives in N_i and ε and the link friction's
#: slopes; per row (the master's column) the crankpin A, its acceleration's parts and the forces
#: F_A, F_O; the ``sel`` of the signs ([0]).
ROWS = Layout("articulated reaction rows",
              "lx", "ly", "dx", "dt", "ab0", "ab1", "dx0", "dx1", "dy0", "dy1", "h0", "h1", "ss",
              "sp", "sj", "n", "rs", "qs", "ox", "oy", "px", "py", "fx", "fy", "vx", "vy", "wx",
              "wy", "ln", "le", "ax", "ay", "aax0", "aax1", "aay0", "aay1", "fox", "foy", "sel",
              start=SHARED.end)
(A_LX, A_LY, A_DX, A_DT, A_AB0, A_AB1, A_DX0, A_DX1, A_DY0, A_DY1, A_H0, A_H1, A_SS, A_SP, A_SJ,
 A_N, A_RS, A_QS, A_OX, A_OY, A_PX, A_PY, A_FX, A_FY, A_VX, A_VY, A_WX, A_WY, A_LN, A_LE, A_AX,
 A_AY, A_AAX0, A_AAX1, A_AAY0, A_AAY1, A_FOX, A_FOY, A_SEL) = ROWS


@kernel(inline=True)
def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@kernel(inline=True)
def _sign(x):
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)


@kernel
def prepare(mp, phi, w, sel, wk):
    """The rows of the state (φ, ω) for :func:`solve`: per cylinder its rod's geometry and the
    parts of the accelerations, per row the crankpin's; the joints' directions at ``sel`` when
    ``sel`` has changed (:func:`_directions`)."""
    c = WK_RX
    r, l = mp[R], mp[L]
    ns = np.int64(mp[N_SLAVES])
    j0 = row0(mp)
    f = mp[ROD_CG] / l
    m_pin, m_cp, m_rod, i_rod = mp[M_PIN], mp[M_CRANKPIN], mp[M_ROD], mp[I_ROD]
    w2 = w * w
    for j in range(np.int64(mp[N_ROWS])):
        k0 = j * (1 + ns)
        ca, sa, cb, sb, db, ddb = master_rod(phi - mp[j0 + j], r, l)
        x1 = -r * sa - l * sb * db  # X₀′ = −s′ (Semenov (31), Gots (12))
        x2 = -r * ca - l * cb * db * db - l * sb * ddb
        ax, ay = r * ca, r * sa
        lx, ly = -l * cb, l * sb  # A − B
        wk[c + A_LX, k0] = lx
        wk[c + A_LY, k0] = ly
        wk[c + A_DX, k0] = x1
        wk[c + A_DT, k0] = -db
        wk[c + A_AX, k0] = ax
        wk[c + A_AY, k0] = ay
        for part in range(2):  # 0: the ω² terms at ε = 0; 1: the slope in ε
            if part == 0:
                aax, aay, abx, tdd = -ax * w2, -ay * w2, x2 * w2, -ddb * w2
            else:
                aax, aay, abx, tdd = -ay, ax, x1, -db
            agx = (1.0 - f) * abx + f * aax
            agy = f * aay
            wk[c + A_AB0 + part, k0] = abx
            wk[c + A_AAX0 + part, k0] = aax
            wk[c + A_AAY0 + part, k0] = aay
            wk[c + A_DX0 + part, k0] = m_pin * abx + m_cp * aax + m_rod * agx
            wk[c + A_DY0 + part, k0] = m_cp * aay + m_rod * agy
            wk[c + A_H0 + part, k0] = (_cross(lx, ly, m_cp * aax, m_cp * aay)
                                       + f * _cross(lx, ly, m_rod * agx, m_rod * agy)
                                       + i_rod * tdd)
        for i in range(ns):
            k = k0 + 1 + i
            s0 = SLAVE0 + SLAVE_STRIDE * i
            X, X1, X2, a1x, a1y, a2x, a2y, t1, t2 = slave(mp, i, r, ca, sa, cb, sb, db, ddb)
            cd, sd = mp[s0 + COS_D], mp[s0 + SIN_D]
            a, q = mp[s0 + LINK_A], mp[s0 + LINK_Q]
            ox, oy = a * cb + q * sb, q * cb - a * sb  # A_i − A = a e + q n
            lx, ly = ax + ox - X * cd, ay + oy - X * sd  # A_i − B_i
            fi = mp[s0 + SLAVE_CG] / mp[s0 + SLAVE_L]
            ms, i_s = mp[s0 + SLAVE_ROD], mp[s0 + SLAVE_I]
            wk[c + A_LX, k] = lx
            wk[c + A_LY, k] = ly
            wk[c + A_DX, k] = X1
            wk[c + A_DT, k] = t1
            wk[c + A_OX, k] = ox
            wk[c + A_OY, k] = oy
            wk[c + A_PX, k] = a1x
            wk[c + A_PY, k] = a1y
            for part in range(2):
                if part == 0:
                    aix, aiy, abx, tdd = a2x * w2, a2y * w2, X2 * w2, t2 * w2
                else:
                    aix, aiy, abx, tdd = a1x, a1y, X1, t1
                agx = (1.0 - fi) * abx * cd + fi * aix
                agy = (1.0 - fi) * abx * sd + fi * aiy
                wk[c + A_AB0 + part, k] = abx
                wk[c + A_DX0 + part, k] = ms * agx
                wk[c + A_DY0 + part, k] = ms * agy
                wk[c + A_H0 + part, k] = fi * _cross(lx, ly, ms * agx, ms * agy) + i_s * tdd
    if wk[c + A_SEL, 0] != sel:
        _directions(mp, sel, wk)


@kernel
def _directions(mp, sel, wk):
    """The signs at the angle ``sel`` of each cylinder's slider rate X′, its piston pin's and its
    big end's (crankpin or link pin) relative rate, per unit σ."""
    c = WK_RX
    r, l = mp[R], mp[L]
    ns = np.int64(mp[N_SLAVES])
    j0 = row0(mp)
    for j in range(np.int64(mp[N_ROWS])):
        k0 = j * (1 + ns)
        ca, sa, cb, sb, db, ddb = master_rod(sel - mp[j0 + j], r, l)
        wk[c + A_SS, k0] = _sign(-r * sa - l * sb * db)
        wk[c + A_SP, k0] = _sign(-db)
        wk[c + A_SJ, k0] = _sign(-db - 1.0)
        for i in range(ns):
            _, X1, _, _, _, _, _, t1, _ = slave(mp, i, r, ca, sa, cb, sb, db, ddb)
            wk[c + A_SS, k0 + 1 + i] = _sign(X1)
            wk[c + A_SP, k0 + 1 + i] = _sign(t1)
            wk[c + A_SJ, k0 + 1 + i] = _sign(t1 + db)
    wk[c + A_SEL, 0] = sel


@kernel
def _row(mp, jp, pair_of, wk, j, eps, w, sigma, mu_on, out):
    """Row j at φ̈ = ``eps`` and the side forces in the rows A_N: each rod's residual and its
    Newton parts r_k, q_k into ``wk`` (module docstring); with ``out`` each joint's S and L added
    to its pair's. Without ``mu_on`` the terms in |·| are left out (the start). Returns
    ``(T, Σ ∂T/∂N_k r_k, ∂T/∂ε − Σ ∂T/∂N_k q_k, converged)``, converged when every |r_k| is
    within TOL of its forces' scale."""
    c = WK_RX
    ns = np.int64(mp[N_SLAVES])
    k0 = j * (1 + ns)
    on = 1.0 if mu_on else 0.0
    mu_s = jp[J_SLIDER, RX_MU] * on
    k_l = jp[J_LINK, RX_MU] * jp[J_LINK, RX_RADIUS] * on
    k_p = jp[J_SLAVE_PIN, RX_MU] * jp[J_SLAVE_PIN, RX_RADIUS] * on
    c_s, c_l, c_p = jp[J_SLIDER, RX_VISCOUS], jp[J_LINK, RX_VISCOUS], jp[J_SLAVE_PIN, RX_VISCOUS]
    ring, ring_p = jp[J_SLIDER, RX_RING_FORCE], jp[J_SLIDER, RX_RING_PRESSURE]
    t0 = wk[c + A_DT, k0]  # the master rod's rate θ₀′
    l0x, l0y = wk[c + A_LX, k0], wk[c + A_LY, k0]
    sfx = sfy = smom = sfx1 = sfy1 = smom1 = 0.0
    converged = True
    for i in range(ns):  # the slaves: their F_Ai and Newton parts
        k = k0 + 1 + i
        s0 = SLAVE0 + SLAVE_STRIDE * i
        cd, sd = mp[s0 + COS_D], mp[s0 + SIN_D]
        N = wk[c + A_N, k]
        P = wk[WK_RX + R_P, k]
        xr, tr = wk[c + A_DX, k], wk[c + A_DT, k]
        s_s, s_p, s_j = wk[c + A_SS, k] * sigma, wk[c + A_SP, k] * sigma, wk[c + A_SJ, k] * sigma
        Fs = -s_s * (mu_s * abs(N) + ring + ring_p * max(P, 0.0)) - c_s * xr * w
        dFs = -s_s * mu_s * (1.0 if N >= 0.0 else -1.0)
        py1 = mp[s0 + SLAVE_PISTON] * wk[c + A_AB1, k]
        py = mp[s0 + SLAVE_PISTON] * wk[c + A_AB0, k] + py1 * eps + P - Fs
        fbx, fby = py * cd + N * sd, py * sd - N * cd
        vx, vy = -dFs * cd + sd, -dFs * sd - cd  # ∂F_B/∂N = ∂F_Ai/∂N
        d1x, d1y = wk[c + A_DX1, k], wk[c + A_DY1, k]
        dx, dy = wk[c + A_DX0, k] + d1x * eps, wk[c + A_DY0, k] + d1y * eps
        fax, fay = fbx + dx, fby + dy
        ex, ey = py1 * cd + d1x, py1 * sd + d1y  # ∂F_Ai/∂ε
        h = wk[c + A_H0, k] + wk[c + A_H1, k] * eps
        lx, ly = wk[c + A_LX, k], wk[c + A_LY, k]
        na, nb = _norm(fax, fay), _norm(fbx, fby)
        ml = -s_j * k_l * na - c_l * (tr - t0) * w
        mb = -s_p * k_p * nb - c_p * tr * w
        ln = s_j * k_l * _slope(fax, fay, vx, vy, na)
        le = s_j * k_l * _slope(fax, fay, ex, ey, na)
        g = _cross(lx, ly, fax, fay) + ml + mb - h
        g_n = _cross(lx, ly, vx, vy) - ln - s_p * k_p * _slope(fbx, fby, vx, vy, nb)
        g_e = (_cross(lx, ly, ex, ey) - le - s_p * k_p * _slope(fbx, fby, py1 * cd, py1 * sd, nb)
               - wk[c + A_H1, k])
        rs = g / g_n
        wk[c + A_RS, k] = rs
        wk[c + A_QS, k] = g_e / g_n
        wk[c + A_FX, k] = fax
        wk[c + A_FY, k] = fay
        wk[c + A_VX, k] = vx
        wk[c + A_VY, k] = vy
        wk[c + A_LN, k] = ln
        converged = converged and abs(rs) <= TOL * (abs(N) + abs(py) + abs(dx) + abs(dy)
                                                   + abs(h) / abs(lx * cd + ly * sd))
        bx, by = l0x + wk[c + A_OX, k], l0y + wk[c + A_OY, k]  # A_i − B
        sfx += fax
        sfy += fay
        smom += _cross(bx, by, fax, fay) + ml
        sfx1 += ex
        sfy1 += ey
        smom1 += _cross(bx, by, ex, ey) - le
        if out:
            _add(pair_of, wk, J_LINK, k, fax * wk[c + A_PX, k] + fay * wk[c + A_PY, k]
                 + ml * t0, -ml * (tr - t0))
            _add(pair_of, wk, J_SLAVE_PIN, k, fbx * xr * cd + fby * xr * sd - mb * tr, -mb * tr)
            _add(pair_of, wk, J_SLIDER, k, -Fs * xr, -Fs * xr)
    # the master piston, the master rod and the throw
    k = k0
    N = wk[c + A_N, k]
    P = wk[WK_RX + R_P, k]
    xr = wk[c + A_DX, k]
    s_s, s_p, s_j = wk[c + A_SS, k] * sigma, wk[c + A_SP, k] * sigma, wk[c + A_SJ, k] * sigma
    k_a = jp[J_CRANKPIN, RX_MU] * jp[J_CRANKPIN, RX_RADIUS] * on
    k_b = jp[J_MASTER_PIN, RX_MU] * jp[J_MASTER_PIN, RX_RADIUS] * on
    k_o = jp[J_MAIN, RX_MU] * jp[J_MAIN, RX_RADIUS] * on
    Fs = -s_s * (mu_s * abs(N) + ring + ring_p * max(P, 0.0)) - c_s * xr * w
    dFs = -s_s * mu_s * (1.0 if N >= 0.0 else -1.0)
    py1 = mp[M_PISTON] * wk[c + A_AB1, k]
    py = mp[M_PISTON] * wk[c + A_AB0, k] + py1 * eps + P - Fs
    fbx, fby = py, -N  # d₀ = x̂, m₀ = ŷ
    d1x, d1y = wk[c + A_DX1, k], wk[c + A_DY1, k]
    dx, dy = wk[c + A_DX0, k] + d1x * eps, wk[c + A_DY0, k] + d1y * eps
    fax, fay = fbx + dx + sfx, fby + dy + sfy
    ex, ey = py1 + d1x + sfx1, d1y + sfy1  # ∂F_A/∂ε
    aax1, aay1 = wk[c + A_AAX1, k], wk[c + A_AAY1, k]
    m_k = mp[M_CRANK]
    fox = fax + m_k * (wk[c + A_AAX0, k] + aax1 * eps)
    foy = fay + m_k * (wk[c + A_AAY0, k] + aay1 * eps)
    h1 = wk[c + A_H1, k]
    h = wk[c + A_H0, k] + h1 * eps
    ax, ay = wk[c + A_AX, k], wk[c + A_AY, k]
    na, nb, no = _norm(fax, fay), _norm(fbx, fby), _norm(fox, foy)
    ma = -s_j * k_a * na - jp[J_CRANKPIN, RX_VISCOUS] * (t0 - 1.0) * w
    mb = -s_p * k_b * nb - jp[J_MASTER_PIN, RX_VISCOUS] * t0 * w
    mo = -sigma * k_o * no - jp[J_MAIN, RX_VISCOUS] * w
    r2 = ax * ax + ay * ay
    g = _cross(l0x, l0y, fax, fay) - smom + ma + mb - h
    T = -_cross(ax, ay, fax, fay) + mo - ma - m_k * r2 * eps
    # in N₀: ∂F_B/∂N₀ = ∂F_A/∂N₀ = ∂F_O/∂N₀ = (−∂F_s/∂N, −1)
    vx, vy = -dFs, -1.0
    sa_n = s_j * k_a * _slope(fax, fay, vx, vy, na)
    g_n = _cross(l0x, l0y, vx, vy) - sa_n - s_p * k_b * _slope(fbx, fby, vx, vy, nb)
    T_n = -_cross(ax, ay, vx, vy) - sigma * k_o * _slope(fox, foy, vx, vy, no) + sa_n
    # in ε
    sa_e = s_j * k_a * _slope(fax, fay, ex, ey, na)
    g_e = (_cross(l0x, l0y, ex, ey) - smom1 - sa_e - s_p * k_b * _slope(fbx, fby, py1, 0.0, nb)
           - h1)
    T_e = (-_cross(ax, ay, ex, ey) - sigma * k_o * _slope(fox, foy, ex + m_k * aax1,
                                                          ey + m_k * aay1, no) + sa_e - m_k * r2)
    # the slaves' N_i enter g₀ and T through F_Ai
    r_sum, q_sum, tr_sum, tq_sum = g, g_e, 0.0, 0.0
    for i in range(ns):
        ki = k0 + 1 + i
        vx, vy = wk[c + A_VX, ki], wk[c + A_VY, ki]
        sa_i = s_j * k_a * _slope(fax, fay, vx, vy, na)
        g_i = -_cross(wk[c + A_OX, ki], wk[c + A_OY, ki], vx, vy) + wk[c + A_LN, ki] - sa_i
        T_i = -_cross(ax, ay, vx, vy) - sigma * k_o * _slope(fox, foy, vx, vy, no) + sa_i
        r_sum -= g_i * wk[c + A_RS, ki]
        q_sum -= g_i * wk[c + A_QS, ki]
        tr_sum += T_i * wk[c + A_RS, ki]
        tq_sum += T_i * wk[c + A_QS, ki]
    r0 = r_sum / g_n
    q0 = q_sum / g_n
    wk[c + A_RS, k] = r0
    wk[c + A_QS, k] = q0
    wk[c + A_FX, k] = fax
    wk[c + A_FY, k] = fay
    wk[c + A_FOX, k] = fox
    wk[c + A_FOY, k] = foy
    converged = converged and abs(r0) <= TOL * (abs(N) + abs(py) + abs(dx) + abs(dy)
                                                + abs(h) / abs(l0x))
    if out:
        _add(pair_of, wk, J_MAIN, k0, -T, -mo)
        _add(pair_of, wk, J_CRANKPIN, k0, -fax * ay + fay * ax + ma, -ma * (t0 - 1.0))
        _add(pair_of, wk, J_MASTER_PIN, k0, fbx * xr - mb * t0, -mb * t0)
        _add(pair_of, wk, J_SLIDER, k0, -Fs * xr, -Fs * xr)
    return T, T_n * r0 + tr_sum, T_e - T_n * q0 - tq_sum, converged


@kernel(inline=True)
def _add(pair_of, wk, joint, k, S, L):
    """Add a joint's S and L to its pair's (none for an ideal joint), L to cylinder k's share
    too: a row's main bearing and master crankpin count as its master cylinder's."""
    p = pair_of[joint]
    if p >= 0:
        wk[WK_S, p] += S
        wk[WK_RX + R_LOSS, p] += L
        wk[WK_CYL_LOSS + p, k] += L


@kernel
def _start(mp, jp, pair_of, wk, eps, w, sigma):
    """The side forces at φ̈ = ``eps`` without the terms in |·|, where the rods' equations are
    linear in them: one elimination from N = 0 solves them."""
    ns = np.int64(mp[N_SLAVES])
    for j in range(np.int64(mp[N_ROWS])):
        for k in range(j * (1 + ns), (j + 1) * (1 + ns)):
            wk[WK_RX + A_N, k] = 0.0
        _row(mp, jp, pair_of, wk, j, eps, w, sigma, False, False)
        for k in range(j * (1 + ns), (j + 1) * (1 + ns)):
            wk[WK_RX + A_N, k] = -wk[WK_RX + A_RS, k]


@kernel
def solve(mp, jp, pair_of, J0, M_shaft, eps0, w, sigma, n_pairs, wk):
    """φ̈ with the joints' friction on their reactions, and per pair η*, S, L into ``wk``, by
    Newton's method on (φ̈, every N_k) from ``eps0`` (module docstring); the rows of
    :func:`prepare` and each cylinder's gas force must be filled. NaN if it does not converge."""
    ns = np.int64(mp[N_SLAVES])
    n = np.int64(mp[N_ROWS]) * (1 + ns)
    eps = eps0
    _start(mp, jp, pair_of, wk, eps, w, sigma)
    for _ in range(MAX_ITER):
        H = J0 * eps - M_shaft
        den = J0
        scale = abs(M_shaft) + J0 * abs(eps)
        small = True
        for j in range(np.int64(mp[N_ROWS])):
            T, T_r, T_q, conv = _row(mp, jp, pair_of, wk, j, eps, w, sigma, True, False)
            H += T_r - T
            den -= T_q
            scale += abs(T)
            small = small and conv
        if not np.isfinite(H):
            return np.nan
        eps -= newton_step(wk, WK_RX + A_N, WK_RX + A_RS, WK_RX + A_QS, n, H, den)
        if small and abs(H) <= TOL * scale:
            _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, n_pairs)
            return eps
    return np.nan


@kernel
def _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, n_pairs):
    """S, L and η* = 1 − L/S of each pair, summed over the rows, and each cylinder's share of
    L in the rows ``WK_CYL_LOSS``; returns Σ T."""
    n = np.int64(mp[N_ROWS]) * (1 + np.int64(mp[N_SLAVES]))
    clear_pairs(wk, n_pairs, n, 0.0)
    total = 0.0
    for j in range(np.int64(mp[N_ROWS])):
        total += _row(mp, jp, pair_of, wk, j, eps, w, sigma, True, True)[0]
    pair_efficiencies(wk, n_pairs)
    return total


@kernel
def inverse_drive(m, eps, w, sigma, M_shaft, wk):
    """The drive torque on the shaft for a prescribed motion (φ̈ = ``eps``), with the joints'
    friction: J₀ ε − M_shaft − Σ T, the side forces by Newton's method at that φ̈ (each row's
    elimination, δε = 0); fills η*, S, L of the pairs. NaN if it does not converge."""
    mp, jp, pair_of = m.mech, m.rx_par, m.rx_pair
    _start(mp, jp, pair_of, wk, eps, w, sigma)
    ns = np.int64(mp[N_SLAVES])
    for j in range(np.int64(mp[N_ROWS])):
        done = False
        for _ in range(MAX_ITER):
            conv = _row(mp, jp, pair_of, wk, j, eps, w, sigma, True, False)[3]
            for k in range(j * (1 + ns), (j + 1) * (1 + ns)):
                wk[WK_RX + A_N, k] -= wk[WK_RX + A_RS, k]
            if conv:
                done = True
                break
        if not done:
            return np.nan
    return m.J0 * eps - M_shaft - _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, m.n_pairs)
