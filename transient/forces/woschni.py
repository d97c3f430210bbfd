"""Single-zone closed cycle with Wiebe heat release and Woschni wall heat transfer (one idea: the
wall heat loss and the cycle it changes).

The numpy definition of the physics that the compiled in-ODE gas model is checked against. The
closed part of the cycle (intake closing IVC → exhaust opening EVO) is the one ideal-gas zone of
:mod:`transient.forces.closed_cycle` (its angle convention: 4-stroke 0 at the gas-exchange TDC and
2π at the firing TDC; the closed part of a 2-stroke runs through 2π ≡ 0 and is integrated in
unwrapped angles past 2π), here losing heat to the walls, at the shaft speed ω > 0 [rad/s]:

    dp/dx   = (γ(T) − 1)/V · (dQ_b/dx − Q̇_w/ω) − γ(T)·p/V · dV/dx       first law, one zone
    dQ_b/dx = m_f·LHV·η_c · dx_b/dx                                      Wiebe heat release
    T       = T_a·p·V/(p_a·V_a)                                           pV = mRT, m fixed
    γ(T)    = gamma + gamma_slope·(T − gamma_t_ref)
    Q̇_w     = h·A_w·(T − T_w)                                            [W], gas → wall
    h       = 3.26·B^(−0.2)·(p/1000)^0.8·T^(−0.55)·w^0.8                 [W/(m² K)]
    w       = c1·c_m + c2·(V_h·T_a/(p_a·V_a))·max(p − p_mot, 0)          [m/s]
    c_m     = S·ω/π                                                       mean piston speed
    p_mot   = p_a·(V_a/V)^γ_a,  γ_a = γ(T_a)                              motored isentrope
    A_w     = π·B²/2 + 4·V/B                                              head + crown + liner

with p = p_a at IVC, c2 taken as 0 before the combustion start and as given from it on, B the
bore [m], S the stroke [m], V_h = π·B²·S/4 the swept volume [m³] (both from
:class:`WoschniParameters`). h is Woschni's correlation (G. Woschni, "A universally applicable
equation for the instantaneous heat transfer coefficient in the internal combustion engine", SAE
670931, 1967) in the form of J. B. Heywood, *Internal Combustion Engine Fundamentals*, §12.4,
eq. (12.19) (B in m, p in kPa, T in K, w in m/s), with its closed-part constants c1 = 2.28 and
c2 = 3.24e-3 m/(s K). With c1 = c2 = 0 (h = 0) the model is the closed part of
:func:`transient.forces.wiebe.wiebe_cycle` (the same integrator and segments, with one more
component, Q_w ≡ 0, in the step control).

The scalar functions (:func:`woschni_coefficient`, :func:`wall_area`, :func:`gas_velocity`,
:func:`motored_pressure`, :func:`wall_heat_flow`, :func:`closed_rate`, and the shared
:func:`~transient.forces.closed_cycle.first_law_rate`) take and return floats only and use
``math`` only, so that a compiled twin can be written (or decorated) line by line.
:func:`closed_cycle` integrates (p, W = ∫p dV, Q_w = ∫Q̇_w/ω dx) over the closed part with
:func:`~transient.forces.closed_cycle.integrate_closed`; :func:`heat_transfer_rate` is the
vectorised h and Q̇_w for plots.

Units: SI inside (Pa, m³, K, J, W, rad, rad/s); only h's correlation reads p in kPa.

What is not modelled
--------------------
* The gas-exchange strokes (Woschni's c1 = 6.18 there) and any heat transfer outside the closed
  part: the model starts at IVC at p_a, T_a whatever happened before.
* Swirl (Woschni's c1 = 2.28 + 0.308·v_swirl/c_m), radiation (diesel soot: Annand's term), and
  the combustion-chamber shape (a bowl in the piston): the piston crown and the head are flat
  discs and the liner is wetted down to the height V/(π B²/4), clearance height included.
* Wall temperature dynamics: one uniform, constant T_w for head, crown and liner.
* Mass change (fuel added, blow-by, crevices), a gas constant that changes with combustion, and
  dissociation, as in :mod:`transient.forces.closed_cycle`.
* The motored pressure of Woschni's velocity term is the isentrope from IVC with the constant
  γ(T_a) (the contract of this model), not the motored pressure of this model with heat
  transfer or with a temperature-dependent γ.
"""
from __future__ import annotations

