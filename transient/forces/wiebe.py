"""Wiebe cycles tabulated against the local crank angle: one table per fuel mass.

The closed part (intake closing → exhaust opening) is the single-zone first law with Wiebe heat
release of :mod:`transient.forces.closed_cycle`, without wall heat transfer. Tabulated, it becomes
a :class:`~transient.forces.gas.PressureTable` in the form :func:`~transient.forces.gas.mixed_cycle`
produces (same angle convention, constant gas-exchange pressures), so it can replace a prescribed
indicator diagram. :func:`wiebe_tables` builds one table per fuel mass for interpolation between
load levels; all its tables share the same knots.

Angles are local crank angles in radians (the scene converts ``*_deg`` keys), pressures absolute
in Pa, volumes in m³, energies in J, temperatures in K.

What is not modelled
--------------------
* **Wall heat transfer.** A Woschni-type loss depends on the gas velocity and the time spent per
  crank degree, so it makes the pressure depend on the shaft speed; such a diagram is not a
  function of the crank angle alone and cannot be this table (:mod:`transient.forces.woschni`
  integrates it at a given speed instead). The combustion efficiency ``η_c`` may lump a
  speed-independent loss.
* What the closed part leaves out (:mod:`transient.forces.closed_cycle`), and gas exchange
  dynamics: the intake and exhaust strokes of a 4-stroke are at constant pressure and a 2-stroke
  is scavenged instantaneously at its exhaust opening, as in
  :func:`~transient.forces.gas.mixed_cycle`.
"""
from __future__ import annotations

import inspect
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from transient.errors import SceneError
from transient.forces.closed_cycle import (
    DEFAULT_A,
    DEFAULT_M,
    DEFAULT_RTOL,
    ClosedPart,
    CycleSetup,
    burned_fraction,
    check_fuel_mass,
    check_volume,
    integrate_closed,
    peak,
    setup_cycle,
    volume_derivative,
)
from transient.forces.gas import (
    IndicatedCycle,
    PressureTable,
    VolumeFunction,
    assemble_table,
    not_a_knot_coef,
    volume_at,
)

__all__ = [
    "DEFAULT_TOLERANCE",
    "WIEBE_STEP",
    "WiebeCycle",
    "wiebe_cycle",
    "wiebe_tables",
]

#: Default largest knot spacing of the tables [rad] (0.125°, as
#: :data:`~transient.forces.gas.DEFAULT_STEP`), refined where needed to meet the tolerance.
#: Measured on the Gots geometry (``tests/validation/test_wiebe_cycle.py``): with 0.05 g of
#: fuel, a 50° combustion from 358° and m = 0.5 the uniform 0.125° grid errs by 2.6e-5 of p_max
#: in its first interval after the combustion start (``p ∝ y**1.5`` there); refining to 1e-10
#: takes 3110 knots instead of 2887. The motored cycle: 6.4e-10 uniform (at the TDC), 1e-10
#: with 4 more knots.
WIEBE_STEP = math.radians(0.125)

#: Default target of the tabulation error, relative to the cycle's largest pressure: intervals
#: whose midpoint error exceeds it are halved (see ``_tabulate``). For m < 0 the pressure
#: rises like ``y**(m + 1)`` with an infinite slope at the combustion start and the target is
#: not met there (m = -0.5: 1.9e-5 with intervals down to 1e-9 rad);
#: :attr:`WiebeCycle.interpolation_error` reports what was reached.
DEFAULT_TOLERANCE = 1e-10

# Knot intervals are not halved below this [rad]; at most this many halving rounds per piece.
_MIN_SPACING = 1e-9
_MAX_REFINE = 60


