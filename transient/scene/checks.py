"""Checks across the tables of a scene, run by :func:`~.read.scene_from_dict` once every table
has been read and before any integration: what no single key can tell (J(φ) > 0 over the cycle,
options that need a compiled method or a dynamic run, a gas model the mechanism supports, the
signals an analysis asks for).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError, show_value
from .reader import Section
from .records import COMPILED_METHODS, RUNAWAY_SPEED, W_METHODS, Scene, Wiebe


def check_consistency(scene: Scene) -> tuple[float, float]:
    """Checks across sections, done before any integration. Returns what the kinematics give
    over the cycle for :func:`check_magnitudes`: the least reduced inertia J_min [kg m²] and the
    lever of the pistons' forces Σ_k max|u_k| [m/rad] (u_k = dx_k/dφ)."""
    # (18) divides by J(φ): it must stay positive over the whole cycle, dead centres included.
    phi = np.linspace(0.0, scene.mechanism.cycle, 721)
    with np.errstate(over="ignore", invalid="ignore"):
        kinematics = scene.mechanism.kinematics_table(phi)
        J = kinematics["J"] + scene.inertia.total
        if scene.shaft is not None:  # (its rigid equivalent's: the line turning as one body)
            J = J + scene.shaft.constant_inertia
        lever = sum(float(np.max(np.abs(kinematics[f"u_{k + 1}"])))
                    for k in range(scene.mechanism.n_cylinders))
    if not np.all(np.isfinite(J)):
        raise SceneError("mechanism", "the reduced inertia J(φ) overflows (is not finite); "
                                      "check the masses and lengths and their units")
    try:
        area = scene.mechanism.piston_area
    except OverflowError:
        area = math.inf
    if not math.isfinite(area):
        raise SceneError("mechanism.bore", "the piston area overflows; check the bore and its "
                                           "unit (mm: 'bore_mm')")
    if J.min() <= 0.0:
        at = math.degrees(phi[int(np.argmin(J))])
        raise SceneError("inertia", f"the reduced inertia J(φ) falls to {J.min():.3g} kg m² at "
                                    f"φ = {at:g}°; give a shaft, flywheel or load inertia > 0")
    sv = scene.solver
    compiled = sv.method in COMPILED_METHODS
    if scene.friction.pairs and scene.friction.policy == "paper" and not compiled:
        raise SceneError("solver.method", "the reference path (scipy-*) follows the power-flow "
                                          "policy only; use method = \"dop853\" or \"dopri5\" "
                                          "with policy \"paper\"")
    if (any(p.model == "reaction" for p in scene.friction.pairs)
            and sv.kinematics == "tabulated" and scene.mechanism.name != "crank-slider"):
        raise SceneError("solver.kinematics", f"friction on the reactions of the "
                                              f"{scene.mechanism.name!r} mechanism takes its "
                                              f"exact kinematics; use kinematics = \"exact\"")
    if any(p.model == "table" for p in scene.friction.pairs) and not compiled:
        raise SceneError("solver.method", f"efficiency maps run on the compiled methods "
                                          f"({', '.join(COMPILED_METHODS)}), not {sv.method!r}")
    if sv.fixed_step > 0.0 and not compiled:
        raise SceneError("solver.fixed_step", f"fixed steps need a compiled method "
                                              f"({', '.join(COMPILED_METHODS)}), not {sv.method!r}")
    if sv.kinematics == "tabulated" and not compiled:
        raise SceneError("solver.kinematics", f"tables are for the compiled methods "
                                              f"({', '.join(COMPILED_METHODS)}); the reference path "
                                              f"{sv.method!r} is exact by design")
    if sv.method in W_METHODS and scene.shaft is None:
        raise SceneError("solver.method", f"{sv.method!r} takes the Jacobian of an elastic "
                                          f"[shaft] line, which this scene has not; use "
                                          f"\"dop853\" for a rigid shaft")
    if sv.fixed_step > 0.0 and sv.domain == "time":
        raise SceneError("solver.fixed_step", "fixed steps are crank-angle steps; use "
                                              "domain = \"auto\" or fixed_step = 0")
    if scene.run.mode == "prescribed-speed" and scene.load.inertia > 0.0:
        raise SceneError("load.inertia", "a prescribed-speed run has no momentum to conserve when "
                                         "an inertia is switched in; leave it out (0)")
    if scene.gas.woschni is not None:
        check_woschni(scene)
    if scene.run.mode == "prescribed-speed" and scene.governor.model in ("pi", "flyweight"):
        raise SceneError("governor.model", f"a prescribed-speed run integrates no governor state; "
                                           f"use model = \"none\" or \"droop\", not "
                                           f"{scene.governor.model!r}")
    if scene.gas.model == "compressor" and scene.governor.model != "none":
        raise SceneError("governor.model", f"a compressor has no fuel for a governor to set; use "
                                           f"model = \"none\", not {scene.governor.model!r} (a "
                                           f"speed is held by the motor or a prescribed speed)")
    check_part_load(scene)
    if scene.run.mode == "dynamic" and scene.initial.omega == 0.0 and scene.starter.torque == 0.0:
        if scene.gas.model == "none":
            raise SceneError("initial.omega", "a machine at rest with no starter and no gas force "
                                              "never moves; give omega or a starter")
    return float(J.min()), lever


