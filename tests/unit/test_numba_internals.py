"""The numba internals that transient's replacements (:mod:`transient.core.jit`) and its compile
helper (:mod:`transient.precompile`) rely on, each checked as it is in the pinned numba release.

A numba release that changes one of them fails here, with a message naming the replacement and
the internal: review the replacement against the new release before setting
``jit.NUMBA_CHECKED`` to it. Under a release other than ``NUMBA_CHECKED`` the replacements are
off (plain ``njit(cache=True)``); that fallback is tested here too."""
from __future__ import annotations

import ast
import inspect
import os
import subprocess
import sys
import textwrap
import threading
import tomllib
from pathlib import Path

import llvmlite.binding as ll
import numba
import pytest
from numba.core import caching, codegen, compiler, cpu, dispatcher, sigutils, typed_passes, types
from numba.core.base import BaseContext
from numba.core.compiler_lock import global_compiler_lock
from numba.core.runtime import rtsys
from numba.core.types import functions as type_functions

from transient.core import jit

REPO = Path(__file__).resolve().parents[2]
REVIEW = f"numba {numba.__version__} changed it: review the replacement"

REGISTRY_FREE = "transient.core.jit._RegistryFreeCache"
PER_TYPE = "transient.core.jit._compile_per_type"
ACROSS_PROCESSES = "transient.core.jit._compile_once_across_processes"
HELPER = "transient.precompile (the compile helper)"


def _statements(fn) -> list[str]:
    """The lines of ``fn``'s body as ``ast.unparse`` writes them, stripped: numba's code without
    its docstring, comments and line breaks, so that only a change in what it does changes
    them."""
    node = ast.parse(textwrap.dedent(inspect.getsource(fn))).body[0]
    body = node.body[1:] if ast.get_docstring(node) is not None else node.body
    return [line.strip() for stmt in body for line in ast.unparse(stmt).splitlines()]


def _code(text: str) -> list[str]:
    """``text`` as :func:`_statements` writes a body."""
    return [line.strip() for line in ast.unparse(ast.parse(textwrap.dedent(text))).splitlines()]


def _in_order(lines: list[str], wanted: list[str]) -> bool:
    """Whether ``wanted`` are among ``lines``, in that order."""
    rest = iter(lines)
    return all(any(line == w for line in rest) for w in wanted)


def _parameters(fn) -> list[str]:
    return list(inspect.signature(fn).parameters)


def _relies(replacement: str, internal: str) -> str:
    return f"{replacement} relies on {internal}; {REVIEW}"


# ----------------------------------------------------------------------------------------------
# the numba release


def test_the_pinned_numba_is_the_checked_one():
    pin = [d for d in tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
           ["dependencies"] if d.replace(" ", "").startswith("numba==")]
    assert pin == [f"numba=={jit.NUMBA_CHECKED}"], (
        f"pyproject.toml pins {pin}, transient.core.jit.NUMBA_CHECKED is {jit.NUMBA_CHECKED}: "
        "the replacements of numba internals are off under any other release; review them "
        "against the pinned release (this file's tests), then set NUMBA_CHECKED to it")
    assert numba.__version__ == jit.NUMBA_CHECKED and jit.REPLACEMENTS_ON, (
        f"numba {numba.__version__} is installed, transient.core.jit's replacements were checked "
        f"against {jit.NUMBA_CHECKED}: they are off (plain njit(cache=True))")


def test_replacements_apply_only_under_the_checked_release():
    assert jit._replacements_apply(jit.NUMBA_CHECKED)
    for other in ("0.68.0", "0.68.2", "0.69.0", "0.68.1rc1", "0.68.1+local", ""):
        assert not jit._replacements_apply(other), other


