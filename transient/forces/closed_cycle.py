"""The closed part of a cycle — compression, combustion, expansion — as one ideal-gas zone (one
idea: that zone's first law, integrated, and what is read from its solution).

Shared by the tabulated Wiebe cycle (:mod:`transient.forces.wiebe`) and the cycle with Woschni
wall heat transfer (:mod:`transient.forces.woschni`): from intake closing (IVC, p = p_a) to
exhaust opening (EVO) the pressure solves the first law

    dp/dx = (γ(T) - 1)/V · (dQ_b/dx - dQ_w/dx) - γ(T) p/V · dV/dx,
    dQ_b/dx = m_f · LHV · η_c · dx_b/dx,       γ(T) = gamma + gamma_slope·(T - gamma_t_ref),

where ``x_b`` is the Wiebe burned fraction (:func:`wiebe_fraction`) and ``dQ_w/dx`` the heat lost
to the walls per crank angle (0 for the Wiebe tables; the Woschni model supplies it). The form is
exact also for a temperature-dependent γ, because ``U = ∫ m c_v dT`` with ``c_v = R/(γ(T) - 1)``.
:func:`integrate_closed` integrates (p, W = ∫p dV[, Q_w]) with DOP853, split at the combustion
start and end, where the heat-release rate has kinks.

Angles are local crank angles in radians: a 4-stroke has 0 at the gas-exchange TDC and 2π at the
firing TDC; a 2-stroke has its firing TDC at 0, and its closed part runs through 2π ≡ 0, so it is
integrated in unwrapped angles past 2π. Pressures absolute in Pa, volumes in m³, energies in J,
temperatures in K.

What is not modelled
--------------------
* **Mass change.** The trapped mass is fixed at intake closing; the fuel mass added (about 3 % of
  the charge) and blow-by are neglected, and the gas constant is the same before and after
  combustion. The temperature ``T = T_a·pV/(p_a V_a)`` follows from ``pV = m R T``.
* Injection, ignition delay and dissociation.
"""
from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from transient.errors import SceneError
from transient.forces.gas import (
    ANGLE_TOL,
    VolumeFunction,
    cycle_period,
    deg_text,
    gas_exchange_pressures,
    volume_at,
)

if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

__all__ = [
    "DEFAULT_A",
    "DEFAULT_M",
    "DEFAULT_RTOL",
    "ClosedPart",
    "CycleSetup",
    "Segment",
    "SegmentLoss",
    "burned_fraction",
    "check_fuel_mass",
    "check_volume",
    "first_law_rate",
    "gamma_at",
    "integrate_closed",
    "peak",
    "setup_cycle",
    "volume_derivative",
    "wiebe_fraction",
    "wiebe_rate",
    "wiebe_rate_y",
]

#: Wiebe efficiency parameter: ``1 - exp(-6.908) = 0.999`` of the fuel has burned at the end of
#: the combustion duration (Vibe's usual choice).
DEFAULT_A = 6.908

#: Wiebe shape exponent: a typical single-Wiebe diesel value (fits of direct-injection diesels
#: are usually quoted below 1, spark ignition near 2); set it from a measured heat release.
DEFAULT_M = 0.5

#: Default relative tolerance of the closed-part integration (DOP853).
DEFAULT_RTOL = 1e-12

#: dQ_w/dx [J/rad] lost to the walls at (x, p, V) on one segment.
SegmentLoss = Callable[[float, float, float], float]


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


def wiebe_rate_y(y: float, a: float, m: float) -> float:
    """``dx_b/dy`` at one normalised angle ``y = (x - start)/duration``, 0 outside [0, 1].

    Floats and ``math`` only, because it is evaluated in the ODE right-hand sides (and has a
    compiled twin); the parameters are not checked.
    """
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
# Scalar physics (floats in, float out; math only, for a compiled twin)
# ----------------------------------------------------------------------------------------

def gamma_at(t: float, gamma: float, gamma_slope: float, gamma_t_ref: float) -> float:
    """γ(T) = gamma + gamma_slope·(T - gamma_t_ref); `gamma` itself for a zero slope, so that a
    constant γ does not depend on the temperature's rounding."""
    return gamma + gamma_slope * (t - gamma_t_ref) if gamma_slope != 0.0 else gamma


def first_law_rate(p: float, v: float, dv: float, dq_b: float, dq_w: float, g: float) -> float:
    """dp per unit of the independent variable, first law of one ideal-gas zone.

    ``(γ - 1)/V·(dQ_b - dQ_w) - γ·p/V·dV`` with every increment (dv [m³], dq_b released, dq_w
    lost to the walls [J]) per unit of the same variable (x, or u inside a Wiebe combustion
    with m < 0); g = γ(T).
    """
    return (g - 1.0) / v * (dq_b - dq_w) - g * p / v * dv


