"""Wall heat transfer in the ODE (``[gas.woschni]``): the cylinder pressures of the closed
part are states of the compiled stepper (``transient.core.model.cylinder``).

Independent checks:
* with h = 0 (c1 = c2 = 0) the states integrate the Wiebe cycle again, so a run must reproduce the
  run on the tabulated Wiebe cycle (``transient.forces.wiebe``, solve_ivp at rtol 1e-12) — with
  latched fuel, whose cycle is the table's exactly;
* at a (nearly) constant speed, the pressure the stepper integrates over a closed part equals
  the numpy closed-cycle integration of ``transient.forces.woschni`` (solve_ivp, its own code);
* the shaft's work–energy balance closes and the two domains (crank angle, time) agree;
* the reference path (solve_ivp, ``transient.reference``) agrees with the compiled one.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from transient.assemble import build_model
from transient.run import integrate
from transient.verify.stress import balance_residual, base, put, scene_of


def woschni_scene(revolutions=20, **woschni) -> dict:
    """The Gots diesel with Wiebe combustion (cases/gots_diesel_wiebe.toml), fuel latched at 340°
    (so that each cycle burns one fuel level, as the table's cycles do), with wall heat."""
    d = base("gots_diesel_wiebe")
    put(d, "gas", injection_deg=340.0)
    put(d, "run", revolutions=revolutions)
    d["gas"]["woschni"] = dict(woschni)
    return d


def without_heat_model(d: dict) -> dict:
    d = dict(d, gas=dict(d["gas"]))
    del d["gas"]["woschni"]
    return d


def off_jumps(model, phi, width=1e-6):
    """Samples not on a breakpoint (where a pressure column holds either limit of a jump)."""
    bp = model.breakpoints
    d = np.abs(np.mod(np.subtract.outer(phi, bp) + model.period / 2, model.period) - model.period / 2)
    return d.min(axis=1) > width


def test_no_heat_transfer_reproduces_the_tabulated_wiebe_cycle():
    d = put(woschni_scene(20, c1=0.0, c2=0.0), "solver", rtol=1e-11, atol=1e-11)
    states = integrate(scene_of(d, "woschni-h0"))
    table = integrate(scene_of(without_heat_model(d), "wiebe-table"))
    a, b = states.trajectory, table.trajectory
    assert states.complete and table.complete
    assert np.array_equal(a["phi"], b["phi"])  # the same crank-angle grid
    e_omega = np.max(np.abs(a["omega"] - b["omega"])) / np.max(b["omega"])
    e_t = np.max(np.abs(a["t"] - b["t"])) / b["t"][-1]
    model, _, _ = build_model(scene_of(d, "woschni-h0"))
    keep = off_jumps(model, a["phi"])
    p_max = max(np.max(b[f"p_{k + 1}"]) for k in range(3))
    e_p = max(np.max(np.abs(a[f"p_{k + 1}"] - b[f"p_{k + 1}"])[keep]) for k in range(3)) / p_max
    print(f"h = 0, states against the table over 20 revolutions: ω {e_omega:.2e}, t {e_t:.2e}, "
          f"p {e_p:.2e} of p_max; steps {states.solver['nsteps']} against "
          f"{table.solver['nsteps']}")
    # (the table's own interpolation error is 1e-10 of p_max, the runs' rtol 1e-11)
    assert e_omega <= 1e-9 and e_t <= 1e-9 and e_p <= 1e-8


def test_heat_transfer_run_balances_and_both_domains_agree():
    d = woschni_scene(20)
    put(d, "solver", rtol=1e-10, atol=1e-10)
    angle = integrate(scene_of(d, "woschni-angle"))
    time = integrate(scene_of(put(d, "solver", domain="time"), "woschni-time"))
    ta, tt = angle.trajectory, time.trajectory
    for data in (angle, time):
        assert data.complete, data.message
        assert balance_residual(data.trajectory, 2) <= 1e-8
    e_t = abs(ta["t"][-1] - tt["t"][-1]) / ta["t"][-1]
    e_w = abs(ta["omega"][-1] - tt["omega"][-1]) / ta["omega"][-1]
    # the heat lost shows: a lower speed than without it after the same revolutions
    plain = integrate(scene_of(put(without_heat_model(d), "solver", domain="auto"), "plain"))
    drop = 1.0 - ta["omega"][-1] / plain.trajectory["omega"][-1]
    print(f"end of 20 revolutions, crank angle against time: t {e_t:.2e}, ω {e_w:.2e}; balance "
          f"{balance_residual(ta, 2):.1e} / {balance_residual(tt, 2):.1e}; speed {drop:.2%} "
          f"below the run without heat transfer")
    assert e_t <= 1e-7 and e_w <= 1e-7
    assert drop > 0.0


def constant_speed_scene(rpm: float, revolutions: float = 6.0, **woschni) -> dict:
    """Full fuel at a held speed: no governor, no pairs, no load, a 10⁶ kg m² flywheel (the net
    torque speeds it up by 5e-7 of itself over the run at 1000 rpm, 3e-8 at 4400 rpm)."""
    d = woschni_scene(revolutions, **woschni)
    for key in ("governor", "friction"):
        d.pop(key, None)
    put(d, "load", fan=0.0)
    put(d, "inertia", flywheel=1e6)
    put(d, "initial", omega_rpm=rpm, phi=0.0)
    return put(d, "solver", rtol=1e-11, atol=1e-11)


def numpy_closed_cycle(scene, omega):
    """The closed part of cylinder 1 by transient.forces.woschni (solve_ivp, rtol 1e-12)."""
    from transient.forces.woschni import WoschniParameters, closed_cycle
    from transient.scene.queries import clearance_volume

    mech, gas = scene.mechanism, scene.gas
    w, h = gas.wiebe, gas.woschni
    volume = mech.volume_function(clearance_volume(scene))
    params = WoschniParameters(bore=mech.bore, stroke=mech.stroke(), c1=h.c1, c2=h.c2,
                               wall_temperature=h.wall_temperature)
    cycle = closed_cycle(volume, p_a=gas.p_a, start=w.start, duration=w.duration,
                         fuel_mass=w.fuel_mass, woschni=params, omega=omega, a=w.a, m=w.m,
                         lhv=w.lhv, efficiency=w.efficiency, gamma=w.gamma,
                         gamma_slope=w.gamma_slope, gamma_t_ref=w.gamma_t_ref, t_a=w.t_a,
                         strokes=mech.strokes)
    return cycle, volume


@pytest.mark.parametrize("rpm", [1000.0, 4400.0])
def test_state_pressure_equals_the_numpy_closed_cycle(rpm):
    """Cylinder 1's second closed part (φ from 5π to 7π; its first starts at the run's start
    from the table's pressure) against the numpy integration at the run's speed, and the
    indicated loop work of the three cylinders over a cycle against closed work + pumping."""
    scene = scene_of(constant_speed_scene(rpm), "woschni-steady")
    data = integrate(scene)
    tr = data.trajectory
    omega = float(np.mean(tr["omega"]))
    swing = np.ptp(tr["omega"]) / omega
    cycle, volume = numpy_closed_cycle(scene, omega)
    inside = (tr["phi"] > 5 * math.pi + 1e-9) & (tr["phi"] < 7 * math.pi - 1e-9)
    x = tr["phi"][inside] - 4 * math.pi  # cylinder 1's local angle, unwrapped
    e_p = np.max(np.abs(tr["p_1"][inside] - cycle.pressure(x))) / cycle.p_max
    # loop work: one cycle of every cylinder, after each has closed its intake once (φ > 3.7π)
    i0, i1 = np.searchsorted(tr["phi"], [4 * math.pi, 8 * math.pi])
    assert tr["phi"][i0] == 4 * math.pi and tr["phi"][i1] == 8 * math.pi
    loop = (tr["W_gas"][i1] - tr["W_gas"][i0]) / 3
    gas = scene.gas
    v = volume(np.array([0.0, cycle.start, cycle.end, 4 * math.pi]))
    pumping = gas.p_intake * (v[1] - v[0]) + gas.p_exhaust * (v[3] - v[2])
    e_w = abs(loop - (cycle.work + pumping)) / abs(cycle.work)
    q_b = cycle.heat_released
    v_h = scene.mechanism.swept_volume()
    print(f"{rpm:g} rpm (swing {swing:.1e}): p against numpy {e_p:.2e} of p_max; loop work "
          f"{loop:.2f} J against {cycle.work + pumping:.2f} J ({e_w:.1e}); heat lost "
          f"{cycle.heat_lost:.1f} J of {q_b:.1f} J ({cycle.heat_lost / q_b:.3f}); p_i "
          f"{loop / v_h / 1e6:.3f} MPa, η_i {loop / (gas.wiebe.fuel_mass * gas.wiebe.lhv):.3f}")
    assert swing <= 1e-6  # (the numpy cycle turns at the mean speed)
    assert e_p <= 1e-8 and e_w <= 1e-8


@pytest.mark.slow
def test_compiled_agrees_with_the_reference_path():
    """The scene of cases/gots_diesel_woschni.toml (droop governor, latched fuel, two non-ideal
    pairs) for 4 revolutions: the compiled stepper against solve_ivp on the numpy twin
    (``transient.reference.twins.CylindersNumpy``, from transient.forces.woschni's functions)."""
    d = put(base("gots_diesel_woschni"), "run", revolutions=4)
    put(d, "solver", rtol=1e-10, atol=1e-10)
    compiled = integrate(scene_of(d, "woschni-compiled"))
    ref_d = put(dict(d, solver=dict(d["solver"])), "solver", method="scipy-DOP853",
                max_step_deg=0.5)
    reference = integrate(scene_of(ref_d, "woschni-reference"))
    a, b = compiled.trajectory, reference.trajectory
    assert compiled.complete and reference.complete
    e_t = abs(a["t"][-1] - b["t"][-1]) / b["t"][-1]
    e_w = abs(a["omega"][-1] - b["omega"][-1]) / b["omega"][-1]
    print(f"compiled against reference over 4 revolutions: t {e_t:.2e}, ω {e_w:.2e}; "
          f"{compiled.solver['nsteps']} against {reference.solver['nsteps']} steps")
    assert e_t <= 1e-8 and e_w <= 1e-8
