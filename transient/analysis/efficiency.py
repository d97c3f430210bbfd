"""Mechanical efficiency over whole cycles in steady state (Antonyuk (30)) and where the power goes.

Two forms are reported, and named apart (as printed, (30) averages an
instantaneous ratio whose denominator crosses zero):

* ``eta_mech_work`` — the ratio of the work integrals over the same whole cycles,
  η = W_out / W_in, W_in = ∫(M_gas + M_starter) ω dt, W_out = −∫(M_load + M_drive) ω dt. This is
  the well-posed form: in steady state the kinetic energy returns to its value, so
  W_in = W_out + Σ W_loss,k and η = 1 − Σ W_loss,k / W_in. A **driven machine** (a compressor, a
  motored engine), where both are negative, takes its power the other way, from the load or the
  drive (a motor) into its gas: there W_in = ∫(M_load + M_drive) ω dt and
  W_out = −∫(M_gas + M_starter) ω dt, so that η = W_gas/W_motor, and ``driven`` is stored (1).
* ``eta_mech_printed`` — (30) as printed, the time average of the instantaneous ratio
  P_out/P_in. P_in crosses zero twice per compression stroke, so the ratio is singular there; the
  samples with |P_in| below ``guard`` × mean |P_in| are left out and the share of the time left out
  is stored with it (``eta_mech_printed_excluded``). Its value depends on that guard: it is kept
  for comparison with the paper, not as a result.

Per pair k, over the same cycles: the energy lost, its share of W_in, the net energy transmitted
∫S_k ω dt and the energy *circulated*, ∫|S_k ω| dt − |∫S_k ω dt|: power that goes through the pair
and comes back within the cycle (inertia driving part of the cycle), on which the pair loses too.
This is why η_mech falls with speed. And how often the pair's mode runs against the power it
transmits (negative loss): the share of the time and the number of such intervals per cycle — zero
for the ``power-flow`` policy, the measure of disagreement for ``paper``. On an elastic shaft line
a pair acts in every throw (theory, (T7)): its loss, FMEP and share of W_in are summed over the
throws, and the rest is given per throw (``<k>_<station>`` in place of ``<k>``, its power at
the station's speed, :func:`~transient.scene.outputs.pair_columns`).

The friction budget
-------------------
A pair's loss follows from the chain's own quantities (:mod:`transient.core.model.chain`): summing the
sub-chain equations ``J_k φ̈ + ½J′_k ω² = M_k + η*_{k−1} S_{k−1} − S_k`` times ω gives::

    d/dt ½J(φ)ω² = Σ_k M_k ω − Σ_k (1 − η*_k) S_k ω,

so pair k dissipates ``P_loss,k = (1 − η*_k) S_k ω`` (the ``P_loss_<k>`` column; its integral
``W_loss_<k>`` is integrated with the motion). ``S_k ω`` is the power the shaft side sends into
the pair and ``η*_k S_k ω`` what the far side receives. Forward (``η* = η_fwd``, ``S_k ω ≥ 0``)
the loss is ``(1 − η_fwd) S_k ω``; backward (``η* = 1/η_bwd``, ``S_k ω < 0``) the far side sends
``−S_k ω/η_bwd`` and the loss is ``(1 − η_bwd)(−S_k ω/η_bwd)``. In either mode the pair loses
the share 1 − η of the power its driving side puts in, ≥ 0 whenever the mode agrees with the
direction of that power (always, under ``power-flow``).

Mean effective pressures refer the work per cycle to the engine's displacement V_d
(:func:`displacement`): ``imep`` = W_in/V_d (gas and starter work), ``bmep`` = W_out/V_d (taken
by load and drive), ``fmep_<k>`` = W_loss,k/V_d and ``fmep`` their sum. Over C whole cycles
imep − fmep − bmep = ΔK/(C V_d), K = ½J(φ)ω², zero in steady state; the relative mismatch of
this balance is ``energy_balance_residual``. On an elastic shaft line K is the line's energy
(``E_line``: its dofs' kinetic and its elements' elastic energy) and the energy its damping took
(``W_line_loss``) is a loss in ``fmep`` too. η_mech = bmep/imep = 1 − fmep/imep. Every pair of
the chains the mechanisms have joins links that all cylinders share (the main bearings of every
throw, the crankpins of every rod, the plate bearing of every piston), so a pair's FMEP is
referred to the whole displacement; for an engine whose cylinders work alike it is also each
cylinder's. The correlation of Chen and Flynn (:func:`chen_flynn_fmep`) gives the order of a whole
engine's FMEP to hold a scene's against.
"""
from __future__ import annotations