@dataclass(frozen=True, eq=False)
class WiebeCycle(IndicatedCycle):
    """Pressure table of a single-zone Wiebe cycle, with what the integration found.

    A :class:`~transient.forces.gas.PressureTable` (use it wherever one is expected), with the
    mean torque and pressure of :class:`~transient.forces.gas.IndicatedCycle`. Angles are table
    angles in [0, period) [rad] unless said otherwise.

    Attributes
    ----------
    work : float
        Indicated loop work ∮p dV per cycle [J]: the closed part from the ODE (an integrated
        component, not the table) plus the constant-pressure parts (the 4-stroke pumping loop
        ``p_intake(V_a - V(0)) + p_exhaust(V(4π) - V_b)``; for a 2-stroke ``p_a(V_a - V_b)``,
        zero when it is scavenged at BDC).
    closed_work : float
        ∫p dV from intake closing to exhaust opening [J].
    p_max : float
        Peak pressure [Pa].
    angle_max : float
        Angle of the peak pressure [rad].
    t_max : float
        Peak gas temperature [K].
    burned_fraction : float
        Wiebe fraction at exhaust opening (``1 - exp(-a)`` once the combustion has ended).
    heat_released : float
        ``m_f·LHV·η_c·burned_fraction`` [J].
    p_end : float
        Pressure at exhaust opening, before the blow-down [Pa].
    v_a, v_b, v_c : float
        Volumes at intake closing, exhaust opening and firing TDC [m³].
    v_h : float
        Swept volume ``V(π) - V_c`` [m³] (π is a BDC in both cycle types).
    intake_closing, exhaust_opening, combustion_start, combustion_end : float
        Angles of those events [rad].
    fuel_mass : float
        Fuel mass per cycle [kg].
    strokes : int
        2 or 4.
    interpolation_error : float
        Tabulation error estimate: the largest ``|table - p|`` at the knot-interval midpoints
        against the dense ODE solution, over the largest pressure (as
        :func:`~transient.forces.gas.table_from_function` estimates it). A 4-points-per-interval
        scan finds up to about 20 % more (end intervals of the not-a-knot splines).
    closed : ClosedPart
        The dense ODE solution (pressure and cumulative work), for checks.
    """

    closed_work: float
    p_max: float
    angle_max: float
    t_max: float
    burned_fraction: float
    heat_released: float
    p_end: float
    v_a: float
    v_b: float
    v_c: float
    v_h: float
    intake_closing: float
    exhaust_opening: float
    combustion_start: float
    combustion_end: float
    fuel_mass: float
    strokes: int
    interpolation_error: float
    closed: ClosedPart


@dataclass(frozen=True, eq=False)
class _Solved:
    """One integrated cycle before tabulation: its pieces and scalars."""

    pieces: list            # (a, b, callable or float) in table angles, in order
    scale: float            # largest pressure of the cycle [Pa]
    fields: dict            # WiebeCycle fields other than the table's


