"""The compiled path (numba DOP853, crank angle / time) against the reference path (plain numpy model
through ``scipy.integrate.solve_ivp``, always in time) on every dynamic scene in ``cases/``.

Runs are shortened (the scenes themselves take up to 1000 revolutions or 8 s):

* revolution-limited scenes: 5 revolutions (coasting) or 6 revolutions = 3 four-stroke cycles
  (Gots spin-up: 45 table corners, every kind of breakpoint of the mixed cycle);
* time-limited scenes: t_end = 0.5 s (swash plate: past the governor's full-fuel corner
  ω_a = 45 rad/s, reached at t ≈ 0.29 s), or 6 revolutions at the initial speed if shorter (the
  generator sets at 4000 rpm: 0.09 s), or 0.25 s for a start from rest.

Both at rtol = atol = 1e-10. The reference runs with max_step = 0.5° (at the start speed): its
output rows are its step points, and they must be dense enough to be interpolated (below).

Accuracy in the scipy way, e = (y − y_ref)/(atol + rtol·|y_ref|):

* **final state** (t, ω; φ too when the run ends on time): e ≤ 100. Each solver keeps its local
  error per step ≤ 1 in these units, and global errors accumulate over the ~10³ steps of a run
  (partly cancelling); scipy's own step choice would use up much of the bound, which is why the
  reference is run with the small max_step.
* **breakpoint events**: both paths cross the same table corners; the time at each, e ≤ 100.
* **samples**: the reference rows interpolated onto the compiled output grid (uniform in φ, where
  φ is monotonic) by cubic Hermite in φ, with the slopes the reference itself writes
  (dω/dφ = ε/ω, dt/dφ = 1/ω). Every table corner is a reference row (solve_ivp segments end
  there), so no interval spans a kink. The interpolation error (∝ Δφ⁴ with Δφ ≲ 1.3° here) adds
  to the solvers' differences, most in the Wiebe scene just after the combustion start, where the
  pressure rises like (x − start)^1.5 and the Hermite interpolation between reference rows is
  poorest; bound 500.
  Samples in the reference interval just past each corner are left out: where the torque jumps
  there (a radial's slave, whose pressure jumps away from its dead centre; a cylinder's latched
  fuel) the reference's row on the corner carries ε from before it, the wrong slope after.

A stalled reference (solve_ivp restarted again and again at the same t) is reported as a failure
at once rather than hanging the test run; a 300 s alarm backs that up (generous: the Woschni
scene's Radau reference is slow on a slow machine).
"""
from __future__ import annotations

import math
import signal
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import constant_main_bearings
from scipy.interpolate import CubicHermiteSpline

import transient.reference.integrate as reference
from transient.run import integrate
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RTOL = ATOL = 1e-10
E_FINAL = 100.0
E_SAMPLES = 500.0
REF_MAX_STEP = math.radians(0.5)
SHORT_REVS = {"coasting_single": 5.0}
DEFAULT_REVS = 6.0
SHORT_T_END = 0.5
START_T_END = 0.25


def dynamic_scenes():
    """The dynamic scenes the reference path runs here: not those with efficiency maps, which
    run on the compiled methods only (their independent check is scipy's interpolator at every
    sample, ``tests/validation/test_eta_table_runs.py``), nor those with friction on the joints'
    reactions, whose reference (the Newton–Euler forces with the friction closed on them at
    every evaluation) is too slow for these runs:
    :func:`test_reaction_friction_agrees_with_reference` runs shorter ones; nor those with an
    elastic shaft line, which the reference path's plain runner does not model (its reference
    is :mod:`transient.reference.torsion`, ``tests/validation/test_elastic_runs.py``)."""
    names = []
    for path in sorted(CASES.glob("*.toml")):
        scene = load_scene(path)
        if scene.run.mode == "dynamic" and scene.shaft is None and not any(
                p.model in ("reaction", "table") for p in scene.friction.pairs):
            names.append(path.stem)
    return names


SCENES = dynamic_scenes()
#: The scenes whose reference runs (the diesel's mixed cycle with governors, pairs, load steps,
#: Wiebe or wall heat: plain-Python right-hand sides over many short steps) make the test slow.
SLOW_SCENES = {"gots_diesel_friction", "gots_diesel_chain_friction", "gots_diesel_governed",
               "gots_diesel_load_steps", "gots_diesel_pi", "gots_diesel_wiebe",
               "gots_diesel_woschni"}


