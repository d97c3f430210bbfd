"""Order analysis (transient.analysis.orders) against closed forms.

* **Resampling**: a sum of cosines of known orders sampled on a random ±40 % mesh; the Hermite and
  spline interpolants against the function itself, within the documented bounds h⁴/384·M₄ and
  (5/384)·h⁴·M₄ (M₄ = Σ|a|ν⁴ ≥ max|v⁽⁴⁾|), converging as h⁴; coinciding grids return the samples;
  cuts and repeated angles keep a corner or a jump out of the interpolation.
* **Spectra**: sums of cosines with known orders, amplitudes and phases, per cycle; a ramp's DFT
  (closed form D/(N sin(πk/N))) for the drift; the Hann window on separated lines.
* **Kinematics at constant ω** (Gots example r = 47, l = 148 mm): odd orders ≥ 3 of W vanish, the
  first order is exactly rω² (r cos φ is the only odd term of s), W(0) = rω²(1 + λ),
  W(π) = −rω²(1 − λ) (Semenov (25)); β only odd orders; Semenov's printed FFT numbers (§5, oracles
  7, 9) for r = 95, l = 313 mm; with an offset the third order against a quadrature of the exact
  travel (Gots (12)) and the leading series term (9/8)kλ³.
* **Prescribed ω(φ) = ω₀(1 + a cos kφ)**: the spectrum of W against the convolution of the
  closed-form series of ω² and ε with the Fourier series of s″, s′ (Gots' exact velocity and
  acceleration, written here, FFT by numpy); the odd-harmonic report on this motion with the
  closed-form time t(φ): δ = 2a/√(1 − a²), ω̄ = ω₀√(1 − a²).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from references import check_all, semenov
from scipy.integrate import quad

from transient.analysis.loads.crank_slider import slider_arrays
from transient.analysis.orders import (
    cycle_spectra,
    odd_harmonic_report,
    order_spectrum,
    piston_acceleration,
    piston_inertia_force,
    resample_angle,
    rod_angular_acceleration,
    to_angle_grid,
)

R, L = 0.047, 0.148  # cases/gots_diesel_4400.toml (Gots App. 1)
LAM = R / L
TWO_PI, FOUR_PI = 2.0 * math.pi, 4.0 * math.pi

# f(φ) = Σ a cos(νφ + θ): whole and half orders
TERMS = [(1.0, 1.0, 0.3), (0.2, 1.5, -1.0), (0.05, 3.5, 2.0), (0.01, 6.0, 0.5)]
M4 = sum(a * nu ** 4 for a, nu, _ in TERMS)


def f(x):
    return sum(a * np.cos(nu * x + th) for a, nu, th in TERMS)


def df(x):
    return sum(-a * nu * np.sin(nu * x + th) for a, nu, th in TERMS)


def jittered(h0, span=FOUR_PI, seed=0):
    """Sample angles with spacings h0·(1 ± 40 %), from a random start; and the largest spacing."""
    rng = np.random.default_rng(seed)
    n = int(span / h0)
    x = np.concatenate([[0.0], np.cumsum(h0 * (1.0 + 0.8 * (rng.random(n) - 0.5)))])
    x += rng.random()
    return x, float(np.diff(x).max())


# ------------------------------------------------------------------------------------------------
# Resampling


@pytest.mark.parametrize("seed", range(4))
def test_resample_hermite_and_spline_within_stated_bounds(seed):
    """Hermite ≤ h⁴M₄/384; spline ≤ (5/384)h⁴M₄ three intervals away from the ends, ≤ twice it
    next to them: bounds with room over seeds 0–39 and h = 0.005…0.056 (-s prints the ratios)."""
    for h0 in (0.04, 0.01):
        x, h = jittered(h0, seed=seed)
        g = np.linspace(x[0], x[-1], 4001)
        e_herm = np.abs(resample_angle(x, f(x), g, df(x)) - f(g))
        e_spl = np.abs(resample_angle(x, f(x), g) - f(g))
        inner = (g > x[3]) & (g < x[-4])
        print(f"h = {h:.4f}: Hermite {e_herm.max() / (h**4 * M4 / 384):.3f} of its bound, spline "
              f"{e_spl[inner].max() / (5 * h**4 * M4 / 384):.3f} (interior), "
              f"{e_spl.max() / (5 * h**4 * M4 / 384):.3f} (ends)")
        assert e_herm.max() <= h ** 4 * M4 / 384
        assert e_spl[inner].max() <= 5 * h ** 4 * M4 / 384
        assert e_spl.max() <= 2 * 5 * h ** 4 * M4 / 384


def test_resample_converges_as_h4():
    errs = {}
    for h0 in (0.04, 0.02, 0.01):
        x, _ = jittered(h0, seed=7)
        g = np.linspace(x[0] + 0.1, x[-1] - 0.1, 3001)
        errs[h0] = (np.abs(resample_angle(x, f(x), g, df(x)) - f(g)).max(),
                    np.abs(resample_angle(x, f(x), g) - f(g)).max())
    for method in (0, 1):
        for coarse, fine in ((0.04, 0.02), (0.02, 0.01)):
            ratio = errs[coarse][method] / errs[fine][method]
            print(f"method {method}: h {coarse} → {fine}: error ratio {ratio:.1f}")
            assert 10.0 < ratio < 25.0


def test_coinciding_grid_returns_the_samples():
    """A grid on the samples (up to rounding of the angles) takes the samples: even a signal that
    no interpolant would reproduce (noise) comes back bit for bit."""
    rng = np.random.default_rng(3)
    phi = np.arange(2000) * (TWO_PI / 72)
    v = rng.standard_normal(phi.size)
    grid = np.arange(100, 1700, 2) * (TWO_PI / 72) * (1.0 + 1e-15)
    out = resample_angle(phi, v, grid)
    assert np.array_equal(out, v[100:1700:2])


def test_cut_keeps_a_corner_out_and_a_repeated_angle_splits_a_jump():
    """v = f(φ) + 3|φ − c| has a corner at c between samples: with the cut the error stays
    O(h⁴) (≤ h⁴/6·M₄ next to the cut, extrapolated Hermite), without it O(h). A jump of 0.5 at a
    sample angle written twice (left and right values) is reproduced on both sides."""
    x, h = jittered(0.02, seed=1)
    c = 0.5 * (x[300] + x[301])
    v = f(x) + 3.0 * np.abs(x - c)
    dv = df(x) + 3.0 * np.sign(x - c)
    g = np.linspace(x[250], x[350], 2001)
    exact = f(g) + 3.0 * np.abs(g - c)
    with_cut = np.abs(resample_angle(x, v, g, dv, cuts=[c]) - exact).max()
    without = np.abs(resample_angle(x, v, g, dv) - exact).max()
    spline_cut = np.abs(resample_angle(x, v, g, cuts=[c]) - exact).max()
    print(f"corner: Hermite with cut {with_cut:.2e}, without {without:.2e}; spline with cut "
          f"{spline_cut:.2e}; h⁴M₄/6 = {h**4 * M4 / 6:.2e}")
    assert with_cut <= h ** 4 * M4 / 6
    assert spline_cut <= h ** 4 * M4 / 6
    assert without > 1e3 * with_cut
    # the corner on a sample: the spline pieces on either side share it
    c = x[300]
    v = f(x) + 3.0 * np.abs(x - c)
    exact = f(g) + 3.0 * np.abs(g - c)
    on_sample = np.abs(resample_angle(x, v, g, cuts=[c]) - exact).max()
    print(f"corner on a sample: spline with cut {on_sample:.2e}")
    assert on_sample <= 2 * 5 * h ** 4 * M4 / 384

    k = 300
    xj = np.concatenate([x[:k + 1], x[k:]])  # x[k] twice
    vj = f(xj) + np.where(np.arange(xj.size) > k, 0.5, 0.0)
    dj = df(xj)
    g = np.linspace(x[200], x[400], 1001)
    exact = f(g) + np.where(g >= x[k], 0.5, 0.0)
    for d in (dj, None):
        err = np.abs(resample_angle(xj, vj, g, d) - exact).max()
        assert err <= 2 * 5 * h ** 4 * M4 / 384


def on_output_grid(cycles: int, extra: int = 36, per_rev: int = 72):
    """Sample angles j·Δφ as a crank-angle run writes them, past the end of ``cycles`` turns,
    and the breakpoint at that end as the stepper computes it (k·Φ + 0): for these counts the
    sample there is one ulp below it."""
    phi = np.arange(per_rev * cycles + extra + 1) * (TWO_PI / per_rev)
    end = cycles * TWO_PI
    k = per_rev * cycles
    assert phi[k] < end and phi[k + 1] > end and end - phi[k] <= 2 * np.spacing(end)
    return phi, k, end


@pytest.mark.parametrize("dv", [True, False], ids=["hermite", "spline"])
@pytest.mark.parametrize("where", [-1, 0, 1], ids=["ulp-below", "on", "ulp-above"])
def test_a_sample_within_rounding_of_a_breakpoint_is_on_it(where, dv):
    """v = f(φ) + B·max(φ − c, 0)²: its second derivative jumps at the breakpoint c, each side
    is smooth. The sample at c, an ulp off it to either side as the output grid rounds, counts
    as on c: the grid point c takes it (to rounding, from either side) and the points around
    it stay within the interpolant's bound of the side they are on (h⁴/384·M₄ Hermite,
    2·(5/384)·h⁴·M₄ spline, M₄ the smooth part's), never extrapolated across c."""
    phi, k, c = on_output_grid(13)
    phi[k] = {-1: np.nextafter(c, 0.0), 0: c, 1: np.nextafter(c, np.inf)}[where]
    B = 40.0

    def v(x):
        return f(x) + B * np.maximum(x - c, 0.0) ** 2

    def dvdx(x):
        return df(x) + 2.0 * B * np.maximum(x - c, 0.0)

    h = TWO_PI / 72
    g = np.linspace(c - 3 * h, c + 3 * h, 601)
    bound = h ** 4 * M4 / 384 if dv else 2 * 5 * h ** 4 * M4 / 384
    d = dvdx(phi) if dv else None
    for side in ("left", "right"):
        at_c = resample_angle(phi, v(phi), np.array([c]), d, cuts=[c], side=side)[0]
        assert abs(at_c - v(c)) <= 1e-12, (side, at_c - v(c))
        err = np.abs(resample_angle(phi, v(phi), g, d, cuts=[c], side=side) - v(g)).max()
        print(f"{side}: at c {at_c - v(c):.1e}, around it {err:.2e} (bound {bound:.2e})")
        assert err <= bound


