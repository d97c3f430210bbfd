r"""The non-ideal pairs on an elastic shaft line (theory, *The elastic shaft line*, (T7)): each
station that carries cylinders turns its throw's mechanism with its own angle θ_d, so it is a
serial chain of its own (:mod:`.chain`), written with θ_d for φ.

A scene's ``[[friction.pairs]]`` name links of the mechanism; on the line they act in every such
chain, numbered c = 0 … in the order of their stations, each pair k of chain c its own switch,
margin, loss state and output columns, number c·n_pairs + k (``layout.n_margins``). Chain c's
links are its station's: the shaft link the station's own inertia J_own,d, acted on by the
load and starter where they act and by the line's torque T_d (sections, dampers, coupling,
absolute damping; known from the angles and speeds at a state, so the stations decouple); each
link of constant reduced inertia ``Model.link_J`` its share of the cylinders' (the crank's
m_crank r² per throw); the pistons' link m Σ u_c² over the station's cylinders c at its angle;
the rest of the station's cylinders' J_c(θ_d) in ``link_rest``; the gas moment of its
cylinders on the last (``.rhs.split_chain``, which splits the rigid machine too). A mechanism
without the cylinders' shares has them all on one station, whose chain is the rigid machine's
with the station's inertia for J0.

Each chain's pairs are solved as the rigid chain's, constant-η (``chain.chain_solve``) or mapped
(``eta_table.solve_held``) with its modes held from the switches, and its margins watched as the
rigid chain's are under the power-flow policy (``rhs.mode_margins``) but on the station's own
speed: S_k ω_d, signed by the held mode. So a mode switches where the power its pair transmits
changes sign, also where a throw's own speed passes zero in the time domain while the reference
turns on. (The paper's criterion (25), which judges a pair by the moments applied on its shaft
side, would count the sections' torques among them on a throw; the scene check refuses it.) The chain's power balance,

    Σ_k (J_k θ̈_d + ½ J′_k ω_d²) = Σ_k M_k − Σ_k (1 − η*_k) S_k,  Σ_k J_k = J_d,

says that the chain's acceleration is the line's equation (T2) of the station with its applied
moment less the loss moment L_d = Σ_k (1 − η*_k) S_k, and its crank-angle form (T5) integrates
K_d with dK_d/dφ = (M_d + T_d − L_d) ω_d/ω_ref, the work–energy law with the pairs' losses: the
line's own kernels then serve unchanged. Each pair's loss power is (1 − η*_k) S_k ω_d, and
(T4) balances with their integrals.

With friction on the joints' reactions (``Model.reaction``; theory, (T7b)) nothing is cut:
each throw's joints are solved by the mechanism's own solver, closed on the station's equation
(:func:`throw_reaction`), and the chain's loss moment L_d, the sum of its pairs' joints' loss
moments, enters the line's equations the same way (:func:`throw_reactions`).
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from . import eta_table as et
from .chain import LOCKED, UNIQUE, chain_solve, modes_power_flow_into
from .layout import (
    LD_CHAIN,
    LD_OWN,
    LD_SHARE,
    LM_LOAD,
    LM_REF,
    N_SCRATCH,
    PHI,
    SW_DIRECTION,
    SW_MODES,
    W_LOSS0,
    WK_CYL_FORCE,
    WK_CYL_LOSS,
    WK_DJ,
    WK_DU,
    WK_ETA,
    WK_G,
    WK_G_MIN,
    WK_J,
    WK_LINE_DJ,
    WK_LINE_J,
    WK_LINE_M,
    WK_LINE_OMEGA,
    WK_LINE_T,
    WK_LINE_THETA,
    WK_M,
    WK_RX,
    WK_S,
    WK_SCRATCH,
    WK_U,
    cylinder_loss_col,
    line_dofs,
    pair_col,
)
from .outputs import pair_rows
from .reactions import R_P, R_SEL, loss_moment
from .rhs import mode_mask, pair_etas, split_chain, table_modes
from .shaft import line_parts, throw_mechanism


@kernel(inline=True)
def station_moment(m, d, M_load, M_starter):
    """The moments applied on dof ``d`` from outside the mechanism: the load's where it acts,
    the starter's on the reference dof."""
    M_ext = 0.0
    if d == np.int64(m.line[0, LM_LOAD]):
        M_ext += M_load
    if d == np.int64(m.line[0, LM_REF]):
        M_ext += M_starter
    return M_ext


