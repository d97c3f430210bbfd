"""The performance targets, measured by ``transient bench`` beside the work-precision record and
written to ``targets.md`` and ``targets.json`` in the record's folder: each target with what was
measured, how, and whether it is met or by how much it is missed. One idea: the targets'
report, each target's measurement beside its verdict, so that what is measured and what it is
held to cannot drift apart.

* speed at equal accuracy (≥ 300× solve_ivp RK45, ≥ 2× CyRK at a final phase error ≤ 1e-6 rad)
  and the error's fall with the tolerance: read from the record's rows (:mod:`transient.verify.bench`);
* stepper overhead (≤ 30 %): a run's integration wall time against its right-hand-side calls ×
  the cost of one compiled call, the call timed in a compiled loop over states along the run's
  last cycle, independent calls (throughput) and chained ones (latency, as a step's stages are);
* the bare scene (equation (18) alone) against a kernel written by hand for that equation
  (within 5 %), and the bare scene against itself carrying unused options (no measurable change);
* friction on the joints' reactions on three pairs against constant efficiencies (≤ 2×), and
  scenes without friction against a build without the friction models (no measurable change:
  :mod:`transient.verify.models_out`);
* warm start (≤ 1 s process wall of ``transient run``) and scale (wall time per revolution at 10⁶
  revolutions within 10 % of 10³, peak memory independent of the length), each in new processes;
* the elastic shaft line (:mod:`transient.verify.torsion`): the in-line six's run-up against its
  rigid equivalent (≤ 10× per cycle), its cost along a generated line of 3 to 30 stations
  (linear), and against scipy on the numpy right-hand side of the same equations at equal
  error (≥ 100×);
* cold start, each in new processes on an empty cache: the first ``transient run`` of the default
  scene (its compile ≤ 20 s), ``transient warmup`` of every bench scene and a radial engine (≤ 60
  s), and the profile of the default scene's compile, function by function
  (:class:`transient.warmup.CompileLog`).

Timings are medians after a warm-up; what is compared runs alternately, so that the machine's
drift shows in both sides alike.
"""
from __future__ import annotations

import dataclasses as dc
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

from ..assemble import build_model
from ..core import CACHE_DIR_VARIABLE
from ..core.jit import kernel
from ..core.model import layout, work
from ..core.model.rhs import derivative
from ..results import open_result
from ..run import SUMMARY_SAMPLES, integrate
from ..scene import Governor, Starter, load_scene
from . import multirev, steady, torsion
from .bench import (
    ADAPTIVE,
    BASELINE_BUDGET_S,
    BENCH_SCENES,
    DEFAULT,
    RUN_ATOL,
    RUN_RTOL,
    SAME_STEPS,
    SAMPLES_PER_REV,
    TARGET_PHASE,
    at_target,
    fastest_as_accurate,
    loose_to_tight,
    median_walls,
    on_plateau,
    order_slope,
    read_record,
    timed_scene,
)
from .models_out import WITHOUT_FRICTION, friction_models_cost

#: Right-hand sides per DOP853 step. The stepper picks each cylinder's gas table piece once per
#: step (``model.select_pieces``, keyed by the step's ``sel``): the timing loop keeps ``sel`` for
#: this many calls too, so that a call costs what it costs inside a step.
CALLS_PER_STEP = 12
OVERHEAD_TARGET, BARE_TARGET, WARM_TARGET_S, SCALE_TARGET = 0.30, 0.05, 1.0, 0.10
#: Cold start: the first run's compile [s], the compile of every kernel (``transient warmup``) [s].
COLD_RUN_TARGET_S, COLD_ALL_TARGET_S = 20.0, 60.0
#: The default scene (``make run``) and the radial engine the cold start compiles besides the
#: bench scenes.
DEFAULT_SCENE = BENCH_SCENES["swash_plate_4cyl"]
RADIAL_SCENE = DEFAULT_SCENE.parent / "radial_5cyl.toml"
#: Functions named in the profile's table, by their own compile time; the rest are summed.
PROFILE_ROWS = 15
#: Peak memory counts as independent of the run's length if it grows by at most this fraction.
MEMORY_TARGET = 0.01
#: Output of the scale runs [samples per turn].
SCALE_SAMPLES_PER_REV = 4
SPEED_TARGETS = {"solve_ivp RK45 (numpy RHS)": 300.0, "CyRK DOP853 (transient's compiled RHS)": 2.0}
#: The bare scene: one cylinder, equation (18) alone (no gas, friction, governor or starter).
BARE_SCENE = BENCH_SCENES["coasting_single"]


# ------------------------------------------------------------------------------------------------
# the cost of one right-hand side


@kernel
def rhs_loop(m, states, y, out, sw, wk, chained, extras):
    """Evaluate the crank-angle RHS at every state (rows: φ, t, K, works); return a checksum.
    ``chained``: each call's state depends on the previous result (0·out still has to wait for
    out), as a Runge–Kutta step's stages do — the RHS's latency; otherwise the calls are
    independent — its throughput, where the division, square root and sine of one call overlap
    the next's. Independent calls read the row itself: copying it into ``y`` costs a measurable
    part of a call on the bare cylinder, and the hand-written loop (:func:`make_hand_loop`) copies
    nothing. ``extras``: the kernels' variant for ``m``
    (:func:`transient.core.model.layout.extras_of`)."""
    acc = 0.0
    for i in range(states.shape[0]):
        state = states[i]
        if chained:
            for j in range(y.shape[0]):
                y[j] = states[i, j] + 0.0 * out[j]
            state = y
        sel = states[i - i % CALLS_PER_STEP, layout.PHI]
        derivative(m, extras, True, state, sel, sw, wk, out)
        acc += out[layout.KINETIC]
    return acc


