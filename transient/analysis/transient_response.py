"""Transient speed response to load changes and spin-up, in the terms of ISO 8528-5 (one idea:
the standard's measures, each defined below against its ISO term).

ISO 8528-5 (generating sets driven by reciprocating engines) judges a set by its *frequency*
after a sudden load change; the shaft speed stands for it here (the frequency is proportional to
it). The terms and their names below:

=============================  ===========================================  ==================
ISO 8528-5 term                here                                         unit
=============================  ===========================================  ==================
initial frequency f_arb        ``omega_before``: cycle-mean speed over      rad/s
                               the last whole cycle before the change
                               (ending on the last sample at or before it)
transient frequency            ``dev_max_pct`` = (ω_ext − ω_before)/ω_r     %
deviation δf_dyn⁻ / δf_dyn⁺    ·100, ω_ext the extreme cycle-mean speed
                               (negative: dip on a load increase;
                               positive: overshoot on a decrease)
(deviation related to rated    ``dev_max_rated_pct`` = (ω_ext − ω_r)/ω_r    %
frequency)                     ·100
frequency recovery time        ``recovery_time``: from the change to the    s
t_f,in / t_f,de                permanent entry of the cycle-mean speed
                               into ω_after ± band·ω_r; NaN if it does
                               not enter before the segment ends
frequency tolerance band α_f   ``band``: the *half* width, a fraction of    1
                               ω_r (0.01: ±1 %)
frequency droop δf_st          ``droop_pct`` = (ω_before − ω_after)/ω_r     %
                               ·100
=============================  ===========================================  ==================

Points to check against the text of the standard (not at hand: the definitions above are from
memory of ISO 8528-5:2005/2013 and are flagged where unsure):

* δf_dyn is taken from the *initial* speed (the 2005 edition's form, as recalled); the form
  from rated speed is reported too (``dev_max_rated_pct``). Both divide by rated speed.
* ISO starts the recovery time, as recalled, when the frequency *leaves* the steady-state band
  after the change; it is measured here from the change itself. The two differ by the time the
  speed takes to leave that band, a small part of the transient for a step that leaves it
  clearly.
* α_f may be the full width of the band in the standard; ``band`` is the half width, so pass
  α_f/2 if so. The performance classes G1…G3 set α_f, the recovery time and δf_dyn limits;
  they are not coded here — compare the reported numbers with the class table.
* δf_st = (f_i,r − f_r)/f_r·100 (no-load minus rated-load frequency over rated frequency,
  positive for a speed that falls with load). ``droop_pct`` is this for a 0 → 100 % load
  increase with ``rated_speed`` = the speed at rated load; for a decrease it has the opposite
  sign, and for a partial step it is the step's share of the droop. With ``rated_speed=None``
  the speed before the change is the reference, which is not ISO's f_r.

Why the cycle-mean speed, not ω(t). A piston engine's speed swings within every cycle (the
coefficient of irregularity δ, Gots §2.8), by several % at low flywheel inertia — as much as
the G-class limits themselves. Read from raw ω(t), the dip would include the swing of the cycle
it falls in, and the band would be left and re-entered every cycle. Every measure here is taken
from the **cycle-mean speed**: the mean over a sliding window of exactly one engine cycle in
crank angle (``cycle`` = 2π for a 2-stroke, 4π for a 4-stroke),

    ω̄(t_i) = cycle / (t_i − t(φ_i − cycle)),

which is the exact time average of ω over the window (∫ω dt = Δφ), whatever the speed. Because
the window is one cycle *in angle*, the part of dt/dφ = 1/ω that is periodic in φ with the
cycle (period cycle/k: the gas and inertia torques' orders) integrates to zero over it exactly,
at any speed; a ripple riding on a changing speed is removed up to the product of its size and
the speed's change within one cycle. A window fixed in *time* would leave a residue whenever
the cycle time is not a whole multiple of it. t(φ) between samples is a cubic Hermite
interpolant with the exact slope dt/dφ = 1/ω (limited to keep it monotone). ω̄ is assigned
to the mid time of its window, where it equals ω_smooth(t_mid) + T²ω″/24 + O(T⁴) (T the
cycle time): no lag for a linear trend, and a dip under-read by T²|ω″|/24 — the price of the
averaging, small when the transient is slow compared with a cycle.
"""
from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Default share of a segment, at its end, over which the steady speed is taken.
SETTLE_SHARE = 0.25
#: Speed reached by a spin-up, as a fraction of rated speed, for ``t90``.
SPIN_UP_FRACTION = 0.9