def shortened(name, method):
    scene = load_scene(CASES / f"{name}.toml")
    run = scene.run
    if math.isfinite(run.revolutions):
        run = replace(run, revolutions=SHORT_REVS.get(name, DEFAULT_REVS), t_end=math.inf)
    elif scene.initial.omega > 0.0:
        w0 = scene.initial.omega
        run = replace(run, t_end=min(SHORT_T_END, 2.0 * math.pi * DEFAULT_REVS / w0))
    else:
        run = replace(run, t_end=START_T_END)
    solver = replace(scene.solver, method=method, rtol=RTOL, atol=ATOL)
    if method != "dop853":
        solver = replace(solver, max_step=REF_MAX_STEP)
    return replace(scene, run=run, solver=solver,
                   output=replace(scene.output, samples_per_rev=720))


def e(y, y_ref):
    return (np.asarray(y) - np.asarray(y_ref)) / (ATOL + RTOL * np.abs(y_ref))


@contextmanager
def watched_reference(monkeypatch, limit_s=300.0):
    """Fail (not hang) if the reference path stalls: solve_ivp called 25 times in a row without
    advancing t, or the run taking more than ``limit_s``."""
    real = reference.solve_ivp
    stalls = []

    def solve_ivp(fun, t_span, y0, **kw):
        sol = real(fun, t_span, y0, **kw)
        if sol.t[-1] == t_span[0]:
            hit = [i for i, te in enumerate(sol.t_events or []) if te.size]
            stalls.append((t_span[0], y0[0], y0[1], hit))
            if len(stalls) >= 25:
                t, phi, w, ev = stalls[-1]
                raise AssertionError(
                    f"reference path stalled: solve_ivp restarted {len(stalls)} times at t = "
                    f"{t!r} s (φ = {phi!r} rad, ω = {w!r} rad/s) without advancing; terminal "
                    f"event(s) {ev} fire again at the start of every segment")
        else:
            stalls.clear()
        return sol

    def alarm(signum, frame):
        raise TimeoutError(f"reference path took more than {limit_s} s")

    monkeypatch.setattr(reference, "solve_ivp", solve_ivp)
    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, limit_s)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


@pytest.fixture(scope="module")
def compiled_runs():
    return {name: integrate(shortened(name, "dop853")) for name in SCENES}


@pytest.mark.parametrize("method", ["scipy-DOP853", "scipy-Radau"])
@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow)
                                  if name in SLOW_SCENES else name for name in SCENES])
def test_compiled_agrees_with_reference(name, method, compiled_runs, monkeypatch):
    comp = compiled_runs[name]
    scene = shortened(name, method)
    assert comp.complete, comp.message
    with watched_reference(monkeypatch):
        ref = integrate(scene)
    assert ref.solver["method"] == method
    c, r = comp.trajectory, ref.trajectory
    ends_on_time = math.isfinite(scene.run.t_end)

    # Final state.
    final = {"t": e(c["t"][-1], r["t"][-1]), "omega": e(c["omega"][-1], r["omega"][-1])}
    if ends_on_time:
        final["phi"] = e(c["phi"][-1], r["phi"][-1])
        assert c["t"][-1] == r["t"][-1] == scene.run.t_end
    else:
        assert c["phi"][-1] == pytest.approx(r["phi"][-1], rel=1e-15)
    print(f"{name} vs {method}: final e = " + ", ".join(f"{k} {v:.3g}" for k, v in final.items()))
    for k, v in final.items():
        assert abs(v) <= E_FINAL, (k, v)

    # Breakpoint events: the same corners, at the same times.
    bc = comp.events.get("breakpoint", np.zeros((0, 2)))
    br = ref.events.get("breakpoint", np.zeros((0, 2)))
    assert bc.shape == br.shape
    if br.size:
        np.testing.assert_allclose(bc[:, 1], br[:, 1], rtol=0, atol=1e-9)
        e_bp = np.max(np.abs(e(bc[:, 0], br[:, 0])))
        print(f"  {len(br)} breakpoints, max |e(t)| = {e_bp:.3g}")
        assert e_bp <= E_FINAL

    # Samples: the reference interpolated onto the compiled grid, where φ is monotonic.
    if scene.initial.omega == 0.0:
        # A start from rest: its reference steps, bounded by the switch speed's max_step, are too
        # long to interpolate once the engine runs; test_start_from_rest.py compares its samples.
        return
    keep = np.concatenate([[True], np.diff(r["phi"]) > 1e-12])
    phi_r, w_r, eps_r, t_r = r["phi"][keep], r["omega"][keep], r["epsilon"][keep], r["t"][keep]
    assert np.all(np.diff(phi_r) > 0) and np.all(w_r > 0)
    w_of_phi = CubicHermiteSpline(phi_r, w_r, eps_r / w_r)
    t_of_phi = CubicHermiteSpline(phi_r, t_r, 1.0 / w_r)
    inside = (c["phi"] >= phi_r[0]) & (c["phi"] <= phi_r[-1])
    assert np.count_nonzero(inside) >= 0.99 * c["phi"].size
    # (leave out the reference interval just past each corner: ε may jump there)
    left = np.clip(np.searchsorted(phi_r, c["phi"], side="right") - 1, 0, phi_r.size - 1)
    on_corner = np.zeros(phi_r.size, dtype=bool)
    if br.size:
        for j in np.searchsorted(phi_r, br[:, 1]) + np.array([[-1], [0]]):  # both neighbours
            j = np.clip(j, 0, phi_r.size - 1)
            on_corner[j[np.abs(phi_r[j] - br[:, 1]) < 1e-9]] = True
    inside &= ~on_corner[left]
    e_w = np.max(np.abs(e(c["omega"][inside], w_of_phi(c["phi"][inside]))))
    e_t = np.max(np.abs(e(c["t"][inside], t_of_phi(c["phi"][inside]))))
    print(f"  {np.count_nonzero(inside)} samples: max |e(ω)| = {e_w:.3g}, max |e(t)| = {e_t:.3g}")
    assert e_w <= E_SAMPLES and e_t <= E_SAMPLES


