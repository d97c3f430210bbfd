"""The right-hand side's work array (``wk``): the rows :data:`.layout.WORK` declares, then, from
``layout.WK_RX`` on, the rows of the reaction solver that needs most (each solver declares its own,
after the rows they share, and a scene has one mechanism: they lie over one another).
"""
from __future__ import annotations

import numpy as np

from ..jit import compiled
from . import articulated_friction as af
from . import joint_friction as jf
from . import swash_friction as sf
from .layout import WK_RX, WK_SEL, line_dofs, n_margins

#: Rows of the work array: enough for any mechanism's reaction solver.
N_WK = WK_RX + max(jf.ROWS.end, sf.ROWS.end, af.ROWS.end)


@compiled
def work_array(m):
    """Scratch space of the right-hand side (rows ``WK_*``), allocated once per run."""
    # (an elastic line's throws solve their joints in the columns from c·n_pairs on,
    # ``line_pairs.throw_reactions``)
    wk = np.empty((N_WK, max(m.ncyl, m.n_pairs + 1, n_margins(m), m.link_sub.shape[0], 2,
                             line_dofs(m),
                             n_margins(m) + m.ncyl if m.reaction and line_dofs(m) > 0 else 0)))
    wk[WK_SEL, :2] = np.nan  # no pieces selected yet, no elastic line's angles at sel
    wk[WK_RX:, :] = np.nan  # (the reaction rows: no angle's directions cached yet)
    return wk
