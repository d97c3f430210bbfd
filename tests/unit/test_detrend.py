"""Detrended run-up spectra (transient.analysis.orders, ``detrend="ramp"``).

A prescribed ω(φ) = ω₀ + g·φ + a·cos(νφ + θ): a linear run-up plus one harmonic of order ν. Over
each 4-stroke cycle (Φ = 4π) the trend rises by D = gΦ; the plain DFT sees it as a sawtooth that
adds D/(πk) to every harmonic k of the cycle. The ramp removes it exactly (the harmonic is periodic
over the cycle), so the detrended spectrum holds the harmonic alone, up to the resampling error
(samples every 1°, offset from the grid: Hermite bound h⁴/384·aν⁴ ≈ 1e-8 rad/s).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from transient.analysis.orders import cycle_spectra, order_spectrum, resolve_detrend, to_angle_grid

CYCLE = 4.0 * math.pi
N = 720
W0, G, A, NU, THETA = 300.0, 1.2, 0.5, 3.0, 0.7  # rad/s, rad/s per rad, rad/s, order, rad
TOL = 1e-6  # relative to A


def ramp_and_harmonic(cycles: int = 3, offset_deg: float = 0.37):
    """Trajectory columns of the prescribed ω(φ), sampled every 1° off the analysis grid."""
    phi = np.radians(np.arange(0.0, 720.0 * cycles + 1.0) + offset_deg)
    phi = np.concatenate([[0.0], phi[phi < cycles * CYCLE], [cycles * CYCLE]])
    omega = W0 + G * phi + A * np.cos(NU * phi + THETA)
    domega = G - A * NU * np.sin(NU * phi + THETA)  # dω/dφ
    return {"phi": phi, "omega": omega, "epsilon": omega * domega}


def test_ramp_detrend_recovers_the_harmonic_and_plain_dft_leaks():
    traj = ramp_and_harmonic()
    starts, spec = cycle_spectra(traj, "omega", N, CYCLE, detrend="ramp")
    _, plain = cycle_spectra(traj, "omega", N, CYCLE, detrend="none")
    assert starts.size == 3
    k = int(round(NU * CYCLE / (2 * math.pi)))  # harmonic 6 of the cycle
    others = np.ones(spec.orders.size, bool)
    others[[0, k]] = False
    amp_err = np.abs(spec.amplitude[:, k] - A).max() / A
    # phase of a·cos(ν(φ − φ_c) + ν φ_c + θ) in each cycle's own reference
    phase = np.angle(np.exp(1j * (NU * starts + THETA)))
    phase_err = np.abs(np.angle(np.exp(1j * (spec.phase[:, k] - phase)))).max()
    rest = spec.amplitude[:, others].max() / A
    plain_err = np.abs(plain.amplitude[:, k] - A).max() / A
    plain_rest = plain.amplitude[:, others].max() / A
    D = G * CYCLE
    print(f"detrended: |A_ν − a|/a = {amp_err:.1e}, phase {phase_err:.1e} rad, other orders "
          f"≤ {rest:.1e} a; plain DFT: |A_ν − a|/a = {plain_err:.2f}, other orders up to "
          f"{plain_rest:.1f} a (sawtooth D/(πk) = {D / math.pi / A:.1f} a at k = 1)")
    assert amp_err <= TOL
    assert phase_err <= TOL
    assert rest <= TOL
    np.testing.assert_allclose(spec.drift, D, rtol=1e-9)
    # the plain DFT is polluted by the sawtooth: at the harmonic and at every other order
    assert plain_err > 0.5
    assert plain_rest == pytest.approx(D / math.pi / A, rel=0.01)


def test_ramp_on_a_periodic_signal_changes_nothing():
    traj = ramp_and_harmonic()
    traj["omega"] = W0 + A * np.cos(NU * traj["phi"] + THETA)
    traj["epsilon"] = -traj["omega"] * A * NU * np.sin(NU * traj["phi"] + THETA)
    _, ramp = cycle_spectra(traj, "omega", N, CYCLE, detrend="ramp")
    _, plain = cycle_spectra(traj, "omega", N, CYCLE, detrend="none")
    # (only the resampling error of the cycle ends, ~1e-8 rad/s, makes a drift here)
    assert np.abs(ramp.coef - plain.coef).max() <= TOL * A


def test_ramp_needs_the_last_end_and_auto_means_spin_up():
    grid, cols = to_angle_grid(ramp_and_harmonic(1), ("omega",), N, CYCLE, closed=True)
    assert grid.size == N + 1 and grid[-1] == pytest.approx(CYCLE, rel=1e-15)
    with pytest.raises(ValueError, match="end"):
        order_spectrum(cols["omega"][:-1], N, CYCLE, detrend="ramp")
    with pytest.raises(ValueError, match="allowed 'none', 'ramp'"):
        order_spectrum(cols["omega"][:-1], N, CYCLE, detrend="linear", end=0.0)
    assert resolve_detrend("auto", 100.0, 400.0) == "ramp"  # starts below 90 % of its end
    assert resolve_detrend("auto", 380.0, 400.0) == "none"
    assert resolve_detrend("none", 100.0, 400.0) == "none"
