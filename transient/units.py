"""Unit suffixes allowed on scene keys, converted once at the edge (docs/guide/scenes.md, Units)."""
from __future__ import annotations

from math import pi

#: quantity kind -> {suffix: factor to SI}
SUFFIXES: dict[str, dict[str, float]] = {
    "angle": {"deg": pi / 180.0},
    "speed": {"rpm": pi / 30.0},
    "length": {"mm": 1e-3},
    "pressure": {"bar": 1e5, "MPa": 1e6},
    "force": {"kN": 1e3},
}
ALL_SUFFIXES = sorted({s for kind in SUFFIXES.values() for s in kind})