# ----------------------------------------------------------------------------------------
# Inputs
# ----------------------------------------------------------------------------------------

def volume_derivative(volume: VolumeFunction) -> VolumeFunction:
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


def check_fuel_mass(fuel_mass: float | None) -> float:
    """The fuel mass per cycle [kg] as a float; a SceneError unless finite and ≥ 0."""
    if fuel_mass is None or not (np.isfinite(fuel_mass) and fuel_mass >= 0.0):
        raise SceneError("gas.wiebe.fuel_mass",
                         f"{fuel_mass!r} kg; the fuel mass per cycle must be finite and ≥ 0")
    return float(fuel_mass)


def _check_positive(key: str, value: float | None, what: str) -> float:
    if value is None or not (np.isfinite(value) and value > 0.0):
        raise SceneError(key, f"{value!r}; {what} must be finite and > 0")
    return float(value)


@dataclass(frozen=True)
class CycleSetup:
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
    rtol: float

    @property
    def gamma_a(self) -> float:
        """γ(T_a), at intake closing."""
        return self.gamma + self.gamma_slope * (self.t_a - self.gamma_t_ref)


def setup_cycle(*, strokes, p_a, start, duration, a, m, lhv, efficiency, gamma, gamma_slope,
                gamma_t_ref, t_a, p_intake, p_exhaust, intake_closing, exhaust_opening,
                rtol) -> CycleSetup:
    """Validate the cycle's inputs and place its events (see ``wiebe_cycle`` for their rules).

    Raises
    ------
    SceneError
        ``gas.strokes``, ``gas.p_a``, ``gas.p_intake``, ``gas.p_exhaust`` (4-stroke),
        ``gas.wiebe.*`` of the combustion, the gas and the intake and exhaust angles.
    ValueError
        `rtol` outside [1e-14, 1e-6].
    """
    period = cycle_period(strokes)
    p_a = _check_positive("gas.p_a", p_a, "the absolute pressure at intake closing")
    p_intake, p_exhaust = gas_exchange_pressures(strokes, p_intake, p_exhaust)
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
    if not (np.isfinite(rtol) and 1e-14 <= rtol <= 1e-6):
        raise ValueError(f"rtol must be in [1e-14, 1e-6], got {rtol!r}")
    tol = ANGLE_TOL * period

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
                             f"intake closes at {deg_text(ivc)}; it must be after 0° (gas-exchange "
                             "TDC) and before 360° (firing TDC)")
        if not (2.0 * math.pi + tol < evo < period - tol):
            raise SceneError("gas.wiebe.exhaust_opening_deg",
                             f"exhaust opens at {deg_text(evo)}; it must be after 360° (firing "
                             "TDC) and before 720°")
    else:
        if not (tol < ivc < period - tol):
            raise SceneError("gas.wiebe.intake_closing_deg",
                             f"ports close at {deg_text(ivc)}; it must be inside (0°, 360°), "
                             "0° being the firing TDC")
        if not (tol < evo < period - tol) or evo > ivc + tol:
            raise SceneError("gas.wiebe.exhaust_opening_deg",
                             f"exhaust opens at {deg_text(evo)}; it must be inside (0°, 360°) and "
                             f"not after the port closing at {deg_text(ivc)}")
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
                         f"combustion starts at {deg_text(start)}, outside the closed part from "
                         f"{deg_text(ivc)} (intake closing) to {deg_text(evo % period)} (exhaust "
                         "opening); it must start inside it")
    end = s + duration
    if abs(end - evo) <= tol:
        end = evo
    if end > evo:
        raise SceneError("gas.wiebe.duration_deg",
                         f"combustion from {deg_text(s % period)} for {deg_text(duration)} ends at "
                         f"{deg_text(end % period)}, after the exhaust opening at "
                         f"{deg_text(evo % period)}; it must end inside the closed part")
    return CycleSetup(strokes=strokes, period=period, ivc=ivc, evo=evo, evo_table=evo_table,
                      start=s, duration=end - s, a=a, m=m, lhv=lhv, efficiency=float(efficiency),
                      gamma=float(gamma), gamma_slope=float(gamma_slope),
                      gamma_t_ref=gamma_t_ref, t_a=t_a, p_a=p_a, p_intake=p_intake,
                      p_exhaust=p_exhaust, rtol=float(rtol))


def check_volume(st: CycleSetup, volume: VolumeFunction) -> None:
    """The volume must be finite and > 0 over the closed part."""
    x = np.linspace(st.ivc, st.evo, 721)
    x = np.where(x > st.period, x - st.period, x)
    v = np.asarray(volume(x), dtype=np.float64)
    if v.shape != x.shape or not np.all(np.isfinite(v) & (v > 0.0)):
        raise SceneError("gas.compression_ratio",
                         "the cylinder volume is not finite and > 0 over the closed part "
                         f"{deg_text(st.ivc)} to {deg_text(st.evo % st.period)}; check the "
                         "geometry")


