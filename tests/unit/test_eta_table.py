"""Efficiency maps η(|ω|, |S|) in the serial chain (transient.core.model.eta_table): the bilinear map
against scipy's interpolator, the exact solve against the sub-chain equations, a closed form (a
map linear in S makes S solve a quadratic), enumeration of every mode vector (exactly one is
power-flow consistent) and the constant-η chain, which a constant map reproduces bit for bit."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from transient.assemble import pack_maps
from transient.core.model import eta_table as et
from transient.core.model.chain import chain_solve, eta_star, modes_power_flow
from transient.errors import SceneError
from transient.scene.eta_map import check_map

N_CASES = 200


def random_map(rng):
    """A map that passes the scene check: η rising with the moment (forward), x/η_bwd rising."""
    while True:
        w = np.cumsum(rng.uniform(5.0, 200.0, rng.integers(1, 5)))
        s = np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 4.0, rng.integers(1, 6)))])
        f = rng.uniform(0.5, 1.0, (w.size, s.size))
        b = rng.uniform(0.5, 1.0, (w.size, s.size))
        try:
            check_map(lambda k: k, tuple(w), tuple(s), tuple(map(tuple, f)), tuple(map(tuple, b)))
        except SceneError:
            continue
        return w, s, f, b


def numpy_eta(m, d, w_abs, x):
    """Map ``d`` of pair map ``m`` by scipy: the point held to the grid, then bilinear."""
    w, s, f, b = m
    grid = f if d == 0 else b
    pw, ps = np.clip(w_abs, w[0], w[-1]), np.clip(x, s[0], s[-1])
    if w.size == 1 and s.size == 1:
        return grid[0, 0]
    if w.size == 1:
        return np.interp(ps, s, grid[0])
    if s.size == 1:
        return np.interp(pw, w, grid[:, 0])
    return RegularGridInterpolator((w, s), grid)([[pw, ps]])[0]


def random_chain(rng, n):
    J = rng.uniform(0.05, 3.0, n + 1)
    dJ = rng.uniform(-2.0, 2.0, n + 1)
    M = rng.uniform(-5.0, 5.0, n + 1)
    w = rng.uniform(-300.0, 300.0)
    return J, dJ, M, w


def test_lookup_is_scipys_bilinear_map_held_at_the_edges():
    rng = np.random.default_rng(1)
    for _ in range(N_CASES):
        m = random_map(rng)
        arrays = pack_maps([m])
        for d in (0, 1):
            for w_abs in (0.0, *rng.uniform(0.0, 1.2 * m[0][-1], 3)):
                for x in (0.0, *rng.uniform(0.0, 1.2 * m[1][-1], 3)):
                    got, slope = et.lookup(*arrays[:4], 0, d, w_abs, x)
                    assert got == pytest.approx(numpy_eta(m, d, w_abs, x), rel=1e-13, abs=1e-15)
                    h = 1e-6 * (m[1][-1] - m[1][0] + 1.0)
                    inside = m[1][0] < x - h and x + h < m[1][-1]
                    knot = np.min(np.abs(m[1] - x)) < 2 * h
                    if inside and not knot:  # the slope against a central difference
                        fd = (numpy_eta(m, d, w_abs, x + h) - numpy_eta(m, d, w_abs, x - h)) / (2 * h)
                        assert slope == pytest.approx(fd, rel=1e-6, abs=1e-9)
                    elif not inside and not knot:
                        assert slope == 0.0


def subchain_residual(J, dJ, M, w, a, S, modes, maps):
    """The sub-chain equations J_k a = R_k + η*_{k−1}S_{k−1} − S_k with η*_k read from the maps
    by scipy at the S_k found: relative residual."""
    n = S.size
    R = M - 0.5 * dJ * w * w
    es = [eta_star(numpy_eta(maps[k], 0, abs(w), abs(S[k])),
                   numpy_eta(maps[k], 1, abs(w), abs(S[k])), not (modes >> k) & 1)
          for k in range(n)]
    res, scale = 0.0, 0.0
    for k in range(n + 1):
        rhs = R[k] + (es[k - 1] * S[k - 1] if k > 0 else 0.0) - (S[k] if k < n else 0.0)
        res = max(res, abs(J[k] * a - rhs))
        scale = max(scale, abs(R[k]), abs(J[k] * a), *(abs(S) if n else [0.0]))
    return res / scale


@pytest.mark.parametrize("n", [1, 2, 3])
def test_held_modes_satisfy_the_subchain_equations_at_their_own_eta(n):
    rng = np.random.default_rng(10 + n)
    for _ in range(N_CASES):
        J, dJ, M, w = random_chain(rng, n)
        maps = [random_map(rng) for _ in range(n)]
        arrays = pack_maps(maps)
        modes = int(rng.integers(0, 1 << n))
        eta_out, S = np.empty(n), np.empty(n)
        a = et.solve_held(J, dJ, M, w, modes, *arrays, eta_out, S)
        assert np.isfinite(a)
        assert subchain_residual(J, dJ, M, w, a, S, modes, maps) <= 1e-13


@pytest.mark.parametrize("n", [1, 2, 3])
def test_exactly_one_mode_vector_is_power_flow_consistent_and_solve_auto_finds_it(n):
    """Every one of the 2ⁿ held-mode solutions is computed; those whose S_k σ agree with their
    modes are counted: one (the theorem), and it is solve_auto's (a, S)."""
    rng = np.random.default_rng(20 + n)
    for _ in range(N_CASES):
        J, dJ, M, w = random_chain(rng, n)
        maps = [random_map(rng) for _ in range(n)]
        arrays = pack_maps(maps)
        sigma = 1.0 if w >= 0.0 else -1.0
        found = []
        for mask in range(1 << n):
            eta_out, S = np.empty(n), np.empty(n)
            a = et.solve_held(J, dJ, M, w, mask, *arrays, eta_out, S)
            if all((S[k] * sigma < 0.0) == bool((mask >> k) & 1) for k in range(n)):
                found.append((a, S.copy()))
        assert len(found) == 1
        eta_out, S = np.empty(n), np.empty(n)
        a = et.solve_auto(J, dJ, M, w, sigma, *arrays, eta_out, S)
        assert a == pytest.approx(found[0][0], rel=1e-13, abs=1e-13)
        np.testing.assert_allclose(S, found[0][1], rtol=1e-12, atol=1e-12)


