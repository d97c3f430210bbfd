"""The trapezoidal gas-force pulse of the swash-plate example (Antonyuk et al. §4).

Antonyuk et al. §4: the force on a piston is zero until its pulse starts, rises linearly over φ₁*
(``ramp``) to the plateau k·φ₁* (``amplitude``), stays there and falls linearly with slope −k to
zero half a turn after the start (``duration``), then stays zero to the end of the period. (The
printed 4th branch is garbled and goes negative; the fall is k[π((i+1)/2 + 2n) − φ₁].) One pulse
per turn: the table's local angle 0 is the start of the pulse, which the mechanism's
``firing_angles`` place at each cylinder's inner dead centre.

The table holds a **force per piston** [N], not a pressure: the model must apply it with scale 1 and
offset 0 (no piston area, no crankcase pressure). Thermodynamics are not modelled, as in the paper.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from .gas import PressureTable, table_from_points

__all__ = ["trapezoid_table"]

#: A plateau shorter than this fraction of the period is treated as none (a triangle): a corner
#: that close to another would be snapped onto it by table_from_points.
_PLATEAU_TOL = 1e-8


def _deg(x: float) -> str:
    return f"{math.degrees(x):.6g}°"


def trapezoid_table(amplitude: float, ramp: float, period: float = 2.0 * math.pi,
                    duration: float = math.pi) -> PressureTable:
    """Periodic trapezoidal force pulse as a piecewise-linear table.

    Parameters
    ----------
    amplitude : float
        Plateau force on one piston [N], ≥ 0.
    ramp : float
        Rise (and fall) angle φ₁* [rad], 0 < ramp ≤ duration/2 (equal: a triangle, no plateau).
    period : float
        Cycle length [rad]; 2π for the two-stroke swash-plate engine.
    duration : float
        Angle from the start of the rise to the end of the fall [rad], 0 < duration < period; the
        paper's pulse lasts half a turn (π).

    Returns
    -------
    PressureTable
        Values [N]: 0 at 0, ``amplitude`` from ``ramp`` to ``duration − ramp``, 0 from ``duration``
        to ``period``, linear in between. Corners (table breakpoints) at 0, ``ramp``,
        ``duration − ramp`` (unless it equals ``ramp``), ``duration`` and ``period``. Its integral
        over the period is ``amplitude·(duration − ramp)`` [N rad].

    Raises
    ------
    SceneError
        ``gas.amplitude`` for a negative or non-finite amplitude; ``gas.duration_deg`` unless
        0 < duration < period; ``gas.ramp_deg`` unless 0 < ramp ≤ duration/2.
    """
    period = float(period)
    if not (math.isfinite(amplitude) and amplitude >= 0.0):
        raise SceneError("gas.amplitude", f"{amplitude!r} N is not allowed; the plateau force on a "
                                          "piston must be finite and ≥ 0")
    if not (math.isfinite(duration) and 0.0 < duration < period):
        raise SceneError("gas.duration_deg", f"{_deg(duration)} is not allowed; the pulse must "
                                             f"last more than 0° and less than the period "
                                             f"{_deg(period)}")
    half = 0.5 * duration
    if not (math.isfinite(ramp) and 0.0 < ramp <= half * (1.0 + 1e-12)):
        raise SceneError("gas.ramp_deg", f"{_deg(ramp)} is not allowed; 0° < ramp ≤ duration/2 = "
                                         f"{_deg(half)} (rise and fall must fit in the pulse)")
    a = float(amplitude)
    if duration - 2.0 * ramp <= _PLATEAU_TOL * period:  # a triangle
        phi = [0.0, half, duration, period]
        force = [0.0, a, 0.0, 0.0]
    else:
        phi = [0.0, ramp, duration - ramp, duration, period]
        force = [0.0, a, a, 0.0, 0.0]
    return table_from_points(np.array(phi), np.array(force), period, corners=phi[1:-1],
                             interpolation="linear")
