"""The Wiebe burned fraction and its derivative; input errors of the Wiebe cycle builders."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from transient.errors import SceneError
from transient.forces.closed_cycle import wiebe_fraction, wiebe_rate
from transient.forces.wiebe import wiebe_cycle, wiebe_tables

DEG = math.pi / 180
START, DURATION = 358 * DEG, 50 * DEG
SHAPES = [(6.908, 0.5), (6.908, 2.0), (5.0, 0.0), (3.0, 1.3), (6.908, -0.4)]

# Gots crank slider (cases/gots_diesel_4400.toml): r = 47 mm, L = 148 mm, D = 88 mm, ε = 18.
R, L, BORE, EPS = 0.047, 0.148, 0.088, 18.0
F_P = math.pi * BORE ** 2 / 4
V_C = F_P * 2 * R / (EPS - 1)


def volume(x):
    x = np.asarray(x, dtype=float)
    return V_C + F_P * (R * (1 - np.cos(x)) + L * (1 - np.sqrt(1 - (R / L * np.sin(x)) ** 2)))


CYCLE = {"p_a": 0.1436e6, "p_intake": 0.165e6, "p_exhaust": 0.182e6, "start": START,
         "duration": DURATION}


@pytest.mark.parametrize("a, m", SHAPES)
def test_fraction_at_the_ends(a, m):
    end = START + DURATION
    x = np.array([START - 1.0, START, end, end + 1e-9, end + 1.0, 10 * end])
    xb = wiebe_fraction(x, START, DURATION, a, m)
    assert xb[0] == 0.0 and xb[1] == 0.0
    # The "end" of combustion leaves 1 − exp(−a) burned, not 1, and the fraction stays there.
    np.testing.assert_allclose(xb[2:], 1 - math.exp(-a), rtol=0, atol=1e-15)


@pytest.mark.parametrize("a, m", SHAPES)
def test_fraction_inside(a, m):
    y = np.array([1e-6, 0.01, 0.3, 0.5, 0.9, 0.999])
    xb = wiebe_fraction(START + y * DURATION, START, DURATION, a, m)
    # The closed form, with math instead of numpy (y recomputed from x as the function does).
    yy = (START + y * DURATION - START) / DURATION
    ref = [1 - math.exp(-a * v ** (m + 1)) for v in yy]
    np.testing.assert_allclose(xb, ref, rtol=1e-12, atol=1e-16)


@pytest.mark.parametrize("a, m", SHAPES)
def test_rate_is_the_derivative(a, m):
    y = np.linspace(0.01, 0.99, 99)
    x = START + y * DURATION
    h = 1e-3 * np.minimum(y, 1 - y) * DURATION     # the stencil stays inside (0, 1)
    # 4th-order central difference of the fraction.
    fd = (-wiebe_fraction(x + 2 * h, START, DURATION, a, m)
          + 8 * wiebe_fraction(x + h, START, DURATION, a, m)
          - 8 * wiebe_fraction(x - h, START, DURATION, a, m)
          + wiebe_fraction(x - 2 * h, START, DURATION, a, m)) / (12 * h)
    rate = wiebe_rate(x, START, DURATION, a, m)
    scale = np.max(np.abs(rate))
    assert np.max(np.abs(rate - fd)) <= 1e-9 * scale
    # Zero outside the combustion.
    out = np.array([START - 0.1, START + DURATION + 0.1])
    assert wiebe_rate(out, START, DURATION, a, m).tolist() == [0.0, 0.0]
    # Integrating the rate gives back the fraction (quad handles the y^m start for m < 0).
    for yi in (0.2, 0.7, 1.0):
        xi = START + yi * DURATION
        integral = quad(lambda t: float(wiebe_rate(t, START, DURATION, a, m)), START, xi,
                        epsabs=1e-12, epsrel=1e-10, limit=200)[0]
        assert integral == pytest.approx(float(wiebe_fraction(xi, START, DURATION, a, m)),
                                         abs=1e-10)


def test_rate_at_the_start():
    # One-sided derivative from inside: 0 for m > 0, a/duration for m = 0, inf for m < 0.
    assert float(wiebe_rate(START, START, DURATION, 6.908, 0.5)) == 0.0
    assert float(wiebe_rate(START, START, DURATION, 5.0, 0.0)) == pytest.approx(5.0 / DURATION)
    assert math.isinf(float(wiebe_rate(START, START, DURATION, 6.908, -0.5)))


@pytest.mark.parametrize("a, m", SHAPES)
def test_monotonic(a, m):
    x = np.linspace(START - 5 * DEG, START + DURATION + 5 * DEG, 20001)
    xb = wiebe_fraction(x, START, DURATION, a, m)
    assert np.all(np.diff(xb) >= 0.0)
    assert np.all(wiebe_rate(x, START, DURATION, a, m) >= 0.0)
    assert xb.min() == 0.0 and xb.max() <= 1 - math.exp(-a) + 1e-16


def expect(key, func, *args, **kwargs):
    with pytest.raises(SceneError) as info:
        func(*args, **kwargs)
    assert info.value.key == key, info.value.line()
    assert info.value.message and "\n" not in info.value.message
    return info.value.message


def test_fraction_errors():
    expect("gas.wiebe.duration_deg", wiebe_fraction, 0.0, START, 0.0)
    expect("gas.wiebe.duration_deg", wiebe_fraction, 0.0, START, -DURATION)
    expect("gas.wiebe.duration_deg", wiebe_rate, 0.0, START, float("nan"))
    expect("gas.wiebe.a", wiebe_fraction, 0.0, START, DURATION, 0.0)
    expect("gas.wiebe.a", wiebe_rate, 0.0, START, DURATION, -1.0)
    assert "-1" in expect("gas.wiebe.m", wiebe_fraction, 0.0, START, DURATION, 6.908, -1.0)
    expect("gas.wiebe.m", wiebe_rate, 0.0, START, DURATION, 6.908, -2.0)
    expect("gas.wiebe.start_deg", wiebe_fraction, 0.0, float("inf"), DURATION)


def cycle_error(key, **change):
    args = dict(CYCLE, fuel_mass=0.05e-3)
    args.update(change)
    return expect(key, wiebe_cycle, volume, **args)


def test_cycle_errors():
    cycle_error("gas.wiebe.fuel_mass", fuel_mass=-1e-6)
    cycle_error("gas.wiebe.fuel_mass", fuel_mass=float("nan"))
    cycle_error("gas.wiebe.duration_deg", duration=0.0)
    cycle_error("gas.wiebe.a", a=0.0)
    cycle_error("gas.wiebe.m", m=-1.0)
    assert "> 1" in cycle_error("gas.wiebe.gamma", gamma=1.0)
    cycle_error("gas.wiebe.gamma", gamma=0.9)
    cycle_error("gas.wiebe.lhv", lhv=0.0)
    cycle_error("gas.wiebe.efficiency", efficiency=0.0)
    cycle_error("gas.wiebe.efficiency", efficiency=1.2)
    cycle_error("gas.wiebe.t_a", t_a=-300.0)
    cycle_error("gas.wiebe.gamma_t_ref", gamma_t_ref=0.0)
    cycle_error("gas.wiebe.tolerance", tolerance=0.0)
    cycle_error("gas.wiebe.step_deg", step=0.0)
    cycle_error("gas.strokes", strokes=3)
    cycle_error("gas.p_a", p_a=-1.0)
    cycle_error("gas.p_intake", p_intake=None)
    cycle_error("gas.p_exhaust", p_exhaust=float("nan"))
    # Combustion outside the closed part (intake closing 180° → exhaust opening 540°).
    msg = cycle_error("gas.wiebe.start_deg", start=100 * DEG)
    assert "180" in msg and "540" in msg
    cycle_error("gas.wiebe.start_deg", start=600 * DEG)
    cycle_error("gas.wiebe.start_deg", start=-2 * DEG)          # 718°: a 4-stroke has 720°
    assert "540" in cycle_error("gas.wiebe.duration_deg", duration=200 * DEG)
    cycle_error("gas.wiebe.duration_deg", duration=90 * DEG, exhaust_opening=420 * DEG)
    cycle_error("gas.wiebe.start_deg", intake_closing=359 * DEG)
    cycle_error("gas.wiebe.duration_deg", duration=182.001 * DEG)         # ends after 540°
    # Valve timing out of range.
    cycle_error("gas.wiebe.intake_closing_deg", intake_closing=400 * DEG)
    cycle_error("gas.wiebe.intake_closing_deg", intake_closing=0.0)
    cycle_error("gas.wiebe.exhaust_opening_deg", exhaust_opening=300 * DEG)
    cycle_error("gas.wiebe.exhaust_opening_deg", exhaust_opening=720 * DEG)
    # 2-stroke: exhaust opening after the port closing.
    two = {"strokes": 2, "p_intake": None, "p_exhaust": None, "start": -2 * DEG}
    cycle_error("gas.wiebe.exhaust_opening_deg", intake_closing=200 * DEG,
                exhaust_opening=210 * DEG, **two)
    cycle_error("gas.wiebe.duration_deg", duration=200 * DEG, **two)


def test_combustion_may_end_at_exhaust_opening():
    mc = wiebe_cycle(volume, **dict(CYCLE, fuel_mass=0.05e-3, duration=182 * DEG))
    assert mc.combustion_end == mc.exhaust_opening == 3 * math.pi
    assert mc.burned_fraction == pytest.approx(1 - math.exp(-6.908), abs=1e-15)
    np.testing.assert_array_equal(mc.corners, [0, math.pi, START, 3 * math.pi, 4 * math.pi])


def test_gamma_of_t():
    # γ(T) = 1.3 − 1.2e-2 (T − 300 K) is 0.94 at T_a = 330 K.
    assert "0.94" in cycle_error("gas.wiebe.gamma_slope", gamma=1.3, gamma_slope=-1.2e-2,
                                 t_a=330.0)
    cycle_error("gas.wiebe.gamma_slope", gamma_slope=float("inf"))
    # γ(T) = 1.3 − 3e-4 (T − 300 K) is 1 at 1300 K: the temperature approaches it, never
    # crosses (dT/dx ∝ γ − 1), so γ stays > 1 although the fuel would heat the gas far above.
    mc = wiebe_cycle(volume, **dict(CYCLE, fuel_mass=0.05e-3, gamma=1.3, gamma_slope=-3e-4,
                                    t_a=330.0))
    assert 1000.0 < mc.t_max < 1300.0


def test_levels_errors():
    def levels_error(levels):
        return expect("gas.wiebe.fuel_levels", wiebe_tables, volume, levels, **CYCLE)

    levels_error([])
    levels_error([0.0, -1e-5])
    levels_error([0.0, float("nan")])
    assert "increase" in levels_error([0.0, 2e-5, 2e-5])
    levels_error([0.0, 3e-5, 2e-5])
    with pytest.raises(TypeError):
        wiebe_tables(volume, [0.0], fuel_mass=1e-5, **CYCLE)


def test_two_stroke_start_before_tdc_is_accepted():
    mc = wiebe_cycle(volume, fuel_mass=0.0, **dict(CYCLE, strokes=2, p_intake=None,
                                                    p_exhaust=None, start=-2 * DEG))
    assert mc.combustion_start == pytest.approx(358 * DEG, abs=1e-14)
    assert mc.combustion_end == pytest.approx(48 * DEG, abs=1e-14)
    assert mc.period == 2 * math.pi
