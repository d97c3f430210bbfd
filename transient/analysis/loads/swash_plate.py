"""Forces in a swash-plate engine along a trajectory φ(t), ω(t), ε(t): pistons, rods, the rods'
joints on link 9 and the torque each cylinder puts on the shaft.

The counterpart of :mod:`transient.analysis.loads.crank_slider` for the mechanism of Antonyuk et
al. (§2, exact kinematics of :mod:`transient.core.model.swash_plate`).
The paper gives the reduced equation (18) with M_П = Σ P_q u_q1 (19)–(20) and no piston or rod
forces: they follow here from d'Alembert's principle on the same geometry with the actual ω and ε.

Frame and signs (as :mod:`transient.core.model.swash_plate`)
------------------------------------------------------------
Fixed frame: ``Ox`` along the shaft toward the plate, the shaft turning from ``Oy`` toward ``Oz``.
Piston k's joint D_k = (x_D, r₁ cos ψ_Dk, r₁ sin ψ_Dk) slides along ``x``; the gas pushes it toward
+x (toward the plate), so u_k = dx_D/dφ (times ``halves``: the kernel sums both pistons of a
cylinder). The rod joins D_k to B_k on link 9, e = (B − D)/ℓ.

* **Piston force** along +x (the sense of the gas force; the crank-slider's "toward the crank"):
  P = P_g + P_j, P_j = −m_j (x_D″ω² + x_D′ε), m_j the piston plus the rod's share at D,
  m(ℓ − c)/ℓ (two-mass split, c the rod's centre of mass from D).
* **Rod.** Between its two masses the rod is massless; a rigid rod's inertia beyond the two masses,
  ΔI = I_G − m c (ℓ − c), gives the d'Alembert couple C = −ΔI e × ë (slender rod, spin about its
  axis ignored as in the kernel; ë = e″ω² + e′ε). The piston pushes the rod, and the rod pushes
  link 9 at B, with Φ = S e + H, H ⊥ e: the couple fixes H = −(ΔI/ℓ) ë_⊥ (ë_⊥ its part across e),
  and the piston's balance along x, P = S e_x + H_x, the **rod force** S = (P − H_x)/e_x
  (compression > 0; Gots (35) generalised: S = P/cos(tilt) for the two-mass rod).
* **Side force** of the cylinder wall on the piston, N = Φ − P x̂ (across x): its components
  ``N_radial`` along (0, cos ψ_D, sin ψ_D) (away from the shaft axis) and ``N_tangential`` along
  (0, −sin ψ_D, cos ψ_D) (the direction of rotation); |N| = P tan(tilt) for the two-mass rod.
* **Joint B** on link 9 takes Φ and the d'Alembert force of the rod's mass there, m c/ℓ:
  F_B = Φ − (m c/ℓ)(B″ω² + B′ε).
* **Torque on the shaft.** Link 9 is held by the plate's bearing (free about the plate normal) and
  by the Hooke cross, whose housing hinge does no work; by virtual work a force F at B_k passes
  the torque F·B_k′ to the shaft (B′ = dB/dφ). ``torque`` = halves·Φ·B′ is the cylinder's torque
  from its rod force (the crank-slider's T r), ``joint_torque`` = halves·F_B·B′ adds the rod's
  mass at B (the crank-slider's r(T + T_rш)), and ``shaft_torque`` = Σ joint_torque −
  (J₉ ε + ½ J₉′ ω²) removes what link 9 and the cross need to be accelerated (J₉: their part of
  the kernel's reduced inertia, Antonyuk (15)–(17), (21)).

Virtual work (the independent checks, ``tests/unit/test_loads_radial_swash.py``)
--------------------------------------------------------------------------------
* Per cylinder: torque·ω = halves·(P ẋ_D − ΔI ė·ë) (the massless rod passes P ẋ_D; the couple's
  power is C·(e × ė) = −ΔI ė·ë), so for two-mass rods Σ torque·ω = Σ P_k ẋ_k and, at any speed,
  Σ torque = Σ_k P_k u_k — the mechanism's generalized force M_П of (19) with the inertia forces
  in P, computed with the kernel's u_k.
* Whole engine: shaft_torque = Σ_k P_g,k u_k − J ε − ½ J′ ω² with J, J′ of
  :func:`transient.core.model.swash_plate.swash_terms` (eq. (18)): every inertia force above is checked
  against the kinetic energy the simulation integrates.

What does not apply
-------------------
There is no crankpin: the crankpin load, the big-end bearing and the running torques along a
crankshaft (Gots §2.6–§2.8) have no counterpart, nor do the main-journal loads by the tabular
method (58) (the shaft's bearings carry the plate's axial and tilting loads, which this analysis
does not resolve: link 9's bearing and the cross's hinge reactions are left out) or the wear
diagrams. With ``halves = 2`` the mirror pistons carry the same forces (mirror images; N's
components as above); the torques count both.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ...core.model import swash_plate as core
from ...mechanisms.swash_plate import SwashPlate
from .common import (
    Array,
    PistonLoads,
    along_trajectory,
    gas_force_array,
    rod_split,
    trajectory_arrays,
)

__all__ = [
    "SwashKinematics",
    "SwashLoads",
    "swash_kinematics",
    "swash_loads",
    "swash_loads_from_trajectory",
]


@dataclass(frozen=True)
class SwashKinematics:
    """Exact kinematics of half 1 at shaft angles φ (n,), derivatives in φ.

    ``B``, ``dB``, ``ddB`` (z, n, 3): joints on link 9 [m, m/rad, m/rad²]; ``x``, ``dx``, ``ddx``
    (z, n): x of the piston joints D (dx = u_k/halves); ``e``, ``de``, ``dde`` (z, n, 3): the rod's
    unit vector (B − D)/ℓ and its derivatives; ``J_link``, ``dJ_link`` (n,): link 9's and the
    cross's part of the reduced inertia, both halves [kg m², kg m²/rad]; ``psi`` (z,) the cylinder
    angles ψ_Dk [rad].
    """

    phi: Array
    B: Array
    dB: Array
    ddB: Array
    x: Array
    dx: Array
    ddx: Array
    e: Array
    de: Array
    dde: Array
    J_link: Array
    dJ_link: Array
    psi: Array


def swash_kinematics(mech: SwashPlate, phi: ArrayLike) -> SwashKinematics:
    """:class:`SwashKinematics` at the shaft angles ``phi`` [rad].

    Positions from the compiled :func:`transient.core.model.swash_plate.swash_points`, the Hooke joint
    from :func:`transient.core.model.swash_plate.hooke` (one sample at a time); the derivatives as the
    kernel :func:`~transient.core.model.swash_plate.swash_terms` forms them — B′ = w × B,
    B″ = w′ × B + w × B′ with w = i + θ′n (eq. (8)) and eq. (10) differentiated twice — here on
    arrays, because the kernel keeps B′, B″ to itself.
    """
    phi = np.ascontiguousarray(np.atleast_1d(np.asarray(phi, dtype=np.float64)))
    mp = mech.pack()
    z, n = mech.cylinders, phi.size
    theta = np.empty(n)
    pts = np.empty((n, z, 6))
    core.swash_points(mp, phi, theta, pts)
    hk = np.array([core.hooke(mp, p) for p in phi]).reshape(n, 5)
    d1, d2, u13, du13 = hk[:, 1], hk[:, 2], hk[:, 3], hk[:, 4]
    ca, sa = mp[core.COS_A], mp[core.SIN_A]
    normal = np.stack([np.full(n, ca), sa * np.cos(phi), sa * np.sin(phi)], axis=-1)
    w = d1[:, None] * normal
    w[:, 0] += 1.0
    dw = d2[:, None] * normal + d1[:, None] * np.cross([1.0, 0.0, 0.0], normal)
    B = np.moveaxis(pts[..., :3], 1, 0)  # (z, n, 3)
    dB = np.cross(w, B)
    ddB = np.cross(dw, B) + np.cross(w, dB)
    lateral = pts[..., 4:].transpose(1, 0, 2) - B[..., 1:]  # (y_D − y_B, z_D − z_B)
    ell = mech.rod_length
    root = np.sqrt(ell * ell - np.sum(lateral * lateral, axis=-1))
    # Eq. (10): x_D = x_B − root, root² = ℓ² − |lateral|²; differentiate twice.
    q1 = -np.sum(lateral * dB[..., 1:], axis=-1)
    q2 = np.sum(dB[..., 1:] ** 2, axis=-1) - np.sum(lateral * ddB[..., 1:], axis=-1)
    r1 = -q1 / root
    r2 = -(q2 + r1 * r1) / root
    x, dx, ddx = B[..., 0] - root, dB[..., 0] - r1, ddB[..., 0] - r2
    along = np.zeros_like(B)
    e = (B - np.concatenate([x[..., None], pts[..., 4:].transpose(1, 0, 2)], axis=-1)) / ell
    along[..., 0] = dx
    de = (dB - along) / ell
    along[..., 0] = ddx
    dde = (ddB - along) / ell
    wn = ca + d1  # link 9's spin about the plate normal over φ̇ (core.hooke)
    halves = mech.halves
    J_link = halves * (mech.link_polar_inertia * wn * wn + mech.link_diametral_inertia * sa * sa
                       + mech.cross_inertia * u13 * u13)
    dJ_link = 2.0 * halves * (mech.link_polar_inertia * wn * d2 + mech.cross_inertia * u13 * du13)
    return SwashKinematics(phi=phi, B=B, dB=dB, ddB=ddB, x=x, dx=dx, ddx=ddx, e=e, de=de, dde=dde,
                           J_link=J_link, dJ_link=dJ_link,
                           psi=np.asarray(mech.bank_angles, dtype=np.float64))


@dataclass(frozen=True)
class SwashLoads(PistonLoads):
    """Forces of every cylinder along a trajectory (module docstring), shape ``(z, n)`` unless
    noted; one piston of each cylinder (the mirror one, ``halves = 2``, carries the same).

    ``x``, ``v`` joint D's x [m] and its rate [m/s]; ``P_g``, ``P_j``, ``P`` gas, inertia and total
    piston force along +x [N]; ``S`` rod force (compression > 0) [N]; ``N_radial``,
    ``N_tangential`` the wall's force on the piston [N]; ``joint_x``, ``joint_y``, ``joint_z`` the
    force on link 9 at B, F_B [N]; ``torque`` halves·Φ·B′ (its sum is
    :attr:`~transient.analysis.loads.common.PistonLoads.engine_torque`, the
    crank-slider's Σ T r), ``joint_torque`` halves·F_B·B′ [N m]; ``rod_power``
    halves·(−ΔI ė·ë) [W]; ``link_torque`` (n,) −(J₉ε + ½J₉′ω²) [N m]; ``halves``, ``area``
    (piston area [m²]).
    """

    x: Array
    N_radial: Array
    N_tangential: Array
    joint_x: Array
    joint_y: Array
    joint_z: Array
    joint_torque: Array
    rod_power: Array
    link_torque: Array
    halves: int

    @property
    def N(self) -> Array:
        """|N| [N]."""
        return np.hypot(self.N_radial, self.N_tangential)

    @property
    def shaft_torque(self) -> Array:
        """Σ joint_torque + link_torque [N m], shape (n,): what link 9 passes to the plate."""
        return self.joint_torque.sum(axis=0) + self.link_torque


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def swash_loads(mech: SwashPlate, phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike,
                gas_force: ArrayLike | None = None) -> SwashLoads:
    """Piston, rod, joint forces and torques of a swash-plate engine.

    Parameters
    ----------
    mech : transient.mechanisms.swash_plate.SwashPlate
    phi, omega, epsilon : array_like, shape (n,) or scalars
        Shaft angle [rad], speed [rad/s], angular acceleration [rad/s²], broadcast together.
    gas_force : array_like, shape (z, n) or broadcastable, optional
        Gas force on each piston toward its plate [N]; 0 if omitted.
    """
    phi, omega, epsilon = trajectory_arrays(phi, omega, epsilon)
    kin = swash_kinematics(mech, phi)
    z, n = mech.cylinders, phi.size
    w, eps = omega, epsilon
    w2 = w * w
    ell = mech.rod_length
    m_d, m_b, d_inertia = rod_split(mech)  # at the piston joint D and at B
    p_g = gas_force_array(gas_force, (z, n))
    p_j = -(mech.piston_mass + m_d) * (kin.ddx * w2 + kin.dx * eps)
    p = p_g + p_j
    e_dot = kin.de * w[:, None]
    e_acc = kin.dde * w2[:, None] + kin.de * eps[:, None]
    h = -(d_inertia / ell) * (e_acc - _dot(e_acc, kin.e)[..., None] * kin.e)
    s = (p - h[..., 0]) / kin.e[..., 0]
    phi_b = s[..., None] * kin.e + h  # the rod's push on link 9 at B (= the piston's on the rod)
    side = phi_b.copy()
    side[..., 0] -= p  # N = Φ − P x̂ (its x component is 0 by the balance along x)
    cp, sp = np.cos(kin.psi)[:, None], np.sin(kin.psi)[:, None]
    f_b = phi_b - m_b * (kin.ddB * w2[:, None] + kin.dB * eps[:, None])
    halves = mech.halves
    return SwashLoads(
        x=kin.x, v=kin.dx * w, P_g=p_g, P_j=p_j, P=p, S=s,
        N_radial=side[..., 1] * cp + side[..., 2] * sp,
        N_tangential=-side[..., 1] * sp + side[..., 2] * cp,
        joint_x=f_b[..., 0], joint_y=f_b[..., 1], joint_z=f_b[..., 2],
        torque=halves * _dot(phi_b, kin.dB), joint_torque=halves * _dot(f_b, kin.dB),
        rod_power=-halves * d_inertia * _dot(e_dot, e_acc),
        link_torque=-(kin.J_link * eps + 0.5 * kin.dJ_link * w2), halves=halves,
        area=mech.piston_area)


def swash_loads_from_trajectory(scene, traj) -> SwashLoads:
    """:func:`swash_loads` along a run's trajectory (``phi``, ``omega``, ``epsilon``; the gas
    force of :func:`~.common.trajectory_gas_force`)."""
    return along_trajectory(swash_loads, scene, traj)
