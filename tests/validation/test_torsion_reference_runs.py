"""The elastic shaft line's reference model (:mod:`transient.reference.torsion`) run in time:

* **energy** (T4): Σ ½ J_k ω_k² + Σ ½ k Δθ² less the applied work plus every loss (sections,
  absolute damping, the dampers' rings, the coupling, the pairs per throw), integrated as extra
  states, is zero to the solver's tolerance on an in-line six with every element;
* **rigid limit**: as the sections stiffen, the flywheel's ω(φ) converges to the rigid reduced
  equation (18) of the same engine, integrated apart in crank angle on the mechanism's twin
  J(φ) (:func:`~transient.reference.torsion.rigid_run`), the error falling as 1/k;
* **Floquet**: the multipliers of the linearised two-mass model with J = J₀(1 + ε cos 2θ) at a
  constant speed Ω, from a monodromy matrix integrated here (Hill's equation (T8)), locate the
  principal parametric instability where Mathieu's chart puts it to first order in ε
  (the gap second order), and predict the growth or decay of a small twist about the periodic
  orbit of the nonlinear reference model.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from engines import SIX_OWN, inline_six_line, inline_six_mech
from hill import hill_monodromy
from scipy.optimize import brentq

from transient.mechanisms.twins import CrankSliderNumpy
from transient.reference.torsion import (
    WORKS,
    Coupling,
    CrankSliderCylinders,
    PressurePulse,
    ShaftLine,
    TorsionModel,
    integrate,
    rigid_run,
)

PULSE = PressurePulse(9e6, math.radians(12.0), math.radians(15.0))
CYCLE = 4.0 * math.pi
SPEED = 200.0  # [rad/s]
MEAN_TORQUE = 356.0  # the pulse's mean moment over a cycle, six cylinders [N m]


def fan(ratio):
    """A fan load on the driven side absorbing about the engine's mean torque at SPEED."""
    return lambda th, w, t: -MEAN_TORQUE * ratio * (w * ratio / SPEED) ** 2


def test_energy_balance_every_element():
    """(T4) at every step: each loss is a visible share of the energy (so that a wrong one
    would show thousands of times above the tolerance), and the residual stays within
    rtol × the energy turned over, at rtol 1e-8 and 1e-10, falling with rtol."""
    mech = inline_six_mech()
    # (absolute damping on the motion relative to the line's only: more, to take a share)
    line = inline_six_line(absolute=np.array([0.0] + [0.5] * 6 + [0.0]),
                           eta=(np.full(8, 0.98), np.full(8, 0.97)))
    model = TorsionModel(line, CrankSliderCylinders(mech, PULSE), driven_load=fan(2.0),
                         external=lambda th, w, t: np.where(np.arange(8) == 0, -5.0, 0.0))
    y0 = model.initial_state(0.0, SPEED)
    residuals = []
    for rtol in (1e-8, 1e-10):
        sol = integrate(model, y0, 2 * CYCLE / SPEED, rtol=rtol, atol=rtol)
        W = dict(zip(WORKS, sol.y[model.i_works:, -1]))
        turned_over = W["W_gas"] + model.kinetic(y0)
        balance = np.array([model.balance(y, y0) for y in sol.y.T])
        assert np.max(np.abs(balance)) <= rtol * turned_over
        for name, value in W.items():
            assert abs(value) >= 1e-5 * turned_over, name
        residuals.append(np.max(np.abs(balance)))
    assert residuals[1] < residuals[0]


def six_line(k: float, ratio: float, zeta: float = 0.3) -> ShaftLine:
    """The six with every section (and the coupling, 3 % of it) of stiffness k, damped at the
    ratio ζ of each section's two neighbours (heavily: the start's free vibration, excited by
    starting without twist, is gone within the first cycle), no rings."""
    J = SIX_OWN + 0.014  # (with the mean of each throw's cylinder)
    ks = np.full(7, k)
    c = 2 * zeta * np.sqrt(ks * np.minimum(J[:-1], J[1:]) / 2)
    kc, Jd = 0.03 * k, 0.5
    return ShaftLine(inertia=SIX_OWN, stiffness=ks, damping=c,
                     absolute=np.array([0.0] + [0.005] * 6 + [0.0]),
                     station_of_cylinder=np.arange(1, 7),
                     coupling=Coupling(7, kc, 2 * zeta * math.sqrt(kc * Jd / ratio ** 2), ratio,
                                       Jd))


