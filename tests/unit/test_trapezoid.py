"""The trapezoidal gas-force pulse of the swash-plate example (Antonyuk et al. §4)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from transient.errors import SceneError
from transient.forces.trapezoid import trapezoid_table

TWO_PI = 2.0 * math.pi


def integral(table):
    """Exact integral over the period of a piecewise-linear table (trapezoid rule on its knots)."""
    values = table.evaluate(table.knots[:-1], np.arange(table.knots.size - 1))[0]
    right = table.evaluate(table.knots[1:], np.arange(table.knots.size - 1))[0]
    return float(np.sum(0.5 * (values + right) * np.diff(table.knots)))


@pytest.mark.parametrize("amplitude, ramp, period, duration", [
    (8000.0, math.radians(30.0), TWO_PI, math.pi),
    (1.0, math.radians(1.0), TWO_PI, math.pi),
    (250.0, math.radians(45.0), 4.0 * math.pi, math.radians(400.0)),
])
def test_values_at_the_corners_and_between(amplitude, ramp, period, duration):
    t = trapezoid_table(amplitude, ramp, period, duration)
    assert t.period == period
    corners = [0.0, ramp, duration - ramp, duration, period]
    np.testing.assert_allclose(t.corners, corners, rtol=0, atol=1e-15 * period)
    # Left and right limits at every corner: continuous, only the slope changes.
    pieces = np.arange(4)
    left = t.evaluate(np.array(corners[1:]), pieces)[0]
    right = t.evaluate(np.array(corners[:-1]), pieces)[0]
    np.testing.assert_allclose(left, [amplitude, amplitude, 0.0, 0.0], rtol=1e-15, atol=0)
    np.testing.assert_allclose(right, [0.0, amplitude, amplitude, 0.0], rtol=1e-15, atol=0)
    # Linear rise and fall, flat plateau, zero after the pulse; periodic.
    x = np.array([0.25 * ramp, 0.5 * ramp, 0.5 * duration, duration - 0.5 * ramp,
                  0.5 * (duration + period)])
    expect = amplitude * np.array([0.25, 0.5, 1.0, 0.5, 0.0])
    np.testing.assert_allclose(t(x), expect, rtol=1e-14, atol=0)
    np.testing.assert_allclose(t(x + 3.0 * period), expect, rtol=1e-9, atol=1e-9 * amplitude)
    _, slope = t.evaluate(np.array([0.5 * ramp, duration - 0.5 * ramp]))
    np.testing.assert_allclose(slope, [amplitude / ramp, -amplitude / ramp], rtol=1e-12)


@pytest.mark.parametrize("amplitude, ramp, duration", [
    (8000.0, math.radians(30.0), math.pi), (3.5, math.radians(10.0), math.radians(120.0)),
    (2.0, math.radians(90.0), math.pi)])  # the last one a triangle
def test_area(amplitude, ramp, duration):
    t = trapezoid_table(amplitude, ramp, duration=duration)
    assert integral(t) == pytest.approx(amplitude * (duration - ramp), rel=1e-14)


def test_triangle_when_the_ramp_is_half_the_pulse():
    t = trapezoid_table(100.0, math.radians(90.0))
    np.testing.assert_allclose(t.corners, [0.0, math.pi / 2, math.pi, TWO_PI], atol=1e-15)
    assert t(math.pi / 2) == pytest.approx(100.0, rel=1e-15)
    assert t(math.pi / 4) == pytest.approx(50.0, rel=1e-15)


def test_zero_amplitude_is_allowed():
    t = trapezoid_table(0.0, math.radians(30.0))
    assert np.all(t(np.linspace(0.0, TWO_PI, 101)) == 0.0)


@pytest.mark.parametrize("kwargs, key", [
    (dict(amplitude=-1.0, ramp=0.5), "gas.amplitude"),
    (dict(amplitude=math.nan, ramp=0.5), "gas.amplitude"),
    (dict(amplitude=math.inf, ramp=0.5), "gas.amplitude"),
    (dict(amplitude=1.0, ramp=0.0), "gas.ramp_deg"),
    (dict(amplitude=1.0, ramp=-0.1), "gas.ramp_deg"),
    (dict(amplitude=1.0, ramp=math.pi / 2 + 1e-6), "gas.ramp_deg"),  # > duration/2
    (dict(amplitude=1.0, ramp=math.nan), "gas.ramp_deg"),
    (dict(amplitude=1.0, ramp=0.5, duration=TWO_PI), "gas.duration_deg"),  # = period
    (dict(amplitude=1.0, ramp=0.5, duration=7.0), "gas.duration_deg"),
    (dict(amplitude=1.0, ramp=0.5, duration=0.0), "gas.duration_deg"),
    (dict(amplitude=1.0, ramp=0.5, duration=-1.0), "gas.duration_deg"),
])
def test_errors(kwargs, key):
    with pytest.raises(SceneError) as info:
        trapezoid_table(**kwargs)
    assert info.value.key == key
    assert "\n" not in info.value.message