@pytest.mark.parametrize("dv", [True, False], ids=["hermite", "spline"])
def test_a_jump_on_a_breakpoint_is_taken_from_the_side_asked(dv):
    """A jump J (value and slope) at c written as two samples an ulp either side of it (the left
    limit, then the right): ``side="left"`` at c gives the left function's value there and
    ``side="right"`` the right one's, each to rounding; the closing point of a whole-cycle grid
    ending on c (``to_angle_grid(closed=True)``) is the left limit, its points after c the
    right function, and none is taken across c."""
    phi, k, c = on_output_grid(13)
    phi = np.concatenate([phi[:k], [np.nextafter(c, 0.0), np.nextafter(c, np.inf)],
                          phi[k + 1:]])
    J, S = 0.5, 2.0
    right = phi > c
    v = f(phi) + np.where(right, J + S * (phi - c), 0.0)
    d = df(phi) + np.where(right, S, 0.0) if dv else None
    h = TWO_PI / 72
    bound = h ** 4 * M4 / 384 if dv else 2 * 5 * h ** 4 * M4 / 384
    left_c = resample_angle(phi, v, np.array([c]), d, cuts=[c], side="left")[0]
    right_c = resample_angle(phi, v, np.array([c]), d, cuts=[c], side="right")[0]
    assert abs(left_c - f(c)) <= 1e-12 and abs(right_c - (f(c) + J)) <= 1e-12
    for side in ("left", "right"):
        g = np.linspace(c - 3 * h, c + 3 * h, 601)
        g = g[g != c]
        exact = f(g) + np.where(g > c, J + S * (g - c), 0.0)
        err = np.abs(resample_angle(phi, v, g, d, cuts=[c], side=side) - exact).max()
        assert err <= bound, (side, err)
    names = {"phi": phi, "v": v}
    derivs = {"v": d} if dv else {}
    grid, cols = to_angle_grid(names, ["v"], 720, TWO_PI, cycles=1, cuts=[c], closed=True,
                               derivatives=derivs)
    assert grid[-1] == c and abs(cols["v"][-1] - f(c)) <= 1e-12


