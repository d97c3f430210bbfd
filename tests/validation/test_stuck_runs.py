"""The stuck mode (:mod:`transient.core.model.stuck`): a machine at rest held by its pairs' friction stays
there while the drive is within what the friction holds, and is released at the instant the drive
exceeds it, checked against closed forms written apart from the kernels:

* **Reaction pairs**: the Gots diesel without gas whose only friction is the rings' tension F_ring
  on the pistons. At rest that friction holds a shaft torque up to H(φ) = F_ring Σ_k |s′_k(φ)|
  (virtual work; s′ from the loads analysis' kinematics), whatever the acceleration. A drive
  rising (falling) linearly in time, a load schedule on a negative ``[load] torque``, releases the
  shaft forward (backward) at the instant it reaches +H (−H).
* **Constant-η pairs**: the Gots diesel with its main bearings and crankpins, at rest at an angle
  where the gas resists with a moment −G (constant at rest: the pressures depend on the angle
  only). A drive s·G on the shaft is held for η_b1 η_b2 ≤ s ≤ 1/(η_f1 η_f2) (the chain's static
  reaction ratio, ``transient.core.model.chain``): the release instants follow from the schedule of s.
* **A load that reverses the machine**: turning forward, the rings bring the shaft to rest
  against a falling drive; it sticks there, ω exactly 0 and W_loss constant, and is released
  backward when the drive reaches −H at the angle where it stopped; every loss ≥ 0 and the
  work–energy balance closes.
* **No chattering**: a drive that oscillates about the threshold gives one stuck and one
  released event per swing above it, never two within 1e-6 s; a drive that comes to rest exactly
  on the threshold gives at most one release.

The release instants are located to the root finder's accuracy (1e-12 of a step) on an event
function that is exact along the stuck phase, so the bound is 1e-9 s.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from balances import check_release_at_holds, closure, drive, gas_forces_at_rest, losses_nonnegative

from transient.analysis.loads.crank_slider import slider_arrays
from transient.analysis.summary import stuck_phases
from transient.run import integrate
from transient.scene import Friction, Gas, Initial, Load, Output, Run, Starter, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
TOL_T = 1e-9  # s


def rings_only(load, phi0, omega0=0.0, t_end=1.0, dt=1e-3):
    """The reaction case without gas, only the rings' tension friction left, driven by ``load``."""
    base = load_scene(CASES / "gots_diesel_reaction_friction.toml")
    pairs = tuple(replace(p, mu=0.0, viscous=0.0, ring_pressure=0.0) for p in
                  base.friction.pairs)
    return replace(base, gas=Gas(model="none"), friction=Friction("power-flow", pairs),
                   load=load, starter=Starter(0.0, 1.0, 1.0), initial=Initial(phi0, omega0),
                   run=Run(t_end=t_end), output=Output(samples_per_rev=72, dt=dt),
                   solver=replace(base.solver, rtol=1e-10, atol=1e-10))


def ring_hold(scene, phi):
    """H(φ) = F_ring Σ |s′_k(φ)|: the drive the rings hold at rest at shaft angle φ."""
    mech = scene.mechanism
    alpha = phi - np.asarray(mech.firing_angles)
    s1 = slider_arrays(alpha, mech.crank_radius, mech.rod_length, mech.offset)[1]
    return scene.friction.pairs[-1].ring_force * float(np.sum(np.abs(s1)))


