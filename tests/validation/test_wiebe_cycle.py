"""Single-zone Wiebe cycle on the Gots diesel geometry, against closed forms and the first law.

Geometry (``cases/gots_diesel_4400.toml``; Gots §2.9, App. 1, App. 2):
r = 47 mm, L = 148 mm, D = 88 mm, ε = 18. Cycle: p_a = 0.1436 MPa and T_a = 329.9 K at intake
closing (App. 2), intake 0.165 MPa and exhaust 0.182 MPa (П4.1), combustion from 358° (injection
advance 15°, ignition delay 13°, App. 1) for 50°, m = 0.5, a = 6.908, 0.05 g of diesel fuel
(App. 2 burns 17.66 kg/h in 3 cylinders at 4400 rpm: 0.0446 g per cycle), LHV 42.5 MJ/kg.

Every reference here is computed independently of the module: closed-form isentropes and
polytrope work, 1-D quadratures of the heat release, and the test's own ODE in other state
variables (``p·V^γ``, or the temperature). Run with ``-s`` to see the numbers.
"""
from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from transient.forces.wiebe import DEFAULT_TOLERANCE, wiebe_cycle, wiebe_tables

R, L, BORE, EPS = 0.047, 0.148, 0.088, 18.0
LAM = R / L
F_P = math.pi * BORE ** 2 / 4
V_H = F_P * 2 * R
V_C = V_H / (EPS - 1)
DEG = math.pi / 180

P_A, T_A = 0.1436e6, 329.9
P_IN, P_EX = 0.165e6, 0.182e6
FUEL, LHV = 0.05e-3, 42.5e6
A, M = 6.908, 0.5
START, DURATION = 358 * DEG, 50 * DEG
GAMMA = 1.35
# γ(T) = 1.38 - 1e-4 (T - 300 K): air-like, 1.16 at 2500 K.
G0, GK, TREF = 1.38, -1e-4, 300.0

BASE = {"p_a": P_A, "t_a": T_A, "p_intake": P_IN, "p_exhaust": P_EX, "start": START,
        "duration": DURATION, "a": A, "m": M, "lhv": LHV}


def volume(x):
    """Crank-slider volume, Gots eq. (1)–(2): V = V_c + F_p·[r(1 − cos x) + L(1 − cos β)]."""
    x = np.asarray(x, dtype=float)
    return V_C + F_P * (R * (1 - np.cos(x)) + L * (1 - np.sqrt(1 - (LAM * np.sin(x)) ** 2)))


def dvolume(x):
    """dV/dx of :func:`volume`."""
    x = np.asarray(x, dtype=float)
    cos_beta = np.sqrt(1 - (LAM * np.sin(x)) ** 2)
    return F_P * R * np.sin(x) * (1 + LAM * np.cos(x) / cos_beta)


def vol(x):
    return float(volume(x))


def heat_rate(x, fuel=FUEL):
    """dQ/dx [J/rad] of the Wiebe law, written out here (not the module's wiebe_rate)."""
    y = (x - START) / DURATION
    if y < 0 or y > 1:
        return 0.0
    return fuel * LHV * A * (M + 1) / DURATION * y ** M * math.exp(-A * y ** (M + 1))


def q_total(fuel=FUEL):
    return fuel * LHV * (1 - math.exp(-A))


def table_loop_work(tab, nodes=8, longest=0.01):
    """∮p dV of the table: Gauss–Legendre on every knot interval with that interval's piece.

    Intervals longer than `longest` [rad] (the constant gas-exchange pieces are one interval
    each) are cut into equal parts first, as dV/dx is not a polynomial.
    """
    xg, wg = np.polynomial.legendre.leggauss(nodes)
    h = np.diff(tab.knots)
    n = np.ceil(h / longest).astype(int)
    interval = np.repeat(np.arange(h.size), n)
    k = np.concatenate([np.arange(j) for j in n])
    a = tab.knots[interval] + h[interval] * k / n[interval]
    half = 0.5 * h[interval] / n[interval]
    x = (a + half)[:, None] + half[:, None] * xg[None, :]
    piece = np.searchsorted(tab.piece_knot, interval, side="right") - 1
    p, _ = tab.evaluate(x, np.broadcast_to(piece[:, None], x.shape))
    return float(np.sum(half[:, None] * wg[None, :] * p * dvolume(x)))


