"""``transient kinematics``: positions, transfer functions, J and dJ/dφ over one cycle."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from .common import (
    EXIT_OK,
    MAX_POINTS,
    add_force,
    check_output_file,
    output_file,
    pyplot,
    save,
    whole,
)


def register(sub) -> None:
    k = sub.add_parser("kinematics", help="tabulate positions, transfer functions, J and dJ/dφ")
    k.add_argument("scene")
    k.add_argument("-o", "--output", default=None, help="CSV file (default: standard output)")
    k.add_argument("--points", type=whole(2, MAX_POINTS), default=361,
                   help="points over one cycle (default 361)")
    k.add_argument("--plot", default=None, help="also write a PNG of the transfer functions and J")
    add_force(k)
    k.set_defaults(func=cmd_kinematics)


def cmd_kinematics(args) -> int:
    from ..scene import load_scene

    scene = load_scene(args.scene)
    for path in filter(None, (args.output, args.plot)):
        check_output_file(path, args.force)
    mech = scene.mechanism
    phi = np.linspace(0.0, mech.cycle, args.points)
    table = _with_constant_inertia(mech.kinematics_table(phi), scene.inertia.total)
    header = ",".join(table)
    data = np.column_stack(list(table.values()))
    if args.output:
        with output_file(args.output, args.force) as fh:
            np.savetxt(fh, data, delimiter=",", header=header, comments="", fmt="%.12g")
        print(f"wrote {args.output}")
    else:
        np.savetxt(sys.stdout, data, delimiter=",", header=header, comments="", fmt="%.12g")
    if args.plot:
        plt = pyplot()

        from .. import plots

        fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        plots.transfer_functions(a1, table)
        plots.reduced_inertia(a2, table)
        a1.set_title(f"{scene.name}: transfer functions and reduced inertia")
        # (a table on standard output stays a clean CSV: the message goes to standard error)
        print(f"wrote {save(fig, Path(args.plot), args.force)}", file=sys.stderr if not args.output else sys.stdout)
    return EXIT_OK


def _with_constant_inertia(table: dict, constant: float) -> dict:
    """The mechanism's table with ``J`` as a result's ``J`` is — the whole machine's reduced
    inertia, the ``[inertia]`` constants included — and the linkage's own as ``J_mechanism``."""
    out = {}
    for name, values in table.items():
        if name == "J":
            out["J"] = values + constant
            out["J_mechanism"] = values
        else:
            out[name] = values
    return out
