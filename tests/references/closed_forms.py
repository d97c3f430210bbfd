"""Closed forms and conservation laws that whole runs must meet.

* **Energy.** A coasting machine keeps ½J(φ)ω², and the time it takes for a turn is
  ∫√(J/2K) dφ: the phase is integrated, not only the energy (the swash plate of Antonyuk's
  example, whose J(φ) varies by about ±30 %). A driven compressor's motor work goes into the
  kinetic energy, the gas and the bearing's loss at every sample.
* **The ideal compressor cycle.** At a held speed the mean drive moment over a turn is the
  cylinders' work per turn over 2π: for identical cylinders z times the closed form
  n/(n − 1)·p_s·V_s·η_v·((p_d/p_s)^((n−1)/n) − 1).

* **The ideal mixed cycle** of the Gots engine (:mod:`.gots`): its closed-form loop work
  against a quadrature and against the gas table, and the mean indicated torque of a run.
"""
from __future__ import annotations

import dataclasses as dc
import functools
import math
import tomllib
from pathlib import Path

import numpy as np
from balances import closure
from sample_integrals import sample_integral_impl
from scene_texts import COMPRESSOR_GAS, SMALL
from scipy.integrate import quad

from transient.analysis.summary import summarize
from transient.assemble import build_model
from transient.core.model.forcing import inertia
from transient.core.model.work import work_array
from transient.run import integrate
from transient.scene import load_scene
from transient.scene.queries import gas_table
from transient.scene.read import scene_from_dict

from . import Comparison, Tolerance, case, gots

CASES = Path(__file__).resolve().parents[2] / "cases"


def coasting(name, revolutions=1000.0, rtol=1e-10):
    """A scene of ``cases/`` without gas, load and governor, coasting from 50 rad/s."""
    scene = load_scene(CASES / name)
    return dc.replace(scene, gas=dc.replace(scene.gas, model="none"),
                      load=dc.replace(scene.load, fan=0.0),
                      governor=dc.replace(scene.governor, model="none"),
                      initial=dc.replace(scene.initial, omega=50.0),
                      run=dc.replace(scene.run, revolutions=revolutions, t_end=float("inf")),
                      solver=dc.replace(scene.solver, rtol=rtol, atol=rtol * 1e-2))


@case("validation/test_swash_runs.py::test_coasting_conserves_kinetic_energy_and_phase")
def coasting_swash_plate():
    """1000 revolutions of the four-cylinder swash plate at rtol 10⁻¹⁰."""
    scene = coasting("swash_plate_4cyl.toml")
    tr = integrate(scene).trajectory
    energy = 0.5 * tr["J"] * tr["omega"] ** 2
    model, _, _ = build_model(scene)
    wk = work_array(model)
    K = energy[0]
    turn = quad(lambda p: np.sqrt(inertia(model, p, wk) / (2 * K)), 0, 2 * np.pi,
                epsabs=1e-16, epsrel=1e-13, limit=400)[0]
    why = "rtol 10⁻¹⁰ over 1000 revolutions"
    return [
        Comparison("variation of J(φ) over its mean", "the example's cross 13 and link 9",
                   "formula", None, float(np.ptp(tr["J"]) / tr["J"].mean()), "",
                   Tolerance(low=0.05, why="J(φ) must really vary for the check to bite")),
        Comparison("kinetic energy ½J(φ)ω² over its start, 1000 revolutions",
                   "conservation of energy: 1", "formula", np.ones(energy.size),
                   energy / energy[0], "", Tolerance(abs=1e-8, why=why),
                   at=np.degrees(tr["phi"])),
        Comparison("time of 1000 revolutions", "1000·∫√(J(φ)/2K) dφ (scipy quad of the "
                   "kernel's J)", "independent", 1000 * turn, float(tr["t"][-1]), "s",
                   Tolerance(rel=1e-9, why=why)),
    ]


