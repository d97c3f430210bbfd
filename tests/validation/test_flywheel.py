"""Flywheel sizing for a target δ (:mod:`transient.study.flywheel`, Gots §2.8).

* The flywheel returned for δ_target, put into the Gots diesel spin-up scene as it is (from
  1000 rpm, 1000 revolutions, its own solver): a fresh run, independent of the helper's own runs
  (which start at the operating point), must settle with δ over the last cycle within 2 % of the
  target (1 ‰ when the helper is asked for 1 ‰).
* Gots' closed form δ = ΔE_max/(J ω_m²) holds when J is constant: with a heavy flywheel (J(φ)
  varies by ±0.1 %) the estimate alone gives δ within 1 % of the target, and ΔE_max agrees with
  the excess work of M_gas + M_load − ½J′ω² from the constant-speed columns.
* The operating point of the fan load is where it absorbs the mean indicated torque, 4400 rpm.

Run with ``-s`` to see the estimates, the runs and their δ.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from transient.analysis.irregularity import cycle_means, fluctuation, steady_state_time
from transient.run import integrate, prescribed
from transient.scene import Load, Output, Run, load_scene
from transient.study.flywheel import flywheel_for_delta

CASES = Path(__file__).resolve().parents[2] / "cases"

SCENE = load_scene(CASES / "gots_diesel_spinup.toml")
RPM_4400 = 4400.0 * math.pi / 30.0


def fresh_delta(scene, flywheel, revolutions=None):
    """δ over the last cycle, last cycle-mean speed and steady-state time of the scene run as it is
    (its spin-up from 1000 rpm) with ``flywheel``, sampled every 0.5°."""
    s = replace(scene, inertia=replace(scene.inertia, flywheel=flywheel),
                output=Output(samples_per_rev=720))
    if revolutions is not None:
        s = replace(s, run=Run(revolutions=revolutions))
    data = integrate(s)
    assert data.complete, data.message
    tr = data.trajectory
    cycle = s.mechanism.cycle
    means, ends = cycle_means(tr["t"], tr["phi"], cycle, s.initial.phi)
    return (fluctuation(tr["t"], tr["phi"], tr["omega"], cycle, s.initial.phi), means[-1],
            steady_state_time(means, ends, rtol=1e-7))


@pytest.mark.parametrize("delta_target", [0.01, 0.02])
def test_flywheel_gives_target_delta_in_fresh_run(delta_target):
    res = flywheel_for_delta(SCENE, delta_target)
    assert res.converged
    assert 1 <= len(res.iterations) <= 3
    assert abs(res.delta / delta_target - 1.0) <= 0.01
    assert res.iterations[-1].delta_change < 1e-5  # the helper's runs ended in steady state
    delta, mean_speed, t_steady = fresh_delta(SCENE, res.flywheel)
    print(f"δ_target {delta_target}: estimate {res.estimate:.5f}, "
          f"flywheel {res.flywheel:.5f} kg m² after {len(res.iterations)} run(s); "
          f"helper δ {res.delta:.6f}, fresh run δ {delta:.6f} "
          f"({delta / delta_target - 1:+.2%}), steady from t = {t_steady:.2f} s")
    assert math.isfinite(t_steady)
    assert mean_speed == pytest.approx(res.speed, rel=1e-3)
    assert abs(delta / delta_target - 1.0) <= 0.02


def test_secant_refinement_to_tight_tolerance():
    """Asked for 1 ‰, the helper corrects the estimate (off by +0.42 %) by simulation."""
    res = flywheel_for_delta(SCENE, 0.01, rtol=1e-3)
    assert res.converged and len(res.iterations) >= 2
    assert res.iterations[0].flywheel == res.estimate
    assert res.flywheel > res.estimate  # the estimate leaves δ too large here
    delta, _, _ = fresh_delta(SCENE, res.flywheel)
    print(f"rtol 1e-3: flywheel {res.flywheel:.5f} kg m², {len(res.iterations)} runs, "
          f"fresh δ {delta:.7f}")
    assert abs(delta / 0.01 - 1.0) <= 1e-3


def test_operating_point_of_the_fan_load_is_4400_rpm():
    """The scene's fan law was sized to absorb the mean indicated torque at 4400 rpm."""
    res = flywheel_for_delta(SCENE, 0.02)
    assert res.speed == pytest.approx(RPM_4400, rel=1e-4)
    assert res.load == SCENE.load  # speed not given: the load is the scene's