def off_knot(tab, lo, hi, per_interval):
    """Points strictly inside knot intervals (never on a knot) within (lo, hi)."""
    x = tab.interior_points(per_interval)
    return x[(x > lo) & (x < hi)]


def reference_pressure_z(x_eval, lo=math.pi, hi=3 * math.pi, fuel=FUEL, gamma=GAMMA):
    """Constant γ: z = p·V^γ obeys dz/dx = (γ − 1)·V^(γ−1)·dQ/dx (the test's own ODE)."""
    x_eval = np.sort(np.asarray(x_eval))
    z = P_A * vol(lo) ** gamma
    out = np.empty(x_eval.size)
    ends = [lo, START, START + DURATION, hi]
    for a, b in itertools.pairwise(ends):
        sel = (x_eval >= a) & (x_eval <= b)
        pts = np.unique(np.concatenate([x_eval[sel], [b]]))
        sol = solve_ivp(lambda x, y: [(gamma - 1) * vol(x) ** (gamma - 1) * heat_rate(x, fuel)],
                        (a, b), [z], method="DOP853", rtol=1e-13, atol=1e-14 * z, t_eval=pts)
        out[sel] = np.interp(x_eval[sel], pts, sol.y[0]) / volume(x_eval[sel]) ** gamma
        z = sol.y[0, -1]
    return x_eval, out


def reference_pressure_t(x_eval):
    """γ(T): the temperature ODE m c_v(T) dT/dx = dQ/dx − p dV/dx, c_v = R/(γ(T) − 1)."""
    x_eval = np.sort(np.asarray(x_eval))
    mr = P_A * vol(math.pi) / T_A   # m·R

    def rhs(x, y):
        t = y[0]
        g = G0 + GK * (t - TREF)
        v = vol(x)
        return [(g - 1) / mr * (heat_rate(x) - mr * t / v * float(dvolume(x)))]

    out = np.empty(x_eval.size)
    t = T_A
    ends = [math.pi, START, START + DURATION, 3 * math.pi]
    for a, b in itertools.pairwise(ends):
        sel = (x_eval >= a) & (x_eval <= b)
        pts = np.unique(np.concatenate([x_eval[sel], [b]]))
        sol = solve_ivp(rhs, (a, b), [t], method="DOP853", rtol=1e-13, atol=1e-14 * T_A,
                        t_eval=pts)
        out[sel] = mr * np.interp(x_eval[sel], pts, sol.y[0]) / volume(x_eval[sel])
        t = sol.y[0, -1]
    return x_eval, out


@pytest.fixture(scope="module")
def motored():
    return wiebe_cycle(volume, dvolume=dvolume, fuel_mass=0.0, gamma=GAMMA, **BASE)


@pytest.fixture(scope="module")
def fired():
    return wiebe_cycle(volume, dvolume=dvolume, fuel_mass=FUEL, gamma=GAMMA, **BASE)


@pytest.fixture(scope="module")
def fired_gamma_t():
    return wiebe_cycle(volume, dvolume=dvolume, fuel_mass=FUEL, gamma=G0, gamma_slope=GK,
                       gamma_t_ref=TREF, **BASE)


def test_geometry():
    assert vol(math.pi) / V_C == pytest.approx(EPS, rel=1e-14)
    assert vol(math.pi) == pytest.approx(0.6053e-3, abs=1e-7)   # V_a of App. 2 (0.6053 dm³)


