"""The layout of the compiled reduced model: the :data:`~transient.core.model.layout.Model` tuple, the
state vector, the
switches, the output columns and the work array, with the index helpers that place the optional
states (governor, latched fuels, cylinder pressures) after the fixed ones.

Every other module of the model and the stepper indexes its arrays by these names, so they are
defined once here, apart from the terms that fill them. The model is equation (18) of the
swash-plate paper with variable ω, J(φ) φ̈ + ½ J′(φ) φ̇² = M(φ, φ̇, t), unit-free (SI); the scene
classes build a :data:`Model` with ``transient.assemble``. In time as independent variable the
third state is ω; in crank angle it is the kinetic energy K = ½ J(φ) ω², for which (18) is the
work–energy law dK/dφ = M(φ, ω, t) and ω = √(2K/J): the same equation multiplied by ω, but an
integration error in it is an error in the energy budget only, never a spurious exchange between
J(φ) and ω, so coasting keeps K exactly.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..declare import BY_INCREMENT, BY_SIZE, NOT_CONTROLLED, Block, Layout, Sized
from ..jit import formula, kernel, typed_by_fingerprint
from . import governor as gv


@formula
def n_margins(m):
    """The pairs' modes, each a switch with its margin and its energy lost: one per non-ideal
    pair in each chain the pairs act in, the machine on a rigid shaft, each station carrying
    cylinders on an elastic line (``line`` :data:`LINE_META`; theory, (T7)). Chain c's pair k
    is number c·n_pairs + k."""
    return m.n_pairs * np.int64(m.line[0, LM_CHAINS])


@formula
def n_losses(m):
    """The state's energies lost: one per non-ideal pair in each chain (:func:`n_margins`)."""
    return n_margins(m)


@formula
def n_governor_states(m):
    """The dynamic governor's states (:data:`.governor.N_STATES`)."""
    return gv.N_STATES[m.gov_dyn]


@formula
def n_latched(m):
    """The latched fuels: one per cylinder with fuel latching."""
    return m.ncyl if m.latch else 0


@formula
def n_pressures(m):
    """The pressures of the cylinders' closed parts: one per cylinder with wall heat."""
    return m.ncyl if m.woschni else 0


#: A row of the element table of an elastic shaft line (:mod:`transient.core.model.shaft`): the two degrees of
#: freedom it joins, its stiffness [N m/rad], damping [N m s/rad] and gear ratio r = ω_i/ω_j [1].
ELEMENT = Layout("element", "i", "j", "stiffness", "damping", "ratio")
EL_I, EL_J, EL_K, EL_C, EL_R = ELEMENT
N_ELEMENT = ELEMENT.size
#: The Model's ``line``, the elastic shaft line packed in one array of N_LINE_COLUMNS columns:
#: row 0 these counts and indices; then a row per cylinder, the dof that carries it in column 0;
#: a row per dof (:data:`LINE_DOF`); a row per element (:data:`ELEMENT`). ``chains``: the chains
#: the non-ideal pairs act in, each with its own modes (:func:`n_margins`), the stations that
#: carry cylinders. A rigid shaft's is one row of zeros but one chain, the whole machine: no
#: dofs.
LINE_META = Layout("line meta", "dofs", "reference", "load", "elements", "cylinders", "chains")
LM_DOFS, LM_REF, LM_LOAD, LM_ELEMENTS, LM_CYLINDERS, LM_CHAINS = LINE_META
#: A dof's row of the Model's ``line``: its own constant inertia [kg m²], its cycle-mean inertia
#: (the weight of its speed in the line's mean speed) [kg m²], its absolute damping [N m s/rad],
#: its gear ratio to the reference [1] (1 for every dof of a scene's line, whose driven inertia
#: is referred to the shaft, :class:`transient.shaft.line.ShaftLine`, so that its angle is
#: φ + q_d), the chain of the pairs it carries (its cylinders' throw; −1 on a dof without
#: cylinders), its share of the cylinders, which is its share of the links' constant
#: inertias (``Model.link_J``) [1], and where its breakpoints begin in ``Model.breakpoints``
#: (its own, on its angle; they end where the next dof's begin).
LINE_DOF = Layout("line dof", "own", "weight", "absolute", "gear", "chain", "share",
                  "breakpoints")
LD_OWN, LD_WEIGHT, LD_ABS, LD_GEAR, LD_CHAIN, LD_SHARE, LD_BREAKPOINTS = LINE_DOF
#: Columns of the Model's packed ``line``: enough for each of its kinds of row.
N_LINE_COLUMNS = max(LINE_META.size, LINE_DOF.size, N_ELEMENT)


