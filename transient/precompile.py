"""Compile the stepper's callees in a helper process while this process compiles the stepper.

On a cold cache, compiling the stepper (:func:`~transient.core.stepper.loop.advance`) is the
bulk of a first run, on one core: while numba types the stepper it compiles, one after another,
each of its callees (every kernel is a compile unit of its own, which LLVM inlines afterwards:
:func:`transient.core.jit.kernel`). A helper process started at the same time compiles those
callees in the reverse order, each under its compile lock
(:func:`transient.core.jit._compile_once_across_processes`), so that the two use two cores. The
stepper's compile loads each callee the helper has saved, waits for the one the helper is
compiling, and compiles the others itself; nothing is compiled twice.

The helper needs each callee's argument types before the stepper's compile has found them: they
are named by the callees' parameters (``_types_by_parameter``), plain types, because
:func:`transient.core.jit._compile_per_type` widens the constants the stepper passes. Were one
wrong, the helper would compile a signature the stepper does not call and the stepper would
compile its own; the test ``test_helper_compiles_the_signatures_the_stepper_calls`` checks each
callee's cache. A helper that fails costs only its help: the stepper's compile compiles what is
missing itself. Without transient's replacements of numba internals (another numba release,
:data:`transient.core.jit.REPLACEMENTS_ON`) no helper is started, because without the compile
lock it would compile what the stepper's compile compiles too.
"""
from __future__ import annotations

import importlib
import inspect
import os
import pickle
import subprocess
import sys
from typing import IO, Any, cast

import numpy as np
from numba import config as numba_config
from numba import typeof, types

from .core import jit
from .core.integrator import rk, rosenbrock
from .core.model import layout, line_jacobian, rhs
from .core.stepper import breakpoints, events, loop
from .core.stepper import io as sio

#: numba's settings, which it sets at import from the environment, out of a type checker's sight.
config: Any = numba_config

#: The stepper's callees, each compiled apart with its own callees (:func:`.core.jit.kernel`), in
#: the reverse of the order in which the stepper's compile first calls for them (recorded with
#: numba's "numba:compile" events), so that the helper and the stepper's compile meet in the
#: middle.
CALLEES = (
    loop._switch_at_event,
    loop._record_event,
    loop._move_to_event,
    loop._take_step,
    loop._emit_step_samples,
    events._locate_events,
    breakpoints._aim_at_breakpoint,
    loop._stiff,
    rk.accepted_size,
    loop._judge_attempt,
    rk.step,
    sio._finish,
    breakpoints._segment_end,
    loop._settle_at_restart,
    rhs.derivative,
    sio._emit_row,
    loop._start_run,
)


def _types_by_parameter(model, tab) -> dict:
    """numba type of each parameter name the callees use, as the stepper passes it."""
    scalar = {types.boolean: ("angle_mode", "upward", "rising", "fixed", "on_corner",
                              "at_segment_end", "after_rejection", "dip", "dense_ready",
                              "redo_hit_breakpoint", "ends_on_breakpoint", "on_breakpoint",
                              "ev_rising", "keep", "cut"),
              types.float64: ("h", "sel", "x", "level", "theta", "theta_end", "x_stop", "d_out",
                              "ga", "gb", "a", "b", "phi", "period", "w", "x_end", "h_max",
                              "tol_end", "rtol", "atol", "corner", "err", "h_planned", "up",
                              "down", "min_step", "w_lo", "w_hi", "ev_theta", "ev_level",
                              "h_next", "err_old"),
              types.int64: ("comp", "k", "direction", "code", "ix", "n_samples", "g0", "g1", "c0",
                            "ev_code", "ev_comp", "n_pairs")}
    array = {types.float64[::1]: ("y", "y_new", "tmp", "out", "row", "cfg", "fst", "bp", "f",
                                  "y_evt"),
             types.float64[:, ::1]: ("K", "F", "outbuf", "evbuf", "wk", "gs"),
             types.int64[::1]: ("ist", "sw", "control")}
    vector, matrix, ints = np.zeros(1), np.zeros((1, 1)), np.zeros(1, np.int64)
    # (``extras`` is None or True: the plain or the full variant, ``core.model.layout.extras_of``)
    extras = typeof(layout.extras_of(model))
    by_name = {"m": typeof(model), "tab": typeof(tab), "extras": extras,
               # the model's derivative in the integrator's form, and its context
               "rhs": typeof(rhs.model_rhs),
               "ctx": types.Tuple((typeof(model), extras, types.boolean, types.float64,
                                   types.int64[::1], types.float64[:, ::1])),
               # the loop's records (stepper.io)
               "io": typeof(sio.Chunk(cfg=vector, bp=vector, fst=vector, ist=ints,
                                      outbuf=matrix, evbuf=matrix)),
               "work": typeof(sio.Work(K=matrix, F=matrix, f=vector, y_new=vector, y_evt=vector,
                                       tmp=vector, wk=matrix, gs=matrix, control=ints,
                                       band=matrix if rosenbrock.is_w_method(tab) else None)),
               # a W-method's: the model's Jacobian and its band's storage
               "jac": typeof(line_jacobian.model_jacobian), "band": types.float64[:, ::1],
               "at": typeof(sio.At(True, 0, 0.0, 0.0, 0.0, ints)),
               "seg": typeof(sio.Segment(*(6 * [0.0]))),
               "seen": types.Tuple((types.boolean, types.float64, types.float64)),
               "crossing": types.Tuple((types.float64, types.int64, types.float64)),
               "event": types.Tuple((types.int64, types.int64, types.float64, types.boolean))}
    for numba_type, names in (scalar | array).items():
        by_name.update(dict.fromkeys(names, numba_type))
    return by_name


