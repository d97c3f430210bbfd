"""The serial chain with non-ideal pairs (transient.core.model.chain) against (18), (22), (26)–(29) of
Antonyuk et al. §3, an independent linear solve, the power balance and the power-flow claims."""
from __future__ import annotations

import numpy as np
import pytest

from transient.core.model import chain
from transient.core.model.chain import (
    AMBIGUOUS,
    LOCKED,
    NONE_CONSISTENT,
    UNIQUE,
    chain_solve,
    eta_star,
    modes_paper,
    modes_power_flow,
    one_pair_reactions,
    pair_losses,
    two_pair_reactions,
)

N_CASES = 300
RTOL = 1e-12


def random_chain(rng, n, eta_low=0.3):
    """Random sub-chain data (n pairs): J ≥ 0 with interior zeros now and then, any J′, M, ω."""
    J = rng.uniform(0.05, 3.0, n + 1)
    if n >= 2 and rng.random() < 0.2:
        J[rng.integers(1, n)] = 0.0  # a massless intermediate sub-chain is allowed
    dJ = rng.uniform(-2.0, 2.0, n + 1)
    M = rng.uniform(-5.0, 5.0, n + 1)
    w = rng.uniform(-10.0, 10.0)
    eta_f = rng.uniform(eta_low, 1.0, n)
    eta_b = rng.uniform(eta_low, 1.0, n)
    return J, dJ, M, w, eta_f, eta_b


def random_modes(rng, eta_f, eta_b):
    fwd = rng.random(eta_f.size) < 0.5
    return np.array([eta_star(f, b, d) for f, b, d in zip(eta_f, eta_b, fwd)])


def linear_solve(J, dJ, M, es, w):
    """Independent reference: the (n + 1) sub-chain equations as a linear system in (φ̈, S_k)."""
    n = es.size
    A = np.zeros((n + 1, n + 1))
    rhs = M - 0.5 * dJ * w * w
    for k in range(n + 1):
        A[k, 0] = J[k]
        if k < n:
            A[k, 1 + k] = 1.0  # −S_k on side k, moved to the left
        if k > 0:
            A[k, k] = -es[k - 1]  # +η*_{k−1} S_{k−1} received from the pair behind
    x = np.linalg.solve(A, rhs)
    return x[0], x[1:]


def scale_of(J, dJ, M, w):
    """Magnitude of the terms, for relative tolerances that mean something near φ̈ = 0."""
    return np.sum(np.abs(M) + np.abs(0.5 * dJ * w * w)), np.sum(J)


def test_eta_star():
    assert eta_star(0.8, 0.5, True) == 0.8
    assert eta_star(0.8, 0.5, False) == 2.0


@pytest.mark.parametrize("n", [0, 1, 2, 4])
def test_all_ideal_pairs_give_equation_18(n):
    rng = np.random.default_rng(18 + n)
    for _ in range(N_CASES):
        J, dJ, M, w, _, _ = random_chain(rng, n)
        S = np.empty(n)
        a = chain_solve(J, dJ, M, np.ones(n), w, S)
        ref = (M.sum() - 0.5 * dJ.sum() * w * w) / J.sum()
        m, j = scale_of(J, dJ, M, w)
        assert abs(a - ref) <= RTOL * max(abs(ref), m / j)


def one_pair_case(rng):
    """I_a, I_b constant in their own coordinates, ratio u = u_ba(φ) with derivative u′."""
    I_a, I_b = rng.uniform(0.1, 3.0, 2)
    u = rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 4.0)
    du = rng.uniform(-3.0, 3.0)
    M_a, M_b = rng.uniform(-5.0, 5.0, 2)
    w = rng.uniform(-10.0, 10.0)
    es = eta_star(rng.uniform(0.3, 1.0), rng.uniform(0.3, 1.0), rng.random() < 0.5)
    J = np.array([I_a, I_b * u * u])
    dJ = np.array([0.0, 2.0 * I_b * u * du])
    M = np.array([M_a, M_b * u])
    return I_a, I_b, u, du, M_a, M_b, w, es, J, dJ, M