@kernel(inline=True)
def throw_chain(m, d, M_load, M_starter, wk):
    """The chain of dof d, its sub-chains' J_k, J′_k and M_k set up in the rows WK_J, WK_DJ,
    WK_M (``rhs.split_chain`` of the station's J_d with its own inertia on the shaft link, its
    share of the constant links and its cylinders' transfer functions, gathered into the
    scratch rows), after ``elastic.line_forces``: on the shaft link the load and starter where
    they act and the line's torque T_d, on the last the gas moment of its cylinders. Returns the
    chain's number, −1 (nothing set up) for a dof without cylinders."""
    carrier, dofs, _ = line_parts(m.line)
    c = np.int64(dofs[d, LD_CHAIN])
    if c < 0:
        return c
    u = wk[WK_SCRATCH]
    du = wk[WK_SCRATCH + 1]
    n_own = 0
    for i in range(m.ncyl):
        if np.int64(carrier[i]) == d:
            u[n_own] = wk[WK_U, i]
            du[n_own] = wk[WK_DU, i]
            n_own += 1
    M_ext = station_moment(m, d, M_load, M_starter)
    split_chain(m, wk[WK_LINE_THETA, d], wk[WK_LINE_J, d], wk[WK_LINE_DJ, d],
                wk[WK_LINE_M, d] - M_ext, M_ext + wk[WK_LINE_T, d], dofs[d, LD_OWN],
                dofs[d, LD_SHARE], u[:n_own], du[:n_own], wk)
    return c


@kernel(inline=True)
def throw_chains(m, y, sel, M_load, M_starter, sw, wk):
    """Each throw's chain with its modes held by ``sw`` (module docstring): its pairs' η*, S and
    mode margins into the rows WK_ETA, WK_S, WK_G (column c·n_pairs + k), and each throw's
    applied moment (WK_LINE_M) less its pairs' loss moment, so that the line's equations (T2),
    (T5) give the chain's. After ``elastic.line_at``; ``M_load``, ``M_starter`` its moments.
    Under reaction friction the throws' joints instead (:func:`throw_reactions`)."""
    if m.reaction:
        throw_reactions(m, y, sel, M_load, M_starter, sw, wk, wk[WK_SCRATCH], False)
        return
    n = m.n_pairs
    for d in range(line_dofs(m)):
        c = throw_chain(m, d, M_load, M_starter, wk)
        if c < 0:
            continue
        w = wk[WK_LINE_OMEGA, d]
        j0 = c * n
        modes = (sw[SW_MODES] >> j0) & ((1 << n) - 1)
        eta = wk[WK_ETA, j0:j0 + n]
        S = wk[WK_S, j0:j0 + n]
        J, dJ, M = wk[WK_J, :n + 1], wk[WK_DJ, :n + 1], wk[WK_M, :n + 1]
        if m.eta_table:  # η* depends on S: solved with the modes held
            et.solve_held(J, dJ, M, w, modes, m.et_speed, m.et_torque, m.et_size, m.et_eta,
                          m.et_min, eta, S)
        else:
            pair_etas(m, modes, eta)
            chain_solve(J, dJ, M, eta, w, S)
        loss = 0.0
        for k in range(n):
            loss += (1.0 - eta[k]) * S[k]
            g = S[k] * w
            wk[WK_G, j0 + k] = -g if (modes >> k) & 1 else g
        wk[WK_LINE_M, d] -= loss


@kernel(inline=True)
def throw_loss_rates(m, q, wk, out):
    """Each pair's loss power (1 − η*_k) S_k ω_d, times ``q`` (1/ω_ref in crank angle), into its
    loss state's rate, and the least margins over a step's stages (``WK_G_MIN``, which the
    stepper watches); after :func:`throw_chains`."""
    dofs = line_parts(m.line)[1]
    n = m.n_pairs
    for d in range(line_dofs(m)):
        c = np.int64(dofs[d, LD_CHAIN])
        if c < 0:
            continue
        w = wk[WK_LINE_OMEGA, d]
        for j in range(c * n, c * n + n):
            lost = loss_moment(wk, j) if m.reaction else (1.0 - wk[WK_ETA, j]) * wk[WK_S, j]
            out[W_LOSS0 + j] = lost * w * q
            wk[WK_G_MIN, j] = min(wk[WK_G_MIN, j], wk[WK_G, j])