import math
import re

import numpy as np
from numpy.typing import NDArray

from ..scene.outputs import cylinder_loss_column, pair_columns
from .irregularity import cycle_boundaries, cycle_means, steady_state_time

#: |P_in| below this fraction of its mean is left out of (30) as printed.
PRINTED_GUARD = 1e-3
#: The names of the values :func:`mechanical_efficiency` gives (absent together where a run has
#: no steady whole cycle to take them over).
EFFICIENCY_VALUES = re.compile(
    r"(steady_phi_start|steady_cycles|W_(in|out)_per_cycle|eta_mech_\w+|"
    r"energy_balance_residual|displacement|[ib]mep|fmep(_\w+)?|pair_mode_switches_per_cycle|"
    r"W_(loss|transmitted|circulated)_\w+|loss_share_\d+|backward_share_\w+|"
    r"mode_against_power_\w+|cylinder_split_residual_\d+)")


def steady_window(scene, traj, rtol: float = 1e-4, cycles: int = 3, periodic: bool = False):
    """(φ_start, φ_end, n_cycles) of the whole cycles after steady state, or None.

    Steady state: the cycle-mean speed changes by less than ``rtol`` for ``cycles`` cycles in a
    row (:func:`~transient.analysis.irregularity.steady_state_time`). A prescribed constant speed
    is steady from the start, and so is a ``periodic`` run (the steady cycles that shooting
    found, :func:`transient.steady`).
    """
    t, phi = traj["t"], traj["phi"]
    cycle, phi0 = scene.mechanism.cycle, scene.initial.phi
    tb, marks = cycle_boundaries(t, phi, cycle, phi0)
    if marks.size < 2:
        return None
    if periodic or (scene.run.mode == "prescribed-speed" and not scene.run.time):
        return float(marks[0]), float(marks[-1]), int(marks.size - 1)
    means, ends = cycle_means(t, phi, cycle, phi0)
    t_steady = steady_state_time(means, ends, rtol, cycles)
    if math.isnan(t_steady):
        return None
    first = int(np.searchsorted(tb, t_steady - 1e-12 * max(1.0, abs(t_steady))))
    if marks.size - 1 - first < 1:
        return None
    return float(marks[first]), float(marks[-1]), int(marks.size - 1 - first)


def displacement(mech) -> float:
    """The engine's displacement V_d [m³]: the number of cylinders times the volume each one
    sweeps between its dead centres (crank-slider F_p·S, Gots (11);
    swash plate both halves of a cylinder; articulated the master's, the slaves' strokes
    differing from it by their ``stroke_excess``). A mean effective pressure is the work per
    cycle over V_d, the cycle being ``mech.cycle`` (4π four-stroke, 2π two-stroke)."""
    return mech.n_cylinders * mech.swept_volume()


#: Coefficients (A [Pa], B [1], C [Pa s/m], D [Pa s²/m²]) of :func:`chen_flynn_fmep`: the
#: generic four-stroke set quoted with Chen & Flynn's form, A = 0.4 bar, B = 0.005,
#: C = 0.09 bar s/m, D = 0.0009 bar s²/m² (not a fit to any engine of this project).
CHEN_FLYNN = (0.4e5, 0.005, 0.09e5, 0.0009e5)


def chen_flynn_fmep(p_max: float, c_m: float, coefficients=CHEN_FLYNN) -> float:
    """Friction mean effective pressure [Pa] by the correlation of Chen and Flynn (1965, SAE
    650733), FMEP = A + B·p_max + C·c_m + D·c_m², from the peak cylinder pressure ``p_max``
    [Pa] and the mean piston speed ``c_m`` [m/s] (:func:`mean_piston_speed`).

    The whole engine's friction — piston and rings, bearings, valve train, auxiliaries — as a
    regression over engines: an order of magnitude to compare a model's FMEP with, not a
    prediction. The constant and the speed terms carry most of it at rated speed; the
    coefficients differ from engine to engine (``coefficients``, default :data:`CHEN_FLYNN`).
    """
    a, b, c, d = coefficients
    return a + b * p_max + c * c_m + d * c_m * c_m


def mean_piston_speed(mech, omega: float) -> float:
    """c_m = 2·S·n [m/s], S the stroke (the mechanism's ``stroke()``), n = ω/2π the speed in
    revolutions per second: each piston travels 2S per revolution."""
    return mech.stroke() * omega / math.pi