def stuck_samples(tr, t0, t1):
    inside = (tr["t"] > t0) & (tr["t"] < t1)
    assert np.count_nonzero(inside) >= 10
    return inside


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_rings_release_the_shaft_when_the_drive_reaches_their_hold(sign):
    """Held at rest from t = 0 (event ``stuck`` at the initial angle), released at
    t* = H/slope in the drive's direction (event ``released``), to 1e-9 s; until then ω = 0 and
    no energy is lost; after it the shaft turns in the drive's direction."""
    phi0 = 0.7
    probe = rings_only(Load(), phi0)
    H = ring_hold(probe, phi0)
    scene = rings_only(drive(0.0, sign * 2.0 * H, 1.0), phi0, t_end=0.8)
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    ev = data.events
    assert ev["stuck"].shape[0] == 1 and ev["released"].shape[0] == 1
    assert ev["stuck"][0, 0] == 0.0 and ev["stuck"][0, 1] == phi0
    t_rel = ev["released"][0, 0]
    print(f"release at {t_rel!r}, closed form 0.5, H = {H:.6g} N m")
    assert abs(t_rel - 0.5) <= TOL_T and ev["released"][0, 1] == phi0
    held = tr["t"] <= t_rel
    assert np.all(tr["omega"][held] == 0.0) and np.all(tr["phi"][held] == phi0)
    assert np.all(tr["W_loss_4"][held] == 0.0) and np.all(tr["W_load"][held] == 0.0)
    assert sign * tr["omega"][-1] > 0.0 and tr["W_loss_4"][-1] > 0.0
    losses_nonnegative(scene, tr)
    summary = stuck_phases(ev, float(tr["t"][-1]))
    assert summary["stuck_phases"][0] == 1.0 and abs(summary["stuck_time"][0] - 0.5) <= TOL_T


@pytest.mark.parametrize("policy", ["power-flow", "paper"])
def test_constant_eta_pairs_release_at_the_static_reaction_ratio(policy):
    """Gas resisting with −G at rest, drive s(t)·G: released forward at s = 1/(η_f1 η_f2),
    backward at s = η_b1 η_b2 (closed form from the efficiencies), to 1e-9 s."""
    base = load_scene(CASES / "gots_diesel_friction.toml")
    base = replace(base, friction=Friction(policy, base.friction.pairs),
                   starter=Starter(0.0, 1.0, 1.0), output=Output(samples_per_rev=72, dt=1e-2),
                   solver=replace(base.solver, rtol=1e-10, atol=1e-10))
    phi0 = 5.5  # a cylinder in compression: the gas resists a forward start
    probe = integrate(replace(base, load=Load(), friction=Friction(), initial=Initial(phi0, 0.0),
                              run=Run(t_end=1e-6)))
    G = -float(probe.trajectory["M_gas"][0])
    assert G > 100.0
    (p1, p2) = base.friction.pairs
    cases = ((1.1, 1.0 / (p1.eta_forward * p2.eta_forward), 1.0),
             (0.9, p1.eta_backward * p2.eta_backward, -1.0))
    for s1, s_rel, sign in cases:
        scene = replace(base, load=drive(G, s1 * G, 1.0), initial=Initial(phi0, 0.0),
                        run=Run(t_end=0.6))
        data = integrate(scene)
        tr = data.trajectory
        t_star = (s_rel - 1.0) / (s1 - 1.0)
        t_rel = data.events["released"][0, 0]
        print(f"{policy}, s → {s1}: release at {t_rel!r}, closed form {t_star!r}")
        assert data.events["stuck"][0, 0] == 0.0
        assert abs(t_rel - t_star) <= TOL_T
        held = stuck_samples(tr, 0.0, t_rel)
        assert np.all(tr["omega"][held] == 0.0) and np.all(tr["phi"][held] == phi0)
        assert np.all(tr["M_gas"][held] == tr["M_gas"][0])  # (the gas at rest: constant)
        for k in (1, 2):
            assert np.all(tr[f"W_loss_{k}"][held] == 0.0)
            assert np.all(tr[f"P_loss_{k}"][held] == 0.0)
        after = tr["t"] > t_rel + 0.02
        assert np.all(sign * tr["omega"][after][:5] > 0.0)
        if policy == "power-flow":
            losses_nonnegative(scene, tr)
        assert closure(scene, tr) <= 1e-8


