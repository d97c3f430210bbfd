"""The elastic shaft line in plain numpy, for the reference path: stations k = 0 … N−1 along the
crankshaft, each with its own angle θ_k, speed ω_k and reduced inertia
J_k(θ_k) = J_own,k + Σ_c J_c(θ_k) of the cylinders c it carries, joined by elastic sections;
dampers' rings and an elastic coupling through a gear to a driven inertia as further degrees of
freedom (the equations of the theory page, *The elastic shaft line*, (T1)–(T9)).

Per station, Lagrange's equation (T2)

    J_k θ̈_k + ½ J′_k ω_k² = M_gas,k + M_ext,k + T_k,

T_k the torque of the sections, rings, coupling and absolute damping on station k; with a
constant-η pair between a station's shaft and its throw's mechanism, (T7) in its place. The work
of the applied moments and the energy every dissipative element takes are integrated as extra
states, so that the balance (T4) holds at every sample to the solver's accuracy.

What it shares with the compiled path: nothing of ``transient.core``. The crank-slider's
per-cylinder terms (:class:`CrankSliderCylinders`) are written here from the mechanism's
geometry and masses (the scene's :class:`~transient.mechanisms.crank_slider.CrankSlider`), apart
from the twin :class:`~transient.mechanisms.twins.CrankSliderNumpy`, which gives their sum and so
checks them; :func:`rigid_run` integrates the rigid reduced equation (18) on that twin for the
rigid limit.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

Array = NDArray[np.float64]


class Cylinders(Protocol):
    """The engine side of a shaft line: each cylinder's own reduced inertia and applied moment,
    as functions of the angle of the station that carries it."""

    def inertia(self, angles: Array) -> tuple[Array, Array]:
        """(J_c, dJ_c/dθ) of each cylinder at its station's angle θ [kg m², kg m²/rad]."""
        ...

    def moments(self, angles: Array, speeds: Array, t: float) -> Array:
        """Each cylinder's applied moment reduced to its station's angle [N m]."""
        ...


#: Applied moments on the stations, (θ, ω, t) ↦ M_ext per station [N m] (load, starter).
StationMoments = Callable[[Array, Array, float], Array]
#: The load on the driven inertia, (θ_d, ω_d, t) ↦ M_load [N m].
DrivenMoment = Callable[[float, float, float], float]


@dataclass(frozen=True)
class Ring:
    """A damper's ring on a station: inertia I_r, and between ring and station a damping c_r
    (the silicone of a viscous damper) and a stiffness k_r (0 for a viscous damper, > 0 for a
    tuned rubber damper)."""

    station: int
    inertia: float
    damping: float
    stiffness: float = 0.0


@dataclass(frozen=True)
class Coupling:
    """An elastic coupling from a station through an ideal gear to a driven inertia J_d: the
    coupling's twist is δ = θ_station − i θ_d, with i = ω_station/ω_d the gear ratio and the
    stiffness and damping referred to the station's side; the gear passes i times its torque
    to the driven side."""

    station: int
    stiffness: float
    damping: float
    ratio: float
    driven_inertia: float


@dataclass(frozen=True)
class ShaftLine:
    """The shaft line's data, stations from the nose.

    ``inertia`` J_own,k (N); ``stiffness`` k_i and ``damping`` c_i of section i between
    stations i and i+1 (N−1); ``absolute`` d_k on each station (N), acting on its speed less
    the line's mean speed (:meth:`TorsionModel.absolute_torques`);
    ``station_of_cylinder`` the station each cylinder rides on; ``eta``: per station the
    (forward, backward) efficiency of a constant-η pair between its shaft and its throw's
    mechanism (1, 1: none)."""

    inertia: Array
    stiffness: Array
    damping: Array
    absolute: Array
    station_of_cylinder: NDArray[np.intp]
    rings: tuple[Ring, ...] = ()
    coupling: Coupling | None = None
    eta: tuple[Array, Array] | None = None

    def __post_init__(self) -> None:
        n = len(self.inertia)
        sizes = {"stiffness": (len(self.stiffness), n - 1), "damping": (len(self.damping), n - 1),
                 "absolute": (len(self.absolute), n)}
        for name, (got, want) in sizes.items():
            if got != want:
                raise ValueError(f"ShaftLine.{name}: {got} values for {n} stations; allowed "
                                 f"{want}")
        if n < 1 or np.any(np.asarray(self.inertia) <= 0.0):
            raise ValueError("ShaftLine.inertia: every station needs an inertia > 0")
        if np.any(np.asarray(self.stiffness) <= 0.0):
            raise ValueError("ShaftLine.stiffness: every section needs a stiffness > 0")
        stations = np.asarray(self.station_of_cylinder)
        if stations.size and (stations.min() < 0 or stations.max() >= n):
            raise ValueError(f"ShaftLine.station_of_cylinder: stations 0 … {n - 1} only")
        for ring in self.rings:
            if not 0 <= ring.station < n or ring.inertia <= 0.0:
                raise ValueError(f"ShaftLine.rings: {ring} needs a station 0 … {n - 1} and an "
                                 f"inertia > 0")
        c = self.coupling
        if c is not None and (not 0 <= c.station < n or c.ratio == 0.0 or c.stiffness <= 0.0
                              or c.driven_inertia <= 0.0):
            raise ValueError(f"ShaftLine.coupling: {c} needs a station 0 … {n - 1}, a ratio ≠ 0 "
                             f"and a stiffness and driven inertia > 0")
        if self.eta is not None:
            f, b = (np.asarray(e, dtype=float) for e in self.eta)
            if f.shape != (n,) or b.shape != (n,) or np.any((f <= 0) | (f > 1) | (b <= 0)
                                                             | (b > 1)):
                raise ValueError("ShaftLine.eta: per station 0 < η ≤ 1, forward and backward")

    @property
    def n(self) -> int:
        return len(self.inertia)


