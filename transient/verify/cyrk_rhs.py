"""transient's right-hand side as a C callback for CyRK's compiled solvers (the benchmark's
compiled peer; optional ``bench`` extra).

A generic solver holds no switches between calls, so each call picks the governor's branch and
the pairs' modes for its own state (``rhs.choose_modes``), with time as the independent
variable and the gas-table piece chosen by the actual angle (the solver steps over the table's
corners with its error control, as it would in a user's script).
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ..core.model.forcing import governor_branch
from ..core.model.layout import (
    N_SWITCHES,
    OMEGA,
    PHI,
    SW_DIRECTION,
    SW_GOVERNOR,
    extras_of,
    n_state,
)
from ..core.model.rhs import choose_modes, derivative
from ..core.model.work import work_array

# CyRK's callback signature: dy (double*), t, y (double*), args (double*).
SIGNATURE = nb.types.void(nb.types.CPointer(nb.types.float64), nb.types.float64,
                          nb.types.CPointer(nb.types.float64), nb.types.CPointer(nb.types.float64))


def make_rhs(m):
    """A C callback dy/dt = f(y) of model ``m``; ``args`` must be ``work_array(m)``, flattened,
    as allocated (its scratch space, which marks no gas table piece selected yet). Compiled for
    this model (its arrays are frozen into the code)."""
    n = n_state(m)
    shape = work_array(m).shape
    extras = extras_of(m)

    @nb.cfunc(SIGNATURE)
    def rhs(dy, t, y, args):
        state = nb.carray(y, (n,))
        out = nb.carray(dy, (n,))
        wk = nb.carray(args, shape)
        sw = np.zeros(N_SWITCHES, dtype=np.int64)
        w = state[OMEGA]
        sw[SW_GOVERNOR] = governor_branch(m, w, True)
        sw[SW_DIRECTION] = 1 if w >= 0.0 else -1
        if m.n_pairs > 0:
            choose_modes(m, extras, False, state, state[PHI], sw, wk)
        derivative(m, extras, False, state, state[PHI], sw, wk, out)

    return rhs
