"""``transient modes``: the torsional modes and critical speeds of a scene's shaft line, without
running it (:mod:`transient.analysis.torsion`), and its Campbell diagram; with ``--response``
its steady forced response to the engine's orders over the speed range
(:mod:`transient.analysis.torsional_response`); with ``--floquet`` its parametric stability,
the Floquet multipliers of the variable-inertia line over the speed range
(:mod:`transient.analysis.floquet`)."""
from __future__ import annotations

import math
from pathlib import Path

from ..errors import SceneError
from .common import (
    EXIT_OK,
    MAX_RPM,
    add_force,
    check_output_file,
    number_list,
    output_folder,
    pyplot,
    real,
    save,
    whole,
    write_columns,
)

#: Speeds of ``--response`` by default: 5 rpm apart over the case's 800–4400 rpm, fine enough
#: for a resonance of a few per cent damping.
RESPONSE_SPEEDS = 721
#: Speeds of ``--floquet`` by default: 20 rpm apart over the case's 800–4400 rpm; a principal
#: region a few per cent of its speed wide spans several of them.
FLOQUET_SPEEDS = 181


def register(sub) -> None:
    m = sub.add_parser("modes", help="a shaft line's torsional modes, criticals and response")
    m.add_argument("scene")
    m.add_argument("-o", "--output", default="results", help="output folder (default results/)")
    m.add_argument("--speed-range", default=None, metavar="LO,HI",
                   help="speeds [rpm] whose critical speeds are listed (default: the scene's "
                        "[shaft] speed_range, else 0 to 1.2 × its highest speed)")
    m.add_argument("--max-order", type=real(gt=0.0, le=1000.0), default=12.0,
                   help="highest engine order [1/rev] (default 12)")
    m.add_argument("--csv", action="store_true",
                   help="also write the modes and the critical speeds as CSV")
    m.add_argument("--response", action="store_true",
                   help="also the steady forced response at constant inertia over the speed "
                        "range: a table (CSV) and a figure of each element's vibratory torque")
    m.add_argument("--floquet", action="store_true",
                   help="also the parametric stability over the speed range: the Floquet "
                        "multipliers of the line with each station's varying inertia, a table "
                        "(CSV) and a chart of the twist's growth per revolution")
    m.add_argument("--speeds", type=whole(2, 100_000), default=None, metavar="N",
                   help=f"speeds of the response and of the stability chart, evenly over the "
                        f"range (default {RESPONSE_SPEEDS} for the response, the critical "
                        f"speeds added; {FLOQUET_SPEEDS} for the chart)")
    add_force(m)
    m.set_defaults(func=cmd_modes)


def cmd_modes(args) -> int:
    import numpy as np

    from .. import plots
    from ..analysis.torsion import critical_speeds, engine_orders, modal_analysis, speed_range
    from ..analysis.torsional_response import check_steady
    from ..scene import load_scene
    from ..shaft import ShaftLine

    scene = load_scene(args.scene)
    if scene.shaft is None:
        raise SceneError("shaft", "the scene has no [shaft] table: its shaft is rigid and has no "
                                  "torsional modes; describe the shaft line (docs: Torsion)",
                         file=args.scene)
    rpm_range = _speed_range(args.speed_range) if args.speed_range else speed_range(scene)
    line = ShaftLine(scene)
    out = output_folder(args.output, Path("results"))
    stem = Path(args.scene).stem
    paths = {"figure": out / f"{stem}_campbell.png"}
    if args.csv:
        paths.update(modes=out / f"{stem}_modes.csv", criticals=out / f"{stem}_criticals.csv")
        if np.any(line.C):
            paths.update(damped_criticals=out / f"{stem}_damped_criticals.csv")
    if args.speeds is not None and not (args.response or args.floquet):
        raise SceneError("--speeds", "sets the speeds of the forced response and the stability "
                                     "chart; add --response or --floquet, or leave --speeds out")
    if args.response:
        check_steady(scene)
        paths.update(response=out / f"{stem}_response.csv",
                     response_figure=out / f"{stem}_response.png")
    if args.floquet:
        paths.update(floquet=out / f"{stem}_floquet.csv",
                     floquet_figure=out / f"{stem}_floquet.png")
    for path in paths.values():  # (before any work: nothing is overwritten without --force)
        check_output_file(path, args.force)

    modal = modal_analysis(line)
    orders = engine_orders(scene.mechanism.cycle, args.max_order)
    criticals = critical_speeds(modal, orders, rpm_range)
    damped = critical_speeds(modal, orders, rpm_range, damped=True)
    _print_modes(scene, modal)
    _print_criticals(criticals, rpm_range)
    if modal.damped:
        _print_criticals(damped, rpm_range, "of the damped line (mode: its number among the "
                                            "damped modes, at f_n)")

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 6))
    plots.modal_campbell(ax, modal, orders, rpm_range, criticals)
    ax.set_title(f"{scene.name}: Campbell diagram of the shaft line")
    written = [save(fig, paths["figure"], args.force)]
    if args.csv:
        cols = {"mode": np.array([m.number for m in modal.modes]),
                "f_Hz": np.array([m.f for m in modal.modes]),
                "band_low_Hz": np.array([m.band[0] for m in modal.modes]),
                "band_high_Hz": np.array([m.band[1] for m in modal.modes])}
        cols.update({f"shape_{name}": np.array([m.shape[i] for m in modal.modes])
                     for i, name in enumerate(line.names)})
        write_columns(paths["modes"], cols, args.force)
        written.append(paths["modes"])
        for name, listed in (("criticals", criticals), ("damped_criticals", damped)):
            if name in paths:
                _write_criticals(paths[name], listed, args.force)
                written.append(paths[name])
    if args.response:
        written += _response(line, orders, rpm_range, criticals, args, paths)
    if args.floquet:
        written += _floquet(line, modal, rpm_range, args, paths)
    for path in written:
        print(f"wrote {path}")
    return EXIT_OK