#: The work integrals at the end of the state, in this order: the applied moments' work (gas,
#: on the stations, on the driven inertia), then the energy taken by the sections' damping, the
#: absolute damping, the rings, the coupling and the pairs.
WORKS = ("W_gas", "W_ext", "W_load", "L_sections", "L_absolute", "L_rings", "L_coupling",
         "L_pairs")


@dataclass
class TorsionModel:
    """Right-hand side in time of the shaft line (T2), with its rings and coupling, and the work
    integrals. State: θ (N), ω (N), the rings' angles and speeds, the driven inertia's angle and
    speed (with a coupling), then :data:`WORKS`."""

    line: ShaftLine
    cylinders: Cylinders
    external: StationMoments | None = None
    driven_load: DrivenMoment | None = None
    engine: SceneEngine | None = None
    nfev: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        n, r = self.line.n, len(self.line.rings)
        self.n_rings = r
        self.i_ring = 2 * n
        self.i_driven = 2 * n + 2 * r
        self.i_engine = self.i_driven + (2 if self.line.coupling is not None else 0)
        self.i_works = self.i_engine
        if self.engine is not None:  # its states (governor, latched fuels, pressures) here
            self.engine.place(self.i_engine, n)
            self.i_works += self.engine.n_states
        self.size = self.i_works + len(WORKS)
        self.carrier = np.asarray(self.line.station_of_cylinder, dtype=np.intp)
        self.weights = self.mean_inertias()

    def mean_inertias(self, samples: int = 720) -> Array:
        """The inertia of every degree of freedom averaged over a revolution, as seen at the
        stations' speed: stations (their cylinders' J at every angle), rings, then the driven
        inertia J_d/i² (its speed there is i ω_d)."""
        angles = 2.0 * math.pi * np.arange(samples) / samples
        J = np.mean([self.station_inertia(np.full(self.line.n, a))[0] for a in angles], axis=0)
        rings = [ring.inertia for ring in self.line.rings]
        c = self.line.coupling
        driven = [c.driven_inertia / c.ratio ** 2] if c is not None else []
        return np.concatenate([J, rings, driven])

    # -- state ------------------------------------------------------------------------------
    def initial_state(self, theta: float, omega: float) -> Array:
        """Every station, ring and the gear's input at angle θ and speed ω (no twist), the
        works zero."""
        y = np.zeros(self.size)
        n, r = self.line.n, self.n_rings
        y[:n], y[n:2 * n] = theta, omega
        y[self.i_ring:self.i_ring + r], y[self.i_ring + r:self.i_driven] = theta, omega
        c = self.line.coupling
        if c is not None:
            y[self.i_driven], y[self.i_driven + 1] = theta / c.ratio, omega / c.ratio
        if self.engine is not None:
            y[self.i_engine:self.i_works] = self.engine.initial(theta, omega)
        return y

    def split(self, y: Array):
        """(θ, ω, ring angles, ring speeds, driven angle, driven speed) of state y."""
        n, r = self.line.n, self.n_rings
        th, w = y[:n], y[n:2 * n]
        rth, rw = y[self.i_ring:self.i_ring + r], y[self.i_ring + r:self.i_driven]
        if self.line.coupling is None:
            return th, w, rth, rw, 0.0, 0.0
        return th, w, rth, rw, y[self.i_driven], y[self.i_driven + 1]

    def station_inertia(self, theta: Array) -> tuple[Array, Array, Array]:
        """(J_k, J′_k, the mechanism's part of J_k) per station at its angle, (T1)."""
        Jc, dJc = self.cylinders.inertia(theta[self.carrier])
        Jm = np.zeros(self.line.n)
        dJ = np.zeros(self.line.n)
        np.add.at(Jm, self.carrier, Jc)
        np.add.at(dJ, self.carrier, dJc)
        return self.line.inertia + Jm, dJ, Jm

    def gas_moments(self, theta: Array, omega: Array, t: float, y: Array | None = None
                    ) -> Array:
        """M_gas,k: the moments of the cylinders each station carries (with an engine, from
        its states in ``y`` too)."""
        if self.engine is None:
            Mc = self.cylinders.moments(theta[self.carrier], omega[self.carrier], t)
        else:
            assert y is not None, "an engine's moments need the state"
            Mc = self.engine.moments(theta, omega, y)
        M = np.zeros(self.line.n)
        np.add.at(M, self.carrier, Mc)
        return M

    # -- the elastic and dissipative elements --------------------------------------------------
    def section_torques(self, theta: Array, omega: Array) -> Array:
        """The torque each section transmits from station i+1 to station i, k_i Δθ_i + c_i Δω_i
        with Δθ_i = θ_{i+1} − θ_i [N m]."""
        return self.line.stiffness * np.diff(theta) + self.line.damping * np.diff(omega)

    def element_torques(self, y: Array):
        """(T_k on each station, the torque on each ring, on the driven inertia, and the power
        each kind of element dissipates: sections, absolute damping, rings, coupling)."""
        line = self.line
        th, w, rth, rw, thd, wd = self.split(y)
        S = self.section_torques(th, w)
        T = np.zeros(line.n)
        T[:-1] += S
        T[1:] -= S
        on_stations, on_rings, on_driven, p_absolute = self.absolute_torques(w, rw, wd)
        T += on_stations
        T_ring = on_rings.copy()
        p_rings = 0.0
        for j, ring in enumerate(line.rings):
            rel = w[ring.station] - rw[j]
            tq = ring.stiffness * (th[ring.station] - rth[j]) + ring.damping * rel
            T[ring.station] -= tq
            T_ring[j] += tq
            p_rings += ring.damping * rel * rel
        T_driven, p_coupling = on_driven, 0.0
        c = line.coupling
        if c is not None:
            rel = w[c.station] - c.ratio * wd
            tq = c.stiffness * (th[c.station] - c.ratio * thd) + c.damping * rel
            T[c.station] -= tq
            T_driven += c.ratio * tq
            p_coupling = c.damping * rel * rel
        p_sections = float(np.sum(line.damping * np.diff(w) ** 2))
        return T, T_ring, T_driven, (p_sections, p_absolute, p_rings, p_coupling)

    def absolute_torques(self, w: Array, ring_speeds: Array, driven_speed: float):
        """The absolute damping d_k of the stations, on each station's speed less the line's
        mean speed ω̄ (every dof's speed at the stations' side weighted by its mean inertia
        m_j): the drags d_k(ω_k − ω̄) and, so that they add no net torque, their sum given back
        to every dof in proportion to m_j. Returns (on the stations, on the rings, on the driven
        inertia's own angle, the power taken Σ d_k (ω_k − ω̄)²)."""
        c = self.line.coupling
        ratio = c.ratio if c is not None else 1.0
        speeds = np.concatenate([w, ring_speeds, [ratio * driven_speed] if c else []])
        mean = float(self.weights @ speeds) / float(self.weights.sum())
        drag = np.asarray(self.line.absolute) * (w - mean)
        back = self.weights / self.weights.sum() * float(drag.sum())
        n, r = self.line.n, self.n_rings
        on_driven = ratio * float(back[n + r]) if c is not None else 0.0
        return (-drag + back[:n], back[n:n + r], on_driven, float(drag @ (w - mean)))

    def potential(self, y: Array) -> float:
        """Σ ½ k Δθ² of the sections, the rings' springs and the coupling [J]."""
        line = self.line
        th, _, rth, _, thd, _ = self.split(y)
        V = 0.5 * float(np.sum(line.stiffness * np.diff(th) ** 2))
        for j, ring in enumerate(line.rings):
            V += 0.5 * ring.stiffness * (th[ring.station] - rth[j]) ** 2
        c = line.coupling
        if c is not None:
            V += 0.5 * c.stiffness * (th[c.station] - c.ratio * thd) ** 2
        return V

    def kinetic(self, y: Array) -> float:
        """Σ ½ J_k(θ_k) ω_k² of the stations, rings and driven inertia [J]."""
        th, w, _, rw, _, wd = self.split(y)
        J = self.station_inertia(th)[0]
        K = 0.5 * float(np.sum(J * w * w))
        K += 0.5 * sum(ring.inertia * rw[j] ** 2 for j, ring in enumerate(self.line.rings))
        if self.line.coupling is not None:
            K += 0.5 * self.line.coupling.driven_inertia * wd * wd
        return K

    def balance(self, y: Array, y0: Array) -> float:
        """(T4): energy now less energy at y0, less the applied work, plus the losses [J]; zero
        in exact arithmetic."""
        W = dict(zip(WORKS, y[self.i_works:]))
        work_in = W["W_gas"] + W["W_ext"] + W["W_load"]
        losses = sum(W[k] for k in WORKS if k.startswith("L_"))
        return (self.kinetic(y) + self.potential(y) - self.kinetic(y0) - self.potential(y0)
                - work_in + losses)

    # -- the equations --------------------------------------------------------------------------
    def accelerations(self, t: float, y: Array):
        """(θ̈ per station, ring accelerations, driven acceleration, applied powers (gas, ext,
        load), dissipated powers (sections, absolute, rings, coupling, pairs))."""
        line = self.line
        th, w, _, rw, thd, wd = self.split(y)
        J, dJ, Jm = self.station_inertia(th)
        M_gas, M_ext = self.applied_moments(t, y)
        T, T_ring, T_driven, dissipated = self.element_torques(y)
        if line.eta is None:
            acc = (M_gas + M_ext + T - 0.5 * dJ * w * w) / J
            p_pairs = 0.0
        else:
            acc, p_pairs, _, _ = self.through_pairs(J - Jm, Jm, dJ, M_ext + T, M_gas, w)
        ring_acc = np.array([T_ring[j] / ring.inertia for j, ring in enumerate(line.rings)])
        M_load = 0.0
        driven_acc = 0.0
        if line.coupling is not None:
            M_load = float(self.driven_load(thd, wd, t)) if self.driven_load is not None else 0.0
            driven_acc = (T_driven + M_load) / line.coupling.driven_inertia
        applied = (float(M_gas @ w), float(M_ext @ w), M_load * wd)
        return acc, ring_acc, driven_acc, applied, (*dissipated, p_pairs)

    def through_pairs(self, J0: Array, Jm: Array, dJm: Array, M0: Array, Mm: Array,
                      w: Array) -> tuple[Array, float, Array, Array]:
        """θ̈ per station with a constant-η pair between each station's shaft (J0, the moments
        M0 of sections, elements and loads) and its throw's mechanism (Jm, J′m, the gas moment
        Mm), (T7): (η* J0 + Jm) θ̈ = η* M0 + Mm − ½ J′m ω², with η* = η_fwd where the shaft's
        moment into the pair S = M0 − J0 θ̈ has the sign of ω and 1/η_bwd where it has the
        other (the power-flow policy, one station at a time); the pairs' loss
        Σ (1 − η*) S ω, and per station S and η*."""
        assert self.line.eta is not None
        fwd, bwd = (np.asarray(e, dtype=float) for e in self.line.eta)
        sigma = np.where(w >= 0.0, 1.0, -1.0)
        R = Mm - 0.5 * dJm * w * w

        def solve(eta):
            a = (eta * M0 + R) / (eta * J0 + Jm)
            return a, M0 - J0 * a

        a_f, S_f = solve(fwd)
        a_b, S_b = solve(1.0 / bwd)
        backward = (S_f * sigma < 0.0) & (S_b * sigma <= 0.0)
        acc = np.where(backward, a_b, a_f)
        S = np.where(backward, S_b, S_f)
        eta = np.where(backward, 1.0 / bwd, fwd)
        return acc, float(np.sum((1.0 - eta) * S * w)), S, eta

    def applied_moments(self, t: float, y: Array) -> tuple[Array, Array]:
        """(M_gas, M_ext) on each station at state ``y``."""
        th, w = self.split(y)[:2]
        M_ext = (np.asarray(self.external(th, w, t), dtype=float) if self.external is not None
                 else np.zeros(self.line.n))
        return self.gas_moments(th, w, t, y), M_ext

    def pairs_at(self, t: float, y: Array) -> tuple[Array, Array]:
        """(S, η*) of each station's pair at state ``y`` (:meth:`through_pairs`)."""
        th, w = self.split(y)[:2]
        J, dJ, Jm = self.station_inertia(th)
        M_gas, M_ext = self.applied_moments(t, y)
        T = self.element_torques(y)[0]
        return self.through_pairs(J - Jm, Jm, dJ, M_ext + T, M_gas, w)[2:]

    def rhs(self, t: float, y: Array) -> Array:
        self.nfev += 1
        _, w, _, rw, _, wd = self.split(y)
        acc, ring_acc, driven_acc, applied, dissipated = self.accelerations(t, y)
        dy = np.empty(self.size)
        n, r = self.line.n, self.n_rings
        dy[:n], dy[n:2 * n] = w, acc
        dy[self.i_ring:self.i_ring + r], dy[self.i_ring + r:self.i_driven] = rw, ring_acc
        if self.line.coupling is not None:
            dy[self.i_driven], dy[self.i_driven + 1] = wd, driven_acc
        if self.engine is not None:
            dy[self.i_engine:self.i_works] = self.engine.rates(y[:n], w, y)
        dy[self.i_works:] = (*applied, *dissipated)
        return dy


