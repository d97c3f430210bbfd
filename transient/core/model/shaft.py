"""The elastic shaft line's equations (theory, *The elastic shaft line*, (T1)–(T5)), on the
degrees of freedom of the line: its stations (each with its own angle θ_d, speed ω_d and inertia
J_d(θ_d)), the rings of its dampers and the driven inertia beyond a coupling, all in one array.

Every elastic or viscous link between two degrees of freedom — a section of the shaft, a damper's
rubber or silicone, a coupling through a gear — is one row of an element table
(:data:`.layout.ELEMENT`): it twists by δ = θ_i − r θ_j (r the gear ratio ω_i/ω_j, 1 on one shaft), its
torque k δ + c δ̇ holds i back and drives j by r times it (a gear passes r times the torque to
the slower side), and it takes c δ̇² of power. One loop over the rows serves sections, rings and
couplings alike, O(N) in the line's length.

The Model holds the line packed in one array (``Model.line``, :data:`.layout.LINE_META`,
:func:`pack_line`), and the kernels that need no gas or load (the dofs' angles and inertias, the
change of the independent variable, the reference's inertia) are here; the derivative and the
output row are :mod:`.elastic`'s.
"""
from __future__ import annotations

import numpy as np

from ..jit import kernel
from .layout import (
    EL_C,
    EL_I,
    EL_J,
    EL_K,
    EL_R,
    LD_BREAKPOINTS,
    LD_CHAIN,
    LD_OWN,
    LD_SHARE,
    LINE_DOF,
    LINE_META,
    LM_CHAINS,
    LM_CYLINDERS,
    LM_DOFS,
    LM_ELEMENTS,
    LM_REF,
    N_ELEMENT,
    N_LINE_COLUMNS,
    PHI,
    WK_CYL_ANGLE,
    WK_CYL_DJ,
    WK_CYL_J,
    WK_DU,
    WK_LINE_DJ,
    WK_LINE_J,
    WK_LINE_THETA,
    WK_U,
    line_dofs,
    line_index,
)


def pack_line(ref: int, load: int, carrier, dofs, elements, starts,
              throws=None) -> np.ndarray:
    """The Model's ``line`` (:data:`.layout.LINE_META`): the reference's and the load's dof, the
    dof of each cylinder (``carrier``), the rows of the dofs (``dofs``, :data:`.layout.LINE_DOF`:
    its first four columns; each dof that carries cylinders is a chain of the pairs, in order,
    with its share of them; ``starts``, where each dof's breakpoints begin in
    ``Model.breakpoints``), of the elements (:data:`.layout.ELEMENT`) and, under reaction
    friction, per chain the mechanism of its cylinders (``throws``, :func:`throw_mechanism`;
    the array is then as wide as they are)."""
    carrier = np.asarray(carrier, dtype=np.int64)
    dofs = np.asarray(dofs, dtype=float)
    elements = np.asarray(elements, dtype=float).reshape(-1, N_ELEMENT)
    rows = np.zeros((len(dofs), LINE_DOF.size))
    rows[:, :dofs.shape[1]] = dofs
    carried = np.bincount(carrier, minlength=len(dofs))
    rows[:, LD_CHAIN] = np.where(carried > 0, np.cumsum(carried > 0) - 1, -1)
    rows[:, LD_SHARE] = carried / max(carrier.size, 1)
    rows[:, LD_BREAKPOINTS] = starts
    throws = np.zeros((0, 1)) if throws is None else np.asarray(throws, dtype=float)
    out = np.zeros((1 + carrier.size + len(dofs) + len(elements) + len(throws),
                    max(N_LINE_COLUMNS, throws.shape[1])))
    out[0, :LINE_META.size] = (len(dofs), ref, load, len(elements), carrier.size,
                               np.count_nonzero(carried))
    out[1:1 + carrier.size, 0] = carrier
    out[1 + carrier.size:1 + carrier.size + len(dofs), :LINE_DOF.size] = rows
    e0 = 1 + carrier.size + len(dofs)
    out[e0:e0 + len(elements), :N_ELEMENT] = elements
    out[e0 + len(elements):, :throws.shape[1]] = throws
    return out


#: What ``Model.line_model`` is asked for (``what``): the derivative into ``out``, the output
#: row into ``out``, the pairs' mode margins into the work array, or the pairs' modes chosen
#: afresh into the switches (:mod:`.elastic`, :mod:`.line_pairs`).
LINE_RATES, LINE_ROW, LINE_MARGINS, LINE_MODES = range(4)
#: ``Model.line_model``'s answer where it did nothing (a rigid shaft's: the rigid model does
#: it); an elastic line's is the status of what it did (``chain.UNIQUE``, or where it chose
#: the modes the worst of its chains', ``chain.LOCKED`` where one is held by its pairs).
NOT_A_LINE = -1


#: The ``line`` of a rigid shaft's Model: no dofs, and one chain of the pairs, the machine.
RIGID_LINE = np.zeros((1, N_LINE_COLUMNS))
RIGID_LINE[0, LM_CHAINS] = 1.0