def _solve(st: CycleSetup, fuel_mass: float, volume: VolumeFunction,
           dvolume: VolumeFunction) -> _Solved:
    """Integrate the closed part and describe the table pieces (not yet tabulated)."""
    period = st.period
    closed = integrate_closed(st, fuel_mass, volume, dvolume)

    def wrap(x: float) -> float:
        # Table angle of an unwrapped one; the exhaust opening exactly as given.
        return st.evo_table if x == st.evo else (x - period if x > period else x)

    # Table pieces (a, b, f) in table angles; a closed piece evaluates the dense solution at
    # the unwrapped angle x + shift.
    pieces: list[tuple[float, float, object]] = []

    def closed_piece(lo: float, hi: float, shift: float) -> None:
        k = int(closed.segment_index(0.5 * (lo + hi) + shift))

        def f(x, seg=closed.segments[k], shift=shift):
            return seg(np.asarray(x, dtype=np.float64) + shift)[0]
        pieces.append((lo, hi, f))

    if st.strokes == 4:
        pieces.append((0.0, st.ivc, st.p_intake))
        for lo, hi in zip(closed.breaks[:-1], closed.breaks[1:]):
            closed_piece(float(lo), float(hi), 0.0)
        pieces.append((st.evo, period, st.p_exhaust))
    else:
        # Split the closed part at the period end 2π ≡ 0 (the firing TDC).
        cuts = sorted(set(closed.breaks.tolist()) | {period})
        spans = list(itertools.pairwise(cuts))
        for lo, hi in spans:                               # 0 → exhaust opening
            if hi > period:
                closed_piece(lo - period, wrap(hi), period)
        if st.evo_table < st.ivc:                          # scavenging at p_a
            pieces.append((st.evo_table, st.ivc, st.p_a))
        for lo, hi in spans:                               # intake closing → 2π
            if hi <= period:
                closed_piece(lo, hi, 0.0)

    p_w_end = closed(np.array([st.evo]))
    closed_work = float(p_w_end[1][0])
    v_a = closed.v_a
    v_b = volume_at(volume, wrap(st.evo))
    if st.strokes == 4:
        work = (closed_work + st.p_intake * (v_a - volume_at(volume, 0.0))
                + st.p_exhaust * (volume_at(volume, period) - v_b))
        v_c = volume_at(volume, 2.0 * math.pi)
    else:
        work = closed_work + st.p_a * (v_a - v_b)
        v_c = volume_at(volume, 0.0)
    p_max, x_max, t_max = peak(closed, volume, period)
    end = st.start + st.duration
    xb = burned_fraction(st)
    fields = {"work": work, "closed_work": closed_work, "p_max": p_max,
              "angle_max": wrap(x_max) % period, "t_max": t_max, "burned_fraction": xb,
              "heat_released": fuel_mass * st.lhv * st.efficiency * xb,
              "p_end": float(p_w_end[0][0]), "v_a": v_a, "v_b": v_b, "v_c": v_c,
              "v_h": volume_at(volume, math.pi) - v_c, "intake_closing": st.ivc,
              "exhaust_opening": st.evo_table, "combustion_start": wrap(st.start) % period,
              "combustion_end": wrap(end) % period, "fuel_mass": fuel_mass,
              "strokes": st.strokes, "closed": closed}
    scale = max(p_max, st.p_a, *(v for v in (st.p_intake, st.p_exhaust) if np.isfinite(v)))
    return _Solved(pieces=pieces, scale=scale, fields=fields)


def _tabulate(solved: Sequence[_Solved], period: float, step: float, tolerance: float
              ) -> list[tuple[PressureTable, float]]:
    """Tables of several cycles on common knots, refined until the midpoint error is small.

    Every piece starts with the fewest equal intervals not longer than `step`. Then every
    interval whose midpoint error ``|spline - f|`` exceeds `tolerance` times the cycle's largest
    pressure, for any of the cycles, is halved, until none does or the interval is shorter than
    :data:`_MIN_SPACING` (the heat-release rate ``∝ y**m`` makes ``p ∝ y**(m + 1)`` near the
    combustion start, which a uniform cubic cannot follow for non-integer m).

    Returns
    -------
    list of (table, rel_error)
        rel_error: the largest midpoint error over the cycle's largest pressure.
    """
    n_cycles = len(solved)
    knots: list[NDArray[np.float64]] = []
    coefs: list[list[NDArray[np.float64]]] = [[] for _ in range(n_cycles)]
    errors = np.zeros(n_cycles)
    n_pieces = len(solved[0].pieces)
    for j in range(n_pieces):
        a, b, _ = solved[0].pieces[j]
        funcs = [s.pieces[j][2] for s in solved]
        if not callable(funcs[0]):
            knots.append(np.array([a, b]))
            for i, f in enumerate(funcs):
                coefs[i].append(np.array([[float(f), 0.0, 0.0, 0.0]]))
            continue
        n = max(1, math.ceil((b - a) / step * (1.0 - 1e-12)))
        x = np.linspace(a, b, n + 1)
        for attempt in range(_MAX_REFINE):
            h = np.diff(x)
            xm = x[:-1] + 0.5 * h
            piece_coef, piece_err = [], []
            bad = np.zeros(h.size, dtype=bool)
            for s, f in zip(solved, funcs):
                c = not_a_knot_coef(x, f(x))
                hm = 0.5 * h
                tm = c[:, 0] + hm * (c[:, 1] + hm * (c[:, 2] + hm * c[:, 3]))
                e = np.abs(tm - f(xm)) / s.scale
                piece_coef.append(c)
                piece_err.append(e)
                bad |= e > tolerance
            bad &= h > 2.0 * _MIN_SPACING
            if not np.any(bad) or attempt == _MAX_REFINE - 1:
                break  # (the coefficients fit these knots; the error says what they reach)
            x = np.sort(np.concatenate([x, xm[bad]]))
        knots.append(x)
        for i in range(n_cycles):
            coefs[i].append(piece_coef[i])
            errors[i] = max(errors[i], float(np.max(piece_err[i])))
    return [(assemble_table(list(zip(knots, coefs[i])), period), float(errors[i]))
            for i in range(n_cycles)]


