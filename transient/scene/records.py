"""The scene's records: frozen dataclasses in SI, one per TOML table, grouped by what they
describe (inertia, gas, load, starter, governor, initial state, run, solver, output, friction,
analysis), with the limits the reader checks them against. The mechanisms' records are the
classes of :mod:`transient.mechanisms`.

One idea, what a scene is as data: a record per table, each field with its unit, default and
limits in one place (the user guide's key tables are generated from them); reading the TOML
into them is :mod:`.read`, the checks across tables :mod:`.checks`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..mechanisms import Mechanism

if TYPE_CHECKING:
    from .read import replace_scene, scene_from_dict
    from .write import to_toml


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
    ``gamma`` [1]: heat capacity ratio, at ``gamma_t_ref`` [K] with ``gamma_slope`` dγ/dT [1/K];
    at most 5/3, a monatomic ideal gas's.
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
    cylinder is a state of the ODE instead of a table (``transient.core.model.cylinder``).

    ``c1`` [1] multiplies the mean piston speed, ``c2`` [m/(s K)] the pressure rise combustion
    causes (from the combustion start on; Woschni's direct-injection value by default);
    ``wall_temperature`` [K]: the mean temperature of head, piston crown and liner.
    """

    c1: float = 2.28
    c2: float = 3.24e-3
    wall_temperature: float = 450.0


#: Largest fuel or pressure factor of a cylinder [1]: beyond twice the full-load cycle the
#: interpolation p_mot + f·(p_full − p_mot) extrapolates far outside what its tables describe.
MAX_CYLINDER_FACTOR = 2.0
#: Largest combustion offset of a cylinder [rad] (30°): an injection timing's spread is a few
#: degrees, and a shift much larger would move a table's combustion into its gas exchange.
MAX_COMBUSTION_OFFSET = math.pi / 6.0


@dataclass(frozen=True)
class Cylinder:
    """How one cylinder departs from the others: a ``[[gas.cylinders]]`` entry.

    ``cylinder`` [1]: its number, 1 to the mechanism's cylinder count. ``fuel`` [1]: its fuel
    factor φ_k, multiplying the governor's command, so that its pressure is
    p_mot + φ_k·f·(p_full − p_mot) (:class:`Gas`; for ``"wiebe"`` with ``[gas.woschni]`` the
    heat released); ``cut_out``: no fuel in any cycle (φ_k = 0, the motored curve: the
    model's compression and expansion without heat release; for ``"trapezoid"`` no force).
    A pressure table needs its ``motored_p`` curve for these and the misfires below. ``pressure``
    [1]: its pressure factor β_k, multiplying its pressure above p0 where it acts on the piston,
    p0 + β_k·(p − p0) (a leaking cylinder, or an indicator's calibration): the gas force, the
    ``p_<k>`` column and the work all see it. Both in [0, 2].

    ``combustion_offset`` δ_k [rad] (``combustion_offset_deg``), within ±30°: its combustion
    happens δ_k later (earlier if negative),
    p = p_mot(x) + φ_k·f·(p_full(x − δ_k) − p_mot(x − δ_k)) at its local angle x: the
    combustion's part only, the motored compression staying with the piston (for
    ``"trapezoid"``, whose motored force is 0, the whole pulse); with ``[gas.woschni]`` the heat
    release and Woschni's combustion term of the closed part, which must then still lie inside
    it.

    **Misfire.** In a misfiring cycle the cylinder burns nothing (its fuel is 0 for that whole
    cycle): it follows the motored curve, compressing and expanding. A cylinder's cycles begin
    at its local angle 0 (the gas-exchange TDC of a 4-stroke) or π (the BDC of a 2-stroke, so
    that no combustion straddles two cycles); cycle 1 is the one in progress at the initial
    angle. ``misfire_cycles``: the cycles that misfire (each ≥ 1); ``misfire_every`` n [1]:
    cycles n, 2n, 3n, … misfire (0: none); ``misfire_rate`` [1] in [0, 1]: each cycle misfires
    with this probability, drawn from ``misfire_seed`` (a counter-based generator,
    :func:`transient.core.model.variation.misfire_draw`, the same draws for the same seed, cylinder
    and cycle in every run and on every machine). A cycle misfires if any of the three says
    so.
    """

    cylinder: int
    fuel: float = 1.0
    pressure: float = 1.0
    cut_out: bool = False
    misfire_cycles: tuple[int, ...] = ()
    misfire_every: int = 0
    misfire_rate: float = 0.0
    misfire_seed: int = 0
    combustion_offset: float = 0.0

    @property
    def combustion_keys(self) -> tuple[str, ...]:
        """The keys of this entry that change its combustion (the fuel it burns, or when), which
        act on the pressure above the motored curve; empty if it only scales the pressure."""
        keys = (("cut_out", self.cut_out), ("fuel", self.fuel != 1.0 and not self.cut_out),
                ("misfire_cycles", bool(self.misfire_cycles)),
                ("misfire_every", self.misfire_every > 0),
                ("misfire_rate", self.misfire_rate > 0.0),
                ("combustion_offset", self.combustion_offset != 0.0))
        return tuple(k for k, on in keys if on)