def test_one_pair_is_equation_22_as_printed():
    rng = np.random.default_rng(22)
    for _ in range(N_CASES):
        I_a, I_b, u, du, M_a, M_b, w, es, J, dJ, M = one_pair_case(rng)
        S = np.empty(1)
        a = chain_solve(J, dJ, M, np.array([es]), w, S)
        lam_theta = I_b * u * u / I_a
        lam_ba = M_b * u / M_a
        lhs = I_a * (lam_theta + es) * a
        rhs = M_a * (lam_ba + es) - I_b * u * du * w * w
        terms = abs(M_a * es) + abs(M_b * u) + abs(I_b * u * du * w * w)
        assert abs(lhs - rhs) <= RTOL * terms


def test_one_pair_reactions_are_26_when_the_ratio_term_vanishes():
    """(26) has no u′φ̇² term: it is exact for a constant ratio (or at rest); in general the
    kernel's M_ab = η*D/((η*J_0 + J_1)u) with D = J_1 R_0 − J_0 R_1 holds."""
    rng = np.random.default_rng(26)
    for i in range(N_CASES):
        I_a, I_b, u, du, M_a, M_b, w, es, J, dJ, M = one_pair_case(rng)
        general = i % 2 == 1
        if not general:
            dJ[:] = 0.0  # u′ = 0
        S = np.empty(1)
        a = chain_solve(J, dJ, M, np.array([es]), w, S)
        M_ba, M_ab = one_pair_reactions(I_a, u, es, S[0])
        # The paper's own sub-chain equations, in a's and b's coordinates:
        ddphi_b = u * a + (du if general else 0.0) * w * w
        terms = abs(M_a) + abs(M_b * u) + abs(I_b * u * du * w * w)
        assert abs(I_a * a - (M_a + M_ba)) <= RTOL * terms
        assert abs(I_b * ddphi_b - (M_b + M_ab)) <= RTOL * terms / abs(u)
        assert abs(M_ab * u + es * M_ba) <= RTOL * terms  # (23)-(24): N_ab/N_ba = −η*
        if general:
            D = J[1] * M[0] - J[0] * (M[1] - 0.5 * dJ[1] * w * w)
            ref_ab = es * D / ((es * J[0] + J[1]) * u)
        else:
            lam_theta, lam_ba = I_b * u * u / I_a, M_b * u / M_a
            ref_ab = M_a * (lam_theta - lam_ba) * es / (u * (es + lam_theta))  # (26)
            assert abs(M_ba - (-ref_ab * u / es)) <= RTOL * terms
        assert abs(M_ab - ref_ab) <= RTOL * terms / abs(u)


def two_pair_case(rng):
    I_a, I_b, I_c, I_d = rng.uniform(0.1, 3.0, 4)
    u_ba, u_dc = rng.choice([-1.0, 1.0], 2) * rng.uniform(0.2, 4.0, 2)
    du_ba, du_dc = rng.uniform(-3.0, 3.0, 2)  # derivatives with respect to φ_a
    M_a, M_b, M_c, M_d = rng.uniform(-5.0, 5.0, 4)
    w = rng.uniform(-10.0, 10.0)
    e1 = eta_star(rng.uniform(0.3, 1.0), rng.uniform(0.3, 1.0), rng.random() < 0.5)
    e2 = eta_star(rng.uniform(0.3, 1.0), rng.uniform(0.3, 1.0), rng.random() < 0.5)
    u_da = u_dc * u_ba
    J = np.array([I_a, (I_b + I_c) * u_ba**2, I_d * u_da**2])
    dJ = np.array([0.0, 2.0 * (I_b + I_c) * u_ba * du_ba,
                   2.0 * I_d * u_da * (du_dc * u_ba + u_dc * du_ba)])
    M = np.array([M_a, (M_b + M_c) * u_ba, M_d * u_da])
    return locals()


def terms_28(c, printed_A=False):
    e1, e2, u_ba, u_dc = c["e1"], c["e2"], c["u_ba"], c["u_dc"]
    I_np = c["I_a"] + (c["I_b"] + c["I_c"]) * u_ba**2 / e1 + c["I_d"] * u_dc**2 * u_ba**2 / (e1 * e2)
    M_np = c["M_a"] + (c["M_b"] + c["M_c"]) * u_ba / e1 + c["M_d"] * u_ba * u_dc / (e1 * e2)
    f1 = 1.0 if printed_A else c["I_b"] + c["I_c"]
    f2 = 1.0 if printed_A else c["I_d"]
    A = (f1 * u_ba * c["du_ba"] / e1
         + f2 * (u_dc * c["du_dc"] * u_ba**2 + u_dc**2 * u_ba * c["du_ba"]) / (e1 * e2))
    return I_np, M_np, A


