"""The Runge–Kutta pairs of :mod:`transient.core.integrator.tableaus` and the dense-output layout of
:mod:`transient.core.integrator.rk`, against SciPy's independent implementations (``RK45`` with its
own interpolant matrix P, ``DOP853``): one step of the same size on a nonlinear system must give
the same new state, the same error estimate's size and the same dense output.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import DOP853, RK45

from transient.core.integrator.rk import (
    STAGEWISE_FROM,
    combination,
    dense_eval,
    error_norm,
    stage_state,
)
from transient.core.integrator.rosenbrock import is_w_method
from transient.core.integrator.tableaus import TABLEAUS

#: The explicit pairs (the W-method's tableau is checked in test_rosenbrock.py).
PAIRS = [name for name, tab in TABLEAUS.items() if not is_w_method(tab)]

SCIPY = {"dopri5": RK45, "dop853": DOP853}


def pendulum(t, y):
    """A nonlinear autonomous system (a damped pendulum), y′ = f(y)."""
    return np.array([y[1], -np.sin(y[0]) - 0.3 * y[1]])


def one_step(tab, y0, h):
    """Stages, new state and dense-output rows F of one step, following the layout documented in
    :mod:`transient.core.integrator.tableaus` (written here in numpy, independently of the compiled loop)."""
    K = np.zeros((tab.n_ext, y0.size))
    K[0] = pendulum(0.0, y0)
    for s in range(1, tab.n_ext):
        K[s] = pendulum(0.0, y0 + h * tab.A[s, :s] @ K[:s])
    y1 = y0 + h * tab.B @ K[: tab.n_stages]
    K[tab.n_stages] = pendulum(0.0, y1)  # FSAL, also row n_stages of A for these pairs
    dy = y1 - y0
    F = np.vstack([dy, h * K[0] - dy, 2 * dy - h * (K[0] + K[tab.n_stages]), h * tab.D @ K])
    return K, y1, F


@pytest.mark.parametrize("name", PAIRS)
def test_consistency_conditions(name):
    """Row sums of A are the nodes c (0 ≤ c ≤ 1), the weights sum to 1, the error estimators
    annihilate constants (sum 0)."""
    tab = TABLEAUS[name]
    c = tab.A.sum(axis=1)
    assert c[0] == 0.0 and np.all((c >= 0) & (c <= 1 + 1e-14))
    assert tab.B.sum() == pytest.approx(1.0, abs=1e-14)
    assert tab.E5.sum() == pytest.approx(0.0, abs=1e-14)
    assert tab.E3.sum() == pytest.approx(0.0, abs=1e-14)
    assert np.allclose(tab.A[tab.n_stages, : tab.n_stages], tab.B, rtol=0, atol=1e-16)


@pytest.mark.parametrize("name", PAIRS)
def test_step_and_dense_output_match_scipy(name):
    tab = TABLEAUS[name]
    y0, h = np.array([1.2, 0.4]), 0.37
    solver = SCIPY[name](pendulum, 0.0, y0, 10.0, first_step=h, max_step=h, rtol=1.0, atol=1.0)
    solver.step()
    assert solver.t == pytest.approx(h, rel=1e-15)
    _, y1, F = one_step(tab, y0, h)
    np.testing.assert_allclose(y1, solver.y, rtol=1e-14, atol=1e-15)
    sol = solver.dense_output()
    out = np.empty(2)
    for theta in (0.0, 0.13, 0.5, 0.77, 1.0):
        dense_eval(F, y0, theta, out)
        np.testing.assert_allclose(out, sol(theta * h), rtol=1e-13, atol=1e-15,
                                   err_msg=f"{name} at θ = {theta}")


@pytest.mark.parametrize("name", PAIRS)
def test_dense_output_order(name):
    """Halving h reduces the interpolant's midpoint error against a tight reference by 2^(q+1)
    with q = 7 (DOP853) or 4 (DOPRI5): checks the D rows beyond agreeing with SciPy at one h."""
    from scipy.integrate import solve_ivp

    tab = TABLEAUS[name]
    q = {"dop853": 7, "dopri5": 4}[name]
    y0 = np.array([1.2, 0.4])
    errs = []
    for h in (0.4, 0.2):
        _, _, F = one_step(tab, y0, h)
        ref = solve_ivp(pendulum, (0.0, 0.5 * h), y0, method="DOP853", rtol=1e-13,
                        atol=1e-15).y[:, -1]
        out = np.empty(2)
        dense_eval(F, y0, 0.5, out)
        errs.append(np.max(np.abs(out - ref)))
    order = np.log2(errs[0] / errs[1])
    print(f"{name}: midpoint errors {errs}, order {order:.2f}")
    assert errs[1] > 1e-14  # above round-off, so the slope means something
    assert q + 1 - 0.5 <= order <= q + 1 + 1.5, (errs, order)


@pytest.mark.parametrize("name", PAIRS)
def test_stage_states_match_numpy(name):
    """Each stage's state y + h Σ_{j<s} a_sj K_j, the compiled sum against numpy's, for a state
    summed component by component and one summed stage by stage (fewer and more components than
    STAGEWISE_FROM); both sum each component in the same order, so the smaller state's
    components are the larger one's first ones to the bit."""
    tab = TABLEAUS[name]
    rng = np.random.default_rng(3)
    n_small, n_large = STAGEWISE_FROM - 3, STAGEWISE_FROM + 12
    K = rng.standard_normal((tab.n_ext, n_large))
    y = rng.standard_normal(n_large)
    h = 0.37
    small, large = np.empty(n_small), np.empty(n_large)
    for s in range(1, tab.n_ext):
        stage_state(tab.A[s], K, s, y, h, large)
        np.testing.assert_allclose(large, y + h * tab.A[s, :s] @ K[:s], rtol=1e-14, atol=1e-14,
                                   err_msg=f"{name} stage {s}")
        stage_state(tab.A[s], np.ascontiguousarray(K[:, :n_small]), s, y[:n_small], h, small)
        assert np.array_equal(small, large[:n_small]), (name, s)


