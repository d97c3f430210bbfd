"""The Floquet multipliers of an elastic shaft line (:mod:`transient.analysis.floquet`) checked
against what is independent of them:

* **Hill's equation**: a Scotch yoke, whose reduced inertia is exactly
  J₀(1 + ε cos 2θ) (m r² sin²θ of its yoke), on a section to a flywheel a million times
  heavier: the product's multipliers, from the scene's line, are those of the two-mass Hill
  equation (T8) integrated apart by scipy (:func:`hill.hill_monodromy`), and the edges of the
  principal region are Mathieu's to first order in ε (T9);
* **the compiled run** (``transient.simulate`` of the same scene): a twist about the steady
  rotation grows per period of the inertia as |μ|max says inside the principal region and decays
  as it says outside; on a three-station line the instability region of the combination
  resonance 2Ω = ω₁ + ω₂, a secondary region that the constant-inertia modes do not show, is
  where the multipliers put its edges: the twist grows just inside each edge and decays just
  outside.

The run's monodromy is measured from its differences over one period of the inertia,
d_n = s_{n+1} − s_n of the states s_n = (twists, their rates/Ω) at the flywheel's angles nπ: the
periodic orbit cancels in them and d_{n+1} = Φ d_n, so Φ follows by least squares and its
largest |μ| is the run's own — about the forced periodic orbit, which the inertia torque
−½J′Ω² holds a few ε/3 rad off θ = Ωt, where the product linearises (T8). That moves the
coefficients by O(ε x) (a few 1e-3 here), the regions' edges by as many parts of Ω: on the
principal region's middle and far outside it the rates agree to a few per cent, a quarter of
a combination region's width (2 % of Ω) from its edges to within a third; the comparison allows
a third of ln|μ|max (and 0.001), and the signs — growth inside, decay outside — are asserted
apart.
"""
from __future__ import annotations

import dataclasses as dc
import math

import numpy as np
import pytest
from hill import hill_monodromy

import transient
from transient.analysis.floquet import growth_per_period, multipliers, region_edge
from transient.scene import load_scene
from transient.shaft import ShaftLine

#: The yoke station: mean inertia J₀, the yoke's m r²/2 = ε J₀ (r = 50 mm), section K.
J0, K, R = 0.1, 1e4, 0.05
W_N = math.sqrt(K / J0)
#: The flywheel's inertia over J₀: it turns at Ω to 1e-6, as (T8) has the second mass.
HEAVY = 1e6


def yoke_line(tmp_path, eps, stations, sections, omega=W_N, periods=100, name="yoke"):
    """A Scotch yoke (yoke mass m = 2εJ₀/r², no block or crank mass, no gas) on the first of
    ``stations`` ((name, own inertia) … , its own inertia J₀(1 − ε) so that its mean is J₀),
    ``sections`` ((k, c) …), the last station the flywheel (the reference); from ``omega``
    [rad/s] untwisted, over ``periods`` half-turns, 8 samples per turn at rtol 1e-10."""
    text = [f'[scene]\nname = "{name}"\n\n[mechanism]\ntype = "scotch-yoke"\n'
            f"crank_radius_mm = {R * 1e3}\nbore_mm = 50\nyoke_mass = {2 * eps * J0 / R ** 2!r}\n"
            "block_mass = 0\ncrank_mass = 0\nstrokes = 2\n\n"
            f"[initial]\nomega = {omega!r}\n\n[run]\nrevolutions = {periods / 2!r}\n\n"
            "[solver]\nrtol = 1e-10\natol = 1e-12\n\n[output]\nsamples_per_rev = 8\n\n[shaft]\n"]
    for i, (st, own) in enumerate(stations):
        text.append(f'[[shaft.stations]]\nname = "{st}"\ninertia = {own!r}\n'
                    + ("cylinders = [1]\n" if i == 0 else ""))
    for k, c in sections:
        text.append(f"[[shaft.sections]]\nstiffness = {k!r}\ndamping = {c!r}\n")
    path = tmp_path / f"{name}.toml"
    path.write_text("\n".join(text), encoding="utf-8")
    return load_scene(path)


def two_mass(tmp_path, eps, zeta, omega=W_N, periods=100):
    c = 2 * zeta * math.sqrt(K * J0)
    return yoke_line(tmp_path, eps, [("yoke", J0 * (1 - eps)), ("flywheel", HEAVY * J0)],
                     [(K, c)], omega, periods)


@pytest.mark.parametrize("ratio", [0.5, 0.9, 0.98, 1.0, 1.02, 1.2, 2.0])
def test_the_two_mass_line_is_hills_equation(tmp_path, ratio):
    """The product's multipliers of the yoke's line at Ω/ω_n = ``ratio`` against the two-mass
    Hill equation's (its J = J₀(1 − ε cos 2θ): the yoke's m r² sin²θ), |μ| to 1e-5 (the
    flywheel's 1e-6 share of the motion, held in the product's mean and fixed in Hill's)."""
    eps, zeta = 0.05, 0.01
    line = ShaftLine(two_mass(tmp_path, eps, zeta))
    omega = ratio * W_N
    mu = multipliers(line, omega)
    hill = np.linalg.eigvals(hill_monodromy(J0, K, -eps, 2 * zeta * math.sqrt(K * J0), omega))
    assert mu.size == 2
    np.testing.assert_allclose(np.sort(np.abs(mu)), np.sort(np.abs(hill)), atol=1e-5)
    # the pair's product is the damping's det Φ = exp(−∫ c/J dt) in both
    assert abs(np.prod(mu) - np.prod(hill)) <= 1e-5


