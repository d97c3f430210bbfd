"""ISO 8528-5 transient-response measures (transient.analysis.transient_response) against closed
forms.

Every synthetic trace is a smooth speed ω_s(s) with a closed-form angle φ_s(s), carrying a cyclic
ripple that is exactly periodic in crank angle. It is built as a time warp: the shaft reaches the
angle φ_s(s) at the time t = s + p(φ_s(s)), p(φ) = ε sin(2φ)/(2 ω_ref) (two pulses per revolution,
a four-cylinder four-stroke; the period π divides both cycle angles). Then

    ω = dφ/dt = ω_s / (1 + ε (ω_s/ω_ref) cos 2φ),

a ripple of relative amplitude ≈ ε, and since p(φ − cycle) = p(φ), the one-cycle time is that of
the smooth motion: t(φ) − t(φ − cycle) = s − s'. The cycle-mean speed of the trace is therefore
*exactly* the cycle mean of ω_s over [s', s], read at a mid time shifted by p(φ) (|p| ≤
ε/(2 ω_ref), the "jitter" allowed in the time tolerances). No ODE is integrated: φ, t and ω are
closed forms on a grid in s whose spacing is not commensurate with the cycle.

The cycle mean of a smooth ω over a window of length T centred on t is ω(t) + T²ω''(t)/24 + O(T⁴):
the averaging lag of each measure below is derived from that and compared with the code; the
"independent" cycle mean of the closed form is also solved for directly (brentq on φ_s).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar
from scipy.special import lambertw

from transient.analysis.transient_response import (
    LoadChangeMetrics,
    SpinUpMetrics,
    cycle_mean_speed,
    load_change_metrics,
    metrics_table,
    spin_up_metrics,
    to_table,
)

RATED = 2.0 * math.pi * 1500.0 / 60.0  # rad/s, a 50 Hz four-pole set
EPS = 0.03                             # relative cyclic ripple
DS = 1.7e-4                            # s, grid step in the smooth time s (not a cycle divisor)
JITTER = EPS / (2.0 * RATED)           # s, bound of |p(φ)| with ω_ref = RATED
CYCLES = [4.0 * math.pi, 2.0 * math.pi]


def warp(s, phi_s, omega_s, eps=EPS, w_ref=RATED):
    """(t, φ, ω) of the smooth motion φ_s(s) carrying the ripple p(φ) = ε sin(2φ)/(2 w_ref)."""
    phi, w = phi_s(s), omega_s(s)
    return (s + eps * np.sin(2.0 * phi) / (2.0 * w_ref), phi,
            w / (1.0 + eps * w / w_ref * np.cos(2.0 * phi)))


def smooth_window(phi_s, m, cycle, h_max=1.0):
    """The one-cycle window of the smooth motion centred on time m: its mean speed and the mid
    time of the rippled trace's window, m + p(φ at its end)."""
    h = brentq(lambda h: phi_s(m + h) - phi_s(m - h) - cycle, 1e-12, h_max, xtol=1e-15)
    return cycle / (2.0 * h), m + EPS * math.sin(2.0 * phi_s(m + h)) / (2.0 * RATED)


def smooth_cycle_mean(phi_s, m, cycle):
    """Cycle-mean speed of the smooth motion over the one-cycle window centred on time m."""
    return smooth_window(phi_s, m, cycle)[0]


def window_gain(T, tau):
    """Mean of e^(−t/τ) over a window of length T centred on t, divided by e^(−t/τ)."""
    x = T / (2.0 * tau)
    return math.sinh(x) / x