def test_two_pairs_are_27_28_with_the_corrected_A():
    rng = np.random.default_rng(27)
    for _ in range(N_CASES):
        c = two_pair_case(rng)
        S = np.empty(2)
        a = chain_solve(c["J"], c["dJ"], c["M"], np.array([c["e1"], c["e2"]]), c["w"], S)
        I_np, M_np, A = terms_28(c)
        w = c["w"]
        scale = abs(M_np) + abs(A * w * w)
        assert abs(I_np * a - (M_np - A * w * w)) <= RTOL * scale


def test_printed_A_of_28_is_not_the_equation_of_motion():
    """The printed A lacks I_b + I_c and I_d: it disagrees except when those happen to be 1."""
    rng = np.random.default_rng(28)
    bad = 0
    for _ in range(N_CASES):
        c = two_pair_case(rng)
        S = np.empty(2)
        a = chain_solve(c["J"], c["dJ"], c["M"], np.array([c["e1"], c["e2"]]), c["w"], S)
        I_np, M_np, A_printed = terms_28(c, printed_A=True)
        w = c["w"]
        bad += abs(I_np * a - (M_np - A_printed * w * w)) > 1e-6 * (abs(M_np) + abs(A_printed * w * w))
    assert bad >= 0.95 * N_CASES
    # Dimensional check: with I_b + I_c = I_d = 1 the printed form coincides.
    c = two_pair_case(np.random.default_rng(5))
    c["I_b"], c["I_c"], c["I_d"] = 0.25, 0.75, 1.0
    c.update(two_pair_case_from(c))
    S = np.empty(2)
    a = chain_solve(c["J"], c["dJ"], c["M"], np.array([c["e1"], c["e2"]]), c["w"], S)
    I_np, M_np, A_printed = terms_28(c, printed_A=True)
    assert abs(I_np * a - (M_np - A_printed * c["w"] ** 2)) <= 1e-12 * (abs(M_np) + abs(A_printed) * c["w"] ** 2)


def two_pair_case_from(c):
    u_ba, u_dc = c["u_ba"], c["u_dc"]
    u_da = u_ba * u_dc
    return {"J": np.array([c["I_a"], (c["I_b"] + c["I_c"]) * u_ba**2, c["I_d"] * u_da**2]),
            "dJ": np.array([0.0, 2.0 * (c["I_b"] + c["I_c"]) * u_ba * c["du_ba"],
                            2.0 * c["I_d"] * u_da * (c["du_dc"] * u_ba + u_dc * c["du_ba"])])}


def test_two_pair_reactions_29_rederived():
    """S_0, S_1 against a 3×3 numpy solve; the paper-coordinate reactions satisfy each body's
    equation and the power relation of each pair; M_ba has the sign of A φ̇² corrected."""
    rng = np.random.default_rng(29)
    for _ in range(N_CASES):
        c = two_pair_case(rng)
        es = np.array([c["e1"], c["e2"]])
        S = np.empty(2)
        a = chain_solve(c["J"], c["dJ"], c["M"], es, c["w"], S)
        a_ref, S_ref = linear_solve(c["J"], c["dJ"], c["M"], es, c["w"])
        m, j = scale_of(c["J"], c["dJ"], c["M"], c["w"])
        assert abs(a - a_ref) <= RTOL * m / j
        np.testing.assert_allclose(S, S_ref, rtol=0, atol=RTOL * m * max(1.0, 1 / es.min()))
        w, u_ba, u_dc = c["w"], c["u_ba"], c["u_dc"]
        M_ba, M_ab, M_dc, M_cd = two_pair_reactions(u_ba, u_dc, c["e1"], c["e2"], S[0], S[1])
        I_np, M_np, A = terms_28(c)
        tol = 1e-11 * (m + abs(A) * w * w)
        assert abs(M_ba - ((c["I_a"] / I_np) * (M_np - A * w * w) - c["M_a"])) <= tol
        # Each body in its own coordinate: a, then b + c (φ̈_b = u_ba φ̈_a + u′_ba φ̇_a²), then d.
        dd_b = u_ba * a + c["du_ba"] * w * w
        dd_d = (u_dc * u_ba) * a + (c["du_dc"] * u_ba + u_dc * c["du_ba"]) * w * w
        assert abs(c["I_a"] * a - (c["M_a"] + M_ba)) <= tol
        assert abs((c["I_b"] + c["I_c"]) * dd_b - (c["M_b"] + c["M_c"] + M_ab + M_dc)) <= tol / abs(u_ba)
        assert abs(c["I_d"] * dd_d - (c["M_d"] + M_cd)) <= tol / abs(u_ba * u_dc)
        assert abs(M_ab * u_ba + c["e1"] * M_ba) <= tol
        assert abs(M_cd * u_dc + c["e2"] * M_dc) <= tol / abs(u_ba)


