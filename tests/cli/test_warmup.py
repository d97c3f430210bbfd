"""``transient warmup``: on an empty cache it compiles, one line per kernel, what runs of every
mechanism and mode then load without compiling anything; a second warm-up finds all cached.

Before it, on the same empty cache, a run of a plain scene compiles none of the kernels that only
the features it does not use need (the kernels' plain variant, ``transient.core.model.layout.extras_of``),
and the warm-up, whose built-in scenes use them, does: the cache's files say which kernels were
compiled, by this process or by its compile helper (``transient.precompile``)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

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


#: Kernels that only the features a plain scene does not use need, by feature.
FEATURE_KERNELS = {
    "friction pairs": ("chain.modes_power_flow_into", "chain._best_candidate", "rhs.margins_at",
                       "rhs.chain_acceleration", "events._pair_event", "events._sample_margins",
                       "loop._settle_modes", "outputs.pair_rows", "events._iterated_g",
                       "events.iterated_value"),
    "governor states": ("forcing.governor_rates", "governor.pi_rates", "governor.flyweight_rates",
                        "forcing.demand", "events._sleeve_event", "events._sleeve_stops",
                        "outputs.governor_rows"),
    "latched fuel": ("breakpoints._cylinder_on",),
    "cylinder states": ("forcing.cylinder_rates", "cylinder.pressure_rate"),
    "per-cylinder variation": ("variation.cycle_fuel", "variation.misfire_draw"),
    "tabulated loads": ("forcing.table_load", "forcing.speed_knot_segment"),
    "reaction friction": ("joint_friction.prepare", "joint_friction.solve",
                          "swash_friction.prepare", "swash_friction.solve",
                          "reactions.acceleration", "rhs.watches_kinks", "rhs.reset_kinks",
                          "rhs.kink_in_attempt"),
}


#: The W-method's kernels (``solver.method = "ros34pw2"``): a scene an explicit pair runs
#: compiles none of them (its step is a compile-time choice, ``rosenbrock.method_step``).
W_KERNELS = ("rosenbrock.w_step", "rosenbrock.band_factor", "rosenbrock.band_solve",
             "line_jacobian.line_jacobian", "line_jacobian.model_jacobian")


def cached_kernels(cache: Path) -> set[str]:
    """The kernels with a compiled version in the numba cache under ``cache``, as module and
    name (``rhs.derivative``): numba names each index file after them (then ``-`` and the line)."""
    return {path.name.split("-")[0] for path in cache.rglob("*.nbi")}


@pytest.mark.slow  # (it compiles every kernel cold, in a cache of its own)
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
    # the default scene: a static droop governor, no friction pairs, nothing else of the kind
    probe = transient(mechanisms[0], code=PROBE)[0].split()
    assert probe[0] != "0"
    # (integer casts are np.int64: numba's int() is an overload compiled as a unit of its own,
    # once for each set of compile flags, core.jit)
    assert not [name for name in probe[1:] if "ol_int" in name]
    plain = cached_kernels(tmp_path / "cache")
    assert {"loop.advance", "rhs.derivative", "forcing.moments"} <= plain
    for feature, kernels in FEATURE_KERNELS.items():
        assert not plain & set(kernels), feature
    assert not plain & set(W_KERNELS)
    lines = transient("warmup", *mechanisms)
    assert lines[0].startswith(f"kernels in {tmp_path / 'cache' / 'numba'}")
    compiled = [line.strip().split()[1] for line in lines[1:-1]]
    assert all(line.strip().startswith("compiled ") for line in lines[1:-1])
    # (the stepper's callees, such as rhs.derivative, may be the compile helper's, which this
    # process then loads: the cache below has them)
    assert {"transient.core.stepper.loop.advance",
            "transient.core.model.inverse.inverse_dynamics"} <= set(compiled)
    assert lines[-1] == f"{len(compiled)} kernel(s) compiled"
    full = cached_kernels(tmp_path / "cache")
    for feature, kernels in FEATURE_KERNELS.items():
        assert set(kernels) <= full, feature
    runs = [*mechanisms, *(str(CASES / f"{c}.toml") for c in (
        "coasting_single", "gots_diesel_governed", "gots_diesel_woschni", "gots_diesel_4400",
        "swash_plate_4cyl_friction", "gots_diesel_start_flyweight", "diesel_4cyl_misfire"))]
    assert transient(*runs, code=PROBE) == ["0"]
    assert transient("warmup")[1:] == ["all kernels were cached"]
