"""Dynamic governors and fuel latching: the PI governor's zero steady error and its
anti-windup, the flyweight governor's stops and static characteristic, the latching of each
cylinder's fuel at its start of injection, and the compiled path against the reference path
(whose governor is written out again in numpy, ``transient.reference.twins.GovernorNumpy``).

Scenes: ``cases/gots_diesel_pi.toml`` (PI, generator load steps, crankpins with friction, fuel
latched 15° before each firing TDC) and ``cases/gots_diesel_start_flyweight.toml`` (flyweight
governor), changed per test as each says.
"""
from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import CASES
from scipy.interpolate import CubicHermiteSpline

from transient.run import integrate
from transient.scene import scene_from_dict

RPM = math.pi / 30.0


def scene(case: str, **sections):
    """The case's scene with whole sections replaced or, for a dict, keys updated."""
    data = tomllib.loads((CASES / case).read_text(encoding="utf-8"))
    for name, value in sections.items():
        if value is None:
            data.pop(name, None)
        elif isinstance(value, dict):
            data.setdefault(name, {}).update(value)
        else:
            data[name] = value
    return scene_from_dict(copy.deepcopy(data), case)


def run(sc):
    data = integrate(sc)
    assert data.complete, data.message
    return data


def mean_speed_over_last_cycles(tr, cycle: float, n: int) -> float:
    """Time-mean speed over the last n cycles, Δφ/Δt between two output samples (exact: the
    samples lie on the angle grid)."""
    phi, t = tr["phi"], tr["t"]
    j = int(np.argmin(np.abs(phi - (phi[-1] - n * cycle))))
    assert abs(phi[j] - (phi[-1] - n * cycle)) < 1e-9
    return (phi[-1] - phi[j]) / (t[-1] - t[j])


# ----------------------------------------------------------------------------------------------
# PI governor


def steady_pi(gain_i: float):
    """PI (or P-only) governor at 4000 rpm under a constant 50 kW, run to a periodic steady state
    (the closed loop's slowest pole is near K_i/K_p ≈ 2.7 1/s: 400 revolutions ≈ 5.7 s)."""
    return scene("gots_diesel_pi.toml", load={"schedule_time": [], "schedule_scale": [],
                                                "generator_power": 50e3},
                 governor={"gain_i": gain_i, "fuel_initial": 0.5},
                 run={"revolutions": 400.0, "t_end": 20.0})


def test_pi_settles_with_zero_steady_error():
    """Periodic steady state: x_I periodic, so ∫e dt = 0 over a cycle and the time-mean speed is
    ω_ref. Measured on the trajectory (Δφ/Δt over the last two cycles), not on the integrator;
    a P-only governor of the same K_p is the control: its steady error is its droop."""
    cycle = 4.0 * math.pi
    errors = {}
    for gain_i in (40.0, 0.0):
        sc = steady_pi(gain_i)
        tr = run(sc).trajectory
        w_mean = mean_speed_over_last_cycles(tr, cycle, 2)
        errors[gain_i] = (w_mean - sc.governor.speed) / sc.governor.speed
    print(f"steady error: PI {errors[40.0]:.3g}, P only {errors[0.0]:.3g} (relative)")
    assert abs(errors[40.0]) <= 1e-7
    assert abs(errors[0.0]) >= 1e-3  # the control: a P governor keeps a droop


def saturating_step(anti_windup: bool):
    """A torque load stepped beyond what full fuel gives (225 N m against ≈ 206 N m) for 0.5 s,
    then back: the rack sits on its limit 1 while the speed falls."""
    return scene("gots_diesel_pi.toml",
                 load={"generator_power": 0.0, "torque": 150.0,
                       "schedule_time": [0.5, 0.5, 1.0, 1.0], "schedule_scale": [1.0, 1.5, 1.5, 1.0]},
                 governor={"anti_windup": anti_windup, "fuel_initial": 0.75},
                 run={"t_end": 3.0})