def test_a_falling_drive_stops_the_shaft_holds_it_and_turns_it_back():
    """Turning forward at 2 rad/s against the rings with a drive H₀(0.5 − 2t): the shaft comes to
    rest (``speed_reversal``), is stuck where it stopped, φ₁, with ω exactly 0 and W_loss
    constant, and is released backward when the drive reaches −H(φ₁) (closed form), to 1e-9 s;
    every loss ≥ 0 and the work–energy balance closes to 1e-8 of the throughput."""
    phi0 = 0.7
    H0 = ring_hold(rings_only(Load(), phi0), phi0)
    scene = rings_only(drive(0.5 * H0, -3.5 * H0, 2.0), phi0, omega0=2.0, t_end=1.0)
    data = integrate(scene)
    assert data.complete, data.message
    tr, ev = data.trajectory, data.events
    assert ev["speed_reversal"].shape[0] == 1 and ev["stuck"].shape[0] == 1
    t_stop, phi1 = ev["stuck"][0]
    assert t_stop == ev["speed_reversal"][0, 0] and phi1 > phi0
    H1 = ring_hold(scene, phi1)
    t_star = (0.5 * H0 + H1) / (2.0 * H0)  # 0.5 H0 − 2 H0 t = −H1
    t_rel = ev["released"][0, 0]
    print(f"stopped at t = {t_stop:.9g} s, φ₁ = {phi1:.9g}; released at {t_rel!r}, closed form "
          f"{t_star!r}")
    assert abs(t_rel - t_star) <= TOL_T and ev["released"][0, 1] == phi1
    held = stuck_samples(tr, t_stop, t_rel)
    assert np.all(tr["omega"][held] == 0.0) and np.all(tr["phi"][held] == phi1)
    W = tr["W_loss_4"][held]
    assert np.all(W == W[0]) and W[0] > 0.0
    assert tr["omega"][-1] < 0.0 and tr["phi"][-1] < phi1
    losses_nonnegative(scene, tr)
    assert closure(scene, tr) <= 1e-8


def test_a_drive_hovering_at_the_threshold_does_not_chatter():
    """A drive swinging ±2 % about the rings' hold H (a triangle of period 0.1 s), and one that
    rises to H exactly and stays: stuck and released alternate, each phase longer than 1e-6 s,
    at most one release per swing above H; the run ends as it should."""
    phi0 = 0.7
    H = ring_hold(rings_only(Load(), phi0), phi0)
    times = tuple(0.025 * j for j in range(21))
    scales = tuple(H * (1.0 + (-0.02 if j % 4 == 0 else 0.02 if j % 4 == 2 else 0.0))
                   for j in range(21))
    scene = rings_only(Load(torque=-1.0, schedule_time=times, schedule_scale=scales), phi0,
                       t_end=0.5)
    data = integrate(scene)
    assert data.complete, data.message
    ev = data.events
    marks = sorted([(t, "s") for t in ev["stuck"][:, 0]] + [(t, "r") for t in ev["released"][:, 0]])
    kinds = [k for _, k in marks]
    print(f"{len(ev['stuck'])} stuck, {len(ev['released'])} released: {marks}")
    assert kinds[0] == "s" and all(a != b for a, b in zip(kinds, kinds[1:]))
    assert np.min(np.diff([t for t, _ in marks])) > 1e-6
    assert 1 <= ev["released"].shape[0] <= 5  # (five swings above H in 0.5 s)
    losses_nonnegative(scene, data.trajectory)
    flat = rings_only(drive(0.0, H, 0.2), phi0, t_end=0.4)
    data = integrate(flat)
    assert data.complete, data.message
    assert data.events["stuck"].shape[0] == 1 and data.events.get(
        "released", np.zeros((0, 2))).shape[0] <= 1


def test_a_load_step_beyond_the_hold_releases_the_shaft_at_the_step():
    """A drive that jumps from H/2 to 3H/2 at t = 0.2 s (a step in the load schedule, an event on
    time): stuck until the step, released at it exactly, forward."""
    phi0 = 0.7
    H = ring_hold(rings_only(Load(), phi0), phi0)
    load = Load(torque=-1.0, schedule_time=(0.2, 0.2), schedule_scale=(0.5 * H, 1.5 * H))
    data = integrate(rings_only(load, phi0, t_end=0.4))
    assert data.complete, data.message
    ev, tr = data.events, data.trajectory
    assert ev["stuck"][:, 0].tolist() == [0.0] and ev["released"][:, 0].tolist() == [0.2]
    assert np.all(tr["omega"][tr["t"] <= 0.2] == 0.0) and tr["omega"][-1] > 0.0