class ExpSegments:
    """Closed-form ω_s, φ_s: on each [knot_k, knot_k+1) the speed relaxes exponentially (time
    constant τ) from its value at knot_k to target_k; continuous, φ_s(0) = 0."""

    def __init__(self, knots, targets, tau, w0):
        self.knots, self.targets, self.tau = list(knots), list(targets), tau
        self.w_start, self.phi_start = [], []
        w, p = w0, 0.0
        for k, tgt in enumerate(self.targets):
            self.w_start.append(w)
            self.phi_start.append(p)
            if k + 1 < len(self.knots):
                d = self.knots[k + 1] - self.knots[k]
                p += tgt * d + (w - tgt) * tau * (1.0 - math.exp(-d / tau))
                w = tgt + (w - tgt) * math.exp(-d / tau)

    def _eval(self, s, want_phi):
        s = np.asarray(s, dtype=np.float64)
        out = np.zeros_like(s)
        k = np.clip(np.searchsorted(self.knots, s, side="right") - 1, 0, None)
        for j in np.unique(k):
            sel = k == j
            d = s[sel] - self.knots[j]
            tgt, dw = self.targets[j], self.w_start[j] - self.targets[j]
            e = np.exp(-d / self.tau)
            out[sel] = (self.phi_start[j] + tgt * d + dw * self.tau * (1.0 - e) if want_phi
                        else tgt + dw * e)
        return out if out.ndim else float(out)

    def phi(self, s):
        return self._eval(s, True)

    def omega(self, s):
        return self._eval(s, False)


# --- cycle-mean speed ---------------------------------------------------------------------------

@pytest.mark.parametrize("cycle", CYCLES)
def test_cycle_mean_of_a_linear_ramp_is_the_mid_time_value(cycle):
    # The time average of a + b s over any window is its value at the mid time, exactly; the
    # ripple must disappear and the mid time carries the jitter p(φ_end), known in closed form.
    a, b = 0.6 * RATED, 0.2 * RATED
    s = np.arange(0.0, 2.0, DS)
    t, phi, omega = warp(s, lambda x: a * x + 0.5 * b * x * x, lambda x: a + b * x)
    tm, wm = cycle_mean_speed(t, phi, cycle, omega)
    ends = phi - phi[0] >= cycle
    assert tm.size == wm.size == int(ends.sum())
    m = tm - EPS * np.sin(2.0 * phi[ends]) / (2.0 * RATED)
    err = np.max(np.abs(wm - (a + b * m))) / RATED
    assert err < 1e-9, err
    # PCHIP without ω: third order, still far below any band.
    _, wm2 = cycle_mean_speed(t, phi, cycle)
    err2 = np.max(np.abs(wm2 - (a + b * m))) / RATED
    assert err2 < 1e-6, err2
    # The raw speed swings by ≈ 2ε around the ramp; the cycle mean removed it.
    assert np.ptp(omega / (a + b * s)) > 1.5 * EPS


def test_cycle_mean_after_a_standstill():
    # The shaft rests for 0.3 s (φ constant), then turns at constant speed: the first window
    # starts when it leaves φ0, every cycle mean is the speed itself.
    w = 0.5 * RATED
    rest = np.arange(0.0, 0.3, DS)
    s = np.arange(0.0, 1.0, DS)
    t1, phi1, om1 = warp(s, lambda x: w * x, lambda x: np.full_like(x, w))
    t = np.r_[rest, 0.3 + DS + t1]
    phi, omega = np.r_[np.zeros(rest.size), phi1], np.r_[np.zeros(rest.size), om1]
    _, wm = cycle_mean_speed(t, phi, 4.0 * math.pi, omega)
    np.testing.assert_allclose(wm, w, rtol=1e-10)


# --- load change: a dip with closed-form minimum and band entry --------------------------------

TAU, D, TC = 0.5, 0.1 * RATED, 1.0
T_END = TC + 30.0 * TAU  # f(30) ≈ 1e-11: the steady speed is ω_f to far below the band


def dip_phi(x):
    """φ_s of ω_s = ω_f − D·u·e^(1−u), u = (s − TC)/τ after TC, ω_f = RATED before."""
    x = np.asarray(x, dtype=np.float64)
    u = np.clip((x - TC) / TAU, 0.0, None)
    return RATED * x - D * TAU * math.e * (1.0 - (1.0 + u) * np.exp(-u))


def dip_omega(x):
    u = np.clip((np.asarray(x, dtype=np.float64) - TC) / TAU, 0.0, None)
    return RATED - D * u * np.exp(1.0 - u)


@pytest.fixture(scope="module", params=CYCLES, ids=["4-stroke", "2-stroke"])
def dip(request):
    cycle = request.param
    t, phi, omega = warp(np.arange(0.0, T_END, DS), dip_phi, dip_omega)
    m = load_change_metrics(t, phi, omega, TC, cycle, band=0.01, rated_speed=RATED,
                            load_step="increase")
    return cycle, t, phi, omega, m


