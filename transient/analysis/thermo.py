"""The run's own thermodynamics, cylinder by cylinder and cycle by cycle: the indicated work and
mean effective pressure from the pressure the run applied, the brake and friction mean effective
pressures from the shaft's work integrals, the peak pressures, and for the combustion models the
apparent heat-release rate and the burned-mass-fraction angles.

**Cycles.** The engine's figures are taken over its cycles, counted from φ0 as
:mod:`.irregularity` counts them; each cylinder's over its own cycles, from its own local angle
0 (a 4-stroke's gas-exchange TDC) or π (a 2-stroke's BDC), where ``[[gas.cylinders]]`` begins
its cycles too (:func:`transient.scene.queries.cycle_begin`), so that a misfire's cycle is one of
its cycles and not two halves. Column j of a cylinder's figures is its cycle that ends in
engine cycle j, its cycle j + 1 as ``[[gas.cylinders]]`` counts them; NaN where that cycle
began before the run (or before its last backward motion), ``thermo_cylinder_cycle_start`` its
first angle.

**Indicated work.** W_i,k = ∮ p_k dV_k over a whole cycle, evaluated as
∫ p_k(φ) V′_k(φ) dφ with the stored pressure
``p_<k>`` and the exact volume V_k(φ) = V_c + A_k·s_k(φ) of the mechanism (s_k the piston's travel
from its top dead centre, A_k the area its pressure acts on: F_p, twice that for the opposed
pistons of a two-half swash plate). The quadrature is interpolatory of degree
:data:`QUAD_DEGREE` on the stored samples, piece by piece between the corners of the cylinder's
pressure curve (a jump written as two samples at one angle splits it too), so that nothing is
interpolated across a corner. A pressure table is a C² cubic between its knots, across which any
rule converges as h⁴ only, so the cylinders' work meets the gas torque's to what the output
spacing allows (the bounds per spacing: tests/validation/test_thermo_runs.py).
IMEP_k = W_i,k/V_d,k over the cylinder's own cycle, V_d,k its exact swept volume; the
engine's IMEP is ΣW_i,k/ΣV_d,k with every W_i,k over the engine's cycle.

**Brake and friction.** From the work integrals the stepper integrates with the motion
(``W_load``, ``W_loss_<k>``, ``W_gas``: :mod:`transient.core.model.layout`), read at the cycle ends:
BMEP = −ΔW_load/ΣV_d (the work the load takes), FMEP = ΣΔW_loss,k/ΣV_d (the pairs' losses), and
the indicated work of the gas torque ΔW_gas = Σ∮(p_k − p0) dV_k = ΣW_i,k (∮dV = 0). Over a cycle
the work–energy law gives

    IMEP − BMEP − FMEP = (ΔK − ΔW_starter − ΔW_drive)/ΣV_d,            K = ½J(φ)ω²,

zero in steady state without starter and prescribed drive; ``thermo_balance_residual`` is what is
left of it per cycle, relative to ΣW_i,k (solver tolerance plus the quadrature's error). Powers
are the works over the cycle time.

**Peak pressure.** The largest stored sample of each cylinder in each of its own cycles and its
local angle there, in [0, Φ) as its gas table counts it (the output spacing is its resolution);
``thermo_last_p_max`` is the largest of every cylinder's samples in the last engine cycle.

**Heat release** (``wiebe``; with ``[gas.woschni]`` the apparent, net of the wall heat): the
single-zone first law with constant γ (Heywood, *Internal Combustion Engine Fundamentals*, 1988,
eq. (9.25)), dQ/dφ = γ/(γ − 1)·p·dV/dφ + 1/(γ − 1)·V·dp/dφ, over the closed part of the cycle
(intake closing to exhaust opening), dp/dφ from a not-a-knot spline of the samples; the burned
fraction is Q over its value at exhaust opening, and MFB10/50/90 are the local angles where it
reaches 10, 50, 90 %. For a Wiebe cycle without wall heat and with constant γ this is the Wiebe
law itself, x_b = 1 − exp(−a((θ − θ_s)/Δθ)^(m+1)) (Heywood eq. (9.31)), so the angles can be
checked against θ_s + Δθ·(−ln(1 − x)/a)^(1/(m+1)).

Stored names (n cylinders, C whole engine cycles): ``thermo_cycle_start`` (C,) [rad],
``thermo_cycle_omega_mean`` (C,) [rad/s], ``thermo_cylinder_cycle_start`` (n, C) [rad],
``thermo_swept_volume`` (n,) [m^3],
``thermo_W_indicated`` (n, C) [J], ``thermo_imep`` (n, C) [Pa], ``thermo_P_indicated`` (n, C)
[W], ``thermo_p_max`` (n, C) [Pa], ``thermo_p_max_angle`` (n, C) [rad]; engine:
``thermo_imep_engine``, ``thermo_bmep``, ``thermo_fmep`` (C,) [Pa],
``thermo_P_indicated_engine``, ``thermo_P_brake``, ``thermo_P_friction`` (C,) [W],
``thermo_W_gas``, ``thermo_W_load``, ``thermo_W_loss``, ``thermo_dK`` (C,) [J],
``thermo_balance_residual`` (C,) [1]; with heat release ``thermo_Q`` (n, C) [J],
``thermo_mfb10``, ``thermo_mfb50``, ``thermo_mfb90`` (n, C) [rad]; and the last cycle's engine
figures and residual as scalars ``thermo_last_*`` for the run's summary.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .irregularity import NoWholeCycle
from .orders import _increasing_part, cycle_marks, resample_angle
from .pistons import piston_kinematics

#: Degree of the interpolatory quadrature of the stored samples (error O(h^(d+1)) per interval).
QUAD_DEGREE = 6

#: Events at which the fuel command, and so the pressure applied, may turn or jump: the
#: governor's saturation and its sleeve's stops, an injection latching a new fuel, and the
#: steps of the load or starter, where ε jumps and a speed-dependent fuel turns.
FUEL_CORNERS = ("governor_corner", "sleeve_stop", "sleeve_free", "injection", "load_schedule",
                "starter_cutout", "generator_min_speed")

#: Burned fractions whose angles are reported.
MFB_LEVELS = (0.1, 0.5, 0.9)


# ------------------------------------------------------------------------------------------------
# Cylinder volumes


def clearance(scene) -> float:
    """V_c [m³] of the scene's cycle model (:func:`transient.scene.queries.clearance_volume`), else 0:
    a gas table gives no clearance, and V is then the swept part A·s only (the indicated work
    does not depend on it)."""
    from ..scene.queries import clearance_volume

    return clearance_volume(scene)


@dataclass(frozen=True)
class Volumes:
    """Every cylinder's volume over the shaft angles asked for.

    Attributes
    ----------
    V, dV : (n, m) arrays
        V_k(φ) [m³] and dV_k/dφ [m³/rad].
    swept : (n,) array
        V_d,k, the exact swept volume of each cylinder [m³].
    clearance : float
        V_c [m³] (0 where the scene's gas model gives no compression ratio).
    """

    V: NDArray[np.float64]
    dV: NDArray[np.float64]
    swept: NDArray[np.float64]
    clearance: float


def cylinder_volumes(scene, phi: ArrayLike) -> Volumes:
    """V_k(φ) = V_c + A_k s_k(φ) and dV_k/dφ of every cylinder at the shaft angles ``phi`` [rad].

    Raises ValueError for a mechanism without piston kinematics (:mod:`.pistons`)."""
    pk = piston_kinematics(scene.mechanism, phi)
    vc = clearance(scene)
    return Volumes(vc + pk.area[:, None] * pk.s, pk.area[:, None] * pk.ds, pk.area * pk.stroke,
                   vc)


# ------------------------------------------------------------------------------------------------
# Quadrature of stored samples


def _interval_integrals(xs, fs, lo, hi, degree):
    """∫ over each [lo_i, hi_i] of the polynomial of degree ≤ ``degree`` through the samples
    (xs, fs) nearest to the interval (all from one smooth piece)."""
    n = xs.size
    if n == 1:
        return fs[0] * (hi - lo)
    d = min(degree, n - 1)
    k = np.searchsorted(xs, 0.5 * (lo + hi))
    start = np.clip(k - (d + 1) // 2, 0, n - d - 1)
    idx = start[:, None] + np.arange(d + 1)[None, :]
    h = hi - lo
    wide = h > 0
    out = np.zeros(lo.size)
    if not wide.any():
        return out
    idx, lo_w, h_w = idx[wide], lo[wide], h[wide]
    # the stencil in units of the interval: well conditioned for the few intervals it spans
    z = (xs[idx] - lo_w[:, None]) / h_w[:, None]
    vander_t = z[:, None, :] ** np.arange(d + 1)[None, :, None]
    moments = np.broadcast_to(1.0 / np.arange(1, d + 2), (lo_w.size, d + 1))
    w = np.linalg.solve(vander_t, moments[..., None])[..., 0]
    out[wide] = h_w * np.sum(w * fs[idx], axis=1)
    return out


def _apart(nodes: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """Sorted ``nodes`` (a segment's ends first and last) without an inner node within ``tol``
    of the one before it or of the segment's end: a sample on a mark to rounding. Between two
    such nodes the interpolatory rule, scaled to the interval, is all rounding — whatever the
    linear solve's kernel makes of the stencil's Vandermonde matrix at 10¹³ interval widths. A
    mark so dropped is found at its neighbour (:func:`integrals_between` looks marks up within
    ``tol``)."""
    gap = np.diff(nodes) > tol
    keep = np.concatenate([[True], gap[:-1], [True]])
    keep[-2] &= gap[-1] or nodes.size == 2
    return nodes[keep]


def integrals_between(x: ArrayLike, f: ArrayLike, marks: ArrayLike, cuts: ArrayLike = (),
                      degree: int = QUAD_DEGREE) -> NDArray[np.float64]:
    """∫ f dx between consecutive ``marks`` from samples (x, f), x non-decreasing.

    The samples are split into smooth segments at the ``cuts`` (corners or jumps of f) and at a
    repeated abscissa (a jump written on both sides). A sample on a cut is left out of both
    segments, since at a jump it may hold either limit; each segment is integrated from cut to
    cut by the interpolatory rule of degree ``degree`` through the samples strictly inside it
    nearest to each interval (extrapolated over the part between the last sample and the cut),
    the marks being nodes too. A segment with fewer than two samples inside is joined to the next
    (a corner closer to the next than the output spacing: it is then interpolated across).
    Returns (len(marks) − 1,).
    """
    x = np.asarray(x, dtype=float)
    f = np.asarray(f, dtype=float)
    marks = np.asarray(marks, dtype=float)
    tol = 1e-12 * max(1.0, float(np.max(np.abs(x))))
    repeated = x[1:][np.diff(x) == 0.0]
    bounds = np.unique(np.concatenate([np.asarray(cuts, dtype=float).ravel(), repeated]))
    bounds = bounds[(bounds > x[0] + tol) & (bounds < x[-1] - tol)]
    edges = np.concatenate([[x[0]], bounds, [x[-1]]])
    ends, parts = [], []
    lo = edges[0]
    for j in range(1, edges.size):
        hi = edges[j]
        # the data's own ends are samples of the first and last segments, not cuts
        first, last = lo == x[0], j == edges.size - 1
        keep = ((x > lo + tol) | (first & (x >= lo))) & ((x < hi - tol) | (last & (x <= hi)))
        if keep.sum() < 2 and not last:
            continue  # joined to the next segment
        xs, fs = x[keep], f[keep]
        inside = marks[(marks > lo) & (marks < hi)]
        nodes = _apart(np.unique(np.concatenate([[lo, hi], xs[(xs > lo) & (xs < hi)], inside])),
                       tol)
        if xs.size:
            parts.append(_interval_integrals(xs, fs, nodes[:-1], nodes[1:], degree))
            ends.append(nodes[1:])
        lo = hi
    hi_nodes = np.concatenate(ends)
    cum = np.concatenate([[0.0], np.cumsum(np.concatenate(parts))])
    # the integral from x[0] up to each mark (every mark is a node)
    at = np.searchsorted(hi_nodes, marks + tol, side="right")
    return np.diff(cum[at])


# ------------------------------------------------------------------------------------------------
# The analysis


def _corner_cuts(scene, phi_lo: float, phi_hi: float, events) -> list[NDArray[np.float64]]:
    """Per cylinder, the shaft angles in [phi_lo, phi_hi] where its pressure curve has a corner:
    its table's corners and cycle start (shifted by the cylinder's phase), and the events of
    :data:`FUEL_CORNERS`. Other events (a pair's mode switch) leave the pressure smooth, and a cut
    there would only shorten the quadrature's segments."""
    from ..scene.queries import gas_phases, gas_tables

    cycle = scene.mechanism.cycle
    tables = [t for t in gas_tables(scene) if t is not None]
    corners = np.unique(np.concatenate([[0.0], *[np.asarray(t.corners) for t in tables]]))
    corners = corners[corners < cycle]
    fuel = [np.asarray(v)[:, 1] for k, v in (events or {}).items() if k in FUEL_CORNERS
            and np.size(v)]
    other = np.concatenate(fuel) if fuel else np.zeros(0)
    out = []
    for phase in gas_phases(scene):
        j0 = math.floor((phi_lo - phase) / cycle) - 1
        j1 = math.ceil((phi_hi - phase) / cycle) + 1
        c = (phase + cycle * np.arange(j0, j1 + 1)[:, None] + corners[None, :]).ravel()
        out.append(np.concatenate([c[(c >= phi_lo) & (c <= phi_hi)], other]))
    return out


def _at_marks(traj, part, name, marks, cuts, derivative=None):
    """Column ``name`` at the cycle marks: the samples there in crank angle, else the cubic
    Hermite interpolant with dv/dφ = ``derivative``, not across the run's breakpoints ``cuts``
    (a cycle mark is often one) (:func:`.orders.resample_angle`)."""
    phi = np.asarray(traj["phi"], float)[part]
    v = np.asarray(traj[name], float)[part]
    d = None if derivative is None else np.asarray(derivative, float)[part]
    return resample_angle(phi, v, marks, d, cuts)


def cycle_thermodynamics(scene, traj: Mapping[str, NDArray[np.float64]], events=None
                         ) -> dict[str, tuple[Any, str]]:
    """The stored names of the module docstring, name → (value, unit).

    ``events``: name → (n, 2) array of (t, φ), as :func:`.requested.requested_analyses` gets
    them. Raises ValueError (:class:`~.irregularity.NoWholeCycle`) if the run holds no whole
    cycle, and for a gas model whose ``p_<k>`` are forces (no pressure to integrate)."""
    from ..scene.queries import gas_is_force

    if scene.gas.model == "none" or gas_is_force(scene):
        raise ValueError(f"gas model {scene.gas.model!r} applies no pressure (a force per piston "
                         f"or none): there is no ∮p dV")
    mech = scene.mechanism
    cycle, n = mech.cycle, mech.n_cylinders
    part = _increasing_part(traj)
    phi = np.asarray(traj["phi"], float)[part]
    marks = cycle_marks(phi, cycle, scene.initial.phi)
    if marks.size < 2:
        raise NoWholeCycle("the run holds no whole cycle")
    vol = cylinder_volumes(scene, phi)
    cuts = _corner_cuts(scene, float(phi[0]), float(phi[-1]), events)
    starts = cylinder_cycle_starts(scene, marks, float(phi[0]))
    w = np.asarray(traj["omega"], float)[part]
    # dt/dφ = 1/ω; NaN where ω = 0, the first sample of a start from rest, where only the mark
    # φ0 falls, read off that sample: the derivative there is never used
    inv_w = np.divide(1.0, w, out=np.full_like(w, np.nan), where=w != 0.0)
    shaft_cuts = np.asarray((events or {}).get("breakpoint", np.zeros((0, 2))))[:, 1]
    W_engine = np.zeros(marks.size - 1)  # Σ_k ∮p_k dV_k over the engine's cycles
    W = np.full((n, marks.size - 1), np.nan)  # each over its own cycles
    P_ind = np.full_like(W, np.nan)
    for k in range(n):
        f = np.asarray(traj[f"p_{k + 1}"], float)[part] * vol.dV[k]
        W_engine += integrals_between(phi, f, marks, cuts[k])
        whole = np.isfinite(starts[k])  # (a suffix: only its first cycles may begin too early)
        if not whole.any():
            continue
        own = np.append(starts[k][whole], starts[k][-1] + cycle)
        W[k, whole] = integrals_between(phi, f, own, cuts[k])
        t_own = _at_marks(traj, part, "t", own, shaft_cuts, inv_w)
        P_ind[k, whole] = W[k, whole] / np.diff(t_own)
    t_marks = _at_marks(traj, part, "t", marks, shaft_cuts, inv_w)
    period = np.diff(t_marks)
    swept = vol.swept
    total = float(swept.sum())

    def delta(name, derivative=None):
        if name not in traj:
            return np.zeros(marks.size - 1)
        return np.diff(_at_marks(traj, part, name, marks, shaft_cuts, derivative))

    M = {c: np.asarray(traj[c], float)[part] for c in ("M_gas", "M_load", "M_starter")}
    W_gas = delta("W_gas", M["M_gas"])
    W_load = delta("W_load", M["M_load"])
    W_starter = delta("W_starter", M["M_starter"])
    W_drive = delta("W_drive", np.asarray(traj["M_drive"], float)[part]
                    if "M_drive" in traj else None)
    W_loss = np.zeros(marks.size - 1)
    for k in range(len(scene.friction.pairs)):
        W_loss += delta(f"W_loss_{k + 1}", np.asarray(traj[f"P_loss_{k + 1}"], float)[part]
                        * inv_w)
    J = np.asarray(traj["J"], float)[part]
    K = 0.5 * J * w * w
    dK_dphi = 0.5 * np.asarray(traj["dJ_dphi"], float)[part] * w * w \
        + J * np.asarray(traj["epsilon"], float)[part]
    dK = np.diff(resample_angle(phi, K, marks, dK_dphi, shaft_cuts))
    W_ind = W_engine
    residual = (W_ind + W_starter + W_drive + W_load - W_loss - dK) / np.where(
        W_ind != 0.0, np.abs(W_ind), 1.0)

    p_max, p_arg = _peaks(scene, phi, traj, part, starts)
    out: dict[str, tuple[Any, str]] = {
        "thermo_cycle_start": (marks[:-1], "rad"),
        "thermo_cycle_omega_mean": (cycle / period, "rad/s"),
        "thermo_cylinder_cycle_start": (starts, "rad"),
        "thermo_swept_volume": (swept, "m^3"),
        "thermo_W_indicated": (W, "J"),
        "thermo_imep": (W / swept[:, None], "Pa"),
        "thermo_P_indicated": (P_ind, "W"),
        "thermo_p_max": (p_max, "Pa"),
        "thermo_p_max_angle": (p_arg, "rad"),
        "thermo_imep_engine": (W_ind / total, "Pa"),
        "thermo_bmep": (-W_load / total, "Pa"),
        "thermo_fmep": (W_loss / total, "Pa"),
        "thermo_P_indicated_engine": (W_ind / period, "W"),
        "thermo_P_brake": (-W_load / period, "W"),
        "thermo_P_friction": (W_loss / period, "W"),
        "thermo_W_gas": (W_gas, "J"),
        "thermo_W_load": (W_load, "J"),
        "thermo_W_loss": (W_loss, "J"),
        "thermo_dK": (dK, "J"),
        "thermo_balance_residual": (residual, "1"),
    }
    if scene.gas.model == "wiebe":
        out.update(heat_release(scene, phi, traj, part, starts, vol))
    for name in ("imep_engine", "bmep", "fmep", "P_indicated_engine", "P_brake", "P_friction",
                 "balance_residual"):
        value, unit = out[f"thermo_{name}"]
        out[f"thermo_last_{name}"] = (float(value[-1]), unit)
    last = (phi >= marks[-2]) & (phi <= marks[-1])
    out["thermo_last_p_max"] = (max(float(np.asarray(traj[f"p_{k + 1}"], float)[part][last].max())
                                    for k in range(n)), "Pa")
    return out


def cylinder_cycle_starts(scene, marks: NDArray[np.float64], phi_first: float
                          ) -> NDArray[np.float64]:
    """(n, C): the shaft angle where each cylinder's own cycle that ends in engine cycle j
    (between ``marks[j]`` and ``marks[j + 1]``, its end included) begins; NaN where that is
    before ``phi_first``, the run's first angle (module docstring, *Cycles*). A cylinder whose
    cycle begins within rounding of the engine's has the engine's marks themselves."""
    from ..scene.queries import cycle_begin, gas_phases

    cycle = scene.mechanism.cycle
    d = np.mod(gas_phases(scene) + cycle_begin(scene.mechanism) - marks[0], cycle)
    d = np.where(cycle - d <= 1e-12 * cycle, 0.0, d)  # (its cycle ends on the engine's)
    starts = marks[None, :-1] + np.where(d > 0.0, d - cycle, 0.0)[:, None]
    return np.where(starts >= phi_first - 1e-12 * max(1.0, abs(phi_first)), starts, np.nan)


def _peaks(scene, phi, traj, part, starts):
    """Largest stored pressure of each cylinder in each of its own cycles (``starts``, NaN: not
    held) and its local angle in [0, Φ)."""
    from ..scene.queries import gas_phases

    cycle = scene.mechanism.cycle
    p_max = np.full(starts.shape, np.nan)
    p_arg = np.full_like(p_max, np.nan)
    for k, phase in enumerate(gas_phases(scene)):
        p = np.asarray(traj[f"p_{k + 1}"], float)[part]
        for j in np.flatnonzero(np.isfinite(starts[k])):
            # the samples from its first angle on, up to its end (the next cycle's first angle)
            lo, hi = np.searchsorted(phi, [starts[k, j], starts[k, j] + cycle])
            if hi > lo:
                i = lo + int(np.argmax(p[lo:hi]))
                p_max[k, j] = p[i]
                p_arg[k, j] = (phi[i] - phase) % cycle
    return p_max, p_arg


def _closed_part(scene):
    """(γ, intake closing, exhaust opening) of the scene's Wiebe cycle, angles local [rad]; None
    if γ varies with temperature (``gamma_slope`` ≠ 0: the constant-γ form would not be the
    model's own first law)."""
    from ..scene.queries import wiebe_levels

    w = scene.gas.wiebe
    if w.gamma_slope != 0.0:
        return None
    table = wiebe_levels(scene.mechanism, scene.gas)[-1]  # its closed part, resolved
    return w.gamma, table.intake_closing, table.exhaust_opening


def _release(gamma, phi, p, V, dV, a, b):
    """(φ, dQ/dφ [J/rad], Q [J] from a) at the samples strictly inside the closed part [a, b]
    (Heywood (9.25)); None with fewer than 8 samples there. The ends are left out: at exhaust
    opening the pressure falls (a jump), and a sample on it may hold either side."""
    from scipy.interpolate import CubicSpline

    tol = 1e-9 * max(1.0, abs(b))
    sel = (phi > a + tol) & (phi < b - tol)
    if sel.sum() < 8:
        return None
    x, pv = phi[sel], p[sel]
    dp = CubicSpline(x, pv, bc_type="not-a-knot")(x, 1)
    rate = gamma / (gamma - 1.0) * pv * dV[sel] + V[sel] * dp / (gamma - 1.0)
    q = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(x))])
    return x, rate, q