def integrate(model: TorsionModel, y0: Array, t_end: float, method: str = "DOP853",
              rtol: float = 1e-10, atol: float = 1e-12, **options):
    """``solve_ivp`` over [0, t_end] from y0; the work integrals are left out of the error
    control (they do not feed back), as the rigid run leaves its own. With an engine whose
    states change where an angle passes a level (:meth:`SceneEngine.triggers`: a fuel
    latched, a closed part started), segment by segment between those terminal events; the
    result's ``sol`` (with ``dense_output``) then evaluates the segment each time lies in."""
    scale = np.ones(model.size)
    scale[model.i_works:] = np.inf  # (atol ∞: never limits the step)
    if model.engine is None or not model.engine.triggers(y0):
        sol = solve_ivp(model.rhs, (0.0, t_end), y0, method=method, rtol=rtol,
                        atol=atol * scale, **options)
        if sol.status == -1:
            raise RuntimeError(f"solve_ivp failed at t = {sol.t[-1]:.9g} s: {sol.message}")
        return sol
    return _integrate_segments(model, y0, t_end, method, rtol, atol * scale, **options)


@dataclass
class Segments:
    """A run of :func:`integrate` in segments: their ends ``t`` (from 0), solutions and dense
    outputs; ``sol(t)`` evaluates the segment each time lies in (at a segment's end the
    next one's start, after its event acted)."""

    t: Array
    pieces: list
    status: int = 0

    def sol(self, t):
        t = np.asarray(t, dtype=float)
        j = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.pieces) - 1)
        out = np.empty((self.pieces[0].sol(self.t[0]).size, t.size))
        for i in np.unique(j):
            out[:, j == i] = self.pieces[i].sol(t[j == i])
        return out