@pytest.mark.slow
def test_rigid_limit():
    """The flywheel's ω against the rigid run's at the flywheel's angle over the third cycle:
    the error falls by more than 10 × over the decade 1e7 → 1e8 N m/rad and as k^−1 (slope
    0.8 … 1.2) from 1e8 to 3e8. The rigid run: J = Σ J_own + J_d/i² + the twin's J(φ), its
    gas moment from the twin's u and the fan reduced through the gear (the absolute damping,
    acting on the motion relative to the line's, has no part in the rigid motion)."""
    mech = inline_six_mech()
    ratio, Jd = 2.0, 0.5
    cyl, twin = CrankSliderCylinders(mech, PULSE), CrankSliderNumpy(mech)
    load = fan(ratio)

    def gas(phi):
        local = np.mod(phi - np.asarray(mech.firing_angles), CYCLE)
        return float(PULSE(local) @ twin.terms(phi)[2] * mech.piston_area)

    cycles = 3
    rigid, omega = rigid_run(SIX_OWN.sum() + Jd / ratio ** 2, twin.terms, gas,
                             lambda phi, w: load(phi / ratio, w / ratio, 0) / ratio,
                             cycles * CYCLE + 1.0, SPEED)
    t_end = rigid.sol(cycles * CYCLE)[0]
    flywheel = 7
    errors = {}
    for k in (1e7, 1e8, 3e8):
        model = TorsionModel(six_line(k, ratio), cyl, driven_load=load)
        sol = integrate(model, model.initial_state(0.0, SPEED), t_end, method="LSODA",
                        rtol=1e-11, atol=1e-11, dense_output=True)
        y = sol.sol(np.linspace(t_end * (cycles - 1) / cycles, t_end, 2000))
        errors[k] = np.max(np.abs(y[8 + flywheel] - omega(y[flywheel])))
    assert errors[1e8] < 0.1 * errors[1e7]
    slope = math.log(errors[1e8] / errors[3e8]) / math.log(3.0)
    assert 0.8 <= slope <= 1.2, (errors, slope)


# -- Floquet ------------------------------------------------------------------------------------

J0, K = 0.1, 1e4
W_N = math.sqrt(K / J0)


def monodromy(eps: float, c: float, Om: float) -> np.ndarray:
    """Hill's two-mass monodromy (:func:`hill.hill_monodromy`) of this module's J₀ and K."""
    return hill_monodromy(J0, K, eps, c, Om)


def principal_region(eps: float) -> tuple[float, float]:
    """The principal instability region's edges in Ω/ω_n, undamped: there det M = 1 (the
    damping term Ω J′/J integrates to zero over a period), so the edges are |tr M| = 2."""
    def edge(r):
        return abs(np.trace(monodromy(eps, 0.0, r * W_N))) - 2.0
    return (brentq(edge, 0.85, 1.0, xtol=1e-12), brentq(edge, 1.0, 1.15, xtol=1e-12))


