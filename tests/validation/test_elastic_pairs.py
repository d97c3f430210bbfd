"""Non-ideal pairs on an elastic shaft line (theory, (T7); :mod:`transient.core.model.line_pairs`):
every pair acts in each throw's own chain, with its own mode. The compiled run checked against
what is independent of it: the reference path's separately written line with a constant-η pair
in each throw (:meth:`transient.reference.torsion.TorsionModel.through_pairs`, integrated by
scipy), the energy balance (T4) with the pairs' losses written out from the output columns, the
rigid model's run of the same pairs as the sections stiffen, and the throws' modes and their
switches against the reference's power through each throw's pair."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from elastic_checks import check_against_reference, line_balance

import transient
from transient.analysis.efficiency import mechanical_efficiency
from transient.assemble import build_model
from transient.core.model import layout
from transient.reference.torsion import WORKS, from_scene, integrate
from transient.scene import load_scene
from transient.scene.outputs import column_name, output_columns
from transient.shaft import rigid_equivalent

CASES = Path(__file__).resolve().parents[2] / "cases"
SIX = (CASES / "inline6_damper.toml").read_text(encoding="utf-8")

#: the main bearing of every throw
MAIN_BEARINGS = """
[[friction.pairs]]
name = "main bearings"
between = ["shaft", "crank"]
eta_forward = 0.95
eta_backward = 0.90
"""


def scene_of(text: str, revolutions: float, rtol: float):
    """The scene of ``text`` over ``revolutions`` at ``rtol`` (atol 1e-2 of it)."""
    sc = load_scene("scene.toml", text=text)
    return dataclasses.replace(
        sc, run=dataclasses.replace(sc.run, revolutions=revolutions),
        solver=dataclasses.replace(sc.solver, rtol=rtol, atol=1e-2 * rtol))


def six(extra: str = MAIN_BEARINGS, revolutions: float = 4.0, rtol: float = 1e-8):
    """The in-line six of cases/inline6_damper.toml with ``extra`` tables over ``revolutions``
    from 800 rpm, at ``rtol``."""
    return scene_of(SIX + extra, revolutions, rtol)


def throws(scene) -> list[str]:
    """The column names of the stations that carry cylinders."""
    return [column_name(st) for st in scene.shaft.throws]


@pytest.fixture(scope="module")
def main_bearings():
    scene = six()
    res = transient.simulate(scene)
    return scene, res


#: friction on the reactions of each throw's main bearing and piston (theory, (T7b))
REACTIONS = """
[[friction.pairs]]
name = "main bearings"
between = ["shaft", "crank"]
model = "reaction"
mu = 0.02
radius = 0.03
viscous = 0.01

