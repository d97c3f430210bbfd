"""Cylinder gas pressure against the local crank angle, as periodic piecewise-cubic tables.

The gas force of a cylinder with a prescribed indicator diagram depends on the crank angle only,
so it is tabulated once per scene (one idea: the periodic pressure table, built from points,
from a function or from the mixed cycle) and evaluated in the compiled right-hand side by
:func:`transient.core.model.tables.table_eval` (layout in :mod:`transient.core.model.tables`). This module
builds the tables:

* :func:`table_from_points`: from user points (a measured or printed indicator diagram);
* :func:`table_from_function`: from closed forms, piece by piece, with an error estimate;
* :func:`mixed_cycle`: the ideal mixed (Trinkler–Sabathé) cycle of Gots App. 2 (the DIZDN
  printout and table П2.1), with its closed-form loop work.

Angles are local crank angles in radians and pressures are absolute, in Pa. The gas force on
the piston is ``(p - p0)*F_p`` (Gots eq. (33)); the crankcase pressure ``p0`` is applied by the
caller, not here.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from transient.errors import SceneError
from transient.roots import bisect_root

__all__ = [
    "ANGLE_TOL",
    "DEFAULT_STEP",
    "INTERPOLATIONS",
    "IndicatedCycle",
    "MixedCycle",
    "PressureTable",
    "VolumeFunction",
    "assemble_table",
    "cycle_period",
    "deg_text",
    "every_knot_a_corner",
    "gas_exchange_pressures",
    "mixed_cycle",
    "not_a_knot_coef",
    "shift_cubic",
    "table_from_function",
    "table_from_points",
    "volume_at",
    "wrapped_pieces",
]

#: Default knot spacing of :func:`table_from_function` [rad] (0.125°). Measured on the Gots
#: example mixed cycle (``tests/validation/test_mixed_cycle.py``): the midpoint error estimate is
#: 5.2e-10 of p_z and a 16-points-per-interval scan finds 5.7e-10, against the 1e-9 required;
#: 0.25° would give 8.3e-9 (the error, ∝ step⁴, peaks in the last compression interval before
#: the firing TDC). It costs about 2700 knots per 4-stroke cycle, i.e. 11 bisection steps.
DEFAULT_STEP = math.radians(0.125)

#: Interpolation methods accepted by :func:`table_from_points`.
INTERPOLATIONS = ("linear", "pchip", "spline")

#: Angles read from degrees (scene.py converts ``*_deg`` keys) miss 0, the period or a corner by
#: a few ulp; anything closer than this (relative to the period) is snapped onto it.
ANGLE_TOL = 1e-9

PieceFunction = Callable[[NDArray[np.float64]], ArrayLike] | float

#: A cylinder volume V(x) [m³], vectorised over local crank angles x [rad].
VolumeFunction = Callable[[NDArray[np.float64]], ArrayLike]


def deg_text(x: float) -> str:
    """An angle in radians, formatted in degrees for a one-line message."""
    return f"{math.degrees(x):.6g}°"


def cycle_period(strokes: int) -> float:
    """The cycle's length [rad]: 4π for a 4-stroke, 2π for a 2-stroke; a SceneError (gas.strokes)
    for any other number of strokes."""
    if strokes not in (2, 4):
        raise SceneError("gas.strokes", f"strokes = {strokes!r}; use 4 or 2")
    return 2.0 * math.pi * strokes / 2.0


def gas_exchange_pressures(strokes: int, p_intake: float | None, p_exhaust: float | None
                           ) -> tuple[float, float]:
    """The constant intake and exhaust pressures of a 4-stroke [Pa], checked finite and ≥ 0;
    NaN for a 2-stroke, which has no gas-exchange strokes."""
    if strokes != 4:
        return float("nan"), float("nan")

    def absolute(key: str, value: float | None) -> float:
        if value is None or not (np.isfinite(value) and value >= 0.0):
            raise SceneError(key, f"{value!r} Pa; a 4-stroke needs an absolute pressure ≥ 0")
        return float(value)

    return absolute("gas.p_intake", p_intake), absolute("gas.p_exhaust", p_exhaust)


@dataclass(frozen=True, eq=False)
class PressureTable:
    """A periodic curve over one cycle, piecewise cubic between corners.

    The four arrays are passed unchanged to the kernels of :mod:`transient.core.model.tables`;
    treat them as read-only.

    Attributes
    ----------
    knots : NDArray[np.float64], shape (n + 1,)
        Knot angles [rad], strictly increasing from 0 to `period`. Every corner is a knot.
    coef : NDArray[np.float64], shape (n, 4)
        Cubic of knot interval ``i`` in ascending powers of ``x - knots[i]`` [Pa, Pa/rad, ...].
    piece_knot : NDArray[np.int64], shape (m + 1,)
        Knot index of each corner, from 0 to n.
    period : float
        Cycle length [rad]: ``4*pi`` for a 4-stroke, ``2*pi`` for a 2-stroke.
    """

    knots: NDArray[np.float64]
    coef: NDArray[np.float64]
    piece_knot: NDArray[np.int64]
    period: float

    def __post_init__(self) -> None:
        knots = np.ascontiguousarray(self.knots, dtype=np.float64)
        coef = np.ascontiguousarray(self.coef, dtype=np.float64)
        piece_knot = np.ascontiguousarray(self.piece_knot, dtype=np.int64)
        period = float(self.period)
        n = knots.size - 1
        # A malformed table is a programming error, not a scene error: the builders below
        # always produce valid ones.
        if knots.ndim != 1 or n < 1 or not np.all(np.diff(knots) > 0):
            raise ValueError("knots must be a strictly increasing 1-D array of at least 2 angles")
        if knots[0] != 0.0 or knots[-1] != period:
            raise ValueError(f"knots must run from 0 to the period {period!r}, "
                             f"got {knots[0]!r} to {knots[-1]!r}")
        if coef.shape != (n, 4):
            raise ValueError(f"coef must have shape ({n}, 4), got {coef.shape}")
        if (piece_knot.ndim != 1 or piece_knot.size < 2 or piece_knot[0] != 0
                or piece_knot[-1] != n or not np.all(np.diff(piece_knot) > 0)):
            raise ValueError(f"piece_knot must increase strictly from 0 to {n}")
        object.__setattr__(self, "knots", knots)
        object.__setattr__(self, "coef", coef)
        object.__setattr__(self, "piece_knot", piece_knot)
        object.__setattr__(self, "period", period)

    @property
    def corners(self) -> NDArray[np.float64]:
        """Corner angles [rad], including 0 and the period; shape (m + 1,)."""
        return self.knots[self.piece_knot]

    @property
    def n_pieces(self) -> int:
        """Number of pieces m."""
        return self.piece_knot.size - 1

    def wrap(self, x: ArrayLike) -> NDArray[np.float64]:
        """Angles reduced into ``[0, period)`` (twin of :func:`~transient.core.model.tables.wrap_angle`)."""
        x = np.asarray(x, dtype=np.float64)
        y = x - self.period * np.floor(x / self.period)
        y = np.where(y >= self.period, y - self.period, y)
        return np.where(y < 0.0, 0.0, y)

    def piece_of(self, x: ArrayLike) -> NDArray[np.int64]:
        """Piece index of angles in ``[0, period)`` (twin of :func:`~transient.core.model.tables.find_piece`)."""
        j = np.searchsorted(self.corners, np.asarray(x, dtype=np.float64), side="right") - 1
        return np.clip(j, 0, self.n_pieces - 1)

    def evaluate(self, x: ArrayLike, piece: ArrayLike | None = None
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Value and slope, vectorised with plain numpy (twin of the compiled kernels).

        Parameters
        ----------
        x : array_like
            Angles [rad].
        piece : array_like of int, optional
            If given, `x` is not wrapped and each value uses the polynomials of its `piece`,
            extrapolated outside it, as :func:`~transient.core.model.tables.table_eval` does.
            If omitted, `x` is wrapped into the cycle and the piece is the one containing it
            (a corner belongs to the piece that starts there, i.e. the right limit of a jump).

        Returns
        -------
        value : NDArray[np.float64]
            Pressure [Pa], shaped like `x`.
        slope : NDArray[np.float64]
            dp/dx [Pa/rad].
        """
        if piece is None:
            x = self.wrap(x)
            piece = self.piece_of(x)
        else:
            x = np.asarray(x, dtype=np.float64)
            piece = np.asarray(piece, dtype=np.int64)
        x, piece = np.broadcast_arrays(x, piece)
        i = np.searchsorted(self.knots, x, side="right") - 1
        i = np.clip(i, self.piece_knot[piece], self.piece_knot[piece + 1] - 1)
        d = x - self.knots[i]
        c = self.coef[i]
        value = c[..., 0] + d * (c[..., 1] + d * (c[..., 2] + d * c[..., 3]))
        slope = c[..., 1] + d * (2.0 * c[..., 2] + 3.0 * d * c[..., 3])
        return value, slope

    def __call__(self, x: ArrayLike) -> NDArray[np.float64]:
        """Pressure [Pa] at angles `x` [rad], wrapped into the cycle; right limit at a jump."""
        return self.evaluate(x)[0]

    def interior_points(self, per_interval: int = 1) -> NDArray[np.float64]:
        """Points strictly inside every knot interval, ``per_interval`` of them, evenly spaced.

        With ``per_interval = 1`` these are the interval midpoints, where the error of a cubic
        interpolant is largest. They never fall on a corner, so a reference function with jumps
        can be compared there without choosing a side.
        """
        frac = (np.arange(per_interval) + 0.5) / per_interval
        h = np.diff(self.knots)
        return (self.knots[:-1, None] + h[:, None] * frac[None, :]).ravel()

    def max_abs_error(self, f: Callable[[NDArray[np.float64]], ArrayLike],
                      per_interval: int = 1) -> float:
        """Largest ``|table - f|`` [Pa] over :meth:`interior_points`.

        Parameters
        ----------
        f : callable
            Vectorised reference ``f(x)`` over the whole cycle, x in [0, period) [rad].
        per_interval : int
            Sample points per knot interval.
        """
        x = self.interior_points(per_interval)
        return float(np.max(np.abs(self(x) - np.asarray(f(x), dtype=np.float64))))