FALLBACK_PROBE = """
import importlib.util, sys, warnings
import numba
numba.__version__ = "0.0.0"  # as if another release were installed
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from transient.core import jit
from numba.core.caching import FunctionCache
from transient import precompile
from transient.assemble import build_model
from transient.core.integrator.tableaus import TABLEAUS
from transient.scene import load_scene

assert not jit.REPLACEMENTS_ON
assert [str(w.message).split(";")[0] for w in caught if w.category is RuntimeWarning] == [
    f"transient.core.jit: numba 0.0.0 is not {jit.NUMBA_CHECKED}, the release its "
    "replacements of numba internals were checked against"], [str(w.message) for w in caught]

spec = importlib.util.spec_from_file_location("kern", sys.argv[1])
module = sys.modules["kern"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
double, kernel, caller = module.double, module.triple, module.caller

assert caller(5) == 16 and kernel(2.5) == 7.5
for d in (double, kernel, caller):
    assert type(d._cache) is FunctionCache, type(d._cache)  # numba's own cache, on
    assert "compile" not in vars(d) and "get_call_template" not in vars(d)  # numba's own
scene = load_scene(sys.argv[2])
model, tab = build_model(scene)[0], TABLEAUS[scene.solver.method]
precompile._cores = lambda: 2
precompile.stepper_is_cached = lambda *args: False
assert precompile.start_helper(model, tab) is None  # no helper without the compile lock
print(";".join(str(s) for s in double.signatures))  # (none where caller was loaded)
print(sum(caller.stats.cache_hits.values()), sum(caller.stats.cache_misses.values()))
assert module.passes_kernel(2.0) == 6.0  # (a kernel as an argument: caller cached all the same)
print(sum(module.passes_kernel.stats.cache_hits.values()))
"""


FALLBACK_KERNELS = """
from transient.core.jit import compiled, kernel


@compiled
def double(x):
    return 2 * x


@kernel
def triple(x):
    return 3 * x


@compiled
def caller(x):
    return double(3) + double(x)


@kernel
def apply(f, x):
    return f(x)


@compiled
def passes_kernel(x):
    return apply(triple, x)
"""


def test_under_another_numba_release_compiled_is_plain_njit_with_a_warning(tmp_path):
    """The fallback: a numba release other than the checked one gets numba's own cache, compile
    and call templates (constants compiled as literals), a warning at import, no helper; a
    second process loads what the first saved."""
    source = tmp_path / "kern.py"
    source.write_text(FALLBACK_KERNELS)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    runs = [subprocess.run([sys.executable, "-c", FALLBACK_PROBE, str(source),
                            str(REPO / "cases" / "coasting_single.toml")], cwd=REPO, env=env,
                           capture_output=True, text=True, timeout=300) for _ in range(2)]
    for run in runs:
        assert run.returncode == 0, run.stderr
    # compiled, double once per constant; then loaded from numba's cache
    assert runs[0].stdout.splitlines() == ["(Literal[int](3),);(int64,)", "0 1", "0"], (
        runs[0].stdout)
    assert runs[1].stdout.splitlines() == ["", "1 0", "1"], runs[1].stdout


# ----------------------------------------------------------------------------------------------
# _RegistryFreeCache


def test_registry_free_cache_replaces_what_cache_true_sets():
    assert _statements(dispatcher.Dispatcher.enable_caching) == _code(
        "self._cache = FunctionCache(self.py_func)"), _relies(
        REGISTRY_FREE, "numba.core.dispatcher.Dispatcher.enable_caching (cache=True) setting "
        "self._cache = FunctionCache(self.py_func), which transient.core.jit.compiled replaces")
    assert caching.FunctionCache.load_overload is caching.Cache.load_overload, _relies(
        REGISTRY_FREE, "numba.core.caching.FunctionCache inheriting Cache.load_overload")