import math
import types
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from transient.errors import SceneError
from transient.forces.closed_cycle import (
    DEFAULT_A,
    DEFAULT_M,
    DEFAULT_RTOL,
    ClosedPart,
    CycleSetup,
    SegmentLoss,
    burned_fraction,
    check_fuel_mass,
    check_volume,
    first_law_rate,
    gamma_at,
    integrate_closed,
    peak,
    setup_cycle,
    volume_derivative,
    wiebe_rate_y,
)
from transient.forces.gas import VolumeFunction, volume_at

__all__ = [
    "DEFAULT_C1",
    "DEFAULT_C2",
    "DEFAULT_WALL_TEMPERATURE",
    "WOSCHNI_CONSTANT",
    "ClosedCycle",
    "WoschniParameters",
    "closed_cycle",
    "closed_rate",
    "gas_velocity",
    "heat_transfer_rate",
    "motored_pressure",
    "wall_area",
    "wall_heat_flow",
    "woschni_coefficient",
]

#: Woschni's constant in h = C·B^(−0.2)·p[kPa]^0.8·T^(−0.55)·w^0.8 [W/(m² K)], B in m, T in K,
#: w in m/s (Heywood eq. 12.19).
WOSCHNI_CONSTANT = 3.26

#: c1 of the compression and the combustion–expansion (Woschni 1967; Heywood §12.4) [-].
DEFAULT_C1 = 2.28

#: c2 of the combustion–expansion of a direct-injection engine [m/(s K)] (Woschni 1967; Heywood
#: §12.4). Applied from the combustion start on, 0 before it.
DEFAULT_C2 = 3.24e-3

#: Wall temperature [K]: a typical mean of head, piston crown and liner (our choice).
DEFAULT_WALL_TEMPERATURE = 450.0


# ----------------------------------------------------------------------------------------
# Scalar physics (floats in, float out; math only, for a compiled twin)
# ----------------------------------------------------------------------------------------

def woschni_coefficient(p: float, t: float, w: float, bore: float) -> float:
    """Woschni heat transfer coefficient h [W/(m² K)] (Heywood eq. 12.19).

    ``h = 3.26·B^(−0.2)·(p/1000)^0.8·T^(−0.55)·w^0.8``.

    Parameters
    ----------
    p : float
        Gas pressure [Pa] (read in kPa by the correlation).
    t : float
        Gas temperature [K], > 0.
    w : float
        Characteristic gas velocity [m/s] (:func:`gas_velocity`).
    bore : float
        Cylinder bore B [m], > 0.

    Returns
    -------
    float
        h; 0 when p ≤ 0 or w ≤ 0, the limit of p^0.8·w^0.8 (a fractional power of a negative
        float is complex in Python and NaN when compiled, so the limit is written out).
    """
    if p <= 0.0 or w <= 0.0:
        return 0.0
    return (WOSCHNI_CONSTANT * bore ** -0.2 * (p / 1000.0) ** 0.8 * t ** -0.55 * w ** 0.8)


def wall_area(v: float, bore: float) -> float:
    """Heat-exchanging wall area A_w [m²] at the cylinder volume v [m³].

    Flat head and piston crown (π B²/4 each) plus the liner down to the piston: its height is
    V/(π B²/4), so its area π B·V/(π B²/4) = 4V/B.
    """
    return 0.5 * math.pi * bore * bore + 4.0 * v / bore


