"""The compile decorators of transient's numba functions.

``compiled`` is ``numba.njit(cache=True)`` whose cache loads without numba's compiler registries
(:class:`_RegistryFreeCache`); ``kernel`` is ``compiled`` without numba's reference counting
(``_nrt=False``). With reference counting, every call that passes arrays — the
:data:`transient.core.model.Model` tuple holds a dozen — increfs and decrefs each of them through
an indirect call: measured on the single cylinder (a throwaway loop timing one small kernel),
passing the Model to it cost 130 ns of 260 ns; without reference counting the same call took
72 ns. The whole right-hand side went from 0.512 µs per call (the previous record of
``scripts/stepper_overhead.py``) to 0.036 µs. Kernels under ``kernel`` must not allocate arrays
(they work in buffers their caller allocated); the few that allocate (the stepper's ``advance``,
work arrays) are ``compiled``.
"""
from __future__ import annotations

from numba import config, njit
from numba.core.caching import FunctionCache
from numba.core.runtime import rtsys


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
    return dispatcher


def kernel(fn=None, **options):
    """``@kernel`` or ``@kernel(inline="always")``: compiled, no reference counting.

    Without ``inline="always"`` a kernel is a call in machine code, and numba passes a tuple
    argument flattened, by value: each array as its pointers, sizes, shape and strides. The
    Model tuple is ~150 words, copied onto the stack at every such call. numba's inlining copies
    the callee's IR at every call site (a third of a cold compile), so inline what runs per step
    at one or two sites, not everything (:mod:`.integrate` says what and what it measured)."""
    return compiled(fn, _nrt=False, **options)
