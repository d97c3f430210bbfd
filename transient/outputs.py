"""The trajectory columns a scene's run writes, with their units (the result-file layout, DESIGN §4).

Below the scene reader: the scene's checks ask which columns a run will have (an ``[analysis]``
request must name one), so this module reads a scene's records without importing their module.
"""
from __future__ import annotations

from .assemble import gas_is_force, governor_kind
from .core import governor as gv
from .core.layout import OUTPUT_UNITS, OUTPUTS, PAIR_OUTPUT_UNITS, PAIR_OUTPUTS


def output_columns(scene) -> dict[str, str]:
    """Trajectory datasets of a run and their units (DESIGN §4)."""
    cols = dict(zip(OUTPUTS, OUTPUT_UNITS))
    for k in range(scene.mechanism.n_cylinders):
        # p_k: cylinder pressure, or the force per piston for force-pulse models
        cols[f"p_{k + 1}"] = "N" if gas_is_force(scene) else "Pa"
    for k in range(len(scene.friction.pairs)):
        for name, unit in zip(PAIR_OUTPUTS, PAIR_OUTPUT_UNITS):
            cols[f"{name}_{k + 1}"] = unit
    kind = governor_kind(scene.governor)
    cols.update(zip(gv.STATE_NAMES[kind], gv.STATE_UNITS[kind]))
    if scene.gas.injection is not None:  # the fuel each cylinder latched at its last injection
        cols.update({f"fuel_{k + 1}": "1" for k in range(scene.mechanism.n_cylinders)})
    if scene.run.mode == "prescribed-speed":
        cols["M_drive"] = "N m"
        cols["W_drive"] = "J"
    return cols