@dataclass(frozen=True)
class _Rising:
    """A terminal event of solve_ivp: the state's component ``index`` rising through ``level``."""

    index: int
    level: float
    terminal: bool = True
    direction: float = 1.0

    def __call__(self, t: float, y: Array) -> float:
        return y[self.index] - self.level


def _integrate_segments(model, y0, t_end, method, rtol, atol, **options) -> Segments:
    t, y = 0.0, np.array(y0, dtype=float)
    ends, pieces = [0.0], []
    while True:
        triggers = model.engine.triggers(y)
        events = [_Rising(index, level) for index, level, _ in triggers]
        sol = solve_ivp(model.rhs, (t, t_end), y, method=method, rtol=rtol, atol=atol,
                        events=events, **options)
        if sol.status == -1:
            raise RuntimeError(f"solve_ivp failed at t = {sol.t[-1]:.9g} s: {sol.message}")
        pieces.append(sol)
        if sol.status == 0:
            ends.append(t_end)
            return Segments(np.array(ends[:-1]), pieces)
        j = next(i for i, te in enumerate(sol.t_events) if te.size)
        t, y = float(sol.t_events[j][0]), np.array(sol.y_events[j][0])
        for index, level, act in triggers:  # every trigger on this level acts
            if abs(y[index] - level) <= 1e-9 * max(1.0, abs(level)):
                act(y)
        ends.append(t)