@kernel(inline=True)
def throw_pair_rows(m, y, wk, row):
    """Every throw's pairs' ``PAIR_OUTPUTS`` into the output row, each at its station's speed;
    after :func:`throw_chains`."""
    dofs = line_parts(m.line)[1]
    for d in range(line_dofs(m)):
        c = np.int64(dofs[d, LD_CHAIN])
        if c >= 0:
            pair_rows(m, wk[WK_LINE_OMEGA, d], c * m.n_pairs, y[W_LOSS0:], wk, row[pair_col(m):])


@kernel(inline=True)
def throw_reaction(m, d, c, sigma, theta_sel, M_load, M_starter, wk):
    """θ̈_d of the throw at dof d (chain c) with the friction on its joints' reactions in
    direction σ, theory (T7b): the mechanism's own solver (``Model.rx_prepare``, ``rx_solve``)
    on the mechanism of the throw's cylinders (:func:`.shaft.throw_mechanism`) at its angle,
    speed and the joints' directions at ``theta_sel``, closed on the station's equation
    J_own,d θ̈_d = M_ext,d + T_d + Σ T_k(θ̈_d) in place of the shaft's (M_ext,d the load and
    starter where they act there, T_d the line's torque on it, a pure couple about the axis).
    It works in the columns from c·n_pairs on of ``wk``, where its pairs' η*, S, loss moments
    land as chain c's (``layout.n_margins``), its cylinders' rows in the columns after (other
    throws' too: nothing cached in them is trusted). After ``elastic.line_at``."""
    carrier, dofs, _ = line_parts(m.line)
    v = wk[:, c * m.n_pairs:]
    n_own = 0
    for i in range(m.ncyl):
        if np.int64(carrier[i]) == d:
            v[WK_RX + R_P, n_own] = wk[WK_CYL_FORCE, i]
            n_own += 1
    M_ext = station_moment(m, d, M_load, M_starter)
    mp = m.line[throw_mechanism(m.line, c)]
    theta = wk[WK_LINE_THETA, d]
    w = wk[WK_LINE_OMEGA, d]
    v[WK_RX + R_SEL, 0] = np.nan
    m.rx_prepare(mp, theta, w, theta_sel, v)
    T = wk[WK_LINE_T, d]
    eps0 = (wk[WK_LINE_M, d] + T - 0.5 * wk[WK_LINE_DJ, d] * w * w) / wk[WK_LINE_J, d]
    return m.rx_solve(mp, m.rx_par, m.rx_pair, dofs[d, LD_OWN], M_ext + T, eps0, w, sigma,
                      m.n_pairs, v)


@kernel(inline=True)
def throw_sigma(sw, j0):
    """The direction σ a throw's joints' friction opposes, held in the mode bit of its chain's
    first pair (``j0``; set: σ = −1), which switches where the throw's speed passes zero."""
    return -1.0 if (sw[SW_MODES] >> j0) & 1 else 1.0


@kernel
def throw_reactions(m, y, sel, M_load, M_starter, sw, wk, row, with_row):
    """Each throw's joints' friction (:func:`throw_reaction`) in its held direction σ
    (:func:`throw_sigma`): its pairs' η*, S and loss moments as its chain's, its applied
    moment (WK_LINE_M) less its pairs' loss moment, so that the line's equations (T2), (T5)
    give its θ̈ (theory, (T7b): the throw's power balance), the margin σ ω_d on its first pair
    (1 on the others: friction on the reactions has no modes); NaN as its moment where its
    solve does not converge, which the stepper reports. ``with_row``: each cylinder's share of
    every pair's loss power into the output ``row`` too."""
    carrier, dofs, _ = line_parts(m.line)
    n = m.n_pairs
    shift = sel - y[PHI]
    for d in range(line_dofs(m)):
        c = np.int64(dofs[d, LD_CHAIN])
        if c < 0:
            continue
        j0 = c * n
        sigma = throw_sigma(sw, j0)
        w = wk[WK_LINE_OMEGA, d]
        eps = throw_reaction(m, d, c, sigma, wk[WK_LINE_THETA, d] + shift, M_load, M_starter,
                             wk)
        loss = 0.0
        for k in range(n):
            loss += loss_moment(wk, j0 + k)
            wk[WK_G, j0 + k] = 1.0
        wk[WK_G, j0] = sigma * w
        wk[WK_LINE_M, d] = wk[WK_LINE_M, d] - loss if np.isfinite(eps) else np.nan
        if with_row:
            out = row[cylinder_loss_col(m):]
            own = 0
            for i in range(m.ncyl):
                if np.int64(carrier[i]) == d:
                    for p in range(n):
                        out[p * m.ncyl + i] = wk[WK_CYL_LOSS + p, j0 + own] * w
                    own += 1


