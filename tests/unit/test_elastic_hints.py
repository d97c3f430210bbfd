"""The elastic line's derivative is a function of the state alone: each cylinder's gas-table piece
and knot interval, which the work array keeps from one evaluation to the next for the next
search to start from (``tables.find_piece_near``, ``tables.interval_near``), are hints, never
state. The derivative of the in-line six (``cases/inline6_damper.toml``) at a twisted state is
the same to the bit from a work array of NaN, of garbage and of one that other states, in other
pieces and cycles, left behind; and what it keeps is the piece and interval a search of the
knots from scratch (numpy's ``searchsorted``) finds."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core.model import layout, rhs, shaft
from transient.core.model.work import work_array
from transient.run import _initial_state
from transient.scene import load_scene

CASE = Path(__file__).resolve().parents[2] / "cases" / "inline6_damper.toml"


def _state(scene, model, angle_mode, phi, rng):
    """A state at shaft angle ``phi``, each dof twisted by up to a milliradian; in crank angle
    the speeds as energies (the stepper's conversion)."""
    y, _, ist = _initial_state(scene, model)
    lo = layout.line_index(model)
    n = layout.n_line_states(model)
    y[lo:lo + n:2] = rng.uniform(-1e-3, 1e-3, n // 2)
    y[layout.PHI] = phi
    if angle_mode:
        wk = work_array(model)
        J = shaft.ref_inertia(model, phi, wk)
        y[layout.KINETIC] = 0.5 * J * y[layout.OMEGA] ** 2
        shaft.line_mode(model, y, True, wk)
    return y, ist[:layout.N_SWITCHES].copy()


def _derivative(model, angle_mode, y, sw, wk):
    out = np.empty_like(y)
    rhs.derivative(model, layout.extras_of(model), angle_mode, y, y[layout.PHI], sw, wk, out)
    return out


@pytest.mark.parametrize("angle_mode", [True, False])
def test_what_the_work_array_kept_changes_nothing(angle_mode):
    scene = load_scene(CASE)
    model, _, _ = build_model(scene)
    rng = np.random.default_rng(17)
    y, sw = _state(scene, model, angle_mode, 0.7, rng)
    runs = []
    for fill in (np.nan, 1e300, -7.3, 2.5):
        wk = work_array(model)
        wk[layout.WK_PIECE:layout.WK_RX] = fill
        runs.append(_derivative(model, angle_mode, y, sw, wk))
    wk = work_array(model)
    for phi in (0.7 + 0.05 * k for k in range(40)):  # a step's stages, then other pieces
        _derivative(model, angle_mode, _state(scene, model, angle_mode, phi, rng)[0], sw, wk)
    for phi in (150.0, -3.0, 0.69):  # other cycles, just behind
        _derivative(model, angle_mode, _state(scene, model, angle_mode, phi, rng)[0], sw, wk)
    runs.append(_derivative(model, angle_mode, y, sw, wk))
    for other in runs[1:]:
        assert np.array_equal(other, runs[0])

    # what it kept: the piece and the knot interval of each cylinder's own angle in its cycle
    local = wk[layout.WK_LOCAL, :model.ncyl]
    theta = np.array([y[layout.PHI] + (0.0 if d == int(model.line[0, layout.LM_REF])
                                       else y[shaft.twist_index(model, d)])
                      for d in shaft.line_parts.py_func(model.line)[0].astype(int)])
    np.testing.assert_allclose(local, np.mod(theta - model.gas_phase, model.period), rtol=0,
                               atol=1e-12)
    corners = model.knots[model.piece_knot]
    piece = np.searchsorted(corners, local, side="right") - 1
    assert np.array_equal(wk[layout.WK_PIECE, :model.ncyl], piece)
    knot = np.clip(np.searchsorted(model.knots, local, side="right") - 1,
                   model.piece_knot[piece], model.piece_knot[piece + 1] - 1)
    assert np.array_equal(wk[layout.WK_CYL_KNOT, :model.ncyl], knot)