def signature(fn, model, tab) -> tuple:
    """The argument types with which the stepper calls the callee ``fn``."""
    by_name = _types_by_parameter(model, tab)
    return tuple(by_name[p] for p in inspect.signature(fn.py_func).parameters)


def callees_of(tab, callees=CALLEES) -> tuple:
    """``callees`` as the stepper of the method ``tab`` calls them: a W-method's step in place
    of the explicit pairs'."""
    if not rosenbrock.is_w_method(tab):
        return callees
    return tuple(rosenbrock.w_step if fn is rk.step else fn for fn in callees)


def compile_callees(model, tab, callees=CALLEES) -> None:
    """Compile (or load from the cache) each of ``callees``, in that order."""
    for fn in callees_of(tab, callees):
        fn.compile(signature(fn, model, tab))


#: The stepper, whose compile the helper joins (taken at import: tests wrap ``stepper.advance``).
STEPPER = loop.advance


def stepper_is_cached(model, tab) -> bool:
    """Whether the stepper, in the kernels' variant for ``model``
    (:func:`~transient.core.model.layout.extras_of`), is compiled in this process or saved in
    numba's cache: a cache that holds only the other variant leaves this one to compile."""
    return is_cached(STEPPER, signature(STEPPER, model, tab))


def is_cached(dispatcher, sig: tuple) -> bool:
    """Whether ``dispatcher`` is compiled for ``sig`` in this process, or saved in its cache for
    this process's CPU: numba's index keys an entry by the signature, the CPU name and features
    the code was compiled for (``NUMBA_CPU_NAME``, ``NUMBA_CPU_FEATURES``) and the function's
    bytecode, and loads only an entry whose whole key matches, so a cache folder shared with
    another CPU's processes may hold the signature and still leave it to compile."""
    if sig in dispatcher.overloads:
        return True
    key = dispatcher._cache._index_key(sig, dispatcher.targetctx.codegen())
    return key in dispatcher._cache._cache_file._load_index()


def _cores() -> int:
    """The cores this process may run on."""
    if hasattr(os, "sched_getaffinity"):  # (Linux)
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def start_helper(model, tab, callees=CALLEES) -> subprocess.Popen | None:
    """A helper process compiling ``callees`` (:func:`compile_callees`), or None where it would
    not help: the stepper is cached (in the model's variant), the JIT is off, numba runs without
    transient's replacements, or this process has one core."""
    if (config.DISABLE_JIT or not jit.REPLACEMENTS_ON or _cores() < 2
            or stepper_is_cached(model, tab)):
        return None
    helper = None
    try:
        helper = subprocess.Popen(
            [sys.executable, "-c", f"import {__name__} as p; p.helper_main()"],
            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            env=helper_environment())
        with cast(IO[bytes], helper.stdin) as pipe:  # (stdin=PIPE: never None)
            pickle.dump((model, tab, [(fn.__module__, fn.__name__) for fn in callees]), pipe)
    except OSError:  # (no process to be had, or it died at once: the compile goes on alone)
        stop_helper(helper)
        return None
    return helper


def helper_environment() -> dict:
    """This process's environment with the numba settings its own compile uses: the cache folder
    and the CPU to compile for. numba reads them from the environment at import, and a program
    may have set them in ``numba.config`` since (the cache folder is transient's own,
    :mod:`transient.core`); a helper compiling for another CPU, or into another folder, would
    save code the stepper's compile cannot load."""
    env = {**os.environ, "NUMBA_CACHE_DIR": config.CACHE_DIR}
    for name, value in (("NUMBA_CPU_NAME", config.CPU_NAME),
                        ("NUMBA_CPU_FEATURES", config.CPU_FEATURES)):
        if value is None:  # (the host's)
            env.pop(name, None)
        else:
            env[name] = value
    return env


def stop_helper(helper: subprocess.Popen | None) -> None:
    """End the helper once the stepper is compiled: what it has left is loading from the cache.
    A kill cannot corrupt the cache: numba writes each file under a temporary name and renames
    it, and an index entry whose data file is missing counts as not cached."""
    if helper is not None:
        helper.kill()
        helper.wait()


def helper_main() -> None:
    """The helper process: compile the callees named on stdin for the model and tableau there."""
    model, tab, names = pickle.load(sys.stdin.buffer)
    compile_callees(model, tab, [getattr(importlib.import_module(mod), name)
                                 for mod, name in names])
