"""Scenes: TOML → frozen dataclasses, validated before any work, and the resolved scene back to TOML.

Every key may be written in SI (``crank_radius = 0.047``) or with one unit suffix at the edge
(``crank_radius_mm = 47``); see :mod:`transient.units`. Unknown keys, wrong types and non-physical
values raise :class:`transient.errors.SceneError` naming the file, the key, what is wrong and what
is allowed.
"""
from __future__ import annotations

import csv
import math
import tomllib
from dataclasses import dataclass, field, fields, is_dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..mechanisms.articulated import Articulated, read_articulated
from ..mechanisms.crank_slider import CrankSlider, read_crank_slider
from ..mechanisms.swash_plate import SwashPlate, read_swash_plate
from ..tomlout import toml_value
from ..units import ALL_SUFFIXES, SUFFIXES

_MISSING = object()


class Section:
    """One TOML table being read: takes keys off it, converts units, and reports what is left."""

    def __init__(self, data: Any, path: str) -> None:
        if not isinstance(data, dict):
            raise SceneError(path, f"must be a table, got {type(data).__name__}")
        self.data = dict(data)
        self.path = path
        self.known: list[str] = []
        self.kinds: dict[str, str | None] = {}
        self.written: dict[str, str] = {}  # base name -> the key as the user wrote it
        self.subs: dict[str, Section] = {}  # sub-tables read so far, for rename()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def _take(self, name: str, kind: str | None):
        """(value, SI factor, key as written) for a quantity given plain or with one unit suffix."""
        self.known.append(name)
        self.kinds[name] = kind
        found = []
        if name in self.data:
            found.append((name, 1.0))
        for suffix, factor in (SUFFIXES.get(kind, {}) if kind else {}).items():
            if f"{name}_{suffix}" in self.data:
                found.append((f"{name}_{suffix}", factor))
        if len(found) > 1:
            raise SceneError(self.key(found[1][0]),
                             f"given twice (also as {found[0][0]!r}); give one of them")
        if not found:
            self._check_suffixes(name)
            return _MISSING, 1.0, name
        written, factor = found[0]
        self.written[name] = written
        return self.data.pop(written), factor, written

    def _check_suffixes(self, name: str) -> None:
        """A key ``name_<suffix>`` with a suffix this quantity does not take is an error here,
        not a 'missing key' later."""
        for key in self.data:
            base, _, suffix = key.rpartition("_")
            if base == name and _looks_like_unit(suffix):
                raise SceneError(self.key(key), self._suffix_problem(name, suffix))

    def _suffix_problem(self, name: str, suffix: str) -> str:
        hint = self._unit_hint(name, self.kinds.get(name))
        if suffix in ALL_SUFFIXES:
            return f"unit suffix '_{suffix}' does not fit this quantity; {hint}"
        return f"unknown unit suffix '_{suffix}'; {hint}"

    def number(self, name: str, kind: str | None = None, default: Any = _MISSING, *,
               gt: float | None = None, ge: float | None = None, lt: float | None = None,
               le: float | None = None) -> float:
        value, factor, written = self._take(name, kind)
        if value is _MISSING:
            if default is _MISSING:
                raise SceneError(self.key(name), f"is missing; {self._unit_hint(name, kind)}")
            return default
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(self.key(written), f"must be a number, got {_show(value)}")
        if not math.isfinite(value):
            raise SceneError(self.key(written), f"must be finite, got {value}")
        self._check_range(written, value, gt, ge, lt, le, factor)
        return float(value) * factor

    def _check_range(self, written, value, gt, ge, lt, le, factor):
        # Bounds are given in SI; compare in the units the user wrote.
        for bound, ok, word in ((gt, lambda v, b: v > b, ">"), (ge, lambda v, b: v >= b, "≥"),
                                (lt, lambda v, b: v < b, "<"), (le, lambda v, b: v <= b, "≤")):
            if bound is not None and not ok(value * factor, bound):
                raise SceneError(self.key(written),
                                 f"must be {word} {bound / factor:g}, got {value:g}")

    def integer(self, name: str, default: Any = _MISSING, *, ge: int | None = None,
                choices: tuple[int, ...] | None = None, le: int | None = None) -> int:
        value, _, written = self._take(name, None)
        if value is _MISSING:
            if default is _MISSING:
                raise SceneError(self.key(name), "is missing; give a whole number")
            return default
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(self.key(written), f"must be a whole number, got {_show(value)}")
        if ge is not None and value < ge:
            raise SceneError(self.key(written), f"must be ≥ {ge}, got {value}")
        if le is not None and value > le:
            raise SceneError(self.key(written), f"must be ≤ {le}, got {value}")
        if choices is not None and value not in choices:
            raise SceneError(self.key(written),
                             f"must be one of {', '.join(map(str, choices))}, got {value}")
        return value

    def flag(self, name: str, default: bool) -> bool:
        value, _, written = self._take(name, None)
        if value is _MISSING:
            return default
        if not isinstance(value, bool):
            raise SceneError(self.key(written), f"must be true or false, got {_show(value)}")
        return value

    def strings(self, name: str, default: Any = _MISSING) -> tuple:
        value, _, written = self._take(name, None)
        if value is _MISSING:
            if default is _MISSING:
                raise SceneError(self.key(name), "is missing; give a list of strings")
            return default
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise SceneError(self.key(written), f"must be a list of strings, got {_show(value)}")
        return tuple(value)

    def string(self, name: str, default: Any = _MISSING, *,
               choices: tuple[str, ...] | None = None) -> str:
        value, _, written = self._take(name, None)
        if value is _MISSING:
            if default is _MISSING:
                allowed = f"; allowed: {', '.join(choices)}" if choices else ""
                raise SceneError(self.key(name), f"is missing{allowed}")
            return default
        if not isinstance(value, str):
            raise SceneError(self.key(written), f"must be a string, got {_show(value)}")
        if choices is not None and value not in choices:
            raise SceneError(self.key(written),
                             f"unknown value {value!r}; allowed: {', '.join(map(repr, choices))}")
        return value

    def numbers(self, name: str, kind: str | None = None, default: Any = _MISSING) -> tuple:
        value, factor, written = self._take(name, kind)
        if value is _MISSING:
            if default is _MISSING:
                raise SceneError(self.key(name), f"is missing; {self._unit_hint(name, kind)} list")
            return default
        if not isinstance(value, list) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                for v in value):
            raise SceneError(self.key(written), f"must be a list of finite numbers, got "
                                                f"{_show(value)}")
        return tuple(float(v) * factor for v in value)

    def integers(self, name: str, default: Any = _MISSING) -> tuple:
        value, _, written = self._take(name, None)
        if value is _MISSING:
            if default is _MISSING:
                raise SceneError(self.key(name), "is missing; give a list of whole numbers")
            return default
        if not isinstance(value, list) or not all(isinstance(v, int) and not isinstance(v, bool)
                                                  for v in value):
            raise SceneError(self.key(written), f"must be a list of whole numbers, got "
                                                f"{_show(value)}")
        return tuple(value)

    def sub(self, name: str, required: bool = False) -> "Section":
        self.known.append(name)
        if name not in self.data:
            if required:
                raise SceneError(self.key(name), "is missing (a table)")
            child = Section({}, self.key(name))
        else:
            child = Section(self.data.pop(name), self.key(name))
        self.subs[name] = child
        return child

    def has(self, name: str, kind: str | None = None) -> bool:
        names = [name] + [f"{name}_{s}" for s in SUFFIXES.get(kind, {})] if kind else [name]
        return any(n in self.data for n in names)

    def finish(self) -> None:
        """Every key must have been read: anything left is unknown (or has a wrong unit suffix)."""
        for key in self.data:
            base, _, suffix = key.rpartition("_")
            if base in self.kinds and _looks_like_unit(suffix):
                raise SceneError(self.key(key), self._suffix_problem(base, suffix))
            raise SceneError(self.key(key), f"unknown key; allowed here: "
                                            f"{', '.join(sorted(set(self.known)))}")

    def rename(self, exc: SceneError) -> SceneError:
        """Re-key an error raised under a base name (``mechanism.firing``, or a suffixed form
        such as ``gas.phi_deg``) to the key the user actually wrote."""
        prefix = f"{self.path}." if self.path else ""
        if exc.key.startswith(prefix):
            name = exc.key[len(prefix):]
            head, dot, _ = name.partition(".")
            if dot and head in self.subs:  # a key of a sub-table (gas.wiebe.start_deg)
                return self.subs[head].rename(exc)
            base = name.rpartition("_")[0] if name.rpartition("_")[2] in ALL_SUFFIXES else name
            if base in self.written:
                exc.key = prefix + self.written[base]
        return exc

    @staticmethod
    def _unit_hint(name: str, kind: str | None) -> str:
        options = [name] + [f"{name}_{s}" for s in SUFFIXES.get(kind, {})] if kind else [name]
        return "give " + " or ".join(repr(o) for o in options) + (" (SI without a suffix)"
                                                                   if kind else "")