[[friction.pairs]]
name = "pistons"
between = ["piston", "cylinder"]
model = "reaction"
mu = 0.05
ring_force = 150.0
"""


@pytest.fixture(scope="module")
def reactions():
    scene = six(REACTIONS)
    res = transient.simulate(scene)
    return scene, res


def test_the_run_is_the_reference_lines_with_a_pair_in_each_throw(main_bearings):
    """Over two cycles from 800 rpm with a main-bearing pair (η 0.95 forward, 0.90 backward)
    in each of the six throws: the reference station's ω(t) within 10·rtol of its largest and a
    middle section's torque within 1000·rtol of its largest, against scipy's DOP853 at rtol
    1e-10 on the reference line's (T7) in each throw; each station's speed within 100·rtol of
    its largest (its vibration at the line's first mode, 270 Hz, carries the phase error of the
    twist); the pairs' losses summed over the throws against the reference's within 100·rtol
    of the largest."""
    scene, res = main_bearings
    tr = res.trajectory
    model, _, y = check_against_reference(scene, tr)
    rtol = scene.solver.rtol
    n = model.line.n
    names = [column_name(st.name) for st in scene.shaft.stations]
    for i, name in enumerate(names):
        w = tr[f"omega_{name}"]
        assert np.max(np.abs(y[n + i] - w)) <= 100 * rtol * np.max(w), name
    lost = sum(tr[f"W_loss_1_{t}"] for t in throws(scene))
    reference = y[model.i_works + WORKS.index("L_pairs")]
    assert lost[-1] > 1e-3 * tr["W_gas"][-1]  # (a visible share of the work)
    assert np.max(np.abs(reference - lost)) <= 1e2 * rtol * np.max(lost)


@pytest.mark.parametrize("case", ["main_bearings", "reactions"])
def test_the_energy_balance_holds_with_the_pairs_losses(case, request):
    """(T4) with friction on, a constant-η main bearing in each throw or friction on the
    reactions of each throw's main bearing and piston: Σ ½J_d ω_d² + Σ ½k δ² − its start − the
    applied work + the line's damping + every throw's pair losses within 1e2·rtol of the gas
    work at every sample; each throw's loss never decreases (power-flow: (1 − η*) S ω ≥ 0;
    the joints' friction opposes their motion), with reaction pairs each pair's loss split
    over its cylinders adds up to its throws' to rounding, and the efficiency analysis closes
    its balance with them."""
    scene, res = request.getfixturevalue(case)
    tr = res.trajectory
    balance, _ = line_balance(scene, tr)
    n_pairs = len(scene.friction.pairs)
    lost = sum(tr[f"W_loss_{k}_{t}"] for t in throws(scene) for k in range(1, n_pairs + 1))
    rtol = scene.solver.rtol
    assert np.max(np.abs(balance)) > 1e3 * rtol * np.max(tr["W_gas"])  # (the pairs take a share)
    assert np.all(tr["W_starter"] == 0.0)  # (no starter: nothing else writes its rate)
    assert np.max(np.abs(balance + lost)) <= 1e2 * rtol * np.max(np.abs(tr["W_gas"]))
    for t in throws(scene):
        for k in range(1, n_pairs + 1):
            assert np.all(np.diff(tr[f"W_loss_{k}_{t}"]) >= -1e-9 * np.max(lost)), (t, k)
            assert np.all(tr[f"P_loss_{k}_{t}"] >= 0.0), (t, k)
    if case == "reactions":
        n = scene.mechanism.n_cylinders
        for k in range(1, n_pairs + 1):
            split = sum(tr[f"P_loss_{k}_cyl{c}"] for c in range(1, n + 1))
            total = sum(tr[f"P_loss_{k}_{t}"] for t in throws(scene))
            assert np.max(np.abs(split - total)) <= 1e-12 * np.max(total), k
    budget = mechanical_efficiency(scene, tr, window=(tr["phi"][0], tr["phi"][-1], 2))
    assert abs(budget["energy_balance_residual"][0]) <= 1e2 * rtol
    per_throw = sum(budget[f"W_loss_1_{t}_per_cycle"][0] for t in throws(scene))
    assert budget["W_loss_1_per_cycle"][0] == pytest.approx(per_throw, rel=1e-12)


def test_the_summary_and_the_figure_show_each_throws_pair(main_bearings, capsys):
    """The run's summary gives the pair's loss over the throws and a line per throw, whose
    losses add up to it; the pairs' figure a transmitted and a lost curve per throw."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from transient.cli.plot import pair_curves
    from transient.cli.run import _print_efficiency, pair_names
    from transient.plots import pair_power

    scene, res = main_bearings
    tr = res.trajectory
    budget = mechanical_efficiency(scene, tr, window=(tr["phi"][0], tr["phi"][-1], 2))
    _print_efficiency({k: v for k, (v, _) in budget.items()}, pair_names(scene))
    out = capsys.readouterr().out
    assert "pair 1 (main bearings): loss" in out and "in each throw:" in out
    lines = [line.split(":")[0].strip() for line in out.splitlines() if "circulated" in line]
    assert lines == throws(scene)
    fig, ax = plt.subplots()
    assert len(pair_power(ax, tr, pair_curves(scene), scene.mechanism.cycle)) == 12
    assert ax.get_lines()[0].get_label() == "main bearings at throw 1: transmitted"
    plt.close(fig)


