"""The parts of the Floquet analysis (:mod:`transient.analysis.floquet`) on the in-line six's
line, each against an independent computation: the stations' Fourier series against the
mechanism's own J and J′ and a finite difference of J′; the reduced line at constant inertias
against the eigenvalues of the free line's first-order system (the modal analysis' damped
modes); the Magnus product against scipy's adaptive DOP853 on the same A(τ)."""
from __future__ import annotations

import dataclasses as dc
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from transient.analysis import floquet as fq
from transient.scene import load_scene
from transient.shaft import ShaftLine

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture(scope="module")
def six():
    return ShaftLine(load_scene(CASES / "inline6_damper.toml"))


def test_the_series_is_the_mechanisms_inertia(six):
    """J and J′ of every station at 50 angles against :meth:`ShaftLine.station_inertia` (the
    crank-slider's own J_k and dJ_k/dθ) to 1e-12 and 1e-10 of the largest mean inertia (the
    harmonics below 1e-12 of it left out, times their order for J′); J″ against the central
    difference of that J′ (h = 1e-4: error h²J⁗/6, below 1e-8 of it); the period: one
    revolution (the rods' obliquity puts odd orders in)."""
    series = fq.inertia_series(six)
    theta = np.linspace(0.0, 2 * math.pi, 50, endpoint=False) + 0.1234
    J, dJ, ddJ = series.at(theta)
    scale = float(series.coef[:, 0].real.max())
    h = 1e-4
    for i, t in enumerate(theta):
        Jm, dJm = six.station_inertia(t)
        np.testing.assert_allclose(J[i], Jm, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(dJ[i], dJm, rtol=0, atol=1e-10 * scale)
        fd = (six.station_inertia(t + h)[1] - six.station_inertia(t - h)[1]) / (2 * h)
        np.testing.assert_allclose(ddJ[i], fd, rtol=0, atol=1e-8 * scale)
    assert series.g == 1 and 1 in series.orders and 2 in series.orders
    assert np.max(np.abs(ddJ)) > 1e-3 * scale  # (the check is not of zeros)


def _variant(what: str) -> ShaftLine:
    """The six's line without its damper (no dof outside the held mean), or with its viscous
    ring and a flywheel 10⁶ times heavier (which then holds the mean in the free line too)."""
    scene = load_scene(CASES / "inline6_damper.toml")
    shaft = scene.shaft
    if what == "no damper":
        shaft = dc.replace(shaft, dampers=())
    else:
        stations = list(shaft.stations)
        stations[-1] = dc.replace(stations[-1], inertia=1e6 * stations[-1].inertia)
        shaft = dc.replace(shaft, stations=tuple(stations))
    return ShaftLine(dc.replace(scene, shaft=shaft))


@pytest.mark.parametrize("what, tol", [("no damper", 1e-9), ("heavy flywheel", 1e-6)])
def test_at_constant_inertia_the_multipliers_are_the_damped_modes(what, tol):
    """With each station's inertia held at its mean the line is time-invariant: its multipliers
    over a revolution are exp(2πλ/Ω) of the eigenvalues λ of the free line's first-order system
    [[0, I], [−M⁻¹K, −M⁻¹C]] but its rigid motion's two zeros (and the viscous ring's angle's
    zero): the free line's elastic motions keep its mean angle. Without a damper to 1e-9; with
    the viscous ring, whose speed the free line's mean includes and the held mean (over the
    dofs a spring ties) does not, on a flywheel heavy enough to hold both, to 1e-6."""
    line = _variant(what)
    mean = fq.inertia_series(line)
    const = fq.InertiaSeries(np.array([0]), mean.coef[:, :1].copy(), 1)
    red = fq.reduce_line(line)
    omega = 2000 * math.pi / 30
    mu = np.linalg.eigvals(fq.monodromy(red, const, omega))
    n = line.n
    M = line.mean_inertia()
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -line.K / M[:, None]
    A[n:, n:] = -line.C / M[:, None]
    lam = np.linalg.eigvals(A)
    zeros = 2 + sum(d.model == "viscous" for d in line.shaft.dampers)
    lam = lam[np.argsort(np.abs(lam))][zeros:]
    expected = np.exp(2 * math.pi * lam / omega)
    assert mu.size == expected.size
    for e in expected:
        assert np.min(np.abs(mu - e)) <= tol


@pytest.mark.parametrize("rpm", [1200.0, 3000.0])
def test_the_magnus_product_is_the_monodromy(six, rpm):
    """Φ of the six's line over a revolution by the Magnus product against scipy's DOP853 at
    rtol 1e-11 on the same A(τ): the multipliers' moduli to 1e-8."""
    series, red = fq.inertia_series(six), fq.reduce_line(six)
    omega = rpm * math.pi / 30
    phi = fq.monodromy(red, series, omega)
    d = phi.shape[0]

    def f(tau, y):
        return (fq.system_matrices(red, series, omega, [tau])[0] @ y.reshape(d, d)).ravel()

    sol = solve_ivp(f, (0.0, 2 * math.pi), np.eye(d).ravel(), method="DOP853", rtol=1e-11,
                    atol=1e-13)
    ref = sol.y[:, -1].reshape(d, d)
    got, want = (np.sort(np.abs(np.linalg.eigvals(m))) for m in (phi, ref))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8)


def test_the_chart_finds_the_unstable_ranges():
    """Consecutive unstable speeds make one range; the growth per revolution is g ln|μ|max."""
    mu = np.array([[1.0 + 0j], [1.01], [1.02], [0.99], [1.001], [0.98]])
    res = fq.Floquet(None, np.arange(6.0) * 100, mu, 2)
    assert res.unstable_ranges() == [(100.0, 200.0), (400.0, 400.0)]
    np.testing.assert_allclose(res.growth_per_rev, 2 * np.log(np.abs(mu[:, 0])))


def test_a_speed_at_rest_is_refused(six):
    with pytest.raises(ValueError, match="mean speed > 0"):
        fq.multipliers(six, 0.0)
