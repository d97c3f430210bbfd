r"""Friction on the reactions of the crank-slider's joints, solved exactly with the motion.

The friction moment of a journal or pin is μ·r·|R| (the friction circle of radius μ·r about
the journal's centre; Meriam & Kraige, *Engineering Mechanics: Statics*, journal bearings,
M = μ r R for small μ) plus a viscous c·q, opposing the joint's relative angular speed q; the
piston in its cylinder (the slider) feels μ·|N| from the side force N, the rings' tension
friction F_ring, a share c_p of the gas force P that presses the top ring to the wall
(p·π·D·h behind a ring of height h, so c_p = 4 μ_ring h/D of P = p·π D²/4; the ring-tension
and gas-pressure terms of Patton, Nitschke & Heywood, SAE 890836, 1989) and a viscous c·v,
all opposing the piston's speed v. Every term of the loss is a magnitude times the speed it
opposes, so the power lost, Σ (μ r |R| + c|q|)|q| + (μ|N| + F_ring + c_p P⁺ + c|v|)|v|, is ≥ 0.

The reactions by Newton–Euler
-----------------------------
Per cylinder, in its own frame (:mod:`transient.core.model.crank_slider`;
``transient.reference.crank_slider_joint_forces`` solves the same bodies as eight linear
equations and is the independent check): the piston
(mass m_p at the pin B), the rod (point masses at B and A and a rigid part at G with inertia I
about G — the packed masses of :mod:`transient.core.model.crank_slider`), the throw (m_k at the crankpin
A). With F_B the rod's force on the piston, F_A the throw's on the rod, P_y = m_p a_By + P + F_s the
piston's axial balance (F_s the slider's friction, toward the crank), D the rod's mass times
acceleration and H its rate of angular momentum about B::

    F_B = (−N, P_y),  F_A = F_B + D,  F_O = F_A + m_k a_A        (Newton)
    l cos β (N − D_x) − l sin β (P_y + D_y) − M_A − M_B + H = 0    (rod, moments about B)
    T = −m_k r² ε − M_O + M_A + A × F_A                          (throw, moments about O)

M_O, M_A, M_B are the joints' friction moments (about z, on the throw, on the rod, on the rod)
and T the throw's torque on the shaft; the shaft obeys J₀ ε = M_load + M_starter + Σ_cyl T.
All accelerations are affine in ε = φ̈ at a given state (φ, ω), so everything above is too,
except the friction, which depends on |F_O|, |F_A|, |F_B|, |N|.

The exact solve
---------------
Each cylinder has one more unknown, N, and one more equation, its rod's g(N, ε) = 0, with
∂g/∂N = l cos β (1 + O(μ tan β) + O(μ r/l)) > 0; the shaft adds h(ε, N) = J₀ ε − M_shaft −
Σ T = 0. Newton's method solves (ε, N_1 … N_n) together, from the frictionless φ̈ and N,
with the exact Jacobian: its only couplings are through ε (an arrowhead matrix), so each
iteration costs one evaluation per cylinder and the correction is explicit (:func:`solve`); the
functions are smooth except for the |·| of N and of the joint forces. It stops when the last
corrections are below :data:`TOL` (1e-7) of the magnitude of the terms and applies them:
convergence being quadratic with a constant of the order of μ·r/l over the forces, what remains
is about 1e-3·TOL² of them, below rounding (in the rare case that a |·| has its kink within the
last correction it is at most μ·TOL instead). Two or three iterations do it. The residuals
of the implicit equations are then rounding (``tests/unit/test_joint_friction.py``). Nothing is
lagged from an earlier evaluation: the solve starts afresh at every state, so the result is a
function of the state alone. If it has not converged after :data:`MAX_ITER` corrections (a
wedging mechanism, which the scene check excludes), φ̈ is NaN and the run stops with the
non-finite derivative reported with its time, angle and state.

Directions and smoothness
-------------------------
The sign of each joint's relative speed is taken at the angle ``sel`` of the current step
(cached per ``sel``) times the direction of motion σ: the piston's speed changes sign at the
dead centres, the rod's rate β̇ at α = 90°, 270°, and ``transient.assemble`` makes those angles
breakpoints, so no friction force reverses inside a step; the throw's and the crankpin's
relative rates keep the sign of ω. What remains non-smooth are the kinks of the |·|: chiefly
μ·|N| where a side force changes side, at angles that depend on the motion (several per
cylinder and cycle: where the forces along the rod change sign, and beside the dead centres,
where the rod stands along the cylinder). In crank angle the stepper puts step ends on them:
every stage's solve records its N (:func:`track_sides`), and a step that the error test rejects
while its stages show an N changing side is retaken at once to end where they put N's root
(:func:`side_change`), so that the kink lies between two steps instead of inside a run of
rejected and shrinking ones. The function integrated is unchanged (no side is held, nothing is
lagged): where a step ends decides only the cost, and the error test judges every step as
before. Beside a dead centre, where the piston's speed is near zero, the slider's friction
barely bends φ̈ and those steps pass the error test as they are. Holding each side over a step
and switching it on a located state event would make every step smooth too, but an event costs
more right-hand sides than such a kink does, and there are events beside every dead centre. At
rest (ω = 0) the chain's rule for the incipient motion applies unchanged
(``reactions.choose_direction``).

Outputs per pair (the joints of all cylinders that one pair names): the loss moment L (the power
lost over ω), the moment S the shaft side puts into the joint (its power over ω: the shaft into
the throws for the main bearings, the throw into the rod for the crankpins, the rod into the
piston for the piston pins, the piston into the wall for the slider) and η* = 1 − L/S, so that
the loss is (1 − η*) S ω as for a constant-η pair: η* < 1 when the shaft side drives, > 1 when
the far side does, 0 for the slider (the wall takes no power), NaN where S = 0.

Shapes: ``jp`` = ``Model.rx_par`` float64[N_JOINTS, N_RX_PAR]; the rows ``WK_RX + R_*`` of
``wk`` hold one value per cylinder (``R_LOSS``: per pair).
"""
from __future__ import annotations