def test_reaction_M_cd_of_29_with_u_ba_where_the_print_has_u_bc():
    """M_cd of (29) as derived (docs: *Theory*): the kernel's reaction on d is
    (I_d/I_np){φ̇²[−A u_ba u_dc + I_np(u′_ba u_dc + u_ba u′_dc)] + u_ba u_dc M_np} − M_d; the
    printed form, with u_bc (= 1, b and c one body) for u_ba and u′_bc (= 0) for u′_dc, is not,
    and M_dc = −M_cd u_dc/η*_dc holds as printed."""
    rng = np.random.default_rng(2929)
    bad = 0
    for _ in range(N_CASES):
        c = two_pair_case(rng)
        S = np.empty(2)
        chain_solve(c["J"], c["dJ"], c["M"], np.array([c["e1"], c["e2"]]), c["w"], S)
        _, _, M_dc, M_cd = two_pair_reactions(c["u_ba"], c["u_dc"], c["e1"], c["e2"], S[0], S[1])
        I_np, M_np, A = terms_28(c)
        w2, u_ba, u_dc, du_ba, du_dc = c["w"] ** 2, c["u_ba"], c["u_dc"], c["du_ba"], c["du_dc"]
        derived = (c["I_d"] / I_np * (w2 * (-A * u_ba * u_dc + I_np * (du_ba * u_dc + u_ba * du_dc))
                                      + u_ba * u_dc * M_np) - c["M_d"])
        printed = (c["I_d"] / I_np * (w2 * (-A * 1.0 * u_dc + I_np * (du_ba * u_dc + u_ba * 0.0))
                                      + 1.0 * u_dc * M_np) - c["M_d"])
        scale = abs(c["I_d"]) * (abs(M_np) + abs(A) * w2 + I_np * w2 * (abs(du_ba) + abs(du_dc))
                                 * max(1.0, abs(u_ba)) * max(1.0, abs(u_dc))) / I_np + abs(c["M_d"])
        assert abs(M_cd - derived) <= 1e-11 * scale
        assert abs(M_dc + M_cd * u_dc / c["e2"]) <= 1e-11 * scale * abs(u_dc) / c["e2"]
        bad += abs(M_cd - printed) > 1e-6 * scale
    assert bad >= 0.95 * N_CASES


@pytest.mark.parametrize("n", [3, 4, 5])
def test_general_chain_against_linear_solve_and_power_balance(n):
    rng = np.random.default_rng(100 + n)
    for _ in range(N_CASES):
        J, dJ, M, w, eta_f, eta_b = random_chain(rng, n)
        es = random_modes(rng, eta_f, eta_b)
        S = np.empty(n)
        a = chain_solve(J, dJ, M, es, w, S)
        a_ref, S_ref = linear_solve(J, dJ, M, es, w)
        m, j = scale_of(J, dJ, M, w)
        gain = np.prod(np.maximum(es, 1.0 / es))  # c_j can amplify the terms by this much
        assert abs(a - a_ref) <= RTOL * gain * m / j
        np.testing.assert_allclose(S, S_ref, rtol=0, atol=RTOL * gain * m)
        loss = np.empty(n)
        pair_losses(es, S, w, loss)
        lhs = np.sum((J * a + 0.5 * dJ * w * w) * w)
        rhs = np.sum(M * w) - loss.sum()
        assert abs(lhs - rhs) <= RTOL * gain * (m * abs(w) + np.sum(np.abs(loss)))


