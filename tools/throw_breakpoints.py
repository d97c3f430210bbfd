"""Where an elastic run's rejected steps are: at the breakpoints of the throws' own angles, or
elsewhere; and its steps per cycle against the same scene with its sections stiffened (the
twist about zero, the step then held by the stiff sections' stability) and rigid.

The run is the bench's (``transient.verify.torsion.against_rigid``: the in-line six with its
damper, run up from 800 rpm at rtol 1e-8). It is driven one step attempt per call of the
stepper (``C_CHUNK_STEPS = 1``: where a chunk ends changes nothing in the run), so that each
rejected attempt (a retake aimed at a breakpoint counts as one) is seen with its start φ and
planned size h. A rejected attempt counts as *at a throw's breakpoint* where a breakpoint of a
cylinder, on its own station's angle θ_d = φ + q_d (q_d at the attempt's start), lies inside it
or within 1e-3 rad ahead of its end; the counts are by the corner's local angle.

Run: ``.venv/bin/python tools/throw_breakpoints.py [REVOLUTIONS]`` (default 20).
"""
import collections
import dataclasses as dc
import math
import sys

import numpy as np

from transient import assemble
from transient.core import stepper
from transient.core.integrator.tableaus import TABLEAUS
from transient.core.model import layout
from transient.core.stepper import io as sio
from transient.run import _config, _initial_state, integrate
from transient.scene import load_scene
from transient.scene.queries import gas_phases, gas_tables
from transient.shaft import rigid_equivalent
from transient.verify.bench import timed_scene
from transient.verify.torsion import ELASTIC_SCENE


def cylinder_corners(scene) -> np.ndarray:
    """The local angles of one cylinder's breakpoints (its tables' corners)."""
    table, motored = gas_tables(scene)
    return assemble.breakpoints(table, np.zeros(1), scene.mechanism.cycle, motored,
                                scene.gas.injection)


def attempts(scene):
    """Each step attempt of the run: (φ at its start, its planned size, accepted, the twist of
    the station carrying each cylinder at its start); and the stepper's integer state at the
    end."""
    model, bp, _ = assemble.build_model(scene)
    cfg = _config(scene)
    cfg[sio.C_CHUNK_STEPS] = 1
    tab = TABLEAUS[scene.solver.method]
    extras = layout.extras_of(model)
    y, fst, ist = _initial_state(scene, model)
    outbuf = np.empty((4096, layout.n_outputs(model)))
    evbuf = np.empty((256, 4))
    carrier = model.line[1:1 + model.ncyl, 0].astype(int)
    ref = int(model.line[0, layout.LM_REF])
    twist = layout.STATE.offsets_for(model)[layout.B_LINE]
    out = []
    status = sio.RUNNING
    while status == sio.RUNNING:
        phi, h, rejected = y[layout.PHI], fst[sio.F_H], ist[sio.I_NREJECT]
        q = np.array([0.0 if d == ref else y[twist + 2 * (d - (d > ref))] for d in carrier])
        status = stepper.advance(model, extras, tab, cfg, bp, y, fst, ist, outbuf, evbuf,
                                 stepper.buffers(model, tab, y.shape[0]))
        ist[sio.I_NOUT] = ist[sio.I_NEV] = 0
        out.append((phi, h, ist[sio.I_NREJECT] == rejected, q))
    return out, ist


def where_rejected(scene, reach=1e-3):
    """Per cycle: steps, rejected attempts, those at a throw's breakpoint and elsewhere, and
    the former by the corner's local angle [deg] (over the whole run)."""
    corners = cylinder_corners(scene)
    phases = gas_phases(scene)
    period = scene.mechanism.cycle
    steps, ist = attempts(scene)
    at_corner = collections.Counter()
    elsewhere = 0
    for phi, h, accepted, twist in steps:
        if accepted:
            continue
        local = np.mod(phi + twist - phases, period)  # each cylinder's own angle at the start
        ahead = np.mod(corners[None, :] - local[:, None], period)
        hit = np.argwhere(ahead <= h + reach)
        if hit.size:
            at_corner[round(math.degrees(corners[hit[0, 1]]), 3)] += 1
        else:
            elsewhere += 1
    cycles = scene.run.revolutions * 2 * math.pi / period
    return {"steps/cycle": round(ist[sio.I_NSTEPS] / cycles, 1),
            "rejected/cycle": round((sum(at_corner.values()) + elsewhere) / cycles, 1),
            "at a throw's breakpoint/cycle": round(sum(at_corner.values()) / cycles, 1),
            "elsewhere/cycle": round(elsewhere / cycles, 1),
            "by corner [deg]": dict(sorted(at_corner.items()))}


def counts(scene):
    """Steps, rejections and right-hand sides per cycle of a whole run."""
    solver = integrate(scene, keep=False).solver
    cycles = scene.run.revolutions * 2 * math.pi / scene.mechanism.cycle
    return {k: round(solver[k] / cycles, 1) for k in ("nsteps", "nreject", "nfev")}


def stiffened(scene, factor):
    """``scene`` with every section ``factor`` times stiffer."""
    shaft = scene.shaft
    sections = tuple(dc.replace(s, stiffness=s.stiffness * factor) for s in shaft.sections)
    return dc.replace(scene, shaft=dc.replace(shaft, sections=sections))


def main():
    revolutions = float(sys.argv[1]) if len(sys.argv) > 1 else 20.0
    scene = timed_scene(load_scene(ELASTIC_SCENE), revolutions)
    print("elastic, where rejected:", where_rejected(scene))
    print("elastic:", counts(scene))
    for factor in (1e2, 1e3):
        print(f"sections x{factor:g}:", counts(stiffened(scene, factor)))
    print("rigid:", counts(rigid_equivalent(scene)))


if __name__ == "__main__":
    main()
