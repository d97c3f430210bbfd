"""Efficiency study: η_mech of an engine at a set of steady speeds and loads.

Each point is a prescribed constant speed (a dynamometer holding ω, the textbook setting and the
limit of a large flywheel), one engine cycle of inverse dynamics through the serial chain: the
motion is periodic, so one cycle is the steady state. The load is the gas-force fraction
``fuel`` (1 full load), as the swash-plate paper's governor sets it; the study holds it, as it
holds the speed, so the scene's governor is left out (it would set the fuel from the speed: a
droop governor cuts it to 0 above its cut-off speed, a PI governor's rack has no state to act
from at a prescribed speed). A value that is NaN in a row (η_mech where no work comes in) has
its reason in the row's ``note``. η_mech is the work ratio of
:mod:`transient.analysis.efficiency`, and each pair's loss and circulated energy say why it falls
with speed: the inertia torques ½J′(φ)ω² grow as ω², and the power they send back and forth
through the pairs is lost on too. Each row carries the friction budget of its point (imep, bmep,
each pair's FMEP and the total); :func:`plot_budget` draws it against speed, :func:`plot_map`
η_mech over speed × load.
"""
from __future__ import annotations

import csv
import dataclasses
import math

from ..analysis.efficiency import mechanical_efficiency
from ..analysis.summary import nan_reason
from ..plots import friction_budget, sweep_heatmap
from ..run import prescribed
from ..scene import Friction, Governor, Initial, Output, Run
from .dynamometer import NoOperatingPoint, held_point, point_row

#: Columns of a study row besides the per-pair ones.
STUDY_COLUMNS = ("policy", "fuel", "rpm", "eta_mech_work", "eta_mech_printed",
                 "eta_mech_printed_excluded", "W_in_per_cycle", "W_out_per_cycle",
                 "energy_balance_residual", "inconsistent_samples", "note")
#: Columns of a steady (dynamometer) row besides: the time-mean speed reached, the cyclic
#: irregularity, the brake torque that holds the speed and the cycles integrated.
STEADY_COLUMNS = ("rpm_mean", "delta", "brake_torque", "cycles_integrated")
#: The values of a row whose NaN the row's note explains.
NAN_SAID = ("eta_mech_work", "eta_mech_printed")


def point_scene(scene, omega: float, policy: str, samples_per_rev: int):
    """The scene as one cycle at the constant speed ``omega`` [rad/s] under ``policy``, without
    its governor (the study holds the fuel)."""
    cycle = scene.mechanism.cycle
    return dataclasses.replace(
        scene,
        run=Run(mode="prescribed-speed", speed=omega, revolutions=cycle / (2 * math.pi)),
        initial=Initial(phi=0.0, omega=omega),
        output=Output(samples_per_rev=samples_per_rev),
        friction=Friction(policy, scene.friction.pairs), governor=Governor())


def study_point(scene, policy: str, fuel: float, rpm: float, samples_per_rev: int = 1440,
                steady: bool = False) -> dict:
    """The study's row of one point: at the prescribed constant speed, or with ``steady`` the
    periodic steady state on a dynamometer with the scene's inertias
    (:func:`~transient.study.dynamometer.held_point`), δ and the brake torque besides; a point
    with no steady state has its reason in ``note`` and no values (NaN in the table)."""
    omega = rpm * math.pi / 30.0
    row: dict = {"policy": policy, "fuel": fuel, "rpm": rpm}
    if steady:
        sc = dataclasses.replace(scene, friction=Friction(policy, scene.friction.pairs))
        try:
            row.update(point_row(held_point(sc, omega, fuel, samples_per_rev)))
        except NoOperatingPoint as exc:
            row["note"] = str(exc)
            return row
    else:
        sc = point_scene(scene, omega, policy, samples_per_rev)
        data = prescribed(sc, fuel)
        row["inconsistent_samples"] = data.solver["inconsistent_samples"]
        row.update({k: v for k, (v, _) in mechanical_efficiency(sc, data.trajectory).items()})
    reasons = ((k, nan_reason(k, row)) for k in NAN_SAID)
    row["note"] = "; ".join(f"{k}: {why}" for k, why in reasons if why)
    return row


def serial(fn, tasks):
    """(i, fn(*tasks[i])) in this process, in order: the study's points without Dask."""
    for i, task in enumerate(tasks):
        yield i, fn(*task)


def efficiency_study(scene, rpm, fuels=(1.0,), policies=None, samples_per_rev: int = 1440,
                     progress=None, steady: bool = False, run_points=serial) -> list[dict]:
    """One row per (policy, fuel, speed): η_mech in both forms and each pair's budget per cycle
    (:func:`study_point`; ``steady``: on a dynamometer). ``run_points(fn, tasks)`` yields
    (i, fn(*tasks[i])) as each point finishes: :func:`serial`, or
    :func:`transient.sweeps.execute.map_tasks` for Dask workers. ``progress(done share)``
    after each point."""
    policies = policies or (scene.friction.policy,)
    points = [(p, f, n) for p in policies for f in fuels for n in rpm]
    rows: list = [None] * len(points)
    tasks = [(scene, p, f, n, samples_per_rev, steady) for p, f, n in points]
    for done, (i, row) in enumerate(run_points(study_point, tasks)):
        rows[i] = row
        if progress:
            progress((done + 1) / len(points))
    return rows