# -- the engine's side: a crank-slider's cylinders, and a pressure pulse ------------------------

class CrankSliderCylinders:
    """Each cylinder of a crank-slider (:class:`~transient.mechanisms.crank_slider.CrankSlider`)
    on its own: with a the local angle from the cylinder's TDC, the crankpin
    A = (r sin a, r cos a), the piston pin B = (e, y_B) on the cylinder's axis,
    y_B = r cos a + √(l² − q²), q = r sin a − e, the rod's angle sin β = q/l and its centre of
    mass G = B + f (A − B), f = l₁/l:

        J_c(a) = m_slide y_B′² + m_rot r² + m_rod |G′|² + I_rod β′²     (T1a)

    (′ = d/da; two-mass rod: its shares at pin and crankpin in m_slide and m_rot, Gots (20)),
    and J_c′ from the second derivatives. The gas moment is (p_c − p₀) A_p u_c with
    u_c = −y_B′ the piston's speed over ω (positive down the stroke). ``pressure``: the gauge
    pressure p − p₀ [Pa] of a cylinder at its local angle in its cycle, vectorised."""

    def __init__(self, mech, pressure: Callable[[Array], Array] | None = None) -> None:
        self.r, self.l, self.e = mech.crank_radius, mech.rod_length, mech.offset
        l1 = mech.rod_cg_from_pin
        two_mass = mech.rod_model == "two-mass"
        self.m_slide = mech.piston_mass + (mech.rod_mass * (self.l - l1) / self.l if two_mass
                                           else 0.0)
        self.m_rot = mech.crank_mass_per_cylinder + (mech.rod_mass * l1 / self.l if two_mass
                                                     else 0.0)
        self.m_rod = 0.0 if two_mass else mech.rod_mass
        self.I_rod = 0.0 if two_mass else mech.rod_inertia_cg
        self.f = l1 / self.l
        self.firing = np.asarray(mech.firing_angles, dtype=float)
        self.cycle = mech.cycle
        self.area = mech.piston_area
        self.pressure = pressure

    def local(self, angles: Array) -> Array:
        """Each cylinder's angle from its firing TDC, in [0, cycle)."""
        return np.mod(angles - self.firing, self.cycle)

    def kinematics(self, angles: Array):
        """(y_B′, y_B″, β′, β″, G′, G″) at the cylinders' local angles."""
        a = angles - self.firing
        r, l = self.r, self.l
        s, c = np.sin(a), np.cos(a)
        q, dq, ddq = r * s - self.e, r * c, -r * s
        root = np.sqrt(l * l - q * q)
        droot = -q * dq / root
        dy = -r * s - q * dq / root
        ddy = -r * c - (dq * dq + q * ddq) / root - (q * dq) ** 2 / root ** 3
        db = dq / root
        ddb = (ddq * root - dq * droot) / root ** 2
        f = self.f
        G1 = np.array([f * r * c, (1 - f) * dy - f * r * s])
        G2 = np.array([-f * r * s, (1 - f) * ddy - f * r * c])
        return dy, ddy, db, ddb, G1, G2

    def inertia(self, angles: Array) -> tuple[Array, Array]:
        dy, ddy, db, ddb, G1, G2 = self.kinematics(angles)
        J = (self.m_slide * dy * dy + self.m_rot * self.r ** 2 + self.m_rod * np.sum(G1 * G1, 0)
             + self.I_rod * db * db)
        dJ = 2.0 * (self.m_slide * dy * ddy + self.m_rod * np.sum(G1 * G2, 0)
                    + self.I_rod * db * ddb)
        return J, dJ

    def piston_speeds(self, angles: Array) -> Array:
        """u_c = ds_c/dθ: the pistons' speeds over ω [m/rad]."""
        return -self.kinematics(angles)[0]

    def moments(self, angles: Array, speeds: Array, t: float) -> Array:
        if self.pressure is None:
            return np.zeros(angles.shape)
        return self.pressure(self.local(angles)) * self.area * self.piston_speeds(angles)


