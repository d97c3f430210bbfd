"""The applied terms of the reduced model at a state: the mechanism's inertia and transfer
functions, the cylinders' gas values (tables, or pressure states with wall heat transfer), the
governors' fuel command and branches, the load with its schedule and generator, the starter, and
their sum into the reduced moments
(:func:`~transient.core.model.forcing.moments`).

These are the physics the right-hand side (:mod:`.rhs`), the output rows
(:mod:`transient.core.model.outputs`) and
the inverse dynamics (:mod:`.inverse`) share; the discrete branches (governor, load segment,
generator) are chosen here too, because each is the same formula the term evaluates, held fixed
over a step so that the right-hand side is smooth inside it.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from . import cylinder as cyl
from . import governor as gv
from . import reactions as rx
from .layout import (
    KINETIC,
    LT_ANGLE,
    LT_NONE,
    LT_SPEED,
    OMEGA,
    PHI,
    SW_GENERATOR,
    SW_GOVERNOR,
    SW_LOAD,
    SW_SLEEVE,
    SW_STARTER,
    WK_CYL_KNOT,
    WK_CYL_KNOT_SHIFT,
    WK_DEMAND,
    WK_DU,
    WK_FUEL,
    WK_LOCAL,
    WK_LOCAL_SHIFT,
    WK_PIECE,
    WK_PIECE_SHIFT,
    WK_RX,
    WK_SEL,
    WK_U,
    T,
    cyl_index,
    gov_index,
    latch_index,
)
from .tables import (
    find_piece,
    held_curve_value,
    table_eval,
    table_eval_near,
    table_eval_pair,
    table_eval_pair_near,
    wrap_angle,
)
from .variation import PRESSURE, SHIFT, cycle_fuel


@kernel(inline=True)
def mechanism_terms(m, phi, u, du, with_dJ):
    """J(φ) and dJ/dφ of the mechanism's moving parts; fills ``u[k]``, ``du[k]`` per cylinder.
    Without ``with_dJ`` dJ and ``du`` may be left NaN (the exact crank-slider skips them). The
    Model's own kernel (``Model.terms``), chosen when the stepper is compiled: no dispatch."""
    return m.terms(m.mech, m.kin_coef, phi, u, du, with_dJ)


@kernel(inline=True)
def select_pieces(m, extras, sel, wk):
    """Each cylinder's angle ``sel`` in its own cycle (WK_LOCAL), the gas table's piece there
    (WK_PIECE) and, with per-cylinder variation, its fuel factor in that cycle (WK_FUEL) and the
    angle and piece of its curve shifted by its combustion offset (WK_LOCAL_SHIFT,
    WK_PIECE_SHIFT). ``sel``
    is one angle for a whole step, so they are computed when it changes and kept, not recomputed
    in each of a step's right-hand sides, whose cost numba's float modulo would otherwise add to
    noticeably."""
    if wk[WK_SEL, 0] != sel:
        for k in range(m.ncyl):
            local_sel = (sel - m.gas_phase[k]) % m.period
            wk[WK_LOCAL, k] = local_sel
            wk[WK_PIECE, k] = find_piece(m.knots, m.piece_knot, local_sel)
            if extras is not None and m.var_on:
                wk[WK_FUEL, k] = cycle_fuel(m, k, sel)
            if extras is not None and m.var_shifted:
                local_shift = (sel - m.gas_phase[k] - m.var_par[k, SHIFT]) % m.period
                wk[WK_LOCAL_SHIFT, k] = local_shift
                wk[WK_PIECE_SHIFT, k] = find_piece(m.knots, m.piece_knot, local_shift)
        wk[WK_SEL, 0] = sel