@dataclass(frozen=True)
class Gas:
    """Cylinder pressure model (angle-only in this version).

    ``model``: ``"none"``, ``"table"`` (indicator diagram: absolute pressures ``p`` [Pa] at the
    local angles ``phi`` [rad] over one cycle, local angle 0 = gas-exchange TDC for a 4-stroke,
    firing TDC for a 2-stroke; ``corners`` [rad] where the curve may jump or kink, also between
    samples; ``interpolation`` ``"pchip"``, ``"spline"`` or ``"linear"``; every angle of the
    table and every corner is a breakpoint; ``motored_p``: the motored pressures [Pa] at the same
    angles, optional), ``"mixed-cycle"`` (Gots App. 2,
    Trinkler–Sabathé: ``compression_ratio`` [1], ``p_a`` [Pa] at the start of compression,
    polytropic exponents ``n1`` and ``n2`` [1], peak pressure ``p_z`` [Pa], pre-expansion ratio
    ``rho`` [1] and, for a 4-stroke, ``p_intake`` and ``p_exhaust`` [Pa]; a 2-stroke, scavenged
    to ``p_a`` at bottom dead centre, has no gas-exchange strokes and refuses them),
    ``"trapezoid"`` (the swash-plate paper's
    force pulse per piston, §4: ``amplitude`` [N], ``ramp`` and ``duration`` [rad]) or
    ``"wiebe"`` (single-zone Wiebe combustion, :class:`Wiebe`; with ``compression_ratio``, ``p_a``
    [Pa] at intake closing and, for a 4-stroke, ``p_intake`` and ``p_exhaust`` [Pa]) or
    ``"compressor"`` (the ideal reciprocating compressor cycle of a compressor or pump,
    :mod:`transient.forces.compressor`: ``p_suction`` and ``p_discharge`` [Pa], polytropic
    exponents ``n`` of the compression and ``n_reexpansion`` of the clearance gas [1], clearance
    ratio ``clearance_ratio`` = V_c/V_s [1]; one cycle a turn, local angle 0 at the top dead
    centre; no fuel: no governor, no fuel factors, misfires or injection). ``p0`` is the
    crankcase pressure [Pa]: piston force (p − p0)·F_p, Gots (33). A ``"table"`` may give
    ``force`` [N] on each piston instead of ``p``: then the force is applied as it is (no
    piston area, no p0), as the trapezoid's.

    **Fuel command.** The governor's fuel f ∈ [0, 1] (1 without a governor) sets the cylinder
    pressure between a motored curve and the full-load curve, p = p_mot + f·(p_full − p_mot):
    the fuel scales the combustion, never the compression. For ``"mixed-cycle"`` p_mot is the
    cycle without heat release, the compression polytrope n1 both ways, and p_mot + f·(p_full −
    p_mot) is exactly the cycle that burns f times the heat at every angle
    (:func:`transient.forces.gas.mixed_cycle`, *Part load*). For ``"table"`` it is ``motored_p``,
    the user's motored curve: a table holds no account of which part of it is compression, so
    without ``motored_p`` a fuel below 1 (a governor, a fuel factor, a misfire or cut-out, a
    combustion offset) is refused. ``"trapezoid"`` is a force pulse without thermodynamics
    whose amplitude the governor sets (Antonyuk §4): f times the force, no force at f = 0.
    For ``"wiebe"`` p_mot is the cycle with
    no fuel and p_full the cycle with ``fuel_mass``: with a constant γ the single-zone pressure is
    linear in the fuel mass, so this is exactly the cycle burning f·fuel_mass. With
    ``gamma_slope`` ≠ 0 (γ(T)) it is not, and the pressure at part load is only approximately
    that cycle's: the author of :mod:`transient.forces.wiebe` reports up to about 2.5 % of p_max
    for fuel levels 0.02 g apart; ``tests/validation/test_wiebe_runs.py`` measures, on the Gots
    engine of ``cases/gots_diesel_wiebe.toml`` with γ = 1.38 − 1e-4·(T − 300 K), 1.1 % of the
    full-load p_max between 0 and 0.02 g and 2.1 % between 0 and 0.031 g (at f = 0.5; the
    indicated work at f = 0.25 is then 7.6 % low). Use a constant γ where part load matters.
    The result columns ``p_<k>`` hold the pressure so applied (the force, for ``"trapezoid"`` and
    a force table).

    **Per-cylinder variation.** ``cylinders``: the ``[[gas.cylinders]]`` entries
    (:class:`Cylinder`), a cylinder's fuel and pressure factors, its cut-out and its misfires;
    cylinders without an entry are as the model gives them.

    **Fuel latching.** With ``injection`` [rad] (a local angle, as the tables'), each cylinder
    takes the governor's command at its start of injection and burns that fuel until its next
    one, so that the governor acts with the real per-cylinder delay (event ``injection``);
    without it every cylinder follows the command at once.
    """

    model: str = "none"
    p0: float = 1.0e5
    phi: tuple[float, ...] = ()
    p: tuple[float, ...] = ()
    motored_p: tuple[float, ...] = ()
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
    force: tuple[float, ...] = ()
    p_suction: float = 0.0
    p_discharge: float = 0.0
    n: float = 0.0
    n_reexpansion: float = 0.0
    clearance_ratio: float = 0.0
    wiebe: Wiebe | None = None
    injection: float | None = None
    woschni: Woschni | None = None
    cylinders: tuple[Cylinder, ...] = ()