def check_magnitudes(scene: Scene, least_inertia: float, lever: float, gas_table) -> None:
    """Refuse the magnitudes no machine has, which pass every other check and fail at the first
    step: a speed beyond :data:`~.records.RUNAWAY_SPEED` (the run would have run away at its
    start), and in a dynamic run a torque that would take the machine from rest past that speed
    within one revolution — the work M·2π would exceed ½ J_min ω_r², so M > J_min ω_r²/(4π),
    J_min the least reduced inertia. The torques: the load's terms at the initial speed (at the
    schedule's largest scale), the starter's, and the gas force's largest (p − p0)·F_p, or
    force, on the pistons' lever Σ_k max|u_k| (``gas_table``: the full-load table, or None)."""
    speeds = {"initial.omega": abs(scene.initial.omega)}
    if scene.run.mode == "prescribed-speed":
        speeds["run.speed_table" if scene.run.time else "run.speed"] = max(
            map(abs, scene.run.speed_table or (scene.run.speed,)))
    for key, w in speeds.items():
        if w > RUNAWAY_SPEED:
            raise SceneError(key, f"{w:.3g} rad/s is beyond {RUNAWAY_SPEED:g} rad/s "
                                  f"({RUNAWAY_SPEED * 30 / math.pi:.3g} rpm), faster than any "
                                  f"piston machine turns (a run reaching it ends as a runaway); "
                                  f"give a speed up to that")
    if scene.run.mode != "dynamic":
        return
    most = least_inertia * RUNAWAY_SPEED ** 2 / (4.0 * math.pi)
    for key, (torque, what) in _torques(scene, lever, gas_table).items():
        if torque > most:
            raise SceneError(key, f"gives a torque of {torque:.3g} N m{what}, which would take "
                                  f"the machine (least reduced inertia {least_inertia:.3g} kg m²) "
                                  f"from rest past {RUNAWAY_SPEED:g} rad/s, faster than any "
                                  f"piston machine turns, within one revolution; allowed up to "
                                  f"J_min·ω²/(4π) = {most:.3g} N m")


def _torques(scene: Scene, lever: float, gas_table) -> dict[str, tuple[float, str]]:
    """The largest torque each source in the scene applies [N m], and how it arises, by the key
    that sets it."""
    load, w0 = scene.load, abs(scene.initial.omega)
    scale = max(map(abs, load.schedule_scale), default=1.0)
    at_start = " at the initial speed"
    out = {"starter.torque": (scene.starter.torque, ""),
           "load.torque": (scale * abs(load.torque), ""),
           "load.linear": (scale * load.linear * w0, at_start),
           "load.fan": (scale * load.fan * w0 * w0, at_start)}
    if load.generator_power > 0.0:
        out["load.generator_power"] = (scale * load.generator_power / max(
            w0, load.generator_min_speed), at_start)
    if load.table is not None:
        out["load.table.torque"] = (scale * max(map(abs, load.table.torque)), "")
    if gas_table is not None:
        from .queries import gas_is_force

        is_force = gas_is_force(scene)
        offset = 0.0 if is_force else scene.gas.p0
        p = np.asarray(gas_table.coef)[:, 0]
        force = float(np.max(np.abs(p - offset)))
        what = f" (a force up to {force:.3g} N per piston"
        if not is_force:
            what = (f" (the pressure difference p − p0 up to {force:.3g} Pa on pistons of "
                    f"{scene.mechanism.piston_area:.3g} m²")
            force *= scene.mechanism.piston_area
        # (the key of the largest pressure: the crankcase's, a gas exchange's, the model's peak)
        exchange = max((scene.gas.p_intake, "gas.p_intake"), (scene.gas.p_exhaust, "gas.p_exhaust"))
        key = {"trapezoid": "gas.amplitude", "table": "gas.force" if is_force else "gas.p",
               "wiebe": "gas.wiebe.fuel_mass", "mixed-cycle": "gas.p_z",
               "compressor": "gas.p_discharge"}[scene.gas.model]
        if scene.gas.model in ("mixed-cycle", "wiebe") and exchange[0] >= float(np.max(p)):
            key = exchange[1]
        out["gas.p0" if offset > float(np.max(p)) else key] = (
            force * lever, f"{what}, on their lever Σ max|dx/dφ| = {lever:.3g} m)")
    return out


def check_part_load(scene: Scene) -> None:
    """What would burn less than full-load fuel (a ``[[gas.cylinders]]`` entry that changes the
    combustion, a governor) needs a gas model that can: a motored curve to scale the combustion
    above (:func:`transient.scene.queries.part_load_refusal`)."""
    from .queries import part_load_refusal

    why = part_load_refusal(scene)
    if why is None:
        return
    for i, c in enumerate(scene.gas.cylinders):
        if c.combustion_keys:
            raise SceneError(f"gas.cylinders[{i}].{c.combustion_keys[0]}", why)
    if scene.governor.model != "none":
        raise SceneError("governor.model", f"the governor's fuel command: {why}")