def _cycles(volume: VolumeFunction, fuel_levels: Sequence[float], *, p_a, start, duration, a,
            m, lhv, efficiency, gamma, gamma_slope, gamma_t_ref, t_a, p_intake, p_exhaust,
            strokes, intake_closing, exhaust_opening, dvolume, step, tolerance,
            rtol) -> tuple[WiebeCycle, ...]:
    """Validate, integrate and tabulate the cycles of `fuel_levels` on common knots."""
    st = setup_cycle(strokes=strokes, p_a=p_a, start=start, duration=duration, a=a, m=m,
                     lhv=lhv, efficiency=efficiency, gamma=gamma, gamma_slope=gamma_slope,
                     gamma_t_ref=gamma_t_ref, t_a=t_a, p_intake=p_intake, p_exhaust=p_exhaust,
                     intake_closing=intake_closing, exhaust_opening=exhaust_opening, rtol=rtol)
    if not (np.isfinite(step) and step > 0.0):
        raise SceneError("gas.wiebe.step_deg", f"knot spacing {step!r} rad; it must be > 0")
    if not (np.isfinite(tolerance) and 1e-13 <= tolerance <= 1e-3):
        raise SceneError("gas.wiebe.tolerance", f"{tolerance!r}; the relative tabulation "
                                                "tolerance must be in [1e-13, 1e-3]")
    check_volume(st, volume)
    dvolume = dvolume or volume_derivative(volume)
    solved = [_solve(st, float(q), volume, dvolume) for q in fuel_levels]
    tables = _tabulate(solved, st.period, float(step), float(tolerance))
    return tuple(WiebeCycle(knots=t.knots, coef=t.coef, piece_knot=t.piece_knot,
                            period=st.period, interpolation_error=err, **s.fields)
                 for s, (t, err) in zip(solved, tables))