@kernel
def throw_directions(m, y, sel, M_load, M_starter, sw, wk):
    """Every throw's σ chosen afresh under reaction friction, as the rigid machine's
    (``reactions.choose_direction``) at its own speed: its sign while it turns, at rest its
    incipient motion (forward if θ̈ > 0 with the friction opposing σ = +1, backward if θ̈ < 0
    with it opposing σ = −1, else held by its joints' friction: ``chain.LOCKED``); into the
    modes' bits of ``sw`` (:func:`throw_sigma`)."""
    dofs = line_parts(m.line)[1]
    n = m.n_pairs
    shift = sel - y[PHI]
    modes = 0
    for d in range(line_dofs(m)):
        c = np.int64(dofs[d, LD_CHAIN])
        if c < 0:
            continue
        w = wk[WK_LINE_OMEGA, d]
        theta_sel = wk[WK_LINE_THETA, d] + shift
        if w == 0.0:
            if throw_reaction(m, d, c, 1.0, theta_sel, M_load, M_starter, wk) > 0.0:
                w = 1.0
            elif throw_reaction(m, d, c, -1.0, theta_sel, M_load, M_starter, wk) < 0.0:
                w = -1.0
            else:
                return LOCKED
        if w < 0.0:
            modes |= 1 << (c * n)
    sw[SW_MODES] = modes
    sw[SW_DIRECTION] = 1 if wk[WK_LINE_OMEGA, np.int64(m.line[0, LM_REF])] >= 0.0 else -1
    return UNIQUE


@kernel
def throw_modes(m, y, sel, M_load, M_starter, sw, wk):
    """Every throw's modes chosen afresh at a state (``rhs.choose_modes``): each chain's as the
    rigid chain's are chosen, at its station's speed (at rest, by its incipient motion), into
    the modes' bits of ``sw``; σ the reference's direction. After ``elastic.line_at``. Returns
    the worst of the chains' statuses (``chain.LOCKED`` where one is held at rest by its
    pairs' friction); under reaction friction each throw's direction (:func:`throw_directions`)."""
    if m.reaction:
        return throw_directions(m, y, sel, M_load, M_starter, sw, wk)
    n = m.n_pairs
    modes = 0
    status = UNIQUE
    for d in range(line_dofs(m)):
        c = throw_chain(m, d, M_load, M_starter, wk)
        if c < 0:
            continue
        w = wk[WK_LINE_OMEGA, d]
        eta = wk[WK_ETA, c * n:c * n + n]
        S = wk[WK_S, c * n:c * n + n]
        if m.eta_table:
            a, chosen = table_modes(m, w, wk, eta, S)
        else:
            a, chosen, _ = modes_power_flow_into(wk[WK_J, :n + 1], wk[WK_DJ, :n + 1],
                                                 wk[WK_M, :n + 1], m.eta_fwd, m.eta_bwd, w,
                                                 eta, S,
                                                 wk[WK_SCRATCH:WK_SCRATCH + N_SCRATCH, :n])
        status = max(status, chosen)
        if chosen == LOCKED:
            return LOCKED
        sigma = 1 if w > 0.0 or (w == 0.0 and a > 0.0) else -1
        modes |= mode_mask(m, sigma, eta, S, wk) << (c * n)
    sw[SW_MODES] = modes
    sw[SW_DIRECTION] = 1 if wk[WK_LINE_OMEGA, np.int64(m.line[0, LM_REF])] >= 0.0 else -1
    return status