@kernel(inline=True)
def gas_value(m, extras, k, phi, sel, wk, kept):
    """Full-load table value (pressure or force) of cylinder k at shaft angle ``phi``.

    ``sel`` is a shaft angle inside the current step: it picks the table piece, so that a step that
    ends exactly on a corner keeps using the piece it integrates over (docs/theory.md, Events and
    breakpoints).
    The piece is the one :func:`select_pieces` left in ``wk`` for it. With combustion offsets
    the value is the curve's δ_k later, p_full(x − δ_k) (:func:`shifted`). ``kept``: see
    :func:`piece_value`.
    """
    if extras is not None and shifted(m):
        return piece_value(m, kept, k, True, wk[WK_LOCAL_SHIFT, k] + (phi - sel), wk)
    return piece_value(m, kept, k, False, wk[WK_LOCAL, k] + (phi - sel), wk)


@kernel(inline=True)
def piece_value(m, kept, k, shift, x, wk):
    """The table's (first curve's) value at x on cylinder k's piece, WK_PIECE (``shift``: on
    the curve its combustion offset shifts, WK_PIECE_SHIFT). ``kept``, on an elastic shaft
    line, where each cylinder is read at its own angle at every evaluation: the knot interval
    searched from the one its last evaluation left in ``wk`` (WK_CYL_KNOT, WK_CYL_KNOT_SHIFT;
    :func:`.tables.interval_near`, the same interval), and left there; else by bisection."""
    piece = np.int64(wk[WK_PIECE_SHIFT, k]) if shift else np.int64(wk[WK_PIECE, k])
    if kept:
        row = WK_CYL_KNOT_SHIFT if shift else WK_CYL_KNOT
        value, i = table_eval_near(m.knots, m.coef, m.piece_knot, piece, x, wk[row, k])
        wk[row, k] = i
        return value
    value, _ = table_eval(m.knots, m.coef, m.piece_knot, piece, x)
    return value


@kernel(inline=True)
def piece_pair(m, kept, k, shift, x, wk):
    """Both curves of a paired table at x on cylinder k's piece, as :func:`piece_value` reads
    the first."""
    piece = np.int64(wk[WK_PIECE_SHIFT, k]) if shift else np.int64(wk[WK_PIECE, k])
    if kept:
        row = WK_CYL_KNOT_SHIFT if shift else WK_CYL_KNOT
        first, second, i = table_eval_pair_near(m.knots, m.coef, m.piece_knot, piece, x,
                                                wk[row, k])
        wk[row, k] = i
        return first, second
    return table_eval_pair(m.knots, m.coef, m.piece_knot, piece, x)


@kernel(inline=True)
def shifted(m):
    """Whether the tables are read at each cylinder's angle less its combustion offset: with
    offsets, unless the closed part is a state (``m.woschni``), whose combustion is shifted in
    its rates (:func:`cylinder_rates`) and whose gas exchange is the same at every fuel."""
    return m.var_shifted and not m.woschni


@kernel(inline=True)
def gas_pair(m, k, phi, sel, wk, kept):
    """Full-load and motored table values of cylinder k at shaft angle ``phi`` (``m.has_motored``
    only: ``m.coef`` pairs the two curves on common knots); ``sel``, ``wk``, ``kept`` as in
    :func:`gas_value`."""
    return piece_pair(m, kept, k, False, wk[WK_LOCAL, k] + (phi - sel), wk)


@kernel(inline=True)
def applied_value(m, extras, k, phi, sel, f, wk, kept):
    """The pressure (or force) acting on piston k at fuel ``f``: p_mot + f·(p_full − p_mot), so
    that the fuel scales the combustion, never the compression.

    Without a paired motored table either the scene burns full-load fuel throughout (f = 1,
    ``transient.scene.queries.burns_part_load``) or the model is a force pulse whose motored force is
    ``gas_offset`` = 0; the value is then gas_offset + f·(p − gas_offset), at f = 1 the table's
    to the last bit. ``kept``: see :func:`piece_value`.
    """
    if m.has_motored:
        p, p_mot = gas_pair(m, k, phi, sel, wk, kept)
        if extras is not None and shifted(m):
            # the combustion's part δ_k later, the motored curve with the piston
            p, p_mot_shift = piece_pair(m, kept, k, True, wk[WK_LOCAL_SHIFT, k] + (phi - sel), wk)
            return p_mot + f * (p - p_mot_shift)
        return p_mot + f * (p - p_mot)
    p = gas_value(m, extras, k, phi, sel, wk, kept)
    if f == 1.0:
        return p
    return m.gas_offset + f * (p - m.gas_offset)


