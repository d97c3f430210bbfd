"""Compile the kernels ahead of a first run (``transient warmup``), and record what a compile
costs, function by function.

A first run on a cold cache compiles the stepper and every kernel it calls (numba's on-disk
cache, :mod:`transient.core`); later runs load them. :func:`warm_up` does that compile at a
time the user chooses — at install, or on each node of a cluster before a sweep — by running
built-in scenes for a fraction of a revolution, and the user's scenes too where given; other
commands compile a few small kernels of their own on first use (the kinematics tables of
``transient kinematics``, a loads analysis). The kernels come in two variants
(:func:`transient.core.model.layout.extras_of`): the plain one that scenes without friction pairs,
governor states, latched fuel, cylinder states, per-cylinder variation or a tabulated load run,
and the full one that the others share (its Model's types do not depend on the features used);
the built-in scenes compile both.

:class:`CompileLog` listens to numba's ``numba:compile`` events, which fire for functions
compiled, not for those loaded from the cache: per function, the seconds it took with and
without the callees compiled inside it. ``transient bench --targets`` records it for a cold
first run.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import Any

from numba.core import event

from .assemble import build_model
from .core.model.layout import extras_of
from .errors import SimulationError
from .run import simulate
from .scene import Friction, Pair, Scene

#: The scene :func:`warm_up` runs: the Gots diesel (Gots, Table 1) with friction pairs and a
#: mixed cycle, which reaches every kind of kernel the stepper calls.
WARMUP_SCENE: dict[str, dict[str, Any]] = {
    "scene": {"name": "warmup", "description": "compiles the kernels (transient warmup)"},
    "mechanism": {"type": "crank-slider", "crank_radius_mm": 47, "rod_length_mm": 148,
                  "bore_mm": 88, "piston_mass": 1.52, "crank_mass": 0.912, "strokes": 4,
                  "cylinders": 3, "firing_order": [1, 2, 3], "firing_deg": [360, 600, 120],
                  "rod": {"model": "two-mass", "mass": 1.752, "cg_from_pin_mm": 107.3}},
    "gas": {"model": "mixed-cycle", "p0_MPa": 0.1, "compression_ratio": 18, "p_a_MPa": 0.1436,
            "n1": 1.368, "p_z_MPa": 10.5, "rho": 1.671, "n2": 1.228, "p_intake_MPa": 0.165,
            "p_exhaust_MPa": 0.182},
    "inertia": {"shaft": 0.02, "flywheel": 0.15},
    "load": {"fan": 9.692e-4},
    "initial": {"omega_rpm": 1000},
    "run": {"revolutions": 0.25},
    "friction": {"pairs": [
        {"name": "main bearings", "between": ["shaft", "crank"], "eta_forward": 0.985,
         "eta_backward": 0.98},
        {"name": "crankpins", "between": ["crank", "rod"], "eta_forward": 0.98,
         "eta_backward": 0.975}]},
}

#: How long :func:`warm_up` runs each scene [revolutions].
WARMUP_REVOLUTIONS: float = WARMUP_SCENE["run"]["revolutions"]
#: The same engine without friction pairs: a plain scene (the kernels' plain variant).
PLAIN_SCENE = {key: value for key, value in WARMUP_SCENE.items() if key != "friction"}
#: A prescribed speed (the inverse dynamics are kernels of their own).
PRESCRIBED = {"run": {"mode": "prescribed-speed", "speed_rpm": 1000,
                      "revolutions": WARMUP_REVOLUTIONS}}
#: The built-in scenes: :data:`WARMUP_SCENE` and :data:`PLAIN_SCENE`, each also at a prescribed
#: speed; and with Wiebe combustion, Woschni's heat transfer and a flyweight governor (Gots §3;
#: the cylinder and governor states start from Python-side calls of the kernels).
WARMUP_SCENES = (
    WARMUP_SCENE,
    {**WARMUP_SCENE, **PRESCRIBED},
    PLAIN_SCENE,
    {**PLAIN_SCENE, **PRESCRIBED},
    {**WARMUP_SCENE,
     "gas": {"model": "wiebe", "p0_MPa": 0.1, "compression_ratio": 18, "p_a_MPa": 0.1436,
             "p_intake_MPa": 0.165, "p_exhaust_MPa": 0.182, "injection_deg": 340,
             "wiebe": {"start_deg": 358, "duration_deg": 50, "a": 6.908, "m": 0.5,
                       "fuel_mass": 0.031e-3, "lhv": 42.5e6, "efficiency": 1.0,
                       "gamma": 1.368, "gamma_slope": 0.0, "t_a": 329.9},
             "woschni": {"c1": 2.28, "c2": 3.24e-3, "wall_temperature": 450}},
     "governor": {"model": "flyweight", "weights": 2, "weight_mass": 0.1, "radius_mm": 30,
                  "arm_ratio": 1.0, "gear_ratio": 0.5, "sleeve_mass": 0.2,
                  "spring_rate": 23.8e3, "spring_preload": 213.0, "damping": 72.0,
                  "travel_mm": 8}},
)


@dataclass(frozen=True)
class Compiled:
    """One function compiled: ``name`` (module and qualified name), the CPU seconds and the
    wall seconds it took including the callees compiled inside it, the CPU seconds of its own
    (``own_cpu_s``: without them), and ``depth``, how many compiles it ran inside (0: called
    from Python)."""

    name: str
    cpu_s: float
    wall_s: float
    own_cpu_s: float
    depth: int


class CompileLog(event.Listener):
    """Records each function numba compiles in this process (:class:`Compiled`), in the order
    the compiles end; ``report`` is called with each."""

    def __init__(self, report: Callable[[Compiled], None] | None = None) -> None:
        self.compiled: list[Compiled] = []
        self._open: list[list] = []
        self._report = report

    def on_start(self, ev) -> None:
        fn = ev.data["dispatcher"].py_func
        self._open.append([f"{fn.__module__}.{fn.__qualname__}", time.process_time(),
                           time.perf_counter(), 0.0])

    def on_end(self, ev) -> None:
        name, cpu0, wall0, inner = self._open.pop()
        cpu = time.process_time() - cpu0
        record = Compiled(name, cpu, time.perf_counter() - wall0, cpu - inner, len(self._open))
        if self._open:
            self._open[-1][3] += cpu
        self.compiled.append(record)
        if self._report is not None:
            self._report(record)

    def __enter__(self) -> CompileLog:
        event.register("numba:compile", self)
        return self

    def __exit__(self, *exc) -> None:
        event.unregister("numba:compile", self)


def both_variants(scene: Scene) -> tuple[Scene, ...]:
    """``scene``, and where it runs the kernels' plain variant
    (:func:`transient.core.model.layout.extras_of`) the same with a lossless constant-η pair
    between its mechanism's first two links, which runs the full one: each mechanism's stepper
    is a compile of its own (``Model.terms``), so the built-in scenes, all crank-sliders, do not
    compile another mechanism's, and its scenes with friction pairs, governor states and the
    like run the full variant."""
    model, _, _ = build_model(scene)
    if extras_of(model) is not None:
        return (scene,)
    first, second = scene.mechanism.links[:2]
    lossless = Pair(between=(first, second), eta_forward=1.0, eta_backward=1.0, name="warmup")
    return scene, replace(scene, friction=Friction("power-flow", (lossless,)))


def warm_up(scenes: Iterable[Scene] = (),
            report: Callable[[Compiled], None] | None = None) -> list[Compiled]:
    """Compile (or load from the cache) the kernels that runs of the built-in scenes and of
    ``scenes`` need, running each for a fraction of a revolution in memory; returns the
    functions compiled (none where all were cached), each passed to ``report`` as it ends."""
    with CompileLog(report) as log:
        for scene in (*map(Scene.from_dict, WARMUP_SCENES), *(v for s in scenes
                                                               for v in both_variants(s))):
            try:
                simulate(replace(scene, run=replace(scene.run, revolutions=WARMUP_REVOLUTIONS,
                                                    t_end=float("inf"))))
            except SimulationError:
                pass  # (a scene that stalls at once has still compiled what it runs)
    return log.compiled