def gas_velocity(c1: float, c2_now: float, c_m: float, p: float, p_mot: float, v_h: float,
                 t_a: float, p_a: float, v_a: float) -> float:
    """Woschni's characteristic gas velocity w [m/s] (Heywood §12.4).

    ``w = c1·c_m + c2·(V_h·T_a/(p_a·V_a))·max(p − p_mot, 0)``.

    Parameters
    ----------
    c1 : float
        Piston-speed factor [-].
    c2_now : float
        Combustion factor [m/(s K)]: 0 before the combustion start, c2 from it on (the caller
        switches it, on a segment end).
    c_m : float
        Mean piston speed S·ω/π [m/s].
    p, p_mot : float
        Gas and motored pressure [Pa]; only the rise of p above p_mot counts.
    v_h : float
        Swept volume [m³].
    t_a, p_a, v_a : float
        Reference state, at intake closing [K, Pa, m³].
    """
    return c1 * c_m + c2_now * (v_h * t_a / (p_a * v_a)) * max(p - p_mot, 0.0)


def motored_pressure(v: float, p_a: float, v_a: float, gamma_a: float) -> float:
    """Motored pressure p_a·(V_a/V)^γ_a [Pa]: the isentrope from intake closing."""
    return p_a * (v_a / v) ** gamma_a


def wall_heat_flow(p: float, v: float, omega: float, t_a: float, p_a: float, v_a: float,
                   gamma_a: float, c1: float, c2_now: float, wall_temperature: float,
                   bore: float, stroke: float) -> float:
    """Heat flow from the gas to the walls Q̇_w = h·A_w·(T − T_w) [W].

    Parameters
    ----------
    p : float
        Gas pressure [Pa].
    v : float
        Cylinder volume [m³].
    omega : float
        Shaft speed [rad/s], > 0 (sets the mean piston speed c_m = S·ω/π).
    t_a, p_a, v_a : float
        State at intake closing [K, Pa, m³]; the temperature is T = T_a·p·V/(p_a·V_a).
    gamma_a : float
        γ(T_a), the exponent of the motored isentrope.
    c1, c2_now : float
        Woschni's factors (c2_now: 0 before the combustion start), see :func:`gas_velocity`.
    wall_temperature : float
        T_w [K].
    bore, stroke : float
        B and S [m]; the swept volume is π B² S/4.

    Returns
    -------
    float
        Q̇_w; negative when the gas is colder than the wall (heat flows in).
    """
    t = t_a / (p_a * v_a) * p * v
    c_m = stroke * omega / math.pi
    v_h = 0.25 * math.pi * bore * bore * stroke
    w = gas_velocity(c1, c2_now, c_m, p, motored_pressure(v, p_a, v_a, gamma_a), v_h,
                     t_a, p_a, v_a)
    return woschni_coefficient(p, t, w, bore) * wall_area(v, bore) * (t - wall_temperature)


def closed_rate(x: float, p: float, v: float, dvdx: float, omega: float, q_total: float,
                start: float, duration: float, a: float, m: float, burning: bool,
                gamma: float, gamma_slope: float, gamma_t_ref: float, t_a: float, p_a: float,
                v_a: float, c1: float, c2_now: float, wall_temperature: float, bore: float,
                stroke: float) -> float:
    """dp/dx [Pa/rad] of the closed part at the angle x: the model's right-hand side.

    Parameters
    ----------
    x : float
        Local crank angle [rad], unwrapped as `start` is.
    p : float
        Gas pressure [Pa].
    v, dvdx : float
        V(x) [m³] and dV/dx [m³/rad].
    omega : float
        Shaft speed [rad/s], > 0.
    q_total : float
        m_f·LHV·η_c [J].
    start, duration, a, m : float
        Wiebe combustion start [rad], duration [rad], efficiency parameter and shape exponent.
    burning : bool
        True on a segment inside [start, start + duration], where dQ_b/dx is the Wiebe rate
        ``q_total·dx_b/dy(y)/duration``, y = (x − start)/duration (at y = 0 it is infinite
        for m < 0: :func:`closed_cycle` integrates such a segment in another variable); False
        elsewhere (dQ_b/dx = 0 also at the segment's ends, as
        :func:`~transient.forces.closed_cycle.integrate_closed`).
    gamma, gamma_slope, gamma_t_ref : float
        γ(T) = gamma + gamma_slope·(T − gamma_t_ref) [-, 1/K, K].
    t_a, p_a, v_a : float
        State at intake closing [K, Pa, m³].
    c1, c2_now : float
        Woschni's factors; c2_now is 0 before the combustion start and c2 from it on (the
        caller switches it per segment). c1 = c2_now = 0 gives h = 0.
    wall_temperature, bore, stroke : float
        T_w [K], B and S [m].

    Returns
    -------
    float
        dp/dx [Pa/rad].
    """
    dq_b = q_total * wiebe_rate_y((x - start) / duration, a, m) / duration if burning else 0.0
    # The temperature in the integration's order of operations, so that h = 0 reproduces it.
    t = t_a / (p_a * v_a) * p * v
    g = gamma_at(t, gamma, gamma_slope, gamma_t_ref)
    gamma_a = gamma + gamma_slope * (t_a - gamma_t_ref)
    q_w = wall_heat_flow(p, v, omega, t_a, p_a, v_a, gamma_a, c1, c2_now, wall_temperature,
                         bore, stroke)
    return first_law_rate(p, v, dvdx, dq_b, q_w / omega, g)