def test_the_principal_region_is_mathieus(tmp_path):
    """Undamped, the edges of the principal region (|μ|max = 1, located by
    :func:`~transient.analysis.floquet.region_edge`) are Mathieu's Ω/ω_n = √(1 ∓ ε/2) within
    ε² (T9), and the region's middle is unstable by more than ε/4 per period."""
    eps = 0.1
    line = ShaftLine(two_mass(tmp_path, eps, 1e-4))  # (a trace of damping: the edges defined)
    lo = region_edge(line, W_N, 0.9 * W_N) / W_N
    hi = region_edge(line, W_N, 1.1 * W_N) / W_N
    assert abs(lo - math.sqrt(1 - eps / 2)) <= eps ** 2
    assert abs(hi - math.sqrt(1 + eps / 2)) <= eps ** 2
    assert growth_per_period(line, 0.5 * (lo + hi) * W_N) > eps / 4


# -- the compiled run -----------------------------------------------------------------------

#: Twists beyond which the run is not used [rad]: J(θ) turns through a radian's worth of its
#: variation there, and the linearisation no longer holds.
LINEAR_TWIST = 0.2
#: Periods of the run from which its monodromy is estimated (at most).
WINDOW = 60


def run_growth(scene) -> tuple[float, np.ndarray]:
    """(ln|μ|max of the run's own monodromy, the largest twist) of ``scene`` run by
    ``transient.simulate``: Φ fitted by least squares to d_{n+1} = Φ d_n over the first
    :data:`WINDOW` periods while the twist is below :data:`LINEAR_TWIST` (every multiplier
    of the run is in the differences from its start, each mode excited by it)."""
    tr = transient.simulate(scene).trajectory
    at = np.flatnonzero(np.abs(tr["phi"] / math.pi - np.round(tr["phi"] / math.pi)) < 1e-9)
    line = ShaftLine(scene)
    names = [d.name for d in line.dofs[:-1]]  # (the flywheel is the reference)
    omega = tr["omega"][at]
    s = np.array([np.concatenate([[tr[f"twist_{n}"][i] for n in names],
                                  [(tr[f"omega_{n}"][i] - tr["omega"][i]) / tr["omega"][i]
                                   for n in names]]) for i in at])
    twist = np.abs(s[:, :len(names)]).max(axis=1)
    linear = np.flatnonzero(twist >= LINEAR_TWIST)
    end = min(WINDOW, linear[0] if linear.size else twist.size)
    d = np.diff(s[:end], axis=0)
    assert d.shape[0] >= 4 * d.shape[1], "too few periods in the linear range"
    assert np.ptp(omega) < 1e-4 * omega[0]  # (the flywheel turns at Ω)
    phi = np.linalg.lstsq(d[:-1], d[1:], rcond=None)[0].T
    return float(np.log(np.abs(np.linalg.eigvals(phi)).max())), twist


def agrees(measured: float, predicted: float) -> bool:
    return abs(measured - predicted) <= max(abs(predicted) / 3.0, 1e-3)


@pytest.mark.parametrize("ratio", [1.0, 1.1])
def test_the_run_grows_inside_the_principal_region_and_decays_outside(tmp_path, ratio):
    """ε = 0.05, ζ = 0.002: at Ω = ω_n (the region's middle) the twist about the orbit grows
    per period as |μ|max says, at 1.1 ω_n (outside) it decays as it says."""
    scene = two_mass(tmp_path, 0.05, 0.002, ratio * W_N, periods=100)
    predicted = growth_per_period(ShaftLine(scene), ratio * W_N)
    measured, _ = run_growth(scene)
    assert (predicted > 0.02) if ratio == 1.0 else (predicted < 0.0)
    assert (measured > 0.0) == (predicted > 0.0)
    assert agrees(measured, predicted), (measured, predicted)


def three_stations(tmp_path, omega, periods=200):
    """Yoke (ε = 0.05), a middle station of J₀, the flywheel; both sections K, c = 2ζ√(K J₀)
    with ζ = 0.003: enough for a visible decay outside the region, which it leaves open."""
    c = 2 * 0.003 * math.sqrt(K * J0)
    return yoke_line(tmp_path, 0.05, [("yoke", 0.95 * J0), ("middle", J0),
                                      ("flywheel", HEAVY * J0)], [(K, c), (K, c)], omega,
                     periods, name="three")


def test_the_combination_region_is_where_floquet_puts_it(tmp_path):
    """2Ω = ω₁ + ω₂ of the three-station line (held at the flywheel: ω₁,₂ = ω_n (3 ∓ √5)/2 at
    mean inertias): Floquet finds an unstable region there, which neither mode's principal
    region reaches; its edges (brentq on |μ|max = 1) bracket it. Runs at a quarter of the
    region's width inside each edge grow, at a quarter outside decay, each at its |μ|max."""
    base = three_stations(tmp_path, W_N)
    line = ShaftLine(base)
    w1, w2 = W_N * math.sqrt((3 - math.sqrt(5)) / 2), W_N * math.sqrt((3 + math.sqrt(5)) / 2)
    middle = 0.5 * (w1 + w2)
    assert growth_per_period(line, middle) > 0.0
    lo = region_edge(line, middle, 0.9 * middle)
    hi = region_edge(line, middle, 1.1 * middle)
    width = hi - lo
    assert w1 < lo < middle < hi < w2 and width < 0.1 * middle
    for edge, inward in ((lo, 1.0), (hi, -1.0)):
        for side in (1.0, -1.0):  # (inside, then outside)
            omega = edge + side * inward * 0.25 * width
            scene = dc.replace(base, initial=dc.replace(base.initial, omega=omega))
            predicted = growth_per_period(line, omega)
            measured, _ = run_growth(scene)
            assert (predicted > 0.0) == (side > 0.0)
            assert (measured > 0.0) == (side > 0.0), (omega, measured, predicted)
            assert agrees(measured, predicted), (omega, measured, predicted)