# --- mode selection --------------------------------------------------------------------------

def both_one_pair_modes(J, dJ, M, w, f, b):
    out = []
    for es in (f, 1.0 / b):
        S = np.empty(1)
        out.append((chain_solve(J, dJ, M, np.array([es]), w, S), S[0]))
    return out


def test_one_pair_power_flow_mode_is_unique():
    """S_0 = D/(η*J_0 + J_1) for both modes: sign S_0 = sign D, exactly one consistent mode."""
    rng = np.random.default_rng(25)
    for _ in range(N_CASES):
        J, dJ, M, w, f, b = random_chain(rng, 1, eta_low=0.05)
        R = M - 0.5 * dJ * w * w
        D = J[1] * R[0] - J[0] * R[1]
        for es, (_, S0) in zip((f[0], 1 / b[0]), both_one_pair_modes(J, dJ, M, w, f[0], b[0])):
            assert abs(S0 - D / (es * J[0] + J[1])) <= RTOL * np.sum(np.abs(R)) * np.sum(J) / (es * J[0] + J[1])
            assert np.sign(S0) == np.sign(D)
        es_out, S = np.empty(1), np.empty(1)
        _a, status, count = modes_power_flow(J, dJ, M, f, b, w, es_out, S)
        assert (status, count) == (UNIQUE, 1)
        expect_forward = D * w >= 0.0
        assert es_out[0] == (f[0] if expect_forward else 1.0 / b[0])
        loss = (1.0 - es_out[0]) * S[0] * w
        assert loss >= 0.0


def test_acceleration_is_continuous_across_a_power_flow_switch():
    """At D = 0 (S_0 = 0) both modes give the same φ̈; near it φ̈ changes by O(D)."""
    rng = np.random.default_rng(250)
    for _ in range(N_CASES):
        J, dJ, M, w, f, b = random_chain(rng, 1, eta_low=0.05)
        half = 0.5 * w * w
        # Put the state on the switching surface: R_1 = R_0 J_1 / J_0.
        M[1] = (M[0] - half * dJ[0]) * J[1] / J[0] + half * dJ[1]
        (a_f, S_f), (a_b, S_b) = both_one_pair_modes(J, dJ, M, w, f[0], b[0])
        m, j = scale_of(J, dJ, M, w)
        assert abs(a_f - a_b) <= 1e-13 * m / j
        assert abs(S_f) <= 1e-13 * m and abs(S_b) <= 1e-13 * m
        eps = 1e-7 * m
        for d in (eps, -eps):
            M2 = M.copy()
            M2[1] += d
            es, S = np.empty(1), np.empty(1)
            a2, _, _ = modes_power_flow(J, dJ, M2, f, b, w, es, S)
            assert abs(a2 - a_f) <= abs(d) / np.min(J) * 1.01


def bisection_root(J, dJ, M, f, b, w):
    """Independent reference for the power-flow solution: the root of the monotone residual F(a)
    of the proof in the module docstring, by bisection."""
    R = M - 0.5 * dJ * w * w
    sigma = 1.0 if w >= 0 else -1.0

    def g(k, s):
        return f[k] * s if s * sigma >= 0.0 else s / b[k]

    def F(a):
        s = R[0] - J[0] * a
        for k in range(1, J.size):
            s = R[k] - J[k] * a + g(k - 1, s)
        return s

    lo, hi = -1.0, 1.0
    while F(lo) < 0:
        lo *= 2
    while F(hi) > 0:
        hi *= 2
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if F(mid) > 0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("n", [1, 2, 3, 6])
def test_serial_chain_has_exactly_one_power_flow_mode(n):
    """The proof's claim for ω ≠ 0: no self-braking, no ambiguity, even at low efficiency;
    and the chosen φ̈ is the unique root of the monotone residual."""
    rng = np.random.default_rng(600 + n)
    for _ in range(N_CASES):
        J, dJ, M, w, f, b = random_chain(rng, n, eta_low=0.02)
        es, S = np.empty(n), np.empty(n)
        a, status, count = modes_power_flow(J, dJ, M, f, b, w, es, S)
        assert (status, count) == (UNIQUE, 1)
        m, j = scale_of(J, dJ, M, w)
        gain = np.prod(np.maximum(es, 1.0 / es))
        assert abs(a - bisection_root(J, dJ, M, f, b, w)) <= 1e-10 * gain * m / j
        loss = np.empty(n)
        pair_losses(es, S, w, loss)
        assert np.all(loss >= 0.0)


