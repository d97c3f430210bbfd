"""The compile decorators of transient's numba functions.

``compiled`` is ``numba.njit`` with numba's on-disk cache and replacements of numba internals,
each for its gain: the cache loads without numba's compiler registries
(:class:`_RegistryFreeCache`) from a folder that copies of the sources at other paths share
(:class:`_SharedLocator`), constants passed between kernels share one compile
(:func:`_compile_per_type`), and processes compiling the same function take turns
(:func:`_compile_once_across_processes`). ``kernel`` is for functions that compiled code
calls: compiled without numba's Python wrappers, a twin with them serving calls from Python
(:class:`_CalledFromCompiledCode`), its library linked into its callers' and never optimized or
made into machine code on its own (:func:`_linked_only`); ``kernel(inline=True)`` adds that
LLVM inlines it at its call sites (:func:`_inlined_by_llvm`). What Python calls to run
(the stepper) is ``compiled``. ``kernel`` is ``compiled`` without numba's reference counting
(``_nrt=False``), because with it every call that passes arrays — the
:data:`transient.core.model.layout.Model` tuple holds a dozen — increfs and decrefs each of them through
an indirect call. Kernels under ``kernel`` must not allocate arrays (they work in buffers their
caller allocated); the few that allocate (work arrays) are ``compiled``. A kernel passed to
another as an argument (the model's derivative to the integrator) is a compile-time constant typed
by its module and name (:class:`_KernelArgument`), so that what is compiled for it is cached.
``formula`` is for functions of a few operations (a layout's size rules): no compile unit at
all, numba's own inliner copies them into their callers, and Python runs them as Python.

The replacements rely on numba internals, so they are on only under the numba release they were
checked against (:data:`NUMBA_CHECKED`, pinned in pyproject.toml;
``tests/unit/test_numba_internals.py`` checks each internal they rely on). Under any other
release ``compiled`` is plain ``njit(cache=True)``, with a warning at import: correct, if slower
to start and to compile, because a replacement running on changed internals could misbehave
without failing.
"""
from __future__ import annotations

import fcntl
import functools
import operator
import os
import warnings
from contextlib import contextmanager

import llvmlite.binding as ll
import numba
from numba import _dynfunc, config, njit, types
from numba.core import sigutils
from numba.core.caching import CompileResultCacheImpl, FunctionCache, UserProvidedCacheLocator
from numba.core.codegen import CPUCodeLibrary, JITCPUCodegen
from numba.core.compiler_lock import global_compiler_lock
from numba.core.cpu import CPUContext
from numba.core.datamodel import register_default
from numba.core.datamodel.models import OpaqueModel
from numba.core.imputils import lower_constant
from numba.core.itanium_mangler import mangle_identifier
from numba.core.registry import CPUDispatcher
from numba.core.runtime import rtsys

#: The numba release whose internals the replacements were checked against.
NUMBA_CHECKED = "0.68.1"


def _replacements_apply(version: str) -> bool:
    """Whether the replacements may run under numba ``version``: only the checked release."""
    return version == NUMBA_CHECKED


#: Whether ``compiled`` uses the replacements (decided once, at import).
REPLACEMENTS_ON = _replacements_apply(numba.__version__)

if not REPLACEMENTS_ON:
    warnings.warn(
        f"transient.core.jit: numba {numba.__version__} is not {NUMBA_CHECKED}, the release its "
        "replacements of numba internals were checked against; compiling with plain "
        "njit(cache=True) instead (correct, slower to start and to compile)",
        RuntimeWarning, stacklevel=2)

#: The name of a function's compile lock in its cache folder, after numba's base name of its
#: cache files (:func:`_compile_once_across_processes`).
COMPILE_LOCK = "{}.compile.lock"


