"""The compile helper (:mod:`transient.precompile`) compiles each of the stepper's callees with the
argument types the stepper calls it with: after the helper's compile and the stepper's (in either
order, on a cold or a warm cache), each callee's numba cache holds one signature, the helper's.
A wrong type would leave two (the helper's and the stepper's own), and the helper's work wasted."""
from __future__ import annotations

from dataclasses import replace

from transient.assemble import build_model
from transient.core.tableaus import TABLEAUS
from transient.precompile import CALLEES, compile_callees, signature
from transient.scene import load_scene
from transient.run import integrate

from conftest import CASES


def test_helper_compiles_the_signatures_the_stepper_calls():
    scene = load_scene(CASES / "coasting_single.toml")
    scene = replace(scene, run=replace(scene.run, revolutions=1.0))
    model, tab = build_model(scene)[0], TABLEAUS[scene.solver.method]
    compile_callees(model, tab)
    assert integrate(scene).complete  # (the stepper compiled, or loaded from the cache)
    for fn in CALLEES:
        saved = [key[0] for key in fn._cache._cache_file._load_index()]
        assert saved == [signature(fn, model, tab)], (fn.__name__, saved)
