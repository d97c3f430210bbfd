"""What an elastic run's output rows say about its shaft line (``[shaft]``): the power and heat of
each damping part, each element's torque cycle by cycle and its vibratory part, and the order
spectra of twists and torques while the speed varies (the data of a run's Campbell overlay).
Everything is derived from the run's columns (docs: Torsion, *Analyses of an elastic run*).

**Power.** An element e (a section, a damper's silicone or rubber, the coupling) joining dofs a
and b with viscous damping c_e takes P_e = c_e (ω_a − ω_b)², and a station's absolute damping
a_s takes P_s = a_s (ω_s − ω̄)², ω̄ = Σ w_d ω_d / Σ w_d the line's rigid-body speed (w_d the
cycle-mean inertias; theory, (T3)). These are the terms whose sum the stepper integrates into
``W_line_loss``: from the speed columns they are exact at every sample.

**Heat.** Q_p(t) = ∫ P_p dt, by Simpson's rule on the samples (each run of increasing time on
its own; a repeated sample, written on both sides of an event, adds nothing). Its error is the
quadrature's, O(h⁴ P⁽⁴⁾) with h the sample spacing in time: Σ_p Q_p against the stepper's own
``W_line_loss`` measures it (:attr:`LineLosses.residual`), the check that the run is sampled
densely enough for its vibration (``[output] samples_per_rev``).

**Cycle means.** The mean power of a part over a whole engine cycle is its heat over the cycle
over the cycle's time, the heat at the cycle's bounds by cubic Hermite interpolation (Q′ = P,
exact at the samples). A silicone damper is sized by this mean power (its heat flow at the
speed where it is largest).

**Vibratory torque.** On a uniform crank-angle grid of whole cycles
(:func:`~.orders.to_angle_grid`), each element's torque less its mean over the cycle; per cycle
its peak-to-peak (greatest less least on the grid), half of which is the vibratory amplitude
that :mod:`.torsional_response` gives at steady speed.

**Orders.** Each cycle's DFT (:func:`~.orders.order_spectrum`) of a twist or a torque on that
grid, the twist interpolated with its exact derivative d(θ_d − φ)/dφ = ω_d/ω − 1; a run-up's
trend removed by the ramp (:func:`~.orders.resolve_detrend`). Against each cycle's mean speed an
order's amplitude peaks where its frequency q·n/60 crosses a natural frequency: the run's own
Campbell diagram.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..scene.outputs import column_name
from ..shaft import ShaftLine
from .irregularity import cycle_boundaries, cycle_means
from .orders import (
    OrderSpectrum,
    order_spectrum,
    resample_angle,
    resolve_detrend,
    to_angle_grid,
)

Array = NDArray[np.float64]
Traj = Mapping[str, NDArray[np.float64]]


@dataclass(frozen=True)
class LineElement:
    """An element of the line as the run's columns name it: its ``label`` (as
    :func:`~.torsion.shaft_elements` words it), its ``kind`` (``"section"``, ``"damper"``,
    ``"coupling"``), the speed columns of its two dofs, its torque column, its stiffness
    ``k`` [N m/rad] and viscous damping ``c`` [N m s/rad] (a loss factor's as the run uses it)."""

    label: str
    kind: str
    omega_a: str
    omega_b: str
    torque: str
    k: float
    c: float


def line_elements(line: ShaftLine) -> list[LineElement]:
    """The line's elements in the order of the run's ``torque_<a>_<b>`` columns."""
    from .torsion import shaft_elements  # (scipy.linalg, loaded for an elastic line only)

    names = [column_name(n) for n in line.names]
    labels = shaft_elements(line, viscous=True)
    out = []
    for (label, a, b), row in zip(labels, line.element_rows(), strict=True):
        if (a, b) != (int(row[0]), int(row[1])):  # (one order of the elements, two writers)
            raise AssertionError(f"element {label!r}: dofs {(a, b)} against {tuple(row[:2])}")
        kind = label.split()[0]
        out.append(LineElement(label, kind, f"omega_{names[a]}", f"omega_{names[b]}",
                               f"torque_{names[a]}_{names[b]}", float(row[2]), float(row[3])))
    return out


# ------------------------------------------------------------------------------------------------
# Power and heat


def line_powers(line: ShaftLine, traj: Traj) -> dict[str, Array]:
    """The power [W] each damping part of ``line`` takes at every sample of ``traj``: per
    element with damping (``LineElement.label``), per station with absolute damping
    (``"absolute at <station>"``); their sum is the rate of ``W_line_loss``."""
    out = {}
    for e in line_elements(line):
        if e.c:
            out[e.label] = e.c * (np.asarray(traj[e.omega_a]) - np.asarray(traj[e.omega_b])) ** 2
    absolute = line.absolute
    if np.any(absolute):
        omega = np.array([traj[f"omega_{column_name(n)}"] for n in line.names], dtype=float)
        mean = line.weights @ omega / line.weights.sum()
        for d in np.nonzero(absolute)[0]:
            out[f"absolute at {line.names[d]}"] = absolute[d] * (omega[d] - mean) ** 2
    return out


def cumulative_heat(t: ArrayLike, power: ArrayLike) -> Array:
    """Q(t_i) = ∫_{t_0}^{t_i} P dt [J] by Simpson's rule on the samples (scipy's cumulative
    Simpson, uneven spacing), each run of increasing ``t`` on its own (a repeated time, a sample
    written twice, adds nothing; a run of two samples by the trapezoid rule)."""
    from scipy.integrate import cumulative_simpson

    t = np.asarray(t, dtype=float)
    p = np.asarray(power, dtype=float)
    if t.shape != p.shape or t.ndim != 1:
        raise ValueError(f"t and power must be 1-D of one length, got {t.shape} and {p.shape}")
    step = np.diff(t)
    if np.any(step < 0):
        raise ValueError("t must be non-decreasing")
    out = np.zeros(t.size)
    cuts = np.concatenate([[0], np.nonzero(step == 0)[0] + 1, [t.size]])
    start = 0.0
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a >= 3:
            out[a:b] = start + cumulative_simpson(p[a:b], x=t[a:b], initial=0.0)
        elif b - a == 2:
            out[a:b] = start + np.array([0.0, 0.5 * (p[a] + p[a + 1]) * (t[a + 1] - t[a])])
        else:
            out[a:b] = start
        start = out[b - 1]
    return out


@dataclass(frozen=True)
class LineLosses:
    """The damping parts of an elastic run (:func:`line_losses`): ``parts`` their labels,
    ``power`` [W] and ``heat`` [J] (n_parts, n_samples), ``t`` [s] the samples' times and
    ``total`` [J] the stepper's own ``W_line_loss`` from the run's start."""

    parts: tuple[str, ...]
    power: Array
    heat: Array
    t: Array
    total: Array

    @property
    def residual(self) -> float:
        """(W_line_loss − Σ_p Q_p)/W_line_loss over the run: the quadrature's error relative
        to the line's loss (NaN without loss)."""
        taken = float(self.total[-1] - self.total[0])
        return (taken - float(self.heat[:, -1].sum())) / taken if taken > 0 else math.nan


def line_losses(line: ShaftLine, traj: Traj) -> LineLosses:
    """Power and heat of every damping part of ``line`` over the run ``traj``."""
    powers = line_powers(line, traj)
    t = np.asarray(traj["t"], dtype=float)
    power = np.array(list(powers.values())).reshape(len(powers), t.size)
    heat = np.array([cumulative_heat(t, p) for p in power]).reshape(power.shape)
    return LineLosses(tuple(powers), power, heat, t, np.asarray(traj["W_line_loss"], float))


def cycle_mean_power(scene, traj: Traj, power: ArrayLike) -> tuple[Array, Array]:
    """(each whole cycle's mean speed [rad/s], the mean of ``power`` [W] over it), whole cycles
    from φ0 while φ increases, as :func:`.irregularity.cycle_means` counts them; none without
    a whole cycle."""
    t = np.asarray(traj["t"], dtype=float)
    p = np.asarray(power, dtype=float)
    cycle = scene.mechanism.cycle
    tb, _ = cycle_boundaries(t, np.asarray(traj["phi"], dtype=float), cycle, scene.initial.phi)
    if tb.size < 2:
        return np.zeros(0), np.zeros(0)
    # the heat at the cycles' bounds: Hermite in time, its derivative the power itself
    heat = resample_angle(t, cumulative_heat(t, p), tb, p)
    return cycle / np.diff(tb), np.diff(heat) / np.diff(tb)


def damper_power_summary(scene, traj: Traj) -> dict[str, tuple[float, str]]:
    """The run's summary of its line's damping: each damper's mean power over the last whole
    cycle (``<ring>_power_last_cycle``, ``pulley_damper_power_last_cycle`` say: the heat flow a
    silicone damper is sized by) and the whole line's (``line_loss_power_last_cycle``, from
    ``W_line_loss`` itself); nothing without a whole cycle."""
    line = ShaftLine(scene)
    t = np.asarray(traj["t"], dtype=float)
    tb, _ = cycle_boundaries(t, np.asarray(traj["phi"], dtype=float), scene.mechanism.cycle,
                             scene.initial.phi)
    if tb.size < 2:
        return {}
    powers = line_powers(line, traj)
    out = {}
    for e in line_elements(line):
        if e.kind == "damper" and e.label in powers:
            ring = e.omega_b.removeprefix("omega_")
            mean = cycle_mean_power(scene, traj, powers[e.label])[1][-1]
            out[f"{ring}_power_last_cycle"] = (float(mean), "W")
    total = sum(powers.values(), np.zeros(t.size))  # (the rate of W_line_loss)
    loss = resample_angle(t, np.asarray(traj["W_line_loss"], dtype=float), tb[-2:], total)
    out["line_loss_power_last_cycle"] = (float((loss[1] - loss[0]) / (tb[-1] - tb[-2])), "W")
    return out


# ------------------------------------------------------------------------------------------------
# Torques cycle by cycle, and the orders of twists and torques


def _derivatives(traj: Traj, names: Sequence[str]) -> dict[str, Array]:
    """d(twist_d)/dφ = ω_d/ω − 1 of the twist columns among ``names`` (exact at the samples)."""
    omega = np.asarray(traj["omega"], dtype=float)
    return {n: np.asarray(traj["omega_" + n.removeprefix("twist_")]) / omega - 1.0
            for n in names if n.startswith("twist_")}


@dataclass(frozen=True)
class LineCycles:
    """Columns of an elastic run on a uniform crank-angle grid of its whole cycles
    (:func:`line_cycles`): ``names``, ``values`` (n_names, n_cycles, N), each cycle's start
    angle ``cycle_start`` [rad] and mean speed ``omega_mean`` [rad/s]."""

    names: tuple[str, ...]
    values: Array
    cycle_start: Array
    omega_mean: Array

    def index(self, name: str) -> int:
        if name not in self.names:
            raise KeyError(f"{name!r} is not among the columns analysed: {', '.join(self.names)}")
        return self.names.index(name)

    @property
    def mean(self) -> Array:
        """Each column's mean over each cycle (n_names, n_cycles)."""
        return self.values.mean(axis=2)

    @property
    def vibratory(self) -> Array:
        """Each column less its cycle's mean (n_names, n_cycles, N)."""
        return self.values - self.mean[:, :, None]

    @property
    def peak_to_peak(self) -> Array:
        """Greatest less least of each column over each cycle (n_names, n_cycles)."""
        return np.ptp(self.values, axis=2)


def line_cycles(scene, traj: Traj, names: Sequence[str], samples_per_cycle: int = 720, *,
                cuts: ArrayLike = ()) -> LineCycles:
    """The columns ``names`` of the run ``traj`` of ``scene`` on a grid of
    ``samples_per_cycle`` points per whole cycle (twists with their exact derivative, the
    others by the spline of :func:`~.orders.resample_angle`), with each cycle's mean speed.
    Raises :class:`~.irregularity.NoWholeCycle` without a whole cycle."""
    n = int(samples_per_cycle)
    cycle, phi0 = scene.mechanism.cycle, scene.initial.phi
    grid, cols = to_angle_grid(traj, names, n, cycle, phi0=phi0, cuts=cuts,
                               derivatives=_derivatives(traj, names))
    values = np.array([cols[name].reshape(-1, n) for name in names])
    means, _ = cycle_means(np.asarray(traj["t"]), np.asarray(traj["phi"]), cycle, phi0)
    return LineCycles(tuple(names), values, grid[::n], means[-values.shape[1]:])


@dataclass(frozen=True)
class LineOrders:
    """Order spectra of columns of an elastic run, cycle by cycle (:func:`line_orders`):
    ``spectra`` name → :class:`~.orders.OrderSpectrum` (a row per cycle), each cycle's start
    angle ``cycle_start`` [rad] and mean speed ``omega_mean`` [rad/s], and the ``detrend``
    applied."""

    spectra: dict[str, OrderSpectrum]
    cycle_start: Array
    omega_mean: Array
    detrend: str

    @property
    def orders(self) -> Array:
        return next(iter(self.spectra.values())).orders

    def track(self, name: str, order: float) -> Array:
        """The amplitude of ``order`` in column ``name``, cycle by cycle."""
        return np.abs(self.spectra[name].at(order))


def line_orders(scene, traj: Traj, names: Sequence[str], samples_per_cycle: int = 720, *,
                cuts: ArrayLike = (), detrend: str = "auto") -> LineOrders:
    """Each whole cycle's order spectrum of the columns ``names`` (twists, torques, speeds of
    the line) of the run ``traj`` of ``scene``; ``detrend`` as for ω in
    :func:`~.orders.run_orders` (``"auto"``: the ramp for a spin-up, whose mean twist and
    torque grow with the load). Raises :class:`~.irregularity.NoWholeCycle` without a whole
    cycle."""
    n = int(samples_per_cycle)
    cycle, phi0 = scene.mechanism.cycle, scene.initial.phi
    detrend = resolve_detrend(detrend, scene.initial.omega, float(traj["omega"][-1]))
    grid, cols = to_angle_grid(traj, names, n, cycle, phi0=phi0, cuts=cuts, closed=True,
                               derivatives=_derivatives(traj, names))
    spectra = {name: order_spectrum(cols[name][:-1], n, cycle, detrend=detrend,
                                    end=cols[name][-1]) for name in names}
    starts = grid[:-1:n]
    means, _ = cycle_means(np.asarray(traj["t"]), np.asarray(traj["phi"]), cycle, phi0)
    return LineOrders(spectra, starts, means[-starts.size:], detrend)


@dataclass(frozen=True)
class OrderPeak:
    """Where the amplitude of ``order`` in a run's column is largest: ``amplitude`` in the
    column's unit, in the cycle of mean speed ``rpm``, with the ``critical`` speed [rpm] of
    ``mode`` for that order nearest to it (NaN and 0 if the order has none in range)."""

    order: float
    amplitude: float
    rpm: float
    critical: float
    mode: int


def order_peaks(lo: LineOrders, name: str, orders: ArrayLike, criticals) -> list[OrderPeak]:
    """Per order of ``orders`` the cycle of its largest amplitude in column ``name`` and the
    critical speed (:class:`~.torsion.Critical`) of that order nearest to it: on a run-up
    through a critical the two are near, the run's a little later (the resonance builds up
    while the speed passes)."""
    rpm = lo.omega_mean * 30.0 / math.pi
    out = []
    for q in np.asarray(orders, dtype=float):
        amp = lo.track(name, float(q))
        i = int(np.argmax(amp))
        mine = [c for c in criticals if abs(c.order - q) < 1e-9]
        near = min(mine, key=lambda c: abs(c.rpm - rpm[i])) if mine else None
        out.append(OrderPeak(float(q), float(amp[i]), float(rpm[i]),
                             near.rpm if near else math.nan, near.mode if near else 0))
    return out


def campbell_overlay(lo: LineOrders, name: str, orders: ArrayLike) -> tuple[Array, Array, Array]:
    """The run's own order amplitudes of column ``name`` as
    :func:`transient.plots.modal_campbell` draws them over the Campbell diagram: (each cycle's
    mean speed [rpm], ``orders`` [1/rev], amplitudes (n_cycles, n_orders))."""
    q = np.asarray(orders, dtype=float)
    amp = np.array([lo.track(name, float(v)) for v in q]).T.reshape(lo.omega_mean.size, q.size)
    return lo.omega_mean * 30.0 / math.pi, q, amp


def torque_column(line: ShaftLine, label: str) -> str:
    """The torque column of the element labelled ``label`` (:func:`~.torsion.shaft_elements`:
    a mode's ``twist_at``)."""
    for e in line_elements(line):
        if e.label == label:
            return e.torque
    raise KeyError(f"no element {label!r} in the line")
