"""The Scotch yoke: a crank whose pin, through a slider block, drives a slotted yoke that carries
the piston, so that the piston's travel is exactly harmonic, s = r (1 − cos α) — no connecting
rod, no rod angle, no second order (the compiled kinematics: :mod:`transient.core.model.scotch_yoke`).

One cylinder on the yoke, its axis the reference axis, its top dead centre at φ = 0. The slot
guides the yoke, so the piston has no side force on its bore; the pin's force on the slot is
along the cylinder axis alone (:mod:`transient.analysis.loads.scotch_yoke`).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from math import pi
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.model import scotch_yoke as core
from ..core.model.layout import LINK_FIXED, LINK_REST
from ..errors import SceneError
from ..tomlout import toml_value

if TYPE_CHECKING:
    from ..scene.reader import Section

# What each key of its ``[mechanism]`` table means, in a line (the scene-key reference).
KEY_MEANINGS = {
    "mechanism": {
        "crank_radius": "Crank radius r, half the stroke: the piston travels r(1 − cos φ).",
        "bore": "Cylinder bore D; piston area πD²/4.",
        "yoke_mass": "Reciprocating mass m: the yoke with its piston (and piston rod).",
        "block_mass": "Mass of the slider block on the crankpin, which goes round at r.",
        "crank_mass": "Unbalanced crank mass reduced to the crank radius.",
        "strokes": "Strokes per cycle: 2 (a cycle of 360°, a compressor's) or 4 (720°).",
    },
}


class ScotchYokeNumpy:
    """J(φ), dJ/dφ and the piston's transfer functions in plain numpy, written from the bodies'
    velocities (eq. (19): J = Σ m |v|²/φ̇²) rather than taken from the kernel: the yoke moves
    along the axis at v = d/dt r(1 − cos φ), block and crank mass go round at r φ̇."""

    def __init__(self, mech: ScotchYoke) -> None:
        self.r, self.m = mech.crank_radius, mech.yoke_mass
        self.m_rot = mech.block_mass + mech.crank_mass

    def terms(self, phi: float):
        """(J, dJ, u[1], u′[1]) at shaft angle φ."""
        v_yoke = np.array([self.r * np.sin(phi)])  # piston velocity over φ̇
        a_yoke = np.array([self.r * np.cos(phi)])  # its derivative in φ
        v_pin = self.r  # speed of the crankpin over φ̇
        J = self.m * float(v_yoke @ v_yoke) + self.m_rot * v_pin**2
        return J, 2.0 * self.m * float(v_yoke @ a_yoke), v_yoke, a_yoke


@dataclass(frozen=True)
class ScotchYoke:
    """A single-cylinder Scotch-yoke engine or compressor.

    Attributes
    ----------
    crank_radius : float
        r [m]; the stroke is 2r.
    bore : float
        Cylinder bore D [m].
    yoke_mass : float
        Reciprocating mass m of yoke and piston [kg].
    block_mass : float
        Slider block on the crankpin [kg] (rotating at r).
    crank_mass : float
        Unbalanced crank mass reduced to r [kg].
    strokes : int
        2 or 4.
    """

    crank_radius: float
    bore: float
    yoke_mass: float
    block_mass: float = 0.0
    crank_mass: float = 0.0
    strokes: int = 2

    #: Its ``type`` in the ``[mechanism]`` table (:data:`transient.mechanisms.MECHANISMS`).
    name: ClassVar[str] = "scotch-yoke"
    #: Its compiled kernel (``Model.terms``).
    kernel: ClassVar[Any] = staticmethod(core.terms)
    #: Its compiled kernel of each cylinder's share of J at its station's angle (``shares``).
    shares_kernel: ClassVar[Any] = staticmethod(core.shares)
    #: Beyond :class:`~transient.mechanisms.Mechanism`: its numpy twin, its pistons' travel and
    #: its loads (:mod:`transient.analysis.loads.scotch_yoke`); no reaction friction, no drawn
    #: diagrams.
    capabilities: ClassVar[frozenset[str]] = frozenset({"twin", "pistons", "loads"})
    twin: ClassVar[type] = ScotchYokeNumpy
    #: No wall heat transfer: the cylinder ODE is built for the crank-slider's volume.
    wall_heat_transfer: ClassVar[bool] = False
    cylinder_count: ClassVar[str] = "1 (one cylinder on the yoke)"
    key_meanings: ClassVar[dict[str, dict[str, str]]] = KEY_MEANINGS
    #: Not the crank-slider's law (its λ = 0 limit): the analyses take s′, s″ from its own.
    slider_law: ClassVar[bool] = False
    #: Links of the serial chain, shaft first: the crank (with the slider block), the yoke (with
    #: the piston), and the cylinder, whose gas does its work on the piston.
    links: ClassVar[tuple[str, ...]] = ("shaft", "crank", "yoke", "cylinder")
    #: The crank's and block's reduced inertia is constant, the yoke's the rest of J(φ).
    link_laws: ClassVar[tuple[int, ...]] = (LINK_FIXED, LINK_FIXED, LINK_REST, LINK_FIXED)
    firing_angles = (0.0,)
    bank_angles = (0.0,)

    @property
    def n_cylinders(self) -> int:
        return 1

    @property
    def cycle(self) -> float:
        """Cycle length in crank angle [rad]."""
        return pi * self.strokes

    @property
    def piston_area(self) -> float:
        return pi * self.bore**2 / 4.0

    @property
    def piston_link_mass(self) -> float:
        """The yoke's m (its link holds the rest of J(φ), m r² sin²φ) [kg]."""
        return self.yoke_mass

    def link_inertias(self) -> tuple[float, ...]:
        """Constant reduced inertia of each link [kg m²]: the crank's with the block,
        (m_b + m_c) r²; the yoke's varies (``link_laws``)."""
        return (0.0, (self.block_mass + self.crank_mass) * self.crank_radius**2, 0.0, 0.0)

    @classmethod
    def read(cls, s: Section) -> ScotchYoke:
        """A :class:`ScotchYoke` from the ``[mechanism]`` table (its ``type`` read by the
        caller, who finishes ``s``)."""
        mech = cls(crank_radius=s.number("crank_radius", "length", gt=0.0),
                   bore=s.number("bore", "length", gt=0.0),
                   yoke_mass=s.number("yoke_mass", "mass", gt=0.0),
                   block_mass=s.number("block_mass", "mass", 0.0, ge=0.0),
                   crank_mass=s.number("crank_mass", "mass", 0.0, ge=0.0),
                   strokes=s.integer("strokes", 2, choices=(2, 4)))
        mech.validate()
        return mech

    def validate(self) -> None:
        """Raise :class:`~transient.SceneError` for a geometry or mass set that cannot work."""
        for key, value, unit in (("crank_radius", self.crank_radius, "m"),
                                 ("bore", self.bore, "m"), ("yoke_mass", self.yoke_mass, "kg")):
            if not value > 0:
                raise SceneError(f"mechanism.{key}", f"must be > 0 {unit}, got {value:g}")
        for key, value in (("block_mass", self.block_mass), ("crank_mass", self.crank_mass)):
            if not value >= 0:
                raise SceneError(f"mechanism.{key}", f"must be ≥ 0 kg, got {value:g}")
        if self.strokes not in (2, 4):
            raise SceneError("mechanism.strokes", f"must be 2 or 4, got {self.strokes}")

    def pack(self) -> NDArray[np.float64]:
        """Parameter array of :func:`transient.core.model.scotch_yoke.scotch_yoke_terms`."""
        mp = np.zeros(core.N_PAR)
        mp[core.R] = self.crank_radius
        mp[core.M_RECIPROCATING] = self.yoke_mass
        mp[core.M_ROTATING] = self.block_mass + self.crank_mass
        mp[core.PHASE] = self.firing_angles[0]
        return mp

    def toml_lines(self) -> list[str]:
        """The ``[mechanism]`` table in SI, read back by :meth:`read` to an equal object."""
        keys = {"type": self.name, "crank_radius": self.crank_radius, "bore": self.bore,
                "yoke_mass": self.yoke_mass, "block_mass": self.block_mass,
                "crank_mass": self.crank_mass, "strokes": self.strokes}
        return ["[mechanism]"] + [f"{k} = {toml_value(v)}" for k, v in keys.items()]

    def travel(self, x: ArrayLike) -> NDArray[np.float64]:
        """The piston's travel from its top dead centre, r (1 − cos x) [m], at local angles x."""
        return self.crank_radius * (1.0 - np.cos(np.asarray(x, dtype=np.float64)))

    def dead_centre_angles(self) -> tuple[float, float]:
        """Local angles [rad] of the dead centres: 0 and π exactly."""
        return 0.0, pi

    def swept_volume(self) -> float:
        """F_p · 2r [m³]."""
        return self.piston_area * 2.0 * self.crank_radius

    def volume_function(self, clearance: float) -> Callable[[ArrayLike], NDArray[np.float64]]:
        """V(x) = V_c + F_p r (1 − cos x) over the local angle x [rad] (vectorised)."""
        return lambda x: clearance + self.piston_area * self.travel(x)

    def geometry(self) -> dict[str, tuple[float, str]]:
        """``stroke`` 2r, ``swept_volume`` and ``displacement`` (one cylinder: the same)."""
        return {"stroke": (2.0 * self.crank_radius, "m"),
                "swept_volume": (self.swept_volume(), "m^3"),
                "displacement": (self.swept_volume(), "m^3")}

    def kinematics_table(self, phi: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """``phi_deg``, ``J``, ``dJ_dphi`` and ``s_1``, ``u_1``, ``du_1`` over ``phi`` [rad]
        (the kernel's)."""
        phi = np.atleast_1d(np.asarray(phi, dtype=np.float64))
        mp, u, du = self.pack(), np.empty(1), np.empty(1)
        rows = []
        for p in phi:
            J, dJ = core.scotch_yoke_terms(mp, p, u, du)
            rows.append((J, dJ, u[0], du[0]))
        J, dJ, u1, du1 = (np.array(c) for c in zip(*rows))
        return {"phi_deg": np.degrees(phi), "J": J, "dJ_dphi": dJ, "s_1": self.travel(phi),
                "u_1": u1, "du_1": du1}

    def reference_terms(self) -> Callable[[float], tuple]:
        """φ ↦ (J, dJ/dφ, u_k, u′_k) for the reference path: the numpy twin
        (:class:`ScotchYokeNumpy`), independent of the kernel."""
        return self.twin(self).terms

    def analysis_summary(self) -> dict[str, tuple[float, str]]:
        """Figures of the mechanism itself for a result's ``/analysis``: none here."""
        return {}