#: Suffixes that read as a unit: an unknown one is reported as a unit suffix, not an unknown key.
_UNIT_LIKE = {"in", "m", "cm", "km", "ft", "s", "ms", "min", "h", "rad", "rps", "hz", "pa", "kpa",
              "psi", "atm", "kg", "g", "lb", "n", "nm", "kw", "w", "k", "c", "l"}


def _looks_like_unit(suffix: str) -> bool:
    return suffix in ALL_SUFFIXES or suffix.lower() in _UNIT_LIKE


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


# ----------------------------------------------------------------------------------------------
# Scene dataclasses (SI). The mechanism classes live in transient.mechanisms.


@dataclass(frozen=True)
class Inertia:
    """Constant inertias on the shaft [kg m²]."""

    shaft: float = 0.0
    flywheel: float = 0.0
    load: float = 0.0

    @property
    def total(self) -> float:
        return self.shaft + self.flywheel + self.load


@dataclass(frozen=True)
class Wiebe:
    """Single-zone Wiebe combustion, the ``[gas.wiebe]`` table of ``model = "wiebe"``
    (:func:`transient.forces.wiebe.wiebe_cycle`, whose parameters these are, in SI).

    ``start`` [rad] (``start_deg``) and ``duration`` [rad] of the combustion, local angles as the
    other gas models (4-stroke: 0 gas-exchange TDC, 2π firing TDC). ``fuel_mass`` [kg]: fuel
    burned per cycle and cylinder at full load (governor fuel 1); 0 runs the engine motored.
    ``a``, ``m`` [1]: Wiebe efficiency parameter and shape exponent. ``lhv`` [J/kg]: lower heating
    value; ``efficiency`` [1]: combustion efficiency η_c, the share of m_f·LHV released.
    ``gamma`` [1]: heat capacity ratio, at ``gamma_t_ref`` [K] with ``gamma_slope`` dγ/dT [1/K].
    ``t_a`` [K]: gas temperature at intake closing. ``intake_closing``, ``exhaust_opening`` [rad]:
    ends of the closed part (None: the BDCs around the firing TDC). ``step`` [rad] and
    ``tolerance`` [1]: largest knot spacing and target relative error of the tables.
    """

    start: float = 0.0
    duration: float = 0.0
    fuel_mass: float = 0.0
    a: float = 6.908
    m: float = 0.5
    lhv: float = 42.5e6
    efficiency: float = 1.0
    gamma: float = 1.35
    gamma_slope: float = 0.0
    gamma_t_ref: float = 300.0
    t_a: float = 330.0
    intake_closing: float | None = None
    exhaust_opening: float | None = None
    step: float = math.radians(0.125)
    tolerance: float = 1e-10


@dataclass(frozen=True)
class Woschni:
    """Wall heat transfer of the closed part, Woschni's correlation: the ``[gas.woschni]`` table
    of ``model = "wiebe"`` (equations in :mod:`transient.forces.woschni`). With it the cylinder
    pressure depends on the shaft speed and on its own history, so the closed part of each
    cylinder is a state of the ODE instead of a table (``transient.core.cylinder``).

    ``c1`` [1] multiplies the mean piston speed, ``c2`` [m/(s K)] the pressure rise combustion
    causes (from the combustion start on; Woschni's direct-injection value by default);
    ``wall_temperature`` [K]: the mean temperature of head, piston crown and liner.
    """

    c1: float = 2.28
    c2: float = 3.24e-3
    wall_temperature: float = 450.0


@dataclass(frozen=True)
class Gas:
    """Cylinder pressure model (angle-only in this version).

    ``model``: ``"none"``, ``"table"`` (indicator diagram p(φ) over one cycle, absolute pressure
    [Pa]; local angle 0 = gas-exchange TDC for 4-stroke, firing TDC for 2-stroke ... see README),
    ``"mixed-cycle"`` (Gots App. 2, Trinkler–Sabathé), ``"trapezoid"`` (the swash-plate paper's
    force pulse per piston, §4: ``amplitude`` [N], ``ramp`` and ``duration`` [rad]) or
    ``"wiebe"`` (single-zone Wiebe combustion, :class:`Wiebe`; with ``compression_ratio``, ``p_a``
    [Pa] at intake closing and, for a 4-stroke, ``p_intake`` and ``p_exhaust`` [Pa]). ``p0`` is the
    crankcase pressure [Pa]: piston force (p − p0)·F_p, Gots (33).

    **Fuel command.** The governor's fuel f ∈ [0, 1] (1 without a governor) sets the cylinder
    pressure between a motored curve and the full-load curve, p = p_mot + f·(p_full − p_mot). For
    ``"table"`` and ``"mixed-cycle"`` the motored curve is the constant p0, so the gas force is
    f·(p − p0)·F_p (for ``"trapezoid"``, f times the force). For ``"wiebe"`` it is the cycle with
    no fuel and p_full the cycle with ``fuel_mass``: with a constant γ the single-zone pressure is
    linear in the fuel mass, so this is exactly the cycle burning f·fuel_mass. With
    ``gamma_slope`` ≠ 0 (γ(T)) it is not, and the pressure at part load is only approximately
    that cycle's: the author of :mod:`transient.forces.wiebe` reports up to about 2.5 % of p_max
    for fuel levels 0.02 g apart; ``tests/validation/test_wiebe_runs.py`` measures, on the Gots
    engine of ``cases/gots_diesel_wiebe.toml`` with γ = 1.38 − 1e-4·(T − 300 K), 1.1 % of the
    full-load p_max between 0 and 0.02 g and 2.1 % between 0 and 0.031 g (at f = 0.5; the
    indicated work at f = 0.25 is then 7.6 % low). Use a constant γ where part load matters.
    The result columns ``p_<k>`` hold the pressure so applied (the force, for ``"trapezoid"``).

    **Fuel latching.** With ``injection`` [rad] (a local angle, as the tables'), each cylinder
    takes the governor's command at its start of injection and burns that fuel until its next
    one, so that the governor acts with the real per-cylinder delay (event ``injection``);
    without it every cylinder follows the command at once.
    """

    model: str = "none"
    p0: float = 1.0e5
    phi: tuple[float, ...] = ()
    p: tuple[float, ...] = ()
    corners: tuple[float, ...] = ()
    interpolation: str = "pchip"
    compression_ratio: float = 0.0
    p_a: float = 0.0
    n1: float = 0.0
    p_z: float = 0.0
    rho: float = 0.0
    n2: float = 0.0
    p_intake: float = 0.0
    p_exhaust: float = 0.0
    amplitude: float = 0.0
    ramp: float = 0.0
    duration: float = math.pi
    wiebe: Wiebe | None = None
    injection: float | None = None
    woschni: Woschni | None = None