from math import cos, sin, sqrt

import numpy as np

from ..declare import Layout
from ..jit import kernel
from .crank_slider import (
    I_ROD,
    M_CRANK,
    M_CRANKPIN,
    M_PIN,
    M_PISTON,
    M_ROD,
    N_CYL,
    ROD_CG,
    SIN0,
    E,
    L,
    R,
    rod_and_piston,
    rod_and_piston_second,
)
from .layout import (
    JOINT_CRANKPIN,
    JOINT_MAIN,
    JOINT_PIN,
    JOINT_SLIDER,
    RX_MU,
    RX_RADIUS,
    RX_RING_FORCE,
    RX_RING_PRESSURE,
    RX_VISCOUS,
    WK_CYL_LOSS,
    WK_ETA,
    WK_RX,
    WK_S,
)

#: The rows from ``layout.WK_RX`` that every reaction solver shares, so that its callers fill
#: and read them alike: each piston's gas force P (filled by :func:`.forcing.moments`), the step's
#: angle ``sel`` that the joints' directions are for ([0]; a solver may keep its own) and, per
#: pair, the moment its losses reduce to.
SHARED = Layout("reaction rows, shared", "P", "sel", "loss")
R_P, R_SEL, R_LOSS = SHARED
#: The crank-slider's own rows, after the shared ones (offsets from ``layout.WK_RX``): geometry at
#: the state (l cos β, l sin β, the crankpin's position r sin α, r cos α, β′, s′), then per
#: acceleration its part at ε = 0 and its slope in ε (a_By, a_Ax, a_Ay, D_x, D_y, H), the signs
#: of the crankpin's, the piston pin's and the piston's relative speed at ``sel`` per unit σ, N's
#: iterate, per cylinder the parts g/g′ and (∂g/∂ε)/g′ of its Newton correction, and 1/(l cos β)
#: (the solve multiplies by it, a division here); then the side forces seen by a step attempt's
#: stages (:func:`track_sides`): the largest abscissa with N ≥ 0 and N there, the least with
#: N < 0 and N there, the largest with N < 0, the least with N ≥ 0 (and N at each).
ROWS = Layout("crank-slider reaction rows",
              "lcb", "lsb", "ax", "ay", "db", "ds", "aby0", "aby1", "aax0", "aax1", "aay0",
              "aay1", "dx0", "dx1", "dy0", "dy1", "h0", "h1", "sa", "sb", "ss", "n", "step",
              "couple", "ilcb", "xp_hi", "np_hi", "xn_lo", "nn_lo", "xn_hi", "nn_hi", "xp_lo",
              "np_lo", start=SHARED.end)
