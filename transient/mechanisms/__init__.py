"""The mechanisms: what each provides (:class:`~transient.mechanisms.Mechanism`) and the registry
of them (:data:`~transient.mechanisms.MECHANISMS`), through which the scene reader, the reference
path and the analyses reach a mechanism without naming its class.

A mechanism maps the shaft angle φ to the positions of its bodies and gives the reduced inertia
J(φ), dJ/dφ and the piston transfer functions u_k(φ) = ds_k/dφ, u′_k(φ): in the compiled core
for the stepper, in plain Python for the reference path.

What a mechanism provides beyond :class:`Mechanism` it claims in its ``capabilities``, each
named in :data:`CAPABILITIES`: the mechanism layer's are Protocols here (:class:`ReactionFriction`,
:class:`NumpyTwin`), the analyses' (which sit above the mechanisms, so a mechanism cannot name
them) are tables keyed by the mechanism's name in the layer that holds them. Every place that
branches on the mechanism asks :func:`provider`, which errors for a mechanism that does not claim
the capability and for one that claims it without a provider, never falls through to another
mechanism's code; ``tests/unit/test_mechanism_registry.py`` holds every registered mechanism to
its claims. Adding a mechanism is ``docs/developer/mechanisms.md``.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .articulated import Articulated
from .crank_slider import CrankSlider
from .scotch_yoke import ScotchYoke
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
    #: Its compiled kernel's entry, ``terms(mp, kin_coef, φ, u, u′, with_dJ) -> (J, dJ/dφ)``
    #: filling u_k, u′_k (``Model.terms``, :mod:`transient.core.model.layout`): the stepper is
    #: compiled for it, and the kinematics tables sample it.
    kernel: ClassVar[Any]
    #: Its compiled kernel of each cylinder's share of J(φ) at the angle of the station that
    #: carries it, ``shares(mp, kin_coef, angles, J_c, J′_c, u, u′, with_dJ)``
    #: (:func:`transient.core.model.crank_slider.shares`; without ``with_dJ`` J′_c and u′ may be
    #: left NaN): the elastic shaft line's per-station inertia. Cylinders that move together (a
    #: row of master and articulated rods, a swash plate's) ride one station, and the first of
    #: them takes their whole share.
    shares_kernel: ClassVar[Any]
    #: What it provides beyond this Protocol, names of :data:`CAPABILITIES`.
    capabilities: ClassVar[frozenset[str]]
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
    #: pistons' s′, s″ come from their capability ``"pistons"``).
    slider_law: ClassVar[bool]
    @property
    def strokes(self) -> int:
        """2 or 4: the gas cycle's length, ``cycle`` = π·strokes."""

    @classmethod
    def read(cls, section: Section, /) -> Mechanism:
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


@runtime_checkable
class ReactionFriction(Protocol):
    """Friction on the joints' reactions (``model = "reaction"`` pairs, capability
    ``"reaction-friction"``): its joints, its compiled solver, where its joints reverse, and the
    checks that its equations stay solvable (wedging)."""

    #: Its links for reaction pairs, shaft side first (the frame last).
    reaction_links: ClassVar[tuple[str, ...]]
    #: The joints reaction pairs may name, (shaft-side link, far link), in the order of the rows
    #: of ``Model.rx_par``.
    reaction_joints: ClassVar[tuple[tuple[str, str], ...]]
    #: The joint where a constant-η or mapped pair may sit among reaction pairs (the main
    #: bearings, ``transient.core.model.reactions``), or None where none may.
    shaft_coupling: ClassVar[tuple[str, str] | None]
    #: Its compiled solver's kernels (prepare, solve, inverse_drive): ``Model.rx_prepare``,
    #: ``rx_solve``, ``rx_inverse``.
    reaction_kernels: ClassVar[tuple[Any, Any, Any]]
    #: Whether its solve leaves each cylinder's side force for the stepper's side tracking
    #: (``Model.rx_sides``).
    tracks_sides: ClassVar[bool]

    @property
    def ideal_reaction_joints(self) -> dict[str, str]:
        """Joints (by their shaft-side link) that cannot have friction on their reactions, each
        with why, for the scene's error."""

    def reaction_reversals(self, cylinders=None) -> NDArray[np.float64]:
        """Shaft angles [rad] in [0, cycle) where a joint's relative motion reverses while ω
        keeps its sign: breakpoints, so that no step straddles a friction force's reversal; of
        the ``cylinders`` (0-based) only where given, with ``"cylinder-inertia"`` (an elastic
        line's throw)."""

    def check_wedging(self, s: Section, pairs, raw) -> None:
        """Raise :class:`~transient.errors.SceneError` (naming the pair as the user wrote it,
        ``raw`` the pairs' tables as written) where a reaction pair's friction could wedge the
        mechanism: its equations must keep one solution over the whole cycle."""