def test_registry_free_cache_is_numbas_load_overload_without_the_refresh():
    assert _parameters(caching.Cache.load_overload) == ["self", "sig", "target_context"], \
        _relies(REGISTRY_FREE, "numba.core.caching.Cache.load_overload(sig, target_context)")
    assert _statements(caching.Cache.load_overload) == _code("""
        target_context.refresh()
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)
        """), _relies(REGISTRY_FREE, "numba.core.caching.Cache.load_overload being refresh(), "
                      "then _load_overload under _guard_against_spurious_io_errors (it is that "
                      "without the refresh)")
    assert _parameters(caching.Cache._load_overload) == ["self", "sig", "target_context"], \
        _relies(REGISTRY_FREE, "numba.core.caching.Cache._load_overload(sig, target_context)")
    assert _parameters(caching.Cache._guard_against_spurious_io_errors) == ["self"], _relies(
        REGISTRY_FREE, "numba.core.caching.Cache._guard_against_spurious_io_errors()")
    assert _in_order(_statements(dispatcher.Dispatcher.compile), _code("""
        cres = self._cache.load_overload(sig, self.targetctx)
        if cres is not None:
            self._cache_hits[sig] += 1
        """)), _relies(REGISTRY_FREE, "numba.core.dispatcher.Dispatcher.compile loading through "
                       "self._cache.load_overload(sig, self.targetctx)")


def test_registry_free_cache_sets_up_what_the_refresh_would_for_loaded_code():
    """What refresh sets up that loaded machine code uses: symbols it links against. numba
    registers symbols (``llvmlite.binding.add_symbol``) in these modules only: the NRT's when it
    is initialized, the hash secrets when ``numba.cpython.hashing`` is imported, the rest when
    the target context is made (before any load) or by the parallel backend."""
    assert _statements(BaseContext.refresh) == _code("""
        self.load_additional_registries()
        self.install_registry(builtin_registry)
        self.typing_context.refresh()
        """), _relies(REGISTRY_FREE, "numba.core.base.BaseContext.refresh doing only "
                      "load_additional_registries, install_registry, typing_context.refresh")
    loads = _statements(cpu.CPUContext.load_additional_registries)
    assert loads[0] == "rtsys.initialize(self)", _relies(
        REGISTRY_FREE, "numba.core.cpu.CPUContext.load_additional_registries initializing the "
        "NRT by rtsys.initialize(self)")
    assert _parameters(rtsys.initialize) == ["ctx"], _relies(
        REGISTRY_FREE, "numba.core.runtime.rtsys.initialize(ctx)")
    root = Path(numba.__file__).parent
    registering = sorted(str(p.relative_to(root)) for p in root.rglob("*.py")
                         if "tests" not in p.relative_to(root).parts
                         and "add_symbol(" in p.read_text())
    assert registering == ["core/base.py", "core/externals.py", "core/runtime/nrt.py",
                           "cpython/hashing.py", "np/ufunc/parallel.py"], _relies(
        REGISTRY_FREE, "numba registering LLVM symbols only in these modules (it sets up the "
                       f"NRT's and the hash secrets itself; found {registering})")
    from numba.cpython import hashing  # noqa: F401

    for name in ("djbx33a_suffix", "siphash_k0", "siphash_k1"):
        assert ll.address_of_symbol(f"_numba_hashsecret_{name}"), _relies(
            REGISTRY_FREE, f"numba.cpython.hashing registering _numba_hashsecret_{name}")


LOAD_PROBE = """
import importlib.util, sys
import llvmlite.binding as ll
from transient.core.jit import compiled
spec = importlib.util.spec_from_file_location("kern", sys.argv[1])
module = sys.modules["kern"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
double, allocate, hash_new = (compiled(getattr(module, name))
                              for name in ("double", "allocate", "hash_new"))
assert double(2.5) == 5.0  # (loading it imports none of numba's string or array code)
secrets = [bool(ll.address_of_symbol(f"_numba_hashsecret_{name}"))
           for name in ("djbx33a_suffix", "siphash_k0", "siphash_k1")]
assert allocate(5) == 7.0
s = "piston" * 3
assert hash_new(s) == hash(s + "!"), (hash_new(s), hash(s + "!"))
print(*(sum(sum(f.stats.cache_hits.values()) for f in (double, allocate, hash_new)),
        sum(sum(f.stats.cache_misses.values()) for f in (double, allocate, hash_new))),
      "numba.np.arraymath" in sys.modules, *secrets)
"""

