"""Energy gained per cycle by one cylinder with a pressure table, against ∮p dV, over rtol:
tables from points (linear, pchip, spline; 21 angles, no corners declared) with every knot a
breakpoint; ``pulse``: the smooth pulse of ``tests/validation/test_energy.py`` on a 1° spline
(every knot a breakpoint too); and the Gots mixed cycle, whose 0.125° spline knots stay inside
steps. With
``--other`` each gets the other treatment of its knots, for comparison: the tables from points
stepped across (as before every knot was a breakpoint), the mixed cycle stopped on every knot.

The scene and the reference are those of ``tests/validation/test_table_knots.py``; ∮p dV here is
Gauss–Legendre (20 points) of (p − p0)·dV/dx on every knot interval of the table the run uses
(its numpy twin), dV/dx differentiated by hand from the crank slider's volume.
Rerun: ``.venv/bin/python tools/table_knots_energy.py linear pchip spline pulse mixed
[--other]``.
"""
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

import transient.forces.gas as gas
import transient.scene.queries as queries
from transient.run import integrate
from transient.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "validation"))
import test_table_knots as case  # noqa: E402
from test_energy import smooth_gas  # noqa: E402

RTOLS = (1e-6, 1e-8, 1e-10, 1e-12)


def scene_of(kind: str, rtol: float):
    if kind in ("linear", "pchip", "spline"):
        return case.scene_with_table(kind, rtol)
    if kind == "pulse":
        return replace(case.scene_with_table("spline", rtol), gas=smooth_gas())
    mixed = load_scene(ROOT / "cases" / "gots_diesel_governed.toml").gas
    return replace(case.scene_with_table("linear", rtol), gas=mixed)


def cycle_work(scene) -> float:
    """∮(p − p0) dV over the table's knot intervals [J]."""
    table = queries.gas_table(scene)
    m = scene.mechanism
    r, l, e, area = m.crank_radius, m.rod_length, m.offset, m.piston_area
    nodes, weights = np.polynomial.legendre.leggauss(20)
    a, b = table.knots[:-1, None], table.knots[1:, None]
    x = 0.5 * (a + b) + 0.5 * (b - a) * nodes
    sb = (r * np.sin(x) - e) / l
    dv = area * (r * np.sin(x) + r * np.cos(x) * sb / np.sqrt(1.0 - sb * sb))
    return float(np.sum(0.5 * (b - a) * weights * (table(x) - scene.gas.p0) * dv))


def main(argv) -> None:
    other = "--other" in argv
    kinds = [a for a in argv if not a.startswith("--")]
    if other:
        every_knot = gas.every_knot_a_corner
        gas.every_knot_a_corner = lambda table: table
        mixed_cycle = queries.mixed_cycle
        queries.mixed_cycle = lambda *a, **k: every_knot(mixed_cycle(*a, **k))
    for kind in kinds:
        for rtol in RTOLS:
            scene = scene_of(kind, rtol)
            work = cycle_work(scene)
            data = integrate(scene)
            gain = case.energy_gain(data) / case.CYCLES
            print(f"{kind:7s} {'other' if other else 'default':7s} rtol {rtol:.0e}: "
                  f"relative error {abs(gain - work) / abs(work):.2e}, "
                  f"{data.solver['nfev']} right-hand sides, {data.solver['nsteps']} steps, "
                  f"{data.solver['nreject']} rejected", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