@dataclass(frozen=True)
class PressurePulse:
    """A smooth gauge pressure for tests: a Gaussian pulse of height ``peak`` [Pa] centred
    ``at`` [rad] after firing TDC with standard width ``width`` [rad], periodic in the cycle
    (its tails at half a cycle are below rounding)."""

    peak: float
    at: float
    width: float
    cycle: float = 4.0 * math.pi

    def __call__(self, local: Array) -> Array:
        d = np.mod(local + 0.5 * self.cycle, self.cycle) - 0.5 * self.cycle - self.at
        return self.peak * np.exp(-0.5 * (d / self.width) ** 2)


# -- a scene's engine: its gas with the cylinders' variation, governor, latching, wall heat ----

class SceneEngine:
    """A crank-slider scene's cylinders as the elastic run drives them, written apart from the
    compiled kernels: each cylinder's pressure at its own station's angle θ, on its table read
    at its local angle x, p = p_mot(x) + f_c (p_full(x − δ_c) − p_mot(x − δ_c)) acting as
    p0 + β_c (p − p0), with f_c the governor's command (or the fuel it latched) times its fuel
    factor in the cycle its own angle is in, 0 in a misfiring one (the scene's
    ``[[gas.cylinders]]``, :class:`~transient.scene.records.Cylinder`, the draws from
    :func:`~transient.reference.twins.misfire_draw`); the governor (droop, PI(D), flyweight:
    the rigid reference's :class:`~transient.reference.twins.GovernorNumpy`) reading the
    reference station's speed;
    each cylinder latching the command where its own station passes its injection angle
    (``gas.injection``); with ``[gas.woschni]`` each cylinder's closed part a pressure state
    (the rigid reference's :class:`~transient.reference.twins.CylindersNumpy`) at its own
    station's angle and speed, set to p_a where its own angle closes the intake.

    States (the block :class:`TorsionModel` gives it, :meth:`place`): the governor's, the
    latched fuels, the pressures. A flyweight sleeve is taken free (no stops)."""

    def __init__(self, scene, cylinders: CrankSliderCylinders, carrier, ref: int) -> None:
        from ..scene.queries import cycle_begin, gas_phases, gas_tables
        from .twins import misfire_draw

        self.draw = misfire_draw
        mech, gas = scene.mechanism, scene.gas
        if gas.model in ("none", "trapezoid") or gas.force:
            raise ValueError("SceneEngine: a gas model of pressures only")
        self.scene, self.cyl, self.carrier, self.ref = scene, cylinders, carrier, ref
        full, self.motored = gas_tables(scene)
        assert full is not None  # (a pressure model has its table)
        self.full = full
        self.p0, self.period = gas.p0, mech.cycle
        self.phase = gas_phases(scene)
        n = mech.n_cylinders
        self.factor, self.beta, self.delta = np.ones(n), np.ones(n), np.zeros(n)
        self.every, self.rate = np.zeros(n, dtype=int), np.zeros(n)
        self.seed, self.cycles = np.zeros(n, dtype=int), [()] * n
        for c in gas.cylinders:
            k = c.cylinder - 1
            self.factor[k], self.beta[k], self.delta[k] = c.fuel, c.pressure, c.combustion_offset
            self.every[k], self.rate[k] = c.misfire_every, c.misfire_rate
            self.seed[k] = c.misfire_seed
            self.cycles[k] = tuple(c.misfire_cycles)
        # cycle 1 of a cylinder: the one in progress at the initial angle
        first = np.mod(self.phase + cycle_begin(mech), self.period)
        phi0 = scene.initial.phi
        self.start = phi0 - np.mod(phi0 - first, self.period)
        self.n = n
        self.n_gov = {"pi": 2 + (scene.governor.gain_d > 0.0), "flyweight": 2}.get(
            scene.governor.model, 0)
        self.latch = gas.injection
        self.woschni = gas.woschni is not None
        self.n_states = self.n_gov + n * (self.latch is not None) + n * self.woschni

    def place(self, i0: int, stations: int) -> None:
        """Its states start at index ``i0`` of the model's state, whose speeds of the
        ``stations`` follow their angles."""
        from .twins import CylindersNumpy, GovernorNumpy

        self.i_speed = stations
        self.governor = GovernorNumpy(self.scene, i0)
        self.i_latch = i0 + self.n_gov
        self.i_p = self.i_latch + (self.n if self.latch is not None else 0)
        self.closed = (CylindersNumpy(self.scene, self.phase, self.period, self.i_p, self.delta)
                       if self.woschni else None)

    # -- the fuel -------------------------------------------------------------------------
    def droop(self, w: float) -> float:
        g = self.scene.governor
        if g.model != "droop":
            return 1.0
        return float(np.clip((g.speed_zero - w) / (g.speed_zero - g.speed_full), 0.0, 1.0))

    def command(self, w_ref: float, y: Array) -> float:
        """The governor's fuel command at the reference's speed."""
        return self.governor.command(w_ref, y, self.droop)

    def cycle_factor(self, k: int, theta: float) -> float:
        """Cylinder k's fuel factor in the cycle its angle θ is in (0: misfiring)."""
        f = self.factor[k]
        n = math.floor((theta - self.start[k]) / self.period) + 1
        if f == 0.0 or n < 1:
            return float(f)
        if ((self.every[k] and n % self.every[k] == 0) or n in self.cycles[k]
                or (self.rate[k] > 0.0 and self.draw(int(self.seed[k]), k, n) < self.rate[k])):
            return 0.0
        return float(f)

    def fuels(self, angles: Array, w_ref: float, y: Array) -> Array:
        """Each cylinder's fuel at its angle."""
        f = (y[self.i_latch:self.i_latch + self.n] if self.latch is not None
             else np.full(self.n, self.command(w_ref, y)))
        return f * np.array([self.cycle_factor(k, a) for k, a in enumerate(angles)])

    # -- pressures and moments ------------------------------------------------------------------
    def table_pressures(self, local: Array, f: Array) -> Array:
        """p_mot(x) + f (p_full(x − δ) − p_mot(x − δ)) at the local angles x (the tables read
        δ later only without wall heat, whose combustion is shifted in its rates)."""
        mot = self.motored if self.motored is not None else (lambda x: np.full(x.shape, self.p0))
        x = local - (self.delta if not self.woschni else 0.0)
        return mot(local) + f * (self.full(x) - mot(x))

    def pressures(self, theta: Array, omega: Array, y: Array) -> Array:
        """Each cylinder's pressure as it acts on its piston, at its station's angle."""
        angles = theta[self.carrier]
        local = np.mod(angles - self.phase, self.period)
        p = self.table_pressures(local, self.fuels(angles, omega[self.ref], y))
        if self.closed is not None:
            p = self.closed.pressures(p, local, y)
        return self.p0 + self.beta * (p - self.p0)

    def moments(self, theta: Array, omega: Array, y: Array) -> Array:
        """Each cylinder's gas moment (p − p0) A_p u_c(θ) [N m]."""
        angles = theta[self.carrier]
        return ((self.pressures(theta, omega, y) - self.p0) * self.cyl.area
                * self.cyl.piston_speeds(angles))

    # -- the states --------------------------------------------------------------------------
    def initial(self, theta: float, omega: float) -> Array:
        """The governor at rest at ω (PI(D): its integrator and rack at ``fuel_initial``, its
        filter at ω; the flyweight's sleeve in its balance, free), each cylinder latched at the
        command, each pressure the table's at it in its closed part (else p_a)."""
        g = self.scene.governor
        if g.model == "pi":
            states = [g.fuel_initial, g.fuel_initial] + ([omega] if g.gain_d > 0.0 else [])
            f0 = g.fuel_initial
        elif g.model == "flyweight":
            c = self.governor.cent * omega ** 2
            z = (c * g.radius - g.spring_preload) / (g.spring_rate - c * self.governor.arm)
            states = [z, 0.0]
            f0 = g.fuel_max + (g.fuel_min - g.fuel_max) * z / g.travel
        else:
            states, f0 = [], self.droop(omega)
        out = list(states) + ([f0] * self.n if self.latch is not None else [])
        if self.closed is not None:
            local = np.mod(theta - self.phase, self.period)
            f = f0 * np.array([self.cycle_factor(k, theta) for k in range(self.n)])
            p = self.table_pressures(local, f)
            out += list(np.where(np.isfinite(self.closed.past_intake(local)), p,
                                 self.closed.p_a))
        return np.array(out, dtype=float)

    def rates(self, theta: Array, omega: Array, y: Array) -> Array:
        """The governor's rates at the reference's speed, zero for the latched fuels, each
        pressure's at its station's angle and speed."""
        w_ref = omega[self.ref]
        out = list(self.governor.rates(w_ref, y)) + [0.0] * (self.n if self.latch is not None
                                                               else 0)
        if self.closed is not None:
            angles = theta[self.carrier]
            local = np.mod(angles - self.phase, self.period)
            out += self.closed.rates(local, 0.0, self.cyl.piston_speeds(angles),
                                     omega[self.carrier], self.fuels(angles, w_ref, y), y)
        return np.array(out, dtype=float)

    def triggers(self, y: Array) -> list:
        """The angle levels next passed where a state is set: (the index of the angle in the
        state, the level, the action on the state)."""
        out = []

        def ahead(angle: float, level: float) -> float:
            return level + self.period * (math.floor((angle - level) / self.period + 1e-9) + 1)

        if self.latch is not None:
            for k in range(self.n):
                def latch(yv, k=k):
                    w_ref = yv[self.i_speed + self.ref]
                    yv[self.i_latch + k] = self.command(w_ref, yv)
                s = int(self.carrier[k])
                out.append((s, ahead(y[s], self.phase[k] + self.latch), latch))
        if self.closed is not None:
            for k in range(self.n):
                def close(yv, k=k):
                    yv[self.i_p + k] = self.closed.p_a
                s = int(self.carrier[k])
                out.append((s, ahead(y[s], self.phase[k] + self.closed.ivc), close))
        return out


