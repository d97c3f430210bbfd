"""Inverse dynamics of the reduced model: for a prescribed motion, the drive torque on the shaft
and the pairs' moments, solved through the serial chain from its far end.

A run with prescribed speed calls this instead of the stepper; it shares the applied terms
(:mod:`.forcing`) and the output rows (:mod:`transient.core.model.outputs`) with the dynamic run, so that
both report the same columns.
"""
from __future__ import annotations

import numpy as np

from ..jit import compiled, kernel
from .eta_table import invert
from .forcing import (
    fuel,
    generator_branch,
    governor_branch,
    load_segment,
    moments,
    speed_knot_segment,
)
from .layout import (
    COL_EPS,
    N_SWITCHES,
    OMEGA,
    PHI,
    POWER_FLOW,
    SW_GENERATOR,
    SW_GOVERNOR,
    SW_LOAD,
    SW_LOAD_TABLE,
    W_LOSS0,
    WK_DJ,
    WK_ETA,
    WK_ETA_TRY,
    WK_J,
    WK_M,
    WK_S,
    WK_S_TRY,
    T,
    cylinder_loss_col,
    latch_index,
    n_state,
    pair_col,
)
from .outputs import cylinder_loss_rows, output_row, pair_rows
from .reactions import inverse_drive
from .rhs import pair_etas, split_subchains
from .work import work_array


@kernel
def inverse_chain(m, a, w, sigma, wk):
    """Drive torque on the shaft and pair moments for a prescribed motion (φ̈ = a, φ̇ = w).

    With a known, the sub-chain equations J_k a = R_k + η*_{k−1} S_{k−1} − S_k
    (``transient.core.model.chain``) are solved from the far end: η*_{n−1} S_{n−1} = J_n a − R_n, …,
    and the drive M_drive = J_0 a − R_0 + S_0. Every mode vector is tried (bit k: pair k backward)
    and the first consistent one kept: for ``power-flow`` S_k σ must have the mode's sign (always
    exactly one vector, because η* > 0 keeps the sign of η* S_k), for ``paper`` the criterion (25)
    with the drive counted among the shaft-side moments; if none is consistent, the one violating
    least. With efficiency maps each pair's S solves η*(|S|)·S = the moment carried
    (``eta_table.invert``; η* > 0 keeps its sign too). Needs the rows J, J′, M of ``wk``; fills
    η*, S. Returns ``(M_drive, n_consistent)``.
    """
    n = m.n_pairs
    half_w2 = 0.5 * w * w
    eta, S = wk[WK_ETA_TRY], wk[WK_S_TRY]
    best = np.nan
    best_viol = np.inf
    n_ok = 0
    for mask in range(1 << n):
        pair_etas(m, mask, eta)
        for k in range(n, 0, -1):  # η*_{k−1} S_{k−1}, the moment arriving from the far side
            carried = wk[WK_J, k] * a - (wk[WK_M, k] - wk[WK_DJ, k] * half_w2)
            if k < n:
                carried += S[k]
            if m.eta_table:  # η* depends on S: h(S) = carried solved for S (``eta_table``)
                S[k - 1], eta[k - 1] = invert(m.et_speed, m.et_torque, m.et_size, m.et_eta,
                                              m.et_min, k - 1, ((mask >> (k - 1)) & 1) == 1,
                                              abs(w), carried)
            else:
                S[k - 1] = carried / eta[k - 1]
        drive = wk[WK_J, 0] * a - (wk[WK_M, 0] - wk[WK_DJ, 0] * half_w2) + S[0]
        ok = True
        viol = 0.0
        upstream = drive
        for k in range(n):
            upstream += wk[WK_M, k]
            v = (S[k] if m.policy == POWER_FLOW else upstream) * sigma
            if (mask >> k) & 1:
                ok = ok and v < 0.0
                viol += max(0.0, v)
            else:
                ok = ok and v >= 0.0
                viol += max(0.0, -v)
        if ok:
            n_ok += 1
        if (ok and n_ok == 1) or (n_ok == 0 and viol < best_viol):
            best, best_viol = drive, viol
            for k in range(n):
                wk[WK_ETA, k] = eta[k]
                wk[WK_S, k] = S[k]
    return best, n_ok


@compiled
def inverse_dynamics(m, extras, t, phi, omega, eps, rows, M_drive, n_consistent):
    """Prescribed motion: the drive torque on the shaft that the chain needs [N m].

    Without pairs M_drive = J ε + ½ J′ ω² − M, from (18); with pairs see :func:`inverse_chain`.
    Fills ``rows`` (one output row per sample, ``epsilon`` being the prescribed one; the work
    columns are left zero, integrated by the caller), ``M_drive`` and ``n_consistent`` (the number
    of consistent mode vectors per sample, 1 unless a policy is ambiguous there). The starter is
    off, ``sel`` is the sample angle itself and a load-schedule corner takes its value after.
    ``extras``: the kernels' variant for ``m`` (:func:`.layout.extras_of`).
    """
    wk = work_array(m)
    y = np.zeros(n_state(m))
    sw = np.zeros(N_SWITCHES, dtype=np.int64)
    n = m.n_pairs
    for i in range(t.shape[0]):
        y[PHI] = phi[i]
        y[T] = t[i]
        y[OMEGA] = omega[i]
        sw[SW_GOVERNOR] = governor_branch(m, omega[i], eps[i] >= 0.0)
        sw[SW_LOAD] = load_segment(m, y[m.load_comp], True)  # t and φ increase here (ω > 0)
        sw[SW_GENERATOR] = generator_branch(m, omega[i], eps[i] >= 0.0)
        if extras is not None:
            sw[SW_LOAD_TABLE] = speed_knot_segment(m, omega[i], eps[i] >= 0.0)
        if extras is not None and m.latch:
            # (a static governor only) at a prescribed speed each cylinder latches it
            for k in range(m.ncyl):
                y[latch_index(m) + k] = fuel(m, omega[i], sw[SW_GOVERNOR])
        J, dJ, w, M_gas, M_load, M_starter = moments(m, extras, False, y, phi[i], sw, wk, True)
        output_row(m, extras, False, y, phi[i], sw, wk, rows[i])
        rows[i, COL_EPS] = eps[i]
        if extras is None or n == 0:
            M_drive[i] = J * eps[i] + 0.5 * dJ * w * w - (M_gas + M_load)
            n_consistent[i] = 1
            continue
        sigma = 1.0 if w > 0.0 or (w == 0.0 and eps[i] >= 0.0) else -1.0
        if m.reaction:
            M_drive[i] = inverse_drive(m, eps[i], w, sigma, M_load, wk)
            n_consistent[i] = 1
        else:
            split_subchains(m, phi[i], J, dJ, M_gas, M_load, wk)
            M_drive[i], n_consistent[i] = inverse_chain(m, eps[i], w, sigma, wk)
        pair_rows(m, w, 0, y[W_LOSS0: W_LOSS0 + n], wk, rows[i, pair_col(m):])
        if m.reaction:
            cylinder_loss_rows(m, w, wk, rows[i, cylinder_loss_col(m):])
