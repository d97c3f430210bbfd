"""Order analysis: signals on a uniform crank-angle grid, per-cycle spectra in engine orders, the
piston acceleration with a variable shaft speed, and the odd-harmonic report: one idea, the
orders of a run, from the grid to the report.

**Engine order.** A component of order ν varies as cos(ν φ + θ): ν harmonics per revolution of the
shaft. Over an engine cycle of angle Φ (2π for a 2-stroke, 4π for a 4-stroke engine) the DFT of
``N`` samples per cycle gives the orders ν_k = 2πk/Φ, k = 0 … N/2, i.e. whole orders for Φ = 2π and
half orders for Φ = 4π.

**Why odd orders.** At constant ω the piston acceleration is W = ω² s″(φ). For a central
crank-slider (e = 0), s(φ) = r(1 − cos φ) + l(1 − √(1 − λ² sin²φ)) (Gots (1)–(2)): the root
depends on sin²φ only, so it has period π and only even orders; r cos φ is the only odd term.
Hence W holds orders 1, 2, 4, 6 … and no odd order ≥ 3 (Semenov §2.5, (14), (19)), while the rod
angle β = arcsin(λ sin φ) holds odd orders only (Semenov (33)). When ω varies,

    W = ω² s″(φ) + ε s′(φ),     ε = dω/dt = ω dω/dφ                     (Semenov §4)

and a speed ripple of order q multiplies the kinematic orders 1, 2, 4 … into q ± 1, q ± 2, q ± 4 …:
odd orders ≥ 3 (and, in a 4-stroke engine, half orders) appear that the constant-speed analysis
does not have (Semenov p. 22: "the acceleration will also contain odd harmonics"). Sizes, relative
to the first order, for ω = ω₀(1 + 0.02 cos qφ) and the Gots geometry (λ = 0.3176): q = 3 gives
order 5 = q + 2 at 1.1e-2, 7 = q + 4 at 1.6e-4, 3 = |q − 6| at 3.9e-6; q = 2 gives order 3 = q + 1
at 4.0e-2; q = 1.5 gives orders 0.5, 2.5, 3.5 at 0.9e-2, 3.5e-2, 0.9e-2.

**Offset mechanism.** With e = k·r ≠ 0 (Gots §1.4), sin β = λ(sin φ − k) and the root is no
longer even in sin φ: odd orders appear even at constant ω. To leading order the −⅛λ⁴(sin φ − k)⁴
term of cos β = √(1 − λ²(sin φ − k)²) holds +½kλ⁴ sin³φ ⊃ −⅛kλ⁴ sin 3φ, so
s = y_TDC − r cos φ − l cos β ⊃ ⅛ l k λ⁴ sin 3φ, and the third order of W = ω²s″ relative to the
first is ≈ (9/8)·k·λ³. For λ = 0.3176: exact 3rd/1st = 8.03e-3 and 5th/1st = 4.5e-4 at k = 0.2
(series 7.21e-3), 3.99e-3 and 2.2e-4 at k = 0.1 (series 3.60e-3) (tests/unit/test_orders.py).

**Radial engines** (:mod:`transient.mechanisms.articulated`). The master piston is a central
crank-slider: orders 1, 2, 4 … at constant ω. A slave piston's link pin is A_i = A + r_i e^{iψ_i}
e, A = r e^{iα} the crankpin and e = c − iλ sin α, c = √(1 − λ² sin²α), the master rod's direction
(Semenov §3). In the slave cylinder's frame (axis δ_i) the pin lies at w = A_i e^{−iδ_i}, whose
part across the axis is h = r sin(α − δ_i) + r_i[sin(ψ_i − δ_i)·c − cos(ψ_i − δ_i)·λ sin α], and
the slave piston at X_i = Re w + √(l_i² − h²). Re w holds order 1 (r cos(α − δ_i), λ sin α) and c
(even orders only). With the link pin at the cylinder's own angle, ψ_i = δ_i, the c term leaves
h, so h is of order 1 alone, h² of orders 0 and 2 and the root of even orders: X_i holds order 1
and even orders, and W = ω̄²X″ no odd order ≥ 3, exactly as the master. With ψ_i ≠ δ_i the
cross term of order 1 × c in h² puts odd orders into the slave's motion at constant speed
(tests/unit/test_orders_mechanisms.py shows both).

**Swash plate** (:mod:`transient.mechanisms.swash_plate`). The piston joint B_k turns on the plate
with θ(φ) = −φ + δ(φ), δ the Hooke joint's non-uniformity, of period π, so B_x ∝ cos(θ + ψ_k)
changes sign over half a turn, B_x(φ + π) = −B_x(φ): odd orders only. The rod of length ℓ adds
x_D = B_x − √(ℓ² − h²) ≈ B_x − ℓ + h²/(2ℓ), h the joint's lateral offset from the cylinder axis,
which holds every order: the even orders of a swash-plate piston at constant speed are that rod
term, O(h²/ℓ), and vanish as ℓ → ∞ (the tests show amplitude·ℓ converging). The δ(φ) ripple
(order 2) turns order 1 into 3, 5 …: a large third order (0.16 of the first at α = 21.4°) that is
kinematic, not a speed effect. The cycle is one turn: no half orders.

**Half orders.** Every piston's travel repeats every turn, so at constant speed a 4-stroke
engine's piston accelerations hold no half order; a speed ripple of a half order (a 5-cylinder
radial fires every 144°: order 2.5) puts them in.

Functions
---------
:func:`resample_angle`, :func:`to_angle_grid`
    Resample trajectory columns onto a uniform crank-angle grid of whole cycles.
:func:`order_spectrum`
    Per-cycle amplitude and phase per order (:class:`OrderSpectrum`).
:func:`piston_acceleration`, :func:`piston_inertia_force`, :func:`rod_angular_acceleration`
    Exact kinematics (:func:`transient.analysis.loads.crank_slider.slider_arrays`, the
    vectorised twin of :func:`transient.core.model.crank_slider.slider`) with ω and ε.
:func:`odd_harmonic_report`, :func:`report_for_scene`
    Orders of the piston acceleration of a run against the same engine at its mean speed
    (:class:`OddHarmonicReport`).
:func:`run_orders`, :func:`orders_up_to`, :func:`strongest_orders`
    What ``transient orders`` shows of a run: the spectra of ω per cycle, of the gas torque and
    of the piston acceleration over the last cycle, δ and the cycle-mean speeds
    (:class:`RunOrders`).
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .irregularity import NoWholeCycle, cycle_means, fluctuation
from .loads.crank_slider import slider_arrays

#: Orders closer than this to a whole number are whole orders (the grid gives ν = 2πk/Φ exactly
#: up to rounding).
_ORDER_TOL = 1e-9

#: A run is a run-up (or a run-down) when its cycle-mean speeds span at least this fraction of
#: the highest, and :data:`RUN_UP_CYCLES` cycles or more lie inside the span: its orders are
#: then read against speed (waterfall over speed, Campbell chart, order tracks). Below it the
#: speed hardly sweeps (a steady run, a load step, a misfire pattern: a tenth or less in the
#: shipped cases) and a speed axis would only sort the cycles by their small differences; the
#: run-ups shipped span a quarter and more.
RUN_UP_SPAN = 0.2
#: Cycles a run-up must have inside its span (their mean speeds more than a tenth of the span
#: from either end): a machine that is up to speed within its first cycle or two samples no
#: speed between, and its Campbell chart would be two columns.
RUN_UP_CYCLES = 4


# ------------------------------------------------------------------------------------------------
# Resampling onto a crank-angle grid


def _coincidence(x: NDArray[np.float64], h: float) -> float:
    """Distance [rad] within which two angles of a run are one point: 1e-9 of its sample spacing
    ``h`` (an error of at most 1e-9·h·|dv/dφ| where a sample is taken for the point), and at
    least 16 ulp of its largest angle, for the rounding of angles computed two ways (an output
    sample j·Δφ and a breakpoint k·Φ + φ_b)."""
    return max(1e-9 * h, 16.0 * float(np.spacing(np.max(np.abs(x)))))


def _pieces(x: NDArray[np.float64], cuts: NDArray[np.float64], tol: float
            ) -> list[tuple[int, int, float]]:
    """Split the non-decreasing abscissae ``x`` into runs that are interpolated on their own.

    A run ends at a repeated abscissa (a sample written on both sides of a jump: the left run
    takes the first, the right run the second) and at a cut (a corner of the signal). Samples
    within ``tol`` of a cut are on it: one such sample is the last of one run and the first of
    the next (the signal is continuous there, so it holds both sides' value); two or more split as
    a repeated abscissa does; with none, one run ends at the last sample before the cut and the
    next starts at the first after it. Returns (start, stop, left boundary) per run; a grid point
    belongs to the last run whose left boundary is ≤ it (see :func:`_run_of`).
    """
    breaks = [(float(x[i + 1]), int(i) + 1, int(i) + 1)
              for i in np.nonzero(np.diff(x) == 0.0)[0]]
    for c in cuts:
        lo = int(np.searchsorted(x, c - tol, side="left"))  # first sample on or after the cut
        hi = int(np.searchsorted(x, c + tol, side="right"))  # first sample after it
        if lo == 0 or hi == x.size:
            continue  # nothing on one side of it: the data end there
        breaks.append((float(c), lo + 1 if hi > lo else lo, max(lo, hi - 1)))
    breaks.sort()
    out: list[tuple[int, int, float]] = []
    start, left = 0, -math.inf
    for bound, stop, nxt in breaks:
        if stop > start:
            out.append((start, stop, left))
        start = max(start, nxt)
        left = bound
    out.append((start, x.size, left))
    return out


def _run_of(lefts: NDArray[np.float64], grid: NDArray[np.float64], tol: float, side: str
            ) -> NDArray[np.intp]:
    """Index of the run (left boundaries ``lefts``) each grid point is taken from: a point within
    ``tol`` of a boundary is on it, and takes the run after it (``side="right"``) or the one
    before (``"left"``)."""
    if side == "right":
        return np.searchsorted(lefts, grid + tol, side="right") - 1
    if side == "left":
        return np.searchsorted(lefts, grid - tol, side="left") - 1
    raise ValueError(f"side {side!r}: allowed 'left', 'right'")


def _hermite(x, v, d, g):
    """Piecewise cubic Hermite interpolant of (x, v, dv/dx) at g (extrapolated past the ends)."""
    if x.size == 1:
        return v[0] + d[0] * (g - x[0])
    i = np.clip(np.searchsorted(x, g, side="right") - 1, 0, x.size - 2)
    h = x[i + 1] - x[i]
    t = (g - x[i]) / h
    s = 1.0 - t
    return ((1.0 + 2.0 * t) * s * s * v[i] + t * s * s * h * d[i]
            + t * t * (3.0 - 2.0 * t) * v[i + 1] - t * t * s * h * d[i + 1])


def _spline(x, v, g):
    """Not-a-knot cubic spline (C²) of (x, v) at g; fewer than 4 samples: lower degree."""
    if x.size == 1:
        return np.full(g.shape, v[0])
    from scipy.interpolate import CubicSpline

    return CubicSpline(x, v, bc_type="not-a-knot", extrapolate=True)(g)


def resample_angle(phi: ArrayLike, values: ArrayLike, grid: ArrayLike,
                   dvalues: ArrayLike | None = None, cuts: ArrayLike = (), side: str = "right"
                   ) -> NDArray[np.float64]:
    """Values of a trajectory column at the crank angles ``grid``.

    Parameters
    ----------
    phi : (n,) array
        Sample angles [rad], non-decreasing. A repeated angle (a sample written on both sides of
        a jump) splits the interpolation there: each side uses its own samples.
    values : (n,) array
        The column at those samples.
    grid : (m,) array
        Angles [rad] wanted, within [phi[0], phi[-1]] (outside, the end pieces are extrapolated).
    dvalues : (n,) array, optional
        dv/dφ at the samples (for ω: ε/ω; for t: 1/ω; in general (dv/dt)/ω). With it the
        interpolant is the piecewise cubic Hermite one; without it a not-a-knot cubic spline (C²).
    cuts : array, optional
        Angles [rad] at which the signal has a corner or a jump (the run's breakpoints, e.g.
        ``data.events["breakpoint"][:, 1]``). No interval is interpolated across a cut: grid points
        between the last sample before it and the cut are extrapolated from the samples before,
        those after from the samples after. A sample within rounding of a cut is on it (a
        crank-angle run's output sample j·Δφ falls an ulp or two to either side of a breakpoint
        k·Φ + φ_b that it equals in exact arithmetic): it ends one piece and starts the next
        (the spline sides are then independent; the Hermite interpolant has only the one
        derivative that sample holds, so where dv/dφ jumps on a sample one side keeps an
        O(h·jump) error, and a value that jumps there needs the sample written twice, left and
        right, as a repeated angle).
    side : ``"right"`` or ``"left"``
        Which limit a grid point on a cut or on a repeated angle (within rounding) takes: the
        piece after it (default: a point that starts an interval, as a cycle's first point) or
        the piece before it (a point that ends one, as a cycle's end). A grid point is never
        taken from the piece on its other side.

    Returns
    -------
    (m,) array

    Notes
    -----
    When every grid angle coincides with a sample (a run integrated in crank angle whose output
    spacing divides the grid's, from the same origin; coincidence within 1e-9 of the sample
    spacing or 16 ulp of the angles, which leaves an error ≤ that times |dv/dφ|) the samples are
    returned: no interpolation. The same distance puts a sample on a cut.

    Accuracy otherwise, h the largest sample spacing near the grid point, v⁽⁴⁾ = d⁴v/dφ⁴:

    * Hermite, exact derivatives: |error| ≤ h⁴/384 · max|v⁽⁴⁾| (the remainder
      v⁽⁴⁾(ξ)(φ − φ_i)²(φ − φ_{i+1})²/4!); an error δd in the derivatives adds ≤ (4/27)·h·|δd|.
      A solver's ε is its right-hand side at the output state, consistent with ω to its tolerance.
    * Spline: ≈ (5/384)·h⁴·max|v⁽⁴⁾| in the interior (Hall & Meyer's bound for the complete
      spline; measured ≤ 0.33 of it on random ±40 % meshes); the not-a-knot end conditions
      make it larger within about three intervals of each end of a piece (measured ≤ 1.7× the
      bound; tests/unit/test_orders.py asserts 2×).
    * Extrapolation next to a cut, over at most one interval: ≤ h⁴/6 · max|v⁽⁴⁾| (Hermite).
    * Across a corner that is not given as a cut (a jump J in dv/dφ inside an interval) both
      fall to O(h·J) locally, and the spline spreads it, decaying ~4× per interval.

    A time-domain run sampled every Δt has h ≈ ω Δt: for Δt = 2e-5 s at 400 rad/s, h = 0.008 rad
    and h⁴/384 = 1.1e-11 (rad⁴).
    """
    phi = np.asarray(phi, dtype=float)
    values = np.asarray(values, dtype=float)
    grid = np.asarray(grid, dtype=float)
    if phi.ndim != 1 or phi.shape != values.shape:
        raise ValueError(f"phi and values must be 1-D of one length, got {phi.shape} and "
                         f"{values.shape}")
    if phi.size == 0:
        raise ValueError("no samples to resample")
    step = np.diff(phi)
    if np.any(step < 0):
        raise ValueError("phi must be non-decreasing (take the part after a reversal)")
    d = None if dvalues is None else np.asarray(dvalues, dtype=float)
    if d is not None and d.shape != phi.shape:
        raise ValueError(f"dvalues must have the shape of phi {phi.shape}, got {d.shape}")

    tol = _coincidence(phi, step[step > 0].min() if np.any(step > 0) else 1.0)
    # Coinciding grids: take the samples themselves; of a repeated angle, the side's (the last
    # sample at or before each point for "right", the first at or after it for "left").
    near = np.clip(_run_of(phi, grid, tol, side) + (side == "left"), 0, phi.size - 1)
    if np.all(np.abs(phi[near] - grid) <= tol):
        return values[near].copy()

    out = np.empty(grid.shape)
    pieces = _pieces(phi, np.sort(np.asarray(cuts, dtype=float).ravel()), tol)
    which = _run_of(np.array([p[2] for p in pieces]), grid, tol, side)
    for j, (a, b, _) in enumerate(pieces):
        sel = which == j
        if not np.any(sel):
            continue
        x, v = phi[a:b], values[a:b]
        out[sel] = _spline(x, v, grid[sel]) if d is None else _hermite(x, v, d[a:b], grid[sel])
    return out


def _increasing_part(traj: Mapping[str, NDArray[np.float64]]) -> slice:
    """The samples after the last backward motion (or stop) of φ, where ω > 0."""
    phi = np.asarray(traj["phi"])
    bad = np.diff(phi) < 0
    if "omega" in traj:
        w = np.asarray(traj["omega"])
        bad = bad | (w[1:] <= 0.0)
    back = np.nonzero(bad)[0]
    return slice(back[-1] + 1 if back.size else 0, phi.size)


def cycle_marks(phi: NDArray[np.float64], cycle: float, phi0: float = 0.0
                ) -> NDArray[np.float64]:
    """Angles phi0 + j·cycle of the whole cycles inside [phi[0], phi[-1]] (start and end marks)."""
    if phi.size < 2:
        return np.zeros(0)
    k0 = math.ceil((phi[0] - phi0) / cycle - 1e-12)
    k1 = math.floor((phi[-1] - phi0) / cycle + 1e-12)
    return phi0 + cycle * np.arange(k0, k1 + 1)


def to_angle_grid(traj: Mapping[str, NDArray[np.float64]], names: Sequence[str],
                  samples_per_cycle: int, cycle: float, *, phi0: float = 0.0,
                  cycles: int | None = None, cuts: ArrayLike = (),
                  derivatives: Mapping[str, NDArray[np.float64]] | None = None,
                  closed: bool = False,
                  ) -> tuple[NDArray[np.float64], dict[str, NDArray[np.float64]]]:
    """Trajectory columns on a uniform crank-angle grid of whole cycles.

    Parameters
    ----------
    traj : mapping
        Trajectory columns (``RunData.trajectory``): needs ``phi``; ``omega`` and ``epsilon`` for
        the Hermite derivatives below.
    names : sequence of str
        Columns wanted.
    samples_per_cycle : int
        N, grid points per cycle.
    cycle : float
        Cycle angle Φ [rad] (``scene.mechanism.cycle``).
    phi0 : float
        Cycles start at phi0 + j·Φ (``scene.initial.phi``, as :mod:`.irregularity` counts them).
    cycles : int, optional
        Keep only the last ``cycles`` whole cycles (default: all).
    cuts : array, optional
        Corner angles, see :func:`resample_angle`.
    derivatives : mapping, optional
        dv/dφ per column name, on the trajectory's samples, for columns other than these known
        ones: ``t`` (1/ω), ``omega`` (ε/ω), ``phi`` (the grid itself). Other columns use the
        not-a-knot spline.
    closed : bool
        Add one point, the end of the last cycle (for the ramp of :func:`order_spectrum`'s
        ``detrend``: its ``end``), taken from inside that cycle (``side="left"`` of
        :func:`resample_angle`); every other point starts an interval and takes the right side.

    Returns
    -------
    grid : (n_cycles·N,) array (one more with ``closed``)
        phi0 + Φ(j0 + i/N), i = 0 … n_cycles·N − 1: each cycle's start, not its end (the end is
        the next cycle's start), as the DFT of :func:`order_spectrum` wants.
    values : dict
        name → (n_cycles·N,) array.

    Only the part of the run after its last backward motion (φ decreasing, or ω ≤ 0) is used.
    Raises :class:`~.irregularity.NoWholeCycle` (a ValueError) if it holds no whole cycle.
    """
    part = _increasing_part(traj)
    phi = np.asarray(traj["phi"], dtype=float)[part]
    marks = cycle_marks(phi, cycle, phi0)
    n_cyc = marks.size - 1
    if n_cyc < 1:
        raise NoWholeCycle(f"the run holds no whole cycle of {math.degrees(cycle):g}° from "
                         f"φ0 = {phi0:g} rad (φ from {phi[0] if phi.size else math.nan:.6g} to "
                         f"{phi[-1] if phi.size else math.nan:.6g} rad)")
    if cycles is not None:
        n_cyc = min(n_cyc, int(cycles))
        marks = marks[-n_cyc - 1:]
    n = int(samples_per_cycle)
    j0 = round((marks[0] - phi0) / cycle)
    grid = phi0 + (cycle / n) * np.arange(j0 * n, (j0 + n_cyc) * n + int(closed))
    derivatives = dict(derivatives or {})
    out = {}
    for name in names:
        if name == "phi":
            out[name] = grid.copy()
            continue
        v = np.asarray(traj[name], dtype=float)[part]
        if name in derivatives:
            d = np.asarray(derivatives[name], dtype=float)[part]
        elif name == "t" and "omega" in traj:
            d = 1.0 / np.asarray(traj["omega"], dtype=float)[part]
        elif name == "omega" and "epsilon" in traj:
            d = np.asarray(traj["epsilon"], dtype=float)[part] / v
        else:
            d = None
        out[name] = resample_angle(phi, v, grid[:grid.size - int(closed)], d, cuts)
        if closed:  # the last cycle's end: the limit from inside that cycle
            out[name] = np.append(out[name], resample_angle(phi, v, grid[-1:], d, cuts, "left"))
    return grid, out


# ------------------------------------------------------------------------------------------------
# Spectra in engine orders


@dataclass(frozen=True)
class OrderSpectrum:
    """Per-cycle spectrum of a signal in engine orders.

    Each cycle c is written v(φ) = Σ_k Re[coef[c, k] · exp(i ν_k (φ − φ_c))], φ_c its first grid
    angle: amplitude |coef| and phase arg(coef) of A_k cos(ν_k (φ − φ_c) + θ_k); coef[:, 0] is the
    cycle mean (real). At the Nyquist order (N even, k = N/2) only A cos θ is measurable: coef is
    that real number.

    Attributes
    ----------
    orders : (n_orders,) array
        ν_k = 2πk/Φ [1/rev], k = 0 … N//2.
    coef : (n_cycles, n_orders) complex array
        In the unit of the signal.
    window : str
        ``"none"`` or ``"hann"``.
    drift : (n_cycles,) array
        v(next cycle's start) − v(this cycle's start); for the last cycle v(its end) − v(start)
        when ``end`` was given, else NaN. For a periodic
        signal it is 0. A drift D (a spin-up) is a ramp across the cycle, which the unwindowed DFT
        sees as a sawtooth: it leaks D/(π k) into the amplitude of every harmonic k of the cycle.
    """

    orders: NDArray[np.float64]
    coef: NDArray[np.complex128]
    window: str
    drift: NDArray[np.float64]
    detrend: str = "none"

    @property
    def amplitude(self) -> NDArray[np.float64]:
        return np.abs(self.coef)

    @property
    def phase(self) -> NDArray[np.float64]:
        """[rad], in (−π, π]."""
        return np.angle(self.coef)

    @property
    def mean(self) -> NDArray[np.float64]:
        return self.coef[:, 0].real

    def at(self, order: float) -> NDArray[np.complex128]:
        """coef[:, k] of the order nearest to ``order`` (which must be on the grid of orders)."""
        k = int(round(order / self.orders[1]))
        if not 0 <= k < self.orders.size or abs(self.orders[k] - order) > _ORDER_TOL:
            raise ValueError(f"order {order:g} is not among the orders k·{self.orders[1]:g}, "
                             f"k = 0 … {self.orders.size - 1}")
        return self.coef[:, k]


def order_spectrum(values_on_grid: ArrayLike, samples_per_cycle: int, cycle: float,
                   window: str = "none", detrend: str = "none", end: float | None = None
                   ) -> OrderSpectrum:
    """Amplitude and phase per engine order of each whole cycle, by the DFT over the cycle.

    Parameters
    ----------
    values_on_grid : (n_cycles·N,) or (n_cycles, N) array
        Samples uniform in crank angle, N per cycle, each cycle's end left out
        (:func:`to_angle_grid`).
    samples_per_cycle : int
        N.
    cycle : float
        Cycle angle Φ [rad]; orders are k·2π/Φ.
    window : ``"none"`` or ``"hann"``
        ``"none"`` (default): a periodic signal (steady state) sampled over whole cycles has no
        leakage, and order k·2π/Φ is exact up to aliasing of the orders above N/2 (choose N so
        that they are negligible). ``"hann"``: the periodic Hann window w_i = ½(1 − cos 2πi/N),
        amplitudes divided by its mean ½ (exact for a line on an order). For a signal that is
        not periodic over the cycle (see ``drift``) it lowers the leakage of the ends from
        ~1/k to ~1/k³, at the price of spreading each line over its neighbours k ± 1 (at half-order
        spacing a half order and the whole orders beside it mix) and of a biased mean.
    detrend : ``"none"`` or ``"ramp"``
        ``"ramp"``: before the DFT, subtract from each cycle the ramp D·i/N that carries its start
        value to its end value (D: the cycle's ``drift``), so that a run-up trend does not leak
        into the orders as a sawtooth (D/(πk) at harmonic k). A linear trend plus any signal
        periodic over the cycle is separated exactly; the mean loses D/2 (the trend's share)
        and the signal's own value at the cycle ends is kept. (A least-squares line would not
        do: it takes a share of every sine harmonic, −3A/(kπ²) of slope for A sin kφ.)
    end : float, optional
        The signal's value at the end of the last cycle (``to_angle_grid(..., closed=True)``);
        needed by ``detrend="ramp"``, whose other cycles end at the next cycle's start.

    Returns
    -------
    OrderSpectrum
    """
    v = np.asarray(values_on_grid, dtype=float)
    n = int(samples_per_cycle)
    if v.ndim == 1:
        if v.size % n or v.size == 0:
            raise ValueError(f"{v.size} samples are not whole cycles of {n}")
        v = v.reshape(-1, n)
    elif v.ndim != 2 or v.shape[1] != n:
        raise ValueError(f"values must be (n_cycles·{n},) or (n_cycles, {n}), got {v.shape}")
    drift = np.full(v.shape[0], np.nan)
    drift[:-1] = v[1:, 0] - v[:-1, 0]
    if end is not None:
        drift[-1] = float(end) - v[-1, 0]
    if detrend == "ramp":
        if end is None:
            raise ValueError("detrend='ramp' needs the value at the end of the last cycle (end)")
        v = v - drift[:, None] * (np.arange(n) / n)[None, :]
    elif detrend != "none":
        raise ValueError(f"detrend {detrend!r}: allowed 'none', 'ramp'")
    if window == "none":
        w = np.ones(n)
    elif window == "hann":
        w = 0.5 * (1.0 - np.cos(2.0 * np.pi * np.arange(n) / n))
    else:
        raise ValueError(f"window {window!r}: allowed 'none', 'hann'")
    X = np.fft.rfft(v * w, axis=1) / w.sum()
    X[:, 1:] *= 2.0
    if n % 2 == 0:
        X[:, -1] = X[:, -1].real / 2.0  # Nyquist: A cos θ, once
    X[:, 0] = X[:, 0].real
    orders = np.arange(X.shape[1]) * (2.0 * np.pi / cycle)
    return OrderSpectrum(orders, X, window, drift, detrend)


def resolve_detrend(mode: str, initial_omega: float, final_omega: float) -> str:
    """``"auto"`` → ``"ramp"`` for a spin-up
    (:func:`transient.analysis.transient_response.is_spin_up`), else ``"none"``; other modes
    as given."""
    from .transient_response import is_spin_up

    if mode != "auto":
        return mode
    return "ramp" if is_spin_up(initial_omega, final_omega) else "none"


def is_run_up(omega_mean: ArrayLike) -> bool:
    """Whether cycle-mean speeds ``omega_mean`` sweep enough of the speed range, in enough
    cycles, to be read against speed: max − min ≥ :data:`RUN_UP_SPAN` · max, with
    :data:`RUN_UP_CYCLES` of them inside the span."""
    w = np.asarray(omega_mean, dtype=float)
    if w.size < 2:
        return False
    span = float(np.ptp(w))
    inside = np.count_nonzero((w > w.min() + 0.1 * span) & (w < w.max() - 0.1 * span))
    return bool(span >= RUN_UP_SPAN * np.max(np.abs(w)) and inside >= RUN_UP_CYCLES)


def cycle_spectra(traj: Mapping[str, NDArray[np.float64]], name: str, samples_per_cycle: int,
                  cycle: float, *, phi0: float = 0.0, cuts: ArrayLike = (),
                  detrend: str = "none") -> tuple[NDArray[np.float64], OrderSpectrum]:
    """Order spectrum of every whole cycle of one trajectory column (the run-up waterfall's rows).

    The column is resampled with :func:`to_angle_grid` (closed: the last cycle's end too, which
    ``detrend="ramp"`` of :func:`order_spectrum` needs). Returns (each cycle's start angle
    [rad], spectrum).
    """
    n = int(samples_per_cycle)
    grid, cols = to_angle_grid(traj, (name,), n, cycle, phi0=phi0, cuts=cuts, closed=True)
    v = cols[name]
    return grid[:-1:n], order_spectrum(v[:-1], n, cycle, detrend=detrend, end=v[-1])


# ------------------------------------------------------------------------------------------------
# Piston kinematics with a variable shaft speed


def piston_acceleration(phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike, r: float,
                        l: float, e: float = 0.0, phase: float = 0.0) -> NDArray[np.float64]:
    """Piston acceleration W = ω² s″(α) + ε s′(α), α = φ − phase [m/s²] (Semenov §4).

    Exact kinematics (no truncated series); positive toward the crank axis (Gots §1: at TDC and
    constant ω, W = rω²(1 + λ) > 0). ``phase``: the shaft angle at which the cylinder's local
    angle is 0 (``mechanism.firing_angles[k]``). ω [rad/s] and ε [rad/s²] broadcast with φ.
    """
    phi = np.asarray(phi, dtype=float)
    _, ds, dds, _, _, _ = slider_arrays(phi - phase, r, l, e)
    return np.asarray(omega) ** 2 * dds + np.asarray(epsilon) * ds


def piston_inertia_force(phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike, r: float,
                         l: float, e: float, m_j: float, phase: float = 0.0
                         ) -> NDArray[np.float64]:
    """Inertia force of the reciprocating mass m_j [kg], P_j = −m_j W [N] (Gots §2.3), positive
    toward the crank axis."""
    return -m_j * piston_acceleration(phi, omega, epsilon, r, l, e, phase)


def rod_angular_acceleration(phi: ArrayLike, omega: ArrayLike, epsilon: ArrayLike, r: float,
                             l: float, e: float = 0.0, phase: float = 0.0
                             ) -> NDArray[np.float64]:
    """Rod angular acceleration ε_ш = ω² β″ + ε β′ [rad/s²] (Semenov §4); odd orders only at
    constant ω for e = 0 (Semenov (35))."""
    phi = np.asarray(phi, dtype=float)
    _, _, _, _, db, ddb = slider_arrays(phi - phase, r, l, e)
    return np.asarray(omega) ** 2 * ddb + np.asarray(epsilon) * db


# ------------------------------------------------------------------------------------------------
# The odd-harmonic report


def _is_odd(orders):
    whole = np.abs(orders - np.round(orders)) <= _ORDER_TOL
    return whole & (np.round(orders) % 2 == 1) & (np.round(orders) >= 3)


def _is_fractional(orders):
    return np.abs(orders - np.round(orders)) > _ORDER_TOL


@dataclass(frozen=True)
class OddHarmonicReport:
    """Orders of the piston acceleration of a run, cycle by cycle, against the same engine turning
    at the cycle's mean speed.

    Attributes
    ----------
    orders : (n_orders,) array
        Engine orders k·2π/Φ.
    cycle_start : (n_cycles,) array
        Angle [rad] at which each cycle starts (the phase reference of the coefficients).
    omega_mean : (n_cycles,) array
        Cycle-mean speed Φ / (cycle time) [rad/s] (as :mod:`.irregularity`).
    delta : (n_cycles,) array
        δ = (ω_max − ω_min)/ω_mean over the cycle, its two ends included.
    coef : (n_cycles, n_orders) complex array
        W with the run's ω(φ), ε(φ) [m/s²] (:class:`OrderSpectrum` convention).
    coef_constant : (n_cycles, n_orders) complex array
        W at constant ω = omega_mean: ω̄² s″(φ).
    drift : (n_cycles,) array
        W(next start) − W(start) [m/s²] (see :class:`OrderSpectrum`).

    The speed fluctuation *adds* coef − coef_constant = spectrum of (ω² − ω̄²)s″ + εs′.
    """

    orders: NDArray[np.float64]
    cycle_start: NDArray[np.float64]
    omega_mean: NDArray[np.float64]
    delta: NDArray[np.float64]
    coef: NDArray[np.complex128]
    coef_constant: NDArray[np.complex128]
    drift: NDArray[np.float64]

    @property
    def amplitude(self):
        return np.abs(self.coef)

    @property
    def amplitude_constant(self):
        return np.abs(self.coef_constant)

    @property
    def first(self) -> NDArray[np.float64]:
        """First-order amplitude of W per cycle [m/s²]."""
        return self.amplitude[:, self._k(1.0)]

    @property
    def relative(self):
        """Amplitudes of W relative to its first order."""
        return self.amplitude / self.first[:, None]

    @property
    def relative_constant(self):
        """Amplitudes of W at constant ω̄ relative to the first order of W at ω̄."""
        return self.amplitude_constant / self.amplitude_constant[:, self._k(1.0), None]

    @property
    def relative_added(self):
        """|coef − coef_constant| relative to the first order of W."""
        return np.abs(self.coef - self.coef_constant) / self.first[:, None]

    @property
    def odd(self) -> NDArray[np.bool_]:
        """Mask of the odd whole orders ≥ 3."""
        return _is_odd(self.orders)

    @property
    def fractional(self) -> NDArray[np.bool_]:
        """Mask of the non-whole orders (half orders of a 4-stroke cycle): absent at constant ω
        for any crank-slider, since s(φ) has period 2π."""
        return _is_fractional(self.orders)

    def _k(self, order: float) -> int:
        return int(round(order / self.orders[1]))

    def table(self, cycle: int = -1, max_order: float = 12.0) -> list[dict]:
        """Rows (order, |W|, |W| at ω̄, relative, relative at ω̄, added relative, kind) of one
        cycle up to ``max_order``; kind is "odd ≥ 3", "fractional" or "kinematic"."""
        rows = []
        for k, nu in enumerate(self.orders):
            if nu == 0.0 or nu > max_order + _ORDER_TOL:
                continue
            kind = ("odd>=3" if self.odd[k] else "fractional" if self.fractional[k]
                    else "kinematic")
            rows.append({"order": float(nu), "amplitude": float(self.amplitude[cycle, k]),
                         "amplitude_constant": float(self.amplitude_constant[cycle, k]),
                         "relative": float(self.relative[cycle, k]),
                         "relative_constant": float(self.relative_constant[cycle, k]),
                         "relative_added": float(self.relative_added[cycle, k]), "kind": kind})
        return rows

    def summary(self, cycle: int = -1, max_order: float = 9.0) -> dict[str, tuple[float, str]]:
        """Flat (value, unit) pairs of one cycle (default the last), for ``/analysis``: δ, ω̄, the
        first-order amplitude, each odd order ≥ 3 up to ``max_order`` relative to the first (run
        and constant ω̄), the largest odd and fractional ones."""
        k1 = self._k(1.0)
        out = {"orders_delta": (float(self.delta[cycle]), "1"),
               "orders_omega_mean": (float(self.omega_mean[cycle]), "rad/s"),
               "orders_W_first": (float(self.amplitude[cycle, k1]), "m/s^2"),
               "orders_W_first_constant": (float(self.amplitude_constant[cycle, k1]), "m/s^2")}
        for k in np.nonzero(self.odd & (self.orders <= max_order + _ORDER_TOL))[0]:
            o = int(round(self.orders[k]))
            out[f"orders_W_odd{o}_rel"] = (float(self.relative[cycle, k]), "1")
            out[f"orders_W_odd{o}_rel_constant"] = (float(self.relative_constant[cycle, k]), "1")
        rel = self.relative[cycle]
        out["orders_W_odd_max_rel"] = (float(rel[self.odd].max(initial=0.0)), "1")
        out["orders_W_odd_max_rel_constant"] = (
            float(self.relative_constant[cycle][self.odd].max(initial=0.0)), "1")
        out["orders_W_fractional_max_rel"] = (float(rel[self.fractional].max(initial=0.0)), "1")
        return out


def odd_harmonic_report(traj: Mapping[str, NDArray[np.float64]], r: float = 0.0,
                        l: float = 0.0, e: float = 0.0, *, cycle: float = 4.0 * math.pi,
                        phi0: float = 0.0, phase: float = 0.0, samples_per_cycle: int = 1440,
                        cycles: int | None = None, cuts: ArrayLike = (),
                        kinematics=None) -> OddHarmonicReport:
    """Orders of the piston acceleration of a run against the same engine at constant mean speed.

    Parameters
    ----------
    traj : mapping
        Trajectory with ``t``, ``phi``, ``omega``, ``epsilon``.
    r, l, e : float
        Crank radius, rod length and offset [m] of the cylinder.
    cycle, phi0 : float
        Cycle angle Φ [rad] and the angle cycles are counted from (``scene.initial.phi``).
    phase : float
        Shaft angle at which the cylinder's local angle is 0 (its firing angle).
    samples_per_cycle : int
        Grid size N per cycle (orders up to N/2 · 2π/Φ; higher ones alias).
    cycles : int, optional
        Only the last ``cycles`` whole cycles.
    cuts : array, optional
        Corner angles of the run (breakpoints), see :func:`resample_angle`.
    kinematics : callable, optional
        φ ↦ (s′(φ), s″(φ)) [m/rad, m/rad²] of the piston at the shaft angles φ, for a piston
        that is not a crank-slider's (:func:`report_for_scene` makes it from
        :func:`transient.analysis.pistons.piston_kinematics`); then r, l, e and phase are unused.

    Notes
    -----
    The comparison is meant for steady state (periodic cycles). In a transient (a spin-up) the
    trend of ω across a cycle enters δ (the 20-revolution Gots spin-up: a rise of 2.6 % of ω̄ over
    its last cycle, δ = 4.7 %) and leaks into every order of the cycle as a sawtooth, ≈
    drift/(πk) at harmonic k of the cycle (see ``drift``): there the "added" orders mix the
    ripple's products with that leakage.

    ω, t are resampled by Hermite interpolation with dω/dφ = ε/ω, dt/dφ = 1/ω; ε by the spline
    (exact when the run's samples lie on the grid). W = ω²s″ + εs′ is then evaluated on the grid
    with the exact kinematics, and at ω̄ as ω̄²s″.
    """
    grid, cols = to_angle_grid(traj, ("t", "omega", "epsilon"), samples_per_cycle, cycle,
                               phi0=phi0, cycles=cycles, cuts=cuts)
    n = int(samples_per_cycle)
    n_cyc = grid.size // n
    # The cycle ends: t for the mean speed, ω to close the cycle for δ.
    part = _increasing_part(traj)
    phi, w = np.asarray(traj["phi"], float)[part], np.asarray(traj["omega"], float)[part]
    eps = np.asarray(traj["epsilon"], float)[part]
    ends = grid[::n] + cycle
    t_end = resample_angle(phi, np.asarray(traj["t"], float)[part], ends, 1.0 / w, cuts, "left")
    w_end = resample_angle(phi, w, ends, eps / w, cuts, "left")
    t_start = cols["t"][::n]
    omega_mean = cycle / (t_end - t_start)
    wc = cols["omega"].reshape(n_cyc, n)
    delta = (np.maximum(wc.max(axis=1), w_end) - np.minimum(wc.min(axis=1), w_end)) / omega_mean

    if kinematics is None:
        def kinematics(x):
            return slider_arrays(x - phase, r, l, e)[1:3]
    ds, dds = kinematics(grid)
    W = cols["omega"] ** 2 * dds + cols["epsilon"] * ds
    W_const = np.repeat(omega_mean, n) ** 2 * dds
    spec = order_spectrum(W, n, cycle)
    spec_c = order_spectrum(W_const, n, cycle)
    # the last cycle's drift from its own end (the next cycle's start is not on the grid)
    drift = spec.drift.copy()
    eps_end = resample_angle(phi, eps, ends[-1:], None, cuts, "left")
    ds_e, dds_e = kinematics(ends[-1:])
    drift[-1] = float(w_end[-1] ** 2 * dds_e[0] + eps_end[0] * ds_e[0] - W[-n])
    return OddHarmonicReport(spec.orders, grid[::n].copy(), omega_mean, delta, spec.coef,
                             spec_c.coef, drift)


def report_for_scene(scene, traj: Mapping[str, NDArray[np.float64]], cylinder: int = 1,
                     **options) -> OddHarmonicReport:
    """:func:`odd_harmonic_report` for cylinder ``cylinder`` (1-based) of the scene's mechanism:
    a crank-slider's r, l, e and firing angle, or any other piston's exact s′, s″
    (:func:`transient.analysis.pistons.piston_kinematics`: a radial engine's master and slave
    pistons, a swash plate's); Φ and φ0 from the scene; ``options`` as there. ValueError for a
    cylinder out of range.

    Which orders the constant-speed W = ω̄²s″ holds is the mechanism's geometry (module
    docstring): a central crank-slider and a radial engine's master piston no odd order ≥ 3; a
    slave piston none either when its link pin lies at its own cylinder's angle on the master
    rod (ψ_i = δ_i); a swash plate's piston no even order in the limit of long rods; and no
    piston a half order, its travel repeating every turn."""
    m = scene.mechanism
    n = len(m.firing_angles)  # one per cylinder
    if not 1 <= cylinder <= n:
        raise ValueError(f"cylinder {cylinder} is out of range; allowed: 1 … {n}")
    common = dict(cycle=m.cycle, phi0=scene.initial.phi, **options)
    if m.slider_law:
        return odd_harmonic_report(traj, m.crank_radius, m.rod_length, m.offset,
                                   phase=m.firing_angles[cylinder - 1], **common)
    from .pistons import piston_kinematics

    def kinematics(x):
        pk = piston_kinematics(m, x)
        return pk.ds[cylinder - 1], pk.dds[cylinder - 1]

    return odd_harmonic_report(traj, kinematics=kinematics, **common)


# ------------------------------------------------------------------------------------------------
# The orders of a stored run


@dataclass(frozen=True)
class RunOrders:
    """Order spectra of a run (:func:`run_orders`).

    Attributes
    ----------
    cycle_start : (n_cycles,) array
        Angle [rad] at which each whole cycle starts.
    omega : OrderSpectrum
        ω of every whole cycle (the run-up waterfall's rows; the last row is the last cycle).
    omega_mean : (n_cycles,) array
        Cycle-mean speed of each of those cycles [rad/s] (:func:`.irregularity.cycle_means`).
    delta : float
        δ of the last whole cycle (:func:`.irregularity.fluctuation`).
    detrend : str
        ``"ramp"`` or ``"none"``: what was done to ω before each cycle's DFT.
    gas_torque : OrderSpectrum or None
        M_gas over the last whole cycle, where the run has gas forces.
    piston : OddHarmonicReport or None
        The piston acceleration of one cylinder over the last whole cycle, where asked for.
    cylinder_torques : OrderSpectrum or None
        Each cylinder's gas torque over the last whole cycle
        (:func:`transient.analysis.pistons.cylinder_torques`), one row per cylinder (where the
        spectrum's rows are otherwise cycles), where the run has gas forces.
    """

    cycle_start: NDArray[np.float64]
    omega: OrderSpectrum
    omega_mean: NDArray[np.float64]
    delta: float
    detrend: str
    gas_torque: OrderSpectrum | None = None
    piston: OddHarmonicReport | None = None
    cylinder_torques: OrderSpectrum | None = None

    @property
    def orders(self) -> NDArray[np.float64]:
        return self.omega.orders

    @property
    def cycles(self) -> int:
        return self.cycle_start.size


def run_orders(scene, traj: Mapping[str, NDArray[np.float64]], samples_per_cycle: int, *,
               cuts: ArrayLike = (), detrend: str = "auto", piston_cylinder: int | None = None
               ) -> RunOrders:
    """The order spectra of a run of ``scene`` on a grid of ``samples_per_cycle`` points per
    engine cycle, whole cycles counted from φ0 as :mod:`.irregularity` counts them.

    Parameters
    ----------
    scene : Scene
        The run's scene (cycle, φ0, initial speed, gas model).
    traj : mapping
        Its trajectory columns (``t``, ``phi``, ``omega``, ``epsilon``; ``M_gas`` if stored).
    samples_per_cycle : int
        N; orders up to N/2 per cycle.
    cuts : array, optional
        Corner angles (the run's breakpoints), see :func:`resample_angle`.
    detrend : ``"auto"``, ``"ramp"`` or ``"none"``
        For ω, as :func:`resolve_detrend`: a spin-up's trend would otherwise leak into every
        order of each cycle.
    piston_cylinder : int, optional
        Cylinder (1-based) whose piston acceleration is reported (:func:`report_for_scene`,
        any mechanism); None: no report.

    Raises :class:`~.irregularity.NoWholeCycle` if the run holds no whole cycle.
    """
    cycle, phi0 = scene.mechanism.cycle, scene.initial.phi
    n = int(samples_per_cycle)
    detrend = resolve_detrend(detrend, scene.initial.omega, float(traj["omega"][-1]))
    starts, omega = cycle_spectra(traj, "omega", n, cycle, phi0=phi0, cuts=cuts,
                                  detrend=detrend)
    gas = per_cylinder = None
    if "M_gas" in traj and scene.gas.model != "none":
        _, cm = to_angle_grid(traj, ("M_gas",), n, cycle, phi0=phi0, cycles=1, cuts=cuts)
        gas = order_spectrum(cm["M_gas"], n, cycle)
        per_cylinder = _cylinder_torque_spectra(scene, traj, n, cuts)
    piston = None
    if piston_cylinder is not None:
        piston = report_for_scene(scene, traj, piston_cylinder, samples_per_cycle=n, cycles=1,
                                  cuts=cuts)
    t, phi = traj["t"], traj["phi"]
    delta = fluctuation(t, phi, traj["omega"], cycle, phi0)
    means, _ = cycle_means(t, phi, cycle, phi0)
    return RunOrders(starts, omega, means[-starts.size:], delta, detrend, gas, piston,
                     per_cylinder)


def _cylinder_torque_spectra(scene, traj, n, cuts) -> OrderSpectrum | None:
    """Each cylinder's gas torque over the last whole cycle, one spectrum row per cylinder: the
    torques on the stored samples of the last two cycles (:func:`.pistons.cylinder_torques`,
    adding up to M_gas there), resampled onto the grid as M_gas is, so that their spectra add up
    to M_gas's (the resampling is linear in the samples). None without per-cylinder columns."""
    from .pistons import cylinder_torques

    count = getattr(scene.mechanism, "n_cylinders", 0)
    names = [f"p_{k + 1}" for k in range(count)]
    if not names or not all(c in traj for c in names):
        return None
    cycle = scene.mechanism.cycle
    part = _increasing_part(traj)
    phi = np.asarray(traj["phi"], dtype=float)[part]
    recent = phi >= phi[-1] - 2.0 * cycle
    cols = {"phi": phi[recent], **{c: np.asarray(traj[c], dtype=float)[part][recent]
                                   for c in names}}
    torques = cylinder_torques(scene, cols)
    named = {"phi": cols["phi"], **{f"M_{k}": m for k, m in enumerate(torques)}}
    _, grid_cols = to_angle_grid(named, list(named)[1:], n, cycle, phi0=scene.initial.phi,
                                 cycles=1, cuts=cuts)
    return order_spectrum(np.array([grid_cols[f"M_{k}"] for k in range(count)]), n, cycle)


def orders_up_to(orders: ArrayLike, max_order: float) -> NDArray[np.intp]:
    """Indices of the orders 0 < ν ≤ ``max_order`` (the mean left out)."""
    orders = np.asarray(orders)
    return np.nonzero((orders > 0.0) & (orders <= max_order + _ORDER_TOL))[0]


def strongest_orders(orders: ArrayLike, amplitude: ArrayLike, max_order: float, count: int = 6
                     ) -> NDArray[np.intp]:
    """Indices of the ``count`` largest amplitudes among the orders 0 < ν ≤ ``max_order``,
    largest first."""
    shown = orders_up_to(orders, max_order)
    return shown[np.argsort(np.asarray(amplitude)[shown])[::-1][:count]]