# ----------------------------------------------------------------------------------------
# Building tables
# ----------------------------------------------------------------------------------------

def shift_cubic(c: NDArray[np.float64], h: float) -> NDArray[np.float64]:
    """Coefficients of ``q(e) = p(e + h)`` for the ascending cubic ``p`` (``c`` of shape (4,) or
    (4, k) with h of shape (k,)): a piece extrapolated to its corner, or a table moved onto other
    knots."""
    c0, c1, c2, c3 = c
    return np.array([c0 + h * (c1 + h * (c2 + h * c3)),
                     c1 + h * (2.0 * c2 + 3.0 * h * c3),
                     c2 + 3.0 * h * c3,
                     c3])


def _ppoly_coef(interp) -> NDArray[np.float64]:
    """Ascending local coefficients (k, 4) from a scipy cubic PPoly (``c`` is descending)."""
    return np.ascontiguousarray(interp.c[::-1].T, dtype=np.float64)


def _tridiagonal_solve(lower, diag, upper, rhs):
    """x with A x = rhs for the tridiagonal A (``lower[i] = A[i+1, i]``, ``upper[i] = A[i, i+1]``),
    by Gaussian elimination without pivoting (the Thomas algorithm).

    Written for the not-a-knot spline's system (:func:`not_a_knot_coef`) so that building a
    table does not import scipy.linalg, a sizeable part of a warm start. Without pivoting it is
    stable there: once the
    first row is eliminated every row is diagonally dominant (interior rows 2(h₀ + h₁) against
    h₀ + h₁ off the diagonal, and the first row's elimination leaves h₀ + h₁ against h₀), so
    every pivot exceeds its row's upper element, and the last row's multiplier is below 1. The
    tests compare it with scipy.linalg.solve_banded (LU with partial pivoting).
    """
    diag = diag.copy()
    rhs = rhs.copy()
    for i in range(1, diag.size):
        w = lower[i - 1] / diag[i - 1]
        diag[i] -= w * upper[i - 1]
        rhs[i] -= w * rhs[i - 1]
    x = np.empty(diag.size)
    x[-1] = rhs[-1] / diag[-1]
    for i in range(diag.size - 2, -1, -1):
        x[i] = (rhs[i] - upper[i] * x[i + 1]) / diag[i]
    return x