def test_motored_is_an_isentrope(motored):
    mc = motored
    x = np.linspace(math.pi, 3 * math.pi, 2001)
    p, _w = mc.closed(x)
    pvg = p * volume(x) ** GAMMA / (P_A * vol(math.pi) ** GAMMA) - 1
    assert np.max(np.abs(pvg)) <= 1e-9
    # Compression π → 2π on the polytrope: W = (p1 V1 − p2 V2)/(γ − 1), p2 = p1 ε^γ.
    v1, v2 = vol(math.pi), vol(2 * math.pi)
    p2 = P_A * (v1 / v2) ** GAMMA
    w_comp = (P_A * v1 - p2 * v2) / (GAMMA - 1)
    w_tdc = float(mc.closed(np.array([2 * math.pi]))[1][0])
    assert abs(w_tdc / w_comp - 1) <= 1e-9
    # Compression and expansion cancel: zero net closed-cycle work.
    assert abs(mc.closed_work) <= 1e-9 * abs(w_comp)
    # Peak at the firing TDC with p_a ε^γ.
    assert mc.p_max == pytest.approx(p2, rel=1e-10)
    assert mc.angle_max == pytest.approx(2 * math.pi, abs=1e-7)
    assert mc.heat_released == 0.0
    # The table against the closed form at off-knot angles.
    xs = off_knot(mc, math.pi, 3 * math.pi, 4)
    err = np.max(np.abs(mc(xs) - P_A * (v1 / volume(xs)) ** GAMMA)) / p2
    assert mc.interpolation_error <= DEFAULT_TOLERANCE
    assert err <= 1.5 * DEFAULT_TOLERANCE
    print(f"\nmotored: max |pV^γ/const − 1| = {np.max(np.abs(pvg)):.1e}; W_comp = {w_comp:.4f} J "
          f"(ODE rel {w_tdc / w_comp - 1:.1e}); net closed work {mc.closed_work:.1e} J "
          f"({abs(mc.closed_work / w_comp):.1e} of W_comp); p_max {mc.p_max / 1e6:.4f} MPa "
          f"(rel {mc.p_max / p2 - 1:.1e}) at {mc.angle_max / DEG:.9f}°; table error "
          f"{mc.interpolation_error:.2e} (estimate), {err:.2e} (4 per interval, closed form); "
          f"{mc.knots.size} knots")


def test_first_law_constant_gamma(fired):
    mc = fired
    q = q_total()
    assert mc.burned_fraction == pytest.approx(1 - math.exp(-A), abs=1e-15)
    assert mc.heat_released == pytest.approx(q, rel=1e-14)
    v_a, v_b = vol(math.pi), vol(3 * math.pi)
    # Module's own end state: ∮p dV = Q − ΔU with U = pV/(γ − 1).
    w_balance = q - (mc.p_end * v_b - P_A * v_a) / (GAMMA - 1)
    assert abs(mc.closed_work / w_balance - 1) <= 1e-8
    # Independent end state: p V^γ = p_a V_a^γ + (γ − 1)∫V^(γ−1) dQ (quadrature).
    z = P_A * v_a ** GAMMA + (GAMMA - 1) * quad(
        lambda x: vol(x) ** (GAMMA - 1) * heat_rate(x), START, START + DURATION,
        epsabs=0, epsrel=1e-13, limit=200)[0]
    p_end = z / v_b ** GAMMA
    assert mc.p_end == pytest.approx(p_end, rel=1e-10)
    w_indep = q - (p_end * v_b - P_A * v_a) / (GAMMA - 1)
    assert abs(mc.closed_work / w_indep - 1) <= 1e-8
    # Superposition (constant γ): each heat element dQ at volume V does dQ·(1 − (V/V_b)^(γ−1))
    # of work on its way to V_b; the motored part is zero here (V_a = V_b).
    w_elem = quad(lambda x: heat_rate(x) * (1 - (vol(x) / v_b) ** (GAMMA - 1)), START,
                  START + DURATION, epsabs=0, epsrel=1e-13, limit=200)[0]
    assert abs(mc.closed_work / w_elem - 1) <= 1e-8
    # So no better than the Otto cycle of the same ε and γ.
    eta_otto = 1 - EPS ** (1 - GAMMA)
    assert mc.closed_work / q < eta_otto
    print(f"\nfired (γ = {GAMMA}): Q = {q:.3f} J, ∮p dV = {mc.closed_work:.6f} J; rel. to "
          f"Q − ΔU {mc.closed_work / w_balance - 1:.1e} (own p_end), "
          f"{mc.closed_work / w_indep - 1:.1e} (quadrature p_end), "
          f"{mc.closed_work / w_elem - 1:.1e} (heat elements); p_end rel "
          f"{mc.p_end / p_end - 1:.1e}; η = {mc.closed_work / q:.4f} (Otto {eta_otto:.4f}); "
          f"p_max {mc.p_max / 1e6:.3f} MPa at {mc.angle_max / DEG:.3f}°, T_max {mc.t_max:.0f} K")


