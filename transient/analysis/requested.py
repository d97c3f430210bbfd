"""The analyses a scene asks for in its ``[analysis]`` table
(:class:`transient.scene.records.Analysis`),
computed at the end of a run and stored under ``/analysis/<name>`` with a unit each
(docs/guide/analyses.md).

Nothing here runs unless the scene asks. :func:`requested_analyses` returns name → (value, unit)
like the end-of-run summary (:func:`transient.analysis.summary.summarize`, which calls it);
values are scalars, strings or arrays. A part that cannot be computed (the run holds no whole
cycle) is left out and ``<part>_skipped`` says why: never guessed.

Stored names (n: cylinders, N: ``samples_per_cycle``, C: whole cycles, K: orders 0 … max_order)

* ``irregularity = true``: ``irregularity_cycle_end_t`` [s], ``irregularity_cycle_omega_mean``
  [rad/s] (cycle angle over cycle time), ``irregularity_cycle_delta`` [1]
  (δ = (ω_max − ω_min)/ω_mean over each cycle's samples, Gots §2.8), each (C,).
* ``orders = [...]``: ``orders_order`` (K,) [1/rev]; ``orders_cycle_start`` (C,) [rad],
  ``orders_cycle_omega_mean`` (C,) [rad/s]; ``orders_detrend`` ("ramp" or "none": what was
  done to ω, the only signal detrended, as ``transient orders`` does); per signal s
  ``orders_<s>_amplitude`` (C, K) [unit of s] and ``orders_<s>_phase`` (C, K) [rad]
  (:class:`transient.analysis.orders.OrderSpectrum`; order 0 is the mean of the detrended cycle).
  A signal is a trajectory column or ``W_<k>``, the piston acceleration of cylinder k,
  W = ω²s″ + εs′ [m/s²] (any mechanism, :mod:`transient.analysis.pistons`).
* ``loads = true`` (crank-slider), over the last whole cycle on a uniform grid of N angles
  (:mod:`transient.analysis.loads.crank_slider`): ``loads_phi`` (N,) [rad]; ``loads_P``,
  ``loads_N``, ``loads_S``, ``loads_K``, ``loads_T`` (Gots (34)–(37)), the crankpin load
  ``loads_R_K``, ``loads_R_T``, ``loads_R`` ((40)/(41) as vectors), each (n, N) [N];
  ``loads_torque`` (n, N) and ``loads_engine_torque`` (N,) [N m]; ``loads_crankpin_R_max`` (n,)
  [N]; the running torques ``loads_journal_torque`` (m+1, N), ``loads_crankpin_torque`` (m, N)
  [N m] (§2.8) and the main journals by the split beam of (58), ``loads_main_x``,
  ``loads_main_y`` (m+1, N) and ``loads_main_R_max`` (m+1,) [N] (frame of crank 1), m the
  throws (n, or n/2 where two rods share a crankpin).
* ``loads = true``, articulated (radial, V; :mod:`transient.analysis.loads.articulated`), the
  same grid and ``loads_phi``: per cylinder ``loads_P``, ``loads_N``, ``loads_S`` (n, N) [N] and
  ``loads_torque`` = P u (n, N) [N m]; per row (its crankpin, ρ rows) ``loads_K``, ``loads_T``,
  ``loads_R_K``, ``loads_R_T``, ``loads_R`` (ρ, N) and ``loads_crankpin_R_max`` (ρ,) [N]; per link
  pin (ρ·z′ slaves) its load in the row frame ``loads_link_x``, ``loads_link_y`` (ρ·z′, N) and
  ``loads_link_R_max`` (ρ·z′,) [N]; ``loads_engine_torque`` Σ T r (N,) [N m]. No main journals
  or running torques.
* ``loads = true``, swash plate (:mod:`transient.analysis.loads.swash_plate`): per cylinder (one
  piston; torques count both halves) ``loads_P``, ``loads_S``, ``loads_N_radial``,
  ``loads_N_tangential`` (z, N) [N], ``loads_torque`` (z, N) [N m]; ``loads_engine_torque``
  (Σ torque) and ``loads_shaft_torque`` (with the rods' and link 9's inertia) (N,) [N m]. No
  crankpin.
* ``thermodynamics = true``: per cylinder and whole cycle ``thermo_*`` — indicated work, IMEP,
  BMEP, FMEP, the powers, the peak pressures and, for Wiebe combustion, the heat released and
  the burned-fraction angles (:mod:`transient.analysis.thermo` lists the names and units).
"""
from __future__ import annotations