def test_pi_anti_windup_on_a_saturating_step():
    """Back-calculation with T_t = K_p/K_i holds the integrator at the limit while the rack is on
    it (x_I → f_max as u_s − u = K_i e T_t − K_p e + … vanishes), so that the speed returns
    without the overshoot of the wound-up integrator. Measured on both runs."""
    res = {}
    for aw in (True, False):
        tr = run(saturating_step(aw)).trajectory
        after = tr["t"] > 1.0
        w_ref = 4000 * RPM
        res[aw] = dict(x_max=tr["gov_integral"].max(), rack_max=tr["gov_rack"].max(),
                       overshoot=(tr["omega"][after].max() - w_ref) / w_ref,
                       dip=(tr["omega"].min() - w_ref) / w_ref)
    print({k: {n: f"{v:.4g}" for n, v in r.items()} for k, r in res.items()})
    assert res[True]["dip"] < -0.05 and res[False]["dip"] < -0.05  # both saturate
    assert res[True]["rack_max"] <= 1.0 and res[False]["rack_max"] <= 1.0
    assert res[True]["x_max"] <= 1.0 + 0.05  # held at the limit
    assert res[False]["x_max"] >= 1.5  # wound up
    assert res[False]["overshoot"] >= 3.0 * max(res[True]["overshoot"], 1e-3)


# ----------------------------------------------------------------------------------------------
# Fuel latching


def test_fuel_latched_exactly_at_each_cylinders_injection():
    """Each cylinder's fuel (``fuel_k``) is constant between its own injections and, from each,
    equals the command (``fuel``) at that instant. The 5° output grid holds every start of
    injection (local 345° → shaft 345°, 585°, 105° for cylinders 1–3); the sample there may show
    the state just before the event or just after it (the grid point and the breakpoint differ
    by rounding), so the latched value is read at the next sample beyond it."""
    sc = scene("gots_diesel_pi.toml", load={"schedule_time": [0.2, 0.2], "schedule_scale": [0.0, 1.0]},
               run={"t_end": 0.6})
    data = run(sc)
    tr, inj = data.trajectory, data.events["injection"]
    cycle, phases = sc.mechanism.cycle, np.radians([0.0, 240.0, 480.0])
    injection = sc.gas.injection
    assert injection == pytest.approx(math.radians(345.0), abs=1e-15)
    phi = tr["phi"]

    def distance(angles, k):  # to cylinder k's nearest start of injection [rad]
        local = np.mod(angles - phases[k] - injection, cycle)
        return np.minimum(local, cycle - local)

    n_changes = 0
    for k in range(3):
        fk = tr[f"fuel_{k + 1}"]
        at = np.flatnonzero(distance(phi, k) < 1e-9)  # samples on its injections
        ev = inj[distance(inj[:, 1], k) < 1e-7]
        assert ev.shape[0] == at.size  # one event per injection passed
        assert np.allclose(ev[:, 1], phi[at], rtol=0, atol=1e-12)
        for i in np.flatnonzero(np.diff(fk) != 0.0):  # a change: across one of its injections
            assert at[min(np.searchsorted(at, i), at.size - 1)] in (i, i + 1)
            n_changes += 1
        assert np.allclose(fk[at + 1], tr["fuel"][at], rtol=0, atol=1e-12)
    print(f"{inj.shape[0]} injection events, {n_changes} latched changes")
    assert n_changes >= 20  # the command moves after the step: every injection latches anew


# ----------------------------------------------------------------------------------------------
# Compiled path against the reference path


@pytest.mark.parametrize("case,sections", [
    pytest.param("gots_diesel_pi.toml",
                 dict(load={"schedule_time": [0.1, 0.1], "schedule_scale": [0.0, 1.0]},
                      governor={"gain_d": 0.02, "rate_limit": 5.0}, run={"t_end": 0.4}),
                 marks=pytest.mark.slow),
    ("gots_diesel_start_flyweight.toml", dict(
        starter={"torque": 0.0}, initial={"omega": 3550 * RPM},
        load={"fan": 0.6e-3, "schedule_time": [0.25, 0.25], "schedule_scale": [1.0, 2.0]},
        run={"t_end": 0.6})),
])
def test_governors_agree_with_the_reference_path(case, sections):
    """Both paths at rtol = atol = 1e-10: the final state (speed, governor states, latched fuels)
    and every governor event (sleeve stops and lift-offs, injections) in t and φ. The paths
    differ most on the PID with its rate limit (in its derivative filter), a kink both paths take
    by step-size control alone (the reference path takes the clipping of the demand so too; the
    compiled one switches it by events); bound 1e-6, above that difference."""
    solver = {"rtol": 1e-10, "atol": 1e-10}
    fast = run(scene(case, solver=solver, **sections))
    ref = run(scene(case, solver={**solver, "method": "scipy-DOP853"}, **sections))
    a, b = fast.trajectory, ref.trajectory
    names = ("omega", "fuel", "gov_integral", "gov_rack", "gov_filter", "sleeve_lift",
             "sleeve_speed", "fuel_1", "fuel_2", "fuel_3")
    worst = {}
    for n in names:
        if n in a:
            scale = max(1.0, abs(b[n][-1])) if n != "sleeve_lift" else 1e-3
            worst[n] = abs(a[n][-1] - b[n][-1]) / scale
    for ev in ("injection", "sleeve_stop", "sleeve_free"):
        assert (ev in fast.events) == (ev in ref.events), ev
        if ev in fast.events:
            assert fast.events[ev].shape == ref.events[ev].shape, ev
            worst[ev] = np.abs(fast.events[ev] - ref.events[ev]).max()
    print(case, {k: f"{v:.2g}" for k, v in worst.items()})
    if "sleeve_lift" in a:
        assert "sleeve_free" in fast.events and "sleeve_stop" in fast.events
    assert max(worst.values()) <= 1e-6