def per_call(loop, *args, rounds=7, loops=100):
    """Time of one call [s] of a loop ``loop(x, states, …)`` over the rows of ``states`` (its
    second argument): median over ``rounds`` of ``loops`` loops, after a warm-up."""
    loop(*args)
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(loops):
            loop(*args)
        times.append((time.perf_counter() - t0) / (loops * args[1].shape[0]))
    return statistics.median(times)


def rhs_arguments(scene, n_states=2000):
    """(model, states, y, out, sw, wk) for ``rhs_loop``: ``n_states`` states over the last cycle
    of a 50-revolution run of ``scene`` (CALLS_PER_STEP of them span about a step), interpolated
    between its samples (SAMPLES_PER_REV per turn)."""
    model, _, _ = build_model(scene)
    tr = integrate(dc.replace(scene, run=dc.replace(scene.run, revolutions=50.0, t_end=math.inf),
                              output=dc.replace(scene.output, samples_per_rev=SAMPLES_PER_REV))
                   ).trajectory
    phi = np.linspace(tr["phi"][-1] - model.period, tr["phi"][-1], n_states)
    states = np.zeros((phi.size, layout.n_state(model)))
    states[:, layout.PHI], states[:, layout.T] = phi, np.interp(phi, tr["phi"], tr["t"])
    states[:, layout.KINETIC] = np.interp(phi, tr["phi"], 0.5 * tr["J"] * tr["omega"] ** 2)
    n = layout.n_state(model)
    return model, states, np.empty(n), np.zeros(n), _switches(), work.work_array(model)


def _switches():
    """The switch states of a run driven forward (the stepper's ``sw``)."""
    sw = np.zeros(layout.N_SWITCHES, dtype=np.int64)
    sw[layout.SW_DIRECTION] = 1
    return sw


def rhs_costs(scene, rounds=7, loops=100) -> tuple[float, float]:
    """(independent, chained) cost of one crank-angle right-hand side of ``scene`` [s]."""
    args = rhs_arguments(scene)
    return tuple(per_call(rhs_loop, *args, chained, layout.extras_of(args[0]), rounds=rounds,
                          loops=loops)
                 for chained in (False, True))


def stepper_overhead(name, path, repeat=5, revolutions=1000.0, samples=(1, SAMPLES_PER_REV),
                     rounds=7) -> list[dict]:
    """Wall time of ``revolutions`` against RHS calls × cost of one call, at each output
    density ``samples`` (per turn); one row per density."""
    base = load_scene(path)
    scenes = [timed_scene(base, revolutions, n) for n in samples]
    medians, _, counts = median_walls(*scenes, repeat=repeat)
    independent, chained = rhs_costs(scenes[0], rounds=rounds)
    return [{"scene": name, "samples_per_rev": n, "wall_s": wall, "nfev": c["nfev"],
             "nsteps": c["nsteps"], "call_independent_s": independent, "call_chained_s": chained,
             "overhead_independent": wall / (c["nfev"] * independent) - 1.0,
             "overhead_chained": wall / (c["nfev"] * chained) - 1.0}
            for n, wall, c in zip(samples, medians, counts)]


# ------------------------------------------------------------------------------------------------
# the bare scene against a kernel written by hand