import re
from typing import Any

import numpy as np

from ..errors import SceneError
from ..mechanisms import PluginTable, provider
from .irregularity import cycle_boundaries
from .loads.common import stored_record
from .orders import order_spectrum, resolve_detrend, to_angle_grid
from .pistons import piston_kinematics
from .thermo import cycle_thermodynamics

#: A derived signal of ``orders``: the piston acceleration of cylinder k.
PISTON_ACCELERATION = re.compile(r"W_([1-9][0-9]*)$")


def requested_analyses(scene, traj: dict[str, np.ndarray], events=None
                       ) -> dict[str, tuple[Any, str]]:
    """Every analysis ``scene.analysis`` asks for, as name → (value, unit); {} if none."""
    req = scene.analysis
    cuts = np.asarray((events or {}).get("breakpoint", np.zeros((0, 2))))[:, 1]
    out: dict[str, tuple[Any, str]] = {}
    parts = (("irregularity", req.irregularity, lambda: cycle_irregularity(scene, traj)),
             ("orders", bool(req.orders), lambda: stored_orders(scene, traj, cuts)),
             ("loads", req.loads, lambda: stored_loads(scene, traj, cuts)),
             ("thermo", req.thermodynamics, lambda: cycle_thermodynamics(scene, traj, events)))
    for name, asked, compute in parts:
        if not asked:
            continue
        try:
            out.update(compute())
        except ValueError as exc:  # e.g. no whole cycle in the run
            out[f"{name}_skipped"] = (str(exc), "")
    return out


def cycle_irregularity(scene, traj) -> dict[str, tuple[Any, str]]:
    """δ and the mean speed of every whole cycle (cycles counted from ``scene.initial.phi``)."""
    t, phi, omega = traj["t"], traj["phi"], traj["omega"]
    cycle = scene.mechanism.cycle
    tb, _ = cycle_boundaries(t, phi, cycle, scene.initial.phi)
    if tb.size < 2:
        raise ValueError("the run holds no whole cycle")
    means = cycle / np.diff(tb)
    lo = np.searchsorted(t, tb[:-1], side="left")
    hi = np.searchsorted(t, tb[1:], side="right")
    delta = np.array([np.ptp(omega[a:b]) if b > a else np.nan for a, b in zip(lo, hi)]) / means
    return {"irregularity_cycle_end_t": (tb[1:], "s"),
            "irregularity_cycle_omega_mean": (means, "rad/s"),
            "irregularity_cycle_delta": (delta, "1")}


def _column_units(scene) -> dict[str, str]:
    from ..scene.outputs import output_columns

    return output_columns(scene)


def stored_orders(scene, traj, cuts) -> dict[str, tuple[Any, str]]:
    """Per-cycle order spectra of the signals ``scene.analysis.orders`` up to ``max_order``."""
    req = scene.analysis
    mech = scene.mechanism
    n, cycle = req.samples_per_cycle, mech.cycle
    units = _column_units(scene)
    derived = {s: int(m.group(1)) for s in req.orders if (m := PISTON_ACCELERATION.match(s))}
    columns = [s for s in req.orders if s not in derived]
    if derived:
        columns += ["omega", "epsilon"]
    names = tuple(dict.fromkeys(["t", *columns]))
    grid, cols = to_angle_grid(traj, names, n, cycle, phi0=scene.initial.phi, cuts=cuts,
                               closed=True)
    if derived:
        pk = piston_kinematics(mech, grid)
        for s, k in derived.items():
            # W = ω²s″ + εs′ (Semenov §4), exact kinematics of any mechanism's piston
            cols[s] = cols["omega"] ** 2 * pk.dds[k - 1] + cols["epsilon"] * pk.ds[k - 1]
            units[s] = "m/s^2"
    mode = resolve_detrend(req.detrend, scene.initial.omega, float(traj["omega"][-1]))
    t_marks = cols["t"][::n]  # every cycle's start and the last one's end (closed grid)
    out: dict[str, tuple[Any, str]] = {"orders_cycle_start": (grid[:-1:n], "rad"),
                                       "orders_cycle_omega_mean": (cycle / np.diff(t_marks),
                                                                   "rad/s"),
                                       "orders_detrend": (mode, "")}
    for s in req.orders:
        v = cols[s]
        # The ramp is ω's trend (a spin-up), as `transient orders` removes it: other signals'
        # trends are not additive (W = ω²s″ + εs′ scales with ω²), and a ramp through their
        # cycle ends would add spurious orders.
        spec = order_spectrum(v[:-1], n, cycle, detrend=mode if s == "omega" else "none",
                              end=v[-1])
        keep = spec.orders <= req.max_order + 1e-9
        out["orders_order"] = (spec.orders[keep], "1/rev")
        out[f"orders_{s}_amplitude"] = (spec.amplitude[:, keep], units[s])
        out[f"orders_{s}_phase"] = (spec.phase[:, keep], "rad")
    return out