@kernel(inline=True)
def cylinder_value(m, extras, k, y, phi, sel, f, wk, kept):
    """The pressure on piston k at its angle ``phi`` (the shaft's, or on an elastic line its
    station's, ``kept``): its state in the closed part with wall heat transfer (``m.woschni``,
    :mod:`.cylinder`), else the table's at fuel ``f`` (:func:`applied_value`)."""
    if extras is not None and m.woschni:
        if cyl.closed_angle(m.cyl_par, wk[WK_LOCAL, k], m.period) >= 0.0:
            return y[cyl_index(m) + k]
    return applied_value(m, extras, k, phi, sel, f, wk, kept)


@kernel(inline=True)
def cylinder_rates(m, angle_mode, y, sel, w, f, wk, out):
    """dp_k/dφ (crank angle) or dp_k/dt (time) of the cylinder pressure states (``m.woschni``):
    the first law with Wiebe's heat release and Woschni's wall heat (:mod:`.cylinder`); zero
    outside the closed part. dV/dφ = F_p·u_k from the row u of ``wk``, the cylinders' angles in
    their cycles from WK_LOCAL (both left by :func:`moments`)."""
    c = cyl_index(m)
    lc = latch_index(m)
    for k in range(m.ncyl):
        local_sel = wk[WK_LOCAL, k]
        x_sel = cyl.closed_angle(m.cyl_par, local_sel, m.period)
        if x_sel < 0.0:
            out[c + k] = 0.0
            continue
        shift = y[PHI] - sel  # the angles at y, continued from the step's piece
        f_k = y[lc + k] if m.latch else f
        x_burn = x_sel  # the combustion's angle: δ_k later with a combustion offset
        if m.var_on:
            f_k *= wk[WK_FUEL, k]
            x_burn -= m.var_par[k, SHIFT]
        A, B = cyl.pressure_rate(m.mech, m.cyl_par, x_burn + shift, x_burn, local_sel + shift,
                                 y[c + k], m.gas_scale[k] * wk[WK_U, k], w, f_k)
        out[c + k] = A - B / w if angle_mode else w * A - B


@kernel(inline=True)
def inertia(m, phi, wk):
    """The inertia of the third state's K = ½Jω² at φ (``Model.reference_inertia``, a
    compile-time choice): on a rigid shaft J(φ) (:func:`rigid_inertia`), on an elastic shaft line
    the reference dof's J_ref(φ) (:func:`.shaft.ref_inertia`); fills the row u of ``wk``."""
    return m.reference_inertia(m, phi, wk)


@kernel(inline=True)
def rigid_inertia(m, phi, wk):
    """Total reduced inertia J(φ), (19); fills the row u of ``wk``."""
    J, _ = mechanism_terms(m, phi, wk[WK_U], wk[WK_DU], False)
    return J + m.J0


@kernel(inline=True)
def speed(J, angle_mode, y):
    """ω from the state: y[2] itself in time mode, √(2K/J) in crank-angle mode (ω > 0 there)."""
    if angle_mode:
        return np.sqrt(2.0 * y[KINETIC] / J)
    return y[OMEGA]


@kernel
def governor_branch(m, w, rising):
    """Branch of the droop characteristic at speed w: 0 full fuel (ω ≤ ω_a), 1 the droop line,
    2 no fuel (ω ≥ ω₁c); on a corner, the branch the motion enters (``rising``: ω increasing)."""
    if w < m.gov_full or (w == m.gov_full and not rising):
        return 0
    if w > m.gov_zero or (w == m.gov_zero and rising):
        return 2
    return 1


