"""Work–energy balance of a two-inertia gear with one non-ideal pair (transient.core.model.chain):
ΔKE = W_in − W_out − W_loss with the loss integrated as an extra state, in forward and backward
power flow, and the locking case at rest."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from transient.core.model.chain import LOCKED, UNIQUE, modes_power_flow

I_A, I_B, RATIO = 0.8, 2.5, 0.4  # shaft inertia, load inertia [kg m²], u = φ̇_b/φ̇_a (constant)
ETA_F, ETA_B = 0.85, 0.7
J = np.array([I_A, I_B * RATIO**2])
DJ = np.zeros(2)


def run(torque_a, torque_b, w0, t_end=3.0):
    """Integrate (φ, ω, W_a, W_b, W_loss); torque_x(ω_x) are the applied moments in each side's
    own coordinate. Returns the solution and the set of (status, η*) seen by the RHS."""
    f, b = np.array([ETA_F]), np.array([ETA_B])
    es, S = np.empty(1), np.empty(1)
    seen = set()

    def rhs(t, y):
        w = y[1]
        M = np.array([torque_a(w), torque_b(RATIO * w) * RATIO])
        a, status, _ = modes_power_flow(J, DJ, M, f, b, w, es, S)
        seen.add((status, es[0]))
        loss = (1.0 - es[0]) * S[0] * w if status != LOCKED else 0.0
        return [w, a, M[0] * w, M[1] * w, loss]

    sol = solve_ivp(rhs, (0.0, t_end), [0.0, w0, 0.0, 0.0, 0.0], method="DOP853",
                    rtol=1e-11, atol=1e-12)
    assert sol.success
    return sol, seen


def energy_terms(sol, w0):
    w1 = sol.y[1, -1]
    dKE = 0.5 * J.sum() * (w1**2 - w0**2)
    W_a, W_b, W_loss = sol.y[2:, -1]
    return dKE, W_a, W_b, W_loss, 0.5 * J[0] * (w1**2 - w0**2), 0.5 * J[1] * (w1**2 - w0**2)


@pytest.mark.parametrize("w0", [0.5, 6.0])
def test_forward_shaft_side_drives(w0):
    """Motor torque on side 0, viscous load on side 1: forward, loss = (1 − η_f)·power into pair."""
    sol, seen = run(lambda w: 10.0 - 0.3 * w, lambda wb: -4.0 * wb, w0)
    assert seen == {(UNIQUE, ETA_F)}
    dKE, W_in, W_b, W_loss, dKE_a, _ = energy_terms(sol, w0)
    W_out = -W_b
    assert W_in > 0 and W_out > 0 and W_loss > 0
    assert abs(dKE - (W_in - W_out - W_loss)) <= 1e-8 * W_in
    # The pair receives what the motor gives minus side 0's kinetic energy gain.
    assert abs(W_loss - (1.0 - ETA_F) * (W_in - dKE_a)) <= 1e-8 * W_in


@pytest.mark.parametrize("w0", [0.5, 6.0])
def test_backward_load_side_drives(w0):
    """Torque on side 1 (e.g. a load overrunning the shaft), brake on side 0: backward mode,
    loss = (1 − η_b)·power side 1 sends into the pair."""
    sol, seen = run(lambda w: -1.5 * w, lambda wb: 6.0, w0)
    assert seen == {(UNIQUE, 1.0 / ETA_B)}
    dKE, W_a, W_in, W_loss, _, dKE_b = energy_terms(sol, w0)
    W_out = -W_a
    assert W_in > 0 and W_out > 0 and W_loss > 0
    assert abs(dKE - (W_in - W_out - W_loss)) <= 1e-8 * W_in
    assert abs(W_loss - (1.0 - ETA_B) * (W_in - dKE_b)) <= 1e-8 * W_in


def test_locking_at_rest():
    """Side 0 at rest holding M_0 = 5 N m; a torque on side 1 whose reduced moment M_1 has
    |M_1| ∈ [η_f M_0, M_0/η_b] is held by the pair's friction: the kernel returns φ̈ = 0, status
    LOCKED, S_0 = M_0, and the integration stays exactly at rest with no loss. Outside that
    interval the gear starts to move in the consistent mode."""
    M0 = 5.0
    f, b = np.array([ETA_F]), np.array([ETA_B])
    es, S = np.empty(1), np.empty(1)
    for M1 in np.linspace(-ETA_F * M0, -M0 / ETA_B, 7):
        a, status, count = modes_power_flow(J, DJ, np.array([M0, M1]), f, b, 0.0, es, S)
        assert (a, status, count, S[0]) == (0.0, LOCKED, 0, M0)
        sol, seen = run(lambda w: M0, lambda wb, M1=M1: M1 / RATIO, 0.0, t_end=1.0)
        assert all(status == LOCKED for status, _ in seen)
        assert np.all(sol.y == 0.0)
    # Just beyond what the losses hold: backward (side 1 drives), a = (M_0 + η_b M_1)/(J_0 + η_b J_1).
    M1 = -1.01 * M0 / ETA_B
    a, status, _ = modes_power_flow(J, DJ, np.array([M0, M1]), f, b, 0.0, es, S)
    assert status == UNIQUE and es[0] == 1.0 / ETA_B
    assert a < 0 and abs(a - (M0 + ETA_B * M1) / (J[0] + ETA_B * J[1])) <= 1e-14
    # Less than η_f M_0 opposing: the shaft side drives forward, a = (η_f M_0 + M_1)/(η_f J_0 + J_1).
    M1 = -0.99 * ETA_F * M0
    a, status, _ = modes_power_flow(J, DJ, np.array([M0, M1]), f, b, 0.0, es, S)
    assert status == UNIQUE and es[0] == ETA_F
    assert a > 0 and abs(a - (ETA_F * M0 + M1) / (ETA_F * J[0] + J[1])) <= 1e-14
    # Without a holding moment on side 0 an efficiency model cannot hold anything (η_b > 0).
    a, status, _ = modes_power_flow(J, DJ, np.array([0.0, -1e-3]), f, b, 0.0, es, S)
    assert status == UNIQUE and a < 0
