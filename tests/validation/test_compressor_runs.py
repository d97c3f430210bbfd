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

The energy balance and the closed-form cycle are cases of ``tests/references/closed_forms.py``,
which the Validation page renders.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from references import check_all, closed_forms

from transient.analysis.summary import summarize
from transient.mechanisms import swash_plate as sp
from transient.run import integrate
from transient.scene import Load
from transient.scene.queries import gas_phases, gas_table

RPM = math.pi / 30.0


@pytest.fixture(scope="module")
def run_up():
    return closed_forms.compressor_run_up()


def test_the_motors_work_goes_into_kinetic_energy_gas_and_bearing(run_up):
    check_all(closed_forms.compressor_energy())
    tr = run_up[1].trajectory
    assert tr["W_load"][-1] > 0 and -tr["W_gas"][-1] > 0 and tr["W_loss_1"][-1] > 0
    # the motor drives: its torque is the negative load, and it ran up from rest
    assert tr["omega"][0] == 0.0 and np.all(tr["M_load"] > 0.0)


def test_the_gas_takes_eta_of_the_motors_work_over_the_steady_cycles(run_up):
    scene, data = run_up
    a = {k: v for k, (v, _) in summarize(scene, data.trajectory, data.events).items()}
    eta = scene.friction.pairs[0].eta_forward
    assert a["driven"] == 1.0 and a["backward_share_1"] == 0.0
    assert a["eta_mech_work"] == pytest.approx(eta, rel=1e-9)
    assert a["W_out_per_cycle"] == pytest.approx(eta * a["W_in_per_cycle"], rel=1e-9)


def test_the_mean_drive_at_a_held_speed_is_the_closed_form_work_over_2pi():
    check_all(closed_forms.compressor_cycle())


def test_the_mean_drive_of_the_seven_cylinders_is_their_work_over_2pi_eta(run_up):
    """Each cylinder's ∮p dV_k = −∮V_k dp over its own piston travel x_D,k(φ) (the mechanism's
    positions, not the kernel's u_k), Gauss–Legendre on every table interval; the drive over a
    held turn integrated between the valves' kinks from the samples."""
    from sample_integrals import sample_integral_impl

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