#: A two-cylinder in-line air compressor on SMALL's crank (2-stroke: one cycle a turn), cranks
#: 180° apart, at a held 1500 rpm.
AIR_COMPRESSOR = SMALL.replace("bore_mm = 88\n", "bore_mm = 88\nstrokes = 2\ncylinders = 2\n"
                                                 "firing_order = [1, 2]\n").replace(
    "[initial]\nomega_rpm = 1000\n", "").replace(
    "[run]\nrevolutions = 2\n", '[run]\nmode = "prescribed-speed"\nspeed_rpm = 1500\n'
                                "revolutions = 3\n").replace(
    "samples_per_rev = 12", "samples_per_rev = 7200") + COMPRESSOR_GAS


def slope_jumps(table):
    """|dp/dx| jump at each corner of a pressure table [Pa/rad] (its kinks)."""
    corners = table.corners[:-1]
    i = np.arange(corners.size)
    right = table.evaluate(corners, i)[1]
    left = table.evaluate(np.where(i > 0, corners, table.period), (i - 1) % table.n_pieces)[1]
    return corners, np.abs(right - left)


@case("validation/test_compressor_runs.py::"
      "test_the_mean_drive_at_a_held_speed_is_the_closed_form_work_over_2pi")
def compressor_cycle():
    """The mean drive of the air compressor at 1500 rpm against z times the closed-form work
    over 2π. The summary's trapezoidal rule over samples h apart is exact for the smooth
    periodic part and off by at most |ΔM′|·h²/8 at each kink of the drive moment (a valve
    opening, where dp/dx jumps by Δp′ and M its slope by F_p·u·Δp′), plus the table's
    interpolation error: that bound is the tolerance."""
    scene = scene_from_dict(tomllib.loads(AIR_COMPRESSOR), file="air.toml")
    data = integrate(scene)
    if not data.complete:
        raise AssertionError(data.message)
    mech = scene.mechanism
    p_s, p_d, n, c, z = 1e5, 8e5, 1.3, 0.05, mech.n_cylinders
    v_s = mech.swept_volume()
    eta_v = 1 - c * ((p_d / p_s) ** (1 / n) - 1)
    work = n / (n - 1) * p_s * v_s * eta_v * ((p_d / p_s) ** ((n - 1) / n) - 1)
    want = z * work / (2 * math.pi)
    got = summarize(scene, data.trajectory)["mean_drive_torque_last_cycle"][0]
    table = gas_table(scene)
    _, jumps = slope_jumps(table)
    phi = np.linspace(0, 2 * math.pi, 3601)
    u_max = np.max(np.abs(np.gradient(mech.volume_function(0.0)(phi), phi))) / mech.piston_area
    h = 2 * math.pi / scene.output.samples_per_rev
    bound = z * np.sum(jumps) * mech.piston_area * u_max * h * h / 8 / (2 * math.pi)
    bound += 10 * table.interpolation_error * p_d * mech.piston_area * u_max * z
    return [
        Comparison("mean drive torque of a 2-cylinder air compressor at 1500 rpm",
                   "z·n/(n − 1)·p_s V_s η_v((p_d/p_s)^((n−1)/n) − 1)/2π", "formula", want, got,
                   "N·m", Tolerance(abs=bound, why="the trapezoid's error at the valves' kinks "
                                                   "and the table's interpolation error")),
        Comparison("that tolerance over the torque", "a sharp check", "formula", None,
                   bound / want, "", Tolerance(high=1e-5, why="the check must be sharp")),
    ]


@functools.cache
def compressor_run_up():
    """(scene, data) of ``cases/ac_compressor_7cyl.toml``: a wobble-plate A/C compressor run up
    from rest by an induction motor's torque curve."""
    scene = load_scene(CASES / "ac_compressor_7cyl.toml")
    data = integrate(scene)
    if not (data.complete and data.status == "finished"):
        raise AssertionError(data.message)
    return scene, data


@case("validation/test_compressor_runs.py::"
      "test_the_motors_work_goes_into_kinetic_energy_gas_and_bearing")