def make_hand_rhs(layout=False, loads=False, records=False):
    """(18) in crank angle for one rigid-rod crank slider, self-contained (its own kinematics:
    Gots (1)–(19) written out once more, on purpose — the baseline a user would write); parameters
    ``p`` in the order of :func:`hand_parameters`; returns dt/dφ and dK/dφ = −M_load in ``out``.
    All flags off: that kernel. Each flag adds one thing transient's right-hand side does, to
    attribute the difference (closure constants: compiled out, not branched): ``layout`` the
    offset, the masses summed per call and the cylinder loop rotating sin φ, cos φ by the
    cylinder's phase; ``loads`` the load's linear and fan terms, the schedule, generator and
    starter switches; ``records`` the three work integrals and the speed range kept for the event
    search (in ``rec``)."""

    @njit(inline="always")  # a closure's dispatcher is not inlined by LLVM
    def rhs(p, y, out, rec):
        r, l, m_rod, cg, I_rod = p[0], p[1], p[4], p[5], p[6]
        f = cg / l
        J = p[7]
        if layout:
            sp, cp = math.sin(y[0]), math.cos(y[0])
            m_slide, m_rot = p[10] + p[11], p[12] + p[13]
            for _ in range(int(p[16])):
                sa, ca = sp * p[15] - cp * p[14], cp * p[15] + sp * p[14]
                sb = (r * sa - p[9]) / l
                cb = math.sqrt(1.0 - sb * sb)
                db = r * ca / (l * cb)
                ds = r * sa + l * sb * db
                gx = f * r * ca
                gy = (1.0 - f) * (-ds) - f * r * sa
                J += m_slide * ds * ds + m_rot * r * r
                J += m_rod * (gx * gx + gy * gy) + I_rod * db * db
        else:
            sa, ca = math.sin(y[0]), math.cos(y[0])
            sb = r * sa / l
            cb = math.sqrt(1.0 - sb * sb)
            db = r * ca / (l * cb)
            ds = r * sa + l * sb * db  # piston velocity per unit ω
            gx = f * r * ca
            gy = (1.0 - f) * (-ds) - f * r * sa
            J += p[2] * ds * ds + p[3] * r * r + m_rod * (gx * gx + gy * gy) + I_rod * db * db
        w = math.sqrt(2.0 * y[2] / J)
        M = -p[8]
        if loads:  # the bare scene has no schedule (s = 1), fan, generator or starter
            s = 1.0 if p[17] == 0.0 else p[18]
            M = -s * (p[8] + p[19] * w + p[20] * w * abs(w))
            if p[21] != 0.0:
                M -= s * p[21] / w
            if p[22] != 0.0:
                M += p[22] * (1.0 - w / p[23])
        out[0] = 1.0
        out[1] = 1.0 / w
        out[2] = M
        if records:
            out[3] = 0.0
            out[4] = M
            out[5] = 0.0
            rec[0] = min(rec[0], w)
            rec[1] = max(rec[1], w)

    return rhs


def make_hand_loop(rhs):
    # Without reference counting, as transient's kernels: with it, the view states[i] is increfed
    # and decrefed at every call unless numba's pruning removes the pair, which it does for the
    # bare kernel but not once the load's branches are in.
    @njit(_nrt=False)
    def loop(p, states, out, rec):
        acc = 0.0
        for i in range(states.shape[0]):
            rhs(p, states[i], out, rec)
            acc += out[1]
        return acc

    return loop


def hand_parameters(base) -> np.ndarray:
    """The bare single cylinder's parameters for :func:`make_hand_rhs`, in its order (the last
    seven are what ``loads`` reads, all idle in the bare scene)."""
    from ..core.model import crank_slider as cs

    mech = base.mechanism
    if not (mech.rod_model == "rigid" and mech.offset == 0.0 and mech.n_cylinders == 1):
        raise ValueError("the hand-written kernel is for one rigid-rod cylinder without offset")
    mp = mech.pack()
    return np.array([mp[cs.R], mp[cs.L], mp[cs.M_PISTON] + mp[cs.M_PIN],
                     mp[cs.M_CRANKPIN] + mp[cs.M_CRANK], mp[cs.M_ROD], mp[cs.ROD_CG],
                     mp[cs.I_ROD], base.inertia.total, 0.0, mp[cs.E], mp[cs.M_PISTON],
                     mp[cs.M_PIN], mp[cs.M_CRANKPIN], mp[cs.M_CRANK], mp[cs.SIN0],
                     mp[cs.SIN0 + 1], 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0])


def hand_arguments(base):
    """(p, states, out, rec) for a hand-written loop: 2000 states over 40 rad at K = 170 J."""
    states = np.zeros((2000, 6))
    states[:, layout.PHI] = np.linspace(0.0, 40.0, 2000)
    states[:, layout.KINETIC] = 170.0
    return hand_parameters(base), states, np.empty(6), np.array([np.inf, -np.inf])


def hand_against_transient(base, rows, **flags) -> tuple[np.ndarray, np.ndarray]:
    """(dt/dφ, dK/dφ) of the hand-written (18) with ``flags`` and of transient's right-hand side,
    each at the ``rows`` of :func:`hand_arguments`' states: two arrays of shape (len(rows), 2)."""
    p, states, out, rec = hand_arguments(base)
    rhs = make_hand_rhs(**flags)
    m, _, _ = build_model(base)
    theirs = np.zeros(6)
    hand, transient = [], []
    for i in rows:
        rhs_loop(m, states[i:i + 1], np.empty(6), theirs, _switches(), work.work_array(m), False,
                 layout.extras_of(m))
        rhs(p, states[i], out, rec)
        hand.append((out[layout.T], out[layout.KINETIC]))
        transient.append((theirs[layout.T], theirs[layout.KINETIC]))
    return np.array(hand), np.array(transient)


def hand_written_cost(base, rounds=7, loops=100, **flags) -> float:
    """Cost of one call of the hand-written (18) [s], after checking it against transient's
    right-hand side on one state (the same equation: to 1e-13)."""
    hand, transient = hand_against_transient(base, [7], **flags)
    if not np.allclose(hand, transient, rtol=1e-13, atol=1e-13):
        raise RuntimeError(f"hand-written (18) {flags}: {hand}, transient {transient}")
    p, states, out, rec = hand_arguments(base)
    return per_call(make_hand_loop(make_hand_rhs(**flags)), p, states, out, rec, rounds=rounds,
                    loops=loops)


