"""The model's parts in plain numpy, for the reference path (:mod:`.integrate`): the serial chain
with constant-η pairs (:class:`~transient.reference.twins.ChainNumpy`, equations (22)–(29) solved
again), the pairs' friction on the joints' reactions by the Newton–Euler oracles of
:mod:`transient.reference.joints` (:class:`~transient.reference.twins.ReactionNumpy` and its
subclasses), the cylinders' closed-part pressures with wall heat
(:class:`~transient.reference.twins.CylindersNumpy`) and the dynamic governors
(:class:`~transient.reference.twins.GovernorNumpy`).

What they share with the compiled path: the Model's arrays that the scene's assembly fills (the
chain's links and their sub-chains, the joints' coefficients, the governor's parameters), the
constants that name them (``layout``, ``governor``), and the swash plate's link-9 inertia
(``swash_plate.link_terms``, compiled); the equations are written here again.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ..core.model.layout import (
    LINK_PISTONS,
    LINK_REST,
    LINK_SWASH,
    RX_MU,
    RX_RADIUS,
    RX_RING_FORCE,
    RX_RING_PRESSURE,
    RX_VISCOUS,
)
from ..core.model.swash_plate import link_terms as swash_link_terms
from ..mechanisms import reaction_joints
from .joints import (
    _at_acceleration,
    articulated_joint_forces,
    crank_slider_friction_laws,
    crank_slider_joint_forces,
    crank_slider_joint_powers,
    crank_slider_joint_signs,
    swash_plate_friction,
)


class ChainNumpy:
    """The serial chain with power-flow modes, solved as the proof in ``transient.core.model.chain``
    suggests rather than as the kernel does: the residual of the last sub-chain, F(a), strictly
    decreases in the acceleration a, so its one root is bracketed and found by Brent's method,
    the mode of each pair following from the sign of the power it transmits."""

    def __init__(self, scene) -> None:
        mech, pairs = scene.mechanism, scene.friction.pairs
        self.n = len(pairs)
        self.eta_f = np.array([p.eta_forward for p in pairs])
        self.eta_b = np.array([p.eta_backward for p in pairs])
        cuts = [mech.links.index(p.between[0]) for p in pairs]
        self.sub = [sum(c < i for c in cuts) for i in range(len(mech.links))]
        self.link_J = mech.link_inertias()
        self.laws = mech.link_laws
        self.rest = self.laws.index(LINK_REST)
        # the links whose own inertia a pair cuts from the rods' (elsewhere it is in the rest)
        self.own = [i for i, law in enumerate(self.laws) if law in (LINK_PISTONS, LINK_SWASH)
                    and self.sub[i] != self.sub[self.rest]]
        self.piston_mass = mech.piston_link_mass
        self.terms = mech.reference_terms()
        self.mp = mech.pack()
        self.J0 = scene.inertia.total

    def inputs(self, phi, J, dJ, M_gas, M_shaft, forces, sel):
        """What :meth:`solve` and :meth:`~transient.reference.twins.ChainNumpy.start_direction` take
        at a state: the sub-chains."""
        return self.split(phi, J, dJ, M_gas, M_shaft)

    def split(self, phi, J, dJ, M_gas, M_shaft):
        """(J_k, J′_k, M_k) per sub-chain from each link's inertia: the shaft's J0, the constant
        ones, where a pair cuts them from the rods the pistons' m Σ u_k² (from the twin's u, u′)
        and the swash plate's link 9 and crosses (its kernel's Python code), and the rest of
        J(φ), J′(φ) for the rods; the load and starter act on the shaft, the gas on the last
        link."""
        Ji = np.array(self.link_J, dtype=float)
        dJi = np.zeros(len(self.laws))
        Ji[0] = self.J0
        if self.own:
            _, _, u, du = self.terms(phi)
        for i in self.own:
            if self.laws[i] == LINK_PISTONS:
                Ji[i], dJi[i] = self.piston_mass * u @ u, 2.0 * self.piston_mass * u @ du
            else:
                Ji[i], dJi[i] = swash_link_terms.py_func(self.mp, phi)
        rest = self.rest
        Ji[rest] = J - (np.sum(Ji) - Ji[rest])
        dJi[rest] = dJ - (np.sum(dJi) - dJi[rest])
        Jk, dJk, Mk = np.zeros(self.n + 1), np.zeros(self.n + 1), np.zeros(self.n + 1)
        np.add.at(Jk, self.sub, Ji)
        np.add.at(dJk, self.sub, dJi)
        Mk[self.sub[0]] += M_shaft
        Mk[self.sub[-1]] += M_gas
        return Jk, dJk, Mk

    def _sweep(self, a, Jk, R, sigma):
        """Pair moments S_k and the last sub-chain's residual for a trial acceleration."""
        S, arriving = np.zeros(self.n), 0.0
        for k in range(self.n):
            S[k] = R[k] - Jk[k] * a + arriving
            arriving = S[k] * (self.eta_f[k] if S[k] * sigma >= 0 else 1.0 / self.eta_b[k])
        return R[-1] - Jk[-1] * a + arriving, S

    def solve(self, inputs, w, sigma):
        """(φ̈, S_k, η*_k, L_k) for direction σ (sign of ω, or of the incipient motion at rest),
        L_k = (1 − η*_k) S_k the loss moments."""
        a, S, eta = self._solve(*inputs, w, sigma)
        return a, S, eta, (1.0 - eta) * S

    def _solve(self, Jk, dJk, Mk, w, sigma):
        R = Mk - 0.5 * dJk * w * w
        # The residual is Σ c_k (R_k − J_k a) with weights c_k, products of n factors η_f or
        # 1/η_b, so its root a = Σ c_k R_k / Σ c_k J_k is within Σ|R| / ΣJ · η_min^(−2n). (ΣJ is
        # J(φ) > 0; a bound on the least J_k overflows when a link's inertia is denormal.)
        eta_min = min(np.min(self.eta_f), np.min(self.eta_b))
        with np.errstate(over="ignore", invalid="ignore"):
            scale = (np.sum(np.abs(R)) + 1e-300) / np.sum(Jk) / eta_min ** (2 * self.n)
        if not np.isfinite(scale):
            # A trial stage of a loose tolerance has left the physical range: a non-finite
            # derivative makes solve_ivp reject the step and shorten it (as the compiled stepper
            # does), where Brent's method would raise.
            nan = np.full(self.n, np.nan)
            return np.nan, nan, nan
        a = brentq(lambda x: self._sweep(x, Jk, R, sigma)[0], -2 * scale, 2 * scale,
                   xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500)
        S = self._sweep(a, Jk, R, sigma)[1]
        eta = np.where(S * sigma >= 0, self.eta_f, 1.0 / self.eta_b)
        return a, S, eta

    def start_direction(self, inputs):
        """σ of the incipient motion at rest, or 0 when the pairs' friction holds the chain."""
        if self.solve(inputs, 0.0, 1.0)[0] > 0:
            return 1.0
        if self.solve(inputs, 0.0, -1.0)[0] < 0:
            return -1.0
        return 0.0


