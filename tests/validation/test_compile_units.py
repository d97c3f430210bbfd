"""The stepper's compile units (:func:`transient.core.jit.kernel`): every kernel is compiled on its
own, and LLVM inlines those marked ``inline=True`` (the per-step work: the right-hand side, the
step, the pieces of the loop) at each call site, so that no call copies the Model's flattened
fields on the hot path."""
from __future__ import annotations

from dataclasses import replace

from transient.core import jit, rk, stepper
from transient.run import simulate
from transient.scene import load_scene

from conftest import CASES


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
    assert any(n.startswith(jit._symbol_prefix(rk._dense.py_func)) for n in names)