@pytest.mark.slow  # (the reference closes the joints' friction in Python at every evaluation)
@pytest.mark.parametrize("case, revolutions, mix",
                         [("gots_diesel_reaction_friction", 2.0, None),
                          ("radial_5cyl_reaction_friction", 1.0, None),
                          ("swash_plate_4cyl_reaction_friction", 1.0, None),
                          ("gots_diesel_mixed_friction", 2.0, None),
                          ("radial_5cyl_reaction_friction", 1.0, constant_main_bearings)])
def test_reaction_friction_agrees_with_reference(case, revolutions, mix, monkeypatch):
    """Friction on the joints' reactions, two ways: the compiled Newton solve of φ̈ and the side
    forces against the reference path's own Newton–Euler of the joint forces with the friction
    laws closed on them (:class:`transient.reference.twins.ReactionNumpy`, :class:`~transient.
    reference.twins.ArticulatedReactionNumpy`: a fixed point; :class:`~transient.reference.twins.
    SwashReactionNumpy`: fsolve), from the case's start: the Gots diesel over two revolutions,
    the radial and the swash plate over one; and with a constant-η pair at the main bearings
    (the diesel's mixed case over two, the radial's main bearings made one), where the compiled
    path holds the pair's mode between located switches and the reference solves both modes at
    every evaluation and takes the consistent one. Final t and ω in the scipy units above
    (≤ E_FINAL); each pair's energy lost and each cylinder's share of its loss power at the end,
    relative to the pair's (2e-6: the loss integrals are 10⁻³ to 10⁻² of the gas work whose
    tolerance they share). A loss no cylinder owns (the swash plate's bearings, a constant-η
    pair) has NaN shares on both paths. The compiled run is at 1e-13, so that what is compared
    is the two models (and the reference's own error): the work integrals are not
    error-controlled (``rk._controlled``), and a kink of a joint's loss inside a step (a side
    force changing side) leaves a loss integral off by more than the tolerance, converging only
    as the steps shrink."""
    scene = load_scene(CASES / f"{case}.toml")
    if mix is not None:
        scene = mix(scene)
    scene = replace(scene, run=replace(scene.run, revolutions=revolutions, t_end=math.inf),
                    solver=replace(scene.solver, rtol=RTOL, atol=ATOL))
    comp = integrate(replace(scene, solver=replace(scene.solver, rtol=1e-13, atol=1e-13)))
    with watched_reference(monkeypatch):
        ref = integrate(replace(scene, solver=replace(scene.solver, method="scipy-DOP853")))
    assert comp.complete and ref.complete, (comp.message, ref.message)
    c, r = comp.trajectory, ref.trajectory
    assert c["phi"][-1] == pytest.approx(r["phi"][-1], rel=1e-15)
    final = {"t": e(c["t"][-1], r["t"][-1]), "omega": e(c["omega"][-1], r["omega"][-1])}
    print("final e = " + ", ".join(f"{k} {v:.3g}" for k, v in final.items()))
    assert max(abs(v) for v in final.values()) <= E_FINAL, final
    n_cyl = scene.mechanism.n_cylinders
    for k in range(1, len(scene.friction.pairs) + 1):
        W, P = r[f"W_loss_{k}"][-1], r[f"P_loss_{k}"][-1]
        assert W > 0.0 and c[f"W_loss_{k}"][-1] == pytest.approx(W, rel=2e-6)
        for cyl in range(1, n_cyl + 1):
            name = f"P_loss_{k}_cyl{cyl}"
            if math.isnan(c[name][-1]):
                assert math.isnan(r[name][-1]), (name, r[name][-1])
            else:  # (a NaN of the reference's alone fails here)
                assert abs(c[name][-1] - r[name][-1]) <= 1e-6 * abs(P), (name, c[name][-1],
                                                                         r[name][-1])