def test_stuck_until_the_end_and_locked_where_nothing_can_release_it():
    """A drive that never reaches the hold keeps the shaft stuck to t_end (the run finishes, stuck
    the whole time); the same drive held constant cannot release it, and the run ends *locked*
    at once, as does a run that ends by revolutions only."""
    phi0 = 0.7
    H = ring_hold(rings_only(Load(), phi0), phi0)
    data = integrate(rings_only(drive(0.0, 0.9 * H, 1.0), phi0, t_end=0.3))
    assert data.complete, data.message
    tr = data.trajectory
    assert tr["t"][-1] == 0.3 and np.all(tr["omega"] == 0.0) and np.all(tr["phi"] == phi0)
    summary = stuck_phases(data.events, float(tr["t"][-1]))
    assert summary["stuck_time"][0] == 0.3
    constant = rings_only(Load(torque=-0.9 * H), phi0, t_end=0.3)
    data = integrate(constant)
    assert not data.complete and data.message.startswith("locked"), data.message
    assert data.trajectory["t"][-1] == 0.0
    by_revolutions = replace(rings_only(drive(0.0, 2.0 * H, 1.0), phi0), run=Run(revolutions=2))
    data = integrate(by_revolutions)
    assert not data.complete and data.message.startswith("locked"), data.message
    assert "run.t_end" in data.message


def static_hold(scene, phi, gas_force, sigma):
    """The drive on the shaft that the joints' friction balances at rest at φ (ε = ω = 0) against
    an incipient motion σ: the Newton–Euler joint forces of every cylinder
    (``transient.reference.crank_slider_joint_forces``) with the friction of each joint on its
    force — μ r |F| against the joint's relative rotation in the main bearing, crankpin and
    piston pin, μ |N| + F_ring + c_p P⁺ against the piston's motion — iterated to a fixed point
    (a contraction: μ r / l and μ tan β are small), then the drive −Σ T that keeps ε = 0."""
    from transient.reference import crank_slider_joint_forces

    mech = scene.mechanism
    main, crankpin, pin, piston = scene.friction.pairs
    alpha = phi - np.asarray(mech.firing_angles)
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    sb = (r * np.sin(alpha) - e) / l
    cb = np.sqrt(1.0 - sb * sb)
    db = r * np.cos(alpha) / (l * cb)  # β′ = dβ/dφ
    vy = -r * np.sin(alpha) - l * sb * db  # the piston's speed along +y (toward the head) per ω
    s_a, s_b = sigma * np.sign(1.0 + db), sigma * np.sign(db)
    P = np.asarray(gas_force, dtype=float)
    f0 = piston.ring_force + piston.ring_pressure * np.maximum(P, 0.0)
    N = np.zeros_like(P)
    moments = (np.zeros_like(P),) * 3
    for _ in range(200):
        # the piston's friction, −sign(v)(μ|N| + f0) along +y, adds to the force toward the crank
        slide = np.sign(vy) * sigma * (piston.mu * np.abs(N) + f0)
        jf = crank_slider_joint_forces(mech, phi, 0.0, 0.0, gas_force=(P + slide)[:, None],
                                       joint_moments=tuple(m[:, None] for m in moments))
        norm = [np.hypot(*np.asarray(v)[:, :, 0]) for v in (jf.main, jf.crankpin, jf.pin)]
        new = (-sigma * main.mu * main.radius * norm[0],
               s_a * crankpin.mu * crankpin.radius * norm[1],
               s_b * pin.mu * pin.radius * norm[2])
        change = max(max(float(np.max(np.abs(n - m))) for n, m in zip(new, moments)),
                     float(np.max(np.abs(jf.N[:, 0] - N))))
        moments, N = new, jf.N[:, 0]
        if change <= 1e-13 * max(1.0, float(np.max(np.abs(P)))):
            break
    # (the last solve's forces are those of the moments one iteration back: within 1e-13)
    return -float(np.sum(jf.throw_torque))


