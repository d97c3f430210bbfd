"""The end-of-run summary: what a run did, as (value, unit) pairs stored under ``/analysis``."""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .efficiency import EFFICIENCY_VALUES, mechanical_efficiency, steady_window
from .irregularity import (
    cycle_boundaries,
    cycle_means,
    fluctuation,
    last_cycle_ranges,
    steady_state_time,
)
from .orders import resample_angle
from .requested import requested_analyses
from .torsion_run import damper_power_summary
from .transient_response import load_step_times, run_response


def summarize(scene, traj: dict[str, NDArray[np.float64]], events=None, periodic: bool = False
              ) -> dict[str, tuple[float, str]]:
    """The end-of-run summary, as (value, unit) pairs stored under ``/analysis``: speed, its
    fluctuation, steady state, the mechanical efficiency over the steady cycles, an elastic
    line's damper power over the last cycle, and the
    ISO 8528-5 measures of each load step and of a spin-up (``transient_response``), and what
    the scene's ``[analysis]`` table asks for (:mod:`.requested`). With load steps, the steady
    state and the efficiency are looked for after the last one. A ``periodic`` run (steady
    cycles from :func:`transient.steady`) is steady throughout."""
    # what the scene's [analysis] table asks for, over the whole stored run (before the cut below)
    requested = requested_analyses(scene, traj, events) if scene.analysis.requested else {}
    stuck = stuck_phases(events or {}, float(traj["t"][-1]))
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
        # the drive's work over the last cycle (dW_drive/dφ = M_drive), over the cycle angle
        marks = cycle_boundaries(t, phi, cycle, phi0)[1][-2:]
        work = resample_angle(phi, traj["W_drive"], marks, traj["M_drive"])
        out["mean_drive_torque_last_cycle"] = (float(work[1] - work[0]) / cycle, "N m")
    if scene.gas.model != "none":
        out.update(mechanical_efficiency(scene, traj, events,
                                         steady_window(scene, traj, periodic=periodic)))
    if scene.shaft is not None:  # the line's damping: what a damper is sized by
        out.update(damper_power_summary(scene, traj))
    out.update(stuck)
    out.update(requested)
    # the mechanism's own figures (articulated rods: slave harmonics against Semenov's series)
    out.update(scene.mechanism.analysis_summary())
    return out


def stuck_phases(events: dict, t_last: float) -> dict[str, tuple[float, str]]:
    """How often and how long the machine was stuck at rest, held by its pairs' friction
    (``transient.core.model.stuck``), from the events ``stuck`` and ``released`` (each stuck phase
    ends with the next release, or with the run at ``t_last``): ``stuck_phases`` [1],
    ``stuck_time`` [s] in all, and the first phase's start ``stuck_first_t`` [s] and angle
    ``stuck_first_phi`` [rad]; nothing if it never was."""
    stuck = np.asarray(events.get("stuck", np.zeros((0, 2))), dtype=float).reshape(-1, 2)
    if not stuck.shape[0]:
        return {}
    released = np.sort(np.asarray(events.get("released", np.zeros((0, 2))),
                                  dtype=float).reshape(-1, 2)[:, 0])
    total = 0.0
    for t0 in stuck[:, 0]:
        later = released[released >= t0]
        total += (later[0] if later.size else t_last) - t0
    return {"stuck_phases": (float(stuck.shape[0]), "1"), "stuck_time": (float(total), "s"),
            "stuck_first_t": (float(stuck[0, 0]), "s"),
            "stuck_first_phi": (float(stuck[0, 1]), "rad")}


def nan_reason(name: str, values: dict[str, float]) -> str:
    """Why the value ``name`` of a run's summary ``values`` (name → number, as stored under
    ``/analysis``) is NaN or absent, in a clause read off the other values; "" if it is a
    number. A study's or a sweep's table says it beside the NaN."""
    value = values.get(name)
    if value is not None and not math.isnan(value):
        return ""
    revolutions = values.get("revolutions", math.nan)
    no_cycle = (f"the run holds no whole cycle turned forwards ({revolutions:.4g} revolutions "
                f"from its start)")
    if name in ("mean_omega_last_cycle", "delta_last_cycle"):
        return no_cycle
    if name == "steady_state_t":
        return NOT_STEADY
    if EFFICIENCY_VALUES.fullmatch(name):
        if "eta_mech_work" not in values:  # (none of them was taken)
            if math.isnan(values.get("mean_omega_last_cycle", math.nan)):
                return no_cycle
            if math.isnan(values.get("steady_state_t", 0.0)):
                return f"no steady cycles to take it over: {NOT_STEADY}"
            return (f"fewer than one whole cycle after the steady state at t = "
                    f"{values['steady_state_t']:.6g} s")
        w_in = values.get("W_in_per_cycle", math.nan)
        if w_in <= 0.0:
            return f"no work in over the steady cycles (W_in = {w_in:.6g} J per cycle)"
    if name.startswith("load_change_") and name.endswith("_recovery_s"):
        band = values.get(name.removesuffix("recovery_s") + "band_pct", math.nan)
        return (f"the cycle-mean speed is not back in its ±{band:.3g} % band by the end of the "
                f"step's segment")
    if name == "spin_up_t90_s":
        return ("the cycle-mean speed never reached 90 % of the final speed, or was past it at "
                "the first whole cycle")
    if name == "spin_up_settling_s":
        band = values.get("spin_up_band_pct", math.nan)
        return (f"the cycle-mean speed is outside its ±{band:.3g} % band at the end, or in it "
                f"from the first whole cycle")
    if value is None:
        return "not in this run's summary (transient info lists what it holds)"
    return "NaN in the run's summary"


#: Why there is no steady state (:func:`~.irregularity.steady_state_time` at its defaults).
NOT_STEADY = ("no steady state: the cycle-mean speed still changed by 1e-4 or more from cycle to "
              "cycle")