def test_the_throws_modes_differ_and_switch_on_their_own_zeros(main_bearings):
    """The throws' pairs are in different modes at once (a firing throw drives its main
    bearing from the crank side while one compressing is driven from the shaft side), each as
    the reference's power through that throw's pair says, and each S_k within 1e-4 of its
    largest of the reference's; every mode switch of the run lands where one throw's S_k ω_k
    is zero in the reference (to 1e-5 of its largest), on several throws' zeros in turn."""
    scene, res = main_bearings
    tr = res.trajectory
    model, _ = from_scene(scene)
    sol = integrate(model, model.initial_state(scene.initial.phi, scene.initial.omega),
                    tr["t"][-1], rtol=1e-10, atol=1e-10, dense_output=True)
    stations = [scene.shaft.station_index(st) for st in scene.shaft.throws]

    def pairs(times):
        at = [model.pairs_at(t, sol.sol(t)) for t in times]
        return (np.array([S[stations] for S, _ in at]).T,
                np.array([eta[stations] for _, eta in at]).T)

    S, eta = pairs(tr["t"])
    names = throws(scene)
    S_run = np.array([tr[f"S_1_{t}"] for t in names])
    eta_run = np.array([tr[f"eta_1_{t}"] for t in names])
    scale = np.max(np.abs(S), axis=1, keepdims=True)
    assert np.max(np.abs(S_run - S) / scale) <= 1e-4
    clear = np.abs(S) > 1e-3 * scale  # (away from a switch, where either mode is right)
    assert np.array_equal(eta_run[clear], eta[clear])
    both = np.any(eta_run == 0.95, axis=0) & np.any(eta_run == 1.0 / 0.90, axis=0)
    assert np.count_nonzero(both) > 0.5 * both.size
    events = res.events["pair_mode"]["t"]
    assert events.size >= 12
    S_at = np.abs(pairs(events)[0]) / scale
    zeros = np.argmin(S_at, axis=0)
    assert np.all(S_at[zeros, np.arange(events.size)] <= 1e-5), S_at.min(axis=0)
    assert len(set(zeros.tolist())) >= 4, zeros


def test_the_w_method_switches_the_throws_modes_and_keeps_the_balance():
    """The same line stepped by ROS34PW2 at rtol 1e-6 (its dense output locating the throws'
    mode switches): (T4) with the pairs' losses within 1e2·rtol of the gas work, and the
    throws' switches as many as DOP853's within a tenth."""
    scene = six(revolutions=2.0, rtol=1e-6)
    scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver,
                                                                  method="ros34pw2"))
    res = transient.simulate(scene)
    tr = res.trajectory
    balance, _ = line_balance(scene, tr)
    lost = sum(tr[f"W_loss_1_{t}"] for t in throws(scene))
    assert np.max(np.abs(balance + lost)) <= 1e2 * 1e-6 * np.max(np.abs(tr["W_gas"]))
    explicit = transient.simulate(dataclasses.replace(
        scene, solver=dataclasses.replace(scene.solver, method="dop853")))
    n, m = res.events["pair_mode"]["t"].size, explicit.events["pair_mode"]["t"].size
    assert m >= 12 and abs(n - m) <= 0.1 * m, (n, m)


# -- the stiff limit ---------------------------------------------------------------------------

#: the six's cylinders all on one station between a pulley and a flywheel; sections damped
LINE = """
[shaft]
[[shaft.stations]]
name = "pulley"
inertia = 0.030

[[shaft.stations]]
name = "crankshaft"
inertia = 0.060
cylinders = [1, 2, 3, 4, 5, 6]

[[shaft.stations]]
name = "flywheel"
inertia = 0.50

[[shaft.sections]]
stiffness = 1.0e6
damping_ratio = 0.05

[[shaft.sections]]
stiffness = 1.0e6
damping_ratio = 0.05
"""

#: a chain of three pairs in each throw: the main bearings, the pistons on their rods (the
#: pistons' inertia m Σ u² a sub-chain of its own) and the pistons in their cylinders, the
#: rods' a map of η over |S|
CHAIN = """
[[friction.pairs]]
name = "main bearings"
between = ["shaft", "crank"]
eta_forward = 0.95
eta_backward = 0.90

[[friction.pairs]]
name = "piston pins"
between = ["rod", "piston"]
model = "table"
speed_rpm = [0, 3000]
torque = [0, 200, 1000]
eta_forward = [[0.90, 0.96, 0.98], [0.88, 0.95, 0.97]]
eta_backward = [[0.89, 0.95, 0.97], [0.87, 0.94, 0.96]]

[[friction.pairs]]
name = "pistons"
between = ["piston", "cylinder"]
eta_forward = 0.97
eta_backward = 0.96
"""


def _one_station(factor: float):
    """The six's cylinders on one station of :data:`LINE` with its sections ``factor`` times
    as stiff and :data:`CHAIN`, over two cycles at rtol 1e-10."""
    text = SIX[:SIX.index("[shaft]")] + CHAIN + LINE.replace("1.0e6", f"{factor:g}e6")
    return scene_of(text, 4.0, 1e-10)


