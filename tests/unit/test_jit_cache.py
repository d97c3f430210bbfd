"""How transient compiles and caches with numba (:mod:`transient.core.jit`): a process about to
compile a function that another process is compiling (``transient sweep``'s workers, the parallel
test suite's) waits for the function's lock, then loads that one's code; the lock is per
function, so that two processes never save different signatures into its index at once; a kernel
called with different constants is compiled once, for their type."""
from __future__ import annotations

import fcntl
import importlib.util
import os
import subprocess
import sys
import threading
import time

import numba

from transient.core import jit
from transient.core.jit import COMPILE_LOCK, compiled

KERNEL = "def double(x):\n    return 2 * x\n"
ACROSS_PROCESSES = "transient.core.jit._compile_once_across_processes"


def _fresh_function(tmp_path, monkeypatch):
    """``compiled`` around a function of a new source file, cached in ``tmp_path``."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "numba"))
    source = tmp_path / "kern.py"
    source.write_text(KERNEL)
    spec = importlib.util.spec_from_file_location("kern", source)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "kern", module)  # (numba's cached code names its module)
    spec.loader.exec_module(module)
    return module.double


CALL_IN_ANOTHER_PROCESS = """
import importlib.util, sys
from transient.core.jit import compiled
spec = importlib.util.spec_from_file_location("kern", sys.argv[1])
module = sys.modules["kern"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
double = compiled(module.double)
assert double(1.5) == 3.0
print(sum(double.stats.cache_hits.values()), sum(double.stats.cache_misses.values()))
"""


def _waits_for_lock(path, pid):
    """Whether process ``pid`` is blocked on a lock of the file ``path`` (Linux's /proc/locks
    lists each waiter after ``->``: ``1: -> FLOCK ADVISORY WRITE <pid> <dev>:<inode> 0 EOF``)."""
    inode = os.stat(path).st_ino
    with open("/proc/locks") as locks:
        rows = [line.split() for line in locks]
    return any(r[1] == "->" and r[5] == str(pid) and int(r[6].rsplit(":", 1)[1]) == inode
               for r in rows if len(r) > 6)


def _hold_compile_lock(dispatcher):
    """The compile lock of ``dispatcher``'s function, taken as a process compiling it holds it:
    (its path, the open file; closing it releases the lock)."""
    cache = dispatcher._cache
    cache._impl.locator.ensure_cache_path()
    path = os.path.join(cache._cache_path, COMPILE_LOCK.format(cache._impl.filename_base))
    lock = open(path, "a")
    fcntl.flock(lock, fcntl.LOCK_EX)
    return path, lock


def _wait_until_blocked(path, pid, running):
    """Wait until process ``pid`` is blocked on the lock ``path``; fail if ``running()`` (the
    waiting thread or process) turns false first, or if nothing blocks within 300 s."""
    deadline = time.monotonic() + 300.0
    while not _waits_for_lock(path, pid):
        assert running(), f"{ACROSS_PROCESSES}: it did not wait for the lock"
        assert time.monotonic() < deadline, f"{ACROSS_PROCESSES}: nothing reached the lock"
        time.sleep(0.01)


def test_a_new_signature_waits_for_the_functions_lock(tmp_path, monkeypatch):
    """The lock is per function, not per signature: numba saves a new signature by a
    read-modify-write of the function's index, so a process saving another signature at once
    would take the same data file."""
    double = _fresh_function(tmp_path, monkeypatch)
    dispatcher = compiled(double)
    assert dispatcher(2) == 4  # (int64,): compiled and saved
    index = dispatcher._cache._cache_file._load_index
    path, lock = _hold_compile_lock(dispatcher)  # as another process compiling (float64,) would
    try:
        worker = threading.Thread(target=dispatcher, args=(1.5,))
        worker.start()
        # (/proc/locks lists a waiting thread under its process's pid)
        _wait_until_blocked(path, os.getpid(), worker.is_alive)
        assert len(index()) == 1
    finally:
        lock.close()
    worker.join(300.0)
    assert not worker.is_alive()
    assert len(index()) == 2

    reloaded = compiled(double)  # a new dispatcher: both saved signatures, loaded
    assert reloaded(2) == 4 and reloaded(1.5) == 3.0
    assert sum(reloaded.stats.cache_hits.values()) == 2 and not reloaded.stats.cache_misses


def test_a_process_waits_for_another_compiling_and_loads_its_code(tmp_path, monkeypatch):
    double = _fresh_function(tmp_path, monkeypatch)
    dispatcher = compiled(double)
    path, lock = _hold_compile_lock(dispatcher)  # this process compiles first
    monkeypatch.setattr(jit, "_COMPILE_LOCKS_HELD", {path})
    other = subprocess.Popen(
        [sys.executable, "-c", CALL_IN_ANOTHER_PROCESS, str(tmp_path / "kern.py")],
        env={**os.environ, "NUMBA_CACHE_DIR": numba.config.CACHE_DIR},
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_until_blocked(path, other.pid, lambda: other.poll() is None)
        assert dispatcher(1.5) == 3.0  # compiled here, and saved
        assert dispatcher.stats.cache_misses
    finally:
        lock.close()  # releases the lock
    out, err = other.communicate(timeout=300.0)
    assert other.returncode == 0, err
    assert out.split() == ["1", "0"]  # loaded from the cache once, compiled never


def test_constants_passed_to_a_kernel_share_its_machine_code(tmp_path, monkeypatch):
    """``jit._compile_per_type``: constants passed from compiled code are typed as literals, and
    numba would compile the callee once per constant."""
    double = compiled(_fresh_function(tmp_path, monkeypatch))

    @compiled
    def caller(x):
        return double(3) + double(4) + double(x) + double(True)

    assert caller(5) == 2 * (3 + 4 + 5 + 1)
    assert [str(sig) for sig in double.signatures] == ["(int64,)", "(bool,)"], (
        f"transient.core.jit._compile_per_type: {double.signatures} (compiled once per constant?)")


KERNELS_AS_VALUES = """
from transient.core.jit import compiled, kernel


@kernel(inline=True)
def square(ctx, x):
    return ctx[0] * x * x


@kernel(inline=True)
def cube(ctx, x):
    return ctx[0] * x * x * x


@kernel
def apply(f, ctx, x):
    return f(ctx, x)


@compiled
def both(x):
    return apply(square, (2.0,), x) + apply(cube, (1.0,), x)
"""

LOAD_BOTH = """
import importlib.util, os, sys
spec = importlib.util.spec_from_file_location("kernarg", sys.argv[1])
module = sys.modules["kernarg"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
if sys.argv[2] == "fresh":  # (only the callee's cache left: both compiles, apply loads)
    for name in os.listdir(module.both._cache._cache_path):
        if name.startswith("kernarg.both"):
            os.remove(os.path.join(module.both._cache._cache_path, name))
assert module.both(3.0) == 2.0 * 9.0 + 27.0
for d in (module.both, module.apply):
    print(sum(d.stats.cache_hits.values()), sum(d.stats.cache_misses.values()))
"""


def test_a_function_taking_kernels_as_arguments_is_cached_across_processes(tmp_path):
    """A kernel passed as an argument (the model's derivative to the integrator) types by its
    module and name (``jit._KernelArgument``): the callee compiled for it is found in the cache
    by another process, once per kernel, and the caller, which passes it as a constant without
    its address, is cached too."""
    source = tmp_path / "kernarg.py"
    source.write_text(KERNELS_AS_VALUES)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def run(mode):
        done = subprocess.run([sys.executable, "-W", "error::numba.NumbaWarning", "-c",
                               LOAD_BOTH, str(source), mode], env=env, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        return [tuple(map(int, line.split())) for line in done.stdout.splitlines()]

    assert run("first") == [(0, 1), (0, 2)]  # both compiled, apply for each kernel
    assert run("again") == [(1, 0), (0, 0)]  # both loaded (no dynamic address in it)
    assert run("fresh") == [(0, 1), (2, 0)]  # both compiled anew, apply's two loaded
    index = [n for n in os.listdir(tmp_path / "numba" / "kernarg") if n.startswith("kernarg.apply")
             and n.endswith(".nbc")]
    assert len(index) == 2  # (one entry per kernel, not one per process)


FORMULAS = """
from transient.core.jit import compiled, formula, kernel


@formula
def half(x):
    return 0.5 * x


@formula
def quarter(x):  # (a formula of a formula: both copied)
    return half(half(x))


@kernel(inline=True, python=lambda x: ("from Python", x))
def three_quarters(x):
    return quarter(x) + half(x)


@compiled
def caller(x):
    return three_quarters(x) + quarter(x)
"""

RUN_FORMULAS = """
import importlib.util, sys
spec = importlib.util.spec_from_file_location("formulas", sys.argv[1])
module = sys.modules["formulas"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
assert module.quarter(2.0) == 0.5  # (from Python: run as Python)
assert module.three_quarters(2.0) == ("from Python", 2.0)  # (kernel(python=…))
assert module.caller(2.0) == 2.0
assert module.three_quarters.python_entry(2.0) == 1.5  # (the compiled twin)
print(len(module.half.overloads), len(module.quarter.overloads),
      sum(module.caller.stats.cache_hits.values()))
"""


def test_a_formula_is_copied_into_its_callers_and_runs_as_python_from_python(tmp_path):
    """``jit.formula``: no compile unit of its own — its callers compile with its code copied in,
    and a caller loaded from the cache needs none either; called from Python it runs as Python.
    A kernel given ``python`` runs that from Python, its compiled twin still at hand."""
    source = tmp_path / "formulas.py"
    source.write_text(FORMULAS)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def run():
        done = subprocess.run([sys.executable, "-W", "error::numba.NumbaWarning", "-c",
                               RUN_FORMULAS, str(source)], env=env, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        return done.stdout.split()

    assert run() == ["0", "0", "0"]  # compiled, the formulas never
    assert run() == ["0", "0", "1"]  # loaded
