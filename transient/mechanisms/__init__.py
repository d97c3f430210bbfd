"""The mechanisms: what each provides (:class:`~transient.mechanisms.Mechanism`) and the registry
of them (:data:`~transient.mechanisms.MECHANISMS`), through which the scene reader, the reference
path and the analyses reach a mechanism without naming its class.

A mechanism maps the shaft angle φ to the positions of its bodies and gives the reduced inertia
J(φ), dJ/dφ and the piston transfer functions u_k(φ) = ds_k/dφ, u′_k(φ): in the compiled core
for the stepper, in plain Python for the reference path.

Adding a mechanism takes

1. its compiled kernel, ``transient/core/<name>.py``: ``<name>_terms(mp, φ, u, du) -> (J, dJ/dφ)``
   filling u_k and u′_k, a kind code in :mod:`transient.core.model.layout` and its branch in
   ``transient.core.model.forcing.mechanism_terms`` (the stepper and the kinematics tables reach it
   there);
2. its mechanism file, ``transient/mechanisms/<name>.py``: a frozen dataclass in SI with the
   members of :class:`Mechanism` (read from its ``[mechanism]`` table, validated, packed for
   the kernel, written back to TOML);
3. its loads analysis: a module of :mod:`transient.analysis` and its line in
   ``transient.analysis.requested.LOADS`` (without one, ``[analysis] loads = true`` is refused
   for it: the analyses sit above the mechanisms, so a mechanism cannot name them itself),
   its pistons' travel in ``transient.analysis.pistons.KINEMATICS`` (cylinder volumes, piston
   accelerations, each cylinder's torque),
   and, if ``transient loads`` is to draw its diagrams, a line in
   ``transient.cli.loads.DRAWERS``;
4. one line in :data:`MECHANISMS` below.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .articulated import Articulated
from .crank_slider import CrankSlider
from .swash_plate import SwashPlate

if TYPE_CHECKING:
    from ..scene.reader import Section


@runtime_checkable
class Mechanism(Protocol):
    """What every mechanism provides, and who uses it.

    All quantities in SI; angles in rad, shaft angle φ from the mechanism's reference position.
    """

    #: Its ``type`` in the ``[mechanism]`` table and its key in :data:`MECHANISMS`; the resolved
    #: scene writes it back (:meth:`toml_lines`) and errors name it.
    name: ClassVar[str]
    #: ``Model.kind`` of its kernel in the compiled core (:mod:`transient.core.model.layout`), for
    #: ``transient.assemble`` and the kinematics tables.
    kind: ClassVar[int]
    #: The links of its serial chain, shaft first: a friction pair joins two neighbours
    #: (the scene's ``[friction]``, the chain of ``transient.assemble`` and the reference path).
    #: The first carries the shaft's inertia and the load, the last the gas forces (the
    #: cylinders: their gas does its work on the pistons through the pair between them).
    links: ClassVar[tuple[str, ...]]
    #: How each link's reduced inertia follows φ (``transient.core.model.layout.LINK_*``): constant
    #: (:meth:`link_inertias`), the pistons' (:attr:`piston_link_mass`), the swash plate's
    #: link 9, or the rest of J(φ) (exactly one link).
    link_laws: ClassVar[tuple[int, ...]]
    #: Whether a scene may give it wall heat transfer (``[gas.woschni]``): the cylinder ODE of
    #: ``transient.core.model.cylinder`` is built for the crank-slider's volume.
    wall_heat_transfer: ClassVar[bool]
    #: The keys its :attr:`n_cylinders` follows from, as the bounds of per-cylinder keys
    #: (``[[gas.cylinders]] cylinder``) name them.
    cylinder_count: ClassVar[str]
    #: What each key of its ``[mechanism]`` table (``"mechanism"``) and sub-tables
    #: (``"mechanism.rod"``) means, in a line: key → meaning, for the scene-key reference.
    key_meanings: ClassVar[dict[str, dict[str, str]]]
    #: Whether every piston follows the crank-slider law s(φ − φ_k) of ``crank_radius``,
    #: ``rod_length`` and ``offset`` (the odd-harmonic report then uses that closed form; other
    #: pistons' s′, s″ come from ``transient.analysis.pistons``, which needs a line for a new
    #: mechanism).
    slider_law: ClassVar[bool]
    #: 2 or 4: the gas cycle's length, ``cycle`` = π·strokes.
    strokes: int

    @classmethod
    def read(cls, section: Section) -> Mechanism:
        """The mechanism from its ``[mechanism]`` table (the scene reader has taken ``type`` and
        finishes the table); validated, errors naming the keys as the user wrote them."""

    def validate(self) -> None:
        """Raise :class:`~transient.errors.SceneError` for a geometry or mass set that cannot
        work."""

    @property
    def n_cylinders(self) -> int:
        """Gas-force points: the length of every per-cylinder array and result column."""

    @property
    def cycle(self) -> float:
        """Length of the engine cycle in shaft angle [rad]."""

    @property
    def firing_angles(self) -> tuple[float, ...]:
        """Shaft angle [rad] at which each cylinder's gas table is at local angle 0, in
        [0, cycle)."""

    @property
    def bank_angles(self) -> tuple[float, ...]:
        """Each cylinder's axis [rad] from the reference axis, in the direction of rotation."""

    @property
    def piston_area(self) -> float:
        """Area of one piston [m²]: pressure times it is the gas force."""

    def swept_volume(self) -> float:
        """Volume [m³] swept in the cylinder :meth:`volume_function` describes; with the
        compression ratio it sets the clearance volume of the cycle models."""

    def volume_function(self, clearance: float) -> Callable[[ArrayLike], NDArray[np.float64]]:
        """V(x) [m³] of a cylinder over its local angle x [rad] (vectorised), ``clearance`` [m³]
        the volume at top dead centre: what the cycle models (mixed, Wiebe, Woschni) compress."""

    def dead_centre_angles(self) -> tuple[float, float]:
        """Local angles [rad] of the top and bottom dead centre of that cylinder, where V is
        least and greatest: a cycle compresses from one to the other, and an offset moves them
        off 0 and π."""

    def pack(self) -> NDArray[np.float64]:
        """The parameter array of its compiled kernel."""

    def link_inertias(self) -> tuple[float, ...]:
        """Constant reduced inertia of each link besides the shaft's [kg m²] (0 where it
        varies with φ, ``link_laws``)."""

    @property
    def piston_link_mass(self) -> float:
        """m of the pistons' link, whose reduced inertia is m·Σ_k u_k² [kg]."""

    def kinematics_table(self, phi: NDArray[np.float64]) -> dict[str, NDArray[np.float64]]:
        """Columns over the shaft angles ``phi`` [rad]: ``phi_deg``, ``J`` [kg m²], ``dJ_dphi``
        [kg m²/rad] and per cylinder k ``u_k`` [m/rad], ``du_k`` [m/rad²] and positions (the
        scene's check J(φ) > 0, ``transient kinematics``)."""

    def reference_terms(self) -> Callable[[float], tuple[float, float, NDArray[np.float64],
                                                         NDArray[np.float64]]]:
        """φ ↦ (J, dJ/dφ, u_k, u′_k) outside the compiled code, for the reference path
        (:mod:`transient.mechanisms.twins`)."""

    def toml_lines(self) -> list[str]:
        """Its ``[mechanism]`` table (and sub-tables) in SI, which :meth:`read` reads back to an
        equal object."""

    def geometry(self) -> dict[str, tuple[float, str]]:
        """What the geometry implies, without a run, name → (value, unit) in SI: every
        mechanism's ``stroke`` [m] and ``swept_volume`` [m³] of the cylinder
        :meth:`volume_function` describes and the engine's ``displacement`` [m³] (every piston's
        swept volume), and its own figures (dead-centre angles, λ, each piston's stroke); the
        names are listed in the user guide's *Mechanisms* page, and ``transient check`` prints
        them as they are named here."""

    def analysis_summary(self) -> dict[str, tuple[float, str]]:
        """Figures of the mechanism itself for a result's ``/analysis``, name → (value, unit);
        {} if it has none."""


def reaction_joints(mech) -> tuple[tuple[str, str], ...]:
    """The joints that pairs with friction on their reactions may name, (shaft-side link, far
    link) in the order of the rows of ``Model.rx_par``: the mechanism's own
    ``reaction_joints``, else the neighbours of its ``reaction_links`` (a chain, as the
    crank-slider's); () if it has no reaction friction."""
    links = getattr(mech, "reaction_links", ())
    return getattr(mech, "reaction_joints", tuple(zip(links, links[1:])))


#: Every mechanism by its ``type`` in the ``[mechanism]`` table.
MECHANISMS: dict[str, type[Mechanism]] = {
    "crank-slider": CrankSlider,
    "swash-plate": SwashPlate,
    "articulated": Articulated,
}