def test_the_joints_release_the_diesel_at_the_newton_euler_hold():
    """The reaction diesel with all four pairs (journals, pins, pistons; the viscous terms vanish
    at rest), at rest where a cylinder compresses, the gas on: the drive it holds forward and
    backward, M₊ and M₋, from an independent static Newton–Euler solution with the friction
    on the joints' forces (:func:`static_hold`); a drive ramping from their mean past M₊ (past M₋)
    releases it forward (backward) at the instant it reaches it, to 1e-8 of M₊."""
    base = load_scene(CASES / "gots_diesel_reaction_friction.toml")
    phi0 = 5.5
    base = replace(base, starter=Starter(0.0, 1.0, 1.0), initial=Initial(phi0, 0.0),
                   output=Output(samples_per_rev=72, dt=1e-2),
                   solver=replace(base.solver, rtol=1e-10, atol=1e-10))
    P = gas_forces_at_rest(base)
    hold_fwd = static_hold(base, phi0, P, 1.0)
    hold_bwd = static_hold(base, phi0, P, -1.0)
    print(f"gas forces {P} N; holds {hold_fwd:.9g} N m forward, {hold_bwd:.9g} N m backward")
    check_release_at_holds(base, hold_fwd, hold_bwd)


def test_a_governor_raises_the_fuel_while_stuck_until_the_gas_breaks_loose():
    """The constant-η diesel at rest early in a cylinder's expansion under a PI governor far below
    its set speed, against a constant load L equal to its gas torque at the initial fuel: stuck, ω
    exactly 0, while the governor's states evolve and raise the fuel; released forward when the
    gas torque reaches L/(η_b1 η_b2) (the gas side drives, both pairs backward; closed form from
    the efficiencies, the gas torque read from the samples around the event, 1e-6 relative)."""
    base = load_scene(CASES / "gots_diesel_friction.toml")
    gov = replace(load_scene(CASES / "gots_diesel_pi.toml").governor, fuel_initial=0.1)
    phi0 = 2.5  # a cylinder early in its expansion: the gas drives forward
    base = replace(base, governor=gov, starter=Starter(0.0, 1.0, 1.0),
                   initial=Initial(phi0, 0.0), output=Output(samples_per_rev=72, dt=2e-6),
                   solver=replace(base.solver, rtol=1e-10, atol=1e-10))
    probe = integrate(replace(base, load=Load(), friction=Friction(), run=Run(t_end=1e-6)))
    L = float(probe.trajectory["M_gas"][0])
    assert L > 100.0
    scene = replace(base, load=Load(torque=L), run=Run(t_end=0.01))
    data = integrate(scene)
    tr, ev = data.trajectory, data.events
    assert ev["stuck"][0, 0] == 0.0
    t_rel = ev["released"][0, 0]
    held = stuck_samples(tr, 0.0, t_rel)
    assert np.all(tr["omega"][held] == 0.0) and np.all(tr["W_loss_1"][held] == 0.0)
    assert np.all(np.diff(tr["fuel"][held]) > 0.0) and np.ptp(tr["gov_integral"][held]) > 0.0
    (p1, p2) = scene.friction.pairs
    M_at = float(np.interp(t_rel, tr["t"], tr["M_gas"]))  # (samples 2e-6 s apart)
    target = L / (p1.eta_backward * p2.eta_backward)
    print(f"released at t = {t_rel:.9g} s: gas torque {M_at:.9g} N m, closed form {target:.9g}")
    assert abs(M_at - target) <= 1e-6 * target
    assert tr["omega"][-1] > 0.0
    losses_nonnegative(scene, tr)


