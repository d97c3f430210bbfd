"""Shared helpers of the validation tests: the Gots tables (``tests/data``), the scenes in
``cases/``, and an accurate quadrature of output samples between known cut points (breakpoints,
events)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"
#: The Gots tables as printed, with their provenance and misprints (``tests/data/README.md``).
GOTS_DATA = REPO / "tests" / "data"


@pytest.fixture(scope="session")
def gots_data() -> Path:
    """Folder of the Gots CSV tables."""
    return GOTS_DATA


def segment_integral(x, f, a: float, b: float, degree: int = 6) -> float:
    """∫_a^b f dx from samples (x, f) of a function smooth on [a, b].

    Each interval between consecutive nodes (a, the samples strictly inside (a, b), b) is
    integrated exactly for the interpolating polynomial of degree ``degree`` through the
    ``degree + 1`` samples nearest to it, all taken from inside the segment (so nothing is
    interpolated across a cut, and the end intervals are extrapolated from inside). Samples
    within 1e-12 of a cut are left out: at a jump of the integrand they may hold either limit.
    The error is O(h^(degree+1)) per interval on any spacing; degree 6 on 0.5° samples of the
    engine torques is ~1e-12 of the work (checked against a 2× coarser sampling in the tests).
    """
    x = np.asarray(x, dtype=float)
    f = np.asarray(f, dtype=float)
    tol = 1e-12 * max(abs(a), abs(b), 1.0)
    inside = (x > a + tol) & (x < b - tol)
    order = np.argsort(x[inside])
    xs, fs = x[inside][order], f[inside][order]
    n = xs.size
    if n < 2:
        raise ValueError(f"segment [{a!r}, {b!r}] holds {n} sample(s); sample more densely")
    d = min(degree, n - 1)
    nodes = np.concatenate([[a], xs, [b]])
    lo, hi = nodes[:-1], nodes[1:]
    k = np.searchsorted(xs, 0.5 * (lo + hi))
    start = np.clip(k - (d + 1) // 2, 0, n - d - 1)
    idx = start[:, None] + np.arange(d + 1)[None, :]
    h = hi - lo
    z = (xs[idx] - lo[:, None]) / h[:, None]  # stencil in units of the interval
    vander_t = z[:, None, :] ** np.arange(d + 1)[None, :, None]  # (m, power, node)
    moments = np.broadcast_to(1.0 / np.arange(1, d + 2), (lo.size, d + 1))
    w = np.linalg.solve(vander_t, moments[..., None])[..., 0]  # ∫₀¹ of each Lagrange basis
    return float(np.sum(h * np.sum(w * fs[idx], axis=1)))


def sample_integral_impl(x, f, cuts, degree: int = 6, merge: float = 1e-9) -> float:
    """∫ f dx over [min(cuts), max(cuts)], segment by segment between the sorted cuts.

    Cuts closer than ``merge`` (relative) are one cut: a segment that short holds no sample and,
    for a bounded integrand, a negligible integral (< merge × |f|max × scale).
    """
    cuts = np.unique(np.asarray(cuts, dtype=float))
    scale = max(1.0, float(np.max(np.abs(cuts))))
    cuts = cuts[np.concatenate([[True], np.diff(cuts) > merge * scale])]
    return sum(segment_integral(x, f, a, b, degree) for a, b in zip(cuts[:-1], cuts[1:]))


@pytest.fixture(scope="session")
def sample_integral():
    """The function :func:`sample_integral_impl` (fixtures keep the test modules import-free)."""
    return sample_integral_impl


def table_end_events_impl(data, scene, tol: float = 1e-6):
    """The run's ``breakpoint`` events (rows of t, φ) where a cylinder's table starts its cycle
    (local angle 0 ≡ the cycle's end): the only corners of a smooth table's curve. Every other
    knot of a table from points is a breakpoint too, but the curve is C² there, so a quadrature
    of the samples needs no cut. ``tol`` [rad] covers a landing in time (to 1e-7 rad)."""
    from transient.assemble import gas_phases

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