def _throw_efficiencies(scene) -> tuple[Array, Array] | None:
    """Per station the (forward, backward) efficiency of a scene's one constant-η pair
    ``["shaft", "crank"]`` (power-flow policy) in each station that carries cylinders, 1 on
    the others; None without pairs."""
    pairs, friction = scene.friction.pairs, scene.friction
    if not pairs:
        return None
    if (len(pairs) != 1 or tuple(pairs[0].between) != ("shaft", "crank")
            or pairs[0].model != "constant-eta" or friction.policy != "power-flow"):
        raise ValueError("from_scene: one constant-η pair [\"shaft\", \"crank\"] under the "
                         "power-flow policy only")
    carries = np.array([bool(st.cylinders) for st in scene.shaft.stations])
    return (np.where(carries, pairs[0].eta_forward, 1.0),
            np.where(carries, pairs[0].eta_backward, 1.0))


# -- the rigid limit ---------------------------------------------------------------------------

def rigid_run(J_rest: float, terms, gas: Callable[[float], float],
              moment: Callable[[float, float], float], phi_end: float, omega0: float,
              rtol: float = 1e-12, atol: float = 1e-12, phi0: float = 0.0):
    """The rigid reduced equation (18) in its crank-angle form, dK/dφ = M, dt/dφ = 1/ω,
    K = ½ J(φ) ω², with J(φ) = J_rest + the mechanism's twin J (``terms``: φ ↦ (J, J′, u, u′),
    :class:`~transient.mechanisms.twins.CrankSliderNumpy`), ``gas`` φ ↦ M_gas and ``moment``
    (φ, ω) ↦ the other moments reduced to φ. Returns the solution in φ, y = (t, K), and
    ω(φ) as a function of it."""
    def total(phi):
        return J_rest + terms(phi)[0]

    def rhs(phi, y):
        w = math.sqrt(2.0 * y[1] / total(phi))
        return [1.0 / w, gas(phi) + moment(phi, w)]

    sol = solve_ivp(rhs, (phi0, phi_end), [0.0, 0.5 * total(phi0) * omega0 ** 2],
                    method="DOP853", rtol=rtol, atol=atol, dense_output=True)
    if sol.status != 0:
        raise RuntimeError(f"rigid run failed at φ = {sol.t[-1]:.9g}: {sol.message}")

    def omega(phi):
        phi = np.asarray(phi, dtype=float)
        K = sol.sol(phi)[1]
        return np.sqrt(2.0 * K / np.vectorize(total)(phi))
    return sol, omega