(R_LCB, R_LSB, R_AX, R_AY, R_DB, R_DS, R_ABY0, R_ABY1, R_AAX0, R_AAX1, R_AAY0, R_AAY1, R_DX0,
 R_DX1, R_DY0, R_DY1, R_H0, R_H1, R_SA, R_SB, R_SS, R_N, R_STEP, R_COUPLE, R_ILCB,
 R_XP_HI, R_NP_HI, R_XN_LO, R_NN_LO, R_XN_HI, R_NN_HI, R_XP_LO, R_NP_LO) = ROWS

#: Newton's method has converged when its corrections are below TOL of their scales; the
#: correction is then applied and, convergence being quadratic with a constant of the order of
#: μ·r/l over the force scale, leaves a relative error of about 1e-3·TOL², below rounding.
TOL = 1e-7
#: Corrections at most before a solve is reported as failed (NaN).
MAX_ITER = 40


@kernel
def prepare(mp, phi, w, sel, wk):
    """The rows of the state (φ, ω) for :func:`solve`: each cylinder's geometry and the parts of
    its accelerations; the joints' directions at ``sel`` when ``sel`` has changed."""
    c = WK_RX
    r = mp[R]
    l = mp[L]
    e = mp[E]
    n = np.int64(mp[N_CYL])
    f = mp[ROD_CG] / l
    m_pin, m_cp, m_rod, i_rod = mp[M_PIN], mp[M_CRANKPIN], mp[M_ROD], mp[I_ROD]
    w2 = w * w
    sp, cp = sin(phi), cos(phi)
    for k in range(n):
        s0 = mp[SIN0 + k]
        c0 = mp[SIN0 + n + k]
        sa = sp * c0 - cp * s0
        ca = cp * c0 + sp * s0
        sb, cb, db, ds = rod_and_piston(sa, ca, r, l, e)
        ddb, dds = rod_and_piston_second(sa, ca, r, l, sb, cb, db)
        lcb, lsb = l * cb, l * sb
        ax, ay = r * sa, r * ca
        wk[c + R_LCB, k] = lcb
        wk[c + R_LSB, k] = lsb
        wk[c + R_ILCB, k] = 1.0 / lcb
        wk[c + R_AX, k] = ax
        wk[c + R_AY, k] = ay
        wk[c + R_DB, k] = db
        wk[c + R_DS, k] = ds
        # part 0: ε = 0 (the ω² terms); part 1: the slope in ε
        for part in range(2):
            if part == 0:
                aby, aax, aay, bdd = -dds * w2, -ax * w2, -ay * w2, ddb * w2
            else:
                aby, aax, aay, bdd = -ds, ay, -ax, db
            agx = f * aax
            agy = (1.0 - f) * aby + f * aay
            wk[c + R_ABY0 + part, k] = aby
            wk[c + R_AAX0 + part, k] = aax
            wk[c + R_AAY0 + part, k] = aay
            wk[c + R_DX0 + part, k] = m_cp * aax + m_rod * agx
            wk[c + R_DY0 + part, k] = m_pin * aby + m_cp * aay + m_rod * agy
            wk[c + R_H0 + part, k] = (lsb * (m_cp * aay + f * m_rod * agy)
                                      + lcb * (m_cp * aax + f * m_rod * agx) + i_rod * bdd)
    if wk[c + R_SEL, 0] != sel:
        ss, cs = sin(sel), cos(sel)
        for k in range(n):
            s0 = mp[SIN0 + k]
            c0 = mp[SIN0 + n + k]
            sb, cb, db, ds = rod_and_piston(ss * c0 - cs * s0, cs * c0 + ss * s0, r, l, e)
            wk[c + R_SA, k] = np.sign(1.0 + db)
            wk[c + R_SB, k] = np.sign(db)
            wk[c + R_SS, k] = np.sign(ds)
        wk[c + R_SEL, 0] = sel


@kernel(inline=True)
def _norm(x, y):
    return sqrt(x * x + y * y)


@kernel(inline=True)
def _inverse(norm):
    """1/|F| for the slopes F̂·dF = (F·dF)/|F| (0 at F = 0, as :func:`_slope`)."""
    if norm == 0.0:
        return 0.0
    return 1.0 / norm


@kernel(inline=True)
def _slope(fx, fy, dx, dy, norm):
    """d|F| for dF = (dx, dy): F̂·dF (0 at F = 0, where |F| has its kink)."""
    if norm == 0.0:
        return 0.0
    return (fx * dx + fy * dy) / norm


