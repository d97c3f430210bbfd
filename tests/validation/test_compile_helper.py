"""The compile helper (:mod:`transient.precompile`) compiles each of the stepper's callees with the
argument types the stepper calls it with: after the helper's compile and the stepper's (in either
order, on a cold or a warm cache), each callee's numba cache holds the helper's signature and no
other but the one of the kernels' other variant (:func:`transient.core.model.layout.extras_of`). A wrong
type would leave one more (the stepper's own), and the helper's work wasted. (The integrator's
kernels are compiled for other derivatives too, the plain ODEs of ``tests/plain_odes.py``: those
signatures are not the stepper's; nor are those of another mechanism's or another method's
stepper.)"""
from __future__ import annotations

import re
from dataclasses import replace

from conftest import CASES
from numba import typeof

from transient.assemble import build_model
from transient.core.integrator.tableaus import TABLEAUS
from transient.core.jit import _KernelArgument
from transient.core.model.layout import extras_of
from transient.precompile import CALLEES, compile_callees, signature
from transient.run import integrate
from transient.scene import load_scene

#: The kernels a signature carries as values (the Model's: its mechanism's, a rigid or an elastic
#: shaft line's; the derivative): each such choice is a stepper compiled on its own, so the
#: shared cache also holds other mechanisms' and elastic lines' signatures, not this scene's.
MODEL_KERNEL = re.compile(r"kernel\((transient\.[\w.]+)\)")


def test_helper_compiles_the_signatures_the_stepper_calls():
    scene = load_scene(CASES / "coasting_single.toml")
    scene = replace(scene, run=replace(scene.run, revolutions=1.0))
    model, tab = build_model(scene)[0], TABLEAUS[scene.solver.method]
    # (a scene with pairs: the kernels' full variant, the other signature the cache may hold)
    full = build_model(load_scene(CASES / "gots_diesel_friction.toml"))[0]
    assert extras_of(model) is None and extras_of(full) is True
    compile_callees(model, tab)
    assert integrate(scene).complete  # (the stepper compiled, or loaded from the cache)
    other_methods = {typeof(t) for t in TABLEAUS.values()} - {typeof(tab)}
    for fn in CALLEES:
        ours = set(MODEL_KERNEL.findall(f"{signature(fn, model, tab)}{signature(fn, full, tab)}"))
        saved = [key[0] for key in fn._cache._cache_file._load_index()
                 if not any(isinstance(a, _KernelArgument) and not a.key[0].startswith("transient.")
                            for a in key[0]) and set(MODEL_KERNEL.findall(str(key[0]))) <= ours
                 and not any(a in other_methods for a in key[0])]
        assert signature(fn, model, tab) in saved, (fn.__name__, saved)
        assert set(saved) <= {signature(fn, model, tab), signature(fn, full, tab)}, (
            fn.__name__, saved)