class ReactionNumpy(ChainNumpy):
    """Friction on the crank-slider's joint reactions, solved as the compiled kernel does not:
    the joint forces by Newton–Euler
    (:func:`~transient.reference.joints.crank_slider_joint_forces`, eight linear equations per
    cylinder) with the friction laws applied to them
    (:func:`~transient.reference.joints.crank_slider_friction_laws`), iterated to a fixed point.
    For given friction moments and forces every joint force is affine in φ̈, so each turn takes
    φ̈ exactly from the shaft's equation J₀ φ̈ = M_shaft + Σ T(φ̈) with the forces at φ̈ = 0
    and 1; the friction is a small share of the forces (μ·r/l), so the
    turns contract to rounding within a few dozen. The joints' directions are those at the
    segment's angle ``sel``, as the compiled path holds them between breakpoints."""

    #: Turns at most; a fixed point not reached by then (a wedging mechanism) is NaN.
    TURNS = 200

    def __init__(self, scene, model) -> None:
        self.mech = scene.mechanism
        self.jp = model.rx_par
        self.pair_of = model.rx_pair
        self.n = len(scene.friction.pairs)
        self.J0 = scene.inertia.total
        # a constant-η pair at the main bearings: (its index, η_fwd, η_bwd)
        self.coupling = next(((k, p.eta_forward, p.eta_backward)
                              for k, p in enumerate(scene.friction.pairs)
                              if p.model == "constant-eta"), None)

    def inputs(self, phi, J, dJ, M_gas, M_shaft, forces, sel):
        return phi, M_shaft, forces, sel

    def solve(self, inputs, w, sigma):
        """(φ̈, S_k, η*_k, L_k) per pair; ``self.cylinder_losses`` (pairs × cylinders) after.

        With a constant-η pair at the main bearings the throws receive η* of the moment
        S = M_shaft − J₀ φ̈ the shaft puts in: both modes are solved, η* = η_fwd and 1/η_bwd, and
        the one whose S has its sign (S σ ≥ 0 forward, ≤ 0 backward) taken, forward at a tie."""
        if self.coupling is None:
            return self.solve_mode(inputs, w, sigma, 1.0)
        k, eta_f, eta_b = self.coupling
        fwd = self.solve_mode(inputs, w, sigma, eta_f)
        cylinder_losses = self.cylinder_losses
        bwd = self.solve_mode(inputs, w, sigma, 1.0 / eta_b)
        if not fwd[1][k] * sigma >= 0.0 and bwd[1][k] * sigma <= 0.0:
            return bwd
        self.cylinder_losses = cylinder_losses
        return fwd

    def coupled(self, eta, S, eta_pairs, L):
        """The pairs' (S, η*, L) of :meth:`pairs` with the constant-η pair at the main bearings
        (if any) passing η* = ``eta``: the joint's S there is what the throws receive, η* of
        the pair's; its loss belongs to no cylinder."""
        if self.coupling is None:
            return S, eta_pairs, L
        k = self.coupling[0]
        S[k] /= eta
        L[k] = (1.0 - eta) * S[k]
        eta_pairs[k] = eta
        self.cylinder_losses[k] = np.nan
        return S, eta_pairs, L

    def solve_mode(self, inputs, w, sigma, eta):
        """:meth:`solve` with the pair at the main bearings (if any) passing η* = ``eta``: the
        shaft's equation J₀ φ̈ = M_shaft + T/η*."""
        phi, M_shaft, P, sel = inputs
        mech, n_cyl = self.mech, self.mech.n_cylinders
        signs = crank_slider_joint_signs(mech, sel) * sigma
        moments, f_s = np.zeros((3, n_cyl)), np.zeros(n_cyl)
        eps = np.nan
        for _ in range(self.TURNS):
            both = crank_slider_joint_forces(mech, phi, w, np.array([0.0, 1.0]),
                                             (P + f_s)[:, None], moments[:, :, None])
            T0, T1 = both.throw_torque[:, 0], both.throw_torque[:, 1]
            eps_new = (M_shaft + np.sum(T0) / eta) / (self.J0 - np.sum(T1 - T0) / eta)
            forces = _at_acceleration(both, eps_new)
            new_moments, new_f_s = crank_slider_friction_laws(mech, self.jp, phi, w, forces, P,
                                                              signs)
            # (moments on the scale of the forces times r, φ̈ on that of the torques over J₀)
            scale = (mech.crank_radius * (np.max(np.abs(forces.main)) + np.max(np.abs(P))
                                          + np.max(np.abs(new_f_s))) + abs(M_shaft) + 1e-300)
            change = max(np.max(np.abs(new_moments - moments)),
                         np.max(np.abs(new_f_s - f_s)) * mech.crank_radius,
                         abs(eps_new - eps) * self.J0) / scale
            moments, f_s, eps = new_moments, new_f_s, eps_new
            if change <= 1e-12:  # (φ̈ from the eight equations' solve is ~1e-13 of its scale)
                break
        else:
            nan = np.full(self.n, np.nan)
            return np.nan, nan, nan, nan
        final = crank_slider_joint_forces(mech, phi, w, eps, (P + f_s)[:, None],
                                          moments[:, :, None])
        loss, through = crank_slider_joint_powers(mech, phi, w, final, moments, f_s)
        return (eps, *self.coupled(eta, *self.pairs(through.sum(axis=1), loss)))

    def pairs(self, S_joints, L_cylinders, L_joints=None):
        """(S_k, η*_k, L_k) of the pairs from each joint's S and its loss in each cylinder (rows:
        the joints in ``rx_pair``'s order); each pair's loss per cylinder into
        ``self.cylinder_losses``. ``L_joints``: each joint's loss, where a joint's loss in the
        cylinders is NaN (a loss no cylinder owns), else their sum."""
        S, L = np.zeros(self.n), np.zeros(self.n)
        self.cylinder_losses = np.zeros((self.n, self.mech.n_cylinders))
        for j, p in enumerate(self.pair_of[:len(S_joints)]):
            if p >= 0:
                S[p] += S_joints[j]
                L[p] += np.sum(L_cylinders[j]) if L_joints is None else L_joints[j]
                self.cylinder_losses[p] += L_cylinders[j]
        with np.errstate(divide="ignore", invalid="ignore"):
            eta = np.where(S != 0.0, 1.0 - L / S, np.nan)
        return S, eta, L