def stored_loads(scene, traj, cuts) -> dict[str, tuple[Any, str]]:
    """Forces, crankpin and main-journal loads and running torques over the last whole cycle,
    by the storer :data:`LOADS` names for the mechanism; a one-line
    :class:`~transient.errors.SceneError` for a mechanism without one."""
    mech = scene.mechanism
    n = scene.analysis.samples_per_cycle
    names = [c for c in ("t", "omega", "epsilon", "fuel") if c in traj]
    names += [f"p_{k + 1}" for k in range(mech.n_cylinders) if f"p_{k + 1}" in traj]
    grid, cols = to_angle_grid(traj, names, n, mech.cycle, phi0=scene.initial.phi, cycles=1,
                               cuts=cuts)
    store = provider(mech, "loads", LOADS)
    if store is None:
        raise SceneError("analysis.loads", f"loads are not computed for {type(mech).__name__}; "
                                           f"allowed here: false")
    return store(scene, grid, {"phi": grid, **cols})


def _stored_crank_slider_loads(scene, grid, traj) -> dict[str, tuple[Any, str]]:
    """Crank-slider (:mod:`transient.analysis.loads.crank_slider`): per cylinder and crankpin,
    the running torques (§2.8) and the main journals by the split beam of (58)."""
    from .loads.crank_slider import loads_from_trajectory, main_journal_loads, running_torques

    mech = scene.mechanism
    ld = loads_from_trajectory(scene, traj)
    out = stored_record(ld, grid, ("P", "N", "S", "K", "T", "R_K", "R_T", "R"))
    out["loads_crankpin_R_max"] = (ld.R.max(axis=1), "N")
    journals, pins = running_torques(mech, ld)
    mj = main_journal_loads(mech, ld, traj["omega"], traj["epsilon"])
    out["loads_journal_torque"] = (journals, "N m")
    out["loads_crankpin_torque"] = (pins, "N m")
    out["loads_main_x"] = (mj.x, "N")
    out["loads_main_y"] = (mj.y, "N")
    out["loads_main_R_max"] = (mj.magnitude.max(axis=1), "N")
    return out


def _stored_articulated_loads(scene, grid, traj) -> dict[str, tuple[Any, str]]:
    """Radial/V rows (:mod:`transient.analysis.loads.articulated`): per cylinder, link pin and
    crankpin; no main journals or running torques (one crankpin carries a whole row)."""
    from .loads.articulated import articulated_loads_from_trajectory

    ld = articulated_loads_from_trajectory(scene, traj)
    out = stored_record(ld, grid, ("P", "N", "S", "K", "T", "R_K", "R_T", "R", "link_x",
                                    "link_y"))
    out["loads_crankpin_R_max"] = (ld.R.max(axis=1), "N")
    out["loads_link_R_max"] = (ld.link_R.max(axis=1), "N")
    return out


def _stored_swash_loads(scene, grid, traj) -> dict[str, tuple[Any, str]]:
    """Swash plate (:mod:`transient.analysis.loads.swash_plate`): per cylinder and the shaft
    torque; no crankpin, journals or running torques."""
    from .loads.swash_plate import swash_loads_from_trajectory

    ld = swash_loads_from_trajectory(scene, traj)
    out = stored_record(ld, grid, ("P", "S", "N_radial", "N_tangential"))
    out["loads_shaft_torque"] = (ld.shaft_torque, "N m")
    return out


#: The storer of each mechanism's loads (capability ``"loads"``) by its name in
#: :data:`transient.mechanisms.MECHANISMS`:
#: (scene, angle grid, trajectory on it) → name → (value, unit).
#: a mechanism's own module of :mod:`transient.analysis.loads` may hold it as ``stored_loads``.
LOADS = PluginTable({"crank-slider": _stored_crank_slider_loads,
                     "articulated": _stored_articulated_loads,
                     "swash-plate": _stored_swash_loads},
                    "transient.analysis.loads.{}", "stored_loads")
