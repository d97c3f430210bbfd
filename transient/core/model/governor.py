"""Dynamic speed governors, whose states are integrated with the engine.

The static droop characteristic of the swash-plate paper (§4) has no state and lives in
``transient.core.model.forcing`` (``fuel``). The two governors here move the fuel rack through states of
their own, appended to the state vector after the pairs' work integrals (``layout.gov_index``):

**PI(D), isochronous.** Relative speed error e = (ω_ref − ω)/ω_ref. Controller output

    u = K_p e + x_I − K_d (ω − x_F)/(τ_D ω_ref),

the last term K_d·de/dt with the derivative filtered: dx_F/dt = (ω − x_F)/τ_D. The demand is
clipped to the rack's position limits, u_s = min(max(u, f_min), f_max), and the integrator
tracks it back when they bind (back-calculation anti-windup, Åström & Hägglund, *Advanced PID
Control*, §3.5):

    dx_I/dt = K_i e + (u_s − u)/T_t        (no second term without anti-windup).

The actuator is a first-order lag with a rate limit: dr/dt = clip((u_s − r)/τ_A, ±ṙ_max); the
fuel command is the rack position r. With x_I periodic in a periodic steady state, ∫e dt = 0
over a period: the time-mean speed is ω_ref exactly (zero steady error).

**Centrifugal flyweight governor** (linearised bell cranks). n_w weights of mass m_w on bell
cranks (arm a to the weight, b to the sleeve) turn at ω_g = i_g ω; at sleeve lift z the weights
run at radius ρ = ρ₀ + (a/b) z. Lagrange's equation with the kinetic energy ½M ż² +
½ n_w m_w ρ² ω_g² (M = m_s + n_w m_w (a/b)², the sleeve plus the weights' radial motion) and a
preloaded spring F₀ + k z gives

    M z̈ = n_w m_w (a/b) i_g² ω² ρ(z) − (F₀ + k z) − c ż.

The rack is linked to the sleeve: f = f_max + (f_min − f_max) z/z_max. The sleeve's travel
[0, z_max] ends on stops: reaching one is a state event that stops the sleeve there (an
inelastic stop, ż := 0); it leaves the stop when the net force turns away from it, which on a
stop is a speed level (``lift_speeds``). The governor's own inertia and its reaction on the
shaft are neglected: in ``cases/gots_diesel_start_flyweight.toml`` at the end of its run the
flyweights hold ½ n_w m_w ρ² ω_g² = 4.19 J against the engine's ½Jω² = 1.56·10⁴ J (2.7·10⁻⁴).

The clipping of the PI demand is held on one branch for a whole step (``clipped``) and switched
by state events where u reaches a limit, as the droop characteristic's corners are: without
that, a demand that grazes a limit every cycle (an engine idling near zero fuel) puts a kink
into most steps, and the step-size control rejects about one step in two. The rate limit is
left a kink inside steps (continuous, taken by the step-size control). The stops of the
flyweight governor change the equations and are events.
"""
from __future__ import annotations

from math import sqrt

from ..jit import kernel

#: ``Model.gov_dyn``: the governor whose states are integrated (PID: PI with the derivative term
#: and its filter state; a PI governor has no filter state to integrate).
NONE, PI, FLYWEIGHT, PID = 0, 1, 2, 3

#: States of the PI(D) governor (offsets from ``layout.gov_index``) and their output columns.
PI_INTEGRAL, PI_RACK, PI_FILTER = range(3)
#: Parameters of the PI(D) governor (``Model.gov_par``, filled by ``transient.assemble``).
(P_REF, P_KP, P_KI, P_KD, P_TAU_D, P_TAU_A, P_RATE, P_FMIN, P_FMAX, P_INV_TT) = range(10)

#: States of the flyweight governor: sleeve lift z [m] and its rate ż [m/s].
FW_LIFT, FW_RATE = range(2)
#: Parameters of the flyweight governor. F_CENT = n_w m_w (a/b) i_g² [kg], F_ARM = a/b.
(F_CENT, F_RHO0, F_ARM, F_PRELOAD, F_SPRING, F_DAMP, F_MASS, F_TRAVEL, F_FMAX, F_FMIN,
 F_W_LIFT, F_W_TOP) = range(12)
#: The sleeve's switch (``layout.SW_SLEEVE``): moving, on the low stop (z = 0), on the high stop.
FREE, ON_LOW_STOP, ON_HIGH_STOP = range(3)

#: Output columns (and units) of each governor's states.
STATE_NAMES = ((), ("gov_integral", "gov_rack"), ("sleeve_lift", "sleeve_speed"),
               ("gov_integral", "gov_rack", "gov_filter"))
STATE_UNITS = ((), ("1", "1"), ("m", "m/s"), ("1", "1", "rad/s"))


#: Number of states of each governor (by ``Model.gov_dyn``).
N_STATES = tuple(len(names) for names in STATE_NAMES)