def test_closing_sample_on_a_breakpoint_adds_no_false_orders():
    """ω = ω₀(1 + a cos 2φ), even orders only, sampled every 5° as a crank-angle run writes it
    (j·Δφ), with breakpoints every 30° as the stepper computes them (k·2π + m·π/6) and the
    data going on past the last whole cycle, whose end sample is an ulp below its breakpoint:
    with the ramp detrend the odd orders stay at rounding (≤ 1e-10 of order 2), the closing
    point being the cycle's own left limit, not an extrapolation from the next cycle's side."""
    phi, _, end = on_output_grid(13)
    omega, eps, t = prescribed_motion(2.0, phi)
    cuts = (np.arange(14)[:, None] * TWO_PI + np.arange(12)[None, :] * (TWO_PI / 12)).ravel()
    assert end in cuts
    traj = {"t": t, "phi": phi, "omega": omega, "epsilon": eps}
    _, spec = cycle_spectra(traj, "omega", 720, TWO_PI, cuts=cuts, detrend="ramp")
    amp = spec.amplitude[-1]
    odd = np.arange(amp.size) % 2 == 1
    print(f"order 2 {amp[2]:.6g} rad/s, odd orders ≤ {amp[odd].max():.2e} rad/s, last drift "
          f"{spec.drift[-1]:.2e}")
    h = TWO_PI / 72  # the grid's 10 points per sample interval: Hermite's h⁴/384·|ω⁽⁴⁾|
    assert abs(amp[2] - W0 * A) <= h ** 4 / 384 * 16 * W0 * A
    assert amp[odd].max() <= 1e-10 * amp[2]
    assert abs(spec.drift[-1]) <= 1e-12 * W0


