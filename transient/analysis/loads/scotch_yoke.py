"""Forces in a Scotch-yoke engine along a trajectory φ(t), ω(t), ε(t), in closed form: the
piston's, the slot's on the crankpin, and the torque on the shaft.

The mechanism of :mod:`transient.mechanisms.scotch_yoke`: the piston's travel from its top dead
centre is s = r (1 − cos α) at the crank angle α, so, with the signs of
:mod:`transient.analysis.loads.crank_slider` (P toward the crank, K toward the shaft axis along
the crank, T in the direction of rotation):

* **Piston force** P = P_g + P_j, P_j = −m (s″ ω² + s′ ε) = −m r (ω² cos α + ε sin α), m the yoke
  with its piston: at constant ω a pure first order, −m r ω² cos α.
* **The slot's force on the slider block** is along the cylinder axis (the slot is across it and
  the yoke has no other guide that the block loads), and equals P: ``S`` = P. On the crankpin its
  components are K = P cos α, T = P sin α (the rod-less Gots (36)–(37), β = 0).
* **Crankpin load** R = (K + K_b, T + T_b) with the block's d'Alembert force K_b = −m_b r ω²,
  T_b = −m_b r ε (:func:`~.common.rotating_inertia_force`); |R| its magnitude.
* **Torque** of the cylinder on the shaft: T r = P r sin α = P s′ — the generalized force of (19).

There is no rod (``S`` is the force across the slot, not a rod force), no side force on the
piston (the yoke is guided) and one crankpin; the main journals are not resolved.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ...mechanisms.scotch_yoke import ScotchYoke
from .common import (
    Array,
    PistonLoads,
    along_trajectory,
    gas_force_array,
    rotating_inertia_force,
    stored_record,
    trajectory_arrays,
)


@dataclass(frozen=True)
class ScotchYokeLoads(PistonLoads):
    """The forces of :func:`scotch_yoke_loads` (module docstring), shape ``(1, n)``: ``s`` the
    piston's travel [m], ``K``, ``T`` the slot's force on the crankpin, ``K_block``, ``T_block``
    the slider block's d'Alembert force, ``R_K``, ``R_T``, ``R`` the crankpin load [N]; ``r``
    the crank radius [m]."""

    s: Array
    K: Array
    T: Array
    K_block: Array
    T_block: Array
    R_K: Array
    R_T: Array
    R: Array
    r: float


def scotch_yoke_loads(mech: ScotchYoke, phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike,
                      gas_force: ArrayLike | None = None) -> ScotchYokeLoads:
    """The loads at shaft angles ``phi`` [rad], speeds ``omega`` [rad/s] and accelerations
    ``epsilon`` [rad/s²] (broadcast together), ``gas_force`` on the piston [N] (0 if None)."""
    phi, w, eps = trajectory_arrays(phi, omega, epsilon)
    r, m = mech.crank_radius, mech.yoke_mass
    alpha = phi - mech.firing_angles[0]
    ca, sa = np.cos(alpha), np.sin(alpha)
    P_g = gas_force_array(gas_force, (1, phi.size))
    P_j = -m * r * (w * w * ca + eps * sa)[None, :]
    P = P_g + P_j
    K, T = P * ca, P * sa
    k_b, t_b = rotating_inertia_force(mech.block_mass, r, w, eps)
    K_block, T_block = np.broadcast_to(k_b, K.shape).copy(), np.broadcast_to(t_b, T.shape).copy()
    R_K, R_T = K + K_block, T + T_block
    return ScotchYokeLoads(v=(r * sa * w)[None, :], P_g=P_g, P_j=P_j, P=P, S=P.copy(),
                           torque=T * r, area=mech.piston_area,
                           s=mech.travel(alpha)[None, :], K=K, T=T, K_block=K_block,
                           T_block=T_block, R_K=R_K, R_T=R_T, R=np.hypot(R_K, R_T), r=r)


def piston_travel(mech: ScotchYoke, phi):
    """``transient.analysis.pistons.KINEMATICS`` of the yoke: s, s′, s″ (1, m), the piston
    area and the stroke 2r."""
    alpha = np.asarray(phi, dtype=np.float64) - mech.firing_angles[0]
    r = mech.crank_radius
    return (mech.travel(alpha)[None, :], (r * np.sin(alpha))[None, :],
            (r * np.cos(alpha))[None, :], np.array([mech.piston_area]),
            np.array([2.0 * r]))


def stored_loads(scene, grid, traj) -> dict:
    """``transient.analysis.requested.LOADS`` of the yoke: the piston's forces, the crankpin
    load and its largest magnitude, the torques."""
    ld = along_trajectory(scotch_yoke_loads, scene, traj)
    out = stored_record(ld, grid, ("P_g", "P_j", "P", "K", "T", "R_K", "R_T", "R"))
    out["loads_crankpin_R_max"] = (ld.R.max(axis=1), "N")
    return out
