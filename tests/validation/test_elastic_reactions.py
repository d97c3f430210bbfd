"""Friction on the joints' reactions on an elastic shaft line (theory, (T8);
:func:`transient.core.model.line_pairs.throw_reactions`): each throw's joints at its own angle,
speed and acceleration, the station's equation closed on them. Checked against what is
independent of the compiled throw solve: the reference crank-slider's Newton–Euler joints with
their friction laws (:func:`transient.reference.crank_slider_friction`, written separately) at
a frozen twisted state, with the line's torques from :class:`~transient.shaft.ShaftLine`'s
matrices; and the rigid model's run with the same reaction pairs as the sections stiffen."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from elastic_checks import line_balance

import transient
from transient.assemble import build_model
from transient.core.model import layout, outputs
from transient.core.model.work import work_array
from transient.reference import crank_slider_friction, crank_slider_joint_signs
from transient.run import _initial_state
from transient.scene import load_scene
from transient.scene.outputs import column_name, cylinder_loss_column, output_columns
from transient.shaft import ShaftLine, rigid_equivalent

CASES = Path(__file__).resolve().parents[2] / "cases"
SIX = (CASES / "inline6_damper.toml").read_text(encoding="utf-8")

#: friction on the reactions of all four joints of each cylinder, coefficients of lubricated
#: pairs raised so that the friction stands far above rounding
JOINTS = """
[[friction.pairs]]
name = "main bearings"
between = ["shaft", "crank"]
model = "reaction"
mu = 0.02
radius = 0.03
viscous = 0.01

[[friction.pairs]]
name = "crankpins"
between = ["crank", "rod"]
model = "reaction"
mu = 0.02
radius = 0.026

[[friction.pairs]]
name = "piston pins"
between = ["rod", "piston"]
model = "reaction"
mu = 0.04
radius = 0.015

[[friction.pairs]]
name = "pistons"
between = ["piston", "cylinder"]
model = "reaction"
mu = 0.05
ring_force = 150.0
ring_pressure = 0.01
viscous = 3.0
"""

JOINT_ORDER = ("main", "crankpin", "pin", "slider")


def _frozen(seed: int):
    """The in-line six with :data:`JOINTS`, its Model and, at a random shaft angle, a state in
    the time domain with each dof twisted by up to 5 mrad and turning at 800 rpm ± 20 %."""
    scene = load_scene("six.toml", text=SIX + JOINTS)
    model = build_model(scene)[0]
    rng = np.random.default_rng(seed)
    y, _, ist = _initial_state(scene, model)
    lo = layout.line_index(model)
    n = layout.n_line_states(model)
    y[layout.PHI] = rng.uniform(0.0, 4.0 * np.pi)
    y[layout.OMEGA] = 800.0 * np.pi / 30.0
    y[lo:lo + n:2] = rng.uniform(-5e-3, 5e-3, n // 2)
    y[lo + 1:lo + n:2] = y[layout.OMEGA] * rng.uniform(0.8, 1.2, n // 2)
    return scene, model, y, ist[:layout.N_SWITCHES].copy()


@pytest.mark.parametrize("seed", [3, 5, 8])
def test_each_throws_friction_is_the_newton_euler_joints_at_its_own_state(seed):
    """At a frozen twisted state: per throw k, with its θ_k, ω_k and the θ̈_k the compiled
    line gives, the reference's joints (friction laws iterated to their fixed point, directions
    at θ_k) close the station's equation J_own,k θ̈_k = T_line,k + Σ T_cyl (T_line from
    ShaftLine's K and C, numpy) to 1e-9 of the throw's torques, and every pair's loss power in
    every throw and every cylinder equals the reference's to 1e-9 of its largest."""
    scene, model, y, sw = _frozen(seed)
    wk = work_array(model)
    row = np.zeros(layout.n_outputs(model))
    outputs.output_row(model, layout.extras_of(model), False, y, y[layout.PHI], sw, wk, row)
    cols = dict(zip(output_columns(scene), row))
    line = ShaftLine(scene)
    names = [column_name(d.name) for d in line.dofs]
    theta = np.array([y[layout.PHI] + cols[f"twist_{d}"] for d in names])
    omega = np.array([cols[f"omega_{d}"] for d in names])
    accel = wk[layout.WK_LINE_RATE, :line.n]
    torque = -line.K @ theta - line.C @ omega
    mech = scene.mechanism
    jp = model.rx_par
    area = mech.piston_area
    P = np.array([(cols[f"p_{c + 1}"] - scene.gas.p0) * area for c in range(mech.n_cylinders)])
    checked = 0
    for s, st in enumerate(scene.shaft.stations):
        if not st.cylinders:
            continue
        d = line.station_dof[s]
        own = np.asarray(st.cylinders) - 1
        signs = crank_slider_joint_signs(mech, theta[d]) * np.sign(omega[d])
        forces, loss, _ = crank_slider_friction(mech, jp, theta[d], omega[d], accel[d], P, signs)
        T_cyl = forces.throw_torque[own, 0]
        scale = np.sum(np.abs(T_cyl)) + abs(torque[d])
        residual = st.inertia * accel[d] - torque[d] - np.sum(T_cyl)
        assert abs(residual) <= 1e-9 * scale, (st.name, residual, scale)
        lost = loss[:, own] * omega[d]  # per joint (= pair) and cylinder [W]
        big = np.max(np.abs(lost))
        assert big > 1.0  # (watts: far above rounding)
        for k in range(4):
            run = cols[f"P_loss_{k + 1}_{column_name(st.name)}"]
            assert run == pytest.approx(np.sum(lost[k]), abs=1e-9 * big), (st.name, k)
            for i, c in enumerate(own):
                assert cols[cylinder_loss_column(k, c)] == pytest.approx(lost[k, i],
                                                                         abs=1e-9 * big)
        checked += 1
    assert checked == 6