@dataclass(frozen=True)
class Load:
    """Resisting moment M_load = −s·(torque + linear·ω + fan·ω|ω| + P/max(ω, ω_min)) [N m]
    (signs as Gots §1: + with rotation).

    ``torque`` [N m], ``linear`` [N m s], ``fan`` [N m s²]. ``generator_power`` P [W]: an
    electrical load, M·ω = −s·P; below ``generator_min_speed`` ω_min [rad/s] its torque is held
    at −s·P/ω_min, so that it stays finite at a start from rest (like ``torque``, it does not
    change sign with ω). ω_min must be > 0 when P > 0.

    The scale s [1] (1 without a schedule) is piecewise linear in time (``schedule_time`` [s])
    or in shaft revolutions from the initial angle (``schedule_revolutions`` [1]) through the
    points (abscissa, ``schedule_scale``), constant before the first and after the last. The
    abscissae do not decrease; two equal ones are a step (value before, value after). The
    corners are state events (``load_schedule``): a step changes s exactly there.

    ``inertia`` J_x [kg m²] switched in at ``inertia_time`` [s]: a load's inertia, at rest, that
    a clutch couples to the shaft at that instant (an inelastic engagement: the angular momentum
    J(φ)ω is conserved, ω₊ = J ω₋/(J + J_x); the kinetic energy lost, ½Jω₋²·J_x/(J + J_x), is
    counted in ``W_load``; event ``inertia_switch``).
    """

    torque: float = 0.0
    linear: float = 0.0
    fan: float = 0.0
    generator_power: float = 0.0
    generator_min_speed: float = 0.0
    schedule_time: tuple[float, ...] = ()
    schedule_revolutions: tuple[float, ...] = ()
    schedule_scale: tuple[float, ...] = ()
    inertia: float = 0.0
    inertia_time: float = 0.0


@dataclass(frozen=True)
class Starter:
    """Starter: M = torque·(1 − ω/noload_speed) until ω first reaches cutout_speed [N m, rad/s]."""

    torque: float = 0.0
    noload_speed: float = 1.0
    cutout_speed: float = 1.0


@dataclass(frozen=True)
class Governor:
    """Speed governor, setting the fuel command f (see :class:`Gas`); equations in
    :mod:`transient.core.governor`.

    ``droop``: the static characteristic of the swash-plate paper (§4): f = 1 below
    ``speed_full`` (ω_a), linearly down to 0 at ``speed_zero`` (ω_1c), 0 above [rad/s].

    ``pi``: isochronous PI(D) at ``speed`` ω_ref [rad/s]: ``gain_p`` K_p [1] and ``gain_i`` K_i
    [1/s] per unit relative speed error, ``gain_d`` K_d [s] with its filter ``derivative_time``
    τ_D [s]; the rack follows the clipped demand with the lag ``actuator_time`` τ_A [s], at most
    ``rate_limit`` [1/s] (0: none), between ``fuel_min`` and ``fuel_max``; ``anti_windup`` back-calculation
    with ``tracking_time`` T_t [s] (0: K_p/K_i); the rack and the integrator start at
    ``fuel_initial``.

    ``flyweight``: a centrifugal governor: ``weights`` n_w of ``weight_mass`` m_w [kg] at
    ``radius`` ρ₀ [m] with the sleeve on its low stop, bell cranks of ``arm_ratio`` a/b [1],
    turning at ``gear_ratio`` i_g times the shaft; ``sleeve_mass`` [kg], ``spring_rate`` k [N/m],
    ``spring_preload`` F₀ [N], ``damping`` c [N s/m], sleeve ``travel`` z_max [m]; the rack gives
    ``fuel_max`` on the low stop, ``fuel_min`` on the high one, linear between.
    """

    model: str = "none"
    speed_full: float = 0.0
    speed_zero: float = 0.0
    speed: float = 0.0
    gain_p: float = 0.0
    gain_i: float = 0.0
    gain_d: float = 0.0
    derivative_time: float = 0.01
    actuator_time: float = 0.02
    rate_limit: float = 0.0
    fuel_min: float = 0.0
    fuel_max: float = 1.0
    anti_windup: bool = True
    tracking_time: float = 0.0
    fuel_initial: float = 1.0
    weights: int = 2
    weight_mass: float = 0.0
    radius: float = 0.0
    arm_ratio: float = 1.0
    gear_ratio: float = 1.0
    sleeve_mass: float = 0.0
    spring_rate: float = 0.0
    spring_preload: float = 0.0
    damping: float = 0.0
    travel: float = 0.0


#: The keys of each governor model (the resolved scene writes these).
GOVERNOR_KEYS = {
    "none": ("model",),
    "droop": ("model", "speed_full", "speed_zero"),
    "pi": ("model", "speed", "gain_p", "gain_i", "gain_d", "derivative_time", "actuator_time",
           "rate_limit", "fuel_min", "fuel_max", "anti_windup", "tracking_time", "fuel_initial"),
    "flyweight": ("model", "weights", "weight_mass", "radius", "arm_ratio", "gear_ratio",
                  "sleeve_mass", "spring_rate", "spring_preload", "damping", "travel", "fuel_min",
                  "fuel_max"),
}


@dataclass(frozen=True)
class Initial:
    """Initial shaft angle [rad] and speed [rad/s]."""

    phi: float = 0.0
    omega: float = 0.0


@dataclass(frozen=True)
class Run:
    """What to run: ``dynamic`` (integrate (18)) or ``prescribed-speed`` (inverse dynamics).

    The run ends at ``t_end`` [s] or after ``revolutions`` of the shaft, whichever comes first
    (``inf`` = not set). For prescribed speed: ``speed`` [rad/s] constant, or a table ``time`` [s],
    ``speed_table`` [rad/s] interpolated by a cubic spline.
    """

    mode: str = "dynamic"
    t_end: float = math.inf
    revolutions: float = math.inf
    speed: float = 0.0
    time: tuple[float, ...] = ()
    speed_table: tuple[float, ...] = ()


