"""Scene → compiled model: packs the mechanism, the pressure tables the scene's gas gives
(:mod:`transient.scene.queries`, where every layer asks what a scene implies), the breakpoints
and the load schedule into the :data:`~transient.core.model.layout.Model`'s arrays.

One place where the scene's dataclasses meet the unit-free arrays of :mod:`transient.core`.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from .core.model import cylinder as cyl
from .core.model import elastic, tabulated
from .core.model import governor as gv
from .core.model import shaft as line_kernels
from .core.model import variation as var
from .core.model.forcing import applied_value, fuel, governor_branch, rigid_inertia, select_pieces
from .core.model.layout import (
    LINK_FIXED,
    LINK_PISTONS,
    LINK_REST,
    LINK_SWASH,
    LT_ANGLE,
    LT_NONE,
    LT_SPEED,
    LT_TIME,
    N_JOINTS,
    N_RX_PAR,
    PAPER,
    PHI,
    POWER_FLOW,
    RX_ETA_BWD,
    RX_ETA_FWD,
    RX_MU,
    RX_RADIUS,
    RX_RING_FORCE,
    RX_RING_PRESSURE,
    RX_VISCOUS,
    Model,
    T,
    extras_of,
)
from .core.model.reactions import NO_REACTIONS
from .core.model.tabulated import terms as tabulated_kernel
from .core.model.variation import cycle_fuel
from .core.model.work import work_array
from .core.stepper.breakpoints import LINE_BREAKPOINTS, NO_LINE_BREAKPOINTS
from .forces.gas import PressureTable, shift_cubic
from .forces.load_table import SCHEDULE_MIN_GAP, LoadCurve, load_curve
from .mechanisms import provides, reaction_joints
from .scene.queries import (
    burns_part_load,
    clearance_volume,
    cycle_begin,
    gas_is_force,
    gas_phases,
    gas_tables,
    governor_kind,
    reaction_friction,
    wiebe_levels,
)
from .shaft import ShaftLine, refuse_elastic_run


def breakpoints(table: PressureTable | None, phases: NDArray[np.float64], period: float,
                motored: PressureTable | None = None,
                injection: float | None = None,
                cycle_begin: float | None = None) -> NDArray[np.float64]:
    """Sorted shaft angles in [0, period) where any cylinder's table (full-load or motored) has a
    corner, or (fuel latching) a cylinder starts its injection, or (per-cylinder variation) a
    cylinder begins a cycle (local angle ``cycle_begin``), where its fuel factor may change."""
    if table is None:
        return np.zeros(0)
    corners = table.corners[:-1]  # the period's end is the next cycle's 0
    if motored is not None:
        corners = np.union1d(corners, motored.corners[:-1])
    if injection is not None:
        corners = np.union1d(corners, [injection])
    if cycle_begin is not None:
        corners = np.union1d(corners, [cycle_begin])
    angles = np.sort(np.mod(np.add.outer(phases, corners).ravel(), period))
    keep = np.concatenate(([True], np.diff(angles) > 1e-12 * period))
    angles = angles[keep]
    if angles.size > 1 and period - angles[-1] < 1e-12 * period:
        angles = angles[:-1]
    return angles


def union_of_angles(a: NDArray[np.float64], b: NDArray[np.float64], period: float
                    ) -> NDArray[np.float64]:
    """The sorted angles of ``a`` and ``b`` in [0, period), those closer than 1e-12 of the
    period (also across the period's end) taken as one, as :func:`breakpoints` merges them."""
    angles = np.union1d(a, np.mod(b, period))
    keep = np.concatenate(([True], np.diff(angles) > 1e-12 * period))
    angles = angles[keep]
    if angles.size > 1 and period - angles[-1] < 1e-12 * period:
        angles = angles[:-1]
    return angles


def breakpoint_jumps(bp: NDArray[np.float64], tables, phases: NDArray[np.float64],
                     period: float, mech, owner=None) -> NDArray[np.bool_]:
    """For each breakpoint, whether a cylinder's gas torque jumps there: its pressure (any of
    ``tables``) jumps while its piston moves (u_k ≠ 0; a jump at a dead centre, as all of the
    crank-slider cycles' are, leaves the torque continuous). The stepper's first stage beyond such
    a breakpoint must be evaluated afresh, not carried over from the step that ended on it (which
    used the table piece before the corner). Vectorised over the corners, which a table from
    points has at every knot. ``owner``: the cylinder of each phase (default: phase k is
    cylinder k's)."""
    owner = np.arange(len(phases)) if owner is None else owner
    out = np.zeros(bp.size, dtype=np.bool_)
    tol = 1e-12 * period
    for table in (t for t in tables if t is not None):
        corners = table.corners[:-1]
        i = np.arange(corners.size)
        right = table.evaluate(corners, i)[0]
        left = table.evaluate(np.where(i > 0, corners, period), (i - 1) % table.n_pieces)[0]
        step = 1e-9 * np.abs(table.coef[:, 0]).max()  # a jump, not the rounding at a kink
        jumps = corners[np.abs(right - left) > step]
        for k, phase in enumerate(phases):
            for angle in np.mod(phase + jumps, period):
                gap = np.abs(bp - angle)
                j = np.flatnonzero(np.minimum(gap, period - gap) <= tol)
                out[j] |= _piston_moves(mech, int(owner[k]), angle)
    return out


def _piston_moves(mech, k: int, angle: float) -> bool:
    """Whether piston k moves at the shaft angle (u_k above 1e-9 of the largest |u|, not a dead
    centre to rounding)."""
    u, du = np.empty(mech.n_cylinders), np.empty(mech.n_cylinders)
    mech.kernel(mech.pack(), np.zeros((1, 1, 6)), angle, u, du, False)
    return bool(abs(u[k]) > 1e-9 * np.abs(u).max())


def paired_table(full: PressureTable, motored: PressureTable
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Both curves on common knots, as the model holds them (``transient.core.model.tables``, paired):
    ``(knots, coef, piece_knot)`` with ``coef`` float64[n, 8], the full-load cubic in columns
    0–3 and the motored one in 4–7, so that the right-hand side finds the interval once.

    Tables on the same knots and corners (the Wiebe levels) are stacked as they are. Otherwise
    the knots and the corners are the unions of both (points closer than 1e-12 of the period
    taken as one), and each curve's cubic is re-expanded about the new knots: exact, as a
    cubic restricted to part of its interval is the same cubic.
    """
    if (full.knots.shape == motored.knots.shape and np.array_equal(full.knots, motored.knots)
            and np.array_equal(full.piece_knot, motored.piece_knot)):
        return full.knots, np.hstack([full.coef, motored.coef]), full.piece_knot
    period = full.period
    tol = 1e-12 * period

    def union(a, b):
        x = np.union1d(a, b)
        return x[np.concatenate(([True], np.diff(x) > tol))]

    knots = union(full.knots, motored.knots)
    knots[-1] = period
    corners = union(full.corners, motored.corners)
    piece_knot = np.searchsorted(knots, corners - tol)
    mid = 0.5 * (knots[:-1] + knots[1:])
    coefs = []
    for table in (full, motored):
        piece = table.piece_of(mid)
        i = np.clip(np.searchsorted(table.knots, mid, side="right") - 1,
                    table.piece_knot[piece], table.piece_knot[piece + 1] - 1)
        coefs.append(shift_cubic(table.coef[i].T, knots[:-1] - table.knots[i]).T)
    return knots, np.ascontiguousarray(np.hstack(coefs)), piece_knot.astype(np.int64)


def load_schedule(scene) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """The load schedule as the model holds it: ``(x, s, component)``.

    ``x`` are the corners as values of the state component they are levels of: times [s] (T), or
    shaft angles φ₀ + 2π·revolutions [rad] (PHI), counted from the initial angle; ``s`` the scale
    at each. Empty arrays without a schedule (s ≡ 1). The knots of a tabulated load in time are
    corners too, with the scale the schedule has there (1 without one), so that the stepper stops
    on each (a state event, as on the schedule's own corners) and no step integrates across the
    curve's kink; the reader refuses a load in time with a schedule in revolutions.
    """
    load = scene.load
    s = np.asarray(load.schedule_scale, dtype=np.float64)
    if load.schedule_revolutions:
        x = scene.initial.phi + 2.0 * math.pi * np.asarray(load.schedule_revolutions,
                                                           dtype=np.float64)
        return x, s, PHI
    x = np.asarray(load.schedule_time, dtype=np.float64)
    if load.table is None or load.table.abscissa != "time":
        return x, s, T
    knots = np.asarray(load.table.x, dtype=np.float64)
    if x.size:  # (a knot within the schedule's least gap of a corner is that corner)
        gap = np.abs(np.subtract.outer(knots, x)).min(axis=1)
        knots = knots[gap > SCHEDULE_MIN_GAP * np.maximum(1.0, np.abs(knots))]
        s_knots = np.interp(knots, x, s)
    else:
        s_knots = np.ones(knots.size)
    order = np.argsort(np.concatenate([x, knots]), kind="stable")
    return (np.concatenate([x, knots])[order], np.concatenate([s, s_knots])[order], T)


def load_table_fields(scene) -> dict:
    """The tabulated load's part of the Model (``transient.core.model.forcing.table_load``): its
    abscissa, knots and cubics; one zero interval without a table (the kernels never read it)."""
    curve = load_table_curve(scene)
    if curve is None:
        return dict(lt_kind=LT_NONE, lt_x=np.array([0.0, 1.0]), lt_coef=np.zeros((1, 4)))
    kind = {"speed": LT_SPEED, "angle": LT_ANGLE, "time": LT_TIME}[curve.abscissa]
    return dict(lt_kind=kind, lt_x=np.ascontiguousarray(curve.knots),
                lt_coef=np.ascontiguousarray(curve.coef))


def load_table_curve(scene) -> LoadCurve | None:
    """The scene's tabulated load T(x) (:mod:`transient.forces.load_table`), or None."""
    table = scene.load.table
    if table is None:
        return None
    return load_curve(table.abscissa, table.x, table.torque, table.interpolation,
                      scene.mechanism.cycle if table.abscissa == "angle" else 0.0)


def build_model(scene, part_load: bool = False
                ) -> tuple[Model, NDArray[np.float64], PressureTable | None]:
    """The compiled model, its breakpoints and the (full-load) pressure table of a scene.

    The motored curve is paired where the scene can burn less than full-load fuel
    (:func:`~transient.scene.queries.burns_part_load`) or ``part_load`` asks for it (a study at
    a fixed fuel)."""
    refuse_elastic_run(scene)
    mech = scene.mechanism
    table, motored = gas_tables(scene)
    if not (part_load or burns_part_load(scene)):
        motored = None
    phases = gas_phases(scene)
    period = mech.cycle
    n = mech.n_cylinders
    if table is None:  # one interval, zero (the kernels never read it)
        knots, coef, piece_knot = np.array([0.0, period]), np.zeros((1, 4)), np.array([0, 1])
    elif motored is None:
        knots, coef, piece_knot = table.knots, table.coef, table.piece_knot
    else:
        knots, coef, piece_knot = paired_table(table, motored)
    kin = kinematics_table(scene)
    tabulated = kin is not None and kin.coef is not None
    load_x, load_s, load_comp = load_schedule(scene)
    variation = variation_fields(scene, phases)
    cylinders = cylinder_fields(scene)
    curve = load_table_curve(scene)
    # on the shaft's (the reference's) own angle: a load's knots in φ, which are kinks, and the
    # reversals of reaction friction, where the derivative jumps
    on_shaft = (curve.corners if curve is not None and curve.abscissa == "angle" else np.zeros(0),
                reaction_breakpoints(scene) if reaction_friction(scene) else np.zeros(0))
    bp, jump, starts = shaft_breakpoints(scene, (table, motored), variation, cylinders["cyl_par"],
                                         on_shaft)
    model = Model(
        terms=tabulated_kernel if tabulated else mech.kernel, mech=mech.pack(),
        kin_coef=kin.coef if tabulated else np.zeros((1, 1, 6)), ncyl=n,
        J0=float(scene.inertia.total),
        has_gas=table is not None, gas_phase=phases,
        gas_scale=np.full(n, 1.0 if gas_is_force(scene) else mech.piston_area),
        gas_offset=0.0 if gas_is_force(scene) else scene.gas.p0, period=period, knots=knots, coef=coef,
        piece_knot=piece_knot.astype(np.int64), has_motored=motored is not None,
        breakpoints=bp, bp_jump=jump,
        load_const=scene.load.torque, load_linear=scene.load.linear, load_fan=scene.load.fan,
        load_x=load_x, load_s=load_s, load_comp=load_comp,
        **load_table_fields(scene), gen_power=scene.load.generator_power,
        gen_min=scene.load.generator_min_speed,
        starter_torque=scene.starter.torque, starter_noload=scene.starter.noload_speed,
        starter_cutout=scene.starter.cutout_speed, gov_on=scene.governor.model == "droop",
        gov_full=scene.governor.speed_full, gov_zero=scene.governor.speed_zero,
        **governor_fields(scene), **chain_fields(scene), **cylinders, **variation,
        **line_fields(scene, tabulated, starts))
    # (the stepper's own breakpoints are the shaft's; an elastic line's are each dof's, which
    # its Model holds and the stepper reads there)
    return model, (bp if scene.shaft is None else np.zeros(0)), table


def shaft_breakpoints(scene, tables, variation: dict, cyl_par: NDArray[np.float64], on_shaft
                      ) -> tuple[NDArray[np.float64], NDArray[np.bool_], list[int]]:
    """The Model's ``breakpoints`` and ``bp_jump``, and where each dof's begin in them.

    On a rigid shaft one sorted list on the shaft's angle: every cylinder's
    (:func:`cylinder_breakpoints`) and the angles ``on_shaft`` (a load's knots in φ, kinks; the
    reversals of reaction friction, where the derivative jumps). On an elastic line each dof's
    own, on its angle, one list after another: those of the cylinders it carries with, under
    reaction friction, the reversals of their joints (:func:`throw_reversals`), and on the
    reference dof, whose angle is the run's crank angle, a load's knots too; ``starts`` the
    index of each dof's first (none on a rigid shaft)."""
    knots, reversals = on_shaft
    n = scene.mechanism.n_cylinders
    if scene.shaft is None:
        bp, jump = cylinder_breakpoints(scene, np.arange(n), tables, variation, cyl_par,
                                        knots, reversals)
        return bp, jump, []
    line = ShaftLine(scene)
    shaft = scene.shaft
    ref = line.station_dof[shaft.station_index(shaft.reference)]
    carried = [np.zeros(0, dtype=np.int64) for _ in range(line.n)]
    for i, st in enumerate(shaft.stations):
        carried[line.station_dof[i]] = np.asarray(st.cylinders, dtype=np.int64) - 1
    lists = [cylinder_breakpoints(scene, carried[d], tables, variation, cyl_par,
                                  knots if d == ref else np.zeros(0),
                                  throw_reversals(scene, carried[d]) if reversals.size
                                  else np.zeros(0))
             for d in range(line.n)]
    starts = np.cumsum([0] + [bp.size for bp, _ in lists])[:-1].tolist()
    return (np.concatenate([bp for bp, _ in lists]),
            np.concatenate([jump for _, jump in lists]), starts)


def throw_reversals(scene, cylinders: NDArray[np.int64]) -> NDArray[np.float64]:
    """The reversals of reaction friction in the joints of the ``cylinders`` (0-based) that a
    station of an elastic line carries, on its own angle: the mechanism's for those cylinders
    where it splits its cylinders over stations (``"cylinder-inertia"``), else all of its
    (its cylinders are then on one station); none on a station without cylinders."""
    if cylinders.size == 0:
        return np.zeros(0)
    mech = scene.mechanism
    if provides(mech, "cylinder-inertia"):
        return mech.reaction_reversals(cylinders)
    return mech.reaction_reversals()


def throw_mechanisms(scene, carrier: NDArray[np.int64], n_dofs: int) -> NDArray[np.float64]:
    """Under reaction friction on an elastic line, one row per station that carries cylinders,
    in order: the compiled parameters of the mechanism of its cylinders alone (the mechanism's
    ``pack_cylinders``; its whole ``pack`` where its cylinders all ride on one station), which
    its throw's reaction solve takes (:mod:`transient.core.model.line_pairs`); no rows
    otherwise."""
    if not reaction_friction(scene):
        return np.zeros((0, 1))
    mech = scene.mechanism
    split = provides(mech, "cylinder-inertia")
    packs = [mech.pack_cylinders(np.flatnonzero(carrier == d)) if split else mech.pack()
             for d in range(n_dofs) if np.any(carrier == d)]
    out = np.zeros((len(packs), max(p.size for p in packs)))
    for i, p in enumerate(packs):
        out[i, :p.size] = p
    return out


def cylinder_breakpoints(scene, which: NDArray[np.int64], tables, variation: dict,
                         cyl_par: NDArray[np.float64], knots: NDArray[np.float64],
                         reversals: NDArray[np.float64]
                         ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The sorted breakpoints of the cylinders ``which`` on one angle, with the angles
    ``knots`` (kinks) and ``reversals`` (jumps of the derivative), and whether the derivative
    jumps at each: :func:`breakpoints` of their phases (with combustion offsets also δ_k
    later, where a cylinder's tables are read too), the jumps of :func:`breakpoint_jumps`,
    of the closed part's corners (wall heat) and of a cycle's begin."""
    mech = scene.mechanism
    period = mech.cycle
    table, motored = tables
    phases = gas_phases(scene)
    shift = variation["var_par"][:, var.SHIFT]
    moved = which[shift[which] != 0.0]
    all_phases = np.concatenate([phases[which], np.mod(phases[moved] + shift[moved], period)])
    owner = np.concatenate([which, moved])
    begin = cycle_begin(mech) if variation["var_on"] else None
    bp = (breakpoints(table, all_phases, period, motored, scene.gas.injection, begin)
          if which.size else np.zeros(0))
    for extra in (knots, reversals):
        if extra.size:
            bp = union_of_angles(bp, extra, period)
    jump = breakpoint_jumps(bp, tables, all_phases, period, mech, owner)
    if cyl_par[cyl.CLOSED] > 0.0:  # (wall heat; its combustion's start and end δ_k later too)
        jump |= _on_closed_part_corner(bp, all_phases, cyl_par, period)
    if begin is not None:
        jump |= _on_cycle_begin(bp, phases[which], which, period, mech, begin)
    if reversals.size:  # a friction force reverses there: the derivative jumps
        gap = np.abs(bp[:, None] - reversals[None, :])
        jump |= np.any(np.minimum(gap, period - gap) <= 1e-12 * period, axis=1)
    return bp, jump


#: The Model's fields of the breakpoints on each dof's own angle, in the order of the stepper's
#: kernels (``LINE_BREAKPOINTS``, ``NO_LINE_BREAKPOINTS``).
LINE_BREAKPOINT_FIELDS = ("line_segment_end", "line_retake", "line_passed")


def line_fields(scene, tabulated_kinematics: bool, starts: list[int]) -> dict:
    """The elastic shaft line's part of the Model (:class:`~transient.shaft.line.ShaftLine`: its
    dofs, inertias, elements, absolute damping and where each dof's breakpoints begin
    (``starts``, :func:`shaft_breakpoints`) packed by
    :func:`~transient.core.model.shaft.pack_line`; the mechanism's shares,
    :func:`transient.core.model.elastic.elastic_model` and the stepper's kernels of the dofs'
    breakpoints), or no dofs and the no-op kernels of :mod:`transient.core.model.shaft` and
    the stepper on a rigid shaft."""
    if scene.shaft is None:
        return dict(line=line_kernels.RIGID_LINE, shares=line_kernels.no_shares,
                    line_model=line_kernels.no_line_model,
                    line_switch=line_kernels.no_line_switch,
                    reference_inertia=rigid_inertia,
                    **dict(zip(LINE_BREAKPOINT_FIELDS, NO_LINE_BREAKPOINTS)))
    line = ShaftLine(scene)
    shaft = scene.shaft
    carrier = np.zeros(scene.mechanism.n_cylinders, dtype=np.int64)
    for i, st in enumerate(shaft.stations):
        carrier[np.asarray(st.cylinders, dtype=np.int64) - 1] = line.station_dof[i]
    dofs = np.column_stack([line.own_inertia, line.weights, line.absolute, np.ones(line.n)])
    packed = line_kernels.pack_line(line.station_dof[shaft.station_index(shaft.reference)],
                                    line.names.index(shaft.load_at), carrier, dofs,
                                    line.element_rows(), starts,
                                    throw_mechanisms(scene, carrier, line.n))
    shares = tabulated.shares if tabulated_kinematics else scene.mechanism.shares_kernel
    return dict(line=packed, shares=shares, line_model=elastic.elastic_model,
                line_switch=line_kernels.line_mode, reference_inertia=line_kernels.ref_inertia,
                **dict(zip(LINE_BREAKPOINT_FIELDS, LINE_BREAKPOINTS)))


def variation_fields(scene, phases: NDArray[np.float64]) -> dict:
    """The per-cylinder variation's part of the Model (:mod:`transient.core.model.variation`) from the
    ``[[gas.cylinders]]`` entries; factors of 1 and no misfires for cylinders without one, and
    ``var_on`` False without any, so that such a scene runs the kernels' plain path."""
    mech, entries = scene.mechanism, scene.gas.cylinders
    n, period = mech.n_cylinders, mech.cycle
    par = np.zeros((n, var.N_VAR_PAR))
    par[:, [var.FUEL, var.PRESSURE]] = 1.0
    listed = max([len(c.misfire_cycles) for c in entries] + [1])
    ints = np.zeros((n, var.CYCLES + listed), dtype=np.int64)
    for c in entries:
        k = c.cylinder - 1
        par[k, [var.FUEL, var.PRESSURE, var.RATE, var.SHIFT]] = (
            c.fuel, c.pressure, c.misfire_rate, c.combustion_offset)
        ints[k, [var.EVERY, var.SEED]] = c.misfire_every, c.misfire_seed
        ints[k, var.CYCLES:var.CYCLES + len(c.misfire_cycles)] = c.misfire_cycles
    # cycle 1 of cylinder k: the one in progress at the initial angle φ0
    first = np.mod(phases + cycle_begin(mech), period)
    phi0 = scene.initial.phi
    par[:, var.START] = phi0 - np.mod(phi0 - first, period)
    return dict(var_on=bool(entries), var_shifted=bool(np.any(par[:, var.SHIFT] != 0.0)),
                var_par=par, var_int=ints)


def _on_cycle_begin(bp: NDArray[np.float64], phases: NDArray[np.float64],
                    owner: NDArray[np.int64], period: float, mech, begin: float
                    ) -> NDArray[np.bool_]:
    """Breakpoints where a cylinder (``owner[j]`` of phase j) begins a cycle while its piston
    moves: its fuel factor may change there, and with it its gas torque (at a dead centre, where
    every crank-slider's cycle begins, the torque stays continuous and the stepper's
    carried-over stage stays valid)."""
    out = np.zeros(bp.size, dtype=np.bool_)
    for k, phase in zip(owner, phases):
        angle = (phase + begin) % period
        gap = np.abs(bp - angle)
        j = np.flatnonzero(np.minimum(gap, period - gap) <= 1e-12 * period)
        out[j] |= _piston_moves(mech, int(k), angle)
    return out


def cylinder_fields(scene) -> dict:
    """The cylinder-pressure states' part of the Model: with ``[gas.woschni]`` the closed part's
    parameters of :mod:`transient.core.model.cylinder` (from the full-load Wiebe cycle, whose closed
    part it integrates again, now with wall heat)."""
    gas = scene.gas
    par = np.zeros(cyl.N_PAR)
    if gas.woschni is None:
        return dict(woschni=False, cyl_par=par)
    mech, w, h = scene.mechanism, gas.wiebe, gas.woschni
    cycle = wiebe_levels(mech, gas)[-1]
    closed = cycle.closed
    area = mech.piston_area
    par[[cyl.IVC, cyl.CLOSED, cyl.START, cyl.DURATION, cyl.WA, cyl.WM]] = (
        closed.start, closed.end - closed.start, (cycle.combustion_start - closed.start) % mech.cycle,
        w.duration, w.a, w.m)
    par[[cyl.Q_FULL, cyl.GAMMA, cyl.GAMMA_SLOPE, cyl.GAMMA_TREF, cyl.T_A, cyl.P_A, cyl.V_A]] = (
        w.fuel_mass * w.lhv * w.efficiency, w.gamma, w.gamma_slope, w.gamma_t_ref, w.t_a,
        gas.p_a, cycle.v_a)
    par[[cyl.V_C, cyl.AREA, cyl.BORE, cyl.STROKE, cyl.V_H]] = (
        clearance_volume(scene), area, mech.bore, cycle.v_h / area, cycle.v_h)
    par[[cyl.C1, cyl.C2, cyl.T_WALL]] = h.c1, h.c2, h.wall_temperature
    par[cyl.GAMMA_A] = w.gamma + w.gamma_slope * (w.t_a - w.gamma_t_ref)
    return dict(woschni=True, cyl_par=par)


def _on_closed_part_corner(bp: NDArray[np.float64], phases: NDArray[np.float64],
                           par: NDArray[np.float64], period: float) -> NDArray[np.bool_]:
    """Breakpoints where a cylinder-pressure state's derivative jumps: its intake closing and
    exhaust opening, and its combustion's start and end (the heat release and Woschni's
    combustion term switch there), so that the stepper evaluates the first stage beyond them
    afresh instead of carrying it over from the step that ended there (FSAL)."""
    corners = par[cyl.IVC] + np.array([0.0, par[cyl.CLOSED], par[cyl.START],
                                       par[cyl.START] + par[cyl.DURATION]])
    d = np.mod(np.subtract.outer(bp, np.add.outer(phases, corners).ravel()), period)
    return np.any(np.minimum(d, period - d) <= 1e-9, axis=1)


def governor_fields(scene) -> dict:
    """The dynamic governor's and the fuel latching's part of the Model (``transient.core.model.governor``
    for the parameters' meaning)."""
    g = scene.governor
    latch = dict(latch=scene.gas.injection is not None,
                 inj_angle=float(scene.gas.injection or 0.0))
    if g.model == "pi":
        par = np.zeros(10)
        tracking = g.tracking_time or (g.gain_p / g.gain_i if g.gain_i > 0.0 else math.inf)
        par[[gv.P_REF, gv.P_KP, gv.P_KI, gv.P_KD, gv.P_TAU_D, gv.P_TAU_A, gv.P_FMIN, gv.P_FMAX]] = (
            g.speed, g.gain_p, g.gain_i, g.gain_d, g.derivative_time, g.actuator_time,
            g.fuel_min, g.fuel_max)
        par[gv.P_RATE] = g.rate_limit or math.inf
        # (a P-only governor with anti-windup tracks with T_t = ∞: it has no integrator to wind)
        par[gv.P_INV_TT] = 1.0 / tracking if g.anti_windup else 0.0
        return dict(gov_dyn=governor_kind(g), gov_par=par, **latch)
    if g.model == "flyweight":
        par = np.zeros(12)
        arm = g.arm_ratio
        cent = g.weights * g.weight_mass * arm * g.gear_ratio ** 2
        par[[gv.F_CENT, gv.F_RHO0, gv.F_ARM, gv.F_PRELOAD, gv.F_SPRING, gv.F_DAMP, gv.F_MASS,
             gv.F_TRAVEL, gv.F_FMAX, gv.F_FMIN]] = (
            cent, g.radius, arm, g.spring_preload, g.spring_rate, g.damping,
            g.sleeve_mass + g.weights * g.weight_mass * arm ** 2, g.travel, g.fuel_max,
            g.fuel_min)
        par[gv.F_W_LIFT], par[gv.F_W_TOP] = gv.lift_speeds(cent, g.radius, arm, g.spring_preload,
                                                           g.spring_rate, g.travel)
        return dict(gov_dyn=gv.FLYWEIGHT, gov_par=par, **latch)
    return dict(gov_dyn=gv.NONE, gov_par=np.zeros(1), **latch)


def initial_governor(scene, model: Model) -> tuple[NDArray[np.float64], int]:
    """Initial values of the governor's states and the latched fuels (the state after the pairs'
    work integrals) and the sleeve's switch: the PI(D) rack and integrator at ``fuel_initial``,
    its filter at the initial speed; the flyweight sleeve at rest in its static balance at the
    initial speed (on a stop if that lies beyond one); each cylinder latched at the command."""
    g, w0 = scene.governor, scene.initial.omega
    sleeve = gv.FREE
    if model.gov_dyn in (gv.PI, gv.PID):
        states = [g.fuel_initial, g.fuel_initial, w0][:gv.n_states(model.gov_dyn)]
        f0 = g.fuel_initial
    elif model.gov_dyn == gv.FLYWEIGHT:
        z, sleeve = gv.sleeve_equilibrium(model.gov_par, w0)
        states = [z, 0.0]
        f0 = gv.rack_of_lift(model.gov_par, z)
    else:
        states = []
        # (the kernels' Python: compiled to be called from Python, once, they would cost a
        # first run a compile of their own besides the stepper's)
        branch = getattr(governor_branch, "py_func", governor_branch)(model, w0, True)
        f0 = getattr(fuel, "py_func", fuel)(model, w0, branch)
    latched = [f0] * model.ncyl if model.latch else []
    return np.array(states + latched + initial_cylinders(scene, model, f0), dtype=np.float64), sleeve


def initial_cylinders(scene, model: Model, f0: float) -> list[float]:
    """Initial cylinder pressures (``model.woschni``): in its closed part at the start, a
    cylinder's pressure is the Wiebe cycle's at fuel f0, without wall heat (the run's first
    cycle of that cylinder carries this approximation); elsewhere p_a, unused until its intake
    closes and the stepper sets it there."""
    if not model.woschni:
        return []
    phi0 = scene.initial.phi
    sel = phi0 + 1e-9  # (the piece just ahead)
    wk = work_array(model)
    select_pieces(model, extras_of(model), sel, wk)
    out = []
    for k in range(model.ncyl):
        local = (phi0 - model.gas_phase[k]) % model.period
        closed = cyl.closed_angle(model.cyl_par, local, model.period) >= 0.0
        f_k = f0 * cycle_fuel(model, k, sel) if model.var_on else f0
        out.append(applied_value(model, extras_of(model), k, phi0, sel, f_k, wk, False) if closed
                   else model.cyl_par[cyl.P_A])
    return out


@lru_cache(maxsize=8)
def kinematics_table(scene):
    """The tables of a ``kinematics = "tabulated"`` scene (:mod:`transient.tabulate`; ``coef`` None
    if none reaches the tolerance), else None. Cached: a scene is frozen."""
    sv = scene.solver
    if sv.kinematics != "tabulated":
        return None
    from .tabulate import FRACTION_OF_RTOL, build_table
    mech = scene.mechanism
    target = sv.table_tolerance or FRACTION_OF_RTOL * sv.rtol
    return build_table(mech.kernel, mech.pack(), mech.n_cylinders, target)


def chain_fields(scene) -> dict:
    """The serial chain's part of the Model: pairs, their efficiencies, the sub-chain of each link.

    Pair k joins links i and i + 1; links between ideal pairs share a sub-chain, so the sub-chain
    of link i is the number of non-ideal pairs before it.
    """
    mech, friction = scene.mechanism, scene.friction
    if reaction_friction(scene):
        return reaction_fields(scene)
    cut_after = [mech.links.index(p.between[0]) for p in friction.pairs]
    link_sub = [sum(c < i for c in cut_after) for i in range(len(mech.links))]
    return dict(
        n_pairs=len(friction.pairs),
        eta_fwd=np.array([p.eta_forward for p in friction.pairs], dtype=np.float64),
        eta_bwd=np.array([p.eta_backward for p in friction.pairs], dtype=np.float64),
        policy=PAPER if friction.policy == "paper" else POWER_FLOW,
        **link_fields(mech, link_sub),
        reaction=False, rx_par=np.zeros((N_JOINTS, N_RX_PAR)),
        rx_pair=np.full(N_JOINTS, -1, dtype=np.int64), **reaction_kernel_fields(mech),
        **eta_table_fields(friction.pairs))


def reaction_kernel_fields(mech) -> dict:
    """The Model's reaction solver: the mechanism's own
    (:class:`~transient.mechanisms.ReactionFriction`), else kernels that are never called
    (``reactions.NO_REACTIONS``), so that the stepper holds no other mechanism's solver."""
    if provides(mech, "reaction-friction"):
        kernels, sides = mech.reaction_kernels, mech.tracks_sides
    else:
        kernels, sides = NO_REACTIONS, False
    return dict(zip(("rx_prepare", "rx_solve", "rx_inverse"), kernels), rx_sides=sides)


def link_fields(mech, link_sub: list[int]) -> dict:
    """The links' part of the Model (``transient.core.model.rhs.split_subchains``): the sub-chain of
    each, their constant inertias, the link with the rest of J(φ), and the law of each link
    whose φ-dependent inertia a pair cuts from the rest's sub-chain (elsewhere it stays in the
    rest: a chain cut only where the links' inertias are constant adds nothing to compute)."""
    laws = mech.link_laws
    rest = laws.index(LINK_REST)
    own = [law if law in (LINK_PISTONS, LINK_SWASH) and link_sub[i] != link_sub[rest]
           else LINK_FIXED for i, law in enumerate(laws)]
    mass = [mech.piston_link_mass if law == LINK_PISTONS else 0.0 for law in laws]
    return dict(link_sub=np.array(link_sub, dtype=np.int64),
                link_J=np.array(mech.link_inertias(), dtype=np.float64), link_rest=rest,
                link_own=np.array(own, dtype=np.int64), link_mass=np.array(mass))


def eta_table_fields(pairs) -> dict:
    """The Model's efficiency maps (:mod:`transient.core.model.eta_table`), padded to one shape: each
    pair's speed and moment axes and its two maps; a constant-η pair among mapped ones becomes a
    one-point map of its two efficiencies (held everywhere: the same η). Without mapped pairs,
    one row of zeros of the same types."""
    n = len(pairs)
    if not any(p.model == "table" for p in pairs):
        return dict(eta_table=False, et_speed=np.zeros((n, 1)), et_torque=np.zeros((n, 1)),
                    et_size=np.zeros((n, 2), dtype=np.int64), et_eta=np.zeros((n, 2, 1, 1)),
                    et_min=np.ones(n))
    maps = [(p.speed, p.torque, p.eta_forward_map, p.eta_backward_map) if p.model == "table"
            else ((0.0,), (0.0,), ((p.eta_forward,),), ((p.eta_backward,),)) for p in pairs]
    speed, torque, size, eta, et_min = pack_maps(maps)
    return dict(eta_table=True, et_speed=speed, et_torque=torque, et_size=size, et_eta=eta,
                et_min=et_min)


def pack_maps(maps) -> tuple:
    """The arrays (speed, torque, size, eta, η_min) of :mod:`transient.core.model.eta_table` from one
    (speed axis, moment axis, η_fwd grid, η_bwd grid) per pair, padded to one shape."""
    n = len(maps)
    nw = max(len(m[0]) for m in maps)
    ns = max(len(m[1]) for m in maps)
    speed, torque = np.zeros((n, nw)), np.zeros((n, ns))
    size, eta = np.zeros((n, 2), dtype=np.int64), np.ones((n, 2, nw, ns))
    for k, (w, s, fwd, bwd) in enumerate(maps):
        size[k] = len(w), len(s)
        speed[k, :len(w)], torque[k, :len(s)] = w, s
        eta[k, 0, :len(w), :len(s)], eta[k, 1, :len(w), :len(s)] = fwd, bwd
    et_min = np.array([min(np.min(m[2]), np.min(m[3])) for m in maps])
    return speed, torque, size, eta, et_min


def reaction_fields(scene) -> dict:
    """The chain's part of the Model with reaction friction (:mod:`transient.core.model.reactions`):
    no sub-chain is cut (the chain is rigid, its joints lose on their reactions); joint j of
    the mechanism's ``reaction_joints`` (:func:`transient.mechanisms.reaction_joints`) has its
    pair's coefficients and reports as that pair; a constant-η pair among them (at the shaft's
    coupling, the scene check allows no other) has its efficiencies there instead, a mapped one
    NaN (its maps are the ``et_*`` fields)."""
    mech, pairs = scene.mechanism, scene.friction.pairs
    joints = reaction_joints(mech)
    rx_par = np.zeros((N_JOINTS, N_RX_PAR))
    rx_pair = np.full(N_JOINTS, -1, dtype=np.int64)
    for k, p in enumerate(pairs):
        j = joints.index(tuple(p.between))
        rx_pair[j] = k
        if p.model != "reaction":
            mapped = p.model == "table"
            rx_par[j, RX_ETA_FWD] = np.nan if mapped else p.eta_forward
            rx_par[j, RX_ETA_BWD] = np.nan if mapped else p.eta_backward
            continue
        rx_par[j, RX_MU] = p.mu
        rx_par[j, RX_RADIUS] = p.radius
        rx_par[j, RX_VISCOUS] = p.viscous
        rx_par[j, RX_RING_FORCE] = p.ring_force
        rx_par[j, RX_RING_PRESSURE] = p.ring_pressure
    n = len(pairs)
    kernels = reaction_kernel_fields(mech)
    if scene.shaft is not None:  # (the throws' solves share the side forces' rows: an elastic
        kernels["rx_sides"] = False  # line leaves the kinks of μ|N| to the error control)
    return dict(n_pairs=n, eta_fwd=np.ones(n), eta_bwd=np.ones(n),
                policy=PAPER if scene.friction.policy == "paper" else POWER_FLOW,
                **link_fields(mech, [0] * len(mech.links)),
                reaction=True, rx_par=rx_par, rx_pair=rx_pair, **kernels,
                **eta_table_fields(pairs))


def reaction_breakpoints(scene) -> NDArray[np.float64]:
    """Shaft angles in [0, cycle) where a joint's relative speed changes sign (reaction friction),
    so that no step straddles a reversal of a friction force: the mechanism's
    ``reaction_reversals`` (:class:`~transient.mechanisms.ReactionFriction`)."""
    return scene.mechanism.reaction_reversals()
