"""Operating points on a dynamometer (transient.study.dynamometer, `transient efficiency
--steady`; docs/guide/steady.md) against independent checks: a direct run of the same scene
with the same brake torque, settled; the requested mean speed; the prescribed-speed study as
the flywheel grows (its infinite-flywheel limit); a point the fuel cannot hold; the CLI's
refusals."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import transient
from transient.analysis.efficiency import mechanical_efficiency
from transient.analysis.irregularity import fluctuation
from transient.cli import main
from transient.study.dynamometer import NoOperatingPoint, held_point, point_row
from transient.study.efficiency import study_point

CASES = Path(__file__).resolve().parents[2] / "cases"
GOTS = CASES / "gots_diesel_friction.toml"


def gots(rtol: float, flywheel_scale: float = 1.0):
    scene = transient.load_scene(GOTS)
    inertia = dataclasses.replace(scene.inertia, flywheel=scene.inertia.flywheel * flywheel_scale)
    return dataclasses.replace(scene, inertia=inertia, solver=dataclasses.replace(
        scene.solver, rtol=rtol, atol=rtol * 1e-2))


def last_cycle(scene, traj) -> dict:
    """η_mech, FMEP per pair, δ and the time-mean speed of a run's last whole cycle."""
    cycle = scene.mechanism.cycle
    phi, t = np.asarray(traj["phi"]), np.asarray(traj["t"])
    n = math.floor((phi[-1] - scene.initial.phi) / cycle + 1e-9)
    a = scene.initial.phi + (n - 1) * cycle
    eff = {k: v for k, (v, _) in mechanical_efficiency(scene, dict(traj),
                                                       window=(a, a + cycle, 1)).items()}
    ta, tb = np.interp([a, a + cycle], phi, t)
    sel = (phi >= a - 1e-12) & (phi <= a + cycle + 1e-12)
    eff["delta"] = fluctuation(t[sel], phi[sel], np.asarray(traj["omega"])[sel], cycle, a)
    eff["rpm_mean"] = cycle / (tb - ta) * 30.0 / math.pi
    return eff


#: The direct run's check: the Gots diesel without its flywheel at 6000 rpm, where a constant
#: brake holds the point stably (its cycle map's multiplier ≈ 0.983: a disturbance decays by
#: e⁻¹ in ~60 cycles, so DIRECT_CYCLES settle the start's few % to below 1e-10). At rtol 1e-10
#: the steady state repeats to ≤ rtol·|x| per cycle, so it lies within rtol/(1 − μ) ≈ 6e-9 of
#: the exact one; AGREE allows ten times that on every quantity.
DIRECT_RTOL, DIRECT_CYCLES, AGREE = 1e-10, 1500, 1e-7


def test_a_held_point_agrees_with_a_settled_direct_run_under_its_brake():
    scene = gots(DIRECT_RTOL, flywheel_scale=0.0)
    omega = 6000 * math.pi / 30
    point = held_point(scene, omega, 1.0, samples_per_rev=72)
    steady = point_row(point)
    # the direct run: the bench scene (the same brake torque) from the same initial state,
    # integrated cycle after cycle as `transient run` does
    run = dataclasses.replace(point.scene.run, t_end=math.inf,
                              revolutions=DIRECT_CYCLES * scene.mechanism.cycle / (2 * math.pi))
    direct_scene = dataclasses.replace(point.scene, run=run)
    direct = last_cycle(direct_scene, transient.simulate(direct_scene).trajectory)
    assert direct["rpm_mean"] == pytest.approx(6000.0, rel=AGREE)
    for name in ("eta_mech_work", "fmep", "fmep_1", "fmep_2", "imep", "bmep", "delta"):
        assert direct[name] == pytest.approx(steady[name], rel=AGREE), name
    # and the point's own record: few cycles, converged
    assert point.cycles <= 12 and point.residuals[-1] <= 1.0


