"""Hill's equation of a two-mass shaft line (theory, (T8)), the tests' independent check of the
Floquet multipliers (on ``pythonpath``, pyproject): one copy."""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def hill_monodromy(J0: float, K: float, eps: float, c: float, Om: float) -> np.ndarray:
    """The twist x = θ₁ − Ωt of a mass J₀(1 + ε cos 2θ₁) on a section (K, c) to a mass turning
    at Ω: J ẍ + (c + Ω J′) ẋ + (K + ½ Ω² J″) x = 0, its fundamental matrix over one period π/Ω
    of the parametric excitation, integrated by scipy's DOP853."""
    def f(t, z):
        co, s = math.cos(2 * Om * t), math.sin(2 * Om * t)
        J, dJ, ddJ = J0 * (1 + eps * co), -2 * J0 * eps * s, -4 * J0 * eps * co
        A = np.array([[0.0, 1.0], [-(K + 0.5 * Om ** 2 * ddJ) / J, -(c + Om * dJ) / J]])
        return (A @ z.reshape(2, 2)).ravel()
    sol = solve_ivp(f, (0.0, math.pi / Om), np.eye(2).ravel(), method="DOP853", rtol=1e-12,
                    atol=1e-14)
    return sol.y[:, -1].reshape(2, 2)
