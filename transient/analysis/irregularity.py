"""Speed fluctuation and steady state from a trajectory.

δ = (ω_max − ω_min)/ω_mean over one engine cycle (Gots §2.8, the coefficient of speed
irregularity); the cycle-mean speed is the cycle angle over the cycle time, exact from t(φ).
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


def cycle_boundaries(t: NDArray[np.float64], phi: NDArray[np.float64], cycle: float,
                     phi0: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Times and angles at which whole engine cycles (from φ0) end, while φ increases."""
    if phi.size < 2 or np.any(np.diff(phi) <= 0):
        # φ not monotonic (reversal): use the part after the last backward motion.
        back = np.nonzero(np.diff(phi) <= 0)[0]
        start = back[-1] + 1 if back.size else 0
        t, phi = t[start:], phi[start:]
        if phi.size < 2:
            return np.zeros(0), np.zeros(0)
    k0 = math.ceil((phi[0] - phi0) / cycle - 1e-12)
    k1 = math.floor((phi[-1] - phi0) / cycle + 1e-12)
    marks = phi0 + cycle * np.arange(k0, k1 + 1)
    return np.interp(marks, phi, t), marks


def cycle_means(t, phi, cycle, phi0):
    """Mean speed of each whole cycle [rad/s] and the times the cycles end."""
    tb, _ = cycle_boundaries(t, phi, cycle, phi0)
    if tb.size < 2:
        return np.zeros(0), np.zeros(0)
    return cycle / np.diff(tb), tb[1:]


def cycle_extremes(t, values, bounds) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Least and greatest of a sampled quantity over each of the time windows between
    consecutive ``bounds`` (the n + 1 times of :func:`cycle_boundaries`): the samples inside
    and the values interpolated at the window's ends, so that a window between two samples
    still has both. Returns two arrays of n."""
    t, values, bounds = (np.asarray(a, dtype=float) for a in (t, values, bounds))
    ends = np.interp(bounds, t, values)
    lo = np.minimum(ends[:-1], ends[1:])
    hi = np.maximum(ends[:-1], ends[1:])
    first = np.searchsorted(t, bounds, side="left")  # the first sample at or after each bound
    last = np.searchsorted(t, bounds, side="right")  # one past the last at or before it
    for i in range(lo.size):
        inside = values[first[i]:last[i + 1]]
        if inside.size:
            lo[i] = min(lo[i], inside.min())
            hi[i] = max(hi[i], inside.max())
    return lo, hi


def steady_state_time(means, ends, rtol: float = 1e-4, cycles: int = 3) -> float:
    """End time of the first cycle after which the cycle-mean speed changes by < rtol for
    ``cycles`` cycles in a row; NaN if the run never settles."""
    if means.size < cycles + 1:
        return math.nan
    change = np.abs(np.diff(means)) / np.abs(means[1:])
    calm = change < rtol
    for i in range(calm.size - cycles + 1):
        if calm[i:i + cycles].all():
            return float(ends[i])
    return math.nan


def fluctuation(t, phi, omega, cycle, phi0) -> float:
    """δ over the last whole cycle (NaN if there is none)."""
    tb, _ = cycle_boundaries(t, phi, cycle, phi0)
    if tb.size < 2:
        return math.nan
    sel = (t >= tb[-2]) & (t <= tb[-1])
    mean = cycle / (tb[-1] - tb[-2])
    return float((omega[sel].max() - omega[sel].min()) / mean)


def last_cycle_ranges(traj, cycle) -> dict[str, tuple[float, str]]:
    """What drives the speed fluctuation in the last cycle: peak |ε|, and the peak-to-peak swing
    of the gas torque, of the inertia torque ½J′(φ)ω² of (18), and of the gas value of piston 1
    (pressure or force, as applied: the governor's fuel included)."""
    phi = traj["phi"]
    sel = phi >= phi[-1] - cycle
    if sel.sum() < 3:
        return {}
    inertia = 0.5 * traj["dJ_dphi"][sel] * traj["omega"][sel] ** 2
    gas1 = traj["p_1"][sel] if "p_1" in traj else np.zeros(1)  # (the fuel is applied in p_1)
    swing = lambda v: float(v.max() - v.min())  # noqa: E731
    return {"epsilon_peak_last_cycle": (float(np.abs(traj["epsilon"][sel]).max()), "rad/s^2"),
            "M_gas_swing_last_cycle": (swing(traj["M_gas"][sel]), "N m"),
            "M_inertia_swing_last_cycle": (swing(inertia), "N m"),
            "gas_1_swing_last_cycle": (swing(gas1), "Pa or N")}


class NoWholeCycle(ValueError):
    """The trajectory holds no whole engine cycle, which a last-cycle analysis needs."""


def last_cycle_window(t: NDArray[np.float64], phi: NDArray[np.float64], cycle: float,
                      phi0: float) -> tuple[NDArray[np.bool_], float]:
    """The samples of the last whole cycle counted from φ0, as :func:`cycle_boundaries` counts
    cycles.

    Returns the mask of the samples, the cycle's end marks included (to 1e-9 of the cycle, so
    that a sample on a mark up to rounding counts), and the cycle's start angle [rad]. Only
    samples after the last backward motion count: a run that reversed passes these angles
    twice. Raises :class:`NoWholeCycle` if the run holds no whole cycle.
    """
    _, marks = cycle_boundaries(t, phi, cycle, phi0)
    if marks.size < 2:
        raise NoWholeCycle(f"the run holds no whole cycle of {math.degrees(cycle):g}°")
    a, b = marks[-2], marks[-1]
    tol = 1e-9 * cycle
    back = np.nonzero(np.diff(phi) < 0)[0]
    start = back[-1] + 1 if back.size else 0
    mask = (phi >= a - tol) & (phi <= b + tol)
    mask[:start] = False
    return mask, a
