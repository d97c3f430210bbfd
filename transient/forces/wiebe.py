"""Single-zone combustion with Wiebe heat release, tabulated against the local crank angle.

The closed part of the cycle (intake closing → exhaust opening) is integrated with the first law
of a single ideal-gas zone,

    dp/dx = (γ - 1)/V · dQ/dx - γ p/V · dV/dx,      dQ/dx = m_f · LHV · η_c · dx_b/dx,

where ``x_b`` is the Wiebe burned fraction (:func:`wiebe_fraction`). The result is a
:class:`~transient.forces.gas.PressureTable` in the form :func:`~transient.forces.gas.mixed_cycle`
produces (same angle convention, constant gas-exchange pressures), so it can replace a prescribed
indicator diagram. :func:`wiebe_tables` builds one table per fuel mass for interpolation between
load levels; all its tables share the same knots.

Angles are local crank angles in radians (the scene converts ``*_deg`` keys), pressures absolute
in Pa, volumes in m³, energies in J, temperatures in K.

What is not modelled
--------------------
* **Wall heat transfer.** A Woschni-type loss depends on the gas velocity and the time spent per
  crank degree, so it makes the pressure depend on the shaft speed; such a diagram is not a
  function of the crank angle alone and cannot be this table. Nothing of it is implemented here;
  the combustion efficiency ``η_c`` may lump a speed-independent loss.
* **Mass change.** The trapped mass is fixed at intake closing; the fuel mass added (about 3 % of
  the charge) and blow-by are neglected, and the gas constant is the same before and after
  combustion. The temperature ``T = T_a·pV/(p_a V_a)`` follows from ``pV = m R T``.
* Injection, ignition delay, dissociation and gas exchange dynamics: the intake and exhaust
  strokes of a 4-stroke are at constant pressure and a 2-stroke is scavenged instantaneously at
  its exhaust opening, as in :func:`~transient.forces.gas.mixed_cycle`.
"""
from __future__ import annotations

import inspect
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from transient.errors import SceneError
from transient.forces.gas import PressureTable

__all__ = [
    "DEFAULT_A",
    "DEFAULT_M",
    "DEFAULT_TOLERANCE",
    "WIEBE_STEP",
    "ClosedPart",
    "WiebeCycle",
    "wiebe_cycle",
    "wiebe_fraction",
    "wiebe_rate",
    "wiebe_tables",
]

#: Wiebe efficiency parameter: ``1 - exp(-6.908) = 0.999`` of the fuel has burned at the end of
#: the combustion duration (Vibe's usual choice).
DEFAULT_A = 6.908

#: Wiebe shape exponent: a typical single-Wiebe diesel value (fits of direct-injection diesels
#: are usually quoted below 1, spark ignition near 2); set it from a measured heat release.
DEFAULT_M = 0.5

#: Default largest knot spacing of the tables [rad] (0.125°, as
#: :data:`~transient.forces.gas.DEFAULT_STEP`), refined where needed to meet the tolerance.
#: Measured on the Gots geometry (``tests/validation/test_wiebe_cycle.py``): with 0.05 g of
#: fuel, a 50° combustion from 358° and m = 0.5 the uniform 0.125° grid errs by 2.6e-5 of p_max
#: in its first interval after the combustion start (``p ∝ y**1.5`` there); refining to 1e-10
#: takes 3110 knots instead of 2887. The motored cycle: 6.4e-10 uniform (at the TDC), 1e-10
#: with 4 more knots.
WIEBE_STEP = math.radians(0.125)

#: Default relative tolerance of the closed-part integration (DOP853).
DEFAULT_RTOL = 1e-12

#: Default target of the tabulation error, relative to the cycle's largest pressure: intervals
#: whose midpoint error exceeds it are halved (see :func:`_tabulate`). For m < 0 the pressure
#: rises like ``y**(m + 1)`` with an infinite slope at the combustion start and the target is
#: not met there (m = -0.5: 1.9e-5 with intervals down to 1e-9 rad);
#: :attr:`WiebeCycle.interpolation_error` reports what was reached.
DEFAULT_TOLERANCE = 1e-10

# Knot intervals are not halved below this [rad]; at most this many halving rounds per piece.
_MIN_SPACING = 1e-9
_MAX_REFINE = 60

# Angles read from degrees miss a corner by a few ulp; closer than this they are snapped onto it
# (the same tolerance as transient.forces.gas).
_ANGLE_TOL = 1e-9