@dataclass(frozen=True)
class LoadTable:
    """A load from data, the ``[load.table]`` table: the resisting torque T(x) ``torque`` [N m]
    at the points of one abscissa, signed as ``[load] torque`` (> 0 resists the rotation, < 0
    drives it), interpolated by ``interpolation`` (:mod:`transient.forces.load_table`).

    The abscissa is one of ``speed`` (the shaft speed ω [rad/s]: a generator's, propeller's or
    fan's map), ``phi`` (the shaft angle in the engine cycle [rad], from 0 to the cycle's
    length, 720° for a 4-stroke: a valve train's or an accessory's torque; periodic) or ``time``
    [s] (a measured trace); the others are empty. Outside the speeds or times of the table its
    end values hold. The abscissae increase strictly; ``interpolation`` ``"linear"`` or
    ``"pchip"`` (monotone cubic, no overshoot). Inline, or from a CSV ``file`` next to the scene
    with a column of the abscissa (``speed``, ``speed_rpm``, ``phi``, ``phi_deg``, ``time``) and
    one ``torque``.
    """

    torque: tuple[float, ...]
    speed: tuple[float, ...] = ()
    phi: tuple[float, ...] = ()
    time: tuple[float, ...] = ()
    interpolation: str = "linear"

    @property
    def abscissa(self) -> str:
        """``"speed"``, ``"angle"`` or ``"time"``
        (:data:`transient.forces.load_table.ABSCISSAE`)."""
        return "speed" if self.speed else "angle" if self.phi else "time"

    @property
    def x(self) -> tuple[float, ...]:
        """The points of the abscissa, in SI."""
        return self.speed or self.phi or self.time


@dataclass(frozen=True)
class Load:
    """Load moment M_load = −s·(torque + linear·ω + fan·ω|ω| + P/max(ω, ω_min) + T(x)) [N m]
    (signs as Gots §1: + with rotation, so M_load < 0 resists and > 0 drives).

    ``torque`` [N m]: > 0 resists the rotation, < 0 drives it (a constant driving torque).
    ``linear`` [N m s], ``fan`` [N m s²] ≥ 0. ``table``: a load from data, T(x)
    (:class:`LoadTable`), or None. ``generator_power`` P [W]: an
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
    table: LoadTable | None = None


@dataclass(frozen=True)
class Starter:
    """Starter: M = torque·(1 − ω/noload_speed) until ω first reaches cutout_speed [N m, rad/s]."""

    torque: float = 0.0
    noload_speed: float = 1.0
    cutout_speed: float = 1.0


@dataclass(frozen=True)
class Governor:
    """Speed governor, setting the fuel command f (see :class:`Gas`); equations in
    :mod:`transient.core.model.governor`.

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


#: Default of ``[run] max_output_bytes``: 4 GB, more than any scene of ``cases/`` writes by far
#: and less than a laptop's free disk.
DEFAULT_MAX_OUTPUT_BYTES = 4e9
#: Default of ``[run] max_steps``: 10⁹ step attempts, hours of stepping.
DEFAULT_MAX_STEPS = 1e9