@formula
def line_dofs(m):
    """The elastic shaft line's degrees of freedom; 0 on a rigid shaft."""
    return np.int64(m.line[0, LM_DOFS])


@formula
def n_line_states(m):
    """The elastic shaft line's states: a twist and an energy (or speed) per degree of freedom
    other than the reference; none on a rigid shaft."""
    n = line_dofs(m)
    return 2 * (n - 1) if n > 0 else 0


@formula
def n_line_loss(m):
    """The energy the shaft line's damping took: one on an elastic line."""
    return 1 if line_dofs(m) > 0 else 0


#: The state vector's blocks, in order (a :class:`~transient.core.declare.Layout`). The first
#: three are the dynamics, φ, t and the third, ω in time or K = ½Jω² in crank angle; then work
#: integrals, quadratures that do not feed back: the work of the gas forces, of the load and of
#: the starter [J], then the energy lost in each non-ideal pair k (``W_loss_<k+1>``).
#: Integrated with the motion, the work–energy balance ½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load +
#: W_starter − Σ W_loss,k holds to the solver's accuracy. After them the dynamic governor's
#: states (:mod:`.governor`), then, with fuel latching, the fuel each cylinder took at its last
#: injection (held constant between injections: their derivative is zero and the stepper sets
#: them), then, with wall heat transfer, each cylinder's pressure in its closed part
#: (:mod:`.cylinder`; the ``p_<k>`` columns show it there). On an elastic shaft line
#: (:func:`line_dofs` > 0; theory, (T5)) φ, the third state and the works are the reference
#: degree of freedom's (the gas work all cylinders', the load's at its own dof), then per other
#: dof in order its twist q_d = θ_d − φ and its K_d = ½J_d(θ_d)ω_d² in crank angle, ω_d in
#: time (:mod:`.elastic`), and the energy the line's damping took.
#:
#: A block whose length depends on the scene is :class:`~transient.core.declare.Sized` by a
#: formula of the Model (:func:`n_losses` …; :func:`transient.core.jit.formula`: copied into
#: the code that calls it, no compile unit of its own). The kernels index the state through
#: :func:`state_offsets`, one kernel that chains the size formulas in the declared order (each
#: offset the one before plus that block's size), by the formulas :func:`gov_index`,
#: :func:`latch_index`, :func:`cyl_index`, …, :func:`n_state`. The Python side lays the state
#: out with the same formulas' code (:meth:`~transient.core.declare.Layout.offsets_for`), and
#: ``tests/unit/test_layouts.py`` checks the two on every case. The offsets are computed, never
#: stored in the Model: a field more there would be copied at every call that passes the Model
#: (a tenth of a bare scene's run time for four fields). A new block of states (per cylinder,
#: per shaft station) is one more entry here with its size formula and its error control
#: (:data:`CONTROL`), its place in :func:`state_offsets`' chain and an index formula.
STATE = Layout(
    "state",
    Block("phi", 1, "shaft angle φ [rad]"),
    Block("t", 1, "time t [s]"),
    Block("omega", 1, "shaft speed ω [rad/s] in time; kinetic energy K = ½Jω² [J] in crank angle"),
    Block("work", 3, "work of the gas forces, of the load, of the starter [J]"),
    Block("loss", Sized(n_losses, "one per non-ideal pair (per pair and throw on a line)"),
          "energy lost in each non-ideal pair [J]"),
    Block("governor", Sized(n_governor_states, "the governor's states"),
          "the dynamic governor's states (governor.STATE_NAMES)"),
    Block("latched", Sized(n_latched, "one per cylinder with latching"),
          "the fuel each cylinder latched at its last injection [1]"),
    Block("pressure", Sized(n_pressures, "one per cylinder with wall heat"),
          "each cylinder's pressure in its closed part [Pa]"),
    Block("line", Sized(n_line_states, "two per shaft-line dof but the reference"),
          "each dof's twist q_d = θ_d − φ [rad], then its K_d = ½J_dω_d² [J] in crank angle or "
          "ω_d [rad/s] in time"),
    Block("line_loss", Sized(n_line_loss, "one on an elastic shaft line"),
          "energy the shaft line's damping took [J]"),
)
#: The blocks' numbers (places in :data:`STATE`).
(B_PHI, B_T, B_OMEGA, B_WORK, B_LOSS, B_GOVERNOR, B_LATCHED, B_PRESSURE, B_LINE,
 B_LINE_LOSS) = range(len(STATE))
