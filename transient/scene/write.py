"""Writing a scene back: the resolved scene as TOML in SI (no unit suffixes, every default
filled in), which :func:`~transient.load_scene` reads back to an equal scene. A result file stores
it (``/scene/toml``) so that it can be rerun.
"""
from __future__ import annotations

import math
from dataclasses import fields, is_dataclass
from typing import Any

from ..tomlout import toml_value
from .records import GOVERNOR_KEYS, Gas, Load, Scene, Shaft


def to_toml(scene: Scene) -> str:
    """The resolved scene as TOML in SI units (no suffixes), round-tripping through load_scene."""
    lines = ["# resolved scene: SI units, every default filled in (written by transient)",
             "[scene]", f"name = {toml_value(scene.name)}", f"description = {toml_value(scene.description)}"]
    lines += [""] + scene.mechanism.toml_lines()
    lines += _section("inertia", scene.inertia)
    lines += _gas_section(scene.gas, scene.mechanism.strokes)
    lines += _load_section(scene.load)
    lines += _section("starter", scene.starter)
    lines += ["", "[governor]"] + [f"{k} = {toml_value(getattr(scene.governor, k))}"
                                   for k in GOVERNOR_KEYS[scene.governor.model]]
    lines += _section("initial", scene.initial)
    run: dict[str, Any] = {"mode": scene.run.mode}
    for k in ("t_end", "revolutions"):
        if math.isfinite(getattr(scene.run, k)):
            run[k] = getattr(scene.run, k)
    if scene.run.mode == "prescribed-speed":
        if scene.run.time:
            run.update(time=list(scene.run.time), speed_table=list(scene.run.speed_table),
                       interpolation=scene.run.interpolation)
        else:
            run["speed"] = scene.run.speed
    run.update(max_output_bytes=scene.run.max_output_bytes, max_steps=scene.run.max_steps)
    lines += ["", "[run]"] + [f"{k} = {toml_value(v)}" for k, v in run.items()]
    lines += _section("solver", scene.solver)
    lines += _section("output", scene.output)
    if scene.analysis.requested:  # (a scene that asks for nothing reads back the same without)
        lines += _section("analysis", scene.analysis)
    lines += ["", "[friction]", f"policy = {toml_value(scene.friction.policy)}"]
    for pair in scene.friction.pairs:
        lines += ["", "[[friction.pairs]]", f"name = {toml_value(pair.name)}",
                  f"between = {toml_value(list(pair.between))}"]
        if pair.model == "reaction":
            keys = (("mu", "ring_force", "ring_pressure", "viscous") if pair.between[0] == "piston"
                    else ("mu", "radius", "viscous"))
            lines += ['model = "reaction"']
            lines += [f"{k} = {toml_value(getattr(pair, k))}" for k in keys]
        elif pair.model == "table":  # (a map from a file is written inline: the scene stands alone)
            lines += ['model = "table"', f"speed = {toml_value(list(pair.speed))}",
                      f"torque = {toml_value(list(pair.torque))}",
                      f"eta_forward = {toml_value([list(r) for r in pair.eta_forward_map])}",
                      f"eta_backward = {toml_value([list(r) for r in pair.eta_backward_map])}"]
        else:
            lines += [f"eta_forward = {toml_value(pair.eta_forward)}",
                      f"eta_backward = {toml_value(pair.eta_backward)}"]
    if scene.shaft is not None:
        lines += _shaft_section(scene.shaft)
    return "\n".join(lines) + "\n"