KERNELS = """
import numpy as np


def double(x):
    return 2 * x


def allocate(n):
    a = np.empty(n)
    for i in range(n):
        a[i] = i
    return a[n - 1] + a[n - 2]


def hash_new(s):
    return hash(s + "!")  # (a new string: its hash computed in machine code)
"""


@pytest.mark.slow  # (kernels compiled cold in processes of their own, in a fresh cache)
def test_registry_free_cache_loads_code_that_allocates_and_hashes(tmp_path):
    """Compiled in one process, loaded in another (with another hash seed) without the
    registries: once the first function is loaded the hash secrets are there (before any of
    numba's string code is loaded, which would set them up too); a function that allocates
    (the NRT); one that hashes a new string (the hash secrets)."""
    source = tmp_path / "kern.py"
    source.write_text(KERNELS)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    out = [subprocess.run([sys.executable, "-c", LOAD_PROBE, str(source)], cwd=REPO,
                          env={**env, "PYTHONHASHSEED": seed}, capture_output=True, text=True,
                          timeout=300) for seed in ("1", "2")]
    assert out[0].returncode == 0, out[0].stderr
    assert out[0].stdout.split() == ["0", "3", "True", "True", "True", "True"]  # compiled
    assert out[1].returncode == 0, f"{REGISTRY_FREE}: exit {out[1].returncode}, {out[1].stderr}"
    assert out[1].stdout.split() == ["3", "0", "False", "True", "True", "True"], (
        f"{REGISTRY_FREE} should load without numba's compiler registries, with the NRT and "
        f"the hash secrets set up (cache hits, misses, registries, secrets): {out[1].stdout}")


# ----------------------------------------------------------------------------------------------
# _compile_per_type


def test_per_type_compile_widens_what_dispatcher_get_call_template_compiles():
    template = dispatcher._DispatcherBase.get_call_template
    assert dispatcher.Dispatcher.get_call_template is template, _relies(
        PER_TYPE, "numba.core.dispatcher.Dispatcher inheriting _DispatcherBase.get_call_template")
    assert _parameters(template) == ["self", "args", "kws"], _relies(
        PER_TYPE, "numba.core.dispatcher.Dispatcher.get_call_template(args, kws)")
    assert _in_order(_statements(template), _code("""
        pysig, args = self._compiler.fold_argument_types(args, kws)
        self.compile(tuple(args))
        """)), _relies(PER_TYPE, "numba.core.dispatcher.Dispatcher.get_call_template compiling "
                       "exactly the argument types it is given, self.compile(tuple(args))")
    assert "self.dispatcher.get_call_template(args, kws)" in inspect.getsource(
        type_functions.Dispatcher.get_call_type), _relies(
        PER_TYPE, "numba.core.types.functions.Dispatcher.get_call_type typing a call from "
        "compiled code by the dispatcher's get_call_template, looked up on the dispatcher")
    assert types.unliteral(types.literal(3)) == types.int64, _relies(
        PER_TYPE, "numba.types.unliteral(Literal[int](3)) being int64")
    assert types.unliteral(types.literal(True)) == types.boolean, _relies(
        PER_TYPE, "numba.types.unliteral(Literal[bool](True)) being bool")


# ----------------------------------------------------------------------------------------------
# _compile_once_across_processes


