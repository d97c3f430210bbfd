"""What ``transient orders`` computes, :func:`transient.analysis.orders.run_orders` and the order
selections, on synthetic runs whose spectra are known in closed form:

* ω = ω₀(1 + a cos 3φ) over four 2-stroke cycles: order 3 of amplitude aω₀ in every cycle and
  nothing else, the cycle-mean speed ω₀√(1 − a²) (the cycle angle over ∫dφ/ω), δ = 2a/√(1 − a²);
* a gas torque M₀ + B cos(2φ + θ): order 2 of amplitude B and phase θ, mean M₀;
* a central crank-slider at constant speed: the first order of W = ω²s″ is ω²r exactly (the
  root of s holds even orders only) and no odd order ≥ 3.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from transient.analysis.irregularity import NoWholeCycle
from transient.analysis.orders import orders_up_to, run_orders, strongest_orders

W0, A = 100.0, 0.02
M0, B, THETA = 250.0, 80.0, 0.4


def _scene(gas="table", initial_omega=W0 * (1 + A), mechanism=None):
    mech = mechanism or SimpleNamespace(cycle=2 * math.pi)
    return SimpleNamespace(mechanism=mech, initial=SimpleNamespace(phi=0.0, omega=initial_omega),
                           gas=SimpleNamespace(model=gas))


def _rippled(cycles=4.0, per_cycle=7200):
    """ω = ω₀(1 + a cos 3φ) from φ = 0, ε = ω dω/dφ, t by the trapezoidal rule (exact to
    rounding at whole periods of the periodic 1/ω)."""
    phi = np.linspace(0.0, cycles * 2 * math.pi, round(cycles * per_cycle) + 1)
    omega = W0 * (1 + A * np.cos(3 * phi))
    eps = omega * (-3 * A * W0 * np.sin(3 * phi))
    inv = 1.0 / omega
    t = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(phi))])
    return {"t": t, "phi": phi, "omega": omega, "epsilon": eps,
            "M_gas": M0 + B * np.cos(2 * phi + THETA)}


def test_rippled_speed_and_gas_torque():
    traj = _rippled()
    ro = run_orders(_scene(), traj, 720)
    assert ro.cycles == 4 and ro.detrend == "none"
    np.testing.assert_allclose(ro.cycle_start, np.arange(4) * 2 * math.pi, atol=1e-12)
    np.testing.assert_array_equal(ro.orders, np.arange(361))  # 2-stroke: whole orders
    amp = ro.omega.amplitude
    np.testing.assert_allclose(amp[:, 3], A * W0, rtol=1e-9)
    np.testing.assert_allclose(ro.omega.mean, W0, rtol=1e-9)
    others = np.delete(amp[:, 1:], 2, axis=1)
    assert others.max() < 1e-9 * A * W0
    np.testing.assert_allclose(ro.omega_mean, W0 * math.sqrt(1 - A * A), rtol=1e-10)
    assert ro.delta == pytest.approx(2 * A / math.sqrt(1 - A * A), rel=1e-10)
    gas = ro.gas_torque
    assert gas.amplitude.shape == (1, 361)  # the last cycle only
    assert gas.amplitude[-1, 2] == pytest.approx(B, rel=1e-9)
    assert gas.phase[-1, 2] == pytest.approx(THETA, abs=1e-9)
    assert gas.mean[-1] == pytest.approx(M0, rel=1e-12)
    assert np.delete(gas.amplitude[-1, 1:], 1).max() < 1e-9 * B
    assert ro.piston is None


def test_no_gas_spectrum_without_gas_forces():
    assert run_orders(_scene(gas="none"), _rippled(), 720).gas_torque is None


def test_spin_up_is_detrended():
    """A run from 0.5 ω₀ to ω₀ whose scene starts at 0.6 ω₀, below 90 % of the speed the run ends
    at: a spin-up, ω detrended by default (its trend would leak into every order); as asked
    otherwise. Starting at 0.95 ω₀ it is not one."""
    phi = np.linspace(0.0, 2 * 2 * math.pi, 2 * 720 + 1)
    omega = W0 * (0.5 + 0.5 * phi / phi[-1])
    inv = 1.0 / omega
    traj = {"t": np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(phi))]),
            "phi": phi, "omega": omega, "epsilon": omega * 0.5 * W0 / phi[-1]}
    assert run_orders(_scene(initial_omega=0.6 * W0), traj, 720).detrend == "ramp"
    assert run_orders(_scene(initial_omega=0.6 * W0), traj, 720, detrend="none").detrend == "none"
    assert run_orders(_scene(initial_omega=0.95 * W0), traj, 720).detrend == "none"


def test_piston_acceleration_of_a_central_crank_slider_at_constant_speed():
    r, l = 0.05, 0.2
    mech = SimpleNamespace(cycle=2 * math.pi, crank_radius=r, rod_length=l, offset=0.0,
                           firing_angles=(0.0,), slider_law=True)
    phi = np.linspace(0.0, 3 * 2 * math.pi, 3 * 720 + 1)
    traj = {"t": phi / W0, "phi": phi, "omega": np.full_like(phi, W0),
            "epsilon": np.zeros_like(phi)}
    ro = run_orders(_scene(gas="none", initial_omega=W0, mechanism=mech), traj, 720,
                    piston_cylinder=1)
    rep = ro.piston
    assert rep.first[-1] == pytest.approx(W0 ** 2 * r, rel=1e-10)
    assert rep.relative[-1][rep.odd].max() < 1e-10
    assert rep.relative_added[-1].max() < 1e-10
    assert ro.delta == 0.0


def test_no_whole_cycle():
    traj = _rippled(cycles=0.8)
    with pytest.raises(NoWholeCycle, match="the run holds no whole cycle of 360°"):
        run_orders(_scene(), traj, 720)


def test_order_selections():
    """Orders 0 < ν ≤ max_order (the mean left out, the bound included up to rounding), and the
    strongest of them, largest first."""
    orders = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2.5])
    amplitude = np.array([100.0, 1.0, 5.0, 3.0, 4.0, 9.0])
    np.testing.assert_array_equal(orders_up_to(orders, 2.0), [1, 2, 3, 4])
    np.testing.assert_array_equal(orders_up_to(orders, 2.0 - 1e-12), [1, 2, 3, 4])
    np.testing.assert_array_equal(strongest_orders(orders, amplitude, 2.0, count=2), [2, 4])
    np.testing.assert_array_equal(strongest_orders(orders, amplitude, 2.0), [2, 4, 3, 1])
    np.testing.assert_array_equal(strongest_orders(orders, amplitude, 3.0, count=1), [5])