@dataclass(frozen=True)
class Run:
    """What to run: ``dynamic`` (integrate (18)) or ``prescribed-speed`` (inverse dynamics).

    The run ends at ``t_end`` [s] or after ``revolutions`` of the shaft, whichever comes first
    (``inf`` = not set); it did what they ask if the shaft turned the revolutions, or with
    ``t_end`` alone runs forwards at the end (status ``finished``; ``t_end`` first is
    ``out-of-time``: :data:`transient.outcome.STATUSES`). For prescribed speed: ``speed``
    [rad/s] constant, or a table ``time`` [s], ``speed_table`` [rad/s] interpolated by
    ``interpolation``: ``"linear"`` (the default: a table with corners, a ramp to a plateau, is
    followed exactly, with ε jumping at each point) or ``"pchip"`` (monotone cubic, C¹: it never
    overshoots the table's speeds); :mod:`transient.forces.load_table`.

    Budgets (:mod:`.budget`), so that a mistyped end or limit is refused before any work instead
    of filling the disk or running for ever: ``max_output_bytes`` [bytes], the trajectory a run
    may write (8 bytes a value before compression) and the analysis grid it may hold;
    ``max_steps`` [1], the step attempts its limits may imply and it may take.
    """

    mode: str = "dynamic"
    t_end: float = math.inf
    revolutions: float = math.inf
    speed: float = 0.0
    time: tuple[float, ...] = ()
    speed_table: tuple[float, ...] = ()
    interpolation: str = "linear"
    max_output_bytes: float = DEFAULT_MAX_OUTPUT_BYTES
    max_steps: float = DEFAULT_MAX_STEPS


#: The multirevolution envelope's relative tolerance by default (``solver.envelope_rtol``).
ENVELOPE_RTOL = 1e-7


@dataclass(frozen=True)
class Solver:
    """Integration settings. ``method``: one of
    :data:`~transient.scene.records.METHODS`: ``"dop853"`` (explicit, order 8, the default),
    ``"dopri5"`` (explicit, order 5), ``"ros34pw2"`` (linearly implicit Rosenbrock–W, order 3,
    L-stable, for an elastic ``[shaft]`` line whose stiff sections would hold an explicit
    method's step by stability: one banded factorisation of the line's Jacobian a step;
    only with ``[shaft]``), ``"auto"`` (DOP853; where Hairer's stiffness test finds an
    elastic line's steps held by stability, ROS34PW2 and DOP853 are tried from there and the
    one that advances further per evaluation runs on; a rigid scene's is DOP853's), or a
    reference path's (``"scipy-*"``); ``rtol`` [1] and ``atol``
    (in the units of each state) as scipy's; ``max_step`` [rad] in crank angle.
    ``switch_speed`` [rad/s]: below it time is the independent variable;
    ``domain``: ``"auto"`` (crank angle above the switch speed) or ``"time"`` (time throughout,
    for comparison; the maximum step is then bounded by the output spacing only).
    ``fixed_step`` [rad]: 0 for adaptive steps; > 0 for steps of that crank angle (compiled
    methods; the last step before a breakpoint ends on it), with no error control, for periodic
    steady runs. Time-domain stretches (below the switch speed) stay adaptive.
    ``kinematics``: ``"exact"`` (the mechanism kernel at every evaluation) or ``"tabulated"``
    (periodic quintic splines of J(φ) and u_k(φ), :mod:`transient.tabulate`), whose relative error
    is kept ≤ ``table_tolerance`` (0: 0.01·rtol); if no table reaches it the run uses the exact
    kernel and says so.
    ``multirevolution``: ``transient run`` follows the run on the envelope of its cycle map
    (:mod:`transient.multirev`), macro steps over many cycles, to the envelope's relative
    tolerance ``envelope_rtol`` [1]; the run must be a whole number of cycles."""

    method: str = "dop853"
    rtol: float = 1e-8
    atol: float = 1e-10
    switch_speed: float = math.pi / 3.0  # 10 rpm
    max_step: float = math.pi
    domain: str = "auto"
    fixed_step: float = 0.0
    kinematics: str = "exact"
    table_tolerance: float = 0.0
    multirevolution: bool = False
    envelope_rtol: float = ENVELOPE_RTOL