def test_compile_lock_wraps_dispatcher_compile_which_tries_the_cache_first():
    assert _parameters(dispatcher.Dispatcher.compile) == ["self", "sig"], _relies(
        ACROSS_PROCESSES, "numba.core.dispatcher.Dispatcher.compile(sig)")
    assert _in_order(_statements(dispatcher.Dispatcher.compile), _code("""
        scope.enter_context(global_compiler_lock)
        args, return_type = sigutils.normalize_signature(sig)
        existing = self.overloads.get(tuple(args))
        cres = self._cache.load_overload(sig, self.targetctx)
        cres = self._compiler.compile(args, return_type)
        self._cache.save_overload(sig, cres)
        """)), _relies(ACROSS_PROCESSES, "numba.core.dispatcher.Dispatcher.compile, under "
                       "numba's compiler lock, looking up self.overloads[tuple(args)], then "
                       "the cache, then compiling and saving")
    calls = [line for fn in (dispatcher._DispatcherBase._compile_for_args,
                             dispatcher._DispatcherBase.get_call_template)
             for line in inspect.getsource(fn).splitlines() if ".compile(" in line]
    assert [c.split("=")[-1].strip() for c in calls] == [
        "self.compile(tuple(argtypes))", "self.compile(tuple(args))"], _relies(
        ACROSS_PROCESSES, "numba compiling for a call from Python (_compile_for_args) and "
        f"from compiled code (get_call_template) through self.compile (found {calls})")
    assert sigutils.normalize_signature((types.float64,)) == ((types.float64,), None), _relies(
        ACROSS_PROCESSES, "numba.core.sigutils.normalize_signature returning (args, return)")


def test_compile_lock_runs_under_numbas_reentrant_compiler_lock():
    done = threading.Event()

    def nested():
        with global_compiler_lock:
            with global_compiler_lock:
                done.set()

    worker = threading.Thread(target=nested, daemon=True)
    worker.start()
    worker.join(10.0)
    assert done.is_set(), _relies(
        ACROSS_PROCESSES, "numba.core.compiler_lock.global_compiler_lock being reentrant")


def test_compile_lock_is_per_function_because_numba_saves_by_read_modify_write(kern):
    assert _statements(caching.IndexDataCacheFile.save) == _code("""
        overloads = self._load_index()
        try:
            data_name = overloads[key]
        except KeyError:
            existing = set(overloads.values())
            for i in itertools.count(1):
                data_name = self._data_name(i)
                if data_name not in existing:
                    break
            overloads[key] = data_name
            self._save_index(overloads)
        self._save_data(data_name, data)
        """), _relies(ACROSS_PROCESSES, "numba.core.caching.IndexDataCacheFile.save being a "
                      "read-modify-write of the function's index (why the lock is per function)")
    cache = caching.FunctionCache(kern.double)
    assert isinstance(cache._cache_path, str) and isinstance(cache._impl.filename_base, str), \
        _relies(ACROSS_PROCESSES, "numba.core.caching.Cache._cache_path and "
                "_impl.filename_base (where the lock file goes, and its name)")
    assert _parameters(cache._impl.locator.ensure_cache_path) == [], _relies(
        ACROSS_PROCESSES, "numba.core.caching's locator.ensure_cache_path()")
    cache._impl.locator.ensure_cache_path()
    assert os.path.isdir(cache._cache_path), _relies(
        ACROSS_PROCESSES, "locator.ensure_cache_path() making the cache folder")


# ----------------------------------------------------------------------------------------------
# transient.precompile


def test_compile_helper_reads_numbas_cache_index(kern):
    """``precompile.stepper_is_cached`` (and the helper's tests) read a function's saved
    signatures from its index."""
    double = jit.compiled(kern.double)
    assert double._cache._cache_file._load_index() == {}, _relies(
        HELPER, "numba.core.caching.IndexDataCacheFile._load_index() ({} when nothing is saved)")
    assert double(2) == 4
    keys = list(double._cache._cache_file._load_index())
    assert [key[0] for key in keys] == [(types.int64,)], _relies(
        HELPER, "numba.core.caching.IndexDataCacheFile._load_index() keyed by (signature, ...)"
        f" (found {keys})")
    codegen = double.targetctx.codegen()
    assert keys == [double._cache._index_key((types.int64,), codegen)], _relies(
        HELPER, "numba.core.caching.Cache._index_key(sig, codegen), the key numba loads by")
    assert keys[0][1] == codegen.magic_tuple() and keys[0][1][1] == codegen._get_host_cpu_name(), \
        _relies(HELPER, "numba's index key holding codegen.magic_tuple(): (triple, CPU name, "
                "features)")


# ----------------------------------------------------------------------------------------------
# _inlined_by_llvm

INLINED = "transient.core.jit._inlined_by_llvm"


