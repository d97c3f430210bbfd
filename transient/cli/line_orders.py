"""``transient orders`` of an elastic run (``[shaft]``): what its shaft line did, cycle by cycle
(:mod:`transient.analysis.torsion_run`) — each element's torque and its vibratory part, each
damping part's mean power, the orders of a twist or a torque against the speed, drawn over the
line's Campbell diagram with its critical speeds (:mod:`transient.analysis.torsion`)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from .common import check_output_file, pyplot, save, write_columns

#: The figures and tables an elastic run adds to ``transient orders``, by their name's ending.
FILES = {"campbell": "campbell_run.png", "cycles_figure": "line_cycles.png",
         "cycles": "line_cycles.csv", "orders": "line_orders.csv"}


#: Output samples per period of the line's first mode below which ``transient orders`` says
#: that the vibration is read between samples (its cubic interpolation errs by about
#: (5/384)·(2π/n)⁴ of the amplitude: 4e-4 at 20).
DENSE = 20.0


def add_options(parser) -> None:
    parser.add_argument(
        "--line-column", default=None, metavar="NAME",
        help="of an elastic run ([shaft]): the twist_<dof> or torque_<a>_<b> column whose "
             "orders are drawn over the Campbell diagram and tabulated cycle by cycle "
             "(default: the torque of the element the first mode twists most)")


def check_column(res, scene, args) -> None:
    """--line-column, before any work: one of the run's twist or torque columns, and only for
    an elastic run."""
    if args.line_column is None:
        return
    if scene.shaft is None:
        raise SceneError("--line-column", "the run has no elastic shaft line ([shaft]): leave "
                                          "the option out", file=str(res.path))
    names = [c for c in res.trajectory if c.startswith(("twist_", "torque_"))]
    if args.line_column not in names:
        raise SceneError("--line-column", f"{args.line_column!r} is not a column of the run's "
                                          f"line; allowed: {', '.join(names)}",
                         file=str(res.path))


def plan(scene, args, out: Path, stem: str) -> dict[str, Path] | None:
    """The files an elastic run adds (None for a rigid run), none of them there unless
    --force, checked before any work."""
    if scene.shaft is None:
        return None
    paths = {key: out / f"{stem}_{end}" for key, end in FILES.items()}
    for path in paths.values():
        check_output_file(path, args.force)
    return paths


@dataclass(frozen=True)
class LineReport:
    """What ``transient orders`` shows of an elastic run's line (:func:`report`): its
    ``scene``, ``modal`` analysis, engine ``orders`` and their ``criticals`` over ``rpm_range``
    (the scene's, widened to the run's), its ``elements``, their torques cycle by cycle
    (``cycles``), the orders of ``column`` (``orders_of_run``), the damping's ``losses`` and each
    part's mean ``power`` per cycle."""

    scene: Any
    modal: Any
    orders: np.ndarray
    rpm_range: tuple[float, float]
    criticals: list
    elements: list
    cycles: Any
    column: str
    orders_of_run: Any
    losses: Any
    power: dict[str, np.ndarray]

    @property
    def rpm(self) -> np.ndarray:
        return self.cycles.omega_mean * 30.0 / math.pi

    @property
    def unit(self) -> str:
        return "rad" if self.column.startswith("twist_") else "N m"