def bare_kernel(rounds=7) -> dict:
    """One right-hand side of the bare scene, exact and tabulated, against the hand-written (18),
    on the same states."""
    base = load_scene(BARE_SCENE)
    hand = hand_written_cost(base, rounds=rounds)
    p, states, _, _ = hand_arguments(base)
    costs = {}
    for kin in ("exact", "tabulated"):
        m, _, _ = build_model(dc.replace(base, solver=dc.replace(base.solver, kinematics=kin)))
        costs[kin] = per_call(rhs_loop, m, states, np.empty(6), np.zeros(6), _switches(),
                              work.work_array(m), False, layout.extras_of(m), rounds=rounds)
    return {"hand_written_s": hand, "exact_s": costs["exact"], "tabulated_s": costs["tabulated"]}


def unused_options(repeat=15, revolutions=1000.0) -> dict:
    """Whole runs of the bare scene against the same scene with a droop governor and a starter
    that never act (medians of ``repeat`` alternating runs), and the spread of the bare runs."""
    bare = timed_scene(load_scene(BARE_SCENE), revolutions)
    unused = dc.replace(bare, governor=Governor(model="droop", speed_full=1e4, speed_zero=2e4),
                        starter=Starter(torque=0.0))
    (w_bare, w_unused), (runs, _), _ = median_walls(bare, unused, repeat=repeat)
    q1, _, q3 = statistics.quantiles(runs, n=4)
    return {"bare_s": w_bare, "unused_s": w_unused, "change": w_unused / w_bare - 1.0,
            "bare_iqr": (q3 - q1) / w_bare}


#: Friction on the joints' reactions (three pairs) against constant efficiencies (the two pairs
#: a crank-slider's constant-η chain has): at most this many times the wall time.
REACTION_TARGET = 2.0
#: The constant-η scene; the reaction scene is it with the main bearings, crankpins and pistons
#: of the reaction case.
FRICTION_SCENE = DEFAULT_SCENE.parent / "gots_diesel_friction.toml"
REACTION_SCENE = DEFAULT_SCENE.parent / "gots_diesel_reaction_friction.toml"


def reaction_cost(repeat=5, revolutions=1000.0) -> dict:
    """Whole runs of the Gots diesel's spin-up with constant-η pairs (main bearings, crankpins)
    against the same with reaction friction on three pairs (main bearings, crankpins, pistons),
    medians of ``repeat`` alternating runs, with their solver counts."""
    from ..scene import Friction

    base = load_scene(FRICTION_SCENE)
    pairs = [p for p in load_scene(REACTION_SCENE).friction.pairs if p.name != "piston pins"]
    constant = timed_scene(base, revolutions)
    reaction = dc.replace(constant, friction=Friction("power-flow", tuple(pairs)))
    (w_c, w_r), _, (c, r) = median_walls(constant, reaction, repeat=repeat)
    return {"constant_s": w_c, "reaction_s": w_r, "ratio": w_r / w_c,
            "constant_nfev": c["nfev"], "reaction_nfev": r["nfev"],
            "per_call_ratio": (w_r / r["nfev"]) / (w_c / c["nfev"])}


def models_cost(quick=False) -> list[dict]:
    """Scenes without friction, and one with constant-η pairs, against a build without the
    friction models (:func:`transient.verify.models_out.friction_models_cost`)."""
    q = dict(scenes=("coasting_single",), rounds=1, repeat=2, revolutions=10.0) if quick else {}
    with tempfile.TemporaryDirectory() as tmp:
        return friction_models_cost(DEFAULT_SCENE.parent, Path(tmp), **q)


# ------------------------------------------------------------------------------------------------
# new processes: warm start, scale


def _process_wall(argv) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def warm_start(repeat=5, scene=BARE_SCENE) -> dict:
    """Process wall of ``transient run SCENE -q`` (the kernels cached: one warm-up run first), and
    of an interpreter doing nothing, for the machine's scale."""
    with tempfile.TemporaryDirectory() as tmp:
        run = [sys.executable, "-m", "transient", "run", str(scene), "-q", "-o", tmp, "--force"]
        _process_wall(run)
        walls = [_process_wall(run) for _ in range(repeat)]
    bare = statistics.median(_process_wall([sys.executable, "-c", "pass"])
                             for _ in range(repeat))
    return {"scene": Path(scene).stem, "walls_s": walls, "median_s": statistics.median(walls),
            "python_alone_s": bare}


_SCALE_CHILD = """
import dataclasses as dc, json, math, sys
from transient.scene import load_scene
from transient.run import simulate
base = load_scene(sys.argv[1])
scene = dc.replace(base, run=dc.replace(base.run, revolutions=float(sys.argv[2]), t_end=math.inf),
                   output=dc.replace(base.output, samples_per_rev=int(sys.argv[3])))
data = simulate(scene, sys.argv[4], force=True)
# the peak resident memory of this process since its exec (ru_maxrss would keep the high-water
# mark of the parent it was forked from)
kb = dict(line.split(":") for line in open("/proc/self/status") if line.startswith("Vm"))
print(json.dumps({"wall_s": data.solver["wall_s"], "peak_mb": int(kb["VmHWM"].split()[0]) / 1024}))
"""