def test_llvm_inlining_marks_the_module_numba_links_into_callers_and_caches():
    link = codegen.CPUCodeLibrary.finalize
    assert _in_order(_statements(link), _code("""
        self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        self._optimize_final_module()
        """)), _relies(INLINED, "numba.core.codegen.CPUCodeLibrary.finalize linking each callee's "
                       "_get_module_for_linking() before optimizing the whole module")
    assert _in_order(_statements(codegen.CPUCodeLibrary.serialize_using_object_code), _code("""
        data = (self._get_compiled_object(), self._get_module_for_linking().as_bitcode())
        """)), _relies(INLINED, "numba.core.codegen.CPUCodeLibrary.serialize_using_object_code "
                       "caching the module for linking beside the machine code")
    assert _parameters(ll.ValueRef.add_function_attribute) == ["self", "attr"], _relies(
        INLINED, "llvmlite.binding.ValueRef.add_function_attribute(attr)")
    assert jit._symbol_prefix(rhs_derivative()) == "_ZN9transient4core5model3rhs10derivativeB", _relies(
        INLINED, "numba.core.itanium_mangler.mangle_identifier (numba names a function's "
        "symbols after its mangled qualified name, then B and its ABI tags)")


LINKED_ONLY = "transient.core.jit._linked_only"


def test_linked_only_libraries_rely_on_how_numba_lowers_links_and_caches():
    lowering = cpu.CPUContext.get_executable
    assert _parameters(lowering) == ["self", "library", "fndesc", "env"], _relies(
        LINKED_ONLY, "numba.core.cpu.CPUContext.get_executable(library, fndesc, env)")
    assert _in_order(_statements(lowering), _code("""
        fnptr = library.get_pointer_to_function(fndesc.llvm_cpython_wrapper_name)
        """)), _relies(LINKED_ONLY, "CPUContext.get_executable finalizing the library by taking "
                       "the address of its Python wrapper (null without one)")
    assert _in_order(_statements(typed_passes.BaseNativeLowering.run_pass), _code("""
        if not flags.no_cpython_wrapper:
            lower.create_cpython_wrapper(flags.release_gil)
        cfunc = targetctx.get_executable(library, fndesc, env)
        """)), _relies(LINKED_ONLY, "numba.core.typed_passes.BaseNativeLowering.run_pass adding "
                       "the Python wrapper to the library before get_executable, only without "
                       "no_cpython_wrapper")
    assert _in_order(_statements(compiler.CompileResult._rebuild.__func__), _code("""
        library = target_context.codegen().unserialize_library(libdata)
        cfunc = target_context.get_executable(library, fndesc, env)
        for env in referenced_envs:
            library.codegen.set_env(env.env_name, env)
        """)), _relies(LINKED_ONLY, "numba.core.compiler.CompileResult._rebuild unserializing the "
                       "library, then get_executable, then set_env for its environments")
    assert _in_order(_statements(codegen.CPUCodeLibrary.finalize), _code("""
        self._raise_if_finalized()
        self._reload_init.update(library._reload_init)
        self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        self._optimize_final_module()
        self._final_module.verify()
        self._finalize_final_module()
        """)), _relies(LINKED_ONLY, "numba.core.codegen.CPUCodeLibrary.finalize: what "
                       "_finalize_linked_only does of it (the linking) and leaves out")
    assert _in_order(_statements(codegen.CPUCodeLibrary._get_module_for_linking), _code("""
        self._ensure_finalized()
        if self._shared_module is not None:
            return self._shared_module
        mod = self._final_module
        """)), _relies(LINKED_ONLY, "CPUCodeLibrary._get_module_for_linking reading "
                       "_shared_module, else _final_module, of a finalized library")
    assert _in_order(_statements(codegen.CPUCodeLibrary._unserialize.__func__), _code("""
        name, kind, data = state
        self = codegen.create_library(name)
        """)), _relies(LINKED_ONLY, "CPUCodeLibrary._unserialize reading (name, kind, data)")
    assert _in_order(_statements(codegen.JITCPUCodegen.set_env), _code("""
        gvaddr = self._engine.get_global_value_address(env_name)
        """)), _relies(LINKED_ONLY, "numba.core.codegen.JITCPUCodegen.set_env writing at the "
                       "environment's address in the execution engine")