def not_a_knot_coef(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    """Ascending local coefficients (k, 4) of the not-a-knot cubic spline through (x, y): the
    curve of :class:`scipy.interpolate.CubicSpline` (``bc_type="not-a-knot"``; its algorithm: the
    knots' slopes from one tridiagonal system), which the tests compare it with.

    Written out because importing scipy.interpolate (it imports scipy.optimize) and
    scipy.linalg, for a banded solver (``_tridiagonal_solve``), would be a sizeable part of a
    warm ``transient run``. With 3 points it is the parabola through them, with 2 the straight
    line (CubicSpline's choices there).
    """
    dx = np.diff(x)
    slope = np.diff(y) / dx
    n = x.size
    if n == 2:
        s = np.array([slope[0], slope[0]])
    elif n == 3:
        # one parabola: its slopes at the ends and the middle (CubicSpline's 3-point case)
        A = np.array([[1.0, 1.0, 0.0],
                      [dx[1], 2.0 * (dx[0] + dx[1]), dx[0]],
                      [0.0, 1.0, 1.0]])
        b = np.array([2.0 * slope[0], 3.0 * (dx[0] * slope[1] + dx[1] * slope[0]),
                      2.0 * slope[1]])
        s = np.linalg.solve(A, b)
    else:
        # C² at the interior knots: dx_i s_{i-1} + 2(dx_{i-1} + dx_i) s_i + dx_{i-1} s_{i+1} = …
        lower = np.append(dx[1:], 0.0)
        diag = np.empty(n)
        diag[1:-1] = 2.0 * (dx[:-1] + dx[1:])
        upper = np.insert(dx[:-1], 0, 0.0)
        b = np.empty(n)
        b[1:-1] = 3.0 * (dx[1:] * slope[:-1] + dx[:-1] * slope[1:])
        # not-a-knot: the third derivative continuous at x_1 and at x_{n-2}, eliminated to
        # keep the system tridiagonal
        d = x[2] - x[0]
        diag[0], upper[0] = dx[1], d
        b[0] = ((dx[0] + 2.0 * d) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d
        d = x[-1] - x[-3]
        diag[-1], lower[-1] = dx[-2], d
        b[-1] = (dx[-1] ** 2 * slope[-2] + (2.0 * d + dx[-1]) * dx[-2] * slope[-1]) / d
        s = _tridiagonal_solve(lower, diag, upper, b)
    # each interval's cubic Hermite polynomial from its end values and slopes
    t = (s[:-1] + s[1:] - 2.0 * slope) / dx
    return np.column_stack([y[:-1], s[:-1], (slope - s[:-1]) / dx - t, t / dx])


def _piece_coef(x: NDArray[np.float64], y: NDArray[np.float64], a: float, b: float,
                interpolation: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Knots and coefficients of one piece [a, b] interpolating (x, y), a <= x[0] < ... <= b.

    If the first (last) data point is inside the piece, the first (last) polynomial is
    extrapolated to the corner: a corner may lie between samples.
    """
    if interpolation == "linear":
        coef = np.zeros((x.size - 1, 4))
        coef[:, 0] = y[:-1]
        coef[:, 1] = np.diff(y) / np.diff(x)
    elif interpolation == "pchip":
        from scipy.interpolate import PchipInterpolator  # (lazily: start-up time)

        coef = _ppoly_coef(PchipInterpolator(x, y))
    else:
        coef = not_a_knot_coef(x, y)
    knots = x.copy()
    if x[0] > a:
        coef = np.vstack([shift_cubic(coef[0], a - x[0]), coef])
        knots = np.concatenate([[a], knots])
    if x[-1] < b:
        coef = np.vstack([coef, shift_cubic(coef[-1], x[-1] - x[-2])])
        knots = np.concatenate([knots, [b]])
    knots[0], knots[-1] = a, b
    return knots, coef


def assemble_table(pieces: Sequence[tuple[NDArray[np.float64], NDArray[np.float64]]],
                   period: float) -> PressureTable:
    """One table from per-piece (knots, coef), pieces in order and sharing their corners."""
    knots = [pieces[0][0]]
    piece_knot = [0, pieces[0][1].shape[0]]
    for k, _ in pieces[1:]:
        knots.append(k[1:])
        piece_knot.append(piece_knot[-1] + k.size - 1)
    return PressureTable(knots=np.concatenate(knots),
                         coef=np.vstack([c for _, c in pieces]),
                         piece_knot=np.array(piece_knot, dtype=np.int64),
                         period=period)


def _check_corners(corners: ArrayLike, period: float, key: str | None) -> NDArray[np.float64]:
    """Sorted unique interior corners [rad]; one outside (0, period) raises.

    With a scene `key` the error is a :class:`SceneError` (user input), otherwise a
    :class:`ValueError` (a programming error in a caller that builds corners itself).
    """
    c = np.unique(np.asarray(corners, dtype=np.float64).ravel())
    for ci in c:
        if not (np.isfinite(ci) and 0.0 < ci < period):
            msg = (f"corner at {deg_text(ci)} is outside (0°, {deg_text(period)}); corners must "
                   f"lie strictly inside the cycle (0° and {deg_text(period)} are corners "
                   "already)")
            raise SceneError(key, msg) if key else ValueError(msg)
    return c


def table_from_points(phi: ArrayLike, p: ArrayLike, period: float, corners: ArrayLike = (),
                      interpolation: str = "pchip") -> PressureTable:
    """Table through user points (a measured or printed indicator diagram).

    Parameters
    ----------
    phi : array_like, shape (k,)
        Local crank angles [rad], non-decreasing, first 0 and last `period`. An angle given
        exactly twice at a declared corner is a jump there: the first of the pair is the value
        left of the corner, the second the value right of it.
    p : array_like, shape (k,)
        Absolute pressures [Pa], ≥ 0.
    period : float
        Cycle length [rad] (``4*pi`` or ``2*pi``).
    corners : array_like
        Interior corner angles [rad], in (0, period): where the curve may jump or kink. A
        corner between two samples is allowed; both neighbouring pieces then extrapolate to it.
    interpolation : {"linear", "pchip", "spline"}
        Per piece: straight lines; shape-preserving C¹ cubic (no overshoot,
        :class:`scipy.interpolate.PchipInterpolator`); or C² not-a-knot cubic spline (the
        curve of :class:`scipy.interpolate.CubicSpline`, a line if the piece has 2 points).
        Pieces are interpolated independently, so nothing is smoothed across a corner.

    Returns
    -------
    PressureTable
        With every knot a corner (:func:`every_knot_a_corner`), declared or not.

    Raises
    ------
    SceneError
        ``gas.p`` if the lengths differ or a pressure is negative or not finite;
        ``gas.corners_deg`` if a corner is outside (0, period); ``gas.phi_deg`` if the angles
        do not cover [0, period], do not increase, repeat an angle that is not a declared corner
        (or more than twice), or leave a piece with fewer than 2 points;
        ``gas.interpolation`` for an unknown method.
    """
    phi = np.array(phi, dtype=np.float64).ravel()
    p = np.array(p, dtype=np.float64).ravel()
    period = float(period)
    if interpolation not in INTERPOLATIONS:
        raise SceneError("gas.interpolation",
                         f"unknown interpolation {interpolation!r}; use one of {INTERPOLATIONS}")
    if p.size != phi.size:
        raise SceneError("gas.p", f"has {p.size} values but gas.phi_deg has {phi.size}; "
                                  "give one pressure per angle")
    if phi.size < 2 or not np.all(np.isfinite(phi)):
        raise SceneError("gas.phi_deg", f"needs at least 2 finite angles from 0° to "
                                        f"{deg_text(period)}, got {phi.size}")
    bad = np.flatnonzero(~np.isfinite(p) | (p < 0.0))
    if bad.size:
        k = bad[0]
        raise SceneError("gas.p", f"pressure {p[k]:.6g} Pa at {deg_text(phi[k])} is not allowed; "
                                  "pressures are absolute, finite and ≥ 0")
    tol = ANGLE_TOL * max(period, 1.0)
    if abs(phi[0]) > tol or abs(phi[-1] - period) > tol:
        raise SceneError("gas.phi_deg", f"angles run from {deg_text(phi[0])} to "
                                        f"{deg_text(phi[-1])}; they must start at 0° and end at "
                                        f"{deg_text(period)}")
    phi[0], phi[-1] = 0.0, period
    corners = _check_corners(corners, period, "gas.corners_deg")
    # Snap angles converted from degrees onto the corner they mean.
    for c in corners:
        phi[np.abs(phi - c) <= tol] = c

    steps = np.diff(phi)
    back = np.flatnonzero(steps < 0.0)
    if back.size:
        k = back[0]
        raise SceneError("gas.phi_deg", f"angles must increase, but {deg_text(phi[k + 1])} follows "
                                        f"{deg_text(phi[k])}")
    for k in np.flatnonzero(steps == 0.0):
        a = phi[k]
        if a not in corners:
            raise SceneError("gas.phi_deg", f"{deg_text(a)} is repeated but is not in "
                                            "gas.corners_deg; repeat an angle only at a declared "
                                            "corner (a jump)")
        if np.count_nonzero(phi == a) > 2:
            raise SceneError("gas.phi_deg", f"{deg_text(a)} is given more than twice; a jump takes "
                                            "exactly two values, left then right")

    ends = np.concatenate([[0.0], corners, [period]])
    # Point index range [first[j], last[j]] of each piece. A single point on a corner is shared
    # by both pieces (continuous there); a repeated one is split (a jump).
    first = [0]
    last = []
    for c in corners:
        lo = int(np.searchsorted(phi, c, side="left"))
        hi = int(np.searchsorted(phi, c, side="right"))
        if hi - lo == 2:
            last.append(lo)
            first.append(lo + 1)
        elif hi - lo == 1:
            last.append(lo)
            first.append(lo)
        else:
            last.append(lo - 1)
            first.append(lo)
    last.append(phi.size - 1)

    pieces = []
    for j in range(ends.size - 1):
        s, e = first[j], last[j]
        if e - s + 1 < 2:
            raise SceneError("gas.phi_deg",
                             f"the piece from {deg_text(ends[j])} to {deg_text(ends[j + 1])} has "
                             f"{max(e - s + 1, 0)} point(s); each piece between corners needs "
                             "at least 2")
        pieces.append(_piece_coef(phi[s:e + 1], p[s:e + 1], ends[j], ends[j + 1], interpolation))
    return every_knot_a_corner(assemble_table(pieces, period))


def every_knot_a_corner(table: PressureTable) -> PressureTable:
    """The same curve with every knot a corner, hence a breakpoint of the stepper.

    Sparse user points leave a derivative that jumps at each knot, below the order the stepper
    relies on (DOP853: 8): the slope for ``"linear"`` (C⁰), the second derivative for
    ``"pchip"`` (C¹) and the third for ``"spline"`` (C², whose jump is of the size of the curve's
    own third derivative where knots are sparse). A step across a jump in the k-th derivative
    has a local error ∝ jump·h^(k+1), which an order-8 pair's error control follows poorly: a
    run's error stayed far above rtol (README, *How it integrates*). Stopping on every knot
    costs one segment per knot and cylinder. (The dense knots of :func:`table_from_function`
    approximate a smooth curve, their jumps are O(step) small, and they stay inside steps.)
    """
    n = table.knots.size - 1
    return PressureTable(knots=table.knots, coef=table.coef,
                         piece_knot=np.arange(n + 1, dtype=np.int64), period=table.period)


def table_from_function(f: PieceFunction | list[PieceFunction] | tuple[PieceFunction, ...],
                        period: float, corners: ArrayLike = (), step: float = DEFAULT_STEP
                        ) -> tuple[PressureTable, float]:
    """Tabulate closed forms piece by piece with a not-a-knot cubic spline.

    Parameters
    ----------
    f : callable, float, or list or tuple of them
        Either one vectorised ``f(x)`` for the whole cycle (continuous at the corners, which
        may be kinks), or one entry per piece. An entry may be a float: a constant piece is
        stored as a single interval. Each callable must be smooth on its closed piece: it is
        evaluated at both ends, so with a jump at a corner give one function per piece.
    period : float
        Cycle length [rad].
    corners : array_like
        Interior corner angles [rad], in (0, period).
    step : float
        Largest knot spacing [rad]; each piece gets the fewest equal intervals not longer than
        it. The default :data:`DEFAULT_STEP` (0.125°) meets a relative error of 1e-9 on the Gots
        mixed cycle.

    Returns
    -------
    table : PressureTable
    rel_error : float
        Estimated interpolation error: the largest ``|table - f|`` at the midpoints between
        knots, where a cubic spline's error peaks inside a piece, divided by the largest ``|f|``
        seen. The end intervals of a not-a-knot spline peak off-centre: on the Gots cycle a
        scan with 8 points per interval finds 8 % more than this estimate.

    Raises
    ------
    ValueError
        For a corner outside (0, period), a non-positive step, a wrong number of piece
        functions or non-finite values.
    """
    period = float(period)
    corners = _check_corners(corners, period, None)
    ends = np.concatenate([[0.0], corners, [period]])
    m = ends.size - 1
    if not step > 0.0:
        raise ValueError(f"step must be positive, got {step!r}")
    funcs = list(f) if isinstance(f, (list, tuple)) else [f] * m
    if len(funcs) != m:
        raise ValueError(f"{len(funcs)} piece functions for {m} pieces")

    pieces = []
    err = 0.0
    scale = 0.0
    for j, fj in enumerate(funcs):
        a, b = ends[j], ends[j + 1]
        if not callable(fj):
            value = float(fj)
            if not np.isfinite(value):
                raise ValueError(f"piece {j} constant is not finite: {value!r}")
            pieces.append((np.array([a, b]), np.array([[value, 0.0, 0.0, 0.0]])))
            scale = max(scale, abs(value))
            continue
        n = max(1, math.ceil((b - a) / step * (1.0 - 1e-12)))
        x = np.linspace(a, b, n + 1)
        y = np.asarray(fj(x), dtype=np.float64)
        if y.shape != x.shape or not np.all(np.isfinite(y)):
            raise ValueError(f"piece {j} ({deg_text(a)} to {deg_text(b)}) gave non-finite or "
                             "misshapen values")
        knots, coef = _piece_coef(x, y, a, b, "spline")
        pieces.append((knots, coef))
        h = 0.5 * np.diff(knots)
        xm = knots[:-1] + h
        fm = np.asarray(fj(xm), dtype=np.float64)
        tm = coef[:, 0] + h * (coef[:, 1] + h * (coef[:, 2] + h * coef[:, 3]))
        err = max(err, float(np.max(np.abs(tm - fm))))
        scale = max(scale, float(np.max(np.abs(y))), float(np.max(np.abs(fm))))
    return assemble_table(pieces, period), (err / scale if scale > 0.0 else err)


# ----------------------------------------------------------------------------------------
# The ideal mixed cycle
# ----------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class IndicatedCycle(PressureTable):
    """A pressure table of one cylinder's whole cycle with its indicated loop work, and what
    follows from the work alone (shared by the mixed and the Wiebe cycle).

    Subclasses give the swept volume ``v_h`` [m³].

    Attributes
    ----------
    work : float
        Indicated loop work ∮p dV per cycle [J] (pumping included).
    """

    work: float

    if TYPE_CHECKING:  # (a field of some subclasses: a property here would refuse their value)
        @property
        def v_h(self) -> float:
            """Swept volume [m³]."""

    @property
    def mean_torque(self) -> float:
        """Mean indicated torque of one cylinder [N·m]: the loop work per shaft angle of a cycle."""
        return self.work / self.period

    @property
    def mean_pressure(self) -> float:
        """Mean indicated pressure [Pa]: the loop work over the swept volume ``v_h``."""
        return self.work / self.v_h


@dataclass(frozen=True, eq=False)
class MixedCycle(IndicatedCycle):
    """Pressure table of an ideal mixed cycle, with its closed-form quantities.

    A :class:`PressureTable` (use it wherever one is expected) plus what :func:`mixed_cycle`
    computed from the closed forms. Volumes in m³, pressures in Pa, angles in rad, work in J.

    Attributes
    ----------
    work : float
        Indicated loop work ∮p dV per cycle [J], from the closed forms (pumping included).
    p_c : float
        End-of-compression pressure ``p_a*(V_a/V_c)**n1`` [Pa] (= ``p_a*ε**n1``).
    p_b : float
        End-of-expansion pressure ``p_z*(V_z/V_b)**n2`` [Pa].
    angle_z : float
        Local angle [rad] where the isobar ends (``V = ρ*V_c``); a corner unless ρ = 1.
    v_c, v_a, v_z, v_b : float
        Clearance volume, volume at the compression start, at the isobar end and at the
        expansion end [m³].
    strokes : int
        2 or 4.
    interpolation_error : float
        Relative tabulation error estimate returned by :func:`table_from_function`.
    motored : PressureTable
        The motored cycle (no fuel) on the same corners: the closed part on the
        compression polytrope both ways, p_a·(V_a/V)^n1, and the same gas exchange
        (:func:`mixed_cycle`, *Part load*).
    """

    p_c: float
    p_b: float
    angle_z: float
    v_c: float
    v_a: float
    v_z: float
    v_b: float
    strokes: int
    interpolation_error: float
    motored: PressureTable

    @property
    def v_h(self) -> float:
        """Swept volume ``V_a - V_c`` [m³] (the compression starts at a BDC)."""
        return self.v_a - self.v_c


def volume_at(volume: VolumeFunction, x: float) -> float:
    """``volume`` at one angle, through its vectorised interface."""
    return float(np.asarray(volume(np.array([x], dtype=np.float64)), dtype=np.float64).ravel()[0])


def mixed_cycle(volume: VolumeFunction, *, compression_ratio: float,
                p_a: float, n1: float, p_z: float, rho: float, n2: float,
                p_intake: float | None = None, p_exhaust: float | None = None, strokes: int = 4,
                step: float = DEFAULT_STEP,
                dead_centres: tuple[float, float] = (0.0, math.pi)) -> MixedCycle:
    """Ideal mixed (Trinkler–Sabathé) cycle tabulated against the local crank angle.

    The indicator diagram of Gots App. 2 (table П2.1: travel and volume by (1), the compression
    polytrope n₁, the isobar p_z, the expansion polytrope n₂, constant gas-exchange pressures as
    in table П4.1), with the volume supplied by the mechanism. For a **4-stroke** the
    angle convention is the Gots tables' one: x = 0 is the gas-exchange TDC and x = 2π (360°)
    the firing TDC; the period is 4π. With V_a = V(π) and V_c = V(2π):

    ====================  ==========================================================
    0 → π                 intake, ``p_intake``
    π → 2π                compression polytrope ``p_a*(V_a/V)**n1``, ending at p_c
    2π                    isochoric jump p_c → p_z (a corner)
    2π → x_z              isobar ``p_z`` until ``V = ρ*V_c`` (x_z solved; a corner)
    x_z → 3π              expansion polytrope ``p_z*(V_z/V)**n2``, ending at p_b
    3π → 4π               exhaust, ``p_exhaust``; jump to ``p_intake`` at 4π ≡ 0
    ====================  ==========================================================

    For a **2-stroke** (period 2π) the firing TDC is x = 0, with V_c = V(0) and V_a = V(π):
    jump to p_z at 0, isobar to x_z, expansion to π; at π (BDC) the cylinder is scavenged
    instantaneously to ``p_a`` (a jump, no pumping loop), then compression from π back to 2π.
    `p_intake` and `p_exhaust` are not used.

    With an offset crank the dead centres lie off 0 and π (`dead_centres`, t and b): the
    compression starts at b, the firing TDC is at 2π + t (4-stroke) or t (2-stroke), the
    expansion ends at 2π + b (4-stroke) or b, so that V_a and V_c are the cylinder's largest and
    least volume; the table keeps its angle 0 and the pieces wrap across it.

    **Part load and misfire.** The cycle's heat release follows from its pressure by the first
    law of one ideal-gas zone, V dp = (k − 1) δQ − k p dV, with the adiabatic exponent k. The
    compression is the cycle's one process without heat release, so k = n₁ (the model holds no
    other). The full-load cycle then releases Q_v = V_c (p_z − p_c)/(n₁ − 1) at the firing TDC,
    δQ = n₁/(n₁ − 1)·p_z dV on the isobar and δQ = (n₁ − n₂)/(n₁ − 1)·p dV on the expansion
    (the afterburning that an n₂ below n₁ stands for). The first law is linear in (p, Q) from
    the common start p_a at V_a, so a cycle that burns f times the heat at every angle (the
    combustion's timing fixed, its heat scaled, as for the Wiebe model) has exactly
    p_f = p_mot + f·(p_full − p_mot), where p_mot is the cycle without heat: the compression
    polytrope both ways, p_a·(V_a/V)^n₁ over the whole closed part (its closed loop encloses no
    work; the pumping loop is left). Its peak is p_z(f) = p_c + f·(p_z − p_c), at the firing
    TDC; the heat addition still ends at V = ρ·V_c, but the pressure falls along it from
    p_z(f) (the isobar is one at f = 1 only). Keeping the isobar at part load, with ρ falling
    too, would make the pressure non-linear in f, and the governor's continuous command would
    need a cycle per fuel level. (Expanding the motored cycle on n₂ instead would leave it above
    its compression and give work from no fuel whenever n₂ < n₁.) ``motored`` is that p_mot.

    Parameters
    ----------
    volume : callable
        Vectorised ``V(x)`` [m³] of the cylinder at local crank angle x [rad].
    compression_ratio : float
        ε; must equal ``V_a/V_c`` of `volume` (largest over least volume) to 1e-9 relative.
    p_a : float
        Pressure at the start of compression [Pa] (Gots App. 2: 0.1436 MPa).
    n1 : float
        Compression polytropic exponent, > 1 (App. 2: 1.368).
    p_z : float
        Maximum (combustion) pressure [Pa], ≥ p_c (App. 2: 10.5 MPa).
    rho : float
        Pre-expansion ratio ρ = V_z/V_c, 1 ≤ ρ < V_b/V_c; ρ = 1 gives no isobar (App. 2 prints
        1.699, but its isobar 360°–380° has the geometric 1.671: data/README.md).
    n2 : float
        Expansion polytropic exponent, > 1 (App. 2: 1.228).
    p_intake, p_exhaust : float, optional
        Constant intake and exhaust pressures [Pa], required for a 4-stroke (Gots П4.1: 0.165
        and 0.182 MPa).
    strokes : {4, 2}
        Cycle type.
    step : float
        Knot spacing of the tabulation [rad], see :func:`table_from_function`.
    dead_centres : (float, float)
        Local angles [rad] of top and bottom dead centre, near 0 and π
        (``Mechanism.dead_centre_angles``).

    Returns
    -------
    MixedCycle
        The table (a :class:`PressureTable`) with the closed-form loop work
        ``W = p_in(V_a - V_c) + (p_a V_a - p_c V_c)/(n1 - 1) + p_z(V_z - V_c)
        + (p_z V_z - p_b V_b)/(n2 - 1) + p_ex(V_c - V_b)`` (polytrope work
        ``(p1 V1 - p2 V2)/(n - 1)``; the intake and exhaust terms are the pumping loop, absent
        for a 2-stroke), p_c, p_b, the isobar end angle and the motored cycle on the same
        corners.

    Raises
    ------
    SceneError
        ``gas.compression_ratio`` if the geometry gives another V_a/V_c (both are quoted);
        ``gas.strokes``, ``gas.p_a``, ``gas.p_z``, ``gas.n1``, ``gas.n2``, ``gas.rho``,
        ``gas.p_intake``, ``gas.p_exhaust`` for values out of range.
    """
    period = cycle_period(strokes)
    for key, value in (("gas.p_a", p_a), ("gas.p_z", p_z)):
        if not (np.isfinite(value) and value > 0.0):
            raise SceneError(key, f"{value!r} Pa; an absolute pressure must be finite and > 0")
    for key, value in (("gas.n1", n1), ("gas.n2", n2)):
        # n = 1 (isothermal) would need the logarithmic work; real engines have 1.2-1.4.
        if not (np.isfinite(value) and value > 1.0):
            raise SceneError(key, f"polytropic exponent {value!r}; it must be > 1")
    p_intake, p_exhaust = gas_exchange_pressures(strokes, p_intake, p_exhaust)
    if not (np.isfinite(compression_ratio) and compression_ratio > 1.0):
        raise SceneError("gas.compression_ratio", f"{compression_ratio!r}; it must be > 1")

    # Angles of the firing TDC, of the BDC that ends the expansion and of the BDC where the
    # compression starts (the same dead centre a cycle earlier).
    tdc, bdc = dead_centres
    shift = 2.0 * math.pi if strokes == 4 else 0.0
    x_tdc, x_bdc, x_start = tdc + shift, bdc + shift, bdc
    v_c = volume_at(volume, x_tdc)
    v_a = volume_at(volume, x_start)
    v_b = volume_at(volume, x_bdc)
    if not (v_c > 0.0 and v_a > v_c):
        raise SceneError("gas.compression_ratio",
                         f"the volume gives V({deg_text(x_start)}) = {v_a:.6g} m³ at bottom and "
                         f"V({deg_text(x_tdc)}) = {v_c:.6g} m³ at top dead centre; need "
                         f"V_a > V_c > 0")
    ratio = v_a / v_c
    if abs(ratio - compression_ratio) > 1e-9 * compression_ratio:
        raise SceneError("gas.compression_ratio",
                         f"the volumes at the dead centres ({deg_text(x_start)}, "
                         f"{deg_text(x_tdc)}) give V_a/V_c = {ratio:.10g}, not the "
                         f"compression_ratio {compression_ratio:.10g}; the clearance volume "
                         f"must be the swept volume/(ε − 1)")
    try:
        p_c = p_a * ratio ** n1
    except OverflowError:  # (an absurd ε or n1: a p_c beyond a double, which p_z cannot reach)
        p_c = math.inf
    if p_z < p_c:
        raise SceneError("gas.p_z", f"p_z = {p_z / 1e6:.6g} MPa is below the compression end "
                                    f"p_c = p_a·ε^n1 = {p_c / 1e6:.6g} MPa (ε = {ratio:.6g}, n1 = "
                                    f"{n1:g}); the mixed cycle needs p_z ≥ p_c")
    v_z = rho * v_c
    if not (np.isfinite(rho) and 1.0 <= rho and v_z < v_b):
        raise SceneError("gas.rho", f"ρ = {rho!r}; it must satisfy 1 ≤ ρ < V_b/V_c = "
                                    f"{v_b / v_c:.6g}")
    p_b = p_z * (v_z / v_b) ** n2

    angle_z = x_tdc
    if rho > 1.0:
        # V rises monotonically from TDC to BDC on a crank slider: bisection finds the crossing
        # to the last bit, so the expansion starts at p_z to ~1e-15 relative.
        angle_z = bisect_root(lambda x: volume_at(volume, x) - v_z, x_tdc, x_bdc)
    # A ρ within rounding of 1 leaves no isobar worth a piece (and no zero-length interval).
    has_isobar = angle_z - x_tdc > 1e-12
    if not has_isobar:
        angle_z = x_tdc

    def compression(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return p_a * (v_a / np.asarray(volume(x), dtype=np.float64)) ** n1

    def expansion(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return p_z * (v_z / np.asarray(volume(x), dtype=np.float64)) ** n2

    # Polytrope work (p1 V1 - p2 V2)/(n - 1) and the isobar p_z (V_z - V_c).
    work = ((p_a * v_a - p_c * v_c) / (n1 - 1.0) + p_z * (v_z - v_c)
            + (p_z * v_z - p_b * v_b) / (n2 - 1.0))
    # Each piece from the angle where it starts; the exhaust ends at the period's end (4π ≡ 0).
    # (the motored cycle's closed part is the compression polytrope throughout, on the same
    # pieces so that both tables share their corners)
    closed: list[tuple[float, PieceFunction]] = [(x_start, compression), (x_tdc, p_z),
                                                 (angle_z, expansion)]
    if not has_isobar:
        closed.pop(1)
    exchange: list[tuple[float, PieceFunction]] = []
    if strokes == 4:
        exchange = [(0.0, float(p_intake)), (x_bdc, float(p_exhaust))]
        # Pumping loop, from the volumes at the same corners the table uses.
        v_0 = volume_at(volume, 0.0)
        v_end = volume_at(volume, period)
        work += p_intake * (v_a - v_0) + p_exhaust * (v_end - v_b)
    funcs, corners = wrapped_pieces(closed + exchange, period)
    table, err = table_from_function(funcs, period, corners, step)
    funcs, _ = wrapped_pieces([(x, compression) for x, _ in closed] + exchange, period)
    motored, _ = table_from_function(funcs, period, corners, step)
    return MixedCycle(knots=table.knots, coef=table.coef, piece_knot=table.piece_knot,
                      period=period, work=work, p_c=p_c, p_b=p_b, angle_z=angle_z, v_c=v_c,
                      v_a=v_a, v_z=v_z, v_b=v_b, strokes=strokes, interpolation_error=err,
                      motored=motored)


def wrapped_pieces(starts: list[tuple[float, PieceFunction]], period: float
                    ) -> tuple[list[PieceFunction], list[float]]:
    """Pieces given by the angles where they start, as :func:`table_from_function` takes them:
    the functions in order over [0, period) and the interior corners. A start off [0, period)
    is taken modulo the period, and the piece running at angle 0 is the last one begun before
    it (a cycle whose dead centre lies before 0 wraps across it)."""
    def wrapped(x: float) -> float:  # (within rounding of the period's ends: its start)
        x = x % period
        return 0.0 if x < 1e-12 * period or x > period * (1.0 - 1e-12) else x

    ordered = sorted(((wrapped(x), f) for x, f in starts), key=lambda item: item[0])
    if ordered[0][0] > 0.0:
        ordered.insert(0, (0.0, ordered[-1][1]))
    return [f for _, f in ordered], [x for x, _ in ordered[1:]]
