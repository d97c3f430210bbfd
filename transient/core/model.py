"""The compiled reduced model: equation (18) of the swash-plate paper with variable ω,

    J(φ) φ̈ + ½ J′(φ) φ̇² = M(φ, φ̇, t),

assembled from a mechanism kernel (J, J′ and the piston transfer functions u_k), gas forces per
cylinder (angle-only pressure tables), loads and a starter. Everything here is numba-compiled and
unit-free (SI); the scene classes build a :data:`Model` with ``transient.assemble``.

State vector (named once, shared by the stepper, the results and the plots): see ``STATE``.
In time as independent variable the third component is ω; in crank angle it is the kinetic
energy K = ½ J(φ) ω², for which (18) is the work–energy law dK/dφ = M(φ, ω, t) and ω = √(2K/J).
That form is the same equation multiplied by ω, but an integration error in it is an error in
the energy budget only, never a spurious exchange between J(φ) and ω: coasting keeps K exactly.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

from .crank_slider import crank_slider_terms
from .swash_plate import swash_terms
from .tables import find_piece, table_eval

#: Names of the state components, in order (the third is K = ½Jω² in crank-angle mode).
STATE = ("phi", "t", "omega")
PHI, T, OMEGA = range(3)
KINETIC = OMEGA
N_STATE = len(STATE)

#: Discrete switches held constant over a step (an int array ``sw``): starter engaged (0/1), and
#: the governor's branch (see :func:`governor_branch`).
SW_STARTER, SW_GOVERNOR = range(2)
N_SWITCHES = 2

#: Mechanism kinds (``Model.kind``).
CRANK_SLIDER, SWASH_PLATE = 0, 1

#: Columns written for every output sample; then one gas column per cylinder.
OUTPUTS = ("t", "phi", "omega", "epsilon", "J", "dJ_dphi", "M_gas", "M_load", "M_starter", "fuel")
OUTPUT_UNITS = ("s", "rad", "rad/s", "rad/s^2", "kg m^2", "kg m^2/rad", "N m", "N m", "N m", "1")
N_OUT_FIXED = len(OUTPUTS)
COL_EPS, COL_J, COL_DJ = OUTPUTS.index("epsilon"), OUTPUTS.index("J"), OUTPUTS.index("dJ_dphi")
COL_M_GAS, COL_M_LOAD = OUTPUTS.index("M_gas"), OUTPUTS.index("M_load")

Model = namedtuple(
    "Model",
    [
        "kind",  # int: CRANK_SLIDER or SWASH_PLATE
        "mech",  # float64[:]: the mechanism's packed parameters
        "ncyl",  # int: number of cylinders (gas force points)
        "J0",  # float: constant inertia of shaft, flywheel and load [kg m²]
        "has_gas",  # bool
        "gas_phase",  # float64[ncyl]: shaft angle at which cylinder k is at local angle 0 [rad]
        "gas_scale",  # float64[ncyl]: force per unit table value (piston area [m²], or 1 for forces)
        "gas_offset",  # float: table value of zero force (crankcase pressure p0 [Pa], or 0)
        "period",  # float: cycle length in local angle [rad] (4π four-stroke, 2π two-stroke)
        "knots",  # float64[:], piecewise-cubic table (transient.core.tables)
        "coef",  # float64[:, 4]
        "piece_knot",  # int64[:]
        "breakpoints",  # float64[:]: sorted shaft angles in [0, period) where a table has a corner
        "load_const",  # float: constant resisting torque [N m]
        "load_linear",  # float: c in −c·ω [N m s]
        "load_fan",  # float: K in −K·ω|ω| [N m s²]
        "starter_torque",  # float: starter stall torque [N m]
        "starter_noload",  # float: speed at which the starter characteristic reaches zero [rad/s]
        "starter_cutout",  # float: speed at which the starter disengages for good [rad/s]
        "gov_on",  # bool: a static droop governor scales the gas forces
        "gov_full",  # float: ω_a, full fuel at and below it [rad/s]
        "gov_zero",  # float: ω_1c, no fuel at and above it [rad/s]
    ],
)


@njit(cache=True)
def mechanism_terms(kind, mech, phi, u, du):
    """J(φ) and dJ/dφ of the mechanism's moving parts; fills ``u[k]``, ``du[k]`` per cylinder."""
    if kind == CRANK_SLIDER:
        return crank_slider_terms(mech, phi, u, du)
    return swash_terms(mech, phi, u, du)


@njit(cache=True)
def gas_value(m, k, phi, sel):
    """Table value (pressure or force) of cylinder k at shaft angle ``phi``.

    ``sel`` is a shaft angle inside the current step: it picks the table piece, so that a step that
    ends exactly on a corner keeps using the piece it integrates over (DESIGN §2, breakpoints).
    """
    local_sel = (sel - m.gas_phase[k]) % m.period
    piece = find_piece(m.knots, m.piece_knot, local_sel)
    value, _ = table_eval(m.knots, m.coef, m.piece_knot, piece, local_sel + (phi - sel))
    return value


@njit(cache=True)
def inertia(m, phi, u, du):
    """Total reduced inertia J(φ) and dJ/dφ, (19) and (21); fills u, du."""
    J, dJ = mechanism_terms(m.kind, m.mech, phi, u, du)
    return J + m.J0, dJ


