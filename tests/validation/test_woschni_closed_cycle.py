"""Closed cycle with Woschni wall heat transfer (``transient.forces.woschni``) on the Gots diesel.

Engine and cycle: ``cases/gots_diesel_wiebe.toml`` (r = 47 mm, L = 148 mm, D = 88 mm, ε = 18,
p_a = 0.1436 MPa, T_a = 329.9 K, combustion from 358° for 50°, m = 0.5, 0.031 g of fuel, γ = 1.368
constant), loaded with ``load_scene`` and built into wiebe.py's tables by
``transient.scene.queries.wiebe_levels`` (the tables a run uses). Woschni's defaults c1 = 2.28,
c2 = 3.24e-3 m/(s K), T_w = 450 K.

The checks are independent of the module's formulation: wiebe.py's own integration (h = 0), the
first law written in closed form for the internal energy, a quadrature of the vectorised heat
flow along the dense solution, hand arithmetic for the scalar functions. Run with ``-s`` to see
the numbers.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import CASES
from scipy.integrate import quad

from transient.errors import SceneError
from transient.forces.wiebe import wiebe_cycle
from transient.forces.woschni import (
    WoschniParameters,
    closed_cycle,
    closed_rate,
    gas_velocity,
    heat_transfer_rate,
    motored_pressure,
    wall_area,
    wall_heat_flow,
    woschni_coefficient,
)
from transient.scene import load_scene
from transient.scene.queries import clearance_volume, wiebe_levels

DEG = math.pi / 180
RPM = math.pi / 30


@pytest.fixture(scope="module")
def gots():
    """(scene, volume function, closed_cycle keywords, WoschniParameters) of the Gots diesel."""
    scene = load_scene(CASES / "gots_diesel_wiebe.toml")
    gas, w = scene.gas, scene.gas.wiebe
    volume = scene.mechanism.volume_function(clearance_volume(scene))
    kw = {"p_a": gas.p_a, "start": w.start, "duration": w.duration, "a": w.a, "m": w.m,
          "lhv": w.lhv, "efficiency": w.efficiency, "gamma": w.gamma,
          "gamma_slope": w.gamma_slope, "gamma_t_ref": w.gamma_t_ref, "t_a": w.t_a,
          "strokes": scene.mechanism.strokes, "intake_closing": w.intake_closing,
          "exhaust_opening": w.exhaust_opening}
    return scene, volume, kw, WoschniParameters.of_mechanism(scene.mechanism)


def internal_energy(c, p, v, gamma, gamma_slope=0.0, gamma_t_ref=300.0):
    """U(T) − U(T_a) [J] in closed form: m c_v = mR/(γ(T) − 1) and mR = p_a V_a/T_a, so
    ∫ mR/(γ(T) − 1) dT is pV/(γ − 1) − p_a V_a/(γ − 1) for a constant γ and
    (mR/k)·ln((γ(T) − 1)/(γ(T_a) − 1)) for γ = γ0 + k (T − T_ref)."""
    if gamma_slope == 0.0:
        return (p * v - c.p_a * c.v_a) / (gamma - 1)
    mr = c.p_a * c.v_a / c.t_a
    g = lambda t: gamma + gamma_slope * (t - gamma_t_ref)
    t = c.t_a * p * v / (c.p_a * c.v_a)
    return mr / gamma_slope * math.log((g(t) - 1) / (g(c.t_a) - 1))


def peak_h(c):
    """Largest Woschni h [W/(m² K)] on a 0.01° scan of the closed part, break points included."""
    x = np.union1d(np.arange(c.start, c.end, 0.01 * DEG), c.breaks)
    return float(np.max(c.heat_transfer(x)[0]))


# ----------------------------------------------------------------------------------------
# 1. h = 0 is wiebe.py's closed part
# ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("no_heat", ["None", "c1=c2=0"])
def test_no_heat_transfer_is_the_wiebe_closed_part(gots, no_heat):
    """Both fuel levels of the scene (motored, full load) against the tables a run uses."""
    scene, volume, kw, wp = gots
    woschni = None if no_heat == "None" else WoschniParameters(wp.bore, wp.stroke, 0.0, 0.0)
    tables = wiebe_levels(scene.mechanism, scene.gas)
    for tab in tables:
        c = closed_cycle(volume, fuel_mass=tab.fuel_mass, woschni=woschni, omega=4400 * RPM,
                         **kw)
        x = np.linspace(c.start, c.end, 7201)
        dense = np.max(np.abs(c.pressure(x) / tab.closed(x)[0] - 1))
        # The table's ends of the closed part belong to the constant gas-exchange pieces.
        table = np.max(np.abs(c.pressure(x[1:-1]) - tab(x[1:-1]))) / tab.p_max
        print(f"\n[{no_heat}, fuel {tab.fuel_mass * 1e3:g} g] max |p/p_wiebe − 1| dense {dense:.2e},"
              f" |p − table|/p_max {table:.2e}; W {c.work:.10g} J vs {tab.closed_work:.10g} J, "
              f"p_EVO {c.p_end:.10g} vs {tab.p_end:.10g} Pa, p_max {c.p_max:.10g} vs "
              f"{tab.p_max:.10g} Pa, Q_w {c.heat_lost!r}")
        assert dense <= 1e-9
        assert table <= 1e-9
        # The motored loop work is ~0 J: measured against the compression work.
        scale = max(abs(tab.closed_work), abs(float(tab.closed(np.array([2 * math.pi]))[1][0])))
        assert abs(c.work - tab.closed_work) <= 1e-9 * scale
        assert c.p_end == pytest.approx(tab.p_end, rel=1e-9)
        assert c.p_max == pytest.approx(tab.p_max, rel=1e-9)
        assert c.t_max == pytest.approx(tab.t_max, rel=1e-9)
        assert c.heat_released == pytest.approx(tab.heat_released, rel=1e-14)
        assert c.heat_lost == 0.0


def gots_volume():
    """The Gots crank slider written out (Gots eq. (1)–(2)), for the direct-call cases."""
    r, l, bore, eps = 0.047, 0.148, 0.088, 18.0
    f_p = math.pi * bore ** 2 / 4
    v_c = f_p * 2 * r / (eps - 1)

    def volume(x):
        x = np.asarray(x, dtype=float)
        return v_c + f_p * (r * (1 - np.cos(x)) + l * (1 - np.sqrt(1 - (r / l * np.sin(x)) ** 2)))

    return volume, WoschniParameters(bore=bore, stroke=2 * r)


# 2-stroke (closed part through 2π ≡ 0), m < 0 (integrated in u = y**(m + 1)) and γ(T).
TWO_STROKE = {"strokes": 2, "p_a": 0.15e6, "t_a": 330.0, "start": -5 * DEG,
              "duration": 60 * DEG, "a": 6.908, "m": -0.3, "lhv": 42.5e6, "gamma": 1.38,
              "gamma_slope": -1e-4, "gamma_t_ref": 300.0, "intake_closing": 230 * DEG,
              "exhaust_opening": 110 * DEG}


def test_no_heat_transfer_two_stroke_m_negative():
    volume, wp = gots_volume()
    tab = wiebe_cycle(volume, fuel_mass=0.03e-3, **TWO_STROKE)
    c = closed_cycle(volume, fuel_mass=0.03e-3, woschni=WoschniParameters(wp.bore, wp.stroke,
                                                                          0.0, 0.0),
                     omega=3000 * RPM, **TWO_STROKE)
    x = np.linspace(c.start, c.end, 7201)
    dense = np.max(np.abs(c.pressure(x) / tab.closed(x)[0] - 1))
    print(f"\n[2-stroke, m = -0.3, γ(T)] max |p/p_wiebe − 1| {dense:.2e}, W {c.work:.10g} vs "
          f"{tab.closed_work:.10g} J, p_max {c.p_max:.6g} Pa")
    assert c.end > 2 * math.pi
    assert dense <= 1e-9
    assert c.work == pytest.approx(tab.closed_work, rel=1e-9)
    assert c.p_end == pytest.approx(tab.p_end, rel=1e-9)


# ----------------------------------------------------------------------------------------
# 2. First law, and the heat lost against a quadrature of the vectorised heat flow
# ----------------------------------------------------------------------------------------

def test_first_law_constant_gamma(gots):
    """Q_b − Q_w = [pV/(γ − 1)]_IVC^EVO + W with the Gots γ = 1.368 (gamma_slope = 0)."""
    scene, volume, kw, wp = gots
    assert kw["gamma_slope"] == 0.0
    for rpm in (1000, 4400):
        c = closed_cycle(volume, fuel_mass=scene.gas.wiebe.fuel_mass, woschni=wp,
                         omega=rpm * RPM, **kw)
        lhs = c.heat_released - c.heat_lost
        rhs = internal_energy(c, c.p_end, c.v_end, kw["gamma"]) + c.work
        err = abs(lhs - rhs) / c.heat_released
        print(f"\n[{rpm} rpm] Q_b {c.heat_released:.8g} J, Q_w {c.heat_lost:.8g} J, "
              f"ΔU {rhs - c.work:.8g} J, W {c.work:.8g} J: first-law residual {err:.2e} of Q_b")
        assert c.heat_lost > 0.0
        assert err <= 1e-9


def test_first_law_gamma_of_t_two_stroke_varying_speed():
    """γ(T), m < 0 (the u-substituted segment carries Q_w too), a 2-stroke and ω(x)."""
    volume, wp = gots_volume()
    omega = lambda x: 3000 * RPM * (1 + 0.2 * math.sin(x))
    c = closed_cycle(volume, fuel_mass=0.03e-3, woschni=wp, omega=omega, **TWO_STROKE)
    du = internal_energy(c, c.p_end, c.v_end, TWO_STROKE["gamma"], TWO_STROKE["gamma_slope"],
                         TWO_STROKE["gamma_t_ref"])
    err = abs(c.heat_released - c.heat_lost - du - c.work) / c.heat_released
    print(f"\n[2-stroke, γ(T), m = -0.3, ω(x)] Q_b {c.heat_released:.8g} J, Q_w "
          f"{c.heat_lost:.8g} J, ΔU {du:.8g} J, W {c.work:.8g} J: residual {err:.2e} of Q_b")
    assert c.heat_lost > 0.0
    assert err <= 1e-9


@pytest.mark.parametrize("case", ["gots 2000 rpm", "2-stroke ω(x)"])
def test_heat_lost_is_the_integral_of_the_heat_flow(gots, case):
    """Q_w (an ODE component, scalar functions) = ∫ Q̇_w(x)/ω dx by adaptive quadrature of the
    vectorised :func:`heat_transfer_rate` along the dense pressure, segment by segment."""
    if case == "gots 2000 rpm":
        scene, volume, kw, wp = gots
        omega = lambda x: 2000 * RPM
        c = closed_cycle(volume, fuel_mass=scene.gas.wiebe.fuel_mass, woschni=wp,
                         omega=2000 * RPM, **kw)
    else:
        volume, wp = gots_volume()
        omega = lambda x: 3000 * RPM * (1 + 0.2 * math.sin(x))
        c = closed_cycle(volume, fuel_mass=0.03e-3, woschni=wp, omega=omega, **TWO_STROKE)

    def integrand(x):
        q = c.heat_transfer(np.array([x]))[1][0]
        return q / omega(x)

    total = 0.0
    for lo, hi in zip(c.breaks[:-1], c.breaks[1:]):
        val, _ = quad(integrand, lo, hi, epsabs=0.0, epsrel=1e-12, limit=400)
        total += val
    err = abs(total - c.heat_lost) / abs(c.heat_lost)
    print(f"\n[{case}] Q_w ODE {c.heat_lost:.12g} J, quadrature {total:.12g} J: rel {err:.2e}")
    assert err <= 1e-8


# ----------------------------------------------------------------------------------------
# 3. Motored cycle
# ----------------------------------------------------------------------------------------

def test_motored_cycle(gots):
    """With heat transfer the motored loop is a net loss and ends below the isentrope; without
    it the closed-part work vanishes (IVC and EVO at the BDCs, constant γ)."""
    _scene, volume, kw, wp = gots
    bare = closed_cycle(volume, fuel_mass=0.0, **kw)
    w_compression = abs(float(bare.state(np.array([2 * math.pi]))[1][0]))
    rel = abs(bare.work) / w_compression
    print(f"\n[motored, no heat transfer] W {bare.work:.3e} J against a compression work "
          f"{w_compression:.6g} J: {rel:.2e}")
    assert rel <= 1e-9
    for rpm in (1000, 4400):
        c = closed_cycle(volume, fuel_mass=0.0, woschni=wp, omega=rpm * RPM, **kw)
        p_isentrope = c.p_a * (c.v_a / c.v_end) ** kw["gamma"]
        print(f"[motored, {rpm} rpm] W {c.work:.6g} J, Q_w {c.heat_lost:.6g} J, "
              f"p_EVO {c.p_end:.6g} Pa against the isentrope's {p_isentrope:.6g} Pa, "
              f"p_max {c.p_max:.6g} Pa (no heat transfer {bare.p_max:.6g} Pa)")
        assert c.work < 0.0
        assert c.p_end < p_isentrope
        assert c.p_max < bare.p_max


# ----------------------------------------------------------------------------------------
# 4. Speed dependence and 5. magnitudes
# ----------------------------------------------------------------------------------------

def test_heat_loss_fraction_falls_with_speed(gots):
    """Q_w/Q_b falls as ω rises: h ∝ w^0.8 while the time per degree ∝ 1/ω. At a fixed gas
    state the c1·c_m part of w scales the loss as ω^(0.8 − 1) = ω^−0.2 and the c2 part (not
    proportional to ω) as ω^−1; the hotter gas of a smaller loss raises it a little, so the
    fitted exponent is expected in (−1, −0.1)."""
    scene, volume, kw, wp = gots
    rpms = np.array([1000.0, 2000.0, 4000.0])
    ratio = np.array([
        (c := closed_cycle(volume, fuel_mass=scene.gas.wiebe.fuel_mass, woschni=wp,
                           omega=n * RPM, **kw)).heat_lost / c.heat_released for n in rpms])
    exponent = np.polyfit(np.log(rpms), np.log(ratio), 1)[0]
    local = np.diff(np.log(ratio)) / np.diff(np.log(rpms))
    print(f"\nQ_w/Q_b at {rpms.tolist()} rpm: {np.round(ratio, 5).tolist()}; fitted exponent "
          f"{exponent:.4f} (local {np.round(local, 4).tolist()})")
    assert np.all(np.diff(ratio) < 0.0)
    assert -1.0 < exponent < -0.1


def test_magnitudes_against_the_literature(gots):
    """Peak h and the share of the fuel heat lost, Gots diesel at full load, 2000–4400 rpm.

    The windows are order-of-magnitude bounds set for this check, not numbers read off a
    published figure or table: peak h in (300, 10 000) W/(m² K) brackets the order 10³ W/(m² K)
    of Woschni-type coefficients in diesel combustion chambers that Heywood's ch. 12 discusses
    with eq. (12.19); Q_w/Q_b in (0.03, 0.4) brackets
    a wall loss of some tens of percent of the fuel heat (Heywood's energy balances, §12.1).
    Pages and figures of Heywood were not re-checked for this test. The Gots App. 2 indicated
    efficiency η_i = 0.428 is a further reference point (this model without heat transfer gives
    0.616, ``cases/gots_diesel_wiebe.toml``); it is printed, not asserted.
    """
    scene, volume, kw, wp = gots
    gas = scene.gas
    fuel = gas.wiebe.fuel_mass
    v_tdc0 = float(volume(np.array([0.0]))[0])
    v_end = float(volume(np.array([4 * math.pi]))[0])
    for rpm in (2000, 3000, 4400):
        c = closed_cycle(volume, fuel_mass=fuel, woschni=wp, omega=rpm * RPM, **kw)
        h = peak_h(c)
        ratio = c.heat_lost / c.heat_released
        # Loop work: the closed part plus the constant-pressure pumping loop (as WiebeCycle.work).
        loop = c.work + gas.p_intake * (c.v_a - v_tdc0) + gas.p_exhaust * (v_end - c.v_end)
        eta_i = loop / (fuel * gas.wiebe.lhv)
        print(f"\n[{rpm} rpm] peak h {h:.5g} W/(m² K), Q_w/Q_b {ratio:.4f}, p_max "
              f"{c.p_max / 1e6:.4f} MPa, T_max {c.t_max:.5g} K, T_EVO {c.t_end:.5g} K, "
              f"η_i {eta_i:.4f}")
        assert 300.0 < h < 10_000.0
        assert 0.03 < ratio < 0.4


# ----------------------------------------------------------------------------------------
# 6. Scalar functions by hand
# ----------------------------------------------------------------------------------------

def test_woschni_coefficient_by_hand():
    """p = 6 MPa, T = 1800 K, w = 23.481 m/s, B = 0.1 m.

    (p/1000)^0.8 = 6000^0.8 = 10^(0.8·3.7781513) = 10^3.0225210 = 1053.2246
    B^−0.2 = 0.1^−0.2 = 10^0.2 = 1.5848932
    T^−0.55 = 1800^−0.55 = 10^(−0.55·3.2552725) = 10^−1.7903999 = 0.016203175
    w^0.8 = 23.481^0.8 = 10^(0.8·1.3707209) = 10^1.0965767 = 12.490312
    h = 3.26 · 1.5848932 · 1053.2246 · 0.016203175 · 12.490312 = 1101.316 W/(m² K)
    """
    hand = 3.26 * 1.5848932 * 1053.2246 * 0.016203175 * 12.490312
    assert hand == pytest.approx(1101.316, rel=1e-6)
    assert woschni_coefficient(6e6, 1800.0, 23.481, 0.1) == pytest.approx(hand, rel=1e-6)
    # No velocity, no pressure: no transfer (the limit of w^0.8, p^0.8).
    assert woschni_coefficient(6e6, 1800.0, 0.0, 0.1) == 0.0
    assert woschni_coefficient(0.0, 1800.0, 23.481, 0.1) == 0.0


def test_gas_velocity_by_hand():
    """c1 = 2.28, c_m = 6 m/s, c2 = 3.24e-3, V_h = 5.5e-4 m³, T_a = 330 K, p_a = 1e5 Pa,
    V_a = 6e-4 m³, p − p_mot = 1 MPa:

    V_h·T_a/(p_a·V_a) = 5.5e-4·330/(1e5·6e-4) = 0.1815/60 = 3.025e-3 m³ K/J
    w = 2.28·6 + 3.24e-3·3.025e-3·1e6 = 13.68 + 9.801 = 23.481 m/s
    Below the motored pressure, or with c2 off, only 13.68 m/s.
    """
    args = (6.0, 6e6, 5e6, 5.5e-4, 330.0, 1e5, 6e-4)
    assert gas_velocity(2.28, 3.24e-3, *args) == pytest.approx(23.481, rel=1e-14)
    assert gas_velocity(2.28, 0.0, *args) == pytest.approx(13.68, rel=1e-14)
    assert gas_velocity(2.28, 3.24e-3, 6.0, 4e6, 5e6, 5.5e-4, 330.0, 1e5,
                        6e-4) == pytest.approx(13.68, rel=1e-14)


def test_wall_area_and_motored_pressure_by_hand():
    """A_w(V = 1e-4 m³, B = 0.1 m) = π·0.01/2 + 4·1e-4/0.1 = 0.01570796327 + 0.004 = 0.01970796327 m²;
    p_mot(V = 1e-4, p_a = 1e5, V_a = 1e-3, γ_a = 1.4) = 1e5·10^1.4 = 1e5·25.1188643 = 2.51188643 MPa.
    """
    assert wall_area(1e-4, 0.1) == pytest.approx(0.01970796327, rel=1e-9)
    assert motored_pressure(1e-4, 1e5, 1e-3, 1.4) == pytest.approx(2.51188643e6, rel=1e-8)


def test_wall_heat_flow_and_closed_rate_by_hand():
    """B = 0.1 m, S = 0.09 m, ω = 2000 rpm = 209.43951 rad/s, T_a = 330 K, p_a = 1e5 Pa,
    V_a = 6e-4 m³, γ_a = 1.4, state p = 6 MPa, V = 1e-4 m³, T_w = 450 K, c2 on:

    c_m = S·ω/π = 0.09·2000/30 = 6 m/s;  V_h = π/4·0.1²·0.09 = 7.0685835e-4 m³
    T = 330·6e6·1e-4/(1e5·6e-4) = 198000/60 = 3300 K
    p_mot = 1e5·(6e-4/1e-4)^1.4 = 1e5·6^1.4 = 1e5·12.286035 = 1.2286035 MPa
    V_h·T_a/(p_a·V_a) = 7.0685835e-4·330/60 = 3.8877209e-3
    w = 2.28·6 + 3.24e-3·3.8877209e-3·(6e6 − 1.2286035e6) = 13.68 + 60.101540 = 73.781540 m/s
    h = 3.26·1.5848932·1053.2246·3300^−0.55·73.781540^0.8
      = 3.26·1.5848932·1053.2246·0.011609602·31.214629 = 1972.0327 W/(m² K)
    A_w = 0.019707963 m² (as above);  Q̇_w = 1972.0327·0.019707963·(3300 − 450) = 110764.53 W

    closed_rate at the same state, burning, m = 0, a = 6.908, y = 0.5, duration 0.8 rad,
    q_total 1500 J, γ = 1.4 constant (so γ_a = 1.4 as above), dV/dx = 2e-5 m³/rad:
    dQ_b/dx = 1500·6.908·exp(−3.454)/0.8 = 1500·6.908·0.031618907/0.8 = 409.54390 J/rad
    Q̇_w/ω = 110764.53/209.43951 = 528.86167 J/rad
    dp/dx = 0.4/1e-4·(409.54390 − 528.86167) − 1.4·6e6/1e-4·2e-5
          = −477271.08 − 1680000 = −2157271.08 Pa/rad
    Not burning: 0.4/1e-4·(−528.86167) − 1680000 = −3795446.68 Pa/rad.
    """
    omega = 2000 * RPM
    q = wall_heat_flow(6e6, 1e-4, omega, 330.0, 1e5, 6e-4, 1.4, 2.28, 3.24e-3, 450.0, 0.1, 0.09)
    hand_q = 3.26 * 1.5848932 * 1053.2246 * 0.011609602 * 31.214629 * 0.019707963 * 2850.0
    assert hand_q == pytest.approx(110764.53, rel=1e-7)
    assert q == pytest.approx(hand_q, rel=1e-6)
    start, duration = 1.0, 0.8
    args = (6e6, 1e-4, 2e-5, omega, 1500.0, start, duration, 6.908, 0.0)
    rest = (1.4, 0.0, 300.0, 330.0, 1e5, 6e-4, 2.28, 3.24e-3, 450.0, 0.1, 0.09)
    dp = closed_rate(start + 0.5 * duration, *args, True, *rest)
    assert dp == pytest.approx(-2157271.08, rel=1e-6)
    # Not burning: the heat release is off, the wall loss stays.
    dp_off = closed_rate(start + 0.5 * duration, *args, False, *rest)
    assert dp_off == pytest.approx(-3795446.68, rel=1e-6)


def test_wall_area_grows_by_four_over_bore_per_volume(gots):
    """dA_w/dV = 4/B: by a central difference in V, and along the crank angle through the
    mechanism's volume (dA_w/dx = 4/B·dV/dx, both sides by central differences)."""
    _scene, volume, _kw, wp = gots
    b = wp.bore
    for v in (5e-5, 3e-4, 6e-4):
        dv = 1e-3 * v
        slope = (wall_area(v + dv, b) - wall_area(v - dv, b)) / (2 * dv)
        assert slope == pytest.approx(4 / b, rel=1e-9)
    x = np.linspace(0.1, 4 * math.pi - 0.1, 37)
    hx = 1e-5
    area = np.vectorize(lambda z: wall_area(float(volume(np.array([z]))[0]), b))
    da = (area(x + hx) - area(x - hx)) / (2 * hx)
    dvx = (volume(x + hx) - volume(x - hx)) / (2 * hx)
    err = np.max(np.abs(da - 4 / b * dvx)) / np.max(np.abs(4 / b * dvx))
    print(f"\ndA_w/dx against 4/B·dV/dx: {err:.2e} of its largest value")
    assert err <= 1e-8


def test_vectorised_twin_matches_the_scalar_functions(gots):
    """heat_transfer_rate (numpy) against wall_heat_flow/woschni_coefficient (scalars) at random
    states, both sides of the combustion start and of the motored pressure."""
    _scene, _volume, _kw, wp = gots
    rng = np.random.default_rng(6)
    n = 200
    x = rng.uniform(3.0, 9.0, n)
    p = rng.uniform(0.05e6, 15e6, n)
    v = rng.uniform(3.5e-5, 6e-4, n)
    omega = rng.uniform(50.0, 500.0, n)
    ref = {"combustion_start": 6.2, "p_a": 0.1436e6, "v_a": 6.05e-4, "t_a": 329.9,
           "gamma_a": 1.368}
    h, q = heat_transfer_rate(x, p, v, omega, wp, **ref)
    for i in range(n):
        c2 = wp.c2 if x[i] >= ref["combustion_start"] else 0.0
        qi = wall_heat_flow(p[i], v[i], omega[i], ref["t_a"], ref["p_a"], ref["v_a"],
                            ref["gamma_a"], wp.c1, c2, wp.wall_temperature, wp.bore, wp.stroke)
        assert q[i] == pytest.approx(qi, rel=1e-12, abs=1e-12)
    assert np.all(h > 0.0)


# ----------------------------------------------------------------------------------------
# 7. Bad input
# ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("field, value, key", [
    ("c1", -0.1, "gas.woschni.c1"), ("c1", math.nan, "gas.woschni.c1"),
    ("c1", math.inf, "gas.woschni.c1"), ("c1", "2.28", "gas.woschni.c1"),
    ("c2", -1e-3, "gas.woschni.c2"), ("c2", math.nan, "gas.woschni.c2"),
    ("c2", math.inf, "gas.woschni.c2"), ("c2", None, "gas.woschni.c2"),
    ("wall_temperature", 0.0, "gas.woschni.wall_temperature"),
    ("wall_temperature", -300.0, "gas.woschni.wall_temperature"),
    ("wall_temperature", math.nan, "gas.woschni.wall_temperature"),
    ("wall_temperature", math.inf, "gas.woschni.wall_temperature"),
    ("bore", 0.0, "mechanism.bore"), ("stroke", -0.094, "mechanism.crank_radius"),
])
def test_bad_parameters(field, value, key):
    good = {"bore": 0.088, "stroke": 0.094, "c1": 2.28, "c2": 3.24e-3,
            "wall_temperature": 450.0}
    with pytest.raises(SceneError) as err:
        WoschniParameters(**{**good, field: value})
    assert err.value.key == key


def test_bad_cycle_input(gots):
    _scene, volume, kw, wp = gots
    with pytest.raises(SceneError) as err:
        closed_cycle(volume, fuel_mass=-1e-6, woschni=wp, omega=400.0, **kw)
    assert err.value.key == "gas.wiebe.fuel_mass"
    with pytest.raises(SceneError) as err:
        closed_cycle(volume, fuel_mass=1e-5, woschni=wp, omega=400.0, **{**kw, "duration": 0.0})
    assert err.value.key == "gas.wiebe.duration_deg"
    with pytest.raises(ValueError, match="omega"):
        closed_cycle(volume, fuel_mass=1e-5, woschni=wp, **kw)
    with pytest.raises(ValueError, match="omega"):
        closed_cycle(volume, fuel_mass=1e-5, woschni=wp, omega=0.0, **kw)
    with pytest.raises(ValueError, match="omega"):
        closed_cycle(volume, fuel_mass=1e-5, woschni=wp, omega=lambda x: -1.0, **kw)
