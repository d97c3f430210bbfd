"""A scene's shaft line as matrices: the degrees of freedom, their constant stiffness K and
damping C, and the angle-dependent inertia of each station.

**Degrees of freedom**, in order along the line: each station, each followed by the rings of
the dampers on it, then the driven inertia of a coupling. Each ring couples to its hub only, so
K and C stay banded (the stations' chain tridiagonal, a ring one place off it).

**Inertia.** Station s carries its own constant inertia and the cylinders of its crankpins:
J_s(θ) = J_own,s + Σ_{k on s} J_k(θ) and J′_s(θ) = Σ_{k on s} dJ_k/dθ, each cylinder's share of
the mechanism's J at the station's own angle θ, with the cylinder's own phase (capability
``"cylinder-inertia"``). A mechanism without it carries all its cylinders on one station, whose
J is then the mechanism's whole J(θ). With every station at one angle, Σ_s J_s(φ) plus the rings'
and the driven side's inertias is the rigid model's J(φ) (:func:`rigid_equivalent`).

**Damping.** Absolute per station, relative per section, a damper's between its ring and hub,
a coupling's across it. A station's absolute damping a_s acts on its motion relative to the
line's rigid-body motion ω̄ = Σ w_d ω_d / Σ w_d (w_d the cycle-mean inertias), never as a drag
on the whole rotation, which at running speed would take a_s·Ω² (0.5 N m s/rad at 3000 rpm is
49 kW): its damping matrix is Pᵀ A P with P = I − 1 wᵀ/Σw and A = diag(a), which has no net
torque and takes Σ a_d (ω_d − ω̄)² of power (theory, (T3)). A section given by a loss factor η or a damping ratio
ζ gets the viscous c = η·k/ω₁ = 2ζ·k/ω₁ at ω₁, the lowest natural frequency of the undamped
line at cycle-mean inertias (hysteretic damping's equivalent at the mode that matters most:
per cycle of that mode it dissipates πηkΘ², as the hysteretic law does).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import cast

import numpy as np
from numpy.typing import NDArray

from ..core.model.layout import MAX_MARGINS
from ..errors import SceneError
from ..mechanisms import CylinderInertia, provides
from ..scene.records import COMPILED_METHODS, Inertia, Scene, Shaft

#: Angles per revolution at which the cycle-mean inertias are sampled: J(θ) is periodic and
#: smooth, so the mean of equally spaced samples converges geometrically.
MEAN_SAMPLES = 720


@dataclass(frozen=True)
class Dof:
    """A degree of freedom of the line (:meth:`~transient.scene.records.Shaft.line_dofs`): its
    ``name`` (a station's, ``"<station> damper"``, ``"driven"``), its ``kind``
    (``"station"``, ``"ring"``, ``"driven"``) and the station it belongs to (for a ring its
    hub's; -1 for the driven inertia)."""

    name: str
    kind: str
    station: int


class ShaftLine:
    """The shaft line of ``scene`` (which has a ``[shaft]`` table)."""

    def __init__(self, scene: Scene) -> None:
        if scene.shaft is None:
            raise ValueError(f"scene {scene.name!r} has no [shaft] table")
        shaft: Shaft = scene.shaft
        self.scene, self.shaft = scene, shaft
        self.dofs = tuple(Dof(*d) for d in shaft.line_dofs())
        self.station_dof = [i for i, d in enumerate(self.dofs) if d.kind == "station"]
        self.n = len(self.dofs)
        self._own = self._own_inertia()
        self._cylinder_terms = _cylinder_terms(scene)
        self.K = self._stiffness()
        #: the dofs' cycle-mean inertias: the weights of the rigid-body motion that the absolute
        #: damping is relative to
        self.weights = self.mean_inertia()
        self.omega_1 = float(np.sqrt(_lowest_elastic(self.K, self.weights, self.rigid_modes)))
        self.C = self._damping()

    # -- the degrees of freedom ---------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(d.name for d in self.dofs)

    @property
    def rigid_modes(self) -> int:
        """Modes of zero frequency: the free line's one, and one per viscous ring, which no
        spring ties to anything."""
        return 1 + sum(d.model == "viscous" for d in self.shaft.dampers)

    def rings(self):
        """(damper, its ring's dof, its hub's dof) of each damper."""
        ring_of = iter(i for i, d in enumerate(self.dofs) if d.kind == "ring")
        by_station = sorted(self.shaft.dampers,
                            key=lambda d: self.shaft.station_index(d.station))
        # (rings follow their stations in order; dampers of one station keep the scene's order)
        for damper in by_station:
            yield damper, next(ring_of), self.station_dof[self.shaft.station_index(damper.station)]

    @property
    def own_inertia(self) -> NDArray[np.float64]:
        """Each dof's own constant inertia [kg m²]: a station's without its cylinders', a
        ring's, the driven inertia referred to the shaft."""
        return self._own.copy()

    def _own_inertia(self) -> NDArray[np.float64]:
        own = np.zeros(self.n)
        for st, i in zip(self.shaft.stations, self.station_dof):
            own[i] = st.inertia
        for damper, ring, _ in self.rings():
            own[ring] = damper.inertia
        if self.shaft.coupling is not None:
            own[-1] = self.shaft.coupling.referred_inertia
        return own

    # -- matrices ------------------------------------------------------------------------------
    def _pairs(self, omega_1: float = np.nan):
        """(dof a, dof b, stiffness, damping) of every element joining two dofs; a section's
        loss factor or damping ratio as the viscous c at ``omega_1`` (one of the three is
        given, the others are 0)."""
        shaft, at = self.shaft, self.station_dof
        for i, sec in enumerate(shaft.sections):
            relative = sec.loss_factor + 2.0 * sec.damping_ratio
            c = sec.damping + (relative * sec.stiffness / omega_1 if relative else 0.0)
            yield at[i], at[i + 1], sec.stiffness, c
        for damper, ring, hub in self.rings():
            yield hub, ring, damper.stiffness, damper.damping
        if shaft.coupling is not None:
            cp = shaft.coupling
            yield at[-1], self.n - 1, cp.stiffness, cp.damping

    def element_rows(self) -> NDArray[np.float64]:
        """The elements as the compiled model's element table
        (:data:`transient.core.model.layout.ELEMENT`): per row the two dofs, stiffness, damping
        and gear ratio (1: the driven inertia is referred to the shaft); the same elements as
        K and C."""
        rows = [(a, b, k, c, 1.0) for a, b, k, c in self._pairs(self.omega_1)]
        return np.array(rows, dtype=float).reshape(len(rows), 5)

    @property
    def absolute(self) -> NDArray[np.float64]:
        """Each dof's absolute damping a_d [N m s/rad] (the stations'; 0 on rings and driven)."""
        a = np.zeros(self.n)
        for st, i in zip(self.shaft.stations, self.station_dof):
            a[i] = st.damping
        return a

    @staticmethod
    def _assemble(n: int, pairs) -> NDArray[np.float64]:
        out = np.zeros((n, n))
        for a, b, value in pairs:
            out[a, a] += value
            out[b, b] += value
            out[a, b] -= value
            out[b, a] -= value
        return out

    def _stiffness(self) -> NDArray[np.float64]:
        return self._assemble(self.n, ((a, b, k) for a, b, k, _ in self._pairs()))

    def _damping(self) -> NDArray[np.float64]:
        C = self._assemble(self.n, ((a, b, c) for a, b, _, c in self._pairs(self.omega_1)))
        P = np.eye(self.n) - np.outer(np.ones(self.n), self.weights) / self.weights.sum()
        return C + P.T @ np.diag(self.absolute) @ P

    # -- inertia ---------------------------------------------------------------------------
    def station_inertia(self, theta) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(J_s, J′_s) of every station at its angle ``theta`` [rad] (one per station, or one
        for all): own inertia plus its cylinders' reduced inertia, and its derivative."""
        stations = self.shaft.stations
        theta = np.broadcast_to(np.asarray(theta, dtype=float), (len(stations),))
        J = np.array([st.inertia for st in stations], dtype=float)
        dJ = np.zeros(len(stations))
        for s, st in enumerate(stations):
            if st.cylinders:
                Jk, dJk = self._cylinder_terms(float(theta[s]))
                cyl = np.asarray(st.cylinders) - 1
                J[s] += float(np.sum(np.asarray(Jk)[cyl]))
                dJ[s] = float(np.sum(np.asarray(dJk)[cyl]))
        return J, dJ

    def mass_diagonal(self, phi: float) -> NDArray[np.float64]:
        """The inertia of every dof with every station frozen at the angle ``phi`` [rad]."""
        diag = self._own.copy()
        diag[self.station_dof] = self.station_inertia(phi)[0]
        return diag

    def mean_inertia(self, samples: int = MEAN_SAMPLES) -> NDArray[np.float64]:
        """Every dof's inertia averaged over one revolution (the linearised line's)."""
        phi = 2.0 * np.pi * np.arange(samples) / samples
        return np.mean([self.mass_diagonal(p) for p in phi], axis=0)


def _cylinder_terms(scene: Scene):
    """θ ↦ (J_k, dJ_k/dθ) per cylinder: the mechanism's own split where it has one, else its
    whole J(θ) given to each cylinder's share as J/n (all of them sit on one station)."""
    mech = scene.mechanism
    if provides(mech, "cylinder-inertia"):
        return cast(CylinderInertia, mech).cylinder_inertia_terms()
    whole = mech.reference_terms()
    n = mech.n_cylinders

    def shares(theta: float):
        J, dJ, _, _ = whole(theta)
        return np.full(n, J / n), np.full(n, dJ / n)
    return shares


def _lowest_elastic(K, M_diag, rigid: int) -> float:
    """ω₁² of the undamped line: its lowest eigenvalue past the ``rigid`` zero ones."""
    # (M is diagonal: K x = ω² M x is the symmetric D K D y = ω² y with D = M^(-1/2), which
    # numpy solves; a run builds the line, and a warm run loads no scipy.linalg)
    scale = 1.0 / np.sqrt(M_diag)
    values = np.linalg.eigvalsh(scale[:, None] * K * scale[None, :])
    return float(values[rigid]) if values.size > rigid else np.nan


#: What the elastic run does not support yet: (the scene's key, whether the scene uses it, what
#: to do instead). Each is refused before any work (:func:`refuse_elastic_run`).
UNSUPPORTED = (
    ("friction.pairs", lambda s: any(p.model == "reaction" for p in s.friction.pairs)
     and any(p.model != "reaction" for p in s.friction.pairs),
     "a pair of constant or mapped efficiency at the main bearings among reaction pairs "
     "would hold a mode of its own in every throw, which the throws' joint solves do not "
     "have: give the main bearings friction on their reactions too (model = \"reaction\"), "
     "or every pair efficiencies"),
    ("friction.pairs", lambda s: len(s.friction.pairs) * len(s.shaft.throws) > MAX_MARGINS,
     f"every pair acts in every station that carries cylinders, each with a mode of its own, "
     f"and a line holds at most {MAX_MARGINS} such modes: give fewer pairs, or fewer stations "
     f"with cylinders"),
    ("friction.policy", lambda s: any(p.model != "reaction" for p in s.friction.pairs)
     and s.friction.policy == "paper",
     "on a throw the paper's criterion (25) would count the sections' torques among the moments "
     "applied on a pair's shaft side: use \"power-flow\", whose modes follow the power each "
     "pair transmits"),
    ("initial.omega", lambda s: bool(s.friction.pairs) and s.initial.omega == 0.0,
     "from rest with [[friction.pairs]] a throw whose pairs' friction holds it would need a "
     "stuck state of its own: start the line turning (initial omega ≠ 0)"),
    ("load.table", lambda s: s.load.table is not None and s.load.table.abscissa == "angle"
     and s.shaft.load_at != s.shaft.reference,
     "a load tabulated against the angle acts at the reference station only (its angle is the "
     "run's crank angle): let the load act there (load_at), or tabulate it against speed or "
     "time"),
    ("load.inertia", lambda s: s.load.inertia > 0.0,
     "switched in, it would change the load's degree of freedom's inertia in the middle of the "
     "run, and with it the line's first natural frequency (which gives the sections' loss "
     "factors and damping ratios their viscous c) and the absolute damping's weights; give "
     "the driven inertia in [shaft.coupling] from the start"),
    ("run.mode", lambda s: s.run.mode != "dynamic", "use \"dynamic\""),
    ("solver.method", lambda s: s.solver.method not in COMPILED_METHODS,
     f"use one of {', '.join(map(repr, COMPILED_METHODS))} (the compiled stepper)"),
    ("solver.kinematics", lambda s: s.solver.kinematics == "tabulated" and len(
        {i for i, st in enumerate(s.shaft.stations) if st.cylinders}) > 1,
     "use the exact kinematics, or put every cylinder on one station (the tables hold the "
     "mechanism's J(φ) whole)"),
)


def refuse_elastic_run(scene: Scene) -> None:
    """Raise :class:`~transient.errors.SceneError` for a scene with ``[shaft]`` that uses what
    the elastic time-domain run does not support (:data:`UNSUPPORTED`): running it without that
    feature, or rigid, would not do what the scene asks."""
    if scene.shaft is None:
        return
    for key, used, instead in UNSUPPORTED:
        if used(scene):
            raise SceneError(key, f"is not supported with an elastic [shaft] line in this "
                                  f"version; {instead}, or run the rigid model without [shaft] "
                                  f"(transient.shaft.rigid_equivalent)",
                             file=scene.source_file)


def rigid_equivalent(scene: Scene) -> Scene:
    """``scene`` with a rigid shaft: no ``[shaft]``, and ``[inertia]`` holding the line's
    constant inertias as one body, the stations' own and the damper rings' as ``shaft`` and
    the driven inertia referred to the shaft (i²·J_d) as ``load``. Its J(φ) is the line's at
    one angle everywhere. A scene without ``[shaft]`` comes back as it is."""
    shaft = scene.shaft
    if shaft is None:
        return scene
    driven = shaft.coupling.referred_inertia if shaft.coupling else 0.0
    own = shaft.constant_inertia - driven
    return replace(scene, shaft=None, inertia=Inertia(shaft=own, load=driven),
                   source_file="", source_text="")
