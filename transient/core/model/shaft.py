"""The elastic shaft line's equations (theory, *The elastic shaft line*, (T1)–(T5)), on the
degrees of freedom of the line: its stations (each with its own angle θ_d, speed ω_d and inertia
J_d(θ_d)), the rings of its dampers and the driven inertia beyond a coupling, all in one array.

Every elastic or viscous link between two degrees of freedom — a section of the shaft, a damper's
rubber or silicone, a coupling through a gear — is one row of an element table
(:data:`ELEMENT`): it twists by δ = θ_i − r θ_j (r the gear ratio ω_i/ω_j, 1 on one shaft), its
torque k δ + c δ̇ holds i back and drives j by r times it (a gear passes r times the torque to
the slower side), and it takes c δ̇² of power. One loop over the rows serves sections, rings and
couplings alike, O(N) in the line's length.
"""
from __future__ import annotations

from ..declare import Layout
from ..jit import kernel

#: A row of the element table: the two degrees of freedom it joins, its stiffness [N m/rad],
#: damping [N m s/rad] and gear ratio r = ω_i/ω_j [1].
ELEMENT = Layout("element", "i", "j", "stiffness", "damping", "ratio")
EL_I, EL_J, EL_K, EL_C, EL_R = ELEMENT
N_ELEMENT = ELEMENT.size


@kernel(inline=True)
def line_inertia(carrier, J_own, Jc, dJc, J, dJ):
    """J_d = J_own,d + Σ J_c over the cylinders c the degree of freedom carries, and J′_d,
    (T1): ``carrier[c]`` the degree of freedom of cylinder c, ``Jc``, ``dJc`` their shares at
    their own angles (the mechanism's ``shares``)."""
    for d in range(J.shape[0]):
        J[d] = J_own[d]
        dJ[d] = 0.0
    for c in range(carrier.shape[0]):
        J[carrier[c]] += Jc[c]
        dJ[carrier[c]] += dJc[c]


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
    for d in range(T.shape[0]):
        T[d] += gear[d] * weights[d] / total * resultant
    for e in range(elements.shape[0]):
        i = int(elements[e, EL_I])
        j = int(elements[e, EL_J])
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


# -- the rigid shaft's kernels in the Model's line fields: the stepper calls them only where
# ``Model.line_n`` > 0, so that a rigid scene's stepper holds none of the line's code


@kernel(inline=True)
def no_shares(mp, kin_coef, angles, Jc, dJc, u, du):
    """``Model.shares`` of a rigid shaft: never called."""


@kernel(inline=True)
def no_line_rates(m, extras, angle_mode, y, sel, sw, wk, out):
    """``Model.line_rates`` of a rigid shaft: never called."""


@kernel(inline=True)
def no_line_row(m, angle_mode, y, sw, wk, row):
    """``Model.line_row`` of a rigid shaft: never called."""


@kernel(inline=True)
def no_line_mode(m, y, to_angle, wk):
    """``Model.line_mode`` of a rigid shaft: never called."""


@kernel(inline=True)
def no_line_inertia(m, phi, wk):
    """``Model.line_ref_inertia`` of a rigid shaft: never called."""
    return 0.0
