"""``transient orders``: order spectra of a stored run as PNG and CSV files
(:func:`transient.analysis.orders.run_orders`); the result file is only read."""
from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from . import line_orders
from .common import (
    EXIT_OK,
    MAX_POINTS,
    add_force,
    output_folder,
    pyplot,
    read_result,
    real,
    result_stem,
    save,
    whole,
    write_columns,
)


def register(sub) -> None:
    od = sub.add_parser(
        "orders", help="order spectra of ω, M_gas and piston acceleration (PNG + CSV)",
        description="Order spectra over the last whole cycle (transient.analysis.orders): ω, "
                    "the gas torque M_gas and each cylinder's, and the piston acceleration of "
                    "one cylinder (any mechanism) against the same engine at constant mean "
                    "speed (odd-harmonic report); δ of the last cycle; with two or more whole "
                    "cycles, for a run-up a waterfall (a colour map), a Campbell chart and "
                    "order tracks of ω against the cycle-mean speed, for any other run the "
                    "waterfall and order tracks cycle by cycle. Of an elastic run ([shaft]) "
                    "also the shaft line cycle by cycle: each element's torque (mean and "
                    "peak-to-peak), each damping part's mean power, the orders of a twist or "
                    "torque (--line-column) over the line's Campbell diagram with its critical "
                    "speeds. Results are written as files into DIR, never into the HDF5 "
                    "result (read only here).")
    od.add_argument("result")
    od.add_argument("-o", "--output", default=None, help="folder (default: beside the result)")
    od.add_argument("--samples-per-cycle", type=whole(16, MAX_POINTS), default=720,
                    help="crank-angle grid points per engine cycle (default 720); orders up to "
                         "half of it per cycle")
    od.add_argument("--max-order", type=real(gt=0.0), default=12.0,
                    help="highest order in the tables and figures (default 12)")
    od.add_argument("--detrend", choices=("auto", "ramp", "none"), default="auto",
                    help="remove each cycle's ramp from ω before its DFT (default auto: for a "
                         "spin-up, a run starting below 90 %% of its final speed)")
    od.add_argument("--cylinder", type=int, default=1, metavar="K",
                    help="cylinder (1-based) of the odd-harmonic report of the piston "
                         "acceleration (default 1)")
    line_orders.add_options(od)
    add_force(od)
    od.set_defaults(func=cmd_orders)


