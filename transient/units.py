"""Units of scene keys (docs/guide/scenes.md, Units): every number a scene gives is of a quantity
kind with an SI unit, and a few kinds also take unit suffixes (``crank_radius_mm``), converted
once at the edge; a bound or default that is another key's value carries that key's name
(:class:`~transient.units.Named`)."""
from __future__ import annotations

from dataclasses import dataclass
from math import pi
from typing import Any

#: quantity kind -> {suffix: factor to SI}
SUFFIXES: dict[str, dict[str, float]] = {
    "angle": {"deg": pi / 180.0},
    "speed": {"rpm": pi / 30.0},
    "length": {"mm": 1e-3},
    "pressure": {"bar": 1e5, "MPa": 1e6},
    "force": {"kN": 1e3},
    "modulus": {"GPa": 1e9},
}
ALL_SUFFIXES = sorted({s for kind in SUFFIXES.values() for s in kind})

#: quantity kind -> the SI unit a number of it is in when written without a suffix. Every number
#: the scene reader takes names its kind (``"1"``: a dimensionless number), so that its unit is
#: known where it is read.
UNITS: dict[str, str] = {
    "1": "1",
    "angle": "rad",
    "speed": "rad/s",
    "length": "m",
    "pressure": "Pa",
    "force": "N",
    "mass": "kg",
    "inertia": "kg m²",
    "torque": "N m",
    "time": "s",
    "temperature": "K",
    "power": "W",
    "revolutions": "rev",
    "order": "1/rev",
    "rate": "1/s",
    "bytes": "bytes",
    "specific energy": "J/kg",
    "per kelvin": "1/K",
    "stiffness": "N/m",
    "torsional stiffness": "N m/rad",
    "modulus": "Pa",
    "linear damping": "N s/m",
    "rotary damping": "N m s/rad",
    "quadratic rotary damping": "N m s²/rad²",
    "woschni c2": "m/(s K)",
    "state": "units of each state (rad, rad/s, …)",
}

#: quantity kind -> (suffix, symbol) of the unit a scene usually writes it in, where that is not
#: SI: the key reference shows defaults and bounds in it (``180°``, not ``3.14159 rad``).
SHOWN: dict[str, tuple[str, str]] = {
    "angle": ("deg", "°"),
    "speed": ("rpm", "rpm"),
    "length": ("mm", "mm"),
    "pressure": ("bar", "bar"),
    "modulus": ("GPa", "GPa"),
}


@dataclass(frozen=True)
class Named:
    """A default or a bound of a scene key known by name: another key's value
    (``noload_speed``), an expression of keys (``rod_length − crank_radius``) or a constant
    (``2⁶³ − 1``). The scene reader uses ``value``; its error messages and the key reference
    show ``name`` too."""

    value: Any
    name: str


def value_of(x: Any) -> Any:
    """The value of a default or bound, :class:`~transient.units.Named` or plain."""
    return x.value if isinstance(x, Named) else x