def scale(lengths=(1e3, 2e5, 1e6), samples_per_rev=SCALE_SAMPLES_PER_REV, scene=BARE_SCENE
          ) -> list[dict]:
    """Each length run to a result file in a new process (as ``transient run`` does, summary
    included): integration wall time per 1000 revolutions and the process's peak resident memory
    (Linux's ``/proc``; the resident memory after the run is no measure: it is what the allocator
    kept of the freed summary window, which differs between lengths whose peaks agree). The
    summary reads a window of the last SUMMARY_SAMPLES samples, full from 125 000 revolutions at
    4 samples per turn: the peak is compared from there on."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in lengths:
            out = subprocess.run([sys.executable, "-c", _SCALE_CHILD, str(scene), repr(n),
                                  str(samples_per_rev), str(Path(tmp) / "scale.h5")],
                                 check=True, capture_output=True, text=True).stdout
            got = json.loads(out.splitlines()[-1])
            rows.append({"revolutions": n, "wall_per_1000_s": got["wall_s"] / n * 1000.0,
                         "peak_mb": got["peak_mb"]})
    return rows


# ------------------------------------------------------------------------------------------------
# cold start


def _cold_env(cache: Path | None) -> dict:
    """The environment of a child process whose caches are in ``cache`` (None: this process's)."""
    env = dict(os.environ)
    if cache is not None:
        env.pop("NUMBA_CACHE_DIR", None)
        env[CACHE_DIR_VARIABLE] = str(cache)
    return env


_PROFILE_CHILD = """
import dataclasses, json, sys
from transient import run
run.start_helper = lambda *args: None  # (every compile in this process, for the log)
from transient.scene import load_scene
from transient.warmup import CompileLog
with CompileLog() as log:
    run.simulate(load_scene(sys.argv[1]))
print(json.dumps([dataclasses.asdict(c) for c in log.compiled]))
"""


def compile_profile(scene: Path, cache: Path | None) -> list[dict]:
    """The functions compiled by a run of ``scene`` in one process (no compile helper), with
    their CPU seconds (:class:`transient.warmup.Compiled`), on the caches in ``cache``."""
    out = subprocess.run([sys.executable, "-c", _PROFILE_CHILD, str(scene)], check=True,
                         capture_output=True, text=True, env=_cold_env(cache)).stdout
    return json.loads(out.splitlines()[-1])


def cold_start(quick=False) -> dict:
    """On empty caches, each in a new process: the first ``transient run`` of the default scene
    (process wall and the compile it reports), ``transient warmup`` of the bench scenes and a
    radial engine, and the default scene's compile profile. ``quick``: on this process's caches
    (the harness only; nothing is compiled where they are warm)."""
    with tempfile.TemporaryDirectory() as tmp:
        def cache(name: str) -> Path | None:
            return None if quick else Path(tmp) / name

        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "transient", "run", str(DEFAULT_SCENE), "-q",
                        "-o", tmp], check=True, stdout=subprocess.DEVNULL,
                       env=_cold_env(cache("run")))
        run_wall = time.perf_counter() - t0
        compile_s = open_result(Path(tmp) / f"{DEFAULT_SCENE.stem}.h5").solver["compile_s"]
        scenes = [*map(str, BENCH_SCENES.values()), str(RADIAL_SCENE)]
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "transient", "warmup", *scenes], check=True,
                       stdout=subprocess.DEVNULL, env=_cold_env(cache("warmup")))
        warmup_wall = time.perf_counter() - t0
        profile = compile_profile(DEFAULT_SCENE, cache("profile"))
    return {"scene": DEFAULT_SCENE.stem, "cold": not quick, "run_wall_s": run_wall,
            "compile_s": compile_s, "warmup_scenes": [Path(p).stem for p in scenes],
            "warmup_wall_s": warmup_wall, "profile": profile}


# ------------------------------------------------------------------------------------------------
# from the record's rows: speed at equal accuracy, the error's fall with the tolerance


def speed_at_equal_accuracy(rows, targets=SPEED_TARGETS) -> list[dict]:
    """Per scene and baseline of ``targets`` (label → the factor it is held to): the baseline's
    wall time over the default path's, both at a final phase error ≤ 1e-6 rad (measured or
    extrapolated, as the record says); where the baseline reaches it by no run, at the
    baseline's most accurate run instead (against the default path's fastest run at least as
    accurate)."""
    out = []
    for scene in sorted({r["scene"] for r in rows}):
        default_wall, _ = at_target(rows, scene, DEFAULT)
        for baseline, factor in targets.items():
            runs = [r for r in rows if r["scene"] == scene and r["method"] == baseline
                    and math.isfinite(r["phase_err_rad"])]
            if not runs:  # no run within the budget, or (nowhere in the record) not installed
                if any(r["method"] == baseline for r in rows):
                    out.append({"scene": scene, "baseline": baseline, "error_rad": math.nan,
                                "how": "no run finished within the budget", "baseline_s": math.nan,
                                "transient_s": math.nan, "ratio": math.nan, "target": factor})
                continue
            wall, how = at_target(rows, scene, baseline)
            error, ours = TARGET_PHASE, default_wall
            if not math.isfinite(wall):
                best = min(runs, key=lambda r: r["phase_err_rad"])
                wall, error = best["wall_s"], best["phase_err_rad"]
                ours, _ = fastest_as_accurate(rows, scene, DEFAULT, error)
                how = f"{TARGET_PHASE:g} rad not reached: at its best error"
            out.append({"scene": scene, "baseline": baseline, "error_rad": error, "how": how,
                        "baseline_s": wall, "transient_s": ours, "ratio": wall / ours,
                        "target": factor})
    return out


