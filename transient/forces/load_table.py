"""Curves through tabulated points: the tabulated load T(x) of ``[load.table]`` (a torque map
against speed, a torque over the cycle, a trace in time) and the prescribed speed ω(t) of
``[run]``, interpolated as the user chooses.

``"linear"`` joins the points by straight lines (a kink at every point). ``"pchip"`` is the
monotone piecewise cubic Hermite interpolant of Fritsch and Carlson (SIAM J. Numer. Anal. 17
(1980) 238–246), with the slopes of Fritsch and Butland as scipy's
:class:`~scipy.interpolate.PchipInterpolator` computes them: C¹, and between two points it stays
between their values, so data with corners (a plateau after a ramp) are not overshot as a cubic
spline overshoots them. Interpolation error for a smooth f with knot spacing h (de Boor, *A
Practical Guide to Splines*, ch. II, (2.5) and ch. IV): linear ≤ h²/8·max|f″|; pchip O(h³)
where the data are strictly monotone, O(h²) near an extremum, where its slope is set to zero.

A load curve is held as the compiled model holds it
(:func:`transient.core.model.tables.held_curve_value`): knots and a cubic per
interval in ascending powers, its end values held outside the knots. A
curve over the cycle (abscissa ``"angle"``) is periodic: its knots run over one period from the
last point shifted back by the period, so that the interval across the cycle's end is one piece.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Distinct corners of a load in time (a schedule's abscissae, a trace's knots) closer than
#: this (relative to max(1, |t|)) are refused or taken as one: the event search could not tell
#: them apart (``transient.core.stepper.events.ON_LEVEL`` is 1e-12).
SCHEDULE_MIN_GAP = 1e-9

#: The interpolations a table may ask for.
INTERPOLATIONS = ("linear", "pchip")

#: The abscissae of a tabulated load: the shaft speed, the shaft angle in the cycle, the time.
ABSCISSAE = ("speed", "angle", "time")


def interpolant(x: ArrayLike, y: ArrayLike, interpolation: str):
    """The curve through the points ``(x, y)`` (x strictly increasing, at least 2) as a
    :class:`scipy.interpolate.PPoly`, which can also be differentiated and integrated."""
    from scipy.interpolate import PchipInterpolator, PPoly  # (lazily: a warm start skips scipy)

    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if interpolation == "pchip":
        return PchipInterpolator(x, y)
    if interpolation != "linear":
        raise ValueError(f"unknown interpolation {interpolation!r}; use one of {INTERPOLATIONS}")
    return PPoly(np.vstack([np.diff(y) / np.diff(x), y[:-1]]), x)


@dataclass(frozen=True)
class LoadCurve:
    """A tabulated load as the model holds it.

    ``abscissa``: one of :data:`ABSCISSAE`. ``knots`` float64[n + 1] increasing [rad/s, rad or
    s]; ``coef`` float64[n, 4]: the cubic of interval i in powers of ``x − knots[i]``, ascending
    [N m]. ``period`` [rad]: the cycle of an ``"angle"`` curve (0 otherwise).
    """

    abscissa: str
    knots: NDArray[np.float64]
    coef: NDArray[np.float64]
    period: float = 0.0

    def evaluate(self, x: ArrayLike) -> NDArray[np.float64]:
        """T(x) in numpy, the twin of :func:`transient.core.model.forcing.table_load` (angles wrapped
        into the period, values held beyond the ends)."""
        x = np.asarray(x, dtype=np.float64)
        k = self.knots
        if self.abscissa == "angle":
            x = k[0] + np.mod(x - k[0], self.period)
        xc = np.clip(x, k[0], k[-1])
        i = np.clip(np.searchsorted(k, xc, side="right") - 1, 0, k.size - 2)
        d = xc - k[i]
        c = self.coef[i]
        return c[..., 0] + d * (c[..., 1] + d * (c[..., 2] + d * c[..., 3]))

    @property
    def corners(self) -> NDArray[np.float64]:
        """The abscissae where the curve's derivative (linear) or second derivative (pchip)
        jumps: every knot; for an ``"angle"`` curve the points of the cycle, in [0, period)."""
        if self.abscissa == "angle":
            return np.sort(np.mod(self.knots[1:], self.period))
        return self.knots.copy()


def load_curve(abscissa: str, x: ArrayLike, torque: ArrayLike, interpolation: str,
               period: float = 0.0) -> LoadCurve:
    """The :class:`LoadCurve` through the points ``(x, torque)``.

    ``x`` strictly increasing (the scene reader checks it); for ``"angle"`` in ``[0, period)``,
    the curve closing from the last point to the first one a period later (pchip with the slopes
    of the periodic data, every point an interior one).
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(torque, dtype=np.float64)
    if abscissa != "angle":
        pp = interpolant(x, y, interpolation)
        return LoadCurve(abscissa, x.copy(), _ascending(pp.c), 0.0)
    n = x.size
    # Two points of the neighbouring cycles on each side, so that every slope of the period's
    # knots is pchip's interior formula; the knots kept run from x[-1] − P to x[-1].
    xe = np.concatenate([x[-2:] - period, x, x[:2] + period])
    ye = np.concatenate([y[-2:], y, y[:2]])
    pp = interpolant(xe, ye, interpolation)
    return LoadCurve("angle", xe[1:n + 2].copy(), _ascending(pp.c[:, 1:n + 1]), float(period))


def _ascending(c: NDArray[np.float64]) -> NDArray[np.float64]:
    """scipy's PPoly coefficients (descending powers, one column per interval) as float64[n, 4]
    in ascending powers."""
    out = np.zeros((c.shape[1], 4))
    out[:, :c.shape[0]] = c[::-1].T
    return np.ascontiguousarray(out)
