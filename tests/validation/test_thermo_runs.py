"""The run's own thermodynamics (:mod:`transient.analysis.thermo`) against independent checks.

* IMEP_k·V_d = ∮p_k dV: recomputed here from the stored ``p_<k>`` and the Gots crank-slider
  volume written out below (s = r(1 − cos α) + l(1 − √(1 − λ² sin²α)), Gots (1)), by the
  validation tier's own degree-6 quadrature (``sample_integral``), with the run's breakpoints as
  cuts: to rounding, 1e-12 asserted (2.4e-14 measured; two interpolatory rules of one degree on
  the same samples differ only where their stencils do).
* Brake power = the load's work over the cycle time, the load's work taken here from its law
  −K·ω² (the scene's fan) and the samples of ω, not from the ``W_load`` integral.
* FMEP·ΣV_d = the energy the pairs lost over the cycle, the stored ``W_loss_<k>`` at its ends.
* IMEP − BMEP − FMEP = ΔK/ΣV_d per cycle (no starter): the work–energy law with the pairs'
  losses, IMEP from the pressure's quadrature and the rest integrated with the motion. It closes
  to 1e-7 of the indicated work at 0.5° samples (measured 6e-8): the solver's rtol 1e-8 plus
  the quadrature of the applied pressure, a C² cubic between the mixed cycle's table knots, across
  which any rule converges as h⁴ only (6e-5 at 5° samples).
* With Wiebe combustion at constant speed and full fuel: IMEP = ``WiebeCycle.work``/V_h (the
  cycle's own integration, :mod:`transient.forces.wiebe`) to 1e-6, and the burned-fraction
  angles MFB10/50/90 from the apparent heat release of the run's pressure against the Wiebe
  law's closed form θ_s + Δθ·(−ln(1 − x)/a)^(1/(m+1)), x the level times x_b(EVO) = 1 − e^(−a),
  within 0.01° (trapezoidal heat release on 0.25° samples; measured 0.0034°), and the heat
  released m_f·LHV·η_c·x_b(EVO) to 1e-4.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.summary import summarize
from transient.analysis.thermo import cycle_thermodynamics
from transient.run import integrate
from transient.scene import Analysis, Friction, Governor, Initial, Output, Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
RPM = math.pi / 30.0
DEG = math.pi / 180.0

# The Gots engine of cases/gots_diesel_friction.toml, as printed there.
R, L, BORE = 0.047, 0.148, 0.088
FIRING = np.radians([360.0, 600.0, 120.0])


def gots_volume_rate(phi, firing):
    """dV/dφ [m³/rad] of the central crank-slider, Gots (1) differentiated, written apart from
    the library's kinematics."""
    a = phi - firing
    lam = R / L
    root = np.sqrt(1.0 - (lam * np.sin(a)) ** 2)
    ds = R * np.sin(a) + L * lam * lam * np.sin(a) * np.cos(a) / root
    return math.pi * BORE ** 2 / 4.0 * ds


@pytest.fixture(scope="module")
def friction_run():
    """The friction case from near its steady speed, 12 revolutions at 0.5° output."""
    base = load_scene(CASES / "gots_diesel_friction.toml")
    scene = replace(base, initial=Initial(phi=0.0, omega=3900 * RPM), run=Run(revolutions=12.0),
                    output=Output(samples_per_rev=720),
                    analysis=Analysis(thermodynamics=True))
    data = integrate(scene)
    assert data.complete, data.message
    return scene, data, cycle_thermodynamics(scene, data.trajectory, data.events)


def own_cycle_starts(engine_starts, firing, cycle=4 * math.pi):
    """The start of the cycle of a 4-stroke cylinder firing at ``firing`` that ends in each
    engine cycle (from each of ``engine_starts``, its end included): its gas-exchange TDCs,
    firing − 2π + m·cycle, the one in (a, a + cycle] less a cycle."""
    own = []
    for a in engine_starts:
        end = firing - 2 * math.pi + cycle * math.floor((a + cycle - (firing - 2 * math.pi))
                                                        / cycle + 1e-12)
        assert a < end <= a + cycle + 1e-9
        own.append(end - cycle)
    return np.array(own)


