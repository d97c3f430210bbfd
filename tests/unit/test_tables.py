"""Piecewise-cubic periodic tables: compiled kernels against their numpy twin, and the builders.

The kernels (transient/core/tables.py) are checked against PressureTable.evaluate, a separate
plain-numpy implementation; the builders against data they must reproduce exactly.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from transient.core.model.tables import (
    NEAR_STEPS,
    find_piece,
    find_piece_near,
    table_eval,
    table_eval_near,
    table_eval_pair,
    table_eval_pair_near,
    table_value,
    wrap_angle,
    wrap_near,
)
from transient.errors import SceneError
from transient.forces.gas import PressureTable, table_from_function, table_from_points

P4 = 4.0 * math.pi
DEG = math.pi / 180.0


def jumpy_table(interpolation: str) -> PressureTable:
    """A 4-stroke-like table with a jump at 360°, a kink at 200° and a corner between samples."""
    rng = np.random.default_rng(7)
    phi_deg = np.concatenate([np.arange(0, 200, 20), [200],                   # piece 0 ends at 200
                              np.arange(210, 361, 30), [360],                 # 360 twice: jump
                              np.arange(370, 500, 15), np.arange(505, 721, 35), [720]])
    phi_deg = np.unique(phi_deg[phi_deg != 360])
    phi_deg = np.sort(np.concatenate([phi_deg, [360, 360]]))
    p = 1e5 + 1e6 * rng.random(phi_deg.size)
    # Corner at 500°: no sample there, both neighbours extrapolate to it.
    return table_from_points(phi_deg * DEG, p, P4, corners=np.array([200, 360, 500]) * DEG,
                             interpolation=interpolation)


def test_the_piece_searched_from_a_kept_one_is_the_piece_the_corners_bound():
    """find_piece_near against the numpy twin's piece_of (a search of its own): for every kept
    value, a piece (the right one, a neighbour, the farthest) or none (NaN, negative, too large,
    between two indices), at angles on every corner, an ulp either side, inside the cycle and at
    its ends."""
    t = jumpy_table("pchip")
    rng = np.random.default_rng(3)
    corners = np.concatenate([t.corners, [P4]])
    x = np.concatenate([rng.uniform(0.0, P4, 300), corners, np.nextafter(corners, 0.0),
                        np.nextafter(corners, P4), [0.0]])
    x = x[x < P4]
    kept = [float(j) for j in range(t.n_pieces)] + [math.nan, -1.0, 1e300, float(t.n_pieces), 1.5]
    for xi, want in zip(x, t.piece_of(x), strict=True):
        assert find_piece(t.knots, t.piece_knot, xi) == want
        for held in kept:
            assert find_piece_near(t.knots, t.piece_knot, xi, held) == want


@pytest.mark.parametrize("interpolation", ["linear", "spline"])
def test_the_interval_searched_from_a_kept_one_gives_the_bisections_values(interpolation):
    """table_eval_near and table_eval_pair_near against table_eval and table_eval_pair (the same
    interval, so the same bits) and against the numpy twin, for every piece, at angles inside,
    on every knot, an ulp either side and outside the piece, from kept intervals near (within
    the walk), far (a bisection), in another piece, NaN and garbage."""
    t = jumpy_table(interpolation)
    paired = np.hstack([t.coef, 0.5 * t.coef[:, ::-1]])  # (a second curve on the same knots)
    rng = np.random.default_rng(4)
    x = np.concatenate([rng.uniform(-0.3, P4 + 0.3, 150), t.knots, np.nextafter(t.knots, -1.0),
                        np.nextafter(t.knots, 2 * P4)])
    for j in range(t.n_pieces):
        lo, hi = t.piece_knot[j], t.piece_knot[j + 1] - 1
        kept = [float(i) for i in (lo, hi, (lo + hi) // 2)] + [math.nan, -5.0, 1e300, lo + 0.5]
        for xi in x:
            want, _ = table_eval(t.knots, t.coef, t.piece_knot, j, xi)
            pair = table_eval_pair(t.knots, paired, t.piece_knot, j, xi)
            found = int(np.clip(np.searchsorted(t.knots, xi, side="right") - 1, lo, hi))
            near = [float(np.clip(found + d, lo, hi)) for d in (-NEAR_STEPS - 1, -1, 0, 2,
                                                                 NEAR_STEPS, NEAR_STEPS + 3)]
            for held in kept + near:
                value, i = table_eval_near(t.knots, t.coef, t.piece_knot, j, xi, held)
                assert (value, i) == (want, found)
                assert table_eval_pair_near(t.knots, paired, t.piece_knot, j, xi, held) == (
                    *pair, found)
        inside = x[(x >= t.corners[j]) & (x < np.append(t.corners, P4)[j + 1])]
        np.testing.assert_allclose(
            [table_eval_near(t.knots, t.coef, t.piece_knot, j, xi, float(lo))[0] for xi in inside],
            t.evaluate(inside, np.full(inside.size, j))[0], rtol=1e-13, atol=1e-6)


@pytest.mark.parametrize("interpolation", ["linear", "pchip", "spline"])
def test_kernels_match_numpy_twin(interpolation):
    t = jumpy_table(interpolation)
    rng = np.random.default_rng(1)
    x = rng.uniform(-2 * P4, 3 * P4, 2000)
    x = np.concatenate([x, t.corners, t.corners + P4, t.knots[1:-1]])  # corners and knots too
    expect = t(x)
    got = np.array([table_value(t.knots, t.coef, t.piece_knot, xi) for xi in x])
    np.testing.assert_allclose(got, expect, rtol=1e-13, atol=0)

    y = t.wrap(x)
    assert np.all((y >= 0) & (y < P4))
    assert np.array_equal(np.array([wrap_angle(xi, P4) for xi in x]), y)
    np.testing.assert_array_equal([find_piece(t.knots, t.piece_knot, yi) for yi in y],
                                  t.piece_of(y))

    # table_eval with an arbitrary piece (extrapolating outside it) against the twin.
    pieces = rng.integers(0, t.n_pieces, x.size)
    xs = rng.uniform(-0.5, P4 + 0.5, x.size)
    val, slope = t.evaluate(xs, pieces)
    for xi, j, v, s in zip(xs, pieces, val, slope):
        vk, sk = table_eval(t.knots, t.coef, t.piece_knot, j, xi)
        assert vk == pytest.approx(v, rel=1e-13, abs=1e-6)
        assert sk == pytest.approx(s, rel=1e-12, abs=1e-3)
    # The kernels' interpreted versions agree too (the twin is not testing numba alone).
    assert table_value.py_func(t.knots, t.coef, t.piece_knot, 3.3) == pytest.approx(t(3.3), rel=1e-14)


def test_slope_is_derivative():
    t = jumpy_table("spline")
    x = t.interior_points(3)
    h = 1e-6
    _, slope = t.evaluate(x)
    fd = (t(x + h) - t(x - h)) / (2 * h)
    np.testing.assert_allclose(slope, fd, rtol=1e-5, atol=1e-6 * np.abs(t.coef[:, 0]).max())


def test_spline_reproduces_cubic_and_linear_reproduces_lines():
    def cubic(x):
        return 2e5 + 3e4 * x - 5e3 * x ** 2 + 700.0 * x ** 3

    # Uneven samples, two pieces with a jump between them (so each piece is its own spline).
    x1 = np.array([0.0, 0.3, 1.1, 1.7, 2.0])
    x2 = np.array([2.0, 2.4, 3.9, 5.0, 2 * math.pi])
    phi = np.concatenate([x1, x2])
    p = np.concatenate([cubic(x1), cubic(x2) + 1e5])
    t = table_from_points(phi, p, 2 * math.pi, corners=[2.0], interpolation="spline")
    xs = np.linspace(0, 2 * math.pi, 1001)[:-1]
    expect = cubic(xs) + np.where(xs >= 2.0, 1e5, 0.0)
    np.testing.assert_allclose(t(xs), expect, rtol=1e-12)

    for method in ("linear", "pchip"):
        tl = table_from_points([0.0, 1.0, 2.5, 2 * math.pi], 1e5 + 1e4 * np.array(
            [0.0, 1.0, 2.5, 2 * math.pi]), 2 * math.pi, interpolation=method)
        np.testing.assert_allclose(tl(xs), 1e5 + 1e4 * xs, rtol=1e-13)


def test_kink_between_samples_is_reproduced():
    # |x - c| sampled off the kink: two linear pieces extrapolated to the declared corner.
    c = 1.234
    phi = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2 * math.pi])
    p = 1e5 + 1e4 * np.abs(phi - c)
    t = table_from_points(phi, p, 2 * math.pi, corners=[c], interpolation="linear")
    xs = np.linspace(0, 2 * math.pi, 777)
    np.testing.assert_allclose(t(xs[:-1]), 1e5 + 1e4 * np.abs(xs[:-1] - c), rtol=1e-13)
    assert t(c) == pytest.approx(1e5, rel=1e-14)


@pytest.mark.parametrize("interpolation", ["linear", "pchip", "spline"])
def test_jump_at_corner(interpolation):
    t = jumpy_table(interpolation)
    c = 360 * DEG
    j = int(np.flatnonzero(np.isclose(t.corners, c))[0])
    k = t.piece_knot[j]
    assert t.knots[k] == c
    phi_left = t.coef[k - 1]  # the left piece's last interval
    h = t.knots[k] - t.knots[k - 1]
    left = phi_left[0] + h * (phi_left[1] + h * (phi_left[2] + h * phi_left[3]))
    right = t.coef[k, 0]
    assert abs(left - right) > 1e3  # the random data do jump here

    # At the corner: right value (the piece that starts there); just left: left value.
    assert t(c) == right
    assert table_value(t.knots, t.coef, t.piece_knot, c) == right
    assert find_piece(t.knots, t.piece_knot, c) == j
    assert t(c - 1e-12) == pytest.approx(left, rel=1e-9)
    assert t(c + 1e-12) == pytest.approx(right, rel=1e-9)

    # A step ending exactly on the corner, evaluated with the left piece: the left polynomial.
    v, _ = table_eval(t.knots, t.coef, t.piece_knot, j - 1, c)
    assert v == pytest.approx(left, rel=1e-14)
    v_twin, _ = t.evaluate(c, j - 1)
    assert v_twin == pytest.approx(left, rel=1e-14)
    # A hair past it, still with the left piece: the left end polynomial extrapolated.
    e = 1e-7
    v, s = table_eval(t.knots, t.coef, t.piece_knot, j - 1, c + e)
    d = h + e
    assert v == pytest.approx(phi_left[0] + d * (phi_left[1] + d * (phi_left[2] + d * phi_left[3])),
                              rel=1e-14)
    # And a hair before the corner with the right piece: the right piece's first polynomial.
    v, _ = table_eval(t.knots, t.coef, t.piece_knot, j, c - e)
    r = t.coef[k]
    assert v == pytest.approx(r[0] - e * (r[1] - e * (r[2] - e * r[3])), rel=1e-14)

    # The cycle wraps: 720° is 0°, and the left limit at 720° is the last point.
    assert t(P4) == t(0.0)
    v, _ = table_eval(t.knots, t.coef, t.piece_knot, t.n_pieces - 1, P4)
    assert v == pytest.approx(t.evaluate(P4, t.n_pieces - 1)[0], rel=1e-15)


def test_angles_from_degrees_are_snapped():
    phi = np.radians(np.arange(0.0, 721.0, 30.0))
    t = table_from_points(phi, np.full(phi.size, 2e5), P4)
    assert t.knots[-1] == P4 and t.period == P4
    assert np.all(t.coef[:, 1:] == 0) and np.all(t.coef[:, 0] == 2e5)


def bad(key: str, phi_deg, p, corners_deg=(), interpolation="pchip", period=P4):
    with pytest.raises(SceneError) as info:
        table_from_points(np.asarray(phi_deg, float) * DEG, p, period,
                          corners=np.asarray(corners_deg, float) * DEG,
                          interpolation=interpolation)
    err = info.value
    assert err.key == key
    assert "\n" not in err.message and err.message
    return err.message


def test_scene_errors():
    p5 = [1e5] * 5
    # Not covering [0, period].
    msg = bad("gas.phi_deg", [10, 100, 300, 500, 720], p5)
    assert "10°" in msg and "720°" in msg
    bad("gas.phi_deg", [0, 100, 300, 500, 700], p5)
    bad("gas.phi_deg", [0], [1e5])
    # Not increasing; a repeated angle that is not a declared corner; three times at a corner.
    msg = bad("gas.phi_deg", [0, 300, 100, 500, 720], p5)
    assert "100°" in msg and "300°" in msg
    msg = bad("gas.phi_deg", [0, 100, 100, 500, 720], p5)
    assert "100°" in msg and "corners" in msg
    bad("gas.phi_deg", [0, 100, 100, 100, 720], p5, corners_deg=[100])
    # Lengths differ.
    msg = bad("gas.p", [0, 100, 300, 720], p5)
    assert "5" in msg and "4" in msg
    # Corner outside (0, period).
    for c in (0, 720, -10, 800):
        bad("gas.corners_deg", [0, 100, 300, 500, 720], p5, corners_deg=[c])
    # Negative absolute pressure, or not finite.
    msg = bad("gas.p", [0, 100, 300, 500, 720], [1e5, 1e5, -2e4, 1e5, 1e5])
    assert "300°" in msg
    bad("gas.p", [0, 100, 300, 500, 720], [1e5, 1e5, np.nan, 1e5, 1e5])
    # Fewer than 2 points in a piece: corners at 150 and 200 leave no sample in between
    # (pieces 150-200 has none); a jump leaves the next piece with one point.
    msg = bad("gas.phi_deg", [0, 100, 300, 500, 720], p5, corners_deg=[150, 200])
    assert "150°" in msg and "200°" in msg
    bad("gas.phi_deg", [0, 100, 100, 720], [1e5] * 4, corners_deg=[100, 300])
    # Unknown interpolation.
    bad("gas.interpolation", [0, 100, 300, 500, 720], p5, interpolation="akima")


def test_table_from_function():
    def cubic(x):
        return 1e5 + 1e4 * x ** 3 - 2e3 * x

    corners = [1.0, 4.0]
    t, err = table_from_function([cubic, 3e5, np.cos], 2 * math.pi, corners, step=0.1)
    np.testing.assert_allclose(t.corners, [0, 1.0, 4.0, 2 * math.pi])
    assert t.piece_knot[2] - t.piece_knot[1] == 1  # the constant piece is one interval
    h = np.diff(t.knots)
    assert np.max(np.delete(h, t.piece_knot[1])) <= 0.1 + 1e-15  # the others are <= step
    x = np.linspace(0, 1, 50, endpoint=False)
    np.testing.assert_allclose(t(x), cubic(x), rtol=1e-12)
    assert t(2.0) == 3e5 and t.evaluate(4.0, 1)[0] == 3e5
    assert t(4.0) == pytest.approx(math.cos(4.0), abs=1e-12)
    # The estimate (midpoints of cos, relative to max |f| = 3e5) matches a direct measurement.
    xs = np.linspace(4.0, 2 * math.pi, 3001)[1:-1]
    direct = np.max(np.abs(t(xs) - np.cos(xs))) / 3e5
    assert err == pytest.approx(direct, rel=0.3) and err < 1e-10
    # One continuous function with a kink corner.
    t1, err1 = table_from_function(lambda x: np.abs(np.sin(x)), 2 * math.pi, [math.pi], 0.05)
    assert err1 < 1e-6
    assert t1.max_abs_error(lambda x: np.abs(np.sin(x)), 4) < 1e-6
    with pytest.raises(ValueError):
        table_from_function([cubic, 3e5], 2 * math.pi, corners)


def test_malformed_table_is_rejected():
    with pytest.raises(ValueError):
        PressureTable(np.array([0.0, 1.0, 0.5, 2.0]), np.zeros((3, 4)), np.array([0, 3]), 2.0)
    with pytest.raises(ValueError):
        PressureTable(np.array([0.0, 1.0, 2.0]), np.zeros((2, 4)), np.array([0, 1]), 2.0)
    with pytest.raises(ValueError):
        PressureTable(np.array([0.0, 1.0, 2.0]), np.zeros((2, 4)), np.array([0, 2]), 3.0)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 12, 400])
def test_not_a_knot_spline_is_scipys_curve(n):
    """The hand-written spline (kept out of scipy.interpolate for start-up time) against
    scipy.interpolate.CubicSpline, an independent implementation: the same coefficients on
    uneven knots and noisy data, to rounding."""
    from scipy.interpolate import CubicSpline

    from transient.forces.gas import not_a_knot_coef
    rng = np.random.default_rng(n)
    x = np.sort(rng.uniform(0.0, 3.0, n))
    y = np.sin(3.0 * x) + rng.normal(0.0, 0.1, n)
    ref = CubicSpline(x, y, bc_type="not-a-knot" if n > 2 else "natural").c[::-1].T
    np.testing.assert_allclose(not_a_knot_coef(x, y), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("spread", [0.0, 3.0, 6.0])
def test_tridiagonal_solve_is_lapacks_pivoted_solution(spread):
    """The not-a-knot system solved without pivoting against scipy.linalg.solve_banded (LAPACK's
    LU with partial pivoting) on knots whose spacings span up to 10^spread: the same slopes to
    rounding, also where a short interval sits beside a long one at either end."""
    from scipy.linalg import solve_banded

    from transient.forces.gas import _tridiagonal_solve
    rng = np.random.default_rng(int(spread))
    n = 200
    dx = 10.0 ** rng.uniform(-spread, 0.0, n - 1)
    dx[:2], dx[-2:] = (1e-6 * dx[0], dx[1]), (1e-6 * dx[-2], dx[-1])  # the end rows' worst case
    lower, upper = np.append(dx[1:], dx[-2] + dx[-1]), np.insert(dx[:-1], 0, dx[0] + dx[1])
    diag = np.concatenate([[dx[1]], 2.0 * (dx[:-1] + dx[1:]), [dx[-2]]])
    b = rng.normal(size=n)
    ab = np.zeros((3, n))
    ab[0, 1:], ab[1], ab[2, :-1] = upper, diag, lower
    ref = solve_banded((1, 1), ab, b)
    x = _tridiagonal_solve(lower, diag, upper, b)
    # (the matrix's condition number reaches 1e14 at spread 6; seen: 0, 3e-15, 1.7e-13)
    np.testing.assert_allclose(x, ref, rtol=1e-12, atol=0)
    # and it solves the system: the residual at rounding of the terms (seen: ≤ 8e-17)
    A = np.diag(diag) + np.diag(lower, -1) + np.diag(upper, 1)
    assert np.max(np.abs(A @ x - b)) <= 1e-15 * np.max(np.abs(A) @ np.abs(x))


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_bisect_root_is_the_root_to_the_last_bit(sign):
    """Bisection of a rising and of a falling function: g with g(b)'s sign at the result and with
    g(a)'s one ulp towards a (a zero counting as positive), and the same root as brentq's to a
    few ulp."""
    from scipy.optimize import brentq

    from transient.roots import bisect_root
    g = lambda x: sign * (math.expm1(x) - 0.3)
    positive = lambda x: g(x) >= 0.0
    x = bisect_root(g, 0.0, 2.0)
    assert positive(x) == positive(2.0) != positive(np.nextafter(x, -np.inf))
    assert abs(x - brentq(g, 0.0, 2.0, xtol=1e-15, rtol=4 * np.finfo(float).eps)) <= 4 * np.spacing(x)
    assert abs(x - math.log(1.3)) <= 2 * np.spacing(x)
    # bracketed the other way round (b < a): the same root, now approached from above
    y = bisect_root(g, 2.0, 0.0)
    assert positive(y) == positive(0.0) != positive(np.nextafter(y, np.inf))
    assert abs(y - x) <= np.spacing(x)


def test_wrap_near_is_wrap_angle():
    """wrap_near reduces as wrap_angle does, the same values: angles inside the cycle, a hair and a
    small twist outside either end, and far outside."""
    rng = np.random.default_rng(2)
    x = np.concatenate([rng.uniform(0.0, P4, 500), rng.uniform(-0.1, 0.0, 100),
                        rng.uniform(P4, P4 + 0.1, 100), rng.uniform(-3 * P4, 5 * P4, 300),
                        [0.0, -0.0, P4, np.nextafter(P4, 0.0), -1e-300, np.nextafter(0.0, -1.0)]])
    got = np.array([wrap_near(xi, P4) for xi in x])
    assert np.array_equal(got, np.array([wrap_angle(xi, P4) for xi in x]))
    assert np.all((got >= 0.0) & (got < P4))