def compressor_energy():
    """W_motor = ΔK − W_gas + W_loss at every sample: the motor's work (its torque curve a
    negative load) goes into the kinetic energy, the gas and the plate bearing's loss."""
    scene, data = compressor_run_up()
    tr = data.trajectory
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    motor, gas, loss = tr["W_load"], -tr["W_gas"], tr["W_loss_1"]
    allowed = Tolerance(high=100 * scene.solver.rtol, why="100 × the solver's rtol")
    return [
        Comparison("work–energy balance of the A/C compressor's run-up, over W_motor",
                   "W_motor = ΔK + W_gas + W_loss", "formula", None,
                   float(np.max(np.abs(motor - (K - K[0] + gas + loss))) / motor[-1]), "",
                   allowed),
        Comparison("work–energy balance, over the run's largest energies",
                   "½J(φ)ω² − ½J₀ω₀² = W_gas + W_load − Σ W_loss", "formula", None,
                   closure(scene, tr), "", allowed),
    ]


@case("validation/test_mixed_cycle.py::test_loop_work")
def mixed_cycle_work():
    """The loop work of the ideal mixed cycle (``MixedCycle.work``, closed form) against an
    adaptive quadrature of the closed-form pressures and against ∮p dV of the tabulated
    pressure, for ρ = 1.671 (the isobar of П2.1) and the printed ρ = 1.699."""
    out = []
    for rho in (1.671, 1.699):
        mc = gots.cycle(rho)
        ends = mc.corners
        w_quad = sum(quad(lambda x, mc=mc: float(gots.exact_pressure(mc, x)) * float(gots.dvolume(x)),
                          a, b, epsabs=1e-12, epsrel=1e-13, limit=200)[0]
                     for a, b in zip(ends[:-1], ends[1:]))
        out += [
            Comparison(f"loop work ∮p dV, closed form, ρ = {rho}", "adaptive quadrature of the "
                       "cycle's polytropes (scipy quad)", "independent", w_quad, mc.work, "J",
                       Tolerance(rel=1e-11, why="the quadrature's tolerance")),
            Comparison(f"loop work of the gas table, ρ = {rho}", "the closed form", "formula",
                       mc.work, gots.table_loop_work(mc), "J",
                       Tolerance(rel=1e-8, why="the table's interpolation error ≤ 10⁻⁹ p_z")),
            Comparison(f"mean torque of one cylinder, ρ = {rho}", "W/4π", "formula",
                       mc.work / (4 * math.pi), mc.mean_torque, "N·m",
                       Tolerance(rel=1e-15, why="rounding")),
        ]
        if rho == 1.671:
            digest = "an independent computation of the same cycle (not in the book)"
            out += [Comparison("mean torque of three cylinders, ρ = 1.671", digest, "independent",
                               205.7, 3 * mc.mean_torque, "N·m",
                               Tolerance(abs=0.1, why="given to 0.1 N·m")),
                    Comparison("mean indicated pressure p_i′, ρ = 1.671", digest, "independent",
                               1.507, mc.mean_pressure / gots.MPA, "MPa",
                               Tolerance(abs=1e-3, why="given to 1 kPa"))]
    return out


@case("validation/test_gots_tables.py::test_mean_indicated_torque_of_the_ideal_cycle")
def mean_indicated_torque():
    """Through the stepper: the mean of −M_drive over a cycle of ``cases/gots_diesel_4400.toml``
    (inverse dynamics at the held 4400 rpm) is 3·W/(4π), W the closed-form loop work: the inertia
    torque ½J′ω² averages to zero over a turn and ∮p₀ dV = 0. The mean is taken with a
    local-polynomial rule between the breakpoints (the table's corners), where the torque has
    kinks: a plain trapezoid on the 0.25° grid is off by 4.5·10⁻⁶."""
    scene = load_scene(gots.SCENE)
    table = gas_table(scene)
    _, bp, _ = build_model(scene)
    tr = integrate(scene).trajectory
    period = 4.0 * math.pi
    if tr["phi"][-1] < period:
        raise AssertionError("the run ends before a whole cycle")
    mean = sample_integral_impl(tr["phi"], -tr["M_drive"],
                                np.concatenate([[0.0, period], bp])) / period
    return [Comparison("mean indicated torque of a run at 4400 rpm, 3 cylinders",
                       "3W/4π, W the mixed cycle's closed-form loop work", "formula",
                       3.0 * table.work / period, mean, "N·m",
                       Tolerance(rel=1e-6, why="the run's tables to 10⁻⁹, the quadrature "
                                               "of its samples to ~10⁻¹³"))]