def figures(res, ro, top: float, cylinder: int):
    """The figures ``transient orders`` writes of the result ``res`` and its order spectra
    ``ro`` (:func:`transient.analysis.orders.run_orders`), orders up to ``top``, the piston of
    ``cylinder``: (name, figure) pairs, each saved as ``<stem>_<name>.png``. With two or more
    whole cycles, ``orders_runup`` for a run-up (:func:`~transient.analysis.orders.is_run_up`),
    else ``orders_cycles``, the cycles in the order they ran."""
    plt = pyplot()

    from .. import plots
    from ..analysis.orders import is_run_up, strongest_orders

    scene = res.scene()
    spec_w, spec_m, rep, per_cyl = ro.omega, ro.gas_torque, ro.piston, ro.cylinder_torques
    means, orders, rpm = ro.omega_mean, ro.orders, plots.RPM
    rows = 1 + (spec_m is not None) + (rep is not None) + (per_cyl is not None)
    fig, axes = plt.subplots(rows, 1, figsize=(10, 3.2 * rows), squeeze=False)
    axes = axes[:, 0]
    plots.order_bars(axes[0], orders, spec_w.amplitude[-1], "ω amplitude [rad/s]", top)
    axes[0].set_title(f"{scene.name}: orders over the last cycle (mean ω "
                      f"{means[-1] * rpm:.5g} rpm, δ = {ro.delta:.4g}"
                      f"{', detrended' if ro.detrend == 'ramp' else ''})", fontsize=10)
    i = 1
    if spec_m is not None:
        plots.order_bars(axes[i], orders, spec_m.amplitude[-1], "M_gas amplitude [N m]", top)
        i += 1
    if per_cyl is not None:
        z = per_cyl.coef.shape[0]
        width = 0.8 * float(orders[1]) / z
        for k in range(z):
            plots.order_bars(axes[i], orders, per_cyl.amplitude[k], "cylinder torque [N m]",
                             top, width=width, offset=(k - (z - 1) / 2) * width,
                             label=f"cylinder {k + 1}", color=f"C{k % 10}")
        plots.legend_outside(axes[i], above=True, ncol=min(z, 8))
        i += 1
    if rep is not None:
        label = f"W / W₁ (cylinder {cylinder})"
        floors = _relative_floors(scene, orders)
        plots.order_bars(axes[i], orders, rep.relative[-1], label, top, width=0.2, offset=-0.1,
                         label="run", log=True, floor=floors["run"][0])
        plots.order_bars(axes[i], orders, rep.relative_constant[-1], label, top, width=0.2,
                         offset=0.1, label="constant ω̄", log=True,
                         floor=floors["constant"][0])
        for (level, words), colour in zip(floors.values(), ("C0", "C1")):
            plots.noise_floor(axes[i], level, words, color=colour)
        axes[i].set_ylim(bottom=0.3 * min(level for level, _ in floors.values()))
        plots.legend_outside(axes[i], above=True, ncol=2)
    yield "orders", fig

    if ro.cycles < 2:
        return
    amp = spec_w.amplitude
    # the last cycle's strongest orders, in order of the order
    tracks = {f"order {orders[j]:g}": amp[:, j]
              for j in sorted(strongest_orders(orders, amp[-1], top))}
    level = RUN_FLOOR_RTOL * scene.solver.rtol * float(np.mean(means))
    floor = (level, f"noise floor: {RUN_FLOOR_RTOL:g} × rtol · ω̄ = {level:.2g} rad/s")
    if is_run_up(means):
        fig, (a1, a3, a2) = plt.subplots(1, 3, figsize=(20, 5.5), layout="constrained")
        plots.order_waterfall(a1, means * rpm, orders, amp, top, label="ω amplitude [rad/s]")
        a1.set_title(f"ω spectrum per cycle ({ro.cycles} cycles) over speed", fontsize=9)
        plots.campbell(a3, means * rpm, orders, amp, top, label="ω amplitude [rad/s]")
        a3.set_title("Campbell chart of ω: orders over speed", fontsize=9)
        plots.order_tracks(a2, means * rpm, tracks, "ω amplitude [rad/s]", floor=floor)
        a2.set_title("order tracks of ω against the cycle-mean speed", fontsize=9)
        fig.suptitle(f"{scene.name}: run-up orders of ω (cycle-mean speed "
                     f"{means.min() * rpm:.0f} … {means.max() * rpm:.0f} rpm)")
        yield "orders_runup", fig
        return
    cycles = np.arange(1, ro.cycles + 1)
    fig = plt.figure(figsize=(16, 7), layout="constrained")
    left, right = fig.subfigures(1, 2, width_ratios=(1.0, 1.3))
    a1 = left.subplots()
    plots.order_waterfall_cycles(a1, cycles, orders, amp, top, label="ω amplitude [rad/s]")
    a1.set_title(f"ω spectrum of each cycle ({ro.cycles} cycles)", fontsize=9)
    a2, a3 = right.subplots(2, 1, sharex=True, height_ratios=(2.0, 1.0))
    plots.order_tracks(a2, cycles, tracks, "ω amplitude [rad/s]", xlabel="", floor=floor)
    a2.set_title("order tracks of ω, cycle by cycle", fontsize=9)
    a3.plot(cycles, means * rpm, lw=1.0, marker="." if cycles.size <= 60 else None, color="k")
    a3.set_xlabel("cycle of the run")
    a3.set_ylabel("cycle-mean ω [rpm]")
    a3.grid(True, alpha=0.3)
    _mark_cycles((a2, a3), res, scene, ro)
    fig.suptitle(f"{scene.name}: orders of ω, cycle by cycle (cycle-mean speed "
                 f"{means.min() * rpm:.0f} … {means.max() * rpm:.0f} rpm)")
    yield "orders_cycles", fig