def test_dip_against_the_cycle_mean_of_the_closed_form(dip):
    cycle, *_, m = dip
    # Independent cycle mean of ω_s: its minimum and the time it re-enters ω_f − 1 %.
    res = minimize_scalar(lambda x: smooth_cycle_mean(dip_phi, x, cycle), method="bounded",
                          bounds=(TC + 0.5 * TAU, TC + 2.0 * TAU), options={"xatol": 1e-10})
    entry = brentq(lambda x: smooth_cycle_mean(dip_phi, x, cycle) - 0.99 * RATED,
                   res.x, TC + 10.0 * TAU, xtol=1e-12)
    assert m.omega_extreme == pytest.approx(res.fun, rel=1e-8)
    assert abs(m.t_dev_max - (smooth_window(dip_phi, res.x, cycle)[1] - TC)) < 2e-6
    assert abs(m.recovery_time - (smooth_window(dip_phi, entry, cycle)[1] - TC)) < 1e-7
    assert m.omega_before == pytest.approx(RATED, rel=1e-10)
    assert m.omega_after == pytest.approx(RATED, rel=1e-9)  # D·f(u ≥ 22.6) ≤ 1e-9 ω_r
    assert m.recovered and m.settled and m.note == ""
    assert abs(m.droop_pct) < 1e-7  # % ; ω_after is the dip's tail, ≤ 1e-9 ω_r


def test_dip_against_the_closed_form_with_its_averaging_lag(dip):
    cycle, *_, m = dip
    # ω_s = ω_f − D f(u), f = u e^(1−u): minimum ω_f − D at u = 1, f'' = (u−2)e^(1−u),
    # f''' = (3−u)e^(1−u). The cycle mean lifts the minimum by T²ω''/24 = D T²/(24τ²) and
    # delays it by T²/(12τ) (where ω̄' = ω' + T²ω'''/24 = 0). What is left: the O(T⁴) term
    # and T varying along the dip, a few ‰ of the lift.
    T = cycle / (RATED - D)
    lift = 100 * D * T**2 / (24 * TAU**2) / RATED
    assert m.dev_max_pct == pytest.approx(-100.0 * D / RATED + lift, abs=0.01 * lift)
    assert m.dev_max_pct == pytest.approx(m.dev_max_rated_pct, abs=1e-8)
    assert abs(m.t_dev_max - (TAU + T**2 / (12 * TAU))) < JITTER + 0.1 * T**2 / (12 * TAU)
    # Permanent entry into ω_f ± b, b = 1 % of rated: u e^(−u) = b/(eD) on the far branch,
    # u = −W₋₁(−b/(eD)); the lag there is −T²ω''/(24ω') = −(T²/(24τ))(u−2)/(1−u).
    b = 0.01 * RATED
    u = float(-lambertw(-b / (math.e * D), -1).real)
    T = cycle / (RATED - b)
    lag = -(T**2 / (24 * TAU)) * (u - 2.0) / (1.0 - u)
    assert abs(m.recovery_time - (TAU * u + lag)) < JITTER + 0.1 * abs(lag)


def test_without_the_cycle_mean_the_dip_is_wrong_by_about_epsilon(dip):
    _, t, _, omega, m = dip
    # The raw minimum is where the ripple's trough meets the dip:
    # ω_min/(1 + ε ω_min/ω_ref), ω_min = ω_f − D.
    w_min = RATED - D
    raw = float(omega.min())
    assert raw == pytest.approx(w_min / (1.0 + EPS * w_min / RATED), rel=1e-4)
    raw_error = (w_min - raw) / RATED            # ≈ ε (ω_min/ω_ref)²
    averaged_error = abs(m.omega_extreme - w_min) / RATED
    assert 0.5 * EPS < raw_error < 1.5 * EPS
    assert averaged_error < 0.01 * EPS
    # Read from the raw trace the band would also be left again every cycle late in the run.
    late = t > T_END - 1.0
    assert np.max(np.abs(omega[late] - RATED)) > 0.01 * RATED