def quadratic_S(J, R, alpha, beta, backward):
    """S of one pair whose efficiency is α + β|S| (η_fwd forward, η_bwd backward), in closed form.

    With a = (R_0 − S)/J_0 from sub-chain 0 and D = J_1 R_0 − J_0 R_1, sub-chain 1's equation
    R_1 − J_1 a + h(S) = 0 becomes, forward (S ≥ 0, h = (α + βS)S),
    J_0 β S² + (J_1 + α J_0) S − D = 0; backward (S < 0, h = S/(α − βS)),
    J_1 β S² − (Dβ + α J_1 + J_0) S + Dα = 0. The root that tends to D/(J_1 + αJ_0), resp.
    αD/(αJ_1 + J_0), as β → 0, in the form free of cancellation."""
    D = J[1] * R[0] - J[0] * R[1]
    if not backward:
        p = J[1] + alpha * J[0]
        return 2.0 * D / (p + np.sqrt(p * p + 4.0 * J[0] * beta * D))
    A, B, C = J[1] * beta, -(D * beta + alpha * J[1] + J[0]), D * alpha
    return 2.0 * C / (-B + np.sqrt(B * B - 4.0 * A * C))


@pytest.mark.parametrize("backward", [False, True])
def test_map_linear_in_S_gives_the_quadratics_root(backward):
    rng = np.random.default_rng(30 + backward)
    for _ in range(N_CASES):
        J, dJ, M, w = random_chain(rng, 1)
        w = abs(w) + 1.0
        R = M - 0.5 * dJ * w * w
        D = J[1] * R[0] - J[0] * R[1]
        if (D < 0.0) != backward:
            M[0], M[1] = M[1], M[0]  # the other sign of D: the mode wanted
            J[0], J[1] = J[1], J[0]
            dJ[0], dJ[1] = dJ[1], dJ[0]
            R = M - 0.5 * dJ * w * w
        top = 10.0 * np.abs(R).max() * J.max() / J.min()  # above |S|: linear throughout
        alpha, beta = rng.uniform(0.6, 0.9), rng.uniform(0.0, 0.1 / top)
        s = np.array([0.0, top])
        lin = np.array([[alpha, alpha + beta * top]])
        other = np.full((1, 2), 0.9)
        m = (np.array([100.0]), s, other if backward else lin, lin if backward else other)
        arrays = pack_maps([m])
        eta_out, S = np.empty(1), np.empty(1)
        a = et.solve_auto(J, dJ, M, w, 1.0, *arrays, eta_out, S)
        want = quadratic_S(J, R, alpha, beta, backward)
        assert abs(want) < top
        assert S[0] == pytest.approx(want, rel=1e-13, abs=1e-14 * np.abs(R).max())
        assert a == pytest.approx((R[0] - want) / J[0], rel=1e-13, abs=1e-14 * np.abs(R).max())


