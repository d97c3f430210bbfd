"""Shared helpers of the validation tests: the scenes in ``cases/`` and an accurate quadrature
of output samples between known cut points (breakpoints, events; ``tests/sample_integrals.py``).
The published tables are read by ``tests/references``."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sample_integrals import sample_integral_impl

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"


@pytest.fixture(scope="session")
def sample_integral():
    """The function :func:`sample_integral_impl` (fixtures keep the test modules import-free)."""
    return sample_integral_impl


def table_end_events_impl(data, scene, tol: float = 1e-6):
    """The run's ``breakpoint`` events (rows of t, φ) where a cylinder's table starts its cycle
    (local angle 0 ≡ the cycle's end): the only corners of a smooth table's curve. Every other
    knot of a table from points is a breakpoint too, but the curve is C² there, so a quadrature
    of the samples needs no cut. ``tol`` [rad] covers a landing in time (to 1e-7 rad)."""
    from transient.scene.queries import gas_phases

    ev = np.asarray(data.events.get("breakpoint", np.zeros((0, 2)))).reshape(-1, 2)
    period = scene.mechanism.cycle
    d = np.mod(np.subtract.outer(ev[:, 1], gas_phases(scene)), period)
    return ev[np.any(np.minimum(d, period - d) <= tol, axis=1)]


@pytest.fixture(scope="session")
def table_end_events():
    """The function :func:`table_end_events_impl`."""
    return table_end_events_impl


class GotsCycle:
    """The Gots diesel's cylinder and mixed cycle as the cases print them (App. 1–2: r, L, D
    [m], ε, and the cycle's pressures [Pa] and exponents), with its closed forms, written apart
    from the library: the volume by Gots (1) and the pressure at a fuel f (gas guide, *Part
    load*)."""

    R, L, BORE, EPS = 0.047, 0.148, 0.088, 18.0
    P_A, N1, P_Z, RHO, N2, P_IN, P_EX = 0.1436e6, 1.368, 10.5e6, 1.671, 1.228, 0.165e6, 0.182e6
    F_P = np.pi * BORE ** 2 / 4
    V_H = F_P * 2 * R
    V_C = V_H / (EPS - 1)
    P_C = P_A * EPS ** N1  # the compression end, a misfire's peak

    def volume(self, x):
        """V at the local angles x of the central crank-slider, Gots (1): V_c + F_p·s."""
        lam = self.R / self.L
        return self.V_C + self.F_P * (self.R * (1 - np.cos(x))
                                      + self.L * (1 - np.sqrt(1 - (lam * np.sin(x)) ** 2)))

    def pressure(self, x, fuel):
        """(p, near): the cycle at fuel f at the local angles x (wrapped), the motored cycle
        p_a(V_a/V)^n1 over the closed part and the gas exchange plus f times what the fired
        cycle (isobar p_z to V = ρV_c, then p_z(ρV_c/V)^n2) adds; ``near``: within 1e-6 rad of a
        corner, where a sample may hold either limit."""
        from scipy.optimize import brentq

        x = np.mod(x, 4 * np.pi)
        x_z = brentq(lambda a: self.volume(a) - self.RHO * self.V_C, 2 * np.pi, 3 * np.pi,
                     xtol=1e-15)
        closed = (x >= np.pi) & (x < 3 * np.pi)
        motored = np.where(closed, self.P_A * (self.EPS * self.V_C / self.volume(x)) ** self.N1,
                           np.where(x < np.pi, self.P_IN, self.P_EX))
        fired = np.where((x >= 2 * np.pi) & (x < x_z), self.P_Z, motored)
        fired = np.where((x >= x_z) & (x < 3 * np.pi),
                         self.P_Z * (self.RHO * self.V_C / self.volume(x)) ** self.N2, fired)
        corners = np.array([0.0, np.pi, 2 * np.pi, x_z, 3 * np.pi, 4 * np.pi])
        near = np.min(np.abs(np.asarray(x)[..., None] - corners), axis=-1) < 1e-6
        return motored + fuel * (fired - motored), near

    def works(self):
        """(fired, motored) loop work of one cylinder [J] from the closed forms: the polytropes'
        (p₁V₁ − p₂V₂)/(n − 1), the isobar p_z(V_z − V_c) and the pumping loop
        (p_in − p_ex)·V_h, which is all a motored cylinder's."""
        v_c, v_a = self.V_C, self.V_C + self.V_H
        v_z = self.RHO * v_c
        p_b = self.P_Z * (v_z / v_a) ** self.N2
        pumping = (self.P_IN - self.P_EX) * self.V_H
        fired = ((self.P_A * v_a - self.P_C * v_c) / (self.N1 - 1) + self.P_Z * (v_z - v_c)
                 + (self.P_Z * v_z - p_b * v_a) / (self.N2 - 1) + pumping)
        return fired, pumping


@pytest.fixture(scope="session")
def gots_cycle() -> GotsCycle:
    """The Gots cycle's closed forms (:class:`GotsCycle`)."""
    return GotsCycle()