# --- load change: droop plateaus, a rejection, hunting ------------------------------------------

def plateaus(w0, w1, tau=0.2, t_end=6.0):
    seg = ExpSegments([0.0, TC], [w0, w1], tau, w0)
    return seg, warp(np.arange(0.0, t_end, DS), seg.phi, seg.omega)


@pytest.mark.parametrize("cycle", CYCLES)
def test_droop_from_two_plateaus(cycle):
    # No load at 1.04 ω_r, rated load at ω_r: ISO δf_st = (f_i,r − f_r)/f_r = 4 %.
    w0, tau = 1.04 * RATED, 0.2
    _, (t, phi, omega) = plateaus(w0, RATED, tau)
    m = load_change_metrics(t, phi, omega, TC, cycle, band=0.01, rated_speed=RATED)
    assert m.droop_pct == pytest.approx(4.0, abs=1e-7)
    assert m.omega_before == pytest.approx(w0, rel=1e-10)
    # Monotone fall: the largest deviation is the new plateau, a dip (negative).
    assert m.dev_max_pct == pytest.approx(-4.0, abs=1e-6)
    # The cycle mean of ω_r + Δe^(−u) is ω_r + Δe^(−u)·G, G = sinh(x)/x, x = T/(2τ), exactly;
    # at the band edge T = cycle/(1.01 ω_r). It enters ω_r ± 1 % when 4 e^(−u) G = 1; the
    # averaging lag τ ln G ≈ T²/(24τ).
    T = cycle / (1.01 * RATED)
    lag = tau * math.log(window_gain(T, tau))
    assert lag == pytest.approx(T**2 / (24 * tau), rel=0.01)
    assert abs(m.recovery_time - (tau * math.log(4.0) + lag)) < JITTER + 1e-6
    assert m.recovered and m.settled


def test_load_rejection_overshoot_is_positive_and_droop_negative():
    _, (t, phi, omega) = plateaus(RATED, 1.04 * RATED)
    m = load_change_metrics(t, phi, omega, TC, 4.0 * math.pi, rated_speed=RATED)
    assert m.dev_max_pct == pytest.approx(4.0, abs=1e-6)
    assert m.droop_pct == pytest.approx(-4.0, abs=1e-7)


def test_default_rated_speed_is_the_speed_before():
    _, (t, phi, omega) = plateaus(1.04 * RATED, RATED)
    m = load_change_metrics(t, phi, omega, TC, 4.0 * math.pi)
    assert m.omega_rated == pytest.approx(1.04 * RATED, rel=1e-10)
    assert m.droop_pct == pytest.approx(100.0 * 0.04 / 1.04, abs=1e-7)


def test_a_step_inside_the_band_recovers_at_once():
    # 0.5 % droop with a ±1 % band: the cycle-mean speed never leaves ω_after ± 1 %.
    _, (t, phi, omega) = plateaus(RATED, 0.995 * RATED)
    m = load_change_metrics(t, phi, omega, TC, 4.0 * math.pi, rated_speed=RATED)
    assert m.recovered and m.recovery_time == 0.0
    assert m.droop_pct == pytest.approx(0.5, abs=1e-7)


def test_hunting_never_recovers():
    # Sustained governor hunting of ±3 % (period 0.5 s ≫ one cycle) after the change, the
    # segment ending on a crest: never inside ±1 %, never steady.
    A, P = 0.03 * RATED, 0.5
    t_end = TC + 8.25 * P

    def phi_s(x):
        x = np.asarray(x, dtype=np.float64)
        d = np.clip(x - TC, 0.0, None)
        return RATED * x + A * P / (2 * math.pi) * (1.0 - np.cos(2 * math.pi * d / P))

    def omega_s(x):
        d = np.clip(np.asarray(x, dtype=np.float64) - TC, 0.0, None)
        return RATED + A * np.sin(2 * math.pi * d / P)

    t, phi, omega = warp(np.arange(0.0, t_end, DS), phi_s, omega_s)
    m = load_change_metrics(t, phi, omega, TC, 4.0 * math.pi, rated_speed=RATED)
    assert m.recovered is False and math.isnan(m.recovery_time)
    assert m.settled is False
    assert "not recovered" in m.note and "too short" in m.note
    # Spread of the per-cycle means ≈ 2A·sinc(π T/P), T = one cycle.
    T = 4.0 * math.pi / RATED
    assert m.settle_spread_pct == pytest.approx(
        200.0 * 0.03 * math.sin(math.pi * T / P) / (math.pi * T / P), rel=0.05)
    table = to_table(m, "load_change_1")
    assert table["load_change_1_recovered"] == (0.0, "1")
    assert math.isnan(table["load_change_1_recovery_s"][0])