def test_rounding_ties_are_reported_and_harmless():
    """Exactly on a switching surface the count may be 0, 1 or 2 from rounding; the status says
    so and φ̈ is the same as with either mode."""
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(N_CASES):
        J, dJ, M, w, f, b = random_chain(rng, 2, eta_low=0.1)
        half = 0.5 * w * w
        # Make pair 0 transmit nothing in every mode: R_0 = J_0 a with a the φ̈ of the rest.
        es1 = f[1] if rng.random() < 0.5 else 1 / b[1]
        a_rest = chain_solve(J[1:], dJ[1:], M[1:], np.array([es1]), w, np.empty(1))
        M[0] = J[0] * a_rest + half * dJ[0]
        es, S = np.empty(2), np.empty(2)
        a, status, count = modes_power_flow(J, dJ, M, f, b, w, es, S)
        seen.add(status)
        assert status == {0: NONE_CONSISTENT, 1: UNIQUE}.get(count, AMBIGUOUS)
        m, j = scale_of(J, dJ, M, w)
        assert abs(a - bisection_root(J, dJ, M, f, b, w)) <= 1e-10 * m / j * 20
    assert seen - {UNIQUE}, "the constructed ties should produce at least one rounding tie"


def test_locking_at_rest_one_pair():
    """ω = 0: locked exactly when the static ratio −M_1/M_0 lies in [η_fwd, 1/η_bwd]."""
    rng = np.random.default_rng(3)
    n_locked = 0
    for _ in range(N_CASES):
        J, dJ, M, _, f, b = random_chain(rng, 1, eta_low=0.1)
        es, S = np.empty(1), np.empty(1)
        a, status, count = modes_power_flow(J, dJ, M, f, b, 0.0, es, S)
        ratio = -M[1] / M[0]
        locked = f[0] <= ratio <= 1.0 / b[0]
        if locked:
            n_locked += 1
            assert (a, status, count) == (0.0, LOCKED, 0)
            assert S[0] == M[0]
        else:
            assert status == UNIQUE
            assert a != 0.0
            assert (es[0] == f[0]) == (S[0] * np.sign(a) >= 0.0)  # mode agrees with incipient power
            # It moves the way the consistent mode accelerates it, and the pair then loses power.
            assert a * S[0] * (1.0 - es[0]) >= 0.0
    assert 20 <= n_locked <= N_CASES - 20


def test_locking_at_rest_is_global_for_longer_chains():
    """With ω = 0 and n = 3 the chain moves iff a consistent direction exists (a_+ > 0 or a_− < 0);
    when locked φ̈ = 0, S_0 = M_0 and the indeterminate interior reactions are NaN."""
    rng = np.random.default_rng(33)
    n_locked = 0
    for _ in range(N_CASES):
        J, _, M, _, f, b = random_chain(rng, 3, eta_low=0.1)
        dJ = np.zeros(4)
        es, S = np.empty(3), np.empty(3)
        a, status, _count = modes_power_flow(J, dJ, M, f, b, 0.0, es, S)
        a_plus = bisection_root(J, dJ, M, f, b, 1e-300)
        a_minus = bisection_root(J, dJ, M, f, b, -1e-300)
        assert a_plus <= a_minus + 1e-12
        if a_plus > 1e-12 or a_minus < -1e-12:
            assert status == UNIQUE
            assert abs(a - (a_plus if a_plus > 0 else a_minus)) <= 1e-10 * np.abs(M).sum() / J.sum() * 100
        elif a_plus < -1e-12 and a_minus > 1e-12:
            n_locked += 1
            assert (a, status) == (0.0, LOCKED)
            assert S[0] == M[0] and np.all(np.isnan(S[1:]))
    assert n_locked >= 10


