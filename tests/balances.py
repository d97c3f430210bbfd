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