# --- spin-up ------------------------------------------------------------------------------------

@pytest.mark.parametrize("cycle", CYCLES)
def test_spin_up_t90(cycle):
    # ω_s = ω_r (1 − e^(−s/τ)) from rest: t90 = τ ln 10. The cycle mean is
    # ω_r (1 − e^(−t/τ) G), G = sinh(x)/x, x = T/(2τ), T = cycle/(0.9 ω_r) at the crossing:
    # it lags by τ ln G ≈ T²/(24τ).
    tau = 0.5
    seg = ExpSegments([0.0], [RATED], tau, 0.0)
    t, phi, omega = warp(np.arange(0.0, 12.0, DS), seg.phi, seg.omega)
    m = spin_up_metrics(t, phi, omega, RATED, cycle, band=0.01)
    T = cycle / (0.9 * RATED)
    lag = tau * math.log(window_gain(T, tau))
    assert lag == pytest.approx(T**2 / (24 * tau), rel=0.01)
    assert abs(m.t90 - (tau * math.log(10.0) + lag)) < JITTER + 1e-6
    # Independently: the mid time of the window whose cycle mean is 0.9 ω_r.
    mid = brentq(lambda x: smooth_cycle_mean(seg.phi, x, cycle) - 0.9 * RATED, 0.5, 3.0,
                 xtol=1e-12)
    assert abs(m.t90 - smooth_window(seg.phi, mid, cycle)[1]) < 1e-7
    T = cycle / (0.99 * RATED)
    expect = tau * math.log(100.0 * window_gain(T, tau))
    assert abs(m.settling_time - expect) < JITTER + 1e-6
    # Monotone: no overshoot beyond the rise left within the settle window, ~e^(−18).
    assert 0.0 <= m.overshoot_pct < 100.0 * math.exp(-18.0)
    assert m.omega_final == pytest.approx(RATED, rel=1e-8)
    assert m.in_band and m.settled


def test_spin_up_overshoot():
    # Up to 1.05 ω_r, then down to ω_r from the knot at 2 s (8τ into the rise): the peak is
    # the corner ω_s(2 s) = ω_p. The cycle mean is largest (to ~r²T/(2f), r and f the slopes
    # either side, here 4e-5 %) for the window [2 s − T, 2 s] ending on the corner, where the
    # rise ω_∞ − (ω_∞ − ω_p) e^(−(s−2)/τ) averages to ω_∞ − (ω_∞ − ω_p)(e^x − 1)/x, x = T/τ.
    # And independently: the largest cycle mean of the closed form.
    tau, cycle = 0.25, 4.0 * math.pi
    seg = ExpSegments([0.0, 2.0], [1.05 * RATED, RATED], tau, 0.0)
    t, phi, omega = warp(np.arange(0.0, 8.0, DS), seg.phi, seg.omega)
    m = spin_up_metrics(t, phi, omega, RATED, cycle)
    peak, w_inf = seg.omega(2.0), 1.05 * RATED
    x = cycle / peak / tau
    top = w_inf - (w_inf - peak) * math.expm1(x) / x
    assert 100.0 * (peak - top) / RATED > 5e-3  # the averaging matters at this resolution
    assert m.overshoot_pct == pytest.approx(100.0 * (top - RATED) / RATED, abs=1e-4)
    res = minimize_scalar(lambda x: -smooth_cycle_mean(seg.phi, x, cycle), method="bounded",
                          bounds=(1.9, 2.0), options={"xatol": 1e-10})
    # The code takes the largest sample, not the continuous maximum: short by up to
    # f·DS²/(8T) ≈ 1e-6 % at this corner.
    assert m.overshoot_pct == pytest.approx(100.0 * (-res.fun - RATED) / RATED, abs=2e-6)