class _SharedLocator(UserProvidedCacheLocator):
    """numba's locator of a function's cache files in ``numba.config.CACHE_DIR``, with their
    folder named by the function's module (``transient.core.model.rhs``) where numba names it by a hash
    of the source file's absolute path: copies of the same sources at other paths (the nodes of a
    cluster, a clone and its worktrees, a fresh virtual environment) share one cache. numba's
    index keys each entry by a hash of the source's contents and by the CPU (its codegen's magic
    tuple), so other sources or another CPU never load each other's code."""

    def __init__(self, py_func, py_file):
        super().__init__(py_func, py_file)
        self._cache_path = os.path.join(config.CACHE_DIR, py_func.__module__)


class _SharedCacheImpl(CompileResultCacheImpl):
    """numba's cache of compile results, found by :class:`_SharedLocator` first."""

    _locator_classes = [_SharedLocator, *CompileResultCacheImpl._locator_classes]


class _RegistryFreeCache(FunctionCache):
    """numba's on-disk cache of a function, in the folder :class:`_SharedLocator` names, loading
    its machine code without first loading numba's compiler registries.

    numba's ``load_overload`` begins with ``target_context.refresh()``, which imports and
    installs the typing and lowering registries of everything numba compiles (its numpy, typed
    containers, random generators; ``numba.np.arraymath`` imports scipy.linalg): much of a warm
    start's time, and needed only to compile. Running loaded machine code needs two things that
    refresh would have set up, so they are set up here: the reference-counting runtime (NRT),
    which the allocating functions call, and the hash secrets that numba's hashing code reads as
    symbols. A function that is not in the cache is compiled as usual, and numba's compiler
    loads the registries itself (``CompilerBase.__init__``)."""

    _impl_class = _SharedCacheImpl

    def load_overload(self, sig, target_context):
        from numba.cpython import hashing  # noqa: F401 (its import registers the hash secrets)

        rtsys.initialize(target_context)
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)


class _PythonEntryCacheImpl(_SharedCacheImpl):
    """The cache files of a kernel's Python entry (:class:`_CalledFromCompiledCode`), named
    apart from the kernel's own: numba's index keys an entry by its signature and CPU, not by
    whether it has numba's Python wrappers."""

    def get_filename_base(self, fullname, abiflags):
        return super().get_filename_base(f"{fullname}-python", abiflags)


class _PythonEntryCache(_RegistryFreeCache):
    _impl_class = _PythonEntryCacheImpl


def compiled(fn=None, *, _cache=_RegistryFreeCache, **options):
    """``@compiled`` or ``@compiled(nogil=True)``: njit, cached (:class:`_RegistryFreeCache`)."""
    if fn is None:
        return lambda f: compiled(f, _cache=_cache, **options)
    if not REPLACEMENTS_ON:
        return njit(fn, cache=True, **options)
    dispatcher = njit(fn, **options)
    if not config.DISABLE_JIT:  # (then njit returns fn itself)
        dispatcher._cache = _cache(dispatcher.py_func)  # (what cache=True sets)
        dispatcher._types_active_call = _TypesKeptAlive()
        _compile_per_type(dispatcher)
        _compile_once_across_processes(dispatcher)
    return dispatcher


class _TypesKeptAlive(dict):
    """numba's set of the types a dispatcher gave arguments it typed in Python
    (``Dispatcher._types_active_call``, which keeps them alive while their codes are in use),
    keyed by identity: a set hashes the type at every call, and numba hashes a type by hashing
    its fields' types in turn, which for the Model (:func:`typed_by_fingerprint`) costs more
    than the rest of the call."""

    def add(self, tp):
        self[id(tp)] = tp


class _Kernel(CPUDispatcher):
    """A kernel's dispatcher: as a value (an argument to another kernel), typed by name
    (:class:`_KernelArgument`), under either numba release."""

    @property
    def _numba_type_(self):
        return _KernelArgument(self)

    def __reduce__(self):
        """A kernel of a module pickles by its module and name, as its type does: a Model that
        holds kernels (``Model.terms``) reaches another process (the compile helper,
        :mod:`transient.precompile`) as the kernels that process imports, not as copies
        compiled apart."""
        module, name = self.py_func.__module__, self.py_func.__qualname__
        if "<locals>" in name:
            return super().__reduce__()
        return _kernel_named, (module, name)