# -- the stiff limit ---------------------------------------------------------------------------

#: the six's throws each on a station of its own between a pulley and a flywheel, no damper
LINE = "\n[shaft]\n" + "".join(
    f'\n[[shaft.stations]]\nname = "{name}"\ninertia = {inertia}\n{cyl}\n'
    for name, inertia, cyl in [("pulley", 0.030, "")]
    + [(f"throw {k}", 0.010, f"cylinders = [{k}]") for k in range(1, 7)]
    + [("flywheel", 0.50, "")]) + (
    "\n[[shaft.sections]]\nstiffness = 1.0e6\ndamping_ratio = 0.05\n" * 7)


def _throws(factor: float):
    """The six with :data:`JOINTS` on :data:`LINE`, its sections ``factor`` times as stiff,
    over one cycle at rtol 1e-9."""
    text = SIX[:SIX.index("[shaft]")] + JOINTS + LINE.replace("1.0e6", f"{factor:g}e6")
    scene = load_scene("six.toml", text=text)
    return dataclasses.replace(
        scene, run=dataclasses.replace(scene.run, revolutions=2.0),
        solver=dataclasses.replace(scene.solver, rtol=1e-9, atol=1e-11))


def test_the_stiff_limit_is_the_rigid_machines_joint_friction():
    """Six throws on stations of their own, reaction friction on all four joints of each: as the
    sections stiffen 10, 100 and 1000 times, the flywheel's ω(φ) over one cycle and each pair's
    loss summed over the throws approach the rigid model's run of the rigid equivalent with the
    same pairs, the errors falling by more than 5 × per decade (1/k gives 10 ×; near 10 × the
    line's modes sit close to orders of the gas torque, which amplify its twist)."""
    rigid = transient.simulate(rigid_equivalent(_throws(1.0))).trajectory
    throws = [f"throw_{k}" for k in range(1, 7)]
    speed, losses = [], []
    for factor in (10.0, 100.0, 1000.0):
        run = transient.simulate(_throws(factor)).trajectory
        np.testing.assert_allclose(run["phi"], rigid["phi"], rtol=1e-12)  # (the same grid)
        speed.append(np.max(np.abs(run["omega"] - rigid["omega"])))
        losses.append(max(np.max(np.abs(sum(run[f"W_loss_{k}_{t}"] for t in throws)
                                        - rigid[f"W_loss_{k}"])) for k in (1, 2, 3, 4)))
    for errors in (speed, losses):
        assert errors[0] > 5.0 * errors[1] > 25.0 * errors[2], errors
    assert speed[2] < 1e-5 * np.max(rigid["omega"])
    assert losses[2] < 1e-4 * min(rigid[f"W_loss_{k}"][-1] for k in (1, 2, 3, 4))


