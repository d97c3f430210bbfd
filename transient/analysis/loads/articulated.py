"""Forces in a master-and-articulated-rod engine (radial; V with fork-and-blade rods) along a
trajectory φ(t), ω(t), ε(t): pistons, rods, link pins and the master crankpin.

The crank-slider counterpart is
:mod:`transient.analysis.loads.crank_slider` (Gots §2.3–§2.6); its conventions are
kept, and what differs is that the master rod carries the slave rods' link pins, so it is not a
two-force member. The kinematics are the mechanism's own exact ones
(:mod:`transient.core.model.articulated`, Semenov (8), (31), (40)–(41) solved exactly), evaluated by the
compiled kernels sample by sample; Semenov's text is pure kinematics at constant ω (Semenov §1,
(17) and p. 22): the forces below follow from d'Alembert's principle on that geometry with the
actual ω and ε.

Frame and signs
---------------
One row, as :mod:`transient.core.model.articulated`: origin O on the crank axis, ``x`` along the master
cylinder toward its piston, ``y`` a quarter-turn on in the direction of rotation; 2-D vectors are
complex numbers x + iy here. Local crank angle α = φ − the row's phase; crankpin A = r e^{iα},
unit vectors ĉ = e^{iα} (crank, outward) and t̂ = i e^{iα} (direction of rotation). Cylinder k of
the row has the outward axis d_k = e^{iδ_k} (δ_0 = 0 for the master) and the side m_k = i d_k
(the side toward which the crankpin moves at its top: the crank-slider's ``x``).

* **Piston force** (positive toward the crank axis, Gots §2.3–2.4): with s_k the travel toward the
  crank (the kernel's u_k = s_k′, u_k′ = s_k″), P_j = −m_j (s″ω² + s′ε), P = P_g + P_j. The
  reciprocating mass m_j is the piston plus the piston-pin share of its rod (the two-mass split of
  Gots (20): m(l − c)/l, c the rod's centre of mass from the piston pin).
* **Rod lean** β_k (the crank-slider's sign: > 0 when the rod leans from the pin toward m_k): the
  master's sin β = λ sin α (Semenov (31)); a slave's is −β_i of Semenov (40)–(41),
  sin β_k = h/l_i with h the link pin's offset from the slave axis. The rod direction from the
  piston pin to its big end is û = sin β m − cos β d.
* **Piston pin.** The piston's balance along d and m with the wall force N m gives the force the
  piston pushes its rod with, Φ = −P d + N m, and

  N = P tan β + H,   H = −C/(l cos β)   (Gots (34) plus the couple's share),

  where C is the moment (in the sense of rotation, about the big end) that the rest of the rod
  system puts on the rod besides the pin force. S = Φ·û = P/cos β + H sin β is the rod force along
  the rod at the pin, compression positive (Gots (35) when H = 0).
* **Slave rod** i: the two-mass split puts m₂ = m c/l_i at the link pin A_i, whose d'Alembert
  force −m₂ (A_i″ω² + A_i′ε) acts on the master rod there; what a rigid rod has beyond the two
  masses, ΔI = I_G − m c (l_i − c), is the couple C = −ΔI β̈_i (rotation sense, the rod turning by
  β̈_i = β_i″ω² + β_i′ε in the kernel's sign). The **link-pin load** — the force the slave rod
  (with its link-pin mass) puts on the master rod at A_i — is F_i = Φ_i − m₂ (A_i″ω² + A_i′ε).
* **Master rod**: the two-mass split again (m₁ at the pin into the master's P, m₂ at the crankpin
  as the crank-slider's K_rш, T_rш) and the couple ΔI β̈ of a rigid master rod (rotation sense:
  the rod's axis turns by −β). Its moment about the crankpin A gives the master's H with
  C = ΔI β̈ + Σ_i (A_i − A) × F_i: the link pins make the master's side force differ from P tan β
  even with massless rods. The rod system's force on the crankpin is Φ_0 + Σ_i F_i, with
  components K (toward the crank axis) and T (direction of rotation), Gots (36)–(37) generalised.
* **Crankpin load** of the row, a vector as in
  :mod:`~transient.analysis.loads.crank_slider`: R_K = K + K_rш,
  R_T = T + T_rш with the master rod's rotating mass, K_rш = −m₂ r ω², T_rш = −m₂ r ε (Gots (32)
  and its ε term); the crank throw's m_k gives K_rk, T_rk the same way (the row's
  ``crank_mass``).

Virtual work (the independent checks, ``tests/unit/test_loads_radial_swash.py``)
--------------------------------------------------------------------------------
* Row by row: T r ω = Σ_k P_k ṡ_k + W_links, where W_links = Σ_i (−m₂ a_Ai)·Ȧ_i − ΔI_i β̈_i β̇_i
  − ΔI β̈ β̇ is the power of the d'Alembert forces not lumped into the pistons or the crankpin
  (:attr:`ArticulatedLoads.link_power`). With two-mass slave rods of no link-pin mass and a two-mass
  master rod, W_links = 0 and T r ω = Σ P_k ṡ_k exactly as for the crank-slider.
* Whole engine, against the kernel's reduced inertia (Antonyuk (18)–(21)):
  Σ_rows r (R_T + T_rk) = Σ_k P_g,k u_k − J ε − ½ J′ ω², with J, J′ of
  :func:`transient.core.model.articulated.articulated_terms` — every inertia force above is checked
  against the kinetic energy the simulation integrates.
* The cylinder's share of the shaft torque is P_k u_k
  (:attr:`~transient.analysis.loads.common.PistonLoads.torque`): the
  slaves do not act on the crankpin directly, so the crank-slider's per-cylinder T r has no
  counterpart; Σ_k P_k u_k = T r − W_links/ω.

What does not apply
-------------------
The main-journal tabular method (58) and the running torques of Gots §2.8 assume one throw per
cylinder along an in-line shaft; a radial row puts all its cylinders on one crankpin, and the
journals of a multi-row shaft are not modelled (no axial positions). They are not computed here.
The crankpin polar diagram applies (one crankpin per row, :func:`transient.plots.crankpin_polar`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...core.model import articulated as core
from ...mechanisms.articulated import Articulated, positions
from .common import (
    Array,
    CrankpinLoads,
    along_trajectory,
    gas_force_array,
    rod_split,
    rotating_inertia_rows,
    trajectory_arrays,
    two_mass_rod,
)
from .crank_slider import slider_arrays

__all__ = [
    "ArticulatedLoads",
    "RowKinematics",
    "articulated_loads",
    "articulated_loads_from_trajectory",
    "pin_forces",
    "row_kinematics",
]


@dataclass(frozen=True)
class RowKinematics:
    """Exact kinematics of one row at local angles α (n,), derivatives in α.

    Pistons (1 + z′, n), the master first: ``s``, ``ds``, ``dds`` travel toward the crank,
    s = l + r − X with X the pin's distance from O along its axis [m], and its derivatives
    [m/rad, m/rad²] (ds is the kernel's u_k);
    ``beta``, ``dbeta``, ``ddbeta`` the rod lean in the crank-slider's sign and its derivatives.
    Link pins (z′, n), complex (row frame): ``A_link``, ``dA_link``, ``ddA_link`` [m, m/rad,
    m/rad²]. ``A`` the crankpin (n,), ``axis`` the outward cylinder axes d_k (1 + z′,) complex.
    """

    alpha: Array
    s: Array
    ds: Array
    dds: Array
    beta: Array
    dbeta: Array
    ddbeta: Array
    A: NDArray[np.complex128]
    A_link: NDArray[np.complex128]
    dA_link: NDArray[np.complex128]
    ddA_link: NDArray[np.complex128]
    axis: NDArray[np.complex128]


def row_kinematics(mech: Articulated, alpha: ArrayLike) -> RowKinematics:
    """:class:`RowKinematics` at the local angles ``alpha`` [rad].

    The master comes from :func:`.crank_slider.slider_arrays` (Semenov (31), exact); the
    slaves' derivatives from the compiled :func:`transient.core.model.articulated.slave`, one sample at a
    time (cheap enough: analyses run once per result), and their positions from the plain-numpy
    :func:`transient.mechanisms.articulated.positions`.
    """
    alpha = np.atleast_1d(np.asarray(alpha, dtype=np.float64))
    r, l, ns = mech.crank_radius, mech.rod_length, mech.n_slaves
    mp = mech.pack()
    s0, ds0, dds0, b0, db0, ddb0 = slider_arrays(alpha, r, l)
    shape = (1 + ns, alpha.size)
    ds, dds = np.empty(shape), np.empty(shape)
    beta, dbeta, ddbeta = np.empty(shape), np.empty(shape), np.empty(shape)
    ds[0], dds[0], beta[0], dbeta[0], ddbeta[0] = ds0, dds0, b0, db0, ddb0
    dA = np.empty((ns, alpha.size), dtype=np.complex128)
    ddA = np.empty_like(dA)
    for j, a in enumerate(alpha):
        ca, sa, cb, sb, db, ddb = core.master_rod(a, r, l)
        for i in range(ns):
            _, x1, x2, a1x, a1y, a2x, a2y, t1, t2 = core.slave(mp, i, r, ca, sa, cb, sb, db, ddb)
            ds[1 + i, j], dds[1 + i, j] = -x1, -x2  # s toward the crank: −X (the kernel's u_k)
            dbeta[1 + i, j], ddbeta[1 + i, j] = -t1, -t2  # crank-slider sign: −β_i of (40)
            dA[i, j], ddA[i, j] = complex(a1x, a1y), complex(a2x, a2y)
    pos = positions(mech, alpha)
    axis = np.exp(1j * np.asarray((0.0,) + tuple(mech.slave_banks)))
    # h: the link pin's offset from its slave axis, toward m = i d; sin β = h/l_i.
    h = (pos["Ai"] / axis[None, 1:]).imag.T
    beta[1:] = np.arcsin(h / np.asarray(mech.slave_lengths)[:, None])
    s = np.empty(shape)
    s[0] = s0
    s[1:] = r + l - (pos["Bi"] / axis[None, 1:]).real.T
    # The points are complex (x + iy) though positions() annotates its dict as float.
    crankpin = np.asarray(pos["A"], dtype=np.complex128)
    link_pins = np.asarray(pos["Ai"].T, dtype=np.complex128)
    return RowKinematics(alpha=alpha, s=s, ds=ds, dds=dds, beta=beta, dbeta=dbeta, ddbeta=ddbeta,
                         A=crankpin, A_link=link_pins, dA_link=dA, ddA_link=ddA, axis=axis)


def pin_forces(P: ArrayLike, beta: ArrayLike, couple: ArrayLike, length: float
               ) -> tuple[Array, Array]:
    """Side force N and rod force S of a piston on a rod leaning by β (module docstring).

    ``P`` piston force toward the crank [N], ``couple`` the moment the rest of the rod system puts
    on the rod about its big end, in the sense of rotation [N m], ``length`` the rod [m]. Returns
    ``(N, S)``: N = P tan β + H, S = P/cos β + H sin β, H = −C/(l cos β).
    """
    p, b = np.asarray(P, dtype=np.float64), np.asarray(beta, dtype=np.float64)
    cb = np.cos(b)
    h = -np.asarray(couple, dtype=np.float64) / (length * cb)
    return p * np.tan(b) + h, p / cb + h * np.sin(b)


def _cross(a, b):
    """a × b of complex 2-D vectors (> 0 in the sense of rotation, x toward y)."""
    return (np.conj(a) * b).imag


def _dot(a, b):
    return (np.conj(a) * b).real


@dataclass(frozen=True)
class ArticulatedLoads(CrankpinLoads):
    """Forces of every cylinder, link pin and crankpin along a trajectory (module docstring).

    A :class:`~.common.CrankpinLoads` with one crankpin per row. Cylinders k = j(1 + z′) + i
    (row j, i = 0 the master), shape ``(n_cylinders, n)``: ``s``, ``v`` travel toward the crank
    [m] and its rate ds/dt [m/s]; ``u`` = ds/dφ [m/rad]; ``beta`` rod lean [rad]; ``P_g``,
    ``P_j``, ``P`` gas, inertia and total piston force toward the crank [N]; ``N`` the wall's
    force on the piston along m (the side toward which the crank turns at the top) [N]; ``S`` rod
    force along the rod at the pin, compression > 0 [N]; ``torque`` the cylinder's share P u
    [N m].

    Link pins, slave i of row j at index j z′ + i, shape ``(rows·z′, n)``: ``link_x``, ``link_y``
    the load F_i on the master rod at the link pin in the row frame [N]; ``link_axial``,
    ``link_normal`` the same along the master rod (from the crankpin toward the master piston pin)
    and across it (a quarter-turn on in the sense of rotation) [N].

    Rows (crankpins), shape ``(rows, n)``: ``alpha`` local crank angle [rad]; ``K``, ``T`` the rod
    system's force on the crankpin, toward the axis and in the direction of rotation [N];
    ``K_rod``, ``T_rod`` the master rod's rotating mass (K_rш, T_rш); ``K_crank``, ``T_crank`` the
    throw's (K_rk, T_rk); ``R_K``, ``R_T``, ``R`` the crankpin load; ``link_power`` W_links [W];
    ``throw_torque`` r (R_T + T_rk), what the row passes to the shaft [N m].
    """

    u: Array
    link_x: Array
    link_y: Array
    link_axial: Array
    link_normal: Array
    link_power: Array

    @property
    def engine_torque(self) -> Array:
        """Σ_rows T r [N m], shape (n,): the crank-slider's indicated torque Σ T r generalised
        (Σ P u, the sum of
        :attr:`~transient.analysis.loads.common.PistonLoads.torque`, leaves out the link pins'
        power)."""
        return self.T.sum(axis=0) * self.r

    @property
    def link_R(self) -> Array:
        """|F_i| of every link pin [N]."""
        return np.hypot(self.link_x, self.link_y)


def _slave_masses(mech: Articulated) -> tuple[Array, Array, Array]:
    """(m₁, m₂, ΔI) of every slave rod: its masses at the piston pin and at the link pin and the
    inertia beyond them (:func:`~.common.two_mass_rod`)."""
    return two_mass_rod(mech.slave_rod_mass, np.asarray(mech.slave_lengths, dtype=np.float64),
                        mech.slave_rod_cg_from_pin, mech.slave_rod_inertia_cg,
                        mech.slave_rod_model)


def _slave_loads(kin: RowKinematics, i: int, p: Array, length: float, m2: float,
                 d_inertia: float, omega: Array, eps: Array):
    """Slave i of a row: ``(N, S, F, power)`` — its piston's side and rod forces, the link-pin load
    F on the master rod (complex, row frame) and the power of its rod's d'Alembert forces at the
    link pin (W_links' share), for the piston force ``p`` (module docstring)."""
    k = 1 + i
    acc = kin.ddbeta[k] * omega**2 + kin.dbeta[k] * eps
    # The slave rod, like the master, turns by −β in the sense of rotation: couple −ΔI·(−β̈).
    N, S = pin_forces(p, kin.beta[k], d_inertia * acc, length)
    d = kin.axis[k]
    inertia = -m2 * (kin.ddA_link[i] * omega**2 + kin.dA_link[i] * eps)
    power = _dot(inertia, kin.dA_link[i] * omega) - d_inertia * acc * kin.dbeta[k] * omega
    return N, S, -p * d + 1j * d * N + inertia, power


def articulated_loads(mech: Articulated, phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike,
                      gas_force: ArrayLike | None = None) -> ArticulatedLoads:
    """Piston, rod, link-pin and crankpin forces of an articulated engine.

    Parameters
    ----------
    mech : transient.mechanisms.articulated.Articulated
    phi, omega, epsilon : array_like, shape (n,) or scalars
        Shaft angle [rad], speed [rad/s], angular acceleration [rad/s²], broadcast together.
    gas_force : array_like, shape (n_cylinders, n) or broadcastable, optional
        Gas force on each piston toward the crank [N] (:func:`~.common.trajectory_gas_force`); 0
        if omitted.
    """
    phi, omega, epsilon = trajectory_arrays(phi, omega, epsilon)
    n, ns, rows = phi.size, mech.n_slaves, mech.rows
    ncyl = mech.n_cylinders
    w2, eps = omega * omega, epsilon
    r, l = mech.crank_radius, mech.rod_length
    p_g = gas_force_array(gas_force, (ncyl, n))
    m1, m2, d_inertia = rod_split(mech.master())
    m1s, m2s, dIs = _slave_masses(mech)
    m_j = mech.piston_mass + np.concatenate(([m1], m1s))[:, None]
    cyl = {name: np.empty((ncyl, n)) for name in ("s", "u", "v", "beta", "P_j", "N", "S")}
    link = {name: np.empty((rows * ns, n)) for name in ("x", "y", "axial", "normal")}
    row = {name: np.empty((rows, n)) for name in ("alpha", "K", "T", "link_power")}
    for j, phase in enumerate(mech.row_phases):
        kin = row_kinematics(mech, phi - phase)
        c0 = j * (1 + ns)
        sl = slice(c0, c0 + 1 + ns)
        p_j = -m_j * (kin.dds * w2 + kin.ds * eps)
        p = p_g[sl] + p_j
        acc_m = kin.ddbeta[0] * w2 + kin.dbeta[0] * eps  # β̈ of the master rod
        # Slaves first: each one's link-pin load enters the master rod's moment balance.
        pin = r * np.cos(kin.alpha) + l * np.cos(kin.beta[0])  # master piston pin B (on x)
        ax = (pin - kin.A) / l  # along the master rod, crankpin → piston pin (the kernel's e)
        couple_m = d_inertia * acc_m  # rigid master rod: −ΔI·(−β̈) in the sense of rotation
        load_sum = np.zeros(n, dtype=np.complex128)
        power = -d_inertia * acc_m * kin.dbeta[0] * omega
        for i in range(ns):
            N, S, F, p_i = _slave_loads(kin, i, p[1 + i], mech.slave_lengths[i], m2s[i], dIs[i],
                                        omega, eps)
            cyl["N"][c0 + 1 + i], cyl["S"][c0 + 1 + i] = N, S
            load_sum += F
            couple_m = couple_m + _cross(kin.A_link[i] - kin.A, F)
            power += p_i
            link["x"][j * ns + i], link["y"][j * ns + i] = F.real, F.imag
            link["axial"][j * ns + i], link["normal"][j * ns + i] = _dot(ax, F), _dot(1j * ax, F)
        N0, S0 = pin_forces(p[0], kin.beta[0], couple_m, l)
        cyl["N"][c0], cyl["S"][c0] = N0, S0
        F0 = -p[0] + 1j * N0 + load_sum  # the rod system's force on the crankpin
        c_hat = np.exp(1j * kin.alpha)
        row["alpha"][j] = kin.alpha
        row["K"][j] = -_dot(c_hat, F0)
        row["T"][j] = _dot(1j * c_hat, F0)
        row["link_power"][j] = power
        cyl["s"][sl], cyl["u"][sl], cyl["v"][sl] = kin.s, kin.ds, kin.ds * omega
        cyl["beta"][sl], cyl["P_j"][sl] = kin.beta, p_j
    k_rod, t_rod = rotating_inertia_rows(m2, r, omega, epsilon, (rows, n))
    k_crank, t_crank = rotating_inertia_rows(mech.crank_mass, r, omega, epsilon, (rows, n))
    r_k, r_t = row["K"] + k_rod, row["T"] + t_rod
    P = p_g + cyl["P_j"]
    return ArticulatedLoads(
        s=cyl["s"], v=cyl["v"], u=cyl["u"], beta=cyl["beta"], P_g=p_g, P_j=cyl["P_j"], P=P,
        N=cyl["N"], S=cyl["S"], torque=P * cyl["u"], link_x=link["x"], link_y=link["y"],
        link_axial=link["axial"], link_normal=link["normal"], alpha=row["alpha"], K=row["K"],
        T=row["T"], K_rod=k_rod, T_rod=t_rod, K_crank=k_crank, T_crank=t_crank, R_K=r_k, R_T=r_t,
        R=np.hypot(r_k, r_t), link_power=row["link_power"], throw_torque=(r_t + t_crank) * r,
        r=r, area=mech.piston_area)


def articulated_loads_from_trajectory(scene, traj) -> ArticulatedLoads:
    """:func:`articulated_loads` along a run's trajectory (``phi``, ``omega``, ``epsilon`` and the
    gas force of :func:`~.common.trajectory_gas_force`)."""
    return along_trajectory(articulated_loads, scene, traj)