@dataclass(frozen=True)
class Solver:
    """Integration settings. ``switch_speed`` [rad/s]: below it time is the independent variable;
    ``domain``: ``"auto"`` (crank angle above the switch speed) or ``"time"`` (time throughout,
    for comparison; the maximum step is then bounded by the output spacing only).
    ``fixed_step`` [rad]: 0 for adaptive steps; > 0 for steps of that crank angle (compiled
    methods; the last step before a breakpoint ends on it), with no error control, for periodic
    steady runs. Time-domain stretches (below the switch speed) stay adaptive.
    ``kinematics``: ``"exact"`` (the mechanism kernel at every evaluation) or ``"tabulated"``
    (periodic quintic splines of J(φ) and u_k(φ), :mod:`transient.tabulate`), whose relative error
    is kept ≤ ``table_tolerance`` (0: 0.01·rtol); if no table reaches it the run uses the exact
    kernel and says so."""

    method: str = "dop853"
    rtol: float = 1e-8
    atol: float = 1e-10
    switch_speed: float = math.pi / 3.0  # 10 rpm
    max_step: float = math.pi  # [rad] in crank angle
    domain: str = "auto"
    fixed_step: float = 0.0
    kinematics: str = "exact"
    table_tolerance: float = 0.0


@dataclass(frozen=True)
class Output:
    """Output sampling: ``samples_per_rev`` in crank angle; in time mode every ``dt`` [s]."""

    samples_per_rev: int = 72
    dt: float = 0.0  # 0: Δφ / switch_speed


#: Output samples per revolution at most (0.00036° apart).
MAX_SAMPLES_PER_REV = 1_000_000

#: Smallest time-mode output spacing [s]: 10⁸ samples per second of engine time, already
#: 0.8 GB per column and second before compression.
MIN_OUTPUT_DT = 1e-8

#: The compiled methods (transient.core.tableaus) and the reference path's (scipy-*).
COMPILED_METHODS = ("dop853", "dopri5")
METHODS = (*COMPILED_METHODS, "scipy-DOP853", "scipy-RK45", "scipy-Radau")


def runs_compiled(scene) -> bool:
    """Whether ``scene`` runs on the compiled stepper (a dynamic run by a compiled method): its
    results stream to the file, and its kernels load from numba's cache, or compile."""
    return scene.run.mode == "dynamic" and scene.solver.method in COMPILED_METHODS


@dataclass(frozen=True)
class Pair:
    """A non-ideal kinematic pair between two neighbouring links (Antonyuk (22)–(25)).

    ``between``: the link on the shaft side first (a), then the far one (b), names from the
    mechanism's ``links``. ``eta_forward`` = η_ba, the efficiency while a (the shaft side) drives;
    ``eta_backward`` = η_ab, while b drives; both in (0, 1] [1].
    """

    between: tuple[str, str]
    eta_forward: float
    eta_backward: float
    name: str = ""


@dataclass(frozen=True)
class Friction:
    """Non-ideal pairs and how their modes are chosen (``transient.core.chain``).

    ``policy``: ``"power-flow"`` (each pair's mode agrees with the power it transmits) or
    ``"paper"`` (criterion (25), the sign of the shaft-side moments' power).
    """

    policy: str = "power-flow"
    pairs: tuple[Pair, ...] = ()


POLICIES = ("power-flow", "paper")


@dataclass(frozen=True)
class Analysis:
    """Derived results computed after the run and stored under ``/analysis`` only when asked
    (:mod:`transient.analysis.requested` lists the names and units).

    ``loads``: forces, crankpin and main-journal loads, running torques over the last cycle
    (crank-slider). ``orders``: signals whose order spectrum is stored per whole cycle —
    trajectory columns (``omega``, ``M_gas``, ``p_1`` …) or ``W_<k>``, the piston acceleration of
    cylinder k. ``irregularity``: δ and the mean speed of every cycle. ``max_order`` [1/rev]:
    orders stored up to it. ``samples_per_cycle``: crank-angle grid per engine cycle.
    ``detrend``: ``"auto"`` (the ramp for a spin-up, none otherwise), ``"ramp"`` or ``"none"``
    (:func:`transient.analysis.orders.order_spectrum`).
    """

    loads: bool = False
    orders: tuple[str, ...] = ()
    irregularity: bool = False
    max_order: float = 12.0
    samples_per_cycle: int = 720
    detrend: str = "auto"

    @property
    def requested(self) -> bool:
        return self.loads or bool(self.orders) or self.irregularity


DETREND = ("auto", "ramp", "none")


@dataclass(frozen=True)
class Scene:
    name: str
    description: str
    mechanism: CrankSlider | SwashPlate | Articulated
    inertia: Inertia = field(default_factory=Inertia)
    gas: Gas = field(default_factory=Gas)
    load: Load = field(default_factory=Load)
    starter: Starter = field(default_factory=Starter)
    governor: Governor = field(default_factory=Governor)
    initial: Initial = field(default_factory=Initial)
    run: Run = field(default_factory=Run)
    solver: Solver = field(default_factory=Solver)
    output: Output = field(default_factory=Output)
    friction: Friction = field(default_factory=Friction)
    analysis: Analysis = field(default_factory=Analysis)


# ----------------------------------------------------------------------------------------------
# Readers, one per section


MECHANISMS = {"crank-slider": read_crank_slider, "swash-plate": read_swash_plate,
              "articulated": read_articulated}


def _read_gas(s: Section, base_dir: Path, strokes: int) -> Gas:
    gas = _read_gas_model(s, base_dir, strokes)
    if gas.model == "none":
        return gas
    cycle = 2.0 * math.pi * strokes / 2
    return replace(gas, injection=s.number("injection", "angle", None, ge=0.0, lt=cycle))


def _read_gas_model(s: Section, base_dir: Path, strokes: int) -> Gas:
    model = s.string("model", "none",
                     choices=("none", "table", "mixed-cycle", "trapezoid", "wiebe"))
    if model == "trapezoid":  # a force per piston [N] (Antonyuk §4): no pressure, no p0
        return Gas(model="trapezoid", p0=0.0, amplitude=s.number("amplitude", ge=0.0),
                   ramp=s.number("ramp", "angle", gt=0.0),
                   duration=s.number("duration", "angle", math.pi, gt=0.0))
    p0 = s.number("p0", "pressure", 1.0e5, ge=0.0)
    if model == "none":
        return Gas(model="none", p0=p0)
    if model == "table":
        if s.has("file"):
            phi, p = _read_pressure_csv(s, base_dir)
        else:
            phi = s.numbers("phi", "angle")
            p = s.numbers("p", "pressure")
        corners = s.numbers("corners", "angle", ())
        interp = s.string("interpolation", "pchip", choices=("pchip", "spline", "linear"))
        return Gas(model="table", p0=p0, phi=phi, p=p, corners=corners, interpolation=interp)
    if model == "wiebe":
        return _read_wiebe(s, p0, strokes)
    return Gas(
        model="mixed-cycle", p0=p0,
        compression_ratio=s.number("compression_ratio", gt=1.0),
        p_a=s.number("p_a", "pressure", gt=0.0), n1=s.number("n1", gt=1.0),
        p_z=s.number("p_z", "pressure", gt=0.0), rho=s.number("rho", ge=1.0),
        n2=s.number("n2", gt=1.0), p_intake=s.number("p_intake", "pressure", gt=0.0),
        p_exhaust=s.number("p_exhaust", "pressure", gt=0.0))


