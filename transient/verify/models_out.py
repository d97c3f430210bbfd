"""What the friction models cost the scenes that do not use them, measured against a build
without them: a copy of this package whose compiled core has every test of a reaction pair
(``m.reaction``), an efficiency map (``m.eta_table``) and the stuck mode (``st.STUCK``,
``loop._stick``, the release) made a constant False, so that LLVM drops the code behind it.
A scene without those models runs the same steps and right-hand sides in both builds, so the
difference in wall time is what the models' presence costs it.

``transient bench --targets`` records it (:func:`friction_models_cost`); ``tools/ab_models.py``
runs ``tools/ab_wall.py`` on both builds. The copy's kernels compile once per version, cold,
into the cache of its own sources. Each pattern of :data:`LEFT_OUT` must match as often as it
says (``tests/unit/test_bench_targets.py`` holds this for the sources as they are).
"""
from __future__ import annotations

import json
import os
import re
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1]

#: (file under ``transient/core``, pattern, replacement, matches): the models' tests, made False.
LEFT_OUT = [
    *((f, r"\bm\.reaction\b", "(False and m.reaction)", n) for f, n in (
        ("model/forcing.py", 3), ("model/inverse.py", 2), ("model/outputs.py", 2),
        ("model/rhs.py", 9), ("model/stuck.py", 2))),
    *((f, r"\bm\.eta_table\b", "(False and m.eta_table)", n) for f, n in (
        ("model/inverse.py", 1), ("model/rhs.py", 3), ("model/stuck.py", 1))),
    ("model/rhs.py", r"sw\[SW_DIRECTION\] == st\.STUCK", "False", 1),
    ("model/rhs.py", r"sigma == st\.STUCK", "False", 1),
    ("stepper/loop.py", r"ist\[I_DIRECTION\] == st\.STUCK", "False", 1),
    ("stepper/loop.py", r"sw\[SW_DIRECTION\] == st\.STUCK and", "False and", 1),
    ("stepper/loop.py", r"and not _stick\(m, extras, cfg, y, evbuf, ist, wk\)", "and True", 2),
    ("stepper/loop.py", r"ev_code == EV_RELEASED:", "ev_code == EV_RELEASED and False:", 1),
]

#: The scenes timed, by name (in ``cases/``): without friction, the plain variant of the kernels
#: and the full one (a PI governor, latched fuel); with constant-η pairs, for comparison.
SCENES = {"coasting_single": "plain variant, no friction",
          "gots_diesel_pi": "full variant, no friction",
          "gots_diesel_governed": "constant-η pairs"}
#: Those of :data:`SCENES` without friction pairs, which are to pay nothing for the models.
WITHOUT_FRICTION = ("coasting_single", "gots_diesel_pi")

_TIMING = """
import json, sys
from transient.run import integrate
from transient.scene import load_scene
from transient.verify.targets import timed_scene
scene = timed_scene(load_scene(sys.argv[1]), float(sys.argv[2]))
integrate(scene, keep=False)
runs = [integrate(scene, keep=False).solver for _ in range(int(sys.argv[3]))]
print(json.dumps({"walls": [r["wall_s"] for r in runs], "nfev": runs[0]["nfev"]}))
"""


def left_out_copy(dest: Path) -> Path:
    """This package copied to ``dest/transient`` with the friction models' tests made False
    (:data:`LEFT_OUT`); returns ``dest``, the folder to put first on ``PYTHONPATH``. A pattern
    that matches another number of times raises ValueError naming it."""
    target = dest / "transient"
    shutil.copytree(PACKAGE, target, ignore=shutil.ignore_patterns("__pycache__"))
    for name, pattern, new, expected in LEFT_OUT:
        path = target / "core" / name
        text, n = re.subn(pattern, new, path.read_text(encoding="utf-8"))
        if n != expected:
            raise ValueError(f"transient/core/{name}: {pattern!r} matches {n} time(s), not "
                             f"{expected} (transient.verify.models_out.LEFT_OUT)")
        path.write_text(text, encoding="utf-8")
    return dest


def _timed(scene: Path, revolutions: float, repeat: int, path: Path | None) -> dict:
    """Integration walls of ``repeat`` runs of ``scene`` in a new process, importing transient
    from ``path`` (None: this build), after a warm-up run."""
    env = dict(os.environ)
    if path is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(path), env.get("PYTHONPATH", "")]).rstrip(
            os.pathsep)
    run = subprocess.run([sys.executable, "-c", _TIMING, str(scene), str(revolutions),
                          str(repeat)], env=env, capture_output=True, text=True, check=True)
    return json.loads(run.stdout.splitlines()[-1])


def friction_models_cost(cases: Path, tmp: Path, scenes=tuple(SCENES), rounds=5, repeat=3,
                         revolutions=1000.0) -> list[dict]:
    """Per scene of ``scenes`` (names of :data:`SCENES`): the median integration wall of this
    build and of the build without the friction models (:func:`left_out_copy` in ``tmp``),
    ``rounds`` alternating processes of ``repeat`` runs each, the relative change and this
    build's interquartile range; the RHS calls of both, which agree where the models are unused."""
    copy = left_out_copy(tmp)
    rows = []
    for name in scenes:
        what = SCENES[name]
        scene = cases / f"{name}.toml"
        walls: dict[str, list[float]] = {"this": [], "out": []}
        nfev = {}
        for _ in range(rounds):
            for side, path in (("this", None), ("out", copy)):
                t = _timed(scene, revolutions, repeat, path)
                walls[side] += t["walls"]
                nfev[side] = t["nfev"]
        this, out = statistics.median(walls["this"]), statistics.median(walls["out"])
        q1, _, q3 = statistics.quantiles(walls["this"], n=4)
        rows.append({"scene": name, "what": what, "this_s": this, "left_out_s": out,
                     "change": this / out - 1.0, "iqr": (q3 - q1) / this,
                     "nfev": nfev["this"], "nfev_left_out": nfev["out"]})
    return rows