VolumeFunction = Callable[[NDArray[np.float64]], ArrayLike]


def _deg(x: float) -> str:
    """An angle in radians, formatted in degrees for a one-line message."""
    return f"{math.degrees(x):.6g}°"


# ----------------------------------------------------------------------------------------
# The Wiebe function
# ----------------------------------------------------------------------------------------

def _check_wiebe(start: float, duration: float, a: float, m: float) -> None:
    """Raise a SceneError for invalid Wiebe parameters."""
    if not np.isfinite(start):
        raise SceneError("gas.wiebe.start_deg", f"combustion start {start!r}; it must be finite")
    if not (np.isfinite(duration) and duration > 0.0):
        raise SceneError("gas.wiebe.duration_deg",
                         f"combustion duration {duration!r} rad; it must be finite and > 0")
    if not (np.isfinite(a) and a > 0.0):
        raise SceneError("gas.wiebe.a", f"a = {a!r}; the Wiebe efficiency parameter must be > 0 "
                                        "(6.908 burns 99.9 %)")
    if not (np.isfinite(m) and m > -1.0):
        raise SceneError("gas.wiebe.m", f"m = {m!r}; the Wiebe shape exponent must be > -1")


def _fraction_y(y: NDArray[np.float64], a: float, m: float) -> NDArray[np.float64]:
    """Burned fraction at the normalised angle ``y = (x - start)/duration``."""
    yc = np.clip(y, 0.0, 1.0)
    # expm1 keeps the small fractions just after the start to full relative precision.
    return -np.expm1(-a * yc ** (m + 1.0))


def _rate_y(y: NDArray[np.float64], a: float, m: float) -> NDArray[np.float64]:
    """``dx_b/dy`` at the normalised angle y, with the in-combustion formula on [0, 1]."""
    yc = np.clip(y, 0.0, 1.0)
    with np.errstate(divide="ignore"):
        r = a * (m + 1.0) * yc ** m * np.exp(-a * yc ** (m + 1.0))
    return np.where((y < 0.0) | (y > 1.0), 0.0, r)


def _rate_scalar(y: float, a: float, m: float) -> float:
    """:func:`_rate_y` for one float (the ODE right-hand side)."""
    if y < 0.0 or y > 1.0:
        return 0.0
    return a * (m + 1.0) * y ** m * math.exp(-a * y ** (m + 1.0))


def wiebe_fraction(x: ArrayLike, start: float, duration: float, a: float = DEFAULT_A,
                   m: float = DEFAULT_M) -> NDArray[np.float64]:
    """Wiebe burned mass fraction.

    ``x_b = 1 - exp(-a·((x - start)/duration)**(m + 1))`` on ``[start, start + duration]``,
    0 before and ``1 - exp(-a)`` after: with this convention the combustion "ends" with the
    fraction ``1 - exp(-a)`` burned (0.999 for a = 6.908), not 1, and the fraction stays there.

    Parameters
    ----------
    x : array_like
        Crank angles [rad] (not wrapped into a cycle).
    start : float
        Start of combustion [rad].
    duration : float
        Combustion duration [rad], > 0.
    a : float
        Efficiency parameter, > 0.
    m : float
        Shape exponent, > -1.

    Returns
    -------
    NDArray[np.float64]
        Burned fraction, shaped like `x`, in [0, 1 - exp(-a)].

    Raises
    ------
    SceneError
        ``gas.wiebe.start_deg``, ``gas.wiebe.duration_deg``, ``gas.wiebe.a``, ``gas.wiebe.m``.
    """
    start, duration, a, m = float(start), float(duration), float(a), float(m)
    _check_wiebe(start, duration, a, m)
    y = (np.asarray(x, dtype=np.float64) - start) / duration
    return _fraction_y(y, a, m)


def wiebe_rate(x: ArrayLike, start: float, duration: float, a: float = DEFAULT_A,
               m: float = DEFAULT_M) -> NDArray[np.float64]:
    """Derivative ``dx_b/dx`` of :func:`wiebe_fraction` [1/rad].

    ``a(m + 1)/duration · y**m · exp(-a y**(m + 1))`` with ``y = (x - start)/duration`` on the
    closed interval ``[start, start + duration]`` (at its ends, the one-sided derivative from
    inside the combustion: at the start 0 for m > 0, ``a/duration`` for m = 0 and +inf for
    m < 0), 0 outside.

    Parameters and errors as :func:`wiebe_fraction`.
    """
    start, duration, a, m = float(start), float(duration), float(a), float(m)
    _check_wiebe(start, duration, a, m)
    y = (np.asarray(x, dtype=np.float64) - start) / duration
    return _rate_y(y, a, m) / duration