@kernel(inline=True)
def cylinder(mp, jp, wk, k, eps, w, sigma, N):
    """Cylinder k at φ̈ = ``eps`` and side force ``N``: the residual g of its rod equation, ∂g/∂N,
    ∂g/∂ε, the throw's torque T, ∂T/∂N, ∂T/∂ε and the scale of its forces."""
    c = WK_RX
    lcb, lsb = wk[c + R_LCB, k], wk[c + R_LSB, k]
    ax, ay = wk[c + R_AX, k], wk[c + R_AY, k]
    db, ds = wk[c + R_DB, k], wk[c + R_DS, k]
    aby1, aax1, aay1 = wk[c + R_ABY1, k], wk[c + R_AAX1, k], wk[c + R_AAY1, k]
    dx1, dy1, h1 = wk[c + R_DX1, k], wk[c + R_DY1, k], wk[c + R_H1, k]
    aby = wk[c + R_ABY0, k] + aby1 * eps
    aax = wk[c + R_AAX0, k] + aax1 * eps
    aay = wk[c + R_AAY0, k] + aay1 * eps
    dx = wk[c + R_DX0, k] + dx1 * eps
    dy = wk[c + R_DY0, k] + dy1 * eps
    h = wk[c + R_H0, k] + h1 * eps
    P = wk[c + R_P, k]
    m_p, m_k, r = mp[M_PISTON], mp[M_CRANK], mp[R]
    s_s = wk[c + R_SS, k] * sigma
    s_a = wk[c + R_SA, k] * sigma
    s_b = wk[c + R_SB, k] * sigma
    # the slider: force toward the crank, opposing the piston's speed s′ω
    mu_s = jp[JOINT_SLIDER, RX_MU]
    f0 = jp[JOINT_SLIDER, RX_RING_FORCE] + jp[JOINT_SLIDER, RX_RING_PRESSURE] * max(P, 0.0)
    sgn_n = 1.0 if N >= 0.0 else -1.0
    Fs = -s_s * (mu_s * abs(N) + f0) - jp[JOINT_SLIDER, RX_VISCOUS] * ds * w
    dFs = -s_s * mu_s * sgn_n
    py = m_p * aby + P + Fs
    fbx, fby = -N, py
    fax, fay = dx - N, py + dy
    fox, foy = fax + m_k * aax, fay + m_k * aay
    nb, na, no = _norm(fbx, fby), _norm(fax, fay), _norm(fox, foy)
    # the unit vectors' factors: each |F| is differentiated twice (in N and in ε), so one
    # division per force, not one per slope (divisions and square roots share one unit)
    ib, ia, io = _inverse(nb), _inverse(na), _inverse(no)
    ka = jp[JOINT_CRANKPIN, RX_MU] * jp[JOINT_CRANKPIN, RX_RADIUS]
    kb = jp[JOINT_PIN, RX_MU] * jp[JOINT_PIN, RX_RADIUS]
    ko = jp[JOINT_MAIN, RX_MU] * jp[JOINT_MAIN, RX_RADIUS]
    # moments about z on the outer body, opposing its relative rate q = ρ ω: ρ = 1 + β′ (rod on
    # throw), β′ (rod on piston), −1 (throw on frame)
    Ma = -s_a * ka * na - jp[JOINT_CRANKPIN, RX_VISCOUS] * (1.0 + db) * w
    Mb = -s_b * kb * nb - jp[JOINT_PIN, RX_VISCOUS] * db * w
    Mo = sigma * ko * no + jp[JOINT_MAIN, RX_VISCOUS] * w
    g = lcb * (N - dx) - lsb * (py + dy) - Ma - Mb + h
    T = -m_k * r * r * eps - Mo + Ma + (ax * fay - ay * fax)
    # in N (dF/dN = (−1, dFs) for F_B, F_A, F_O alike): d|F| = F̂·dF (:func:`_slope`)
    dMa = -s_a * ka * (dFs * fay - fax) * ia
    dMb = -s_b * kb * (dFs * fby - fbx) * ib
    dMo = sigma * ko * (dFs * foy - fox) * io
    g_n = lcb - lsb * dFs - dMa - dMb
    T_n = -dMo + dMa + (ax * dFs + ay)
    # in ε at fixed N
    py1 = m_p * aby1
    fax1, fay1 = dx1, py1 + dy1
    Ma1 = -s_a * ka * (fax * fax1 + fay * fay1) * ia
    Mb1 = -s_b * kb * fby * py1 * ib
    Mo1 = sigma * ko * (fox * (fax1 + m_k * aax1) + foy * (fay1 + m_k * aay1)) * io
    g_e = -lcb * dx1 - lsb * (py1 + dy1) - Ma1 - Mb1 + h1
    T_e = -m_k * r * r - Mo1 + Ma1 + (ax * fay1 - ay * fax1)
    scale = abs(N) + abs(py) + abs(dx) + abs(dy) + abs(h) * wk[c + R_ILCB, k]
    return g, g_n, g_e, T, T_n, T_e, scale


