"""A prototype: an exponential Runge–Kutta step that carries the shaft line's linear part
exactly, against DOP853, in steps per cycle at equal error on the reference station's ω.

The elastic run's step is held by the line's highest mode (accuracy, not stability: see
``throw_breakpoints.py``), which the rigid run does not have. An exponential integrator takes
the linear part of the line — each dof's section, ring and coupling torques (linear in the
angles and speeds) over its inertia frozen at the step's start, J_d(θ_d(t_n)) — exactly,
through the φ-functions of h L_n, and only the rest N(y) = f(y) − L_n y (the gas moments, the
load, the inertias' change over the step, J′ω² …) explicitly: ETDRK4 of Cox & Matthews (J.
Comput. Phys. 176, 2002, (26)–(29)), with L_n frozen per step (an exponential Rosenbrock-type
use of it, Hochbruck & Ostermann, Acta Numerica 19, 2010, §2.3, §4). φ_k(hL) from one matrix
exponential of an augmented matrix (Higham, *Functions of Matrices*, §10.7.4; Saad 1992).

Both run the reference path's numpy right-hand side of the bench's scene
(:mod:`transient.reference.torsion`, the motion's states only) in time over the first
REVOLUTIONS of the run-up, against a tight DOP853 run (rtol 1e-12): DOP853 adaptive at a
ladder of rtol, the exponential method at fixed steps. Printed: steps per cycle, right-hand
sides per cycle and the reference station's final ω's relative error, for each run.

Run: ``.venv/bin/python tools/exponential_line.py [REVOLUTIONS]`` (default 10; slow, numpy).
"""
import math
import sys

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from transient.reference.torsion import from_scene
from transient.scene import load_scene
from transient.verify.torsion import ELASTIC_SCENE


def motion_rhs(model):
    """f(t, y) of the motion's states (the work integrals left out: nothing depends on them)."""
    works = np.zeros(model.size - model.i_works)

    def f(t, y):
        return model.rhs(t, np.concatenate([y, works]))[:model.i_works]
    return f


def line_parts(model):
    """Indices of the angles and speeds of every dof (stations, rings, driven inertia) in the
    motion state, and the torque matrices: torques = Gq @ angles + Gv @ speeds (the
    elements' and the absolute damping's, linear), by probing ``element_torques``."""
    n, r = model.line.n, model.n_rings
    q = list(range(n)) + list(range(2 * n, 2 * n + r))
    v = list(range(n, 2 * n)) + list(range(2 * n + r, 2 * n + 2 * r))
    if model.line.coupling is not None:
        q.append(model.i_driven)
        v.append(model.i_driven + 1)
    q, v = np.array(q), np.array(v)
    y0 = np.zeros(model.size)

    def torques(y):
        T, T_ring, T_driven, _ = model.element_torques(y)
        return np.concatenate([T, T_ring, np.atleast_1d(T_driven)[:len(q) - n - r]])
    base = torques(y0)
    Gq = np.empty((len(q), len(q)))
    Gv = np.empty((len(q), len(q)))
    for k in range(len(q)):
        y = y0.copy()
        y[q[k]] = 1.0
        Gq[:, k] = torques(y) - base
        y = y0.copy()
        y[v[k]] = 1.0
        Gv[:, k] = torques(y) - base
    return q, v, Gq, Gv


def inertias(model, y):
    """Each dof's inertia at state y: the stations' J_d(θ_d), the rings', the driven one's
    (y None: each dof's mean over a revolution, ``TorsionModel.mean_inertias``, at its own
    speed: the driven one's J/i² there, so J itself here)."""
    if y is None:
        J = model.weights.copy()
        c = model.line.coupling
        if c is not None:
            J[-1] = c.driven_inertia
        return J
    J = model.station_inertia(y[:model.line.n])[0]
    rings = [ring.inertia for ring in model.line.rings]
    c = model.line.coupling
    driven = [c.driven_inertia] if c is not None else []
    return np.concatenate([J, rings, driven])


def linear_part(model, parts, y, size):
    """L_n: dθ/dt = ω, dω/dt = (Gq θ + Gv ω)/J(y) on the line's dofs, zero elsewhere."""
    q, v, Gq, Gv = parts
    L = np.zeros((size, size))
    Jinv = 1.0 / inertias(model, y)
    L[q, v] = 1.0
    L[np.ix_(v, q)] = Jinv[:, None] * Gq
    L[np.ix_(v, v)] = Jinv[:, None] * Gv
    return L


