"""The compile decorators of transient's numba functions.

``compiled`` is ``numba.njit(cache=True)`` whose cache loads without numba's compiler registries
(:class:`_RegistryFreeCache`); ``kernel`` is ``compiled`` without numba's reference counting
(``_nrt=False``). With reference counting, every call that passes arrays — the
:data:`transient.core.model.Model` tuple holds a dozen — increfs and decrefs each of them through
an indirect call: measured on the single cylinder (a throwaway loop timing one small kernel),
passing the Model to it cost 130 ns of 260 ns; without reference counting the same call took
72 ns. The whole right-hand side went from 0.512 µs per call (the previous record of
``tools/stepper_overhead.py``) to 0.036 µs. Kernels under ``kernel`` must not allocate arrays
(they work in buffers their caller allocated); the few that allocate (the stepper's ``advance``,
work arrays) are ``compiled``.
"""
from __future__ import annotations

import fcntl
import os
from contextlib import contextmanager

from numba import config, njit, types
from numba.core import sigutils
from numba.core.caching import FunctionCache
from numba.core.compiler_lock import global_compiler_lock
from numba.core.runtime import rtsys


#: The name of a function's compile lock in its cache folder, after numba's base name of its
#: cache files (:func:`_compile_once_across_processes`).
COMPILE_LOCK = "{}.compile.lock"


class _RegistryFreeCache(FunctionCache):
    """numba's on-disk cache of a function, loading its machine code without first loading
    numba's compiler registries.

    numba's ``load_overload`` begins with ``target_context.refresh()``: it imports and installs
    the typing and lowering registries of everything numba compiles (its numpy, its typed
    containers, its random generators; ``numba.np.arraymath`` imports scipy.linalg to find BLAS):
    timed around ``load_overload`` in a diesel run, 0.35–0.38 s for the first function loaded,
    0.003–0.05 s for each of the others (README *Start-up*). Those registries serve only
    compiling. Running loaded machine code needs two things they would have set up: the
    reference-counting runtime (NRT), which the allocating functions call, and the hash secrets
    that numba's hashing code reads as symbols; both are set up here. A function that is not in
    the cache is compiled as usual, and numba's compiler loads the registries itself
    (``CompilerBase.__init__``). numba is pinned in pyproject.toml; the test
    ``test_warm_run_loads_no_compiler_registries`` checks in a fresh process that this path is
    the one taken and that its results are bit-identical.
    """

    def load_overload(self, sig, target_context):
        from numba.cpython import hashing  # noqa: F401 (its import registers the hash secrets)

        rtsys.initialize(target_context)
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)


def compiled(fn=None, **options):
    """``@compiled`` or ``@compiled(nogil=True)``: njit, cached (:class:`_RegistryFreeCache`)."""
    if fn is None:
        return lambda f: compiled(f, **options)
    dispatcher = njit(fn, **options)
    if not config.DISABLE_JIT:  # (then njit returns fn itself)
        dispatcher._cache = _RegistryFreeCache(dispatcher.py_func)  # (what cache=True sets)
        _compile_per_type(dispatcher)
        _compile_once_across_processes(dispatcher)
    return dispatcher


def _compile_once_across_processes(dispatcher):
    """A process about to compile ``dispatcher`` first waits for any other process compiling
    it, then loads what that one saved instead of compiling it again.

    Processes started together on a cold cache — the test suite's workers, ``transient sweep``'s
    — otherwise all compile the same stepper at once (~210–240 s each on the slower test machine,
    README *Start-up*). numba's ``compile`` tries the cache before compiling, so it runs under an
    exclusive ``flock`` on the function's lock file in its cache folder: the second process takes
    the lock once the first has saved, and loads. The lock is per function, not per signature,
    because numba saves a new signature by a read-modify-write of the function's index (it takes
    the first data-file number the index does not list): two processes saving different
    signatures at once would take the same number, lose one entry, and let a later run load one
    process's machine code for the other's types. The lock is taken under numba's compiler lock,
    so only one thread per process holds such locks; the ones it already holds (a compile inside
    a compile) are not taken again. Processes cannot wait on each other in a circle, because
    one waiting for a function another holds would need that function to call, through its
    callees, one it holds: recursion, which no kernel of transient uses."""
    compile_here = dispatcher.compile
    cache = dispatcher._cache
    path = os.path.join(cache._cache_path, COMPILE_LOCK.format(cache._impl.filename_base))

    def compile(sig):
        with global_compiler_lock:  # (reentrant)
            args, _ = sigutils.normalize_signature(sig)
            if tuple(args) in dispatcher.overloads or path in _COMPILE_LOCKS_HELD:
                return compile_here(sig)
            with _holding_lock(cache, path):
                _COMPILE_LOCKS_HELD.add(path)
                try:
                    return compile_here(sig)
                finally:
                    _COMPILE_LOCKS_HELD.discard(path)

    dispatcher.compile = compile


@contextmanager
def _holding_lock(cache, path):
    """An exclusive ``flock`` on the file ``path`` in ``cache``'s folder, for the with-block;
    none if that folder cannot be written (numba cannot save there either)."""
    try:
        try:
            lock = open(path, "a")
        except FileNotFoundError:  # (a cold cache: numba makes its folder when first needed)
            cache._impl.locator.ensure_cache_path()
            lock = open(path, "a")
    except OSError:
        lock = None  # (yielded below, not here, so that the block's errors do not chain to it)
    if lock is None:
        yield
        return
    with lock:  # (closing the file releases the lock)
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


#: The compile locks this process holds (:func:`_compile_once_across_processes`).
_COMPILE_LOCKS_HELD = set()


def _compile_per_type(dispatcher):
    """Calls from compiled code compile ``dispatcher`` once per argument types, not once per
    constant passed.

    numba types a constant argument (an event code, a state index, ``True``) as a literal, and
    a call from compiled code compiles the callee for exactly the argument types it is given
    (``Dispatcher.get_call_template``): one machine-code copy per constant. The stepper reports
    its events with seven different codes (seven copies of ``_emit_event``, 1.6–2.8 s of
    compiling each), and ``_crossing`` took both a constant and a variable state index (two
    copies of it, and of the root finder ``_root`` it calls, ~12 s per copy of ``_root``). No
    kernel of transient branches on an argument's value at compile time, so the literal types
    are widened to their plain types before numba compiles."""
    per_constant = dispatcher.get_call_template

    def get_call_template(args, kws):
        return per_constant(tuple(types.unliteral(a) for a in args),
                            {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template


def kernel(fn=None, **options):
    """``@kernel`` or ``@kernel(inline="always")``: compiled, no reference counting.

    Without ``inline="always"`` a kernel is a call in machine code, and numba passes a tuple
    argument flattened, by value: each array as its pointers, sizes, shape and strides. The
    Model tuple is ~150 words, copied onto the stack at every such call. numba's inlining copies
    the callee's IR at every call site (a third of a cold compile), so inline what runs per step
    at one or two sites, not everything (:mod:`.integrate` says what and what it measured)."""
    return compiled(fn, _nrt=False, **options)
