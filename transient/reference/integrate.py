"""The reference path's run: the model in plain numpy
(:class:`~transient.reference.integrate.ReferenceModel`, with the parts of
:mod:`transient.reference.twins`), integrated by ``scipy.integrate.solve_ivp`` in time (the state is
(φ, ω) and the work integrals, (18) written out again; the mechanism's J(φ), dJ/dφ and transfer
functions come from its plain-Python twin, ``reference_terms``, :mod:`transient.mechanisms.twins`).
Breakpoints, the starter's cut-out and the switches' corners are terminal events of solve_ivp, so
every segment between them is smooth.

What it shares with the compiled path, and so does not check: the scene's assembly
(:func:`transient.assemble.build_model`: the gas tables, the breakpoints, the load schedule, the
governor's parameters and initial state, the per-cylinder variation), the search of the next
breakpoint (``integrator.breakpoints.next_breakpoint``), the load schedule's and the generator's
branches (``forcing.load_segment``, ``generator_branch``), the cycle's fuel factor
(``variation.cycle_fuel``) and the constants that name the Model's fields; these are compiled
kernels called from Python. Everything else, the integrator, its events and the model's
equations, is its own.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from ..assemble import build_model, initial_governor, load_table_curve
from ..core.integrator.breakpoints import next_breakpoint
from ..core.model import governor as gv
from ..core.model.forcing import generator_branch, load_segment
from ..core.model.layout import T
from ..core.model.variation import PRESSURE, SHIFT, cycle_fuel
from ..errors import SimulationError
from ..mechanisms import PluginTable, needed
from ..scene.queries import gas_tables
from .twins import (
    ArticulatedReactionNumpy,
    ChainNumpy,
    CylindersNumpy,
    GovernorNumpy,
    ReactionNumpy,
    SwashReactionNumpy,
)

#: The numpy twin of each mechanism's reaction solver, by its name in
#: :data:`transient.mechanisms.MECHANISMS` (capability ``"reaction-twin"``).
#: A mechanism's own module ``transient.reference.reaction_<name>`` may hold it as
#: ``ReactionTwin``.
REACTION_TWINS = PluginTable({"crank-slider": ReactionNumpy,
                              "articulated": ArticulatedReactionNumpy,
                              "swash-plate": SwashReactionNumpy},
                             "transient.reference.reaction_{}", "ReactionTwin")


class ReferenceModel:
    """Right-hand side of (18) (or of the serial chain) in time, dy/dt = (ω, ε, powers), numpy.

    The state is (φ, ω, W_gas, W_load, W_starter, W_loss per pair, the governor's states); the
    fuel each cylinder latched (``latched``) changes only at terminal events."""

    def __init__(self, scene) -> None:
        self.scene = scene
        self.model, self.bp, self.table = build_model(scene)
        # The motored curve (None: gas_offset, a force pulse's zero, or a table's that runs at
        # full fuel only) between which and the table the fuel interpolates, as PressureTable
        # objects rather than the model's arrays.
        self.motored = gas_tables(scene)[1]
        self.mechanism_terms = scene.mechanism.reference_terms()
        self.starter_on = scene.starter.torque > 0 and scene.initial.omega < scene.starter.cutout_speed
        self.pieces: NDArray[np.int64] | None = None
        w0 = scene.initial.omega
        self.branch = self.droop_branch(w0)
        self.chain = None  # the non-ideal pairs: a serial chain, or the joints' reactions
        if scene.friction.pairs:
            reaction = any(p.model == "reaction" for p in scene.friction.pairs)
            self.chain = (ChainNumpy(scene) if not reaction else
                          needed(scene.mechanism, "reaction-twin", REACTION_TWINS)(scene,
                                                                                   self.model))
        self.sigma = 1.0 if w0 >= 0 else -1.0
        m = self.model
        # the load schedule's segment and the generator's branch, switched at terminal events
        x0 = 0.0 if m.load_comp == T else scene.initial.phi
        self.seg = int(load_segment(m, x0, True))
        self.gen_low = bool(generator_branch(m, w0, True))
        self.t = 0.0  # time of the state being evaluated (the schedule may be in time)
        self.load_curve = load_table_curve(scene)  # the tabulated load, in numpy
        self.governor = GovernorNumpy(scene, 5 + len(scene.friction.pairs))
        self.n_gov = gv.n_states(m.gov_dyn)
        # fuel per cylinder, with latching (set by run_reference)
        self.latched: NDArray[np.float64] | None = None
        # each cylinder's fuel factor in its cycle (set by select)
        self.factors: float | NDArray[np.float64] = 1.0
        self.shift = None  # combustion offsets the tables are read with (set by select)
        self.cylinders = (CylindersNumpy(scene, m.gas_phase, m.period, self.governor.g + self.n_gov,
                                         m.var_par[:, SHIFT])
                          if m.woschni else None)

    def load_scale(self, phi: float) -> float:
        """The schedule's scale s on the current segment (``model.load_scale``, in numpy)."""
        m = self.model
        n, j = m.load_x.size, self.seg
        if n == 0:
            return 1.0
        if j <= 0 or j >= n:
            return float(m.load_s[0 if j <= 0 else n - 1])
        x = self.t if m.load_comp == T else phi
        x0, s0 = m.load_x[j - 1], m.load_s[j - 1]
        return float(s0 + (m.load_s[j] - s0) * (x - x0) / (m.load_x[j] - x0))

    def select(self, a: float, b: float) -> None:
        """Table pieces for the segment of shaft angle (a, b) between two breakpoints."""
        mid = (0.5 * (a + b) if math.isfinite(a) and math.isfinite(b)
               else (a if math.isfinite(a) else b))
        self.mid = mid  # (the joints' directions of reaction friction are taken here too)
        if self.table is None:
            return
        local = np.mod(mid - self.model.gas_phase, self.model.period)
        self.pieces = self.table.piece_of(local)
        if self.motored is not None:
            self.motored_pieces = self.motored.piece_of(local)
        m = self.model
        # each cylinder's fuel factor in the cycle of the segment (its cycle begins on a breakpoint)
        self.factors = (np.array([cycle_fuel(m, k, mid) for k in range(m.ncyl)])
                        if m.var_on else 1.0)
        # with combustion offsets the tables are also read δ_k earlier (not the Woschni closed
        # part's: its combustion is shifted in CylindersNumpy.rates)
        self.shift = m.var_par[:, SHIFT] if m.var_shifted and not m.woschni else None
        if self.shift is not None:
            local_shift = np.mod(mid - m.gas_phase - self.shift, m.period)
            self.pieces_shift = self.table.piece_of(local_shift)
            if self.motored is not None:
                self.motored_pieces_shift = self.motored.piece_of(local_shift)

    def moments(self, phi: float, w: float, y):
        m = self.model
        J, dJ, u, _ = self.mechanism_terms(phi)
        J += m.J0
        M_gas = 0.0
        p = np.zeros(m.ncyl)
        if self.table is not None:
            local = np.mod(self.mid - m.gas_phase, m.period) + (phi - self.mid)
            f = (self.latched if self.latched is not None else self.command(w, y)) * self.factors
            p_full = self.table.evaluate(local, self.pieces)[0]
            # p = p_mot + f·(p_full − p_mot); gas_offset without a motored table
            p_mot = (self.motored.evaluate(local, self.motored_pieces)[0]
                     if self.motored is not None else m.gas_offset)
            if self.shift is None:
                p = p_mot + f * (p_full - p_mot)
            else:  # p_mot(x) + f·(p_full(x − δ) − p_mot(x − δ))
                x = np.mod(self.mid - m.gas_phase - self.shift, m.period) + (phi - self.mid)
                p_full = self.table.evaluate(x, self.pieces_shift)[0]
                p_mot_shift = (self.motored.evaluate(x, self.motored_pieces_shift)[0]
                               if self.motored is not None else m.gas_offset)
                p = p_mot + f * (p_full - p_mot_shift)
            if self.cylinders is not None:
                p = self.cylinders.pressures(p, np.mod(self.mid - m.gas_phase, m.period), y)
            if m.var_on:  # the pressure factor acts on p − p0 (transient.scene.Cylinder)
                p = m.gas_offset + m.var_par[:, PRESSURE] * (p - m.gas_offset)
            M_gas = float(np.sum(m.gas_scale * (p - m.gas_offset) * u))
        resist = m.load_const + m.load_linear * w + m.load_fan * w * abs(w)
        if m.gen_power != 0.0:  # an electrical load of power s·P, held below ω_min
            resist += m.gen_power / (m.gen_min if self.gen_low else w)
        if self.load_curve is not None:  # T(x) at the speed, the angle or the time
            x = {"speed": w, "angle": phi, "time": self.t}[self.load_curve.abscissa]
            resist += float(self.load_curve.evaluate(x))
        M_load = -self.load_scale(phi) * resist
        M_starter = m.starter_torque * (1 - w / m.starter_noload) if self.starter_on else 0.0
        return J, dJ, M_gas, M_load, M_starter, p

    def droop_branch(self, w: float) -> int:
        """Branch of the droop characteristic at speed w (0 full fuel, 1 the line, 2 none)."""
        g = self.scene.governor
        return 0 if w < g.speed_full else (2 if w >= g.speed_zero else 1)

    def command(self, w: float, y) -> float:
        """The governor's fuel command at state y."""
        return self.governor.command(w, y, self.fuel)

    def fuel(self, w: float) -> float:
        """Static droop characteristic (Antonyuk §4) on the segment's branch (0 full fuel, 1 the
        droop line, 2 none), extrapolated so that solve_ivp sees a smooth function; the corners
        are terminal events. 1 without a governor."""
        g = self.scene.governor
        if g.model == "none" or self.branch == 0:
            return 1.0
        return 0.0 if self.branch == 2 else (g.speed_zero - w) / (g.speed_zero - g.speed_full)

    def evaluate(self, phi, w, y):
        """(moments, φ̈, S_k, η*_k, L_k) at state y (φ, ω and the governor's states), L_k the
        pairs' loss moments."""
        J, dJ, Mg, Ml, Ms, pc = self.moments(phi, w, y)
        if self.chain is None:
            return (J, dJ, Mg, Ml, Ms, pc), (Mg + Ml + Ms - 0.5 * dJ * w * w) / J, (), (), ()
        # σ is held over a segment and changed only at rest, as the compiled path holds it: taken
        # from sign ω, the friction would flip inside a step where the shaft comes to rest
        # against pairs that lock, and solve_ivp's steps would shrink towards ω = 0 for ever
        # instead of crossing it to the rest event.
        a, S, eta, L = self.chain.solve(self.friction_inputs(phi, J, dJ, Mg, Ml + Ms, pc), w,
                                        self.sigma)
        return (J, dJ, Mg, Ml, Ms, pc), a, S, eta, L

    def friction_inputs(self, phi, J, dJ, M_gas, M_shaft, p):
        """The pairs' solve's inputs at a state, its pressures ``p`` giving the pistons' forces."""
        m = self.model
        forces = m.gas_scale * (p - m.gas_offset) if self.table is not None else np.zeros(m.ncyl)
        return self.chain.inputs(phi, J, dJ, M_gas, M_shaft, forces, self.mid)

    def rhs(self, t, y):
        self.t = t
        phi, w = y[:2]
        (J, dJ, Mg, Ml, Ms, _), a, S, eta, L = self.evaluate(phi, w, y)
        return [w, a, Mg * w, Ml * w, Ms * w, *(np.asarray(L) * w),
                *self.governor.rates(w, y), *self.cylinder_rates(phi, w, y)]

    def cylinder_rates(self, phi, w, y):
        """dp_k/dt of the cylinder pressure states (wall heat transfer), else nothing."""
        if self.cylinders is None:
            return []
        m = self.model
        u = self.mechanism_terms(phi)[2]
        fuel = (self.latched if self.latched is not None
                else np.full(m.ncyl, self.command(w, y))) * self.factors
        return self.cylinders.rates(np.mod(self.mid - m.gas_phase, m.period), phi - self.mid, u,
                                    w, fuel, y)

    def rows(self, t, y):
        out = []
        for ti, yi in zip(t, y.T):
            self.t = ti
            p, w = yi[:2]
            (J, dJ, Mg, Ml, Ms, pc), a, S, eta, L = self.evaluate(p, w, yi)
            pairs = [v for k in range(len(S)) for v in (S[k], eta[k], L[k] * w, yi[5 + k])]
            latched = [] if self.latched is None else list(self.latched)
            g = self.governor.g
            split = (list(self.chain.cylinder_losses.ravel() * w)
                     if isinstance(self.chain, ReactionNumpy) else [])  # (and its subclass)
            out.append([ti, p, w, a, J, dJ, Mg, Ml, Ms, self.command(w, yi), *yi[2:5], *pc, *pairs,
                        *yi[g:g + self.n_gov], *latched, *split])
        return np.asarray(out)


@dataclass(frozen=True)
class _Event:
    """An event function of solve_ivp, g(t, y), with the attributes solve_ivp reads: whether
    reaching g = 0 ends the integration, and the direction of the crossing (0 either way)."""

    g: Callable[[float, NDArray[np.float64]], float]
    terminal: bool
    direction: float

    def __call__(self, t: float, y: NDArray[np.float64]) -> float:
        return self.g(t, y)


def _speed_crossing(ref, t, y, level) -> _Event:
    """Terminal event ω = level in the direction ω must go to reach it; starting on the level
    (just after stopping there), the direction away from where the speed is heading now, so
    that solve_ivp does not stop again at once (and :func:`_leaving_start`)."""
    gap = y[1] - level
    if abs(gap) <= 1e-12 * max(1.0, abs(level)):
        direction = -np.sign(ref.rhs(t, y)[1]) or 1.0
    else:
        direction = -np.sign(gap)

    def g(t, yy):
        return yy[1] - level
    return _Event(g, True, direction)


def _leaving_start(g: _Event, t_start: float) -> _Event:
    """The terminal event ``g`` of a segment starting at ``t_start``, except that where the
    state starts exactly on its level, g there takes the sign of the side its direction leaves
    from: the event then fires only when the state comes back across the level later.

    With g = 0 at the start, a step that ends across the level (the speed turning back within
    it) had its root put at the start by solve_ivp's root finder, and the run stopped there again
    and again without advancing (found on the governed diesel by RK45 at rtol 1e-5: a segment
    starting on the droop corner)."""
    def h(t, yy):
        v = g(t, yy)
        if v == 0.0 and t == t_start:
            return -g.direction * 1e-300
        return v
    return _Event(h, g.terminal, g.direction)


def _level_crossing(in_time: bool, level: float, direction: int) -> _Event:
    """Terminal event: t (``in_time``) or φ reaching ``level`` in ``direction``."""
    def g(t, yy):
        return (t if in_time else yy[0]) - level
    return _Event(g, True, direction)


def _segment(ref, phi, omega):
    """The breakpoints enclosing φ; on a breakpoint, the segment the motion enters."""
    period = ref.model.period
    down = next_breakpoint(ref.bp, period, phi, False)
    up = next_breakpoint(ref.bp, period, phi, True)
    on = next_breakpoint(ref.bp, period, down, True)  # the breakpoint φ may sit on
    if math.isfinite(on) and abs(on - phi) <= 1e-13 * max(1.0, abs(phi)):
        return (on, up) if omega >= 0 else (down, on)
    return down, up


def _sleeve_events(gov: GovernorNumpy, y) -> list[tuple[str, _Event]]:
    """Terminal events of the flyweight governor: a moving sleeve reaching a stop; on a stop, the
    net force turning away from it (the balance of centrifugal force and spring, ω free)."""
    if gov.gov.model != "flyweight":
        return []
    g, travel = gov.g, gov.gov.travel
    if gov.sleeve == 0:
        def low(t, yy):
            return yy[g]

        def high(t, yy):
            return yy[g] - travel
        return [("sleeve_stop", _Event(low, True, -1)), ("sleeve_stop", _Event(high, True, 1))]
    z = 0.0 if gov.sleeve == 1 else travel

    def away(t, yy):
        return gov.force(yy[1], z, 0.0)
    return [("sleeve_free", _Event(away, True, 1 if gov.sleeve == 1 else -1))]


def _with_dense_tail(sol, ts, phi_from):
    """The step points ``ts`` (states from ``sol``) plus eight dense-output samples inside every
    step that ends beyond the angle ``phi_from``."""
    steps = sol.t
    inside = [np.linspace(a, b, 10)[1:-1] for a, b in zip(steps[:-1], steps[1:])
              if sol.sol(b)[0] >= phi_from]
    t_all = np.unique(np.concatenate([ts, *inside])) if inside else ts
    return t_all, sol.sol(t_all) if inside else sol.y[:, -ts.size:]


def run_reference(scene, on_block=None, progress=None, state_only: bool = False,
                  dense_tail: float = 0.0):
    """Integrate a dynamic scene with solve_ivp (method from ``scene.solver.method``).

    ``state_only``: keep only t, φ, ω at the steps (what a hand-written solve_ivp script keeps;
    the benchmark times that). ``dense_tail`` > 0: over that last angle [rad] before the end, add
    eight samples per step from solve_ivp's dense output (for error measures between steps).
    """
    from ..results import RunData
    from ..scene.outputs import output_columns

    ref = ReferenceModel(scene)
    method = scene.solver.method.removeprefix("scipy-")
    sv, run = scene.solver, scene.run
    t_end = run.t_end if math.isfinite(run.t_end) else 1e12
    phi_end = scene.initial.phi + 2 * math.pi * run.revolutions
    n_pairs = len(scene.friction.pairs)
    start, ref.governor.sleeve = initial_governor(scene, ref.model)
    n_gov, n_cyl = ref.n_gov, ref.model.ncyl
    if ref.model.latch:
        ref.latched = start[n_gov:n_gov + n_cyl].copy()
    cylinders = start[start.size - n_cyl:] if ref.cylinders is not None else np.empty(0)
    t, y = 0.0, np.concatenate([[scene.initial.phi, scene.initial.omega], np.zeros(3 + n_pairs),
                                start[:n_gov], cylinders])
    message = ""
    blocks: list[NDArray[np.float64]] = []
    events: dict[str, list[tuple[float, float]]] = {"breakpoint": [], "starter_cutout": [],
                                                    "governor_corner": []}
    nfev, nsteps = 0, 0
    t0 = time.perf_counter()
    max_step = sv.max_step / max(sv.switch_speed, abs(scene.initial.omega), 1e-9)
    while True:
        down, up = _segment(ref, y[0], y[1])
        ref.select(down, up)
        evs: list[tuple[str, _Event]] = []

        def crossing(level: float, direction: int) -> _Event:
            def g(t, yy):
                return yy[0] - level
            return _Event(g, True, direction)

        if math.isfinite(up):
            evs.append(("breakpoint", crossing(up, 1)))
        if math.isfinite(down):
            evs.append(("breakpoint", crossing(down, -1)))
        if math.isfinite(phi_end):
            evs.append(("end", crossing(phi_end, 1)))
        if scene.governor.model == "droop":  # corners of the characteristic
            evs.append(("governor_full", _speed_crossing(ref, t, y, scene.governor.speed_full)))
            evs.append(("governor_zero", _speed_crossing(ref, t, y, scene.governor.speed_zero)))
        if not math.isfinite(run.t_end):  # a stall would never reach the end: stop there
            def stop(t, yy):
                return yy[1]
            evs.append(("stall", _Event(stop, True, -1)))
        if ref.chain is not None and y[1] == 0.0:  # at rest: the pairs may hold the chain
            J, dJ, Mg, Ml, Ms, pc = ref.moments(y[0], 0.0, y)
            ref.sigma = ref.chain.start_direction(ref.friction_inputs(y[0], J, dJ, Mg, Ml + Ms, pc))
            if ref.sigma == 0.0:
                message = (f"locked: at rest at t = {t:.9g} s, φ = {y[0]:.9g} rad the friction of "
                           f"the non-ideal pairs holds the applied moments")
                events.setdefault("locked", []).append((t, y[0]))
                row = ref.rows([t], y[:, None])  # the state at rest, ω exactly 0
                if blocks:
                    blocks[-1][-1] = row[0]
                else:
                    blocks.append(row)
                break
        if ref.chain is not None and math.isfinite(run.t_end):
            def rest(t, yy):  # friction turns with the motion: stop where the shaft stops
                return yy[1]
            evs.append(("rest", _Event(rest, True, -np.sign(y[1]) or -ref.sigma)))
        elif math.isfinite(run.t_end):  # (recorded as it passes, as the compiled path does)
            def through_zero(t, yy):
                return yy[1]
            evs.append(("through_zero", _Event(through_zero, False, 0)))
        m = ref.model
        if ref.seg < m.load_x.size:  # the next corner of the load schedule, and the one behind
            evs.append(("load_up", _level_crossing(m.load_comp == T, m.load_x[ref.seg], 1)))
        if ref.seg > 0 and m.load_comp != T:  # (time never turns back)
            evs.append(("load_down", _level_crossing(False, m.load_x[ref.seg - 1], -1)))
        if m.gen_power != 0.0:
            evs.append(("generator", _speed_crossing(ref, t, y, m.gen_min)))
        evs += _sleeve_events(ref.governor, y)
        if scene.load.inertia > 0.0 and t < scene.load.inertia_time < t_end:
            evs.append(("inertia_switch", _level_crossing(True, scene.load.inertia_time, 1)))
        if ref.starter_on:
            def cut(t, yy):
                return yy[1] - scene.starter.cutout_speed
            evs.append(("starter_cutout", _Event(cut, True, 1)))
        dense = dense_tail > 0 and not up < phi_end - dense_tail  # may reach the tail
        sol = solve_ivp(ref.rhs, (t, t_end), y, method=method, rtol=sv.rtol, atol=sv.atol,
                        events=[_leaving_start(e, t) for _, e in evs] or None,
                        max_step=max_step, dense_output=dense)
        if sol.status == -1:
            raise SimulationError(f"solve_ivp failed at t = {sol.t[-1]:.9g} s: {sol.message}")
        nfev += sol.nfev
        nsteps += sol.t.size - 1
        ts, ys = (sol.t[1:], sol.y[:, 1:]) if blocks else (sol.t, sol.y)
        if dense:
            ts, ys = _with_dense_tail(sol, ts, phi_end - dense_tail)
        blocks.append(np.column_stack([ts, ys[0], ys[1]]) if state_only else ref.rows(ts, ys))
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if progress:
            progress(min(1.0, max(t / t_end, (y[0] - scene.initial.phi) / (phi_end - scene.initial.phi))))
        for (name, _), te, ye in zip(evs, sol.t_events or (), sol.y_events or ()):
            if name == "through_zero":  # (not at the segment's start, where ω may be 0)
                events.setdefault("speed_reversal", []).extend(
                    (tz, yz[0]) for tz, yz in zip(te, ye) if tz > sol.t[0])
        if sol.status == 0:
            break
        hit = [name for (name, e), te in zip(evs, sol.t_events) if te.size and e.terminal]
        if "end" in hit:
            break
        if "stall" in hit:  # (judged as the compiled path's stall: transient.outcome)
            events.setdefault("speed_reversal", []).append((t, y[0]))
            message = (f"stalled: the speed reached zero at t = {t:.9g} s, φ = {y[0]:.9g} rad "
                       f"({math.degrees(y[0]):.6g}°) before the {run.revolutions:g} revolutions "
                       f"the run ends by; give run.t_end to follow the motion after a stall")
            break
        if "rest" in hit:
            y[1] = 0.0
            events.setdefault("speed_reversal", []).append((t, y[0]))
        if "starter_cutout" in hit:
            ref.starter_on = False
            events["starter_cutout"].append((t, y[0]))
        for name, corner, low in (("governor_full", scene.governor.speed_full, 0),
                                  ("governor_zero", scene.governor.speed_zero, 1)):
            if name in hit:  # cross into the branch on the other side of this corner
                y[1] = corner
                ref.branch = low + 1 if ref.branch == low else low
                events["governor_corner"].append((t, y[0]))
        if "load_up" in hit or "load_down" in hit:
            rising = "load_up" in hit
            x = m.load_x[ref.seg if rising else ref.seg - 1]
            if m.load_comp != T:
                y[0] = x
            ref.seg = int(load_segment(m, x, rising))
            events.setdefault("load_schedule", []).append((t, y[0]))
        if "generator" in hit:
            y[1] = m.gen_min
            ref.gen_low = not ref.gen_low
            events.setdefault("generator_min_speed", []).append((t, y[0]))
        if "inertia_switch" in hit:  # a clutch couples J_x at rest: J(φ)ω is conserved
            t = scene.load.inertia_time
            J = ref.mechanism_terms(y[0])[0] + ref.model.J0
            extra = scene.load.inertia
            w_new = J * y[1] / (J + extra)
            y[3] -= 0.5 * J * y[1] ** 2 - 0.5 * (J + extra) * w_new ** 2  # W_load
            y[1] = w_new
            ref.model = ref.model._replace(J0=ref.model.J0 + extra)
            ref.branch = ref.droop_branch(w_new)  # (ω jumped: its switches afresh)
            ref.gen_low = bool(generator_branch(ref.model, w_new, True))
            if ref.chain is not None:
                ref.chain.J0 += extra
            events.setdefault("inertia_switch", []).append((t, y[0]))
        if "sleeve_stop" in hit:
            z, w = y[ref.governor.g], y[1]
            y[ref.governor.g + 1] = 0.0
            low = z < 0.5 * scene.governor.travel
            y[ref.governor.g] = 0.0 if low else scene.governor.travel
            force = ref.governor.force(w, y[ref.governor.g], 0.0)
            ref.governor.sleeve = (1 if force <= 0 else 0) if low else (2 if force >= 0 else 0)
            events.setdefault("sleeve_stop", []).append((t, y[0]))
        if "sleeve_free" in hit:
            ref.governor.sleeve = 0
            events.setdefault("sleeve_free", []).append((t, y[0]))
        if "breakpoint" in hit:
            # Put φ on the breakpoint it reached (solve_ivp locates it to ~1e-12 rad), so that
            # the next segment starts there and takes the table pieces beyond it.
            level = up if y[1] >= 0 else down
            y[0] = level
            events["breakpoint"].append((t, y[0]))
            if level >= phi_end:
                # The end sits on this breakpoint to rounding (2 revolutions less an ulp):
                # solve_ivp reports the first of two terminal events at one time only, and past
                # the end its event would never cross again.
                break
            if ref.cylinders is not None:
                ref.cylinders.close_intakes(y[0], y)
            if ref.latched is not None and y[1] > 0:  # a cylinder's start of injection
                m = ref.model
                local = np.mod(y[0] - m.gas_phase - m.inj_angle, m.period)
                for k in np.flatnonzero(np.minimum(local, m.period - local) < 1e-9):
                    ref.latched[k] = ref.command(y[1], y)
                    events.setdefault("injection", []).append((t, y[0]))
    rows = np.concatenate(blocks)
    names = ["t", "phi", "omega"] if state_only else list(output_columns(scene))
    traj = {n: rows[:, j] for j, n in enumerate(names)}
    solver = {"method": scene.solver.method, "rtol": sv.rtol, "atol": sv.atol, "nfev": nfev,
              "nsteps": nsteps, "nreject": -1, "wall_s": time.perf_counter() - t0, "compile_s": 0.0}
    return RunData(traj, {k: np.asarray(v).reshape(-1, 2) for k, v in events.items() if v}, solver,
                   complete=not message, message=message)
