"""What the figures over a run are built on, against hand computations: each cycle's least and
greatest value (:func:`transient.analysis.irregularity.cycle_extremes`) and when a run counts as
a run-up (:func:`transient.analysis.orders.is_run_up`)."""
from __future__ import annotations

import numpy as np
import pytest

from transient.analysis.irregularity import cycle_extremes
from transient.analysis.orders import RUN_UP_CYCLES, RUN_UP_SPAN, is_run_up


def test_cycle_extremes_of_samples_and_window_ends():
    """v = t² sampled at t = 0, 1, …, 6 in windows [0.5, 2.5], [2.5, 5.2]: the first holds the
    samples 1, 4 and the ends 0.5, 6.5 (on the lines between the samples), the second 9, 16, 25
    and the ends 6.5, 27.2 (25 + 0.2·11)."""
    t = np.arange(7.0)
    lo, hi = cycle_extremes(t, t**2, [0.5, 2.5, 5.2])
    np.testing.assert_allclose(lo, [0.5, 6.5], rtol=1e-15)
    np.testing.assert_allclose(hi, [6.5, 27.2], rtol=1e-15)


def test_cycle_extremes_of_a_window_between_two_samples():
    """A window inside one sample interval has only its interpolated ends."""
    lo, hi = cycle_extremes([0.0, 1.0], [2.0, 4.0], [0.25, 0.75])
    assert lo[0] == pytest.approx(2.5) and hi[0] == pytest.approx(3.5)


def test_cycle_extremes_of_a_sine():
    """sin(2π t) over whole periods: −1 and 1 in each, at a sampling that hits the peaks."""
    t = np.linspace(0.0, 5.0, 2001)
    lo, hi = cycle_extremes(t, np.sin(2 * np.pi * t), np.arange(6.0))
    np.testing.assert_allclose(lo, -1.0, rtol=1e-12)
    np.testing.assert_allclose(hi, 1.0, rtol=1e-12)


def test_run_up():
    """A sweep of the speed over enough cycles is a run-up (or a run-down); a small swing, a
    machine up to speed in a cycle, or too few cycles inside the sweep are not."""
    assert RUN_UP_SPAN == 0.2 and RUN_UP_CYCLES == 4
    sweep = np.linspace(100.0, 300.0, 12)
    assert is_run_up(sweep) and is_run_up(sweep[::-1])
    assert not is_run_up(300.0 + 5.0 * np.sin(np.arange(50.0)))  # a steady run's wobble
    assert not is_run_up(np.r_[100.0, np.full(40, 300.0)])  # up to speed in one cycle
    # the span: just below a fifth of the highest speed is no run-up, just above is
    assert not is_run_up(np.linspace(0.801 * 300.0, 300.0, 20))
    assert is_run_up(np.linspace(0.799 * 300.0, 300.0, 20))
    # cycles inside the span (more than a tenth of it from either end): three are too few
    assert not is_run_up(np.r_[100.0, 150.0, 200.0, 250.0, 300.0])
    assert is_run_up(np.r_[100.0, 140.0, 180.0, 220.0, 260.0, 300.0])
    assert not is_run_up([300.0])