@kernel(inline=True)
def fuel(m, w, branch):
    """Fuel command f of the static droop governor (Antonyuk §4): 1 below ω_a, falling linearly
    to 0 at ω_1c, 0 above; 1 without a governor. The cylinder pressure is p_mot + f·(p_full −
    p_mot) (:func:`applied_value`), i.e. f scales the combustion's part of the gas force (all of
    a force pulse's, as the paper's P₀). The branch is fixed for a whole step (a state event
    stops on each corner), so that the right-hand side is smooth inside every step."""
    if not m.gov_on or branch == 0:
        return 1.0
    if branch == 2:
        return 0.0
    return (m.gov_zero - w) / (m.gov_zero - m.gov_full)


@kernel(inline=True)
def command(m, extras, w, y, sw):
    """The governor's fuel command at state ``y``: the rack of a dynamic governor (PI(D): its
    position state; flyweight: linked to the sleeve), else the droop characteristic (:func:`fuel`)."""
    if extras is not None and is_pi(m):
        return y[gov_index(m) + gv.PI_RACK]
    if extras is not None and m.gov_dyn == gv.FLYWEIGHT:
        return gv.rack_of_lift(m.gov_par, y[gov_index(m) + gv.FW_LIFT])
    return fuel(m, w, sw[SW_GOVERNOR])


@kernel(inline=True)
def is_pi(m):
    """Whether the governor is a PI(D) one (its demand's clipping is a switch, ``SW_GOVERNOR``)."""
    return m.gov_dyn == gv.PI or m.gov_dyn == gv.PID


@kernel(inline=True)
def demand(m, w, y):
    """The PI(D) governor's demand u at state y (before clipping)."""
    return gv.pi_demand(m.gov_dyn, m.gov_par, w, y, gov_index(m))[1]


@kernel
def start_branch(m, extras, w, y):
    """``SW_GOVERNOR`` at the start of a run: the PI demand's clipping branch, or the droop
    characteristic's branch (:func:`governor_branch`)."""
    if extras is not None and is_pi(m):
        return gv.demand_branch(m.gov_par, demand(m, w, y), True)
    return governor_branch(m, w, True)


@kernel(inline=True)
def governor_rates(m, w, y, scale, sw, wk, out):
    """Derivatives of the dynamic governor's states (× ``scale``: 1/ω in crank angle) and zero
    for the latched fuels, into ``out``; the PI demand's range over a step into ``wk``."""
    g = gov_index(m)
    if is_pi(m):
        u = gv.pi_rates(m.gov_dyn, m.gov_par, w, y, g, sw[SW_GOVERNOR], scale, out)
        wk[WK_DEMAND, 0] = min(wk[WK_DEMAND, 0], u)
        wk[WK_DEMAND, 1] = max(wk[WK_DEMAND, 1], u)
    elif m.gov_dyn == gv.FLYWEIGHT:
        gv.flyweight_rates(m.gov_par, w, y, g, sw[SW_SLEEVE], scale, out)
    if m.latch:
        c = latch_index(m)
        for k in range(m.ncyl):
            out[c + k] = 0.0


@kernel
def load_segment(m, x, rising):
    """Segment of the load schedule at abscissa ``x`` (a time or a shaft angle, as ``m.load_comp``).

    Segment j lies between corners j − 1 and j (segment 0 before the first, n after the last,
    n corners): the number of corners below x, and on a corner the segment the motion enters
    (``rising``: x increasing), so that a step (two equal corners) takes its value after the
    step in the direction of motion. A step's empty segment is never the result.
    """
    return knots_passed(m.load_x, x, rising)


@kernel(inline=True)
def knots_passed(knots, x, rising):
    """The number of ``knots`` (increasing) below x, counting one at x where the motion leaves
    it (``rising``: x increasing): the interval the motion is in, on a knot the one it enters."""
    j = 0
    n = knots.shape[0]
    while j < n and (knots[j] < x or (knots[j] == x and rising)):
        j += 1
    return j