def _read_wiebe(s: Section, p0: float, strokes: int) -> Gas:
    """``model = "wiebe"``: the cycle's pressures in [gas], the combustion in [gas.wiebe].

    Ranges of single keys are checked here; what needs several of them (the combustion inside
    the closed part, γ(T) > 1 at intake closing) by :mod:`transient.forces.wiebe` when the table
    is built, still inside :func:`load_scene` (``_check_gas_table``).
    """
    d = Wiebe()
    ratio = s.number("compression_ratio", gt=1.0)
    p_a = s.number("p_a", "pressure", gt=0.0)
    # A 2-stroke is scavenged to p_a: it has no intake or exhaust stroke.
    need = _MISSING if strokes == 4 else 0.0
    p_in = s.number("p_intake", "pressure", need, ge=0.0)
    p_ex = s.number("p_exhaust", "pressure", need, ge=0.0)
    w = s.sub("wiebe", required=True)
    wiebe = Wiebe(
        start=w.number("start", "angle"), duration=w.number("duration", "angle", gt=0.0),
        fuel_mass=w.number("fuel_mass", ge=0.0), a=w.number("a", default=d.a, gt=0.0),
        m=w.number("m", default=d.m, gt=-1.0), lhv=w.number("lhv", default=d.lhv, gt=0.0),
        efficiency=w.number("efficiency", default=d.efficiency, gt=0.0, le=1.0),
        gamma=w.number("gamma", default=d.gamma, gt=1.0),
        gamma_slope=w.number("gamma_slope", default=d.gamma_slope),
        gamma_t_ref=w.number("gamma_t_ref", default=d.gamma_t_ref, gt=0.0),
        t_a=w.number("t_a", default=d.t_a, gt=0.0),
        intake_closing=w.number("intake_closing", "angle", None),
        exhaust_opening=w.number("exhaust_opening", "angle", None),
        step=w.number("step", "angle", d.step, gt=0.0),
        tolerance=w.number("tolerance", default=d.tolerance, gt=0.0))
    w.finish()
    woschni = None
    if s.has("woschni"):
        h, dh = s.sub("woschni"), Woschni()
        woschni = Woschni(c1=h.number("c1", default=dh.c1, ge=0.0),
                          c2=h.number("c2", default=dh.c2, ge=0.0),
                          wall_temperature=h.number("wall_temperature", default=dh.wall_temperature,
                                                    gt=0.0))
        h.finish()
    return Gas(model="wiebe", p0=p0, compression_ratio=ratio, p_a=p_a, p_intake=p_in,
               p_exhaust=p_ex, wiebe=wiebe, woschni=woschni)


def _read_pressure_csv(s: Section, base_dir: Path):
    """Indicator diagram from a CSV with an angle column and a pressure column (units in names)."""
    name = s.string("file")
    path = (base_dir / name).resolve()
    if not path.is_file():
        raise SceneError(s.key("file"), f"no such file {str(path)!r}; give a CSV path relative "
                                        f"to the scene")
    angle_cols = {"phi_deg": math.pi / 180.0, "phi": 1.0}
    p_cols = {"p": 1.0, "p_bar": 1e5, "p_MPa": 1e6, "p_Pa": 1.0}
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            rows = list(csv.reader(line for line in fh if not line.startswith("#")))
    except UnicodeDecodeError as exc:
        raise SceneError(s.key("file"), f"{path.name}: not UTF-8 text (byte {exc.start}); "
                                        f"save the table as UTF-8 CSV") from None
    header = [h.strip() for h in rows[0]] if rows else []
    a = next((c for c in header if c in angle_cols), None)
    b = next((c for c in header if c in p_cols), None)
    if a is None or b is None:
        raise SceneError(s.key("file"), f"{path.name}: needs an angle column ({', '.join(angle_cols)})"
                                        f" and a pressure column ({', '.join(p_cols)}); "
                                        f"header is {header}")
    ia, ib = header.index(a), header.index(b)
    try:
        phi = tuple(float(r[ia]) * angle_cols[a] for r in rows[1:] if r)
        p = tuple(float(r[ib]) * p_cols[b] for r in rows[1:] if r)
    except (ValueError, IndexError) as exc:
        raise SceneError(s.key("file"), f"{path.name}: a row is not numeric ({exc})") from None
    return phi, p


def _read_friction(s: Section, links: tuple[str, ...]) -> Friction:
    """The [friction] table: a policy and an array of [[friction.pairs]] between neighbouring
    links of the mechanism (shaft side first)."""
    policy = s.string("policy", "power-flow", choices=POLICIES)
    s.known.append("pairs")
    raw = s.data.pop("pairs", [])
    if not isinstance(raw, list):
        raise SceneError(s.key("pairs"), "must be an array of tables ([[friction.pairs]])")
    chain = " – ".join(links)
    pairs, seen = [], {}
    for i, item in enumerate(raw):
        ps = Section(item, f"{s.key('pairs')}[{i}]")
        ps.known.append("between")
        between = ps.data.pop("between", None)
        if (not isinstance(between, list) or len(between) != 2
                or not all(isinstance(b, str) for b in between)):
            raise SceneError(ps.key("between"), f"must be two link names, got {_show(between)}; "
                                                f"the links are {chain}")
        for b in between:
            if b not in links:
                raise SceneError(ps.key("between"), f"unknown link {b!r}; the links are {chain}")
        ia, ib = links.index(between[0]), links.index(between[1])
        if abs(ia - ib) != 1:
            raise SceneError(ps.key("between"),
                             f"{between[0]!r} and {between[1]!r} are not neighbours; a pair joins "
                             f"two adjacent links of the chain {chain}")
        if ib < ia:
            raise SceneError(ps.key("between"), f"give the shaft-side link first: "
                                                f"[{between[1]!r}, {between[0]!r}]")
        if ia in seen:
            raise SceneError(ps.key("between"), f"the same pair as {s.key('pairs')}[{seen[ia]}]")
        seen[ia] = i
        pair = Pair(between=(between[0], between[1]), eta_forward=_efficiency(ps, "eta_forward"),
                    eta_backward=_efficiency(ps, "eta_backward"),
                    name=ps.string("name", f"{between[0]}-{between[1]}"))
        ps.finish()
        twin = next((j for j, q in enumerate(pairs) if q.name == pair.name), None)
        if twin is not None:
            raise SceneError(ps.key("name"), f"{pair.name!r} names {s.key('pairs')}[{twin}] "
                                             f"too; give each pair its own name (it labels the "
                                             f"pair's result columns and reports)")
        pairs.append(pair)
    pairs.sort(key=lambda p: links.index(p.between[0]))
    return Friction(policy, tuple(pairs))


def _efficiency(s: Section, name: str) -> float:
    """An efficiency in (0, 1]; η ≤ 0 would be a self-locking pair, which the model excludes."""
    eta = s.number(name, le=1.0)
    if eta <= 0.0:
        raise SceneError(s.key(name), f"must be > 0, got {eta:g}; an efficiency ≤ 0 is a "
                                      f"self-locking pair (the paper's ξ regime), not modelled")
    return eta


#: Distinct abscissae of a load schedule closer than this (relative to max(1, |x|)) are
#: refused: a ramp that short is a step to the solver, and the event search could not tell its
#: two corners apart (``transient.core.integrate.ON_LEVEL`` is 1e-12).
SCHEDULE_MIN_GAP = 1e-9