@dataclass(frozen=True)
class Output:
    """Output sampling. In crank angle (forwards, above the switch speed) a sample every
    360°/``samples_per_rev``. In time (below the switch speed, whenever the shaft turns
    backwards, ``solver.domain = "time"``) a sample every ``dt`` [s] (0: the angle spacing at
    1.5 × the switch speed), and besides wherever the shaft angle crosses a multiple of
    360°/``samples_per_rev``, either way, and at every speed reversal (the turning point, ω = 0):
    so a rocking or reversing shaft is sampled as densely in angle as one turning forwards, and
    ``dt`` bounds the time between the samples of a slow one. (The reference path, scipy-*,
    writes its own steps.)"""

    samples_per_rev: int = 72
    dt: float = 0.0  # 0: Δφ / switch_speed


#: A speed no piston machine reaches [rad/s] (about 955 000 rpm): beyond it a run ran away
#: (status ``runaway``), and a scene that would start there, or whose torques would drive its
#: least inertia there within a revolution, is refused (``checks.check_magnitudes``).
RUNAWAY_SPEED = 1e5

#: The largest ratio of specific heats of an ideal gas, a monatomic one's (γ = 1 + 2/f, f ≥ 3
#: degrees of freedom): the Wiebe cycle's ``gamma`` is at most this.
MAX_GAMMA = 5.0 / 3.0

#: Output samples per revolution at most (0.00036° apart).
MAX_SAMPLES_PER_REV = 1_000_000

#: Smallest knot spacing of the Wiebe tables [rad] (0.00057°): 1.3 million knots a 720° cycle,
#: and a finer one would only fill memory (their tolerance refines them where it matters).
MIN_WIEBE_STEP = 1e-5

#: Smallest time-mode output spacing [s]: 10⁸ samples per second of engine time, already
#: 0.8 GB per column and second before compression.
MIN_OUTPUT_DT = 1e-8

#: The compiled methods (transient.core.integrator.tableaus) and the reference path's (scipy-*).
COMPILED_METHODS = ("dop853", "dopri5", "ros34pw2", "auto")
#: The compiled methods that take the elastic shaft line's Jacobian (linearly implicit).
W_METHODS = ("ros34pw2",)
#: ``"auto"``: the explicit method a run starts with, and the W-method it tries where the
#: stiffness test finds an elastic line's steps held by stability (``transient.run``).
AUTO_METHODS = ("dop853", "ros34pw2")
#: Every ``[solver] method``: the compiled ones, then the reference path's.
METHODS = (*COMPILED_METHODS, "scipy-DOP853", "scipy-RK45", "scipy-Radau")


def runs_compiled(scene) -> bool:
    """Whether ``scene`` runs on the compiled stepper (a dynamic run by a compiled method): its
    results stream to the file, and its kernels load from numba's cache, or compile."""
    return scene.run.mode == "dynamic" and scene.solver.method in COMPILED_METHODS


