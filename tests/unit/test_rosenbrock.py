"""The Rosenbrock–W method ROS34PW2 (:mod:`transient.core.integrator.rosenbrock`) on its own:
its coefficients against the order conditions of W-methods and its stability function, the
stepper's transformed form against the method as published, the observed order of convergence on
the harmonic oscillator with the exact and with wrong Jacobians, the adaptive solve with its
dense output and an event against closed forms, and a stiff problem (Prothero–Robinson) where
the explicit pair's step is held by stability and the W-method's is not.

The order conditions are those of Hairer & Wanner, *Solving ODEs II*, §IV.7 for a W-method
(the Jacobian replaced by an arbitrary matrix A, so that the trees with A-nodes are conditions of
their own; Γ with γ on its diagonal, 1 the vector of ones):

    order 1: bᵀ1 = 1;  order 2: bᵀα1 = 1/2, bᵀΓ1 = 0;
    order 3: bᵀ(α1)² = 1/3, bᵀαα1 = 1/6, bᵀαΓ1 = 0, bᵀΓα1 = 0, bᵀΓΓ1 = 0.
"""
from __future__ import annotations

import math

import numpy as np
import plain_odes as po
import pytest

from transient.core.integrator.rosenbrock import ros34pw2, ros34pw2_coefficients, w_tableau
from transient.core.integrator.tableaus import TABLEAUS

G, ALPHA, GAMMA, B, B_HAT = ros34pw2_coefficients()
ONE = np.ones(4)


def w_conditions(b, order):
    """The residuals of the W-method conditions up to ``order`` for the weights ``b``."""
    a1 = ALPHA @ ONE
    res = [b @ ONE - 1.0]
    if order >= 2:
        res += [b @ a1 - 0.5, b @ GAMMA @ ONE]
    if order >= 3:
        res += [b @ a1 ** 2 - 1.0 / 3.0, b @ ALPHA @ a1 - 1.0 / 6.0, b @ ALPHA @ GAMMA @ ONE,
                b @ GAMMA @ ALPHA @ ONE, b @ GAMMA @ GAMMA @ ONE]
    return np.array(res)


def stability(z, b):
    """R(z) = 1 + z bᵀ(I − z(α + Γ))⁻¹1, the method's on y′ = λy (z = hλ)."""
    return 1.0 + z * b @ np.linalg.solve(np.eye(4) - z * (ALPHA + GAMMA), ONE)


def test_the_coefficients_satisfy_the_w_method_order_conditions():
    """Order 3 for any matrix in place of J; the embedded solution order 2 (and not 3: its
    difference from the solution is an error estimate)."""
    assert np.max(np.abs(w_conditions(B, 3))) <= 1e-15
    assert np.max(np.abs(w_conditions(B_HAT, 2))) <= 1e-15
    assert np.max(np.abs(w_conditions(B_HAT, 3))) > 1e-2


def test_the_method_is_l_stable_and_stiffly_accurate():
    """γ is the root of the L-stability polynomial of order 3 (γ³ − 3γ² + 3γ/2 − 1/6 = 0);
    stiffly accurate: b is the last row of α + Γ, so R(∞) = 0; A-stable: |R| ≤ 1 on the
    imaginary axis and on the negative real axis."""
    assert abs(G ** 3 - 3 * G ** 2 + 1.5 * G - 1 / 6) <= 1e-15
    assert np.max(np.abs(B - (ALPHA + GAMMA)[3])) <= 1e-15
    assert abs(stability(-1e12, B)) <= 1e-10
    for y in np.geomspace(1e-3, 1e4, 200):
        assert abs(stability(1j * y, B)) <= 1.0 + 1e-12
        assert abs(stability(-y, B)) <= 1.0 + 1e-12


