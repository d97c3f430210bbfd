"""The motion of a prescribed-speed run and its work columns.

A prescribed-speed run (:func:`transient.run.prescribed`) computes no motion: ω(t) is the scene's
speed table through its interpolant (or a constant), φ(t) its exact integral from φ₀, ε(t) its
derivative (:class:`Motion`). The work columns are what a dynamic run integrates with the motion as
states: W_x(t) = ∫ P_x dt of each power on the shaft (M_gas ω, M_load ω, M_starter ω, M_drive ω)
and each pair's loss P_loss,k. Here they are integrals of known functions of t, taken by
adaptive Gauss–Kronrod quadrature (:mod:`transient.quadrature`) to the scene's ``rtol`` and
``atol``, on pieces that end on every output sample and on every corner of the motion and the
model (:func:`corner_times`) so that no piece holds a jump of the integrand that the quadrature
would have to close in on. Since the inverse dynamics makes the powers add up to the change of
the kinetic energy at every instant (Jωε + ½J′ω³ = ΣP, the reduced equation (18) times ω), the
columns then close the work–energy balance

    W_drive + W_gas + W_load + W_starter − Σ W_loss,k = ½J(φ)ω² − ½J(φ₀)ω₀²

to within rtol·Σ∫|P_x| dt + atol per column, whatever the output spacing.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .core.model import layout
from .core.model.inverse import inverse_dynamics
from .core.model.layout import n_outputs
from .forces.load_table import interpolant
from .quadrature import integrals

if TYPE_CHECKING:
    from scipy.interpolate import PPoly

#: The torque columns whose power M·ω is a work column, by that column's name.
TORQUE_WORK = {"W_gas": "M_gas", "W_load": "M_load", "W_starter": "M_starter"}


@dataclass(frozen=True)
class Motion:
    """A prescribed motion from (t0, φ0): ω(t) the scene's speed table through its interpolant
    (``speed``, a :class:`scipy.interpolate.PPoly`), or the constant ``omega`` without a table."""

    t0: float
    phi0: float
    omega: float = 0.0
    speed: PPoly | None = None  # ω(t) and its antiderivative, with a table
    angle: PPoly | None = None

    @classmethod
    def of(cls, scene) -> Motion:
        run = scene.run
        if not run.time:
            return cls(0.0, scene.initial.phi, omega=run.speed)
        speed = interpolant(run.time, run.speed_table, run.interpolation)
        return cls(float(run.time[0]), scene.initial.phi, speed=speed,
                   angle=speed.antiderivative())

    def at(self, t: NDArray[np.float64]
           ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """(φ, ω, ε) at the times ``t``; at a point of a linear table ε is the slope after it."""
        t = np.asarray(t, dtype=np.float64)
        if self.speed is None or self.angle is None:  # (both are given, or neither)
            return (self.phi0 + self.omega * (t - self.t0), np.full_like(t, self.omega),
                    np.zeros_like(t))
        return self.phi0 + self.angle(t) - self.angle(self.t0), self.speed(t), self.speed(t, 1)

    def corners(self) -> NDArray[np.float64]:
        """Times where ε jumps or kinks: the speed table's points."""
        return np.zeros(0) if self.speed is None else np.asarray(self.speed.x, dtype=np.float64)

    def time_at(self, angles: NDArray[np.float64], t: NDArray[np.float64],
                phi: NDArray[np.float64]) -> NDArray[np.float64]:
        """The times at which the shaft is at ``angles`` (inside the samples (t, φ) of the
        motion): Newton's method on φ(t) = angle from the samples' linear interpolant, φ′ = ω > 0
        (a prescribed speed is positive), to the rounding of t."""
        angles = np.asarray(angles, dtype=np.float64)
        if self.speed is None:
            return self.t0 + (angles - self.phi0) / self.omega
        x = np.interp(angles, phi, t)
        for _ in range(50):
            p, w, _ = self.at(x)
            step = (p - angles) / w
            x = np.clip(x - step, t[0], t[-1])
            if np.all(np.abs(step) <= 4.0 * np.spacing(np.maximum(np.abs(x), 1.0))):
                break
        return x


def corner_times(model, motion: Motion, t: NDArray[np.float64], phi: NDArray[np.float64]
                 ) -> NDArray[np.float64]:
    """Times strictly inside the samples' span where an integrand may jump or kink: the speed
    table's points, the shaft angles k·Φ + φ_b of the model's breakpoints (a pressure table's
    corners, an angle table's knots, the reaction pairs' dead centres) and the load schedule's
    corners (times, or angles)."""
    lo, hi = phi[0], phi[-1]
    k = np.arange(np.floor(lo / model.period), np.floor(hi / model.period) + 1.0)
    angles = (k[:, None] * model.period + np.asarray(model.breakpoints)[None, :]).ravel()
    times = [motion.corners()]
    if model.load_x.size:
        x = np.asarray(model.load_x, dtype=np.float64)
        if model.load_comp == layout.T:
            times.append(x)
        else:
            angles = np.concatenate([angles, x])
    angles = angles[(angles > lo) & (angles < hi)]
    times.append(motion.time_at(angles, t, phi))
    out = np.unique(np.concatenate(times))
    return out[(out > t[0]) & (out < t[-1])]


def work_columns(model, motion: Motion, t: NDArray[np.float64], phi: NDArray[np.float64],
                 columns: list[str], n_pairs: int, rtol: float, atol: float
                 ) -> tuple[dict[str, NDArray[np.float64]], dict[str, int]]:
    """The work columns at the sample times ``t`` (angles ``phi``): W_gas, W_load, W_starter,
    W_drive and W_loss_k for k = 1 … ``n_pairs``, from 0 at t[0] (module docstring). ``columns``:
    the output row's column names (``transient.scene.outputs.output_columns``), ``model`` the one the
    rows come from. Returns the columns and the quadrature's counts (``quadrature_pieces``,
    ``quadrature_evaluations``, ``quadrature_unresolved``: pieces left above their tolerance).
    """
    extras = layout.extras_of(model)
    names = [*TORQUE_WORK, "W_drive", *(f"W_loss_{k + 1}" for k in range(n_pairs))]
    torque = [columns.index(TORQUE_WORK[n]) for n in TORQUE_WORK]
    loss = [columns.index(f"P_loss_{k + 1}") for k in range(n_pairs)]

    def powers(x):
        p, w, e = motion.at(x)
        rows = np.empty((x.size, n_outputs(model)))
        drive = np.empty(x.size)
        inverse_dynamics(model, extras, x, p, w, e, rows, drive, np.empty(x.size, np.int64))
        return np.vstack([rows[:, torque].T * w, drive * w, rows[:, loss].T])

    edges = np.union1d(t, corner_times(model, motion, t, phi))
    q = integrals(powers, edges[:-1], edges[1:], rtol, atol)
    cumulative = np.concatenate([np.zeros((len(names), 1)), np.cumsum(q.value, axis=1)], axis=1)
    at = np.searchsorted(edges, t)
    works = {name: cumulative[j, at] for j, name in enumerate(names)}
    counts = {"quadrature_pieces": q.pieces, "quadrature_evaluations": q.evaluations,
              "quadrature_unresolved": q.unresolved}
    return works, counts
