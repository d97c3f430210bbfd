"""Equal tolerance against equal error: the bench's elastic run-up and its rigid equivalent
(``transient.verify.torsion.against_rigid``'s two scenes) at a ladder of rtol (atol = rtol·1e-3,
the targets' ratio), each against its own tight run (rtol 1e-13): steps, rejected attempts and
right-hand sides per cycle, and the error of the reference station's final time (as a phase,
× its final ω) and final ω. With ``VARIANTS=1`` also the elastic run with parts of the line's
states left out of the error control (the twists q_d, the energies K_d, both), to see which of
them hold the step. Nothing here changes a tolerance of the package: the control is replaced in
this process only (``state_control`` as the stepper's ``buffers`` reads it).

Run: ``.venv/bin/python tools/elastic_equal_error.py [REVOLUTIONS [RTOLS]]``
(defaults 200 and 1e-8; RTOLS comma-separated).
"""
import dataclasses as dc
import math
import os
import sys

import transient.core.stepper.loop as loop
from transient.core.declare import NOT_CONTROLLED
from transient.core.model import layout
from transient.run import integrate
from transient.scene import load_scene
from transient.shaft import rigid_equivalent
from transient.verify.bench import timed_scene
from transient.verify.torsion import ELASTIC_SCENE

ORIGINAL = layout.state_control
VARIANT = {"left out": None}


def controlled(m):
    """The state's error control, less the line's states VARIANT names."""
    c = ORIGINAL(m).copy()
    out = VARIANT["left out"]
    if out is None or layout.line_dofs(m) == 0:
        return c
    first, n = layout.line_index(m), 2 * (layout.line_dofs(m) - 1)
    if out in ("twists", "line"):
        c[first:first + n:2] = NOT_CONTROLLED
    if out in ("energies", "line"):
        c[first + 1:first + n:2] = NOT_CONTROLLED
    return c


def run(scene, rtol):
    scene = dc.replace(scene, solver=dc.replace(scene.solver, rtol=rtol, atol=rtol * 1e-3))
    data = integrate(scene, keep=False)
    tr = data.trajectory
    return data.solver, tr["t"][-1], tr["omega"][-1]


def main():
    revolutions = float(sys.argv[1]) if len(sys.argv) > 1 else 200.0
    rtols = [float(x) for x in (sys.argv[2].split(",") if len(sys.argv) > 2 else ["1e-8"])]
    loop.state_control = controlled
    elastic = timed_scene(load_scene(ELASTIC_SCENE), revolutions)
    rigid = rigid_equivalent(elastic)
    cycles = revolutions * 2.0 * math.pi / elastic.mechanism.cycle
    tight = {name: run(scene, 1e-13)[1:] for name, scene in (("elastic", elastic),
                                                             ("rigid", rigid))}
    rows = [("rigid", rigid, None), ("elastic", elastic, None)]
    if os.environ.get("VARIANTS"):
        rows += [("elastic", elastic, out) for out in ("twists", "energies", "line")]
    for rtol in rtols:
        for name, scene, out in rows:
            VARIANT["left out"] = out
            s, t, w = run(scene, rtol)
            t0, w0 = tight[name]
            label = name + (f", {out} not controlled" if out else "")
            print(f"rtol {rtol:.0e} {label:34s} {s['nsteps'] / cycles:7.1f} steps "
                  f"{s['nreject'] / cycles:5.1f} rejected {s['nfev'] / cycles:6.0f} RHS per "
                  f"cycle; phase error {abs(t - t0) * w0:.2e} rad, ω error {abs(w / w0 - 1):.2e}")


if __name__ == "__main__":
    main()