def test_spin_up_of_a_run_that_starts_at_speed_has_no_t90():
    _, (t, phi, omega) = plateaus(1.04 * RATED, RATED)
    m = spin_up_metrics(t, phi, omega, RATED, 4.0 * math.pi)
    assert math.isnan(m.t90) and "not resolved" in m.note


def test_spin_up_that_never_gets_there():
    seg = ExpSegments([0.0], [0.8 * RATED], 0.5, 0.0)
    t, phi, omega = warp(np.arange(0.0, 4.0, DS), seg.phi, seg.omega)
    m = spin_up_metrics(t, phi, omega, RATED, 4.0 * math.pi)
    assert math.isnan(m.t90) and "never reaches 90 %" in m.note


# --- the /analysis table ------------------------------------------------------------------------

def test_metrics_table_of_spin_up_and_two_load_changes():
    # Spin-up to 1.04 ω_r (no load), full load at 3 s (droop to ω_r), rejection at 6 s.
    w0, tau = 1.04 * RATED, 0.2
    seg = ExpSegments([0.0, 3.0, 6.0], [w0, RATED, w0], tau, 0.0)
    t, phi, omega = warp(np.arange(0.0, 9.0, DS), seg.phi, seg.omega)
    table = metrics_table(t, phi, omega, 4.0 * math.pi, [3.0, 6.0], rated_speed=RATED,
                          spin_up=True)
    # Each plateau ends 15τ into its relaxation (e^(−15) ≈ 3e-7) and ω_after averages the
    # last quarter of a segment (from 11τ): both within 5e-5 % of the targets.
    assert table["load_change_1_droop_pct"][0] == pytest.approx(4.0, abs=1e-4)
    assert table["load_change_2_droop_pct"][0] == pytest.approx(-4.0, abs=1e-4)
    assert table["load_change_1_dev_max_pct"][0] < 0 < table["load_change_2_dev_max_pct"][0]
    G = window_gain(4.0 * math.pi / (0.9 * RATED), tau)
    assert abs(table["spin_up_t90_s"][0] - tau * math.log(G * 1.04 / 0.14)) < JITTER + 1e-6
    units = {k: u for k, (_, u) in table.items()}
    assert units["load_change_1_recovery_s"] == "s"
    assert units["load_change_2_omega_after_rad_s"] == "rad/s"
    assert units["spin_up_t90_s"] == "s"
    assert units["load_change_1_band_pct"] == "%" and table["load_change_1_band_pct"][0] == 1.0
    for k, (v, u) in table.items():
        assert isinstance(v, float)
        assert u in ("%", "s", "rad/s", "1"), k
        if u == "1":
            assert v in (0.0, 1.0), k
    # The table is the dataclass, flattened.
    m = load_change_metrics(t, phi, omega, 3.0, 4.0 * math.pi, rated_speed=RATED, t_end=6.0)
    assert isinstance(m, LoadChangeMetrics)
    assert table["load_change_1_recovery_s"][0] == m.recovery_time
    assert set(to_table(m, "x")) == {"x_" + k.split("load_change_1_", 1)[1]
                                     for k in table if k.startswith("load_change_1_")}
    assert isinstance(spin_up_metrics(t, phi, omega, RATED, 4.0 * math.pi, t_end=3.0),
                      SpinUpMetrics)


# --- input validation ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def run():
    seg = ExpSegments([0.0, TC], [1.04 * RATED, RATED], 0.2, 1.04 * RATED)
    return warp(np.arange(0.0, 3.0, 5 * DS), seg.phi, seg.omega)


C4 = 4.0 * math.pi


@pytest.mark.parametrize("change, match", [
    (lambda t, p, w: (t[::-1], p, w), "t must be strictly increasing"),
    (lambda t, p, w: (t, p[::-1], w), "phi decreases"),
    (lambda t, p, w: (t, p[:-1], w), "phi has .* samples, t has"),
    (lambda t, p, w: (t, p, np.where(t > 1.5, np.nan, w)), "omega has non-finite"),
    (lambda t, p, w: (t, p, w.reshape(-1, 1)), "1-D"),
])
def test_bad_trajectory(run, change, match):
    t, p, w = change(*run)
    with pytest.raises(ValueError, match=match):
        load_change_metrics(t, p, w, TC, C4)