#: The components at offsets known at import (every block before them has a fixed size).
PHI, T, OMEGA = STATE.fixed_offset("phi"), STATE.fixed_offset("t"), STATE.fixed_offset("omega")
KINETIC = OMEGA
W_GAS, W_LOAD, W_STARTER = range(STATE.fixed_offset("work"), STATE.fixed_offset("loss"))
N_DYNAMIC = STATE.fixed_offset("work")
N_STATE_BASE = STATE.fixed_offset("loss")
W_LOSS0 = N_STATE_BASE  # y[W_LOSS0 + k]: energy lost in pair k
#: Names of the components of fixed offset, in order (the third is K = ½Jω² in crank angle).
STATE_NAMES = ("phi", "t", "omega", "W_gas", "W_load", "W_starter")
#: How the step's error control treats each block (:data:`transient.core.declare.BY_SIZE` …):
#: φ and t accumulate, so an error in them is scaled by their increment over the step; the work
#: integrals, the losses and the latched fuels are not controlled (they do not feed back, or are
#: held constant between injections).
CONTROL = {"phi": BY_INCREMENT, "t": BY_INCREMENT, "omega": BY_SIZE, "work": NOT_CONTROLLED,
           "loss": NOT_CONTROLLED, "governor": BY_SIZE, "latched": NOT_CONTROLLED,
           "pressure": BY_SIZE, "line": BY_SIZE, "line_loss": NOT_CONTROLLED}
#: Which blocks repeat from one engine cycle to the next in a periodic steady state
#: (:mod:`transient.shooting`): the speed (the third state), the governor's states, the latched fuels,
#: the closed parts' pressures and the shaft line's twists and speeds. φ advances by the cycle;
#: t, the works and the losses accumulate, so they are no part of it.
PERIODIC = {"phi": False, "t": False, "omega": True, "work": False, "loss": False,
            "governor": True, "latched": True, "pressure": True, "line": True,
            "line_loss": False}


def state_control(m) -> np.ndarray:
    """The error control of each component of model ``m``'s state (:data:`CONTROL`): the
    argument ``control`` of the integrator's error norm (the stepper's ``Work.control``)."""
    return np.concatenate([np.full(n, CONTROL[b.name], dtype=np.int64)
                           for b, n in zip(STATE.blocks, STATE.sizes_for(m))])


def periodic_states(m) -> np.ndarray:
    """The indices of model ``m``'s state components that repeat in a periodic steady state
    (:data:`PERIODIC`), in the state's order."""
    at = STATE.offsets_for(m)
    return np.concatenate([np.arange(at[k], at[k + 1]) for k, b in enumerate(STATE.blocks)
                           if PERIODIC[b.name]]).astype(np.int64)


#: The most modes of non-ideal pairs a Model may have (:func:`n_margins`): each a bit of the
#: switch ``modes``, an int64.
MAX_MARGINS = 62
#: Discrete switches held constant over a step (an int array ``sw``, the first block of the
#: stepper's integer state, ``stepper.io.INTS``): starter engaged (0/1), the governor's branch
#: (see :func:`.forcing.governor_branch`), the modes of the non-ideal pairs (bit k set: pair k
#: backward, its far side drives; on an elastic line bit c·n_pairs + k for pair k of chain c,
#: :func:`n_margins`), the direction of motion σ = ±1 that the pair modes refer to
#: (sign of ω; changed only at a speed reversal, where the modes are chosen afresh), the segment
#: of the load schedule (:func:`.forcing.load_segment`) and the generator's low-speed branch
#: (:func:`.forcing.generator_branch`), the flyweight governor's sleeve, moving or on a stop
#: (``governor.FREE``, ``ON_LOW_STOP``, ``ON_HIGH_STOP``), and the interval of a tabulated load
#: against speed (:func:`.forcing.speed_knot_segment`).
SWITCHES = Layout("switches", "starter", "governor", "modes", "direction", "load", "generator",
                  "sleeve", "load_table")
(SW_STARTER, SW_GOVERNOR, SW_MODES, SW_DIRECTION, SW_LOAD, SW_GENERATOR, SW_SLEEVE,
 SW_LOAD_TABLE) = SWITCHES
N_SWITCHES = SWITCHES.size

#: How the reduced inertia of a link of the serial chain follows φ (a mechanism's ``link_laws``;
#: ``Model.link_own`` holds the first two where a pair cuts such a link from the rest):
#: LINK_FIXED a constant (``Model.link_J``), LINK_PISTONS the pistons' m·Σ_k u_k² (m
#: ``Model.link_mass``), LINK_SWASH the swash plate's link 9 with cross 13
#: (``swash_plate.link_terms``), LINK_REST what J(φ) holds beyond every other link (the rods).
LINK_FIXED, LINK_PISTONS, LINK_SWASH, LINK_REST = 0, 1, 2, 3

#: Abscissae of a tabulated load (``Model.lt_kind``; :func:`.forcing.table_load`): none, the
#: speed ω, the shaft angle φ in its cycle, the time t.
LT_NONE, LT_SPEED, LT_ANGLE, LT_TIME = 0, 1, 2, 3