def wiebe_cycle(volume: VolumeFunction, *, p_a: float, start: float, duration: float,
                fuel_mass: float, a: float = DEFAULT_A, m: float = DEFAULT_M,
                lhv: float = 42.5e6, efficiency: float = 1.0, gamma: float = 1.35,
                gamma_slope: float = 0.0, gamma_t_ref: float = 300.0, t_a: float = 330.0,
                p_intake: float | None = None, p_exhaust: float | None = None,
                strokes: int = 4, intake_closing: float | None = None,
                exhaust_opening: float | None = None,
                dvolume: VolumeFunction | None = None, step: float = WIEBE_STEP,
                tolerance: float = DEFAULT_TOLERANCE, rtol: float = DEFAULT_RTOL
                ) -> WiebeCycle:
    """Single-zone Wiebe cycle tabulated against the local crank angle.

    From intake closing to exhaust opening the pressure solves

        dp/dx = (γ - 1)/V · dQ/dx - γ p/V · dV/dx,   dQ/dx = m_f · LHV · η_c · dx_b/dx,

    (first law of one ideal-gas zone, ``U = ∫ m c_v dT`` with ``c_v = R/(γ(T) - 1)``; exact
    also for a temperature-dependent γ), integrated with DOP853 at `rtol` and split at the
    combustion start and end, where the heat-release rate has kinks (these are table corners
    too). The work ∫p dV/dx dx is a second ODE component, so
    :attr:`~transient.forces.gas.IndicatedCycle.work` does not
    come from the table. Outside the closed part the pressure is constant: a 4-stroke is at
    `p_intake` from 0 to intake closing and at `p_exhaust` from exhaust opening to 4π; a
    2-stroke jumps to `p_a` at exhaust opening and stays there until intake closing.

    There is no wall heat transfer: a Woschni loss makes the pressure depend on the shaft speed,
    which a table against the crank angle cannot express; it is not part of this model.

    Parameters
    ----------
    volume : callable
        Vectorised ``V(x)`` [m³] at local crank angles x [rad], > 0. It is called at table
        angles in [0, period] and, without `dvolume`, up to 0.016 rad outside them (central
        differences), so it must be defined there (periodic, as a crank mechanism's is).
    dvolume : callable, optional
        Vectorised ``dV/dx`` [m³/rad]. If omitted, an 8th-order central difference of `volume`
        is used (about 1e-13 of V for a crank slider).
    p_a : float
        Pressure at intake closing, the start of compression [Pa].
    fuel_mass : float
        Fuel mass burned per cycle [kg], ≥ 0 (0: motored). Gots App. 2: 17.66 kg/h for 3
        cylinders at 4400 rpm, i.e. 0.0446 g per cycle.
    start : float
        Combustion start [rad], a table angle; moved by whole periods into the closed part
        (a 2-stroke start of -2° is 358°). Scene key ``gas.wiebe.start_deg``.
    duration : float
        Combustion duration [rad], > 0 (``gas.wiebe.duration_deg``).
    a, m : float
        Wiebe efficiency parameter (> 0) and shape exponent (> -1), see
        :func:`~transient.forces.closed_cycle.wiebe_fraction`.
    lhv : float
        Lower heating value of the fuel [J/kg] (diesel 42.5e6).
    efficiency : float
        Combustion efficiency η_c in (0, 1]: the share of ``m_f·LHV`` released.
    gamma : float
        Heat capacity ratio γ > 1; with `gamma_slope` it is γ at `gamma_t_ref`.
    gamma_slope : float
        dγ/dT [1/K]: ``γ(T) = gamma + gamma_slope·(T - gamma_t_ref)``. 0 (default) for a
        constant γ; air-like mixtures fall about 1e-4 per K. γ(T_a) must be > 1; then γ stays
        > 1, because ``dT/dx ∝ γ(T) - 1`` makes a temperature with γ = 1 unreachable (it is
        approached with an ever larger c_v: choose a line that stays well above 1 up to the
        peak temperature, :attr:`WiebeCycle.t_max`).
    gamma_t_ref : float
        Reference temperature of γ(T) [K].
    t_a : float
        Gas temperature at intake closing [K] (Gots App. 2: T_a = 329.9 K). It fixes the trapped
        mass ``m R = p_a V_a/T_a`` and so the temperature ``T = pV/(m R)``; it matters for the
        pressure only through γ(T).
    p_intake, p_exhaust : float, optional
        Constant intake and exhaust pressures of a 4-stroke [Pa], required there; unused for a
        2-stroke.
    strokes : {4, 2}
        Cycle type. 4-stroke: period 4π, x = 0 gas-exchange TDC, x = 2π firing TDC. 2-stroke:
        period 2π, firing TDC at 0, scavenged instantaneously to `p_a` at exhaust opening.
    intake_closing : float, optional
        Start of the closed part [rad]; default π (the BDC before firing TDC). 4-stroke: in
        (0, 2π); 2-stroke: in (0, 2π).
    exhaust_opening : float, optional
        End of the closed part [rad]; default the BDC after firing TDC (3π for a 4-stroke,
        π for a 2-stroke). 4-stroke: in (2π, 4π); 2-stroke: in (0, intake_closing]; between the
        two a 2-stroke is at `p_a`.
    step : float
        Largest knot spacing of the table [rad]: each piece starts with the fewest equal
        intervals not longer than it (as :func:`~transient.forces.gas.table_from_function`).
    tolerance : float
        Target tabulation error relative to the largest pressure: an interval whose midpoint
        error against the dense ODE solution exceeds it is halved, down to 1e-9 rad. Needed
        near the combustion start for non-integer m, where ``p - p_smooth ∝ y**(m + 1)``.
    rtol : float
        Relative tolerance of the DOP853 integration (absolute tolerances 1e-3·rtol of the
        intake-closing pressure and of ``p_a V_a``).

    Returns
    -------
    WiebeCycle
        The table with the ODE's loop work, peak pressure and angle, burned fraction and
        tabulation error.

    Raises
    ------
    SceneError
        ``gas.strokes``, ``gas.p_a``, ``gas.p_intake``, ``gas.p_exhaust``,
        ``gas.wiebe.fuel_mass``, ``gas.wiebe.start_deg`` (combustion starting outside the
        closed part), ``gas.wiebe.duration_deg`` (≤ 0, or ending after exhaust opening),
        ``gas.wiebe.a``, ``gas.wiebe.m``, ``gas.wiebe.lhv``, ``gas.wiebe.efficiency``,
        ``gas.wiebe.gamma``, ``gas.wiebe.gamma_slope`` (also when γ(T_a) ≤ 1),
        ``gas.wiebe.gamma_t_ref``, ``gas.wiebe.t_a``, ``gas.wiebe.intake_closing_deg``,
        ``gas.wiebe.exhaust_opening_deg``, ``gas.wiebe.step_deg``, ``gas.wiebe.tolerance``;
        ``gas.compression_ratio``
        if the volume is not positive over the closed part.
    """
    return _cycles(volume, [check_fuel_mass(fuel_mass)], p_a=p_a, start=start, duration=duration,
                   a=a, m=m, lhv=lhv, efficiency=efficiency, gamma=gamma, gamma_slope=gamma_slope,
                   gamma_t_ref=gamma_t_ref, t_a=t_a, p_intake=p_intake, p_exhaust=p_exhaust,
                   strokes=strokes, intake_closing=intake_closing,
                   exhaust_opening=exhaust_opening, dvolume=dvolume, step=step,
                   tolerance=tolerance, rtol=rtol)[0]