def elastic_against_scipy(rows) -> dict:
    """The elastic line's rows (:func:`.torsion.scipy_rows`) compared as the rigid scenes' are,
    each scipy method at :data:`.torsion.SCIPY_TARGET`: every comparison, and the fastest method's
    (least ratio)."""
    each = speed_at_equal_accuracy(rows, {f"solve_ivp {m} (numpy RHS)": torsion.SCIPY_TARGET
                                          for m in torsion.SCIPY_METHODS})
    finite = [s for s in each if math.isfinite(s["ratio"])]
    return {"each": each, "best": min(finite, key=lambda s: s["ratio"]) if finite else None}


def error_monotone(rows, floors: dict[str, float]) -> list[dict]:
    """Per scene and adaptive path, from loose to tight rtol: the tolerances at which the final
    phase error rose (both errors above 100× the scene's reference floor, ``floors``), those at
    which it stayed flat (the same steps and the same error, both within ``bench.SAME_STEPS``:
    the breakpoints set the steps there, not the tolerance; listed, not counted as rises), and
    the slope of log(error) against log(rtol) where the tolerance set the steps."""
    out = []
    for scene, floor in floors.items():
        for method in ADAPTIVE:
            runs = loose_to_tight(rows, scene, method)
            rises, flat = [], []
            for prev, run in zip(runs, runs[1:]):
                e_prev, e = prev["phase_err_rad"], run["phase_err_rad"]
                if not e > e_prev > 100 * floor:
                    continue
                if on_plateau(prev, run) and e <= (1.0 + SAME_STEPS) * e_prev:
                    flat.append((run["rtol"], e / e_prev))
                else:
                    rises.append((run["rtol"], e / e_prev))
            out.append({"scene": scene, "method": method, "rises": rises, "flat": flat,
                        "slope": order_slope(rows, scene, method, floor)})
    return out


# ------------------------------------------------------------------------------------------------
# all of it, and the report


def measure_targets(rows, floors, quick=False, progress=print) -> dict:
    """Every target's measurement (``quick``: the harness on short runs, one repeat)."""
    q = dict(repeat=1, revolutions=10.0, rounds=1) if quick else {}
    res: dict[str, Any] = {"speed": speed_at_equal_accuracy(rows),
                           "monotone": error_monotone(rows, floors), "overhead": []}
    for name, path in BENCH_SCENES.items():
        res["overhead"] += stepper_overhead(name, path, **q)
        progress(f"targets: stepper overhead, {name}")
    res["bare"] = bare_kernel(rounds=q.get("rounds", 7))
    res["unused"] = unused_options(**({"repeat": 2, "revolutions": 10.0} if quick else {}))
    progress("targets: bare scene")
    res["reaction"] = reaction_cost(**({"repeat": 1, "revolutions": 10.0} if quick else {}))
    progress("targets: reaction friction")
    res["models"] = models_cost(quick)
    progress("targets: friction models left out")
    res["warm_start"] = warm_start(repeat=1 if quick else 5)
    progress("targets: warm start")
    res["scale"] = scale((10.0, 100.0) if quick else (1e3, 2e5, 1e6))
    progress("targets: scale")
    res["cold_start"] = cold_start(quick)
    progress("targets: cold start")
    res["torsion"] = torsion.measure(quick, progress)
    res["torsion"]["scipy"] = elastic_against_scipy(res["torsion"]["rows"])
    res["steady"] = steady.measure(quick, progress)
    res["multirevolution"] = multirev.measure(quick)
    progress("targets: multirevolution")
    return res


def _missed(value, target, larger_is_better=False) -> str:
    if not math.isfinite(value):
        return "**not measured**"
    ok = value >= target if larger_is_better else value <= target
    return "met" if ok else "**missed**"


