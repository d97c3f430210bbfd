"""The trajectory columns a scene's run writes, with their units (the result file's layout:
docs/guide/results.md).

A query on the scene, with it: the scene's checks ask which columns a run will have (an
``[analysis]`` request must name one), and the layers above (the run, the results, the analyses)
name the columns through it. It reads a scene's records without importing their module.
"""
from __future__ import annotations

import re

from ..core.model import governor as gv
from ..core.model.layout import OUTPUT_UNITS, OUTPUTS, PAIR_OUTPUT_UNITS, PAIR_OUTPUTS
from .queries import gas_is_force, governor_kind, reaction_friction


def output_columns(scene) -> dict[str, str]:
    """Trajectory datasets of a run and their units."""
    cols = dict(zip(OUTPUTS, OUTPUT_UNITS))
    for k in range(scene.mechanism.n_cylinders):
        # p_k: cylinder pressure, or the force per piston for force-pulse models
        cols[f"p_{k + 1}"] = "N" if gas_is_force(scene) else "Pa"
    for suffix in pair_suffixes(scene):
        for name, unit in zip(PAIR_OUTPUTS, PAIR_OUTPUT_UNITS):
            cols[f"{name}_{suffix}"] = unit
    kind = governor_kind(scene.governor)
    cols.update(zip(gv.STATE_NAMES[kind], gv.STATE_UNITS[kind]))
    if scene.gas.injection is not None:  # the fuel each cylinder latched at its last injection
        cols.update({f"fuel_{k + 1}": "1" for k in range(scene.mechanism.n_cylinders)})
    if reaction_friction(scene):  # each reaction pair's loss split over the cylinders
        cols.update({cylinder_loss_column(k, c): "W" for k in range(len(scene.friction.pairs))
                     for c in range(scene.mechanism.n_cylinders)})
    if scene.run.mode == "prescribed-speed":
        cols["M_drive"] = "N m"
        cols["W_drive"] = "J"
    if scene.shaft is not None:  # the elastic line's (layout.OUTPUT, block "line")
        for name, _, _ in scene.shaft.line_dofs():
            cols[f"twist_{column_name(name)}"] = "rad"
            cols[f"omega_{column_name(name)}"] = "rad/s"
        for a, b in scene.shaft.line_elements():
            cols[f"torque_{column_name(a)}_{column_name(b)}"] = "N m"
        cols["E_line"] = "J"
        cols["W_line_loss"] = "J"
    return cols


def column_name(name: str) -> str:
    """A shaft-line dof's name as part of a column's: each run of characters other than
    letters, digits and ``_`` one ``_`` (``"throw 1"`` → ``throw_1``)."""
    return re.sub(r"\W+", "_", name).strip("_")


def pair_columns(scene) -> list[list[tuple[str, str]]]:
    """Per non-ideal pair, the (suffix, speed column) of each of its sets of columns
    ``S_<suffix>``, ``eta_<suffix>``, ``P_loss_<suffix>``, ``W_loss_<suffix>``, with the column of
    the speed its chain turns at: pair k's one set ``"<k>"`` at ``omega``; on an elastic line
    one in each station that carries cylinders (:attr:`~transient.scene.records.Shaft.throws`),
    ``"<k>_<station>"`` at ``omega_<station>``."""
    n = len(scene.friction.pairs)
    if scene.shaft is None:
        return [[(f"{k + 1}", "omega")] for k in range(n)]
    return [[(f"{k + 1}_{column_name(st)}", f"omega_{column_name(st)}")
             for st in scene.shaft.throws] for k in range(n)]


def pair_suffixes(scene) -> list[str]:
    """The suffixes of :func:`pair_columns` in the order the run writes them: pair by pair, on
    an elastic line station by station (each station's pairs together)."""
    by_pair = pair_columns(scene)
    return [by_pair[k][c][0] for c in range(len(by_pair[0]) if by_pair else 0)
            for k in range(len(by_pair))]


def cylinder_loss_column(pair: int, cylinder: int) -> str:
    """The column of the power that reaction pair ``pair`` loses in ``cylinder`` (both from 0)."""
    return f"P_loss_{pair + 1}_cyl{cylinder + 1}"


