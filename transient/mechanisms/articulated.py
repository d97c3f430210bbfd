"""Radial and V engines with a master rod and articulated (slave) rods (Semenov §§1, 3, 4): one
idea, the articulated mechanism, as each mechanism has its one module.

The compiled kinematics and the frame are described in :mod:`transient.core.model.articulated`; this
module holds the scene-side description (SI units), packs it for the kernel, and gives the numpy
geometry of every body (:func:`positions`), the slave dimensions of Semenov (6)–(7)
(:func:`slave_dimensions`), the exact dead centres and strokes that (55)–(58) approximate
(:func:`dead_centres`, :func:`piston_strokes`), the exact dynamic parameter λ_i that (61)
approximates (:func:`dynamic_parameters`), all of them by name in :meth:`Articulated.geometry`,
and the harmonics of the slave pistons from the exact geometry beside Semenov's series (45),
(47), (50) and (61) (:func:`harmonics`).

A row is one crankpin with a master rod and z′ slaves; all rows share one geometry and differ by the
angle of their master cylinder (``row_banks``) and of their crankpin (``row_cranks``). Cylinders
are numbered row by row, the master first: k = j(1 + z′) + i, i = 0 the master.

How it fills the mechanism interface (:class:`transient.mechanisms.Mechanism`):

* ``volume_function`` and ``stroke`` describe the master cylinder, an exact centred crank-slider
  (stroke 2r, dead centres at α = 0, π). Every cylinder gets the same pressure table, shifted to its
  own firing TDC: the slaves' slightly different strokes and motion laws (Semenov §4, 2nd-harmonic
  distortion) are not fed back into the cycle.
* ``firing_angles`` default to each piston's exact outer dead centre (not the bank angle δ_i: the
  slave reaches it a little off, (55)–(57)) plus, for a four-stroke, 360° for every second cylinder
  of a row — the firing order 1-3-5-2-4 of a five-cylinder radial, even firing for any odd z.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, partial
from math import cos, degrees, hypot, inf, pi, sin, sqrt
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.model import articulated as core
from ..core.model import articulated_friction
from ..core.model.layout import LINK_FIXED, LINK_PISTONS, LINK_REST
from ..errors import SceneError
from ..roots import bisect_root
from ..tomlout import toml_value
from ..units import Named
from .crank_slider import CrankSlider
from .throws import at_phases
from .twins import KernelTwin

if TYPE_CHECKING:
    from ..scene.reader import Section

#: Samples per turn of the sampled checks and of the Fourier analysis (exact to rounding: the
#: harmonics fall like λ^k, and 512 samples alias order 512 − k onto k).
SAMPLES = 512

# What each key of its ``[mechanism]`` table and sub-tables means, in a line: the scene-key
# reference (docs/guide/scene_keys) shows it beside what the reader asks of the key.
KEY_MEANINGS = {
    "mechanism": {
        "crank_radius": "Crank radius r, half the master piston's stroke.",
        "rod_length": "Master rod length l, crankpin to master piston pin; λ = r/l < 1.",
        "strokes": "Strokes per cycle: 4 (a cycle of 720°) or 2 (360°).",
        "bank": "Each slave cylinder's axis δ_i from the master cylinder's, in the direction "
                "of rotation; one per slave.",
        "link_angle": "Each link pin's angle ψ_i from the master-rod axis; one per slave.",
        "link_radius": "Each link pin's distance r_i from the crankpin centre (0: central "
                       "articulation); one number or one per slave; without it, from "
                       "``slave_rod_length`` by Semenov (6)–(7).",
        "slave_rod_length": "Each slave rod's length l_i, link pin to piston pin; one number "
                            "or one per slave; without it, from ``link_radius`` by Semenov "
                            "(6)–(7); it must reach its cylinder's axis.",
        "rows": "Rows of cylinders, one crankpin and master rod each.",
        "row_bank": "Each row's master cylinder axis from row 1's.",
        "row_crank": "Each row's crankpin from row 1's.",
        "rod": "The master rod (``[mechanism.rod]``).",
        "slave_rod": "Every slave rod (``[mechanism.slave_rod]``).",
        "bore": "Cylinder bore, every cylinder.",
        "piston_mass": "Mass of each piston group.",
        "crank_mass": "Unbalanced crank-throw mass reduced to the crank radius, per row.",
        "firing": "Each cylinder's firing angle, one per cylinder, in [0, cycle).",
    },
    "mechanism.rod": {
        "model": "``two-mass`` or ``rigid``, as the crank-slider's rod; its link pins are part "
                 "of it.",
        "mass": "Mass of the master rod.",
        "cg_from_pin": "Distance from the master piston pin to its centre of mass, along its "
                       "axis.",
        "inertia_cg": "Moment of inertia about its centre of mass (``rigid``).",
    },
    "mechanism.slave_rod": {
        "model": "``two-mass`` or ``rigid``, as the master rod.",
        "mass": "Mass of each slave rod.",
        "cg_from_pin": "Distance from the slave piston pin to its centre of mass.",
        "inertia_cg": "Moment of inertia about its centre of mass (``rigid``).",
    },
}


def _per_slave(s: Section, name: str, n: int, **bounds) -> tuple[float, ...] | None:
    """A length given once for every slave or as a list of one per slave, within ``bounds``
    (:meth:`Section.number`'s); None if absent."""
    raw = next((s.data[k] for k in (name, f"{name}_mm") if k in s.data), None)
    other = Named(None, "from the other of link_radius, slave_rod_length (Semenov (6)–(7))")
    if isinstance(raw, list):
        values = s.numbers(name, "length", other, **bounds)
        if len(values) != n:
            raise s.rename(SceneError(s.key(name), f"has {len(values)} entries; must have one per "
                                                   f"slave cylinder ({n}), or give one number"))
        return values
    value = s.number(name, "length", other, **bounds)
    return None if value is None else (value,) * n


@dataclass(frozen=True, kw_only=True)
class Articulated:
    """A master-and-articulated-rod engine (radial, or V with a slave rod).

    Attributes
    ----------
    crank_radius, rod_length : float
        r and the master rod l between the crankpin and the master piston pin [m]; λ = r/l < 1.
    bore : float
        Cylinder bore [m], every cylinder.
    piston_mass : float
        Piston group mass [kg], every piston.
    crank_mass : float
        Unbalanced crank-throw mass reduced to r [kg], per row.
    rod_model, rod_mass, rod_cg_from_pin, rod_inertia_cg
        The master rod as a crank-slider's rod (``"two-mass"`` or ``"rigid"``; kg, m from the master
        piston pin along its axis, kg m² about the centre of mass); its link pins are part of it.
    slave_banks : tuple of float
        δ_i [rad], slave cylinder axes from the master cylinder, in the direction of rotation.
    link_angles : tuple of float
        ψ_i [rad], link pins from the master-rod axis (crankpin → piston pin), same sense.
    link_radii : tuple of float
        r_i [m], link pins from the crankpin centre; 0 is central articulation (slave on the
        crankpin, Semenov §3).
    slave_lengths : tuple of float
        l_i [m], slave rods between link pin and piston pin.
    slave_rod_model, slave_rod_mass, slave_rod_cg_from_pin, slave_rod_inertia_cg
        Every slave rod, as the master rod (centre of mass from the slave piston pin).
    strokes : int
        2 or 4.
    row_banks, row_cranks : tuple of float
        Per row [rad]: its master cylinder's axis and its crankpin, from row 1's (row 1: 0, 0).
    firing : tuple of float
        Shaft angle [rad] of each cylinder's firing TDC, or () for the default (module docstring).
    """

    crank_radius: float
    rod_length: float
    bore: float
    piston_mass: float
    crank_mass: float = 0.0
    rod_model: str = "rigid"
    rod_mass: float
    rod_cg_from_pin: float
    rod_inertia_cg: float = 0.0
    slave_banks: tuple[float, ...]
    link_angles: tuple[float, ...]
    link_radii: tuple[float, ...]
    slave_lengths: tuple[float, ...]
    slave_rod_model: str = "two-mass"
    slave_rod_mass: float
    slave_rod_cg_from_pin: float
    slave_rod_inertia_cg: float = 0.0
    strokes: int = 4
    row_banks: tuple[float, ...] = (0.0,)
    row_cranks: tuple[float, ...] = (0.0,)
    firing: tuple[float, ...] = ()

    #: Its ``type`` in the ``[mechanism]`` table (:data:`transient.mechanisms.MECHANISMS`).
    name: ClassVar[str] = "articulated"
    #: Its compiled kernel (``Model.terms``).
    kernel: ClassVar[Any] = staticmethod(core.terms)
    #: Its compiled kernel of each cylinder's share of J at its station's angle (``shares``).
    shares_kernel: ClassVar[Any] = staticmethod(core.shares)
    #: Beyond :class:`~transient.mechanisms.Mechanism` (:data:`~transient.mechanisms.CAPABILITIES`):
    #: no numpy twin (the reference path runs the kernel's Python code).
    capabilities: ClassVar[frozenset[str]] = frozenset(
        {"reaction-friction", "reaction-twin", "pistons", "loads", "drawers"})
    #: No wall heat transfer: the cylinder ODE is built for the crank-slider's volume.
    wall_heat_transfer: ClassVar[bool] = False
    cylinder_count: ClassVar[str] = "mechanism.rows × (1 + the slaves in mechanism.bank)"
    key_meanings: ClassVar[dict[str, dict[str, str]]] = KEY_MEANINGS
    #: The slave pistons do not follow the crank-slider's law, from which the analyses derive W_k.
    slider_law: ClassVar[bool] = False
    #: Links of the serial chain, shaft first, as the crank-slider's: the crank throws, the rods
    #: (each row's master rod with its slave rods: the link pins join them inside the link, the
    #: master piston hanging on the master rod beside the slaves, not beyond them), the pistons
    #: and the cylinders, whose gas does its work on the pistons.
    links: ClassVar[tuple[str, ...]] = ("shaft", "crank", "rod", "piston", "cylinder")
    #: How each link's reduced inertia follows φ (``core.layout.LINK_*``), as the crank-slider's.
    link_laws: ClassVar[tuple[int, ...]] = (LINK_FIXED, LINK_FIXED, LINK_REST, LINK_PISTONS, LINK_FIXED)
    #: Links for pairs with friction on their reactions
    #: (:mod:`transient.core.model.articulated_friction`).
    reaction_links: ClassVar[tuple[str, ...]] = (
        "shaft", "crank", "master rod", "slave rod", "piston", "cylinder")
    #: The joints such a pair may name, in the order of ``articulated_friction.J_*``: the main
    #: bearings, the master crankpins, the link pins, the master piston pins, the slave piston
    #: pins and the pistons in their cylinders (every cylinder of every row that the joint has).
    reaction_joints: ClassVar[tuple[tuple[str, str], ...]] = (
        ("shaft", "crank"), ("crank", "master rod"), ("master rod", "slave rod"), ("master rod", "piston"),
        ("slave rod", "piston"), ("piston", "cylinder"))
    #: The reaction joint that may have a constant-η or mapped pair among reaction pairs: the
    #: main bearings, which couple the shaft to the mechanism (:mod:`transient.core.model.reactions`).
    shaft_coupling: ClassVar[tuple[str, str] | None] = ("shaft", "crank")
    #: The solver of :mod:`transient.core.model.articulated_friction`, which keeps its side
    #: forces apart from the crank-slider's side tracking.
    reaction_kernels: ClassVar[tuple[Any, Any, Any]] = (
        articulated_friction.prepare, articulated_friction.solve, articulated_friction.inverse_drive)
    tracks_sides: ClassVar[bool] = False
    #: No joint of it is kept ideal.
    ideal_reaction_joints: ClassVar[dict[str, str]] = {}

    # -- sizes and constants ---------------------------------------------------------------------
    @property
    def n_slaves(self) -> int:
        return len(self.slave_banks)

    @property
    def rows(self) -> int:
        return len(self.row_banks)

    @property
    def n_cylinders(self) -> int:
        return self.rows * (1 + self.n_slaves)

    @property
    def piston_area(self) -> float:
        return pi * self.bore**2 / 4.0

    @property
    def cycle(self) -> float:
        """Cycle length in crank angle [rad]."""
        return pi * self.strokes

    @property
    def lam(self) -> float:
        """λ = r/l of the master rod."""
        return self.crank_radius / self.rod_length

    @property
    def row_phases(self) -> tuple[float, ...]:
        """Shaft angle at which each row is at local angle α = 0 (crankpin on its master axis)."""
        return tuple(b - c for b, c in zip(self.row_banks, self.row_cranks))

    @property
    def bank_angles(self) -> tuple[float, ...]:
        """Axis of every cylinder [rad] from row 1's master cylinder, in the direction of rotation."""
        return tuple(b + d for b in self.row_banks for d in (0.0,) + self.slave_banks)

    def link_inertias(self) -> tuple[float, ...]:
        """Constant reduced inertia per link besides the shaft's [kg m²]: the crank throws'."""
        return (0.0, self.rows * self.crank_mass * self.crank_radius**2, 0.0, 0.0, 0.0)

    @property
    def piston_link_mass(self) -> float:
        """m of the pistons' reduced inertia m·Σ_k u_k² [kg]: every piston's group mass."""
        return self.piston_mass

    def master(self) -> CrankSlider:
        """The master cylinder alone, a centred crank-slider (its kernel header and its volume)."""
        return CrankSlider(
            crank_radius=self.crank_radius, rod_length=self.rod_length, offset=0.0,
            bore=self.bore, piston_mass=self.piston_mass, crank_mass=self.crank_mass,
            rod_model=self.rod_model, rod_mass=self.rod_mass,
            rod_cg_from_pin=self.rod_cg_from_pin, rod_inertia_cg=self.rod_inertia_cg,
            strokes=self.strokes, firing_angles=(0.0,), bank_angles=(0.0,))

    # -- reading, validation and packing ---------------------------------------------------------
    @classmethod
    def read(cls, s: Section) -> Articulated:
        """An :class:`Articulated` from the ``[mechanism]`` table (its ``type`` is read by the
        caller).

        Keys (lengths in m or ``_mm``, angles in rad or ``_deg``): the master cylinder as a
        crank-slider's — ``crank_radius``, ``rod_length``, ``bore``, ``piston_mass``,
        ``crank_mass`` (per row), ``strokes``, and the master rod in ``[mechanism.rod]``; the
        slaves — ``bank`` (δ_i, a list), ``link_angle`` (ψ_i, default = bank), ``link_radius``
        (r_i) and/or ``slave_rod_length`` (l_i), each one number or a list, the missing one from
        Semenov (6)–(7), and every slave rod in ``[mechanism.slave_rod]``; ``rows`` (1),
        ``row_bank`` (0 …), ``row_crank`` (360°·j/rows), ``firing`` (optional, one per
        cylinder).
        """
        r = s.number("crank_radius", "length", gt=0.0)
        l = s.number("rod_length", "length", gt=Named(r, "crank_radius"))
        strokes_ = s.integer("strokes", 4, choices=(2, 4))
        banks = s.numbers("bank", "angle")
        n = len(banks)
        if n < 1:
            raise s.rename(SceneError(s.key("bank"), "must list at least one slave cylinder"))
        psi = s.numbers("link_angle", "angle", Named(banks, "bank"))
        if len(psi) != n:
            raise s.rename(SceneError(s.key("link_angle"), f"has {len(psi)} entries; must have one "
                                                           f"per slave cylinder ({n})"))
        ri = _per_slave(s, "link_radius", n, ge=0.0, lt=Named(l, "rod_length"))
        li = _per_slave(s, "slave_rod_length", n, gt=0.0)
        if ri is None and li is None:
            raise SceneError(s.key("link_radius"), "is missing; give link_radius and/or "
                                                   "slave_rod_length (the other follows from "
                                                   "Semenov (6)–(7))")
        if ri is None or li is None:
            dims = [slave_dimensions(r, l, d, None if ri is None else ri[i],
                                     None if li is None else li[i]) for i, d in enumerate(banks)]
            computed = "link_radius" if ri is None else "slave_rod_length"
            ri, li = tuple(x for x, _ in dims), tuple(y for _, y in dims)
        else:
            computed = None
        rows = s.integer("rows", 1, ge=1)
        row_bank = s.numbers("row_bank", "angle", Named((0.0,) * rows, "0° for every row"))
        row_crank = s.numbers("row_crank", "angle", Named(
            tuple(2 * pi * j / rows for j in range(rows)), "360° · (row − 1)/rows"))
        if len(row_bank) != rows:
            raise s.rename(SceneError(s.key("row_bank"), f"has {len(row_bank)} entries; must have "
                                                         f"one per row ({rows})"))
        rods: dict[str, dict[str, Any]] = {}
        # (the master rod carries the master piston: a mass; a slave rod may be massless)
        for table, massless, length in (("rod", False, Named(l, "rod_length")),
                                        ("slave_rod", True,
                                         Named(min(li), "the shortest slave_rod_length"))):
            rod = s.sub(table, required=True)
            model = rod.string("model", "two-mass", choices=("two-mass", "rigid"))
            mass = (rod.number("mass", "mass", ge=0.0) if massless
                    else rod.number("mass", "mass", gt=0.0))
            rods[table] = dict(model=model, mass=mass,
                               cg_from_pin=rod.number("cg_from_pin", "length", ge=0.0,
                                                      le=length),
                               inertia_cg=(rod.number("inertia_cg", "inertia", 0.0, ge=0.0)
                                           if model == "rigid" else 0.0))
            rod.finish()
        mech = cls(
            crank_radius=r, rod_length=l, bore=s.number("bore", "length", gt=0.0),
            piston_mass=s.number("piston_mass", "mass", gt=0.0),
            crank_mass=s.number("crank_mass", "mass", 0.0, ge=0.0),
            **{f"rod_{k}": v for k, v in rods["rod"].items()},
            slave_banks=banks, link_angles=psi, link_radii=ri, slave_lengths=li,
            **{f"slave_rod_{k}": v for k, v in rods["slave_rod"].items()},
            strokes=strokes_, row_banks=row_bank, row_cranks=row_crank,
            firing=s.numbers("firing", "angle", Named((), "each cylinder's outer dead centre, "
                                                          "firing evenly (1-3-5-2-4 for five)")))
        try:
            mech.validate()
        except SceneError as exc:
            if computed and exc.key == f"mechanism.{computed}":
                exc.key = s.key("link_radius" if computed == "slave_rod_length" else
                                "slave_rod_length")
                exc.message += f" ({computed} from Semenov (6)–(7))"
            raise s.rename(exc) from None
        return mech

    def validate(self) -> None:
        """Raise :class:`~transient.SceneError` for a geometry or mass set that cannot work or
        assemble."""
        self.master().validate()
        n, l = self.n_slaves, self.rod_length
        for key, values in (("link_angle", self.link_angles), ("link_radius", self.link_radii),
                            ("slave_rod_length", self.slave_lengths)):
            if len(values) != n:
                raise SceneError(f"mechanism.{key}", f"has {len(values)} entries; must have one "
                                                     f"per slave cylinder ({n})")
        for i, (ri, li) in enumerate(zip(self.link_radii, self.slave_lengths)):
            if not 0.0 <= ri < l:
                raise SceneError("mechanism.link_radius",
                                 f"link pin {i + 1} at {ri * 1e3:g} mm is outside the master rod; "
                                 f"allowed 0 ≤ r_i < l = {l * 1e3:g} mm")
            if not li > 0.0:
                raise SceneError("mechanism.slave_rod_length",
                                 f"slave rod {i + 1}: must be > 0, got {li * 1e3:g} mm")
        reach = slave_reach(self)
        for i, (li, h) in enumerate(zip(self.slave_lengths, reach)):
            if not h < li:
                raise SceneError("mechanism.slave_rod_length",
                                 f"slave rod {i + 1} ({li * 1e3:g} mm) is too short for its "
                                 f"cylinder at {degrees(self.slave_banks[i]):g}°: its link pin "
                                 f"swings {h * 1e3:.4g} mm off the axis; allowed l_i > "
                                 f"{h * 1e3:.4g} mm")
        if self.slave_rod_model not in ("two-mass", "rigid"):
            raise SceneError("mechanism.slave_rod.model", f"unknown model "
                             f"{self.slave_rod_model!r}; allowed: 'two-mass', 'rigid'")
        if not self.slave_rod_mass >= 0:
            raise SceneError("mechanism.slave_rod.mass",
                             f"must be ≥ 0 kg, got {self.slave_rod_mass:g}")
        if not 0.0 <= self.slave_rod_cg_from_pin <= min(self.slave_lengths, default=np.inf):
            raise SceneError("mechanism.slave_rod.cg_from_pin",
                             f"{self.slave_rod_cg_from_pin * 1e3:g} mm is off the slave rods; "
                             f"allowed 0 … {min(self.slave_lengths) * 1e3:g} mm (the shortest)")
        if not self.slave_rod_inertia_cg >= 0:
            raise SceneError("mechanism.slave_rod.inertia_cg",
                             f"must be ≥ 0, got {self.slave_rod_inertia_cg:g}")
        if len(self.row_cranks) != self.rows:
            raise SceneError("mechanism.row_crank", f"has {len(self.row_cranks)} entries; must "
                                                    f"have one per row ({self.rows})")
        if self.firing:
            if len(self.firing) != self.n_cylinders:
                raise SceneError("mechanism.firing", f"has {len(self.firing)} entries; must have "
                                                     f"one per cylinder ({self.n_cylinders})")
            for a in self.firing:
                if not 0.0 <= a < self.cycle:
                    raise SceneError("mechanism.firing",
                                     f"{degrees(a):g}° is outside the cycle; allowed 0 ≤ angle < "
                                     f"{degrees(self.cycle):g}°")

    def pack(self) -> NDArray[np.float64]:
        """Parameter array for :func:`transient.core.model.articulated.articulated_terms`."""
        ns = self.n_slaves
        mp = np.zeros(core.SLAVE0 + core.SLAVE_STRIDE * ns + self.rows)
        mp[:core.N_ROWS] = self.master().pack()[:core.N_ROWS]  # the crank-slider header
        mp[core.N_ROWS] = self.rows
        mp[core.N_SLAVES] = ns
        cg = self.slave_rod_cg_from_pin
        for i in range(ns):
            k = core.SLAVE0 + core.SLAVE_STRIDE * i
            ri, psi, li, delta = (self.link_radii[i], self.link_angles[i], self.slave_lengths[i],
                                  self.slave_banks[i])
            mp[k + core.LINK_A] = ri * cos(psi)
            mp[k + core.LINK_Q] = ri * sin(psi)
            mp[k + core.COS_D] = cos(delta)
            mp[k + core.SIN_D] = sin(delta)
            mp[k + core.SLAVE_L] = li
            mp[k + core.SLAVE_PISTON] = self.piston_mass
            mp[k + core.SLAVE_ROD] = self.slave_rod_mass
            mp[k + core.SLAVE_CG] = cg
            # Two masses m(l − c)/l at the piston pin and m c/l at the link pin are the rigid rod
            # with I = m c (l − c) about its centre of mass.
            mp[k + core.SLAVE_I] = (self.slave_rod_inertia_cg if self.slave_rod_model == "rigid"
                                    else self.slave_rod_mass * cg * (li - cg))
        mp[core.SLAVE0 + core.SLAVE_STRIDE * ns:] = self.row_phases
        return mp

    # -- what the rest of transient asks of a mechanism -----------------------------------------
    @cached_property
    def firing_angles(self) -> tuple[float, ...]:
        """Shaft angle [rad] in [0, cycle) of each cylinder's firing TDC (module docstring)."""
        if self.firing:
            return self.firing
        tdc, _ = dead_centres(self)
        out = []
        for phase in self.row_phases:
            for i, a in enumerate(tdc):
                extra = 2.0 * pi * (i % 2) if self.strokes == 4 else 0.0
                out.append(float((phase + a + extra) % self.cycle))
        return tuple(0.0 if a >= self.cycle else a for a in out)

    def stroke(self) -> float:
        """Stroke of the master piston, 2r exactly (Semenov (1), (20)); slaves: :func:`dead_centres`."""
        return 2.0 * self.crank_radius

    def swept_volume(self) -> float:
        """Swept volume of the master cylinder, F_p·2r [m³]."""
        return self.piston_area * self.stroke()

    def volume_function(self, clearance: float):
        """V(x) of the master cylinder over its local angle x [rad] (vectorised)."""
        return self.master().volume_function(clearance)

    def reaction_reversals(self) -> NDArray[np.float64]:
        """Shaft angles [rad] in [0, cycle) where a joint's relative motion reverses: the row's
        (:meth:`row_reversals`) at each row's phase."""
        return at_phases(self.row_reversals(), self.row_phases, self.cycle)

    def check_wedging(self, s: Section, pairs, raw) -> None:
        """Friction must not wedge a rod: as for the crank-slider
        (:meth:`~transient.mechanisms.crank_slider.CrankSlider.check_wedging`), each rod's equation
        in its piston's side force has a slope of at least c (1 − q), q = μ_slider tan β_max + (μ r
        of its two pins)(1 + μ_slider)/c with c = l cos β_max at its largest angle to its cylinder
        (the master rod: sin β_max = λ; slave rod i: its link pin's largest offset from its axis
        over l_i, :func:`slave_reach`); q < 1 for every rod keeps the row's equations solvable
        (:mod:`transient.core.model.articulated_friction`)."""
        by_joint = {p.between: p for p in pairs}
        joints = self.reaction_joints

        def mu_r(j: int) -> float:
            p = by_joint.get(joints[j])
            return p.mu * p.radius if p is not None else 0.0

        slider = by_joint.get(joints[5])
        mu_s = slider.mu if slider is not None else 0.0
        rods = [(self.rod_length, self.crank_radius, mu_r(1) + mu_r(3), "master rod")]
        rods += [(li, h, mu_r(2) + mu_r(4), f"slave rod {i + 1}")
                 for i, (li, h) in enumerate(zip(self.slave_lengths, slave_reach(self)))]
        for length, reach, mr, rod in rods:
            sin_b = reach / length
            cos_b = sqrt(max(1.0 - sin_b * sin_b, 0.0))
            c = length * cos_b
            q = (mu_s * sin_b / cos_b + mr * (1.0 + mu_s) / c) if cos_b > 0.0 else inf
            if q >= 1.0:
                i = next(i for i, item in enumerate(raw) if isinstance(item, dict)
                         and item.get("between", [None])[-1] in ("cylinder", "piston",
                                                                  "slave rod", "master rod"))
                raise SceneError(f"{s.key('pairs')}[{i}].mu",
                                 f"the friction would wedge the {rod}: μ_slider·tan β_max + "
                                 f"(μ·r of its pins)(1 + μ_slider)/(l cos β_max) = {q:.3g} ≥ 1; "
                                 f"allowed below 1 (lubricated pairs are around 0.01)")

    def row_reversals(self) -> NDArray[np.float64]:
        """Local angles α [rad] in [0, 2π) of a row where a joint's relative rate changes sign
        (:mod:`transient.core.model.articulated_friction`, *Directions*): the master piston's dead
        centres 0, π and the master rod's β′ = 0 at π/2, 3π/2 exactly; per slave the roots of
        its piston's X_i′, of its rod's β_i′ and of its link pin's β_i′ + β′, bracketed on a
        grid and refined by bisection to the last bit. The crankpin's −β′ − 1 never vanishes."""
        grid = np.linspace(0.0, 2.0 * pi, 4 * SAMPLES + 1)
        rates = np.array([_slave_rates(self, a) for a in grid])  # (n, 3, z′)
        out = [0.0, 0.5 * pi, pi, 1.5 * pi]
        for which in range(3):
            for i in range(self.n_slaves):
                f = rates[:, which, i]
                for j in np.flatnonzero(np.sign(f[:-1]) * np.sign(f[1:]) <= 0.0):
                    if f[j] == 0.0:
                        out.append(float(grid[j]))
                    elif f[j + 1] != 0.0:
                        root = bisect_root(partial(self._slave_rate, which=which, i=i),
                                           grid[j], grid[j + 1])
                        out.append(float(root))
        return np.unique(np.mod(np.array(out), 2.0 * pi))

    def _slave_rate(self, a: float, which: int, i: int) -> float:
        """One of slave i's rates at crank angle ``a``: u (``which`` 0), u′ (1) or u″ (2)."""
        return float(_slave_rates(self, a)[which, i])

    def dead_centre_angles(self) -> tuple[float, float]:
        """Dead centres [rad] of the master cylinder, a centred crank-slider: 0 and π."""
        return self.master().dead_centre_angles()

    def reference_terms(self) -> Callable[[float], tuple]:
        """φ ↦ (J, dJ/dφ, u_k, u′_k) for the reference path: the kernel's pure-Python code
        (:class:`~.twins.KernelTwin`), there being no numpy twin of it."""
        return KernelTwin(self, core.articulated_terms).terms

    def kinematics_table(self, phi: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """Columns ``phi_deg``, ``J``, ``dJ_dphi`` and per cylinder k: ``s_k`` travel from its outer
        dead centre [m], ``u_k`` [m/rad], ``du_k`` [m/rad²] (the kernel's)."""
        phi = np.atleast_1d(np.asarray(phi, dtype=np.float64))
        mp = self.pack()
        n = self.n_cylinders
        u, du = np.empty((phi.size, n)), np.empty((phi.size, n))
        JdJ = np.array([core.articulated_terms(mp, p, u[j], du[j]) for j, p in enumerate(phi)])
        x_top = np.diag(axial_positions(self, dead_centres(self)[0])[0])  # X_i at its own TDC
        cols: dict[str, NDArray[np.float64]] = {"phi_deg": np.degrees(phi), "J": JdJ[:, 0],
                                                "dJ_dphi": JdJ[:, 1]}
        for j, phase in enumerate(self.row_phases):
            x = axial_positions(self, phi - phase)[0]
            for i in range(1 + self.n_slaves):
                k = j * (1 + self.n_slaves) + i
                cols[f"s_{k + 1}"] = x_top[i] - x[:, i]
                cols[f"u_{k + 1}"] = u[:, k]
                cols[f"du_{k + 1}"] = du[:, k]
        return cols

    def geometry(self) -> dict[str, tuple[float, str]]:
        """What the geometry implies, name → (value, unit), for the pistons c = 1 … 1 + z′ of a
        row (row j's cylinders are c + j(1 + z′), alike): ``lambda`` λ = r/l of the master rod;
        per piston ``cyl_<c>_tdc``, ``cyl_<c>_bdc`` the local crank angles α of its exact outer
        and inner dead centre (:func:`dead_centres`; the master's 0 and π), ``cyl_<c>_stroke``
        between them (:func:`piston_strokes`) and ``cyl_<c>_lambda`` its dynamic parameter
        (:func:`dynamic_parameters`, Semenov (61) solved exactly); per slave
        ``cyl_<c>_stroke_excess`` over the master's 2r and ``cyl_<c>_tdc_after_bank``, its TDC's
        lag behind δ_i in (−π, π] ((55)–(57) solved exactly); ``stroke`` and ``swept_volume`` of the
        master cylinder, the gas cycle's, and ``displacement`` F_p·Σ strokes over every
        cylinder."""
        tdc, bdc = dead_centres(self)
        strokes = piston_strokes(self)
        lam = dynamic_parameters(self)
        out = {"lambda": (self.lam, "1")}
        for i in range(1 + self.n_slaves):
            c = f"cyl_{i + 1}_"
            out[c + "tdc"] = (float(tdc[i]), "rad")
            out[c + "bdc"] = (float(bdc[i]), "rad")
            out[c + "stroke"] = (float(strokes[i]), "m")
            out[c + "lambda"] = (float(lam[i]), "1")
            if i:
                out[c + "stroke_excess"] = (float(strokes[i] - self.stroke()), "m")
                lag = float(tdc[i] - self.slave_banks[i - 1])
                # in (−π, π]: a slave near 0° has its TDC just before 2π or just after 0
                lag -= 2.0 * pi * ((lag > pi) - (lag <= -pi))
                out[c + "tdc_after_bank"] = (lag, "rad")
        out["stroke"] = (self.stroke(), "m")
        out["swept_volume"] = (self.swept_volume(), "m^3")
        out["displacement"] = (float(self.rows * self.piston_area * strokes.sum()), "m^3")
        return out

    def analysis_summary(self) -> dict[str, tuple[float, str]]:
        """Per slave of a row (cylinder c = 2 … 1 + z′), for a result's ``/analysis``: λ_i exact and
        by (61), the stroke's excess over 2r, its TDC's lag behind δ_i (those of
        :meth:`geometry`), the 3rd harmonic of its displacement exact and by (45), and the largest
        error of Semenov's acceleration series."""
        out = {}
        geometry = self.geometry()
        for h in harmonics(self):
            c = f"cyl_{h.cylinder}_"
            out[c + "lambda"] = geometry[c + "lambda"]
            out[c + "lambda_semenov"] = (h.lam_semenov, "1")
            out[c + "stroke_excess"] = geometry[c + "stroke_excess"]
            out[c + "tdc_after_bank"] = geometry[c + "tdc_after_bank"]
            out[c + "S3"] = (hypot(*h.exact[0][3]), "m")
            out[c + "S3_semenov"] = (hypot(*h.series[0][3]), "m")
            out[c + "series_error_W"] = (h.error[2], "m/rad^2")
        return out

    def toml_lines(self) -> list[str]:
        """The ``[mechanism]``, ``[mechanism.rod]`` and ``[mechanism.slave_rod]`` tables in SI,
        which :meth:`read` reads back to an equal object."""
        keys = {"type": self.name, "crank_radius": self.crank_radius,
                "rod_length": self.rod_length, "bore": self.bore,
                "piston_mass": self.piston_mass, "crank_mass": self.crank_mass,
                "strokes": self.strokes, "bank": list(self.slave_banks),
                "link_angle": list(self.link_angles), "link_radius": list(self.link_radii),
                "slave_rod_length": list(self.slave_lengths), "rows": self.rows,
                "row_bank": list(self.row_banks), "row_crank": list(self.row_cranks)}
        if self.firing:
            keys["firing"] = list(self.firing)
        lines = ["[mechanism]"] + [f"{k} = {toml_value(v)}" for k, v in keys.items()]
        for table, prefix in (("rod", "rod_"), ("slave_rod", "slave_rod_")):
            model = getattr(self, prefix + "model")
            rod = {"model": model, "mass": getattr(self, prefix + "mass"),
                   "cg_from_pin": getattr(self, prefix + "cg_from_pin")}
            if model == "rigid":
                rod["inertia_cg"] = getattr(self, prefix + "inertia_cg")
            lines += ["", f"[mechanism.{table}]"] + [f"{k} = {toml_value(v)}" for k, v in rod.items()]
        return lines


# ------------------------------------------------------------------------------------------------
# Geometry


def slave_dimensions(r: float, l: float, delta: float, link_radius: float | None = None,
                     slave_length: float | None = None) -> tuple[float, float]:
    """(r_i, l_i) such that the slave piston is near the master's TDC distance l + r from O when
    the crank points along its axis, Semenov (5)–(7): l = r_i √(1 − λ² sin²δ_i) + l_i. Give one of
    ``link_radius`` (then l_i by (6)) or ``slave_length`` (then r_i by (7)). The relation takes
    cos β_i ≈ 1 at that position; the exact dead centres are :func:`dead_centres`'s."""
    root = sqrt(1.0 - (r / l * sin(delta)) ** 2)
    if link_radius is not None and slave_length is None:
        return link_radius, l - link_radius * root  # (6)
    if slave_length is not None and link_radius is None:
        return (l - slave_length) / root, slave_length  # (7)
    raise ValueError("give exactly one of link_radius and slave_length")


def axial_positions(mech: Articulated, alpha: ArrayLike
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """X_k, dX_k/dα, d²X_k/dα² of row 1's pistons along their axes from O [m, m/rad, m/rad²] at
    local angles ``alpha`` [rad]: arrays (n, 1 + z′), column 0 the master (from the kernel)."""
    alpha = np.atleast_1d(np.asarray(alpha, dtype=np.float64))
    mp = mech.pack()
    out = np.empty((3, alpha.size, 1 + mech.n_slaves))
    for j, a in enumerate(alpha):
        core.axial_positions(mp, a, out[0, j], out[1, j], out[2, j])
    return out[0], out[1], out[2]


def positions(mech: Articulated, alpha: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """Every point of row 1 at local angles ``alpha`` [rad], in plain numpy (complex numbers x + iy
    in the row frame; independent of the kernel, for plots and checks).

    Keys: ``A`` crankpin, ``B`` master piston pin, ``G`` master-rod centre of mass (n,);
    ``Ai`` link pins, ``Bi`` slave piston pins, ``Gi`` slave-rod centres of mass (n, z′);
    ``master_angle`` arg(B − A), ``slave_angle`` arg(A_i − B_i) [rad] (n,), (n, z′).
    """
    alpha = np.atleast_1d(np.asarray(alpha, dtype=np.float64))
    r, l = mech.crank_radius, mech.rod_length
    A = r * np.exp(1j * alpha)
    B = (r * np.cos(alpha) + np.sqrt(l * l - (r * np.sin(alpha)) ** 2)) + 0j
    e = (B - A) / l
    link = np.asarray(mech.link_radii) * np.exp(1j * np.asarray(mech.link_angles))
    Ai = A[:, None] + link[None, :] * e[:, None]  # a e + q n = (a + iq) e, n = i e
    d = np.exp(1j * np.asarray(mech.slave_banks))[None, :]
    w = Ai / d  # link pin in the slave cylinder's frame: along (real) and across (imaginary)
    li = np.asarray(mech.slave_lengths)[None, :]
    Bi = (w.real + np.sqrt(li**2 - w.imag**2)) * d
    f, fi = mech.rod_cg_from_pin / l, mech.slave_rod_cg_from_pin / li
    return {"A": A, "B": B, "G": B + f * (A - B), "Ai": Ai, "Bi": Bi, "Gi": Bi + fi * (Ai - Bi),
            "master_angle": np.angle(B - A), "slave_angle": np.angle(Ai - Bi)}


def _slave_rates(mech: Articulated, alpha: float) -> NDArray[np.float64]:
    """(3, z′): per slave its piston's X_i′, its rod's β_i′ and its link pin's relative rate
    β_i′ + β′ at local angle α (the kernel's :func:`transient.core.model.articulated.slave`)."""
    r, l = mech.crank_radius, mech.rod_length
    mp = mech.pack()
    ca, sa, cb, sb, db, ddb = core.master_rod(alpha, r, l)
    out = np.empty((3, mech.n_slaves))
    for i in range(mech.n_slaves):
        _, X1, _, _, _, _, _, t1, _ = core.slave(mp, i, r, ca, sa, cb, sb, db, ddb)
        out[:, i] = X1, t1, t1 + db
    return out


def slave_reach(mech: Articulated, samples: int = 4 * SAMPLES) -> NDArray[np.float64]:
    """Largest offset |h| [m] of each link pin from its slave cylinder's axis over a turn (sampled;
    a slave rod must be longer to reach its cylinder). Needs no slave-rod length."""
    alpha = np.linspace(0.0, 2.0 * pi, samples, endpoint=False)
    with np.errstate(invalid="ignore"):  # (the slave pins of rods too short are NaN)
        Ai = positions(mech, alpha)["Ai"]
    return np.abs((Ai / np.exp(1j * np.asarray(mech.slave_banks))[None, :]).imag).max(axis=0)


def dead_centres(mech: Articulated) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Local angles α [rad] of the outer (TDC, X largest) and inner (BDC) dead centre of each
    piston of a row, (1 + z′,) each, the master first (exactly 0 and π).

    Semenov (55)–(57) find them by the secant method on his truncated series; here they are the
    roots of the exact dX/dα, bracketed on a grid and refined by bisection to the last bit,
    wrapped to [0, 2π).
    """
    grid = np.linspace(0.0, 2.0 * pi, SAMPLES + 1)
    h = grid[1]
    x = axial_positions(mech, grid)[0]
    mp = mech.pack()
    bufs = [np.empty(1 + mech.n_slaves) for _ in range(3)]

    def rate(a: float, i: int) -> float:
        core.axial_positions(mp, a, *bufs)
        return bufs[1][i]

    tdc, bdc = np.zeros(1 + mech.n_slaves), np.full(1 + mech.n_slaves, pi)
    for i in range(1, 1 + mech.n_slaves):
        for out, j in ((tdc, np.argmax(x[:, i])), (bdc, np.argmin(x[:, i]))):
            out[i] = bisect_root(partial(rate, i=i), grid[j] - h, grid[j] + h) % (2.0 * pi)
    return tdc, bdc


def dynamic_parameters(mech: Articulated) -> NDArray[np.float64]:
    """Exact dynamic parameter λ_i of each piston of a row (1 + z′,), the master first: the
    amplitude of the 2nd harmonic of its acceleration d²X/dα² over r, four times that of its
    displacement X (Semenov (61) from the truncated series, (51); for the master λ + λ³/4 + …)."""
    alpha = np.linspace(0.0, 2.0 * pi, SAMPLES, endpoint=False)
    second = fourier(axial_positions(mech, alpha)[0], 2)[2]  # (2, 1 + z′): a₂, b₂ of X
    return 4.0 * np.hypot(second[0], second[1]) / mech.crank_radius


def piston_strokes(mech: Articulated) -> NDArray[np.float64]:
    """Exact stroke of each piston of a row [m], X(TDC) − X(BDC) (Semenov (58), solved exactly)."""
    tdc, bdc = dead_centres(mech)
    n = 1 + mech.n_slaves
    return (np.diag(axial_positions(mech, tdc)[0]) - np.diag(axial_positions(mech, bdc)[0])
            ).reshape(n)


# ------------------------------------------------------------------------------------------------
# Harmonics: exact against Semenov's series


def semenov_series(r: float, l: float, link_radius: float, link_angle: float, slave_length: float,
                   bank: float) -> tuple[NDArray[np.float64], str]:
    """Semenov's Fourier coefficients of the slave displacement S_Bi along its axis from O,
    ``(coef, source)`` with ``coef[k] = (a_k, b_k)`` of a_k cos kα + b_k sin kα, k = 0 … 4.

    S = x_Bi cos δ_i + y_Bi sin δ_i from the coefficients of x_Bi, y_Bi:

    * ψ_i = δ_i: (47) for order 1, (49)–(50) for orders 0, 2, 4 with Macalpine's t_k (9); no
      order 3 ("the 3rd-order harmonics are absent", (46)).
    * otherwise the general (45) to order 3 with (41), (43) (Rickert's case; its n₃, m₃ leave out
      the sin⁴β_i term, see the reference's caveat).
    """
    lam = r / l
    a, q = link_radius * cos(link_angle), link_radius * sin(link_angle)
    b = l - a
    c, s_ = cos(bank), sin(bank)
    li = slave_length
    A, B, C, D = (np.zeros(5) for _ in range(4))
    k, s, p = _ksp(r, l, link_radius, link_angle, slave_length, bank)  # (41); (46): p = 0
    if link_angle == bank:
        K = k * k + s * s
        t = (1 - lam**2 / 4 - 3 * lam**4 / 64 - 5 * lam**6 / 256,  # (9), Macalpine
             lam**2 / 4 + lam**4 / 16 + 15 * lam**6 / 512, -lam**4 / 64 - 3 * lam**6 / 256)
        n = (1 - K / 4 - 3 * K * K / 64, -(k * k - s * s) * (1 + K / 4) / 4,  # (49)
             -(k**4 - 6 * k * k * s * s + s**4) / 64)
        m = (0.0, -k * s * (1 + K / 4) / 2, -k * s * (k * k - s * s) / 16)
        for j, order in enumerate((0, 2, 4)):  # (50)
            A[order] = t[j] * a + n[j] * li * c
            B[order] = m[j] * li * c
            C[order] = t[j] * q + n[j] * li * s_
            D[order] = m[j] * li * s_
        A[1], B[1] = r * c * c, r * sin(2 * bank) / 2  # (47)
        C[1], D[1] = r * sin(2 * bank) / 2, r * s_ * s_
        source = "(47), (50)"
    else:
        L = 1 - lam**2 / 4
        n0 = 1 - (k * k + s * s + (2 - lam**2) * p * p) / 4  # (43)
        n1, m1 = -(1 - lam**2 / 8) * k * p, -(1 - 3 * lam**2 / 8) * s * p
        n2, m2 = -(k * k - s * s + lam**2 * p * p) / 4, -k * s / 2
        n3, m3 = -lam**2 * k * p / 8, -lam**2 * s * p / 8
        A[:4] = (L * a + li * (n0 * c - L * p * s_), r + li * (n1 * c - k * s_),  # (45)
                 lam**2 * a / 4 + li * (n2 * c - lam**2 * p * s_ / 4), li * n3 * c)
        B[1:4] = (lam * q + li * (m1 * c - s * s_), li * m2 * c, li * m3 * c)
        C[:4] = (L * q + li * (n0 * s_ + L * p * c), li * (n1 * s_ + k * c),
                 lam**2 * q / 4 + li * (n2 * s_ + lam**2 * p * c / 4), li * n3 * s_)
        D[1:4] = (lam * b + li * (m1 * s_ + s * c), li * m2 * s_, li * m3 * s_)
        source = "(45)"
    return np.column_stack([A * c + C * s_, B * c + D * s_]), source


def _ksp(r, l, link_radius, link_angle, slave_length, bank):
    """k_i, s_i, p_i of Semenov (41)."""
    li, dd = slave_length, bank - link_angle
    return (r / li * sin(bank), r / l * link_radius / li * cos(dd) - r / li * cos(bank),
            link_radius / li * sin(dd))


def lambda_semenov(r: float, l: float, link_radius: float, link_angle: float,
                   slave_length: float, bank: float) -> float:
    """Semenov's slave dynamic parameter (61), 2nd-harmonic amplitude of W_Bi over rω²:
    λ_i = √{[λ² r_i/r − (l_i/r)(k² − s²)]² + (2 s sin δ_i)²}, from (51)'s a₂, b₂ (derived for
    ψ_i = δ_i; with ψ_i ≠ δ_i it uses (41)'s k_i, s_i and leaves p_i out)."""
    k, s, _ = _ksp(r, l, link_radius, link_angle, slave_length, bank)
    lam = r / l
    return hypot(lam**2 * link_radius / r - slave_length / r * (k * k - s * s),
                 2.0 * s * sin(bank))


def third_harmonic(r: float, l: float, link_radius: float, link_angle: float,
                   slave_length: float, bank: float) -> tuple[float, float]:
    """(a₃, b₃) [m] of the slave displacement to leading order, with the term (43) leaves out.

    S_Bi's order 3 is l_i (n₃, m₃) (A₃ cos δ + C₃ sin δ of (45)). Keeping −⅛ sin⁴β_i in
    cos β_i (the errata's "4ks³cosφ sin³φ" hints at it) adds −⅛ p k(k² − 3s²) to n₃ and
    −⅛ p s(3k² − s²) to m₃ (the 3rd harmonic of 4p(k cos φ + s sin φ)³) — derived here, not in
    the text. At δ = 72°, ψ = 67° (Semenov's dimensions): exact a₃ = −0.0806 mm, this −0.0725 mm,
    (45) −0.0286 mm.
    """
    k, s, p = _ksp(r, l, link_radius, link_angle, slave_length, bank)
    lam = r / l
    n3 = -lam**2 * k * p / 8.0 - p * k * (k * k - 3.0 * s * s) / 8.0
    m3 = -lam**2 * s * p / 8.0 - p * s * (3.0 * k * k - s * s) / 8.0
    return slave_length * n3, slave_length * m3


def fourier(values: NDArray[np.float64], orders: int) -> NDArray[np.float64]:
    """(a_k, b_k), k = 0 … orders, of samples over one period starting at 0 (columns: functions):
    shape (orders + 1, 2, ...)."""
    F = np.fft.rfft(values, axis=0) / values.shape[0]
    coef = np.stack([2.0 * F.real, -2.0 * F.imag], axis=1)[: orders + 1]
    coef[0] /= 2.0
    return coef


def series_values(coef: NDArray[np.float64], alpha: NDArray[np.float64]) -> NDArray[np.float64]:
    """Σ a_k cos kα + b_k sin kα at ``alpha`` (``coef[k] = (a_k, b_k)``)."""
    ka = np.arange(coef.shape[0])[:, None] * alpha[None, :]
    return (coef[:, 0:1] * np.cos(ka) + coef[:, 1:2] * np.sin(ka)).sum(axis=0)


@dataclass(frozen=True)
class SlaveHarmonics:
    """One slave piston's harmonics from the exact geometry beside Semenov's series.

    ``exact`` (3, orders + 1, 2): (a_k, b_k) of the displacement X [m], the velocity dX/dα [m/rad]
    and the acceleration d²X/dα² [m/rad²] (V = ω dX/dα, W = ω² d²X/dα² at constant ω), X along
    the axis from O; ``series`` the same from :func:`semenov_series` (zero beyond its orders);
    ``error`` the largest |exact − series| over a turn of X, dX/dα, d²X/dα² (the truncation error);
    ``lam`` the exact slave dynamic parameter, 2nd-harmonic amplitude of W over rω², and
    ``lam_semenov`` Semenov's (61); ``third_corrected`` (a₃, b₃) of X by :func:`third_harmonic`
    [m]; ``tdc``, ``bdc`` local angles of its exact dead centres [rad] and ``stroke`` between
    them [m].
    """

    cylinder: int
    bank: float
    link_angle: float
    exact: NDArray[np.float64]
    series: NDArray[np.float64]
    source: str
    error: tuple[float, float, float]
    lam: float
    lam_semenov: float
    third_corrected: tuple[float, float]
    tdc: float
    bdc: float
    stroke: float


def harmonics(mech: Articulated, orders: int = 6) -> list[SlaveHarmonics]:
    """:class:`SlaveHarmonics` of every slave of a row (cylinders 2 … 1 + z′)."""
    alpha = np.linspace(0.0, 2.0 * pi, SAMPLES, endpoint=False)
    X = axial_positions(mech, alpha)
    exact = fourier(np.stack(X, axis=1), orders)  # (orders + 1, 2, 3, 1 + z′)
    tdc, bdc = dead_centres(mech)
    stroke = piston_strokes(mech)
    lam = dynamic_parameters(mech)
    r = mech.crank_radius
    out = []
    for i in range(mech.n_slaves):
        coef, source = semenov_series(r, mech.rod_length, mech.link_radii[i], mech.link_angles[i],
                                      mech.slave_lengths[i], mech.slave_banks[i])
        series = np.zeros((orders + 1, 2))
        series[: min(5, orders + 1)] = coef[: orders + 1]
        ex = np.stack([exact[:, :, d, 1 + i] for d in range(3)])
        se = np.stack([series, _derive(series, 1), _derive(series, 2)])
        e = [float(np.max(np.abs(X[d][:, 1 + i] - series_values(se[d], alpha)))) for d in range(3)]
        err = (e[0], e[1], e[2])
        out.append(SlaveHarmonics(
            cylinder=i + 2, bank=mech.slave_banks[i], link_angle=mech.link_angles[i], exact=ex,
            series=se, source=source, error=err, lam=float(lam[1 + i]),
            lam_semenov=lambda_semenov(r, mech.rod_length, mech.link_radii[i],
                                       mech.link_angles[i], mech.slave_lengths[i],
                                       mech.slave_banks[i]),
            third_corrected=third_harmonic(r, mech.rod_length, mech.link_radii[i],
                                           mech.link_angles[i], mech.slave_lengths[i],
                                           mech.slave_banks[i]), tdc=float(tdc[1 + i]),
            bdc=float(bdc[1 + i]), stroke=float(stroke[1 + i])))
    return out


def _derive(coef: NDArray[np.float64], order: int) -> NDArray[np.float64]:
    """Coefficients of the ``order``-th derivative of a series (Semenov (53)–(54))."""
    k = np.arange(coef.shape[0])
    a, b = coef[:, 0], coef[:, 1]
    if order == 1:
        return np.column_stack([k * b, -k * a])
    return np.column_stack([-k * k * a, -k * k * b])