def _shaft_section(shaft: Shaft) -> list[str]:
    """[shaft] and its arrays: sections by their stiffness (the geometry resolved), a damper's
    stiffness only for a tuned one."""
    lines = ["", "[shaft]", f"reference = {toml_value(shaft.reference)}",
             f"load_at = {toml_value(shaft.load_at)}"]
    if shaft.speed_range:
        lines.append(f"speed_range = {toml_value(list(shaft.speed_range))}")
    for station in shaft.stations:
        lines += ["", "[[shaft.stations]]"] + [
            f"{f.name} = {toml_value(list(v) if isinstance(v, tuple) else v)}"
            for f in fields(station) for v in [getattr(station, f.name)]]
    for section in shaft.sections:
        lines += ["", "[[shaft.sections]]", f"stiffness = {toml_value(section.stiffness)}"]
        lines += [f"{k} = {toml_value(getattr(section, k))}"
                  for k in ("damping", "loss_factor", "damping_ratio") if getattr(section, k)]
    for damper in shaft.dampers:
        lines += ["", "[[shaft.dampers]]"] + [
            f"{f.name} = {toml_value(getattr(damper, f.name))}" for f in fields(damper)
            if f.name != "stiffness" or damper.model == "tuned"]
    if shaft.coupling is not None:
        lines += _section("shaft.coupling", shaft.coupling)
    return lines


def _gas_section(gas: Gas, strokes: int) -> list[str]:
    keep = {"none": ("model", "p0"), "table": ("model", "p0", "phi", "p", "corners", "interpolation"),
            "trapezoid": ("model", "amplitude", "ramp", "duration"),
            "wiebe": ("model", "p0", "compression_ratio", "p_a", "p_intake", "p_exhaust"),
            "compressor": ("model", "p0", "p_suction", "p_discharge", "n", "n_reexpansion",
                           "clearance_ratio")}
    names = keep.get(gas.model, ("model", "p0", "compression_ratio", "p_a", "n1", "p_z", "rho",
                                 "n2", "p_intake", "p_exhaust"))
    if strokes != 4:  # (a 2-stroke has no gas-exchange strokes: the reader refuses the keys)
        names = tuple(n for n in names if n not in ("p_intake", "p_exhaust"))
    if gas.force:  # a force table: no pressure, no p0
        names = ("model", "phi", "force", "corners", "interpolation")
    if gas.motored_p:
        names = (*names, "motored_p")
    if gas.injection is not None:
        names = (*names, "injection")
    lines = ["", "[gas]"] + [f"{k} = {toml_value(getattr(gas, k))}" for k in names]
    # Model "wiebe"'s table: unset optional angles (None) are left out, they read back as None.
    if gas.wiebe is not None:
        lines += ["", "[gas.wiebe]"] + [f"{f.name} = {toml_value(getattr(gas.wiebe, f.name))}"
                                        for f in fields(gas.wiebe)
                                        if getattr(gas.wiebe, f.name) is not None]
    if gas.woschni is not None:
        lines += ["", "[gas.woschni]"] + [f"{f.name} = {toml_value(getattr(gas.woschni, f.name))}"
                                          for f in fields(gas.woschni)]
    for c in gas.cylinders:  # (a cut-out writes no fuel: the reader refuses both together)
        lines += ["", "[[gas.cylinders]]"] + [
            f"{f.name} = {toml_value(list(v) if isinstance(v, tuple) else v)}"
            for f in fields(c) for v in [getattr(c, f.name)]
            if not (f.name == "fuel" and c.cut_out)
            and (gas.model != "compressor" or f.name in ("cylinder", "pressure"))]
    return lines


def _load_section(load: Load) -> list[str]:
    """[load] with the schedule's keys only when there is one (and only its abscissa)."""
    names = ["torque", "linear", "fan", "generator_power", "generator_min_speed"]
    if load.inertia > 0.0:
        names += ["inertia", "inertia_time"]
    if load.schedule_scale:
        names += ["schedule_revolutions" if load.schedule_revolutions else "schedule_time",
                  "schedule_scale"]
    lines = ["", "[load]"] + [f"{k} = {toml_value(getattr(load, k))}" for k in names]
    if load.table is not None:  # (a table from a file is written inline: the scene stands alone)
        key = next(k for k in ("speed", "phi", "time") if getattr(load.table, k))
        lines += ["", "[load.table]", f"{key} = {toml_value(list(load.table.x))}",
                  f"torque = {toml_value(list(load.table.torque))}",
                  f"interpolation = {toml_value(load.table.interpolation)}"]
    return lines


def _section(name: str, obj: Any) -> list[str]:
    assert is_dataclass(obj)
    return ["", f"[{name}]"] + [f"{f.name} = {toml_value(getattr(obj, f.name))}" for f in fields(obj)]
