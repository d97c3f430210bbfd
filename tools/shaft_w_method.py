"""Steps and wall time per engine cycle of the compiled stepper on the elastic in-line six
(``cases/inline6_damper.toml``), DOP853 against the Rosenbrock–W method ROS34PW2 and ``"auto"``, and each run's
error against DOP853 at rtol 1e-12: on the case's line, and on the same line with a stiff front
end (the pulley's section stiffened until f_max/f_1 ≈ 40).

Prints per line its natural frequencies' range (``transient.analysis.torsion`` at the cycle-mean
inertias), and per method and rtol: steps per cycle, rejected steps, right-hand sides per cycle
(the W-method counts its Jacobian as one), wall time per cycle (the stepper's, compile
excluded), the steps of the run DOP853's stiffness test found held by stability
(``held_steps``: those after 15 in a row), the largest error of
the reference's ω and of the torque of the section between throws 3 and 4, relative to their
largest values, against the tight run on the same sample grid, and for ``"auto"`` which methods
ran (its trial's evaluations not counted). Each run is two cycles from
800 rpm, the first compiled apart (a run of a quarter turn) so that wall times hold no compile.

Rerun: ``.venv/bin/python tools/shaft_w_method.py [REVOLUTIONS]`` (4 by default).
"""
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

import transient
from transient.analysis.torsion import natural_modes
from transient.scene import load_scene
from transient.shaft import ShaftLine

CASE = Path(__file__).resolve().parents[1] / "cases" / "inline6_damper.toml"
CYCLE_REVS = 2.0
COLUMNS = ("omega", "torque_throw_3_throw_4")


def scene_with(scene, revolutions, **solver):
    return dataclasses.replace(scene, run=dataclasses.replace(scene.run, revolutions=revolutions),
                               solver=dataclasses.replace(scene.solver, **solver))


def stiff_front(scene, factor):
    first = dataclasses.replace(scene.shaft.sections[0],
                                stiffness=factor * scene.shaft.sections[0].stiffness)
    return dataclasses.replace(scene, shaft=dataclasses.replace(
        scene.shaft, sections=(first, *scene.shaft.sections[1:])))


def frequencies(scene):
    """The line's elastic natural frequencies [Hz] at the cycle-mean inertias."""
    line = ShaftLine(scene)
    omega, _ = natural_modes(line.K, line.mean_inertia(), line.rigid_modes)
    return omega[line.rigid_modes:] / (2 * math.pi)


def front_factor(scene, target=40.0):
    """The factor on the pulley's section that brings f_max/f_1 to ``target`` (bisection on
    its logarithm: f_max rises with it, f_1 hardly moves)."""
    lo, hi = 1.0, 1e4
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        f = frequencies(stiff_front(scene, mid))
        lo, hi = (mid, hi) if f[-1] / f[0] < target else (lo, mid)
    return math.sqrt(lo * hi)


def run(scene, revolutions, **solver):
    transient.simulate(scene_with(scene, 0.25, **solver))  # (compile or load, apart)
    return transient.simulate(scene_with(scene, revolutions, **solver))


def main():
    revolutions = float(sys.argv[1]) if len(sys.argv) > 1 else 4.0
    cycles = revolutions / CYCLE_REVS
    base = load_scene(CASE)
    factor = front_factor(base)
    for name, scene in (("case", base), (f"stiff front (pulley section x{factor:.1f})",
                                         stiff_front(base, factor))):
        f = frequencies(scene)
        print(f"{name}: f_1 = {f[0]:.1f} Hz, f_max = {f[-1]:.1f} Hz, f_max/f_1 = "
              f"{f[-1] / f[0]:.1f}")
        tight = run(scene, revolutions, method="dop853", rtol=1e-12, atol=1e-14).trajectory
        scale = {c: np.max(np.abs(tight[c])) for c in COLUMNS}
        print("  method    rtol   steps/cycle  rejected  nfev/cycle  wall/cycle [ms]  "
              "held  err omega  err torque")
        for rtol in (1e-6, 1e-8):
            for method in ("dop853", "ros34pw2", "auto"):
                res = run(scene, revolutions, method=method, rtol=rtol, atol=1e-2 * rtol)
                s, tr = res.solver, res.trajectory
                held = str(s["held_steps"])
                errors = [np.max(np.abs(tr[c] - tight[c])) / scale[c] for c in COLUMNS]
                print(f"  {method:9s} {rtol:.0e} {s['nsteps'] / cycles:11.0f} "
                      f"{s['nreject'] / cycles:9.0f} {s['nfev'] / cycles:11.0f} "
                      f"{1e3 * s['wall_s'] / cycles:16.2f} {held:>5s} {errors[0]:10.2e} "
                      f"{errors[1]:11.2e}  {s.get('ran', '').partition(' (')[0]}")


if __name__ == "__main__":
    main()
