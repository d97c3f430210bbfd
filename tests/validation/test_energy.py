"""Energy and phase of equation (18), J(φ)φ̈ + ½J′(φ)φ̇² = M, on the compiled path.

* **Coasting** (M = 0): K = ½J(φ)ω² is a first integral. In crank angle the stepper's third state
  *is* K and dK/dφ = M = 0, so K is kept to round-off by construction (the check is still made on
  the output columns J and ω, i.e. on ω = √(2K/J) and the J written out). In time the stepper
  integrates (18) for ω itself, and K drifts by the accumulated local errors: that drift must be
  bounded by C·rtol and fall as rtol tightens.
* **Phase**: coasting, dt/dφ = √(J(φ)/(2K)), so 1000 revolutions take
  1000·∫₀^{2π} √(J/(2K)) dφ, computed here with ``scipy.integrate.quad`` (relative error ~1e-14).
* **Work–energy**: for a driven run, K(end) − K(0) = ∫M dφ = ∫(M_gas + M_load + M_starter) ω dt.

Scenes are variants of ``cases/coasting_single.toml`` (rigid rod, λ = 0.318, J varying by ~±12 %)
built with ``dataclasses.replace``: λ = 0.5, offset e/r = 0.2, and a two-mass rod.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from transient.core.model.crank_slider import crank_slider_terms
from transient.run import integrate
from transient.scene import Gas, Initial, Load, Output, Run, Solver, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"

REVS = 1000

# Time-domain energy drift bound, drift ≤ C·rtol over 1000 revolutions (10⁴ to 3·10⁴ steps for
# the variants below). The stepper keeps each step's error norm ≤ 1 (≈ rtol·ω per step, ≈ 2 rtol·K
# in energy), and a non-symplectic method accumulates these with a systematic sign, so the
# a-priori bound is ~N_steps·rtol; the drift stays a small fraction of it. C = 3000 ≈ 0.1·N_steps
# (at 1e-10) leaves a margin above that fraction (run with -s to see the drifts).
C_DRIFT = 3000.0


def coasting_variants():
    base = load_scene(CASES / "coasting_single.toml")
    m = base.mechanism
    r = m.crank_radius
    mechs = {
        "rigid-lam0.318": m,
        "rigid-lam0.5": replace(m, rod_length=2 * r, rod_cg_from_pin=0.725 * 2 * r),
        "rigid-offset0.2": replace(m, offset=0.2 * r),
        "two-mass-lam0.5-offset0.2": replace(m, rod_length=2 * r, rod_cg_from_pin=0.725 * 2 * r,
                                             offset=0.2 * r, rod_model="two-mass",
                                             rod_inertia_cg=0.0),
    }
    out = {}
    for name, mech in mechs.items():
        mech.validate()
        # 1000 rpm, no forces, 1000 revolutions at rtol 1e-10 (K ≈ 170 J and ω ≈ 105 rad/s make
        # atol = 1e-12 irrelevant), as coasting_single.toml says, but set here explicitly.
        out[name] = replace(base, mechanism=mech, run=Run(revolutions=REVS),
                            initial=Initial(0.0, 1000.0 * math.pi / 30.0),
                            solver=replace(base.solver, method="dop853", rtol=1e-10, atol=1e-12))
        assert base.gas.model == "none" and base.load == Load() and base.starter.torque == 0.0
    return out


VARIANTS = coasting_variants()


def inertia_fn(scene):
    """J(φ) of the scene (kernel + constant inertias)."""
    mp = scene.mechanism.pack()
    n = scene.mechanism.n_cylinders
    u, du = np.empty(n), np.empty(n)
    return lambda p: crank_slider_terms(mp, p, u, du)[0] + scene.inertia.total


def coast_time(scene, revs=REVS):
    """Exact time to coast ``revs`` revolutions from φ = 0 (J is 2π-periodic for one cylinder)."""
    assert scene.mechanism.n_cylinders == 1 and scene.initial.phi == 0.0
    J = inertia_fn(scene)
    K0 = 0.5 * J(0.0) * scene.initial.omega ** 2
    one, err = quad(lambda p: math.sqrt(J(p) / (2.0 * K0)), 0.0, 2.0 * math.pi,
                    epsabs=0.0, epsrel=1e-13, limit=200)
    assert err <= 1e-12 * one
    return revs * one, K0


def energy(traj):
    return 0.5 * traj["J"] * traj["omega"] ** 2


def time_domain(scene, rtol):
    """The same scene integrated in time throughout: switch speed above any speed it reaches."""
    return replace(scene, solver=replace(scene.solver, rtol=rtol,
                                         switch_speed=2.0 * scene.initial.omega))


# ------------------------------------------------------------------------------------------------
# Coasting


@pytest.mark.parametrize("name", list(VARIANTS))
def test_coasting_angle_domain_keeps_energy_and_phase(name):
    """1000 revolutions at rtol 1e-10: K constant to 1e-8, time to 1e-9 of the quadrature."""
    scene = VARIANTS[name]
    t_exact, K0 = coast_time(scene)
    data = integrate(scene)
    tr = data.trajectory
    assert data.complete
    assert tr["phi"][-1] == pytest.approx(2 * math.pi * REVS, rel=1e-14)
    # The test has teeth only if J(φ) — hence ω — varies: here by ~10 % peak to peak.
    assert tr["omega"].max() / tr["omega"].min() - 1.0 > 0.05
    drift = np.max(np.abs(energy(tr) / K0 - 1.0))
    phase = tr["t"][-1] / t_exact - 1.0
    print(f"{name}: angle domain, |ΔK/K|max = {drift:.2e}, phase error {phase:.2e}")
    assert drift <= 1e-8
    assert abs(phase) <= 1e-9


@pytest.mark.parametrize("name", list(VARIANTS))
def test_coasting_time_domain_drift_scales_with_rtol(name):
    """Time domain (18) in (φ, ω): drift ≤ C·rtol at rtol 1e-8 and 1e-10, falling ≥ 10× between.

    Phase: ω = √(2K/J) is off by ½·δK/K, so the time to turn the run's angle is off by
    −½·⟨δK/K⟩ (its time average) of the run time: the phase error must be that of the drift
    (within 5 %, plus the 1e-11 floor of the angle-domain phase); and |phase| ≤ ½·C·rtol. (For a
    drift that grows linearly in time this is −¼·δK/K(end).)
    """
    scene = VARIANTS[name]
    t_exact, K0 = coast_time(scene)
    drifts = {}
    for rtol in (1e-8, 1e-10):
        data = integrate(time_domain(scene, rtol))
        tr = data.trajectory
        assert data.complete
        assert "to_angle_domain" not in data.events  # the run really stayed in time
        assert tr["phi"][-1] == pytest.approx(2 * math.pi * REVS, rel=1e-14)
        rel = energy(tr) / K0 - 1.0
        drift, end_drift = float(np.max(np.abs(rel))), float(rel[-1])
        phase = tr["t"][-1] / t_exact - 1.0
        predicted = -0.5 * np.trapezoid(rel, tr["t"]) / (tr["t"][-1] - tr["t"][0])
        drifts[rtol] = drift
        print(f"{name}: time domain rtol {rtol:g}: |ΔK/K|max = {drift:.3e} "
              f"({drift / rtol:.0f} rtol), phase {phase:.3e} ({phase / rtol:.0f} rtol), "
              f"predicted from the drift {predicted:.3e}, ΔK_end {end_drift:.3e}")
        assert drift <= C_DRIFT * rtol
        assert abs(phase) <= 0.5 * C_DRIFT * rtol
        assert abs(phase - predicted) <= 0.05 * abs(predicted) + 1e-11
    assert drifts[1e-10] <= 0.1 * drifts[1e-8]


# ------------------------------------------------------------------------------------------------
# Work–energy balance of a driven run


def smooth_gas(p0=1.0e5):
    """A smooth periodic indicator diagram on a 1° grid, as a ``table`` with a cubic spline.

    p = p0 + 0.05 MPa + 4 MPa·exp(−8(1 − cos((x − 2π − 0.35)/2))): a 4π-periodic C^∞ pulse
    peaking 20° after the firing TDC (so the cycle does net work); its only corners are the
    table's ends 0 ≡ 720°, where its value is within 1e-7 of the base and its slopes vanish.
    """
    x = np.radians(np.arange(0.0, 721.0))
    p = p0 + 0.05e6 + 4.0e6 * np.exp(-8.0 * (1.0 - np.cos((x - 2.0 * np.pi - 0.35) / 2.0)))
    return Gas(model="table", p0=p0, phi=tuple(x), p=tuple(p), interpolation="spline")


W0 = 2000.0 * math.pi / 30.0


def driven_scene(domain, revs=20, samples_per_rev=720, rtol=1e-10):
    """The Gots 3-cylinder engine with flywheel (cases/gots_diesel_spinup.toml), gas from
    :func:`smooth_gas`, a load with all three terms, from 2000 rpm (it speeds up to ~2900 rpm).

    Time domain: switch speed 10× the start speed, and output every 2e-5 s (~0.25…0.35°).
    """
    base = load_scene(CASES / "gots_diesel_spinup.toml")
    time_mode = domain == "time"
    solver = Solver(rtol=rtol, atol=1e-12, switch_speed=10.0 * W0 if time_mode else math.pi / 3)
    output = Output(samples_per_rev=samples_per_rev, dt=2e-5 if time_mode else 0.0)
    return replace(base, gas=smooth_gas(), load=Load(torque=50.0, linear=0.1, fan=5e-4),
                   initial=Initial(0.0, W0), run=Run(revolutions=revs), solver=solver,
                   output=output)


def work_balance(data, scene, sample_integral, table_end_events, domain):
    """(ΔK, {W_gas, W_load, W_starter}) of a run; the works by quadrature of the output samples.

    Why quadrature of the samples: the output M columns are the moments the stepper used, at the
    dense-output state, so ∫M dφ is the work done *in the run*, including any ω-dependence of the
    load. Every M here is smooth between the gas table's ends (its other knots, breakpoints too,
    are C²), so a degree-6
    local-polynomial rule on 0.25–0.5° samples between the breakpoint events (and the run's ends)
    is accurate to ~1e-11 of the work (see :func:`test_work_quadrature_is_converged`). In crank angle the integral
    is ∫M dφ over φ-samples; in time ∫M ω dt over t-samples.
    """
    tr = data.trajectory
    bp = table_end_events(data, scene)
    if domain == "angle":
        x, w, cuts = tr["phi"], np.ones_like(tr["phi"]), bp[:, 1]
    else:
        x, w, cuts = tr["t"], tr["omega"], bp[:, 0]
    cuts = np.concatenate([[x[0], x[-1]], cuts])
    works = {c: sample_integral(x, tr[c] * w, cuts) for c in ("M_gas", "M_load", "M_starter")}
    K = energy(tr)
    return K[-1] - K[0], works


@pytest.mark.parametrize("domain,revs", [("angle", 20), ("time", 20), ("time", 2)])
def test_work_energy_balance_of_a_driven_run(domain, revs, sample_integral, table_end_events):
    """K(end) − K(0) = W_gas + W_load + W_starter to 1e-8 of |W_gas| + |W_load| + |W_starter| at
    rtol 1e-10. In crank angle K is the state, so this checks the moments written out against the
    state; in time it checks the integration of (18) with its ½J′ω² term.

    Both run lengths end on a breakpoint (an integer number of cycles, and every cylinder's table
    has a corner at 0 ≡ 720°).
    """
    scene = driven_scene(domain, revs)
    data = integrate(scene)
    assert data.complete
    tr = data.trajectory
    assert ("to_angle_domain" in data.events) is False
    assert tr["phi"][-1] == pytest.approx(2 * math.pi * revs, rel=1e-14)
    # The last step ends the run on φ = 2π·revs: the final sample must follow from the one
    # before it, Δφ = ∫ω dt = Δt(ω₀ + ω₁)/2 + Δt²(ε₀ − ε₁)/12 + O(Δt⁵) (Hermite), ~1e-9 here.
    dt = tr["t"][-1] - tr["t"][-2]
    hermite = (0.5 * dt * (tr["omega"][-1] + tr["omega"][-2])
               + dt**2 / 12.0 * (tr["epsilon"][-2] - tr["epsilon"][-1]))
    assert tr["phi"][-1] - tr["phi"][-2] == pytest.approx(hermite, rel=1e-6), (
        "the final state does not follow from the last sample: Δφ = "
        f"{math.degrees(tr['phi'][-1] - tr['phi'][-2]):.6g}° over Δt = {dt:.6g} s at "
        f"ω = {tr['omega'][-1]:.6g} rad/s")
    dK, works = work_balance(data, scene, sample_integral, table_end_events, domain)
    total = sum(abs(v) for v in works.values())
    residual = (dK - sum(works.values())) / total
    print(f"{domain} domain, {revs} rev: ΔK = {dK:.6f} J, W = {works}, residual {residual:.2e}")
    assert abs(works["M_gas"]) > 0.1 * total and abs(works["M_load"]) > 0.1 * total
    assert abs(residual) <= 1e-8


def test_work_quadrature_is_converged(sample_integral, table_end_events):
    """The quadrature behind the balance: doubling the output sampling (720 → 1440 per revolution)
    changes the work by < 1e-10 of the total (4th-order convergence, set by the spline table's 1°
    knots), so the 1e-8 balance measures the integration, not the quadrature."""
    works = []
    for spr in (720, 1440):
        scene = driven_scene("angle", 20, samples_per_rev=spr)
        works.append(work_balance(integrate(scene), scene, sample_integral, table_end_events,
                                  "angle")[1])
    total = sum(abs(v) for v in works[0].values())
    for c in works[0]:
        assert abs(works[0][c] - works[1][c]) <= 1e-10 * total


def test_time_domain_breakpoints_are_reported_once():
    """In time, a step that would cross a breakpoint is retaken to end on it, and the breakpoint
    is reported as a ``breakpoint`` event. Each crossing must be reported once, on it: every knot
    of the 1° table is a breakpoint, and the cylinders' phases (0°, 240°, 480°) put all of them on
    the shaft's 1° grid, so the 20-revolution driven run crosses 7200 (the last one is the run's
    end)."""
    data = integrate(driven_scene("time", 20))
    bp = data.events["breakpoint"]
    step = math.radians(1.0)
    nearest = np.round(bp[:, 1] / step) * step
    print(f"{len(bp)} breakpoint events; largest distance from a knot "
          f"{np.max(np.abs(bp[:, 1] - nearest)):.2e} rad")
    assert np.max(np.abs(bp[:, 1] - nearest)) <= 1e-12 * 2 * math.pi * 20
    assert np.unique(nearest).size == len(bp)
    assert 7199 <= len(bp) <= 7200


@pytest.mark.parametrize("rtol", [1e-3, 1e-4, 1e-5])
def test_time_domain_breakpoints_once_at_loose_tolerances(rtol):
    """At loose tolerances a step retaken to end on a corner lands short of it by up to ~1e-3 rad
    (the dense output it is aimed with is that inaccurate); it is lengthened by a secant step,
    so that each corner is still reached once (else the next step would cross the sliver and be
    retaken again, and a corner would count as several breakpoint events)."""
    from transient.verify.stress import put, scene_of, spinup

    def events(r):
        d = put(put(spinup(10), "output", dt=1e-4), "solver", rtol=r, atol=r * 1e-2,
                domain="time")
        return integrate(scene_of(d, "spinup-time")).events["breakpoint"]

    loose, tight = events(rtol), events(1e-9)
    print(f"rtol {rtol:g}: {len(loose)} breakpoint events against {len(tight)} at 1e-9")
    assert abs(len(loose) - len(tight)) <= 1  # (the run's last corner may be its end)
