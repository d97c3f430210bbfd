"""What a scene's records imply, asked by every layer above the scene (the model's assembly, the
trajectory's columns, the analyses, the plots) and by the scene's own checks: whether its gas
acts as a force or a pressure, each cylinder's phase and its cycle's beginning, the clearance
volume, the gas tables the cycle model gives (full-load and motored; the Wiebe cycles cached),
whether and why it can burn less than full-load fuel, the cycle's figures, the governor's kind
and whether the pairs' friction is on their reactions.

They read the records and the force models only; nothing here assembles the compiled model
(:mod:`transient.assemble` builds it from these answers).
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from ..core.model import governor as gv
from ..errors import SceneError
from ..forces.compressor import CompressorCycle, compressor_cycle
from ..forces.gas import IndicatedCycle, PressureTable, mixed_cycle, table_from_points
from ..forces.trapezoid import trapezoid_table


def gas_is_force(scene) -> bool:
    """True when the gas table holds a force per piston [N] rather than a pressure [Pa]."""
    return scene.gas.model == "trapezoid" or bool(scene.gas.force)


def gas_phases(scene) -> NDArray[np.float64]:
    """Shaft angle at which each cylinder's pressure table is at local angle 0.

    Tables are written with 0 at the gas-exchange TDC of a 4-stroke (firing TDC at 360°, the Gots
    tables' convention) and at the firing TDC of a 2-stroke.
    """
    mech = scene.mechanism
    shift = 2.0 * math.pi if mech.strokes == 4 else 0.0
    return np.mod(np.asarray(mech.firing_angles) - shift, mech.cycle)


def cycle_begin(mech) -> float:
    """Local angle where a cylinder's cycle begins, for its fuel factor and misfires
    (:mod:`transient.core.model.variation`): 0, the gas-exchange TDC of a 4-stroke, whose cycle then
    holds one intake, compression, combustion and exhaust; π, the BDC of a 2-stroke, whose
    local 0 is its firing TDC, so that no combustion straddles two cycles."""
    return 0.0 if mech.strokes == 4 else math.pi


def clearance_volume(scene) -> float:
    """V_c [m³]: c·V_h of a compressor's clearance ratio c, V_h/(ε − 1) of a cycle's compression
    ratio ε (mixed cycle, Wiebe); 0 for a model that gives neither (a table, a force)."""
    gas, swept = scene.gas, scene.mechanism.swept_volume()
    if gas.model == "compressor":
        return gas.clearance_ratio * swept
    return swept / (gas.compression_ratio - 1.0) if gas.compression_ratio > 1.0 else 0.0


def gas_table(scene) -> PressureTable | None:
    """The cylinder pressure table of the scene (absolute pressure [Pa] over the local angle) at
    full load (governor fuel 1); see :func:`gas_tables` for the motored one."""
    return gas_tables(scene)[0]


def gas_tables(scene) -> tuple[PressureTable | None, PressureTable | None]:
    """``(full, motored)``: the full-load table and the motored one, between which the fuel f
    interpolates, p = p_mot + f·(p_full − p_mot): the fuel scales the combustion, never the
    compression (:class:`transient.scene.records.Gas`).

    ``motored`` is the cycle without fuel on the same corners as the full-load one: for
    ``"mixed-cycle"`` the compression polytrope both ways
    (:func:`~transient.forces.gas.mixed_cycle`), for ``"wiebe"`` the cycle without fuel (both
    from one :func:`~transient.forces.wiebe.wiebe_tables`; with ``fuel_mass = 0`` both are that
    cycle), for ``"table"`` the user's ``motored_p`` at the table's angles. It is None for a
    force pulse (``"trapezoid"``, whose motored force is 0), and for a table without
    ``motored_p`` and a compressor, which cannot burn less than full-load fuel
    (:func:`part_load_refusal`).
    """
    gas = scene.gas
    mech = scene.mechanism
    if gas.model == "none":
        return None, None
    if gas.model == "trapezoid":  # a force per piston [N] (Antonyuk §4)
        return trapezoid_table(gas.amplitude, gas.ramp, mech.cycle, gas.duration), None
    if gas.model == "table":  # pressures [Pa] (and the motored ones), or forces per piston [N]
        return (_points_table(scene, gas.force or gas.p, "gas.p"),
                _points_table(scene, gas.motored_p, "gas.motored_p") if gas.motored_p else None)
    if gas.model == "wiebe":
        tables = wiebe_levels(mech, gas)
        return tables[-1], tables[0]
    if gas.model == "compressor":  # no fuel: the one cycle at every command
        return compressor_cycle(mech.volume_function(clearance_volume(scene)),
                                p_suction=gas.p_suction, p_discharge=gas.p_discharge, n=gas.n,
                                n_reexpansion=gas.n_reexpansion,
                                clearance_ratio=gas.clearance_ratio, strokes=mech.strokes,
                                dead_centres=mech.dead_centre_angles()), None
    cycle = mixed_cycle(mech.volume_function(clearance_volume(scene)),
                        compression_ratio=gas.compression_ratio, p_a=gas.p_a, n1=gas.n1,
                        p_z=gas.p_z, rho=gas.rho, n2=gas.n2, p_intake=gas.p_intake,
                        p_exhaust=gas.p_exhaust, strokes=mech.strokes,
                        dead_centres=mech.dead_centre_angles())
    return cycle, cycle.motored


def _points_table(scene, values, key: str) -> PressureTable:
    """The table through ``values`` (pressures or forces) at the scene's table angles, its errors
    on the values reported under ``key``."""
    gas = scene.gas
    try:
        return table_from_points(np.asarray(gas.phi), np.asarray(values), scene.mechanism.cycle,
                                 corners=gas.corners, interpolation=gas.interpolation)
    except SceneError as exc:
        if exc.key == "gas.p":
            exc.key = key
        raise


@lru_cache(maxsize=8)
def wiebe_levels(mech, gas) -> tuple:
    """The Wiebe cycles of ``gas`` (``model = "wiebe"``) on the mechanism's cylinder volume:
    ``(motored, full load)``, or ``(motored,)`` with no fuel
    (:class:`~transient.forces.wiebe.WiebeCycle`).

    Cached in the process (the mechanism and the gas model are frozen: ``load_scene`` builds them
    to validate the scene, and every run of a scene with the same engine and cycle uses them
    again) and on disk between processes (:mod:`transient.forces.wiebe_cache`; a warm start
    then neither integrates them nor imports scipy's integrators).
    """
    from ..forces.wiebe_cache import cached_cycles  # (lazily: only Wiebe scenes need it)

    w = gas.wiebe
    clearance = mech.swept_volume() / (gas.compression_ratio - 1.0)
    levels = [0.0, w.fuel_mass] if w.fuel_mass > 0.0 else [0.0]
    cycle = dict(
        p_a=gas.p_a, start=w.start, duration=w.duration, a=w.a, m=w.m, lhv=w.lhv,
        efficiency=w.efficiency, gamma=w.gamma, gamma_slope=w.gamma_slope,
        gamma_t_ref=w.gamma_t_ref, t_a=w.t_a,
        p_intake=gas.p_intake if mech.strokes == 4 else None,
        p_exhaust=gas.p_exhaust if mech.strokes == 4 else None, strokes=mech.strokes,
        intake_closing=w.intake_closing, exhaust_opening=w.exhaust_opening, step=w.step,
        tolerance=w.tolerance)

    def compute() -> tuple:
        from ..forces.wiebe import wiebe_tables

        return wiebe_tables(mech.volume_function(clearance), levels, **cycle)

    # Everything the cycles depend on besides the code, as exact text (floats' reprs round-trip).
    return cached_cycles(f"{mech!r}\nclearance={clearance!r}\nlevels={levels!r}\n{cycle!r}",
                         compute)


def burns_part_load(scene) -> bool:
    """Whether a cylinder of the scene can burn less than full-load fuel in a run: under a
    governor's command, or by a ``[[gas.cylinders]]`` entry that changes its combustion
    (:attr:`transient.scene.records.Cylinder.combustion_keys`). Only then does the model pair
    the motored curve with the full-load one: at full fuel throughout the pressure is the
    full-load table's, and the kernels keep their one-table path."""
    return (scene.governor.model != "none"
            or any(c.combustion_keys for c in scene.gas.cylinders))


def part_load_refusal(scene) -> str | None:
    """Why the scene's gas model cannot burn less than full-load fuel, or None. A fuel below 1
    scales the combustion only, so a model needs its motored curve for it: a table of pressures
    or forces holds no account of which part of it is compression (unless the motored
    pressures come with it), and a compressor burns nothing."""
    gas = scene.gas
    if gas.model == "compressor":
        return "a compressor burns no fuel: its cycle is the same at every fuel"
    if gas.model != "table" or gas.motored_p:
        return None
    return ("a fuel below 1 scales the combustion only, p_mot + f·(p_full − p_mot), and a "
            f"{'force' if gas.force else 'pressure'} table holds no account of which part of it "
            "is compression; give the pressures with the motored ones at the table's angles, "
            "gas.motored_p (or a motored_p column of its file)")


def cycle_figures(scene) -> dict[str, tuple[float, str]]:
    """What the scene's gas cycle implies, without a run, name → (value, unit) in SI: for a
    cycle with a loop work (mixed, Wiebe, compressor) ∮p dV per cylinder and cycle and the mean
    moment all cylinders put on the shaft (signed as ``M_gas``); for a compressor also the work
    done on the gas, the volumetric efficiency, the volume drawn in and the local angles where
    the valves open; at a constant prescribed speed the indicated power, and the mean drive
    moment that speed needs without friction. Empty for the other models."""

    table = gas_table(scene)
    if not isinstance(table, IndicatedCycle):
        return {}
    n = scene.mechanism.n_cylinders
    out = {"cycle_work": (table.work, "J"), "mean_gas_torque": (n * table.mean_torque, "N m")}
    if isinstance(table, CompressorCycle):  # (the table of gas.model "compressor")
        out.update(indicated_work=(table.indicated_work, "J"),
                   volumetric_efficiency=(table.volumetric_efficiency, "1"),
                   suction_volume=(table.suction_volume, "m^3"),
                   suction_opens=(table.angle_suction, "rad"),
                   discharge_opens=(table.angle_discharge, "rad"))
    if scene.run.mode == "prescribed-speed" and not scene.run.time:
        out["indicated_power"] = (n * table.mean_torque * scene.run.speed, "W")
        out["mean_drive_torque_ideal"] = (-n * table.mean_torque, "N m")
    return out


def governor_kind(governor) -> int:
    """The dynamic governor (``transient.core.model.governor``) of a scene's governor: none for the
    static droop; PID only with a derivative gain (else the filter state would be integrated for
    nothing)."""
    if governor.model == "pi":
        return gv.PID if governor.gain_d > 0.0 else gv.PI
    return gv.FLYWEIGHT if governor.model == "flyweight" else gv.NONE


def reaction_friction(scene) -> bool:
    """Whether the scene's pairs have friction on their reactions (then all do, but for a
    constant-η or mapped pair at the shaft's coupling)."""
    return any(p.model == "reaction" for p in scene.friction.pairs)