def test_principal_region_against_mathieu():
    """To first order in ε (T9) the twist obeys Mathieu's y″ + (a − 2q cos 2τ) y = 0 with
    a = (ω_n/Ω)², q = aε/2, whose first region a = 1 ± q puts the edges at
    Ω/ω_n = √(1 ∓ ε/2); the Floquet edges differ by O(ε²): at most ε², and 4 × less
    (3 … 5) at half the ε."""
    gaps = []
    for eps in (0.1, 0.05):
        lo, hi = principal_region(eps)
        mathieu = (math.sqrt(1 - eps / 2), math.sqrt(1 + eps / 2))
        gap = max(abs(lo - mathieu[0]), abs(hi - mathieu[1]))
        assert gap <= eps ** 2
        gaps.append(gap)
        mid = np.abs(np.linalg.eigvals(monodromy(eps, 0.0, 0.5 * (lo + hi) * W_N)))
        out = np.abs(np.linalg.eigvals(monodromy(eps, 0.0, (hi + 0.02) * W_N)))
        assert mid.max() > 1.0 + eps / 4 and abs(out.max() - 1.0) < 1e-9
    assert 3.0 <= gaps[0] / gaps[1] <= 5.0


class VariableInertia:
    """A 'cylinder' of inertia J₀ ε cos 2θ on a station of J₀: J = J₀ (1 + ε cos 2θ)."""

    def __init__(self, eps: float) -> None:
        self.eps = eps

    def inertia(self, a):
        return J0 * self.eps * np.cos(2 * a), -2 * J0 * self.eps * np.sin(2 * a)

    def moments(self, a, w, t):
        return np.zeros(a.shape)


@pytest.mark.parametrize("ratio", [1.0, 1.2, 0.9])
def test_floquet_predicts_the_twist(ratio):
    """The nonlinear reference, two stations (the second of 10⁹ J₀, turning at Ω), ε = 0.2,
    ζ = 0.01: its periodic orbit by shooting (Newton on the twist and its rate after one
    period), the multipliers of its finite-difference monodromy against Hill's within ε²/2
    (the linearisation about θ = Ωt rather than the orbit), and a twist of 1e-6 rad added to
    the orbit grows over 20 periods at the centre of the region (|μ| > 1) by at least
    |μ|^20 / 2 and decays outside it (|μ| < 1), to below |μ|^20 × 2 (the complex pair's
    beat between the two measures of the twist)."""
    eps, zeta = 0.2, 0.01
    c = 2 * zeta * math.sqrt(K * J0)
    Om = ratio * W_N
    period = math.pi / Om
    line = ShaftLine(inertia=np.array([J0, 1e9 * J0]), stiffness=np.array([K]),
                     damping=np.array([c]), absolute=np.zeros(2),
                     station_of_cylinder=np.array([0]))
    model = TorsionModel(line, VariableInertia(eps))

    def start(x):
        y = model.initial_state(0.0, Om)
        y[0] += x[0]
        y[2] += x[1]
        return y

    def twist(y):
        return np.array([y[0] - y[1], y[2] - y[3]])

    def run(x, periods=1):
        return integrate(model, start(x), periods * period, rtol=1e-12, atol=1e-13,
                         dense_output=True)

    x, h = np.zeros(2), 1e-7
    for _ in range(8):
        F = twist(run(x).y[:, -1]) - x
        dF = np.column_stack([(twist(run(x + h * e).y[:, -1]) - x - h * e - F) / h
                              for e in np.eye(2)])
        x = x - np.linalg.solve(dF, F)
        if np.max(np.abs(F)) <= 1e-10:
            break
    assert np.max(np.abs(F)) <= 1e-10
    mu = np.abs(np.linalg.eigvals(monodromy(eps, c, Om))).max()
    monodromy_ref = dF + np.eye(2)  # (the map's own, about its periodic orbit)
    assert abs(np.abs(np.linalg.eigvals(monodromy_ref)).max() - mu) <= 0.5 * eps ** 2
    n = 20
    base, pert = run(x, n), run(x + np.array([1e-6, 0.0]), n)
    at = np.array([0.0, n * period])
    d = np.array([twist(p) - twist(b) for p, b in zip(pert.sol(at).T, base.sol(at).T)])
    grown = math.hypot(d[1, 0] * Om, d[1, 1]) / math.hypot(d[0, 0] * Om, d[0, 1])
    if mu > 1.0:
        assert grown >= mu ** n / 2 > 1.0
    else:
        assert grown <= 2 * mu ** n and grown < 1.0