@runtime_checkable
class NumpyTwin(Protocol):
    """A plain-numpy twin of its kernel (capability ``"twin"``), written from the equations
    again, for the reference path, which must not share the compiled code it checks; a mechanism
    without one runs its kernel's Python code there (:class:`~.twins.KernelTwin`)."""

    #: Built from the mechanism, its ``terms(φ)`` gives (J, dJ/dφ, u_k, u′_k).
    twin: ClassVar[type]


@runtime_checkable
class CylinderInertia(Protocol):
    """Each cylinder's own share of J(φ) (capability ``"cylinder-inertia"``), so that an elastic
    shaft line (:mod:`transient.shaft`) can put each crankpin's cylinders on a station of their
    own, each at its station's angle. A mechanism without it keeps its cylinders together: its
    whole J(φ) on one station."""

    @property
    def crankpins(self) -> tuple[tuple[int, ...], ...]:
        """The cylinders (0-based) by the crankpin they ride on, from the nose: the cylinders
        of one crankpin move together and stay on one station."""

    def cylinder_inertia_terms(self) -> Callable[[float], tuple[NDArray[np.float64],
                                                                NDArray[np.float64]]]:
        """θ ↦ (J_k(θ), dJ_k/dθ) of every cylinder k at shaft angle θ (each at its own phase)
        [kg m², kg m²/rad], whose sum over k is the mechanism's J(θ), dJ/dθ."""

    def pack_cylinders(self, cylinders) -> NDArray[np.float64]:
        """The compiled parameter array (``pack``) of the mechanism made of the ``cylinders``
        (0-based) alone, each at its own phase: a throw of an elastic line, whose joints'
        reaction friction its solver takes at the throw's own angle."""


#: Every capability a mechanism may claim, and who provides it: a Protocol of this module (the
#: mechanism itself), or the table that holds it keyed by the mechanism's name.
CAPABILITIES: dict[str, type | str] = {
    "reaction-friction": ReactionFriction,
    "twin": NumpyTwin,
    "cylinder-inertia": CylinderInertia,
    "reaction-twin": "transient.reference.integrate.REACTION_TWINS",
    "pistons": "transient.analysis.pistons.KINEMATICS",
    "loads": "transient.analysis.requested.LOADS",
    "drawers": "transient.cli.loads.DRAWERS",
}


#: Capabilities that claim others: the reference path checks reaction friction by its twin.
IMPLIES: dict[str, tuple[str, ...]] = {"reaction-friction": ("reaction-twin",)}


class PluginTable(Mapping[str, Any]):
    """A table of a layer above the mechanisms (an analysis's, keyed by mechanism name) whose
    entries are its own or live in one module per mechanism of that layer: ``module`` with
    ``{}`` for the mechanism's name in snake case (``"scotch-yoke"`` → ``scotch_yoke``) and
    ``attr`` the entry's name there. A mechanism's plugin thus adds its analysis as a file of
    its own, imported when first asked for; the layer names the module, so nothing imports
    upward."""

    def __init__(self, own: Mapping[str, Any], module: str, attr: str) -> None:
        self.own, self.module, self.attr = dict(own), module, attr

    def _found(self, name: str):
        import importlib
        import importlib.util

        where = self.module.format(name.replace("-", "_"))
        if name not in MECHANISMS or importlib.util.find_spec(where) is None:
            return None
        return getattr(importlib.import_module(where), self.attr, None)

    def __getitem__(self, name: str):
        if name in self.own:
            return self.own[name]
        found = self._found(name)
        if found is None:
            raise KeyError(name)
        return found

    def __iter__(self):
        return iter([n for n in MECHANISMS if n in self])

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and (name in self.own or self._found(name) is not None)

    def __repr__(self) -> str:
        return f"{self.module}.{self.attr}"