def _closed_window(scene, start: float, ivc: float, evo: float) -> tuple[float, float]:
    """Shaft angles of intake closing and exhaust opening (local ``ivc``, ``evo``) in the
    cylinder's own cycle that begins at the shaft angle ``start``."""
    from ..scene.queries import cycle_begin

    a = start + (ivc - cycle_begin(scene.mechanism)) % scene.mechanism.cycle
    return a, a + (evo - ivc)


def heat_release(scene, phi, traj, part, starts, vol) -> dict[str, tuple[Any, str]]:
    """Apparent heat released per cylinder over the closed part of each of its own cycles
    (``starts``, NaN: not held; Heywood (9.25), module docstring) and the MFB angles;
    ``thermo_heat_release_skipped`` if γ varies with temperature."""
    from ..scene.queries import gas_phases

    closed = _closed_part(scene)
    if closed is None:
        return {"thermo_heat_release_skipped": ("γ varies with temperature (gamma_slope ≠ 0)",
                                                "")}
    g, ivc, evo = closed
    cycle = scene.mechanism.cycle
    Q = np.full(starts.shape, np.nan)
    mfb = np.full((len(MFB_LEVELS),) + starts.shape, np.nan)
    for k, phase in enumerate(gas_phases(scene)):
        p = np.asarray(traj[f"p_{k + 1}"], float)[part]
        for j in np.flatnonzero(np.isfinite(starts[k])):
            a, b = _closed_window(scene, starts[k, j], ivc, evo)
            got = None if b > phi[-1] else _release(g, phi, p, vol.V[k], vol.dV[k], a, b)
            if got is None:
                continue
            x, _, q = got
            Q[k, j] = q[-1]
            frac = q / q[-1] if q[-1] > 0 else q * np.nan
            for i, level in enumerate(MFB_LEVELS):
                hit = np.nonzero(frac >= level)[0]
                if hit.size and hit[0] > 0:
                    h = hit[0]
                    theta = np.interp(level, frac[h - 1: h + 1], x[h - 1: h + 1])
                    mfb[i, k, j] = (theta - phase) % cycle
    out = {"thermo_Q": (Q, "J")}
    for i, level in enumerate(MFB_LEVELS):
        out[f"thermo_mfb{round(100 * level)}"] = (mfb[i], "rad")
    return out