def verdicts(res) -> list[tuple[str, str, str, str]]:
    """(target, case, measured, met / missed) for every target."""
    lines = []
    for s in res["speed"]:
        measured = (f"{s['ratio']:.3g}× at {s['error_rad']:.1e} rad ({s['how']})"
                    if math.isfinite(s["ratio"]) else s["how"])
        verdict = _missed(s["ratio"], s["target"], larger_is_better=True)
        if s["error_rad"] > TARGET_PHASE and verdict == "met":  # (compared at a looser error)
            verdict = "met at the baseline's best error"
        lines.append((f"≥ {s['target']:g}× {s['baseline']}", s["scene"], measured, verdict))
    for o in res["overhead"]:
        if o["samples_per_rev"] == 1:
            lines.append((f"stepper overhead ≤ {OVERHEAD_TARGET:.0%} (chained calls, 1 sample "
                          "per turn)", o["scene"], f"{o['overhead_chained']:+.0%}",
                          _missed(o["overhead_chained"], OVERHEAD_TARGET)))
    b = res["bare"]
    for kin in ("exact", "tabulated"):
        above = b[f"{kin}_s"] / b["hand_written_s"] - 1.0
        lines.append((f"bare scene within {BARE_TARGET:.0%} of hand-written (18)", kin,
                      f"{above:+.0%}", _missed(above, BARE_TARGET)))
    u = res["unused"]
    lines.append(("unused options change nothing measurable (within the bare runs' IQR)",
                  "idle governor + starter", f"{u['change']:+.1%} (IQR {u['bare_iqr']:.1%})",
                  _missed(abs(u["change"]), u["bare_iqr"])))
    rx = res.get("reaction")  # (none in a record from before it was measured)
    if rx is not None:
        lines.append((f"reaction friction on three pairs ≤ {REACTION_TARGET:g}× constant η",
                      FRICTION_SCENE.stem,
                      f"{rx['ratio']:.2f}× ({rx['reaction_s']:.3f} s against "
                      f"{rx['constant_s']:.3f} s; {rx['reaction_nfev']} against "
                      f"{rx['constant_nfev']} RHS calls, {rx['per_call_ratio']:.2f}× per call)",
                      _missed(rx["ratio"], REACTION_TARGET)))
    for r in res.get("models", []):  # (none in a record from before it was measured)
        if r["scene"] in WITHOUT_FRICTION:
            lines.append(("a scene without friction pays nothing for the friction models "
                          "(within its runs' IQR)", f"{r['scene']} ({r['what']})",
                          f"{r['change']:+.1%} (IQR {r['iqr']:.1%})",
                          _missed(abs(r["change"]), r["iqr"])))
    w = res["warm_start"]
    lines.append((f"warm start ≤ {WARM_TARGET_S:g} s", w["scene"],
                  f"{w['median_s']:.2f} s (interpreter alone {w['python_alone_s']:.2f} s)",
                  _missed(w["median_s"], WARM_TARGET_S)))
    lines += _cold_verdicts(res.get("cold_start"))
    for m in res["monotone"]:
        rises = ", ".join(f"rtol {r:.0e} ×{k:.3g}" for r, k in m["rises"]) or "none"
        flat = ", ".join(f"{r:.0e} ×{k:.4f}" for r, k in m.get("flat", []))
        flat = f"; flat on the same steps at rtol {flat}" if flat else ""
        lines.append(("error falls monotonically with rtol", f"{m['scene']}, {m['method']}",
                      f"rises: {rises}{flat}; slope {m['slope']:.2f}",
                      "met" if not m["rises"] else "**missed**"))
    if "torsion" in res:  # (none in a record from before it was measured)
        lines += torsion.verdicts(res["torsion"], _missed)
    if "steady" in res:  # (none in a record from before it was measured)
        lines += steady.verdicts(res["steady"], _missed)
    if "multirevolution" in res:
        lines += multirev.verdicts(res["multirevolution"], _missed)
    first, last = res["scale"][0], res["scale"][-1]
    growth = last["wall_per_1000_s"] / first["wall_per_1000_s"] - 1.0
    lines.append((f"wall per revolution within {SCALE_TARGET:.0%} from {first['revolutions']:g} "
                  f"to {last['revolutions']:g} revolutions", BARE_SCENE.stem, f"{growth:+.1%}",
                  _missed(abs(growth), SCALE_TARGET)))
    # from where the summary's window of the last SUMMARY_SAMPLES samples is full
    window = SUMMARY_SAMPLES / SCALE_SAMPLES_PER_REV
    full = [s for s in res["scale"] if s["revolutions"] >= window] or res["scale"][-2:]
    peak = full[-1]["peak_mb"] - full[0]["peak_mb"]
    lines.append((f"peak memory independent of the length (≤ {MEMORY_TARGET:.0%} growth)",
                  BARE_SCENE.stem,
                  f"{peak:+.1f} MB ({peak / full[0]['peak_mb']:+.1%}) from "
                  f"{full[0]['revolutions']:g} to {full[-1]['revolutions']:g} revolutions "
                  f"(peak {full[-1]['peak_mb']:.0f} MB)",
                  _missed(peak / full[0]["peak_mb"], MEMORY_TARGET)))
    return lines


def _cold_verdicts(c) -> list[tuple[str, str, str, str]]:
    """The cold start's verdicts (none in a record from before it was measured)."""
    if c is None:
        return []
    how = "" if c["cold"] else " (quick: caches warm)"
    return [(f"cold first run: compile ≤ {COLD_RUN_TARGET_S:g} s", c["scene"] + how,
             f"{c['compile_s']:.1f} s (process wall {c['run_wall_s']:.1f} s)",
             _missed(c["compile_s"], COLD_RUN_TARGET_S)),
            (f"cold compile of every kernel ≤ {COLD_ALL_TARGET_S:g} s",
             f"transient warmup {' '.join(c['warmup_scenes'])}{how}",
             f"{c['warmup_wall_s']:.1f} s", _missed(c["warmup_wall_s"], COLD_ALL_TARGET_S))]