@dataclass(frozen=True)
class Pair:
    """A non-ideal kinematic pair between two neighbouring links (Antonyuk (22)–(25)).

    ``between``: the link on the shaft side first (a), then the far one (b), names from the
    mechanism's ``links`` (crank-slider and articulated ``shaft`` – ``crank`` – ``rod`` –
    ``piston`` – ``cylinder``, swash plate ``shaft`` – ``link`` – ``rod`` – ``piston`` –
    ``cylinder``; any number of pairs, each couple of neighbours once, gaps allowed; a pair into
    the ``cylinder`` passes on the gas forces' work, so it needs a gas model); for the reaction
    model two links of one of its reaction joints
    (``transient.mechanisms.reaction_joints``): crank-slider ``shaft`` – ``crank`` – ``rod`` –
    ``piston`` – ``cylinder``, swash plate ``shaft`` – ``plate`` – ``link`` – ``rod`` – ``piston``
    – ``cylinder`` (its ball joints, ``["link", "rod"]`` and ``["rod", "piston"]``, stay ideal),
    the articulated mechanism's joints by their links. ``eta_forward`` = η_ba, the efficiency
    while a (the shaft side) drives; ``eta_backward`` = η_ab, while b drives; both in (0, 1] [1].

    On an elastic ``[shaft]`` line each pair acts in every station that carries cylinders, in
    that throw's chain (theory, (T7)): its ``shaft`` is the station's own inertia, which the
    sections, dampers and the load there act on, and its other links are the parts of the
    station's cylinders. A one-pair ``["shaft", "crank"]`` is then the main bearing of every
    throw, each with its own mode and its own columns (``S_<k>_<station>``, …); constant-eta
    and table pairs, not the reaction model.
    """

    between: tuple[str, str]
    eta_forward: float
    eta_backward: float
    name: str = ""
    #: ``"constant-eta"`` (the efficiencies above) or ``"reaction"``: friction on the joint's
    #: reaction (every mechanism, :mod:`transient.core.model.reactions`; then η is
    #: unused, 1). Among reaction pairs, a constant-eta or table pair only at the main bearings
    #: (``["shaft", "crank"]``, crank-slider and articulated), under the power-flow policy.
    model: str = "constant-eta"
    #: Reaction model: friction coefficient μ [1] (journal: friction-circle μ·r·|R|; slider:
    #: μ·|N| on the side force).
    mu: float = 0.0
    #: Reaction model, journals and bearings: the journal's, pin's or bearing's radius r [m].
    radius: float = 0.0
    #: Reaction model: viscous coefficient, journals on the relative angular speed [N m s/rad],
    #: the slider on the piston speed [N s/m].
    viscous: float = 0.0
    #: Reaction model, slider: friction force of the rings' tension [N].
    ring_force: float = 0.0
    #: Reaction model, slider: friction from the gas pressure behind the rings as a share of
    #: the gas force on the piston, c_p = 4 μ_ring h/D for a top ring of height h [1].
    ring_pressure: float = 0.0
    #: Table model (:mod:`transient.core.model.eta_table`; then the scalar η are unused, 1): the maps'
    #: speed axis |ω| [rad/s] and moment axis |S| [N m], each increasing and ≥ 0.
    speed: tuple[float, ...] = ()
    torque: tuple[float, ...] = ()
    #: Table model: η_fwd and η_bwd on the grid, one row per speed, one value per moment, in
    #: (0, 1] [1]; read from the keys ``eta_forward``, ``eta_backward`` given as such grids.
    eta_forward_map: tuple[tuple[float, ...], ...] = field(default=(),
                                                           metadata={"key": "eta_forward"})
    eta_backward_map: tuple[tuple[float, ...], ...] = field(default=(),
                                                            metadata={"key": "eta_backward"})


@dataclass(frozen=True)
class Friction:
    """Non-ideal pairs and how their modes are chosen (``transient.core.model.chain``).

    ``policy``: ``"power-flow"`` (each pair's mode agrees with the power it transmits) or
    ``"paper"`` (criterion (25), the sign of the shaft-side moments' power). On an elastic
    ``[shaft]`` line each throw's pairs follow the power they transmit at the station's own
    speed (``"power-flow"`` only: a throw's shaft side carries the sections' torques, which
    criterion (25) would count as applied moments).
    """

    policy: str = "power-flow"
    pairs: tuple[Pair, ...] = ()


POLICIES = ("power-flow", "paper")
#: Friction models of a pair.
PAIR_MODELS = ("constant-eta", "reaction", "table")


@dataclass(frozen=True)
class Analysis:
    """Derived results computed after the run and stored under ``/analysis`` only when asked
    (:mod:`transient.analysis.requested` lists the names and units).

    ``loads``: forces, pin and journal loads and torques over the last cycle, as the mechanism's
    loads analysis gives them. ``orders``: signals whose order spectrum is stored per whole cycle
    — trajectory columns (``omega``, ``M_gas``, ``p_1`` …) or ``W_<k>``, the piston acceleration
    of cylinder k (any mechanism). ``irregularity``: δ and the mean speed of every cycle.
    ``max_order`` [1/rev]: orders stored up to it. ``samples_per_cycle``: crank-angle grid per
    engine cycle.
    ``detrend``: what is done to ω before each cycle's DFT, as ``transient orders --detrend``:
    ``"auto"`` (the ramp for a spin-up, none otherwise), ``"ramp"`` or ``"none"``
    (:func:`transient.analysis.orders.order_spectrum`); other signals are not detrended.
    ``thermodynamics``: per cylinder and
    cycle the indicated work, IMEP, BMEP, FMEP, powers, peak pressures and, for Wiebe
    combustion, the heat release and burned-fraction angles, from the pressure the run applied
    (:mod:`transient.analysis.thermo`).
    """

    loads: bool = False
    orders: tuple[str, ...] = ()
    irregularity: bool = False
    thermodynamics: bool = False
    max_order: float = 12.0
    samples_per_cycle: int = 720
    detrend: str = "auto"

    @property
    def requested(self) -> bool:
        return self.loads or bool(self.orders) or self.irregularity or self.thermodynamics


DETREND = ("auto", "ramp", "none")