def check_woschni(scene: Scene) -> None:
    """Wall heat transfer makes each cylinder's pressure a state of the ODE (built for the
    crank-slider's exact cylinder volume, integrated by the compiled and the reference paths)."""
    if not scene.mechanism.wall_heat_transfer:
        raise SceneError("gas.woschni", f"wall heat transfer is built for crank-slider engines "
                                        f"(their cylinder volume enters the ODE), not for the "
                                        f"{scene.mechanism.name!r} mechanism; leave "
                                        f"[gas.woschni] out")
    if scene.run.mode == "prescribed-speed":
        raise SceneError("gas.woschni", "with wall heat transfer the cylinder pressures are "
                                        "states of the ODE, which a prescribed-speed run does not "
                                        "integrate; run it dynamic (a large flywheel holds the "
                                        "speed) or leave [gas.woschni] out")
    m = combustion(scene).m
    if m < 0.0:
        raise SceneError("gas.wiebe.m", f"m = {m:g}: with wall heat transfer the "
                                        f"heat-release rate enters the ODE, and for m < 0 it is "
                                        f"infinite at the combustion start; give m ≥ 0")
    if scene.solver.kinematics == "tabulated":
        raise SceneError("solver.kinematics", "the cylinder volumes of wall heat transfer use the "
                                              "exact kinematics; use kinematics = \"exact\"")


def combustion(scene: Scene) -> Wiebe:
    """The Wiebe combustion that wall heat transfer integrates (the reader reads
    ``[gas.woschni]`` only with it)."""
    if scene.gas.wiebe is None:
        raise SceneError("gas.woschni", 'wall heat transfer is built for model = "wiebe"; leave '
                                        '[gas.woschni] out')
    return scene.gas.wiebe


def check_gas_table(scene: Scene, section: Section):
    """Build (and so validate) the pressure table; report under the key the user wrote.
    Returns the table (None without gas forces)."""
    from .queries import gas_table

    try:
        table = gas_table(scene)
    except SceneError as exc:
        if "file" in section.written and exc.key in ("gas.phi_deg", "gas.p", "gas.phi",
                                                     "gas.force", "gas.motored_p"):
            exc.key = "gas.file"
        raise section.rename(exc) from None
    if scene.gas.woschni is not None:
        check_offsets_in_closed_part(scene)
    return table


def check_offsets_in_closed_part(scene: Scene) -> None:
    """With wall heat transfer a cylinder's combustion is integrated inside its closed part:
    shifted by its combustion offset, it must still lie between intake closing and exhaust
    opening."""
    from .queries import wiebe_levels

    mech, gas, duration = scene.mechanism, scene.gas, combustion(scene).duration
    # (mypy sees no __hash__ on a Protocol-typed value; each mechanism is a frozen dataclass)
    cycle = wiebe_levels(mech, gas)[-1]  # type: ignore[arg-type]
    closed = (cycle.closed.end - cycle.closed.start) % mech.cycle or mech.cycle
    start = (cycle.combustion_start - cycle.closed.start) % mech.cycle
    for i, c in enumerate(gas.cylinders):
        a, b = start + c.combustion_offset, start + duration + c.combustion_offset
        if a < 0.0 or b > closed:
            lo, hi = -start, closed - start - duration
            raise SceneError(f"gas.cylinders[{i}].combustion_offset",
                             f"{math.degrees(c.combustion_offset):g}° moves the combustion out "
                             f"of the closed part (intake closing to exhaust opening), which "
                             f"[gas.woschni] integrates; allowed {math.degrees(lo):g}° to "
                             f"{math.degrees(hi):g}°")


def check_analysis(scene: Scene) -> None:
    """The [analysis] signals exist in this scene's trajectory and the orders fit the grid."""
    from .outputs import output_columns

    a, mech = scene.analysis, scene.mechanism
    columns = list(output_columns(scene))
    # every mechanism's pistons have an acceleration (transient.analysis.pistons)
    derived = [f"W_{k + 1}" for k in range(mech.n_cylinders)]
    for name in a.orders:
        if name not in columns + derived:
            raise SceneError("analysis.orders", f"unknown signal {show_value(name)}; allowed: "
                                                f"{', '.join(columns + derived)}")
    from .queries import gas_is_force

    if a.thermodynamics and (scene.gas.model == "none" or gas_is_force(scene)):
        raise SceneError("analysis.thermodynamics",
                         f"gas model {show_value(scene.gas.model)} applies no cylinder pressure "
                         f"(∮p dV needs one); allowed with it: false")
    if len(set(a.orders)) != len(a.orders):
        raise SceneError("analysis.orders", "a signal is named twice; name each once")
    nyquist = (a.samples_per_cycle // 2) * 2.0 * math.pi / mech.cycle
    if a.orders and a.max_order > nyquist:
        raise SceneError("analysis.max_order", f"must be ≤ {nyquist:g} (the Nyquist order of "
                                               f"samples_per_cycle = {a.samples_per_cycle} over "
                                               f"a {math.degrees(mech.cycle):g}° cycle), got "
                                               f"{a.max_order:g}")
