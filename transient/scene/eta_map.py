"""A pair's efficiency map (``model = "table"``): the grid from a CSV file's rows or from inline
arrays, and the checks that make the chain's solve with it exist and be unique
(:mod:`transient.core.model.eta_table`).

Every refusal is a :class:`~transient.errors.SceneError` naming the key, what is wrong and what is
allowed; speeds are quoted in rpm, as a map is usually written.
"""
from __future__ import annotations

import math

from ..errors import SceneError

#: Largest number of knots on either axis of a map: a measured map has tens; far more is a
#: mistake that would only slow every lookup's search.
MAX_KNOTS = 1000


def _rpm(w: float) -> str:
    return f"{w * 30.0 / math.pi:.6g} rpm"


def grid_from_points(key: str, points: list[tuple[int, float, float, float, float]]):
    """(speed, torque, η_fwd rows, η_bwd rows) from a table's data rows, each (row, |ω| [rad/s],
    |S| [N m], η_fwd, η_bwd), in any order: the axes are the distinct values, and every
    combination of them must be given exactly once (a complete rectangular grid)."""
    if not points:
        raise SceneError(key, "the table has no data rows; give one row per grid point "
                              "(speed, torque, eta_forward, eta_backward)")
    speed = sorted({p[1] for p in points})
    torque = sorted({p[2] for p in points})
    at: dict[tuple[float, float], int] = {}
    for line, w, s, _, _ in points:
        if (w, s) in at:
            raise SceneError(key, f"data row {line} repeats the grid point ({_rpm(w)}, {s:g} N m) "
                                  f"of data row {at[(w, s)]}; give each point once")
        at[(w, s)] = line
    if len(at) != len(speed) * len(torque):
        missing = next((w, s) for w in speed for s in torque if (w, s) not in at)
        raise SceneError(key, f"the grid is incomplete: no row for ({_rpm(missing[0])}, "
                              f"{missing[1]:g} N m); give every speed with every torque "
                              f"({len(speed)} × {len(torque)} rows, got {len(at)})")
    row = {(p[1], p[2]): p for p in points}
    fwd = tuple(tuple(row[(w, s)][3] for s in torque) for w in speed)
    bwd = tuple(tuple(row[(w, s)][4] for s in torque) for w in speed)
    return tuple(speed), tuple(torque), fwd, bwd


def check_map(key, speed, torque, fwd, bwd) -> None:
    """A map the solve accepts: ``key(name)`` gives the key of each part.

    Axes increasing, ≥ 0 (they are magnitudes), at most :data:`MAX_KNOTS`; η in (0, 1], one row
    per speed of one value per torque; and the transmitted moment increasing in the moment taken,
    η_fwd + x ∂η_fwd/∂x > 0 and η_bwd − x ∂η_bwd/∂x > 0 (x = |S|, the map bilinear, so checked
    at both ends of every cell of every speed row; module docstring of
    :mod:`transient.core.model.eta_table`). |x ∂η/∂x| < η is sufficient for both.
    """
    for name, axis in (("speed", speed), ("torque", torque)):
        if not axis:
            raise SceneError(key(name), "is empty; give at least one value")
        if len(axis) > MAX_KNOTS:
            raise SceneError(key(name), f"has {len(axis)} values; at most {MAX_KNOTS} allowed")
        if axis[0] < 0.0:
            raise SceneError(key(name), f"starts at {axis[0]:g}; a map's axes are magnitudes "
                                        f"(|ω|, |S|), ≥ 0")
        for a, b in zip(axis, axis[1:]):
            if not b > a:
                shown = (_rpm(a), _rpm(b)) if name == "speed" else (f"{a:g}", f"{b:g}")
                raise SceneError(key(name), f"must increase strictly, got {shown[0]} then "
                                            f"{shown[1]}")
    for name, grid, sign in (("eta_forward", fwd, 1.0), ("eta_backward", bwd, -1.0)):
        if len(grid) != len(speed) or any(len(r) != len(torque) for r in grid):
            raise SceneError(key(name), f"must have {len(speed)} row(s) (one per speed) of "
                                        f"{len(torque)} value(s) (one per torque)")
        for i, r in enumerate(grid):
            for j, e in enumerate(r):
                if not (0.0 < e <= 1.0):
                    raise SceneError(key(name), f"is {e:g} at ({_rpm(speed[i])}, "
                                                f"{torque[j]:g} N m); allowed: 0 < η ≤ 1")
            for j in range(len(torque) - 1):
                x0, x1 = torque[j], torque[j + 1]
                slope = (r[j + 1] - r[j]) / (x1 - x0)
                for x, e in ((x0, r[j]), (x1, r[j + 1])):
                    if not e + sign * x * slope > 0.0:
                        what = "η_fwd + x·∂η_fwd/∂x" if sign > 0 else "η_bwd − x·∂η_bwd/∂x"
                        raise SceneError(
                            key(name), f"at {_rpm(speed[i])} between {x0:g} and {x1:g} N m, "
                                       f"{what} = {e + sign * x * slope:.3g} at {x:g} N m; the "
                                       f"moment a pair passes on must grow with the moment it "
                                       f"takes, so allowed: {what} > 0 (|x·∂η/∂x| < η suffices)")