#: Mode-selection policies of the non-ideal pairs (``Model.policy``; ``transient.core.model.chain``).
POWER_FLOW, PAPER = 0, 1

#: Columns written for every output sample; then one gas column per cylinder, then
#: ``PAIR_OUTPUTS`` for each non-ideal pair, then the dynamic governor's states
#: (``governor.STATE_NAMES``) and, with fuel latching, the fuel latched by each cylinder.
OUTPUTS = ("t", "phi", "omega", "epsilon", "J", "dJ_dphi", "M_gas", "M_load", "M_starter", "fuel",
           "W_gas", "W_load", "W_starter")
OUTPUT_UNITS = ("s", "rad", "rad/s", "rad/s^2", "kg m^2", "kg m^2/rad", "N m", "N m", "N m", "1",
                "J", "J", "J")
N_OUT_FIXED = len(OUTPUTS)
COL_EPS, COL_J, COL_DJ = OUTPUTS.index("epsilon"), OUTPUTS.index("J"), OUTPUTS.index("dJ_dphi")
COL_M_GAS, COL_M_LOAD = OUTPUTS.index("M_gas"), OUTPUTS.index("M_load")
#: Per pair k: S_k, the moment it takes out of its shaft side (reduced to φ; the far side receives
#: η*_k S_k), η*_k in use, the power lost (1 − η*_k) S_k ω and the energy lost so far.
PAIR_OUTPUTS = ("S", "eta", "P_loss", "W_loss")
PAIR_OUTPUT_UNITS = ("N m", "1", "W", "J")
@formula
def n_gas_columns(m):
    """The output row's applied pressures (forces): one per cylinder."""
    return m.ncyl


@formula
def n_pair_columns(m):
    """The output row's PAIR_OUTPUTS of every non-ideal pair (in each chain, :func:`n_margins`)."""
    return len(PAIR_OUTPUTS) * n_margins(m)


@formula
def n_cylinder_loss_columns(m):
    """The output row's losses of every reaction pair in every cylinder."""
    return m.n_pairs * m.ncyl if m.reaction else 0


@formula
def n_line_columns(m):
    """The output row's shaft-line columns: per dof its twist and speed, per element its
    torque, the line's energy and the energy its damping took; none on a rigid shaft."""
    n = line_dofs(m)
    return 2 * n + np.int64(m.line[0, LM_ELEMENTS]) + 2 if n > 0 else 0


#: The output row's blocks (``transient.scene.outputs.output_columns`` names the columns in this
#: order), sized per scene as the state's and indexed through :func:`output_offsets` by the
#: formulas :func:`pair_col`, :func:`governor_col`, :func:`cylinder_loss_col`, :func:`line_col`
#: and :func:`n_outputs`.
OUTPUT = Layout(
    "output row",
    Block("fixed", len(OUTPUTS), "the columns OUTPUTS"),
    Block("gas", Sized(n_gas_columns, "one per cylinder"),
          "the pressure (force) applied in each cylinder"),
    Block("pairs", Sized(n_pair_columns, "PAIR_OUTPUTS per pair"),
          "each non-ideal pair's PAIR_OUTPUTS"),
    Block("governor", Sized(n_governor_states, "the governor's states"),
          "the dynamic governor's states"),
    Block("latched", Sized(n_latched, "one per cylinder with latching"),
          "the fuel each cylinder latched"),
    Block("cyl_loss", Sized(n_cylinder_loss_columns, "one per reaction pair and cylinder"),
          "the power each reaction pair loses in each cylinder (pair 1 in cylinders 1 … n, …)"),
    Block("line", Sized(n_line_columns, "2 per dof, 1 per element, 2"),
          "each shaft-line dof's twist [rad] and speed [rad/s], each element's torque [N m], "
          "the line's kinetic and elastic energy and the energy its damping took [J]"),
)
O_FIXED, O_GAS, O_PAIRS, O_GOVERNOR, O_LATCHED, O_CYL_LOSS, O_LINE = range(len(OUTPUT))