def _at(traj, name: str, phi_marks) -> NDArray[np.float64]:
    """Column ``name`` at shaft angles ``phi_marks`` (linear in φ; exact on a sample)."""
    phi = traj["phi"]
    keep = np.ones(phi.size, bool)
    back = np.nonzero(np.diff(phi) <= 0)[0]
    if back.size:  # the forward part after the last reversal
        keep[: back[-1] + 1] = False
    return np.interp(phi_marks, phi[keep], traj[name][keep])


def _delta(traj, name: str, a: float, b: float) -> float:
    if name not in traj:
        return 0.0
    va, vb = _at(traj, name, [a, b])
    return float(vb - va)


def mechanical_efficiency(scene, traj: dict[str, NDArray[np.float64]], events=None,
                          window=None, guard: float = PRINTED_GUARD
                          ) -> dict[str, tuple[float, str]]:
    """η_mech in both forms and the per-pair energy budget over ``window`` (φ_a, φ_b, cycles),
    by default the steady whole cycles (:func:`steady_window`). Empty if there is no window.
    ``events`` (name → (n, 2) array of t, φ) adds the pair-mode switches per cycle."""
    window = window or steady_window(scene, traj)
    if window is None:
        return {}
    by_pair = pair_columns(scene)
    n_pairs = len(by_pair)
    a, b, n_cyc = window
    W_gas = _delta(traj, "W_gas", a, b) + _delta(traj, "W_starter", a, b)
    W_shaft = -(_delta(traj, "W_load", a, b) + _delta(traj, "W_drive", a, b))
    driven = W_gas < 0.0 and W_shaft < 0.0  # (the power flows from the load or drive to the gas)
    W_in, W_out = (-W_shaft, -W_gas) if driven else (W_gas, W_shaft)
    chain_loss = {s: _delta(traj, f"W_loss_{s}", a, b) for chains in by_pair for s, _ in chains}
    losses = [sum(chain_loss[s] for s, _ in chains) for chains in by_pair]
    # an elastic shaft line: its energy, and what its damping took (0 without one)
    line_loss = _delta(traj, "W_line_loss", a, b)
    if "E_line" in traj:
        dK = _delta(traj, "E_line", a, b)
    else:
        dK = _delta({"phi": traj["phi"], "K": 0.5 * traj["J"] * traj["omega"] ** 2}, "K", a, b)
    v_d = displacement(scene.mechanism)
    out = {
        "steady_phi_start": (a, "rad"),
        "steady_cycles": (float(n_cyc), "1"),
        "W_in_per_cycle": (W_in / n_cyc, "J"),
        "W_out_per_cycle": (W_out / n_cyc, "J"),
        "eta_mech_work": (W_out / W_in if W_in > 0 else math.nan, "1"),
        "energy_balance_residual": ((dK - (W_in - W_out - sum(losses) - line_loss))
                                    / _throughput(W_in, W_out, dK, [*losses, line_loss]), "1"),
        "displacement": (v_d, "m^3"),
        "imep": (W_gas / n_cyc / v_d, "Pa"),
        "bmep": (W_shaft / n_cyc / v_d, "Pa"),
        "fmep": ((sum(losses) + line_loss) / n_cyc / v_d, "Pa"),
    }
    if driven:
        out["driven"] = (1.0, "1")
    if events is not None and n_pairs:
        switches = np.asarray(events.get("pair_mode", np.zeros((0, 2))))
        inside = (switches[:, 1] >= a) & (switches[:, 1] < b) if switches.size else []
        out["pair_mode_switches_per_cycle"] = (float(np.sum(inside)) / n_cyc, "1")
    sel = (traj["phi"] >= a - 1e-12) & (traj["phi"] <= b + 1e-12)
    out.update(_printed(traj, sel, guard, driven))
    t = traj["t"][sel]
    for k in range(n_pairs):
        out[f"W_loss_{k + 1}_per_cycle"] = (losses[k] / n_cyc, "J")
        out[f"fmep_{k + 1}"] = (losses[k] / n_cyc / v_d, "Pa")
        out[f"loss_share_{k + 1}"] = (losses[k] / W_in if W_in > 0 else math.nan, "1")
        for s, speed in by_pair[k]:  # (the pair itself; on an elastic line in each throw)
            P = traj[f"S_{s}"][sel] * traj[speed][sel]
            net = float(np.trapezoid(P, t))
            gross = float(np.trapezoid(np.abs(P), t))
            out[f"W_loss_{s}_per_cycle"] = (chain_loss[s] / n_cyc, "J")
            out[f"W_transmitted_{s}_per_cycle"] = (net / n_cyc, "J")
            out[f"W_circulated_{s}_per_cycle"] = ((gross - abs(net)) / n_cyc, "J")
            out[f"backward_share_{s}"] = (_time_share(t, traj[f"eta_{s}"][sel] > 1.0), "1")
            # A mode against the transmitted power has a negative loss (the paper's criterion
            # can pick one when inertia drives; the power-flow policy never does).
            loss = traj[f"P_loss_{s}"][sel]
            against = loss < -1e-9 * max(float(np.max(np.abs(loss))), 1e-300)
            out[f"mode_against_power_share_{s}"] = (_time_share(t, against), "1")
            out[f"mode_against_power_per_cycle_{s}"] = (
                float(np.count_nonzero(against[1:] & ~against[:-1]) + against[0]) / n_cyc, "1")
    n_cyl = scene.mechanism.n_cylinders
    out.update(_cylinder_budget(traj, sel, losses, n_cyc, n_cyl, v_d / n_cyl))
    return out