def _metric(key: str | None, unit: str):
    """A dataclass field with its table key and unit (``key=None``: not in the table)."""
    return field(metadata={"key": key, "unit": unit})


@dataclass(frozen=True)
class LoadChangeMetrics:
    """Response of the cycle-mean speed to one sudden load change (ISO 8528-5 terms).

    Times are from the change unless they say otherwise; percentages are of ``omega_rated``.
    """

    t_change: float = _metric("t_s", "s")
    """Time of the load change [s]."""
    t_end: float = _metric("t_end_s", "s")
    """End of the segment: the next change or the end of the run [s]."""
    omega_rated: float = _metric("omega_rated_rad_s", "rad/s")
    """Rated speed, the reference of every percentage [rad/s]."""
    omega_before: float = _metric("omega_before_rad_s", "rad/s")
    """Cycle-mean speed over the last whole cycle before the change (ISO f_arb) [rad/s]."""
    omega_after: float = _metric("omega_after_rad_s", "rad/s")
    """Steady speed after the change: mean over the whole cycles of the settle window [rad/s]."""
    omega_extreme: float = _metric("omega_extreme_rad_s", "rad/s")
    """Extreme cycle-mean speed after the change (minimum on a dip) [rad/s]."""
    dev_max_pct: float = _metric("dev_max_pct", "%")
    """Transient speed deviation δ_dyn = (ω_ext − ω_before)/ω_rated·100 [%]: negative for a dip
    (load increase), positive for an overshoot (load decrease)."""
    dev_max_rated_pct: float = _metric("dev_max_rated_pct", "%")
    """(ω_ext − ω_rated)/ω_rated·100, the deviation from rated speed [%]."""
    t_dev_max: float = _metric("t_dev_max_s", "s")
    """Time from the change to the extreme [s]."""
    recovery_time: float = _metric("recovery_s", "s")
    """From the change until the cycle-mean speed enters ω_after ± band·ω_rated for good [s];
    NaN if it does not before the segment ends; 0 if it never leaves the band."""
    droop_pct: float = _metric("droop_pct", "%")
    """Steady speed change (ω_before − ω_after)/ω_rated·100 [%]; ISO δf_st for a 0 → 100 %
    load increase."""
    band: float = _metric("band_pct", "%")
    """Half width of the tolerance band as a fraction of rated speed [1] (table: in %)."""
    settle_window: float = _metric("settle_window_s", "s")
    """Length of the whole cycles at the segment end over which ``omega_after`` is taken [s]."""
    settle_spread_pct: float = _metric("settle_spread_pct", "%")
    """Max − min of the per-cycle mean speeds in the settle window, in % of rated [%]."""
    recovered: bool = _metric("recovered", "1")
    """The cycle-mean speed enters the band for good before the segment ends."""
    settled: bool = _metric("settled", "1")
    """The per-cycle means in the settle window vary by less than the band (ω_after is steady)."""
    note: str = _metric(None, "")
    """Why a flag is False or a value NaN, in words; empty if all is well."""


@dataclass(frozen=True)
class SpinUpMetrics:
    """Run-up of the cycle-mean speed from the start of the trace to a steady speed.

    Times are from the first sample ``t[0]``; percentages are of ``omega_rated``.
    """

    omega_rated: float = _metric("omega_rated_rad_s", "rad/s")
    """Rated speed [rad/s]."""
    omega_final: float = _metric("omega_final_rad_s", "rad/s")
    """Steady speed at the end: mean over the whole cycles of the settle window [rad/s]."""
    t90: float = _metric("t90_s", "s")
    """First time the cycle-mean speed reaches 0.9·ω_rated [s]; NaN if it never does (or is
    above it already at the first whole cycle)."""
    settling_time: float = _metric("settling_s", "s")
    """Time until the cycle-mean speed enters ω_final ± band·ω_rated for good [s]; NaN if not."""
    overshoot_pct: float = _metric("overshoot_pct", "%")
    """max(0, max ω̄ − ω_final)/ω_rated·100 [%]."""
    band: float = _metric("band_pct", "%")
    """Half width of the band as a fraction of rated speed [1] (table: in %)."""
    settle_window: float = _metric("settle_window_s", "s")
    """Length of the whole cycles at the end over which ``omega_final`` is taken [s]."""
    settle_spread_pct: float = _metric("settle_spread_pct", "%")
    """Max − min of the per-cycle mean speeds in the settle window, in % of rated [%]."""
    in_band: bool = _metric("in_band", "1")
    """The cycle-mean speed enters the band for good before the segment ends."""
    settled: bool = _metric("settled", "1")
    """The per-cycle means in the settle window vary by less than the band."""
    note: str = _metric(None, "")
    """Why a flag is False or a value NaN, in words; empty if all is well."""