@pytest.mark.parametrize("max_step_deg", [180.0, 10.0, 5.0, 2.0, 1.0])
def test_compiled_run_reaches_its_end_for_any_max_step(max_step_deg, compiled_runs):
    """The step-size limit is a solver setting, not the model: for every max_step the compiled run
    must finish on φ = 6 revolutions (a table corner: 3 whole cycles) and stop on each of the 45
    corners the reference path crosses, once each (crank angle stops on breakpoints exactly)."""
    name = "gots_diesel_spinup"
    scene = shortened(name, "dop853")
    scene = replace(scene, solver=replace(scene.solver, max_step=math.radians(max_step_deg)))
    data = integrate(scene)
    assert data.complete, data.message
    assert data.trajectory["phi"][-1] == pytest.approx(2 * math.pi * DEFAULT_REVS, rel=1e-15)
    expected = compiled_runs[name].events["breakpoint"][:, 1]  # 45, = the reference's (above)
    got = data.events.get("breakpoint", np.zeros((0, 2)))[:, 1]
    assert expected.size == 45
    assert got.size == expected.size, f"{got.size} breakpoint events, expected {expected.size}"
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_chain_of_a_nonfinite_trial_stage_is_not_a_number():
    """A trial stage of solve_ivp at a loose tolerance can leave the physical range (the bench's
    governed diesel at rtol 1e-3: a moment overflowed). The chain then gives a non-finite
    acceleration, which solve_ivp rejects and retakes shorter, so the chain must return NaN
    rather than let Brent's method raise a ValueError (which would fail the whole reference
    run)."""
    scene = load_scene(CASES / "gots_diesel_governed.toml")
    chain = reference.ChainNumpy(scene)
    n = chain.n
    Jk, dJk = np.full(n + 1, 0.1), np.zeros(n + 1)
    a, S, eta, L = chain.solve((Jk, dJk, np.full(n + 1, 10.0)), 100.0, 1.0)
    assert np.isfinite(a) and np.all(np.isfinite(S))  # (a finite state: a number)
    for Mk in (np.array([np.inf] + [0.0] * n), np.array([1e308] * (n + 1))):
        a, S, eta, L = chain.solve((Jk, dJk, Mk), 100.0, 1.0)
        assert np.isnan(a) and np.all(np.isnan(S)) and np.all(np.isnan(eta))
        assert np.all(np.isnan(L))


def test_a_segment_started_on_a_governor_corner_does_not_stop_at_once(monkeypatch):
    """The governed diesel by RK45 at rtol 1e-5 (tools/rk45_diesel.py): at t = 0.66299 s a
    segment starts on the droop corner with the speed heading up, and its first step ends below
    the corner (the speed turning back within it). The event function is 0 at the start; were the
    crossing put there, the run would stop at once, flip the governor's branch and start again,
    for ever at the same t. The run passes it, crossing the corner where the speed does."""
    base = load_scene(CASES / "gots_diesel_governed.toml")
    solver = replace(base.solver, method="scipy-RK45", rtol=1e-5, atol=1e-8)
    scene = replace(base, solver=solver, run=replace(base.run, revolutions=math.inf, t_end=0.67))
    with watched_reference(monkeypatch):
        data = reference.run_reference(scene, state_only=True)
    assert data.trajectory["t"][-1] == 0.67
    corners = data.events["governor_corner"]
    assert len(corners) >= 2 and all(b[0] > a[0] for a, b in zip(corners, corners[1:])), corners