def _kernel_named(module: str, name: str):
    """The kernel ``name`` of ``module``, imported (``_Kernel.__reduce__``)."""
    import importlib

    return getattr(importlib.import_module(module), name)


class _CalledFromCompiledCode(_Kernel):
    """A kernel compiled without numba's Python wrappers (``no_cpython_wrapper``,
    ``no_cfunc_wrapper``), for the calls from compiled code: each wrapper unboxes every field of
    its arguments — the Model's dozens — and was a large part of compiling a small kernel that
    compiled code alone calls. A call from Python goes to :attr:`python_entry`, the same function
    compiled with the wrappers (and cached apart), made on the first such call."""

    def __call__(self, *args, **kwargs):
        return self.python_entry(*args, **kwargs)

    @property
    def python_entry(self):
        entry = self.__dict__.get("_python_entry")
        if entry is None:
            options = {k: v for k, v in self.targetoptions.items()
                       if k not in ("no_cpython_wrapper", "no_cfunc_wrapper", "nopython")}
            entry = self.__dict__["_python_entry"] = compiled(
                self.py_func, _cache=_PythonEntryCache, **options)
        return entry


class _CalledAsPythonFromPython(_CalledFromCompiledCode):
    """A kernel whose calls from Python run the Python function given for it
    (``kernel(python=…)``) instead of a compiled twin: for a kernel as cheap as a Python call
    that the Python side needs before any run (the state's length), whose twin's compile would
    cost a first run more than it saves. :attr:`_CalledFromCompiledCode.python_entry` is still
    the compiled twin, for the tests that check the two agree."""

    def __call__(self, *args, **kwargs):
        return self.__dict__["_python"](*args, **kwargs)


class _Formula(CPUDispatcher):
    """A :func:`formula`'s dispatcher: a call from Python runs its Python code."""

    def __call__(self, *args, **kwargs):
        return self.py_func(*args, **kwargs)


def formula(fn):
    """``@formula``: a function of a few operations on its arguments (a layout's size rule, an
    offset read from the layout's kernel), which is no compile unit of its own.

    numba copies its code into the code of each kernel that calls it, before typing (its own
    inliner, ``inline="always"``); a call from Python runs it as Python. A compile unit costs a
    fixed share of a cold compile (typing, lowering, its module linked into each caller) that is
    all of what a few operations cost; a larger function copied so would be typed anew at every
    call site, and nested ones once per level, so formulas stay small and call kernels, not
    chains of formulas. Nothing is pruned inside a formula on an argument typed None (numba's
    inliner runs after the pruning), so a formula takes no ``extras``."""
    dispatcher = njit(fn, inline="always")
    if not config.DISABLE_JIT:
        dispatcher.__class__ = _Formula
    return dispatcher


class _KernelArgument(types.Dispatcher):
    """The numba type of a kernel as a value: a kernel passed to a function as an argument (the
    model's derivative to the integrator, :mod:`transient.core.integrator`), which the callee is
    compiled for as a constant, its call inlined where the kernel is.

    numba's type of a function (``types.Dispatcher``) is named, compared and hashed by the
    function object, its address in the name: in the cache's index a signature with it never
    matches in another process, so a callee taking a kernel would be compiled anew in every
    process and the compile helper's work (:mod:`transient.precompile`) never used. This type is
    named, compared, hashed and pickled by the kernel's module and qualified name, which is what
    the kernel is from one process to the next (the cache folder is named by a hash of every
    source, so a changed kernel never meets an old index). Read back from an index, a type whose
    kernel's module is not imported compares equal by name without importing it (an index lists
    every signature its function was ever cached for)."""

    def __init__(self, dispatcher=None, where=None):
        if dispatcher is not None:
            where = (dispatcher.py_func.__module__, dispatcher.py_func.__qualname__)
            self._store_object(dispatcher)
        else:
            self._wr = _unresolved
        self._where = tuple(where)
        types.Type.__init__(self, f"kernel({self._where[0]}.{self._where[1]})")

    @property
    def key(self):
        return self._where

    def __eq__(self, other):
        if type(self) is type(other):
            return self._where == other._where
        return NotImplemented

    def __hash__(self):
        return hash(self._where)

    def __reduce__(self):
        return _kernel_argument, self._where