def test_imep_is_the_loop_integral_of_the_stored_pressure(friction_run, sample_integral):
    """Each cylinder's over its own cycles (from its gas-exchange TDC), the engine's over the
    engine's cycles: both ∮p dV of the stored samples by the independent quadrature."""
    scene, data, th = friction_run
    tr = data.trajectory
    phi = tr["phi"]
    starts = th["thermo_cycle_start"][0]
    cuts_all = np.asarray(data.events["breakpoint"])[:, 1]
    V_d = math.pi * BORE ** 2 / 4.0 * 2 * R
    assert th["thermo_swept_volume"][0] == pytest.approx(np.full(3, V_d), rel=1e-14)
    W = th["thermo_W_indicated"][0]

    def loop(f, a):
        b = a + 4 * math.pi
        return sample_integral(phi, f, np.concatenate([[a, b], cuts_all[(cuts_all > a)
                                                                         & (cuts_all < b)]]))

    worst = 0.0
    engine = np.zeros(starts.size)
    for k in range(3):
        f = tr[f"p_{k + 1}"] * gots_volume_rate(phi, FIRING[k])
        own = own_cycle_starts(starts, FIRING[k])
        np.testing.assert_allclose(th["thermo_cylinder_cycle_start"][0][k],
                                   np.where(own >= phi[0], own, np.nan), rtol=1e-14)
        for j, a in enumerate(starts):
            engine[j] += loop(f, a)
            if own[j] < phi[0]:  # its cycle began before the run
                assert np.isnan(W[k, j]) and np.isnan(th["thermo_imep"][0][k, j])
                continue
            expected = loop(f, own[j])
            worst = max(worst, abs(W[k, j] / expected - 1.0))
            assert W[k, j] == pytest.approx(expected, rel=1e-12)
            assert th["thermo_imep"][0][k, j] == pytest.approx(expected / V_d, rel=1e-12)
    total = th["thermo_swept_volume"][0].sum()
    np.testing.assert_allclose(th["thermo_imep_engine"][0] * total, engine, rtol=1e-12)
    print(f"\n∮p dV: the analysis against the independent quadrature, {worst:.1e} at most")
    held = np.isfinite(W)
    assert held.sum() == 3 * starts.size - 2  # cylinders 2 and 3 begin after φ0 = 0
    assert np.all(W[held] > 500.0)  # a firing diesel cylinder: ~800 J per cycle


def test_brake_power_is_the_loads_work_per_unit_time(friction_run, sample_integral):
    scene, data, th = friction_run
    tr = data.trajectory
    fan = scene.load.fan
    starts = th["thermo_cycle_start"][0]
    for j, a in enumerate(starts):
        b = a + 4 * math.pi
        sel = (tr["phi"] >= a - 1e-9) & (tr["phi"] <= b + 1e-9)
        t_a, t_b = np.interp([a, b], tr["phi"], tr["t"])
        work = sample_integral(tr["phi"], fan * tr["omega"] ** 2, [a, b])  # ∫K ω² dφ
        assert sel.sum() > 1000
        assert th["thermo_P_brake"][0][j] == pytest.approx(work / (t_b - t_a), rel=1e-9)


def test_fmep_is_the_pairs_losses_and_the_balance_closes(friction_run, sample_integral):
    scene, data, th = friction_run
    tr = data.trajectory
    total = float(th["thermo_swept_volume"][0].sum())
    starts = th["thermo_cycle_start"][0]
    for j, a in enumerate(starts):
        b = a + 4 * math.pi
        # the stored energies lost, at the cycle's ends (samples there)
        ends = np.searchsorted(tr["phi"], [a, b])
        assert np.all(np.abs(tr["phi"][ends] - [a, b]) <= 1e-12 * b)
        stored = sum(np.diff(tr[f"W_loss_{k}"][ends])[0] for k in (1, 2))
        assert th["thermo_fmep"][0][j] * total == pytest.approx(stored, rel=1e-12)
    imep, bmep, fmep = (th[f"thermo_{n}"][0] for n in ("imep_engine", "bmep", "fmep"))
    dK = th["thermo_dK"][0]
    W_ind = imep * total
    assert np.all(fmep > 0.0) and np.all(bmep > 0.0)
    closure = (imep - bmep - fmep) * total - dK
    print(f"\nIMEP {imep[-1] / 1e5:.5g} bar, BMEP {bmep[-1] / 1e5:.5g} bar, FMEP "
          f"{fmep[-1] / 1e5:.5g} bar; closure {np.max(np.abs(closure / W_ind)):.2e} of W_i")
    assert np.max(np.abs(closure / W_ind)) <= 1e-7
    assert th["thermo_balance_residual"][0] == pytest.approx(closure / W_ind, abs=1e-12)
    # the indicated work of the cylinders is the gas torque's work (∮dV = 0 removes p0)
    assert th["thermo_W_gas"][0] == pytest.approx(W_ind, rel=1e-7)