def test_the_point_turns_at_the_requested_mean_speed():
    """The steady cycle's duration gives the time-mean speed asked for, to the tolerance the
    shooting meets (a residual ≤ 1 in units of atol + rtol·ω̄) and the rounding of the output
    cycle's own integration (a few rtol)."""
    rtol = 1e-8
    scene = gots(rtol)
    for rpm, fuel in ((1200.0, 1.0), (3500.0, 0.4)):
        point = held_point(scene, rpm * math.pi / 30, fuel, samples_per_rev=72)
        t = np.asarray(point.result.trajectory["t"])
        mean = scene.mechanism.cycle / (t[-1] - t[0]) * 30 / math.pi
        assert mean == pytest.approx(rpm, rel=10 * rtol, abs=0.0)
        assert point.residuals[-1] <= 1.0
        # the brake torque balances the cycle's work: T·cycle = W_out (the brake takes it all)
        w_out = point_row(point)["W_out_per_cycle"]
        assert point.brake_torque * scene.mechanism.cycle == pytest.approx(w_out, rel=1e-6)


def test_a_heavier_flywheel_approaches_the_prescribed_speed_study():
    """The prescribed-speed study is the infinite-flywheel limit: as the flywheel grows ×10 and
    ×100, δ falls as 1/J and the steady η_mech's distance from the study's with it."""
    rows = [(study_point(gots(1e-8, k), "power-flow", 1.0, 2000.0, 72, steady=True),
             study_point(gots(1e-8, k), "power-flow", 1.0, 2000.0, 72, steady=False))
            for k in (1.0, 10.0, 100.0)]
    gaps = [abs(s["eta_mech_work"] - p["eta_mech_work"]) for s, p in rows]
    deltas = [s["delta"] for s, _ in rows]
    assert gaps[0] > 1e-3  # (the real flywheel's point differs from the limit's)
    assert gaps[1] < gaps[0] / 5 and gaps[2] < gaps[1] / 5 and gaps[2] < 1e-4
    assert deltas[1] < deltas[0] / 5 and deltas[2] < deltas[1] / 5


def test_a_fuel_too_low_for_the_friction_is_reported_in_its_row():
    """At 2 % fuel the gas work does not cover the pairs' losses: a brake cannot hold the
    point (it would have to drive). The prescribed-speed study, a separate model, agrees: its
    drive torque puts work in (W_out < 0)."""
    scene = gots(1e-8)
    with pytest.raises(NoOperatingPoint, match="would have to drive the engine"):
        held_point(scene, 2000 * math.pi / 30, 0.02, samples_per_rev=72)
    row = study_point(scene, "power-flow", 0.02, 2000.0, 72, steady=True)
    assert "would have to drive the engine" in row["note"] and "eta_mech_work" not in row
    assert study_point(scene, "power-flow", 0.02, 2000.0, 72)["W_out_per_cycle"] < 0.0


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_steady_study_writes_its_table_and_figures(tmp_path, capsys):
    code, out, err = cli(capsys, "efficiency", GOTS, "--steady", "--rpm", "1500,3000",
                         "--fuel", "1,0.02", "--samples-per-rev", "72", "-o", tmp_path)
    assert (code, err) == (0, "")
    csv = (tmp_path / "gots_diesel_friction_steady_efficiency.csv").read_text().splitlines()
    header = csv[0].split(",")
    assert header[11:15] == ["rpm_mean", "delta", "brake_torque", "cycles_integrated"]
    rows = [dict(zip(header, line.split(",", len(header) - 1))) for line in csv[1:]]
    held = [r for r in rows if r["fuel"] == "1"]
    assert all(float(r["rpm_mean"]) == pytest.approx(float(r["rpm"]), rel=1e-6) for r in held)
    assert all(0 < float(r["delta"]) < 1 and float(r["brake_torque"]) > 0 for r in held)
    low = [r for r in rows if r["fuel"] == "0.02"]
    assert len(low) == 2 and all(r["eta_mech_work"] == "nan" for r in low)
    assert all("would have to drive" in r["note"] for r in low)
    assert "NaN at 1500 rpm, fuel 0.02" in out
    for figure in ("efficiency", "friction_budget", "efficiency_map", "delta_map"):
        assert (tmp_path / f"gots_diesel_friction_steady_{figure}.png").stat().st_size > 10_000
    # nothing overwritten without --force, refused before any work
    code, out, err = cli(capsys, "efficiency", GOTS, "--steady", "--rpm", "1500",
                         "-o", tmp_path)
    assert code == 2 and out == "" and "--force" in err and err.count("\n") == 1


