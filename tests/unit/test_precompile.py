"""The compile helper (:mod:`transient.precompile`): a process that compiles the stepper's callees
into the shared numba cache while the stepper is compiled, started only where it can help.

(Which argument types it compiles is checked against the stepper's own calls in
``tests/validation/test_compile_helper.py``: that needs the stepper compiled.)"""
from __future__ import annotations

import pickle
from pathlib import Path

from numba import config, types

from transient import precompile
from transient.assemble import build_model
from transient.core import jit
from transient.core.integrator.tableaus import TABLEAUS
from transient.core.stepper import breakpoints
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"


def _model_and_tableau():
    scene = load_scene(CASES / "coasting_single.toml")
    return build_model(scene)[0], TABLEAUS[scene.solver.method]


def test_a_helper_process_compiles_into_the_shared_cache_for_this_processs_cpu(tmp_path,
                                                                              monkeypatch):
    """The helper compiles into the cache folder and for the CPU of this process's numba
    settings, also where a program set them in ``numba.config`` rather than the environment
    (here: the x86-64 baseline, ``generic`` with no extra features, unlike any host's)."""
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(config, "CPU_NAME", "generic")
    monkeypatch.setattr(config, "CPU_FEATURES", "")
    monkeypatch.setattr(precompile, "stepper_is_cached", lambda *args: False)
    monkeypatch.setattr(precompile, "_cores", lambda: 2)
    helper = precompile.start_helper(*_model_and_tableau(), callees=(breakpoints.next_breakpoint,))
    assert helper is not None
    assert helper.wait(timeout=300) == 0
    saved = {p.suffix: p for p in tmp_path.rglob("breakpoints.next_breakpoint-*")}
    assert {".nbi", ".nbc"} <= set(saved), sorted(tmp_path.rglob("*"))  # (index, machine code)
    with open(saved[".nbi"], "rb") as index:
        pickle.load(index)  # (numba's version)
        _, entries = pickle.loads(index.read())
    assert [key[1][1:] for key in entries] == [("generic", "")], list(entries)  # (CPU, features)


def test_a_function_saved_for_another_cpu_is_not_cached_for_this_one(kern, monkeypatch):
    """``is_cached`` asks numba's index for the whole key numba loads by: a cache folder that
    other CPUs' processes share may hold the signature compiled for another CPU only."""
    sig = (types.int64,)
    assert not precompile.is_cached(jit.compiled(kern.double), sig)
    assert jit.compiled(kern.double)(2) == 4  # (compiled, and saved)
    fresh = jit.compiled(kern.double)  # (another process's view: nothing compiled in it)
    assert not fresh.overloads and precompile.is_cached(fresh, sig)
    codegen = type(fresh.targetctx.codegen())
    host = codegen.magic_tuple
    monkeypatch.setattr(codegen, "magic_tuple",
                        lambda self: (host(self)[0], "generic", ""))  # (the x86-64 baseline)
    assert not precompile.is_cached(fresh, sig)


def test_no_helper_where_it_cannot_help(monkeypatch):
    model, tab = _model_and_tableau()
    monkeypatch.setattr(precompile, "stepper_is_cached", lambda *args: True)
    monkeypatch.setattr(precompile, "_cores", lambda: 2)
    assert precompile.start_helper(model, tab) is None  # cached: nothing to compile
    monkeypatch.setattr(precompile, "stepper_is_cached", lambda *args: False)
    monkeypatch.setattr(precompile, "_cores", lambda: 1)
    assert precompile.start_helper(model, tab) is None  # one core: it would only take turns
    monkeypatch.setattr(precompile, "_cores", lambda: 2)

    def no_process(*args, **kwargs):
        raise OSError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(precompile.subprocess, "Popen", no_process)
    assert precompile.start_helper(model, tab) is None  # no process to be had: none, no error


def test_stop_helper_ends_the_process(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(precompile, "stepper_is_cached", lambda *args: False)
    monkeypatch.setattr(precompile, "_cores", lambda: 2)
    helper = precompile.start_helper(*_model_and_tableau())  # (all callees: minutes of work)
    precompile.stop_helper(helper)
    assert helper.poll() is not None
    precompile.stop_helper(None)  # (no helper: nothing to do)


def test_the_stepper_counts_as_cached_in_the_models_variant_only(monkeypatch):
    """A cache holding the stepper's plain variant leaves a scene of the full variant to compile
    with the helper's help, and the other way round (:func:`transient.core.model.layout.extras_of`)."""
    plain, tab = _model_and_tableau()
    full = build_model(load_scene(CASES / "gots_diesel_friction.toml"))[0]
    saved = {}

    class Stepper:  # (numba's dispatcher as stepper_is_cached reads it)
        py_func = precompile.STEPPER.py_func
        overloads = {}

        class targetctx:
            @staticmethod
            def codegen():
                return "cpu"

        class _cache:
            @staticmethod
            def _index_key(sig, codegen):
                return sig, codegen

            class _cache_file:
                @staticmethod
                def _load_index():
                    return saved

    monkeypatch.setattr(precompile, "STEPPER", Stepper)
    assert not precompile.stepper_is_cached(plain, tab)
    saved[(precompile.signature(Stepper, plain, tab), "cpu")] = 1  # (saved in the cache)
    assert precompile.stepper_is_cached(plain, tab)
    assert not precompile.stepper_is_cached(full, tab)
    Stepper.overloads = {precompile.signature(Stepper, full, tab): None}  # (compiled here)
    assert precompile.stepper_is_cached(full, tab)
