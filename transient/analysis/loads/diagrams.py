"""The loads of a run's last whole cycle as the load diagrams show them: the crankpin load in
its crank's frame (the polar diagram), the wear diagram's rays, the most loaded main journal
and the running torques of a crank-slider engine (Gots §2.6–§2.8), and the crankpin and link-pin
loads of an articulated engine.

The last whole cycle is counted from φ0 as :mod:`.irregularity` counts cycles, so the diagrams
describe the same cycle as δ and the summary; its samples are the stored ones (no resampling),
each weighted in the wear diagram by the crank angle it stands for.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..irregularity import last_cycle_window
from ..wear import angle_weights, wear_rays
from .articulated import ArticulatedLoads, articulated_loads_from_trajectory
from .crank_slider import (
    CylinderLoads,
    MainJournalLoads,
    loads_from_trajectory,
    main_journal_loads,
    running_torques,
)

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CycleWindow:
    """The stored samples of the last whole cycle.

    Attributes
    ----------
    columns : dict
        Every trajectory column on those samples (``t``, ``phi``, ``omega``, ``epsilon`` …).
    start : float
        Angle at which the cycle starts [rad]; it ends one cycle later.
    angle_deg : (n,) array
        Angle of each sample within the cycle [deg].
    samples : int
        n, the samples in the window.
    """

    columns: dict[str, Array]
    start: float
    angle_deg: Array
    samples: int


def cycle_window(scene, traj: Mapping[str, Array]) -> CycleWindow:
    """:func:`~.irregularity.last_cycle_window` of a run of ``scene`` (its cycle and φ0), the
    columns cut to it. Raises :class:`~.irregularity.NoWholeCycle` for a run shorter than a
    cycle."""
    mask, start = last_cycle_window(traj["t"], traj["phi"], scene.mechanism.cycle,
                                    scene.initial.phi)
    columns = {k: v[mask] for k, v in traj.items()}
    return CycleWindow(columns, start, np.degrees(columns["phi"] - start), int(mask.sum()))


def dead_centres(scene, window: CycleWindow, cylinder: int) -> dict[str, float]:
    """The top dead centres of ``cylinder`` (1-based) as angles in the ``window`` [deg], in
    [0, cycle): a 4-stroke's firing and gas-exchange TDC, a 2-stroke's TDC (a firing one); at
    the mechanism's true dead centre (an offset moves it off the crank's local 0)."""
    mech = scene.mechanism
    tdc = mech.firing_angles[cylinder - 1] + mech.dead_centre_angles()[0]

    def at(angle):
        a = (angle - window.start) % mech.cycle
        return 0.0 if a > mech.cycle * (1.0 - 1e-12) else math.degrees(a)  # (the cycle's end is 0)

    if mech.strokes == 4:
        return {"firing TDC": at(tdc), "gas-exchange TDC": at(tdc + math.pi * 2.0)}
    return {"TDC (firing)": at(tdc)}


@dataclass(frozen=True)
class CrankSliderDiagrams:
    """What the load diagrams of a crank-slider engine draw, over the last whole cycle.

    Frame of the crankpin's pictures: its crank pointing up (+y, outward), +x the direction of
    rotation at the crankpin, so that the load on the crankpin is (R_T, −R_K). Main journals in
    the frame of crank 1 (Gots (58)), likewise (R_x, −R_y).

    Attributes
    ----------
    window : CycleWindow
    loads : CylinderLoads
        Every cylinder's forces on the window's samples.
    engine_torque : (n,) array
        Σ T r [N m].
    cylinder : int
        The cylinder (1-based) whose crankpin the polar and wear diagrams show.
    crankpin_x, crankpin_y : (n,) arrays
        Its load in its crank's frame [N].
    crankpin_wear : (rays [deg], sums [N])
        Its wear diagram (:func:`~.wear.wear_rays`, 36 rays).
    wear_weight : float
        Σ of the samples' angle weights (:func:`~.wear.angle_weights`): a ray's sum over it is
        the cycle-mean load within the wear arc of the ray [N] (loads outside count 0), which
        does not depend on how densely the cycle is sampled.
    journal_torques : (n_throws + 1, n) array
        Running torques of the main journals [N m].
    crankpin_torques : (n_throws, n) array
        Running torques of the crankpins, in each throw's middle [N m].
    main_journals : MainJournalLoads
        Loads of every main journal.
    most_loaded : int
        Index (0-based) of the main journal with the largest peak load.
    journal_x, journal_y : (n,) arrays
        That journal's load in the frame of crank 1 [N].
    journal_wear : (rays [deg], sums [N])
        Its wear diagram.
    """

    window: CycleWindow
    loads: CylinderLoads
    engine_torque: Array
    cylinder: int
    crankpin_x: Array
    crankpin_y: Array
    crankpin_wear: tuple[Array, Array]
    wear_weight: float
    journal_torques: Array
    crankpin_torques: Array
    main_journals: MainJournalLoads
    most_loaded: int
    journal_x: Array
    journal_y: Array
    journal_wear: tuple[Array, Array]


def crank_slider_diagrams(scene, traj: Mapping[str, Array], cylinder: int = 1
                          ) -> CrankSliderDiagrams:
    """The load diagrams of a crank-slider run over its last whole cycle.

    Parameters
    ----------
    scene : Scene
        The run's scene (a crank-slider mechanism).
    traj : mapping
        Its trajectory columns (``t``, ``phi``, ``omega``, ``epsilon`` and the gas columns).
    cylinder : int
        The cylinder (1-based, from the nose) whose crankpin is drawn.

    Raises :class:`~.irregularity.NoWholeCycle` for a run shorter than a cycle, ValueError for
    a cylinder that does not exist.
    """
    mech = scene.mechanism
    n_cyl = mech.n_cylinders
    if not 1 <= cylinder <= n_cyl:
        raise ValueError(f"cylinder must be 1 … {n_cyl}, got {cylinder}")
    window = cycle_window(scene, traj)
    win = window.columns
    loads = loads_from_trajectory(scene, win)
    k = cylinder - 1
    x, y = loads.R_T[k], -loads.R_K[k]
    weight = angle_weights(win["phi"])
    journals, crankpins = running_torques(mech, loads)
    mj = main_journal_loads(mech, loads, win["omega"], win["epsilon"])
    best = int(np.argmax(mj.magnitude.max(axis=1)))
    jx, jy = mj.x[best], -mj.y[best]
    return CrankSliderDiagrams(
        window=window, loads=loads, engine_torque=loads.engine_torque, cylinder=cylinder,
        crankpin_x=x, crankpin_y=y, crankpin_wear=wear_rays(np.arctan2(y, x), loads.R[k], weight),
        wear_weight=float(weight.sum()),
        journal_torques=journals, crankpin_torques=crankpins, main_journals=mj,
        most_loaded=best, journal_x=jx, journal_y=jy,
        journal_wear=wear_rays(np.arctan2(jy, jx), mj.magnitude[best], weight))


@dataclass(frozen=True)
class ArticulatedDiagrams:
    """What the load diagrams of an articulated (radial) engine draw, over the last whole cycle.

    Attributes
    ----------
    window : CycleWindow
    loads : ArticulatedLoads
        Every cylinder's, link pin's and crankpin's forces on the window's samples.
    link_load : (rows·z′, n) array
        |F| at each link pin [N].
    """

    window: CycleWindow
    loads: ArticulatedLoads
    link_load: Array


def articulated_diagrams(scene, traj: Mapping[str, Array]) -> ArticulatedDiagrams:
    """The load diagrams of an articulated-engine run over its last whole cycle (main journals
    and running torques do not apply). Raises :class:`~.irregularity.NoWholeCycle` for a run
    shorter than a cycle."""
    window = cycle_window(scene, traj)
    loads = articulated_loads_from_trajectory(scene, window.columns)
    return ArticulatedDiagrams(window, loads, np.hypot(loads.link_x, loads.link_y))