def heat_release_rate(scene, traj: Mapping[str, NDArray[np.float64]], cylinder: int,
                      start: float) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """(local angle [rad], dQ/dφ [J/rad]) of ``cylinder`` (1-based) over the closed part of its
    own cycle that starts at the shaft angle ``start`` (:func:`own_cycles`), from the stored
    pressure; None where the scene's gas model is not Wiebe combustion with constant γ or the run
    does not hold that closed part."""
    closed = _closed_part(scene) if scene.gas.model == "wiebe" else None
    if closed is None:
        return None
    g, ivc, evo = closed
    part = _increasing_part(traj)
    phi = np.asarray(traj["phi"], float)[part]
    a, b = _closed_window(scene, start, ivc, evo)
    if b > phi[-1]:
        return None
    window = (phi > a - 1e-6) & (phi < b + 1e-6)
    x = phi[window]
    vol = cylinder_volumes(scene, x)
    p = np.asarray(traj[f"p_{cylinder}"], float)[part][window]
    got = _release(g, x, p, vol.V[cylinder - 1], vol.dV[cylinder - 1], a, b)
    return None if got is None else (local_angle(scene, got[0], start), got[1])


# ------------------------------------------------------------------------------------------------
# Per cylinder, for the plots


def own_cycles(scene, traj: Mapping[str, NDArray[np.float64]], cylinder: int
               ) -> NDArray[np.float64]:
    """Shaft angles [rad] at which the whole cycles of ``cylinder`` (1-based) in the run start:
    its own cycles (module docstring, *Cycles*) whose end the run reaches, after its last
    backward motion. Raises ValueError for a cylinder out of range."""
    from ..scene.queries import cycle_begin, gas_phases

    n = scene.mechanism.n_cylinders
    if not 1 <= cylinder <= n:
        raise ValueError(f"cylinder {cylinder} is out of range; allowed: 1 … {n}")
    phi = np.asarray(traj["phi"], float)[_increasing_part(traj)]
    begin = float(gas_phases(scene)[cylinder - 1]) + cycle_begin(scene.mechanism)
    return cycle_marks(phi, scene.mechanism.cycle, begin)[:-1]


