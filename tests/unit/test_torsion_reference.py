"""The elastic shaft line's reference model (:mod:`transient.reference.torsion`), part by part:
each cylinder's own reduced inertia (T1a) against the mechanism's twin, whose total J(φ) and
transfer functions are written apart (:class:`~transient.mechanisms.twins.CrankSliderNumpy`);
J′_c against a central difference; each station's equation against its Lagrangian by finite
differences; bad shaft lines refused."""
from __future__ import annotations

import math

import numpy as np
import pytest
from engines import MECHS, inline_six_mech

from transient.mechanisms.twins import CrankSliderNumpy
from transient.reference.torsion import (
    CrankSliderCylinders,
    PressurePulse,
    Ring,
    ShaftLine,
    TorsionModel,
)

ALL = {**MECHS, "inline-six": inline_six_mech()}
ANGLES = np.linspace(0.0, 4.0 * math.pi, 181)


@pytest.mark.parametrize("name", ALL)
def test_cylinders_sum_to_the_twins_total(name):
    """Σ_c J_c(φ), Σ J′_c and each u_c at one shaft angle are the twin's J, J′, u to rounding:
    the same mechanism, written once by the radicand √(l² − q²), once by Gots' β."""
    mech = ALL[name]
    cyl, twin = CrankSliderCylinders(mech), CrankSliderNumpy(mech)
    r = mech.crank_radius
    for phi in ANGLES:
        J, dJ, u, _ = twin.terms(phi)
        at = np.full(mech.n_cylinders, phi)
        Jc, dJc = cyl.inertia(at)
        assert abs(Jc.sum() - J) <= 1e-14 * J
        assert abs(dJc.sum() - dJ) <= 1e-14 * J
        assert np.max(np.abs(cyl.piston_speeds(at) - u)) <= 1e-14 * r


@pytest.mark.parametrize("name", ALL)
def test_cylinder_inertia_derivative(name):
    """J′_c against a central difference (step 1e-4 rad: truncation ~1e-8 J J‴, rounding
    ~1e-12 J)."""
    mech = ALL[name]
    cyl = CrankSliderCylinders(mech)
    h = 1e-4
    at = np.add.outer(ANGLES, np.zeros(mech.n_cylinders))
    for a in at:
        fd = (cyl.inertia(a + h)[0] - cyl.inertia(a - h)[0]) / (2 * h)
        scale = np.max(cyl.inertia(a)[0])
        assert np.max(np.abs(fd - cyl.inertia(a)[1])) <= 1e-7 * scale


def test_gas_moment_is_the_pressure_force_times_piston_speed():
    """At a cylinder's angle the gas moment is (p − p₀) A_p u_c with the twin's u, the pulse
    peaking where asked."""
    mech = inline_six_mech()
    pulse = PressurePulse(9e6, math.radians(12.0), math.radians(15.0))
    cyl, twin = CrankSliderCylinders(mech, pulse), CrankSliderNumpy(mech)
    assert pulse(np.array([math.radians(12.0)]))[0] == pytest.approx(9e6, rel=1e-15)
    for phi in ANGLES:
        u = twin.terms(phi)[2]
        local = np.mod(phi - np.asarray(mech.firing_angles), 4 * math.pi)
        want = pulse(local) * mech.piston_area * u
        got = cyl.moments(np.full(6, phi), np.zeros(6), 0.0)
        # (floor: rounding of u at a dead centre, on the scale p_peak A_p r)
        floor = 1e-14 * 9e6 * mech.piston_area * mech.crank_radius
        assert np.allclose(got, want, rtol=1e-14, atol=floor)


def test_station_equation_is_lagranges():
    """Each station's acceleration solves d/dt ∂L/∂ω_k − ∂L/∂θ_k = Q_k, L = Σ ½ J_k(θ_k) ω_k² −
    Σ ½ k_i Δθ_i², with ∂L/∂θ_k by a central difference of L itself (not of J), the damping's
    and the applied moments' Q_k written out here: d/dt(J_k ω_k) = J′_k ω_k² + J_k θ̈_k."""
    mech = inline_six_mech()
    pulse = PressurePulse(9e6, math.radians(12.0), math.radians(15.0))
    line = ShaftLine(inertia=np.array([0.03] + [0.05] * 6 + [1.2]),
                     stiffness=np.array([6e5] + [1.2e6] * 5 + [1.5e6]),
                     damping=np.array([5.0] + [10.0] * 6), absolute=np.full(8, 0.01),
                     station_of_cylinder=np.arange(1, 7))
    model = TorsionModel(line, CrankSliderCylinders(mech, pulse))
    rng = np.random.default_rng(7)
    th = 0.3 + rng.normal(0.0, 1e-3, 8)
    w = 200.0 + rng.normal(0.0, 2.0, 8)
    y = np.concatenate([th, w, np.zeros(8)])

    def lagrangian(theta):
        J = model.station_inertia(theta)[0]
        return 0.5 * np.sum(J * w * w) - 0.5 * np.sum(line.stiffness * np.diff(theta) ** 2)

    J, dJ, _ = model.station_inertia(th)
    acc = model.rhs(0.0, y)[8:16]
    h = 1e-6
    dL = np.array([(lagrangian(th + h * e) - lagrangian(th - h * e)) / (2 * h)
                   for e in np.eye(8)])
    dw = np.diff(w)
    damping = np.zeros(8)
    damping[:-1] += line.damping * dw
    damping[1:] -= line.damping * dw
    # the absolute damping as the matrix Pᵀ A P on the speeds less their mean (P = I − 1 mᵀ/Σm,
    # m the cycle-mean inertias): no net torque, Σ a (ω − ω̄)² of power
    P = np.eye(8) - np.outer(np.ones(8), model.weights) / model.weights.sum()
    Q = model.gas_moments(th, w, 0.0) + damping - P.T @ np.diag(line.absolute) @ P @ w
    residual = dJ * w * w + J * acc - dL - Q
    assert np.max(np.abs(residual)) <= 1e-6 * np.max(np.abs(Q))


@pytest.mark.parametrize("change, says", [
    (dict(stiffness=np.array([1e6])), "stiffness: 1 values for 3 stations"),
    (dict(inertia=np.array([0.1, 0.0, 0.1])), "inertia > 0"),
    (dict(station_of_cylinder=np.array([3])), "stations 0 … 2"),
    (dict(rings=(Ring(5, 0.1, 1.0),)), "rings"),
    (dict(eta=(np.full(3, 1.2), np.ones(3))), "0 < η ≤ 1"),
])
def test_bad_lines_refused(change, says):
    base = dict(inertia=np.array([0.1, 0.1, 0.1]), stiffness=np.array([1e6, 1e6]),
                damping=np.zeros(2), absolute=np.zeros(3), station_of_cylinder=np.array([1]))
    with pytest.raises(ValueError, match=says):
        ShaftLine(**{**base, **change})