#: Rows of the work array ``wk`` (:func:`.work.work_array`), one column per cylinder, pair or link:
#: transfer functions u, u′ per cylinder; per sub-chain J_k, J′_k, M_k (on an elastic line of
#: the chain being solved); per pair (per pair and chain, :func:`n_margins`) η*_k, S_k, the
#: mode margins g_k, their least value over the right-hand sides evaluated since the stepper
#: reset it, and η*, S of a trial mode vector; the least and largest speed ω over those
#: right-hand sides ([0], [1] of WK_SPEED), and of the PI governor's demand u (WK_DEMAND); per
#: cylinder the angle ``sel`` in its own cycle and the gas table's piece there (WK_LOCAL,
#: WK_PIECE), for the ``sel`` in WK_SEL[0] (:func:`.forcing.select_pieces`; on an elastic line
#: the cylinder's angle at the reference's ``sel`` in WK_CYL_SEL, for the ``sel`` in WK_SEL[1],
#: :func:`.elastic.cylinders_at_sel`), with per-cylinder
#: variation its fuel factor in that cycle (WK_FUEL, :func:`.variation.cycle_fuel`) and, with
#: combustion offsets, its angle and piece on the curve shifted by its offset (WK_LOCAL_SHIFT,
#: WK_PIECE_SHIFT); scratch rows for ``chain.modes_power_flow_into``; with reaction friction,
#: row WK_CYL_LOSS + p holds pair p's loss moment in each cylinder (the split of the pair's loss
#: that the output rows report per cylinder; one row per joint, the most pairs there can be).
#:
#: From WK_RX on, the rows of the mechanism's reaction solver (``Model.reaction``,
#: :mod:`.reactions`): the rows every solver shares (``reactions.SHARED``: each piston's gas
#: force, the angle its joints' directions are for, the pairs' loss moments), then each solver's
#: own, which it declares (``joint_friction.ROWS``, ``swash_friction.ROWS``,
#: ``articulated_friction.ROWS``), laid over one another: a scene has one mechanism
#: (:mod:`.work` allocates the array, with the rows of the solver that needs most).
WORK = Layout(
    "work array rows",
    "u", "du", "J", "dJ", "M", "eta", "S", "g", "g_min", "eta_try", "S_try", "speed", "demand",
    "local", "piece", "sel", "fuel", "local_shift", "piece_shift",
    ("scratch", 4, "scratch of chain.modes_power_flow_into"),
    ("cyl_loss", 6, "each reaction pair's loss moment in each cylinder"),
    ("line_theta", 1, "each shaft-line dof's angle θ_d"),
    ("line_omega", 1, "each dof's speed ω_d"),
    ("line_J", 1, "each dof's inertia J_d(θ_d)"),
    ("line_dJ", 1, "each dof's J′_d(θ_d)"),
    ("line_M", 1, "the applied moments on each dof"),
    ("line_T", 1, "the line's torques on each dof"),
    ("line_rate", 2, "each dof's two rates (dq/dφ, dK/dφ; or ε in time)"),
    ("cyl_angle", 1, "each cylinder's angle, its station's"),
    ("cyl_J", 1, "each cylinder's share of J at its angle"),
    ("cyl_dJ", 1, "its derivative"),
    ("cyl_knot", 1, "each cylinder's gas-table knot interval at its last evaluation"),
    ("cyl_knot_shift", 1, "its knot interval on the curve its combustion offset shifts"),
    ("cyl_force", 1, "each piston's gas force at its station's angle, for its throw's joints"),
    ("cyl_sel", 1, "each cylinder's angle in its own cycle at the reference's sel"),
)
(WK_U, WK_DU, WK_J, WK_DJ, WK_M, WK_ETA, WK_S, WK_G, WK_G_MIN, WK_ETA_TRY, WK_S_TRY,
 WK_SPEED, WK_DEMAND, WK_LOCAL, WK_PIECE, WK_SEL, WK_FUEL, WK_LOCAL_SHIFT, WK_PIECE_SHIFT,
 WK_SCRATCH, WK_CYL_LOSS, WK_LINE_THETA, WK_LINE_OMEGA, WK_LINE_J, WK_LINE_DJ, WK_LINE_M,
 WK_LINE_T, WK_LINE_RATE, WK_CYL_ANGLE, WK_CYL_J, WK_CYL_DJ, WK_CYL_KNOT,
 WK_CYL_KNOT_SHIFT, WK_CYL_FORCE, WK_CYL_SEL) = WORK
N_SCRATCH = WORK.size_of("scratch")
WK_RX = WORK.end