def own_cycle_numbers(scene, cylinder: int, starts: ArrayLike) -> NDArray[np.int64]:
    """The numbers of ``cylinder``'s (1-based) own cycles that begin at the shaft angles
    ``starts`` (:func:`own_cycles`), as ``[[gas.cylinders]]`` counts them for its misfires: 1
    the cycle in progress at the initial angle (:func:`transient.assemble.variation_fields`)."""
    from ..assemble import variation_fields
    from ..core.model.variation import START
    from ..scene.queries import gas_phases

    first = variation_fields(scene, gas_phases(scene))["var_par"][cylinder - 1, START]
    return np.rint((np.asarray(starts, dtype=float) - first) / scene.mechanism.cycle
                   ).astype(np.int64) + 1


def cycle_fuel_of(scene):
    """``fuel(cylinder, φ)``: the fuel factor [1] the run applied in the cylinder's (1-based)
    own cycle that the shaft angle φ lies in, and whether that cylinder is cut out for the whole
    run: ``(factor, cut_out)``; ``[[gas.cylinders]]`` sets them (its factor, 0 in a misfiring
    cycle). Every cycle of a scene without such entries burns full fuel, (1, False)."""
    if not scene.gas.cylinders:
        return lambda cylinder, phi: (1.0, False)
    from ..assemble import build_model
    from ..core.model.variation import FUEL, cycle_fuel

    model = build_model(scene)[0]
    return lambda cylinder, phi: (float(cycle_fuel(model, cylinder - 1, phi)),
                                  bool(model.var_par[cylinder - 1, FUEL] == 0.0))