#: The run's noise floor in solver tolerances: the error the solver leaves in ω and ε (and the
#: resampling onto the angle grid adds) is a few times its local tolerance rtol; a cross-plane
#: V8's half orders of W/W₁, nought in exact arithmetic, come out at about 2·rtol.
RUN_FLOOR_RTOL = 10.0


def _relative_floors(scene, orders) -> dict[str, tuple[float, str]]:
    """Noise floors of the piston acceleration's orders relative to its first: the run's,
    :data:`RUN_FLOOR_RTOL` times the solver's relative tolerance; the same engine's at constant
    ω̄ (computed in closed form, no solver), the rounding of an N-point DFT, N·ε_mach."""
    n = 2 * (len(orders) - 1)
    run = RUN_FLOOR_RTOL * scene.solver.rtol
    return {"run": (run, f"run: {RUN_FLOOR_RTOL:g} × solver rtol = {run:.0e}"),
            "constant": (n * np.finfo(float).eps, f"constant ω̄: rounding, N·ε = "
                                                   f"{n * np.finfo(float).eps:.0e}")}


def _mark_cycles(axes, res, scene, ro):
    """The run's events (:func:`transient.plots.run_events`) on axes over the cycle number:
    each at the cycle it happened in."""
    from .. import plots
    from ..analysis.irregularity import cycle_boundaries

    tb, marks = cycle_boundaries(res.trajectory["t"], res.trajectory["phi"],
                                 scene.mechanism.cycle, scene.initial.phi)
    first = int(np.argmin(np.abs(marks - ro.cycle_start[0])))  # the bound of cycle 1
    events = [(kind, words, np.searchsorted(tb[first:], times, side="right").astype(float))
              for kind, words, times in plots.run_events(res, scene)]
    handles = plots.mark_events(axes, events, ro.cycles)
    if handles:
        plots.legend_outside(axes[1], handles=handles)