@kernel(inline=True)
def load_scale(m, y, seg):
    """Scale s of the load at state ``y`` in schedule segment ``seg``: 1 without a schedule, the
    first (last) value before (after) the corners, linear between two of them.

    The segment is held for a whole step (a state event stops on each corner and moves it on),
    so that the right-hand side is smooth inside every step and a step changes s exactly at its
    event; inside a step the segment's line is extrapolated, as the governor's branch is.
    """
    n = m.load_x.shape[0]
    if n == 0:
        return 1.0
    if seg <= 0:
        return m.load_s[0]
    if seg >= n:
        return m.load_s[n - 1]
    x0 = m.load_x[seg - 1]
    s0 = m.load_s[seg - 1]
    return s0 + (m.load_s[seg] - s0) * (y[m.load_comp] - x0) / (m.load_x[seg] - x0)


@kernel
def speed_knot_segment(m, w, rising):
    """Interval of a tabulated load against speed (``m.lt_kind`` = LT_SPEED) at the speed w: the
    number of its knots below w, on a knot the interval the motion enters (``rising``: ω
    increasing), as :func:`load_segment` counts a schedule's corners; 0 for other loads."""
    if m.lt_kind != LT_SPEED:
        return 0
    return knots_passed(m.lt_x, w, rising)


@kernel(inline=True)
def table_load(m, w, y):
    """The tabulated load's resisting torque [N m] (``m.lt_kind`` ≠ LT_NONE): the curve at the
    speed ω, at the shaft angle in its cycle (the knots span one period from a negative first
    one, :func:`transient.forces.load_table.load_curve`), or at the time t; below the first knot
    and above the last the end values hold.

    Steps end on the knots, where the curve kinks (linear) or its curvature jumps (pchip): the
    angle curve's knots are breakpoints, the time curve's load corners, the speed curve's levels
    of ω (state events, watched from the interval :func:`speed_knot_segment`). The value is
    always the curve's at x, found by bisection, so that a knot the event search passes over
    costs accuracy in that step only, never a value off the curve."""
    if m.lt_kind == LT_SPEED:
        x = w
    elif m.lt_kind == LT_ANGLE:
        x0 = m.lt_x[0]
        x = x0 + wrap_angle(y[PHI] - x0, m.period)
    else:
        x = y[T]
    return held_curve_value(m.lt_x, m.lt_coef, x)


@kernel
def generator_branch(m, w, rising):
    """1 while the generator's torque is held at −s·P/ω_min (ω < ω_min, or on it falling), else 0."""
    if w < m.gen_min or (w == m.gen_min and not rising):
        return 1
    return 0


@kernel(inline=True)
def load_moment(m, extras, w, y, sw):
    """The load's moment at its speed ``w`` [N m]: −s·(torque + linear·ω + fan·ω|ω| +
    P/max(ω, ω_min) + T(x)) (:func:`moments`)."""
    # (with s = 1 exactly the formula without a schedule, to the last bit)
    s = load_scale(m, y, sw[SW_LOAD])
    M_load = -s * (m.load_const + m.load_linear * w + m.load_fan * w * abs(w))
    if m.gen_power != 0.0:
        # An electrical load of power s·P: M ω = −s·P. Below ω_min (a start from rest) the
        # torque is held at its value there, so that it stays finite; a state event switches
        # the branch at ω_min, as at the governor's corners, keeping each step smooth.
        w_gen = m.gen_min if sw[SW_GENERATOR] else w
        M_load -= s * m.gen_power / w_gen
    if extras is not None and m.lt_kind != LT_NONE:
        M_load -= s * table_load(m, w, y)
    return M_load


@kernel(inline=True)
def starter_moment(m, w, sw):
    """The starter's moment at speed ``w`` while it is engaged [N m]."""
    if sw[SW_STARTER]:
        return m.starter_torque * (1.0 - w / m.starter_noload)
    return 0.0


