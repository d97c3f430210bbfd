r"""Friction on the reactions of the swash-plate mechanism's joints, solved exactly with the motion.

The joints with friction and their laws (as :mod:`.joint_friction` has them for the crank-slider):

* the main bearing (frame – shaft with the plates): μ·r·|F_O| + c·ω about the shaft axis, opposing
  ω; F_O is the frame's force on the shaft, the resultant of the plate bearings' forces (with one
  half it includes the pistons' axial thrust, which a thrust bearing of the same mean radius
  takes; with the mirror half the axial forces of the two plates cancel). The bearings' tilting
  moments, which depend on their spacing (no datum of the scene), are left out of the friction;
* the plate bearing 11 (plate – link 9, turning on the plate about its normal n by θ):
  μ·r·|F_P| + c·|q| about n, opposing link 9's rate on the plate q = θ′ω (θ′ < 0 at every angle,
  so q has the sign of −ω throughout); F_P the plate's force on link 9, its tilting moment left
  out as the main bearing's;
* each piston in its cylinder: side force N_k, a 2-D vector across the cylinder axis, and along
  the axis μ|N_k| + F_ring + c_p·P_k⁺ + c·|v_k| opposing the piston's speed v_k = x_D′ω (the laws
  and sources of :mod:`.joint_friction`).

The ball joints B_k (link 9 – rod) and D_k (rod – piston) and the Hooke joint's cross 13 are ideal
here. Ideal ball joints pass forces only, so a rod's equation about its own axis is 0 = 0 and its
spin about that axis, which nothing fixes, never enters. With friction in both joints (a moment
μ r |R| about the direction of each joint's relative angular velocity, the friction circle's 3-D
form) the spin is a further unknown per rod, set where the two joints' axial moments cancel (the
rod has no inertia about its axis). That balance is single-valued only while the rod swings:
where its swing turns, its rate across its axis e × ė vanishes (exactly, for a cylinder on the
plane of symmetry of the swing), the balance becomes a stick–slip choice (the spin sticks to the
piston's joint or slips in it) and the across-axis friction at D reverses. Near those angles the
balance is a near-step in the spin, on which a Newton iteration carrying the spin with the other
unknowns oscillates; friction in the ball joints needs the spin solved apart (bracketed, it is
monotone) and those angles as breakpoints.

Frame, kinematics and equation numbers are those of :mod:`transient.core.model.swash_plate` (Antonyuk et
al. §2:
(5), (6), (8), (10)); the reduced model is their (18)–(21), which the frictionless Newton–Euler
below reproduces (``tests/unit/test_swash_friction.py``).

The reactions by Newton–Euler
-----------------------------
All accelerations are affine in ε = φ̈ at a state (φ, ω): per unit shaft rate, x_D′, x_D″ of
piston k, its rod's direction e_k = (B_k − D_k)/ℓ with e′, e″, link 9's w = ω₉/φ̇ = i + θ′n and
w′ (8), cross 13's u₁₃, u₁₃′ (:func:`.swash_plate.rod_motion`, :func:`.swash_plate.link_motion`).

*Piston k* (mass m_p, D_k on its axis x̂): with G_k the piston's force on the rod, P_k the gas
force (toward +x) and f_k the cylinder's axial friction force on it,
m_p a_D x̂ = −G_k + (P_k + f_k) x̂ + N_k, so G_k⊥ = N_k, G_kx = P_k + f_k − m_p a_D.

*Rod k* (mass m at G = D + c·e, inertia I across its axis, none about it), F_k the force of link 9
on it at B: F_k + G_k = m a_G, and about G, (ℓ − c) e × F_k − c e × G_k = I e × ë. Eliminating F_k,
e × G_k = e × Q_k with Q_k = ((ℓ − c) m a_G − I ë)/ℓ: the moment equation fixes G_k up to its
component along the rod, G_k = Q_k + t_k e_k (the axial force t_k; the third moment equation, about
e, is 0 = 0, the indeterminacy of a rod between ball joints). The piston's axial equation gives
t_k = (P_k + f_k − m_p a_D − Q_kx)/e_kx, its lateral one N_k = Q_k⊥ + t_k e_k⊥, and
F_k = K_k − t_k e_k with K_k = m a_G − Q_k.

*Link 9* (centre at O, inertia J_p about n, J_d across): the cross carries only moments here (its
force, at O like the plate bearing's, is statically indeterminate against it; the plate bearing
is taken to carry all), so F_P = Σ_k F_k. Its moment equation about O,

    M_P + M_f n + M_c − Σ_k B_k × F_k = Ḣ₉,   Ḣ₉ = J α₉ + ω₉ × J ω₉ = ε H₁ + ω² H₀,

with M_P ⊥ n the plate bearing's reaction moment, M_f its friction moment, and M_c the cross's
moment: its hinge on link 9 (axis c) passes no moment about c, and cross 13 turns about its fixed
housing hinge a with I₁₃ ψ̈, ψ̇ = u₁₃ω (its housing hinge passes none about a), so
M_c = −I₁₃ ψ̈ a + λ (a × c) with λ unknown. Three equations for (M_P, λ): with
V = Ḣ₉ + I₁₃ ψ̈ a + Σ B_k × F_k, λ = (V − M_f n)·n / ((a × c)·n) and M_P = V − M_f n − λ (a × c).
((a × c)·n ≠ 0: a·n ≤ sin α < 1.)

*Shaft with the plates* (J₀, balanced): the torque link 9 puts on it is T = −x̂·(M_P + M_f n) per
half, i.e.

    T = −ξ·(Ḣ₉ + I₁₃ ψ̈ a) − Σ_k (ξ × B_k)·F_k − κ M_f,   ξ = x̂ − κ n,  κ = x̂·(a × c) / (a × c)·n,

so J₀ ε = M_shaft − M_O + h T, h = 1 or 2 halves (the mirror half's torque equals half 1's, its
force is half 1's mirrored: F_O = F_P with one half, (0, 2F_Py, 2F_Pz) with two). Without
friction h·T = −(J ε + ½J′ω² − Σ P u), the reduced model's (18).

The exact solve
---------------
Unknowns (ε, f_1 … f_z): each piston's friction equation g_k = f_k + s_k (μ|N_k| + F_ring +
c_p P_k⁺) + c x_D′ω = 0 involves only f_k and ε (N_k is affine in both, ∂N_k/∂f_k = e_k⊥/e_kx),
and the shaft's H = J₀ε − M_shaft + M_O − hT = 0 all of them: the Jacobian is an arrowhead, as
the crank-slider's, and Newton's method (from the frictionless φ̈, each f_k from its N at
f = 0) corrects δf_k = −g_k/g_k′ − (∂g_k/∂ε)/g_k′ δε, with δε from the shaft's row (:func:`solve`).
∂g_k/∂f_k = 1 + s_k μ N̂_k·e_k⊥/e_kx ≥ 1 − μ tan(rod tilt) > 0 (the tilt is a few degrees), so
each piston's equation has one root. The friction moments M_O, M_f are explicit in (ε, f): the
forces do not depend on the moments. The stopping rule, the NaN on failure, and the absence of
anything lagged are those of :mod:`.joint_friction` (:data:`~transient.core.model.joint_friction.TOL`,
:data:`~transient.core.model.joint_friction.MAX_ITER`).

Directions: each piston's speed changes sign at its dead centres, which ``transient.assemble``
makes breakpoints (signs taken at the step's angle ``sel``, per unit σ); the plate bearing's and
the main bearing's rates keep the sign of ω.

Outputs per pair (``Model.rx_pair`` per joint, summed over the halves and cylinders), as
:mod:`.joint_friction` defines them: the main bearing S = M_O − hT (what the shaft puts into the
plates), L = M_O; the plate bearing S = −hT (what the plates put into link 9), L = −h M_f θ′; the
pistons S = L = −h Σ f_k x_D′ (the wall takes no power, η* = 0).

Shapes: ``jp`` = ``Model.rx_par`` float64[N_JOINTS, N_RX_PAR] (rows :data:`J_MAIN` …); the rows
``WK_RX + S_*`` of ``wk`` per cylinder, ``S_G*`` one value (column 0).
"""
from __future__ import annotations