# ------------------------------------------------------------------------------------------------
# Spectra


def test_order_spectrum_recovers_orders_amplitudes_phases():
    """Three 4-stroke cycles (N = 720, half orders), each its own amplitudes and phases, plus the
    Nyquist line (order 180: A cos θ); and a 2-stroke cycle. All to 1e-12."""
    n = 720
    lines = [(0.5, 2.0, 0.4), (1.0, 1.0, -2.5), (1.5, 0.3, 1.1), (3.0, 0.02, 3.0),
             (7.5, 1e-3, -0.7),
             (60.0, 5e-4, 0.2)]
    cycles = []
    for c in range(3):
        x = np.arange(n) * (FOUR_PI / n)  # local angle from the cycle start
        v = 10.0 + c + sum((c + 1) * a * np.cos(nu * x + th) for nu, a, th in lines)
        v += 0.25 * np.cos(180.0 * x + 0.6)
        cycles.append(v)
    sp = order_spectrum(np.concatenate(cycles), n, FOUR_PI)
    assert sp.orders.size == n // 2 + 1
    assert np.allclose(sp.orders, 0.5 * np.arange(n // 2 + 1), rtol=0, atol=1e-13)
    for c in range(3):
        expect = np.zeros(n // 2 + 1, complex)
        expect[0] = 10.0 + c
        for nu, a, th in lines:
            expect[int(round(2 * nu))] = (c + 1) * a * np.exp(1j * th)
        expect[-1] = 0.25 * math.cos(0.6)
        assert np.abs(sp.coef[c] - expect).max() <= 1e-12
        assert sp.amplitude[c, 3] == pytest.approx(0.3 * (c + 1), abs=1e-12)
        assert sp.phase[c, 3] == pytest.approx(1.1, abs=1e-12)
        assert sp.mean[c] == pytest.approx(10.0 + c, abs=1e-12)
    np.testing.assert_allclose(sp.at(1.5), 0.3 * np.arange(1, 4) * np.exp(1.1j), atol=1e-12)
    # a 2-stroke cycle as (n_cycles, N)
    x = np.arange(360) * (TWO_PI / 360)
    sp2 = order_spectrum(np.stack([3 * np.cos(2 * x - 1), np.sin(5 * x)]), 360, TWO_PI)
    assert sp2.orders[1] == pytest.approx(1.0)
    assert sp2.coef[0, 2] == pytest.approx(3 * np.exp(-1j), abs=1e-12)
    assert sp2.coef[1, 5] == pytest.approx(np.exp(-0.5j * math.pi), abs=1e-12)


def test_drift_and_hann():
    """A ramp of total rise D over each cycle: drift = D; DFT amplitude at harmonic k exactly
    D/(N sin(πk/N)) (→ D/(πk)). Hann on lines two or more harmonics apart: exact."""
    n, D = 144, 3.0
    ramp = D * np.arange(3 * n) / n
    sp = order_spectrum(ramp, n, FOUR_PI)
    np.testing.assert_allclose(sp.drift[:2], D, rtol=1e-13)
    assert math.isnan(sp.drift[-1])
    k = np.arange(1, n // 2)
    np.testing.assert_allclose(sp.amplitude[0, 1:n // 2], D / (n * np.sin(np.pi * k / n)),
                               rtol=1e-10)
    x = np.arange(n) * (FOUR_PI / n)
    v = 1.5 * np.cos(1.0 * x + 0.2) + 0.5 * np.cos(3.0 * x - 1.0)  # harmonics 2 and 6 of 4π
    h = order_spectrum(v, n, FOUR_PI, window="hann")
    assert h.coef[0, 2] == pytest.approx(1.5 * np.exp(0.2j), abs=1e-12)
    assert h.coef[0, 6] == pytest.approx(0.5 * np.exp(-1j), abs=1e-12)
    with pytest.raises(ValueError):
        order_spectrum(np.zeros(100), 72, FOUR_PI)
    with pytest.raises(ValueError):
        order_spectrum(np.zeros(144), 72, FOUR_PI, window="hamming")


# ------------------------------------------------------------------------------------------------
# Piston kinematics at constant speed


def grid(n, cycle=TWO_PI):
    return np.arange(n) * (cycle / n)


def test_constant_speed_central_only_first_and_even_orders():
    """e = 0, ω = 300 rad/s: odd orders ≥ 3 of W below 1e-12 of the first; the first is exactly
    rω²; W(0) = rω²(1 + λ), W(π) = −rω²(1 − λ) (Semenov (25), exact to all orders); the inertia
    force at TDC is −m_j rω²(1 + λ) (Gots §2.3: pulls away from the crank)."""
    n, w = 720, 300.0
    phi = grid(n)
    W = piston_acceleration(phi, w, 0.0, R, L)
    sp = order_spectrum(W, n, TWO_PI)
    a = sp.amplitude[0]
    odd = np.arange(3, n // 2 + 1, 2)
    print(f"central: max odd≥3/first = {a[odd].max() / a[1]:.1e}, "
          f"orders 2, 4, 6: {a[2] / a[1]:.6f} {a[4] / a[1]:.3e} {a[6] / a[1]:.3e}")
    assert a[odd].max() <= 1e-12 * a[1]
    assert a[1] == pytest.approx(R * w * w, rel=1e-12)
    assert a[2] > 0.3 * a[1] and a[4] > 1e-3 * a[1] and a[6] > 1e-5 * a[1]
    assert W[0] == pytest.approx(R * w * w * (1 + LAM), rel=1e-13)
    assert W[n // 2] == pytest.approx(-R * w * w * (1 - LAM), rel=1e-13)
    P = piston_inertia_force(np.array([0.0]), w, 0.0, R, L, 0.0, m_j=1.52)
    assert P[0] == pytest.approx(-1.52 * R * w * w * (1 + LAM), rel=1e-13)


def test_rod_angle_only_odd_orders():
    """β(φ) = arcsin(λ sin φ): even orders (and the mean) below 1e-12 of the first; so is ε_ш at
    constant ω, which equals Gots' closed form −ω²λ(1 − λ²) sin φ/(1 − λ² sin²φ)^{3/2}."""
    n, w = 720, 300.0
    phi = grid(n)
    beta = slider_arrays(phi, R, L, 0.0)[3]
    eps_rod = rod_angular_acceleration(phi, w, 0.0, R, L)
    closed = -w * w * LAM * (1 - LAM**2) * np.sin(phi) / (1 - LAM**2 * np.sin(phi) ** 2) ** 1.5
    assert np.abs(eps_rod - closed).max() <= 1e-12 * np.abs(closed).max()
    for v in (beta, eps_rod):
        a = order_spectrum(v, n, TWO_PI).amplitude[0]
        assert a[0::2].max() <= 1e-12 * a[1]
        assert a[3] > 1e-3 * a[1]


def test_semenov_printed_fft_numbers():
    """Semenov §2, series (9) and (31)–(35), to the digits of an independent FFT of the exact
    geometry (``tests/references/semenov.py``): λ = 0.304: W amplitudes in units of rω² 1,
    0.3113, 0.0075, 0.0002 (orders 1, 2, 4, 6); β = 0.30764 sin φ − 0.001235 sin 3φ + …
    r = 95, l = 313 mm: x_B = r cos φ + l cos β has the mean 305.662 mm and the coefficients 95,
    7.3821, −0.0446, 0.0005 mm (orders 1, 2, 4, 6); s = (l + r) − x_B; no odd order ≥ 3."""
    check_all(semenov.master_series())


def test_offset_adds_odd_orders_at_constant_speed():
    """e = k·r: odd orders at constant ω. The 3rd order of s″ against the quadrature of the exact
    travel s = √((l + r)² − e²) − r cos φ − √(l² − (r sin φ − e)²) (Gots (12)): coefficient of
    order m of s″ is −m² times that of s. The ratio 3rd/1st is the leading term (9/8)kλ³ to
    within 15 % (the rest is O(λ², k²), about a tenth here)."""
    n = 720
    phi = grid(n)
    for k in (0.1, 0.2):
        e = k * R

        def s(x, e=e):
            return math.sqrt((L + R) ** 2 - e * e) - R * math.cos(x) - math.sqrt(
                L * L - (R * math.sin(x) - e) ** 2)

        def coef(m):
            c = quad(s, 0, TWO_PI, weight="cos", wvar=m, epsabs=1e-13, epsrel=1e-12)[0]
            d = quad(s, 0, TWO_PI, weight="sin", wvar=m, epsabs=1e-13, epsrel=1e-12)[0]
            return -m * m * (c - 1j * d) / math.pi  # of s″, as A e^{iθ}

        sp = order_spectrum(piston_acceleration(phi, 1.0, 0.0, R, L, e), n, TWO_PI)
        ratio = sp.amplitude[0, 3] / sp.amplitude[0, 1]
        fifth = sp.amplitude[0, 5] / sp.amplitude[0, 1]
        print(f"k = {k}: 3rd/1st = {ratio:.4e}, 5th/1st = {fifth:.3e}, "
              f"series (9/8)kλ³ = {9 / 8 * k * LAM**3:.4e}")
        for m in (1, 3, 5):
            assert abs(sp.coef[0, m] - coef(m)) <= 1e-10 * R
        assert ratio == pytest.approx(9 / 8 * k * LAM ** 3, rel=0.15)


# ------------------------------------------------------------------------------------------------
# Prescribed speed ω(φ) = ω₀(1 + a cos kφ)

W0, A = 300.0, 0.02


def exact_ds_dds(phi):
    """Gots §2.2–2.3 exact: s′ = r sin(φ + β)/cos β, s″ = r[cos(φ + β)/cos β + λ cos²φ/cos³β]."""
    b = np.arcsin(LAM * np.sin(phi))
    cb = np.cos(b)
    return (R * np.sin(phi + b) / cb,
            R * (np.cos(phi + b) / cb + LAM * np.cos(phi) ** 2 / cb ** 3))


def two_sided(cos_coef=None, sin_coef=None, size=None):
    """Two-sided exponential coefficients C_{−M…M} of Σ c_j cos jθ + Σ d_j sin jθ."""
    m = size - 1
    out = np.zeros(2 * m + 1, complex)
    if cos_coef is not None:
        for j, c in enumerate(cos_coef):
            if j == 0:
                out[m] += c
            else:
                out[m + j] += c / 2
                out[m - j] += c / 2
    if sin_coef is not None:
        for j, d in enumerate(sin_coef):
            if j:
                out[m + j] += d / 2j
                out[m - j] -= d / 2j
    return out


def predicted_W(k, n):
    """coef of W over the 4π cycle (harmonic j ↔ order j/2), from the closed-form series of
    ω² = ω₀²[(1 + a²/2) + 2a cos kφ + (a²/2) cos 2kφ] and
    ε = −ω₀²ak[sin kφ + (a/2) sin 2kφ], convolved with the Fourier series of s″ (cos) and s′ (sin)
    (numpy FFT of Gots' closed forms on n points per 4π)."""
    phi = grid(n, FOUR_PI)
    ds, dds = exact_ds_dds(phi)
    S2 = np.fft.rfft(dds) / n
    S1 = np.fft.rfft(ds) / n
    size = n // 2 + 1
    s2 = two_sided(cos_coef=np.r_[S2[0].real, 2 * S2[1:].real], size=size)
    s1 = two_sided(sin_coef=np.r_[0.0, -2 * S1[1:].imag], size=size)
    j = int(round(2 * k))  # kφ = (2k)·(φ/2)
    w2 = np.zeros(2 * j + 1)
    w2[0], w2[j], w2[2 * j] = W0**2 * (1 + A * A / 2), 2 * A * W0**2, A * A / 2 * W0**2
    ep = np.zeros(2 * j + 1)
    ep[j], ep[2 * j] = -W0**2 * A * k, -W0**2 * A * k * A / 2
    conv = (np.convolve(two_sided(cos_coef=w2, size=2 * j + 1), s2)
            + np.convolve(two_sided(sin_coef=ep, size=2 * j + 1), s1))
    mid = conv.size // 2
    out = 2 * conv[mid:mid + size]
    out[0] /= 2
    return out


def prescribed_motion(k, phi):
    """ω, ε and the exact time t(φ) = (kφ − 2 atan2(b sin kφ, 1 + b cos kφ))/(kω₀√(1 − a²)),
    b = (1 − √(1 − a²))/a (the series of 1/(1 + a cos x), integrated term by term)."""
    x = k * phi
    omega = W0 * (1 + A * np.cos(x))
    eps = -W0**2 * A * k * np.sin(x) * (1 + A * np.cos(x))
    b = (1 - math.sqrt(1 - A * A)) / A
    t = (x - 2 * np.arctan2(b * np.sin(x), 1 + b * np.cos(x))) / (k * W0 * math.sqrt(1 - A * A))
    return omega, eps, t


@pytest.mark.parametrize("k", [3.0, 2.0, 1.5])
def test_prescribed_speed_spectrum_is_the_convolution(k):
    """The spectrum of W (piston_acceleration) equals the convolution of the closed-form series to
    1e-9 of the first order; the odd orders it predicts are there: k = 3 adds
    5 = k + 2, 7 = k + 4 (and 3 = |k − 6|); k = 2 adds 3 = k + 1; k = 1.5 the half orders."""
    n = 1440
    phi = grid(n, FOUR_PI)
    omega, eps, _ = prescribed_motion(k, phi)
    W = piston_acceleration(phi, omega, eps, R, L)
    sp = order_spectrum(W, n, FOUR_PI)
    pred = predicted_W(k, n)
    first = abs(pred[2])
    err = np.abs(sp.coef[0] - pred).max() / first
    rel = sp.amplitude[0] / sp.amplitude[0, 2]
    show = {o: f"{rel[int(2 * o)]:.2e}" for o in (0.5, 1.5, 2.5, 3, 3.5, 5, 7, 9)}
    print(f"k = {k}: |coef − convolution|/first = {err:.1e}; relative amplitudes {show}")
    assert err <= 1e-9
    if k == 3.0:
        assert rel[10] > 1e-3 and rel[14] > 1e-4 and rel[6] > 1e-7  # orders 5, 7, 3
    if k == 2.0:
        assert rel[6] > 1e-3  # order 3 = k + 1
    if k == 1.5:
        assert rel[1] > 1e-3 and rel[5] > 1e-3 and rel[7] > 1e-3  # orders 0.5, 2.5, 3.5
    # constant ω₀: odd orders ≥ 3 and half orders vanish
    c = order_spectrum(piston_acceleration(phi, W0, 0.0, R, L), n, FOUR_PI).amplitude[0]
    absent = [j for j in range(n // 2 + 1) if j % 2 == 1 or (j % 4 == 2 and j > 2)]
    assert c[absent].max() <= 1e-12 * c[2]


@pytest.mark.parametrize("uniform", [True, False])
def test_odd_harmonic_report_on_prescribed_speed(uniform):
    """The report on ω = ω₀(1 + a cos 3φ) over 2π cycles, sampled on the grid (exact path) or on a
    random ±40 % mesh of 0.25° mean spacing (Hermite for ω and t, spline for ε):
    ω̄ = ω₀√(1 − a²) (time mean), δ = 2a/√(1 − a²) (ω₀(1 ± a) are on the grid), the spectrum
    at ω̄ = ω̄² × series of s″ (odd orders ≥ 3 below 1e-12 of the first), the run's spectrum the
    convolution of :func:`predicted_W` (with 4π cycles halved)."""
    k, n = 3.0, 720
    if uniform:
        phi = np.arange(5 * n + 1) * (TWO_PI / n)
    else:
        phi, _ = jittered(math.radians(0.25), span=5 * TWO_PI + 0.02, seed=11)
        phi -= phi[0] + 0.01
    omega, eps, t = prescribed_motion(k, phi)
    rep = odd_harmonic_report({"t": t, "phi": phi, "omega": omega, "epsilon": eps}, R, L,
                              cycle=TWO_PI, samples_per_cycle=n)
    n_cyc = 5 if uniform else 4
    assert rep.cycle_start.size == n_cyc
    tol = 1e-12 if uniform else 1e-8
    wbar = W0 * math.sqrt(1 - A * A)
    np.testing.assert_allclose(rep.omega_mean, wbar, rtol=tol)
    np.testing.assert_allclose(rep.delta, 2 * A / math.sqrt(1 - A * A), rtol=1e-12 if uniform
                               else 1e-6)  # off-grid extremes: O(h²) short of ω₀(1 ± a)
    # on 2π cycles harmonic m is order m: take the even harmonics of the 4π prediction
    pred = predicted_W(k, 2 * n)[::2]
    first = abs(pred[1])
    err = np.abs(rep.coef - pred).max() / first
    _, dds = exact_ds_dds(grid(n))
    const = np.fft.rfft(dds) / n * 2 * wbar**2
    err_c = np.abs(rep.coef_constant - const[None, :]).max() / first
    print(f"uniform={uniform}: run spectrum error {err:.1e}, constant-ω̄ error {err_c:.1e} of the "
          f"first order; odd 3, 5, 7 relative: {rep.relative[-1, [3, 5, 7]]}; "
          f"δ = {rep.delta[-1]:.10f}")
    assert err <= (1e-9 if uniform else 1e-7)
    assert err_c <= tol
    odd = rep.odd
    assert rep.relative_constant[:, odd].max() <= 1e-12
    assert rep.relative[:, 5].min() > 1e-3 and rep.relative[:, 7].min() > 1e-4
    np.testing.assert_allclose(rep.relative_added[:, odd], rep.relative[:, odd], atol=1e-12)
    summary = rep.summary()
    assert summary["orders_W_odd5_rel"][0] == pytest.approx(rep.relative[-1, 5])
    assert summary["orders_delta"] == (rep.delta[-1], "1")
    assert not rep.fractional.any()
    assert [row["kind"] for row in rep.table(max_order=4)] == ["kinematic", "kinematic",
                                                               "odd>=3", "kinematic"]


def test_to_angle_grid_whole_cycles_and_hermite_columns():
    """Grid of whole 4π cycles from φ0; t and ω from non-uniform samples by Hermite (derivatives
    1/ω and ε/ω from the trajectory) within h⁴/384 of their closed-form 4th derivatives' bound."""
    k = 1.5
    phi, h = jittered(math.radians(0.5), span=3 * FOUR_PI + 1.0, seed=5)
    omega, eps, t = prescribed_motion(k, phi)
    traj = {"t": t, "phi": phi, "omega": omega, "epsilon": eps}
    phi0 = 0.3
    g, cols = to_angle_grid(traj, ["t", "omega", "phi"], 360, FOUR_PI, phi0=phi0)
    assert g.size % 360 == 0 and g[0] >= phi[0] and g[-1] + FOUR_PI / 360 <= phi[-1] + 1e-12
    assert (g[0] - phi0) / FOUR_PI == pytest.approx(round((g[0] - phi0) / FOUR_PI), abs=1e-12)
    w_g, _, t_g = prescribed_motion(k, g)
    m4_w = W0 * A * k**4  # |d⁴ω/dφ⁴| ≤ ω₀ a k⁴
    assert np.abs(cols["omega"] - w_g).max() <= h**4 / 384 * m4_w
    # d⁴t/dφ⁴ = (1/ω)''': bounded numerically on a fine grid by differences of the closed form
    fine = np.linspace(0, FOUR_PI, 20001)
    inv = 1 / prescribed_motion(k, fine)[0]
    m4_t = np.abs(np.diff(inv, 3)).max() / (fine[1] - fine[0]) ** 3 * 1.01
    assert np.abs(cols["t"] - t_g).max() <= h**4 / 384 * m4_t
    assert np.array_equal(cols["phi"], g)
    g1, c1 = to_angle_grid(traj, ["omega"], 360, FOUR_PI, phi0=phi0, cycles=1)
    assert np.array_equal(g1, g[-360:]) and np.array_equal(c1["omega"], cols["omega"][-360:])