@kernel(inline=True)
def n_states(kind):
    """Number of states of governor ``kind``."""
    return N_STATES[kind]


#: Branches of the PI(D) demand's clipping (held for a step, like the droop characteristic's,
#: and switched by state events where u reaches a limit): on f_max, between, on f_min.
AT_MAX, BETWEEN, AT_MIN = range(3)


@kernel(inline=True)
def pi_demand(kind, par, w, y, g):
    """(e, u): relative speed error and the PI or PID demand; states from y[g]."""
    e = (par[P_REF] - w) / par[P_REF]
    u = par[P_KP] * e + y[g + PI_INTEGRAL]
    if kind == PID:
        u -= par[P_KD] * (w - y[g + PI_FILTER]) / (par[P_TAU_D] * par[P_REF])
    return e, u


@kernel(inline=True)
def clipped(par, u, branch):
    """u_s: the demand on the branch's side of the limits (u itself between them, extrapolated
    across a limit inside a step until its event switches the branch)."""
    if branch == AT_MAX:
        return par[P_FMAX]
    if branch == AT_MIN:
        return par[P_FMIN]
    return u


@kernel
def demand_branch(par, u, rising):
    """Branch of the clipping at demand u; on a limit, the side u moves to (``rising``)."""
    if u > par[P_FMAX] or (u == par[P_FMAX] and rising):
        return AT_MAX
    if u < par[P_FMIN] or (u == par[P_FMIN] and not rising):
        return AT_MIN
    return BETWEEN


@kernel(inline=True)
def pi_rates(kind, par, w, y, g, branch, scale, out):
    """Time derivatives of the PI(D) states, times ``scale`` (1/ω in crank angle), into out[g:];
    returns the demand u."""
    e, u = pi_demand(kind, par, w, y, g)
    u_s = clipped(par, u, branch)
    out[g + PI_INTEGRAL] = (par[P_KI] * e + (u_s - u) * par[P_INV_TT]) * scale
    rate = (u_s - y[g + PI_RACK]) / par[P_TAU_A]
    out[g + PI_RACK] = min(max(rate, -par[P_RATE]), par[P_RATE]) * scale
    if kind == PID:
        out[g + PI_FILTER] = (w - y[g + PI_FILTER]) / par[P_TAU_D] * scale
    return u


@kernel(inline=True)
def sleeve_force(par, w, z, v):
    """Net axial force on the flyweight governor's sleeve [N] (the module's equation)."""
    rho = par[F_RHO0] + par[F_ARM] * z
    return par[F_CENT] * rho * w * w - (par[F_PRELOAD] + par[F_SPRING] * z) - par[F_DAMP] * v


@kernel(inline=True)
def flyweight_rates(par, w, y, g, sleeve, scale, out):
    """Time derivatives of (z, ż), times ``scale``; zero on a stop (``sleeve`` ≠ FREE)."""
    if sleeve != FREE:
        out[g + FW_LIFT] = 0.0
        out[g + FW_RATE] = 0.0
        return
    v = y[g + FW_RATE]
    out[g + FW_LIFT] = v * scale
    out[g + FW_RATE] = sleeve_force(par, w, y[g + FW_LIFT], v) / par[F_MASS] * scale


@kernel(inline=True)
def rack_of_lift(par, z):
    """Fuel command of the rack linked to the sleeve at lift z."""
    return par[F_FMAX] + (par[F_FMIN] - par[F_FMAX]) * z / par[F_TRAVEL]


def lift_speeds(cent, rho0, arm, preload, spring, travel):
    """Shaft speeds [rad/s] at which the sleeve leaves its low stop (rising) and its high stop
    (falling): where the centrifugal force balances the spring there, n_w m_w (a/b) i_g² ω² ρ =
    F₀ + k z."""
    w_low = sqrt(preload / (cent * rho0))
    w_top = sqrt((preload + spring * travel) / (cent * (rho0 + arm * travel)))
    return w_low, w_top


def sleeve_equilibrium(par, w):
    """Static sleeve lift at constant speed w [m], on the stops if the balance lies beyond them,
    and the switch: ``(z, sleeve)``. Solves n_w m_w (a/b) i_g² ω² (ρ₀ + (a/b) z) = F₀ + k z."""
    c = par[F_CENT] * w * w
    if c * par[F_RHO0] <= par[F_PRELOAD]:
        return 0.0, ON_LOW_STOP
    stiffness = par[F_SPRING] - c * par[F_ARM]
    travel = par[F_TRAVEL]
    if stiffness <= 0.0:  # the centrifugal force grows faster than the spring: up to the stop
        return travel, ON_HIGH_STOP
    z = (c * par[F_RHO0] - par[F_PRELOAD]) / stiffness
    if z >= travel:
        return travel, ON_HIGH_STOP
    return z, FREE