def _cylinder_budget(traj, sel, losses, n_cyc: int, n_cylinders: int, v_cyl: float) -> dict:
    """Each reaction pair's loss split over the cylinders (``P_loss_<k>_cyl<c>`` columns): per
    cylinder c the energy lost per cycle in pair k, its FMEP on the cylinder's own swept volume
    ``v_cyl`` and the cylinder's total FMEP (``fmep_cyl<c>``). The shares come from the trapezoidal
    rule over the samples and scale the pair's exact integral, so that the cylinders sum to it;
    ``cylinder_split_residual_<k>`` is the quadrature's relative mismatch of that integral, which
    finer output sampling makes smaller. Empty without those columns (constant-η and mapped pairs
    join links that every cylinder shares: their loss has no split); a pair whose columns are NaN
    (the swash plate's bearings, which every cylinder loads) has none, and ``fmep_cyl<c>`` sums
    the pairs that split."""
    if not losses or cylinder_loss_column(0, 0) not in traj:
        return {}
    out: dict[str, tuple[float, str]] = {}
    t = traj["t"][sel]
    total = np.zeros(n_cylinders)
    for k, exact in enumerate(losses):
        quad = np.array([np.trapezoid(traj[cylinder_loss_column(k, c)][sel], t)
                         for c in range(n_cylinders)])
        if np.isnan(quad).any():
            continue
        whole = float(np.sum(quad))
        share = quad / whole if whole != 0.0 else np.zeros(n_cylinders)
        out[f"cylinder_split_residual_{k + 1}"] = (
            whole / exact - 1.0 if exact != 0.0 else math.nan, "1")
        for c in range(n_cylinders):
            w_c = exact * share[c] / n_cyc
            out[f"W_loss_{k + 1}_cyl{c + 1}_per_cycle"] = (w_c, "J")
            out[f"fmep_{k + 1}_cyl{c + 1}"] = (w_c / v_cyl, "Pa")
            total[c] += w_c
    for c in range(n_cylinders):
        out[f"fmep_cyl{c + 1}"] = (total[c] / v_cyl, "Pa")
    return out


def _time_share(t, flag) -> float:
    """Share of the time span of ``t`` during which ``flag`` holds (sample weights dt)."""
    dt = np.gradient(t) if t.size > 1 else np.ones(1)
    return float(np.sum(dt[flag]) / np.sum(dt))


def _throughput(W_in: float, W_out: float, dK: float, losses) -> float:
    """The largest energy the balance moves, which its residual is relative to: W_in for an
    engine, the load's work or ΔK where no gas or starter works (a machine coasting or driven)."""
    return max(abs(W_in), abs(W_out), abs(dK), sum(abs(x) for x in losses), 1e-300)


def _printed(traj, sel, guard: float, driven: bool = False) -> dict[str, tuple[float, str]]:
    """(30) as printed: the time average of P_out/P_in, leaving out |P_in| < guard·mean|P_in|
    (``driven``: the power in from the load and drive, out to the gas)."""
    w = traj["omega"][sel]
    drive = traj["M_drive"][sel] if "M_drive" in traj else 0.0
    P_in = (traj["M_gas"][sel] + traj["M_starter"][sel]) * w
    P_out = -(traj["M_load"][sel] + drive) * w
    if driven:
        P_in, P_out = -P_out, -P_in
    keep = np.abs(P_in) > guard * np.mean(np.abs(P_in))  # (none where no power comes in)
    dt = np.gradient(traj["t"][sel]) if w.size > 1 else np.ones(1)
    if not keep.any():
        return {}
    ratio = P_out[keep] / P_in[keep]
    return {"eta_mech_printed": (float(np.sum(ratio * dt[keep]) / np.sum(dt[keep])), "1"),
            "eta_mech_printed_excluded": (float(np.sum(dt[~keep]) / np.sum(dt)), "1")}
