"""The output row of the reduced model at a state: the columns ``layout.OUTPUTS``, each
cylinder's applied pressure, the pairs' moments and losses, the governor's states and the latched
fuels.

Kept apart from the right-hand side because it evaluates everything the row shows (dJ/dφ, the
acceleration in crank angle too), which the integration does not need; it comes inlined for the
stepper's grid samples and as a call for the rows written at events.
"""
from __future__ import annotations

from ..jit import kernel
from .forcing import command, cylinder_value, moments
from .layout import (
    N_OUT_FIXED,
    PAIR_OUTPUTS,
    PHI,
    W_GAS,
    W_LOAD,
    W_LOSS0,
    W_STARTER,
    WK_CYL_LOSS,
    WK_ETA,
    WK_FUEL,
    WK_S,
    T,
    cyl_index,
    cylinder_loss_col,
    gov_index,
    governor_col,
    latch_index,
    pair_col,
)
from .reactions import loss_moment
from .rhs import acceleration
from .shaft import LINE_ROW, NOT_A_LINE
from .variation import PRESSURE


@kernel
def output_row(m, extras, angle_mode, y, sel, sw, wk, row):
    """:func:`output_row_inline` as a call: one compiled copy of the model's terms for the
    output rows written at events."""
    output_row_inline(m, extras, angle_mode, y, sel, sw, wk, row)


@kernel(inline=True)
def output_row_inline(m, extras, angle_mode, y, sel, sw, wk, row):
    """Fill one output sample: columns ``OUTPUTS``, the gas value applied to each cylinder
    (p_mot + f·(p_full − p_mot), see :func:`~transient.core.model.forcing.applied_value`, with a
    cylinder's fuel and pressure factors), ``PAIR_OUTPUTS`` of each pair, the
    dynamic governor's states and the latched fuels. Inlined where the stepper writes the grid's
    samples (``stepper_io._emit_samples``): there a call would copy the Model for every sample.
    An elastic shaft line writes its own row (``Model.line_model``, :mod:`.elastic`)."""
    if m.line_model(m, extras, LINE_ROW, angle_mode, y, sel, sw, wk, row) != NOT_A_LINE:
        return
    J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, angle_mode, y, sel, sw, wk, True)
    row[0] = y[T]
    row[1] = y[PHI]
    row[2] = w
    row[3] = acceleration(m, extras, y[PHI], J, dJ, w, M_gas, M_load, M_starter, sw, wk)
    row[4] = J
    row[5] = dJ
    row[6] = M_gas
    row[7] = M_load
    row[8] = M_starter
    f = command(m, extras, w, y, sw)
    row[9] = f
    row[10] = y[W_GAS]
    row[11] = y[W_LOAD]
    row[12] = y[W_STARTER]
    for k in range(m.ncyl):  # the pressure (force) applied, at the cylinder's fuel
        f_k = y[latch_index(m) + k] if extras is not None and m.latch else f
        if extras is not None and m.var_on:
            f_k *= wk[WK_FUEL, k]
        p_k = cylinder_value(m, extras, k, y, y[PHI], sel, f_k, wk, False) if m.has_gas else 0.0
        beta = m.var_par[k, PRESSURE] if extras is not None and m.var_on else 1.0
        if beta != 1.0:  # (as it acts on the piston: p0 + β_k(p − p0))
            p_k = m.gas_offset + beta * (p_k - m.gas_offset)
        row[N_OUT_FIXED + k] = p_k
    if extras is not None:  # (a plain scene has no pairs, governor states or latched fuels)
        pair_rows(m, w, 0, y[W_LOSS0: W_LOSS0 + m.n_pairs], wk, row[pair_col(m):])
        governor_rows(m, y, row)
    if extras is not None and m.reaction:
        cylinder_loss_rows(m, w, wk, row[cylinder_loss_col(m):])


@kernel(inline=True)
def governor_rows(m, y, row):
    """The dynamic governor's states and the latched fuels, as they are in the state."""
    j = governor_col(m)
    for i in range(gov_index(m), cyl_index(m)):
        row[j] = y[i]
        j += 1


@kernel(inline=True)
def cylinder_loss_rows(m, w, wk, out):
    """The power each reaction pair loses in each cylinder (pair 1 in cylinders 1 … n, then pair
    2, …), from the rows ``WK_CYL_LOSS`` that the joints' solve leaves."""
    for p in range(m.n_pairs):
        for k in range(m.ncyl):
            out[p * m.ncyl + k] = wk[WK_CYL_LOSS + p, k] * w


@kernel(inline=True)
def pair_rows(m, w, first, w_loss, wk, out):
    """``PAIR_OUTPUTS`` of the pairs ``first`` … ``first`` + n_pairs − 1 (a chain's, turning at
    ω = ``w``: the machine's, or on an elastic line a throw's, ``layout.n_margins``) from the
    rows η*, S of ``wk`` (with reaction friction its loss moment, :mod:`.reactions`);
    ``w_loss``: every pair's energy lost so far."""
    np_ = len(PAIR_OUTPUTS)
    for j in range(first, first + m.n_pairs):
        out[np_ * j] = wk[WK_S, j]
        out[np_ * j + 1] = wk[WK_ETA, j]
        if m.reaction:
            out[np_ * j + 2] = loss_moment(wk, j) * w
        else:
            out[np_ * j + 2] = (1.0 - wk[WK_ETA, j]) * wk[WK_S, j] * w
        out[np_ * j + 3] = w_loss[j]