#: Shear modulus of steel [Pa], the default of a shaft section given by its geometry.
STEEL_SHEAR_MODULUS = 80e9
#: The damper models of ``[[shaft.dampers]]``: a ring coupled to its hub by a viscous film
#: only, or by a spring (rubber) with its damping.
DAMPER_MODELS = ("viscous", "tuned")


@dataclass(frozen=True)
class Station:
    """A station of the shaft line, a ``[[shaft.stations]]`` entry (in order from the front
    end): a rigid disc where the line carries inertia.

    ``name`` labels it (unique). ``inertia`` [kg m²]: its own constant inertia (pulley, damper
    hub, webs and counterweights, flywheel), to which the reduced inertia of the cylinders it
    carries is added at its own angle. ``damping`` [N m s/rad]: absolute damping (≥ 0), acting
    on the station's motion relative to the line's rigid-body motion (its speed less the line's
    mean speed weighted by the cycle-mean inertias), never as a drag on the whole rotation.
    ``cylinders``: the numbers (1-based) of the cylinders whose crankpin it carries (in-line:
    one; V: the two of a throw; radial and swash plate: all); empty for a pulley or a flywheel.
    """

    name: str
    inertia: float = 0.0
    damping: float = 0.0
    cylinders: tuple[int, ...] = ()


@dataclass(frozen=True)
class ShaftSection:
    """A shaft section between two consecutive stations, a ``[[shaft.sections]]`` entry
    (section i joins stations i and i + 1).

    ``stiffness`` k [N m/rad], given, or from the geometry of a round shaft: ``length`` L,
    ``diameter`` d, ``bore`` d_i (hollow; default 0) and ``shear_modulus`` G (default steel,
    80 GPa): k = G·π(d⁴ − d_i⁴)/(32 L). Its relative damping (between its two stations), at most
    one of: ``damping`` c [N m s/rad]; ``loss_factor`` η [1]; ``damping_ratio`` ζ [1]. A loss
    factor (hysteretic damping) and a damping ratio become a viscous coefficient at the line's
    first natural frequency ω₁ (of the undamped line at cycle-mean inertias,
    :mod:`transient.shaft`): c = η·k/ω₁ = 2ζ·k/ω₁, so that the section dissipates per cycle of
    the first mode what the hysteretic law does (η = 2ζ).
    """

    stiffness: float
    damping: float = 0.0
    loss_factor: float = 0.0
    damping_ratio: float = 0.0


@dataclass(frozen=True)
class Damper:
    """A torsional vibration damper, a ``[[shaft.dampers]]`` entry: a ring of its own degree of
    freedom on the hub of ``station``. ``model``: ``"viscous"`` (a ring in silicone, coupled to
    the hub by ``damping`` c [N m s/rad] only) or ``"tuned"`` (a rubber-sprung ring: also
    ``stiffness`` k [N m/rad]). ``inertia`` [kg m²]: the ring's (> 0); the hub's is the
    station's.
    """

    station: str
    model: str
    inertia: float
    damping: float
    stiffness: float = 0.0


@dataclass(frozen=True)
class Coupling:
    """What the shaft line drives beyond its last station, the ``[shaft.coupling]`` table: an
    elastic coupling of ``stiffness`` [N m/rad] and ``damping`` [N m s/rad] at shaft speed (on
    the flywheel side of the gear), then a rigid gear without inertia of ``gear_ratio`` i =
    n_driven / n_shaft [1], then the driven machine's ``driven_inertia`` J_d [kg m²]. Referred
    to the shaft, the driven inertia is i²·J_d (the same kinetic energy ½J_d(iθ̇)²) and a torque
    T on the driven shaft is i·T (the same power).
    """

    stiffness: float
    driven_inertia: float
    damping: float = 0.0
    gear_ratio: float = 1.0

    @property
    def referred_inertia(self) -> float:
        """i²·J_d [kg m²]: the driven inertia seen at the shaft's speed."""
        return self.gear_ratio ** 2 * self.driven_inertia


