"""How transient compiles and caches with numba (:mod:`transient.core.jit`): saving new machine
code waits for the cache folder's lock, so that processes compiling at once (``transient sweep``'s
workers, the parallel test suite) do not hand out the same data file to different signatures; a
process about to compile a function another process is compiling waits, then loads that one's
code; a kernel called with different constants is compiled once, for their type."""
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
from transient.core.jit import COMPILE_LOCK, SAVE_LOCK, compiled

KERNEL = "def double(x):\n    return 2 * x\n"


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


def test_saving_waits_for_the_cache_folder_lock(tmp_path, monkeypatch):
    double = _fresh_function(tmp_path, monkeypatch)
    dispatcher = compiled(double)
    cache = dispatcher._cache
    cache._impl.locator.ensure_cache_path()
    lock = open(f"{cache._cache_path}/{SAVE_LOCK}", "a")
    fcntl.flock(lock, fcntl.LOCK_EX)  # as another process saving would hold it
    try:
        worker = threading.Thread(target=dispatcher, args=(1.5,))
        worker.start()
        deadline = time.monotonic() + 300.0
        # numba adds the compiled code to the dispatcher, then saves it
        while not dispatcher.overloads and time.monotonic() < deadline:
            time.sleep(0.01)
        assert dispatcher.overloads, "the function was not compiled"
        worker.join(1.0)
        assert worker.is_alive(), "the save did not wait for the lock"
        assert cache._cache_file._load_index() == {}
    finally:
        lock.close()  # releases the lock
    worker.join(60.0)
    assert not worker.is_alive()
    assert len(cache._cache_file._load_index()) == 1

    reloaded = compiled(double)  # a new dispatcher: the saved code, loaded
    assert reloaded(1.5) == 3.0
    assert reloaded.stats.cache_hits and not reloaded.stats.cache_misses


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


def test_a_process_waits_for_another_compiling_and_loads_its_code(tmp_path, monkeypatch):
    double = _fresh_function(tmp_path, monkeypatch)
    dispatcher = compiled(double)
    cache = dispatcher._cache
    cache._impl.locator.ensure_cache_path()
    lock_path = os.path.join(cache._cache_path, COMPILE_LOCK.format(cache._impl.filename_base))
    lock = open(lock_path, "a")
    fcntl.flock(lock, fcntl.LOCK_EX)  # this process compiles first, as a cold suite's worker would
    monkeypatch.setattr(jit, "_COMPILE_LOCKS_HELD", {lock_path})
    other = subprocess.Popen(
        [sys.executable, "-c", CALL_IN_ANOTHER_PROCESS, str(tmp_path / "kern.py")],
        env={**os.environ, "NUMBA_CACHE_DIR": numba.config.CACHE_DIR},
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 300.0
        while not _waits_for_lock(lock_path, other.pid):
            assert other.poll() is None, f"it did not wait for the lock: {other.communicate()}"
            assert time.monotonic() < deadline, "the other process never reached the lock"
            time.sleep(0.01)
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
    assert [str(sig) for sig in double.signatures] == ["(int64,)", "(bool,)"]
