"""The shooting's pieces on their own: the energy coordinates Newton steps in, the step limit on
the speeds, and the bench's count of the cycles a direct run needs to settle."""
from __future__ import annotations

import math

import numpy as np

from transient.shooting import SPEED_FACTOR, _energy_coordinates, _speed_limited
from transient.verify.steady import settled_at

SPEEDS = np.array([0, 3])


def test_energy_coordinates_round_trip_and_their_slope_is_the_derivative():
    to_z, from_z, slope = _energy_coordinates(SPEEDS)
    x = np.array([420.0, -0.3, 2.5, -15.0])
    z = to_z(x)
    assert z[0] == 420.0 ** 2 and z[3] == -15.0 ** 2 and z[1] == -0.3 and z[2] == 2.5
    np.testing.assert_allclose(from_z(z), x, rtol=1e-15)
    for i in range(x.size):  # (central differences of each component)
        h = 1e-6 * max(abs(x[i]), 1.0)
        up, down = x.copy(), x.copy()
        up[i] += h
        down[i] -= h
        fd = (to_z(up)[i] - to_z(down)[i]) / (2 * h)
        assert abs(fd - slope(x)[i]) <= 1e-7 * abs(slope(x)[i])


def test_speed_limit_keeps_each_speed_within_its_factor():
    to_z, from_z, _ = _energy_coordinates(SPEEDS)
    x = np.array([100.0, 1.0, 1.0, 50.0])
    z = to_z(x)
    for dz in (np.array([1e9, 0, 0, 0]), np.array([0, 0, 0, -1e9]),
               np.array([-0.9 * z[0], 5.0, 0, 3 * z[3]])):
        lam = _speed_limited(z, dz, SPEEDS)
        moved = from_z(z + lam * dz)
        ratio = moved[SPEEDS] / x[SPEEDS]
        assert np.all(ratio <= SPEED_FACTOR * (1 + 1e-12))
        assert np.all(ratio >= (1 - 1e-12) / SPEED_FACTOR)
    assert _speed_limited(z, 0.1 * z, SPEEDS) == 1.0  # (a small step is taken whole)


def test_settled_cycle_of_a_geometric_approach_is_its_closed_form():
    """Speeds ω_n = ω*(1 + e₀μⁿ): within 1e-9 of the last from n ≥ log(1e-9/e₀)/log μ (the
    last is itself within e₀μ^N of ω*, far below)."""
    mu, e0, n = 0.8, 0.5, 200
    speeds = 400.0 * (1 + e0 * mu ** np.arange(n + 1))
    expected = math.ceil(math.log(1e-9 / e0) / math.log(mu))
    assert abs(settled_at(speeds) - expected) <= 1


def test_settled_cycle_is_held_to_the_run_own_scatter():
    """A noisy map (a jitter of 1e-8 from cycle to cycle): settled from where the approach is
    within that scatter, not never."""
    rng = np.random.default_rng(1)
    mu, e0, n = 0.5, 0.1, 80
    speeds = 400.0 * (1 + e0 * mu ** np.arange(n + 1) + 1e-8 * rng.uniform(-1, 1, n + 1))
    k = settled_at(speeds)
    assert 0 < k < n - 10
    assert e0 * mu ** k <= 4e-8  # (within twice the scatter's span of the last)