# ----------------------------------------------------------------------------------------
# Parameters
# ----------------------------------------------------------------------------------------

def _finite(value) -> bool:
    """A finite real number (not a bool, a string or None)."""
    if isinstance(value, (bool, str)) or value is None:
        return False
    try:
        return math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


@dataclass(frozen=True)
class WoschniParameters:
    """Woschni wall heat transfer of one cylinder.

    Attributes
    ----------
    bore : float
        Cylinder bore B [m], > 0.
    stroke : float
        Piston stroke S [m], > 0 (the swept volume is π B² S/4).
    c1 : float
        Piston-speed factor of the gas velocity [-], ≥ 0 (Woschni: 2.28 closed part).
    c2 : float
        Combustion factor of the gas velocity [m/(s K)], ≥ 0 (Woschni: 3.24e-3 direct
        injection), applied from the combustion start on.
    wall_temperature : float
        Uniform wall temperature T_w [K], > 0.
    """

    bore: float
    stroke: float
    c1: float = DEFAULT_C1
    c2: float = DEFAULT_C2
    wall_temperature: float = DEFAULT_WALL_TEMPERATURE

    def __post_init__(self) -> None:
        for key, value, what in (("gas.woschni.c1", self.c1, "c1 [-]"),
                                 ("gas.woschni.c2", self.c2, "c2 [m/(s K)]")):
            if not (_finite(value) and value >= 0.0):
                raise SceneError(key, f"{value!r}; {what} must be finite and ≥ 0")
        t_w = self.wall_temperature
        if not (_finite(t_w) and t_w > 0.0):
            raise SceneError("gas.woschni.wall_temperature",
                             f"{t_w!r} K; the wall temperature must be finite and > 0 K")
        # Bore and stroke come from the mechanism, which validates them; checked here too for
        # direct use.
        for key, value, what in (("mechanism.bore", self.bore, "the bore [m]"),
                                 ("mechanism.crank_radius", self.stroke,
                                  "the stroke [m] (from the crank radius)")):
            if not (_finite(value) and value > 0.0):
                raise SceneError(key, f"{value!r}; {what} must be finite and > 0")

    @property
    def swept_volume(self) -> float:
        """V_h = π B² S/4 [m³], the swept volume of the gas-velocity term."""
        return 0.25 * math.pi * self.bore ** 2 * self.stroke

    @classmethod
    def of_mechanism(cls, mechanism, **factors) -> WoschniParameters:
        """Bore and exact stroke of a crank-slider mechanism (``bore``, ``stroke()``), with
        `factors` (c1, c2, wall_temperature) or their defaults."""
        return cls(bore=float(mechanism.bore), stroke=float(mechanism.stroke()), **factors)


# ----------------------------------------------------------------------------------------
# Vectorised twin, for plots and analysis
# ----------------------------------------------------------------------------------------