@pytest.mark.parametrize("argv, key", [
    (["--rpm", "12"], "--rpm"),  # below the crank-angle range of the cycle map
    (["--scheduler", "nowhere"], "--scheduler"),
    (["--workers", "2"], "--workers"),  # (without --scheduler local)
    (["--fuel", "1.5"], "--fuel"),
])
def test_steady_study_refuses_bad_input_before_any_work(tmp_path, capsys, argv, key):
    code, out, err = cli(capsys, "efficiency", GOTS, "--steady", *argv, "-o", tmp_path)
    assert code == 2 and out == "" and err.count("\n") == 1 and key in err, err
    assert not any(tmp_path.iterdir())


def test_steady_study_refuses_a_scene_that_cannot_be_periodic(tmp_path, capsys):
    """A starter still engaged at the lowest speed asked for changes the cycle once it cuts
    out: refused with its key, before any work."""
    text = GOTS.read_text().replace("[initial]\n", "[starter]\ntorque = 50\ncutout_speed = 200\n"
                                                   "noload_speed = 300\n\n[initial]\n")
    path = tmp_path / "started.toml"
    path.write_text(text)
    out_dir = tmp_path / "out"
    code, out, err = cli(capsys, "efficiency", path, "--steady", "--rpm", "1000,3000",
                         "-o", out_dir)
    assert code == 2 and out == "" and "starter.torque" in err and err.count("\n") == 1
    assert not out_dir.exists()


# --- sweep points marked steady (sweep.steady = true) ----------------------------------------

def test_steady_sweep_points_agree_with_settled_direct_runs(tmp_path):
    """Each point of a steady sweep (the Gots diesel on its own fan load, two flywheels)
    against the last cycle of a direct run of the same scene settled over 600 revolutions (its
    fan load contracts a disturbance a hundredfold in well under a hundred cycles): mean speed,
    δ, η_mech and FMEP within AGREE at rtol 1e-10. A mended sweep computes the points again
    when they change kind (stored direct runs are not steady states)."""
    scene = gots(DIRECT_RTOL)
    axes = {"inertia.flywheel": [0.05, 0.15]}
    collect = ["mean_speed_rpm", "delta", "eta_mech", "fmep_kPa"]
    swept = transient.sweep(scene, axes, collect=collect, scheduler="serial", steady=True,
                            output=tmp_path, name="fly")
    table = swept.table.columns
    assert table["status"].tolist() == ["finished", "finished"]
    for k, flywheel in enumerate(axes["inertia.flywheel"]):
        sc = dataclasses.replace(scene, inertia=dataclasses.replace(scene.inertia,
                                                                    flywheel=flywheel))
        direct = last_cycle(sc, transient.simulate(sc).trajectory)
        assert table["mean_speed_rpm"][k] == pytest.approx(direct["rpm_mean"], rel=AGREE)
        assert table["delta"][k] == pytest.approx(direct["delta"], rel=AGREE)
        assert table["eta_mech"][k] == pytest.approx(direct["eta_mech_work"], rel=AGREE)
        assert table["fmep_kPa"][k] == pytest.approx(direct["fmep"] / 1e3, rel=AGREE)
        # the point is one steady cycle, found in a few
        res = swept.run(k)
        assert res.analysis["steady_cycles_integrated"][0] < 20
        del res  # (closes the sweep file, which the mending below opens)
    again = transient.sweep(scene, axes, collect=collect, scheduler="serial", steady=False,
                            output=tmp_path, name="fly")
    assert again.reused == [] and sorted(again.computed) == [0, 1]


def test_a_steady_sweep_refuses_a_point_that_cannot_be_periodic(tmp_path):
    """A load programme changes the load from cycle to cycle: refused with the run and the key,
    before any work."""
    scene = gots(1e-8)
    scene = dataclasses.replace(scene, load=dataclasses.replace(
        scene.load, schedule_time=(0.0, 1.0), schedule_scale=(1.0, 0.5)))
    with pytest.raises(transient.SceneError, match=r"run 0 .*load\.schedule_time"):
        transient.sweep(scene, {"inertia.flywheel": [0.1, 0.2]}, scheduler="serial",
                        steady=True, output=tmp_path)
    assert not (tmp_path / f"{scene.name}.sweep.h5").exists()
