"""Checks of runs with friction pairs that the tests share (on ``pythonpath``, pyproject)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from transient.run import integrate
from transient.scene import Output, Run


def closure(scene, tr) -> float:
    """Relative residual of the work–energy balance ½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load +
    W_starter − Σ W_loss,k at every sample, against the largest energies of the run."""
    n = len(scene.friction.pairs)
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    works = tr["W_gas"] + tr["W_load"] + tr["W_starter"]
    lost = sum(tr[f"W_loss_{k + 1}"] for k in range(n))
    scale = K.max() + np.abs(tr["W_gas"]).max() + np.abs(tr["W_load"]).max() + np.abs(
        tr["W_starter"]).max()
    return float(np.max(np.abs(K - K[0] - (works - lost))) / scale)


def losses_nonnegative(scene, tr) -> None:
    """Every pair's loss is finite and ≥ 0 at every sample (beyond rounding): the held modes agree
    with the power the pairs transmit, including crossings inside a step."""
    for k in range(len(scene.friction.pairs)):
        P = tr[f"P_loss_{k + 1}"]
        assert np.all(np.isfinite(P)) and P.min() >= -1e-9 * max(np.abs(P).max(), 1e-300), (
            k, P.min())


def dense_spin_up(make):
    """``make(**changes)`` → a scene with friction pairs, run 8 revolutions in time throughout
    (a switch speed above every ω reached) at tight tolerances, densely sampled; (scene, data)."""
    base = make()
    scene = make(run=Run(revolutions=8.0),
                 solver=replace(base.solver, rtol=1e-11, atol=1e-11, switch_speed=1e4),
                 output=Output(samples_per_rev=720, dt=1e-6))
    data = integrate(scene)
    assert data.complete, data.message
    assert "to_angle_domain" not in data.events
    return scene, data


def without_friction(pairs):
    """Reaction pairs with every coefficient 0: the same joints, losing nothing."""
    return tuple(replace(p, mu=0.0, viscous=0.0, ring_force=0.0, ring_pressure=0.0)
                 for p in pairs)


def loss_is_share_of_transmitted(tr, k) -> None:
    """Pair k's loss is (1 − η*) S ω at every sample where η* is defined, as for a constant-η
    pair (rounding)."""
    P, S, eta = tr[f"P_loss_{k}"], tr[f"S_{k}"], tr[f"eta_{k}"]
    ok = np.isfinite(eta)
    assert np.allclose(P[ok], (1.0 - eta[ok]) * S[ok] * tr["omega"][ok], rtol=1e-12,
                       atol=1e-9 * np.max(np.abs(P))), k


def check_zero_friction_is_ideal(base, axis: str) -> None:
    """``base`` with its reaction pairs' coefficients all 0 loses nothing and moves as the scene
    without friction pairs: ω over ``axis`` ("phi" or "t") to 1e-6 of its largest value."""
    from transient.scene import Friction

    zero = integrate(replace(base, friction=Friction("power-flow",
                                                     without_friction(base.friction.pairs))))
    ideal = integrate(replace(base, friction=Friction()))
    assert zero.complete and ideal.complete, (zero.message, ideal.message)
    tr = zero.trajectory
    for k in range(1, len(base.friction.pairs) + 1):
        assert np.all(tr[f"P_loss_{k}"] == 0.0) and np.all(tr[f"W_loss_{k}"] == 0.0), k
    x = np.linspace(tr[axis][0], tr[axis][-1], 2001)
    w1 = np.interp(x, tr[axis], tr["omega"])
    w0 = np.interp(x, ideal.trajectory[axis], ideal.trajectory["omega"])
    print(f"max |Δω| / max ω = {np.max(np.abs(w1 - w0)) / np.max(w0):.1e}")
    assert np.max(np.abs(w1 - w0)) <= 1e-6 * np.max(w0)


def drive(d0, d1, t1):
    """A drive torque on the shaft going linearly from d0 at t = 0 to d1 at t1 [N m] (a load
    schedule scaling a negative torque)."""
    from transient.scene import Load

    return Load(torque=-1.0, schedule_time=(0.0, t1), schedule_scale=(d0, d1))


def gas_forces_at_rest(base) -> np.ndarray:
    """Each piston's gas force [N] at the start of ``base`` (at rest the pressures depend on the
    angle only): from a run of 1 µs without load or friction."""
    from transient.scene import Friction, Load

    probe = integrate(replace(base, load=Load(), friction=Friction(), run=Run(t_end=1e-6)))
    mech = base.mechanism
    return np.array([(probe.trajectory[f"p_{k + 1}"][0] - base.gas.p0) * mech.piston_area
                     for k in range(mech.n_cylinders)])


def check_release_at_holds(base, hold_fwd: float, hold_bwd: float) -> None:
    """``base`` at rest, stuck, under a drive ramping from the mean of the holds M₊ > M₋ (the
    drives its friction holds forward and backward, from an independent solution) past M₊ (past
    M₋): released forward (backward) at the instant the drive reaches it, to 1e-8 of M₊; ω and
    φ exactly held until then; stuck again later only where the shaft came to a stop (a speed
    reversal at that instant: an engine rocking against a compression); the losses ≥ 0."""
    assert hold_bwd < hold_fwd
    phi0 = base.initial.phi
    mid = 0.5 * (hold_fwd + hold_bwd)
    width = hold_fwd - hold_bwd
    for target, sign in ((hold_fwd, 1.0), (hold_bwd, -1.0)):
        end = mid + sign * width  # reached at t = 1 s
        scene = replace(base, load=drive(mid, end, 1.0), run=Run(t_end=0.8))
        data = integrate(scene)
        assert data.complete, data.message
        ev, tr = data.events, data.trajectory
        t_rel = ev["released"][0, 0]
        t_star = (target - mid) / (end - mid)
        print(f"σ = {sign:+g}: release at {t_rel!r}, Newton–Euler {t_star!r}")
        assert ev["stuck"][0, 0] == 0.0
        stops = ev["speed_reversal"][:, 0] if "speed_reversal" in ev else np.zeros(0)
        assert np.all(np.isin(ev["stuck"][1:, 0], stops)), (ev["stuck"][:, 0], stops)
        assert abs(t_rel - t_star) * abs(end - mid) <= 1e-8 * abs(hold_fwd)
        held = tr["t"] <= t_rel
        assert np.all(tr["omega"][held] == 0.0) and np.all(tr["phi"][held] == phi0)
        after = tr["t"] > t_rel + 0.05
        assert np.all(sign * tr["omega"][after][:5] > 0.0)
        losses_nonnegative(scene, tr)


def with_main_bearings(scene, pair):
    """``scene`` with ``pair`` at its main bearings (``["shaft", "crank"]``), power-flow policy."""
    from transient.scene import Friction

    return replace(scene, friction=Friction("power-flow", tuple(
        pair if tuple(p.between) == ("shaft", "crank") else p for p in scene.friction.pairs)))


def constant_main_bearings(scene):
    """``scene`` with its main bearings a constant-η pair (the efficiencies of
    ``cases/gots_diesel_friction.toml``), named as the pair it replaces."""
    from transient.scene import Pair

    name = next(p.name for p in scene.friction.pairs if tuple(p.between) == ("shaft", "crank"))
    return with_main_bearings(scene, Pair(between=("shaft", "crank"), eta_forward=0.985,
                                          eta_backward=0.98, name=name))