def test_summary_carries_the_last_cycle(friction_run):
    scene, data, th = friction_run
    summary = summarize(scene, data.trajectory, data.events)
    assert summary["thermo_last_bmep"][0] == th["thermo_bmep"][0][-1]
    assert summary["thermo_last_imep_engine"][1] == "Pa"
    phi = data.trajectory["phi"]
    last = (phi >= th["thermo_cycle_start"][0][-1]) & (phi <= th["thermo_cycle_start"][0][-1]
                                                       + 4 * math.pi)
    peak = max(data.trajectory[f"p_{k}"][last].max() for k in (1, 2, 3))
    assert summary["thermo_last_p_max"][0] == pytest.approx(peak, rel=1e-15)


@pytest.fixture(scope="module")
def wiebe_run():
    """The Wiebe case at a prescribed 2000 rpm, full fuel, two cycles at 0.25° output."""
    base = load_scene(CASES / "gots_diesel_wiebe.toml")
    scene = replace(base, run=Run(mode="prescribed-speed", speed=2000 * RPM, revolutions=4.0),
                    initial=Initial(phi=0.0, omega=2000 * RPM), friction=Friction(),
                    governor=Governor(), output=Output(samples_per_rev=1440),
                    analysis=Analysis(thermodynamics=True))
    data = integrate(scene)
    assert data.complete, data.message
    return scene, data, cycle_thermodynamics(scene, data.trajectory, data.events)


def test_wiebe_imep_and_burned_fraction_angles(wiebe_run):
    from transient.scene.queries import gas_tables

    scene, _, th = wiebe_run
    full = gas_tables(scene)[0]
    imep = th["thermo_imep"][0]
    assert imep.shape == (3, 2)
    # (cylinders 2 and 3 began their first cycle before the run's start, φ0 = 0)
    held = np.isfinite(imep)
    assert held.tolist() == [[True, True], [False, True], [False, True]]
    assert imep[held] == pytest.approx(full.work / full.v_h, rel=1e-6)
    w = scene.gas.wiebe
    for level in (10, 50, 90):
        # the fraction of what burns by exhaust opening, x_b(EVO) = 1 − e^(−a)
        x = level / 100.0 * (1.0 - math.exp(-w.a))
        closed = w.start + w.duration * (-math.log(1.0 - x) / w.a) ** (1.0 / (w.m + 1.0))
        got = th[f"thermo_mfb{level}"][0]
        print(f"MFB{level}: closed form {math.degrees(closed):.4f}°, run "
              f"{np.degrees(got).round(4).tolist()}")
        # each cylinder's own cycles the run holds whole, as the IMEP's
        done = np.isfinite(got)
        assert np.array_equal(done, held)
        assert np.all(np.abs(got[done] - closed) <= 0.01 * DEG)
    # the heat released is the fuel's, m_f·LHV·η_c·x_b(EVO) (no wall heat here)
    Q = th["thermo_Q"][0]
    assert Q[np.isfinite(Q)] == pytest.approx(full.heat_released, rel=1e-4)