#: The joints of the crank-slider that reaction friction acts in (rows of ``Model.rx_par``): the
#: main bearing (frame – throw), the crankpin (throw – rod), the piston pin (rod – piston) and the
#: piston in its cylinder (the slider). The swash plate's are ``swash_friction.J_*``.
JOINT_MAIN, JOINT_CRANKPIN, JOINT_PIN, JOINT_SLIDER = range(4)
#: Rows of ``Model.rx_par`` and ``Model.rx_pair``: the most joints of a mechanism's reaction
#: friction (the articulated mechanism's six, ``articulated_friction.J_*``), so that the arrays
#: have one shape and one compile serves every scene.
N_JOINTS = WORK.size_of("cyl_loss")
#: Columns of ``Model.rx_par``: the friction coefficient μ [1], the journal's radius r [m], the
#: viscous coefficient (journal: N m s/rad on the relative angular speed; slider: N s/m on the
#: piston speed), the rings' tension friction force [N] and the share of the gas force that
#: presses the rings to the wall times their μ [1] (slider only); the efficiencies η_fwd, η_bwd
#: of a constant-η pair at the joint that couples the shaft to the mechanism (row 0, the main
#: bearings; ``reactions.acceleration``), NaN for a mapped pair there (its η from the ``et_*``
#: fields), 0 in every other row and without such a pair.
RX_MU, RX_RADIUS, RX_VISCOUS, RX_RING_FORCE, RX_RING_PRESSURE, RX_ETA_FWD, RX_ETA_BWD = range(7)
N_RX_PAR = 7

