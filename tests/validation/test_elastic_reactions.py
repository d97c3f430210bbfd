"""Friction on the joints' reactions on an elastic shaft line (theory, (T8);
:func:`transient.core.model.line_pairs.throw_reactions`): each throw's joints at its own angle,
speed and acceleration, the station's equation closed on them. Checked against what is
independent of the compiled throw solve: the reference crank-slider's Newton–Euler joints with
their friction laws (:func:`transient.reference.crank_slider_friction`, written separately) at
a frozen twisted state, with the line's torques from :class:`~transient.shaft.ShaftLine`'s
matrices; and the rigid model's run with the same reaction pairs as the sections stiffen."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

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