@kernel(inline=True)
def joint_terms(mp, jp, wk, k, eps, w, sigma, N):
    """Per joint of cylinder k at (ε, N): ``(S_main, S_crankpin, S_pin, S_slider, L_main, …)``,
    the moment the shaft side puts into the joint and the loss moment (powers over ω; module
    docstring), as :func:`cylinder` computes its forces."""
    c = WK_RX
    ax, ay = wk[c + R_AX, k], wk[c + R_AY, k]
    db, ds = wk[c + R_DB, k], wk[c + R_DS, k]
    aby = wk[c + R_ABY0, k] + wk[c + R_ABY1, k] * eps
    aax = wk[c + R_AAX0, k] + wk[c + R_AAX1, k] * eps
    aay = wk[c + R_AAY0, k] + wk[c + R_AAY1, k] * eps
    dx = wk[c + R_DX0, k] + wk[c + R_DX1, k] * eps
    dy = wk[c + R_DY0, k] + wk[c + R_DY1, k] * eps
    P = wk[c + R_P, k]
    m_p, m_k, r = mp[M_PISTON], mp[M_CRANK], mp[R]
    s_s = wk[c + R_SS, k] * sigma
    s_a = wk[c + R_SA, k] * sigma
    s_b = wk[c + R_SB, k] * sigma
    f0 = jp[JOINT_SLIDER, RX_RING_FORCE] + jp[JOINT_SLIDER, RX_RING_PRESSURE] * max(P, 0.0)
    Fs = -s_s * (jp[JOINT_SLIDER, RX_MU] * abs(N) + f0) - jp[JOINT_SLIDER, RX_VISCOUS] * ds * w
    py = m_p * aby + P + Fs
    fax, fay = dx - N, py + dy
    fox, foy = fax + m_k * aax, fay + m_k * aay
    Ma = (-s_a * jp[JOINT_CRANKPIN, RX_MU] * jp[JOINT_CRANKPIN, RX_RADIUS] * _norm(fax, fay)
          - jp[JOINT_CRANKPIN, RX_VISCOUS] * (1.0 + db) * w)
    Mb = (-s_b * jp[JOINT_PIN, RX_MU] * jp[JOINT_PIN, RX_RADIUS] * _norm(N, py)
          - jp[JOINT_PIN, RX_VISCOUS] * db * w)
    Mo = (sigma * jp[JOINT_MAIN, RX_MU] * jp[JOINT_MAIN, RX_RADIUS] * _norm(fox, foy)
          + jp[JOINT_MAIN, RX_VISCOUS] * w)
    T = -m_k * r * r * eps - Mo + Ma + (ax * fay - ay * fax)
    L_s = -Fs * ds
    return (-T, fax * ay - fay * ax - Ma, -py * ds - Mb * db, L_s,
            Mo, -Ma * (1.0 + db), -Mb * db, L_s)


@kernel(inline=True)
def start_n(mp, jp, wk, k, eps, w, sigma):
    """N of cylinder k at φ̈ = ``eps`` without the friction that depends on the forces (the rod
    equation is then linear in N): where Newton's method starts, so that its first step already
    has the side force's sign."""
    c = WK_RX
    lsb, db, ds = wk[c + R_LSB, k], wk[c + R_DB, k], wk[c + R_DS, k]
    P = wk[c + R_P, k]
    f0 = jp[JOINT_SLIDER, RX_RING_FORCE] + jp[JOINT_SLIDER, RX_RING_PRESSURE] * max(P, 0.0)
    py = (mp[M_PISTON] * (wk[c + R_ABY0, k] + wk[c + R_ABY1, k] * eps) + P
          - wk[c + R_SS, k] * sigma * f0 - jp[JOINT_SLIDER, RX_VISCOUS] * ds * w)
    dx = wk[c + R_DX0, k] + wk[c + R_DX1, k] * eps
    dy = wk[c + R_DY0, k] + wk[c + R_DY1, k] * eps
    h = wk[c + R_H0, k] + wk[c + R_H1, k] * eps
    m_visc = -(jp[JOINT_CRANKPIN, RX_VISCOUS] * (1.0 + db) + jp[JOINT_PIN, RX_VISCOUS] * db) * w
    return dx + (lsb * (py + dy) + m_visc - h) * wk[c + R_ILCB, k]