def test_first_law_gamma_of_t(fired_gamma_t):
    mc = fired_gamma_t
    q = q_total()
    v_a, v_b = vol(math.pi), vol(3 * math.pi)
    mr = P_A * v_a / T_A
    t_end = T_A * mc.p_end * v_b / (P_A * v_a)
    # U(T) = m ∫ c_v dT, c_v = R/(γ(T) − 1), γ linear: ΔU = mR/k · ln((γ2 − 1)/(γ1 − 1)).
    g1, g2 = G0 + GK * (T_A - TREF), G0 + GK * (t_end - TREF)
    du = mr / GK * math.log((g2 - 1) / (g1 - 1))
    assert abs(mc.closed_work / (q - du) - 1) <= 1e-8
    # End state from the test's own temperature ODE.
    _, p_ref = reference_pressure_t(np.array([3 * math.pi - 1e-9]))
    assert mc.p_end == pytest.approx(p_ref[0], rel=1e-9)
    print(f"\nfired, γ(T): ∮p dV = {mc.closed_work:.6f} J, Q − ΔU = {q - du:.6f} J (rel "
          f"{mc.closed_work / (q - du) - 1:.1e}); T_end {t_end:.1f} K, T_max {mc.t_max:.0f} K, "
          f"p_max {mc.p_max / 1e6:.3f} MPa")


def test_table_matches_independent_ode(fired, fired_gamma_t):
    lo, hi = math.pi, 3 * math.pi
    for mc, ref, name in ((fired, reference_pressure_z, "γ const"),
                          (fired_gamma_t, reference_pressure_t, "γ(T)")):
        x1 = off_knot(mc, lo, hi, 1)
        x4 = off_knot(mc, lo, hi, 4)
        x1, p1 = ref(x1)
        x4, p4 = ref(x4)
        ode = np.max(np.abs(mc.closed(x4)[0] - p4)) / mc.p_max
        mid = np.max(np.abs(mc(x1) - p1)) / mc.p_max
        four = np.max(np.abs(mc(x4) - p4)) / mc.p_max
        assert ode <= 1e-10
        assert mc.interpolation_error <= DEFAULT_TOLERANCE
        assert mid <= mc.interpolation_error + 2e-11
        assert four <= 1.5 * mc.interpolation_error
        # The peak against the reference sampled finely around it.
        xp = np.linspace(mc.angle_max - 0.5 * DEG, mc.angle_max + 0.5 * DEG, 2001)
        xp, pp = ref(xp)
        assert pp.max() <= mc.p_max * (1 + 1e-10)
        assert pp.max() >= mc.p_max * (1 - 1e-9)
        print(f"\n{name}: dense ODE vs reference {ode:.1e}; table: estimate "
              f"{mc.interpolation_error:.2e}, midpoints {mid:.2e}, 4 per interval {four:.2e} "
              f"(of p_max); {mc.knots.size} knots")


