"""The elastic shaft line's derivative and output row: the kernel an elastic scene's Model
carries as ``line_model`` (a rigid scene's the no-op of :mod:`transient.core.model.shaft`), so that only elastic
scenes' steppers compile them.

The state (:data:`.layout.STATE`): φ, t and the third state are the reference dof's (θ_ref = φ;
K_ref = ½J_ref ω_ref² in crank angle, ω_ref in time), the works W_gas (all cylinders'), W_load
(at the load's dof) and W_starter (at the reference); then the governor's states, the latched
fuels and the cylinders' pressure states as in the rigid model; then per other dof d in order
its twist q_d = θ_d − φ and K_d (ω_d in time), and the energy the line's damping took. Each
cylinder's share of J, its transfer function and its gas pressure are taken at the angle of the
dof that carries it (theory, (T1)–(T5)). Its table's piece, its cycle (fuel factor, misfire),
its combustion offset's curve and whether it is in its closed part (pressure state with wall
heat) are held for a step as the rigid model holds them: found at the stepper's angle ``sel``
inside the step moved by the dof's twist, θ_sel = sel + θ_d − φ, a point of the dof's own
angle inside the step. The stepper ends a step on each breakpoint of a dof's own cylinders on
that dof's angle (:mod:`transient.core.stepper.breakpoints`), so no step crosses a corner of
its tables and the piece held is the one the dof's angle is in. The governor (droop, PI(D),
flyweight) reads the reference's speed, and a cylinder latches its fuel where its own angle
passes its injection angle; the load acts at its own dof's speed, a tabulated one at that speed
too (the generator's low-speed branch and the map's knots are switched on the reference's
speed, as every speed event: a knot crossed at another dof is a kink inside a step, the value
always the curve's); a cylinder's pressure state evolves at its own station's angle and speed.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from . import cylinder as cyl
from . import governor as gv
from .chain import UNIQUE
from .forcing import command, cylinder_value, governor_rates, load_moment, shifted, starter_moment
from .layout import (
    EL_C,
    EL_I,
    EL_J,
    EL_K,
    EL_R,
    KINETIC,
    LD_ABS,
    LD_GEAR,
    LD_WEIGHT,
    LM_LOAD,
    LM_REF,
    N_OUT_FIXED,
    OMEGA,
    PHI,
    W_GAS,
    W_LOAD,
    W_STARTER,
    WK_CYL_ANGLE,
    WK_CYL_FORCE,
    WK_CYL_SEL,
    WK_LINE_DJ,
    WK_LINE_J,
    WK_LINE_M,
    WK_LINE_OMEGA,
    WK_LINE_RATE,
    WK_LINE_T,
    WK_LINE_THETA,
    WK_LOCAL,
    WK_LOCAL_SHIFT,
    WK_PIECE,
    WK_PIECE_SHIFT,
    WK_SEL,
    WK_SPEED,
    WK_U,
    T,
    cyl_index,
    latch_index,
    line_col,
    line_dofs,
    line_loss_index,
)
from .line_pairs import (
    throw_chains,
    throw_loss_rates,
    throw_modes,
    throw_pair_rows,
    throw_reactions,
)
from .outputs import governor_rows
from .shaft import (
    LINE_MODES,
    LINE_RATES,
    LINE_ROW,
    line_accelerations,
    line_angle_rates,
    line_inertias,
    line_parts,
    line_torques,
    twist_index,
)
from .tables import find_piece_near, wrap_angle, wrap_near
from .variation import PRESSURE, SHIFT, cycle_fuel


@kernel(inline=True)
def elastic_model(m, extras, what, angle_mode, y, sel, sw, wk, out):
    """``Model.line_model``: the derivative (:func:`elastic_rates`) or the output row at ``y``
    into ``out``, or the non-ideal pairs' margins or modes chosen afresh (``what``:
    ``shaft.LINE_RATES`` …, the pairs' :mod:`.line_pairs`), the tables' pieces held by ``sel``;
    the status of what it did (``chain.UNIQUE``, the modes' status), the rigid model's own left
    undone."""
    if what == LINE_ROW:
        elastic_row(m, extras, angle_mode, y, sel, sw, wk, out)
    elif what == LINE_RATES:
        elastic_rates(m, extras, angle_mode, y, sel, sw, wk, out)
    elif extras is not None:
        return pairs_at(m, what, angle_mode, y, sel, sw, wk)
    return UNIQUE


@kernel
def pairs_at(m, what, angle_mode, y, sel, sw, wk):
    """The non-ideal pairs' margins (``shaft.LINE_MARGINS``) or modes chosen afresh
    (``LINE_MODES``) at ``y``, each throw's chain's (:mod:`.line_pairs`); the status."""
    _, _, M_load, M_starter, _ = line_at(m, angle_mode, y, sel, sw, wk, True)
    if what == LINE_MODES:
        return throw_modes(m, y, sel, M_load, M_starter, sw, wk)
    throw_chains(m, y, sel, M_load, M_starter, sw, wk)
    return UNIQUE


@kernel(inline=True)
def line_speeds(m, angle_mode, y, wk):
    """Each dof's speed ω_d (WK_LINE_OMEGA): √(2K_d/J_d) in crank angle (NaN where K_d < 0,
    which the stepper reports as a non-finite state), the state itself in time; after
    :func:`~transient.core.model.shaft.line_inertias`."""
    ref = np.int64(m.line[0, LM_REF])
    for d in range(line_dofs(m)):
        v = y[KINETIC] if d == ref else y[twist_index(m, d) + 1]
        wk[WK_LINE_OMEGA, d] = np.sqrt(2.0 * v / wk[WK_LINE_J, d]) if angle_mode else v


@kernel(inline=True)
def cylinder_fuel(m, c, theta, y, f):
    """Cylinder c's fuel at its dof's angle ``theta``: the fuel it latched at its last injection
    (fuel latching) or the governor's command f, times its factor in the cycle its own angle is
    in (per-cylinder variation: 0 in a misfiring cycle), as :func:`.forcing.moments` takes it."""
    f_c = y[latch_index(m) + c] if m.latch else f
    if m.var_on:
        f_c *= cycle_fuel(m, c, theta)
    return f_c


@kernel(inline=True)
def cylinders_at_sel(m, sel, wk):
    """Each cylinder's angle in its own cycle at the reference's angle ``sel`` (WK_CYL_SEL),
    computed where ``sel`` changes (once a step; WK_SEL[1] the ``sel`` they are for), so that a
    right-hand side moves each by its throw's twist instead of reducing an angle into the cycle
    (a division) for every cylinder (:func:`cylinder_pressure`)."""
    if wk[WK_SEL, 1] != sel:
        for c in range(m.ncyl):
            wk[WK_CYL_SEL, c] = wrap_angle(sel - m.gas_phase[c], m.period)
        wk[WK_SEL, 1] = sel


@kernel(inline=True)
def cylinder_pressure(m, c, theta, sel, y, f, wk):
    """The pressure (force) acting on piston c at its dof's angle ``theta`` and its fuel (at the
    governor's command f, :func:`cylinder_fuel`): the table's piece found at the dof's angle
    θ_sel = sel + θ − φ that holds the step's pieces (WK_LOCAL, the cylinder's own angle there
    — its angle at ``sel`` moved by the twist, after :func:`cylinders_at_sel` — and WK_PIECE;
    with a combustion offset also on the curve δ_c later, WK_LOCAL_SHIFT, WK_PIECE_SHIFT), then
    the rigid model's :func:`~.forcing.cylinder_value` at ``theta`` (in its closed part with
    wall heat, its pressure state); with a pressure factor β_c, p0 + β_c(p − p0), as it acts on
    the piston. The piece is searched from the one this cylinder's last evaluation left
    (:func:`~.tables.find_piece_near`): the same piece, found with two comparisons at most
    evaluations."""
    twist = theta - y[PHI]
    theta_sel = sel + twist
    local = wrap_near(wk[WK_CYL_SEL, c] + twist, m.period)
    wk[WK_LOCAL, c] = local
    wk[WK_PIECE, c] = find_piece_near(m.knots, m.piece_knot, local, wk[WK_PIECE, c])
    if shifted(m):
        local_shift = wrap_angle(local - m.var_par[c, SHIFT], m.period)
        wk[WK_LOCAL_SHIFT, c] = local_shift
        wk[WK_PIECE_SHIFT, c] = find_piece_near(m.knots, m.piece_knot, local_shift,
                                                wk[WK_PIECE_SHIFT, c])
    p = cylinder_value(m, True, c, y, theta, theta_sel, cylinder_fuel(m, c, theta_sel, y, f), wk,
                       True)
    if m.var_on:
        p = m.gas_offset + m.var_par[c, PRESSURE] * (p - m.gas_offset)
    return p


@kernel(inline=True)
def cylinder_pressure_rate(m, c, y, shift, w, f_c, wk):
    """dp_c/dt of cylinder c's pressure state (wall heat, ``m.woschni``) at its own angle in its
    cycle, WK_LOCAL (the step's, left by :func:`cylinder_pressure`) + ``shift`` (φ − sel), and
    its station's speed w: the rigid model's first law (:func:`.cylinder.pressure_rate`), its
    closed part and the combustion on or off as the step's angle (less its combustion offset)
    says, as :func:`.forcing.cylinder_rates` holds them; 0 outside its closed part."""
    local = wk[WK_LOCAL, c]
    x = cyl.closed_angle(m.cyl_par, local, m.period)
    if x < 0.0:
        return 0.0
    if m.var_on:
        x -= m.var_par[c, SHIFT]
    A, B = cyl.pressure_rate(m.mech, m.cyl_par, x + shift, x, local + shift, y[cyl_index(m) + c],
                             m.gas_scale[c] * wk[WK_U, c], w, f_c)
    return w * A - B


@kernel(inline=True)
def line_forces(m, y, sel, sw, wk):
    """The applied moments on each dof (WK_LINE_M) and the line's torques (WK_LINE_T), after
    :func:`line_speeds`, each cylinder's table pieces held by ``sel`` moved by its dof's twist.
    Returns (M_gas, its power, M_load, M_starter, the power the line's damping takes)."""
    carrier, dofs, elements = line_parts(m.line)
    n = line_dofs(m)
    for d in range(n):
        wk[WK_LINE_M, d] = 0.0
    ref = np.int64(m.line[0, LM_REF])
    load = np.int64(m.line[0, LM_LOAD])
    w_ref = wk[WK_LINE_OMEGA, ref]
    M_gas = 0.0
    P_gas = 0.0
    if m.has_gas:
        f = command(m, True, w_ref, y, sw)
        cylinders_at_sel(m, sel, wk)
        for c in range(m.ncyl):
            d = np.int64(carrier[c])
            p = cylinder_pressure(m, c, wk[WK_LINE_THETA, d], sel, y, f, wk)
            P_c = m.gas_scale[c] * (p - m.gas_offset)
            M_c = P_c * wk[WK_U, c]
            if m.reaction:  # (the force on the piston, for its throw's joints)
                wk[WK_CYL_FORCE, c] = P_c
            wk[WK_LINE_M, d] += M_c
            M_gas += M_c
            P_gas += M_c * wk[WK_LINE_OMEGA, d]
    elif m.reaction:
        for c in range(m.ncyl):
            wk[WK_CYL_FORCE, c] = 0.0
    M_load = load_moment(m, True, wk[WK_LINE_OMEGA, load], y, sw)
    wk[WK_LINE_M, load] += M_load
    M_starter = starter_moment(m, w_ref, sw)
    wk[WK_LINE_M, ref] += M_starter
    taken = line_torques(elements, dofs[:, LD_ABS], dofs[:, LD_WEIGHT], dofs[:, LD_GEAR],
                         wk[WK_LINE_THETA, :n], wk[WK_LINE_OMEGA, :n], wk[WK_LINE_T, :n])
    return M_gas, P_gas, M_load, M_starter, taken


@kernel(inline=True)
def line_at(m, angle_mode, y, sel, sw, wk, with_dJ):
    """Every dof's inertia, speed, applied moments and the line's torques at ``y`` into ``wk``
    (what the derivative and the output row both start from; J′_d only ``with_dJ``); returns
    :func:`line_forces`'."""
    line_inertias(m, y, wk, with_dJ)
    line_speeds(m, angle_mode, y, wk)
    return line_forces(m, y, sel, sw, wk)


@kernel(inline=True)
def elastic_rates(m, extras, angle_mode, y, sel, sw, wk, out):
    """dy/dt, or dy/dφ in the reference's crank angle (T5), of an elastic scene's state, in the
    form of :func:`.rhs.derivative`; with non-ideal pairs each throw's chain (T7)."""
    n = line_dofs(m)
    ref = np.int64(m.line[0, LM_REF])
    pairs = extras is not None and m.n_pairs > 0
    # (in crank angle the rates are the work–energy law's, (T5): no J′_d, unless the throws'
    # chains split their moments, (T7))
    M_gas, P_gas, M_load, M_starter, taken = line_at(m, angle_mode, y, sel, sw, wk,
                                                     pairs or not angle_mode)
    if pairs:
        throw_chains(m, y, sel, M_load, M_starter, sw, wk)
    w = wk[WK_LINE_OMEGA, :n]
    w_ref = w[ref]
    wk[WK_SPEED, 0] = min(wk[WK_SPEED, 0], w_ref)
    wk[WK_SPEED, 1] = max(wk[WK_SPEED, 1], w_ref)
    first = wk[WK_LINE_RATE, :n]
    second = wk[WK_LINE_RATE + 1, :n]
    gear = line_parts(m.line)[1][:, LD_GEAR]
    if angle_mode:
        line_angle_rates(ref, gear, wk[WK_LINE_M, :n], wk[WK_LINE_T, :n], w, first, second)
        q = 1.0 / w_ref
        out[PHI] = 1.0
        out[T] = q
        out[KINETIC] = second[ref]
    else:
        line_accelerations(wk[WK_LINE_J, :n], wk[WK_LINE_DJ, :n], wk[WK_LINE_M, :n],
                           wk[WK_LINE_T, :n], w, second)
        for d in range(n):
            first[d] = gear[d] * w[d] - w_ref
        q = 1.0
        out[PHI] = w_ref
        out[T] = 1.0
        out[OMEGA] = second[ref]
    for d in range(n):
        if d != ref:
            out[twist_index(m, d)] = first[d]
            out[twist_index(m, d) + 1] = second[d]
    out[W_GAS] = P_gas * q
    out[W_LOAD] = M_load * w[np.int64(m.line[0, LM_LOAD])] * q
    out[W_STARTER] = M_starter * w_ref * q
    out[line_loss_index(m)] = taken * q
    if extras is not None and m.n_pairs > 0:
        throw_loss_rates(m, q, wk, out)
    if m.gov_dyn != gv.NONE or m.latch:  # the reference's speed drives the governor
        governor_rates(m, w_ref, y, q, sw, wk, out)
    if m.woschni:
        pressure_rates(m, y, sel, sw, w, q, wk, out)


@kernel(inline=True)
def pressure_rates(m, y, sel, sw, w, q, wk, out):
    """The cylinders' pressure states' rates (× ``q``: 1/ω_ref in crank angle), each at its
    station's angle and speed ``w[d]`` (after :func:`line_forces`)."""
    carrier = line_parts(m.line)[0]
    f = command(m, True, w[np.int64(m.line[0, LM_REF])], y, sw)
    shift = y[PHI] - sel
    for c in range(m.ncyl):
        d = np.int64(carrier[c])
        f_c = cylinder_fuel(m, c, wk[WK_LINE_THETA, d] - shift, y, f)
        out[cyl_index(m) + c] = q * cylinder_pressure_rate(m, c, y, shift, w[d], f_c, wk)


@kernel
def elastic_row(m, extras, angle_mode, y, sel, sw, wk, row):
    """An elastic scene's output row: the fixed columns of the reference
    dof (ω, ε, J, J′ its own; M_gas all cylinders', M_load at its dof), each cylinder's
    pressure at its own angle, then per dof its twist θ_d − φ and speed, per element its torque
    k δ + c δ̇ (δ = θ_a − r θ_b), the line's energy Σ ½J_d ω_d² + Σ ½k δ² and the energy its
    damping took."""
    n = line_dofs(m)
    ref = np.int64(m.line[0, LM_REF])
    M_gas, _, M_load, M_starter, _ = line_at(m, angle_mode, y, sel, sw, wk, True)
    if extras is not None and m.reaction:  # (each cylinder's share of the losses too)
        throw_reactions(m, y, sel, M_load, M_starter, sw, wk, row, True)
    elif extras is not None and m.n_pairs > 0:
        throw_chains(m, y, sel, M_load, M_starter, sw, wk)
    acc = wk[WK_LINE_RATE, :n]
    line_accelerations(wk[WK_LINE_J, :n], wk[WK_LINE_DJ, :n], wk[WK_LINE_M, :n],
                       wk[WK_LINE_T, :n], wk[WK_LINE_OMEGA, :n], acc)
    w_ref = wk[WK_LINE_OMEGA, ref]
    row[0] = y[T]
    row[1] = y[PHI]
    row[2] = w_ref
    row[3] = acc[ref]
    row[4] = wk[WK_LINE_J, ref]
    row[5] = wk[WK_LINE_DJ, ref]
    row[6] = M_gas
    row[7] = M_load
    row[8] = M_starter
    f = command(m, True, w_ref, y, sw)
    row[9] = f
    row[10] = y[W_GAS]
    row[11] = y[W_LOAD]
    row[12] = y[W_STARTER]
    if m.has_gas:
        cylinders_at_sel(m, sel, wk)
    for c in range(m.ncyl):
        row[N_OUT_FIXED + c] = (cylinder_pressure(m, c, wk[WK_CYL_ANGLE, c], sel, y, f, wk)
                                if m.has_gas else 0.0)
    governor_rows(m, y, row)
    if extras is not None and m.n_pairs > 0:
        throw_pair_rows(m, y, wk, row)
    k = line_col(m)
    energy = 0.0
    for d in range(n):
        row[k] = wk[WK_LINE_THETA, d] - y[PHI]
        row[k + 1] = wk[WK_LINE_OMEGA, d]
        energy += 0.5 * wk[WK_LINE_J, d] * row[k + 1] * row[k + 1]
        k += 2
    th = wk[WK_LINE_THETA]
    w = wk[WK_LINE_OMEGA]
    elements = line_parts(m.line)[2]
    for e in range(elements.shape[0]):
        i = np.int64(elements[e, EL_I])
        j = np.int64(elements[e, EL_J])
        r = elements[e, EL_R]
        twist = th[i] - r * th[j]
        row[k] = elements[e, EL_K] * twist + elements[e, EL_C] * (w[i] - r * w[j])
        energy += 0.5 * elements[e, EL_K] * twist * twist
        k += 1
    row[k] = energy
    row[k + 1] = y[line_loss_index(m)]
