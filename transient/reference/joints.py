"""Joint reactions by Newton–Euler, body by body, for a prescribed motion, for every mechanism:
the oracles that the reduced model's torques, the analyses' force relations and the compiled
reaction-friction solvers are checked against (one idea, three mechanisms: longer than the
project's usual module, each part written out in full).

- The crank-slider (:func:`crank_slider_joint_forces`): every cylinder's rod and piston, the
  forces at its main bearing, crankpin, piston pin and wall (:class:`JointForces`), and the
  friction laws on them (:func:`crank_slider_friction`, a fixed point on the forces).
- The articulated mechanism (:func:`articulated_joint_forces`): master and articulated rods,
  with the friction on its joints, solving for φ̈ where it is not given.
- The swash plate (:func:`swash_plate_reactions`): every body's equations as one linear system,
  the friction closed on them by ``fsolve`` (:func:`swash_plate_friction`).

What they share with the compiled path: the mechanisms' parameter records (the scene's
``mechanism``) and, for the articulated mechanism, the positions of its pins
(:func:`transient.mechanisms.articulated.positions`, plain Python); the rows of
``Model.rx_par`` they read the joints' coefficients from (``layout.RX_*``, ``JOINT_*``); and,
for the swash plate, the compiled kinematics of the plate (``swash_plate.hooke``,
``swash_points``), whose θ(φ) the Hooke joint's equations give. Their equations are written here
again, never taken from the compiled solvers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..core.model.layout import (
    JOINT_CRANKPIN,
    JOINT_MAIN,
    JOINT_PIN,
    JOINT_SLIDER,
    RX_MU,
    RX_RADIUS,
    RX_RING_FORCE,
    RX_RING_PRESSURE,
    RX_VISCOUS,
)
from ..mechanisms.articulated import positions

# ------------------------------------------------------------------------------------------------
# The crank-slider


@dataclass(frozen=True)
class JointForces:
    """The joint forces of every cylinder of a crank-slider, from :func:`crank_slider_joint_forces`.

    Arrays ``(n_cylinders, n)`` [N, N·m]; vectors as ``(2, n_cylinders, n)`` in each cylinder's
    frame (x to the side the crankpin moves at the top, y along the cylinder axis toward the
    head, Gots §1).

    Attributes
    ----------
    main : force of the throw on the main bearing (the frame), the throw's share of the shaft's
        journal load.
    crankpin : force of the rod on the crankpin.
    pin : force of the rod on the piston at the piston pin.
    N : force of the cylinder wall on the piston along +x (Gots (34)'s N).
    S : the rod force compression-positive as Gots splits the rod (35): the pin force plus the
        force that accelerates the pin's share m₁ = m(l − l₁)/l of the rod mass, along the rod,
        −(pin + m₁ a_B)·û with û = (A − B)/l.
    throw_torque : moment of the throw on the shaft, positive in the direction of rotation.
    """

    main: NDArray[np.float64]
    crankpin: NDArray[np.float64]
    pin: NDArray[np.float64]
    N: NDArray[np.float64]
    S: NDArray[np.float64]
    throw_torque: NDArray[np.float64]


def crank_slider_joint_forces(mech, phi, omega, epsilon, gas_force=None,
                              joint_moments=(0.0, 0.0, 0.0)) -> JointForces:
    """Joint forces of a crank-slider for a prescribed motion φ, ω, ε by Newton–Euler: the
    independent check of the analyses' force relations (Gots (34)–(41)) and of the reduced model.

    Each cylinder is three bodies in its own plane — the throw (its unbalanced mass m_k at the
    crankpin A, turning with the shaft; half of it where two cylinders share the throw), the rod
    (mass m at G, l₁ from the pin, inertia I_G about G; a two-mass rod is the rigid one with I_G = m
    l₁(l − l₁), the inertia of its end masses), the piston (mass m_p at the pin B, sliding along the
    axis at the offset e) — and the eight unknowns: the bearing's force on the throw (2), the
    shaft's moment on the throw, the throw's force on the rod at A (2), the rod's force on the
    piston at B (2) and the wall's force N. The throw's and the rod's Newton and Euler equations and
    the piston's Newton equation are eight linear equations, solved per sample
    (``numpy.linalg.solve``). The kinematics are written out here from the loop x_B = e: sin β = (r
    sin α − e)/l, β̇ = r cos α ω/(l cos β), β̈ and ÿ_B by differentiating once more.

    Parameters
    ----------
    mech : transient.mechanisms.crank_slider.CrankSlider
    phi, omega, epsilon : array_like (n,)
        Shaft angle [rad], speed [rad/s], acceleration [rad/s²]; cylinder k is at the local angle
        α = φ − ``firing_angles[k]``.
    gas_force : array_like (n_cylinders, n), optional
        Gas force on each piston toward the crank [N]; 0 if omitted.
    joint_moments : three array_like (n_cylinders, n) or scalars
        Known moments [N·m] in the main bearing, the crankpin and the piston pin, each on the
        joint's outer body (throw, rod, rod) and opposite on the inner one (frame, throw, piston;
        the wall holds the piston's), positive in the direction of rotation: where a friction
        model's joint moments are checked against the chain's.

    Returns
    -------
    JointForces
    """
    phi, omega, epsilon = (np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in
                           np.broadcast_arrays(phi, omega, epsilon))
    alpha = phi[None, :] - np.asarray(mech.firing_angles, dtype=np.float64)[:, None]
    w = np.broadcast_to(omega, alpha.shape)
    eps = np.broadcast_to(epsilon, alpha.shape)
    shape = alpha.shape
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    m, l1 = mech.rod_mass, mech.rod_cg_from_pin
    i_g = mech.rod_inertia_cg if mech.rod_model == "rigid" else m * l1 * (l - l1)
    p_g = np.zeros(shape) if gas_force is None else np.broadcast_to(gas_force, shape)
    # The moments about +z (x × y): the shaft turns clockwise in this frame, so a moment in the
    # direction of rotation is −z; the rod turns by +β̇ about z.
    m_main, m_pin_a, m_pin_b = (-np.broadcast_to(np.asarray(v, dtype=np.float64), shape)
                                for v in joint_moments)
    sa, ca = np.sin(alpha), np.cos(alpha)
    sb = (r * sa - e) / l
    cb = np.sqrt(1.0 - sb * sb)
    db = r * ca * w / (l * cb)  # β̇
    ddb = (-r * sa * w**2 + r * ca * eps + l * sb * db**2) / (l * cb)  # β̈
    pos_a = np.array([r * sa, r * ca])
    pos_b = np.array([np.full(shape, e), r * ca + l * cb])
    acc_a = np.array([r * (-sa * w**2 + ca * eps), r * (-ca * w**2 - sa * eps)])
    acc_b = np.array([np.zeros(shape), -r * ca * w**2 - r * sa * eps - l * cb * db**2
                      - l * sb * ddb])
    f = l1 / l
    pos_g = (1.0 - f) * pos_b + f * pos_a
    acc_g = (1.0 - f) * acc_b + f * acc_a
    ra, rb = pos_a - pos_g, pos_b - pos_g  # from G to the rod's ends
    # Unknowns: F_O (x, y) bearing → throw, M the shaft's moment on the throw (z), F_A (x, y)
    # throw → rod, F_B (x, y) rod → piston, N.
    A = np.zeros(shape + (8, 8))
    rhs = np.zeros(shape + (8,))
    m_k, m_p = mech.crank_mass_per_cylinder, mech.piston_mass  # its share of a shared throw
    # Throw: F_O − F_A = m_k a_A; about O: M + A × (−F_A) − M_A = I_O·(−ε), I_O = m_k r².
    A[..., 0, 0], A[..., 0, 3] = 1.0, -1.0
    A[..., 1, 1], A[..., 1, 4] = 1.0, -1.0
    rhs[..., 0], rhs[..., 1] = m_k * acc_a[0], m_k * acc_a[1]
    A[..., 2, 2] = 1.0
    A[..., 2, 3], A[..., 2, 4] = pos_a[1], -pos_a[0]  # A × (−F_A)
    rhs[..., 2] = -m_k * r * r * eps - m_main + m_pin_a
    # Rod: F_A − F_B = m a_G; about G: (A − G) × F_A + (B − G) × (−F_B) + M_A + M_B = I_G β̈.
    A[..., 3, 3], A[..., 3, 5] = 1.0, -1.0
    A[..., 4, 4], A[..., 4, 6] = 1.0, -1.0
    rhs[..., 3], rhs[..., 4] = m * acc_g[0], m * acc_g[1]
    A[..., 5, 3], A[..., 5, 4] = -ra[1], ra[0]
    A[..., 5, 5], A[..., 5, 6] = rb[1], -rb[0]
    rhs[..., 5] = i_g * ddb - m_pin_a - m_pin_b
    # Piston: F_B + N x̂ − P_g ŷ = m_p a_B (its moment, −M_B, held by the wall).
    A[..., 6, 5], A[..., 6, 7] = 1.0, 1.0
    A[..., 7, 6] = 1.0
    rhs[..., 6], rhs[..., 7] = m_p * acc_b[0], m_p * acc_b[1] + p_g
    x = np.moveaxis(np.linalg.solve(A, rhs[..., None])[..., 0], -1, 0)
    pin = x[5:7]
    u_hat = (pos_a - pos_b) / l
    m1 = m * (l - l1) / l
    return JointForces(main=-x[0:2], crankpin=-x[3:5], pin=pin, N=x[7],
                       S=-np.sum((pin + m1 * acc_b) * u_hat, axis=0), throw_torque=x[2])


# ------------------------------------------------------------------------------------------------
# Friction on the crank-slider's joint reactions, applied to the Newton–Euler forces


def _rod_and_piston_rates(mech, phi):
    """β′ = dβ/dα and s′ = ds/dα (toward the crank) of every cylinder at shaft angle φ, from the
    loop x_B = e as :func:`crank_slider_joint_forces` writes it: sin β = (r sin α − e)/l,
    β′ = r cos α/(l cos β), and y_B = r cos α + l cos β gives s′ = −y_B′ = r sin α + l sin β·β′."""
    alpha = phi - np.asarray(mech.firing_angles, dtype=np.float64)
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    sb = (r * np.sin(alpha) - e) / l
    db = r * np.cos(alpha) / (l * np.sqrt(1.0 - sb * sb))
    return db, r * np.sin(alpha) + l * sb * db


def crank_slider_joint_signs(mech, sel) -> NDArray[np.float64]:
    """Per joint (main bearing, crankpin, piston pin, slider; rows) and cylinder the sign of its
    relative rate per unit of ω at the angle ``sel``: the throw on the frame 1, the rod on the
    throw 1 + β′, the rod on the piston β′, the piston s′."""
    db, ds = _rod_and_piston_rates(mech, sel)
    return np.array([np.ones_like(db), np.sign(1.0 + db), np.sign(db), np.sign(ds)])


def crank_slider_friction_laws(mech, jp, phi, w, forces: JointForces, P, signs):
    """The joints' friction from their forces (``forces`` at one sample, trailing axis 1): the
    moments (3, n_cylinders) on the outer bodies, positive in the direction of rotation, of the
    main bearing (on the throw), the crankpin and the piston pin (on the rod), each
    ±μ·r·|F| and a viscous term opposing the relative rate (``signs`` × σ:
    :func:`crank_slider_joint_signs`), and the slider's force on the piston toward the crank,
    −(μ|N| + F_ring + c_p P⁺) against the piston's speed and −c·s′ω (``jp`` = ``Model.rx_par``)."""
    db, ds = _rod_and_piston_rates(mech, phi)
    k = jp[:, RX_MU] * jp[:, RX_RADIUS]
    visc = jp[:, RX_VISCOUS]
    m_main = (-signs[0] * k[JOINT_MAIN] * np.hypot(*forces.main[:, :, 0])
              - visc[JOINT_MAIN] * w)
    m_cp = (signs[1] * k[JOINT_CRANKPIN] * np.hypot(*forces.crankpin[:, :, 0])
            + visc[JOINT_CRANKPIN] * (1.0 + db) * w)
    m_pin = signs[2] * k[JOINT_PIN] * np.hypot(*forces.pin[:, :, 0]) + visc[JOINT_PIN] * db * w
    f_s = (-signs[3] * (jp[JOINT_SLIDER, RX_MU] * np.abs(forces.N[:, 0])
                        + jp[JOINT_SLIDER, RX_RING_FORCE]
                        + jp[JOINT_SLIDER, RX_RING_PRESSURE] * np.maximum(P, 0.0))
           - visc[JOINT_SLIDER] * ds * w)
    return np.array([m_main, m_cp, m_pin]), f_s


def crank_slider_joint_powers(mech, phi, w, forces: JointForces, moments, f_s):
    """Per joint (rows: main bearing, crankpin, piston pin, slider) and cylinder the loss moment
    (the power lost over ω) and the moment its shaft side puts in (the power it sends in over ω),
    from the forces and the friction at one sample: the shaft into the throw −T, the throw into
    the rod (the crankpin's force on the rod times the crankpin's velocity, over ω, and the
    friction moment), the rod into the piston, the piston into the wall."""
    db, ds = _rod_and_piston_rates(mech, phi)
    alpha = phi - np.asarray(mech.firing_angles, dtype=np.float64)
    m_main, m_cp, m_pin = moments
    f_a = -forces.crankpin[:, :, 0]  # the throw's force on the rod
    r = mech.crank_radius
    loss = np.array([-m_main, m_cp * (1.0 + db), m_pin * db, -f_s * ds])
    through = np.array([-forces.throw_torque[:, 0],
                        r * (f_a[0] * np.cos(alpha) - f_a[1] * np.sin(alpha)) + m_cp,
                        -forces.pin[1, :, 0] * ds + m_pin * db,
                        -f_s * ds])
    return loss, through


def crank_slider_friction(mech, jp, phi, w, eps, P, signs, turns=60):
    """The joint forces at a prescribed φ̈ = ``eps`` with the friction laws applied to them,
    iterated ``turns`` times (a contraction: the friction is μ·r/l of the forces):
    ``(forces, loss, through)`` as :func:`crank_slider_joint_powers`."""
    n = mech.n_cylinders
    moments, f_s = np.zeros((3, n)), np.zeros(n)
    for _ in range(turns):
        forces = crank_slider_joint_forces(mech, phi, w, eps, (P + f_s)[:, None],
                                           moments[:, :, None])
        moments, f_s = crank_slider_friction_laws(mech, jp, phi, w, forces, P, signs)
    forces = crank_slider_joint_forces(mech, phi, w, eps, (P + f_s)[:, None], moments[:, :, None])
    return (forces, *crank_slider_joint_powers(mech, phi, w, forces, moments, f_s))


def _at_acceleration(both: JointForces, eps: float) -> JointForces:
    """The forces at φ̈ = ``eps`` from those at φ̈ = 0 and 1 (last axis), being affine in φ̈ at
    given friction; the last axis of the result has length 1."""
    def at(v):
        return v[..., :1] + eps * (v[..., 1:2] - v[..., :1])
    return JointForces(*(at(getattr(both, f)) for f in
                         ("main", "crankpin", "pin", "N", "S", "throw_torque")))


# ------------------------------------------------------------------------------------------------
# The articulated mechanism, with friction on its joints


@dataclass(frozen=True)
class ArticulatedForces:
    """The joint forces of an articulated mechanism at one state, from
    :func:`articulated_joint_forces`; vectors ``(2, …)`` in each row's frame
    (:mod:`transient.core.model.articulated`: x along the row's master cylinder, y a quarter-turn on
    in the direction of rotation), cylinders numbered as the mechanism numbers them.

    Attributes
    ----------
    epsilon : φ̈ [rad/s²] (the prescribed one, or the solution of the shaft's equation).
    N : (n_cyl,) the wall's side force on each piston along ẑ × (its axis) [N].
    pin : (2, n_cyl) each rod's force on its piston [N].
    big_end : (2, n_cyl) at the master cylinders the throw's force on the master rod at the
        crankpin, at the slaves the master rod's on the slave rod at its link pin [N].
    main : (2, rows) the frame's force on each throw [N].
    throw_torque : (rows,) each throw's moment on the shaft, positive in the direction of
        rotation [N m].
    S, L : (6,) per joint (main bearings, crankpins, link pins, master pins, slave pins,
        pistons) summed over the rows: the moment the shaft side puts into the joint and the
        loss moment [N m] (powers over ω, as ``transient.core.model.articulated_friction`` defines
        them).
    L_cyl : (6, n_cyl) the loss moments per joint and cylinder, a row's main bearing and
        crankpin counted as its master cylinder's; they sum to L.
    iterations : fixed-point turns taken by the friction.
    """

    epsilon: float
    N: NDArray[np.float64]
    pin: NDArray[np.float64]
    big_end: NDArray[np.float64]
    main: NDArray[np.float64]
    throw_torque: NDArray[np.float64]
    S: NDArray[np.float64]
    L: NDArray[np.float64]
    L_cyl: NDArray[np.float64]
    iterations: int


def _loop_rates(ap: complex, app: complex, rod: float, u: complex, d: complex,
                t1: float | None = None) -> tuple[float, float]:
    """A loop P + rod·u = X d (u = e^{iθ}, d fixed): (θ′, X′) from P′ = ``ap`` when ``t1`` is
    None, else (θ″, X″) from P″ = ``app`` and θ′ = ``t1``: i rod u θ″ − rod u θ′² + P″ = X″ d."""
    c1, c2 = 1j * rod * u, -d
    rhs = -ap if t1 is None else -(app - rod * u * t1 * t1)
    A = np.array([[c1.real, c2.real], [c1.imag, c2.imag]])
    x = np.linalg.solve(A, np.array([rhs.real, rhs.imag]))
    return float(x[0]), float(x[1])


def _cross2(a: complex, b: complex) -> float:
    return a.real * b.imag - a.imag * b.real


def articulated_joint_forces(mech, phi: float, omega: float, gas_force, coefficients,
                             sigma: float | None = None, epsilon: float | None = None,
                             J0: float = 0.0, M_shaft: float = 0.0, turns: int = 400,
                             sel: float | None = None) -> ArticulatedForces:
    """Joint forces of an articulated mechanism (radial or V) at one state by Newton–Euler, with
    friction on its joints: the independent check of ``transient.core.model.articulated_friction``.

    Each row is 3 + 2 + 5 z′ bodies' equations — the throw (mass m_k at the crankpin: Newton and
    Euler about O, with the shaft's moment on it unknown), the master rod (rigid: mass at its
    centre of mass, inertia about it; a two-mass rod is the rigid one with I = m c(l − c)), the
    master piston (Newton along and across its axis, the wall's side force unknown), each slave
    rod and slave piston alike — linear in the joint forces and in φ̈ when the friction moments
    are known; with ``epsilon`` None, φ̈ is an unknown too and the shaft's J₀ φ̈ = M_shaft + Σ T
    closes the system. The kinematics are written out here by loop closure, not from the kernel:
    positions from :func:`transient.mechanisms.articulated.positions`, and per loop (crankpin →
    master piston pin on the x axis; link pin → slave piston pin on its axis) the rod's rate and
    the piston's from the loop's derivative, two linear equations, and their derivatives from the
    loop's second derivative.

    The friction (``coefficients`` = the (6, 5) rows of ``Model.rx_par``: per joint μ, radius,
    viscous, ring force, ring pressure share) acts as the module docstring of
    ``transient.core.model.articulated_friction`` states it, on the forces of the previous solve: a plain
    fixed point, repeated until nothing changes by more than 1e-15 of the largest force (each
    turn contracts by about μ, so a few dozen turns). The directions are the relative rates' signs
    at ``sel`` (default φ) times σ (default sign ω).
    """
    jp = np.asarray(coefficients, dtype=np.float64)
    sigma = float(np.sign(omega)) if sigma is None else sigma
    sel = phi if sel is None else sel
    ns, rows = mech.n_slaves, mech.rows
    nc = rows * (1 + ns)
    l = mech.rod_length
    P = np.broadcast_to(np.asarray(gas_force, dtype=np.float64), (nc,))
    m_k, m_p = mech.crank_mass, mech.piston_mass
    m0, c0 = mech.rod_mass, mech.rod_cg_from_pin
    i0 = mech.rod_inertia_cg if mech.rod_model == "rigid" else m0 * c0 * (l - c0)
    ms, cs = mech.slave_rod_mass, mech.slave_rod_cg_from_pin
    li = np.asarray(mech.slave_lengths)
    i_s = (np.full(ns, mech.slave_rod_inertia_cg) if mech.slave_rod_model == "rigid"
           else ms * cs * (li - cs))
    d_s = np.exp(1j * np.asarray(mech.slave_banks))
    z_s = np.asarray(mech.link_radii) * np.exp(1j * np.asarray(mech.link_angles))

    def kinematics(alpha):
        """Per row: points (position, first, second derivative in α) and rod rates."""
        pos = positions(mech, alpha)
        A = pos["A"][0]
        Ap, App = 1j * A, -A
        B = pos["B"][0]
        u0 = (B - A) / l
        t0, x0 = _loop_rates(Ap, 0j, l, u0, 1.0 + 0j)
        t0b, x0b = _loop_rates(Ap, App, l, u0, 1.0 + 0j, t0)
        out = {"A": (A, Ap, App), "B": (B, x0 + 0j, x0b + 0j), "t0": (t0, t0b), "slaves": []}
        for i in range(ns):
            Ai = pos["Ai"][0, i]
            Aip = Ap + 1j * z_s[i] * u0 * t0
            Aipp = App + 1j * z_s[i] * u0 * t0b - z_s[i] * u0 * t0 * t0
            Bi = pos["Bi"][0, i]
            ui = (Bi - Ai) / li[i]
            ti, xi = _loop_rates(Aip, 0j, li[i], ui, d_s[i])
            tib, xib = _loop_rates(Aip, Aipp, li[i], ui, d_s[i], ti)
            out["slaves"].append({"A": (Ai, Aip, Aipp), "B": (Bi, xi * d_s[i], xib * d_s[i]),
                                  "t": (ti, tib), "X1": xi})
        return out

    phases = np.asarray(mech.row_phases)
    kin = [kinematics(phi - ph) for ph in phases]
    at_sel = [kinematics(sel - ph) for ph in phases]
    w2 = omega * omega
    unknown_eps = epsilon is None
    per_row = 8 + 5 * ns
    n = rows * per_row + (1 if unknown_eps else 0)
    ie = n - 1

    def acc(p):  # acceleration of point p = (pos, p′, p″): constant part, ε coefficient
        return p[2] * w2, p[1]

    # friction state (from the previous solve): moments on the outer bodies, slider forces
    M_O, M_A, M_B0 = np.zeros(rows), np.zeros(rows), np.zeros(rows)
    M_L, M_Bs = np.zeros((rows, ns)), np.zeros((rows, ns))
    F_s = np.zeros(nc)
    mu = jp[:, 0] * jp[:, 1]  # μ r per journal
    sl_mu, sl_ring, sl_p, sl_c = jp[5, 0], jp[5, 3], jp[5, 4], jp[5, 2]
    prev = None
    for it in range(turns):
        Amat = np.zeros((n, n))
        rhs = np.zeros(n)
        for j in range(rows):
            o = j * per_row
            K = kin[j]
            iFO, iM, iFA, iFB, iN = o, o + 2, o + 3, o + 5, o + 7
            A, Ap, App = K["A"]
            B = K["B"][0]
            t0, t0b = K["t0"]
            # throw: F_O − F_A = m_k a_A;  −A × F_A + M_sh = m_k A × a_A + M_A − M_O
            aA0, aA1 = acc(K["A"])
            e = o
            Amat[e, iFO], Amat[e, iFA] = 1.0, -1.0
            Amat[e + 1, iFO + 1], Amat[e + 1, iFA + 1] = 1.0, -1.0
            rhs[e], rhs[e + 1] = m_k * aA0.real, m_k * aA0.imag
            Amat[e + 2, iFA], Amat[e + 2, iFA + 1] = A.imag, -A.real
            Amat[e + 2, iM] = 1.0
            rhs[e + 2] = m_k * _cross2(A, aA0) + M_A[j] - M_O[j]
            if unknown_eps:
                Amat[e, ie], Amat[e + 1, ie] = -m_k * aA1.real, -m_k * aA1.imag
                Amat[e + 2, ie] = -m_k * _cross2(A, aA1)
            else:
                rhs[e] += m_k * aA1.real * epsilon
                rhs[e + 1] += m_k * aA1.imag * epsilon
                rhs[e + 2] += m_k * _cross2(A, aA1) * epsilon
            # master rod: F_A − F_B0 − Σ F_Ai = m a_G; about G: moments = I θ̈
            f = c0 / l
            G = B + f * (A - B)
            Gp = (1 - f) * K["B"][1] + f * Ap
            Gpp = (1 - f) * K["B"][2] + f * App
            aG0, aG1 = Gpp * w2, Gp
            e = o + 3
            Amat[e, iFA], Amat[e, iFB] = 1.0, -1.0
            Amat[e + 1, iFA + 1], Amat[e + 1, iFB + 1] = 1.0, -1.0
            ra, rb = A - G, B - G
            Amat[e + 2, iFA], Amat[e + 2, iFA + 1] = -ra.imag, ra.real
            Amat[e + 2, iFB], Amat[e + 2, iFB + 1] = rb.imag, -rb.real
            rhs[e], rhs[e + 1] = m0 * aG0.real, m0 * aG0.imag
            rhs[e + 2] = i0 * t0b * w2 - M_A[j] - M_B0[j] + M_L[j].sum()
            if unknown_eps:
                Amat[e, ie], Amat[e + 1, ie] = -m0 * aG1.real, -m0 * aG1.imag
                Amat[e + 2, ie] = -i0 * t0
            else:
                rhs[e] += m0 * aG1.real * epsilon
                rhs[e + 1] += m0 * aG1.imag * epsilon
                rhs[e + 2] += i0 * t0 * epsilon
            # master piston: F_B0 + N ŷ + (F_s − P) x̂ = m_p a_B
            k = j * (1 + ns)
            aB0, aB1 = acc(K["B"])
            e = o + 6
            Amat[e, iFB], Amat[e + 1, iFB + 1], Amat[e + 1, iN] = 1.0, 1.0, 1.0
            rhs[e] = m_p * aB0.real + P[k] - F_s[k]
            rhs[e + 1] = m_p * aB0.imag
            if unknown_eps:
                Amat[e, ie], Amat[e + 1, ie] = -m_p * aB1.real, -m_p * aB1.imag
            else:
                rhs[e] += m_p * aB1.real * epsilon
                rhs[e + 1] += m_p * aB1.imag * epsilon
            for i, S_ in enumerate(K["slaves"]):
                q = o + 8 + 5 * i
                iFa, iFb, iNi = q, q + 2, q + 4
                k = j * (1 + ns) + 1 + i
                Ai = S_["A"][0]
                Bi = S_["B"][0]
                ti, tib = S_["t"]
                # the slave's force on the master rod, −F_Ai: in its Newton and its moment
                Amat[o + 3, iFa], Amat[o + 4, iFa + 1] = -1.0, -1.0
                rai = Ai - G
                Amat[o + 5, iFa], Amat[o + 5, iFa + 1] = rai.imag, -rai.real
                # slave rod: F_Ai − F_Bi = m_s a_Gi; about G_i
                fi = cs / li[i]
                Gi = Bi + fi * (Ai - Bi)
                Gip = (1 - fi) * S_["B"][1] + fi * S_["A"][1]
                Gipp = (1 - fi) * S_["B"][2] + fi * S_["A"][2]
                Amat[q, iFa], Amat[q, iFb] = 1.0, -1.0
                Amat[q + 1, iFa + 1], Amat[q + 1, iFb + 1] = 1.0, -1.0
                rhs[q], rhs[q + 1] = ms * (Gipp * w2).real, ms * (Gipp * w2).imag
                ra, rb = Ai - Gi, Bi - Gi
                Amat[q + 2, iFa], Amat[q + 2, iFa + 1] = -ra.imag, ra.real
                Amat[q + 2, iFb], Amat[q + 2, iFb + 1] = rb.imag, -rb.real
                rhs[q + 2] = i_s[i] * tib * w2 - M_L[j, i] - M_Bs[j, i]
                # slave piston: F_Bi + N_i m_i + (F_s − P) d_i = m_p a_Bi
                d = d_s[i]
                mi = 1j * d
                aB0, aB1 = acc(S_["B"])
                Amat[q + 3, iFb], Amat[q + 4, iFb + 1] = 1.0, 1.0
                Amat[q + 3, iNi], Amat[q + 4, iNi] = mi.real, mi.imag
                rhs[q + 3] = m_p * aB0.real - (F_s[k] - P[k]) * d.real
                rhs[q + 4] = m_p * aB0.imag - (F_s[k] - P[k]) * d.imag
                if unknown_eps:
                    Amat[q, ie], Amat[q + 1, ie] = -ms * Gip.real, -ms * Gip.imag
                    Amat[q + 2, ie] = -i_s[i] * ti
                    Amat[q + 3, ie], Amat[q + 4, ie] = -m_p * aB1.real, -m_p * aB1.imag
                else:
                    rhs[q] += ms * Gip.real * epsilon
                    rhs[q + 1] += ms * Gip.imag * epsilon
                    rhs[q + 2] += i_s[i] * ti * epsilon
                    rhs[q + 3] += m_p * aB1.real * epsilon
                    rhs[q + 4] += m_p * aB1.imag * epsilon
            if unknown_eps:  # the shaft: J₀ ε + Σ M_sh = M_shaft
                Amat[ie, iM] = 1.0
        if unknown_eps:
            Amat[ie, ie] = J0
            rhs[ie] = M_shaft
        x = np.linalg.solve(Amat, rhs)
        eps = x[ie] if epsilon is None else epsilon
        # the friction of these forces
        N = np.empty(nc)
        pin, big, main = np.empty((2, nc)), np.empty((2, nc)), np.empty((2, rows))
        for j in range(rows):
            o = j * per_row
            k = j * (1 + ns)
            main[:, j] = x[o:o + 2]
            big[:, k] = x[o + 3:o + 5]
            pin[:, k] = x[o + 5:o + 7]
            N[k] = x[o + 7]
            for i in range(ns):
                q = o + 8 + 5 * i
                big[:, k + 1 + i] = x[q:q + 2]
                pin[:, k + 1 + i] = x[q + 2:q + 4]
                N[k + 1 + i] = x[q + 4]
        scale = max(np.abs(x[:ie if unknown_eps else n]).max(), 1.0)
        if prev is not None and np.max(np.abs(x - prev)) <= 1e-15 * scale and it > 2:
            break
        prev = x
        for j in range(rows):
            k = j * (1 + ns)
            t0 = kin[j]["t0"][0]
            s0 = at_sel[j]["t0"][0]
            M_O[j] = -sigma * mu[0] * np.hypot(*main[:, j]) - jp[0, 2] * omega
            M_A[j] = (-np.sign(s0 - 1.0) * sigma * mu[1] * np.hypot(*big[:, k])
                      - jp[1, 2] * (t0 - 1.0) * omega)
            M_B0[j] = -np.sign(s0) * sigma * mu[3] * np.hypot(*pin[:, k]) - jp[3, 2] * t0 * omega
            x0 = kin[j]["B"][1].real
            F_s[k] = (-np.sign(at_sel[j]["B"][1].real) * sigma
                      * (sl_mu * abs(N[k]) + sl_ring + sl_p * max(P[k], 0.0)) - sl_c * x0 * omega)
            for i in range(ns):
                ti = kin[j]["slaves"][i]["t"][0]
                si = at_sel[j]["slaves"][i]["t"][0]
                M_L[j, i] = (-np.sign(si - s0) * sigma * mu[2] * np.hypot(*big[:, k + 1 + i])
                             - jp[2, 2] * (ti - t0) * omega)
                M_Bs[j, i] = (-np.sign(si) * sigma * mu[4] * np.hypot(*pin[:, k + 1 + i])
                              - jp[4, 2] * ti * omega)
                xi = kin[j]["slaves"][i]["X1"]
                F_s[k + 1 + i] = (-np.sign(at_sel[j]["slaves"][i]["X1"]) * sigma
                                  * (sl_mu * abs(N[k + 1 + i]) + sl_ring
                                     + sl_p * max(P[k + 1 + i], 0.0)) - sl_c * xi * omega)
    # throw torques and each joint's S, L
    T = np.empty(rows)
    S = np.zeros(6)
    L_cyl = np.zeros((6, nc))  # a row's main bearing and crankpin count as its master cylinder's
    for j in range(rows):
        o = j * per_row
        k = j * (1 + ns)
        K = kin[j]
        T[j] = -x[o + 2]
        t0 = K["t0"][0]
        Ap = K["A"][1]
        fa = complex(*big[:, k])
        fb = complex(*pin[:, k])
        S[0] += x[o + 2]
        L_cyl[0, k] -= M_O[j]
        S[1] += fa.real * Ap.real + fa.imag * Ap.imag + M_A[j]
        L_cyl[1, k] -= M_A[j] * (t0 - 1.0)
        x0 = K["B"][1].real
        S[3] += fb.real * x0 - M_B0[j] * t0
        L_cyl[3, k] -= M_B0[j] * t0
        S[5] -= F_s[k] * x0
        L_cyl[5, k] -= F_s[k] * x0
        for i in range(ns):
            Sl = K["slaves"][i]
            ti = Sl["t"][0]
            fa = complex(*big[:, k + 1 + i])
            fb = complex(*pin[:, k + 1 + i])
            Aip, Bip = Sl["A"][1], Sl["B"][1]
            S[2] += fa.real * Aip.real + fa.imag * Aip.imag + M_L[j, i] * t0
            L_cyl[2, k + 1 + i] -= M_L[j, i] * (ti - t0)
            S[4] += fb.real * Bip.real + fb.imag * Bip.imag - M_Bs[j, i] * ti
            L_cyl[4, k + 1 + i] -= M_Bs[j, i] * ti
            S[5] -= F_s[k + 1 + i] * Sl["X1"]
            L_cyl[5, k + 1 + i] -= F_s[k + 1 + i] * Sl["X1"]
    L = L_cyl.sum(axis=1)
    return ArticulatedForces(epsilon=float(eps), N=N, pin=pin, big_end=big, main=main,
                             throw_torque=T, S=S, L=L, L_cyl=L_cyl, iterations=it + 1)


# ------------------------------------------------------------------------------------------------
# The swash plate, with friction on its joints


@dataclass(frozen=True)
class SwashReactions:
    """The motion and the joint reactions of a swash-plate engine at one state, from
    :func:`swash_plate_reactions` (half 1; vectors in the fixed frame of
    :mod:`transient.core.model.swash_plate`) [rad/s², N, N·m].

    Attributes
    ----------
    epsilon : φ̈.
    main : force of the frame on the shaft (both halves).
    plate : force of the plate on link 9 (F_P); ``plate_moment`` its reaction moment (⊥ n).
    B, D : (z, 3) force of link 9 on rod k at B_k, of piston k on rod k at D_k.
    N : (z, 2) the wall's side force on piston k (y, z).
    f : (z,) the cylinder's axial friction force on piston k (along +x).
    M_main, M_plate : the main bearing's friction moment on the shaft about x (opposing ω; the
        shaft's equation has −M_main) and the plate bearing's on link 9 about n.
    loss, through : (3,) per pair, main bearing, plate bearing, pistons (both halves): the power
        lost over ω, and the power the shaft side puts into the joint over ω.
    piston_loss : (z,) the pistons' loss over ω in each cylinder (both halves' piston), whose
        sum is ``loss[2]``; the bearings' losses are no cylinder's (every cylinder loads them).
    """

    epsilon: float
    main: NDArray[np.float64]
    plate: NDArray[np.float64]
    plate_moment: NDArray[np.float64]
    B: NDArray[np.float64]
    D: NDArray[np.float64]
    N: NDArray[np.float64]
    f: NDArray[np.float64]
    M_main: float
    M_plate: float
    loss: NDArray[np.float64]
    through: NDArray[np.float64]
    piston_loss: NDArray[np.float64]


def _cross3(a, b) -> NDArray[np.float64]:
    """a × b of two 3-vectors, written out: numpy's general ``cross`` costs far more on a single
    pair, and the swash plate's reactions take thousands per evaluation of the reference path."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _rodrigues(axis, angle):
    """Rotation matrix by ``angle`` about the unit ``axis``."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def swash_plate_motion(mech, phi, omega, epsilon):
    """The swash plate's bodies at a state, from positions and rotation matrices: link 9's
    ω₉ = ω(x̂ + θ′n) and α₉ (Antonyuk (8), differentiated once more), each joint's B = Q₉ B₀ and
    its acceleration α₉ × B + ω₉ × (ω₉ × B), D on its cylinder axis at distance ℓ from B (10),
    ẋ_D, ẍ_D from |B − D|² = ℓ² differentiated twice, the rods' e, ė, ë and the cross's hinge
    c = Q₉ c₀ with ψ̈ = α₉·a. Only θ(φ), θ′, θ″ come from :func:`transient.core.model.swash_plate.hooke`;
    the Hooke constraint a·c = 0 is returned to be checked. A dict of arrays."""
    from ..core.model import swash_plate as core
    from ..mechanisms.swash_plate import HINGES

    mp = mech.pack()
    a_sw, R = mech.swash_angle, mech.joint_radius
    x = np.array([1.0, 0.0, 0.0])
    theta, d1, d2, _, _ = core.hooke(mp, phi)
    n0 = np.array([math.cos(a_sw), math.sin(a_sw), 0.0])
    Rx = _rodrigues(x, phi)
    Q9 = Rx @ _rodrigues(n0, theta)
    n = Rx @ n0
    w9 = omega * (x + d1 * n)
    al9 = epsilon * (x + d1 * n) + omega ** 2 * (d2 * n + d1 * _cross3(x, n))
    hinge = np.array(HINGES[mech.hinge][1])
    c0 = _cross3(n0, hinge)
    c = Q9 @ (c0 / np.linalg.norm(c0))
    z = mech.cylinders
    m_in_plate = np.array([-math.sin(a_sw), math.cos(a_sw), 0.0])  # eq. (6) at argument 0
    out = {k: np.zeros((z, 3)) for k in ("B", "aB", "D", "e", "de", "dde")}
    out.update(xd1=np.zeros(z), xd2=np.zeros(z))
    for k in range(z):
        psi = 2.0 * math.pi * k / z
        B = Q9 @ (R * (math.cos(psi) * m_in_plate + math.sin(psi) * np.array([0.0, 0.0, 1.0])))
        vB = _cross3(w9, B)
        aB = _cross3(al9, B) + _cross3(w9, vB)
        yz = mech.cylinder_radius * np.array([math.cos(psi), math.sin(psi)])
        lat = B[1:] - yz
        D = np.array([B[0] - math.sqrt(mech.rod_length ** 2 - lat @ lat), *yz])
        r = B - D
        vD = (r @ vB) / r[0]  # (B − D)·(Ḃ − Ḋ) = 0, Ḋ = ẋ_D x̂
        dv = vB - vD * x
        aD = (r @ aB + dv @ dv) / r[0]
        ell = mech.rod_length
        out["B"][k], out["aB"][k], out["D"][k] = B, aB, D
        out["e"][k], out["de"][k], out["dde"][k] = r / ell, dv / ell, (aB - aD * x) / ell
        out["xd1"][k], out["xd2"][k] = vD, aD
    out.update(n=n, w9=w9, al9=al9, a=hinge, c=c, dtheta=d1, hooke=float(hinge @ c))
    return out


def swash_plate_reactions(mech, phi, omega, epsilon, gas_force, M_main=0.0, M_plate=0.0,
                          f=None, J0=None, M_shaft=None, motion=None) -> SwashReactions:
    """The joint reactions of the swash plate by Newton–Euler, every body's equations one linear
    system: the independent check of :mod:`transient.core.model.swash_friction` and, without friction,
    of the reduced model (18).

    Bodies (half 1; the mirror half of ``halves = 2`` is its mirror image, so it doubles the
    torque on the shaft and adds its force mirrored, (−F_x, F_y, F_z), at the main bearing):
    piston k (mass m_p on its axis; the gas force P_k and the friction f_k along +x, the wall's
    N_k across), rod k (mass m at G = D + c e, inertia I_G across its axis; ball joints at both
    ends, so its moment equation about G counts only across e), link 9 (centre at O, inertia
    J_p about n and J_d across; forces from the plate bearing and the rods, moments from the plate
    bearing (⊥ n, and the friction M_plate about n) and from the cross: −I₁₃ψ̈ a + λ (a × c), the
    cross carrying no force), the shaft with the plates (J₀; the frame's force F_O, the friction
    M_main, the drive M_shaft). Unknowns: φ̈ if ``J0`` is given (else ``epsilon`` is prescribed
    and the shaft's moment equation is left out), per cylinder the forces at B and D and N, F_P,
    the plate bearing's moment M_P (with M_P·n = 0), λ and F_O: 8z + 10 (+1) equations, solved by
    ``numpy.linalg.solve``. Known friction: ``M_main``, ``M_plate``, ``f`` (z,). ``motion``:
    :func:`swash_plate_motion` at (φ, ω, ``epsilon`` or 0 with ``J0``) and at (φ, 0, 1), for a
    caller that solves one state again and again.

    Returns
    -------
    SwashReactions
        Its loss and through are computed from the given friction (see
        :func:`swash_plate_friction` for the friction laws closed on the reactions).
    """
    free = J0 is not None
    kin, kin1 = motion or (swash_plate_motion(mech, phi, omega, 0.0 if free else epsilon),
                           swash_plate_motion(mech, phi, 0.0, 1.0))  # (kin1: slopes in φ̈)
    z, h = mech.cylinders, mech.halves
    f = np.zeros(z) if f is None else np.asarray(f, dtype=np.float64)
    P = np.broadcast_to(np.asarray(gas_force, dtype=np.float64), (z,))
    m_p, m_r, ell, cg = mech.piston_mass, mech.rod_mass, mech.rod_length, mech.rod_cg_from_pin
    i_g = mech.rod_inertia_cg if mech.rod_model == "rigid" else m_r * cg * (ell - cg)
    n, a, c = kin["n"], kin["a"], kin["c"]
    J9 = mech.link_diametral_inertia * np.eye(3) + (
        mech.link_polar_inertia - mech.link_diametral_inertia) * np.outer(n, n)
    ic = mech.cross_inertia
    x = np.array([1.0, 0.0, 0.0])
    size = 8 * z + 10 + (1 if free else 0)
    E = 8 * z + 10  # column of φ̈
    iF = lambda k: 8 * k  # noqa: E731 (column blocks)
    iG = lambda k: 8 * k + 3  # noqa: E731
    iN = lambda k: 8 * k + 6  # noqa: E731
    iP, iM, iL, iO = 8 * z, 8 * z + 3, 8 * z + 6, 8 * z + 7
    A = np.zeros((size, size))
    rhs = np.zeros(size)
    row = 0

    def accel(key, k=None):
        """(part at the given φ̈ or at φ̈ = 0, slope in φ̈) of a kinematic quantity."""
        v0 = kin[key] if k is None else kin[key][k]
        v1 = kin1[key] if k is None else kin1[key][k]
        if free:
            return v0, v1
        return v0, 0.0 * v1

    def put(eq_rows, known, slope):
        """Move the φ̈ part of an equation's right-hand side to the left."""
        nonlocal row
        for j in range(len(eq_rows)):
            rhs[row + j] = known[j]
            if free:
                A[row + j, E] = -slope[j]
        row += len(eq_rows)

    for k in range(z):
        aD, aD1 = accel("xd2", k)
        dde, dde1 = accel("dde", k)
        e, B, D = kin["e"][k], kin["B"][k], kin["D"][k]
        G = D + cg * e
        aG, aG1 = aD * x + cg * dde, aD1 * x + cg * dde1
        # piston: −G_k + (P + f) x̂ + (0, N) = m_p a_D x̂
        for j in range(3):
            A[row + j, iG(k) + j] = -1.0
        A[row + 1, iN(k)], A[row + 2, iN(k) + 1] = 1.0, 1.0
        put(range(3), m_p * aD * x - (P[k] + f[k]) * x, m_p * aD1 * x)
        # rod: F + G = m a_G
        for j in range(3):
            A[row + j, iF(k) + j] = 1.0
            A[row + j, iG(k) + j] = 1.0
        put(range(3), m_r * aG, m_r * aG1)
        # rod about G, across e: (B − G) × F + (D − G) × G_D = I_G e × ë
        u1 = _cross3(e, [0.0, 0.0, 1.0] if abs(e[2]) < 0.9 else [0.0, 1.0, 0.0])
        u1 /= np.linalg.norm(u1)
        u2 = _cross3(e, u1)
        for j, u in enumerate((u1, u2)):
            # (r × F)·u = F·(u × r)
            A[row + j, iF(k): iF(k) + 3] = _cross3(u, B - G)
            A[row + j, iG(k): iG(k) + 3] = _cross3(u, D - G)
        put(range(2), [i_g * _cross3(e, dde) @ u for u in (u1, u2)],
            [i_g * _cross3(e, dde1) @ u for u in (u1, u2)])
    # link 9, force: F_P − Σ F_k = 0 (its centre O does not move)
    for j in range(3):
        A[row + j, iP + j] = 1.0
        for k in range(z):
            A[row + j, iF(k) + j] = -1.0
    put(range(3), np.zeros(3), np.zeros(3))
    # link 9, moments about O: M_P + M_plate n − I₁₃ψ̈ a + λ (a × c) − Σ B_k × F_k = Ḣ₉
    al9, al91 = accel("al9")
    w9 = kin["w9"]
    dH, dH1 = J9 @ al9 + _cross3(w9, J9 @ w9), J9 @ al91
    psi2, psi21 = al9 @ a, al91 @ a
    axc = _cross3(a, c)
    for j in range(3):
        A[row + j, iM + j] = 1.0
        A[row + j, iL] = axc[j]
    for k in range(z):
        B = kin["B"][k]
        Bx = np.array([[0.0, -B[2], B[1]], [B[2], 0.0, -B[0]], [-B[1], B[0], 0.0]])
        A[row: row + 3, iF(k): iF(k) + 3] = -Bx
    put(range(3), dH - M_plate * n + ic * psi2 * a, dH1 + ic * psi21 * a)
    # M_P ⊥ n: the plate bearing passes no moment about n but its friction
    A[row, iM: iM + 3] = n
    put(range(1), [0.0], [0.0])
    # shaft, forces: F_O = F_P (one half) or F_P + its mirror image
    mirror = np.diag([-1.0, 1.0, 1.0])
    for j in range(3):
        A[row + j, iO + j] = 1.0
    A[row: row + 3, iP: iP + 3] = -(np.eye(3) + (mirror if h == 2 else 0.0))
    put(range(3), np.zeros(3), np.zeros(3))
    if free:  # shaft about x: J₀ φ̈ = M_shaft − M_main − h x̂·(M_P + M_plate n)
        A[row, iM] = h
        put(range(1), [M_shaft - M_main - h * M_plate * n[0]], [-J0])
    assert row == size
    sol = np.linalg.solve(A, rhs)
    eps = sol[E] if free else epsilon
    M_P = sol[iM: iM + 3]
    torque = h * (M_P[0] + M_plate * n[0])  # what the plates put into link 9, over ω
    v = kin["xd1"] / omega if omega != 0.0 else swash_plate_motion(mech, phi, 1.0, 0.0)["xd1"]
    piston_loss = -h * f * v
    loss = np.array([M_main, -h * M_plate * kin["dtheta"], np.sum(piston_loss)])
    through = np.array([M_main + torque, torque, loss[2]])
    return SwashReactions(
        epsilon=float(eps), main=sol[iO: iO + 3], plate=sol[iP: iP + 3], plate_moment=M_P,
        B=np.array([sol[iF(k): iF(k) + 3] for k in range(z)]),
        D=np.array([sol[iG(k): iG(k) + 3] for k in range(z)]),
        N=np.array([sol[iN(k): iN(k) + 2] for k in range(z)]), f=f, M_main=float(M_main),
        M_plate=float(M_plate), loss=loss, through=through, piston_loss=piston_loss)


def swash_plate_friction(mech, coefficients, phi, omega, gas_force, J0, M_shaft,
                         sigma=None, epsilon=None, sel=None) -> SwashReactions:
    """φ̈ and the joint reactions with friction on them, closed by ``scipy.optimize.fsolve``.

    The friction laws, written out again: the main bearing's moment on the shaft
    M_main = σ μ r |F_O| + c ω; the plate bearing's on link 9 about n, opposing link 9's rate on
    the plate q = θ′ω, M_plate = −sign(q) μ r |F_P| − c q; the cylinder's axial force on piston k,
    opposing its speed v_k = ẋ_D, f_k = −sign(v_k)(μ |N_k| + F_ring + c_p P_k⁺) − c v_k. The
    unknowns (M_main, M_plate, f_1 … f_z) solve these, each evaluation solving
    :func:`swash_plate_reactions` (with φ̈) for the forces they depend on.

    ``coefficients``: dict with ``main`` and ``plate`` = (μ, r, c) and ``pistons`` = (μ, F_ring,
    c_p, c). ``sigma``: the direction of motion (sign ω, needed at ω = 0). The sign of q is σ's
    opposite (θ′ < 0); those of v_k are taken at the state itself (off the dead centres), or at
    the angle ``sel`` if given, where a run holds them between the pistons' dead centres (its
    breakpoints) so that no friction force flips inside a step. With ``epsilon`` the motion is
    prescribed (inverse dynamics): φ̈ is ``epsilon`` and the drive the shaft then needs,
    J₀φ̈ − M_shaft + (what the shaft puts into the plates), is ``through[0]`` + J₀φ̈ − M_shaft.
    """
    from scipy.optimize import fsolve

    sigma = float(np.sign(omega)) if sigma is None else sigma
    mu_o, r_o, c_o = coefficients["main"]
    mu_p, r_p, c_p = coefficients["plate"]
    mu_s, ring, share, c_s = coefficients["pistons"]
    P = np.broadcast_to(np.asarray(gas_force, dtype=np.float64), (mech.cylinders,))
    kin = swash_plate_motion(mech, phi, 1.0, 0.0)
    v_unit, q_unit = kin["xd1"], kin["dtheta"]  # per unit ω
    sliding = np.sign(v_unit if sel is None else swash_plate_motion(mech, sel, 1.0, 0.0)["xd1"])
    scale_f = np.abs(P).max() + 1.0
    scale_m = scale_f * mech.joint_radius
    motion = (swash_plate_motion(mech, phi, omega, 0.0 if epsilon is None else epsilon),
              swash_plate_motion(mech, phi, 0.0, 1.0))

    def solve(m_o, m_f, fk):
        if epsilon is None:
            return swash_plate_reactions(mech, phi, omega, None, P, m_o, m_f, fk, J0, M_shaft,
                                         motion=motion)
        return swash_plate_reactions(mech, phi, omega, epsilon, P, m_o, m_f, fk, motion=motion)

    def laws(y):
        m_o, m_f, fk = y[0] * scale_m, y[1] * scale_m, y[2:] * scale_f
        r = solve(m_o, m_f, fk)
        law_o = sigma * mu_o * r_o * np.linalg.norm(r.main) + c_o * omega
        law_f = sigma * mu_p * r_p * np.linalg.norm(r.plate) - c_p * q_unit * omega
        law_s = (-sliding * sigma * (mu_s * np.hypot(r.N[:, 0], r.N[:, 1]) + ring
                                     + share * np.maximum(P, 0.0))
                 - c_s * v_unit * omega)
        return np.concatenate([[(law_o - m_o) / scale_m], [(law_f - m_f) / scale_m],
                               (law_s - fk) / scale_f])

    y, info, _, _ = fsolve(laws, np.zeros(2 + mech.cylinders), xtol=1e-14, full_output=True)
    if not np.max(np.abs(info["fvec"])) <= 1e-13:  # relative to the forces' scale
        raise ArithmeticError(f"the friction laws are not closed: residual {info['fvec']}")
    return solve(y[0] * scale_m, y[1] * scale_m, y[2:] * scale_f)