# --- the cycle-mean speed ------------------------------------------------------------------------

def _check_trajectory(t, phi, omega=None):
    """Float arrays t, φ (and ω) after checking shapes, finiteness and monotonicity."""
    t = np.asarray(t, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    arrays = {"t": t, "phi": phi}
    if omega is not None:
        arrays["omega"] = omega = np.asarray(omega, dtype=np.float64)
    for name, a in arrays.items():
        if a.ndim != 1:
            raise ValueError(f"{name} must be a 1-D array, got shape {a.shape}")
        if a.size != t.size:
            raise ValueError(f"{name} has {a.size} samples, t has {t.size}: they must match")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{name} has non-finite values (first at index "
                             f"{int(np.argmin(np.isfinite(a)))})")
    if t.size < 4:
        raise ValueError(f"need at least 4 samples, got {t.size}")
    bad = np.nonzero(np.diff(t) <= 0)[0]
    if bad.size:
        raise ValueError(f"t must be strictly increasing: t[{bad[0] + 1}] = {t[bad[0] + 1]!r} "
                         f"<= t[{bad[0]}] = {t[bad[0]]!r}")
    back = np.nonzero(np.diff(phi) < 0)[0]
    if back.size:
        raise ValueError(f"phi decreases at t = {t[back[0] + 1]:.6g} s (the shaft turns "
                         "backwards): the cycle-mean speed needs phi unwrapped and non-decreasing")
    return t, phi, omega


def _check_positive(**values) -> None:
    for name, v in values.items():
        if not (isinstance(v, (int, float, np.floating, np.integer)) and math.isfinite(v)
                and v > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {v!r}")


def _hermite(x, y, m) -> Callable[[ArrayLike], NDArray[np.float64]]:
    """The cubic Hermite interpolant through (x, y) with slopes m, extrapolated by its end
    cubics: the curve of :class:`scipy.interpolate.CubicHermiteSpline` (the tests compare them).

    Written out because importing scipy.interpolate costs a noticeable part of the warm start of
    every ``transient run`` that summarizes a spin-up; evaluating a cubic is three lines.
    """
    dx = np.diff(x)
    secant = np.diff(y) / dx
    c2 = (3.0 * secant - 2.0 * m[:-1] - m[1:]) / dx
    c3 = (m[:-1] + m[1:] - 2.0 * secant) / dx**2

    def evaluate(q: ArrayLike) -> NDArray[np.float64]:
        q = np.asarray(q, dtype=np.float64)
        i = np.clip(np.searchsorted(x, q, side="right") - 1, 0, x.size - 2)
        e = q - x[i]
        return y[i] + e * (m[i] + e * (c2[i] + e * c3[i]))

    return evaluate


def _pchip_slopes(x, secant) -> NDArray[np.float64]:
    """The slopes of :class:`scipy.interpolate.PchipInterpolator` at the samples x, from the
    secants between them: Fritsch & Butland's weighted harmonic mean of the adjacent secants, 0
    at a local extremum; the ends by the shape-preserving three-point formula. The tests compare
    them with scipy's. Written out for the reason :func:`_hermite` gives: a start from rest
    (ω = 0) needs them."""
    if x.size == 2:
        return np.full(2, secant[0])
    h = np.diff(x)
    m = np.zeros(x.size)
    w1, w2 = 2.0 * h[1:] + h[:-1], h[1:] + 2.0 * h[:-1]
    same = (np.sign(secant[1:]) == np.sign(secant[:-1])) & (secant[1:] != 0) & (secant[:-1] != 0)
    with np.errstate(divide="ignore", invalid="ignore"):  # (the cases np.where drops)
        m[1:-1] = np.where(same, (w1 + w2) / (w1 / secant[:-1] + w2 / secant[1:]), 0.0)
    m[0] = _pchip_end(h[0], h[1], secant[0], secant[1])
    m[-1] = _pchip_end(h[-1], h[-2], secant[-1], secant[-2])
    return m


def _pchip_end(h0: float, h1: float, s0: float, s1: float) -> float:
    """PCHIP's end slope: the three-point estimate, 0 if against the end secant's sign, at most
    3 × that secant where the data turn (Moler, *Numerical Computing with MATLAB*, §3.4)."""
    d = ((2.0 * h0 + h1) * s0 - h0 * s1) / (h0 + h1)
    if np.sign(d) != np.sign(s0):
        return 0.0
    if np.sign(s0) != np.sign(s1) and abs(d) > 3.0 * abs(s0):
        return 3.0 * s0
    return d


def _monotone_hermite(x, y, slope) -> Callable[[ArrayLike], NDArray[np.float64]]:
    """Cubic Hermite y(x) through samples with increasing x and non-decreasing y.

    ``slope`` is the known dy/dx at the samples; where it is not finite or negative (ω = 0 at
    rest, a solver wiggle) the PCHIP slope replaces it. Slopes are limited to
    0 ≤ m ≤ 3·min(adjacent secants), Fritsch & Carlson's bound, so the interpolant is monotone.
    """
    secant = np.diff(y) / np.diff(x)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(slope) & (slope >= 0)
    m = np.array(slope, dtype=np.float64)
    if not ok.all():  # (only a start from rest: not every run pays for the slopes)
        m[~ok] = _pchip_slopes(x, secant)[~ok]
    limit = 3.0 * np.minimum(np.r_[secant[0], secant], np.r_[secant, secant[-1]])
    return _hermite(x, y, np.clip(m, 0.0, limit))


def _time_of_angle(t, phi, omega=None) -> Callable[[ArrayLike], NDArray[np.float64]]:
    """t(φ), slopes 1/ω when ω is given (PCHIP otherwise). Of samples at the same φ (shaft at
    rest) the last one is kept, so a window starts when the shaft last left that angle."""
    keep = np.r_[np.diff(phi) > 0, True]
    if keep.sum() < 2:
        raise ValueError("phi does not advance: the shaft never turns")
    if omega is None:
        slope = np.full(int(keep.sum()), np.nan)
    else:
        with np.errstate(divide="ignore"):
            slope = 1.0 / omega[keep]
    return _monotone_hermite(phi[keep], t[keep], slope)


def _cycle_windows(t, phi, cycle, t_of):
    """(start, stop) times of the one-cycle windows that end on the samples with
    φ_i − φ_0 ≥ cycle."""
    ends = phi - phi[0] >= cycle
    return t_of(phi[ends] - cycle), t[ends]


def cycle_mean_speed(t: NDArray[np.float64], phi: NDArray[np.float64], cycle: float,
                     omega: NDArray[np.float64] | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean speed over a sliding window of one engine cycle in crank angle.

    Parameters
    ----------
    t : (n,) array
        Sample times [s], strictly increasing.
    phi : (n,) array
        Shaft angle [rad], unwrapped, non-decreasing.
    cycle : float
        Cycle angle [rad]: 2π for a 2-stroke, 4π for a 4-stroke engine.
    omega : (n,) array, optional
        Shaft speed [rad/s]. When given, t(φ) is interpolated with its exact slope 1/ω
        (fourth order); otherwise with PCHIP.

    Returns
    -------
    t_mid : (m,) array
        Mid time of each window [s], one per sample i with φ_i − φ_0 ≥ cycle.
    omega_mean : (m,) array
        cycle / (t_i − t(φ_i − cycle)) [rad/s], the exact time average of ω over the window.
    """
    t, phi, omega = _check_trajectory(t, phi, omega)
    _check_positive(cycle=cycle)
    if phi[-1] - phi[0] < cycle:
        raise ValueError(f"the run turns {phi[-1] - phi[0]:.6g} rad, less than one cycle "
                         f"({cycle:.6g} rad): no cycle-mean speed")
    start, stop = _cycle_windows(t, phi, cycle, _time_of_angle(t, phi, omega))
    return 0.5 * (start + stop), cycle / (stop - start)


# --- pieces of the metrics ----------------------------------------------------------------------

def _last_sample(t, time: float) -> int:
    """Index of the last sample at or before ``time``. Windows end on samples, not between:
    at a load change ω has a corner, and interpolating φ(t) across it would cost accuracy
    (a simulation stops on the change, so there is normally a sample on it)."""
    return int(np.searchsorted(t, time, side="right")) - 1


def _steady(t, phi, t_end, settle_window, cycle, t_of):
    """Steady speed over the whole cycles that fit in ``settle_window`` and end on the last
    sample at or before ``t_end``.

    Returns (ω_mean [rad/s], length of those cycles [s], max − min of the per-cycle means
    [rad/s]). At least two cycles are needed to say whether the speed still moves.
    """
    i = _last_sample(t, t_end)
    t_e, phi_e = float(t[i]), float(phi[i])
    turned = phi_e - float(np.interp(t_end - settle_window, t, phi))
    n = math.floor(turned / cycle + 1e-9)
    if n < 2:
        raise ValueError(f"settle_window = {settle_window:.6g} s holds {n} whole cycle(s) at "
                         f"t = {t_end:.6g} s; at least 2 are needed to judge whether the speed "
                         "has settled: lengthen it (or the segment)")
    bounds = t_of(phi_e - cycle * np.arange(n, -1, -1))
    bounds[-1] = t_e
    per_cycle = cycle / np.diff(bounds)
    return n * cycle / (t_e - bounds[0]), t_e - bounds[0], float(np.ptp(per_cycle))


def _default_window(settle_window, t_a, t_b, what: str) -> float:
    length = t_b - t_a
    if settle_window is None:
        return SETTLE_SHARE * length
    _check_positive(settle_window=settle_window)
    if settle_window > length:
        raise ValueError(f"settle_window = {settle_window:.6g} s is longer than the {what} "
                         f"({length:.6g} s)")
    return float(settle_window)


def _entry_time(tm, w, ref, half_width) -> float:
    """Time the series w(tm) enters ref ± half_width for good (linear between samples); NaN if
    its last sample is outside; tm[0] if it is never outside."""
    excess = np.abs(w - ref) - half_width
    outside = np.nonzero(excess > 0)[0]
    if outside.size == 0:
        return float(tm[0])
    k = int(outside[-1])
    if k == w.size - 1:
        return math.nan
    e0, e1 = excess[k], excess[k + 1]
    return float(tm[k] + (tm[k + 1] - tm[k]) * e0 / (e0 - e1))


def _vertex(tm, w, k) -> tuple[float, float]:
    """Extreme of the parabola through samples k−1, k, k+1 (the sample itself at an end or if
    the three are collinear)."""
    if k == 0 or k == w.size - 1:
        return float(tm[k]), float(w[k])
    x = tm[k - 1:k + 2] - tm[k]
    a, b, c = np.polyfit(x, w[k - 1:k + 2], 2)
    if a == 0.0:
        return float(tm[k]), float(w[k])
    xv = float(np.clip(-b / (2.0 * a), x[0], x[2]))
    return float(tm[k] + xv), float(np.polyval([a, b, c], xv))


def _extreme(tm, w, ref, load_step: str) -> tuple[float, float]:
    """(time, value) of the extreme of w: the minimum on a load increase, the maximum on a
    decrease, the largest excursion from ``ref`` either way for ``auto``."""
    if load_step == "increase":
        k = int(np.argmin(w))
    elif load_step == "decrease":
        k = int(np.argmax(w))
    else:
        k = int(np.argmax(np.abs(w - ref)))
    return _vertex(tm, w, k)


def _check_band(band) -> None:
    _check_positive(band=band)
    if band >= 1.0:
        raise ValueError(f"band = {band!r} is a fraction of rated speed (0.01 for ±1 %); it "
                         "must be < 1")


# --- the metrics --------------------------------------------------------------------------------

def load_change_metrics(t: NDArray[np.float64], phi: NDArray[np.float64],
                        omega: NDArray[np.float64], t_change: float, cycle: float,
                        band: float = 0.01, rated_speed: float | None = None,
                        settle_window: float | None = None, t_end: float | None = None,
                        load_step: str = "auto") -> LoadChangeMetrics:
    """ISO 8528-5 measures of the cycle-mean speed after a sudden load change.

    Parameters
    ----------
    t, phi, omega : (n,) arrays
        Trajectory: time [s] (strictly increasing), shaft angle [rad] (unwrapped,
        non-decreasing), speed [rad/s].
    t_change : float
        Time of the load change [s]; at least one whole cycle of the run must precede it.
    cycle : float
        Cycle angle [rad]: 2π (2-stroke) or 4π (4-stroke).
    band : float
        Half width of the tolerance band as a fraction of rated speed [1]; 0.01 is ±1 %.
    rated_speed : float, optional
        Rated speed [rad/s], the reference of the percentages; by default the speed before
        the change.
    settle_window : float, optional
        Length [s] at the end of the segment over which the steady speed after the change is
        taken (the whole cycles that fit in it, at least 2); by default a quarter of the
        segment.
    t_end : float, optional
        End of the segment [s]: the next load change; by default the end of the run.
    load_step : {"auto", "increase", "decrease"}
        Which extreme is the transient deviation: the minimum (increase), the maximum
        (decrease), or the largest excursion from the speed before (auto).

    Returns
    -------
    LoadChangeMetrics
    """
    t, phi, omega = _check_trajectory(t, phi, omega)
    _check_positive(cycle=cycle)
    _check_band(band)
    if load_step not in ("auto", "increase", "decrease"):
        raise ValueError(f"load_step = {load_step!r}; allowed: 'auto', 'increase', 'decrease'")
    t_end = float(t[-1]) if t_end is None else float(t_end)
    if not (t[0] < t_change < t[-1]):
        raise ValueError(f"t_change = {t_change!r} s is outside the run "
                         f"({t[0]:.6g} s, {t[-1]:.6g} s)")
    if not (t_change < t_end <= t[-1]):
        raise ValueError(f"t_end = {t_end!r} s must be after t_change = {t_change!r} s and not "
                         f"after the end of the run ({t[-1]:.6g} s)")
    t_of = _time_of_angle(t, phi, omega)
    i_c = _last_sample(t, t_change)
    if phi[i_c] - phi[0] < cycle:
        raise ValueError(f"t_change = {t_change:.6g} s comes {phi[i_c] - phi[0]:.6g} rad after "
                         f"the start, less than one cycle ({cycle:.6g} rad): no speed before it")
    omega_before = cycle / (t[i_c] - float(t_of(phi[i_c] - cycle)))
    rated = omega_before if rated_speed is None else rated_speed
    _check_positive(rated_speed=rated)
    window = _default_window(settle_window, t_change, t_end, "segment after the change")
    omega_after, window, spread = _steady(t, phi, t_end, window, cycle, t_of)

    start, stop = _cycle_windows(t, phi, cycle, t_of)
    tm, wm = 0.5 * (start + stop), cycle / (stop - start)
    seg = (tm >= t_change) & (stop <= t_end)
    if seg.sum() < 3:
        raise ValueError(f"the segment {t_change:.6g} s … {t_end:.6g} s has {int(seg.sum())} "
                         "cycle-mean samples; at least 3 are needed (sample more densely)")
    tm, wm = tm[seg], wm[seg]

    t_ext, w_ext = _extreme(tm, wm, omega_before, load_step)
    entry = _entry_time(tm, wm, omega_after, band * rated)
    recovered = not math.isnan(entry)
    recovery = 0.0 if recovered and entry == tm[0] else entry - t_change
    settled = spread < band * rated
    notes = []
    if not recovered:
        notes.append("the cycle-mean speed is outside the band at the end of the segment: "
                     "not recovered (recovery time NaN)")
    if not settled:
        notes.append(f"segment too short to settle: over the last {window:.4g} s the per-cycle "
                     f"mean speed still varies by {100 * spread / rated:.3g} % of rated, more "
                     f"than the band ({100 * band:.3g} %); omega_after is not a steady value")
    return LoadChangeMetrics(
        t_change=float(t_change), t_end=t_end, omega_rated=float(rated),
        omega_before=float(omega_before), omega_after=float(omega_after),
        omega_extreme=w_ext, dev_max_pct=100.0 * (w_ext - omega_before) / rated,
        dev_max_rated_pct=100.0 * (w_ext - rated) / rated, t_dev_max=t_ext - t_change,
        recovery_time=float(recovery), droop_pct=100.0 * (omega_before - omega_after) / rated,
        band=float(band), settle_window=float(window), settle_spread_pct=100.0 * spread / rated,
        recovered=recovered, settled=bool(settled), note="; ".join(notes))


def spin_up_metrics(t: NDArray[np.float64], phi: NDArray[np.float64],
                    omega: NDArray[np.float64], rated_speed: float, cycle: float,
                    band: float = 0.01, settle_window: float | None = None,
                    t_end: float | None = None) -> SpinUpMetrics:
    """Run-up measures of the cycle-mean speed, from the first sample to ``t_end``.

    Parameters
    ----------
    t, phi, omega : (n,) arrays
        Trajectory [s], [rad], [rad/s] as in :func:`load_change_metrics`.
    rated_speed : float
        Rated speed [rad/s].
    cycle : float
        Cycle angle [rad]: 2π (2-stroke) or 4π (4-stroke).
    band : float
        Half width of the band around the final speed as a fraction of rated speed [1].
    settle_window : float, optional
        Length [s] at the end over which the final steady speed is taken (whole cycles, at
        least 2); by default a quarter of the run-up.
    t_end : float, optional
        End of the run-up [s] (e.g. the first load change); by default the end of the run.

    Returns
    -------
    SpinUpMetrics
        Times are from t[0]. The first cycle-mean speed exists one cycle after the start and
        belongs to the mid time of that cycle: a run-up that is past 90 % by then has no t90.
    """
    t, phi, omega = _check_trajectory(t, phi, omega)
    _check_positive(cycle=cycle, rated_speed=rated_speed)
    _check_band(band)
    t_end = float(t[-1]) if t_end is None else float(t_end)
    if not (t[0] < t_end <= t[-1]):
        raise ValueError(f"t_end = {t_end!r} s is outside the run ({t[0]:.6g} s, {t[-1]:.6g} s]")
    t_of = _time_of_angle(t, phi, omega)
    window = _default_window(settle_window, float(t[0]), t_end, "run-up")
    omega_final, window, spread = _steady(t, phi, t_end, window, cycle, t_of)
    start, stop = _cycle_windows(t, phi, cycle, t_of)
    seg = stop <= t_end
    if seg.sum() < 3:
        raise ValueError(f"the run-up up to {t_end:.6g} s has {int(seg.sum())} cycle-mean "
                         "samples; at least 3 are needed")
    tm, wm = 0.5 * (start[seg] + stop[seg]) - t[0], cycle / (stop[seg] - start[seg])

    notes = []
    target = SPIN_UP_FRACTION * rated_speed
    above = np.nonzero(wm >= target)[0]
    if above.size == 0:
        t90 = math.nan
        notes.append("the cycle-mean speed never reaches 90 % of rated (t90 NaN)")
    elif above[0] == 0:
        t90 = math.nan
        notes.append("the cycle-mean speed is above 90 % of rated at the first whole cycle "
                     "(t90 NaN: not resolved)")
    else:
        k = int(above[0])
        t90 = float(tm[k - 1] + (tm[k] - tm[k - 1]) * (target - wm[k - 1]) / (wm[k] - wm[k - 1]))
    entry = _entry_time(tm, wm, omega_final, band * rated_speed)
    in_band = not math.isnan(entry)
    if not in_band:
        notes.append("the cycle-mean speed is outside the band at the end: settling time NaN")
    elif entry == tm[0]:
        entry = math.nan
        notes.append("the cycle-mean speed is in the band at the first whole cycle: no run-up "
                     "to time (settling time NaN)")
    settled = spread < band * rated_speed
    if not settled:
        notes.append(f"run-up too short to settle: over the last {window:.4g} s the per-cycle "
                     f"mean speed varies by {100 * spread / rated_speed:.3g} % of rated")
    return SpinUpMetrics(
        omega_rated=float(rated_speed), omega_final=float(omega_final), t90=t90,
        settling_time=float(entry),
        overshoot_pct=100.0 * max(0.0, float(wm.max()) - omega_final) / rated_speed,
        band=float(band), settle_window=float(window),
        settle_spread_pct=100.0 * spread / rated_speed,
        in_band=in_band,
        settled=bool(settled), note="; ".join(notes))


# --- the table for /analysis --------------------------------------------------------------------

def to_table(metrics: LoadChangeMetrics | SpinUpMetrics, prefix: str
             ) -> dict[str, tuple[float, str]]:
    """Flat ``{prefix_key: (value, unit)}`` of a metrics object: flags as 0/1 with unit "1",
    the band in %, the note left out."""
    out = {}
    for f in fields(metrics):
        key, unit = f.metadata["key"], f.metadata["unit"]
        if key is None:
            continue
        value = getattr(metrics, f.name)
        if f.name == "band":
            value = 100.0 * value
        out[f"{prefix}_{key}"] = (float(value), unit)
    return out


def metrics_table(t: NDArray[np.float64], phi: NDArray[np.float64],
                  omega: NDArray[np.float64], cycle: float, t_changes: Sequence[float] = (),
                  rated_speed: float | None = None, band: float = 0.01,
                  settle_window: float | None = None, spin_up: bool = False
                  ) -> dict[str, tuple[float, str]]:
    """Every transient-response measure of a run as ``name -> (value, unit)`` for ``/analysis``.

    Load change k (from 1, in time order) covers ``t_changes[k-1]`` up to the next change or
    the end of the run; its entries are named ``load_change_<k>_<key>``, e.g.
    ``load_change_1_dev_max_pct``, ``load_change_1_recovery_s``, ``load_change_1_droop_pct``.
    With ``spin_up`` the run-up from the start to the first change (or the end) adds
    ``spin_up_<key>``, e.g. ``spin_up_t90_s``; it needs ``rated_speed``. Units: "%", "s",
    "rad/s", and "1" for the flags (0/1). ``settle_window`` (s) applies to every segment;
    ``None`` takes a quarter of each. ``rated_speed=None`` makes each change its own reference
    (the speed before it). See :func:`load_change_metrics` for the rest.
    """
    t_changes = [float(c) for c in t_changes]
    if any(b <= a for a, b in itertools.pairwise(t_changes)):
        raise ValueError(f"t_changes must be strictly increasing, got {t_changes}")
    t_last = float(np.asarray(t)[-1])
    out: dict[str, tuple[float, str]] = {}
    if spin_up:
        if rated_speed is None:
            raise ValueError("spin-up measures need rated_speed")
        out.update(to_table(spin_up_metrics(t, phi, omega, rated_speed, cycle, band,
                                            settle_window,
                                            t_changes[0] if t_changes else None), "spin_up"))
    ends = t_changes[1:] + [t_last]
    for k, (tc, te) in enumerate(zip(t_changes, ends), start=1):
        m = load_change_metrics(t, phi, omega, tc, cycle, band, rated_speed, settle_window, te)
        out.update(to_table(m, f"load_change_{k}"))
    return out


# --- a run's summary ------------------------------------------------------------------------------

#: Tolerance band of the summary's recovery times, a fraction of the reference speed (±1 %).
SUMMARY_BAND = 0.01


def load_step_times(scene, events) -> list[float]:
    """Times of the run's sudden load changes: the steps of its load schedule (two equal
    abscissae), from the ``load_schedule`` events (a step in revolutions happens at a time the run
    finds). Ramps are not load changes in the ISO 8528-5 sense and are left out."""
    load = scene.load
    x = np.asarray(load.schedule_time or load.schedule_revolutions, dtype=float)
    steps = x[1:][np.diff(x) == 0.0]
    rows = np.asarray(events.get("load_schedule", np.zeros((0, 2))) if events else np.zeros((0, 2)))
    if steps.size == 0 or rows.size == 0:
        return []
    if load.schedule_time:
        at = rows[:, 0]
        return [float(t) for t in rows[:, 0] if np.any(np.abs(steps - t) <= 1e-9 * max(1.0, t))
                ] if at.size else []
    angles = scene.initial.phi + 2.0 * np.pi * steps
    return [float(t) for t, p in rows if np.any(np.abs(angles - p) <= 1e-9 * max(1.0, abs(p)))]


def is_spin_up(initial_omega: float, final_omega: float) -> bool:
    """A run that starts below 90 % of the speed it ends at (so it has a 90 % to reach): its
    spin-up is measured (:func:`run_response`) and its order spectra are detrended
    (:func:`transient.analysis.orders.order_spectrum`)."""
    return final_omega > 0 and initial_omega < SPIN_UP_FRACTION * final_omega


def rated_speed(scene) -> float | None:
    """The scene's rated speed [rad/s]: the isochronous (PI) governor's set speed; None for the
    others (a droop governor's speed moves with the load), whose measures refer each load step
    to the speed before it and a spin-up to the speed it ends at."""
    return scene.governor.speed if scene.governor.model == "pi" else None


def run_response(scene, traj, events) -> dict[str, tuple[float, str]]:
    """ISO 8528-5 measures of a dynamic run for ``/analysis`` (:func:`metrics_table`): one set per
    load step of the schedule, and for a run that starts below 90 % of the rated speed the
    spin-up. The reference of the percentages is the rated speed (:func:`rated_speed`) where the
    scene has one, else the speed before each step and the speed the spin-up ends at. Entries that
    cannot be measured (a change too close to the start or the end, too short a run) are left
    out, never guessed."""
    t, phi, omega = traj["t"], traj["phi"], traj["omega"]
    cycle = scene.mechanism.cycle
    rated = rated_speed(scene)
    out: dict[str, tuple[float, str]] = {}
    changes = [tc for tc in load_step_times(scene, events) if t[0] < tc < t[-1]]
    for k, tc in enumerate(changes, start=1):
        end = changes[k] if k < len(changes) else float(t[-1])
        try:
            m = load_change_metrics(t, phi, omega, tc, cycle, SUMMARY_BAND, rated_speed=rated,
                                    t_end=end)
        except ValueError:
            continue  # (e.g. less than a cycle before the change, or a settle window too short)
        out.update(to_table(m, f"load_change_{k}"))
    final = float(np.mean(omega[-max(2, omega.size // 50):]))
    if is_spin_up(scene.initial.omega, rated or final):
        try:
            sm = spin_up_metrics(t, phi, omega, rated or final, cycle, SUMMARY_BAND,
                                 t_end=changes[0] if changes else None)
            out.update(to_table(sm, "spin_up"))
        except ValueError:
            pass  # too short a run to measure
    return out