def write_csv(rows: list[dict], fh) -> None:
    """The study as CSV into the text file ``fh``, one row per point; columns STUDY_COLUMNS then
    the per-pair ones."""
    steady = [c for c in STEADY_COLUMNS if any(c in r for r in rows)]
    extra = sorted({k for r in rows for k in r} - set(STUDY_COLUMNS) - set(steady)
                   - {"steady_phi_start", "steady_cycles"})
    cols = list(STUDY_COLUMNS) + steady + extra
    out = csv.writer(fh, lineterminator="\n")  # (quotes a note holding a comma)
    out.writerow(cols)
    for r in rows:
        out.writerow([r.get(c, "") if isinstance(r.get(c), str)
                      else f"{r.get(c, math.nan):.10g}" for c in cols])


def plot_study(ax_eta, ax_loss, rows: list[dict], n_pairs: int, names) -> list:
    """η_mech against speed (one line per policy and fuel; policies that coincide stay visible by
    their markers) on ``ax_eta``; for the first policy at its largest fuel, each pair's loss [% of
    W_in] on ``ax_loss`` and the energy it circulates [× W_in] on a twin axis. Returns the artists."""
    keys = sorted({(r["policy"], r["fuel"]) for r in rows}, key=lambda k: (k[0], -k[1]))
    styles = dict(zip(sorted({k[0] for k in keys}), (("o", "-"), ("x", "--"))))
    artists = []
    for policy, fuel in keys:
        sel = [r for r in rows if r["policy"] == policy and r["fuel"] == fuel]
        marker, line = styles.get(policy, ("o", "-"))
        artists += ax_eta.plot([r["rpm"] for r in sel], [_value(r, "eta_mech_work") for r in sel],
                               marker=marker, linestyle=line, label=f"{policy}, fuel {fuel:g}")
    ax_eta.set_ylabel("η_mech = W_out / W_in")
    ax_eta.legend(fontsize=8)
    ax_eta.grid(alpha=0.3)
    policy, fuel = keys[0]
    sel = [r for r in rows if r["policy"] == policy and r["fuel"] == fuel]
    n = [r["rpm"] for r in sel]
    twin = ax_loss.twinx()
    for k in range(n_pairs):
        artists += ax_loss.plot(n, [100 * _value(r, f"loss_share_{k + 1}") for r in sel], "o-",
                                label=f"loss, {names[k]}")
        # (no work in, above a governor's cut-off: no share to plot there)
        artists += twin.plot(n, [_value(r, f"W_circulated_{k + 1}_per_cycle")
                                 / r["W_in_per_cycle"] if _value(r, "W_in_per_cycle") > 0.0
                                 else math.nan for r in sel], "s:",
                             label=f"circulated, {names[k]}")
    ax_loss.set_xlabel("speed [rpm]")
    ax_loss.set_ylabel(f"loss [% of W_in] ({policy}, fuel {fuel:g})")
    twin.set_ylabel("energy circulated through the pair [× W_in]")
    if n_pairs:
        ax_loss.legend(loc="upper left", fontsize=8)
        twin.legend(loc="upper right", fontsize=8)
    else:  # (an empty panel would read as losses of zero measured)
        ax_loss.text(0.5, 0.5, "no friction pairs in the scene: no losses", ha="center",
                     va="center", transform=ax_loss.transAxes)
    ax_loss.grid(alpha=0.3)
    return artists


def _first_policy(rows: list[dict]) -> tuple[str, list[float], list[float]]:
    """The policy the figures show (the first), its fuels (largest first) and speeds."""
    policy = rows[0]["policy"]
    sel = [r for r in rows if r["policy"] == policy]
    fuels = sorted({r["fuel"] for r in sel}, reverse=True)
    rpm = sorted({r["rpm"] for r in sel})
    return policy, fuels, rpm


def _value(row: dict, key: str) -> float:
    """A row's value, NaN where its point has none (no steady state: every value left out)."""
    return row.get(key, math.nan)


def _row(rows, policy, fuel, rpm) -> dict:
    return next(r for r in rows if (r["policy"], r["fuel"], r["rpm"]) == (policy, fuel, rpm))


def plot_budget(ax, rows: list[dict], names) -> list:
    """Each pair's FMEP [kPa] stacked at every speed, for the first policy at its largest fuel
    (:func:`transient.plots.friction_budget`). Returns the bars."""
    policy, fuels, rpm = _first_policy(rows)
    sel = [_row(rows, policy, fuels[0], n) for n in rpm]
    fmep = [[_value(r, f"fmep_{k + 1}") for r in sel] for k in range(len(names))]
    bars = friction_budget(ax, [f"{n:g}" for n in rpm], fmep, names)
    ax.set_xlabel(f"speed [rpm] ({policy}, fuel {fuels[0]:g})")
    return bars


def plot_map(ax, rows: list[dict], key: str = "eta_mech_work",
             label: str = "η_mech = W_out / W_in"):
    """A column (η_mech unless ``key`` says) over speed × fuel for the first policy, each cell
    labelled (:func:`transient.plots.sweep_heatmap`). Returns the mesh."""
    policy, fuels, rpm = _first_policy(rows)
    fuels = fuels[::-1]  # the lowest load at the bottom
    z = [[_value(_row(rows, policy, f, n), key) for n in rpm] for f in fuels]
    mesh = sweep_heatmap(ax, rpm, fuels, z, "speed [rpm]", "fuel (gas-force fraction)", label)
    ax.set_title(f"{label.split(' = ')[0]} over speed and load ({policy})")
    return mesh