@njit(cache=True)
def speed(J, angle_mode, y):
    """ω from the state: y[2] itself in time mode, √(2K/J) in crank-angle mode (ω > 0 there)."""
    if angle_mode:
        return np.sqrt(2.0 * y[KINETIC] / J)
    return y[OMEGA]


@njit(cache=True)
def governor_branch(m, w, rising):
    """Branch of the droop characteristic at speed w: 0 full fuel (ω ≤ ω_a), 1 the droop line,
    2 no fuel (ω ≥ ω₁c); on a corner, the branch the motion enters (``rising``: ω increasing)."""
    if w < m.gov_full or (w == m.gov_full and not rising):
        return 0
    if w > m.gov_zero or (w == m.gov_zero and rising):
        return 2
    return 1


@njit(cache=True)
def fuel(m, w, branch):
    """Gas-force scale of the static droop governor (Antonyuk §4): 1 below ω_a, falling linearly
    to 0 at ω_1c, 0 above; 1 without a governor. The branch is fixed for a whole step (a state
    event stops on each corner), so that the right-hand side is smooth inside every step."""
    if not m.gov_on or branch == 0:
        return 1.0
    if branch == 2:
        return 0.0
    return (m.gov_zero - w) / (m.gov_zero - m.gov_full)


@njit(cache=True)
def moments(m, angle_mode, y, sel, sw, u, du):
    """Reduced inertia, speed and moments at state ``y``.

    Returns ``(J, dJ, w, M_gas, M_load, M_starter)``; u, du are work arrays of length ncyl that
    are left holding the transfer functions. Generalized forces follow (19): M = Σ P_q u_q + Σ M_k.
    """
    phi = y[PHI]
    J, dJ = inertia(m, phi, u, du)
    w = speed(J, angle_mode, y)
    M_gas = 0.0
    if m.has_gas:
        for k in range(m.ncyl):
            M_gas += m.gas_scale[k] * (gas_value(m, k, phi, sel) - m.gas_offset) * u[k]
        M_gas *= fuel(m, w, sw[SW_GOVERNOR])
    M_load = -(m.load_const + m.load_linear * w + m.load_fan * w * abs(w))
    M_starter = 0.0
    if sw[SW_STARTER]:
        M_starter = m.starter_torque * (1.0 - w / m.starter_noload)
    return J, dJ, w, M_gas, M_load, M_starter


@njit(cache=True)
def acceleration(J, dJ, M, w):
    """φ̈ from (18): (M − ½ J′ ω²) / J."""
    return (M - 0.5 * dJ * w * w) / J


@njit(cache=True)
def derivative(m, angle_mode, y, sel, sw, u, du, out):
    """dy/dt = (ω, 1, ε), or in crank angle dy/dφ = (1, 1/ω, M) with y[2] = K."""
    J, dJ, w, M_gas, M_load, M_starter = moments(m, angle_mode, y, sel, sw, u, du)
    if angle_mode:
        out[PHI] = 1.0
        out[T] = 1.0 / w
        out[KINETIC] = M_gas + M_load + M_starter
    else:
        eps = acceleration(J, dJ, M_gas + M_load + M_starter, w)
        out[PHI] = w
        out[T] = 1.0
        out[OMEGA] = eps


@njit(cache=True)
def output_row(m, angle_mode, y, sel, sw, u, du, row):
    """Fill one output sample (columns ``OUTPUTS`` then the gas value of each cylinder)."""
    J, dJ, w, M_gas, M_load, M_starter = moments(m, angle_mode, y, sel, sw, u, du)
    row[0] = y[T]
    row[1] = y[PHI]
    row[2] = w
    row[3] = acceleration(J, dJ, M_gas + M_load + M_starter, w)
    row[4] = J
    row[5] = dJ
    row[6] = M_gas
    row[7] = M_load
    row[8] = M_starter
    row[9] = fuel(m, w, sw[SW_GOVERNOR])
    for k in range(m.ncyl):
        row[N_OUT_FIXED + k] = gas_value(m, k, y[PHI], sel) if m.has_gas else 0.0


@njit(cache=True)
def inverse_dynamics(m, t, phi, omega, eps, rows, M_drive):
    """Prescribed motion: the drive torque (18) needs, M_drive = J ε + ½ J′ ω² − M [N m].

    Fills ``rows`` (one output row per sample, ``epsilon`` being the prescribed one) and
    ``M_drive``; the starter is off and ``sel`` is the sample angle itself.
    """
    n = max(m.ncyl, 1)
    u = np.empty(n)
    du = np.empty(n)
    y = np.empty(N_STATE)
    sw = np.zeros(N_SWITCHES, dtype=np.int64)
    for i in range(t.shape[0]):
        y[PHI] = phi[i]
        y[T] = t[i]
        y[OMEGA] = omega[i]
        sw[SW_GOVERNOR] = governor_branch(m, omega[i], eps[i] >= 0.0)
        output_row(m, False, y, phi[i], sw, u, du, rows[i])
        rows[i, COL_EPS] = eps[i]
        M = rows[i, COL_M_GAS] + rows[i, COL_M_LOAD]
        M_drive[i] = rows[i, COL_J] * eps[i] + 0.5 * rows[i, COL_DJ] * omega[i] ** 2 - M