class ArticulatedReactionNumpy(ReactionNumpy):
    """Friction on the articulated mechanism's joint reactions for the reference path: φ̈ and the
    joints' forces by its own Newton–Euler
    (:func:`~transient.reference.joints.articulated_joint_forces`, the shaft's equation closing
    the linear system, the friction a fixed point on its forces), not by the kernels' Newton solve;
    directions at the segment's angle ``sel``, as the compiled path holds them."""

    def solve_mode(self, inputs, w, sigma, eta):
        """:meth:`ReactionNumpy.solve_mode`: the shaft's equation, which closes the linear
        system, J₀ φ̈ = M_shaft + T/η*, passed as η* J₀ and η* M_shaft."""
        phi, M_shaft, P, sel = inputs
        try:
            f = articulated_joint_forces(self.mech, phi, w, P, self.jp, sigma=sigma,
                                         J0=self.J0 * eta, M_shaft=M_shaft * eta, sel=sel)
        except (np.linalg.LinAlgError, FloatingPointError):
            f = None
        if f is None or not np.isfinite(f.epsilon):
            nan = np.full(self.n, np.nan)
            return np.nan, nan, nan, nan
        return (f.epsilon, *self.coupled(eta, *self.pairs(f.S, f.L_cyl)))


class SwashReactionNumpy(ReactionNumpy):
    """Friction on the swash plate's joint reactions for the reference path: φ̈ and the reactions
    by its Newton–Euler of every body as one linear system, the friction laws closed on them by
    ``scipy.optimize.fsolve`` (:func:`~transient.reference.joints.swash_plate_friction`), not by
    the kernels' Newton solve;
    the pistons' directions at the segment's angle ``sel``, as the compiled path holds them. The
    bearings' losses are the engine's, no cylinder's: their columns per cylinder are NaN."""

    def __init__(self, scene, model) -> None:
        super().__init__(scene, model)
        joints = reaction_joints(self.mech)
        self.rows = [joints.index(j) for j in (("shaft", "plate"), ("plate", "link"),
                                               ("piston", "cylinder"))]
        main, plate, pistons = (self.jp[j] for j in self.rows)
        self.coefficients = dict(
            main=(main[RX_MU], main[RX_RADIUS], main[RX_VISCOUS]),
            plate=(plate[RX_MU], plate[RX_RADIUS], plate[RX_VISCOUS]),
            pistons=(pistons[RX_MU], pistons[RX_RING_FORCE], pistons[RX_RING_PRESSURE],
                     pistons[RX_VISCOUS]))
        self.n_joints = len(joints)

    def solve(self, inputs, w, sigma):
        """(φ̈, S_k, η*_k, L_k) per pair; ``self.cylinder_losses`` (pairs × cylinders) after."""
        phi, M_shaft, P, sel = inputs
        try:
            r = swash_plate_friction(self.mech, self.coefficients, phi, w, P, self.J0, M_shaft,
                                     sigma=sigma, sel=sel)
        except (ArithmeticError, np.linalg.LinAlgError):
            r = None  # (a trial stage far off: solve_ivp retakes it shorter)
        if r is None or not np.isfinite(r.epsilon):
            nan = np.full(self.n, np.nan)
            return np.nan, nan, nan, nan
        S, L = np.zeros(self.n_joints), np.zeros(self.n_joints)
        L_cyl = np.full((self.n_joints, self.mech.n_cylinders), np.nan)
        S[self.rows], L[self.rows] = r.through, r.loss
        L_cyl[self.rows[2]] = r.piston_loss
        return (r.epsilon, *self.pairs(S, L_cyl, L))