Model = namedtuple(
    "Model",
    [
        # The mechanism's kernel, terms(mech, kin_coef, φ, u, u′, with_dJ) -> (J, dJ/dφ) filling
        # u_k, u′_k: a compile-time constant (a kernel as a value, transient.core.jit), so that
        # a scene's stepper holds its own mechanism's kernel alone, inlined, and no dispatch
        "terms",  # kernel: the mechanism's J(φ), dJ/dφ and transfer functions
        "mech",  # float64[:]: the mechanism's packed parameters
        "kin_coef",  # float64[1 + ncyl, n, 6]: the tabulated kernel's splines (transient.core.model.tabulated)
        "ncyl",  # int: number of cylinders (gas force points)
        "J0",  # float: constant inertia of shaft, flywheel and load [kg m²]
        "has_gas",  # bool
        "gas_phase",  # float64[ncyl]: shaft angle at which cylinder k is at local angle 0 [rad]
        "gas_scale",  # float64[ncyl]: force per unit table value (piston area [m²], or 1 for forces)
        "gas_offset",  # float: table value of zero force (crankcase pressure p0 [Pa], or 0)
        "period",  # float: cycle length in local angle [rad] (4π four-stroke, 2π two-stroke)
        "knots",  # float64[:], piecewise-cubic table (transient.core.model.tables)
        "coef",  # float64[:, 4], or [:, 8] with has_motored (full-load, then motored cubic)
        "piece_knot",  # int64[:]
        "has_motored",  # bool: coef pairs a motored curve; else it is the constant gas_offset
        "breakpoints",  # float64[:]: sorted shaft angles in [0, period) where a table has a corner;
        #   on an elastic line each dof's own angles in turn, sorted each (LD_BREAKPOINTS)
        "bp_jump",  # bool[:]: whether a cylinder's pressure jumps at each breakpoint
        "load_const",  # float: constant resisting torque [N m]
        "load_linear",  # float: c in −c·ω [N m s]
        "load_fan",  # float: K in −K·ω|ω| [N m s²]
        "load_x",  # float64[:]: corners of the load schedule, non-decreasing (empty: s ≡ 1)
        "load_s",  # float64[:]: the load's scale s at each corner (piecewise linear between)
        "load_comp",  # int: state component the corners are values of, T [s] or PHI [rad]
        "lt_kind",  # int: the tabulated load's abscissa, LT_NONE, LT_SPEED, LT_ANGLE or LT_TIME
        "lt_x",  # float64[n + 1]: its knots, increasing [rad/s, rad or s]
        "lt_coef",  # float64[n, 4]: its cubic per knot interval, ascending powers [N m]
        "gen_power",  # float: generator power P in −s·P/max(ω, ω_min) [W] (0: none)
        "gen_min",  # float: ω_min, below it the generator's torque is held at −s·P/ω_min [rad/s]
        "starter_torque",  # float: starter stall torque [N m]
        "starter_noload",  # float: speed at which the starter characteristic reaches zero [rad/s]
        "starter_cutout",  # float: speed at which the starter disengages for good [rad/s]
        "gov_on",  # bool: a static droop governor scales the gas forces
        "gov_full",  # float: ω_a, full fuel at and below it [rad/s]
        "gov_zero",  # float: ω_1c, no fuel at and above it [rad/s]
        "gov_dyn",  # int: governor with states (transient.core.model.governor: NONE, PI, PID, FLYWEIGHT)
        "gov_par",  # float64[:]: its parameters (governor.P_* or governor.F_*)
        "latch",  # bool: each cylinder's fuel is latched at its start of injection
        "inj_angle",  # float: local angle of the start of injection [rad] (with latch)
        "woschni",  # bool: the closed part's pressures are states (wall heat transfer, .cylinder)
        "cyl_par",  # float64[cylinder.N_PAR]: their parameters (transient.core.model.cylinder)
        "n_pairs",  # int: number of non-ideal pairs (0: ideal constraints, equation (18))
        "eta_fwd",  # float64[n_pairs]: efficiency of pair k when its shaft side drives
        "eta_bwd",  # float64[n_pairs]: efficiency of pair k when its far side drives
        "policy",  # int: POWER_FLOW or PAPER
        "link_sub",  # int64[n_links]: sub-chain of each link (shaft first, gas-carrying link last)
        "link_J",  # float64[n_links]: constant reduced inertia of the middle links [kg m²]
        "link_rest",  # int: the link that holds J(φ) less every other link's inertia
        "link_own",  # int64[n_links]: LINK_PISTONS or LINK_SWASH where a pair cuts the link
        #   from link_rest's sub-chain (its inertia then computed on its own), else LINK_FIXED
        "link_mass",  # float64[n_links]: m of a LINK_PISTONS link, J = m·Σ_k u_k² [kg]
        # per-cylinder variation (transient.core.model.variation; the arrays' types are the same
        # without it, so that one compile serves every scene; packed in two arrays, as a
        # kernel that is not inlined copies every field of the Model at each call)
        "var_on",  # bool: some cylinder has a [[gas.cylinders]] entry
        "var_shifted",  # bool: some cylinder has a combustion offset
        "var_par",  # float64[ncyl, variation.N_VAR_PAR]: factors, cycle start, rate, offset
        "var_int",  # int64[ncyl, 2 + cycles listed]: misfire period, seed, misfiring cycles
        # reaction friction in the mechanism's joints (transient.core.model.reactions); the
        # pairs are then the joints that have friction, and no sub-chain is cut
        "reaction",  # bool: the pairs' losses follow from the joint reactions
        "rx_par",  # float64[N_JOINTS, N_RX_PAR]: each joint's coefficients (zeros: ideal)
        "rx_pair",  # int64[N_JOINTS]: the pair each joint reports as, −1 for an ideal joint
        # the mechanism's reaction solver (compile-time constants as ``terms``; the kernels of
        # transient.core.model.reactions.NO_REACTIONS for a mechanism without one): its
        # prepare(mech, φ, ω, sel, wk), solve(mech, rx_par, rx_pair, J0, M_shaft, ε0, ω, σ,
        # n_pairs, wk) and inverse_drive(m, ε, ω, σ, M_shaft, wk)
        "rx_prepare",  # kernel: the joints' geometry at φ, into the work array
        "rx_solve",  # kernel: φ̈ and the joints' losses with friction on their reactions
        "rx_inverse",  # kernel: the drive moment that gives a prescribed φ̈ (inverse dynamics)
        "rx_sides",  # bool: its solve leaves each cylinder's side force for track_sides
        # efficiencies mapped over speed and transmitted moment (transient.core.model.eta_table); the
        # arrays keep their types without maps (one row of zeros), so one compile serves all
        "eta_table",  # bool: the pairs' η come from the maps below (eta_fwd, eta_bwd unused)
        "et_speed",  # float64[n_pairs, nw_max]: pair k's speed axis |ω|, increasing [rad/s]
        "et_torque",  # float64[n_pairs, ns_max]: its moment axis |S|, increasing [N m]
        "et_size",  # int64[n_pairs, 2]: the lengths of pair k's two axes
        "et_eta",  # float64[n_pairs, 2, nw_max, ns_max]: η_fwd, η_bwd on pair k's grid [1]
        "et_min",  # float64[n_pairs]: the least η of pair k's two maps [1]
        # the elastic shaft line (transient.shaft.ShaftLine; theory, The elastic shaft line),
        # packed in one array, with its kernels as fields so that a rigid shaft's stepper, whose
        # line has no dofs and whose kernels are no-ops, compiles none of them
        "line",  # float64[rows, N_LINE_COLUMNS]: the line packed (LINE_META, LINE_DOF, ELEMENT)
        "shares",  # kernel: the mechanism's shares(mp, kin_coef, angles, Jc, dJc, u, du, with_dJ)
        "line_model",  # kernel: the line's derivative, output row, pairs' margins or modes
        "line_switch",  # kernel: each other dof's speed state to K_d or back (m, y, to_angle, wk)
        "reference_inertia",  # kernel: J of the third state's K = ½Jω² at φ (m, phi, wk)
        # the breakpoints on each dof's own angle (transient.core.stepper.breakpoints; a rigid
        # shaft's, whose breakpoints are the shaft's, the stepper's bp, are no-ops)
        "line_segment_end",  # kernel: where the next step ends for one (m, fst, f, angle_mode,
        #   x, y, x_end, tol_end)
        "line_retake",  # kernel: a step that crossed one retaken (tab, m, extras, at, y, work,
        #   fst, ist, min_step, dense_ready)
        "line_passed",  # kernel: what those a move of the state reached do (m, extras, y, y_to,
        #   sw, evbuf, ist, wk, fst)
    ],
)
typed_by_fingerprint(Model)  # (its kernels have no numba fingerprint)


