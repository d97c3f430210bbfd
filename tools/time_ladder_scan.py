"""The stress suite's time-domain tolerance ladder, scanned finer than ``transient stress`` does,
with scipy's DOP853 beside it: on the Gots spin-up (40 revolutions, output every 1e-4 s, atol =
rtol/100), transient's compiled DOP853 in time and ``solve_ivp(method="DOP853")`` on the reference
path's numpy right-hand side, each against the compiled run at rtol 1e-13.

Columns: rtol; transient's largest error along the run (``stress.ladder_error``), its steps; the
final-state error (larger of |Δt|/t and |Δω|/ω, ``stress.end_error``) of transient and of scipy,
scipy's steps. Rerun: ``.venv/bin/python tools/time_ladder_scan.py``.
"""
import tempfile
import time
from pathlib import Path

from transient.verify.stress import Context, end_error, ladder_error, put, run_scene, spinup

RTOLS = (1e-3, 3e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6, 1e-7, 1e-8, 1e-9)


def build(rtol, **solver):
    d = put(spinup(40), "output", dt=1e-4)
    return put(d, "solver", rtol=rtol, atol=rtol * 1e-2, domain="time", **solver)


with tempfile.TemporaryDirectory() as out:
    ctx = Context(Path(out), time.monotonic() + 3600.0)
    ref = run_scene(build(1e-13), "ref", ctx)
    print("rtol    along-run  steps  end: transient  scipy     scipy steps")
    for rtol in RTOLS:
        mine = run_scene(build(rtol), f"c{rtol:.0e}", ctx)
        scipy = run_scene(build(rtol, method="scipy-DOP853"), f"s{rtol:.0e}", ctx)
        print(f"{rtol:.0e}  {ladder_error(mine, ref, 't'):.2e}   {mine.solver['nsteps']:5d}  "
              f"{end_error(mine, ref):.2e}       {end_error(scipy, ref):.2e}  "
              f"{scipy.solver['nsteps']:5d}")