def test_paper_criterion_can_pick_a_mode_with_negative_loss():
    """(25) looks at M_a φ̇_a only: side 1 accelerating faster than side 0 drives the pair
    backward while M_a φ̇_a > 0 — the paper's mode then 'creates' power; power-flow does not."""
    J, dJ = np.array([1.0, 1.0]), np.zeros(2)
    M = np.array([1.0, 3.0])  # D = J_1 M_0 − J_0 M_1 = −2 < 0: the power flows from 1 to 0
    f, b, w = np.array([0.8]), np.array([0.7]), 2.0
    es, S = np.empty(1), np.empty(1)
    modes_paper(M, f, b, w, es)
    assert es[0] == 0.8
    chain_solve(J, dJ, M, es, w, S)
    assert (1 - es[0]) * S[0] * w < 0.0
    _a, status, _ = modes_power_flow(J, dJ, M, f, b, w, es, S)
    assert status == UNIQUE and es[0] == 1 / 0.7 and (1 - es[0]) * S[0] * w > 0.0


def test_paper_criterion_uses_upstream_sums():
    es = np.empty(3)
    modes_paper(np.array([1.0, -2.0, 3.0, 5.0]), np.full(3, 0.9), np.full(3, 0.5), 1.0, es)
    np.testing.assert_array_equal(es, [0.9, 2.0, 0.9])  # sums 1, −1, 2
    modes_paper(np.array([1.0, -2.0, 3.0, 5.0]), np.full(3, 0.9), np.full(3, 0.5), -1.0, es)
    np.testing.assert_array_equal(es, [2.0, 0.9, 2.0])


def test_kernels_equal_their_python_twins():
    rng = np.random.default_rng(99)
    for i in range(N_CASES):
        n = 1 + i % 4
        J, dJ, M, w, f, b = random_chain(rng, n)
        if i % 5 == 0:
            w = 0.0
        es = random_modes(rng, f, b)
        S1, S2 = np.empty(n), np.empty(n)
        assert chain.chain_solve(J, dJ, M, es, w, S1) == chain.chain_solve.py_func(J, dJ, M, es, w, S2)
        np.testing.assert_array_equal(S1, S2)
        L1, L2 = np.empty(n), np.empty(n)
        chain.pair_losses(es, S1, w, L1)
        chain.pair_losses.py_func(es, S1, w, L2)
        np.testing.assert_array_equal(L1, L2)
        e1, e2 = np.empty(n), np.empty(n)
        chain.modes_paper(M, f, b, w, e1)
        chain.modes_paper.py_func(M, f, b, w, e2)
        np.testing.assert_array_equal(e1, e2)
        r1 = chain.modes_power_flow(J, dJ, M, f, b, w, e1, S1)
        r2 = chain.modes_power_flow.py_func(J, dJ, M, f, b, w, e2, S2)
        assert r1 == r2
        np.testing.assert_array_equal(e1, e2)
        np.testing.assert_array_equal(S1, S2)
        assert chain.eta_star(f[0], b[0], i % 2 == 0) == chain.eta_star.py_func(f[0], b[0], i % 2 == 0)
        assert (chain.two_pair_reactions(1.5, -0.7, 0.8, 1.2, S1[0], 0.3)
                == chain.two_pair_reactions.py_func(1.5, -0.7, 0.8, 1.2, S1[0], 0.3))
        assert chain.one_pair_reactions(2.0, 1.5, 0.8, S1[0]) == chain.one_pair_reactions.py_func(2.0, 1.5, 0.8, S1[0])


def test_exact_zero_transmission_counts_as_forward():
    """S_0 ω = 0 exactly: forward (≥) is consistent, backward (<) is not — one mode, no tie."""
    J, dJ, M = np.array([1.0, 1.0]), np.zeros(2), np.array([1.0, 1.0])
    es, S = np.empty(1), np.empty(1)
    a, status, count = modes_power_flow(J, dJ, M, np.array([0.8]), np.array([0.6]), 3.0, es, S)
    assert (a, S[0], status, count, es[0]) == (1.0, 0.0, UNIQUE, 1, 0.8)
