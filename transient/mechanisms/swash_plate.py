"""Swash-plate engines (Antonyuk et al., Fig. 1): geometry, masses, validation, positions, tables
(one idea, the swash-plate mechanism on the scene's side, as each mechanism has its one module).

The compiled kinematics and the frame are described in :mod:`transient.core.model.swash_plate`; this module
holds the scene-side description (SI units), packs it for the kernel and gives numpy-level positions
of every body for plots and checks.

Choices the paper (Antonyuk et al. §2, §4) leaves open:

* Cylinder k (k = 0 … z−1; tables label it k + 1 like the paper's i) sits at ψ_Dk = 2πk/z (the
  even spacing meant by "2π/i"), and its joint on link 9 at the same angle, ψ_k = ψ_Dk. In the
  inverted motion link 9 turns on the plate by θ = −φ + δ(φ), with δ the Hooke joint's periodic
  non-uniformity, while the cylinders turn by −φ; ψ_k = ψ_Dk keeps B_k on D_k's meridian on average,
  so the lateral offset of the rod swings symmetrically about zero. A numeric minimax over ψ_k at
  α = 21.4° (r₁ = R(1 + cos α)/2, either hinge) finds no better angle within 0.06°; at α = 44°
  shifts of up to 0.36° lower the worst offset by about 2 %, not worth a second rule.
* The rod's mass is split statically for the two-mass model: m(ℓ − c)/ℓ at D, m·c/ℓ at B
  (c = ``rod_cg_from_pin``); this equals a rigid rod with inertia m·c(ℓ − c) about its centre of mass.
* Link 9's centre of mass is at O (it is symmetric about the plate normal), so it only rotates.
* ``halves = 2`` adds the mirror image through the plane I–I: plate 4, link 10, cross 15, rods 8 and
  pistons 6 (opposed pistons in the same cylinders, same gas force).

How it fills the mechanism interface (:class:`transient.mechanisms.Mechanism`):

* ``kind = 1`` (``core.layout.SWASH_PLATE``), ``strokes = 2`` (two-stroke, one power pulse per turn),
  ``cycle = 2π``; ``bank_angles`` are the cylinder angles ψ_Dk.
* ``firing_angles``: the shaft angle at which cylinder k's gas table is at local angle 0 is its
  *inner dead centre* (x_D smallest: the piston nearest the plane I–I, end of compression), found
  exactly as a root of u_k. Cylinder k's joint B_k is lowest when φ − δ(φ) = ψ_k, δ = θ + φ the
  Hooke joint's non-uniformity, so the dead centres are 2πk/z only where δ vanishes by symmetry:
  at multiples of π/2 (z = 1, 2, 4 and the first cylinder always). There the paper's rule holds
  exactly — the pulses of cylinder i start at π(i − 1)/2 for z = 4, a sequence shifted by 2π/z —
  and the angle is snapped onto 2πk/z (the root is within 1e-15 of it). Otherwise the dead centres
  are off the even spacing by about the largest non-uniformity δ_max = atan((1 − cos α)/(2√cos α))
  (2.05° at α = 21.4°; the in-plane hinge gives ±1.88° for z = 3 and up to 2.13° for z = 5, the
  rods' swing adding a little): the pistons really reach their dead centres at uneven intervals,
  and a gas pulse timed by the even spacing would start before the piston has stopped.
* ``volume_function(clearance)`` and ``stroke()`` describe cylinder 1 (ψ_D = 0), whose dead
  centres are exactly at φ = 0 and π for every geometry whose pistons turn at their dead centres
  only (x_D is even about both, δ being odd; :func:`dead_centre_limits` bounds r₁ so), so
  that V(π) − V(0) = halves·F_p·stroke() exactly, as the mixed cycle requires. The other cylinders'
  strokes differ by < 1e-5 relative at the example geometry (module function :func:`stroke`).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, lru_cache, partial
from math import asin, atan, cos, degrees, inf, pi, sin, tan
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.model import swash_friction
from ..core.model import swash_plate as core
from ..core.model.layout import LINK_FIXED, LINK_PISTONS, LINK_REST, LINK_SWASH
from ..errors import SceneError
from ..roots import bisect_root
from ..tomlout import toml_value
from ..units import Named
from .twins import KernelTwin

if TYPE_CHECKING:
    from ..scene.reader import Section

#: Housing hinge of cross 13 → (phase φ_h of the Hooke relation, hinge axis a = R_x(−φ_h) e_z);
#: see transient.core.model.swash_plate.
HINGES = {"normal": (0.0, (0.0, 0.0, 1.0)), "in-plane": (pi / 2.0, (0.0, 1.0, 0.0))}

#: Cylinders at most (a scene check: every per-cylinder array is sized by it).
MAX_CYLINDERS = 64

# What each key of its ``[mechanism]`` table and sub-tables means, in a line: the scene-key
# reference (docs/guide/scene_keys) shows it beside what the reader asks of the key.
KEY_MEANINGS = {
    "mechanism": {
        "swash": "Swash angle α: tilt of the plate from the plane normal to the shaft.",
        "joint_radius": "Radius R of the circle of the rods' joints B on link 9.",
        "rod_length": "Rod length ℓ between its spherical joints B and D; it must bridge the "
                      "joints' largest lateral offset over a turn.",
        "cylinder_radius": "Radius r₁ of the circle of the cylinder axes.",
        "cylinders": "Cylinders z per half, evenly spaced around the shaft.",
        "bore": "Cylinder bore.",
        "halves": "1, or 2 for the opposed-piston engine with the mirror half (two pistons per "
                  "cylinder).",
        "hinge": "Housing hinge of cross 13: ``in-plane`` (along Oy, as the paper's text) or "
                 "``normal`` (along Oz, as its printed equation (1)).",
        "piston_mass": "Mass of one piston.",
        "link_inertia": "Moment of inertia of an isotropic link 9 (instead of the polar and "
                        "diametral ones).",
        "link_polar_inertia": "Link 9's moment of inertia about the plate normal (with "
                              "``link_diametral_inertia``).",
        "link_diametral_inertia": "Link 9's moment of inertia about a diameter in the plate "
                                  "plane (with ``link_polar_inertia``).",
        "cross_inertia": "Moment of inertia I₁₃ of cross 13 about its housing hinge.",
        "rod": "The rods (``[mechanism.rod]``).",
    },
    "mechanism.rod": {
        "model": "``two-mass``: masses at the joints; ``rigid``: a rigid body with its moment "
                 "of inertia.",
        "mass": "Mass of one rod.",
        "cg_from_pin": "Distance from the piston joint D to the rod's centre of mass.",
        "inertia_cg": "Moment of inertia of a rod about its centre of mass, across its axis "
                      "(``rigid``).",
    },
}


@dataclass(frozen=True, kw_only=True)
class SwashPlate:
    """A swash-plate engine with a Hooke-joint anti-rotation link (Antonyuk et al., Figs. 1–3).

    Attributes
    ----------
    swash_angle : float
        α [rad], tilt of the plate from the plane normal to the shaft; 0 < α < 45°.
    joint_radius : float
        R [m], radius of the circle of the joints B on link 9.
    cylinder_radius : float
        r₁ [m], radius of the circle of the cylinder axes.
    rod_length : float
        ℓ [m], distance between the spherical joints B and D of a rod.
    bore : float
        Cylinder bore [m].
    cylinders : int
        Cylinders z per half, evenly spaced at ψ_Dk = 2πk/z from Oy.
    halves : int
        1, or 2 for the opposed-piston engine with the mirror half (two pistons per cylinder).
    hinge : str
        Housing hinge of cross 13: ``"in-plane"`` (along Oy at φ = 0, in the plane of the shaft axis
        and the plate normal, as the paper's text says) or ``"normal"`` (along Oz, for which the
        printed (1) tan φ₉,₀ = tan φ₀,₀ cos α holds).
    piston_mass : float
        Mass of one piston [kg].
    rod_model : str
        ``"two-mass"`` (masses at the joints, split by ``rod_cg_from_pin``) or ``"rigid"``.
    rod_mass : float
        Mass of one rod [kg].
    rod_cg_from_pin : float
        Distance from the piston joint D to the rod's centre of mass [m], 0 … ℓ.
    rod_inertia_cg : float
        Rod moment of inertia about its centre of mass across its axis [kg m²] (rigid model only;
        spin about the axis of a slender rod is ignored).
    link_polar_inertia : float
        Link 9's moment of inertia about the plate normal [kg m²].
    link_diametral_inertia : float
        Link 9's moment of inertia about a diameter in the plate plane [kg m²] (isotropic I₉: equal
        to the polar one).
    cross_inertia : float
        I₁₃ [kg m²], cross 13 about its housing hinge.
    """

    swash_angle: float
    joint_radius: float
    cylinder_radius: float
    rod_length: float
    bore: float
    cylinders: int
    halves: int = 1
    hinge: str = "in-plane"
    piston_mass: float
    rod_model: str = "two-mass"
    rod_mass: float
    rod_cg_from_pin: float
    rod_inertia_cg: float = 0.0
    link_polar_inertia: float
    link_diametral_inertia: float
    cross_inertia: float

    #: Its ``type`` in the ``[mechanism]`` table (:data:`transient.mechanisms.MECHANISMS`).
    name: ClassVar[str] = "swash-plate"
    #: Its compiled kernel (``Model.terms``).
    kernel: ClassVar[Any] = staticmethod(core.terms)
    #: Its compiled kernel of each cylinder's share of J at its station's angle (``shares``).
    shares_kernel: ClassVar[Any] = staticmethod(core.shares)
    #: Beyond :class:`~transient.mechanisms.Mechanism` (:data:`~transient.mechanisms.CAPABILITIES`):
    #: no numpy twin (the reference path runs the kernel's Python code), no load diagrams.
    capabilities: ClassVar[frozenset[str]] = frozenset(
        {"reaction-friction", "reaction-twin", "pistons", "loads"})
    #: No wall heat transfer: the cylinder ODE is built for the crank-slider's volume.
    wall_heat_transfer: ClassVar[bool] = False
    cylinder_count: ClassVar[str] = "mechanism.cylinders"
    key_meanings: ClassVar[dict[str, dict[str, str]]] = KEY_MEANINGS
    #: Its pistons do not follow the crank-slider's law, from which the analyses derive W_k.
    slider_law: ClassVar[bool] = False
    #: Two-stroke: one gas pulse per cylinder and turn.
    strokes = 2
    #: Cycle length in shaft angle [rad].
    cycle = 2.0 * pi
    #: Links of the serial chain, shaft first (friction pairs join neighbours): the shaft with the
    #: plates, link 9 with cross 13 (beyond plate bearing 11; the Hooke joint's cross only turns
    #: with it), the rods, the pistons, and the cylinders, whose gas does its work on the pistons.
    #: So [shaft, link] is plate bearing 11, [link, rod] the ball joints B_k, [rod, piston] the
    #: ball joints D_k and [piston, cylinder] the pistons in their bores.
    links: ClassVar[tuple[str, ...]] = ("shaft", "link", "rod", "piston", "cylinder")
    #: How each link's reduced inertia follows φ (``core.layout.LINK_*``): link 9's and the
    #: crosses' by (15)–(17), the rods' what J(φ) holds beyond the others, the pistons'
    #: m_p·Σ_k u_k²/halves.
    link_laws: ClassVar[tuple[int, ...]] = (LINK_FIXED, LINK_SWASH, LINK_REST, LINK_PISTONS, LINK_FIXED)
    #: Links for pairs with friction on their reactions (:mod:`transient.core.model.swash_friction`),
    #: the shaft side first: the shaft with flywheel and load, the plate on it, link 9, the rods,
    #: the pistons and the cylinders (the frame). So [shaft, plate] is the main bearing (the
    #: plate carries the mechanism's forces into it), [plate, link] the plate bearing 11,
    #: [link, rod] the ball joints B_k, [rod, piston] the ball joints D_k and [piston, cylinder]
    #: the pistons in their cylinders.
    reaction_links: ClassVar[tuple[str, ...]] = ("shaft", "plate", "link", "rod", "piston", "cylinder")
    #: The joints among them that stay ideal (named by their shaft-side link): the ball joints,
    #: whose rods' spin about their own axes the solver does not carry.
    ideal_reaction_joints = {"link": "the ball joints B_k of the rods on link 9",
                             "rod": "the ball joints D_k of the rods on the pistons"}
    #: The joints reaction pairs may name: each link with its neighbour (a chain).
    reaction_joints: ClassVar[tuple[tuple[str, str], ...]] = tuple(zip(reaction_links, reaction_links[1:]))
    #: No constant-η or mapped pair among reaction pairs: the main bearing sits in the shaft's
    #: equation itself (:mod:`transient.core.model.reactions`).
    shaft_coupling: ClassVar[tuple[str, str] | None] = None
    #: The solver of :mod:`transient.core.model.swash_friction`, which keeps its side forces
    #: apart from the crank-slider's side tracking.
    reaction_kernels: ClassVar[tuple[Any, Any, Any]] = (
        swash_friction.prepare, swash_friction.solve, swash_friction.inverse_drive)
    tracks_sides: ClassVar[bool] = False

    def link_inertias(self) -> tuple[float, ...]:
        """Constant reduced inertia of each link besides the shaft's: none here [kg m²]."""
        return (0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def piston_link_mass(self) -> float:
        """m of the pistons' reduced inertia m·Σ_k u_k² [kg]: u_k sums the ``halves`` pistons
        of cylinder k, which move alike, so m_p·halves·(u_k/halves)² = (m_p/halves)·u_k²."""
        return self.piston_mass / self.halves

    def max_rod_tilt(self) -> float:
        """The largest angle [rad] of a rod to its cylinder axis over a turn (sampled,
        :func:`max_offset`): asin(lateral offset/ℓ)."""
        return asin(max_offset(self) / self.rod_length)

    def reaction_reversals(self) -> NDArray[np.float64]:
        """Shaft angles [rad] in [0, cycle) at which a joint with reaction friction reverses its
        relative motion: every piston's dead centres (the main and plate bearings turn one way
        while ω keeps its sign; ``transient.core.model.swash_friction``)."""
        inner, outer = dead_centres(self)
        angles = tuple(self.firing_angles) + tuple(
            _snapped(a, 2.0 * pi * k / self.cylinders + pi) for k, a in enumerate(outer))
        return np.unique(np.mod(np.asarray(angles, dtype=np.float64), self.cycle))

    def check_wedging(self, s: Section, pairs, raw) -> None:
        """Friction must not wedge the pistons: each piston's friction equation has a slope of
        at least 1 − μ tan γ in its friction force, γ the largest rod tilt to the cylinder axis
        (:mod:`transient.core.model.swash_friction`); μ tan γ < 1 keeps it increasing, hence one
        solution at every state."""
        piston = next((p for p in pairs if p.between[0] == "piston"), None)
        if piston is None:
            return
        tan_g = tan(self.max_rod_tilt())
        if piston.mu * tan_g >= 1.0:
            i = next(i for i, item in enumerate(raw) if isinstance(item, dict)
                     and item.get("between", [None])[0] == "piston")
            raise SceneError(f"{s.key('pairs')}[{i}].mu",
                             f"the friction would wedge the pistons: μ·tan γ_max = "
                             f"{piston.mu * tan_g:.3g} ≥ 1 at the largest rod tilt "
                             f"γ_max = {degrees(atan(tan_g)):.3g}°; allowed "
                             f"μ < {1.0 / tan_g:.3g}")

    @property
    def n_cylinders(self) -> int:
        """Cylinders (gas-force points) z; with two halves each holds two pistons."""
        return self.cylinders

    @property
    def bank_angles(self) -> tuple[float, ...]:
        """Cylinder angles ψ_Dk = 2πk/z [rad] from Oy toward Oz, eq. (5)."""
        return tuple(2.0 * pi * k / self.cylinders for k in range(self.cylinders))

    @cached_property
    def firing_angles(self) -> tuple[float, ...]:
        """Shaft angle [rad] in [0, 2π) at which each cylinder's gas table is at local angle 0.

        The inner dead centre of each cylinder (module docstring): 2πk/z for z = 1, 2, 4, and within
        about the Hooke joint's largest non-uniformity of it otherwise. Validates the geometry.
        """
        tdc, _ = dead_centres(self)
        return tuple(_snapped(a, 2.0 * pi * k / self.cylinders) for k, a in enumerate(tdc))

    @property
    def piston_area(self) -> float:
        """π bore²/4 [m²]."""
        return pi * self.bore**2 / 4.0

    @classmethod
    def read(cls, s: Section) -> SwashPlate:
        """A :class:`SwashPlate` from the ``[mechanism]`` table (its ``type`` is read by the
        caller).

        Keys (lengths plain in m or with ``_mm``, the angle plain in rad or with ``_deg``):
        ``swash``, ``joint_radius``, ``cylinder_radius``, ``rod_length``, ``bore``,
        ``cylinders`` (default 1), ``halves`` (1 | 2, default 1), ``hinge`` (``"in-plane"``
        default | ``"normal"``), ``piston_mass`` [kg], link 9 either ``link_inertia`` (isotropic)
        or both ``link_polar_inertia`` and ``link_diametral_inertia`` [kg m²], ``cross_inertia``
        [kg m²] (default 0); and the table ``[mechanism.rod]``: ``model`` (``"two-mass"`` default
        | ``"rigid"``), ``mass`` [kg], ``cg_from_pin`` (length, from the piston joint D),
        ``inertia_cg`` [kg m²] (rigid model only, default 0). Unknown keys of the rod table are
        rejected here; the caller finishes ``s``.

        Every error names the key as written in the file (``mechanism.swash_deg`` if the user
        wrote ``swash_deg``, ``mechanism.swash`` if they wrote ``swash``): :meth:`validate`
        reports its canonical keys (angles as ``*_deg``, everything else by its SI name), which
        are mapped here.
        """
        swash = s.number("swash", "angle", gt=0.0, lt=pi / 4.0)
        R = s.number("joint_radius", "length", gt=0.0)
        ell = s.number("rod_length", "length", gt=0.0)
        z = s.integer("cylinders", 1, ge=1, le=MAX_CYLINDERS)
        hinge = s.string("hinge", "in-plane", choices=tuple(HINGES))
        # (B's distance from the axis swings over R cos α … R: a rod of ℓ must reach the axis,
        # and stay far enough from its full reach that each piston turns at its dead centres)
        low, high = dead_centre_limits(swash, R, ell, z, hinge)
        r1 = s.number("cylinder_radius", "length",
                      gt=Named(low, "max(joint_radius − rod_length, 0)" if low == max(R - ell, 0.0)
                               else "the least r₁ whose pistons turn at their dead centres only"),
                      lt=Named(high, "joint_radius · cos(swash) + rod_length"
                               if high == R * cos(swash) + ell
                               else "the largest r₁ whose pistons turn at their dead centres only"))
        gap = Named(2.0 * r1 * sin(pi / z) if z > 1 else inf,  # (cylinders must not overlap)
                    "2 · cylinder_radius · sin(180°/cylinders) (cylinders > 1)")
        bore = s.number("bore", "length", gt=0.0, lt=gap)
        halves = s.integer("halves", 1, choices=(1, 2))
        piston_mass = s.number("piston_mass", "mass", ge=0.0)
        iso = s.number("link_inertia", "inertia", None, ge=0.0)
        polar = s.number("link_polar_inertia", "inertia", None, ge=0.0)
        diametral = s.number("link_diametral_inertia", "inertia", None, ge=0.0)
        if iso is not None:
            if polar is not None or diametral is not None:
                raise SceneError(s.key("link_inertia"),
                                 "give either link_inertia (isotropic link 9) or both "
                                 "link_polar_inertia and link_diametral_inertia, not both forms")
            polar = diametral = iso
        elif polar is None and diametral is None:
            raise SceneError(s.key("link_inertia"),
                             "is missing; give link_inertia [kg m²] (isotropic link 9) or both "
                             "link_polar_inertia and link_diametral_inertia")
        else:
            for key, value in (("link_polar_inertia", polar),
                               ("link_diametral_inertia", diametral)):
                if value is None:
                    raise SceneError(s.key(key), "is missing; link_polar_inertia and "
                                                 "link_diametral_inertia go together (or give "
                                                 "link_inertia alone for an isotropic link 9)")
        cross = s.number("cross_inertia", "inertia", 0.0, ge=0.0)
        rod = s.sub("rod", required=True)
        model = rod.string("model", "two-mass", choices=("two-mass", "rigid"))
        mech = cls(
            swash_angle=swash, joint_radius=R, cylinder_radius=r1, rod_length=ell, bore=bore,
            cylinders=z, halves=halves, hinge=hinge, piston_mass=piston_mass, rod_model=model,
            rod_mass=rod.number("mass", "mass", ge=0.0),
            rod_cg_from_pin=rod.number("cg_from_pin", "length", ge=0.0,
                                       le=Named(ell, "rod_length")),
            rod_inertia_cg=(rod.number("inertia_cg", "inertia", 0.0, ge=0.0) if model == "rigid"
                            else 0.0),
            link_polar_inertia=polar, link_diametral_inertia=diametral, cross_inertia=cross)
        rod.finish()
        try:
            mech.validate()
        except SceneError as exc:
            if iso is not None and exc.key.startswith("mechanism.link_"):
                exc.key = s.key("link_inertia")
            raise rod.rename(s.rename(exc)) from None
        return mech

    def validate(self) -> None:
        """Raise :class:`~transient.SceneError` for a geometry or mass set that cannot work."""
        a, R, r1, ell = self.swash_angle, self.joint_radius, self.cylinder_radius, self.rod_length
        if not 0.0 < a < pi / 4.0:
            raise SceneError("mechanism.swash_deg", f"{degrees(a):g}° is not allowed; 0° < α < 45°")
        if not R > 0:
            raise SceneError("mechanism.joint_radius", f"must be > 0, got {R * 1e3:g} mm")
        if not isinstance(self.cylinders, (int, np.integer)) or self.cylinders < 1:
            raise SceneError("mechanism.cylinders", f"must be an integer ≥ 1, got {self.cylinders!r}")
        if self.halves not in (1, 2):
            raise SceneError("mechanism.halves",
                             f"must be 1 or 2 (opposed pistons), got {self.halves!r}")
        if self.hinge not in HINGES:
            raise SceneError("mechanism.hinge", f"unknown orientation {self.hinge!r}; allowed: "
                                                "'in-plane', 'normal'")
        if not ell > 0:
            raise SceneError("mechanism.rod_length", f"must be > 0, got {ell * 1e3:g} mm")
        # Even the best-placed cylinder sees B's distance from the axis swing over R cos α … R.
        lo, hi = max(R - ell, 0.0), R * cos(a) + ell
        if not lo < r1 < hi:
            raise SceneError("mechanism.cylinder_radius",
                             f"{r1 * 1e3:g} mm cannot be reached by rods of {ell * 1e3:g} mm from "
                             f"joints at R = {R * 1e3:g} mm; allowed {lo * 1e3:g} < r₁ < "
                             f"{hi * 1e3:g} mm")
        reach = max_offset(self)
        if not reach < ell:
            raise SceneError("mechanism.rod_length",
                             f"{ell * 1e3:g} mm is too short: over a turn a rod must bridge a lateral "
                             f"offset of {reach * 1e3:.4g} mm; allowed ℓ > {reach * 1e3:.4g} mm")
        if not turns_at_dead_centres_only(self):
            low, high = dead_centre_limits(a, R, ell, self.cylinders, self.hinge)
            raise SceneError("mechanism.cylinder_radius",
                             f"{r1 * 1e3:g} mm puts the rods so near their full reach that a "
                             f"piston turns back between its dead centres; allowed "
                             f"{low * 1e3:.6g} < r₁ < {high * 1e3:.6g} mm (or a longer rod)")
        if not self.bore > 0:
            raise SceneError("mechanism.bore", f"must be > 0, got {self.bore * 1e3:g} mm")
        if self.cylinders > 1 and self.bore >= 2.0 * r1 * sin(pi / self.cylinders):
            raise SceneError("mechanism.bore",
                             f"{self.bore * 1e3:g} mm makes neighbouring cylinders overlap; allowed "
                             f"< {2e3 * r1 * sin(pi / self.cylinders):.4g} mm at r₁ = {r1 * 1e3:g} mm")
        if self.rod_model not in ("two-mass", "rigid"):
            raise SceneError("mechanism.rod.model",
                             f"unknown model {self.rod_model!r}; allowed: 'two-mass', 'rigid'")
        if not 0.0 <= self.rod_cg_from_pin <= ell:
            raise SceneError("mechanism.rod.cg_from_pin",
                             f"{self.rod_cg_from_pin * 1e3:g} mm is off the rod; allowed 0 … "
                             f"{ell * 1e3:g} mm (the rod length)")
        for key, value in (("piston_mass", self.piston_mass), ("rod.mass", self.rod_mass),
                           ("rod.inertia_cg", self.rod_inertia_cg),
                           ("link_polar_inertia", self.link_polar_inertia),
                           ("link_diametral_inertia", self.link_diametral_inertia),
                           ("cross_inertia", self.cross_inertia)):
            if not value >= 0:
                raise SceneError(f"mechanism.{key}", f"must be ≥ 0, got {value:g}")

    def pack(self) -> NDArray[np.float64]:
        """Parameter array for the kernels of :mod:`transient.core.model.swash_plate` (validates first)."""
        self.validate()
        return self._pack()

    def _pack(self) -> NDArray[np.float64]:
        z, ell, cg = self.cylinders, self.rod_length, self.rod_cg_from_pin
        mp = np.zeros(core.CYL0 + core.CYL_STRIDE * z)
        mp[core.ALPHA] = self.swash_angle
        mp[core.COS_A] = cos(self.swash_angle)
        mp[core.SIN_A] = sin(self.swash_angle)
        mp[core.JOINT_R] = self.joint_radius
        mp[core.CYL_R] = self.cylinder_radius
        mp[core.ROD_L] = ell
        mp[core.N_CYL] = z
        mp[core.HALVES] = self.halves
        mp[core.HINGE_PHASE] = HINGES[self.hinge][0]
        mp[core.M_PISTON] = self.piston_mass
        mp[core.M_ROD] = self.rod_mass
        mp[core.ROD_CG] = cg
        # Two masses m(ℓ − c)/ℓ at D and m c/ℓ at B are the rigid rod with I_G = m c (ℓ − c).
        rigid = self.rod_model == "rigid"
        mp[core.I_ROD] = self.rod_inertia_cg if rigid else self.rod_mass * cg * (ell - cg)
        mp[core.J_POLAR] = self.link_polar_inertia
        mp[core.J_DIAM] = self.link_diametral_inertia
        mp[core.I_CROSS] = self.cross_inertia
        psi_d = 2.0 * pi * np.arange(z) / z  # eq. (5) with the even spacing
        psi = psi_d  # joints on link 9: ψ_k = ψ_Dk (module docstring)
        cyl = mp[core.CYL0:].reshape(z, core.CYL_STRIDE)
        cyl[:, core.Y_D] = self.cylinder_radius * np.cos(psi_d)
        cyl[:, core.Z_D] = self.cylinder_radius * np.sin(psi_d)
        cyl[:, core.COS_PSI] = np.cos(psi)
        cyl[:, core.SIN_PSI] = np.sin(psi)
        return mp

    def kinematics_table(self, phi: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """See :func:`kinematics_table`."""
        return kinematics_table(self, phi)

    def stroke(self) -> float:
        """Stroke [m] of cylinder 1's piston(s), x_D(π) − x_D(0): its exact dead centres.

        The one :meth:`volume_function` uses (module docstring); :func:`stroke` gives every
        cylinder's. Validates first.
        """
        x = _points(self.pack(), np.array([0.0, pi]))[2][:, 0, 0]
        return float(x[1] - x[0])

    def swept_volume(self) -> float:
        """Volume [m³] swept in cylinder 1 between its dead centres: halves·F_p·stroke()."""
        return self.halves * self.piston_area * self.stroke()

    def dead_centre_angles(self) -> tuple[float, float]:
        """Dead centres [rad] of cylinder 1, inner and outer: 0 and π (module docstring)."""
        return 0.0, pi

    def geometry(self) -> dict[str, tuple[float, str]]:
        """What the geometry implies, name → (value, unit): per cylinder c ``cyl_<c>_tdc`` and
        ``cyl_<c>_bdc``, the shaft angles [rad] in [0, 2π) of its piston's inner dead centre
        (the end of compression, its firing angle) and outer one (:func:`dead_centres`), and
        ``cyl_<c>_stroke`` between them, per piston (:func:`stroke`); ``stroke`` and
        ``swept_volume`` of cylinder 1, the gas cycle's (:meth:`stroke`), and ``displacement``
        halves·F_p·Σ strokes, every piston's."""
        _, outer = dead_centres(self)
        strokes = stroke(self)
        out = {}
        for k in range(self.cylinders):
            c = f"cyl_{k + 1}_"
            out[c + "tdc"] = (self.firing_angles[k], "rad")
            out[c + "bdc"] = (_snapped(outer[k], 2.0 * pi * k / self.cylinders + pi), "rad")
            out[c + "stroke"] = (float(strokes[k]), "m")
        out["stroke"] = (self.stroke(), "m")
        out["swept_volume"] = (self.swept_volume(), "m^3")
        out["displacement"] = (float(self.halves * self.piston_area * strokes.sum()), "m^3")
        return out

    def volume_function(self, clearance: float) -> Callable[[ArrayLike], NDArray[np.float64]]:
        """V(x) [m³] of cylinder 1 over the local angle x [rad] (= shaft angle; vectorised).

        V = clearance + halves·F_p·(x_D(x) − x_D(0)): with ``halves = 2`` the volume between the two
        opposed pistons (each moving as far, so twice the swept volume of one piston), with one
        half the volume above the piston, between it and a cylinder head fixed at the piston's
        inner dead centre. ``clearance`` is that volume at the inner dead centre x = 0; x = π is
        the outer dead centre, so V(π)/V(0) = 1 + swept_volume()/clearance exactly.
        """
        mp = self.pack()
        area = self.halves * self.piston_area
        x0 = float(_points(mp, np.zeros(1))[2][0, 0, 0])

        def volume(x: ArrayLike) -> NDArray[np.float64]:
            x = np.asarray(x, dtype=np.float64)
            flat = np.ascontiguousarray(x.ravel())
            xd = _points(mp, flat)[2][:, 0, 0]
            return (clearance + area * (xd - x0)).reshape(x.shape)

        return volume

    def toml_lines(self) -> list[str]:
        """The ``[mechanism]`` and ``[mechanism.rod]`` tables in SI (no unit suffixes), which
        :meth:`read` reads back to an equal object (the rod's ``inertia_cg`` is
        written, and read, for the rigid model only)."""
        keys = {"type": self.name, "swash": self.swash_angle, "joint_radius": self.joint_radius,
                "cylinder_radius": self.cylinder_radius, "rod_length": self.rod_length,
                "bore": self.bore, "cylinders": self.cylinders, "halves": self.halves,
                "hinge": self.hinge, "piston_mass": self.piston_mass,
                "link_polar_inertia": self.link_polar_inertia,
                "link_diametral_inertia": self.link_diametral_inertia,
                "cross_inertia": self.cross_inertia}
        rod = {"model": self.rod_model, "mass": self.rod_mass, "cg_from_pin": self.rod_cg_from_pin}
        if self.rod_model == "rigid":
            rod["inertia_cg"] = self.rod_inertia_cg
        return (["[mechanism]"] + [f"{k} = {toml_value(v)}" for k, v in keys.items()]
                + ["", "[mechanism.rod]"] + [f"{k} = {toml_value(v)}" for k, v in rod.items()])


    def reference_terms(self) -> Callable[[float], tuple]:
        """φ ↦ (J, dJ/dφ, u_k, u′_k) for the reference path: the kernel's pure-Python code
        (:class:`~.twins.KernelTwin`), there being no numpy twin of it."""
        return KernelTwin(self, core.swash_terms).terms

    def analysis_summary(self) -> dict[str, tuple[float, str]]:
        """Figures of the mechanism itself for a result's ``/analysis``: none here."""
        return {}


def antonyuk_example(**changes) -> SwashPlate:
    """The worked example of Antonyuk et al. §4, completed where the paper is silent.

    From the paper: α = 21.4°, R = 0.136 m, m₅ = 6 kg, m₇ = 1 kg, I₉ = I₁₃ = 0.3 kg m² (isotropic
    link 9), 4 cylinders per half. Chosen here [D]: r₁ = R(1 + cos α)/2 (the middle of the swing
    R cos α … R of B's distance from the shaft, which minimises the worst lateral offset), ℓ = 0.30 m
    (rod tilt ≤ 1.8°, inside the paper's 2°), rod centre of mass mid-way, bore 0.10 m, one half.
    Keyword arguments replace fields.
    """
    alpha, R = np.radians(21.4), 0.136
    base = dict(swash_angle=alpha, joint_radius=R, cylinder_radius=R * (1.0 + cos(alpha)) / 2.0,
                rod_length=0.30, bore=0.10, cylinders=4, halves=1, hinge="in-plane",
                piston_mass=6.0, rod_model="two-mass", rod_mass=1.0, rod_cg_from_pin=0.15,
                rod_inertia_cg=0.0, link_polar_inertia=0.3, link_diametral_inertia=0.3,
                cross_inertia=0.3)
    base.update(changes)
    return SwashPlate(**base)


def _snapped(angle: float, even: float) -> float:
    """A dead centre's shaft angle wrapped to [0, 2π), and snapped onto the even spacing
    ``even`` where it lies there by symmetry (module docstring): the root is within a few ulp
    of it, far inside 1e-9 rad."""
    if abs((angle - even + pi) % (2.0 * pi) - pi) < 1e-9:
        angle = even
    w = float(angle % (2.0 * pi))
    return 0.0 if w >= 2.0 * pi else w


def _points(mp: NDArray[np.float64], phi: NDArray[np.float64]):
    """θ(φ) and the joints B, D of half 1 (shape (n, z, 3) each) from the kernel."""
    z = int(mp[core.N_CYL])
    theta = np.empty(phi.size)
    pts = np.empty((phi.size, z, 6))
    core.swash_points(mp, np.ascontiguousarray(phi, dtype=np.float64), theta, pts)
    return theta, pts[..., :3], pts[..., 3:]


#: Shaft angles at which :func:`turns_at_dead_centres_only` samples the pistons' travel.
TRAVEL_SAMPLES = 2881


def turns_at_dead_centres_only(geom: SwashPlate) -> bool:
    """Whether every piston moves in and out once a turn: its travel x_D(φ), sampled, turns
    twice, at its inner and outer dead centre. A rod working near its full reach (its lateral
    offset near ℓ) toggles, and the piston turns back in between: cylinder 1's inner dead
    centre is then no longer its least volume (the gas cycles' V(x) would fall below the
    clearance), nor its firing angle the end of its compression."""
    _, _, D = _points(geom._pack(), np.linspace(0.0, 2.0 * pi, TRAVEL_SAMPLES))
    return bool(np.all(travel_turns(D[..., 0]) == 2))


#: A piston that turns back by less than this share of its stroke does not turn: at a dead
#: centre about to toggle the travel is flat to fourth order, and what it does there is
#: rounding, or a dip of no consequence to the cylinder volume.
TRAVEL_ROUNDING = 1e-9


def travel_turns(x: NDArray[np.float64]) -> NDArray[np.int64]:
    """How often each column of the sampled travel ``x`` (samples over one turn, pistons)
    turns between in and out, going round once from its least value; a turn back by less than
    :data:`TRAVEL_ROUNDING` of its stroke is none."""
    out = np.empty(x.shape[1], dtype=np.int64)
    for k in range(x.shape[1]):
        xs = np.roll(x[:-1, k], -int(np.argmin(x[:-1, k])))  # (the closing sample repeats)
        xs = np.append(xs, xs[0])
        step = np.sign(np.diff(xs))
        ends = np.flatnonzero(step[1:] != step[:-1]) + 1  # candidate turns, rounding included
        tol = TRAVEL_ROUNDING * (xs.max() - xs.min())
        turns, rising, extreme = 0, True, xs[0]
        for v in xs[ends].tolist() + [xs[-1]]:
            if (v > extreme) == rising:
                extreme = v
            elif abs(v - extreme) > tol:
                turns, rising, extreme = turns + 1, not rising, v
        out[k] = turns + (not rising)  # (back at the least value: the last turn, if rising)
    return out


@lru_cache(maxsize=64)
def dead_centre_limits(swash: float, R: float, ell: float, z: int, hinge: str
                       ) -> tuple[float, float]:
    """The range (r_low, r_high) [m] of cylinder radii r₁ over which every rod reaches its
    piston and every piston turns at its dead centres only (:func:`turns_at_dead_centres_only`):
    the reach limits max(R − ℓ, 0) and R cos α + ℓ, closed in on by bisection (to 1e-12 of the
    range) from the middle of the joints' swing, R(1 + cos α)/2, where the rods' offsets are
    least. Where even the middle toggles, the reach limits (the rod is then too short:
    :meth:`SwashPlate.validate` says so). The limits are where :data:`TRAVEL_SAMPLES` samples
    first see a piston turn back; a grid 20 times finer sees it within about 1e-7 of r₁ of
    there (a dip of 1e-9 of the stroke, the tolerance)."""
    low, high = max(R - ell, 0.0), R * cos(swash) + ell
    middle = R * (1.0 + cos(swash)) / 2.0

    def good(r1: float) -> bool:
        geom = SwashPlate(swash_angle=swash, joint_radius=R, cylinder_radius=r1, rod_length=ell,
                          bore=0.0, cylinders=z, hinge=hinge, piston_mass=0.0, rod_mass=0.0,
                          rod_cg_from_pin=0.0, link_polar_inertia=0.0,
                          link_diametral_inertia=0.0, cross_inertia=0.0)
        return max_offset(geom) < ell and turns_at_dead_centres_only(geom)

    if not low < middle < high or not good(middle):
        return low, high

    def closed_in(inside: float, outside: float) -> float:
        """The last r₁ found good between a good ``inside`` and the ``outside`` limit."""
        if good(np.nextafter(outside, inside)):
            return outside
        while abs(outside - inside) > 1e-12 * (high - low):
            mid = 0.5 * (inside + outside)
            inside, outside = (mid, outside) if good(mid) else (inside, mid)
        return inside

    return closed_in(middle, low), closed_in(middle, high)


def max_offset(geom: SwashPlate, samples: int = 1441) -> float:
    """Largest lateral offset |(B − D) × e_x| [m] of any rod over a turn, sampled (no validation).

    It needs no x_D, so it also measures rods too short to reach (which is what validation asks).
    """
    _, B, D = _points(geom._pack(), np.linspace(0.0, 2.0 * pi, samples))
    return float(np.hypot(B[..., 1] - D[..., 1], B[..., 2] - D[..., 2]).max())


def _rotation(axis: NDArray[np.float64], angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation matrices (n, 3, 3) by ``angle`` (n,) about the unit ``axis`` (3,) (Rodrigues)."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    c, s = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def positions(geom: SwashPlate, phi: ArrayLike, mirror_x: float | None = None
              ) -> dict[str, NDArray[np.float64]]:
    """Positions and orientations of every moving body at shaft angle(s) ``phi`` [rad].

    Parameters
    ----------
    geom : SwashPlate
    phi : float or array (n,)
        Shaft angles [rad].
    mirror_x : float, optional
        x [m] of the symmetry plane I–I for ``halves = 2`` (drawing only: no dynamics depends on it).
        Default: one bore beyond the farthest reach of the joints D.

    Returns
    -------
    dict
        Arrays with leading axes (n, halves) (n dropped for a scalar ``phi``); half 1 first:

        ``theta`` (n,) θ = φ₉,₀ [rad]; ``normal`` (…, 3) plate normal n; ``Q9`` (…, 3, 3) rotation of
        link 9 from its pose at φ = 0; ``hinge_axis`` (…, 3) housing hinge a of cross 13;
        ``cross_axis`` (…, 3) its hinge c on link 9 (a·c = 0 is the Hooke constraint); ``Q13``
        (…, 3, 3) rotation of cross 13; ``B``, ``D``, ``G`` (…, z, 3) rod joints on link 9, piston
        joints and rod centres of mass [m]; ``e_x`` (…, 3) the direction in which the gas force
        pushes the pistons (toward their plate).
    """
    scalar = np.ndim(phi) == 0
    phi = np.atleast_1d(np.asarray(phi, dtype=np.float64))
    mp = geom.pack()
    theta, B, D = _points(mp, phi)
    a = geom.swash_angle
    n0 = np.array([cos(a), sin(a), 0.0])
    Rx = _rotation(np.array([1.0, 0.0, 0.0]), phi)
    Q9 = Rx @ _rotation(n0, theta)
    # The link-9 hinge c of cross 13 starts along n₀ × a, in the plate plane and across a.
    hinge = np.array(HINGES[geom.hinge][1])
    c0 = np.cross(n0, hinge)
    c0 /= np.linalg.norm(c0)
    c = Q9 @ c0
    frame = np.stack([np.broadcast_to(hinge, c.shape), c, np.cross(hinge, c)], axis=-1)
    frame0 = np.stack([hinge, c0, np.cross(hinge, c0)], axis=-1)
    out = {"normal": Rx @ n0, "Q9": Q9, "hinge_axis": np.broadcast_to(hinge, c.shape).copy(),
           "cross_axis": c, "Q13": frame @ frame0.T, "B": B, "D": D,
           "G": D + geom.rod_cg_from_pin / geom.rod_length * (B - D),
           "e_x": np.broadcast_to([1.0, 0.0, 0.0], c.shape).copy()}
    out = {k: v[:, None] for k, v in out.items()}
    if geom.halves == 2:
        if mirror_x is None:
            mirror_x = -(geom.rod_length + geom.joint_radius * sin(a) + geom.bore)
        P = np.diag([-1.0, 1.0, 1.0])
        shift = np.array([2.0 * mirror_x, 0.0, 0.0])
        mirrored = {}
        for k, v in out.items():
            if k.startswith("Q"):
                mirrored[k] = P @ v @ P  # the mirror body's rotation from its own initial pose
            elif k in ("B", "D", "G"):
                mirrored[k] = v @ P + shift
            else:
                mirrored[k] = v @ P  # directions
        out = {k: np.concatenate([v, mirrored[k]], axis=1) for k, v in out.items()}
    out["theta"] = theta
    if scalar:
        out = {k: v[0] for k, v in out.items()}
    return out


def dead_centres(geom: SwashPlate) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Shaft angles [rad] of each cylinder's inner (x_D smallest) and outer dead centre, (z,) each.

    The extremes of x_D are found on a grid and refined as roots of u_k = dx_D/dφ (bisection to the
    last bit).
    Angles are not wrapped: each lies within a grid step (0.5°) of [0, 2π].
    """
    mp = geom.pack()
    z = geom.cylinders
    u, du = np.empty(z), np.empty(z)

    def rate(p: float, k: int) -> float:
        core.swash_terms(mp, p, u, du)
        return u[k]

    grid = np.linspace(0.0, 2.0 * pi, 721)
    h = grid[1]
    x = _points(mp, grid)[2][..., 0]
    inner, outer = np.empty(z), np.empty(z)
    for k in range(z):
        inner[k], outer[k] = (bisect_root(partial(rate, k=k), grid[j] - h, grid[j] + h)
                              for j in (np.argmin(x[:, k]), np.argmax(x[:, k])))
    return inner, outer


def stroke(geom: SwashPlate) -> NDArray[np.float64]:
    """Exact stroke of each cylinder's piston (z,) [m]: x_D max − min over a turn (the opposed
    piston of ``halves = 2`` moves as far).

    For ℓ → ∞ every stroke tends to 2R sin α; for finite ℓ the rod's lateral swing changes it slightly
    and differently per cylinder (:meth:`SwashPlate.stroke` is cylinder 1's).
    """
    inner, outer = dead_centres(geom)
    mp = geom.pack()
    z = geom.cylinders
    lo = _points(mp, inner)[2][np.arange(z), np.arange(z), 0]
    hi = _points(mp, outer)[2][np.arange(z), np.arange(z), 0]
    return hi - lo


def kinematics_table(geom: SwashPlate, phi: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """Positions, transfer functions and J(φ), dJ/dφ over the shaft angles ``phi`` [rad].

    Columns: ``phi_deg``; ``u9`` = |ω₉|/φ̇ and ``u13`` = ω₁₃/φ̇ (eq. (13), derived from positions);
    per cylinder k = 1 … z: ``x_<k>`` x of piston joint D [m] (negative: the pistons lie on the −x side
    of the plate centre O), ``u_<k>`` = dx_<k>/dφ [m/rad] and ``du_<k>`` [m/rad²] of that one
    piston (the kernel's sum over both pistons when halves = 2, divided by halves: the same
    piston as ``x_<k>``), ``rod_tilt_<k>_deg`` angle between rod and cylinder axis;
    ``J`` [kg m²], ``dJ_dphi`` [kg m²/rad]: the kernel's parts (all but shaft and plates).
    """
    phi = np.atleast_1d(np.asarray(phi, dtype=np.float64))
    mp = geom.pack()
    z = geom.cylinders
    sa2 = sin(geom.swash_angle) ** 2
    _, B, D = _points(mp, phi)
    cols: dict[str, NDArray[np.float64]] = {"phi_deg": np.degrees(phi)}
    link = np.array([core.hooke(mp, p) for p in phi])
    cols["u9"] = np.sqrt((cos(geom.swash_angle) + link[:, 1]) ** 2 + sa2)  # see core.hooke
    cols["u13"] = link[:, 3]
    u, du = np.empty((phi.size, z)), np.empty((phi.size, z))
    JdJ = np.array([core.swash_terms(mp, p, u[j], du[j]) for j, p in enumerate(phi)])
    rod = B - D
    tilt = np.degrees(np.arctan2(np.hypot(rod[..., 1], rod[..., 2]), rod[..., 0]))
    for k in range(z):
        cols[f"x_{k + 1}"] = D[:, k, 0]
        cols[f"u_{k + 1}"] = u[:, k] / geom.halves
        cols[f"du_{k + 1}"] = du[:, k] / geom.halves
        cols[f"rod_tilt_{k + 1}_deg"] = tilt[:, k]
    cols["J"] = JdJ[:, 0]
    cols["dJ_dphi"] = JdJ[:, 1]
    return cols

