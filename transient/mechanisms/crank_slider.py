"""Crank-slider engines (in-line, V, offset): geometry, masses, validation and the kinematics table.

The compiled kinematics live in :mod:`transient.core.model.crank_slider`; this module holds the scene-side
description (SI units) and packs it for the kernel; :mod:`.throws` reads how the cylinders sit
on the crank.

Two cylinders on one throw (a V engine) are two crank-sliders at their own local angles, as every
cylinder is: the kernel sums the cylinders and needs nothing else. The throw's unbalanced mass is
counted once: each of its cylinders carries half of it
(:attr:`CrankSlider.crank_mass_per_cylinder`), at its own crankpin, which is the same mass at the
same place unless the pins are split. The rods' arrangement on the pin does not enter J(φ): the
motion is planar, and where along the pin a rod runs changes no velocity. It places the rods'
forces along the shaft, which the main-journal loads and running torques of
:mod:`transient.analysis.loads.crank_slider` use.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from math import asin, degrees, pi
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from ..core.model import crank_slider as core
from ..core.model import joint_friction
from ..core.model.layout import LINK_FIXED, LINK_PISTONS, LINK_REST
from ..errors import SceneError
from ..tomlout import toml_value
from ..units import Named
from . import throws
from .throws import ANGLE_TOL, SHARED, SINGLE, at_phases, equal_angles, read_crank, wrap_angle
from .twins import CrankSliderNumpy

if TYPE_CHECKING:
    from ..scene.reader import Section

#: Cylinders at most (a scene check: every per-cylinder array is sized by it).
MAX_CYLINDERS = 64

# What each key of its ``[mechanism]`` table and sub-tables means, in a line: the scene-key
# reference (docs/guide/scene_keys) shows it beside what the reader asks of the key.
KEY_MEANINGS = {
    "mechanism": {
        **throws.KEY_MEANINGS,
        "crank_radius": "Crank radius r, half the stroke.",
        "rod_length": "Connecting-rod length l between pin centres; λ = r/l < 1.",
        "strokes": "Strokes per cycle: 4 (a cycle of 720°) or 2 (360°).",
        "cylinders": "Number of cylinders, all of one geometry.",
        "firing_order": "The cylinders in the order they fire, each once.",
        "offset": "Cylinder-axis offset e, positive in the direction of rotation (Gots §1.4).",
        "rod": "The connecting rod (``[mechanism.rod]``).",
        "bore": "Cylinder bore D; piston area πD²/4.",
        "piston_mass": "Mass of the piston group (piston, rings, pin).",
        "crank_mass": "Unbalanced crank-throw mass reduced to the crank radius, Gots (28), per "
                      "throw.",
    },
    "mechanism.rod": {
        "model": "``two-mass``: masses at pin and crankpin, Gots (20); ``rigid``: a rigid body "
                 "with its moment of inertia.",
        "mass": "Mass of the rod.",
        "cg_from_pin": "Distance from the piston pin to the rod's centre of mass, Gots l₁.",
        "inertia_cg": "Moment of inertia of the rod about its centre of mass (``rigid``).",
    },
}


@dataclass(frozen=True)
class CrankSlider:
    """A crank-slider engine; all cylinders share one geometry (Gots §1, §2.2).

    Attributes
    ----------
    crank_radius : float
        r [m].
    rod_length : float
        Connecting-rod length between pin centres, l [m]; λ = r/l < 1.
    offset : float
        Cylinder-axis offset e [m], positive in the direction of rotation (Gots §1.4).
    bore : float
        Cylinder bore D [m]; piston area π D²/4.
    piston_mass : float
        Piston group mass [kg].
    crank_mass : float
        Unbalanced crank-throw mass reduced to the crank radius, Gots (28) [kg] (per throw).
    rod_model : str
        ``"two-mass"`` (Gots (20): masses at pin and crankpin, rod inertia not kept) or ``"rigid"``.
    rod_mass : float
        Connecting-rod mass [kg].
    rod_cg_from_pin : float
        Distance from the piston-pin centre to the rod's centre of mass, Gots l₁ [m].
    rod_inertia_cg : float
        Rod moment of inertia about its centre of mass [kg m²] (rigid model only).
    strokes : int
        2 or 4.
    firing_angles : tuple of float
        Shaft angle [rad] at which each cylinder's crank is at local angle 0 (its firing TDC for a
        central mechanism), in [0, cycle).
    bank_angles : tuple of float
        Cylinder-axis angles [rad] from the reference axis, in the direction of rotation (V engines).
        Each cylinder's crankpin stands (bank − firing) ahead of the shaft's reference line
        (:meth:`pin_angles`).
    rod_arrangement : str
        ``"single"``: every cylinder has a throw of its own; ``"side-by-side"`` or
        ``"fork-and-blade"``: cylinders 2t − 1 and 2t share throw t (numbered from the nose),
        their two big ends next to each other along the pin (2t − 1 nearer the nose) or in one
        plane, one rod forked around the other.
    rod_spacing : float
        Side-by-side rods: distance along the pin between the two big ends' middle planes [m]
        (0 otherwise).
    journal_spacing : float
        Side-by-side rods: distance between the two main journals beside a throw [m], the span
        of the split beam the main-journal loads use (0 otherwise).
    """

    crank_radius: float
    rod_length: float
    offset: float
    bore: float
    piston_mass: float
    crank_mass: float
    rod_model: str
    rod_mass: float
    rod_cg_from_pin: float
    rod_inertia_cg: float
    strokes: int
    firing_angles: tuple[float, ...]
    bank_angles: tuple[float, ...]
    rod_arrangement: str = SINGLE
    rod_spacing: float = 0.0
    journal_spacing: float = 0.0

    #: Its ``type`` in the ``[mechanism]`` table (:data:`transient.mechanisms.MECHANISMS`).
    name: ClassVar[str] = "crank-slider"
    #: Its compiled kernel (``Model.terms``).
    kernel: ClassVar[Any] = staticmethod(core.terms)
    #: Its compiled kernel of each cylinder's share of J at its station's angle (``shares``).
    shares_kernel: ClassVar[Any] = staticmethod(core.shares)
    #: Beyond :class:`~transient.mechanisms.Mechanism` (:data:`~transient.mechanisms.CAPABILITIES`).
    capabilities: ClassVar[frozenset[str]] = frozenset(
        {"reaction-friction", "twin", "reaction-twin", "pistons", "loads", "drawers", "cylinder-inertia"})
    #: Its numpy twin, for the reference path.
    twin: ClassVar[type] = CrankSliderNumpy
    #: Wall heat transfer may be given: the cylinder ODE is built for this volume.
    wall_heat_transfer: ClassVar[bool] = True
    cylinder_count: ClassVar[str] = "mechanism.cylinders"
    key_meanings: ClassVar[dict[str, dict[str, str]]] = KEY_MEANINGS
    #: Its pistons follow the slider law the analyses derive piston accelerations W_k from.
    slider_law: ClassVar[bool] = True
    #: Links of the serial chain, shaft first (friction pairs join neighbours): the shaft with
    #: flywheel and load, the crank throws, the rods, the pistons, and the cylinders, whose gas
    #: does its work on the pistons (so [shaft, crank] are the main bearings, [crank, rod] the
    #: crankpins, [rod, piston] the piston pins, [piston, cylinder] the pistons in their bores).
    links: ClassVar[tuple[str, ...]] = ("shaft", "crank", "rod", "piston", "cylinder")
    #: How each link's reduced inertia follows φ (``core.layout.LINK_*``): the crank's is
    #: constant, the rods' what J(φ) holds beyond the others, the pistons' m_p·Σ u_k².
    link_laws: ClassVar[tuple[int, ...]] = (LINK_FIXED, LINK_FIXED, LINK_REST, LINK_PISTONS, LINK_FIXED)
    #: Links for pairs with friction on their reactions (:mod:`transient.core.model.joint_friction`):
    #: the piston is a link of its own and the cylinder (the frame) the last, so the pairs are
    #: the main bearings, the crankpins, the piston pins and the pistons in their cylinders.
    reaction_links: ClassVar[tuple[str, ...]] = ("shaft", "crank", "rod", "piston", "cylinder")
    #: The joints reaction pairs may name: each link with its neighbour (a chain).
    reaction_joints: ClassVar[tuple[tuple[str, str], ...]] = tuple(zip(reaction_links, reaction_links[1:]))
    #: The solver of :mod:`transient.core.model.joint_friction`, which leaves each cylinder's
    #: side force for the stepper's side tracking.
    reaction_kernels: ClassVar[tuple[Any, Any, Any]] = (
        joint_friction.prepare, joint_friction.solve, joint_friction.inverse_drive)
    tracks_sides: ClassVar[bool] = True
    #: The reaction joint that may have a constant-η or mapped pair among reaction pairs: the
    #: main bearings, which couple the shaft to the mechanism (:mod:`transient.core.model.reactions`).
    shaft_coupling: ClassVar[tuple[str, str] | None] = ("shaft", "crank")

    @property
    def n_cylinders(self) -> int:
        return len(self.firing_angles)

    @property
    def cylinders_per_throw(self) -> int:
        """1, or 2 where two rods share a crankpin."""
        return 1 if self.rod_arrangement == SINGLE else 2

    @property
    def n_throws(self) -> int:
        return self.n_cylinders // self.cylinders_per_throw

    @property
    def crank_mass_per_cylinder(self) -> float:
        """Each cylinder's share of its throw's unbalanced mass [kg]: all of it, or half where
        two cylinders share the throw (at its own pin where the pins are split)."""
        return self.crank_mass / self.cylinders_per_throw

    @property
    def ideal_reaction_joints(self) -> dict[str, str]:
        """Joints that cannot have friction on their reactions (``scene.read``): the crankpin of
        fork-and-blade rods, where the blade turns on the fork's big end, which carries both
        rods' forces: the per-rod journal of the reaction model is not that bearing."""
        if self.rod_arrangement == "fork-and-blade":
            return {"crank": "the crankpin of fork-and-blade rods, where the blade turns on the "
                             "fork's big end, which carries both rods' forces"}
        return {}

    def reaction_reversals(self, cylinders=None) -> NDArray[np.float64]:
        """Shaft angles in [0, cycle) where a joint's relative motion reverses: each piston's
        dead centres (its speed) and its local 90° and 270° (the rod's rate β̇ ∝ cos α,
        :mod:`transient.core.model.joint_friction`); of the ``cylinders`` (0-based) only where
        given (an elastic line's throw, on its own angle)."""
        tdc, bdc = self.dead_centre_angles()
        phases = np.asarray(self.firing_angles, dtype=np.float64)
        if cylinders is not None:
            phases = phases[np.asarray(cylinders, dtype=np.int64)]
        return at_phases([tdc, 0.5 * pi, bdc, 1.5 * pi], phases, self.cycle)

    def check_wedging(self, s: Section, pairs, raw) -> None:
        """Friction must not wedge the crank-slider: the rod's equation in the side force N has a
        slope of at least l cos β (1 − q), q = μ_s tan β + (μ r of crankpin and pin)(1 + μ_s)/(l
        cos β) at the largest rod angle (:mod:`transient.core.model.joint_friction`); q < 1
        keeps it increasing, hence one solution at every state."""
        r, l, e = self.crank_radius, self.rod_length, self.offset
        sin_b = (r + abs(e)) / l
        cos_b = math.sqrt(max(1.0 - sin_b * sin_b, 0.0))
        by_joint = {p.between[0]: p for p in pairs}
        mu_s = by_joint["piston"].mu if "piston" in by_joint else 0.0
        mr = sum(by_joint[j].mu * by_joint[j].radius for j in ("crank", "rod") if j in by_joint)
        q = (mu_s * sin_b / cos_b + mr * (1.0 + mu_s) / (l * cos_b)) if cos_b > 0.0 else math.inf
        if q >= 1.0:
            i = next(i for i, item in enumerate(raw) if isinstance(item, dict)
                     and item.get("between", [None])[0] in ("piston", "crank", "rod"))
            raise SceneError(f"{s.key('pairs')}[{i}].mu",
                             f"the friction would wedge the mechanism: μ_slider·tan β_max + "
                             f"(μ·r of crankpin and pin)(1 + μ_slider)/(l cos β_max) = {q:.3g} "
                             f"≥ 1; allowed below 1 (lubricated pairs are around 0.01)")

    def throw_of_cylinder(self) -> NDArray[np.intp]:
        """The throw (0-based, from the nose) each cylinder rides on."""
        return np.arange(self.n_cylinders) // self.cylinders_per_throw

    def pin_angles(self) -> NDArray[np.float64]:
        """Each cylinder's crankpin angle ahead of the shaft's reference line, in the direction
        of rotation [rad], in [0, 2π): bank − firing (the crankpin stands at φ + this)."""
        return np.mod(np.asarray(self.bank_angles, dtype=np.float64)
                      - np.asarray(self.firing_angles, dtype=np.float64), 2.0 * pi)

    def axial_positions(self) -> NDArray[np.float64]:
        """Where each cylinder's rod bears along the shaft: its big end's middle plane from its
        throw's middle, toward the rear, over the journal spacing [1]; 0 but for side-by-side
        rods, which sit at ∓ rod_spacing / (2 journal_spacing)."""
        if self.rod_arrangement != "side-by-side":
            return np.zeros(self.n_cylinders)
        half = 0.5 * self.rod_spacing / self.journal_spacing
        return np.where(np.arange(self.n_cylinders) % 2 == 0, -half, half)

    def throw_angles(self) -> tuple[tuple[float, ...], float]:
        """Each throw's angle ahead of the shaft's reference line [rad] (the middle of its
        pins) and the split of its pins (the even cylinder's pin ahead of the odd one's) [rad]."""
        pins = self.pin_angles()
        if self.cylinders_per_throw == 1:
            return tuple(float(a) for a in pins), 0.0
        split = float(wrap_angle(pins[1] - pins[0]))
        return tuple(float(np.mod(a + split / 2.0, 2.0 * pi)) for a in pins[::2]), split

    def link_inertias(self) -> tuple[float, ...]:
        """Constant reduced inertia of each link besides the shaft's [kg m²]: the crank throws'
        n_throws·m_crank·r²; the rods' and the pistons' vary with φ (``link_laws``)."""
        return (0.0, self.n_throws * self.crank_mass * self.crank_radius ** 2, 0.0, 0.0, 0.0)

    @property
    def piston_link_mass(self) -> float:
        """m of the pistons' reduced inertia m·Σ_k u_k² [kg]: the piston group (the two-mass
        rod's share at the pin is the rod's)."""
        return self.piston_mass

    @property
    def piston_area(self) -> float:
        return pi * self.bore**2 / 4.0

    @property
    def cycle(self) -> float:
        """Cycle length in crank angle [rad]."""
        return 2.0 * pi * self.strokes / 2.0

    @property
    def lam(self) -> float:
        """λ = r/l."""
        return self.crank_radius / self.rod_length

    @classmethod
    def read(cls, s: Section) -> CrankSlider:
        """A :class:`CrankSlider` from the ``[mechanism]`` table (its ``type`` is read by the
        caller, who also finishes ``s``); errors name the keys as written."""
        r = s.number("crank_radius", "length", gt=0.0)
        l = s.number("rod_length", "length", gt=Named(r, "crank_radius"))
        strokes = s.integer("strokes", 4, choices=(2, 4))
        n = s.integer("cylinders", 1, ge=1, le=MAX_CYLINDERS)
        cycle = math.pi * strokes
        order = s.integers("firing_order", Named(tuple(range(1, n + 1)), "1, 2, …, cylinders"))
        if sorted(order) != list(range(1, n + 1)):
            raise SceneError(s.key("firing_order"),
                             f"must list each cylinder 1 … {n} once, got {list(order)}")
        crank = read_crank(s, n, cycle, order)
        reach = l - r  # (the rod must reach the axis at both dead centres: |e| < l − r)
        offset = s.number("offset", "length", 0.0, gt=Named(-reach, "−(rod_length − crank_radius)"),
                          lt=Named(reach, "rod_length − crank_radius"))
        rod = s.sub("rod", required=True)
        model = rod.string("model", "two-mass", choices=("two-mass", "rigid"))
        mech = cls(
            crank_radius=r, rod_length=l, offset=offset,
            bore=s.number("bore", "length", gt=0.0),
            piston_mass=s.number("piston_mass", "mass", gt=0.0),
            crank_mass=s.number("crank_mass", "mass", 0.0, ge=0.0), rod_model=model,
            rod_mass=rod.number("mass", "mass", gt=0.0),
            rod_cg_from_pin=rod.number("cg_from_pin", "length", ge=0.0,
                                       le=Named(l, "rod_length")),
            rod_inertia_cg=(rod.number("inertia_cg", "inertia", 0.0, ge=0.0) if model == "rigid"
                            else 0.0),
            strokes=strokes, **crank)
        rod.finish()
        try:
            mech.validate()
        except SceneError as exc:
            raise rod.rename(s.rename(exc)) from None
        return mech

    def validate(self) -> None:
        """Raise :class:`~transient.SceneError` for a geometry or mass set that cannot work."""
        r, l, e = self.crank_radius, self.rod_length, self.offset
        if not r > 0:
            raise SceneError("mechanism.crank_radius", f"must be > 0, got {r * 1e3:g} mm")
        if not l > 0:
            raise SceneError("mechanism.rod_length", f"must be > 0, got {l * 1e3:g} mm")
        if r / l >= 1.0:
            raise SceneError("mechanism.rod_length",
                             f"λ = r/l = {r / l:.4g} must be < 1: the rod ({l * 1e3:g} mm) must be "
                             f"longer than the crank radius ({r * 1e3:g} mm)")
        if abs(e) >= l - r:
            raise SceneError("mechanism.offset",
                             f"|offset| = {abs(e) * 1e3:g} mm is too large for the geometry; "
                             f"allowed |offset| < l − r = {(l - r) * 1e3:g} mm")
        if not self.bore > 0:
            raise SceneError("mechanism.bore", f"must be > 0, got {self.bore * 1e3:g} mm")
        if not self.piston_mass > 0:
            raise SceneError("mechanism.piston_mass", f"must be > 0 kg, got {self.piston_mass:g}")
        if not self.crank_mass >= 0:
            raise SceneError("mechanism.crank_mass", f"must be ≥ 0 kg, got {self.crank_mass:g}")
        if self.rod_model not in ("two-mass", "rigid"):
            raise SceneError("mechanism.rod.model",
                             f"unknown model {self.rod_model!r}; allowed: 'two-mass', 'rigid'")
        if not self.rod_mass > 0:
            raise SceneError("mechanism.rod.mass", f"must be > 0 kg, got {self.rod_mass:g}")
        if not 0.0 <= self.rod_cg_from_pin <= l:
            raise SceneError("mechanism.rod.cg_from_pin",
                             f"{self.rod_cg_from_pin * 1e3:g} mm is off the rod; allowed 0 … "
                             f"{l * 1e3:g} mm (the rod length)")
        if not self.rod_inertia_cg >= 0:
            raise SceneError("mechanism.rod.inertia_cg", f"must be ≥ 0, got {self.rod_inertia_cg:g}")
        if self.strokes not in (2, 4):
            raise SceneError("mechanism.strokes", f"must be 2 or 4, got {self.strokes}")
        if self.n_cylinders < 1:
            raise SceneError("mechanism.cylinders", "must be ≥ 1")
        for a in self.firing_angles:
            if not 0.0 <= a < self.cycle:
                raise SceneError("mechanism.firing",
                                 f"{degrees(a):g}° is outside the cycle; allowed 0 ≤ angle < "
                                 f"{degrees(self.cycle):g}°")
        self._validate_throws()

    def _validate_throws(self) -> None:
        """Two cylinders on a throw: an even count, on two banks, one pin for fork-and-blade
        rods and one split for every throw, side-by-side rods between the journals."""
        n, arrangement = self.n_cylinders, self.rod_arrangement
        if len(self.bank_angles) != n:
            raise SceneError("mechanism.bank", f"has {len(self.bank_angles)} entries; must have "
                                               f"one per cylinder ({n})")
        if arrangement not in (SINGLE, *SHARED):
            raise SceneError("mechanism.rod_arrangement",
                             f"unknown arrangement {arrangement!r}; allowed: "
                             f"{', '.join(map(repr, (SINGLE, *SHARED)))}")
        spacing = (self.rod_spacing, self.journal_spacing)
        if arrangement != "side-by-side" and spacing != (0.0, 0.0):
            raise SceneError("mechanism.rod_spacing",
                             f"applies to side-by-side rods only; with rod_arrangement = "
                             f"{arrangement!r} it and journal_spacing must be 0")
        if arrangement == SINGLE:
            return
        if n % 2:
            raise SceneError("mechanism.rod_arrangement",
                             f"two cylinders per throw need an even count, got {n}")
        banks = np.asarray(self.bank_angles)
        if np.any(np.abs(wrap_angle(banks[1::2] - banks[::2])) <= ANGLE_TOL):
            raise SceneError("mechanism.bank", "the two cylinders of a throw must sit on two "
                                               "banks")
        pins = self.pin_angles()
        splits = wrap_angle(pins[1::2] - pins[::2])
        if arrangement == "fork-and-blade" and np.any(np.abs(splits) > ANGLE_TOL):
            raise SceneError("mechanism.pin_split", "must be 0 for fork-and-blade rods, which "
                                                    "share one pin")
        if np.ptp(splits) > ANGLE_TOL:
            raise SceneError("mechanism.pin_split",
                             f"the throws' pins are split by {np.degrees(splits).round(6)}°; "
                             f"a crank has one split for every throw")
        if arrangement == "side-by-side" and not 0.0 < self.rod_spacing < self.journal_spacing:
            raise SceneError("mechanism.rod_spacing",
                             f"{self.rod_spacing * 1e3:g} mm must be > 0 and less than the "
                             f"journal spacing ({self.journal_spacing * 1e3:g} mm): both big "
                             f"ends run between the throw's journals")

    def pack(self) -> NDArray[np.float64]:
        """Parameter array for :func:`transient.core.model.crank_slider.crank_slider_terms`."""
        l = self.rod_length
        n = self.n_cylinders
        mp = np.zeros(core.SIN0 + 2 * n)
        mp[core.R] = self.crank_radius
        mp[core.L] = l
        mp[core.E] = self.offset
        mp[core.M_PISTON] = self.piston_mass
        mp[core.M_CRANK] = self.crank_mass_per_cylinder
        if self.rod_model == "two-mass":  # Gots (20): m₁ = m(l − l₁)/l at the pin, m₂ = m l₁/l
            mp[core.M_PIN] = self.rod_mass * (l - self.rod_cg_from_pin) / l
            mp[core.M_CRANKPIN] = self.rod_mass * self.rod_cg_from_pin / l
        else:
            mp[core.M_ROD] = self.rod_mass
            mp[core.ROD_CG] = self.rod_cg_from_pin
            mp[core.I_ROD] = self.rod_inertia_cg
        mp[core.N_CYL] = self.n_cylinders
        phase = np.asarray(self.firing_angles, dtype=np.float64)
        mp[core.SIN0:core.SIN0 + n] = np.sin(phase)
        mp[core.SIN0 + n:] = np.cos(phase)
        return mp

    def pack_cylinders(self, cylinders) -> NDArray[np.float64]:
        """:meth:`pack` of the mechanism made of the ``cylinders`` (0-based) alone, each at its
        own phase: an elastic line's throw, whose joints its reaction solver solves at the
        throw's own angle (capability ``"cylinder-inertia"``)."""
        mp = self.pack()
        n = self.n_cylinders
        which = np.asarray(cylinders, dtype=np.int64)
        out = np.zeros(core.SIN0 + 2 * which.size)
        out[:core.SIN0] = mp[:core.SIN0]
        out[core.N_CYL] = which.size
        out[core.SIN0:core.SIN0 + which.size] = mp[core.SIN0 + which]
        out[core.SIN0 + which.size:] = mp[core.SIN0 + n + which]
        return out

    def toml_lines(self) -> list[str]:
        """The ``[mechanism]`` and ``[mechanism.rod]`` tables in SI, read back by
        :meth:`read` to an equal object."""
        keys = {"type": self.name, "crank_radius": self.crank_radius,
                "rod_length": self.rod_length, "offset": self.offset, "bore": self.bore,
                "piston_mass": self.piston_mass, "crank_mass": self.crank_mass,
                "strokes": self.strokes, "cylinders": self.n_cylinders,
                "firing": list(self.firing_angles), "bank": list(self.bank_angles)}
        keys.update(self._crank_keys())
        rod = {"model": self.rod_model, "mass": self.rod_mass, "cg_from_pin": self.rod_cg_from_pin}
        if self.rod_model == "rigid":
            rod["inertia_cg"] = self.rod_inertia_cg
        return (["[mechanism]"] + [f"{k} = {toml_value(v)}" for k, v in keys.items()]
                + ["", "[mechanism.rod]"] + [f"{k} = {toml_value(v)}" for k, v in rod.items()])

    def _crank_keys(self) -> dict:
        """The keys that place a V engine's cylinders on the crank (:mod:`.throws`); none for an
        in-line engine, whose firing gives its crank."""
        if self.rod_arrangement == SINGLE and equal_angles(self.bank_angles):
            return {}
        throws, split = self.throw_angles()
        keys: dict[str, object] = {"throws": list(throws)}
        if self.rod_arrangement != SINGLE:
            keys["rod_arrangement"] = self.rod_arrangement
        if self.rod_arrangement == "side-by-side":
            keys.update(pin_split=split, rod_spacing=self.rod_spacing,
                        journal_spacing=self.journal_spacing)
        return keys

    def tdc_angle(self) -> float:
        """Local crank angle of the true top dead centre, Gots (9): sin φ₁ = e/(l + r)."""
        return asin(self.offset / (self.rod_length + self.crank_radius))

    def dead_centre_angles(self) -> tuple[float, float]:
        """Local angles [rad] of the true dead centres, where crank and rod are in line: at TDC
        stretched (the pin at l + r from the piston, Gots (9): sin φ₁ = e/(l + r)), at BDC
        folded (the crank pointing away from the piston at l − r: φ₂ = π + asin(e/(l − r)))."""
        r, l, e = self.crank_radius, self.rod_length, self.offset
        return asin(e / (l + r)), pi + asin(e / (l - r))

    def stroke(self) -> float:
        """Exact stroke, Gots (11)."""
        r, l, e = self.crank_radius, self.rod_length, self.offset
        return np.sqrt((l + r) ** 2 - e**2) - np.sqrt((l - r) ** 2 - e**2)

    def swept_volume(self) -> float:
        """Swept volume of one cylinder, F_p·S [m³]."""
        return self.piston_area * self.stroke()

    def geometry(self) -> dict[str, tuple[float, str]]:
        """What the geometry implies, name → (value, unit), every cylinder alike: ``lambda``
        λ = r/l and ``offset_ratio`` k = e/r (Gots §1.4), ``stroke`` S (11), ``tdc`` and ``bdc``
        the local crank angles of the true dead centres (:meth:`dead_centre_angles`; 0 and π
        without offset), ``swept_volume`` V_h = F_p·S and ``displacement`` i·V_h (Gots §2.2)."""
        tdc, bdc = self.dead_centre_angles()
        return {"lambda": (self.lam, "1"),
                "offset_ratio": (self.offset / self.crank_radius, "1"),
                "stroke": (float(self.stroke()), "m"), "tdc": (tdc, "rad"), "bdc": (bdc, "rad"),
                "swept_volume": (float(self.swept_volume()), "m^3"),
                "displacement": (float(self.n_cylinders * self.swept_volume()), "m^3")}

    def kinematics_table(self, phi: NDArray[np.float64]) -> dict[str, NDArray[np.float64]]:
        """Positions, transfer functions and J(φ), dJ/dφ of the moving parts over ``phi`` [rad]."""
        mp = self.pack()
        n = self.n_cylinders
        cols: dict[str, list[float]] = {"phi_deg": list(np.degrees(phi)), "J": [], "dJ_dphi": []}
        per: dict[str, list[float]] = {f"{name}_{k + 1}": [] for k in range(n) for name in ("s", "u", "du", "beta_deg")}
        u = np.empty(n)
        du = np.empty(n)
        for p in phi:
            J, dJ = core.crank_slider_terms(mp, p, u, du)
            cols["J"].append(J)
            cols["dJ_dphi"].append(dJ)
            for k in range(n):
                s, ds, dds, beta, _, _ = core.slider(p - self.firing_angles[k], self.crank_radius,
                                                     self.rod_length, self.offset)
                per[f"s_{k + 1}"].append(s)
                per[f"u_{k + 1}"].append(ds)
                per[f"du_{k + 1}"].append(dds)
                per[f"beta_deg_{k + 1}"].append(degrees(beta))
        cols.update(per)
        return {k: np.asarray(v) for k, v in cols.items()}

    def volume_function(self, clearance: float):
        """V(x) = V_c + F_p·s(x) over the local angle x [rad] (vectorised), for the cycle models."""
        r, l, e, area = self.crank_radius, self.rod_length, self.offset, self.piston_area

        def volume(x):
            x = np.asarray(x, dtype=float)
            sb = (r * np.sin(x) - e) / l
            s = np.sqrt((l + r) ** 2 - e * e) - (r * np.cos(x) + l * np.sqrt(1.0 - sb * sb))
            return clearance + area * s

        return volume

    def reference_terms(self) -> Callable[[float], tuple]:
        """φ ↦ (J, dJ/dφ, u_k, u′_k) for the reference path: the numpy twin written from the Gots
        relations (:class:`~.twins.CrankSliderNumpy`), independent of the kernel."""
        return self.twin(self).terms

    @property
    def crankpins(self) -> tuple[tuple[int, ...], ...]:
        """The cylinders (0-based) of each throw, from the nose (capability
        ``"cylinder-inertia"``)."""
        throw = self.throw_of_cylinder()
        return tuple(tuple(int(k) for k in np.flatnonzero(throw == t))
                     for t in range(self.n_throws))

    def cylinder_inertia_terms(self) -> Callable[[float], tuple[NDArray[np.float64],
                                                                NDArray[np.float64]]]:
        """θ ↦ (J_k, dJ_k/dθ) per cylinder, from the numpy twin's per-cylinder terms (each
        cylinder's slider, rotating, rod and rod-rotation parts), whose sum is J(θ)."""
        return self.twin(self).cylinder_terms

    def analysis_summary(self) -> dict[str, tuple[float, str]]:
        """Figures of the mechanism itself for a result's ``/analysis``: none here."""
        return {}

