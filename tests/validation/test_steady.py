"""The periodic steady state by shooting (transient.steady; docs/guide/steady.md) against
independent checks: the last cycle of a long direct run that has settled to rounding, a
finite-difference monodromy of the direct run's own one-cycle map, the closed form of a linear
load's work balance, and the refusals."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scene_texts import SMALL

import transient
from transient.analysis.efficiency import mechanical_efficiency
from transient.analysis.orders import run_orders
from transient.assemble import build_model
from transient.cli import main
from transient.shooting import NoSteadyState
from transient.verify.steady import bench_scene, cycle_starts, cycles_of

RTOL = 1e-12
#: Every column of the steady cycle against the settled run's last cycle, relative to the
#: column's largest magnitude over the cycle, with an absolute floor for a column that is zero
#: in exact arithmetic.
AGREE, FLOOR = 1e-9, 1e-12


STEADY_CASES = {
    "constant-eta": "gots_diesel_friction",
    "reaction-friction": "gots_diesel_reaction_friction",
    "droop": "gots_diesel_governed",
    "pi": "gots_diesel_pi",
    "swash-plate": "swash_plate_4cyl_friction",
    "elastic": "inline6_damper",
}
#: The elastic line's at a looser tolerance (a cycle of it costs a hundred of a rigid scene's):
#: agreement then to its direct run's own scatter (SETTLED).
RTOLS = {"elastic": 1e-9}
#: Columns of a neutral state (a damper ring's twist: any value repeats, so the direct run's is
#: where its transient left it): compared from their value at the cycle's start.
NEUTRAL_COLUMNS = {"elastic": ("twist_pulley_damper",)}


#: How far the direct run's cycle-start speed may still move from cycle to cycle once settled:
#: rounding, but for reaction friction, whose jumps (the slider's Coulomb friction turning at
#: the dead centres, the pairs' side forces changing side; located by retaken steps) make the
#: cycle map itself noisy at rtol 1e-12: there the direct run is a reference only to its own
#: scatter from cycle to cycle, which then sets the agreement where it exceeds AGREE (it does
#: nowhere else).
SETTLED = {"reaction-friction": 1e-9, "elastic": 1e-8}
#: The direct run's last cycles whose scatter is measured.
SCATTER_CYCLES = 6


def direct_cycles(scene, n: int) -> list[dict[str, np.ndarray]]:
    """The last SCATTER_CYCLES + 1 cycles of a direct run of ``n`` cycles, each its samples
    from its start to its end (the end's sample and row, which coincide, once)."""
    direct = transient.simulate(cycles_of(scene, n)).trajectory
    starts = cycle_starts(scene, direct, n)
    cycles = []
    for j in range(n - SCATTER_CYCLES - 1, n):
        rows = np.arange(starts[j], starts[j + 1] + 1)
        cycles.append({k: np.asarray(v)[rows] for k, v in direct.items()})
    return cycles, np.asarray(direct["omega"])[starts]


def on_corners(scene, phi) -> np.ndarray:
    """The samples where a column may jump, and either side's value is right: a table's corner
    (a pressure table's point) and each piston's dead centres, where it stops (the slider's
    Coulomb friction turns there, and so ε and the losses of reaction friction jump)."""
    cycle = scene.mechanism.cycle
    model, bp, _ = build_model(scene)
    corners = np.mod(np.r_[bp, model.gas_phase, model.gas_phase + math.pi], cycle)
    gap = np.abs(np.mod(phi, cycle)[:, None] - corners[None, :])
    return np.min(np.minimum(gap, cycle - gap), axis=1) < 1e-9


def compared(scene, cycle: dict, mask, neutral=()) -> dict[str, np.ndarray]:
    """A cycle's columns as compared: the accumulated ones (t, φ, the works and losses) and
    the ``neutral`` ones from zero at its start, the samples on a corner left out."""
    out = {}
    for k, v in cycle.items():
        if k in ("t", "phi") or k.startswith("W_") or k in neutral:
            v = v - v[0]
        out[k] = v[~mask]
    return out


@pytest.mark.parametrize("label", STEADY_CASES)
def test_steady_cycle_is_the_settled_run_last_cycle(label):
    scene = bench_scene(STEADY_CASES[label], RTOLS.get(label, RTOL))
    res = transient.steady(scene)
    mu = abs(res.analysis["steady_multiplier_max"][0])
    assert mu < 1.0
    neutral = NEUTRAL_COLUMNS.get(label, ())
    assert ("steady_neutral_states" in res.analysis) == bool(neutral)
    # long enough for a disturbance of order 1 to die to rounding, at the rate the direct run
    # itself must show below
    n = max(int(math.ceil(math.log(1e-15) / math.log(max(mu, 1e-3)))), 20) + 10
    cycles, starts = direct_cycles(scene, n)
    change = np.abs(np.diff(starts)) / starts[-1]
    floor = SETTLED.get(label, 1e-12)
    assert change[-SCATTER_CYCLES:].max() <= floor, "the direct run has not settled"
    settled = int(np.flatnonzero(change > floor)[-1]) + 2 if (change > floor).any() else 1
    print(f"{label}: the direct run settles in {settled} cycles, shooting integrated "
          f"{res.analysis['steady_cycles_integrated'][0]} (multiplier {mu:.4g})")
    steady = {k: np.asarray(v) for k, v in res.trajectory.items()}
    assert cycles[-1]["t"].size == steady["t"].size
    if "eta_mech_work" in res.analysis or scene.friction.pairs:
        # the summary's η_mech over the steady cycle, as the settled run's last cycles have it
        # (to their own scatter, added up as the columns' below)
        etas = [mechanical_efficiency(scene, c, window=(float(c["phi"][0]),
                                                        float(c["phi"][-1]), 1))
                ["eta_mech_work"][0] for c in cycles]
        eta_scatter = float(np.abs(np.diff(etas)).max())
        eta = res.analysis["eta_mech_work"][0]
        assert abs(eta - etas[-1]) <= max(AGREE, eta_scatter / (1.0 - mu)) + FLOOR, (
            eta, etas[-1], eta_scatter)

    mask = on_corners(scene, steady["phi"])
    assert np.count_nonzero(~mask) >= 0.7 * mask.size  # (most samples compared)
    ours = compared(scene, steady, mask, neutral)
    theirs = [compared(scene, c, mask, neutral) for c in cycles]
    for k in steady:
        scale = np.abs(theirs[-1][k]).max()
        scatter = max(np.abs(a[k] - b[k]).max() for a, b in zip(theirs[1:], theirs[:-1]))
        err = np.abs(ours[k] - theirs[-1][k]).max()
        # (a disturbance the size of the run's own scatter in every cycle, each dying by μ a
        # cycle, adds up to scatter/(1 − μ): as far as either can be from the other)
        assert err <= max(AGREE * scale, scatter / (1.0 - mu)) + FLOOR, (k, err, scale, scatter)
        if label not in SETTLED:  # (settled to rounding: the agreement is AGREE's)
            assert scatter / (1.0 - mu) <= AGREE * scale + FLOOR, (k, scatter)


def one_cycle_speed(scene, omega: float) -> float:
    """The direct run's map: the speed after one cycle from ``omega`` at the initial angle."""
    start = dataclasses.replace(scene.initial, omega=omega)
    res = transient.simulate(cycles_of(dataclasses.replace(scene, initial=start), 1))
    return float(res.trajectory["omega"][-1])


@pytest.mark.parametrize("label", ["constant-eta", "reaction-friction", "droop"])
def test_multiplier_is_the_direct_map_derivative(label):
    """A scene whose one periodic state is the speed: the multiplier is dΦ/dω of the direct
    run's own one-cycle map, by central differences of its own step."""
    scene = bench_scene(STEADY_CASES[label])
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


#: A single cylinder, unfired, driven by a constant torque against a load linear in ω.
LINEAR = SMALL.replace("rtol = 1e-6\natol = 1e-8", "rtol = 1e-12\natol = 1e-14").replace(
    "samples_per_rev = 12", "samples_per_rev = 360") + "\n[load]\ntorque = -20.0\nlinear = 0.1\n"


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
    ("[starter]\ntorque = 50\nnoload_speed_rpm = 3000\ncutout_speed_rpm = 2000\n",
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


def test_refuses_an_unstable_steady_state_a_governor_that_hunts():
    """A PI governor with a large integral gain and a slow actuator: Newton finds the periodic
    state, the multipliers put it outside the unit circle, and the direct run indeed never
    settles there (its cycle-start speed still swings after 100 cycles)."""
    scene = bench_scene("gots_diesel_pi")
    scene = dataclasses.replace(scene, governor=dataclasses.replace(
        scene.governor, gain_i=400.0, actuator_time=0.05))
    with pytest.raises(NoSteadyState, match=r"is unstable: the multiplier .* ≥ 1\) .*hunts") as e:
        transient.steady(scene)
    assert abs(e.value.record.multipliers[0]) > 1.0
    _, starts = direct_cycles(scene, 100)
    assert np.abs(np.diff(starts[-10:])).max() > 1e-3 * starts[-1]


def test_orders_and_loads_at_the_point_read_the_steady_cycle(tmp_path, capsys):
    """The analyses of an operating point from the steady cycle, not a long settle: its order
    spectrum of ω is the settled direct run's last cycle's, and ``transient orders`` and
    ``transient loads`` read the steady result file as a run's."""
    scene = bench_scene(STEADY_CASES["constant-eta"], RTOL)
    res = transient.steady(scene, tmp_path / "point.h5")
    settled = transient.simulate(cycles_of(scene, 200))  # (μ²⁰⁰ < 1e-11)
    ours = run_orders(scene, res.trajectory, 720).omega.coef[-1]
    theirs = run_orders(scene, settled.trajectory, 720).omega.coef[-1]
    assert abs(ours[0] - theirs[0]) <= AGREE * abs(theirs[0])  # (the cycle's mean speed)
    # (the harmonics to the stepper's tolerance of the speed they ride on)
    assert np.abs(ours[1:] - theirs[1:]).max() <= 100 * RTOL * abs(theirs[0])
    assert np.abs(theirs[1:]).max() > 1e-3 * abs(theirs[0])  # (there are harmonics to compare)
    for command in ("orders", "loads"):
        assert main([command, str(tmp_path / "point.h5"), "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    assert (tmp_path / "point_orders.csv").stat().st_size > 0
    assert (tmp_path / "point_loads.csv").stat().st_size > 0
