"""The shaft line's Jacobian for the W-method (:mod:`transient.core.model.line_jacobian`) against
central differences of the compiled derivative (:func:`transient.core.model.rhs.derivative`) of
the in-line six (``cases/inline6_damper.toml``) at a twisted state, in crank angle and in time:
entry for entry where the module says it is exact — on a line without absolute damping, every
entry but a cylinder's station's energy (speed) rate against its own twist, where the gas
moment's angle dependence is left out — and every coupling of the line's states that the
derivative has lies inside the band :func:`~transient.core.model.line_jacobian.line_band`
allocates."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core.model import layout, rhs, shaft
from transient.core.model.line_jacobian import line_band, line_jacobian
from transient.core.model.work import work_array
from transient.run import _initial_state
from transient.scene import load_scene
from transient.shaft import ShaftLine

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"
RNG = np.random.default_rng(3)


def _scene(absolute: bool):
    sc = load_scene(CASE)
    stations = sc.shaft.stations if absolute else tuple(
        dataclasses.replace(s, damping=0.0) for s in sc.shaft.stations)
    return dataclasses.replace(sc, shaft=dataclasses.replace(sc.shaft, stations=stations))


def _twisted_state(scene, model, angle_mode):
    """A state near the run's start, each dof twisted by up to a milliradian and its speed off
    by up to 2 %; in crank angle the speeds as energies (the stepper's conversion)."""
    y, _, ist = _initial_state(scene, model)
    lo = layout.line_index(model)
    n = layout.n_line_states(model)
    y[lo:lo + n:2] = RNG.uniform(-1e-3, 1e-3, n // 2)
    y[lo + 1:lo + n:2] *= RNG.uniform(0.98, 1.02, n // 2)
    y[layout.PHI] = 0.7
    wk = work_array(model)
    if angle_mode:
        J = shaft.ref_inertia(model, y[layout.PHI], wk)
        y[layout.KINETIC] = 0.5 * J * y[layout.OMEGA] ** 2
        shaft.line_mode(model, y, True, wk)
    return y, ist[:layout.N_SWITCHES].copy(), wk


def _derivative(model, angle_mode, y, sw, wk):
    out = np.empty_like(y)
    rhs.derivative(model, layout.extras_of(model), angle_mode, y, y[layout.PHI], sw, wk, out)
    return out


def _jacobians(absolute: bool, angle_mode: bool):
    """(the module's J over the line's block as a dense matrix, the central differences of the
    derivative over the same block, the scene's line, the model)."""
    scene = _scene(absolute)
    model = build_model(scene)[0]
    y, sw, wk = _twisted_state(scene, model, angle_mode)
    lo = layout.line_index(model)
    rows, kb = line_band(model.line)
    band = np.zeros((rows, 2 * kb + 1))
    f0 = _derivative(model, angle_mode, y, sw, wk)
    assert line_jacobian(model, angle_mode, y, f0, wk, band) == lo
    J = np.zeros((rows, rows))
    for r in range(rows):
        for c in range(max(0, r - kb), min(rows, r + kb + 1)):
            J[r, c] = band[r, c - r + kb]
    fd = np.zeros((rows, rows))
    for c in range(rows):
        h = 1e-7 if c % 2 == 0 else 1e-6 * abs(y[lo + c])  # (a twist; an energy or a speed)
        up, down = y.copy(), y.copy()
        up[lo + c] += h
        down[lo + c] -= h
        fd[:, c] = (_derivative(model, angle_mode, up, sw, wk)[lo:lo + rows]
                    - _derivative(model, angle_mode, down, sw, wk)[lo:lo + rows]) / (2 * h)
    return J, fd, ShaftLine(scene), model


@pytest.mark.parametrize("angle_mode", [True, False])
def test_the_jacobian_is_the_derivatives_where_it_claims_to_be(angle_mode):
    J, fd, line, model = _jacobians(absolute=False, angle_mode=angle_mode)
    ref = int(model.line[0, layout.LM_REF])
    load = int(model.line[0, layout.LM_LOAD])
    carriers = set(model.line[1:1 + model.ncyl, 0].astype(int))
    dofs = [d for d in range(line.n) if d != ref]  # (in the block's order)
    scale = np.max(np.abs(fd), axis=1, keepdims=True)  # (each row's own)
    exact = np.ones_like(J, dtype=bool)
    for p, d in enumerate(dofs):
        if d in carriers:
            exact[2 * p + 1, 2 * p] = False
        if d == load:
            exact[2 * p + 1, 2 * p + 1] = False
    assert exact.sum() == exact.size - 6  # (the six throws; the load is at the reference)
    error = np.abs(J - fd) / scale
    assert np.max(error[exact]) <= 1e-6, np.unravel_index(np.argmax(error * exact), error.shape)
    # the stiff couplings are there and large: a section's k between neighbours
    assert np.count_nonzero(np.abs(fd) > 1e-3 * scale) >= 3 * len(dofs)


def test_the_band_holds_every_coupling_of_the_line():
    """Without absolute damping (its rank-one term couples every dof) the derivative couples
    no two of the line's states further apart than the band's half-width; with the rings after
    their stations that is 5 (the pulley to throw 1 past the ring), whatever the line's length."""
    J, fd, line, model = _jacobians(absolute=False, angle_mode=True)
    rows, kb = line_band(model.line)
    assert rows == 2 * (line.n - 1) and kb == 5
    scale = np.max(np.abs(fd))
    r, c = np.nonzero(np.abs(fd) > 1e-9 * scale)
    assert np.max(np.abs(r - c)) <= kb


def test_the_absolute_dampings_diagonal_is_kept():
    """With the case's absolute damping at the throws, the pulley's and the ring's own blocks
    stay exact (its diagonal is in the Jacobian; its coupling of two dofs is not)."""
    J, fd, line, model = _jacobians(absolute=True, angle_mode=True)
    scale = np.max(np.abs(fd), axis=1, keepdims=True)
    for block in (slice(0, 2), slice(2, 4)):  # the pulley's, the ring's (no cylinder, no load)
        assert np.max(np.abs(J[block, block] - fd[block, block]) / scale[block]) <= 1e-5
    assert math.isfinite(np.sum(J))