def test_the_stiff_limit_is_the_rigid_chain():
    """The six's cylinders on one station (its chain the rigid machine's), three pairs — one
    of them mapped — in it: as the sections stiffen 10, 100 and 1000 times, the flywheel's
    ω(φ) over two cycles and each pair's loss approach the rigid model's run of the rigid
    equivalent with the same pairs, the errors falling by more than 7 × per decade (as 1/k)."""
    rigid = transient.simulate(rigid_equivalent(_one_station(1.0))).trajectory
    speed, losses = [], []
    for factor in (10.0, 100.0, 1000.0):
        run = transient.simulate(_one_station(factor)).trajectory
        np.testing.assert_allclose(run["phi"], rigid["phi"], rtol=1e-12)  # (the same grid)
        speed.append(np.max(np.abs(run["omega"] - rigid["omega"])))
        losses.append(max(np.max(np.abs(run[f"W_loss_{k}_crankshaft"] - rigid[f"W_loss_{k}"]))
                          for k in (1, 2, 3)))
    for errors in (speed, losses):
        assert errors[0] > 7.0 * errors[1] > 49.0 * errors[2], errors
    assert speed[2] < 1e-5 * np.max(rigid["omega"])
    assert losses[2] < 1e-4 * rigid["W_loss_1"][-1]


# -- what the line refuses ---------------------------------------------------------------------

@pytest.mark.parametrize("extra, key", [
    (MAIN_BEARINGS + '\n[[friction.pairs]]\nbetween = ["piston", "cylinder"]\n'
     'model = "reaction"\nmu = 0.05\n', "friction.pairs"),
    ("[friction]\npolicy = \"paper\"\n" + MAIN_BEARINGS, "friction.policy"),
])
def test_what_the_line_refuses(extra, key):
    """A constant-η pair at the main bearings among reaction pairs and the paper's criterion
    are refused with an elastic line before any work, naming the key."""
    scene = six(extra)
    with pytest.raises(transient.SceneError, match=key.replace(".", r"\.")):
        transient.simulate(scene)


def test_more_modes_than_the_switch_holds_are_refused():
    """Four pairs in each of 16 throws are 64 modes, beyond the 62 bits of the modes' switch:
    refused before any work, naming friction.pairs."""
    head = SIX[:SIX.index("[shaft]")].replace("cylinders = 6\nfiring_order = [1, 5, 3, 6, 2, 4]\n",
                                              "cylinders = 16\n")
    links = ("shaft", "crank", "rod", "piston", "cylinder")
    pairs = "".join(f'\n[[friction.pairs]]\nbetween = ["{a}", "{b}"]\neta_forward = 0.95\n'
                    f"eta_backward = 0.95\n" for a, b in zip(links, links[1:]))
    line = "".join(f'\n[[shaft.stations]]\nname = "t{i}"\ninertia = 0.01\ncylinders = [{i}]\n'
                   for i in range(1, 17))
    line += '\n[[shaft.stations]]\nname = "flywheel"\ninertia = 0.5\n'
    line += "\n[[shaft.sections]]\nstiffness = 1e6\n" * 16
    scene = load_scene("sixteen.toml", text=head + pairs + "[shaft]\n" + line)
    with pytest.raises(transient.SceneError, match=r"friction\.pairs: .* at most 62"):
        transient.simulate(scene)


def test_a_start_from_rest_is_refused():
    """From rest a throw held by its pairs would need a stuck state of its own: refused,
    naming initial.omega."""
    scene = six()
    scene = dataclasses.replace(scene, initial=dataclasses.replace(scene.initial, omega=0.0))
    with pytest.raises(transient.SceneError, match=r"initial\.omega"):
        transient.simulate(scene)


def test_the_columns_and_the_state_hold_each_throws_pairs():
    """Each pair's columns per throw, in the order the compiled row writes them, and one loss
    state per pair and throw."""
    scene = _one_station(1.0)
    assert [c for c in output_columns(scene) if c.startswith("S_")] == [
        "S_1_crankshaft", "S_2_crankshaft", "S_3_crankshaft"]
    scene = six(MAIN_BEARINGS + MAIN_BEARINGS.replace('"shaft", "crank"', '"crank", "rod"')
                .replace("main bearings", "crankpins"))
    cols = [c for c in output_columns(scene) if c.startswith("eta_")]
    assert cols[:4] == ["eta_1_throw_1", "eta_2_throw_1", "eta_1_throw_2", "eta_2_throw_2"]
    assert len(cols) == 12
    model = build_model(scene)[0]
    sizes = dict(zip([b.name for b in layout.STATE.blocks], layout.STATE.sizes_for(model)))
    assert sizes["loss"] == 12 and layout.n_margins.py_func(model) == 12
