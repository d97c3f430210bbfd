"""``transient warmup``: on an empty cache it compiles, one line per kernel, what runs of every
mechanism and mode then load without compiling anything; a second warm-up finds all cached."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"

PROBE = """
import dataclasses as dc, sys
from transient.run import simulate
from transient.scene import load_scene
from transient.warmup import CompileLog
with CompileLog() as log:
    for path in sys.argv[1:]:
        scene = load_scene(path)
        simulate(dc.replace(scene, run=dc.replace(scene.run, revolutions=0.5, t_end=float("inf"))))
print(len(log.compiled), *(c.name for c in log.compiled))
"""


def test_warmup_compiles_what_runs_then_load(tmp_path):
    env = {**os.environ, "TRANSIENT_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("NUMBA_CACHE_DIR", None)

    def transient(*argv, code=None) -> list[str]:
        cmd = [sys.executable, "-m", "transient", *argv] if code is None else \
            [sys.executable, "-c", code, *argv]
        run = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=1200)
        assert run.returncode == 0, run.stderr
        return run.stdout.splitlines()

    mechanisms = [str(CASES / f"{c}.toml") for c in ("swash_plate_4cyl", "radial_5cyl")]
    lines = transient("warmup", *mechanisms)
    assert lines[0].startswith(f"kernels in {tmp_path / 'cache' / 'numba'}")
    compiled = [line.strip().split()[1] for line in lines[1:-1]]
    assert all(line.strip().startswith("compiled ") for line in lines[1:-1])
    assert {"transient.core.stepper.advance", "transient.core.rhs.derivative",
            "transient.core.inverse.inverse_dynamics"} <= set(compiled)
    assert lines[-1] == f"{len(compiled)} kernel(s) compiled"
    runs = [*mechanisms, *(str(CASES / f"{c}.toml") for c in (
        "coasting_single", "gots_diesel_governed", "gots_diesel_woschni", "gots_diesel_4400",
        "swash_plate_4cyl_friction", "gots_diesel_start_flyweight", "diesel_4cyl_misfire"))]
    assert transient(*runs, code=PROBE) == ["0"]
    assert transient("warmup")[1:] == ["all kernels were cached"]