@kernel(inline=True)
def line_parts(line):
    """Views of the Model's packed ``line``: each cylinder's dof (a column of floats), the
    dofs' rows and the element table."""
    n = np.int64(line[0, LM_DOFS])
    d0 = 1 + np.int64(line[0, LM_CYLINDERS])
    e0 = d0 + n
    return line[1:d0, 0], line[d0:e0, :], line[e0:e0 + np.int64(line[0, LM_ELEMENTS]), :]


@kernel(inline=True)
def throw_mechanism(line, c):
    """The row of ``line`` with the compiled parameters of the mechanism made of chain c's
    cylinders (under reaction friction, :func:`pack_line`): what its throw's reaction solve
    takes for ``Model.mech``."""
    return (1 + np.int64(line[0, LM_CYLINDERS]) + np.int64(line[0, LM_DOFS])
            + np.int64(line[0, LM_ELEMENTS]) + c)


@kernel(inline=True)
def line_inertia(carrier, J_own, Jc, dJc, J, dJ):
    """J_d = J_own,d + Σ J_c over the cylinders c the degree of freedom carries, and J′_d,
    (T1): ``carrier[c]`` the degree of freedom of cylinder c, ``Jc``, ``dJc`` their shares at
    their own angles (the mechanism's ``shares``)."""
    for d in range(J.shape[0]):
        J[d] = J_own[d]
        dJ[d] = 0.0
    for c in range(carrier.shape[0]):
        J[np.int64(carrier[c])] += Jc[c]
        dJ[np.int64(carrier[c])] += dJc[c]


@kernel(inline=True)
def line_torques(elements, absolute, weights, gear, theta, omega, T):
    """T_d: the torques of the elements and of the absolute damping on each degree of freedom,
    (T3); returns the power they take [W] (Σ c δ̇² + Σ a_d (g_d ω_d − ω̄)²).

    The absolute damping a_d acts on each dof's motion relative to the line's rigid-body motion
    ω̄ = Σ w_d g_d ω_d / Σ w_d (``weights`` w_d the cycle-mean inertias at the reference's
    speed, ``gear`` g_d each dof's ratio to it, as in :func:`line_angle_rates`): with
    r_d = a_d (g_d ω_d − ω̄), τ_d = g_d (−r_d + (w_d/Σw) Σ_e r_e), the torque −Pᵀ A P ω of
    P = I − 1 wᵀ/Σw on the speeds g_d ω_d. It has no net torque, so it never brakes the
    rotation as a whole, and takes Σ a_d (g_d ω_d − ω̄)²."""
    total = 0.0
    moment = 0.0
    for d in range(T.shape[0]):
        total += weights[d]
        moment += weights[d] * gear[d] * omega[d]
    mean = moment / total
    resultant = 0.0
    taken = 0.0
    for d in range(T.shape[0]):
        slip = gear[d] * omega[d] - mean
        r = absolute[d] * slip
        T[d] = -gear[d] * r
        resultant += r
        taken += r * slip
    per_weight = resultant / total  # (one division, not one per dof)
    for d in range(T.shape[0]):
        T[d] += gear[d] * weights[d] * per_weight
    for e in range(elements.shape[0]):
        i = np.int64(elements[e, EL_I])
        j = np.int64(elements[e, EL_J])
        r = elements[e, EL_R]
        rate = omega[i] - r * omega[j]
        torque = elements[e, EL_K] * (theta[i] - r * theta[j]) + elements[e, EL_C] * rate
        T[i] -= torque
        T[j] += r * torque
        taken += elements[e, EL_C] * rate * rate
    return taken


@kernel(inline=True)
def line_accelerations(J, dJ, M, T, omega, acc):
    """θ̈_d = (M_d + T_d − ½ J′_d ω_d²)/J_d, Lagrange's equation per degree of freedom (T2)."""
    for d in range(J.shape[0]):
        acc[d] = (M[d] + T[d] - 0.5 * dJ[d] * omega[d] * omega[d]) / J[d]


@kernel(inline=True)
def line_angle_rates(ref, gear, M, T, omega, d_twist, d_energy):
    """In the reference's crank angle φ (T5): each degree of freedom's twist q_d = g_d θ_d − φ
    (g_d its gear ratio to the reference) and energy K_d = ½ J_d ω_d² change at
    dq_d/dφ = g_d ω_d/ω_ref − 1 and dK_d/dφ = (M_d + T_d) ω_d/ω_ref, the work–energy law of
    each, as (18) is of the rigid shaft."""
    inv = 1.0 / omega[ref]
    for d in range(omega.shape[0]):
        d_twist[d] = gear[d] * omega[d] * inv - 1.0
        d_energy[d] = (M[d] + T[d]) * omega[d] * inv


# -- the line's state (layout.STATE, block "line")