# ----------------------------------------------------------------------------------------
# The dense solution
# ----------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Segment:
    """One integration segment [lo, hi] of the closed part and its dense solution.

    Inside a Wiebe combustion with m < 0 the heat-release rate is infinite at the start, so the
    segment is integrated in ``u = y**(m + 1)`` (``y = (x - lo)/(hi - lo)``), where
    ``dx_b/du = a·exp(-a u)`` is smooth; otherwise ``u = x``.
    """

    lo: float
    hi: float
    power: float | None  # m + 1 when integrated in u, else None
    sol: OdeSolution     # with the components (p, W[, Q_w])
    size: int            # number of components

    def u_of_x(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        x = np.clip(x, self.lo, self.hi)
        if self.power is None:
            return x
        return np.clip((x - self.lo) / (self.hi - self.lo), 0.0, 1.0) ** self.power

    def __call__(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """The components at angles in [lo, hi], shape (size,) + x.shape."""
        x = np.asarray(x, dtype=np.float64)
        return np.asarray(self.sol(self.u_of_x(x).ravel())).reshape((self.size,) + x.shape)


@dataclass(frozen=True, eq=False)
class ClosedPart:
    """Dense solution of the closed part.

    Angles here run continuously from `start` (intake closing) to `end` (exhaust opening); for a
    2-stroke the part after the firing TDC is at ``x + 2π`` (so ``end > 2π``).

    Attributes
    ----------
    start, end : float
        Intake closing and exhaust opening [rad], unwrapped.
    breaks : NDArray[np.float64]
        Segment ends [rad]: start, combustion start and end (when they differ from the part's
        ends), end.
    segments : tuple of Segment
        One dense solution per segment, components (p, W) or, with wall heat transfer,
        (p, W, Q_w).
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

    def state(self, x: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """Pressure [Pa], work ``W(x) = ∫ p dV`` [J] and, with wall heat transfer, heat lost
        ``Q_w(x) = ∫ Q̇_w/ω dx`` [J] from intake closing to the unwrapped angles x in
        [start, end] [rad] (at a segment end, the segment that starts there: the solution is
        continuous, so either side agrees)."""
        x = np.asarray(x, dtype=np.float64)
        if np.any((x < self.start - 1e-12) | (x > self.end + 1e-12)):
            raise ValueError(f"angles must lie in the closed part [{deg_text(self.start)}, "
                             f"{deg_text(self.end)}]")
        k = self.segment_index(x)
        out = np.empty((self.segments[0].size,) + x.shape)
        for j, seg in enumerate(self.segments):
            sel = k == j
            if np.any(sel):
                out[:, sel] = seg(x[sel])
        return tuple(out)

    def segment_index(self, x: ArrayLike) -> NDArray[np.int64]:
        """Index of the segment holding each unwrapped angle x [rad] (at a segment end, the one
        that starts there; before the first and past the last, those)."""
        return np.clip(np.searchsorted(self.breaks, x, side="right") - 1, 0,
                       len(self.segments) - 1)

    def __call__(self, x: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pressure [Pa] and work ``W(x) = ∫ p dV`` from intake closing to x [J] (as
        :meth:`state`)."""
        p, w = self.state(x)[:2]
        return p, w

    def temperature(self, p: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
        """Gas temperature [K] from pressure [Pa] and volume [m³]: ``T_a·pV/(p_a V_a)``, in the
        order of operations of the integration's γ(T)."""
        return self.t_a / (self.p_a * self.v_a) * np.asarray(p) * np.asarray(v)


# ----------------------------------------------------------------------------------------
# The integration
# ----------------------------------------------------------------------------------------

def integrate_closed(st: CycleSetup, fuel_mass: float, volume: VolumeFunction,
                     dvolume: VolumeFunction,
                     wall_loss: Callable[[float], SegmentLoss] | None = None) -> ClosedPart:
    """Integrate the closed part with DOP853, segment by segment, from intake closing to exhaust
    opening.

    The segments end at the combustion start and end, so that the right-hand side is smooth
    inside each one. Inside a combustion with m < 0 a segment is integrated in the variable
    u = y**(m + 1) on [0, 1], where the Wiebe rate in x (∝ y**m, infinite at the start) becomes
    ``dx_b/du = a·exp(-a u)``; elsewhere in the angle itself.

    Parameters
    ----------
    st : CycleSetup
    fuel_mass : float
        Fuel mass of the cycle [kg], ≥ 0.
    volume, dvolume : callable
        Vectorised V(x) [m³] and dV/dx [m³/rad] at table angles.
    wall_loss : callable, optional
        ``wall_loss(lo)`` gives the heat loss ``loss(x, p, v)`` [J/rad] of the segment starting
        at `lo` (the Woschni model switches its combustion term there). Without it the
        components are (p, W); with it (p, W, Q_w), Q_w = ∫ loss dx — a third component changes
        the step control, so it is there only when asked for.

    Returns
    -------
    ClosedPart
        The pressure carried into the next segment is clipped at 0 (a rounding below it).
    """
    # scipy is imported where it is used: a cycle read from the table cache
    # (:mod:`transient.forces.wiebe_cache`) must not pay for importing its integrators.
    from scipy.integrate import solve_ivp

    period = st.period

    def wrap(x: float) -> float:
        # The closed part of a 2-stroke runs past 2π; the volume is asked at table angles.
        return x - period if x > period else x

    v_a = volume_at(volume, st.ivc)
    q_total = fuel_mass * st.lhv * st.efficiency
    t_scale = st.t_a / (st.p_a * v_a)   # T = t_scale·p·V
    end = st.start + st.duration

    def vol(x: float) -> tuple[float, float]:
        xw = np.array([wrap(x)])
        return float(np.asarray(volume(xw)).ravel()[0]), float(np.asarray(dvolume(xw)).ravel()[0])

    def segment_rhs(lo: float, hi: float, burning: bool, power: float | None):
        loss = None if wall_loss is None else wall_loss(lo)

        def rhs(u, y):
            if power is None:
                x, dxdu = u, 1.0
                dq = q_total * wiebe_rate_y((x - st.start) / st.duration, st.a,
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
            g = gamma_at(t_scale * p * v, st.gamma, st.gamma_slope, st.gamma_t_ref)
            dvdu = dv * dxdu
            if loss is None:
                return [first_law_rate(p, v, dvdu, dq, 0.0, g), p * dvdu]
            dq_w = loss(x, p, v) * dxdu
            return [first_law_rate(p, v, dvdu, dq, dq_w, g), p * dvdu, dq_w]

        return rhs

    size = 2 if wall_loss is None else 3
    scale = 1e-3 * st.rtol
    atol = np.array([scale * st.p_a] + [scale * st.p_a * v_a] * (size - 1))
    y0 = np.array([st.p_a] + [0.0] * (size - 1))
    ends = [st.ivc]
    for b in (st.start, end, st.evo):
        if b > ends[-1]:
            ends.append(b)
    breaks = np.array(ends)
    segments = []
    for lo, hi in itertools.pairwise(breaks):
        burning = q_total > 0.0 and lo >= st.start and hi <= end
        power = st.m + 1.0 if burning and st.m < 0.0 else None
        u_lo, u_hi = (lo, hi) if power is None else (0.0, 1.0)
        with np.errstate(all="ignore"):  # (a failure is said below, in one line)
            sol = solve_ivp(segment_rhs(lo, hi, burning, power), (u_lo, u_hi), y0,
                            method="DOP853", rtol=st.rtol, atol=atol, dense_output=True)
        if sol.status != 0 or not np.all(np.isfinite(sol.y[:, -1])):
            # Physical inputs give a smooth solution: this is a magnitude that none has.
            raise SceneError("gas.wiebe", f"the cycle's pressure cannot be integrated from "
                                          f"{deg_text(lo)} to {deg_text(hi)} ({sol.message}): "
                                          f"its inputs give no physical gas; check fuel_mass, "
                                          f"lhv, m, gamma, gamma_slope and p_a, and their units")
        segments.append(Segment(lo=float(lo), hi=float(hi), power=power, sol=sol.sol, size=size))
        y0 = sol.y[:, -1].copy()
        y0[0] = max(y0[0], 0.0)
    return ClosedPart(start=st.ivc, end=st.evo, breaks=breaks, segments=tuple(segments),
                      p_a=st.p_a, v_a=v_a, t_a=st.t_a)


# ----------------------------------------------------------------------------------------
# What the solution gives
# ----------------------------------------------------------------------------------------

def peak(closed: ClosedPart, volume: VolumeFunction, period: float
         ) -> tuple[float, float, float]:
    """Peak pressure [Pa], its unwrapped angle [rad] and the peak temperature [K] over the closed
    part (the temperature on a 4001-point scan of every segment)."""
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


def burned_fraction(st: CycleSetup) -> float:
    """Wiebe fraction burned at exhaust opening: ``1 - exp(-a)`` once the combustion has ended."""
    if st.evo >= st.start + st.duration:
        return float(-np.expm1(-st.a))
    return float(_fraction_y(np.array((st.evo - st.start) / st.duration), st.a, st.m))