# -- the mechanisms whose cylinders ride on one crankpin or plate ------------------------------

def _one_station(case: str, factor: float):
    """``case`` (its friction on the reactions of every joint) with its cylinders on one
    station between a front end and its flywheel, the sections 10⁶·``factor`` N m/rad, damped,
    over two revolutions at rtol 1e-9."""
    text = (CASES / case).read_text(encoding="utf-8")
    start = text.index("[inertia]")
    block = text[start:text.index("\n\n", start) + 2]
    own = dict(line.split(" = ") for line in block.splitlines()[1:] if " = " in line)
    n = load_scene(case, text=text).mechanism.n_cylinders
    line = (f'\n[shaft]\n\n[[shaft.stations]]\nname = "front"\ninertia = 0.05\n'
            f'\n[[shaft.stations]]\nname = "crankpin"\ninertia = {own["shaft"]}\n'
            f"cylinders = {list(range(1, n + 1))}\n"
            f'\n[[shaft.stations]]\nname = "flywheel"\ninertia = {own.get("flywheel", "0.5")}\n'
            + f"\n[[shaft.sections]]\nstiffness = {factor:g}e6\ndamping_ratio = 0.05\n" * 2)
    scene = load_scene(case, text=text.replace(block, "") + line)
    return dataclasses.replace(
        scene, run=dataclasses.replace(scene.run, revolutions=2.0, t_end=math.inf),
        solver=dataclasses.replace(scene.solver, rtol=1e-9, atol=1e-11))


@pytest.mark.parametrize("case", ["radial_5cyl_reaction_friction.toml",
                                  "swash_plate_4cyl_reaction_friction.toml"])
def test_one_crankpins_or_plates_joints_on_a_line(case):
    """The radial's master and articulated rods and the swash plate, their joints' friction
    solved at the station's own state: the energy balance (T4) with the joints' losses within
    1e2·rtol of the gas work; as the sections stiffen 1, 10 and 100 times the flywheel's ω(φ)
    (past the first quarter turn, where the start's free vibration has decayed) approaches the
    rigid model's run of the rigid equivalent, its error falling by more than 5 × per decade,
    and at the stiffest every pair's loss is the rigid run's within 2e-5 of itself (the loss
    integrals, which do not set the steps, differ by about 1e-5 of themselves between two step
    sequences: *Friction on the reactions* in the guide)."""
    scene = _one_station(case, 1.0)
    tr = transient.simulate(scene).trajectory
    balance, _ = line_balance(scene, tr)
    n_pairs = len(scene.friction.pairs)
    lost = sum(tr[f"W_loss_{k}_crankpin"] for k in range(1, n_pairs + 1))
    rtol = scene.solver.rtol
    assert lost[-1] > 1e3 * rtol * np.max(np.abs(tr["W_gas"]))
    assert np.max(np.abs(balance + lost)) <= 1e2 * rtol * np.max(np.abs(tr["W_gas"]))
    rigid = transient.simulate(rigid_equivalent(scene)).trajectory
    later = rigid["phi"] - rigid["phi"][0] >= 0.5 * np.pi
    speed = []
    for factor in (1.0, 10.0, 100.0):
        run = transient.simulate(_one_station(case, factor)).trajectory if factor > 1.0 else tr
        np.testing.assert_allclose(run["phi"], rigid["phi"], rtol=1e-12)
        speed.append(np.max(np.abs(run["omega"] - rigid["omega"])[later]))
    assert speed[0] > 5.0 * speed[1] > 25.0 * speed[2], speed
    for k in range(1, n_pairs + 1):
        total = rigid[f"W_loss_{k}"]
        assert np.max(np.abs(run[f"W_loss_{k}_crankpin"] - total)) <= 2e-5 * total[-1], k