@kernel(inline=True)
def twist_index(m, d):
    """Index in the state of dof d's twist q_d (d not the reference); its K_d (ω_d) follows."""
    return twist_at(line_index(m), np.int64(m.line[0, LM_REF]), d)


@kernel(inline=True)
def twist_at(first, ref, d):
    """:func:`twist_index` from the line's first state (``layout.line_index``) and the reference
    dof, for a loop over the dofs that reads them once."""
    return first + 2 * (d if d < ref else d - 1)


@kernel(inline=True)
def line_inertias(m, y, wk, with_dJ):
    """Each dof's angle θ_d (WK_LINE_THETA), J_d and J′_d (WK_LINE_J, WK_LINE_DJ) at state
    ``y``, (T1); each cylinder's transfer functions at its dof's angle in the rows u, u′. Without
    ``with_dJ`` J′_d and u′ may be left NaN: the derivative in crank angle needs neither (T5)."""
    carrier, dofs, _ = line_parts(m.line)
    n = line_dofs(m)
    ref, first = np.int64(m.line[0, LM_REF]), line_index(m)
    for d in range(n):
        wk[WK_LINE_THETA, d] = angle_at(y, d, first, ref)
    for c in range(m.ncyl):
        wk[WK_CYL_ANGLE, c] = wk[WK_LINE_THETA, np.int64(carrier[c])]
    m.shares(m.mech, m.kin_coef, wk[WK_CYL_ANGLE, :m.ncyl], wk[WK_CYL_J], wk[WK_CYL_DJ],
             wk[WK_U], wk[WK_DU], with_dJ)
    line_inertia(carrier, dofs[:, LD_OWN], wk[WK_CYL_J, :m.ncyl], wk[WK_CYL_DJ, :m.ncyl],
                 wk[WK_LINE_J, :n], wk[WK_LINE_DJ, :n])


@kernel
def line_mode(m, y, to_angle, wk):
    """Each dof but the reference from ω_d to K_d = ½J_d(θ_d)ω_d² (``to_angle``) or back, where
    the independent variable changes (the stepper converts the reference's own with
    :func:`ref_inertia`, through ``forcing.inertia``)."""
    line_inertias(m, y, wk, False)
    ref = np.int64(m.line[0, LM_REF])
    for d in range(line_dofs(m)):
        if d != ref:
            i = twist_index(m, d) + 1
            J = wk[WK_LINE_J, d]
            y[i] = 0.5 * J * y[i] * y[i] if to_angle else np.sqrt(2.0 * y[i] / J)


@kernel
def ref_inertia(m, phi, wk):
    """J_ref(φ), the reference dof's own inertia and its cylinders' shares at φ, summed as
    :func:`line_inertia` sums them (so that K_ref = ½J_ref ω_ref² converts both ways to the same
    bits); fills the row u at φ."""
    carrier, dofs, _ = line_parts(m.line)
    ref = np.int64(m.line[0, LM_REF])
    for c in range(m.ncyl):
        wk[WK_CYL_ANGLE, c] = phi
    m.shares(m.mech, m.kin_coef, wk[WK_CYL_ANGLE, :m.ncyl], wk[WK_CYL_J], wk[WK_CYL_DJ],
             wk[WK_U], wk[WK_DU], False)
    J = dofs[ref, LD_OWN]
    for c in range(m.ncyl):
        if np.int64(carrier[c]) == ref:
            J += wk[WK_CYL_J, c]
    return J


@kernel(inline=True)
def dof_angle(m, y, d):
    """θ_d of dof d at state ``y``: the reference's φ, any other's φ + q_d."""
    return angle_at(y, d, line_index(m), np.int64(m.line[0, LM_REF]))


@kernel(inline=True)
def angle_at(y, d, first, ref):
    """:func:`dof_angle` from the line's first state and the reference dof (:func:`twist_at`)."""
    return y[PHI] if d == ref else y[PHI] + y[twist_at(first, ref, d)]


@kernel(inline=True)
def dof_breakpoints(m, d):
    """Dof d's own breakpoints, sorted angles of its cycle on its angle θ_d (a view of
    ``Model.breakpoints``), and the index of the first in it (``Model.bp_jump`` alike)."""
    dofs = line_parts(m.line)[1]
    first = np.int64(dofs[d, LD_BREAKPOINTS])
    end = np.int64(dofs[d + 1, LD_BREAKPOINTS]) if d + 1 < dofs.shape[0] else m.breakpoints.shape[0]
    return m.breakpoints[first:end], first


# -- a rigid shaft's kernels in the Model's line fields (never called: there are no dofs)


@kernel(inline=True)
def no_shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ):
    """``Model.shares`` of a rigid shaft."""


@kernel(inline=True)
def no_line_switch(m, y, to_angle, wk):
    """``Model.line_switch`` of a rigid shaft: no dofs to convert."""


@kernel(inline=True)
def no_line_model(m, extras, what, angle_mode, y, sel, sw, wk, out):
    """``Model.line_model`` of a rigid shaft: nothing done, as its NOT_A_LINE says."""
    return NOT_A_LINE
