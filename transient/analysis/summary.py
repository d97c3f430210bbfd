"""The end-of-run summary: what a run did, as (value, unit) pairs stored under ``/analysis``."""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .efficiency import mechanical_efficiency
from .irregularity import cycle_means, fluctuation, last_cycle_ranges, steady_state_time
from .requested import requested_analyses
from .transient_response import load_step_times, run_response


def summarize(scene, traj: dict[str, NDArray[np.float64]], events=None
              ) -> dict[str, tuple[float, str]]:
    """The end-of-run summary, as (value, unit) pairs stored under ``/analysis``: speed, its
    fluctuation, steady state, the mechanical efficiency over the steady cycles, and the
    ISO 8528-5 measures of each load step and of a spin-up (``transient_response``), and what
    the scene's ``[analysis]`` table asks for (:mod:`.requested`). With load steps, the steady
    state and the efficiency are looked for after the last one."""
    # what the scene's [analysis] table asks for, over the whole stored run (before the cut below)
    requested = requested_analyses(scene, traj, events) if scene.analysis.requested else {}
    response = run_response(scene, traj, events) if scene.run.mode == "dynamic" else {}
    steps = load_step_times(scene, events) if scene.run.mode == "dynamic" else []
    if steps and steps[-1] < traj["t"][-1]:
        after = traj["t"] >= steps[-1]
        traj = {k: v[after] for k, v in traj.items()}
        events = {k: v[v[:, 0] >= steps[-1]] for k, v in (events or {}).items()}
    t, phi, omega = traj["t"], traj["phi"], traj["omega"]
    cycle = scene.mechanism.cycle
    phi0 = scene.initial.phi
    means, ends = cycle_means(t, phi, cycle, phi0)
    out = {
        "final_omega": (float(omega[-1]), "rad/s"),
        "final_t": (float(t[-1]), "s"),
        "revolutions": (float((phi[-1] - phi0) / (2 * math.pi)), "1"),
        "mean_omega_last_cycle": (float(means[-1]) if means.size else math.nan, "rad/s"),
        "delta_last_cycle": (fluctuation(t, phi, omega, cycle, phi0), "1"),
    }
    if scene.run.mode == "dynamic":
        out["steady_state_t"] = (steady_state_time(means, ends), "s")
        out.update(response)
    out.update(last_cycle_ranges(traj, cycle))
    if "M_drive" in traj and means.size:
        last = (t >= ends[-1] - cycle / means[-1]) & (t <= ends[-1])
        out["mean_drive_torque_last_cycle"] = (float(np.trapezoid(traj["M_drive"][last],
                                                                  phi[last]) / cycle), "N m")
    if scene.gas.model != "none":
        out.update(mechanical_efficiency(scene, traj, events))
    out.update(requested)
    # the mechanism's own figures (articulated rods: slave harmonics against Semenov's series)
    out.update(scene.mechanism.analysis_summary())
    return out
