"""Swash-plate engine under equation (18): energy is conserved when coasting, and a constant gas force
does exactly the work F·Δx on its piston(s) (Antonyuk et al. (18), (19)).

The kernel's J, dJ/dφ and u_k are integrated with scipy's DOP853 at tight tolerance; a wrong dJ/dφ
or a sign slip between u_k and the piston positions would show as an energy drift.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from transient.core.model import swash_plate as core
from transient.mechanisms import swash_plate as sp

J_SHAFT = 1.0  # I₁ of the paper's example [kg m²]


def spin(geom, force, turns=3.0, omega0=10.0):
    """Integrate (18) from φ = 0, ω = ω₀ with a constant force on the piston(s) of cylinder 1."""
    mp = geom.pack()
    u, du = np.empty(geom.cylinders), np.empty(geom.cylinders)

    def rhs(t, y):
        J, dJ = core.swash_terms(mp, y[0], u, du)
        return [y[1], (force * u[0] - 0.5 * dJ * y[1] ** 2) / (J_SHAFT + J)]

    sol = solve_ivp(rhs, (0.0, 2.0 * np.pi * turns / omega0), [0.0, omega0], method="DOP853",
                    rtol=1e-12, atol=1e-12, dense_output=True)
    phi, omega = sol.y
    J = np.array([core.swash_terms(mp, p, u, du)[0] for p in phi])
    return phi, 0.5 * (J_SHAFT + J) * omega**2


@pytest.mark.parametrize("changes", [{}, dict(hinge="normal", halves=2, rod_model="rigid",
                                              rod_inertia_cg=0.01, link_polar_inertia=0.45)])
def test_coasting_conserves_energy(changes):
    _, energy = spin(sp.antonyuk_example(**changes), force=0.0)
    np.testing.assert_allclose(energy, energy[0], rtol=1e-9)


@pytest.mark.parametrize("halves", [1, 2])
def test_constant_gas_force_does_the_work_F_dx(halves):
    geom = sp.antonyuk_example(halves=halves)
    force = 2.0e3  # N on each piston of cylinder 1, pushing it toward its plate
    phi, energy = spin(geom, force)
    x = sp.positions(geom, phi)["D"][:, 0, 0, 0]  # half 1; the mirror piston moves as far
    np.testing.assert_allclose(energy - energy[0], halves * force * (x - x[0]), rtol=0,
                               atol=1e-9 * energy[0])
