"""The quadrature of stored samples behind ∮p dV
(:func:`transient.analysis.thermo.integrals_between`) against closed forms: a smooth function
converges as h⁷ or faster (degree 6), a jump given as a cut or written as two samples at one
angle is integrated as two smooth pieces, a sample on a cut that holds the wrong side is not
used, and marks between samples are exact nodes."""
from __future__ import annotations

import math

import numpy as np
import pytest

from transient.analysis.thermo import integrals_between


def f(x):
    """sin x + 0.3 cos 3x below 2, and 5 + x² from 2 on: a jump of ≈ 9.5 at x = 2."""
    return np.where(x < 2.0, np.sin(x) + 0.3 * np.cos(3 * x), 5.0 + x * x)


def F(x):
    """Its antiderivative, continuous across 2 by construction of the pieces' integrals."""
    x = np.asarray(x, dtype=float)
    lo = -np.cos(np.minimum(x, 2.0)) + 0.1 * np.sin(3 * np.minimum(x, 2.0))
    hi = np.where(x > 2.0, 5.0 * (x - 2.0) + (x ** 3 - 8.0) / 3.0, 0.0)
    return lo - (-1.0) + hi


def test_smooth_pieces_and_a_cut_converge_as_h7():
    """Measured: 5.9e-9 at h = 0.05, 1.9e-11 at 0.025 (the interval next to the cut, which
    is extrapolated over); asserted ≤ 1e-8 and a ratio ≥ 2⁶ per halving."""
    marks = np.array([0.013, 1.0, 2.0, 3.3333, 4.0])
    want = np.diff(F(marks))
    errors = []
    for h in (0.05, 0.025):
        x = np.arange(0.0, 4.0 + h / 2, h)  # 2.0 is a sample: it holds the right side
        errors.append(np.max(np.abs(integrals_between(x, f(x), marks, cuts=[2.0]) - want)))
    assert errors[0] <= 1e-8 and errors[0] / errors[1] >= 2 ** 6


def test_a_jump_written_twice_and_a_wrong_sided_sample():
    h = 0.02
    x = np.arange(0.0, 4.0 + h / 2, h)
    x = np.sort(np.append(x, 2.0))  # 2.0 twice: left and right limits
    v = f(x)
    i = np.searchsorted(x, 2.0)  # the first of the pair holds the left limit
    v[i] = math.sin(2.0) + 0.3 * math.cos(6.0)
    marks = np.array([0.0, 4.0])
    assert integrals_between(x, v, marks)[0] == pytest.approx(F(4.0) - F(0.0), rel=1e-12)
    # a single sample on the cut holding the left limit is left out with the cut given
    y = np.arange(0.0, 4.0 + h / 2, h)
    w = f(y)
    w[np.argmin(np.abs(y - 2.0))] = math.sin(2.0) + 0.3 * math.cos(6.0)
    assert integrals_between(y, w, marks, cuts=[2.0])[0] == pytest.approx(F(4.0) - F(0.0),
                                                                           rel=1e-12)
    # without the cut the jump is smeared: the rule is only as good as its cuts
    assert abs(integrals_between(y, w, marks)[0] - (F(4.0) - F(0.0))) > 1e-4


@pytest.mark.parametrize("ulps", [1, 4, -4])
def test_a_mark_on_a_sample_to_rounding_makes_no_interval_of_rounding(monkeypatch, ulps):
    """A cycle mark a few ulps off a sample (the run's samples sit on the cycle's angles): the
    two are one node, not the ends of an interval 1e-15 wide, whose rule scaled to it is a
    Vandermonde solve at 10¹³ widths: all rounding, which some LAPACK kernels amplify to a
    visible part of a cycle's ∮p dV. The integrals stay exact to rounding."""
    from transient.analysis import thermo

    widths = []
    quadrature = thermo._interval_integrals

    def recording(xs, fs, lo, hi, degree):
        widths.append(np.min(hi - lo))
        return quadrature(xs, fs, lo, hi, degree)

    monkeypatch.setattr(thermo, "_interval_integrals", recording)
    x = np.linspace(0.0, 12 * math.pi, 3 * 1440 + 1)
    marks = np.array([0.0, 4 * math.pi, 8 * math.pi, 12 * math.pi])
    marks[1:3] += ulps * np.spacing(marks[1:3])
    got = integrals_between(x, np.cos(x) + 2.0, marks)
    assert min(widths) > 1e-12 * x[-1]
    exact = np.diff(2.0 * marks + np.sin(marks))
    assert got == pytest.approx(exact, rel=1e-13)
