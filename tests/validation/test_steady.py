"""The periodic steady state by shooting (transient.steady; docs/guide/steady.md) against
independent checks: the last cycle of a long direct run that has settled to rounding, a
finite-difference monodromy of the direct run's own one-cycle map, the closed form of a linear
load's work balance, and the refusals."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import transient
from transient.assemble import build_model
from transient.cli import main
from transient.shooting import NoSteadyState

CASES = Path(__file__).resolve().parents[2] / "cases"
RTOL = 1e-12
#: Every column of the steady cycle against the settled run's last cycle, relative to the
#: column's largest magnitude over the cycle, with an absolute floor for a column that is zero
#: in exact arithmetic.
AGREE, FLOOR = 1e-9, 1e-12


def tight(scene, rtol=RTOL):
    return dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, rtol=rtol,
                                                                 atol=rtol * 1e-2))


def case(name: str):
    scene = transient.load_scene(CASES / f"{name}.toml")
    if scene.load.schedule_time:  # (the PI case's load programme: its full load, constant)
        scene = dataclasses.replace(scene, load=dataclasses.replace(
            scene.load, schedule_time=(), schedule_scale=()))
    return tight(scene)


def cycles_of(scene, n: float):
    """``scene`` run for ``n`` engine cycles from its initial state."""
    run = dataclasses.replace(scene.run, revolutions=n * scene.mechanism.cycle / (2 * math.pi),
                              t_end=math.inf)
    return dataclasses.replace(scene, run=run)


STEADY_CASES = {
    "constant-eta": "gots_diesel_friction",
    "reaction-friction": "gots_diesel_reaction_friction",
    "droop": "gots_diesel_governed",
    "pi": "gots_diesel_pi",
    "swash-plate": "swash_plate_4cyl_friction",
}


@pytest.mark.parametrize("label", STEADY_CASES)
def test_steady_cycle_is_the_settled_run_last_cycle(label):
    scene = case(STEADY_CASES[label])
    res = transient.steady(scene)
    mu = abs(res.analysis["steady_multiplier_max"][0])
    assert mu < 1.0
    # long enough for a disturbance of order 1 to die to rounding, at the rate the direct run
    # itself must show below
    n = int(math.ceil(math.log(1e-15) / math.log(max(mu, 1e-3)))) + 10
    direct = transient.simulate(cycles_of(scene, n)).trajectory
    cycle, p0 = scene.mechanism.cycle, scene.initial.phi
    phi = np.asarray(direct["phi"])
    starts = np.searchsorted(phi, p0 + cycle * np.arange(n + 1) - 1e-9)
    w = np.asarray(direct["omega"])[starts]
    change = np.abs(np.diff(w)) / w[-1]
    assert change[-3:].max() <= 1e-12, "the direct run has not settled"
    settled = int(np.flatnonzero(change > 1e-12)[-1]) + 2 if (change > 1e-12).any() else 1
    print(f"{label}: the direct run settles in {settled} cycles, shooting integrated "
          f"{res.analysis['steady_cycles_integrated'][0]} (multiplier {mu:.4g})")
    i0 = starts[-2]
    keep = np.r_[True, np.diff(phi[i0:]) > 1e-9]  # (the end's sample and row coincide)
    last = {k: np.asarray(v[i0:])[keep] for k, v in direct.items()}
    steady = res.trajectory
    assert last["t"].size == steady["t"].size
    _, bp, _ = build_model(scene)
    local = np.mod(np.asarray(steady["phi"]), scene.mechanism.cycle)
    on_corner = np.min(np.abs(local[:, None] - np.r_[bp, scene.mechanism.cycle]), axis=1) < 1e-9
    accumulated = ("t", "phi") + tuple(k for k in steady if k.startswith("W_"))
    for k in steady:
        a, b = np.asarray(steady[k]), last[k]
        if k in accumulated:  # (from zero at the steady cycle's start)
            a, b = a - a[0], b - b[0]
        if k.startswith("p_"):  # a pressure jumps at a table's corner: either side's value
            a, b = a[~on_corner], b[~on_corner]
        err = np.abs(a - b).max()
        assert err <= AGREE * np.abs(b).max() + FLOOR, (k, err, np.abs(b).max())


def one_cycle_speed(scene, omega: float) -> float:
    """The direct run's map: the speed after one cycle from ``omega`` at the initial angle."""
    start = dataclasses.replace(scene.initial, omega=omega)
    res = transient.simulate(cycles_of(dataclasses.replace(scene, initial=start), 1))
    return float(res.trajectory["omega"][-1])