def _speed_range(text: str) -> tuple[float, float]:
    values = number_list(text, "--speed-range", -1e-300, MAX_RPM)
    if len(values) != 2 or not values[0] < values[1]:
        raise SceneError("--speed-range", f"give two speeds LO,HI [rpm] with LO < HI, got "
                                          f"{text!r}")
    return values[0], values[1]


def _print_modes(scene, modal) -> None:
    line = modal.line
    print(f"{scene.name}: shaft line of {len(line.shaft.stations)} stations, {line.n} degrees of "
          f"freedom, at cycle-mean inertias; {modal.rigid} rigid mode(s) at 0 Hz")
    print(f"{'mode':>4} {'f [Hz]':>10} {'frozen band [Hz]':>21}  largest amplitude / twist")
    for m in modal.modes:
        print(f"{m.number:4d} {m.f:10.4g} {m.band[0]:10.4g} – {m.band[1]:<8.4g}  {m.largest_at} / "
              f"{m.twist_at}")
    if modal.damped:
        print(f"damped: {'f_n [Hz]':>10} {'ζ':>8} {'f_d [Hz]':>10}"
              + (f"  ({modal.creeping} real eigenvalue(s): rigid or creeping motions)"
                 if modal.creeping else ""))
        for d in modal.damped:
            print(f"        {d.omega_n / (2 * math.pi):10.4g} {d.zeta:8.4f} "
                  f"{d.omega_d / (2 * math.pi):10.4g}")


def _write_criticals(path, criticals, force: bool) -> None:
    import numpy as np

    kinds = {"major": 0, "integer": 1, "half": 2}
    write_columns(path, {
        "mode": np.array([c.mode for c in criticals]),
        "order": np.array([c.order for c in criticals]),
        "kind_major0_integer1_half2": np.array([kinds[c.kind] for c in criticals]),
        "rpm": np.array([c.rpm for c in criticals]),
        "relative_excitation": np.array([c.excitation for c in criticals])}, force)


def _print_criticals(criticals, rpm_range, which: str = "") -> None:
    lo, hi = rpm_range
    print(f"critical speeds {which + ' ' if which else ''}from {lo:g} to {hi:g} rpm (relative "
          f"excitation: the vector sum of the mode's amplitudes at the cylinders, 0 … 1):")
    if not criticals:
        print("  none")
    print(f"  {'rpm':>9} {'mode':>4} {'order':>6} {'kind':>8} {'excitation':>10}")
    for c in criticals:
        print(f"  {c.rpm:9.1f} {c.mode:4d} {c.order:6g} {c.kind:>8} {c.excitation:10.3f}")