#: What each trajectory column holds, with its sign convention (torques and speeds positive in
#: the direction of rotation, forces toward the crank axis, after Gots §1). ``{k}`` is
#: a cylinder's or a pair's number.
DESCRIPTIONS = {
    "t": "time since the start of the run",
    "phi": "crank angle, unwrapped: it grows with forward rotation and is not reduced to a cycle",
    "omega": "shaft speed dφ/dt, positive in the direction of rotation",
    "epsilon": "shaft acceleration dω/dt, positive when speeding up in the direction of rotation",
    "J": "reduced moment of inertia J(φ) of the whole machine about the shaft, the [inertia] "
         "constants included",
    "dJ_dphi": "dJ/dφ, the rate of change of the reduced inertia with the crank angle",
    "M_gas": "moment of the gas forces on the shaft, positive driving the shaft forward",
    "M_load": "moment of the load on the shaft, positive driving it forward (a brake is negative)",
    "M_starter": "moment of the starter on the shaft, positive driving it forward",
    "fuel": "fuel command between the motored (0) and the full-load (1) pressure curve",
    "W_gas": "work of M_gas on the shaft since the start, ∫M_gas ω dt",
    "W_load": "work of M_load on the shaft since the start (negative: taken by the load)",
    "W_starter": "work of M_starter on the shaft since the start",
    "p_{k}": "pressure in cylinder {k} (for force-pulse models the force on piston {k}), pushing "
             "the piston toward the crank axis",
    "S_{k}": "moment that non-ideal pair {k} takes from its shaft side, reduced to φ; the far "
             "side receives eta_{k}·S_{k}",
    "eta_{k}": "efficiency in use in pair {k}: η_forward (< 1) when power flows forward, "
               "1/η_backward (> 1) when it flows back",
    "P_loss_{k}": "power lost in pair {k}, (1 − eta_{k})·S_{k}·ω",
    "W_loss_{k}": "energy lost in pair {k} since the start, ∫P_loss_{k} dt",
    "S_{k}_{d}": "moment that non-ideal pair {k} takes from its shaft side in the throw of "
                 "shaft-line station {d}, reduced to the station's angle; the far side receives "
                 "eta_{k}_{d}·S_{k}_{d} (elastic [shaft])",
    "eta_{k}_{d}": "efficiency in use in pair {k} of station {d}: η_forward (< 1) when power "
                   "flows forward through it, 1/η_backward (> 1) when it flows back (elastic "
                   "[shaft])",
    "P_loss_{k}_{d}": "power lost in pair {k} of station {d}, (1 − eta_{k}_{d})·S_{k}_{d}·"
                      "omega_{d} (elastic [shaft])",
    "W_loss_{k}_{d}": "energy lost in pair {k} of station {d} since the start, "
                      "∫P_loss_{k}_{d} dt (elastic [shaft])",
    "P_loss_{k}_cyl{c}": "power lost in reaction pair {k} at the joints of cylinder {c}; over "
                         "the cylinders it sums to P_loss_{k}",
    "gov_integral": "the PI(D) governor's integral state",
    "gov_rack": "the PI(D) governor's rack (actuator) position",
    "gov_filter": "the PID governor's filtered speed",
    "sleeve_lift": "the flyweight governor's sleeve lift",
    "sleeve_speed": "the flyweight governor's sleeve speed, d(sleeve_lift)/dt",
    "fuel_{k}": "fuel command latched by cylinder {k} at its last injection",
    "M_drive": "drive moment the prescribed speed needs on the shaft, positive driving it forward",
    "twist_{d}": "twist of shaft-line dof {d} against the reference, θ − φ (elastic [shaft])",
    "omega_{d}": "speed of shaft-line dof {d}, dθ/dt (elastic [shaft])",
    "torque_{a}_{b}": "torque of the shaft-line element between dofs {a} and {b}, k·(θ_a − θ_b) "
                      "+ c·(ω_a − ω_b): positive where {a} leads {b}",
    "E_line": "energy of the shaft line: its dofs' kinetic energies Σ ½J_d ω_d² and its "
              "elements' elastic energies Σ ½k δ²",
    "W_line_loss": "energy the shaft line's damping took since the start (sections, dampers, "
                   "coupling, absolute damping)",
    "W_drive": "work of M_drive on the shaft since the start, ∫M_drive ω dt (to the solver's "
               "tolerance, at any output spacing)",
}


def describe(column: str) -> str:
    """The description of a trajectory column (:data:`DESCRIPTIONS`), for numbered ones too."""
    if column in DESCRIPTIONS:
        return DESCRIPTIONS[column]
    split = re.fullmatch(r"P_loss_(\d+)_cyl(\d+)", column)
    if split:
        k, c = split.groups()
        return DESCRIPTIONS["P_loss_{k}_cyl{c}"].replace("{k}", k).replace("{c}", c)
    throw = re.fullmatch(r"(S|eta|P_loss|W_loss)_(\d+)_(\w+)", column)
    if throw:
        name, k, d = throw.groups()
        return DESCRIPTIONS[f"{name}_{{k}}_{{d}}"].replace("{k}", k).replace("{d}", d)
    for prefix, pattern in (("twist_", "twist_{d}"), ("omega_", "omega_{d}")):
        if column.startswith(prefix):
            return DESCRIPTIONS[pattern].replace("{d}", column[len(prefix):])
    if column.startswith("torque_"):
        return DESCRIPTIONS["torque_{a}_{b}"].replace("{a} and {b}", column[len("torque_"):]
                                                      ).replace("{a}", "the first").replace(
                                                          "{b}", "the second")
    head, _, k = column.rpartition("_")
    pattern = f"{head}_{{k}}"
    if k.isdigit() and pattern in DESCRIPTIONS:
        return DESCRIPTIONS[pattern].replace("{k}", k)
    raise KeyError(f"{column}: no description; add one to transient.scene.outputs.DESCRIPTIONS")