class MissingCapability(LookupError):
    """A mechanism claims a capability that nothing provides for it (a defect of the mechanism's
    plugin, not of the scene)."""


def provides(mech, capability: str) -> bool:
    """Whether ``mech`` (a mechanism or its class) claims ``capability``; an unknown name is an
    error."""
    if capability not in CAPABILITIES:
        raise ValueError(f"unknown capability {capability!r}; known: {', '.join(CAPABILITIES)}")
    return capability in mech.capabilities


def provider(mech, capability: str, table: Mapping[str, Any]):
    """``table[mech.name]``, the provider of ``capability`` for ``mech``; None if it does not
    claim it (the caller refuses the request with its own message); :class:`MissingCapability`
    if it claims it and ``table`` has no entry for it."""
    if not provides(mech, capability):
        return None
    try:
        return table[mech.name]
    except KeyError:
        raise MissingCapability(f"{mech.name!r} claims {capability!r}, which "
                                f"{CAPABILITIES[capability]} does not provide for it") from None


def needed(mech, capability: str, table: Mapping[str, Any]):
    """:func:`provider` where the caller cannot go on without it: :class:`MissingCapability`
    if ``mech`` does not claim ``capability`` either (:data:`IMPLIES` keeps it from happening)."""
    found = provider(mech, capability, table)
    if found is None:
        raise MissingCapability(f"{mech.name!r} does not claim {capability!r}, which is needed "
                                f"here")
    return found


def protocol_members(protocol: type) -> set[str]:
    """The names a class must have to follow ``protocol``: its annotated attributes and its
    methods and properties."""
    names = set(getattr(protocol, "__annotations__", {}))
    names |= {n for n, v in vars(protocol).items()
              if not n.startswith("_") and (callable(v) or isinstance(v, (property,
                                                                           classmethod)))}
    return names


def capability_gaps(cls: type, tables: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """What mechanism class ``cls`` lacks of :class:`Mechanism` and of what it claims, one line
    each ([] if nothing): a claimed name not in :data:`CAPABILITIES`, a member of a claimed
    Protocol it does not define, a claimed table capability with no entry in ``tables`` (its
    table by capability name), an entry there it does not claim, a claim :data:`IMPLIES` that
    it does not make."""
    fields = ({f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls)
              else set[str]())
    # a class that lacks them is reported below, as lacking members of Mechanism
    claims: frozenset[str] = getattr(cls, "capabilities", frozenset())
    name: str = getattr(cls, "name", cls.__name__)

    def lacks(member: str) -> bool:
        return member not in fields and not any(member in vars(c) for c in cls.__mro__)

    gaps = [f"{cls.__name__} lacks {member!r} of Mechanism"
            for member in sorted(protocol_members(Mechanism)) if lacks(member)]
    for cap in sorted(claims):
        what = CAPABILITIES.get(cap)
        if what is None:
            gaps.append(f"{cls.__name__} claims {cap!r}, not a capability")
        elif isinstance(what, type):
            gaps += [f"{cls.__name__} claims {cap!r} but lacks {member!r} of {what.__name__}"
                     for member in sorted(protocol_members(what)) if lacks(member)]
        gaps += [f"{cls.__name__} claims {cap!r} but not {also!r}, which it implies"
                 for also in IMPLIES.get(cap, ()) if also not in claims]
    for cap, table in tables.items():
        claimed, listed = cap in claims, name in table
        if claimed and not listed:
            gaps.append(f"{cls.__name__} claims {cap!r} but {CAPABILITIES[cap]} has no "
                        f"{name!r}")
        if listed and not claimed:
            gaps.append(f"{CAPABILITIES[cap]} has {name!r}, which does not claim {cap!r}")
    return gaps


def reaction_joints(mech) -> tuple[tuple[str, str], ...]:
    """The joints that pairs with friction on their reactions may name, in the order of the rows
    of ``Model.rx_par``; () if it has no reaction friction."""
    return mech.reaction_joints if provides(mech, "reaction-friction") else ()


#: Every mechanism by its ``type`` in the ``[mechanism]`` table.
MECHANISMS: dict[str, type[Mechanism]] = {
    "crank-slider": CrankSlider,
    "swash-plate": SwashPlate,
    "articulated": Articulated,
    "scotch-yoke": ScotchYoke,
}