def heat_transfer_rate(x: ArrayLike, p: ArrayLike, v: ArrayLike, omega: ArrayLike,
                       woschni: WoschniParameters, *, combustion_start: float, p_a: float,
                       v_a: float, t_a: float, gamma_a: float
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Woschni h [W/(m² K)] and Q̇_w [W] along a cylinder state, vectorised.

    The same equations as :func:`wall_heat_flow`, written with numpy for arrays (a twin: the
    tests compare the two).

    Parameters
    ----------
    x : array_like
        Local crank angles [rad], unwrapped as `combustion_start` (c2 applies where
        ``x >= combustion_start``).
    p, v : array_like
        Pressure [Pa] and volume [m³] at `x`.
    omega : array_like
        Shaft speed [rad/s], > 0, scalar or shaped like `x`.
    woschni : WoschniParameters
    combustion_start : float
        Unwrapped combustion start [rad].
    p_a, v_a, t_a : float
        State at intake closing [Pa, m³, K].
    gamma_a : float
        γ(T_a) of the motored isentrope.

    Returns
    -------
    (h, q_dot) : tuple of NDArray[np.float64]
        Broadcast shape of the inputs.
    """
    x, p, v, omega = (np.asarray(z, dtype=np.float64) for z in (x, p, v, omega))
    bore, stroke = woschni.bore, woschni.stroke
    t = t_a / (p_a * v_a) * p * v
    c2 = np.where(x >= combustion_start, woschni.c2, 0.0)
    p_mot = p_a * (v_a / v) ** gamma_a
    w = (woschni.c1 * stroke * omega / math.pi
         + c2 * woschni.swept_volume * t_a / (p_a * v_a) * np.maximum(p - p_mot, 0.0))
    pos = (p > 0.0) & (w > 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        h = np.where(pos, WOSCHNI_CONSTANT * bore ** -0.2 * (np.where(pos, p, 1.0) / 1000.0) ** 0.8
                     * t ** -0.55 * np.where(pos, w, 1.0) ** 0.8, 0.0)
    area = 0.5 * math.pi * bore ** 2 + 4.0 * v / bore
    return h, h * area * (t - woschni.wall_temperature)


# ----------------------------------------------------------------------------------------
# The closed part
# ----------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class ClosedCycle(ClosedPart):
    """The closed part (IVC → EVO) with wall heat transfer: dense solution and totals.

    A :class:`~transient.forces.closed_cycle.ClosedPart` whose segments hold the components
    (p, W, Q_w)
    (:meth:`~transient.forces.closed_cycle.ClosedPart.state`). Angles are local and unwrapped: from
    `start` (intake closing) to `end` (exhaust opening), past 2π for a 2-stroke.

    Attributes
    ----------
    start, end, breaks, segments, p_a, v_a, t_a
        As :class:`~transient.forces.closed_cycle.ClosedPart`.
    combustion_start : float
        Unwrapped combustion start [rad] (c2 applies from it on).
    gamma_a : float
        γ(T_a).
    work : float
        Closed-part work ∫p dV from IVC to EVO [J] (an ODE component).
    heat_released : float
        Q_b = m_f·LHV·η_c·x_b(EVO) [J] (closed form of the Wiebe fraction).
    heat_lost : float
        Q_w = ∫Q̇_w/ω dx from IVC to EVO [J] (an ODE component; negative if the walls heat the
        gas on balance).
    p_end, t_end, v_end : float
        Pressure [Pa], temperature [K] and volume [m³] at EVO.
    p_max : float
        Peak pressure [Pa].
    angle_max : float
        Unwrapped angle of the peak pressure [rad].
    t_max : float
        Peak temperature [K] (on a 4001-point scan of every segment).
    fuel_mass : float
        Fuel mass of the cycle [kg].
    woschni : WoschniParameters or None
        The heat transfer integrated (None: none).
    """

    combustion_start: float
    gamma_a: float
    work: float
    heat_released: float
    heat_lost: float
    p_end: float
    t_end: float
    v_end: float
    p_max: float
    angle_max: float
    t_max: float
    fuel_mass: float
    woschni: WoschniParameters | None
    _omega: Callable[[float], float]
    _volume: Callable[[NDArray[np.float64]], NDArray[np.float64]]

    def pressure(self, x: ArrayLike) -> NDArray[np.float64]:
        """Pressure [Pa] at unwrapped angles x in [start, end] [rad]."""
        return self.state(x)[0]

    def volume(self, x: ArrayLike) -> NDArray[np.float64]:
        """Cylinder volume [m³] at unwrapped angles x [rad]."""
        return self._volume(np.asarray(x, dtype=np.float64))

    def heat_transfer(self, x: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Woschni h [W/(m² K)] and Q̇_w [W] along the solution at unwrapped angles x [rad]
        (zeros without heat transfer)."""
        x = np.asarray(x, dtype=np.float64)
        p = self.pressure(x)
        if self.woschni is None:
            return np.zeros(x.shape), np.zeros(x.shape)
        omega = np.vectorize(self._omega, otypes=[float])(x)
        return heat_transfer_rate(x, p, self.volume(x), omega, self.woschni,
                                  combustion_start=self.combustion_start, p_a=self.p_a,
                                  v_a=self.v_a, t_a=self.t_a, gamma_a=self.gamma_a)


def _speed(omega: float | Callable[[float], float] | None, needed: bool
           ) -> Callable[[float], float]:
    """ω as a function of the unwrapped angle, checked > 0 and finite wherever it is read."""
    if omega is None:
        if needed:
            raise ValueError("omega [rad/s] is required with wall heat transfer")
        return lambda x: 1.0  # never enters: Q̇_w = 0 without heat transfer
    if not callable(omega):
        w = float(omega)
        if not (math.isfinite(w) and w > 0.0):
            raise ValueError(f"omega = {omega!r} rad/s; the shaft speed must be finite and > 0")
        return lambda x: w

    def checked(x: float) -> float:
        w = float(omega(x))
        if not (math.isfinite(w) and w > 0.0):
            raise ValueError(f"omega({x!r}) = {w!r} rad/s; the shaft speed must be finite and > 0")
        return w
    return checked


def _wall_loss(st: CycleSetup, v_a: float, woschni: WoschniParameters | None,
               omega_at: Callable[[float], float]) -> Callable[[float], SegmentLoss]:
    """dQ_w/dx = Q̇_w/ω of every segment, for
    :func:`~transient.forces.closed_cycle.integrate_closed`.

    c2 is switched on from the segment that starts at the combustion start, so that the loss is
    smooth inside every segment except where p crosses p_mot (a kink of max(p − p_mot, 0)).
    """
    # Without heat transfer: c1 = c2 = 0 make w = 0 and h = 0 exactly; the geometry is unused.
    wp = woschni or types.SimpleNamespace(c1=0.0, c2=0.0, wall_temperature=1.0, bore=1.0,
                                          stroke=1.0)
    gamma_a = st.gamma_a

    def segment(lo: float) -> SegmentLoss:
        c2_now = wp.c2 if lo >= st.start else 0.0

        def loss(x: float, p: float, v: float) -> float:
            om = omega_at(x)
            return wall_heat_flow(p, v, om, st.t_a, st.p_a, v_a, gamma_a, wp.c1, c2_now,
                                  wp.wall_temperature, wp.bore, wp.stroke) / om

        return loss

    return segment


def closed_cycle(volume: VolumeFunction, *, p_a: float, start: float, duration: float,
                 fuel_mass: float, woschni: WoschniParameters | None = None,
                 omega: float | Callable[[float], float] | None = None,
                 a: float = DEFAULT_A, m: float = DEFAULT_M, lhv: float = 42.5e6,
                 efficiency: float = 1.0, gamma: float = 1.35, gamma_slope: float = 0.0,
                 gamma_t_ref: float = 300.0, t_a: float = 330.0, strokes: int = 4,
                 intake_closing: float | None = None, exhaust_opening: float | None = None,
                 p_intake: float | None = None, p_exhaust: float | None = None,
                 dvolume: VolumeFunction | None = None, rtol: float = DEFAULT_RTOL
                 ) -> ClosedCycle:
    """Integrate the closed part with Wiebe heat release and Woschni wall heat transfer.

    The model of the module docstring: (p, W = ∫p dV, Q_w = ∫Q̇_w/ω dx) from intake closing
    (p = p_a) to exhaust opening with DOP853 at `rtol` (absolute tolerances 1e-3·rtol of p_a and
    of p_a·V_a), by :func:`~transient.forces.closed_cycle.integrate_closed` as
    :func:`~transient.forces.wiebe.wiebe_cycle` (split at the combustion start and end, in the
    variable u = y**(m + 1) inside a combustion with m < 0). The inputs are validated by
    :func:`~transient.forces.closed_cycle.setup_cycle` (the same errors and angle rules as
    ``wiebe_cycle``); nothing is tabulated.

    Parameters
    ----------
    volume, dvolume : callable
        Vectorised V(x) [m³] and optional dV/dx [m³/rad] at table angles, as in ``wiebe_cycle``
        (default dV/dx: the 8th-order central difference of
        :func:`~transient.forces.closed_cycle.volume_derivative`).
    p_a : float
        Pressure at intake closing [Pa].
    start, duration : float
        Combustion start and duration [rad] (start moved by whole periods into the closed part).
    fuel_mass : float
        Fuel per cycle [kg], finite and ≥ 0 (0: motored).
    woschni : WoschniParameters, optional
        Wall heat transfer; None for none (then the pressure is that of ``wiebe_cycle``'s
        closed part).
    omega : float or callable, optional
        Shaft speed [rad/s] > 0, constant or ``omega(x)`` of the unwrapped local angle x [rad];
        required with `woschni`.
    a, m, lhv, efficiency, gamma, gamma_slope, gamma_t_ref, t_a, strokes, intake_closing,
    exhaust_opening
        As in ``wiebe_cycle`` (same defaults).
    p_intake, p_exhaust : float, optional
        Not used by the closed part; accepted (and validated as ``wiebe_cycle`` does for a
        4-stroke) so that the same keywords serve both functions. Default p_a.
    rtol : float
        Relative tolerance of DOP853, in [1e-14, 1e-6].

    Returns
    -------
    ClosedCycle

    Raises
    ------
    SceneError
        As ``wiebe_cycle`` for the cycle inputs (``gas.wiebe.*``, ``gas.p_a``, ``gas.strokes``,
        ``gas.compression_ratio`` for a volume that is not > 0); ``gas.wiebe.fuel_mass``.
    ValueError
        `omega` missing with `woschni`, or not finite and > 0 where it is read.
    """
    fuel_mass = check_fuel_mass(fuel_mass)
    st = setup_cycle(strokes=strokes, p_a=p_a, start=start, duration=duration, a=a, m=m,
                     lhv=lhv, efficiency=efficiency, gamma=gamma, gamma_slope=gamma_slope,
                     gamma_t_ref=gamma_t_ref, t_a=t_a,
                     p_intake=p_a if p_intake is None else p_intake,
                     p_exhaust=p_a if p_exhaust is None else p_exhaust,
                     intake_closing=intake_closing, exhaust_opening=exhaust_opening, rtol=rtol)
    check_volume(st, volume)
    dvolume = dvolume or volume_derivative(volume)
    omega_at = _speed(omega, woschni is not None)
    # Q_w is a component even without heat transfer (then ≡ 0): the cycle has the same state
    # and step control whether or not h vanishes.
    wall = _wall_loss(st, volume_at(volume, st.ivc), woschni, omega_at)
    part = integrate_closed(st, fuel_mass, volume, dvolume, wall)
    period = st.period

    def unwrapped_volume(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(volume(np.where(x > period, x - period, x)), dtype=np.float64)

    p_max, x_max, t_max = peak(part, volume, period)
    p_end, w_end, q_w_end = part.segments[-1](np.array(st.evo))
    v_end = float(unwrapped_volume(np.array([st.evo]))[0])
    return ClosedCycle(
        **vars(part), combustion_start=st.start, gamma_a=st.gamma_a, work=float(w_end),
        heat_released=fuel_mass * st.lhv * st.efficiency * burned_fraction(st),
        heat_lost=float(q_w_end), p_end=float(p_end),
        t_end=float(part.temperature(float(p_end), v_end)), v_end=v_end, p_max=p_max,
        angle_max=x_max, t_max=t_max, fuel_mass=fuel_mass, woschni=woschni, _omega=omega_at,
        _volume=unwrapped_volume)