def test_a_run_resumed_inside_a_stuck_phase_is_bit_identical():
    """The stuck switch is part of the stepper's state that a checkpoint keeps: the reversing
    run resumed from every block that ends while it is stuck continues bit-identically."""
    from transient.results import Checkpoint
    from transient.run import run_compiled

    phi0 = 0.7
    H0 = ring_hold(rings_only(Load(), phi0), phi0)
    scene = rings_only(drive(0.5 * H0, -3.5 * H0, 2.0), phi0, omega0=2.0, t_end=1.0, dt=2e-5)
    states = []
    whole = run_compiled(scene, on_block=lambda block, ev, state: states.append(
        (block["t"].size, state)))
    assert whole.complete, whole.message
    t_stop, t_rel = whole.events["stuck"][0, 0], whole.events["released"][0, 0]
    rows, resumed = 0, 0
    for n, (floats, ints, switched, code) in states:
        rows += n
        t = whole.trajectory["t"][rows - 1]
        if not t_stop < t < t_rel:
            continue
        part = run_compiled(scene, start=Checkpoint(rows, 0, switched, code, floats, ints))
        assert part.complete
        for name, column in part.trajectory.items():
            assert np.array_equal(column, whole.trajectory[name][rows:]), name
        assert np.array_equal(part.events["released"], whole.events["released"])
        resumed += 1
    assert resumed >= 2


def test_stuck_phases_from_the_events():
    """The summary's count and total time of the stuck phases, the last one open to the end."""
    ev = {"stuck": np.array([[0.0, 1.0], [2.0, 3.0], [5.0, 4.0]]),
          "released": np.array([[0.5, 1.0], [2.25, 3.0]])}
    s = stuck_phases(ev, 6.0)
    assert s["stuck_phases"][0] == 3.0 and s["stuck_time"][0] == 0.5 + 0.25 + 1.0
    assert s["stuck_first_t"][0] == 0.0 and s["stuck_first_phi"][0] == 1.0
    assert stuck_phases({}, 1.0) == {}
    assert math.isclose(stuck_phases({"stuck": np.array([[1.0, 0.0]])}, 3.0)["stuck_time"][0], 2.0)


def test_mapped_pairs_stick_and_release_as_their_constants():
    """Pairs given as efficiency maps that hold their constant-η values everywhere stick and are
    released at the same instants as the constant-η pairs, and keep the balance (the mapped
    chain's solve at rest, ``eta_table.solve_auto``, reduces to the constant one)."""
    base = load_scene(CASES / "gots_diesel_friction.toml")
    base = replace(base, starter=Starter(0.0, 1.0, 1.0),
                   output=Output(samples_per_rev=72, dt=1e-2),
                   solver=replace(base.solver, rtol=1e-10, atol=1e-10))
    phi0 = 5.5
    probe = integrate(replace(base, load=Load(), friction=Friction(), initial=Initial(phi0, 0.0),
                              run=Run(t_end=1e-6)))
    G = -float(probe.trajectory["M_gas"][0])
    pairs = base.friction.pairs
    mapped = Friction(base.friction.policy, tuple(
        replace(p, model="table", eta_forward=1.0, eta_backward=1.0, speed=(0.0, 600.0),
                torque=(0.0, 10.0, 1000.0), eta_forward_map=((p.eta_forward,) * 3,) * 2,
                eta_backward_map=((p.eta_backward,) * 3,) * 2) for p in pairs))
    for s1 in (1.1, 0.9):
        common = dict(load=drive(G, s1 * G, 1.0), initial=Initial(phi0, 0.0), run=Run(t_end=0.6))
        constant = integrate(replace(base, **common))
        table = integrate(replace(base, friction=mapped, **common))
        for name in ("stuck", "released"):
            np.testing.assert_allclose(table.events[name][:, 0], constant.events[name][:, 0],
                                       rtol=0.0, atol=TOL_T)
        scene = replace(base, friction=mapped, **common)
        assert closure(scene, table.trajectory) <= 1e-8
        losses_nonnegative(scene, table.trajectory)
