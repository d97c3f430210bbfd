"""A run's own error, measured: how far the same scene run at a hundredth of its rtol and atol puts
a value. The tests share it (on ``pythonpath``, pyproject) where a result of the adaptive stepper
is compared with something that took other steps — another model of the same physics, the golden
values (``tests/cli/golden.py``) on another CPU — and so can agree only to the errors both carry.

Those errors are not one step's tolerance: an end state after tens of revolutions sums the errors
of thousands of steps (and the phase error, through dω/dφ, moves ω too), and a kink inside a step
(a friction map's grid line, a side force changing side) is met at an error the embedded
estimate only approximates. So they are measured rather than assumed: at a hundredth of the
tolerance a fifth- or eighth-order method's error falls by 100^(5/6) or more, so the distance
from that run is the value's error at the scene's tolerance, to a few per cent.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from transient.run import integrate

#: The reference run's rtol and atol are the scene's divided by this.
TIGHTER = 100.0
#: Two results of the same physics that took other steps differ by at most the sum of their
#: errors; each error is one run's estimate, so it is counted twice.
AGREE = 2.0
#: How many times its error a value of one scene may move where the steps differ (another CPU's
#: rounding): runs with numba, numpy and OpenBLAS built for other CPUs moved every value of every
#: scene in ``cases/`` by at most 1.2 times its error, apart from rounding noise in values that are
#: zero in exact arithmetic (which a floor of rtol times their scale covers).
MOVE = 10.0


def tightened(scene):
    """``scene`` with its rtol and atol divided by :data:`TIGHTER`."""
    return replace(scene, solver=replace(scene.solver, rtol=scene.solver.rtol / TIGHTER,
                                         atol=scene.solver.atol / TIGHTER))


def errors(scene, data, columns) -> dict[str, float]:
    """The error of each of ``columns`` in ``data`` (a run of ``scene``): the largest distance,
    over the samples, from the same scene run at the tighter tolerance (whose samples sit at the
    same output angles)."""
    ref = integrate(tightened(scene))
    assert ref.complete, ref.message
    out = {}
    for c in columns:
        x, y = data.trajectory[c], ref.trajectory[c]
        assert x.shape == y.shape, (c, x.shape, y.shape)
        out[c] = float(np.nanmax(np.abs(x - y), initial=0.0))
    return out


def assert_reproduces(scene, data, recorded: dict[str, float]) -> None:
    """The end values of ``data`` (a run of ``scene``) are the ``recorded`` ones, each to
    :data:`MOVE` times its error (:func:`errors`) plus one step's tolerance, rtol·|x| + atol."""
    err = errors(scene, data, recorded)
    rtol, atol = scene.solver.rtol, scene.solver.atol
    for name, value in recorded.items():
        x = float(data.trajectory[name][-1])
        bound = MOVE * err[name] + rtol * abs(value) + atol
        assert abs(x - value) <= bound, (name, x, value, bound)


def assert_agree(scene_a, a, scene_b, b, columns) -> None:
    """Runs ``a`` of ``scene_a`` and ``b`` of ``scene_b`` (the same physics, other models or
    other paths, at one tolerance) agree in each of ``columns`` at every sample to
    :data:`AGREE` times the sum of their errors (:func:`errors`), plus one step's tolerance,
    rtol·max|x| + atol, for a value whose error happens to vanish."""
    ea, eb = errors(scene_a, a, columns), errors(scene_b, b, columns)
    rtol, atol = scene_a.solver.rtol, scene_a.solver.atol
    for c in columns:
        x, y = a.trajectory[c], b.trajectory[c]
        bound = AGREE * (ea[c] + eb[c]) + rtol * float(np.nanmax(np.abs(y))) + atol
        worst = float(np.nanmax(np.abs(x - y), initial=0.0))
        print(f"{c}: apart by {worst:.2e} at most, errors {ea[c]:.2e} and {eb[c]:.2e}")
        assert worst <= bound, (c, worst, bound, ea[c], eb[c])