register_default(_KernelArgument)(OpaqueModel)  # (numba's data model of types.Dispatcher)


@lower_constant(_KernelArgument)
def _no_address(context, builder, ty, pyval):
    """A kernel passed as a value carries nothing at run time: its calls are resolved by its type
    when the callee is compiled. numba's constant of a function value is the function object's
    address (``lower_constant(types.Dispatcher)``), a run-time address that numba then refuses
    to cache in the calling function's machine code."""
    return context.get_dummy_value()


def _unresolved():
    """The weak reference of a :class:`_KernelArgument` read back without its kernel: none."""
    return None


def _kernel_argument(module: str, qualname: str) -> _KernelArgument:
    """A :class:`_KernelArgument` read back from the cache's index: the kernel's own type where
    its module is imported (numba interns types, and the two compare equal), else one by name."""
    return _KernelArgument(None, (module, qualname))


def typed_by_fingerprint(cls):
    """numba's type of a ``cls`` (a namedtuple holding kernels as values, the
    :data:`transient.core.model.layout.Model`) as an argument from Python, found by the
    fingerprint of its other fields.

    numba's dispatcher types an argument from Python by a fingerprint computed in C (a string of
    each field's kind, dtype and layout), which it has for numbers, arrays and tuples of them but
    not for a kernel: a tuple holding one is typed in Python field by field, about a hundred
    times slower than the rest of the call, at every call. This caches the type by the C
    fingerprint of the fields that have one and the kernels themselves, which together are what
    numba's type of the tuple is made of. The fields that hold kernels are found on the first
    value; a value with a kernel elsewhere is typed as numba types it. Off under another numba
    release (the fingerprint is an internal)."""
    if not REPLACEMENTS_ON:
        return cls
    from numba._dispatcher import compute_fingerprint
    from numba.core.typing.typeof import typeof_impl

    as_tuple = typeof_impl.dispatch(tuple)
    fields: list = []  # (the getters of the fields with a fingerprint and of the kernels)
    types_seen: dict = {}

    @typeof_impl.register(cls)
    def _typeof(val, c):
        if not fields:
            kernels = [i for i, v in enumerate(val) if isinstance(v, _Kernel)]
            rest = [i for i in range(len(val)) if i not in kernels]
            fields.extend(operator.itemgetter(*f) if f else _nothing for f in (rest, kernels))
        try:
            key = (compute_fingerprint(fields[0](val)), fields[1](val))
        except NotImplementedError:  # (no fingerprint: a kernel in another field)
            return as_tuple(val, c)
        found = types_seen.get(key)
        if found is None:
            found = types_seen[key] = as_tuple(val, c)
        return found

    return cls


def _nothing(_val) -> tuple:
    """The getter of no fields (:func:`typed_by_fingerprint`)."""
    return ()