from math import cos, sin, sqrt

import numpy as np

from ..declare import Layout
from ..jit import kernel
from .joint_friction import (
    MAX_ITER,
    R_LOSS,
    R_P,
    R_SEL,
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
from .swash_plate import (
    COS_A,
    HALVES,
    HINGE_PHASE,
    I_CROSS,
    I_ROD,
    J_DIAM,
    J_POLAR,
    M_PISTON,
    M_ROD,
    N_CYL,
    ROD_CG,
    ROD_L,
    SIN_A,
    link_motion,
    rod_motion,
)

#: The swash plate's joints (rows of ``Model.rx_par``), in the order of its ``reaction_links``:
#: the main bearing (frame – shaft), the plate bearing (plate – link 9), the ball joints B_k
#: (link 9 – rod) and D_k (rod – piston), ideal here, and the pistons in their cylinders.
J_MAIN, J_PLATE, J_BALL_B, J_BALL_D, J_SLIDER = range(5)

#: The swash plate's own rows, after the rows every solver shares (``joint_friction.SHARED``:
#: the gas force R_P, the angle R_SEL, the losses R_LOSS), offsets from ``layout.WK_RX``; per
#: cylinder: the rod's axial force t at f = 0 (the part at ε = 0, its slope in ε; the gas force
#: is added when solving), the side force N at f = 0 (y, z; part and slope), e⊥/e_x (∂N/∂f),
#: K = m a_G − Q (x, y, z; part and slope), e, the shaft-torque terms −(ξ × B)·K (part, slope)
#: and ρ = (ξ × B)·e, x_D′, the piston's direction of sliding at ``sel`` per unit σ, f's iterate
#: and the two parts of its Newton correction. Then one value each (column 0): link 9's and the
#: cross's part of T (part, slope), κ and θ′.
ROWS = Layout("swash-plate reaction rows",
              "t0", "t1", "ny0", "ny1", "nz0", "nz1", "ry", "rz", "kx0", "kx1", "ky0", "ky1",
              "kz0", "kz1", "ex", "ey", "ez", "tau0", "tau1", "rho", "x1", "ss", "f", "step",
              "couple", "gx0", "gx1", "gkappa", "gdth", start=SHARED.end)
(S_T0, S_T1, S_NY0, S_NY1, S_NZ0, S_NZ1, S_RY, S_RZ, S_KX0, S_KX1, S_KY0, S_KY1, S_KZ0, S_KZ1,
 S_EX, S_EY, S_EZ, S_TAU0, S_TAU1, S_RHO, S_X1, S_SS, S_F, S_STEP, S_COUPLE, S_GX0, S_GX1,
 S_GKAPPA, S_GDTH) = ROWS


@kernel(inline=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel(inline=True)
def _cross3(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@kernel(inline=True)
def _slope3(f, d, norm):
    """d|F| for dF = d (0 at F = 0, where |F| has its kink)."""
    if norm == 0.0:
        return 0.0
    return (f[0] * d[0] + f[1] * d[1] + f[2] * d[2]) / norm


@kernel
def cross_hinge(mp, c_phi, s_phi, c_theta, s_theta):
    """The cross's housing hinge a and its hinge c on link 9 at the state (unit vectors): a =
    (0, sin φ_h, cos φ_h) fixed, c = R_x(φ) R_n₀(θ) c₀, c₀ = n₀ × a/|n₀ × a| (in the plate plane)."""
    ca, sa = mp[COS_A], mp[SIN_A]
    ay, az = sin(mp[HINGE_PHASE]), cos(mp[HINGE_PHASE])
    norm = sqrt(az * az + ca * ca * ay * ay)
    c0 = (sa * az / norm, -ca * az / norm, ca * ay / norm)
    m0 = _cross3((ca, sa, 0.0), c0)  # n₀ × c₀
    v = (c_theta * c0[0] + s_theta * m0[0], c_theta * c0[1] + s_theta * m0[1],
         c_theta * c0[2] + s_theta * m0[2])
    return (0.0, ay, az), (v[0], c_phi * v[1] - s_phi * v[2], s_phi * v[1] + c_phi * v[2])


@kernel
def prepare(mp, phi, w, sel, wk):
    """The rows of the state (φ, ω) for :func:`solve` (module docstring): per cylinder the parts
    of t, N, K and of its terms of T, link 9's and the cross's part of T; the pistons' directions
    at ``sel`` when ``sel`` has changed."""
    c = WK_RX
    w2 = w * w
    ell, cg = mp[ROD_L], mp[ROD_CG]
    m_p, m_r, i_r = mp[M_PISTON], mp[M_ROD], mp[I_ROD]
    jp_, jd = mp[J_POLAR], mp[J_DIAM]
    c_phi, s_phi, c_th, s_th, n, wv, dw, d1, _, u13, du13 = link_motion(mp, phi)
    a, ch = cross_hinge(mp, c_phi, s_phi, c_th, s_th)
    axc = _cross3(a, ch)
    kappa = axc[0] / _dot(axc, n)
    xi = (1.0 - kappa * n[0], -kappa * n[1], -kappa * n[2])
    ixn = (0.0, -n[2], n[1])
    wn, dwn = _dot(wv, n), _dot(dw, n)
    dj = jp_ - jd
    # Ḣ₉ = ε H₁ + ω² H₀; the cross: I₁₃ ψ̈ a, ψ̈ = u₁₃ ε + u₁₃′ ω²
    h1 = (jd * wv[0] + dj * wn * n[0], jd * wv[1] + dj * wn * n[1], jd * wv[2] + dj * wn * n[2])
    h0 = (jd * dw[0] + dj * (dwn * n[0] + wn * ixn[0]),
          jd * dw[1] + dj * (dwn * n[1] + wn * ixn[1]),
          jd * dw[2] + dj * (dwn * n[2] + wn * ixn[2]))
    ic = mp[I_CROSS]
    wk[c + S_GX0, 0] = -(_dot(xi, h0) + ic * du13 * _dot(xi, a)) * w2
    wk[c + S_GX1, 0] = -(_dot(xi, h1) + ic * u13 * _dot(xi, a))
    wk[c + S_GKAPPA, 0] = kappa
    wk[c + S_GDTH, 0] = d1
    for k in range(np.int64(mp[N_CYL])):
        b, _, _, x1, x2, e, e1, e2 = rod_motion(mp, k, c_phi, s_phi, c_th, s_th, wv, dw)
        cb = _cross3(xi, b)
        rho = _dot(cb, e)
        wk[c + S_EX, k] = e[0]
        wk[c + S_EY, k] = e[1]
        wk[c + S_EZ, k] = e[2]
        wk[c + S_RY, k] = e[1] / e[0]
        wk[c + S_RZ, k] = e[2] / e[0]
        wk[c + S_RHO, k] = rho
        wk[c + S_X1, k] = x1
        # part 0: ε = 0 (the ω² terms); part 1: the slope in ε
        for part in range(2):
            if part == 0:
                ad = x2 * w2
                ee = (e2[0] * w2, e2[1] * w2, e2[2] * w2)
            else:
                ad = x1
                ee = e1
            ag = (ad + cg * ee[0], cg * ee[1], cg * ee[2])
            q = (((ell - cg) * m_r * ag[0] - i_r * ee[0]) / ell,
                 ((ell - cg) * m_r * ag[1] - i_r * ee[1]) / ell,
                 ((ell - cg) * m_r * ag[2] - i_r * ee[2]) / ell)
            kk = (m_r * ag[0] - q[0], m_r * ag[1] - q[1], m_r * ag[2] - q[2])
            t = (-m_p * ad - q[0]) / e[0]
            wk[c + S_T0 + part, k] = t
            wk[c + S_NY0 + part, k] = q[1] + t * e[1]
            wk[c + S_NZ0 + part, k] = q[2] + t * e[2]
            wk[c + S_KX0 + part, k] = kk[0]
            wk[c + S_KY0 + part, k] = kk[1]
            wk[c + S_KZ0 + part, k] = kk[2]
            wk[c + (S_TAU0 if part == 0 else S_TAU1), k] = -_dot(cb, kk)
    if wk[c + R_SEL, 0] != sel:
        c_phi, s_phi, c_th, s_th, n, wv, dw, _, _, _, _ = link_motion(mp, sel)
        for k in range(np.int64(mp[N_CYL])):
            x1 = rod_motion(mp, k, c_phi, s_phi, c_th, s_th, wv, dw)[3]
            wk[c + S_SS, k] = np.sign(x1)
        wk[c + R_SEL, 0] = sel


@kernel(inline=True)
def _axial(wk, k, eps):
    """The rod's axial force t_k at φ̈ = ``eps`` and the piston's friction force in row S_F."""
    c = WK_RX
    return (wk[c + S_T0, k] + wk[c + S_T1, k] * eps
            + (wk[c + R_P, k] + wk[c + S_F, k]) / wk[c + S_EX, k])


@kernel
def shaft(mp, jp, wk, eps, w, sigma):
    """The shaft's terms at φ̈ = ``eps`` and the pistons' friction forces in row S_F:
    ``(T, ∂T/∂ε at fixed f, F_P, ∂F_P/∂ε, F_O, M_O, M_f, ∂M_O/∂ε, ∂M_f/∂ε)`` (module docstring)."""
    c = WK_RX
    h = mp[HALVES]
    tt = wk[c + S_GX0, 0] + wk[c + S_GX1, 0] * eps
    tt_e = wk[c + S_GX1, 0]
    fx = fy = fz = 0.0
    gx = gy = gz = 0.0
    for k in range(np.int64(mp[N_CYL])):
        t = _axial(wk, k, eps)
        t1 = wk[c + S_T1, k]
        ex, ey, ez = wk[c + S_EX, k], wk[c + S_EY, k], wk[c + S_EZ, k]
        fx += wk[c + S_KX0, k] + wk[c + S_KX1, k] * eps - t * ex
        fy += wk[c + S_KY0, k] + wk[c + S_KY1, k] * eps - t * ey
        fz += wk[c + S_KZ0, k] + wk[c + S_KZ1, k] * eps - t * ez
        gx += wk[c + S_KX1, k] - t1 * ex
        gy += wk[c + S_KY1, k] - t1 * ey
        gz += wk[c + S_KZ1, k] - t1 * ez
        tt += wk[c + S_TAU0, k] + wk[c + S_TAU1, k] * eps + t * wk[c + S_RHO, k]
        tt_e += wk[c + S_TAU1, k] + t1 * wk[c + S_RHO, k]
    fp = (fx, fy, fz)
    dfp = (gx, gy, gz)
    if h == 2.0:  # the mirror plate's force: half 1's with its x negated
        fo = (0.0, 2.0 * fy, 2.0 * fz)
        dfo = (0.0, 2.0 * gy, 2.0 * gz)
    else:
        fo = fp
        dfo = dfp
    n_p = sqrt(fx * fx + fy * fy + fz * fz)
    n_o = sqrt(fo[0] * fo[0] + fo[1] * fo[1] + fo[2] * fo[2])
    k_o = sigma * jp[J_MAIN, RX_MU] * jp[J_MAIN, RX_RADIUS]
    k_p = sigma * jp[J_PLATE, RX_MU] * jp[J_PLATE, RX_RADIUS]
    m_o = k_o * n_o + jp[J_MAIN, RX_VISCOUS] * w
    m_f = k_p * n_p - jp[J_PLATE, RX_VISCOUS] * wk[c + S_GDTH, 0] * w
    m_o_e = k_o * _slope3(fo, dfo, n_o)
    m_f_e = k_p * _slope3(fp, dfp, n_p)
    kappa = wk[c + S_GKAPPA, 0]
    return (tt - kappa * m_f, tt_e - kappa * m_f_e, fp, n_p, fo, n_o, m_o, m_f, m_o_e)


@kernel(inline=True)
def _piston(jp, wk, k, eps, w, sigma):
    """Piston k's side force (N_y, N_z) at φ̈ = ``eps`` and f in row S_F, and the constant part
    of its friction: F_ring + c_p P⁺."""
    c = WK_RX
    P = wk[c + R_P, k]
    pf = P + wk[c + S_F, k]
    ny = wk[c + S_NY0, k] + wk[c + S_NY1, k] * eps + pf * wk[c + S_RY, k]
    nz = wk[c + S_NZ0, k] + wk[c + S_NZ1, k] * eps + pf * wk[c + S_RZ, k]
    f0 = jp[J_SLIDER, RX_RING_FORCE] + jp[J_SLIDER, RX_RING_PRESSURE] * max(P, 0.0)
    return ny, nz, f0


@kernel(inline=True)
def _friction_force(jp, wk, k, w, sigma, ny, nz, f0):
    """The cylinder's axial friction force on piston k for the side force (N_y, N_z)."""
    c = WK_RX
    return (-wk[c + S_SS, k] * sigma * (jp[J_SLIDER, RX_MU] * _norm(ny, nz) + f0)
            - jp[J_SLIDER, RX_VISCOUS] * wk[c + S_X1, k] * w)


@kernel
def start_f(jp, wk, eps, w, sigma, n):
    """Each piston's friction force from its side force at f = 0: where Newton's method starts."""
    for k in range(n):
        wk[WK_RX + S_F, k] = 0.0
        ny, nz, f0 = _piston(jp, wk, k, eps, w, sigma)
        wk[WK_RX + S_F, k] = _friction_force(jp, wk, k, w, sigma, ny, nz, f0)


@kernel
def solve(mp, jp, pair_of, J0, M_shaft, eps0, w, sigma, n_pairs, wk):
    """φ̈ with the joints' friction on their reactions, and per pair η*, S, L into ``wk``.

    Newton's method on (φ̈, f_1 … f_z) together (module docstring), from ``eps0`` (the
    frictionless φ̈); ``pair_of`` = ``Model.rx_pair``; the rows of :func:`prepare` and each
    piston's gas force (row R_P) must be filled. NaN if it does not converge."""
    c = WK_RX
    n = np.int64(mp[N_CYL])
    h = mp[HALVES]
    mu = jp[J_SLIDER, RX_MU]
    k_o = sigma * jp[J_MAIN, RX_MU] * jp[J_MAIN, RX_RADIUS]
    k_p = sigma * jp[J_PLATE, RX_MU] * jp[J_PLATE, RX_RADIUS]
    eps = eps0
    start_f(jp, wk, eps, w, sigma, n)
    for _ in range(MAX_ITER):
        T, T_e, fp, n_p, fo, n_o, m_o, m_f, m_o_e = shaft(mp, jp, wk, eps, w, sigma)
        kappa = wk[c + S_GKAPPA, 0]
        H = J0 * eps - M_shaft + m_o - h * T
        den = J0 + m_o_e - h * T_e
        scale = abs(M_shaft) + J0 * abs(eps) + abs(m_o) + h * abs(T)
        num = H
        small = True
        for k in range(n):
            ny, nz, f0 = _piston(jp, wk, k, eps, w, sigma)
            s = wk[c + S_SS, k] * sigma
            nn = _norm(ny, nz)
            f = wk[c + S_F, k]
            g = f - _friction_force(jp, wk, k, w, sigma, ny, nz, f0)
            g_f = 1.0 + s * mu * _slope(ny, nz, wk[c + S_RY, k], wk[c + S_RZ, k], nn)
            g_e = s * mu * _slope(ny, nz, wk[c + S_NY1, k], wk[c + S_NZ1, k], nn)
            r = g / g_f
            q = g_e / g_f
            ex = wk[c + S_EX, k]
            d = (-wk[c + S_EX, k] / ex, -wk[c + S_EY, k] / ex, -wk[c + S_EZ, k] / ex)
            if h == 2.0:
                do = (0.0, 2.0 * d[1], 2.0 * d[2])
            else:
                do = d
            H_f = (k_o * _slope3(fo, do, n_o)
                   - h * (wk[c + S_RHO, k] / ex - kappa * k_p * _slope3(fp, d, n_p)))
            num -= H_f * r
            den -= H_f * q
            wk[c + S_STEP, k] = r
            wk[c + S_COUPLE, k] = q
            small = small and abs(r) <= TOL * (nn + abs(f) + abs(wk[c + R_P, k]) + f0)
        if not np.isfinite(num):
            return np.nan
        eps -= newton_step(wk, c + S_F, c + S_STEP, c + S_COUPLE, n, num, den)
        if small and abs(H) <= TOL * scale:
            _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, n_pairs)
            return eps
    return np.nan


@kernel
def joint_terms(mp, jp, wk, eps, w, sigma):
    """``(S_main, S_plate, S_pistons, L_main, L_plate, L_pistons)`` at (ε, f in row S_F), both
    halves (module docstring)."""
    h = mp[HALVES]
    T, _, _, _, _, _, m_o, m_f, _ = shaft(mp, jp, wk, eps, w, sigma)
    ls = 0.0
    for k in range(np.int64(mp[N_CYL])):
        ls -= wk[WK_RX + S_F, k] * wk[WK_RX + S_X1, k]
    ls *= h
    return (m_o - h * T, -h * T, ls, m_o, -h * m_f * wk[WK_RX + S_GDTH, 0], ls)


@kernel
def _pair_terms(mp, jp, pair_of, wk, eps, w, sigma, n_pairs):
    """S, L and η* = 1 − L/S of each pair into ``wk``; the pistons' L per cylinder (both halves'
    piston) in the rows ``WK_CYL_LOSS``, NaN for the bearings, which every cylinder loads
    (their loss is the engine's, no cylinder's)."""
    n = np.int64(mp[N_CYL])
    clear_pairs(wk, n_pairs, n, np.nan)
    t = joint_terms(mp, jp, wk, eps, w, sigma)
    for i in range(3):
        p = pair_of[(J_MAIN, J_PLATE, J_SLIDER)[i]]
        if p >= 0:
            wk[WK_S, p] += t[i]
            wk[WK_RX + R_LOSS, p] += t[3 + i]
    p = pair_of[J_SLIDER]
    if p >= 0:
        for k in range(n):
            wk[WK_CYL_LOSS + p, k] = -mp[HALVES] * wk[WK_RX + S_F, k] * wk[WK_RX + S_X1, k]
    pair_efficiencies(wk, n_pairs)


@kernel
def inverse_drive(m, eps, w, sigma, M_shaft, wk):
    """The drive torque on the shaft for a prescribed motion (φ̈ = ``eps``), with the joints'
    friction: J₀ε − M_shaft + M_O − hT; fills η*, S, L of the pairs. NaN if a piston's friction
    equation does not converge (Newton's method in f_k alone)."""
    mp, jp = m.mech, m.rx_par
    c = WK_RX
    mu = jp[J_SLIDER, RX_MU]
    n = np.int64(mp[N_CYL])
    start_f(jp, wk, eps, w, sigma, n)
    for k in range(n):
        done = False
        for _ in range(MAX_ITER):
            ny, nz, f0 = _piston(jp, wk, k, eps, w, sigma)
            nn = _norm(ny, nz)
            f = wk[c + S_F, k]
            g = f - _friction_force(jp, wk, k, w, sigma, ny, nz, f0)
            g_f = 1.0 + wk[c + S_SS, k] * sigma * mu * _slope(ny, nz, wk[c + S_RY, k],
                                                                  wk[c + S_RZ, k], nn)
            step = g / g_f
            wk[c + S_F, k] = f - step
            if abs(step) <= TOL * (nn + abs(f) + abs(wk[c + R_P, k]) + f0):
                done = True
                break
        if not done:
            return np.nan
    T, _, _, _, _, _, m_o, _, _ = shaft(mp, jp, wk, eps, w, sigma)
    _pair_terms(mp, jp, m.rx_pair, wk, eps, w, sigma, m.n_pairs)
    return m.J0 * eps - M_shaft + m_o - mp[HALVES] * T