def _read_load(s: Section) -> Load:
    """The [load] table: resisting torques, a generator and the schedule of their scale."""
    torque = s.number("torque", default=0.0, ge=0.0)
    linear = s.number("linear", default=0.0, ge=0.0)
    fan = s.number("fan", default=0.0, ge=0.0)
    power = s.number("generator_power", default=0.0, ge=0.0)
    given = s.has("generator_min_speed", "speed")
    w_min = s.number("generator_min_speed", "speed", 0.0, ge=0.0)
    if power > 0.0 and w_min <= 0.0:
        key = s.key(s.written.get("generator_min_speed", "generator_min_speed"))
        what = "must be > 0" if given else "is missing"
        raise SceneError(key, f"{what} with a generator_power: below it the torque −P/ω is held "
                              f"at −P/ω_min (finite at rest); give 'generator_min_speed' or "
                              f"'generator_min_speed_rpm' > 0")
    times = s.numbers("schedule_time", default=())
    revs = s.numbers("schedule_revolutions", default=())
    scale = s.numbers("schedule_scale", default=())
    if times and revs:
        raise SceneError(s.key("schedule_revolutions"),
                         "given together with 'schedule_time'; a schedule runs against time or "
                         "against revolutions: give one of them")
    name, x = ("schedule_time", times) if times else ("schedule_revolutions", revs)
    if scale and not x:
        raise SceneError(s.key("schedule_scale"), "has no abscissae; give 'schedule_time' [s] or "
                                                  "'schedule_revolutions' with one entry per "
                                                  "value")
    if x and not scale:
        raise SceneError(s.key(name), "has no values; give 'schedule_scale', the load's scale "
                                      "at each entry")
    if len(x) != len(scale):
        raise SceneError(s.key("schedule_scale"), f"needs as many entries as {name!r}; got "
                                                  f"{len(scale)} and {len(x)}")
    for i in range(1, len(x)):
        a, b = x[i - 1], x[i]
        if b < a:
            raise SceneError(s.key(name), f"must not decrease, but {b:g} follows {a:g} (entry "
                                          f"{i + 1}); a step is two equal entries, a ramp two "
                                          f"increasing ones")
        if i >= 2 and x[i - 2] == a == b:
            raise SceneError(s.key(name), f"{b:g} appears three times in a row (entries {i - 1} "
                                          f"to {i + 1}); a step is two equal entries: the value "
                                          f"before and the value after")
        if 0.0 < b - a < SCHEDULE_MIN_GAP * max(1.0, abs(a), abs(b)):
            raise SceneError(s.key(name), f"{a!r} and {b!r} (entries {i} and {i + 1}) are closer "
                                          f"than {SCHEDULE_MIN_GAP:g} (relative); give equal "
                                          f"entries for a step, or a longer ramp")
    for i, v in enumerate(scale):
        if v < 0.0:
            raise SceneError(s.key("schedule_scale"), f"must be ≥ 0, got {v:g} (entry {i + 1}); "
                                                      f"the scale multiplies a resisting load")
    extra = s.number("inertia", default=0.0, ge=0.0)
    at = s.number("inertia_time", default=_MISSING if extra > 0.0 else 0.0, gt=0.0)
    return Load(torque, linear, fan, power, w_min, times, revs, scale, extra, at)


def _read_governor(s: Section) -> Governor:
    model = s.string("model", "none", choices=tuple(GOVERNOR_KEYS))
    if model == "none":
        return Governor()
    if model == "droop":
        full = s.number("speed_full", "speed", gt=0.0)
        zero = s.number("speed_zero", "speed", gt=full)
        return Governor(model, full, zero)
    d = Governor()
    f_min = s.number("fuel_min", default=d.fuel_min, ge=0.0)
    f_max = s.number("fuel_max", default=d.fuel_max, gt=f_min)
    if model == "flyweight":
        return Governor(
            model, fuel_min=f_min, fuel_max=f_max, weights=s.integer("weights", d.weights, ge=1),
            weight_mass=s.number("weight_mass", gt=0.0), radius=s.number("radius", "length", gt=0.0),
            arm_ratio=s.number("arm_ratio", default=d.arm_ratio, gt=0.0),
            gear_ratio=s.number("gear_ratio", default=d.gear_ratio, gt=0.0),
            sleeve_mass=s.number("sleeve_mass", default=0.0, ge=0.0),
            spring_rate=s.number("spring_rate", ge=0.0),
            spring_preload=s.number("spring_preload", gt=0.0),
            damping=s.number("damping", ge=0.0), travel=s.number("travel", "length", gt=0.0))
    gain_p = s.number("gain_p", ge=0.0)
    gain_i = s.number("gain_i", ge=0.0)
    if gain_p == 0.0 and gain_i == 0.0:
        raise SceneError(s.key("gain_i"), "gain_p and gain_i are both 0: the governor would never "
                                          "move the rack; give gain_i > 0 (isochronous)")
    return Governor(
        model, speed=s.number("speed", "speed", gt=0.0), gain_p=gain_p, gain_i=gain_i,
        gain_d=s.number("gain_d", default=0.0, ge=0.0),
        derivative_time=s.number("derivative_time", default=d.derivative_time, gt=0.0),
        actuator_time=s.number("actuator_time", default=d.actuator_time, gt=0.0),
        rate_limit=s.number("rate_limit", default=0.0, ge=0.0),
        fuel_min=f_min, fuel_max=f_max, anti_windup=s.flag("anti_windup", True),
        tracking_time=s.number("tracking_time", default=0.0, ge=0.0),
        fuel_initial=s.number("fuel_initial", default=f_max, ge=f_min, le=f_max))


def _read_run(s: Section) -> Run:
    mode = s.string("mode", "dynamic", choices=("dynamic", "prescribed-speed"))
    t_end = s.number("t_end", default=math.inf, gt=0.0)
    revs = s.number("revolutions", default=math.inf, gt=0.0)
    if math.isinf(t_end) and math.isinf(revs):
        raise SceneError(s.key("t_end"), "the run needs an end: give t_end [s] and/or revolutions")
    if mode == "dynamic":
        return Run(mode=mode, t_end=t_end, revolutions=revs)
    if s.has("speed", "speed"):
        speed = s.number("speed", "speed", gt=0.0)
        return Run(mode=mode, t_end=t_end, revolutions=revs, speed=speed)
    if not s.has("time") and not s.has("speed_table", "speed"):
        raise SceneError(s.key("speed"), "is missing; a prescribed-speed run needs 'speed' (or "
                                         "'speed_rpm'), or a table 'time' [s] with 'speed_table'")
    time = s.numbers("time")
    table = s.numbers("speed_table", "speed")
    if len(time) != len(table) or len(time) < 2:
        raise SceneError(s.key("speed_table"), f"needs as many entries as 'time' (≥ 2); got "
                                               f"{len(table)} and {len(time)}")
    if any(b <= a for a, b in zip(time, time[1:])):
        raise SceneError(s.key("time"), "must increase strictly")
    if min(table) <= 0:
        raise SceneError(s.key("speed_table"), "speeds must be > 0 in a prescribed-speed run")
    return Run(mode=mode, t_end=min(t_end, time[-1]), revolutions=revs, time=time,
               speed_table=table)