def test_wiebe_heat_release_rate_is_the_wiebe_law(wiebe_run):
    """dQ/dφ of the run's pressure (the plots' curve) against the Wiebe law's rate
    Q·a(m+1)/Δθ·y^m·exp(−a·y^(m+1)), y = (θ − θ_s)/Δθ, Q = m_f·LHV·η_c, at every sample 1°
    or more from the combustion's start and end (at the start y^m has an infinite slope, at
    the end the rate jumps to 0, which the spline of dp/dφ rounds off): within 1e-4 of the
    peak rate (measured 9e-6 on 0.25° samples)."""
    from transient.analysis.thermo import heat_release_rate, own_cycles
    from transient.scene.queries import gas_tables

    scene, data, th = wiebe_run
    w = scene.gas.wiebe
    total = gas_tables(scene)[0].heat_released / (1.0 - math.exp(-w.a))
    start = own_cycles(scene, data.trajectory, 1)[0]
    theta, rate = heat_release_rate(scene, data.trajectory, 1, start)
    y = np.clip((theta - w.start) / w.duration, 0.0, None)
    law = np.where(y <= 1.0, total * w.a * (w.m + 1.0) / w.duration * y ** w.m
                   * np.exp(-w.a * y ** (w.m + 1.0)), 0.0)
    end = w.start + w.duration
    away = (theta > w.start + DEG) & (np.abs(theta - end) > DEG)
    err = np.max(np.abs(rate[away] - law[away])) / law.max()
    print(f"\nheat-release rate against the Wiebe law: {err:.1e} of the peak at "
          f"{np.degrees(theta[away][np.argmax(np.abs(rate[away] - law[away]))]):.2f}°")
    assert err <= 1e-4
    assert heat_release_rate(scene, data.trajectory, 1, start + 8 * math.pi) is None


def test_woschni_state_pressure_work_and_net_heat():
    """With wall heat the closed part's pressure is a state of the run. At a held 4400 rpm (a
    10⁶ kg m² flywheel, full fuel, no load or pairs) each cylinder's ∮p dV over its second
    cycle equals the closed work of transient.forces.woschni's own integration (solve_ivp at
    rtol 1e-12) plus the pumping loop, to 1e-6; the apparent heat release of the run's pressure
    is the fuel's heat less the wall's, Q_b − Q_w of that integration, to 1e-4 (measured 3.5e-5;
    the heat release is a trapezoid over 0.25° samples, and dp/dφ a spline of them)."""
    from transient.forces.woschni import WoschniParameters, closed_cycle
    from transient.scene import Load
    from transient.scene.queries import clearance_volume

    base = load_scene(CASES / "gots_diesel_woschni.toml")
    omega = 4400 * RPM
    scene = replace(base, governor=Governor(), friction=Friction(), load=Load(),
                    inertia=replace(base.inertia, flywheel=1e6),
                    initial=Initial(phi=0.0, omega=omega), run=Run(revolutions=6.0),
                    solver=replace(base.solver, rtol=1e-11, atol=1e-11),
                    output=Output(samples_per_rev=1440), analysis=Analysis(thermodynamics=True))
    data = integrate(scene)
    assert data.complete, data.message
    th = cycle_thermodynamics(scene, data.trajectory, data.events)
    mech, gas = scene.mechanism, scene.gas
    w, h = gas.wiebe, gas.woschni
    volume = mech.volume_function(clearance_volume(scene))
    ref = closed_cycle(volume, p_a=gas.p_a, start=w.start, duration=w.duration,
                       fuel_mass=w.fuel_mass,
                       woschni=WoschniParameters(bore=mech.bore, stroke=mech.stroke(), c1=h.c1,
                                                 c2=h.c2, wall_temperature=h.wall_temperature),
                       omega=float(np.mean(data.trajectory["omega"])), a=w.a, m=w.m, lhv=w.lhv,
                       efficiency=w.efficiency, gamma=w.gamma, gamma_slope=w.gamma_slope,
                       gamma_t_ref=w.gamma_t_ref, t_a=w.t_a, strokes=mech.strokes)
    v = volume(np.array([0.0, ref.start, ref.end, 4 * math.pi]))
    loop = ref.work + gas.p_intake * (v[1] - v[0]) + gas.p_exhaust * (v[3] - v[2])
    # the second engine cycle: every cylinder has closed its intake once before it
    W = th["thermo_W_indicated"][0][:, 1]
    print(f"\nWoschni at 4400 rpm: ∮p dV {W.round(3).tolist()} J against {loop:.3f} J; Q "
          f"{th['thermo_Q'][0][:, 1].round(2).tolist()} J against "
          f"{ref.heat_released - ref.heat_lost:.2f} J")
    assert W == pytest.approx(np.full(3, loop), rel=1e-6)
    assert th["thermo_Q"][0][:, 1] == pytest.approx(ref.heat_released - ref.heat_lost, rel=1e-4)


