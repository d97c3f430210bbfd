"""Runs with load schedules and a generator load on the compiled path.

The schedule's corners are state events (``load_schedule``): in time they are levels of t, in
revolutions levels of φ = φ₀ + 2π·rev; on the independent variable the step also ends on them.
What must hold:

* **A step lands on its event.** The event record sits on the corner (t or φ) to 1e-12, and the
  load written out takes the value before the step on every sample before the event and the
  value after on every sample after it (with a generator load alone, M_load·ω = −s·P to 1e-12:
  the power check). In crank angle and in time, for steps in time and in revolutions; in
  revolutions the two domains put the event at the same time to the integration's accuracy.
* **Work–energy across steps and ramps.** ½J(φ)ω²(end) − ½J(φ)ω²(0) = W_gas + W_load + W_starter
  to 1e-8 of Σ|W|, from the state integrals (the ``W_*`` columns) and, independently, from a
  quadrature of the M columns between the events (load corners, table corners): a jump or kink of
  the load anywhere but at its event would spoil the piecewise-polynomial quadrature.
* **The generator's minimum speed.** From rest (time domain), the torque is −P/ω_min below
  ω_min and M·ω = −P above, switching at a ``generator_min_speed`` event at ω = ω_min.
* **Turning back over a corner in revolutions** (time domain, ω < 0): the lower corner is an
  event too, and the scale returns to its value before.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.run import integrate
from transient.scene import Gas, Initial, Load, Output, Run, Solver, Starter, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
W0 = 2000.0 * math.pi / 30.0
P_GEN = 20e3


def smooth_gas(p0=1.0e5):
    """The smooth indicator diagram of ``test_energy.smooth_gas`` (a C^∞ pulse on a 1° spline
    table; its only corners are the table's ends), so that the quadrature sees no kinks but the
    load's."""
    x = np.radians(np.arange(0.0, 721.0))
    p = p0 + 0.05e6 + 4.0e6 * np.exp(-8.0 * (1.0 - np.cos((x - 2.0 * np.pi - 0.35) / 2.0)))
    return Gas(model="table", p0=p0, phi=tuple(x), p=tuple(p), interpolation="spline")


def engine(load, domain="angle", revs=20, rtol=1e-10, t_end=math.inf, phi0=0.0):
    """The Gots 3-cylinder engine with flywheel (cases/gots_diesel_spinup.toml), smooth gas, from
    2000 rpm. Time domain: switch speed 10× the start speed, output every 2e-5 s."""
    base = load_scene(CASES / "gots_diesel_spinup.toml")
    time_mode = domain == "time"
    solver = Solver(rtol=rtol, atol=1e-12, switch_speed=10.0 * W0 if time_mode else math.pi / 3)
    output = Output(samples_per_rev=720, dt=2e-5 if time_mode else 0.0)
    return replace(base, gas=smooth_gas(), load=load, initial=Initial(phi0, W0),
                   run=Run(revolutions=revs, t_end=t_end), solver=solver, output=output)


def run(scene):
    data = integrate(scene)
    assert data.complete, data.message
    return data


def scale_seen(tr):
    """s from the output of a generator-only load: M_load = −s·P/ω (ω above ω_min)."""
    return -tr["M_load"] * tr["omega"] / P_GEN


# ------------------------------------------------------------------------------------------------
# A step lands on its event


@pytest.mark.parametrize("domain", ["angle", "time"])
def test_time_step_lands_on_its_event(domain):
    """Generator only, s = 0.5 → 1.0 at t = 0.05 s: one event at t = 0.05 s, M·ω = −0.5 P on
    every sample before it and −P after (1e-12)."""
    t_step = 0.05
    load = Load(generator_power=P_GEN, generator_min_speed=10.0, schedule_time=(t_step, t_step),
                schedule_scale=(0.5, 1.0))
    data = run(engine(load, domain, revs=6))
    tr = data.trajectory
    ev = data.events["load_schedule"]
    print(f"{domain}: load_schedule events {ev.tolist()}, {tr['t'].size} samples")
    assert ev.shape == (1, 2)
    assert abs(ev[0, 0] - t_step) <= 1e-12
    s = scale_seen(tr)
    before, after = tr["t"] < t_step - 1e-12, tr["t"] > t_step + 1e-12
    assert before.sum() > 100 and after.sum() > 100
    assert np.max(np.abs(s[before] - 0.5)) <= 1e-12
    assert np.max(np.abs(s[after] - 1.0)) <= 1e-12
    # the event's angle is where the samples put t = t_step (cubic through the 4 nearest)
    near = np.argsort(np.abs(tr["t"] - t_step))[:4]
    phi_at = np.polyval(np.polyfit(tr["t"][near] - t_step, tr["phi"][near], 3), 0.0)
    assert abs(ev[0, 1] - phi_at) <= 1e-8


def test_revolution_step_lands_on_its_angle():
    """s = 0.2 → 1.0 after 2.5 revolutions from φ₀ = 0.3 rad: the event at φ₀ + 2π·2.5 (1e-12)
    in both domains, the samples on either side with their scale, and the two domains agree on
    the event's time to 1e-8 (rtol 1e-10)."""
    phi0 = 0.3
    load = Load(generator_power=P_GEN, generator_min_speed=10.0,
                schedule_revolutions=(2.5, 2.5), schedule_scale=(0.2, 1.0))
    corner = phi0 + 2.0 * math.pi * 2.5
    times = {}
    for dom in ("angle", "time"):
        data = run(engine(load, dom, revs=5, phi0=phi0))
        tr = data.trajectory
        ev = data.events["load_schedule"]
        assert ev.shape == (1, 2)
        assert abs(ev[0, 1] - corner) <= 1e-12 * corner
        s = scale_seen(tr)
        before, after = tr["phi"] < corner - 1e-12, tr["phi"] > corner + 1e-12
        assert before.sum() > 100 and after.sum() > 100
        assert np.max(np.abs(s[before] - 0.2)) <= 1e-12
        assert np.max(np.abs(s[after] - 1.0)) <= 1e-12
        times[dom] = ev[0, 0]
    print(f"event time: angle {times['angle']!r}, time {times['time']!r}, "
          f"difference {times['angle'] - times['time']:.2e} s")
    assert abs(times["angle"] - times["time"]) <= 1e-8 * times["angle"]


# ------------------------------------------------------------------------------------------------
# Work–energy across steps and ramps

# s: 1 → 2 (step at 0.1 s), ramp down to 0.5 (0.2 … 0.3 s), 0.5 → 1.5 (step at 0.35 s)
TIME_SCHEDULE = {"schedule_time": (0.1, 0.1, 0.2, 0.3, 0.35, 0.35),
                 "schedule_scale": (1.0, 2.0, 2.0, 0.5, 0.5, 1.5)}
REV_SCHEDULE = {"schedule_revolutions": (3.0, 3.0, 6.0, 9.0, 12.0, 12.0),
                "schedule_scale": (1.0, 2.0, 2.0, 0.5, 0.5, 1.5)}


def work_balance(data, scene, sample_integral, table_end_events, domain):
    """(ΔK, works from the W_* columns, works by quadrature of the M columns between events: the
    load schedule's and the gas table's ends, its only corners)."""
    tr = data.trajectory
    cuts_ev = [table_end_events(data, scene)] + [data.events[k] for k in ("load_schedule",)
                                                 if k in data.events]
    cuts_ev = np.concatenate(cuts_ev) if cuts_ev else np.zeros((0, 2))
    if domain == "angle":
        x, w, cuts = tr["phi"], np.ones_like(tr["phi"]), cuts_ev[:, 1]
    else:
        x, w, cuts = tr["t"], tr["omega"], cuts_ev[:, 0]
    cuts = np.concatenate([[x[0], x[-1]], cuts])
    quad = {c: sample_integral(x, tr[f"M_{c}"] * w, cuts) for c in ("gas", "load", "starter")}
    state = {c: tr[f"W_{c}"][-1] - tr[f"W_{c}"][0] for c in ("gas", "load", "starter")}
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    return K[-1] - K[0], state, quad


@pytest.mark.parametrize("domain", ["angle", "time"])
@pytest.mark.parametrize("schedule", ["time", "revolutions"])
def test_work_energy_balance_across_steps_and_ramps(domain, schedule, sample_integral,
                                                    table_end_events):
    """All four load terms scaled by the schedule (two steps and a ramp), 20 revolutions at
    rtol 1e-10: ΔK = ΣW to 1e-8 of Σ|W| from the state integrals and from the quadrature, and
    the two agree on W_load to 1e-8."""
    sched = TIME_SCHEDULE if schedule == "time" else REV_SCHEDULE
    load = Load(torque=10.0, linear=0.05, fan=2e-4, generator_power=5e3,
                generator_min_speed=50.0, **sched)
    scene = engine(load, domain)
    data = run(scene)
    assert data.events["load_schedule"].shape[0] == 4  # 4 corners (each step's two are one)
    if schedule == "time":
        assert np.all(np.abs(data.events["load_schedule"][:, 0] - [0.1, 0.2, 0.3, 0.35])
                      <= 1e-12)
    else:
        assert np.all(np.abs(data.events["load_schedule"][:, 1]
                             - 2 * np.pi * np.array([3.0, 6.0, 9.0, 12.0])) <= 1e-12 * 80)
        if domain == "angle":
            # the table corners come every 240° (2/3 rev): the corners at 6 and 12 rev sit on
            # breakpoints, and the step that lands on both reports both
            bp = table_end_events(data, scene)[:, 1]
            assert len(bp) == 30
            assert all(np.any(np.abs(bp - 2 * np.pi * r) <= 1e-12 * 80) for r in (6.0, 12.0))
    dK, state, quad = work_balance(data, scene, sample_integral, table_end_events, domain)
    total = sum(abs(v) for v in quad.values())
    res_state = (dK - sum(state.values())) / total
    res_quad = (dK - sum(quad.values())) / total
    print(f"{domain} domain, schedule in {schedule}: ΔK = {dK:.6f} J, W = {quad}, residuals: "
          f"state {res_state:.2e}, quadrature {res_quad:.2e}, W_load state − quadrature "
          f"{(state['load'] - quad['load']) / total:.2e}")
    assert abs(quad["load"]) > 0.2 * total
    assert abs(res_state) <= 1e-8
    assert abs(res_quad) <= 1e-8
    assert abs(state["load"] - quad["load"]) <= 1e-8 * total


def test_quadrature_sees_a_misplaced_step(sample_integral, table_end_events):
    """The quadrature check has teeth: without the step's event among the cuts (as if the load
    jumped where no event says), the balance misses by far more than 1e-8."""
    load = Load(generator_power=5e3, generator_min_speed=50.0, **TIME_SCHEDULE)
    scene = engine(load, "angle")
    data = run(scene)
    tr = data.trajectory
    bp = table_end_events(data, scene)[:, 1]
    x = tr["phi"]
    full = sample_integral(x, tr["M_load"], np.concatenate([[x[0], x[-1]], bp,
                                                           data.events["load_schedule"][:, 1]]))
    blind = sample_integral(x, tr["M_load"], np.concatenate([[x[0], x[-1]], bp]))
    print(f"W_load with the events as cuts {full:.9f} J, without {blind:.9f} J")
    assert abs(full - blind) > 1e-6 * abs(full)


# ------------------------------------------------------------------------------------------------
# The generator's minimum speed, from rest

@pytest.mark.parametrize("domain", ["auto", "time"])
def test_generator_min_speed_from_rest(domain):
    """The engine started from rest by its starter (as in test_start_from_rest) against a 500 W
    generator with ω_min = 100 rad/s: on the low branch (from the start to the first
    ``generator_min_speed`` event, and between later pairs of them: the speed dips below ω_min
    in the first compressions) M_load = −P/ω_min exactly and ω ≤ ω_min, on the high branch
    M·ω = −P (1e-12) and ω ≥ ω_min; each event at ω = ω_min; work–energy closes (1e-8).

    (The start is delicate: with 5 N m at rest the starter of test_start_from_rest carries the
    engine into firing; with 67 N m (2 kW, ω_min = 30 rad/s) it cannot carry it through its first
    compression and the engine rocks to a stop, as it does with a 400 N m starter and no load,
    which cuts out before the first firing.)"""
    base = load_scene(CASES / "gots_diesel_spinup.toml")
    w_min, power = 100.0, 500.0
    scene = replace(
        base, load=Load(generator_power=power, generator_min_speed=w_min),
        starter=Starter(torque=300.0, noload_speed=600.0 * math.pi / 30.0,
                        cutout_speed=400.0 * math.pi / 30.0),
        initial=Initial(0.0, 0.0), run=Run(revolutions=4, t_end=2.0),
        solver=replace(base.solver, rtol=1e-10, atol=1e-10, domain=domain),
        output=Output(samples_per_rev=720, dt=5e-6))
    data = run(scene)
    tr = data.trajectory
    ev = data.events["generator_min_speed"]
    print(f"generator_min_speed events {ev.tolist()}, final ω {tr['omega'][-1]:.4g} rad/s")
    assert ev.shape[0] >= 1 and tr["omega"][-1] > 2 * w_min
    t = tr["t"]
    for t_ev in ev[:, 0]:
        # ω at the event from the samples nearest to it (cubic): the speed is on its level
        near = np.argsort(np.abs(t - t_ev))[:4]
        w_at = np.polyval(np.polyfit(t[near] - t_ev, tr["omega"][near], 3), 0.0)
        assert abs(w_at - w_min) <= 1e-6 * w_min
    crossed = np.searchsorted(ev[:, 0], t)  # events at or before each sample
    on_event = np.min(np.abs(t[:, None] - ev[None, :, 0]), axis=1) <= 1e-12
    low, high = (crossed % 2 == 0) & ~on_event, (crossed % 2 == 1) & ~on_event
    assert low.sum() > 100 and high.sum() > 100
    assert np.all(tr["omega"][low] <= w_min * (1 + 1e-9))
    assert np.all(tr["omega"][high] >= w_min * (1 - 1e-9))
    assert np.all(tr["M_load"][low] == -power / w_min)
    assert np.max(np.abs(tr["M_load"][high] * tr["omega"][high] / power + 1.0)) <= 1e-12
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    W = {c: tr[f"W_{c}"][-1] for c in ("gas", "load", "starter")}
    residual = (K[-1] - K[0] - sum(W.values())) / sum(abs(v) for v in W.values())
    print(f"from rest, domain {domain}: W = {W}, residual {residual:.2e}")
    assert abs(residual) <= 1e-8


# ------------------------------------------------------------------------------------------------
# Turning back over a corner in revolutions

def test_turning_back_over_a_revolution_corner():
    """One cylinder, no gas, a constant load torque T that doubles after half a revolution: the
    shaft passes φ = π (s 1 → 2), stops, turns back (the load keeps its sign) and recrosses π
    going down (s 2 → 1). Two ``load_schedule`` events, both at φ = π exactly, a reversal
    between; the load on every sample is −T (φ < π) or −2T (φ > π)."""
    base = load_scene(CASES / "coasting_single.toml")
    torque = 1.0
    scene = replace(base, load=Load(torque=torque, schedule_revolutions=(0.5, 0.5),
                                    schedule_scale=(1.0, 2.0)),
                    initial=Initial(0.0, 20.0), run=Run(t_end=1.5),
                    solver=replace(base.solver, rtol=1e-10, atol=1e-12),
                    output=Output(samples_per_rev=720, dt=1e-4))
    data = run(scene)
    tr = data.trajectory
    ev = data.events["load_schedule"]
    rev = data.events["speed_reversal"]
    print(f"load_schedule {ev.tolist()}, speed_reversal {rev.tolist()}")
    assert ev.shape == (2, 2) and rev.shape[0] >= 1
    assert np.all(ev[:, 1] == math.pi)
    assert ev[0, 0] < rev[0, 0] < ev[1, 0]
    assert tr["omega"][-1] < 0.0 and tr["phi"][-1] < math.pi
    above, below = tr["phi"] > math.pi + 1e-12, tr["phi"] < math.pi - 1e-12
    assert above.sum() > 50 and below.sum() > 50
    assert np.all(tr["M_load"][above] == -2.0 * torque)
    assert np.all(tr["M_load"][below] == -torque)


@pytest.mark.slow  # (the reference path's Python right-hand side over many short steps)
@pytest.mark.parametrize("schedule", ["time", "revolutions"])
def test_compiled_agrees_with_the_reference_path(schedule):
    """The same schedule (a step, a ramp) and generator load through scipy's DOP853 in
    ``transient.reference`` (its own numpy model, the corners as terminal events): final t and ω
    agree to 1e-8 and the load_schedule events sit at the same times to 1e-9 s."""
    if schedule == "time":
        load = Load(torque=20.0, generator_power=P_GEN, generator_min_speed=50.0,
                    schedule_time=(0.05, 0.05, 0.1, 0.15), schedule_scale=(0.5, 1.0, 1.0, 0.2))
    else:
        load = Load(torque=20.0, generator_power=P_GEN, generator_min_speed=50.0,
                    schedule_revolutions=(2.0, 2.0, 4.0, 6.0),
                    schedule_scale=(0.5, 1.0, 1.0, 0.2))
    scene = engine(load, revs=8, rtol=1e-11)
    comp = run(scene)
    ref = integrate(replace(scene, solver=replace(scene.solver, method="scipy-DOP853")))
    assert ref.complete, ref.message
    c, r = comp.trajectory, ref.trajectory
    assert c["phi"][-1] == pytest.approx(r["phi"][-1], rel=1e-14)
    dt = abs(c["t"][-1] / r["t"][-1] - 1.0)
    dw = abs(c["omega"][-1] / r["omega"][-1] - 1.0)
    ec, er = comp.events["load_schedule"], ref.events["load_schedule"]
    print(f"{schedule}: final Δt/t {dt:.1e}, Δω/ω {dw:.1e}; events {ec[:, 0]} vs {er[:, 0]}")
    assert dt <= 1e-8 and dw <= 1e-8
    assert ec.shape == er.shape == (3, 2)
    np.testing.assert_allclose(ec[:, 0], er[:, 0], rtol=0, atol=1e-9)
