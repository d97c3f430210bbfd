"""Forces in a crank-slider engine along a trajectory φ(t), ω(t), ε(t): piston, rod, crankpin,
big-end bearing, main journals and the running torques (Gots §2.3–§2.8).

The textbook assumes a constant speed; here ω and ε are arbitrary, so every inertia force has a
term in ε besides the one in ω². Everything is plain numpy over arrays of samples (this is the
user-facing analysis layer, DESIGN §2); the kinematics are the exact crank-slider of
:func:`transient.core.crank_slider.slider`, of which :func:`slider_arrays` is the vectorised twin
(``tests/unit/test_loads.py`` checks them against each other to 1e-13).

Frame and signs (DESIGN §4, Gots §1, Fig. 27)
---------------------------------------------
One cylinder, as :mod:`transient.core.crank_slider`: origin on the crank axis, ``y`` along the
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
at ``firing_angles[k]``). Its gas table is read at φ − :func:`transient.assemble.gas_phases`
(local 0 = gas-exchange TDC of a 4-stroke). For an in-line engine (one cylinder per throw,
cylinders numbered from the nose) crank k leads crank 1 by γ_k = ``firing_angles[0]`` −
``firing_angles[k]`` (mod 2π) in the direction of rotation (Gots §2.7.1: clockwise seen from
the nose).

* **Engine torque**: Σ T_k r (Gots §2.8, table П4.2), :attr:`CylinderLoads.engine_torque`.
* **Running torques** (§2.8, П4.4/П4.5): journal j carries the torque of the throws ahead of it
  (journal 1 at the nose carries none, the last one the total), crankpin k carries the journal
  ahead of it plus half its own cylinder's torque. With ε ≠ 0 a throw passes to the shaft
  r(T + T_rш + T_rk), not T r: the rotating masses ahead of a journal need torque to be
  accelerated; :func:`running_torques` includes it unless told not to (at ε = 0 it is the same).
* **Main journals**, tabular method (58) for symmetric throws on a split beam: each support
  carries half of each adjacent throw's load R_k = R + K_rk (+ counterweight) (42)/(43). In the
  frame of crank 1 (y along K₁, toward the axis; x along T₁, the direction of rotation — the axes
  Gots' positive K and T map onto, §2.7.3), throw i contributes
  x: ½(T_Σ cos γ_i − K_Σ sin γ_i), y: ½(T_Σ sin γ_i + K_Σ cos γ_i), which is (58) with the
  constant reactions R_iK, R_iT of §2.7.1 equal to half the throw's centrifugal (and, with ε,
  tangential) forces.

Units: SI (N, N·m, rad). Divide by :attr:`CylinderLoads.area` for Gots' specific forces.
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
    :func:`transient.core.crank_slider.slider`.

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

    A :class:`~.common.CrankpinLoads` with one crankpin per cylinder: every array has the shape
    ``(n_cylinders, n_samples)``; forces in N, torques in N·m.

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
    K_crank, T_crank : the same for the crank throw's unbalanced mass m_k (Gots (28)): K_rk, T_rk.
    R_K, R_T, R : crankpin load K + K_rш, T + T_rш and its magnitude (40)/(41) as vectors.
    R_axial, R_normal : the crankpin load in the rod frame (big-end bearing), see the module
        docstring.
    torque : cylinder torque T r (38); its sum over the cylinders is :attr:`engine_torque`.
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
    k_crank, t_crank = rotating_inertia_rows(mech.crank_mass, r, w, eps, alpha.shape)
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


def _check_inline(mech) -> None:
    banks = np.asarray(mech.bank_angles, dtype=np.float64)
    if banks.size and np.ptp(banks) > 1e-12:
        raise ValueError("running torques and main-journal loads are implemented for in-line "
                         "engines (one cylinder per throw, all bank angles equal); got bank "
                         f"angles {np.degrees(banks).tolist()}°")


def running_torques(mech, loads: CylinderLoads, include_rotating: bool = True
                    ) -> tuple[Array, Array]:
    """Running (cumulative) torques of an in-line engine (Gots §2.8, tables П4.4 and П4.5).

    Cylinders (throws) are numbered from the nose; journal 1 is ahead of throw 1.

    Parameters
    ----------
    mech : CrankSlider
        In-line (all bank angles equal).
    loads : CylinderLoads
    include_rotating : bool
        Use the throw torque r(T + T_rш + T_rk) (default; the torque in the shaft when ω varies)
        instead of the cylinder torque T r. Identical at constant speed.

    Returns
    -------
    journals : ndarray, shape (n_cylinders + 1, n)
        M_кш,j = Σ_{k<j} M_k: 0 at journal 1, the engine torque at the last journal [N·m].
    crankpins : ndarray, shape (n_cylinders, n)
        M_шш,k = M_кш,k + ½ M_k [N·m].
    """
    _check_inline(mech)
    m = loads.throw_torque if include_rotating else loads.torque
    journals = np.concatenate([np.zeros((1, m.shape[1])), np.cumsum(m, axis=0)], axis=0)
    return journals, journals[:-1] + 0.5 * m


@dataclass(frozen=True)
class MainJournalLoads:
    """Main-journal loads of an in-line engine, shape ``(n_cylinders + 1, n)`` [N].

    The force with which journal j presses on its bearing (the sum of half the loads of the two
    throws beside it, (43)), in the frame of crank 1 as Gots' (58) — ``x`` along T₁ (direction of
    rotation at crankpin 1), ``y`` along K₁ (from crankpin 1 toward the axis) — and in the
    cylinder block's frame: ``side`` along the cylinder frame's +x, ``down`` along the cylinder
    axis away from the head (the sense of P).

    Attributes
    ----------
    x, y : components in the frame of crank 1 [N].
    side, down : components in the block frame [N].
    gamma : angle of each crank ahead of crank 1 in the direction of rotation [rad], (n_cylinders,).
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
    """Main-journal loads by the tabular method (58) for symmetric throws (split beam).

    Throw i loads its two supports equally with R_k,i = R_i + K_rk + the counterweight's force
    (Gots (42), (43)): radial K_Σ = K + K_rш + K_rk + K_cw and tangential T_Σ = T + T_rш + T_rk +
    T_cw (the tangential d'Alembert terms only when ε ≠ 0).

    Parameters
    ----------
    mech : CrankSlider
        In-line engine; throws numbered from the nose like the cylinders.
    loads : CylinderLoads
        From :func:`crank_slider_loads` with the same ``omega``, ``epsilon``.
    omega, epsilon : array_like
        Speed [rad/s] and angular acceleration [rad/s²] of the samples (for the counterweights).
    counterweight_mass : float
        Counterweight mass per throw reduced to the crank radius [kg] (both webs together, placed
        symmetrically so the throw stays symmetric), 0 for none.
    counterweight_angle : float
        Its angle ahead of the crank in the direction of rotation [rad]; π: opposite the crank.
    """
    _check_inline(mech)
    firing = np.asarray(mech.firing_angles, dtype=np.float64)
    gamma = np.mod(firing[0] - firing, 2.0 * math.pi)
    k_cw, t_cw = rotating_inertia_force(counterweight_mass, mech.crank_radius, omega, epsilon,
                                        counterweight_angle)
    k_sum = loads.R_K + loads.K_crank + k_cw
    t_sum = loads.R_T + loads.T_crank + t_cw
    cg, sg = np.cos(gamma)[:, None], np.sin(gamma)[:, None]
    half_x = 0.5 * (t_sum * cg - k_sum * sg)  # (58), each throw's half
    half_y = 0.5 * (t_sum * sg + k_sum * cg)
    n = half_x.shape[1]
    z = np.zeros((1, n))
    x = np.concatenate([half_x, z]) + np.concatenate([z, half_x])
    y = np.concatenate([half_y, z]) + np.concatenate([z, half_y])
    a1 = loads.alpha[0][None, :]
    ca, sa = np.cos(a1), np.sin(a1)
    return MainJournalLoads(x=x, y=y, side=x * ca - y * sa, down=x * sa + y * ca, gamma=gamma)
