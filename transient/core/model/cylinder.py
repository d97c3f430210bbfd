"""Cylinder pressures as states of the ODE: the closed part of the cycle with Woschni's wall heat
transfer (``[gas.woschni]`` of ``model = "wiebe"``).

With heat transfer the pressure depends on the time spent per degree, i.e. on the shaft speed
and on the cylinder's own history, so it cannot be an angle-only table. From intake closing (IVC)
to exhaust opening (EVO) the pressure p_k of cylinder k is then a state, set to p_a at its IVC
(a breakpoint, where the stepper sets it as it latches fuels; on an elastic shaft line one on
the angle of the cylinder's own station) and integrated with the dynamics:

    dp/dx = A − B/ω,   A = (γ − 1)/V · dQ_b/dx − γ p/V · dV/dx,   B = (γ − 1)/V · Q̇_w,

so dp/dφ = A − B/ω in crank angle and dp/dt = ω A − B in time (no division by ω: a cylinder at
rest cools). The equations and their sources are those of :mod:`transient.forces.woschni`
(Woschni 1967; Heywood §12.4), written again here for the compiled kernel:

* heat release dQ_b/dx = f_k·m_f·LHV·η_c·dx_b/dx, Wiebe's rate (``transient.forces.wiebe``),
  f_k the cylinder's fuel (latched, or the governor's command);
* T = T_a·p·V/(p_a·V_a), γ(T) = γ_ref + γ′·(T − T_ref);
* Q̇_w = h·A_w·(T − T_w), A_w = πB²/2 + 4V/B, h = 3.26·B^−0.2·(p/kPa)^0.8·T^−0.55·w^0.8;
* w = c1·c_m + c2·V_h·T_a/(p_a·V_a)·max(p − p_mot, 0), c2 from the combustion start on,
  c_m = S·|ω|/π, p_mot = p_a·(V_a/V)^γ(T_a).

Outside the closed part the pressure is the gas-exchange table's (the same for every fuel) and
the state is held. A shaft that turns backwards is not modelled for these states (no valve runs
backwards): the closed part restarts at p_a whenever the shaft is on an intake closing.
Crank-slider only: V = V_c + F_p·s(x) from the exact kinematics, and
dV/dφ = F_p·u_k, the transfer function the mechanism kernel has already computed.
"""
from __future__ import annotations

import math

from ..jit import kernel
from .crank_slider import E, L, R, slider

#: Layout of ``Model.cyl_par`` (filled by ``transient.assemble.cylinder_fields``): intake
#: closing (local angle), length of the closed part, combustion start after IVC and duration
#: [rad]; Wiebe a, m; heat released by a full-load cycle m_f·LHV·η_c [J]; γ_ref, γ′ [1/K],
#: T_ref [K]; T_a [K], p_a [Pa], V_a [m³] at IVC; clearance V_c [m³], piston area F_p [m²], bore
#: B [m], stroke S [m], swept volume V_h [m³]; Woschni c1 [1], c2 [m/(s K)], wall temperature
#: T_w [K]; γ(T_a) [1].
(IVC, CLOSED, START, DURATION, WA, WM, Q_FULL, GAMMA, GAMMA_SLOPE, GAMMA_TREF, T_A, P_A, V_A,
 V_C, AREA, BORE, STROKE, V_H, C1, C2, T_WALL, GAMMA_A) = range(22)
N_PAR = 22


@kernel(inline=True)
def closed_angle(par, local, period):
    """Angle past intake closing [rad] if the local angle ``local`` is in the closed part, else
    −1."""
    x = (local - par[IVC]) % period
    return x if x < par[CLOSED] else -1.0


@kernel(inline=True)
def volume(mech, par, local):
    """Cylinder volume V = V_c + F_p·s at the local angle [m³] (s from the true TDC)."""
    s = slider(local, mech[R], mech[L], mech[E])[0]
    return par[V_C] + par[AREA] * s


@kernel(inline=True)
def release_rate(par, x, fuel):
    """dQ_b/dx [J/rad] at ``x`` past intake closing inside the combustion: Wiebe's rate times
    the cycle's heat (the normalised angle kept in [0, 1]: a step's stages may reach a hair past
    the combustion's ends, where y**m of y < 0 is not a number)."""
    y = min(max((x - par[START]) / par[DURATION], 0.0), 1.0)
    a, m = par[WA], par[WM]
    return fuel * par[Q_FULL] * a * (m + 1.0) * y ** m * math.exp(-a * y ** (m + 1.0)) / par[DURATION]


@kernel(inline=True)
def wall_heat(par, burnt, p, V, T, w):
    """Q̇_w [W], the heat flow into the walls at gas temperature T (Woschni's h, see the module
    docstring); ``burnt``: past the combustion start (Woschni's combustion term on)."""
    bore = par[BORE]
    c_m = par[STROKE] * abs(w) / math.pi
    velocity = par[C1] * c_m
    if burnt:
        p_mot = par[P_A] * (par[V_A] / V) ** par[GAMMA_A]
        rise = max(p - p_mot, 0.0)  # Woschni's term: the pressure rise combustion causes
        velocity += par[C2] * par[V_H] * par[T_A] / (par[P_A] * par[V_A]) * rise
    h = 3.26 * bore ** -0.2 * (p * 1e-3) ** 0.8 * T ** -0.55 * velocity ** 0.8
    area = 0.5 * math.pi * bore * bore + 4.0 * V / bore
    return h * area * (T - par[T_WALL])


@kernel(inline=True)
def pressure_rate(mech, par, x, x_sel, local, p, dVdx, w, fuel):
    """(A, B) of dp/dx = A − B/ω at ``x`` past intake closing (module docstring; ``x`` and
    ``x_sel`` less the cylinder's combustion offset, which moves its combustion, not its
    volume at ``local``). The combustion
    and Woschni's combustion term are on or off for the whole step, as the angle ``x_sel`` of
    the step's piece says (its start and end are breakpoints), so that every step integrates a
    smooth right-hand side."""
    V = volume(mech, par, local)
    T = par[T_A] * p * V / (par[P_A] * par[V_A])
    g = par[GAMMA] + par[GAMMA_SLOPE] * (T - par[GAMMA_TREF])
    burnt = x_sel >= par[START]
    release = release_rate(par, x, fuel) if burnt and x_sel < par[START] + par[DURATION] else 0.0
    A = (g - 1.0) / V * release - g * p / V * dVdx
    B = (g - 1.0) / V * wall_heat(par, burnt, p, V, T, w)
    return A, B