def wiebe_tables(volume: VolumeFunction, fuel_levels: Sequence[float], **cycle
                 ) -> tuple[WiebeCycle, ...]:
    """One :func:`wiebe_cycle` per fuel mass, for interpolation between load levels.

    All tables share the same knots and corners (the combustion start and end are corners even
    for the motored cycle), so interpolating between two levels is interpolating their
    coefficient arrays.

    Parameters
    ----------
    volume : callable
        As in :func:`wiebe_cycle`.
    fuel_levels : sequence of float
        Fuel masses per cycle [kg], finite, ≥ 0 and strictly increasing; 0 is the motored cycle.
        Not a scene key: a scene (``[gas.wiebe]``) has the levels 0 and ``fuel_mass``
        (:func:`transient.scene.queries.wiebe_levels`), always valid ones.
    **cycle
        Every other keyword of :func:`wiebe_cycle` (not `fuel_mass`).

    Returns
    -------
    tuple of WiebeCycle
        In the order of `fuel_levels`.

    Raises
    ------
    SceneError
        ``gas.wiebe.fuel_levels`` for an empty, negative, non-finite or not strictly increasing
        list; otherwise as :func:`wiebe_cycle`.
    """
    if "fuel_mass" in cycle:
        raise TypeError("wiebe_tables takes fuel_levels, not fuel_mass")
    levels = np.asarray(fuel_levels, dtype=np.float64).ravel()
    if levels.size == 0:
        raise SceneError("gas.wiebe.fuel_levels", "is empty; give at least one fuel mass [kg]")
    bad = np.flatnonzero(~np.isfinite(levels) | (levels < 0.0))
    if bad.size:
        raise SceneError("gas.wiebe.fuel_levels", f"fuel mass {levels[bad[0]]!r} kg is not "
                                                   "allowed; fuel masses must be finite and ≥ 0")
    back = np.flatnonzero(np.diff(levels) <= 0.0)
    if back.size:
        k = back[0]
        raise SceneError("gas.wiebe.fuel_levels", f"{levels[k + 1]!r} kg follows {levels[k]!r} kg;"
                                                   " fuel levels must increase strictly")
    # The defaults live in wiebe_cycle's signature only.
    args = inspect.signature(wiebe_cycle).bind(volume, fuel_mass=0.0, **cycle)
    args.apply_defaults()
    kwargs = dict(args.arguments)
    del kwargs["volume"], kwargs["fuel_mass"]
    return _cycles(volume, levels.tolist(), **kwargs)