def test_loop_work_and_pumping(fired, motored):
    for mc in (fired, motored):
        pumping = P_IN * (vol(math.pi) - vol(0.0)) + P_EX * (vol(4 * math.pi) - vol(3 * math.pi))
        assert mc.work - mc.closed_work == pytest.approx(pumping, rel=1e-12)
        w_table = table_loop_work(mc)
        assert abs(w_table - mc.work) <= 1e-9 * abs(mc.closed_work if mc.fuel_mass else pumping)
    # Motored: only the pumping loop, (p_in − p_ex)·V_h.
    assert motored.work == pytest.approx((P_IN - P_EX) * V_H, rel=1e-9)
    assert fired.mean_torque == pytest.approx(fired.work / (4 * math.pi), rel=1e-15)
    assert fired.mean_pressure == pytest.approx(fired.work / V_H, rel=1e-12)
    print(f"\nW = {fired.work:.4f} J (table {table_loop_work(fired):.4f}), p_i = "
          f"{fired.mean_pressure / 1e6:.3f} MPa, mean torque {fired.mean_torque:.2f} N·m")


def test_valve_timing():
    ivc, evo = 200 * DEG, 500 * DEG
    mc = wiebe_cycle(volume, dvolume=dvolume, fuel_mass=FUEL, gamma=GAMMA,
                     intake_closing=ivc, exhaust_opening=evo, **BASE)
    np.testing.assert_array_equal(mc.corners, [0, ivc, START, START + DURATION, evo, 4 * math.pi])
    pumping = P_IN * (vol(ivc) - vol(0.0)) + P_EX * (vol(4 * math.pi) - vol(evo))
    assert mc.work - mc.closed_work == pytest.approx(pumping, rel=1e-12)
    assert abs(table_loop_work(mc) / mc.work - 1) <= 1e-9
    # Constant gas exchange, jump to p_a at intake closing and to p_exhaust at exhaust opening.
    assert mc(np.array([1e-3, ivc - 1e-9])).tolist() == [P_IN, P_IN]
    assert mc(ivc) == pytest.approx(P_A, rel=1e-14)
    assert mc(np.array([evo, 4 * math.pi - 1e-9])).tolist() == [P_EX, P_EX]
    # First law over the shorter closed part (V_a ≠ V_b now).
    v_a, v_b = vol(ivc), vol(evo)
    assert mc.v_a == v_a and mc.v_b == v_b
    w_balance = q_total() - (mc.p_end * v_b - P_A * v_a) / (GAMMA - 1)
    assert abs(mc.closed_work / w_balance - 1) <= 1e-8
    # Motored part: the isentrope from V_a to V_b, (p_a V_a − p_b V_b)/(γ − 1); heat elements
    # as in the constant-γ test.
    w_mot = P_A * v_a * (1 - (v_a / v_b) ** (GAMMA - 1)) / (GAMMA - 1)
    w_elem = quad(lambda x: heat_rate(x) * (1 - (vol(x) / v_b) ** (GAMMA - 1)), START,
                  START + DURATION, epsabs=0, epsrel=1e-13, limit=200)[0]
    assert abs(mc.closed_work / (w_mot + w_elem) - 1) <= 1e-8


def test_numeric_volume_derivative(fired):
    mc = wiebe_cycle(volume, fuel_mass=FUEL, gamma=GAMMA, **BASE)   # dV/dx by differences
    assert mc.closed_work == pytest.approx(fired.closed_work, rel=1e-10)
    assert mc.p_max == pytest.approx(fired.p_max, rel=1e-10)
    x = off_knot(fired, math.pi, 3 * math.pi, 2)
    assert np.max(np.abs(mc.closed(x)[0] - fired.closed(x)[0])) <= 1e-10 * fired.p_max