@pytest.mark.parametrize("label", ["constant-eta", "reaction-friction", "droop"])
def test_multiplier_is_the_direct_map_derivative(label):
    """A scene whose one periodic state is the speed: the multiplier is dΦ/dω of the direct
    run's own one-cycle map, by central differences of its own step."""
    scene = case(STEADY_CASES[label])
    res = transient.steady(scene)
    assert res.analysis["steady_multipliers_real"][0].size == 1
    mu = res.analysis["steady_multipliers_real"][0][0]
    w = float(res.trajectory["omega"][0])
    h = 1e-4 * w
    fd = (one_cycle_speed(scene, w + h) - one_cycle_speed(scene, w - h)) / (2 * h)
    assert res.analysis["steady_multipliers_imag"][0][0] == 0.0
    assert abs(mu - fd) <= 1e-6, (mu, fd)
    # and the fixed point: the direct map returns the steady speed
    assert abs(one_cycle_speed(scene, w) - w) <= 1e-10 * w


LINEAR = """\
[scene]
name = "linear-load"
[mechanism]
type = "crank-slider"
crank_radius_mm = 47
rod_length_mm = 148
bore_mm = 88
piston_mass = 1.52
crank_mass = 0.912
[mechanism.rod]
model = "two-mass"
mass = 1.752
cg_from_pin_mm = 107.3
[inertia]
shaft = 0.05
[load]
torque = -20.0
linear = 0.1
[initial]
omega_rpm = 1000
[run]
revolutions = 4
[solver]
rtol = 1e-12
atol = 1e-14
[output]
samples_per_rev = 360
"""


def test_linear_load_mean_speed_closed_form(tmp_path):
    """A constant driving torque T against a load c·ω: over a steady cycle the work balance
    T·Θ = ∮ c·ω dφ gives the angle-mean speed T/c exactly, whatever J(φ)."""
    path = tmp_path / "linear.toml"
    path.write_text(LINEAR)
    res = transient.steady(transient.load_scene(path))
    phi = np.asarray(res.trajectory["phi"])
    w = np.asarray(res.trajectory["omega"])
    mean = np.trapezoid(w, phi) / (phi[-1] - phi[0])  # (periodic: the trapezoid is spectral)
    assert abs(mean - 20.0 / 0.1) <= 1e-9 * 200.0
    assert abs(w[-1] - w[0]) <= 1e-10 * w[0]


def test_refuses_a_scene_that_accelerates_for_ever(tmp_path):
    path = tmp_path / "runaway.toml"
    path.write_text(LINEAR.replace("linear = 0.1", "linear = 0.0"))
    with pytest.raises(NoSteadyState, match="accelerates for ever.*transient run"):
        transient.steady(transient.load_scene(path))


def test_refuses_a_scene_that_decelerates_for_ever(tmp_path):
    path = tmp_path / "brake.toml"
    path.write_text(LINEAR.replace("torque = -20.0", "torque = 20.0"))
    with pytest.raises(NoSteadyState, match="decelerates for ever"):
        transient.steady(transient.load_scene(path))


@pytest.mark.parametrize("table, key", [
    ("[load]\nschedule_time = [0.0, 1.0]\nschedule_scale = [1.0, 2.0]\n",
     "load.schedule_time"),
    ("[starter]\ntorque = 50\nnoload_speed_rpm = 300\ncutout_speed_rpm = 2000\n",
     "starter.torque"),
])
def test_refuses_a_time_dependent_scene_before_any_work(tmp_path, capsys, table, key):
    text = LINEAR.replace("[load]\ntorque = -20.0\nlinear = 0.1\n", "") + table
    if "[load]" not in table:
        text += "[load]\nlinear = 0.1\n"
    path = tmp_path / "timed.toml"
    path.write_text(text)
    out = tmp_path / "out.h5"
    code = main(["steady", str(path), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and f"{path}: {key}: " in err and "periodic" in err, err
    assert not out.exists()


def test_cli_writes_the_steady_cycles_and_refuses_to_overwrite(tmp_path, capsys):
    path = tmp_path / "linear.toml"
    path.write_text(LINEAR)
    out = tmp_path / "linear_steady.h5"
    assert main(["steady", str(path), "-o", str(out), "--cycles", "2", "-q"]) == 0
    res = transient.open_result(out)
    assert res.summary()["revolutions"] == pytest.approx(4.0)
    assert res.analysis["steady_residuals"][0].ndim == 1
    assert main(["steady", str(path), "-o", str(out), "-q"]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["info", str(out)]) == 0
    assert "steady_multiplier_max" in capsys.readouterr().out