def _models_section(rows) -> list[str]:
    """Each scene against the build without the friction models."""
    if not rows:
        return []
    return ["", "## Friction models left out", "",
            "Integration wall (1000 revolutions, rtol 1e-8, atol 1e-11) of this build against a "
            "copy whose compiled core leaves out the reaction pairs, efficiency maps and stuck "
            "mode (`transient/verify/models_out.py`), medians of alternating processes.", "",
            "| scene | | this build [s] | models left out [s] | change | IQR | RHS calls |",
            "|---|---|---|---|---|---|---|",
            *(f"| {r['scene']} | {r['what']} | {r['this_s']:.4g} | {r['left_out_s']:.4g} | "
              f"{r['change']:+.1%} | {r['iqr']:.1%} | {r['nfev']} / {r['nfev_left_out']} |"
              for r in rows)]


def _profile_section(c) -> list[str]:
    """The cold compile's profile: the functions of longest own compile, the rest summed."""
    if c is None:
        return []
    rows = sorted(c["profile"], key=lambda r: -r["own_cpu_s"])
    total = sum(r["own_cpu_s"] for r in rows)
    rest = rows[PROFILE_ROWS:]
    md = ["", "## Cold compile profile", "",
          f"A run of `{c['scene']}.toml` in one process without the compile helper, on "
          + ("an empty cache" if c["cold"] else "warm caches (quick)")
          + f": {len(rows)} functions compiled in {total:.1f} s of CPU. Own: without the "
          "callees compiled inside it; with callees: including them.", "",
          "| function | own CPU [s] | with callees [s] |", "|---|---|---|",
          *(f"| `{r['name']}` | {r['own_cpu_s']:.2f} | {r['cpu_s']:.2f} |"
            for r in rows[:PROFILE_ROWS])]
    if rest:
        md.append(f"| the other {len(rest)} | {sum(r['own_cpu_s'] for r in rest):.2f} | |")
    return md


def write_targets(res, out: Path) -> Path:
    """``targets.json`` (every measurement) and ``targets.md`` (the verdicts, then the details)."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "targets.json").write_text(json.dumps(res, indent=1) + "\n")
    md = ["# Benchmark targets", "",
          "Written by `transient bench` (`transient bench --targets` alone) on this machine, in "
          "one run; what each measures: `transient/verify/targets.py`. Speed and the error's fall "
          "are read from `work_precision.csv` (solve_ivp: each run stopped at the bench's budget, "
          f"{BASELINE_BUDGET_S:g} s by default).", "",
          "| target | case | measured | |", "|---|---|---|---|",
          *(f"| {t} | {c} | {m} | {v} |" for t, c, m, v in verdicts(res)), "",
          f"## Stepper overhead (1000 revolutions, rtol {RUN_RTOL:g}, atol {RUN_ATOL:g}; median "
          "of 5 runs)", "",
          "| scene | samples per turn | wall [s] | RHS calls | steps | one call, independent / "
          "chained [µs] | overhead against independent / chained calls |",
          "|---|---|---|---|---|---|---|"]
    md += [f"| {o['scene']} | {o['samples_per_rev']} | {o['wall_s']:.4g} | {o['nfev']} | "
           f"{o['nsteps']} | {o['call_independent_s'] * 1e6:.3f} / "
           f"{o['call_chained_s'] * 1e6:.3f} | {o['overhead_independent']:+.0%} / "
           f"{o['overhead_chained']:+.0%} |" for o in res["overhead"]]
    b, u, w = res["bare"], res["unused"], res["warm_start"]
    md += ["", "## Bare scene", "",
           f"One right-hand side: hand-written (18) {b['hand_written_s'] * 1e9:.1f} ns, transient "
           f"exact {b['exact_s'] * 1e9:.1f} ns, tabulated {b['tabulated_s'] * 1e9:.1f} ns. "
           f"Whole runs: bare {u['bare_s']:.4g} s, with an idle governor and starter "
           f"{u['unused_s']:.4g} s.", "",
           "## Warm start", "", f"`transient run {w['scene']}.toml -q`: "
           + ", ".join(f"{x:.2f}" for x in w["walls_s"]) + " s.", "",
           "## Scale (4 samples per turn, to a result file)", "",
           "| revolutions | integration per 1000 revolutions [s] | peak resident memory [MB] |",
           "|---|---|---|",
           *(f"| {s['revolutions']:g} | {s['wall_per_1000_s']:.4g} | {s['peak_mb']:.1f} |"
             for s in res["scale"])]
    md += _models_section(res.get("models"))
    md += _profile_section(res.get("cold_start"))
    if "torsion" in res:
        md += torsion.section(res["torsion"])
    if "steady" in res:
        md += steady.section(res["steady"])
    if "multirevolution" in res:
        md += multirev.section(res["multirevolution"])
    path = out / "targets.md"
    path.write_text("\n".join(md) + "\n", encoding="utf-8")
    return path


def run_targets(out, quick=False, progress=print) -> dict:
    """Measure the targets against the record in ``out`` (its rows and references) and write
    ``targets.md`` and ``targets.json`` there."""
    rows, refs = read_record(Path(out))
    res = measure_targets(rows, {n: r.confirm_phase for n, r in refs.items()}, quick, progress)
    write_targets(res, Path(out))
    return res


def rewrite_targets(out) -> bool:
    """Rewrite ``targets.md`` from ``targets.json`` (after a change to the report, without
    measuring again); False if there is no ``targets.json``."""
    path = Path(out) / "targets.json"
    if not path.is_file():
        return False
    write_targets(json.loads(path.read_text()), Path(out))
    return True