# -- a scene's line --------------------------------------------------------------------------

def from_scene(scene) -> tuple[TorsionModel, int]:
    """The reference model of a crank-slider scene's ``[shaft]`` line and the index of its
    reference station: the stations', sections', dampers' and coupling's data from the scene's
    records, the cylinders (:class:`CrankSliderCylinders`) driven by its gas as the elastic run
    drives them (:class:`SceneEngine`: the cylinders' variation and misfires, the governor,
    fuel latching, the closed part with wall heat), and its load's torque, linear and fan terms
    and table (:func:`transient.assemble.load_table_curve`, at its dof's speed, angle or the
    time) acting where ``load_at`` says. What it shares with the compiled path: the scene's
    records, the pressure tables, the load's curve and the sections' viscous c of a loss
    factor or damping ratio (:class:`transient.shaft.line.ShaftLine`, which needs the line's
    ω₁); a constant-η pair between the shaft and the crank, under the power-flow policy, in each
    station that carries cylinders (:meth:`TorsionModel.through_pairs`). A starter,
    generator, schedule, a force model of the gas, other pairs or a mechanism other than the
    crank-slider is beyond it (ValueError)."""
    from ..assemble import load_table_curve
    from ..shaft import ShaftLine as CompiledLine

    shaft, mech, load = scene.shaft, scene.mechanism, scene.load
    if (mech.name != "crank-slider" or scene.starter.torque > 0.0
            or load.generator_power or load.schedule_scale):
        raise ValueError("from_scene: a crank-slider scene with a fixed load only")
    compiled = CompiledLine(scene)
    names = [st.name for st in shaft.stations]
    n = len(names)
    carrier = np.zeros(mech.n_cylinders, dtype=np.intp)
    for i, st in enumerate(shaft.stations):
        carrier[np.asarray(st.cylinders, dtype=np.intp) - 1] = i
    c_sections = compiled.element_rows()[:n - 1, 3]
    rings = tuple(Ring(names.index(d.station), d.inertia, d.damping, d.stiffness)
                  for d, _, _ in compiled.rings())
    coupling = None
    if shaft.coupling is not None:
        cp = shaft.coupling
        coupling = Coupling(n - 1, cp.stiffness, cp.damping, 1.0 / cp.gear_ratio,
                            cp.driven_inertia)
    line = ShaftLine(inertia=np.array([st.inertia for st in shaft.stations]),
                     stiffness=np.array([s.stiffness for s in shaft.sections]),
                     damping=c_sections, absolute=np.array([st.damping for st in shaft.stations]),
                     station_of_cylinder=carrier, rings=rings, coupling=coupling,
                     eta=_throw_efficiencies(scene))
    ref = names.index(shaft.reference)
    cylinders = CrankSliderCylinders(mech)
    engine = SceneEngine(scene, cylinders, carrier, ref) if scene.gas.model != "none" else None

    curve = load_table_curve(scene)

    def torque(th, w, t):
        resist = load.torque + load.linear * w + load.fan * w * np.abs(w)
        if curve is not None:  # T(x) at its dof's speed, angle or the time
            resist += curve.evaluate({"speed": w, "angle": th, "time": t}[curve.abscissa])
        return -resist

    external = driven = None
    if shaft.load_at == "driven":
        ratio = coupling.ratio if coupling is not None else 1.0

        def driven(th, w, t):  # the law at the speed seen at the shaft, its power kept
            return ratio * torque(ratio * th, ratio * w, t)
    else:
        at = names.index(shaft.load_at)

        def external(th, w, t):
            M = np.zeros(n)
            M[at] = torque(th[at], w[at], t)
            return M
    model = TorsionModel(line, cylinders, external, driven, engine)
    return model, ref
