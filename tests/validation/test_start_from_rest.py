"""The Gots engine started from rest by a starter (``cases/gots_diesel_spinup.toml``, ω₀ = 0).

Scene changes (our choices): starter M = 300 N·m·(1 − ω/ω_nl) with ω_nl = 600 rpm, cutting out
for good at 400 rpm; 4 revolutions (2 cycles, ending on a table corner), t_end = 2 s as a guard;
rtol = atol = 1e-10; output every 0.25° in crank angle and every 5 µs in time. From φ = 0 the
starter has to push cylinder 3 through its compression (firing TDC at φ = 120°); the gas then
takes over and the starter cuts out at φ ≈ 133.6°, t ≈ 0.095 s; the run ends at ω ≈ 228 rad/s.

What must happen:

* the run starts in time (ω₀ = 0 is below the switch speed) and switches to crank angle once,
  when ω reaches 1.5 × switch_speed (the switch hysteresis, ``run._config``), never back;
* the starter cuts out exactly once, at ω = cutout speed to 1e-9 — ω at the event is read from
  the compiled samples before it (a degree-7 polynomial through the last 8, extrapolated to the
  event's φ or t, well inside 1e-9 at this sampling);
* compiled and reference (scipy DOP853 and Radau) agree: final t and ω, and the cut-out event's
  t and φ, with e = (y − y_ref)/(atol + rtol |y_ref|) ≤ 100 (global error over ~10³ steps of
  local errors ≤ 1);
* work–energy: ½J ω²(end) − 0 = ∫(M_gas + M_load + M_starter) ω dt over the whole run, to 1e-8
  of |W_gas| + |W_load| + |W_starter|. The quadrature is in t for both domains: ω(φ) has a
  √φ-type singularity at the start from rest, which would spoil a polynomial rule in φ, while
  ω(t) is smooth. Cuts at the domain switch, the cut-out (M_starter jumps) and every breakpoint
  (kinks of the torque). Twice the sampling leaves the residual as it is: it is the
  integration's, not the quadrature's.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from transient.run import integrate
from transient.scene import Initial, Output, Run, Starter, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RTOL = ATOL = 1e-10
CUTOUT = 400.0 * math.pi / 30.0
REVS = 4


def scene_from_rest(method="dop853"):
    base = load_scene(CASES / "gots_diesel_spinup.toml")
    return replace(
        base,
        starter=Starter(torque=300.0, noload_speed=600.0 * math.pi / 30.0, cutout_speed=CUTOUT),
        initial=Initial(phi=0.0, omega=0.0), run=Run(revolutions=REVS, t_end=2.0),
        solver=replace(base.solver, method=method, rtol=RTOL, atol=ATOL),
        output=Output(samples_per_rev=1440, dt=5e-6))


@pytest.fixture(scope="module")
def compiled():
    data = integrate(scene_from_rest())
    assert data.complete, data.message
    return data


def e(y, y_ref):
    return (np.asarray(y) - np.asarray(y_ref)) / (ATOL + RTOL * np.abs(y_ref))


def extrapolate(x, y, x0, n=8):
    """Value at x0 of the degree n−1 polynomial through the last n samples (x < x0)."""
    p = Polynomial.fit(x[-n:], y[-n:], n - 1)
    return float(p(x0))


def test_domains_and_events(compiled):
    tr, ev = compiled.trajectory, compiled.events
    scene = scene_from_rest()
    w_hi = 1.5 * scene.solver.switch_speed
    assert tr["omega"][0] == 0.0 and tr["t"][0] == 0.0
    assert tr["phi"][-1] == pytest.approx(2 * math.pi * REVS, rel=1e-15)
    assert "to_angle_domain" in ev and len(ev["to_angle_domain"]) == 1
    assert "to_time_domain" not in ev and "speed_reversal" not in ev
    assert len(ev["starter_cutout"]) == 1
    t_s, phi_s = ev["to_angle_domain"][0]
    t_c, phi_c = ev["starter_cutout"][0]
    assert 0.0 < t_s < t_c < tr["t"][-1]

    # Time domain first: samples every dt in t up to the switch, then every Δφ in crank angle.
    before = tr["t"] < t_s
    assert np.count_nonzero(before) >= 20
    np.testing.assert_allclose(np.diff(tr["t"][before]), scene.output.dt, rtol=1e-6)
    after_phi = tr["phi"][~before][:-1]  # the last row is the end state
    np.testing.assert_allclose(np.diff(after_phi), 2 * math.pi / scene.output.samples_per_rev,
                               rtol=1e-9)
    w_switch = extrapolate(tr["t"][before], tr["omega"][before], t_s)
    print(f"to_angle_domain at t = {t_s:.6g} s, ω = {w_switch:.12g} (1.5·switch_speed = {w_hi:.12g})")
    assert w_switch == pytest.approx(w_hi, rel=1e-9)

    # Starter on until the cut-out and off after it; ω there is the cut-out speed.
    on = tr["M_starter"] > 0.0
    assert np.all(tr["phi"][on] < phi_c) and np.all(tr["phi"][~on & (tr["t"] > 0)] > phi_c)
    left = (tr["phi"] < phi_c) & (tr["t"] > t_s)
    w_cut = extrapolate(tr["phi"][left], tr["omega"][left], phi_c)
    print(f"starter_cutout at t = {t_c:.9g} s, φ = {math.degrees(phi_c):.9g}°, "
          f"ω/ω_cut − 1 = {w_cut / CUTOUT - 1:.2e}")
    assert w_cut == pytest.approx(CUTOUT, rel=1e-9)


@pytest.mark.parametrize("method", ["scipy-DOP853", "scipy-Radau"])
def test_compiled_agrees_with_reference(compiled, method):
    ref = integrate(scene_from_rest(method))
    assert ref.solver["method"] == method
    c, r = compiled.trajectory, ref.trajectory
    assert r["phi"][-1] == pytest.approx(c["phi"][-1], rel=1e-15)
    assert len(ref.events["starter_cutout"]) == 1
    errs = {"t_end": e(c["t"][-1], r["t"][-1]), "omega_end": e(c["omega"][-1], r["omega"][-1]),
            "t_cutout": e(compiled.events["starter_cutout"][0, 0], ref.events["starter_cutout"][0, 0]),
            "phi_cutout": e(compiled.events["starter_cutout"][0, 1],
                            ref.events["starter_cutout"][0, 1])}
    print(f"compiled vs {method}: " + ", ".join(f"e({k}) = {v:.3g}" for k, v in errs.items()))
    for k, v in errs.items():
        assert abs(v) <= 100.0, (k, v)


def test_work_energy_balance_through_the_switch(compiled, sample_integral):
    tr, ev = compiled.trajectory, compiled.events
    t_s = ev["to_angle_domain"][0, 0]
    t_c = ev["starter_cutout"][0, 0]
    cuts = np.concatenate([[0.0, tr["t"][-1], t_s, t_c], ev["breakpoint"][:, 0]])
    works = {c: sample_integral(tr["t"], tr[c] * tr["omega"], cuts)
             for c in ("M_gas", "M_load", "M_starter")}
    k_end = 0.5 * tr["J"][-1] * tr["omega"][-1] ** 2
    total = sum(abs(v) for v in works.values())
    residual = (k_end - sum(works.values())) / total
    print(f"from rest: K(end) = {k_end:.6f} J, W = {works}, residual {residual:.2e}")
    assert works["M_starter"] > 0.05 * total and works["M_load"] < 0.0
    assert abs(residual) <= 1e-8