@kernel(inline=True)
def moments(m, extras, angle_mode, y, sel, sw, wk, with_dJ):
    """Reduced inertia, speed and moments at state ``y``.

    Returns ``(J, dJ, w, M_gas, M_load, M_starter)``, dJ possibly NaN without ``with_dJ``; the
    rows u, u′ of ``wk`` are left holding the transfer functions and, with gas, WK_LOCAL and
    WK_PIECE the cylinders' pieces at ``sel`` (:func:`select_pieces`), for :func:`cylinder_rates`
    and :func:`.outputs.output_row`.

    Generalized forces follow (19): M = Σ P_q u_q + Σ M_k. The gas force of cylinder k is
    (p_k − p0)·F_p with p_k = p_mot + f·(p_full − p_mot) at the governor's fuel f
    (:func:`applied_value`); with per-cylinder variation f is cylinder k's fuel factor in its
    cycle times the command, and the force is multiplied by its pressure factor β_k
    (:mod:`.variation`). The load is M_load = −s·(torque + linear·ω + fan·ω|ω| +
    P/max(ω, ω_min) + T(x)), s from the schedule's segment ``sw[SW_LOAD]``, the max from the
    generator's branch ``sw[SW_GENERATOR]`` and T(x) the tabulated load (:func:`table_load`).
    With fuel latching cylinder k burns the fuel it took at its last injection, else every
    cylinder the governor's command (:func:`command`).
    """
    phi = y[PHI]
    u = wk[WK_U]
    J, dJ = mechanism_terms(m, phi, u, wk[WK_DU], with_dJ)
    J += m.J0
    w = speed(J, angle_mode, y)
    M_gas = 0.0
    if m.has_gas:
        f = command(m, extras, w, y, sw)
        select_pieces(m, extras, sel, wk)
        if (extras is not None and m.latch) or m.has_motored:
            # p = p_mot + f_k·(p_full − p_mot), per cylinder
            for k in range(m.ncyl):
                f_k = y[latch_index(m) + k] if extras is not None and m.latch else f
                if extras is not None and m.var_on:
                    f_k *= wk[WK_FUEL, k]
                p_k = cylinder_value(m, extras, k, y, phi, sel, f_k, wk, False)
                M_k = m.gas_scale[k] * (p_k - m.gas_offset) * u[k]
                if extras is not None and m.var_on:
                    M_k *= m.var_par[k, PRESSURE]
                M_gas += M_k
                if extras is not None and m.reaction:  # each piston's force, for the joints
                    wk[WK_RX + rx.R_P, k] = (m.gas_scale[k] * (p_k - m.gas_offset)
                                             * (m.var_par[k, PRESSURE] if m.var_on else 1.0))
        else:  # f = 1, or a force pulse (motored force 0): f·Σ(p − p0)F_p u, one multiplication
            for k in range(m.ncyl):
                p_k = gas_value(m, extras, k, phi, sel, wk, False)
                M_k = m.gas_scale[k] * (p_k - m.gas_offset) * u[k]
                if extras is not None and m.var_on:  # (factors of 1 leave M_k to the last bit)
                    M_k *= wk[WK_FUEL, k] * m.var_par[k, PRESSURE]
                M_gas += M_k
                if extras is not None and m.reaction:
                    wk[WK_RX + rx.R_P, k] = (f * m.gas_scale[k] * (p_k - m.gas_offset)
                                             * (wk[WK_FUEL, k] * m.var_par[k, PRESSURE]
                                                if m.var_on else 1.0))
            M_gas *= f
    M_load = load_moment(m, extras, w, y, sw)
    M_starter = starter_moment(m, w, sw)
    if extras is not None and m.reaction:
        if not m.has_gas:
            for k in range(m.ncyl):
                wk[WK_RX + rx.R_P, k] = 0.0
        rx.prepare(m, phi, w, sel, wk)
    return J, dJ, w, M_gas, M_load, M_starter
