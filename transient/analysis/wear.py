"""The conventional wear diagram of a crankpin or journal (Gots §2.6, Table 14).

Wear is taken proportional to the load, and each load vector wears the arc of ±60° around its
direction; a ray of the diagram sums the loads whose direction lies within that arc of it. The
least loaded ray is where the oil hole goes.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Half-width of the arc each load vector wears [deg] (Gots §2.6, the ±60° rule).
WEAR_HALF_ARC_DEG = 60.0


def angle_weights(phi: ArrayLike) -> NDArray[np.float64]:
    """Crank angle each sample stands for, over the mean step.

    Each sample stands for half the interval on either side of it (the trapezoidal rule), so
    ``Σ w·f`` times the mean step integrates f over [phi[0], phi[-1]] as the trapezoidal rule
    does; on equal steps the weights are 1 inside and ½ at the ends. Extra samples that cluster
    around breakpoints therefore do not count twice.

    Parameters
    ----------
    phi : (n,) array
        Non-decreasing crank angles of the samples [rad].

    Returns
    -------
    (n,) array
        Weights, summing to n − 1 (ones for a single sample).
    """
    phi = np.asarray(phi, dtype=float)
    if phi.size < 2:
        return np.ones_like(phi)
    gaps = np.diff(phi)
    w = np.zeros_like(phi)
    w[:-1] += 0.5 * gaps
    w[1:] += 0.5 * gaps
    return w / (w.sum() / (phi.size - 1))


def wear_rays(direction: ArrayLike, magnitude: ArrayLike, weight: ArrayLike, n_rays: int = 36,
              half_arc_deg: float = WEAR_HALF_ARC_DEG
              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The wear diagram's ray sums.

    For each of ``n_rays`` equally spaced directions, the sum of ``magnitude · weight`` over the
    samples whose ``direction`` lies within ±``half_arc_deg`` of it (the arc's ends included).
    Gots draws 12 (or 18) rays over samples at equal crank-angle steps; ``weight`` (from
    :func:`angle_weights`: 1 for equal steps) lets unequal steps count by the angle they stand
    for.

    Parameters
    ----------
    direction : (n,) array
        Direction of each load vector in the diagram's frame [rad].
    magnitude : (n,) array
        Its magnitude (any unit, e.g. N).
    weight : (n,) array
        Weight of each sample.
    n_rays : int
        Rays, the first at 0°.
    half_arc_deg : float
        Half-width of the arc a load wears [deg].

    Returns
    -------
    rays : (n_rays,) array
        Ray angles [deg], counter-clockwise from the frame's x axis.
    sums : (n_rays,) array
        Sums [unit of ``magnitude``].
    """
    rays = np.arange(n_rays, dtype=np.float64) * (360.0 / n_rays)
    d = np.degrees(np.asarray(direction, dtype=float))[None, :] - rays[:, None]
    d = (d + 180.0) % 360.0 - 180.0
    # (the tolerance keeps a load exactly on the arc's end, up to rounding, inside)
    inside = np.abs(d) <= half_arc_deg + 1e-9
    return rays, (inside * (np.asarray(magnitude) * np.asarray(weight))[None, :]).sum(axis=1)