def test_closed_form_with_constant_inertia():
    """Heavy flywheel: J(φ) = J̄(1 ± 0.1 %), and Gots' δ = ΔE_max/(J ω_m²) holds to < 1 %."""
    heavy = replace(SCENE, inertia=replace(SCENE.inertia, flywheel=2.0))
    delta_target = 0.002
    res = flywheel_for_delta(heavy, delta_target)
    # ΔE_max independently, from the constant-speed columns: E = ∫(M_gas + M_load − ½J′ω²) dφ.
    pr = prescribed(replace(heavy, run=Run(mode="prescribed-speed", speed=res.speed,
                                           revolutions=2.0),
                            output=Output(samples_per_rev=7200))).trajectory
    m_e = pr["M_gas"] + pr["M_load"] - 0.5 * pr["dJ_dphi"] * res.speed ** 2
    phi = pr["phi"]
    E = cumulative_trapezoid(m_e - np.trapezoid(m_e, phi) / (phi[-1] - phi[0]), phi, initial=0.0)
    assert np.ptp(pr["J"]) / pr["J"].mean() < 3e-3
    assert res.excess_work == pytest.approx(np.ptp(E), rel=1e-6)
    J_total = res.excess_work / (delta_target * res.speed ** 2)
    assert res.estimate == pytest.approx(J_total - res.inertia_rest, rel=1e-12)
    assert res.inertia_rest == pytest.approx(np.trapezoid(pr["J"], phi) / (phi[-1] - phi[0]) - 2.0,
                                                rel=1e-9)
    # τ = J/(2 K ω) ≈ 2 s ≈ 150 revolutions for the fan law: 3000 revolutions to settle.
    delta, mean_speed, t_steady = fresh_delta(heavy, res.estimate, revolutions=3000)
    assert math.isfinite(t_steady) and mean_speed == pytest.approx(res.speed, rel=1e-4)
    print(f"heavy flywheel: ΔE_max {res.excess_work:.2f} J, estimate {res.estimate:.4f} kg m², "
          f"fresh δ {delta:.7f} ({delta / delta_target - 1:+.3%})")
    assert abs(delta / delta_target - 1.0) <= 0.01


def test_given_speed_offsets_the_load():
    """At 3000 rpm the fan load absorbs less than the mean indicated torque: a constant torque is
    added so that the engine settles there, and δ is met in a fresh run at that speed."""
    w = 3000.0 * math.pi / 30.0
    res = flywheel_for_delta(SCENE, 0.01, speed=w)
    assert res.speed == w and res.load.torque > 0.0 and res.load.fan == SCENE.load.fan
    delta, mean_speed, _ = fresh_delta(replace(SCENE, load=res.load), res.flywheel)
    assert mean_speed == pytest.approx(w, rel=1e-3)
    assert abs(delta / 0.01 - 1.0) <= 0.02


@pytest.mark.parametrize("kwargs", [
    {"delta_target": 0.0}, {"delta_target": 0.5}, {"delta_target": -0.01},
    {"delta_target": math.nan}, {"delta_target": 0.01, "speed": -1.0},
    {"delta_target": 0.01, "speed": math.inf},
    {"delta_target": 0.01, "load": Load(fan=1e-3, schedule_revolutions=(0.0, 10.0),
                                        schedule_scale=(1.0, 0.5))},
    {"delta_target": 0.01, "load": Load(torque=100.0), "speed": RPM_4400},  # no restoring moment
    {"delta_target": 0.01, "load": Load()},  # nothing absorbs the engine's torque
    {"delta_target": 0.2},  # met without a flywheel (δ ≈ 0.086 with the mechanism alone)
])
def test_invalid_inputs(kwargs):
    with pytest.raises(ValueError):
        flywheel_for_delta(SCENE, **kwargs)


def test_prescribed_scene_is_rejected():
    scene = replace(SCENE, run=Run(mode="prescribed-speed", speed=RPM_4400, revolutions=2.0))
    with pytest.raises(ValueError):
        flywheel_for_delta(scene, 0.01)