@pytest.fixture(scope="module")
def misfire_run():
    """cases/diesel_4cyl_misfire.toml as it stands (cylinder 2 at 80 % fuel, cylinder 3 misfiring
    in its cycles 10, 20 …; 200 revolutions from φ0 = 0 at 1° output), with thermodynamics."""
    base = load_scene(CASES / "diesel_4cyl_misfire.toml")
    scene = replace(base, analysis=Analysis(thermodynamics=True))
    data = integrate(scene)
    assert data.complete, data.message
    return scene, data, cycle_thermodynamics(scene, data.trajectory, data.events)


def test_misfire_case_imep_over_each_cylinders_own_cycle(misfire_run, sample_integral,
                                                         gots_cycle):
    """Every cylinder's IMEP over its own cycles (from its gas-exchange TDC, the cycles
    [[gas.cylinders]] counts) is ∮p dV of its stored pressure over that cycle, by the
    independent quadrature of the samples with the run's breakpoints as cuts (to 1e-12 of a
    fired cycle's work); and it is the mixed cycle's closed form at the cylinder's fuel:
    W_fired, a misfire's pumping loop (p_in − p_ex)·V_h, 80 % fuel's 0.8·W_fired +
    0.2·W_pumping (to 1e-8 of W_fired: the tables' interpolation, 1e-9 of p_z, and the
    quadrature of 1° samples; measured 2.4e-9). The engine's IMEP stays over the engine's
    cycles: the sum of the four cylinders' ∮p dV there."""
    scene, data, th = misfire_run
    tr = data.trajectory
    phi = tr["phi"]
    cuts_all = np.asarray(data.events["breakpoint"])[:, 1]
    cycle = 4 * math.pi
    firing = np.radians([360.0, 180.0, 540.0, 720.0])  # firing_deg (cylinder 4's 0° ≡ 720°)
    V_d = math.pi * BORE ** 2 / 4.0 * 2 * R
    W_fired, W_pumping = gots_cycle.works()
    starts = th["thermo_cycle_start"][0]
    W = th["thermo_W_indicated"][0]
    assert W.shape == (4, 100) and starts.size == 100

    def loop(f, a):
        b = a + cycle
        inner = cuts_all[(cuts_all > a) & (cuts_all < b)]
        return sample_integral(phi, f, np.concatenate([[a, b], inner]))

    engine = np.zeros(starts.size)
    worst_quad, worst_closed = 0.0, 0.0
    for k in range(4):
        f = tr[f"p_{k + 1}"] * gots_volume_rate(phi, firing[k])
        own = own_cycle_starts(starts, firing[k])
        for j, a in enumerate(starts):
            engine[j] += loop(f, a)
            if own[j] < phi[0]:
                assert np.isnan(W[k, j])
                continue
            got = th["thermo_imep"][0][k, j] * V_d
            expected = loop(f, own[j])
            worst_quad = max(worst_quad, abs(got - expected) / W_fired)
            # (of W_fired: a misfire's ∮p dV is a small difference of its strokes' works)
            assert got == pytest.approx(expected, abs=1e-12 * W_fired)
            # cylinder 3's cycle n = j + 1 (cycle 1: the one in progress at φ0)
            fuel = 0.8 if k == 1 else (0.0 if k == 2 and (j + 1) % 10 == 0 else 1.0)
            closed = fuel * W_fired + (1.0 - fuel) * W_pumping
            worst_closed = max(worst_closed, abs(got - closed) / W_fired)
            assert got == pytest.approx(closed, abs=1e-8 * W_fired)
    imep = th["thermo_imep"][0] / 1e5
    print(f"\nIMEP of cylinder 3 in its cycles 9–11: {imep[2, 8:11].round(4).tolist()} bar "
          f"(misfire: p_in − p_ex = {(gots_cycle.P_IN - gots_cycle.P_EX) / 1e5:.3f} bar); "
          f"against the quadrature "
          f"{worst_quad:.1e}, against the closed forms {worst_closed:.1e}, of W_fired")
    assert np.sum(imep[2] < 0.0) == 10  # its cycles 10, 20 … 100
    total = th["thermo_swept_volume"][0].sum()
    W_engine = th["thermo_imep_engine"][0] * total
    np.testing.assert_allclose(W_engine[:-1], engine[:-1], rtol=1e-12)
    # the last cycle ends with the run, on cylinder 4's compression end: there the reference
    # quadrature extrapolates its last 1° (a cut at each end), the analysis takes the last
    # sample (measured 1.2e-9 apart)
    assert W_engine[-1] == pytest.approx(engine[-1], rel=1e-8)