def report(res, scene, args, cuts) -> LineReport:
    """The analyses of the run ``res`` of ``scene`` that ``transient orders`` shows, with its
    options ``args`` (--line-column, --samples-per-cycle, --max-order, --detrend)."""
    from ..analysis.torsion import critical_speeds, engine_orders, modal_analysis, speed_range
    from ..analysis.torsion_run import (
        cycle_mean_power,
        line_cycles,
        line_elements,
        line_losses,
        line_orders,
        torque_column,
    )
    from ..shaft import ShaftLine

    traj, n = res.trajectory, args.samples_per_cycle
    line = ShaftLine(scene)
    modal = modal_analysis(line)
    column = args.line_column or torque_column(line, modal.modes[0].twist_at)
    elements = line_elements(line)
    cycles = line_cycles(scene, traj, [e.torque for e in elements], n, cuts=cuts)
    losses = line_losses(line, traj)
    power = {p: cycle_mean_power(scene, traj, losses.power[i])[1][-cycles.omega_mean.size:]
             for i, p in enumerate(losses.parts)}
    rpm = cycles.omega_mean * 30.0 / math.pi
    lo, hi = speed_range(scene)
    rpm_range = (min(lo, 0.95 * float(rpm.min())), max(hi, 1.05 * float(rpm.max())))
    orders = engine_orders(scene.mechanism.cycle, args.max_order)
    return LineReport(scene, modal, orders, rpm_range, critical_speeds(modal, orders, rpm_range),
                      elements, cycles, column,
                      line_orders(scene, traj, [column], n, cuts=cuts, detrend=args.detrend),
                      losses, power)


def write(res, scene, args, paths: dict[str, Path], cuts) -> list[Path]:
    """The elastic run's tables and figures (:func:`plan`'s ``paths``), its summary printed;
    returns the files written."""
    from ..analysis.torsion_run import campbell_overlay
    from ..scene.outputs import column_name

    r = report(res, scene, args, cuts)
    table = {"cycle": np.arange(1, r.rpm.size + 1), "cycle_start_rad": r.cycles.cycle_start,
             "cycle_omega_mean_rad_s": r.cycles.omega_mean}
    for e, mean, pp in zip(r.elements, r.cycles.mean, r.cycles.peak_to_peak, strict=True):
        table[f"{e.torque}_mean_Nm"] = mean
        table[f"{e.torque}_peak_to_peak_Nm"] = pp
    for part, p in r.power.items():
        table[f"power_{column_name(part)}_W"] = p
    write_columns(paths["cycles"], table, args.force)
    speeds, qs, amp = campbell_overlay(r.orders_of_run, r.column, r.orders)
    by_order = {"cycle": np.arange(1, speeds.size + 1), "cycle_omega_mean_rpm": speeds}
    by_order.update({f"{r.column}_order_{q:g}_{r.unit.replace(' ', '')}": amp[:, j]
                     for j, q in enumerate(qs)})
    write_columns(paths["orders"], by_order, args.force)
    written = [paths["cycles"], paths["orders"]]
    for name, fig in figures(r):
        written.append(save(fig, paths[name], args.force, res))
    _print_line(r, args.max_order)
    return written


def figures(r: LineReport):
    """The figures of :func:`report`, as (key of :data:`FILES`, figure) pairs: the Campbell
    diagram with the run's orders of its column, and the line cycle by cycle (against the
    cycle-mean speed for a run-up, :func:`~transient.analysis.orders.is_run_up`, else against
    the cycle)."""
    from .. import plots
    from ..analysis.orders import is_run_up
    from ..analysis.torsion_run import campbell_overlay

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(11, 7.5), layout="constrained")
    plots.modal_campbell(ax, r.modal, r.orders, r.rpm_range, r.criticals,
                         run_orders=campbell_overlay(r.orders_of_run, r.column, r.orders),
                         run_label=f"{r.column}: order amplitude [{r.unit}]")
    ax.set_title(f"{r.scene.name}: Campbell diagram with the run's orders of {r.column}")
    yield "campbell", fig
    run_up = is_run_up(r.cycles.omega_mean)
    x = r.rpm if run_up else np.arange(1, r.rpm.size + 1)
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(11, 10), sharex=True, layout="constrained")
    plots.cycle_curves(a1, x, {e.label: 0.5 * pp for e, pp in
                               zip(r.elements, r.cycles.peak_to_peak, strict=True)
                               if e.kind != "damper" or e.k},
                       "vibratory torque, ½ peak-to-peak [N m]", xlabel="")
    a1.set_title("each element's vibratory torque, cycle by cycle", fontsize=9)
    tracks = {f"order {p.order:g}": r.orders_of_run.track(r.column, p.order)
              for p in sorted(_strongest(r), key=lambda p: p.order)}
    plots.order_tracks(a2, x, tracks, f"order amplitude [{r.unit}]", xlabel="")
    a2.set_title(f"{r.column}: its strongest orders, cycle by cycle", fontsize=9)
    plots.cycle_curves(a3, x, _grouped(r.power), "mean power over the cycle [W]",
                       xlabel="cycle-mean speed [rpm]" if run_up else "cycle of the run")
    if not r.power:
        a3.text(0.5, 0.5, "the line has no damping", transform=a3.transAxes, ha="center")
    a3.set_title("power the damping takes, cycle by cycle", fontsize=9)
    fig.suptitle(f"{r.scene.name}: the shaft line cycle by cycle")
    yield "cycles_figure", fig


