"""The Scotch yoke's compiled kinematics: a crank whose pin slides in the slot of a yoke that
carries the piston, so that the piston's travel from its top dead centre is exactly

    s(α) = r (1 − cos α),   s′ = r sin α,   s″ = r cos α,

at the local angle α = φ − φ₀ (no rod, no rod angle: pure first order). The yoke with its piston
(m) reciprocates, the slider block on the crankpin (m_b) and the crank's unbalanced mass reduced
to r (m_c) go round the circle of radius r, so that (19) gives

    J(φ) = (m_b + m_c) r² + m r² sin² α,   J′(φ) = m r² sin 2α.
"""
from __future__ import annotations

from math import cos, sin

from ..jit import kernel

#: Packed parameters (``ScotchYoke.pack``): the crank radius r [m], the reciprocating mass m of
#: yoke and piston [kg], the rotating mass m_b + m_c at r [kg], the phase φ₀ [rad].
R, M_RECIPROCATING, M_ROTATING, PHASE = range(4)
N_PAR = 4


@kernel(inline=True)
def scotch_yoke_terms(mp, phi, u, du):
    """J(φ), dJ/dφ of crank, slider block, yoke and piston; fills u[0] = s′, du[0] = s″."""
    r = mp[R]
    sa = sin(phi - mp[PHASE])
    ca = cos(phi - mp[PHASE])
    u[0] = r * sa
    du[0] = r * ca
    m = mp[M_RECIPROCATING]
    return mp[M_ROTATING] * r * r + m * u[0] * u[0], 2.0 * m * u[0] * du[0]


@kernel(inline=True)
def shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ):
    """``Model.shares`` of the Scotch yoke: its one cylinder's J and J′ at its station's angle."""
    Jc[0], dJc[0] = scotch_yoke_terms(mp, angles[0], u, du)


@kernel(inline=True)
def terms(mp, kin_coef, phi, u, du, with_dJ):
    """``Model.terms`` of the Scotch yoke: :func:`scotch_yoke_terms` (``kin_coef`` is the
    tabulated kernel's)."""
    return scotch_yoke_terms(mp, phi, u, du)