@kernel
def solve_cylinder(mp, jp, wk, k, eps, w, sigma):
    """N of cylinder k at a given φ̈ = ``eps`` (inverse dynamics) by Newton's method from
    :func:`start_n`, into the row R_N; returns False if it does not converge."""
    N = start_n(mp, jp, wk, k, eps, w, sigma)
    for _ in range(MAX_ITER):
        g, g_n, _, _, _, _, scale = cylinder(mp, jp, wk, k, eps, w, sigma, N)
        step = g / g_n
        N -= step
        if abs(step) <= TOL * scale:
            wk[WK_RX + R_N, k] = N
            return True
    return False


@kernel
def solve(mp, jp, pair_of, J0, M_shaft, eps0, w, sigma, n_pairs, wk):
    """φ̈ with the joints' friction on their reactions, and per pair η*, S, L into ``wk``.

    Newton's method on the unknowns (φ̈, N_1 … N_n) together (module docstring): with r_k = g_k/g′_k
    and q_k = (∂g_k/∂ε)/g′_k the correction of N_k is −r_k − q_k δε, and the shaft's equation
    H = J₀ ε − M_shaft − Σ T_k = 0 gives δε = −(H + Σ ∂T_k/∂N r_k) / (J₀ − Σ (∂T_k/∂ε −
    ∂T_k/∂N q_k)). ``eps0`` starts it (the frictionless φ̈), N from 0; ``pair_of`` =
    ``Model.rx_pair``; the rows of :func:`prepare` and each cylinder's gas force (row R_P) must be
    filled. Returns NaN if it does not converge (module docstring)."""
    n = np.int64(mp[N_CYL])
    c = WK_RX
    eps = eps0
    for k in range(n):
        wk[c + R_N, k] = start_n(mp, jp, wk, k, eps, w, sigma)
    for _ in range(MAX_ITER):
        H = J0 * eps - M_shaft
        den = J0
        scale = abs(M_shaft) + J0 * abs(eps)
        small = True
        for k in range(n):
            g, g_n, g_e, T, T_n, T_e, s = cylinder(mp, jp, wk, k, eps, w, sigma, wk[c + R_N, k])
            i_n = 1.0 / g_n
            r = g * i_n
            q = g_e * i_n
            wk[c + R_STEP, k] = r
            wk[c + R_COUPLE, k] = q
            H += T_n * r - T
            den -= T_e - T_n * q
            scale += abs(T)
            small = small and abs(r) <= TOL * s
        if not np.isfinite(H):
            return np.nan
        eps -= newton_step(wk, c + R_N, c + R_STEP, c + R_COUPLE, n, H, den)
        if small and abs(H) <= TOL * scale:
            _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, n_pairs)
            return eps
    return np.nan


@kernel
def _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, n_pairs):
    """S, L and η* = 1 − L/S of each pair, summed over the cylinders, into ``wk``; each
    cylinder's share of L in the rows ``WK_CYL_LOSS``."""
    n = np.int64(mp[N_CYL])
    clear_pairs(wk, n_pairs, n, 0.0)
    for k in range(n):
        t = joint_terms(mp, jp, wk, k, eps, w, sigma, wk[WK_RX + R_N, k])
        for j in range(4):
            p = pair_of[j]
            if p >= 0:
                wk[WK_S, p] += t[j]
                wk[WK_RX + R_LOSS, p] += t[4 + j]
                wk[WK_CYL_LOSS + p, k] += t[4 + j]
    pair_efficiencies(wk, n_pairs)


@kernel(inline=True)
def newton_step(wk, row_x, row_r, row_q, n, num, den):
    """The step of φ̈ in a Newton iteration on (φ̈, x_1 … x_n) whose Jacobian is an arrowhead,
    each x_k's own row eliminated already into x_k's step r_k − q_k δφ̈ (rows ``row_r``,
    ``row_q`` of ``wk``): δφ̈ = num/den, and every x_k (row ``row_x``) moved by its step. The
    three mechanisms' solvers share it."""
    step = num / den
    for k in range(n):
        wk[row_x, k] -= wk[row_r, k] - wk[row_q, k] * step
    return step