def scene_from_dict(data: dict, file: str = "", base_dir: Path | None = None) -> Scene:
    """Build and validate a scene from parsed TOML. Raises :class:`SceneError`."""
    base_dir = base_dir or Path.cwd()
    try:
        root = Section(data, "")
        head = root.sub("scene")
        name = head.string("name", Path(file).stem if file else "scene")
        if not name.strip():
            raise SceneError(head.key(head.written.get("name", "name")),
                             "must not be empty; it names the result (leave it out to use the "
                             "file's name)")
        description = head.string("description", "")
        head.finish()
        ms = root.sub("mechanism", required=True)
        kind = ms.string("type", choices=tuple(MECHANISMS))
        mech = MECHANISMS[kind](ms)
        ms.finish()
        sections = {}
        si = root.sub("inertia")
        sections["inertia"] = Inertia(si.number("shaft", default=0.0, ge=0.0),
                                      si.number("flywheel", default=0.0, ge=0.0),
                                      si.number("load", default=0.0, ge=0.0))
        si.finish()
        sg = root.sub("gas")
        sections["gas"] = _read_gas(sg, base_dir, mech.strokes)
        sg.finish()
        sl = root.sub("load")
        sections["load"] = _read_load(sl)
        sl.finish()
        ss = root.sub("starter")
        torque = ss.number("torque", default=0.0, ge=0.0)
        noload = ss.number("noload_speed", "speed", 1.0, gt=0.0)
        cutout = ss.number("cutout_speed", "speed", noload, gt=0.0, le=noload)
        sections["starter"] = Starter(torque, noload, cutout)
        ss.finish()
        sgv = root.sub("governor")
        sections["governor"] = _read_governor(sgv)
        sgv.finish()
        s0 = root.sub("initial")
        sections["initial"] = Initial(s0.number("phi", "angle", 0.0),
                                      s0.number("omega", "speed", 0.0))
        s0.finish()
        sr = root.sub("run", required=True)
        sections["run"] = _read_run(sr)
        sr.finish()
        sv = root.sub("solver")
        sections["solver"] = Solver(
            method=sv.string("method", "dop853", choices=METHODS),
            rtol=sv.number("rtol", default=1e-8, gt=0.0, lt=1.0),
            atol=sv.number("atol", default=1e-10, gt=0.0),
            switch_speed=sv.number("switch_speed", "speed", math.pi / 3.0, gt=0.0),
            max_step=sv.number("max_step", "angle", math.pi, gt=0.0),
            domain=sv.string("domain", "auto", choices=("auto", "time")),
            fixed_step=sv.number("fixed_step", "angle", 0.0, ge=0.0),
            kinematics=sv.string("kinematics", "exact", choices=("exact", "tabulated")),
            table_tolerance=sv.number("table_tolerance", default=0.0, ge=0.0, lt=1.0))
        sv.finish()
        so = root.sub("output")
        spr = so.integer("samples_per_rev", 72, ge=4)
        if spr > MAX_SAMPLES_PER_REV:  # (every sample is written: a run must stay finite)
            raise SceneError(so.key("samples_per_rev"), f"must be ≤ {MAX_SAMPLES_PER_REV}, got "
                                                        f"{spr}")
        dt = so.number("dt", default=0.0, ge=0.0)
        if 0.0 < dt < MIN_OUTPUT_DT:  # (every sample is written: a run must stay finite)
            raise SceneError(so.key("dt"), f"must be 0 (the default spacing) or ≥ "
                                           f"{MIN_OUTPUT_DT:g} s, got {dt:g}")
        sections["output"] = Output(spr, dt)
        so.finish()
        sf = root.sub("friction")
        sections["friction"] = _read_friction(sf, mech.links)
        sf.finish()
        sa = root.sub("analysis")
        sections["analysis"] = _read_analysis(sa)
        sa.finish()
        root.finish()
        scene = Scene(name=name, description=description, mechanism=mech, **sections)
        _check_consistency(scene)
        _check_gas_table(scene, sg)
        _check_analysis(scene)
        return scene
    except SceneError as exc:
        exc.file = exc.file or file
        exc.args = (exc.line(),)
        raise


def _check_woschni(scene: Scene) -> None:
    """Wall heat transfer makes each cylinder's pressure a state of the ODE (built for the
    crank-slider's exact cylinder volume, integrated by the compiled and the reference paths)."""
    if not isinstance(scene.mechanism, CrankSlider):
        kind = {SwashPlate: "swash-plate", Articulated: "articulated"}[type(scene.mechanism)]
        raise SceneError("gas.woschni", f"wall heat transfer is built for crank-slider engines "
                                        f"(their cylinder volume enters the ODE), not for the "
                                        f"{kind!r} mechanism; leave [gas.woschni] out")
    if scene.run.mode == "prescribed-speed":
        raise SceneError("gas.woschni", "with wall heat transfer the cylinder pressures are "
                                        "states of the ODE, which a prescribed-speed run does not "
                                        "integrate; run it dynamic (a large flywheel holds the "
                                        "speed) or leave [gas.woschni] out")
    if scene.gas.wiebe.m < 0.0:
        raise SceneError("gas.wiebe.m", f"m = {scene.gas.wiebe.m:g}: with wall heat transfer the "
                                        f"heat-release rate enters the ODE, and for m < 0 it is "
                                        f"infinite at the combustion start; give m ≥ 0")
    if scene.solver.kinematics == "tabulated":
        raise SceneError("solver.kinematics", "the cylinder volumes of wall heat transfer use the "
                                              "exact kinematics; use kinematics = \"exact\"")


def _check_consistency(scene: Scene) -> None:
    """Checks across sections, done before any integration."""
    # (18) divides by J(φ): it must stay positive over the whole cycle, dead centres included.
    phi = np.linspace(0.0, scene.mechanism.cycle, 721)
    with np.errstate(over="ignore", invalid="ignore"):
        J = scene.mechanism.kinematics_table(phi)["J"] + scene.inertia.total
    if not np.all(np.isfinite(J)):
        raise SceneError("mechanism", "the reduced inertia J(φ) overflows (is not finite); "
                                      "check the masses and lengths and their units")
    try:
        area = scene.mechanism.piston_area
    except OverflowError:
        area = math.inf
    if not math.isfinite(area):
        raise SceneError("mechanism.bore", f"the piston area overflows; check the bore and its "
                                           f"unit (mm: 'bore_mm')")
    if J.min() <= 0.0:
        at = math.degrees(phi[int(np.argmin(J))])
        raise SceneError("inertia", f"the reduced inertia J(φ) falls to {J.min():.3g} kg m² at "
                                    f"φ = {at:g}°; give a shaft, flywheel or load inertia > 0")
    sv = scene.solver
    compiled = sv.method in COMPILED_METHODS
    if scene.friction.pairs and scene.friction.policy == "paper" and not compiled:
        raise SceneError("solver.method", "the reference path (scipy-*) follows the power-flow "
                                          "policy only; use method = \"dop853\" or \"dopri5\" "
                                          "with policy \"paper\"")
    if sv.fixed_step > 0.0 and not compiled:
        raise SceneError("solver.fixed_step", f"fixed steps need a compiled method "
                                              f"({', '.join(COMPILED_METHODS)}), not {sv.method!r}")
    if sv.kinematics == "tabulated" and not compiled:
        raise SceneError("solver.kinematics", f"tables are for the compiled methods "
                                              f"({', '.join(COMPILED_METHODS)}); the reference path "
                                              f"{sv.method!r} is exact by design")
    if sv.fixed_step > 0.0 and sv.domain == "time":
        raise SceneError("solver.fixed_step", "fixed steps are crank-angle steps; use "
                                              "domain = \"auto\" or fixed_step = 0")
    if scene.run.mode == "prescribed-speed" and scene.load.inertia > 0.0:
        raise SceneError("load.inertia", "a prescribed-speed run has no momentum to conserve when "
                                         "an inertia is switched in; leave it out (0)")
    if scene.gas.woschni is not None:
        _check_woschni(scene)
    if scene.run.mode == "prescribed-speed" and scene.governor.model in ("pi", "flyweight"):
        raise SceneError("governor.model", f"a prescribed-speed run integrates no governor state; "
                                           f"use model = \"none\" or \"droop\", not "
                                           f"{scene.governor.model!r}")
    if scene.run.mode == "dynamic" and scene.initial.omega == 0.0 and scene.starter.torque == 0.0:
        if scene.gas.model == "none":
            raise SceneError("initial.omega", "a machine at rest with no starter and no gas force "
                                              "never moves; give omega or a starter")