def test_the_transformed_step_is_the_published_method():
    """One step of the stepper's kernel on y′ = Ly (L a 3×3 matrix, not normal) with a matrix A
    ≠ L in place of the Jacobian equals the method as published, (I − hγA)k_i = h f(y +
    Σα_ij k_j) + hA Σ_{j<i} γ_ij k_j, y₁ = y + Σ b_i k_i, computed here with numpy."""
    rng = np.random.default_rng(7)
    L = rng.normal(size=(3, 3)) - 2.0 * np.eye(3)
    A = L + 0.3 * rng.normal(size=(3, 3))
    y0 = rng.normal(size=3)
    h = 0.37
    k = np.zeros((4, 3))
    W = np.eye(3) - h * G * A
    for i in range(4):
        k[i] = np.linalg.solve(W, h * L @ (y0 + ALPHA[i] @ k) + h * A @ (GAMMA[i, :i] @ k[:i]))
    expected = y0 + B @ k
    tab = w_tableau(G, ALPHA, GAMMA, B, B_HAT, order=3)
    got = po.linear_step(tab, L, A, y0, h)
    assert np.max(np.abs(got[0] - expected)) <= 1e-13 * np.max(np.abs(expected))
    # the error estimate: y₁ − ŷ₁ = Σ (b_i − b̂_i) k_i
    assert np.max(np.abs(got[1] - (B - B_HAT) @ k)) <= 1e-13 * np.max(np.abs(k))


@pytest.mark.parametrize("scale", [1.0, 0.5, 0.0])
def test_the_observed_order_is_three_with_any_jacobian(scale):
    """Fixed steps on the oscillator y″ = −4y over 1.5 periods: halving h divides the error by
    2³ with the exact Jacobian, half of it, or none (W = I: the W-method's order does not rest
    on the Jacobian)."""
    errors = []
    for n in (400, 800, 1600):
        y = po.oscillator_fixed("ros34pw2", n, jacobian_scale=scale)
        errors.append(np.max(np.abs(y - po.oscillator_exact(3.0 * math.pi, 2.0))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 3.0) <= 0.15), orders


@pytest.mark.parametrize("rtol", [1e-5, 1e-8])
def test_the_adaptive_solve_follows_the_closed_form(rtol):
    """The oscillator, adaptive at rtol, with its dense output (cubic Hermite) sampled between
    steps: the error a small multiple of rtol on the amplitude's scale, as for the explicit
    pairs (tests/unit/test_integrator.py)."""
    (x, y, y_out, n_out, n_steps, _, _, status), x_out = po.solve_oscillator("ros34pw2", rtol)
    assert status == 0 and x == 3.0 * math.pi and n_out == x_out.size
    assert np.max(np.abs(y - po.oscillator_exact(x, 2.0))) <= 10.0 * rtol * 2.0
    assert np.max(np.abs(y_out - po.oscillator_exact(x_out, 2.0))) <= 10.0 * rtol * 2.0


def test_the_error_follows_the_tolerance():
    errors = []
    for rtol in (1e-5, 1e-8):
        (x, y, *_), _ = po.solve_oscillator("ros34pw2", rtol)
        errors.append(np.max(np.abs(y - po.oscillator_exact(x, 2.0))))
    assert errors[1] < errors[0] / 1e2


def test_an_event_is_located_on_the_dense_output():
    """The oscillator's first fall through zero at x = π/4, located on the cubic Hermite dense
    output to its accuracy at rtol 1e-9."""
    (x, y, _, _, _, _, _, status), _ = po.solve_oscillator("ros34pw2", 1e-9, event=True)
    assert status == 1
    assert abs(x - math.pi / 4.0) <= 1e-9
    assert abs(y[0]) <= 1e-9 and abs(y[1] + 2.0) <= 1e-8


def test_a_stiff_problem_takes_the_w_method_few_steps():
    """Prothero–Robinson with λ = −10⁵: DOP853's step is held at hλ ≈ −6 (its stability
    bound), so it needs about |λ|·x_end/6 ≈ 3·10⁴ steps; the W-method's step follows the
    solution sin x alone. Both end on sin x to their tolerance."""
    lam, rtol = -1e5, 1e-6
    (x, y, y_out, _, steps_w, *_), x_out = po.solve_prothero_robinson("ros34pw2", rtol, lam)
    (x8, y8, _, _, steps_8, *_), _ = po.solve_prothero_robinson("dop853", rtol, lam)
    assert x == x8 == 2.0
    assert abs(y[0] - math.sin(2.0)) <= 10.0 * rtol
    assert np.max(np.abs(y_out[:, 0] - np.sin(x_out))) <= 10.0 * rtol
    assert abs(y8[0] - math.sin(2.0)) <= 10.0 * rtol
    assert steps_8 >= abs(lam) * 2.0 / 6.2 * 0.9
    assert steps_w * 100 <= steps_8


def test_the_registry_holds_the_w_method():
    tab = TABLEAUS["ros34pw2"]
    assert tab.exponent == pytest.approx(1.0 / 3.0) and tab.D.shape[0] == 0
    assert np.array_equal(tab.m, ros34pw2().m)
