"""Forces in a crank-slider engine along a trajectory φ(t), ω(t), ε(t): piston, rod, crankpin,
big-end bearing, main journals and the running torques (Gots §2.3–§2.8).

The textbook assumes a constant speed; here ω and ε are arbitrary, so every inertia force has a
term in ε besides the one in ω². Everything is plain numpy over arrays of samples (this is the
user-facing analysis layer, above the compiled core); the kinematics are the exact crank-slider of
:func:`transient.core.model.crank_slider.slider`, of which :func:`slider_arrays` is the vectorised twin
(``tests/unit/test_loads.py`` checks them against each other to 1e-13).

Frame and signs (Gots §1, Fig. 27)
----------------------------------
One cylinder, as :mod:`transient.core.model.crank_slider`: origin on the crank axis, ``y`` along the
cylinder axis toward the head, ``x`` to the side the crankpin moves at the top. Crankpin
A = r(sin α, cos α) at the local crank angle α (from the cylinder axis, in the direction of
rotation); piston pin B = (e, y_B); sin β = (r sin α − e)/l, β > 0 when the rod leans in the
direction of rotation. Piston travel s is measured from the true TDC, s′ = ds/dα > 0 toward the
crank. Unit vectors: ĉ = A/r (crank, outward), t̂ = dĉ/dα = (cos α, −sin α) (direction of
rotation), û = (A − B)/l = (sin β, −cos β) (along the rod, from the pin to the crankpin).

* **Piston forces** (positive toward the crank axis, Gots §2.3–2.4): the piston-pin acceleration
  toward the crank is d²s/dt² = s″ω² + s′ε, so

  P_j = −m_j (s″ω² + s′ε),  P_g = (p − p0) F_p (33),  P = P_g + P_j,

  with m_j = m_piston + m₁ (Gots: reciprocating mass). At constant speed this is (30) with the exact
  acceleration; the ε s′ term is what the textbook lacks.
* **Rod force and side force.** The two-mass rod (Gots (20)) between its end masses is a
  two-force member: it pushes the pin with −S û and the crankpin with +S û (S > 0: compression).
  The piston's balance along y, −P + S cos β = 0, and along x, N − S sin β = 0 (N: the wall's force
  on the piston along +x) give

  S = P / cos β (35),  N = P tan β (34).

  N > 0 means the wall pushes the piston toward +x, i.e. the piston bears on the −x wall (the
  major-thrust side on the power stroke).
* **Crankpin components** of +S û: K = −(S û)·ĉ = S cos(α+β) (36), positive toward the crank axis,
  and T = (S û)·t̂ = S sin(α+β) (37), positive in the direction of rotation. These hold exactly for
  the offset mechanism too (β from the offset geometry). Torque of the cylinder M = T r (38):
  since s′ = r sin(α+β)/cos β, T r = P s′, i.e. T r ω = P ds/dt (virtual work; unit-tested to
  1e-12).
* **Rotating masses** (rod's m₂ at the crankpin, Gots (32)): the crankpin's acceleration is
  −ω² r ĉ + ε r t̂, so its d'Alembert force is K_rш = −m₂ r ω² (radial, negative: centrifugal) and
  **T_rш = −m₂ r ε** (tangential, the term that the constant-speed textbook does not have). The
  same for the crank's unbalanced mass m_k (28): K_rk = −m_k r ω², T_rk = −m_k r ε.
* **Crankpin load** (40)/(41) as a vector: R = (K + K_rш) along −ĉ and (T + T_rш) along t̂, and
  |R| = √((K + K_rш)² + (T + T_rш)²). The book's scalar "√(S² + K_rш²)" in (40)/(41) is wrong:
  it holds only for perpendicular vectors (found by re-deriving; the vector sum is what
  reproduces the example's R_max = 6.33 MPa).
* **Big-end bearing, rod frame.** The crankpin load rotated by (α + β): the axial component
  R_a = (K+K_rш) cos(α+β) + (T+T_rш) sin(α+β) along û (equal to S plus the m₂ inertia's share),
  and the normal one R_n = −(K+K_rш) sin(α+β) + (T+T_rш) cos(α+β) along (cos β, sin β) (the
  direction that is t̂ at α + β = 0). The force on the bearing shell is the opposite vector: Gots'
  polar of the big-end bearing, "rotate by 180° + (φ + β)" (Gots §2.6), plots it.
* **Rigid rod.** A rigid rod (mass m at G, l₁ from the pin, inertia I_G) is the two-mass rod
  (m₁ = m(l − l₁)/l, m₂ = m l₁/l, whose own inertia about G is m l₁(l − l₁)) plus a couple from
  the difference ΔI = I_G − m l₁(l − l₁): C = −ΔI β̈ with β̈ = β″ω² + β′ε (in the sense of β).
  The piston cannot carry it along y, so it is reacted by equal and opposite forces ±H along x at
  the two ends, H = C/(l cos β): they add H to N, −H sin α to K, H cos α to T and H sin β to S
  (then the rod's axial force at the crankpin). The virtual-work identity becomes
  T r ω = P ds/dt + C β̇. For the two-mass rod ΔI = 0 and these terms vanish (Gots neglects
  them, §2.2: "the difference is ignored").

Multi-cylinder engines
----------------------
Cylinder k sits at local angle α_k = φ − ``firing_angles[k]`` (its crank is at the cylinder axis
at ``firing_angles[k]``). Its gas table is read at φ − :func:`transient.scene.queries.gas_phases`
(local 0 = gas-exchange TDC of a 4-stroke). Its crankpin stands θ_k = δ_k − ``firing_angles[k]``
ahead of the shaft's reference line (δ_k its bank; ``CrankSlider.pin_angles``), so crankpin k
leads crankpin 1 by γ_k = θ_k − θ_1 (mod 2π) in the direction of rotation (Gots §2.7.1:
clockwise seen from the nose); in an in-line engine γ_k = ``firing_angles[0]`` −
``firing_angles[k]``. Throws are numbered from the nose: one per cylinder, or, in a V engine
with two rods on a pin, cylinders 2k − 1 and 2k on throw k (:mod:`transient.mechanisms.throws`).
Each cylinder's record carries its share of its throw's unbalanced mass (K_rk, T_rk): all of it,
or half where two cylinders share the throw.

* **Engine torque**: Σ T_k r (Gots §2.8, table П4.2),
  :attr:`~transient.analysis.loads.common.PistonLoads.engine_torque`.
* **Running torques** (§2.8, П4.4/П4.5): journal j carries the torque of the throws ahead of it
  (journal 1 at the nose carries none, the last one the total), a crankpin the journal ahead of
  it plus what its throw adds up to its middle: half of a rod's torque at the middle (one rod,
  or fork-and-blade rods), the whole of a side-by-side rod ahead of the middle and none of the
  one behind it, and half of the crank's own term. With ε ≠ 0 a throw passes to the shaft
  r(T + T_rш + T_rk), not T r: the rotating masses ahead of a journal need torque to be
  accelerated; :func:`running_torques` includes it unless told not to (at ε = 0 it is the same).
* **Main journals**, the split beam of (58): the crank is cut at every main journal, and each
  throw is a beam simply supported on the two journals beside it, so a force at the distance
  a behind the front journal of a span L puts F(L − a)/L on that journal and F a/L on the one
  behind (the lever rule). The throw's unbalanced mass and a counterweight sit symmetrically:
  half to each journal (42)/(43). A rod's force R = K + K_rш, T + T_rш acts in its big end's
  middle plane: in the throw's middle for one rod or fork-and-blade rods (half to each
  journal, (58) exactly), at ∓ b/2 from it for side-by-side rods b apart (½ ± b/(2L)), so the
  couple of the two rods' offset is carried by the journals as a difference of their loads. In
  the frame of crank 1 (y along K₁, toward the axis; x along T₁, the direction of rotation — the
  axes Gots' positive K and T map onto, §2.7.3), a force with radial K_Σ and tangential T_Σ
  at a crankpin γ ahead of crank 1 has x: T_Σ cos γ − K_Σ sin γ, y: T_Σ sin γ + K_Σ cos γ.

Units: SI (N, N·m, rad). Divide by
:attr:`~transient.analysis.loads.common.PistonLoads.area` for Gots' specific forces.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .common import (
    Array,
    CrankpinLoads,
    along_trajectory,
    gas_force_array,
    rod_split,
    rotating_inertia_force,
    rotating_inertia_rows,
    trajectory_arrays,
)

__all__ = [
    "CylinderLoads",
    "MainJournalLoads",
    "crank_slider_loads",
    "loads_from_trajectory",
    "main_journal_loads",
    "running_torques",
    "slider_arrays",
]


def slider_arrays(alpha: ArrayLike, r: float, l: float, e: float = 0.0
                  ) -> tuple[Array, Array, Array, Array, Array, Array]:
    """Exact crank-slider kinematics, vectorised: the numpy twin of
    :func:`transient.core.model.crank_slider.slider`.

    Returns ``(s, ds, dds, beta, dbeta, ddbeta)`` at the local angles ``alpha`` [rad]: piston
    travel from the true TDC [m] and its derivatives in α [m/rad, m/rad²] (positive toward the
    crank), the rod angle [rad] and its derivatives [1, 1/rad] (Gots (1), (7)–(8), (12)–(19)).
    """
    alpha = np.asarray(alpha, dtype=np.float64)
    sa = np.sin(alpha)
    ca = np.cos(alpha)
    sb = (r * sa - e) / l
    cb = np.sqrt(1.0 - sb * sb)
    db = r * ca / (l * cb)
    ddb = (l * sb * db * db - r * sa) / (l * cb)
    y_pin = r * ca + l * cb
    dy_pin = -r * sa - l * sb * db
    ddy_pin = -r * ca - l * cb * db * db - l * sb * ddb
    y_tdc = math.sqrt((l + r) ** 2 - e * e)
    return y_tdc - y_pin, -dy_pin, -ddy_pin, np.arcsin(sb), db, ddb


@dataclass(frozen=True)
class CylinderLoads(CrankpinLoads):
    """Forces of every cylinder along a trajectory (module docstring: derivations and signs).

    A :class:`~.common.CrankpinLoads` with a row per cylinder: every array has the shape
    ``(n_cylinders, n_samples)`` (the crankpin's rows are its rod's load on it: a pin that two
    rods share carries the rows of both); forces in N, torques in N·m.

    Attributes
    ----------
    alpha : local crank angle of each cylinder, φ − firing angle [rad].
    s, v : piston travel from the true TDC [m] and velocity ds/dt toward the crank [m/s].
    beta : rod angle [rad].
    P_g, P_j, P : gas force (p − p0)F_p, reciprocating inertia force −m_j(s″ω² + s′ε), and their
        sum; positive toward the crank axis (Gots (30), (33)).
    N : side force of the wall on the piston along +x, P tan β (34) (+ the rigid rod's H).
    S : rod force, compression positive, P/cos β (35) (+ H sin β for a rigid rod).
    K, T : the rod's force on the crankpin, radial (toward the axis) and tangential (in the
        direction of rotation): P cos(α+β)/cos β (36), P sin(α+β)/cos β (37).
    K_rod, T_rod : d'Alembert force of the rod's rotating mass m₂: −m₂ r ω² (K_rш, (32)) and
        −m₂ r ε (tangential, only when the speed varies).
    K_crank, T_crank : the same for the cylinder's share of its throw's unbalanced mass m_k (Gots
        (28)): K_rk, T_rk.
    R_K, R_T, R : crankpin load K + K_rш, T + T_rш and its magnitude (40)/(41) as vectors.
    R_axial, R_normal : the crankpin load in the rod frame (big-end bearing), see the module
        docstring.
    torque : cylinder torque T r (38); its sum over the cylinders is
        :attr:`~transient.analysis.loads.common.PistonLoads.engine_torque`.
    throw_torque : r (T + T_rш + T_rk), what the throw passes to the shaft; = torque at ε = 0.
    r, area : crank radius [m] and piston area F_p [m²].
    """

    R_axial: Array
    R_normal: Array


def crank_slider_loads(mech, phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike,
                       gas_force: ArrayLike | None = None) -> CylinderLoads:
    """Piston, rod and crankpin forces of every cylinder of a crank-slider engine.

    Parameters
    ----------
    mech : transient.mechanisms.crank_slider.CrankSlider
        Geometry and masses (any offset, two-mass or rigid rod).
    phi, omega, epsilon : array_like, shape (n,) or scalars
        Shaft angle [rad], speed [rad/s] and angular acceleration [rad/s²], broadcast together
        (constant speed: a scalar ω and ε = 0).
    gas_force : array_like, shape (n_cylinders, n) or broadcastable, optional
        Gas force on each piston P_g [N], positive toward the crank
        (:func:`~.common.gas_force_from_pressure`, :func:`~.common.gas_forces`). Omitted: 0
        (inertia only).

    Returns
    -------
    CylinderLoads
    """
    phi, omega, epsilon = trajectory_arrays(phi, omega, epsilon)
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    alpha = phi[None, :] - np.asarray(mech.firing_angles, dtype=np.float64)[:, None]
    w, eps = omega[None, :], epsilon[None, :]
    w2 = w * w
    s, ds, dds, beta, db, ddb = slider_arrays(alpha, r, l, e)
    m1, m2, d_inertia = rod_split(mech)
    m_j = mech.piston_mass + m1
    p_g = gas_force_array(gas_force, alpha.shape)
    p_j = -m_j * (dds * w2 + ds * eps)
    p = p_g + p_j
    cb = np.cos(beta)
    sab = np.sin(alpha + beta)
    cab = np.cos(alpha + beta)
    rod = p / cb
    # The rigid rod's couple ΔI β̈ in the sense of β, reacted by ±H along x (module docstring).
    h = -d_inertia * (ddb * w2 + db * eps) / (l * cb) if d_inertia != 0.0 else 0.0
    sa, ca = np.sin(alpha), np.cos(alpha)
    N = p * np.tan(beta) + h
    S = rod + h * np.sin(beta)
    K = rod * cab - h * sa
    T = rod * sab + h * ca
    k_rod, t_rod = rotating_inertia_rows(m2, r, w, eps, alpha.shape)
    k_crank, t_crank = rotating_inertia_rows(mech.crank_mass_per_cylinder, r, w, eps,
                                             alpha.shape)
    r_k = K + k_rod
    r_t = T + t_rod
    return CylinderLoads(
        alpha=alpha, s=s, v=ds * w, beta=beta, P_g=p_g, P_j=p_j, P=p, N=N, S=S, K=K, T=T,
        K_rod=k_rod, T_rod=t_rod, K_crank=k_crank, T_crank=t_crank,
        R_K=r_k, R_T=r_t, R=np.hypot(r_k, r_t),
        R_axial=r_k * cab + r_t * sab, R_normal=-r_k * sab + r_t * cab,
        torque=T * r, throw_torque=(T + t_rod + t_crank) * r, r=r,
        area=mech.piston_area)


def loads_from_trajectory(scene, traj) -> CylinderLoads:
    """:func:`crank_slider_loads` along a run's trajectory (``phi``, ``omega``, ``epsilon``), the
    gas force from :func:`~.common.trajectory_gas_force`."""
    return along_trajectory(crank_slider_loads, scene, traj)


def running_torques(mech, loads: CylinderLoads, include_rotating: bool = True
                    ) -> tuple[Array, Array]:
    """Running (cumulative) torques along the crank (Gots §2.8, tables П4.4 and П4.5).

    Throws are numbered from the nose; journal 1 is ahead of throw 1.

    Parameters
    ----------
    mech : CrankSlider
    loads : CylinderLoads
    include_rotating : bool
        Use the throw torque r(T + T_rш + T_rk) (default; the torque in the shaft when ω varies)
        instead of the cylinder torque T r. Identical at constant speed.

    Returns
    -------
    journals : ndarray, shape (n_throws + 1, n)
        M_кш,j = Σ of the throws ahead: 0 at journal 1, the engine torque at the last [N·m].
    crankpins : ndarray, shape (n_throws, n)
        M_шш,k = M_кш,k + what throw k adds up to its middle (module docstring); with one rod per
        throw M_кш,k + ½ M_k [N·m].
    """
    throw = mech.throw_of_cylinder()
    rods = loads.torque + (loads.T_rod * loads.r if include_rotating else 0.0)
    crank = loads.T_crank * loads.r if include_rotating else np.zeros_like(rods)
    ahead = 0.5 - 0.5 * np.sign(mech.axial_positions())[:, None]  # ½ in the middle plane
    journals = np.zeros((mech.n_throws + 1, rods.shape[1]))
    np.add.at(journals, throw + 1, rods + crank)
    middle = np.zeros((mech.n_throws, rods.shape[1]))
    np.add.at(middle, throw, ahead * rods + 0.5 * crank)
    journals = np.cumsum(journals, axis=0)
    return journals, journals[:-1] + middle


@dataclass(frozen=True)
class MainJournalLoads:
    """Main-journal loads, shape ``(n_throws + 1, n)`` [N].

    The force with which journal j presses on its bearing (its shares of the loads of the two
    throws beside it, (43), by the lever rule of the split beam), in the frame of crank 1 as
    Gots' (58) — ``x`` along T₁ (direction of rotation at crankpin 1), ``y`` along K₁ (from
    crankpin 1 toward the axis) — and in the block's frame: ``side`` perpendicular to the
    reference axis (bank angle 0), toward where the crankpins pass at the top, ``down`` along it
    away from the heads (for an in-line engine on bank 0, the cylinder frame's +x and the sense
    of P).

    Attributes
    ----------
    x, y : components in the frame of crank 1 [N].
    side, down : components in the block frame [N].
    gamma : angle of each cylinder's crankpin ahead of crankpin 1 in the direction of rotation
        [rad], (n_cylinders,).
    """

    x: Array
    y: Array
    side: Array
    down: Array
    gamma: Array

    @property
    def magnitude(self) -> Array:
        """R = √(R_x² + R_y²) (59) [N]."""
        return np.hypot(self.x, self.y)


def main_journal_loads(mech, loads: CylinderLoads, omega: ArrayLike, epsilon: ArrayLike,
                       counterweight_mass: float = 0.0, counterweight_angle: float = math.pi
                       ) -> MainJournalLoads:
    """Main-journal loads by the split beam of (58): each throw on the two journals beside it.

    A rod's load R = K + K_rш, T + T_rш acts in its big end's middle plane and is shared by the
    lever rule (half each in the throw's middle); the throw's unbalanced mass and counterweight
    half each (Gots (42), (43)); the tangential d'Alembert terms only when ε ≠ 0.

    Parameters
    ----------
    mech : CrankSlider
        Throws and cylinders numbered from the nose.
    loads : CylinderLoads
        From :func:`crank_slider_loads` with the same ``omega``, ``epsilon``.
    omega, epsilon : array_like
        Speed [rad/s] and angular acceleration [rad/s²] of the samples (for the counterweights).
    counterweight_mass : float
        Counterweight mass per throw reduced to the crank radius [kg] (both webs together, placed
        symmetrically so the throw stays symmetric), 0 for none; with split pins half of it
        turns with each pin, as the crank mass does.
    counterweight_angle : float
        Its angle ahead of the crank in the direction of rotation [rad]; π: opposite the crank.
    """
    gamma = np.mod(mech.pin_angles() - mech.pin_angles()[0], 2.0 * math.pi)
    k_cw, t_cw = rotating_inertia_force(counterweight_mass / mech.cylinders_per_throw,
                                        mech.crank_radius, omega, epsilon, counterweight_angle)
    cg, sg = np.cos(gamma)[:, None], np.sin(gamma)[:, None]

    def crank1(k, t):  # (58): a load at crankpin γ in the frame of crank 1
        return t * cg - k * sg, t * sg + k * cg

    rod_x, rod_y = crank1(loads.R_K, loads.R_T)
    mass_x, mass_y = crank1(loads.K_crank + k_cw, loads.T_crank + t_cw)
    zeta = mech.axial_positions()[:, None]
    throw = mech.throw_of_cylinder()
    x = np.zeros((mech.n_throws + 1, rod_x.shape[1]))
    y = np.zeros_like(x)
    for journal, lever in ((throw, 0.5 - zeta), (throw + 1, 0.5 + zeta)):  # ahead, behind
        np.add.at(x, journal, lever * rod_x + 0.5 * mass_x)
        np.add.at(y, journal, lever * rod_y + 0.5 * mass_y)
    psi = loads.alpha[0][None, :] + mech.bank_angles[0]  # crank 1 from the reference axis
    cp, sp = np.cos(psi), np.sin(psi)
    return MainJournalLoads(x=x, y=y, side=x * cp - y * sp, down=x * sp + y * cp, gamma=gamma)