def _grouped(power: dict) -> dict:
    """The damping parts' powers as a figure shows them: each damper and the coupling on its
    own, the sections and the stations' absolute damping each summed (the table keeps every
    part)."""
    groups: dict = {}
    for part, p in sorted(power.items(), key=lambda kv: not kv[0].startswith("damper")):
        key = ("sections, all" if part.startswith("section") else
               "absolute damping, all stations" if part.startswith("absolute") else part)
        groups[key] = groups.get(key, 0.0) + p
    return groups


def _strongest(r: LineReport, count: int = 6) -> list:
    """The peaks (:func:`~transient.analysis.torsion_run.order_peaks`) of the ``count``
    orders of the column that are largest over the run, largest first."""
    from ..analysis.torsion_run import order_peaks

    peaks = order_peaks(r.orders_of_run, r.column, r.orders, r.criticals)
    return sorted(peaks, key=lambda p: p.amplitude, reverse=True)[:count]


def _print_line(r: LineReport, top: float) -> None:
    rpm = r.rpm
    print(f"  shaft line over {rpm.size} whole cycle(s), {rpm.min():.6g} … {rpm.max():.6g} rpm "
          f"(cycle means):")
    half = 0.5 * r.cycles.peak_to_peak
    e = int(np.argmax(half.max(axis=1)))
    i = int(np.argmax(half[e]))
    print(f"  largest vibratory torque: {r.elements[e].label}, ½ peak-to-peak "
          f"{half[e, i]:.5g} N m in the cycle at {rpm[i]:.6g} rpm")
    for part, mean in r.power.items():
        if part.startswith("damper"):
            k = int(np.argmax(mean))
            print(f"  {part}: mean power at most {mean[k]:.5g} W, at {rpm[k]:.6g} rpm; "
                  f"{mean[-1]:.5g} W in the last cycle")
    losses = r.losses
    if losses.parts:
        print(f"  heats of the damping parts: Σ = {losses.heat[:, -1].sum():.8g} J against "
              f"the run's W_line_loss {losses.total[-1] - losses.total[0]:.8g} J (relative "
              f"difference {losses.residual:.2e}: the sampling's quadrature error)")
    peaks = _strongest(r)
    print(f"  {r.column}, strongest orders up to {top:g}: largest amplitude and where, against "
          f"the nearest critical speed of the order:")
    for p in sorted(peaks, key=lambda p: p.order):
        near = (f"critical {p.critical:.1f} rpm (mode {p.mode})" if p.mode
                else "no critical in range")
        print(f"    order {p.order:5g}: {p.amplitude:.5g} {r.unit} at {p.rpm:.6g} rpm; {near}")
    first = r.modal.modes[0].f
    per_period = r.scene.output.samples_per_rev * float(rpm.min()) / 60.0 / first
    print(f"  the output's samples per period of the first mode ({first:.4g} Hz): "
          f"{per_period:.3g} at {rpm.min():.6g} rpm"
          + (f" — fewer than {DENSE:g}: the peaks of the vibratory torque and the heats are "
             f"read between samples; raise [output] samples_per_rev" if per_period < DENSE
             else ""))