def rhs_derivative():
    from transient.core.model.rhs import derivative

    return derivative.py_func


INLINE_KERNELS = """
import numpy as np
from transient.core.jit import kernel


@kernel(inline=True)
def scaled(t, x):
    return t[0][1] * x + t[1]


@kernel
def offset(t, x):  # (recursive: LLVM's own heuristics leave it a call)
    if x < 1.0:
        return t[0][0] + x
    return offset(t, x - 1.0) + offset(t, x - 2.0)


@kernel
def caller(t, x):
    return scaled(t, x) + scaled(t, 2.0 * x) + offset(t, x)
"""

INLINE_PROBE = """
import importlib.util, sys
import numpy as np
spec = importlib.util.spec_from_file_location("kern", sys.argv[1])
module = sys.modules["kern"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
from transient.core.jit import _symbol_prefix
t = (np.arange(3.0), 0.5)
if sys.argv[2] == "callees":  # compiled and cached, as the compile helper does
    from numba import float64, typeof
    module.scaled.compile((typeof(t), float64))
    module.offset.compile((typeof(t), float64))
    print(module.scaled(t, 1.0))  # (from Python: the Python entry, compiled apart)
elif sys.argv[2] == "python":
    print(module.scaled(t, 1.0), sum(module.scaled.python_entry.stats.cache_hits.values()),
          sum(module.scaled.stats.cache_hits.values()))
else:
    assert module.caller(t, 2.0) == (2.0 + 0.5) + (4.0 + 0.5) + module.offset.py_func(t, 2.0)
    entry = module.caller.python_entry
    ir = entry.inspect_llvm(entry.signatures[0])
    calls = [line for line in ir.splitlines() if " call " in line]
    callees = [c.library for d in (module.scaled, module.offset) for c in d.overloads.values()]
    print(any(_symbol_prefix(module.scaled.py_func) in c for c in calls),
          any(_symbol_prefix(module.offset.py_func) in c for c in calls),
          sum(module.scaled.stats.cache_hits.values()),
          len(callees) == 2 and all(lib._linked_only for lib in callees),
          any(getattr(lib, "_compiled_object", None) for lib in callees))
"""