_MASK64 = (1 << 64) - 1


def mix64(z: int) -> int:
    """SplitMix64's output function (Steele, Lea & Flood 2014, Fig. 3), in Python integers."""
    z = (z + 0x9E3779B97F4A7C15) & _MASK64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK64
    return z ^ (z >> 31)


def misfire_draw(seed: int, k: int, n: int) -> float:
    """The uniform draw in [0, 1) of cylinder k (from 0) in its cycle n under ``seed``, as
    :class:`transient.scene.records.Cylinder` defines it: the top 53 bits of
    mix64(mix64(mix64(seed) ^ k) ^ n); the twin of
    :func:`transient.core.model.variation.misfire_draw`."""
    return (mix64(mix64(mix64(seed) ^ k) ^ n) >> 11) / float(1 << 53)


class CylindersNumpy:
    """The cylinder pressures of the closed part with wall heat transfer (``[gas.woschni]``),
    from the scalar functions of :mod:`transient.forces.woschni` and
    :mod:`transient.forces.closed_cycle` (not from the kernels of
    ``transient.core.model.cylinder``): the state is ``y[c:]`` of the reference state, in time,
    dp/dt = (γ − 1)/V·(ω dQ_b/dx − Q̇_w) − γ p/V·dV/dt, dV/dt = F_p·u_k·ω. The combustion and
    Woschni's combustion term are switched by the segment between breakpoints, as in
    :func:`transient.forces.closed_cycle.integrate_closed`."""

    def __init__(self, scene, phases: np.ndarray, period: float, c: int,
                 offsets: np.ndarray) -> None:
        from ..forces import closed_cycle, woschni
        from ..scene.queries import clearance_volume, wiebe_levels

        gas, mech = scene.gas, scene.mechanism
        self.fn, self.w, self.c, self.period, self.phases = woschni, gas.wiebe, c, period, phases
        self.offsets = offsets  # each cylinder's combustion offset [rad]
        self.zone = closed_cycle
        self.heat = woschni.WoschniParameters.of_mechanism(
            mech, c1=gas.woschni.c1, c2=gas.woschni.c2,
            wall_temperature=gas.woschni.wall_temperature)
        cycle = wiebe_levels(mech, gas)[-1]
        self.ivc, self.v_a, self.p_a = cycle.intake_closing, cycle.v_a, gas.p_a
        self.closed = (cycle.exhaust_opening - self.ivc) % period or period
        self.start = (cycle.combustion_start - self.ivc) % period
        self.volume = mech.volume_function(clearance_volume(scene))
        self.area = mech.piston_area
        w = self.w
        self.gamma_a = w.gamma + w.gamma_slope * (w.t_a - w.gamma_t_ref)

    def past_intake(self, local):
        """Angles past intake closing, NaN outside the closed part."""
        x = np.mod(local - self.ivc, self.period)
        return np.where(x < self.closed, x, np.nan)

    def pressures(self, p_table, local_mid, y):
        """The applied pressures: the states in the closed part, else the table's."""
        closed = np.isfinite(self.past_intake(local_mid))
        return np.where(closed, y[self.c:self.c + p_table.size], p_table)

    def rates(self, local_mid, phi_shift, u, w, fuel, y):
        """dp_k/dt per cylinder; ``w`` the shaft's speed, or each cylinder's (an elastic
        line's stations)."""
        w_ = self.w
        out = []
        speeds = np.broadcast_to(w, np.shape(local_mid))
        for k, x_mid in enumerate(self.past_intake(local_mid)):
            w_k = float(speeds[k])
            if not np.isfinite(x_mid):
                out.append(0.0)
                continue
            v = float(self.volume(np.array([local_mid[k] + phi_shift]))[0])
            x_mid = x_mid - self.offsets[k]  # (the combustion's angle, δ_k later)
            x, p = x_mid + phi_shift, y[self.c + k]
            burnt = x_mid >= self.start
            burning = burnt and x_mid < self.start + w_.duration
            q = fuel[k] * w_.fuel_mass * w_.lhv * w_.efficiency
            dq_b = (q * self.zone.wiebe_rate_y(min(max((x - self.start) / w_.duration, 0.0), 1.0),
                                               w_.a, w_.m) / w_.duration if burning else 0.0)
            h = self.heat
            q_w = self.fn.wall_heat_flow(p, v, w_k, w_.t_a, self.p_a, self.v_a, self.gamma_a, h.c1,
                                         h.c2 if burnt else 0.0, h.wall_temperature, h.bore,
                                         h.stroke)
            g = w_.gamma + w_.gamma_slope * (w_.t_a * p * v / (self.p_a * self.v_a)
                                             - w_.gamma_t_ref)
            out.append(self.zone.first_law_rate(p, v, self.area * u[k] * w_k, dq_b * w_k, q_w,
                                                g))
        return out

    def close_intakes(self, phi, y) -> None:
        """At a breakpoint: the cylinders whose intake closes here start at p_a."""
        local = np.mod(phi - self.phases - self.ivc, self.period)
        for k in np.flatnonzero(np.minimum(local, self.period - local) < 1e-9):
            y[self.c + k] = self.p_a