def test_two_stroke():
    ivc, evo = 200 * DEG, 140 * DEG
    mc = wiebe_cycle(volume, dvolume=dvolume, fuel_mass=FUEL, gamma=GAMMA, strokes=2,
                     intake_closing=ivc, exhaust_opening=evo,
                     **dict(BASE, start=-2 * DEG, p_intake=None, p_exhaust=None))
    assert mc.period == 2 * math.pi and mc.strokes == 2
    end = (START + DURATION) - 2 * math.pi
    np.testing.assert_allclose(mc.corners, [0, end, evo, ivc, START, 2 * math.pi], rtol=0,
                               atol=1e-14)
    assert mc.combustion_start == pytest.approx(358 * DEG, abs=1e-14)
    # Continuous through the firing TDC at 2π ≡ 0 (inside the combustion).
    left = float(mc.evaluate(2 * math.pi, mc.n_pieces - 1)[0])
    assert left == pytest.approx(float(mc(0.0)), rel=1e-12)
    # Scavenged at p_a from exhaust opening to intake closing.
    assert mc(np.array([evo, 0.5 * (evo + ivc)])).tolist() == [P_A, P_A]
    # Work: closed part plus p_a·(V(ivc) − V(evo)); the table agrees.
    assert mc.work - mc.closed_work == pytest.approx(P_A * (vol(ivc) - vol(evo)), rel=1e-12)
    assert abs(table_loop_work(mc) / mc.work - 1) <= 1e-9
    # Same heat elements as the 4-stroke, on 2-stroke angles.
    v_a, v_b = vol(ivc), vol(evo)
    w_mot = P_A * v_a * (1 - (v_a / v_b) ** (GAMMA - 1)) / (GAMMA - 1)
    w_elem = quad(lambda x: heat_rate(x) * (1 - (vol(x) / v_b) ** (GAMMA - 1)), START,
                  START + DURATION, epsabs=0, epsrel=1e-13, limit=200)[0]
    assert abs(mc.closed_work / (w_mot + w_elem) - 1) <= 1e-8
    assert mc.interpolation_error <= DEFAULT_TOLERANCE


def test_fuel_levels():
    levels = [0.0, 0.02e-3, 0.04e-3, 0.06e-3]
    tabs = wiebe_tables(volume, levels, dvolume=dvolume, gamma=GAMMA, **BASE)
    assert len(tabs) == 4
    for t in tabs[1:]:
        np.testing.assert_array_equal(t.knots, tabs[0].knots)
        np.testing.assert_array_equal(t.piece_knot, tabs[0].piece_knot)
    assert [t.fuel_mass for t in tabs] == levels
    assert all(t.interpolation_error <= DEFAULT_TOLERANCE for t in tabs)
    # Each level against its heat-element work (constant γ: linear in the fuel).
    v_b = vol(3 * math.pi)
    unit = quad(lambda x: heat_rate(x, 1.0) * (1 - (vol(x) / v_b) ** (GAMMA - 1)), START,
                START + DURATION, epsabs=0, epsrel=1e-13, limit=200)[0]
    for t, q in zip(tabs, levels):
        assert abs(t.closed_work - q * unit) <= 1e-8 * max(q * unit, 1.0)
        x = off_knot(t, math.pi, 3 * math.pi, 1)
        x, p = reference_pressure_z(x, fuel=q)
        assert np.max(np.abs(t(x) - p)) / t.p_max <= t.interpolation_error + 2e-11
    assert np.all(np.diff([t.p_max for t in tabs]) > 0)
    # The motored level is the motored cycle (its knots are the union of all levels').
    single = wiebe_cycle(volume, dvolume=dvolume, fuel_mass=0.0, gamma=GAMMA, **BASE)
    assert tabs[0].closed_work == single.closed_work and tabs[0].work == single.work
    print(f"\nlevels {[q * 1e3 for q in levels]} g: p_max "
          f"{[round(t.p_max / 1e6, 3) for t in tabs]} MPa, p_i "
          f"{[round(t.mean_pressure / 1e6, 3) for t in tabs]} MPa; {tabs[0].knots.size} common "
          f"knots (motored alone {single.knots.size})")