@kernel(inline=True)
def clear_pairs(wk, n_pairs, n_cyl, split):
    """Before a mechanism's joints add their S and L to their pairs': every pair's S and L 0,
    each cylinder's share ``split`` (0, or NaN for a pair whose loss no cylinder owns)."""
    for p in range(n_pairs):
        wk[WK_S, p] = 0.0
        wk[WK_RX + R_LOSS, p] = 0.0
        for k in range(n_cyl):
            wk[WK_CYL_LOSS + p, k] = split


@kernel(inline=True)
def pair_efficiencies(wk, n_pairs):
    """η* = 1 − L/S of each pair from its S and L (NaN where S = 0), as every mechanism's
    reaction pairs report it (module docstring)."""
    for p in range(n_pairs):
        s = wk[WK_S, p]
        wk[WK_ETA, p] = 1.0 - wk[WK_RX + R_LOSS, p] / s if s != 0.0 else np.nan


@kernel
def reset_sides(n, wk):
    """Before a step attempt: no stage has seen the side force of any of the n cylinders yet
    (:func:`track_sides`)."""
    c = WK_RX
    for k in range(n):
        wk[c + R_XP_HI, k] = -np.inf
        wk[c + R_XN_HI, k] = -np.inf
        wk[c + R_XN_LO, k] = np.inf
        wk[c + R_XP_LO, k] = np.inf


@kernel(inline=True)
def track_sides(n, x, wk):
    """After a stage's solve at abscissa ``x``: the N of each of the n cylinders (row R_N) into
    the extremes of the abscissae at which the step's stages saw it on either side
    (:func:`side_change`)."""
    c = WK_RX
    for k in range(n):
        N = wk[c + R_N, k]
        if N >= 0.0:
            if x > wk[c + R_XP_HI, k]:
                wk[c + R_XP_HI, k] = x
                wk[c + R_NP_HI, k] = N
            if x < wk[c + R_XP_LO, k]:
                wk[c + R_XP_LO, k] = x
                wk[c + R_NP_LO, k] = N
        else:
            if x > wk[c + R_XN_HI, k]:
                wk[c + R_XN_HI, k] = x
                wk[c + R_NN_HI, k] = N
            if x < wk[c + R_XN_LO, k]:
                wk[c + R_XN_LO, k] = x
                wk[c + R_NN_LO, k] = N


@kernel
def side_change(n, wk):
    """The earliest abscissa at which a step attempt's stages show a side force changing side
    (:func:`track_sides`), or ∞: where every stage with N on one side lies before every stage with
    it on the other, N's root between the two nearest, by linear interpolation. Only where it
    is: stages that alternate (two changes, or none in the ε of a stage state's error) show
    none."""
    c = WK_RX
    first = np.inf
    for k in range(n):
        x0, x1 = wk[c + R_XP_HI, k], wk[c + R_XN_LO, k]  # positive, then negative
        n0, n1 = wk[c + R_NP_HI, k], wk[c + R_NN_LO, k]
        if not x0 < x1:
            x0, x1 = wk[c + R_XN_HI, k], wk[c + R_XP_LO, k]  # negative, then positive
            n0, n1 = wk[c + R_NN_HI, k], wk[c + R_NP_LO, k]
        if x0 < x1 and np.isfinite(x0) and np.isfinite(x1):
            first = min(first, x0 + (x1 - x0) * n0 / (n0 - n1))
    return first


@kernel
def inverse_drive(m, eps, w, sigma, M_shaft, wk):
    """The drive torque on the shaft for a prescribed motion (φ̈ = ``eps``), with the joints'
    friction: J₀ ε − M_shaft − Σ T; fills η*, S, L of the pairs. NaN if a cylinder's solve does
    not converge."""
    mp = m.mech
    total = 0.0
    for k in range(np.int64(mp[N_CYL])):
        if not solve_cylinder(mp, m.rx_par, wk, k, eps, w, sigma):
            return np.nan
        total -= joint_terms(mp, m.rx_par, wk, k, eps, w, sigma, wk[WK_RX + R_N, k])[0]
    _pair_terms(mp, m.rx_par, m.rx_pair, wk, eps, w, sigma, m.n_pairs)
    return m.J0 * eps - M_shaft - total