# ----------------------------------------------------------------------------------------------
# Flyweight governor


def flyweight_balance(g, w2, z):
    """Net static force on the sleeve (centrifugal less spring) from the scene's dimensions, with
    the mean of ω² for ω² [N] (the module's equation, written from the governor's geometry)."""
    cent = g.weights * g.weight_mass * g.arm_ratio * g.gear_ratio ** 2 * w2
    return cent * (g.radius + g.arm_ratio * z) - g.spring_preload - g.spring_rate * z


def test_flyweight_lifts_off_at_its_closed_form_speed_and_settles_on_its_characteristic():
    """From rest: the sleeve stays on its low stop until n_w m_w (a/b) i_g² ω² ρ₀ = F₀ (3600 rpm
    by the scene's choice of F₀), then governs. In the periodic steady state at the end, the cycle
    means of the centrifugal force and of the spring balance (the sleeve's mean acceleration and
    velocity vanish); what is left is the correlation of ω² and z within a cycle."""
    sc = scene("gots_diesel_start_flyweight.toml")
    data = run(sc)
    g, tr = sc.governor, data.trajectory
    w_lift = math.sqrt(g.spring_preload / (g.weights * g.weight_mass * g.arm_ratio
                                           * g.gear_ratio ** 2 * g.radius))
    first = data.events["sleeve_free"][0]
    i = int(np.argmin(np.abs(tr["t"] - first[0])))
    assert abs(w_lift / RPM - 3600.0) < 2.0  # the scene's stated choice
    on_stop = tr["t"] < first[0]
    assert np.all(tr["sleeve_lift"][on_stop] == 0.0) and np.all(tr["fuel"][on_stop] == 1.0)
    # ω at the event from the samples around it: cubic Hermite with ε = dω/dt
    j = np.searchsorted(tr["t"], first[0])
    around = slice(j - 1, j + 1)
    w_at = float(CubicHermiteSpline(tr["t"][around], tr["omega"][around],
                                    tr["epsilon"][around])(first[0]))
    print(f"lift-off at t = {first[0]:.6g} s, ω = {w_at / RPM:.6f} rpm (closed form "
          f"{w_lift / RPM:.6f}); sample {i}")
    assert tr["omega"][j - 1] < w_lift < tr["omega"][j]
    assert abs(w_at - w_lift) <= 1e-7 * w_lift
    cycle = sc.mechanism.cycle
    last = tr["phi"] >= tr["phi"][-1] - cycle
    t_last = tr["t"][last]
    # time means over the last cycle (trapezoid on the 5° samples; the integrands are smooth)
    mean = (lambda f: np.trapezoid(f[last], t_last) / (t_last[-1] - t_last[0]))
    z_mean, w2_mean = mean(tr["sleeve_lift"]), mean(tr["omega"] ** 2)
    residual = flyweight_balance(g, w2_mean, z_mean) / g.spring_preload
    print(f"steady: z = {z_mean * 1e3:.4f} mm, ω = {math.sqrt(w2_mean) / RPM:.2f} rpm, "
          f"force residual {residual:.2e} of F0")
    assert 0.0 < z_mean < g.travel
    assert abs(residual) <= 1e-3
