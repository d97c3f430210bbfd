"""The stepper's compile units (:func:`transient.core.jit.kernel`): every kernel is compiled on its
own, and LLVM inlines those marked ``inline=True`` (the per-step work: the right-hand side, the
step, the pieces of the loop) at each call site, so that no call copies the Model's flattened
fields on the hot path; and the kernels' plain variant (:func:`transient.core.model.layout.extras_of`)
changes no result of a scene it serves. (That a plain scene's run compiles none of the other
variant's feature kernels is checked on an empty cache in ``tests/cli/test_warmup.py``.)"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from conftest import CASES

from transient.assemble import build_model
from transient.core import jit, stepper
from transient.core.integrator import rk
from transient.core.model import layout
from transient.run import simulate
from transient.scene import load_scene


def _functions_in_stepper() -> list[str]:
    """The names of the functions the stepper's optimized module defines or calls."""
    names = []
    for cres in stepper.advance.overloads.values():
        names += [fn.name for fn in cres.library._get_module_for_linking().functions]
    return names


def test_the_stepper_calls_no_kernel_marked_inline():
    scene = load_scene(CASES / "gots_diesel_friction.toml")
    simulate(replace(scene, run=replace(scene.run, revolutions=1.0, t_end=float("inf"))))
    names = _functions_in_stepper()
    inlined = tuple(jit._INLINED_BY_LLVM)
    assert len(inlined) > 50  # (the right-hand side, the step, the loop's pieces, …)
    assert [n for n in names if n.startswith(inlined)] == []
    # a kernel left a call (the dense output: run when output or an event needs it) is seen
    assert any(n.startswith(jit._symbol_prefix(rk.dense.py_func)) for n in names)


def test_a_plain_scene_runs_the_same_in_either_variant(monkeypatch):
    """The plain variant leaves out only code that a plain scene never reaches: the default scene
    run with the full variant's kernels gives the same trajectory to the last bit."""
    scene = load_scene(CASES / "swash_plate_4cyl.toml")
    scene = replace(scene, run=replace(scene.run, revolutions=20.0, t_end=float("inf")))
    assert layout.extras_of(build_model(scene)[0]) is None
    plain = simulate(scene).trajectory
    monkeypatch.setattr(layout, "extras_of", lambda m: True)
    full = simulate(scene).trajectory
    assert stepper.advance.signatures and len(stepper.advance.signatures) >= 2
    for column in ("t", "phi", "omega", "epsilon", "M_gas", "M_load", "fuel", "W_gas", "W_load"):
        assert np.array_equal(plain[column], full[column]), column
