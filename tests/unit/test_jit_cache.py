"""How transient compiles and caches with numba (:mod:`transient.core.jit`): saving new machine
code waits for the cache folder's lock, so that processes compiling at once (``transient sweep``'s
workers, the parallel test suite) do not hand out the same data file to different signatures; a
kernel called with different constants is compiled once, for their type."""
from __future__ import annotations

import fcntl
import importlib.util
import threading
import time

import numba

from transient.core.jit import SAVE_LOCK, compiled

KERNEL = "def double(x):\n    return 2 * x\n"


def _fresh_function(tmp_path, monkeypatch):
    """``compiled`` around a function of a new source file, cached in ``tmp_path``."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "numba"))
    source = tmp_path / "kern.py"
    source.write_text(KERNEL)
    spec = importlib.util.spec_from_file_location("kern", source)
    module = importlib.util.module_from_spec(spec)
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


def test_constants_passed_to_a_kernel_share_its_machine_code(tmp_path, monkeypatch):
    """``jit._compile_per_type``: constants passed from compiled code are typed as literals, and
    numba would compile the callee once per constant."""
    double = compiled(_fresh_function(tmp_path, monkeypatch))

    @compiled
    def caller(x):
        return double(3) + double(4) + double(x) + double(True)

    assert caller(5) == 2 * (3 + 4 + 5 + 1)
    assert [str(sig) for sig in double.signatures] == ["(int64,)", "(bool,)"]