@pytest.mark.slow  # (kernels compiled cold in processes of their own, in a fresh cache)
def test_a_kernel_marked_inline_is_inlined_by_llvm_also_when_loaded_from_the_cache(tmp_path):
    """``kernel(inline=True)``: no call to it is left in a caller's optimized code, whether the
    callee was compiled with the caller or loaded from numba's cache (where the compile helper
    saved it); a plain kernel stays a call, which shows the check sees calls. Called from
    Python, a kernel runs its Python entry, compiled and cached apart from the kernel. Both
    callees' libraries are linked only, compiled or loaded: no machine code of their own
    (:func:`transient.core.jit._linked_only`), while the caller's Python entry runs."""
    source = tmp_path / "kern.py"
    source.write_text(INLINE_KERNELS)

    def probe(cache: str, what: str) -> list[str]:
        env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / cache)}
        run = subprocess.run([sys.executable, "-c", INLINE_PROBE, str(source), what], cwd=REPO,
                             env=env, capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        return run.stdout.split()

    # inlined, a call, compiled; linked only, no machine code
    assert probe("together", "caller") == ["False", "True", "0", "True", "False"]
    assert probe("apart", "callees") == ["1.5"]
    assert probe("apart", "python") == ["1.5", "1", "0"]  # the Python entry, loaded
    assert probe("apart", "caller") == ["False", "True", "1", "True", "False"]  # the same, loaded


# ----------------------------------------------------------------------------------------------
# _SharedLocator

SHARED = "transient.core.jit._SharedLocator"

SHARE_PROBE = """
import importlib.util, sys
spec = importlib.util.spec_from_file_location("kern", sys.argv[1])
module = sys.modules["kern"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
from transient.core.jit import compiled
double = compiled(module.double)
assert double(2.5) == float(sys.argv[2])
print(sum(double.stats.cache_hits.values()), sum(double.stats.cache_misses.values()))
"""


def test_copies_of_the_sources_at_other_paths_share_the_cache_and_other_sources_do_not(tmp_path):
    """A cluster's nodes or a fresh clone: the same module at another path (another mtime too)
    loads what the first saved; changed contents compile afresh."""
    first, second, changed = (tmp_path / name / "kern.py" for name in ("a", "b", "c"))
    for path, body in ((first, "2 * x"), (second, "2 * x"), (changed, "3 * x")):
        path.parent.mkdir()
        path.write_text(f"def double(x):\n    return {body}\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def probe(source, result) -> list[str]:
        run = subprocess.run([sys.executable, "-c", SHARE_PROBE, str(source), result], cwd=REPO,
                             env=env, capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        return run.stdout.split()

    assert probe(first, "5.0") == ["0", "1"]  # compiled
    assert probe(second, "5.0") == ["1", "0"], _relies(
        SHARED, "numba's cache folder being the locator's get_cache_path()")
    assert probe(changed, "7.5") == ["0", "1"], _relies(
        SHARED, "numba's index keyed by a hash of the source's contents (get_source_stamp)")
    assert [p.name for p in (tmp_path / "numba").iterdir() if "kern" in p.name] == ["kern"]


def test_shared_locator_is_numbas_user_provided_locator_with_another_folder():
    assert _parameters(caching.UserProvidedCacheLocator.__init__) == ["self", "py_func",
                                                                     "py_file"], _relies(
        SHARED, "numba.core.caching.UserProvidedCacheLocator(py_func, py_file)")
    assert "self._cache_path = os.path.join(config.CACHE_DIR, cache_subpath)" in _statements(
        caching.UserProvidedCacheLocator.__init__), _relies(
        SHARED, "UserProvidedCacheLocator keeping its folder in self._cache_path")
    assert caching.UserProvidedCacheLocator.get_cache_path(
        type("L", (), {"_cache_path": "x"})()) == "x"
    assert "_locator_classes" in vars(caching.CompileResultCacheImpl) or hasattr(
        caching.CompileResultCacheImpl, "_locator_classes"), _relies(
        SHARED, "numba.core.caching._CacheImpl._locator_classes")


# ----------------------------------------------------------------------------------------------
# typed_by_fingerprint and _TypesKeptAlive

FINGERPRINT = "transient.core.jit.typed_by_fingerprint"
KEPT_ALIVE = "transient.core.jit._TypesKeptAlive"


def test_fingerprint_covers_what_typed_by_fingerprint_leaves_to_it():
    from numba._dispatcher import compute_fingerprint
    from numba.core.typing.typeof import typeof_impl

    kern = jit.kernel(lambda x: x)
    with pytest.raises(NotImplementedError):  # (why the kernels are keyed apart)
        compute_fingerprint((1.0, kern))
    assert compute_fingerprint((1.0, (2, 3.0))) != compute_fingerprint((1.0, (2.0, 3))), _relies(
        FINGERPRINT, "numba._dispatcher.compute_fingerprint telling apart the types of a tuple's "
        "fields, nested tuples included")
    assert typeof_impl.dispatch(tuple).__name__ == "_typeof_tuple", _relies(
        FINGERPRINT, "numba typing a tuple by typeof_impl's registration for tuple")


def test_types_kept_alive_stands_for_the_set_numba_only_adds_to_and_clears():
    source = inspect.getsource(dispatcher)
    uses = {line.strip() for line in source.splitlines() if "_types_active_call" in line}
    assert uses == {"self._types_active_call = set()", "self._types_active_call.add(tp)",
                    "self._types_active_call.clear()"}, _relies(
        KEPT_ALIVE, f"numba's Dispatcher using _types_active_call by add and clear alone: {uses}")