def cmd_orders(args) -> int:
    from ..analysis.irregularity import NoWholeCycle
    from ..analysis.orders import orders_up_to, run_orders, strongest_orders

    res = read_result(args.result)
    scene = res.scene()
    mech = scene.mechanism
    n = args.samples_per_cycle
    traj = res.trajectory
    cuts = res.events.get("breakpoint", {}).get("phi", np.zeros(0))
    if not 1 <= args.cylinder <= mech.n_cylinders:
        raise SceneError("--cylinder", f"cylinder {args.cylinder} is out of range; allowed: "
                                       f"1 … {mech.n_cylinders}", file=str(res.path))
    line_orders.check_column(res, scene, args)
    out = output_folder(args.output, res.path.parent)
    stem = result_stem(res.path)
    line_paths = line_orders.plan(scene, args, out, stem)
    try:
        ro = run_orders(scene, traj, n, cuts=cuts, detrend=args.detrend,
                        piston_cylinder=args.cylinder)
    except NoWholeCycle as exc:
        raise SceneError("(trajectory)", str(exc), file=str(res.path)) from None
    spec_w, spec_m, rep, per_cyl = ro.omega, ro.gas_torque, ro.piston, ro.cylinder_torques
    k_w = args.cylinder
    starts, means, n_cyc, detrend = ro.cycle_start, ro.omega_mean, ro.cycles, ro.detrend
    rpm = 30.0 / math.pi
    orders = ro.orders
    top = args.max_order
    written = []
    cols_csv = {"order": orders, "omega_amplitude_rad_s": spec_w.amplitude[-1],
                "omega_phase_rad": spec_w.phase[-1]}
    if spec_m is not None:
        cols_csv["M_gas_amplitude_Nm"] = spec_m.amplitude[-1]
        cols_csv["M_gas_phase_rad"] = spec_m.phase[-1]
    if per_cyl is not None:
        for k in range(per_cyl.coef.shape[0]):
            cols_csv[f"M_cylinder_{k + 1}_amplitude_Nm"] = per_cyl.amplitude[k]
            cols_csv[f"M_cylinder_{k + 1}_phase_rad"] = per_cyl.phase[k]
    if rep is not None:  # W_k: cylinder k's piston acceleration, as [analysis] orders names it
        col = f"W_{args.cylinder}"
        cols_csv[f"{col}_amplitude_m_s2"] = rep.amplitude[-1]
        cols_csv[f"{col}_amplitude_constant_m_s2"] = rep.amplitude_constant[-1]
        cols_csv[f"{col}_relative"] = rep.relative[-1]
        cols_csv[f"{col}_relative_constant"] = rep.relative_constant[-1]
        cols_csv[f"{col}_relative_added"] = rep.relative_added[-1]
    csv = out / f"{stem}_orders.csv"
    write_columns(csv, cols_csv, args.force)
    written.append(csv)

    for name, fig in figures(res, ro, top, args.cylinder):
        written.append(save(fig, out / f"{stem}_{name}.png", args.force, res))
    if n_cyc >= 2:
        amp = spec_w.amplitude
        run = {"cycle": np.arange(1, n_cyc + 1), "cycle_start_rad": starts,
               "cycle_omega_mean_rad_s": means}
        run.update({f"omega_order_{orders[j]:g}_rad_s": amp[:, j]
                    for j in orders_up_to(orders, top)})
        csv = out / f"{stem}_orders_runup.csv"
        write_columns(csv, run, args.force)
        written.append(csv)

    print(f"{res.path}: orders over the last whole cycle (φ = {starts[-1]:.6g} … "
          f"{starts[-1] + mech.cycle:.6g} rad, {n} points; {n_cyc} whole cycle(s); ω spectra "
          f"{'detrended (ramp)' if detrend == 'ramp' else 'not detrended'})")
    print(f"  δ = {ro.delta:.12g} (last cycle, (ω_max − ω_min)/ω_mean), cycle-mean ω = "
          f"{means[-1]:.6g} rad/s ({means[-1] * rpm:.6g} rpm)")
    print("  ω, strongest orders: " + ", ".join(
        f"{orders[j]:g}: {spec_w.amplitude[-1][j]:.4g} rad/s"
        for j in strongest_orders(orders, spec_w.amplitude[-1], top)))
    if spec_m is not None:
        print(f"  M_gas (mean {spec_m.mean[-1]:.6g} N m), strongest orders: " + ", ".join(
            f"{orders[j]:g}: {spec_m.amplitude[-1][j]:.4g} N m"
            for j in strongest_orders(orders, spec_m.amplitude[-1], top)))
    if per_cyl is not None:
        for k in range(per_cyl.coef.shape[0]):
            print(f"  cylinder {k + 1} torque (mean {per_cyl.mean[k]:.6g} N m), strongest "
                  f"orders: " + ", ".join(f"{orders[j]:g}: {per_cyl.amplitude[k][j]:.4g} N m"
                                          for j in strongest_orders(orders, per_cyl.amplitude[k],
                                                                    top, 4)))
    if rep is not None:
        print(f"  piston acceleration W of cylinder {k_w}, relative to its first order "
              f"(|W₁| = {rep.first[-1]:.6g} m/s²), against the same engine at constant "
              f"ω̄ = {rep.omega_mean[-1]:.6g} rad/s:")
        print(f"  {'order':>6} {'|W| [m/s²]':>12} {'rel. run':>10} {'rel. ω̄':>10} "
              f"{'added':>10}  kind")
        for r in rep.table(-1, max_order=top):
            print(f"  {r['order']:6g} {r['amplitude']:12.5g} {r['relative']:10.3e} "
                  f"{r['relative_constant']:10.3e} {r['relative_added']:10.3e}  {r['kind']}")
        if rep.drift[-1] and abs(rep.drift[-1]) > 1e-6 * rep.first[-1]:
            print(f"  (the cycle is not periodic: W drifts by {rep.drift[-1]:.3g} m/s² across "
                  f"it, which leaks into every order)")
    if line_paths is not None:
        written += line_orders.write(res, scene, args, line_paths, cuts)
    for w in written:
        print(f"wrote {w}")
    return EXIT_OK