def _response(line, orders, rpm_range, criticals, args, paths) -> list[Path]:
    """The forced response over ``rpm_range``: its summary printed, its table and figure
    written; returns their paths."""
    import numpy as np

    from .. import plots
    from ..analysis.torsional_response import forced_response, speed_grid

    points = args.speeds or RESPONSE_SPEEDS
    res = forced_response(line, speed_grid(rpm_range, points, criticals), orders)
    _print_response(res)
    cols = {"rpm": res.rpm}
    for e, label in enumerate(res.elements):
        name = label.replace(",", ";")
        cols[f"{name} peak-to-peak [N m]"] = res.torque_pp[:, e]
        cols[f"{name} sum of orders [N m]"] = res.torque_sum[:, e]
        if np.any(res.power[:, :, e]):
            cols[f"{name} power [W]"] = res.power[:, :, e].sum(axis=1)
    for e, label in enumerate(res.elements):
        for j, q in enumerate(res.orders):
            cols[f"{label.replace(',', ';')} order {q:g} [N m]"] = np.abs(res.torque[:, j, e])
    write_columns(paths["response"], cols, args.force)
    plt = pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(11, 8), sharex=True)
    plots.torsional_response(axes, res, criticals)
    fig.suptitle(f"{line.scene.name}: steady forced response at constant inertia (full load)")
    return [paths["response"], save(fig, paths["response_figure"], args.force)]


def _print_response(res) -> None:
    import numpy as np

    print(f"steady forced response at {res.rpm.size} speeds from {res.rpm[0]:.6g} to "
          f"{res.rpm[-1]:.6g} rpm, orders {res.orders[0]:g} … {res.orders[-1]:g}, full load, "
          f"cycle-mean inertias:")
    print(f"  {'element':<34} {'peak-to-peak [N m]':>18} {'at [rpm]':>9} {'leading order':>13}"
          f" {'its amplitude [N m]':>19}")
    for e, label in enumerate(res.elements):
        i = int(np.argmax(res.torque_pp[:, e]))
        j = int(np.argmax(np.abs(res.torque[i, :, e])))
        print(f"  {label:<34} {res.torque_pp[i, e]:18.5g} {res.rpm[i]:9.1f} "
              f"{res.orders[j]:13g} {abs(res.torque[i, j, e]):19.5g}")
        total = res.power[:, :, e].sum(axis=1)
        if label.startswith("damper") and np.any(total):
            k = int(np.argmax(total))
            print(f"  {'':<34} dissipates at most {total[k]:.5g} W, at {res.rpm[k]:.1f} rpm")


def _floquet(line, modal, rpm_range, args, paths) -> list[Path]:
    """The stability chart over ``rpm_range``: its summary printed, its table and figure
    written; returns their paths."""
    import numpy as np

    from .. import plots
    from ..analysis.floquet import floquet_chart, parametric_resonances
    from ..analysis.torsional_response import speed_grid

    res = floquet_chart(line, speed_grid(rpm_range, args.speeds or FLOQUET_SPEEDS))
    marks = parametric_resonances(line, [m.f for m in modal.modes], rpm_range)
    _print_floquet(res)
    cols = {"rpm": res.rpm, "mu_max": res.mu_max, "growth_per_rev": res.growth_per_rev,
            "unstable": res.unstable.astype(float)}
    cols.update({f"mu_abs_{i + 1}": np.abs(res.multipliers[:, i])
                 for i in range(res.multipliers.shape[1])})
    write_columns(paths["floquet"], cols, args.force)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(11, 5.5))
    plots.floquet_chart(ax, res, marks)
    ax.set_title(f"{line.scene.name}: parametric stability of the shaft line (Floquet, inertias "
                 f"varying with each station's angle)")
    return [paths["floquet"], save(fig, paths["floquet_figure"], args.force)]


def _print_floquet(res) -> None:
    import numpy as np

    period = 360.0 / res.g
    print(f"parametric stability at {res.rpm.size} speeds from {res.rpm[0]:.6g} to "
          f"{res.rpm[-1]:.6g} rpm (Floquet multipliers over the inertias' period, {period:g}°, "
          f"the line's rigid motion held at the mean speed):")
    worst = int(np.argmax(res.mu_max))
    ranges = res.unstable_ranges()
    if not ranges:
        print(f"  stable at every speed; largest |μ| {res.mu_max[worst]:.6f} at "
              f"{res.rpm[worst]:.1f} rpm")
    for lo, hi in ranges:
        sel = (res.rpm >= lo) & (res.rpm <= hi)
        k = int(np.argmax(np.where(sel, res.mu_max, -np.inf)))
        print(f"  unstable from {lo:.1f} to {hi:.1f} rpm: largest |μ| {res.mu_max[k]:.6f} at "
              f"{res.rpm[k]:.1f} rpm, the twist growing {res.growth_per_rev[k]:.3g} e-folds per "
              f"revolution")
