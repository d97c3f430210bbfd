"""``transient bench``: wall time of the compiled path against the solve_ivp reference path.

For each scene, at ``rtol`` (1e-8): the compiled path is compiled once (compile time reported
apart) and timed ``repeat`` times (median) over ``revolutions`` (1000); the reference path (plain
numpy + ``scipy.integrate.solve_ivp``, DOP853 and RK45) is timed once over ``baseline_revolutions``
(100, as it is some 100× slower), and so is the compiled path over the same length, in the same
process: the ratio compares equal runs. The cost per revolution does not depend on the run length
(constant speed after the spin-up), so "per 1000 revolutions" of the baselines is their time × 10,
stated as such. The error of each run against a tight compiled run of the same length
(rtol 1e-12) is reported beside its time. Issue 5 extends this to the full work-precision record.
"""
from __future__ import annotations

import dataclasses as dc
import statistics
import time
from pathlib import Path

from .scene import load_scene
from .simulate import integrate

DEFAULT_SCENES = ("cases/gots_diesel_spinup.toml", "cases/gots_diesel_friction.toml",
                  "cases/swash_plate_4cyl.toml")


def _with(scene, method, rtol, revolutions):
    return dc.replace(scene, run=dc.replace(scene.run, revolutions=revolutions, t_end=float("inf")),
                      solver=dc.replace(scene.solver, method=method, rtol=rtol, atol=rtol * 1e-2))


def _timed(scene, repeat):
    walls, data = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        data = integrate(scene)
        walls.append(time.perf_counter() - t0)
    return statistics.median(walls), data


def _error(data, ref) -> tuple[float, float]:
    """Relative errors of the end time (phase) and the end speed against the tight run."""
    t, w = data.trajectory["t"][-1], data.trajectory["omega"][-1]
    t_ref, w_ref = ref.trajectory["t"][-1], ref.trajectory["omega"][-1]
    return abs(t / t_ref - 1), abs(w / w_ref - 1)


def _row(scene_name, label, revs, wall, data, ref):
    return dict(scene=scene_name, path=label, revs=revs, wall=wall,
                compile=data.solver["compile_s"], nfev=data.solver["nfev"], err=_error(data, ref))


def run_bench(scenes=DEFAULT_SCENES, revolutions=1000.0, rtol=1e-8, repeat=5, baselines=True,
              out=None, baseline_revolutions=100.0) -> list[dict]:
    """Measure and return one row per (scene, path, length); print a markdown table."""
    rows = []
    for path in scenes:
        scene = load_scene(path)
        name = Path(path).stem
        fast = _with(scene, "dop853", rtol, revolutions)
        compile_s = integrate(fast).solver["compile_s"]  # warm-up: compile or load the cache
        wall, data = _timed(fast, repeat)
        rows.append(_row(name, "compiled DOP853", revolutions, wall, data,
                         integrate(_with(scene, "dop853", 1e-12, revolutions))))
        rows[-1]["compile"] = compile_s
        if not baselines:
            continue
        ref = integrate(_with(scene, "dop853", 1e-12, baseline_revolutions))
        short = _with(scene, "dop853", rtol, baseline_revolutions)
        wall, data = _timed(short, repeat)
        rows.append(_row(name, "compiled DOP853", baseline_revolutions, wall, data, ref))
        for method in ("scipy-DOP853", "scipy-RK45"):
            wall, data = _timed(_with(scene, method, rtol, baseline_revolutions), 1)
            rows.append(_row(name, f"solve_ivp {method[6:]} (Python RHS)", baseline_revolutions,
                             wall, data, ref))
    lines = [f"rtol = {rtol:g}, atol = rtol/100; compiled: median of {repeat} runs after a "
             f"warm-up; solve_ivp: one run. Errors against the compiled path at rtol 1e-12 over "
             f"the same revolutions. compile: the first run's compile or cache load. Python RHS: "
             f"plain numpy for the crank-slider, the kernel's pure-Python code for the swash "
             f"plate.",
             "", "| scene | path | revolutions | wall [s] | per 1000 rev [s] | × compiled | "
             "compile [s] | RHS calls | phase error | ω error |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        base = next(x["wall"] for x in rows if x["scene"] == r["scene"] and x["revs"] == r["revs"])
        lines.append(f"| {r['scene']} | {r['path']} | {r['revs']:g} | {r['wall']:.4g} | "
                     f"{r['wall'] * 1000 / r['revs']:.4g} | {r['wall'] / base:.0f} | "
                     f"{r['compile']:.3g} | {r['nfev']} | {r['err'][0]:.1e} | {r['err'][1]:.1e} |")
    text = "\n".join(lines)
    print(text)
    if out:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        Path(out).write_text(text + "\n")
    return rows