def extras_of(m):
    """The kernels' ``extras`` argument for model ``m``: None for a plain scene, True for one
    that uses a feature only the full variant of the kernels compiles: non-ideal friction pairs,
    a governor with states (PI, PID, flyweight), latched fuel, cylinder-pressure states
    (Woschni), per-cylinder variation or a tabulated load.

    Each kernel that reaches such a feature takes ``extras`` as a direct argument and tests it
    with ``extras is not None``: numba prunes a branch on whether an argument typed None is None
    before it types the function, so the plain variant (``extras`` typed None) neither compiles
    the kernels inside such branches nor branches around them at run time. A test on a field of
    the Model would not be pruned (its fields are run-time values), nor one on a local. The two
    variants are two signatures of the same kernels, each compiled once and cached."""
    plain = (m.n_pairs == 0 and m.gov_dyn == gv.NONE and not m.latch and not m.woschni
             and not m.var_on and not m.var_shifted and m.lt_kind == LT_NONE)
    return None if plain else True


@kernel(inline=True, python=lambda m: tuple(STATE.offsets_for(m)))
def state_offsets(m):
    """The offset of every block of :data:`STATE` in model ``m``'s state, then its length: each
    the one before plus that block's size, in the declared order.

    The kernels index the state through it (by the formulas below), one compile unit for the
    whole layout; inlined by LLVM, what a caller does not read is left out of its code. Called
    from Python it is the declaration's own :meth:`~transient.core.declare.Layout.offsets_for`
    (``tests/unit/test_layouts.py`` checks the compiled chain against it on every case)."""
    gov = W_LOSS0 + n_losses(m)
    latched = gov + n_governor_states(m)
    pressure = latched + n_latched(m)
    line = pressure + n_pressures(m)
    line_loss = line + n_line_states(m)
    return (PHI, T, OMEGA, W_GAS, W_LOSS0, gov, latched, pressure, line, line_loss,
            line_loss + n_line_loss(m))


@formula
def gov_index(m):
    """Index of the dynamic governor's first state (:data:`STATE`: after the losses)."""
    return state_offsets(m)[B_GOVERNOR]


@formula
def latch_index(m):
    """Index of cylinder 0's latched fuel (with ``m.latch``), after the governor's states."""
    return state_offsets(m)[B_LATCHED]


@formula
def cyl_index(m):
    """Index of cylinder 0's pressure state (with ``m.woschni``), after the latched fuels."""
    return state_offsets(m)[B_PRESSURE]


@formula
def line_index(m):
    """Index of the shaft line's first state (on an elastic line), after the pressures."""
    return state_offsets(m)[B_LINE]


@formula
def line_loss_index(m):
    """Index of the energy the shaft line's damping took (on an elastic line)."""
    return state_offsets(m)[B_LINE_LOSS]


@formula
def n_state(m):
    """Length of the state vector of model ``m``: after the line's loss."""
    return state_offsets(m)[-1]


@kernel(inline=True, python=lambda m: tuple(OUTPUT.offsets_for(m)))
def output_offsets(m):
    """The column of an output row where each block of :data:`OUTPUT` starts, then the row's
    length: as :func:`state_offsets` for the state."""
    pairs = N_OUT_FIXED + n_gas_columns(m)
    governor = pairs + n_pair_columns(m)
    latched = governor + n_governor_states(m)
    cyl_loss = latched + n_latched(m)
    line = cyl_loss + n_cylinder_loss_columns(m)
    return (O_FIXED, N_OUT_FIXED, pairs, governor, latched, cyl_loss, line,
            line + n_line_columns(m))


@formula
def pair_col(m):
    """Column of an output row where the pairs' PAIR_OUTPUTS start (:data:`OUTPUT`)."""
    return output_offsets(m)[O_PAIRS]


@formula
def governor_col(m):
    """Column of an output row where the governor's states start, then the latched fuels."""
    return output_offsets(m)[O_GOVERNOR]


@formula
def cylinder_loss_col(m):
    """Column of an output row where the reaction pairs' losses per cylinder start (pair 1 in
    cylinders 1 … n, then pair 2, …)."""
    return output_offsets(m)[O_CYL_LOSS]


@formula
def line_col(m):
    """Column of an output row where the shaft line's columns start (on an elastic line)."""
    return output_offsets(m)[O_LINE]


@formula
def n_outputs(m):
    """Columns of an output row of model ``m``."""
    return output_offsets(m)[-1]