def phis(A):
    """e^A, φ1(A), φ2(A), φ3(A) from one exponential of the augmented block matrix."""
    d = A.shape[0]
    B = np.zeros((4 * d, 4 * d))
    B[:d, :d] = A
    eye = np.eye(d)
    B[:d, d:2 * d] = eye
    B[d:2 * d, 2 * d:3 * d] = eye
    B[2 * d:3 * d, 3 * d:] = eye
    E = expm(B)
    return E[:d, :d], E[:d, d:2 * d], E[:d, 2 * d:3 * d], E[:d, 3 * d:]


def etdrk4(f, model, parts, y0, t_end, n_steps, frozen=True):
    """ETDRK4 (Cox–Matthews) with the linear part frozen at each step's start (``frozen``) or
    the mean-inertia line's, one L for the run; returns the state at t_end and the right-hand
    sides taken."""
    h = t_end / n_steps
    y = y0.copy()
    t = 0.0
    calls = 0
    if not frozen:
        L = linear_part(model, parts, None, y.size)
        E, p1, p2, p3 = phis(h * L)
        E2, q1, _, _ = phis(0.5 * h * L)
    for _ in range(n_steps):
        if frozen:
            L = linear_part(model, parts, y, y.size)
            E, p1, p2, p3 = phis(h * L)
            E2, q1, _, _ = phis(0.5 * h * L)

        Nu = f(t, y) - L @ y
        a = E2 @ y + 0.5 * h * q1 @ Nu
        Na = f(t + 0.5 * h, a) - L @ a
        b = E2 @ y + 0.5 * h * q1 @ Na
        Nb = f(t + 0.5 * h, b) - L @ b
        c = E2 @ a + 0.5 * h * q1 @ (2.0 * Nb - Nu)
        Nc = f(t + h, c) - L @ c
        y = (E @ y + h * ((p1 - 3.0 * p2 + 4.0 * p3) @ Nu + (2.0 * p2 - 4.0 * p3) @ (Na + Nb)
                          + (4.0 * p3 - p2) @ Nc))
        t += h
        calls += 4
    return y, calls


def main():
    revolutions = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    scene = load_scene(ELASTIC_SCENE)
    model, at = from_scene(scene)
    f = motion_rhs(model)
    y0 = model.initial_state(scene.initial.phi, scene.initial.omega)[:model.i_works]
    cycles = revolutions * 2.0 * math.pi / scene.mechanism.cycle
    # t_end: where the tight run's reference station has turned REVOLUTIONS
    phi_end = scene.initial.phi + 2.0 * math.pi * revolutions

    def turned(t, y):
        return y[at] - phi_end
    turned.terminal = True
    ref = solve_ivp(f, (0.0, 60.0), y0, method="DOP853", rtol=1e-12, atol=1e-15,
                    events=turned)
    t_end = ref.t[-1]
    w_ref = ref.y[model.line.n + at, -1]
    print(f"{revolutions:g} revolutions = {cycles:g} cycles in {t_end:.6g} s, final ω_ref "
          f"{w_ref:.10g} rad/s (DOP853 rtol 1e-12, {ref.t.size - 1} steps)")
    for rtol in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9):
        model.nfev = 0
        sol = solve_ivp(f, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-3)
        err = abs(sol.y[model.line.n + at, -1] / w_ref - 1.0)
        print(f"DOP853 rtol {rtol:.0e}: {(sol.t.size - 1) / cycles:8.1f} steps/cycle "
              f"{model.nfev / cycles:8.0f} RHS/cycle  ω_ref error {err:.2e}")
    parts = line_parts(model)
    for frozen, name in ((True, "J(θ_n) frozen per step"), (False, "mean inertias")):
        for per_cycle in (20, 40, 80, 160, 320, 640):
            y, calls = etdrk4(f, model, parts, y0, t_end, int(round(per_cycle * cycles)), frozen)
            err = abs(y[model.line.n + at] / w_ref - 1.0)
            print(f"ETDRK4, line exact, {name}: {per_cycle:4d} steps/cycle {calls / cycles:8.0f} "
                  f"RHS/cycle  ω_ref error {err:.2e}"
                  + ("" if np.all(np.isfinite(y)) else " (non-finite)"))


if __name__ == "__main__":
    main()