def _compile_once_across_processes(dispatcher):
    """A process about to compile ``dispatcher`` first waits for any other process compiling
    it, then loads what that one saved instead of compiling it again.

    Processes started together on a cold cache — the test suite's workers, ``transient sweep``'s,
    the compile helper of :mod:`transient.precompile` — would otherwise each compile the same
    functions. numba's ``compile`` tries the cache before compiling, so it runs under an
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
    (``Dispatcher.get_call_template``): one machine-code copy per constant, each compiled
    separately. The stepper passes its event codes and state indices as constants, and the
    compile helper (:mod:`transient.precompile`) can compile the callees only for plain types.
    No kernel of transient branches on an argument's value at compile time, so the literal types
    are widened to their plain types before numba compiles."""
    per_constant = dispatcher.get_call_template

    def get_call_template(args, kws):
        return per_constant(tuple(types.unliteral(a) for a in args),
                            {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template


def kernel(fn=None, *, inline=False, python=None, **options):
    """``@kernel`` or ``@kernel(inline=True)``: compiled for calls from compiled code, no
    reference counting; ``python``: a function that calls from Python run instead
    (:class:`_CalledAsPythonFromPython`).

    A kernel is a compile unit of its own, compiled without numba's Python wrappers; a call from
    Python goes to a twin compiled with them (:class:`_CalledFromCompiledCode`). Its library is
    only ever linked into its callers', so it is neither optimized as a module nor turned into
    machine code on its own (:func:`_linked_only`): the caller that Python calls does both once,
    for everything linked into it. As a plain call in machine code, numba passes a tuple argument
    flattened, by value: each array as its pointers, sizes, shape and strides, so the Model
    tuple's ~150 words would be copied onto the stack at every call. With ``inline=True`` LLVM
    inlines the kernel at every call site (:func:`_inlined_by_llvm`), where the copy vanishes.
    numba's own inlining (``inline="always"``) copies the callee's IR into every caller before
    typing it, which made the cold compile grow with the nesting of calls."""
    if fn is None:
        return lambda f: kernel(f, inline=inline, python=python, **options)
    if not REPLACEMENTS_ON:  # a plain call: numba's inliner would defeat the pruning of a
        # branch on an argument typed None (:func:`.rosenbrock.method_step` relies on it)
        dispatcher = compiled(fn, _nrt=False, **options)
        kind = _Kernel
    else:
        if inline:
            _INLINED_BY_LLVM.add(_symbol_prefix(fn))
        _LINKED_ONLY.add(_symbol_prefix(fn))
        dispatcher = compiled(fn, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True,
                              **options)
        kind = _CalledFromCompiledCode
    if not config.DISABLE_JIT:
        dispatcher.__class__ = kind if python is None else _CalledAsPythonFromPython
        if python is not None:
            dispatcher.__dict__["_python"] = python
    return dispatcher


#: The symbol prefixes of the kernels that LLVM inlines at their call sites.
_INLINED_BY_LLVM: set[str] = set()


def _symbol_prefix(fn) -> str:
    """The start of the symbols numba gives ``fn``'s compiled versions: the Itanium-mangled
    qualified name, then its ABI tags (``B…``) and argument types (which vary)."""
    return "_ZN" + mangle_identifier(f"{fn.__module__}.{fn.__qualname__}")[1:-1] + "B"


def _inlined_by_llvm(get_module_for_linking):
    """numba's ``CPUCodeLibrary._get_module_for_linking``, with the kernels compiled with
    ``inline=True`` marked ``alwaysinline``.

    numba links the module of each callee into its caller's and optimizes the whole with LLVM,
    whose inliner then takes every function so marked. The module for linking is also what
    numba's cache stores beside the machine code, so a callee loaded from the cache is inlined
    alike."""

    @functools.wraps(get_module_for_linking)
    def get_marked_module(library):
        module = get_module_for_linking(library)
        prefixes = tuple(_INLINED_BY_LLVM)
        for fn in module.functions:
            if fn.is_declaration or not fn.name.startswith(prefixes):
                continue
            if not {bytes(a) for a in fn.attributes} & {b"alwaysinline", b"noinline"}:
                fn.add_function_attribute("alwaysinline")
        return module

    return get_marked_module


#: The symbol prefixes of every kernel: compiled without the Python wrappers, their libraries
#: are linked only (:func:`_linked_only`).
_LINKED_ONLY: set[str] = set()

#: numba's serialization kind of a library that is linked only: its module for linking, as
#: bitcode (:func:`_serialize_linked_only`).
LINKED_ONLY_KIND = "transient-linked-only"


def _is_linked_only(library, fndesc) -> bool:
    """Whether ``library``, lowered for ``fndesc``, is a kernel's without the Python wrappers.
    Its twin with them (:class:`_CalledFromCompiledCode`) has the same symbol prefix and the
    wrapper, and is compiled in full; so is every other function numba compiles."""
    if library._finalized:  # (loaded from the cache)
        return getattr(library, "_linked_only", False)
    if not fndesc.mangled_name.startswith(tuple(_LINKED_ONLY)):
        return False
    try:
        library._final_module.get_function(fndesc.llvm_cpython_wrapper_name)
    except NameError:
        return True
    return False


def _finalize_linked_only(library):
    """``CPUCodeLibrary.finalize`` without its optimization and its machine code: the callees'
    modules are linked in, so that the module for linking holds everything the kernel calls,
    and the library is marked finalized but never added to the execution engine. The caller
    that Python calls optimizes the whole and generates its machine code, as numba's finalize
    does for it anyway; optimizing each kernel's module and generating code for it as well was
    most of a cold compile, and that code was never run."""
    library._raise_if_finalized()
    seen = set()
    for callee in library._linking_libraries:
        if callee not in seen:
            seen.add(callee)
            library._reload_init.update(callee._reload_init)
            library._final_module.link_in(callee._get_module_for_linking(), preserve=True)
    library._final_module.verify()
    library._finalized = True
    library._linked_only = True


def _linked_only(get_executable):
    """numba's ``CPUContext.get_executable``, which finalizes a library and takes its function's
    address, with a kernel's library finalized by :func:`_finalize_linked_only` and a null
    address, as numba gives a function without the Python wrapper."""

    @functools.wraps(get_executable)
    def get(context, library, fndesc, env):
        if not _is_linked_only(library, fndesc):
            return get_executable(context, library, fndesc, env)
        if not library._finalized:
            _finalize_linked_only(library)
        return _dynfunc.make_function(fndesc.lookup_module(), fndesc.qualname.split(".")[-1],
                                      "linked only", 0, env, (library,))

    return get


def _serialize_linked_only(serialize):
    """numba's ``CPUCodeLibrary.serialize_using_object_code``, which the cache calls: a library
    that is linked only has no machine code, and is saved as its module for linking."""

    @functools.wraps(serialize)
    def save(library):
        if getattr(library, "_linked_only", False):
            return (library.name, LINKED_ONLY_KIND, library._get_module_for_linking().as_bitcode())
        return serialize(library)

    return save


def _unserialize_linked_only(unserialize):
    """numba's ``CPUCodeLibrary._unserialize`` (a classmethod's function), reading back what
    :func:`_serialize_linked_only` saved without optimizing it or making machine code."""

    @functools.wraps(unserialize)
    def load(cls, codegen, state):
        name, kind, data = state
        if kind != LINKED_ONLY_KIND:
            return unserialize(cls, codegen, state)
        library = codegen.create_library(name)
        library._final_module = library._shared_module = ll.parse_bitcode(data)
        library._finalized = True
        library._linked_only = True
        return library

    return classmethod(load)


def _environment_in_engine(set_env):
    """numba's ``JITCPUCodegen.set_env``, which a loaded function's environments go through, with
    those of a library that is linked only (so not in the execution engine, where the address
    of its environment would be null) left alone: its code never runs."""

    @functools.wraps(set_env)
    def set_if_loaded(codegen, env_name, env):
        if codegen._engine.get_global_value_address(env_name):
            set_env(codegen, env_name, env)

    return set_if_loaded


if REPLACEMENTS_ON:
    CPUCodeLibrary._get_module_for_linking = _inlined_by_llvm(
        CPUCodeLibrary._get_module_for_linking)
    CPUContext.get_executable = _linked_only(CPUContext.get_executable)
    CPUCodeLibrary.serialize_using_object_code = _serialize_linked_only(
        CPUCodeLibrary.serialize_using_object_code)
    CPUCodeLibrary._unserialize = _unserialize_linked_only(CPUCodeLibrary._unserialize.__func__)
    JITCPUCodegen.set_env = _environment_in_engine(JITCPUCodegen.set_env)