class GovernorNumpy:
    """The dynamic governors of ``transient.core.model.governor``, written out again from the equations
    in its docstring (not from its kernels): the state is ``y[g:]`` of the reference state."""

    def __init__(self, scene, g: int) -> None:
        self.gov, self.g = scene.governor, g
        gov = self.gov
        if gov.model == "pi":
            self.tracking = gov.tracking_time or (gov.gain_p / gov.gain_i if gov.gain_i else math.inf)
        if gov.model == "flyweight":
            self.arm = gov.arm_ratio
            self.cent = gov.weights * gov.weight_mass * gov.arm_ratio * gov.gear_ratio ** 2
            self.mass = gov.sleeve_mass + gov.weights * gov.weight_mass * gov.arm_ratio ** 2
        self.sleeve = 0  # 0 moving, 1 on the low stop, 2 on the high stop

    def force(self, w, z, v):
        """Net force on the flyweight sleeve: centrifugal, less spring and damper [N]."""
        gov = self.gov
        return (self.cent * w * w * (gov.radius + self.arm * z)
                - gov.spring_preload - gov.spring_rate * z - gov.damping * v)

    def pi_demand(self, w, y):
        gov = self.gov
        e = 1.0 - w / gov.speed
        u = gov.gain_p * e + y[self.g]
        if gov.gain_d:
            u -= gov.gain_d * (w - y[self.g + 2]) / (gov.derivative_time * gov.speed)
        return e, u, float(np.clip(u, gov.fuel_min, gov.fuel_max))

    def rates(self, w, y):
        gov, g = self.gov, self.g
        if gov.model == "pi":
            e, u, u_s = self.pi_demand(w, y)
            back = (u_s - u) / self.tracking if gov.anti_windup else 0.0
            rack = (u_s - y[g + 1]) / gov.actuator_time
            if gov.rate_limit:
                rack = float(np.clip(rack, -gov.rate_limit, gov.rate_limit))
            rates = [gov.gain_i * e + back, rack]
            return rates + ([(w - y[g + 2]) / gov.derivative_time] if gov.gain_d else [])
        if gov.model == "flyweight":
            if self.sleeve:
                return [0.0, 0.0]
            return [y[g + 1], self.force(w, y[g], y[g + 1]) / self.mass]
        return []

    def command(self, w, y, droop):
        gov = self.gov
        if gov.model == "pi":
            return y[self.g + 1]
        if gov.model == "flyweight":
            return gov.fuel_max + (gov.fuel_min - gov.fuel_max) * y[self.g] / gov.travel
        return droop(w)