@pytest.mark.parametrize("n", [1, 2, 3])
def test_a_constant_map_is_the_constant_eta_chain_bit_for_bit(n):
    rng = np.random.default_rng(40 + n)
    for _ in range(N_CASES):
        J, dJ, M, w = random_chain(rng, n)
        ef, eb = rng.uniform(0.3, 1.0, n), rng.uniform(0.3, 1.0, n)
        maps = [(np.array([0.0, 50.0]), np.array([0.0, 1.0, 9.0]), np.full((2, 3), ef[k]),
                 np.full((2, 3), eb[k])) for k in range(n)]
        arrays = pack_maps(maps)
        e_ref, S_ref = np.empty(n), np.empty(n)
        a_ref, _, _ = modes_power_flow(J, dJ, M, ef, eb, w, e_ref, S_ref)
        e, S = np.empty(n), np.empty(n)
        a = et.solve_auto(J, dJ, M, w, 1.0 if w >= 0 else -1.0, *arrays, e, S)
        assert a == a_ref and np.array_equal(S, S_ref) and np.array_equal(e, e_ref)
        modes = int(rng.integers(0, 1 << n))
        es = np.array([eta_star(ef[k], eb[k], not (modes >> k) & 1) for k in range(n)])
        S_ref = np.empty(n)
        a_ref = chain_solve(J, dJ, M, es, w, S_ref)
        a = et.solve_held(J, dJ, M, w, modes, *arrays, e, S)
        assert a == a_ref and np.array_equal(S, S_ref) and np.array_equal(e, es)
        received = rng.uniform(-5.0, 5.0)
        back = bool(modes & 1)
        S0, e0 = et.invert(*arrays, 0, back, abs(w), received)
        assert S0 == received / es[0] and e0 == es[0]


def test_invert_solves_the_pairs_transfer():
    rng = np.random.default_rng(50)
    for _ in range(N_CASES):
        m = random_map(rng)
        arrays = pack_maps([m])
        w_abs = rng.uniform(0.0, 1.2 * m[0][-1])
        received = rng.uniform(-1.5, 1.5) * m[1][-1]
        for back in (False, True):
            S, e = et.invert(*arrays, 0, back, w_abs, received)
            eta = numpy_eta(m, 1 if back else 0, w_abs, abs(S))
            assert e == pytest.approx(1.0 / eta if back else eta, rel=1e-13)
            assert e * S == pytest.approx(received, rel=1e-13, abs=1e-13 * m[1][-1])


def test_a_map_that_breaks_uniqueness_is_refused():
    """η_fwd falling fast enough with the moment makes x·η_fwd(x) decrease: refused, naming the
    speed and the cell."""
    ok = ((0.9, 0.95),)
    with pytest.raises(SceneError, match=r"η_fwd \+ x·∂η_fwd/∂x = -"):
        check_map(lambda k: k, (10.0,), (0.0, 1.0), ((0.9, 0.3),), ok)
    with pytest.raises(SceneError, match=r"η_bwd − x·∂η_bwd/∂x"):
        check_map(lambda k: k, (10.0,), (1.0, 2.0), ok, ((0.3, 0.9),))
    check_map(lambda k: k, (10.0,), (0.0, 1.0), ((0.9, 0.5),), ((0.5, 0.9),))  # steep, yet kept