def misfires(scene, traj: Mapping[str, NDArray[np.float64]]
             ) -> list[tuple[int, int, float]]:
    """The misfires of a run: (cylinder, its cycle's number, time of that cycle's firing TDC
    [s]) for every own cycle that the run reaches the firing TDC of and that burned no fuel
    though its cylinder is not cut out; in time order."""
    from ..scene.queries import cycle_begin, gas_phases

    if not scene.gas.cylinders:
        return []
    fuel = cycle_fuel_of(scene)
    part = _increasing_part(traj)
    phi, t = np.asarray(traj["phi"], float)[part], np.asarray(traj["t"], float)[part]
    mech = scene.mechanism
    to_firing = 2.0 * math.pi - cycle_begin(mech)  # from a cycle's first angle to its firing TDC
    out = []
    for entry in scene.gas.cylinders:
        k = entry.cylinder
        begin = float(gas_phases(scene)[k - 1]) + cycle_begin(mech)
        j0 = math.ceil((phi[0] - to_firing - begin) / mech.cycle)
        j1 = math.floor((phi[-1] - to_firing - begin) / mech.cycle)
        starts = begin + mech.cycle * np.arange(j0, j1 + 1)
        for a, n in zip(starts, own_cycle_numbers(scene, k, starts)):
            f, cut = fuel(k, a + 0.5 * mech.cycle)
            if f == 0.0 and not cut:
                out.append((k, int(n), float(np.interp(a + to_firing, phi, t))))
    return sorted(out, key=lambda m: m[2])


def local_angle(scene, phi: ArrayLike, start: float) -> NDArray[np.float64]:
    """A cylinder's local angle (as its gas table counts it) at the shaft angles ``phi`` of its
    own cycle that begins at ``start`` (:func:`own_cycles`), increasing through the whole cycle
    (a 2-stroke's, begun at π, runs on past 2π)."""
    from ..scene.queries import cycle_begin

    return cycle_begin(scene.mechanism) + (np.asarray(phi, dtype=float) - start)