@pytest.mark.parametrize("name", PAIRS)
def test_error_estimators_match_numpy(name):
    """The estimators' combinations Σ_s E_s K_s and the error norm against numpy's, written
    from the norm's definition (Hairer's blend of the two estimators, the RMS over the controlled
    components; t scaled by its increment, the independent variable left out), for states
    summed component by component and stage by stage; the smaller state's combinations are the
    larger one's first components to the bit."""
    from transient.core.declare import BY_INCREMENT, BY_SIZE, NOT_CONTROLLED

    tab = TABLEAUS[name]
    rng = np.random.default_rng(4)
    m = tab.n_stages + 1
    n_small, n_large = STAGEWISE_FROM - 3, STAGEWISE_FROM + 12
    K = rng.standard_normal((tab.n_ext, n_large))
    y, y_new = rng.standard_normal(n_large), rng.standard_normal(n_large)
    control = np.full(n_large, BY_SIZE, dtype=np.int64)
    control[1], control[3] = BY_INCREMENT, NOT_CONTROLLED
    h, rtol, atol, ix = 0.37, 1e-6, 1e-9, 0
    e5_np, e3_np = tab.E5[:m] @ K[:m], tab.E3[:m] @ K[:m]
    keep = (control != NOT_CONTROLLED) & (np.arange(n_large) != ix)
    sc = np.where(control == BY_INCREMENT, atol + rtol * np.abs(y_new - y),
                  atol + rtol * np.maximum(np.abs(y), np.abs(y_new)))[keep]
    err5, err3 = np.sum((e5_np[keep] / sc) ** 2), np.sum((e3_np[keep] / sc) ** 2)
    expect = h * err5 / np.sqrt((err5 + 0.01 * err3) * keep.sum())
    e5, e3 = np.empty(n_large), np.empty(n_large)
    got = error_norm(tab, K, h, y, y_new, rtol, atol, ix, control, e5, e3)
    assert got == pytest.approx(expect, rel=1e-13)
    np.testing.assert_allclose(e5, e5_np, rtol=1e-13, atol=1e-14)
    # a state under STAGEWISE_FROM components: its own sums, the same norm as numpy's
    sl = slice(0, n_small)
    keep_s = keep[sl]
    sc_s = np.where(control[sl] == BY_INCREMENT, atol + rtol * np.abs(y_new[sl] - y[sl]),
                    atol + rtol * np.maximum(np.abs(y[sl]), np.abs(y_new[sl])))[keep_s]
    err5_s = np.sum((e5_np[sl][keep_s] / sc_s) ** 2)
    err3_s = np.sum((e3_np[sl][keep_s] / sc_s) ** 2)
    got_s = error_norm(tab, np.ascontiguousarray(K[:, sl]), h, y[sl].copy(), y_new[sl].copy(),
                       rtol, atol, ix, control[sl].copy(), np.empty(n_small), np.empty(n_small))
    assert got_s == pytest.approx(h * err5_s / np.sqrt((err5_s + 0.01 * err3_s) * keep_s.sum()),
                                  rel=1e-13)
    small = np.empty(n_small)
    combination(tab.E5, np.ascontiguousarray(K[:, :n_small]), m, small)
    assert np.array_equal(small, e5[:n_small])