@pytest.mark.parametrize("kwargs, match", [
    ({"band": 0.0}, "band must be a finite number > 0"),
    ({"band": -0.01}, "band must be"),
    ({"band": 1.5}, "fraction of rated speed"),
    ({"cycle": 0.0}, "cycle must be"),
    ({"t_change": 5.0}, "outside the run"),
    ({"t_change": -1.0}, "outside the run"),
    ({"t_change": 0.05}, "less than one cycle"),
    ({"t_end": 0.5}, "must be after t_change"),
    ({"t_end": 9.0}, "must be after t_change"),
    ({"rated_speed": 0.0}, "rated_speed must be"),
    ({"settle_window": 5.0}, "longer than the segment"),
    ({"settle_window": 0.01}, "at least 2 are needed"),
    ({"settle_window": -1.0}, "settle_window must be"),
    ({"load_step": "up"}, "load_step"),
])
def test_bad_arguments(run, kwargs, match):
    args = {"t_change": TC, "cycle": C4} | kwargs
    with pytest.raises(ValueError, match=match):
        load_change_metrics(*run, **args)


def test_bad_arguments_elsewhere(run):
    t, p, w = run
    with pytest.raises(ValueError, match="less than one cycle"):
        cycle_mean_speed(t[:20], p[:20], C4)
    with pytest.raises(ValueError, match="t_changes must be strictly increasing"):
        metrics_table(t, p, w, C4, [2.0, 1.0])
    with pytest.raises(ValueError, match="need rated_speed"):
        metrics_table(t, p, w, C4, [1.0], spin_up=True)
    with pytest.raises(ValueError, match="rated_speed must be"):
        spin_up_metrics(t, p, w, -1.0, C4)
    with pytest.raises(ValueError, match="outside the run"):
        spin_up_metrics(t, p, w, RATED, C4, t_end=10.0)


def test_hermite_is_scipys_curve():
    """The hand-written Hermite interpolant (kept out of scipy.interpolate for start-up time)
    against scipy.interpolate.CubicHermiteSpline, an independent implementation: inside, on the
    knots and extrapolated past both ends, to rounding."""
    from scipy.interpolate import CubicHermiteSpline

    from transient.analysis.transient_response import _hermite
    rng = np.random.default_rng(3)
    x = np.sort(rng.uniform(0.0, 10.0, 40))
    y, m = rng.normal(size=40), rng.normal(size=40)
    q = np.concatenate([rng.uniform(-1.0, 11.0, 500), x])
    np.testing.assert_allclose(_hermite(x, y, m)(q), CubicHermiteSpline(x, y, m)(q),
                               rtol=0, atol=1e-12)
    assert float(_hermite(x, y, m)(x[7])) == pytest.approx(y[7], abs=1e-14)


@pytest.mark.parametrize("n", [2, 3, 40])
def test_pchip_slopes_are_scipys(n):
    """The hand-written PCHIP slopes (a start from rest needs them; kept out of
    scipy.interpolate for start-up time) against scipy.interpolate.PchipInterpolator's
    derivative at the samples, on data with local extrema, flat runs and monotone stretches,
    and on increasing data (t over φ, as the spin-up's time of angle uses them)."""
    from scipy.interpolate import PchipInterpolator

    from transient.analysis.transient_response import _pchip_slopes
    rng = np.random.default_rng(5)
    x = np.sort(rng.uniform(0.0, 10.0, n))
    wavy = np.round(rng.normal(size=n), 1)  # rounded: some equal neighbours (zero secants)
    rising = np.cumsum(rng.uniform(0.0, 1.0, n))
    for y in (wavy, rising, -rising):
        expected = PchipInterpolator(x, y).derivative()(x)
        np.testing.assert_allclose(_pchip_slopes(x, np.diff(y) / np.diff(x)), expected,
                                   rtol=1e-13, atol=1e-13)
