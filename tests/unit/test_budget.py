"""Bounded work: a run's output, analysis grid and steps are estimated before any work, and a
scene beyond its budgets, or one that could not advance, is one line naming the key (exit 2),
through ``check`` and ``run`` alike, with no result written."""
from __future__ import annotations

import math

import pytest
from scene_texts import SMALL

from transient.cli import main
from transient.scene import load_scene
from transient.scene.budget import RTOL_MIN, estimate
from transient.scene.outputs import output_columns


def text(old: str | tuple, new: str | tuple) -> str:
    """SMALL with one exact fragment (or each of a tuple) replaced."""
    out = SMALL
    for o, n in zip(*((old, new) if isinstance(old, tuple) else ((old,), (new,)))):
        assert out.count(o) == 1, o
        out = out.replace(o, n)
    return out


def test_the_estimate_of_a_small_run():
    """2 revolutions at 12 samples a revolution, one more for the start; max_step π: 4 steps."""
    scene = load_scene("small.toml", text=SMALL)
    work = estimate(scene)
    assert work.samples == 25
    assert work.bytes == 25 * 8 * len(output_columns(scene))
    assert work.steps == pytest.approx(4.0)
    assert work.analysis_bytes == 0.0
    assert work.phi_max == pytest.approx(4 * math.pi)


def test_by_time_the_least_speed_of_the_crank_angle_domain_counts():
    """t_end only: at least min(ω_s·n/2π, 1/Δt) samples a second, ω_s the switch speed."""
    scene = load_scene("small.toml", text=text("revolutions = 2", "t_end = 10"))
    per_second = min(math.pi / 3 * 12 / (2 * math.pi), 1.5 * math.pi / 3 / (2 * math.pi / 12))
    assert estimate(scene).samples == pytest.approx(1 + 10 * per_second)


def test_a_prescribed_speed_run_is_counted_at_its_speed():
    scene = load_scene("small.toml", text=text(
        "revolutions = 2", 'mode = "prescribed-speed"\nspeed_rpm = 600\nt_end = 1'))
    assert estimate(scene).samples == pytest.approx(2 + 10 * 12)


# (id, fragment of SMALL, its replacement, the line after "<file>: ")
REFUSED = [
    ("t_end-1e30", "revolutions = 2", "t_end = 1e30",
     "run.t_end: the run would write at least 2e+30 samples, 2.24e+20 TB (run.max_output_bytes "
     "= 4 GB); shorten the run, sample it more coarsely or raise run.max_output_bytes"),
    ("revolutions-1e30", "revolutions = 2", "revolutions = 1e30",
     "run.revolutions: the run would write at least 1.2e+31 samples, 1.34e+21 TB "
     "(run.max_output_bytes = 4 GB); shorten the run, sample it more coarsely or raise "
     "run.max_output_bytes"),
    ("switch-speed-1e30-rpm", "atol = 1e-8", "atol = 1e-8\nswitch_speed_rpm = 1e30",
     "solver.switch_speed_rpm: makes the time-domain sample spacing Δφ/(1.5 ω_s) = 3.33e-30 s, "
     "below 1e-08 s; give switch_speed ≤ 3.49e+07 rad/s, or output.dt"),
    ("analysis-grid-1e10", "samples_per_rev = 12",
     'samples_per_rev = 12\n\n[analysis]\norders = ["omega"]\nsamples_per_cycle = 10000000000',
     "analysis.samples_per_cycle: 10000000000 samples a cycle need at least 320 GB for the "
     "analysis grid (run.max_output_bytes = 4 GB); give fewer samples_per_cycle"),
    ("max-step-1e-9-deg", "atol = 1e-8", "atol = 1e-8\nmax_step_deg = 1e-9",
     "solver.max_step_deg: implies at least 7.2e+11 steps (run.max_steps = 1e+09); give a "
     "larger step or raise run.max_steps"),
    ("fixed-step-1e-12-deg", "atol = 1e-8", "atol = 1e-8\nfixed_step_deg = 1e-12",
     "solver.fixed_step_deg: implies at least 7.2e+14 steps (run.max_steps = 1e+09); give a "
     "larger step or raise run.max_steps"),
    ("rtol-1e-16", "rtol = 1e-6", "rtol = 1e-16",
     "solver.rtol: 1e-16 is below what double precision can deliver (100 ε = 2.22e-14: "
     "round-off alone exceeds it); give rtol ≥ 2.22e-14"),
    ("initial-phi-1e20", "omega_rpm = 1000", "omega_rpm = 1000\nphi = 1e20",
     "initial.phi: 1e+20 rad: a double there resolves only 1.64e+04 rad, too coarse for the "
     "increment 0.524 rad of output.samples_per_rev (the run would not advance); give |phi| ≤ "
     "2.36e+11 rad"),
    ("fixed-step-unresolved-at-the-end", ("revolutions = 2", "atol = 1e-8"),
     ("revolutions = 2e6\nmax_steps = 1e14", "atol = 1e-8\nfixed_step = 1e-6"),
     "solver.fixed_step: 1e-06 rad is finer than the shaft angle resolves at φ = 1.26e+07 rad "
     "(1.86e-09 rad), where the run ends (the run would not advance); give a coarser value or "
     "a shorter run"),
    ("budget-lowered", "revolutions = 2", "revolutions = 2\nmax_output_bytes = 1000",
     "run.revolutions: the run would write at least 25 samples, 2.8 kB (run.max_output_bytes = "
     "1 kB); shorten the run, sample it more coarsely or raise run.max_output_bytes"),
]


@pytest.mark.parametrize("command", ["check", "run"])
@pytest.mark.parametrize("old, new, line", [pytest.param(o, n, l, id=i) for i, o, n, l in REFUSED])
def test_unbounded_work_is_refused_before_any(tmp_path, capsys, command, old, new, line):
    scene = tmp_path / "bad.toml"
    scene.write_text(text(old, new), encoding="utf-8")
    out = tmp_path / "out"
    argv = ["check", str(scene)] if command == "check" else ["run", str(scene), "-o", str(out)]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.err == f"{scene}: {line}\n" and captured.out == ""
    assert not out.exists() or not any(out.iterdir())


def test_the_budgets_are_settable_and_written_back(tmp_path):
    """A run refused by the default budget passes with a larger one, which the resolved scene
    keeps."""
    from transient.scene import to_toml

    scene = load_scene("big.toml", text=text(
        "revolutions = 2", "revolutions = 2e7\nmax_output_bytes = 1e12\nmax_steps = 1e10"))
    assert (scene.run.max_output_bytes, scene.run.max_steps) == (1e12, 1e10)
    again = load_scene("again.toml", text=to_toml(scene))
    assert again.run == scene.run


def test_the_least_tolerance_is_what_scipy_allows():
    assert RTOL_MIN == pytest.approx(2.22e-14, rel=1e-3)
    load_scene("ok.toml", text=text("rtol = 1e-6", f"rtol = {RTOL_MIN!r}"))
