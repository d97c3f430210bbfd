"""What the load analyses of every mechanism share: the records' common fields, the gas force on
the pistons, the two-mass split of a rod and the d'Alembert force of a mass turning with the crank.

Conventions as the crank-slider's (:mod:`transient.analysis.loads.crank_slider`, Gots §2.3–§2.6):
piston forces are
positive in the sense the gas pushes (toward the crank, or toward the swash plate), inertia forces
are d'Alembert forces −m·a with the actual ω and ε, and arrays are ``(rows of the record, n
samples)``. Units SI (N, N·m, m, rad).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Array",
    "CrankpinLoads",
    "PistonLoads",
    "along_trajectory",
    "gas_force_array",
    "gas_force_from_pressure",
    "gas_forces",
    "rod_split",
    "rotating_inertia_force",
    "rotating_inertia_rows",
    "trajectory_arrays",
    "trajectory_gas_force",
    "two_mass_rod",
]

Array = NDArray[np.float64]


# ----------------------------------------------------------------------------------------
# Records
# ----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PistonLoads:
    """The forces every mechanism's record has, per cylinder, shape ``(n_cylinders, n)``.

    Attributes
    ----------
    v : piston speed [m/s], positive in the sense of P.
    P_g, P_j, P : gas force, reciprocating inertia force −m_j·a and their sum [N] (Gots (30),
        (33)), positive in the sense the gas pushes.
    S : rod force along the rod at the piston pin, compression positive [N] (Gots (35)).
    torque : the cylinder's torque on the shaft [N·m] (the crank-slider's T r (38)).
    area : piston area F_p [m²].
    """

    v: Array
    P_g: Array
    P_j: Array
    P: Array
    S: Array
    torque: Array
    area: float

    @property
    def engine_torque(self) -> Array:
        """Σ_k torque_k [N·m], shape (n,): the indicated engine torque (Gots §2.8, table П4.2)."""
        return self.torque.sum(axis=0)

    def specific(self, name: str) -> Array:
        """Force ``name`` per piston area [Pa] (Gots' specific forces; /1e6 for MPa)."""
        return getattr(self, name) / self.area


@dataclass(frozen=True)
class CrankpinLoads(PistonLoads):
    """A record of a mechanism with crankpins: the pistons' fields and each crankpin's load.

    Per cylinder, shape ``(n_cylinders, n)``: ``s`` travel toward the crank [m], ``beta`` rod
    lean [rad], ``N`` the wall's side force on the piston [N]. Per crankpin (one per cylinder on
    a crank-slider, one per row on an articulated engine), shape ``(n_crankpins, n)``: ``alpha``
    local crank angle [rad]; ``K``, ``T`` the rods' force on the crankpin toward the axis and in
    the direction of rotation (Gots (36)–(37)); ``K_rod``, ``T_rod`` the d'Alembert force of the
    rod mass at the crankpin (K_rш (32), T_rш); ``K_crank``, ``T_crank`` that of the throw's
    unbalanced mass (K_rk (28), T_rk); ``R_K``, ``R_T``, ``R`` the crankpin load K + K_rш,
    T + T_rш and its magnitude ((40)/(41) as vectors); ``throw_torque`` what the throw passes to
    the shaft [N·m]. ``r`` crank radius [m].
    """

    s: Array
    beta: Array
    N: Array
    alpha: Array
    K: Array
    T: Array
    K_rod: Array
    T_rod: Array
    K_crank: Array
    T_crank: Array
    R_K: Array
    R_T: Array
    R: Array
    throw_torque: Array
    r: float

    @property
    def psi(self) -> Array:
        """Angle of the crankpin load from the crank toward the axis, tan ψ = R_T/R_K (Gots §2.6)
        [rad], in (−π, π]."""
        return np.arctan2(self.R_T, self.R_K)


# ----------------------------------------------------------------------------------------
# Inputs
# ----------------------------------------------------------------------------------------

def trajectory_arrays(phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike
                      ) -> tuple[Array, Array, Array]:
    """φ [rad], ω [rad/s] and ε [rad/s²] as float arrays broadcast together, at least 1-D (a
    constant speed is a scalar ω and ε = 0)."""
    phi_b, omega_b, epsilon_b = np.broadcast_arrays(
        np.atleast_1d(np.asarray(phi, dtype=np.float64)),
        np.asarray(omega, dtype=np.float64), np.asarray(epsilon, dtype=np.float64))
    return phi_b, omega_b, epsilon_b


def gas_force_array(gas_force: ArrayLike | None, shape: tuple[int, int]) -> Array:
    """The gas force on each piston [N] as a writable array of ``shape``; 0 when omitted."""
    if gas_force is None:
        return np.zeros(shape)
    return np.broadcast_to(np.asarray(gas_force, dtype=np.float64), shape).copy()


def gas_force_from_pressure(mech, p: ArrayLike, p0: float) -> Array:
    """P_g = (p − p0)·F_p [N] (Gots (33)) from absolute cylinder pressures ``p`` [Pa]."""
    return (np.asarray(p, dtype=np.float64) - p0) * mech.piston_area


def gas_forces(scene, phi: ArrayLike, fuel: ArrayLike = 1.0) -> Array:
    """Gas force on each piston of a scene [N], shape ``(n_cylinders, n)``, from its gas tables.

    Cylinder k reads the table at φ − ``gas_phases(scene)[k]``; the pressure is
    p_mot + f·(p_full − p_mot) at the fuel command ``fuel`` (scalar or per sample), as the
    compiled model applies it (:class:`transient.scene.records.Gas`). A force-pulse model
    (``trapezoid``) gives the force directly.
    """
    # (lazily: the table builders import scipy)
    from ...scene.queries import gas_is_force, gas_phases, gas_tables

    mech = scene.mechanism
    phi = np.atleast_1d(np.asarray(phi, dtype=np.float64))
    full, motored = gas_tables(scene)
    shape = (mech.n_cylinders, phi.size)
    if full is None:
        return np.zeros(shape)
    x = phi[None, :] - gas_phases(scene)[:, None]
    value = full(x)
    f = np.asarray(fuel, dtype=np.float64)
    force = gas_is_force(scene)
    base = motored(x) if motored is not None else (0.0 if force else scene.gas.p0)
    value = base + f * (value - base)
    if force:
        return np.broadcast_to(value, shape).copy()
    return gas_force_from_pressure(mech, value, scene.gas.p0)


def trajectory_gas_force(scene, traj) -> Array | None:
    """Gas force on each piston [N], shape ``(n_cylinders, n)``, along a run's trajectory; None
    without gas. Any mechanism with ``n_cylinders`` and ``piston_area``.

    From the recorded ``p_<k>`` columns (the value applied at the governor's fuel; Pa, or N for a
    force model) when present, else from the scene's tables at the recorded ``fuel`` (1 if
    absent). A prescribed-speed run with ``fuel`` ≠ 1 (:func:`transient.run.prescribed`)
    scales the force without recording it in ``p_<k>``, so its loads are those at full fuel.
    """
    from ...scene.queries import gas_is_force

    mech = scene.mechanism
    names = [f"p_{k + 1}" for k in range(mech.n_cylinders)]
    if scene.gas.model == "none":
        return None
    if all(n in traj for n in names):
        value = np.vstack([np.asarray(traj[n], dtype=np.float64) for n in names])
        return value if gas_is_force(scene) else gas_force_from_pressure(mech, value,
                                                                         scene.gas.p0)
    return gas_forces(scene, np.asarray(traj["phi"], dtype=np.float64), traj.get("fuel", 1.0))


def along_trajectory(loads: Callable, scene, traj):
    """``loads(mechanism, phi, omega, epsilon, gas_force)`` along a run's trajectory (``phi``,
    ``omega``, ``epsilon``), the gas force from :func:`trajectory_gas_force`."""
    return loads(scene.mechanism, np.asarray(traj["phi"], dtype=np.float64), traj["omega"],
                 traj["epsilon"], trajectory_gas_force(scene, traj))


# ----------------------------------------------------------------------------------------
# Masses
# ----------------------------------------------------------------------------------------

def two_mass_rod(mass, length, cg_from_pin, inertia_cg, model: str):
    """``(m1, m2, dI)`` of a rod (scalars or arrays): its mass at the piston pin and at the big
    end [kg] (Gots (20): m₁ = m(l − l₁)/l, m₂ = m l₁/l) and the inertia the two masses miss,
    ΔI = I_G − m l₁(l − l₁) [kg m²] — 0 for ``model = "two-mass"``, whose rod has no other
    inertia; ΔI enters the loads as the couple −ΔI·(rod's angular acceleration)."""
    m1 = mass * (length - cg_from_pin) / length
    m2 = mass * cg_from_pin / length
    d_inertia = (0.0 * length if model == "two-mass"
                 else inertia_cg - mass * cg_from_pin * (length - cg_from_pin))
    return m1, m2, d_inertia


def rod_split(mech) -> tuple[float, float, float]:
    """:func:`two_mass_rod` of a mechanism's rod (``rod_mass``, ``rod_length``,
    ``rod_cg_from_pin``, ``rod_inertia_cg``, ``rod_model``: a crank-slider, an articulated
    engine's master rod, a swash plate's rods)."""
    return two_mass_rod(mech.rod_mass, mech.rod_length, mech.rod_cg_from_pin,
                        mech.rod_inertia_cg, mech.rod_model)


def rotating_inertia_force(mass: float, radius: float, omega: ArrayLike, epsilon: ArrayLike,
                           angle: float = 0.0) -> tuple[Array, Array]:
    """d'Alembert force of a point mass turning with the crank, in the crank's (K, T) components.

    The mass sits at ``radius`` on a ray ``angle`` [rad] ahead of the crank in the direction of
    rotation (0: on the crank, π: a counterweight opposite it). Position ρ = radius·(cos δ ĉ +
    sin δ t̂), acceleration −ω² ρ + ε dρ/dα, so the force −m·acceleration has

    K = −m radius (ω² cos δ + ε sin δ)   (positive toward the axis along the crank),
    T = m radius (ω² sin δ − ε cos δ)    (positive in the direction of rotation).

    At δ = 0: K = −m r ω² (Gots (32), K_rш, K_rk) and T = −m r ε.
    """
    w2 = np.square(np.asarray(omega, dtype=np.float64))
    eps = np.asarray(epsilon, dtype=np.float64)
    c, s = math.cos(angle), math.sin(angle)
    return -mass * radius * (w2 * c + eps * s), mass * radius * (w2 * s - eps * c)


def rotating_inertia_rows(mass: float, radius: float, omega: ArrayLike, epsilon: ArrayLike,
                          shape: tuple[int, int]) -> tuple[Array, Array]:
    """:func:`rotating_inertia_force` of a mass on the crank (δ = 0), the same on every row of a
    record: (K, T) as writable arrays of ``shape``."""
    k, t = rotating_inertia_force(mass, radius, omega, epsilon)
    return np.broadcast_to(k, shape).copy(), np.broadcast_to(t, shape).copy()


def stored_record(ld, grid, forces) -> dict[str, tuple[Any, str]]:
    """What every mechanism stores: the grid, the forces named [N], the cylinders' torques and
    the engine torque [N m]."""
    out: dict[str, tuple[Any, str]] = {"loads_phi": (grid, "rad")}
    for name in forces:
        out[f"loads_{name}"] = (getattr(ld, name), "N")
    out["loads_torque"] = (ld.torque, "N m")
    out["loads_engine_torque"] = (ld.engine_torque, "N m")
    return out
