"""Compressors run: ``cases/ac_compressor_7cyl.toml`` (a wobble-plate A/C compressor run up from
rest by an induction motor's torque curve) and a two-cylinder in-line air compressor, against the
work–energy law and the closed form of the ideal compressor cycle.

* **Energy.** The motor's work (``W_load``, its torque curve a negative load) goes into the
  kinetic energy, the gas (``−W_gas``, the compressor's indicated work) and the plate bearing's
  loss: W_motor = ΔK − W_gas + W_loss at every sample, to the solver's tolerance.
* **Efficiency of a driven machine.** The plate bearing's η = 0.9 carries the motor's power
  forward all the time, so over the steady cycles the gas takes exactly 0.9 of the motor's work.
* **Drive at a prescribed speed.** At a constant speed the mean drive moment over a turn is the
  compressor's work per turn over 2π (over η with the bearing): for identical cylinders z times
  the closed form n/(n − 1)·p_s·V_s·η_v·((p_d/p_s)^((n−1)/n) − 1); for the seven cylinders of
  the swash plate, whose pistons each move a little differently (the Hooke joint), the sum of
  each cylinder's ∮p dV_k, integrated here from the mechanism's piston positions.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import closure
from scene_texts import COMPRESSOR_GAS, SMALL

from transient.analysis.summary import summarize
from transient.assemble import gas_phases, gas_table
from transient.mechanisms import swash_plate as sp
from transient.run import integrate
from transient.scene import Load, load_scene
from transient.scene.read import scene_from_dict

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0


@pytest.fixture(scope="module")
def run_up():
    scene = load_scene(CASES / "ac_compressor_7cyl.toml")
    data = integrate(scene)
    assert data.complete and data.status == "finished", data.message
    return scene, data


def test_the_motors_work_goes_into_kinetic_energy_gas_and_bearing(run_up):
    scene, data = run_up
    tr = data.trajectory
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    motor, gas, loss = tr["W_load"], -tr["W_gas"], tr["W_loss_1"]
    assert motor[-1] > 0 and gas[-1] > 0 and loss[-1] > 0
    residual = np.max(np.abs(motor - (K - K[0] + gas + loss))) / motor[-1]
    print(f"W_motor {motor[-1]:.6g} J = ΔK {K[-1] - K[0]:.6g} + W_gas {gas[-1]:.6g} + W_loss "
          f"{loss[-1]:.6g}; residual {residual:.2e} of W_motor")
    assert residual <= 100 * scene.solver.rtol
    assert closure(scene, tr) <= 100 * scene.solver.rtol
    # the motor drives: its torque is the negative load, and it ran up from rest
    assert tr["omega"][0] == 0.0 and np.all(tr["M_load"] > 0.0)


def test_the_gas_takes_eta_of_the_motors_work_over_the_steady_cycles(run_up):
    scene, data = run_up
    a = {k: v for k, (v, _) in summarize(scene, data.trajectory, data.events).items()}
    eta = scene.friction.pairs[0].eta_forward
    assert a["driven"] == 1.0 and a["backward_share_1"] == 0.0
    assert a["eta_mech_work"] == pytest.approx(eta, rel=1e-9)
    assert a["W_out_per_cycle"] == pytest.approx(eta * a["W_in_per_cycle"], rel=1e-9)


def slope_jumps(table):
    """|dp/dx| jump at each corner of a pressure table [Pa/rad] (its kinks)."""
    corners = table.corners[:-1]
    i = np.arange(corners.size)
    right = table.evaluate(corners, i)[1]
    left = table.evaluate(np.where(i > 0, corners, table.period), (i - 1) % table.n_pieces)[1]
    return corners, np.abs(right - left)


#: A two-cylinder in-line air compressor on SMALL's crank (2-stroke: one cycle a turn), cranks
#: 180° apart, at a held 1500 rpm.
AIR_COMPRESSOR = SMALL.replace("bore_mm = 88\n", "bore_mm = 88\nstrokes = 2\ncylinders = 2\n"
                                                 "firing_order = [1, 2]\n").replace(
    "[initial]\nomega_rpm = 1000\n", "").replace(
    "[run]\nrevolutions = 2\n", '[run]\nmode = "prescribed-speed"\nspeed_rpm = 1500\n'
                                "revolutions = 3\n").replace(
    "samples_per_rev = 12", "samples_per_rev = 7200") + COMPRESSOR_GAS


def test_the_mean_drive_at_a_held_speed_is_the_closed_form_work_over_2pi():
    import tomllib

    scene = scene_from_dict(tomllib.loads(AIR_COMPRESSOR), file="air.toml")
    data = integrate(scene)
    assert data.complete, data.message
    mech = scene.mechanism
    p_s, p_d, n, c, z = 1e5, 8e5, 1.3, 0.05, mech.n_cylinders
    v_s = mech.swept_volume()
    eta_v = 1 - c * ((p_d / p_s) ** (1 / n) - 1)
    work = n / (n - 1) * p_s * v_s * eta_v * ((p_d / p_s) ** ((n - 1) / n) - 1)
    want = z * work / (2 * math.pi)
    got = summarize(scene, data.trajectory)["mean_drive_torque_last_cycle"][0]
    # The summary's trapezoidal rule over samples h apart: exact for the smooth periodic part,
    # off by at most |ΔM′|·h²/8 at each kink of the drive moment (a valve opening, where dp/dx
    # jumps by Δp′ and M jumps its slope by F_p·u·Δp′), plus the table's interpolation error.
    table = gas_table(scene)
    corners, jumps = slope_jumps(table)
    phi = np.linspace(0, 2 * math.pi, 3601)
    u_max = np.max(np.abs(np.gradient(mech.volume_function(0.0)(phi), phi))) / mech.piston_area
    h = 2 * math.pi / scene.output.samples_per_rev
    bound = z * np.sum(jumps) * mech.piston_area * u_max * h * h / 8 / (2 * math.pi)
    bound += 10 * table.interpolation_error * p_d * mech.piston_area * u_max * z
    print(f"mean drive {got:.9g} N m against z·W/2π = {want:.9g}: {got - want:.2e} "
          f"(bound {bound:.2e})")
    assert abs(got - want) <= bound
    assert bound < 1e-5 * want  # (the check is a sharp one)


def test_the_mean_drive_of_the_seven_cylinders_is_their_work_over_2pi_eta(run_up):
    """Each cylinder's ∮p dV_k = −∮V_k dp over its own piston travel x_D,k(φ) (the mechanism's
    positions, not the kernel's u_k), Gauss–Legendre on every table interval; the drive over a
    held turn integrated between the valves' kinks from the samples."""
    from conftest import sample_integral_impl

    base, _ = run_up
    speed = 1460 * RPM  # (held by the test bench's drive instead of the motor)
    scene = replace(base, load=Load()).replace(
        run={"mode": "prescribed-speed", "speed": speed, "revolutions": 2},
        output={"samples_per_rev": 3600}, analysis={"thermodynamics": False})
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    eta = scene.friction.pairs[0].eta_forward
    assert np.all(tr["eta_1"] == eta)  # the bearing carries the drive forward throughout
    mech, table = scene.mechanism, gas_table(scene)
    xg, wg = np.polynomial.legendre.leggauss(8)
    a, b = table.knots[:-1], table.knots[1:]
    x = (0.5 * (a + b))[:, None] + 0.5 * (b - a)[:, None] * xg[None, :]
    piece = np.searchsorted(table.piece_knot, np.arange(a.size), side="right") - 1
    _, dp = table.evaluate(x, np.broadcast_to(piece[:, None], x.shape))
    works = []
    for k, phase in enumerate(gas_phases(scene)):
        travel = sp.positions(mech, (x + phase).ravel())["D"][:, 0, k, 0].reshape(x.shape)
        works.append(-float(np.sum(0.5 * (b - a)[:, None] * wg * mech.piston_area * travel * dp)))
    works = np.array(works)
    want = -works.sum() / (2 * math.pi) / eta
    phi = tr["phi"]
    last = phi >= phi[-1] - 2 * math.pi - 1e-9
    cuts = np.concatenate([[phi[-1] - 2 * math.pi, phi[-1]], phi[-1] - 2 * math.pi + np.mod(
        np.add.outer(gas_phases(scene), table.corners).ravel(), 2 * math.pi)])
    got = sample_integral_impl(phi[last], tr["M_drive"][last], cuts) / (2 * math.pi)
    print(f"cylinders' ∮p dV: {np.array2string(works, precision=5)} J (closed form "
          f"{table.work:.5f}); mean drive {got:.9g} against {want:.9g} N m")
    assert got == pytest.approx(want, rel=1e-7)
    # cylinder 1's travel is the cycle's own volume: its work is the closed form
    assert works[0] == pytest.approx(table.work, rel=1e-8)