@dataclass(frozen=True)
class Shaft:
    """The elastic shaft line, the ``[shaft]`` table (absent: the rigid shaft of J(φ) and
    ``[inertia]``): its ``stations`` in order from the front end, the ``sections`` between them
    (one fewer), the ``dampers`` on them, the ``coupling`` to a driven inertia (or None).

    ``reference``: the station whose angle is the run's crank angle (default: the station with
    the largest own inertia, the flywheel's, the first of equals). ``load_at``: where the load
    acts, a station's name or ``"driven"`` (default: the driven inertia with a coupling, else
    the last station). ``speed_range`` [rad/s]: the speeds whose critical speeds ``transient
    modes`` lists (default: 0 to 1.2 times the highest speed the scene names). ``[inertia]`` is
    zero or absent with a shaft line: the stations hold its inertias.
    """

    stations: tuple[Station, ...]
    sections: tuple[ShaftSection, ...]
    dampers: tuple[Damper, ...] = ()
    coupling: Coupling | None = None
    reference: str = ""
    load_at: str = ""
    speed_range: tuple[float, ...] = ()

    @property
    def constant_inertia(self) -> float:
        """The line's constant inertias as one rigid body [kg m²]: the stations' own, the damper
        rings' and the driven inertia referred to the shaft (the rigid equivalent's
        ``[inertia]``; the cylinders' J(φ) comes on top)."""
        driven = self.coupling.referred_inertia if self.coupling else 0.0
        return (sum(s.inertia for s in self.stations) + sum(d.inertia for d in self.dampers)
                + driven)

    @property
    def throws(self) -> tuple[str, ...]:
        """The names of the stations that carry cylinders, in order: on each, its cylinders'
        mechanism is a chain of the non-ideal pairs of its own (``[[friction.pairs]]``,
        theory (T7))."""
        return tuple(s.name for s in self.stations if s.cylinders)

    def station_index(self, name: str) -> int:
        """The position (0-based) of the station called ``name``."""
        return [s.name for s in self.stations].index(name)

    def line_dofs(self) -> tuple[tuple[str, str, int], ...]:
        """(name, kind, station) of the line's degrees of freedom in order: each station
        (``"station"``), then the rings of the dampers on it (``"ring"``, named ``"<station>
        damper"``, numbered from the second on one station), then with a coupling the driven
        inertia (``"driven"``, station −1)."""
        out = []
        for i, st in enumerate(self.stations):
            out.append((st.name, "station", i))
            rings = sum(d.station == st.name for d in self.dampers)
            out += [(f"{st.name} damper" + (f" {k + 1}" if k else ""), "ring", i)
                    for k in range(rings)]
        if self.coupling is not None:
            out.append(("driven", "driven", -1))
        return tuple(out)

    def line_elements(self) -> tuple[tuple[str, str], ...]:
        """The names of the two dofs each element of the line joins, in order: the sections,
        each damper (hub, ring) by station, the coupling (last station, driven)."""
        names = [s.name for s in self.stations]
        out = list(zip(names[:-1], names[1:]))
        out += [(hub, ring) for ring, kind, i in self.line_dofs() if kind == "ring"
                for hub in [names[i]]]
        if self.coupling is not None:
            out.append((names[-1], "driven"))
        return tuple(out)


@dataclass(frozen=True)
class Scene:
    """A validated scene: what :func:`transient.load_scene` returns, one record per TOML
    table. ``name`` labels the result (the file's stem by default), ``description`` is free text;
    ``mechanism`` is one of :data:`transient.mechanisms.MECHANISMS`.

    ``source_file`` and ``source_text``: the file the scene was read from and its text as read,
    comments included (where each number comes from), which a result stores beside the resolved
    scene; empty for a scene built in code. Not part of what the scene is: two scenes that differ
    only there are equal.

    A scene is frozen: :meth:`~transient.Scene.replace` makes a changed copy, validated as a
    file is; :meth:`~transient.Scene.to_toml` writes it back as TOML that
    :func:`transient.load_scene` reads to an equal scene.

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> stroke, unit = scene.geometry()["stroke"]
    >>> print(f"{stroke:.3f} {unit}")
    0.094 m
    >>> text = scene.to_toml()
    >>> transient.load_scene("copy.toml", text=text) == scene
    True
    """

    name: str
    description: str
    mechanism: Mechanism
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
    shaft: Shaft | None = None
    source_file: str = field(default="", compare=False, repr=False)
    source_text: str = field(default="", compare=False, repr=False)

    if TYPE_CHECKING:  # (bound in transient.scene, where the reader, which imports this, is known)
        from_dict = staticmethod(scene_from_dict)
        replace = replace_scene
        to_toml = to_toml

    def geometry(self) -> dict[str, tuple[float, str]]:
        """What the mechanism's geometry implies, without a run, name → (value, unit) in SI
        (:meth:`transient.mechanisms.Mechanism.geometry`): stroke, swept volume, displacement,
        dead-centre angles, λ, each piston's stroke; what ``transient check`` prints."""
        return self.mechanism.geometry()