# ----------------------------------------------------------------------------------------
# The closed part: first-law integration
# ----------------------------------------------------------------------------------------

def _volume_derivative(volume: VolumeFunction) -> VolumeFunction:
    """dV/dx by an 8th-order central difference (h = 2**-8 rad) through one vectorised call.

    For a crank-slider volume the truncation error is below 1e-18 of V and the rounding error
    about 1e-13 of V (``tests/validation/test_wiebe_cycle.py`` compares with the closed form).
    """
    h = 2.0 ** -8
    offsets = h * np.array([-4.0, -3.0, -2.0, -1.0, 1.0, 2.0, 3.0, 4.0])
    weights = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 4 / 5, -1 / 5, 4 / 105, -1 / 280]) / h

    def dvolume(x: NDArray[np.float64]) -> NDArray[np.float64]:
        x = np.asarray(x, dtype=np.float64)
        v = np.asarray(volume((x[..., None] + offsets).ravel()), dtype=np.float64)
        return v.reshape(x.shape + (8,)) @ weights

    return dvolume


@dataclass(frozen=True, eq=False)
class _Segment:
    """One integration segment [lo, hi] of the closed part and its dense solution.

    Inside a Wiebe combustion with m < 0 the heat-release rate is infinite at the start, so the
    segment is integrated in ``u = y**(m + 1)`` (``y = (x - lo)/(hi - lo)``), where
    ``dx_b/du = a·exp(-a u)`` is smooth; otherwise ``u = x``.
    """

    lo: float
    hi: float
    power: float | None  # m + 1 when integrated in u, else None
    sol: object          # scipy OdeSolution with components (p, W)

    def u_of_x(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        x = np.clip(x, self.lo, self.hi)
        if self.power is None:
            return x
        return np.clip((x - self.lo) / (self.hi - self.lo), 0.0, 1.0) ** self.power

    def __call__(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """(p, W) at angles in [lo, hi], shape (2,) + x.shape."""
        x = np.asarray(x, dtype=np.float64)
        return np.asarray(self.sol(self.u_of_x(x).ravel())).reshape((2,) + x.shape)


@dataclass(frozen=True, eq=False)
class ClosedPart:
    """Dense solution of the closed part, independent of the table.

    Angles here run continuously from `start` (intake closing) to `end` (exhaust opening); for a
    2-stroke the part after the firing TDC is at ``x + 2π`` (so ``end > 2π``).

    Attributes
    ----------
    start, end : float
        Intake closing and exhaust opening [rad], unwrapped.
    breaks : NDArray[np.float64]
        Segment ends [rad]: start, combustion start and end (when they differ from the part's
        ends), end.
    segments : tuple
        One dense solution per segment.
    p_a, v_a, t_a : float
        State at intake closing [Pa, m³, K].
    """

    start: float
    end: float
    breaks: NDArray[np.float64]
    segments: tuple
    p_a: float
    v_a: float
    t_a: float

    def __call__(self, x: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pressure [Pa] and work ``W(x) = ∫ p dV`` from intake closing to x [J].

        Parameters
        ----------
        x : array_like
            Unwrapped angles in [start, end] [rad]; at a segment end, the segment that starts
            there is used (the solution is continuous, so either side agrees).
        """
        x = np.asarray(x, dtype=np.float64)
        if np.any((x < self.start - 1e-12) | (x > self.end + 1e-12)):
            raise ValueError(f"angles must lie in the closed part [{_deg(self.start)}, "
                             f"{_deg(self.end)}]")
        k = np.clip(np.searchsorted(self.breaks, x, side="right") - 1, 0, len(self.segments) - 1)
        p = np.empty(x.shape)
        w = np.empty(x.shape)
        for j, seg in enumerate(self.segments):
            sel = k == j
            if np.any(sel):
                pw = seg(x[sel])
                p[sel], w[sel] = pw[0], pw[1]
        return p, w

    def temperature(self, p: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
        """Gas temperature [K] from pressure [Pa] and volume [m³]: ``T_a·pV/(p_a V_a)``."""
        return self.t_a * np.asarray(p) * np.asarray(v) / (self.p_a * self.v_a)


@dataclass(frozen=True, eq=False)
class WiebeCycle(PressureTable):
    """Pressure table of a single-zone Wiebe cycle, with what the integration found.

    A :class:`~transient.forces.gas.PressureTable` (use it wherever one is expected). Angles are
    table angles in [0, period) [rad] unless said otherwise.

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

    work: float
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

    @property
    def mean_torque(self) -> float:
        """Mean indicated torque of one cylinder [N·m]: the loop work per shaft angle of a cycle."""
        return self.work / self.period

    @property
    def mean_pressure(self) -> float:
        """Mean indicated pressure [Pa]: the loop work over the swept volume :attr:`v_h`."""
        return self.work / self.v_h


def _scalar(volume: VolumeFunction, x: float) -> float:
    return float(np.asarray(volume(np.array([x], dtype=np.float64)), dtype=np.float64).ravel()[0])


def _check_positive(key: str, value: float | None, what: str) -> float:
    if value is None or not (np.isfinite(value) and value > 0.0):
        raise SceneError(key, f"{value!r}; {what} must be finite and > 0")
    return float(value)


@dataclass(frozen=True)
class _Setup:
    """Validated inputs of one cycle (everything but the fuel mass)."""

    strokes: int
    period: float
    ivc: float           # intake closing, table angle
    evo: float           # exhaust opening, unwrapped (> 2π for a 2-stroke)
    evo_table: float     # exhaust opening, table angle (as given)
    start: float         # combustion start, unwrapped, in [ivc, evo)
    duration: float
    a: float
    m: float
    lhv: float
    efficiency: float
    gamma: float
    gamma_slope: float
    gamma_t_ref: float
    t_a: float
    p_a: float
    p_intake: float
    p_exhaust: float
    step: float
    rtol: float


def _setup(*, strokes, p_a, start, duration, a, m, lhv, efficiency, gamma, gamma_slope,
           gamma_t_ref, t_a, p_intake, p_exhaust, intake_closing, exhaust_opening, step,
           rtol) -> _Setup:
    if strokes not in (2, 4):
        raise SceneError("gas.strokes", f"strokes = {strokes!r}; use 4 or 2")
    period = 2.0 * math.pi * strokes / 2.0
    p_a = _check_positive("gas.p_a", p_a, "the absolute pressure at intake closing")
    if strokes == 4:
        for key, value in (("gas.p_intake", p_intake), ("gas.p_exhaust", p_exhaust)):
            if value is None or not (np.isfinite(value) and value >= 0.0):
                raise SceneError(key, f"{value!r} Pa; a 4-stroke needs an absolute pressure ≥ 0")
        p_intake, p_exhaust = float(p_intake), float(p_exhaust)
    else:
        p_intake = p_exhaust = float("nan")
    start, duration, a, m = float(start), float(duration), float(a), float(m)
    _check_wiebe(start, duration, a, m)
    lhv = _check_positive("gas.wiebe.lhv", lhv, "the lower heating value [J/kg]")
    if not (np.isfinite(efficiency) and 0.0 < efficiency <= 1.0):
        raise SceneError("gas.wiebe.efficiency",
                         f"{efficiency!r}; the combustion efficiency must be in (0, 1]")
    if not (np.isfinite(gamma) and gamma > 1.0):
        raise SceneError("gas.wiebe.gamma", f"γ = {gamma!r}; the heat capacity ratio must be > 1")
    if not np.isfinite(gamma_slope):
        raise SceneError("gas.wiebe.gamma_slope", f"{gamma_slope!r} 1/K; it must be finite")
    gamma_t_ref = _check_positive("gas.wiebe.gamma_t_ref", gamma_t_ref,
                                  "the reference temperature of γ(T) [K]")
    t_a = _check_positive("gas.wiebe.t_a", t_a, "the temperature at intake closing [K]")
    # dT/dx ∝ γ(T) - 1 in this model, so a temperature where γ = 1 is never crossed: γ > 1 at
    # intake closing keeps it > 1 over the whole cycle.
    g_a = gamma + gamma_slope * (t_a - gamma_t_ref)
    if not g_a > 1.0:
        raise SceneError("gas.wiebe.gamma_slope",
                         f"γ(T) = {gamma:g} + {gamma_slope:g}·(T - {gamma_t_ref:g} K) is {g_a:.4g} "
                         f"at intake closing (T_a = {t_a:g} K); it must be > 1 there")
    if not (np.isfinite(step) and step > 0.0):
        raise SceneError("gas.wiebe.step_deg", f"knot spacing {step!r} rad; it must be > 0")
    if not (np.isfinite(rtol) and 1e-14 <= rtol <= 1e-6):
        raise ValueError(f"rtol must be in [1e-14, 1e-6], got {rtol!r}")
    tol = _ANGLE_TOL * period

    # Intake closing and exhaust opening (table angles); defaults: the BDCs around firing TDC.
    ivc = math.pi if intake_closing is None else float(intake_closing)
    evo = math.pi if strokes == 2 else 3.0 * math.pi
    evo = evo if exhaust_opening is None else float(exhaust_opening)
    for key, value in (("gas.wiebe.intake_closing_deg", ivc),
                       ("gas.wiebe.exhaust_opening_deg", evo)):
        if not np.isfinite(value):
            raise SceneError(key, f"{value!r}; the angle must be finite")
    if strokes == 4:
        if not (tol < ivc < 2.0 * math.pi - tol):
            raise SceneError("gas.wiebe.intake_closing_deg",
                             f"intake closes at {_deg(ivc)}; it must be after 0° (gas-exchange "
                             "TDC) and before 360° (firing TDC)")
        if not (2.0 * math.pi + tol < evo < period - tol):
            raise SceneError("gas.wiebe.exhaust_opening_deg",
                             f"exhaust opens at {_deg(evo)}; it must be after 360° (firing TDC) "
                             "and before 720°")
    else:
        if not (tol < ivc < period - tol):
            raise SceneError("gas.wiebe.intake_closing_deg",
                             f"ports close at {_deg(ivc)}; it must be inside (0°, 360°), "
                             "0° being the firing TDC")
        if not (tol < evo < period - tol) or evo > ivc + tol:
            raise SceneError("gas.wiebe.exhaust_opening_deg",
                             f"exhaust opens at {_deg(evo)}; it must be inside (0°, 360°) and not "
                             f"after the port closing at {_deg(ivc)}")
        if abs(evo - ivc) <= tol:
            evo = ivc
    evo_table = evo
    if strokes == 2:
        evo += period  # the closed part runs through the firing TDC at 2π ≡ 0

    # Combustion start: moved by whole periods into [ivc, ivc + period) (a 2-stroke start of
    # -2° means 358°); it and the end must lie inside the closed part.
    s = start
    while s < ivc - tol:
        s += period
    while s >= ivc + period - tol:
        s -= period
    if abs(s - ivc) <= tol:
        s = ivc
    if s >= evo:
        raise SceneError("gas.wiebe.start_deg",
                         f"combustion starts at {_deg(start)}, outside the closed part from "
                         f"{_deg(ivc)} (intake closing) to {_deg(evo % period)} (exhaust "
                         "opening); it must start inside it")
    end = s + duration
    if abs(end - evo) <= tol:
        end = evo
    if end > evo:
        raise SceneError("gas.wiebe.duration_deg",
                         f"combustion from {_deg(s % period)} for {_deg(duration)} ends at "
                         f"{_deg(end % period)}, after the exhaust opening at "
                         f"{_deg(evo % period)}; it must end inside the closed part")
    return _Setup(strokes=strokes, period=period, ivc=ivc, evo=evo, evo_table=evo_table, start=s,
                  duration=end - s, a=a, m=m, lhv=lhv, efficiency=float(efficiency),
                  gamma=float(gamma), gamma_slope=float(gamma_slope), gamma_t_ref=gamma_t_ref,
                  t_a=t_a, p_a=p_a, p_intake=p_intake, p_exhaust=p_exhaust, step=float(step),
                  rtol=float(rtol))


def _integrate(st: _Setup, fuel_mass: float, volume: VolumeFunction,
               dvolume: VolumeFunction) -> ClosedPart:
    """Integrate (p, W) over the closed part, segment by segment, with DOP853."""
    period = st.period

    def wrap(x: float) -> float:
        # The closed part of a 2-stroke runs past 2π; the volume is asked at table angles.
        return x - period if x > period else x

    v_a = _scalar(volume, st.ivc)
    q_total = fuel_mass * st.lhv * st.efficiency
    t_scale = st.t_a / (st.p_a * v_a)   # T = t_scale·p·V
    g0, gk, tref = st.gamma, st.gamma_slope, st.gamma_t_ref

    def vol(x: float) -> tuple[float, float]:
        xw = np.array([wrap(x)])
        return float(np.asarray(volume(xw)).ravel()[0]), float(np.asarray(dvolume(xw)).ravel()[0])

    def segment_rhs(lo, hi, burning, power):
        def rhs(u, y):
            if power is None:
                x, dxdu = u, 1.0
                dq = q_total * _rate_scalar((x - st.start) / st.duration, st.a,
                                            st.m) / st.duration if burning else 0.0
            else:
                # x = lo + (hi - lo)·u**(1/power); dx_b/du = a·exp(-a u).
                uc = min(max(u, 0.0), 1.0)
                k = 1.0 / power
                x = lo + (hi - lo) * uc ** k
                dxdu = (hi - lo) * k * uc ** (k - 1.0)
                dq = q_total * st.a * math.exp(-st.a * uc)
            v, dv = vol(x)
            p = y[0]
            g = g0 + gk * (t_scale * p * v - tref) if gk != 0.0 else g0
            dvdu = dv * dxdu
            return [(g - 1.0) / v * dq - g * p / v * dvdu, p * dvdu]

        return rhs

    atol = np.array([1e-3 * st.rtol * st.p_a, 1e-3 * st.rtol * st.p_a * v_a])
    breaks, segments = closed_segments(st, q_total, segment_rhs, np.array([st.p_a, 0.0]), atol,
                                       _Segment)
    return ClosedPart(start=st.ivc, end=st.evo, breaks=breaks, segments=tuple(segments),
                      p_a=st.p_a, v_a=v_a, t_a=st.t_a)


def closed_segments(st: _Setup, q_total: float, segment_rhs, y0: NDArray[np.float64],
                    atol: NDArray[np.float64], segment_type) -> tuple[NDArray[np.float64], list]:
    """The closed part integrated with DOP853 segment by segment, from intake closing to exhaust
    opening, split at the combustion start and end so that the right-hand side is smooth inside
    every segment; y[0] is the pressure. Inside a combustion with m < 0 a segment is integrated
    in the variable u = y**(m + 1) on [0, 1] (``power`` = m + 1; its right-hand side maps u to
    the angle), else in the angle itself (``power`` None).

    ``segment_rhs(lo, hi, burning, power)`` gives f(u, y) of the segment [lo, hi]; ``burning``:
    fuel burns over it. Returns the breaks and one ``segment_type(lo, hi, power, sol)`` per
    segment (``sol``: the dense solution in u). The pressure carried into the next segment is
    clipped at 0 (a rounding below it)."""
    # scipy is imported where it is used: a cycle read from the table cache
    # (:mod:`transient.forces.wiebe_cache`) must not pay for importing its integrators.
    from scipy.integrate import solve_ivp

    end = st.start + st.duration
    breaks = [st.ivc]
    for b in (st.start, end, st.evo):
        if b > breaks[-1]:
            breaks.append(b)
    breaks = np.array(breaks)
    segments = []
    for lo, hi in itertools.pairwise(breaks):
        burning = q_total > 0.0 and lo >= st.start and hi <= end
        power = st.m + 1.0 if burning and st.m < 0.0 else None
        u_lo, u_hi = (lo, hi) if power is None else (0.0, 1.0)
        sol = solve_ivp(segment_rhs(lo, hi, burning, power), (u_lo, u_hi), y0, method="DOP853",
                        rtol=st.rtol, atol=atol, dense_output=True)
        if sol.status != 0:
            raise RuntimeError(f"closed-cycle integration failed from {_deg(lo)} to {_deg(hi)}: "
                               f"{sol.message}")
        segments.append(segment_type(lo=float(lo), hi=float(hi), power=power, sol=sol.sol))
        y0 = sol.y[:, -1].copy()
        y0[0] = max(y0[0], 0.0)
    return breaks, segments


def _peak(closed: ClosedPart, volume: VolumeFunction, period: float
          ) -> tuple[float, float, float]:
    """Peak pressure, its unwrapped angle and the peak temperature over the closed part."""
    from scipy.optimize import brentq

    best_p, best_x = -1.0, closed.start
    t_max = 0.0
    for seg in closed.segments:
        x = np.linspace(seg.lo, seg.hi, 4001)
        p = seg(x)[0]
        xv = np.where(x > period, x - period, x)
        t_max = max(t_max, float(np.max(closed.temperature(p, np.asarray(volume(xv))))))
        i = int(np.argmax(p))
        xi, pi = float(x[i]), float(p[i])
        if 0 < i < x.size - 1:
            # Refine on the dense solution: the zero of its slope between the neighbours
            # (a central difference of the dense output, smooth inside the segment).
            def slope(z, seg=seg):
                h = 1e-6 * (seg.hi - seg.lo)
                z0, z1 = max(z - h, seg.lo), min(z + h, seg.hi)
                return float(np.diff(seg(np.array([z0, z1]))[0])[0]) / (z1 - z0)
            a_, b_ = float(x[i - 1]), float(x[i + 1])
            if slope(a_) > 0.0 > slope(b_):
                z = brentq(slope, a_, b_, xtol=1e-13, rtol=1e-15)
                pz = float(seg(np.array([z]))[0][0])
                if pz >= pi:
                    xi, pi = z, pz
        if pi > best_p:
            best_p, best_x = pi, xi
    return best_p, best_x, t_max


@dataclass(frozen=True, eq=False)
class _Solved:
    """One integrated cycle before tabulation: its pieces and scalars."""

    pieces: list            # (a, b, callable or float) in table angles, in order
    scale: float            # largest pressure of the cycle [Pa]
    fields: dict            # WiebeCycle fields other than the table's


def _solve(st: _Setup, fuel_mass: float, volume: VolumeFunction,
           dvolume: VolumeFunction) -> _Solved:
    """Integrate the closed part and describe the table pieces (not yet tabulated)."""
    period = st.period
    closed = _integrate(st, fuel_mass, volume, dvolume)

    def wrap(x: float) -> float:
        # Table angle of an unwrapped one; the exhaust opening exactly as given.
        return st.evo_table if x == st.evo else (x - period if x > period else x)

    # Table pieces (a, b, f) in table angles; a closed piece evaluates the dense solution at
    # the unwrapped angle x + shift.
    pieces: list[tuple[float, float, object]] = []

    def closed_piece(lo: float, hi: float, shift: float) -> None:
        k = int(np.clip(np.searchsorted(closed.breaks, 0.5 * (lo + hi) + shift, side="right") - 1,
                        0, len(closed.segments) - 1))

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
    v_b = _scalar(volume, wrap(st.evo))
    if st.strokes == 4:
        work = (closed_work + st.p_intake * (v_a - _scalar(volume, 0.0))
                + st.p_exhaust * (_scalar(volume, period) - v_b))
        v_c = _scalar(volume, 2.0 * math.pi)
    else:
        work = closed_work + st.p_a * (v_a - v_b)
        v_c = _scalar(volume, 0.0)
    p_max, x_max, t_max = _peak(closed, volume, period)
    end = st.start + st.duration
    if st.evo >= end:
        xb = float(-np.expm1(-st.a))
    else:
        xb = float(_fraction_y(np.array((st.evo - st.start) / st.duration), st.a, st.m))
    fields = {"work": work, "closed_work": closed_work, "p_max": p_max,
              "angle_max": wrap(x_max) % period, "t_max": t_max, "burned_fraction": xb,
              "heat_released": fuel_mass * st.lhv * st.efficiency * xb,
              "p_end": float(p_w_end[0][0]), "v_a": v_a, "v_b": v_b, "v_c": v_c,
              "v_h": _scalar(volume, math.pi) - v_c, "intake_closing": st.ivc,
              "exhaust_opening": st.evo_table, "combustion_start": wrap(st.start) % period,
              "combustion_end": wrap(end) % period, "fuel_mass": fuel_mass,
              "strokes": st.strokes, "closed": closed}
    scale = max(p_max, st.p_a, *(v for v in (st.p_intake, st.p_exhaust) if np.isfinite(v)))
    return _Solved(pieces=pieces, scale=scale, fields=fields)


def _spline_coef(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    """Ascending local cubic coefficients (n, 4) of the spline through (x, y).

    Not-a-knot, as :func:`~transient.forces.gas.table_from_function` (natural with 2 points,
    i.e. the straight line).
    """
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(x, y, bc_type="not-a-knot" if x.size > 2 else "natural")
    return np.ascontiguousarray(spline.c[::-1].T, dtype=np.float64)


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
        for _ in range(_MAX_REFINE):
            h = np.diff(x)
            xm = x[:-1] + 0.5 * h
            piece_coef, piece_err = [], []
            bad = np.zeros(h.size, dtype=bool)
            for s, f in zip(solved, funcs):
                c = _spline_coef(x, f(x))
                hm = 0.5 * h
                tm = c[:, 0] + hm * (c[:, 1] + hm * (c[:, 2] + hm * c[:, 3]))
                e = np.abs(tm - f(xm)) / s.scale
                piece_coef.append(c)
                piece_err.append(e)
                bad |= e > tolerance
            bad &= h > 2.0 * _MIN_SPACING
            if not np.any(bad):
                break
            x = np.sort(np.concatenate([x, xm[bad]]))
        knots.append(x)
        for i in range(n_cycles):
            coefs[i].append(piece_coef[i])
            errors[i] = max(errors[i], float(np.max(piece_err[i])))
    all_knots = np.concatenate([knots[0]] + [k[1:] for k in knots[1:]])
    piece_knot = np.concatenate([[0], np.cumsum([k.size - 1 for k in knots])]).astype(np.int64)
    return [(PressureTable(knots=all_knots, coef=np.vstack(coefs[i]), piece_knot=piece_knot,
                           period=period), float(errors[i])) for i in range(n_cycles)]


def _cycles(volume: VolumeFunction, fuel_levels: Sequence[float], *, p_a, start, duration, a,
            m, lhv, efficiency, gamma, gamma_slope, gamma_t_ref, t_a, p_intake, p_exhaust,
            strokes, intake_closing, exhaust_opening, dvolume, step, tolerance,
            rtol) -> tuple[WiebeCycle, ...]:
    """Validate, integrate and tabulate the cycles of `fuel_levels` on common knots."""
    st = _setup(strokes=strokes, p_a=p_a, start=start, duration=duration, a=a, m=m, lhv=lhv,
                efficiency=efficiency, gamma=gamma, gamma_slope=gamma_slope,
                gamma_t_ref=gamma_t_ref, t_a=t_a, p_intake=p_intake, p_exhaust=p_exhaust,
                intake_closing=intake_closing, exhaust_opening=exhaust_opening, step=step,
                rtol=rtol)
    if not (np.isfinite(tolerance) and 1e-13 <= tolerance <= 1e-3):
        raise SceneError("gas.wiebe.tolerance", f"{tolerance!r}; the relative tabulation "
                                                "tolerance must be in [1e-13, 1e-3]")
    _check_volume(st, volume)
    dvolume = dvolume or _volume_derivative(volume)
    solved = [_solve(st, float(q), volume, dvolume) for q in fuel_levels]
    tables = _tabulate(solved, st.period, st.step, float(tolerance))
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
    too). The work ∫p dV/dx dx is a second ODE component, so :attr:`WiebeCycle.work` does not
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
        Wiebe efficiency parameter (> 0) and shape exponent (> -1), see :func:`wiebe_fraction`.
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
    if fuel_mass is None or not (np.isfinite(fuel_mass) and fuel_mass >= 0.0):
        raise SceneError("gas.wiebe.fuel_mass",
                         f"{fuel_mass!r} kg; the fuel mass per cycle must be finite and ≥ 0")
    return _cycles(volume, [float(fuel_mass)], p_a=p_a, start=start, duration=duration, a=a,
                   m=m, lhv=lhv, efficiency=efficiency, gamma=gamma, gamma_slope=gamma_slope,
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
        (:func:`transient.assemble.wiebe_levels`), always valid ones.
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


def _check_volume(st: _Setup, volume: VolumeFunction) -> None:
    """The volume must be finite and > 0 over the closed part."""
    x = np.linspace(st.ivc, st.evo, 721)
    x = np.where(x > st.period, x - st.period, x)
    v = np.asarray(volume(x), dtype=np.float64)
    if v.shape != x.shape or not np.all(np.isfinite(v) & (v > 0.0)):
        raise SceneError("gas.compression_ratio",
                         "the cylinder volume is not finite and > 0 over the closed part "
                         f"{_deg(st.ivc)} to {_deg(st.evo % st.period)}; check the geometry")