def _read_analysis(s: Section) -> Analysis:
    return Analysis(loads=s.flag("loads", False), orders=s.strings("orders", ()),
                    irregularity=s.flag("irregularity", False),
                    max_order=s.number("max_order", default=12.0, gt=0.0),
                    samples_per_cycle=s.integer("samples_per_cycle", 720, ge=16),
                    detrend=s.string("detrend", "auto", choices=DETREND))


def _check_analysis(scene: Scene) -> None:
    """The [analysis] signals exist in this scene's trajectory and the orders fit the grid."""
    from ..outputs import output_columns

    a, mech = scene.analysis, scene.mechanism
    crank_slider = isinstance(mech, CrankSlider)
    columns = list(output_columns(scene))
    derived = [f"W_{k + 1}" for k in range(mech.n_cylinders)] if crank_slider else []
    for name in a.orders:
        if name not in columns + derived:
            raise SceneError("analysis.orders", f"unknown signal {name!r}; allowed: "
                                                f"{', '.join(columns + derived)}")
    if len(set(a.orders)) != len(a.orders):
        raise SceneError("analysis.orders", "a signal is named twice; name each once")
    nyquist = (a.samples_per_cycle // 2) * 2.0 * math.pi / mech.cycle
    if a.orders and a.max_order > nyquist:
        raise SceneError("analysis.max_order", f"must be ≤ {nyquist:g} (the Nyquist order of "
                                               f"samples_per_cycle = {a.samples_per_cycle} over "
                                               f"a {math.degrees(mech.cycle):g}° cycle), got "
                                               f"{a.max_order:g}")


def _check_gas_table(scene: Scene, section: Section) -> None:
    """Build (and so validate) the pressure table; report under the key the user wrote."""
    from ..assemble import gas_table

    try:
        gas_table(scene)
    except SceneError as exc:
        if "file" in section.written and exc.key in ("gas.phi_deg", "gas.p", "gas.phi"):
            exc.key = "gas.file"
        raise section.rename(exc) from None


def load_scene(source: str | Path, *, text: str | None = None) -> Scene:
    """Read and validate a scene file (or TOML ``text``, with ``source`` naming it)."""
    path = Path(source)
    if text is None:
        try:
            text = path.read_text(encoding="utf-8-sig")  # (a byte-order mark is not TOML)
        except OSError as exc:
            raise SceneError("(file)", f"cannot read: {exc.strerror}", file=str(path)) from None
        except UnicodeDecodeError as exc:
            raise SceneError("(file)", f"not UTF-8 text (byte {exc.start}); save the scene as "
                                       f"UTF-8", file=str(path)) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("(syntax)", f"not valid TOML: {exc}", file=str(path)) from None
    return scene_from_dict(data, file=str(path), base_dir=path.parent)


# ----------------------------------------------------------------------------------------------
# Resolved scene → TOML (SI, every default filled in); load_scene reads it back to the same scene


def to_toml(scene: Scene) -> str:
    """The resolved scene as TOML in SI units (no suffixes), round-tripping through load_scene."""
    lines = ["# resolved scene: SI units, every default filled in (written by transient)",
             "[scene]", f"name = {toml_value(scene.name)}", f"description = {toml_value(scene.description)}"]
    lines += [""] + scene.mechanism.toml_lines()
    lines += _section("inertia", scene.inertia)
    lines += _gas_section(scene.gas)
    lines += _load_section(scene.load)
    lines += _section("starter", scene.starter)
    lines += ["", "[governor]"] + [f"{k} = {toml_value(getattr(scene.governor, k))}"
                                   for k in GOVERNOR_KEYS[scene.governor.model]]
    lines += _section("initial", scene.initial)
    run = {"mode": scene.run.mode}
    for k in ("t_end", "revolutions"):
        if math.isfinite(getattr(scene.run, k)):
            run[k] = getattr(scene.run, k)
    if scene.run.mode == "prescribed-speed":
        if scene.run.time:
            run.update(time=list(scene.run.time), speed_table=list(scene.run.speed_table))
        else:
            run["speed"] = scene.run.speed
    lines += ["", "[run]"] + [f"{k} = {toml_value(v)}" for k, v in run.items()]
    lines += _section("solver", scene.solver)
    lines += _section("output", scene.output)
    if scene.analysis.requested:  # (a scene that asks for nothing reads back the same without)
        lines += _section("analysis", scene.analysis)
    lines += ["", "[friction]", f"policy = {toml_value(scene.friction.policy)}"]
    for pair in scene.friction.pairs:
        lines += ["", "[[friction.pairs]]", f"name = {toml_value(pair.name)}",
                  f"between = {toml_value(list(pair.between))}",
                  f"eta_forward = {toml_value(pair.eta_forward)}",
                  f"eta_backward = {toml_value(pair.eta_backward)}"]
    return "\n".join(lines) + "\n"


def _gas_section(gas: Gas) -> list[str]:
    keep = {"none": ("model", "p0"), "table": ("model", "p0", "phi", "p", "corners", "interpolation"),
            "trapezoid": ("model", "amplitude", "ramp", "duration"),
            "wiebe": ("model", "p0", "compression_ratio", "p_a", "p_intake", "p_exhaust")}
    names = keep.get(gas.model, ("model", "p0", "compression_ratio", "p_a", "n1", "p_z", "rho",
                                 "n2", "p_intake", "p_exhaust"))
    if gas.injection is not None:
        names = (*names, "injection")
    lines = ["", "[gas]"] + [f"{k} = {toml_value(getattr(gas, k))}" for k in names]
    if gas.model == "wiebe":  # unset optional angles (None) are left out: they read back as None
        lines += ["", "[gas.wiebe]"] + [f"{f.name} = {toml_value(getattr(gas.wiebe, f.name))}"
                                        for f in fields(gas.wiebe)
                                        if getattr(gas.wiebe, f.name) is not None]
    if gas.woschni is not None:
        lines += ["", "[gas.woschni]"] + [f"{f.name} = {toml_value(getattr(gas.woschni, f.name))}"
                                          for f in fields(gas.woschni)]
    return lines


def _load_section(load: Load) -> list[str]:
    """[load] with the schedule's keys only when there is one (and only its abscissa)."""
    names = ["torque", "linear", "fan", "generator_power", "generator_min_speed"]
    if load.inertia > 0.0:
        names += ["inertia", "inertia_time"]
    if load.schedule_scale:
        names += ["schedule_revolutions" if load.schedule_revolutions else "schedule_time",
                  "schedule_scale"]
    return ["", "[load]"] + [f"{k} = {toml_value(getattr(load, k))}" for k in names]


def _section(name: str, obj: Any) -> list[str]:
    assert is_dataclass(obj)
    return ["", f"[{name}]"] + [f"{f.name} = {toml_value(getattr(obj, f.name))}" for f in fields(obj)]

