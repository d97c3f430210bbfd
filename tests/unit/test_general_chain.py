"""The general serial chain from a scene: constant-η pairs between any neighbouring links of a
mechanism (crank-slider ``shaft`` – ``crank`` – ``rod`` – ``piston`` – ``cylinder``), each
passing on the power it really transmits (``transient.core.model.rhs.split_subchains``).

Independent checks:

* a model of the four-pair crank-slider written here from the Gots relations (exact piston
  velocity, two-mass rod), the gas by ``np.interp`` of its table, and Antonyuk's (27)–(28)
  generalised to n pairs (I_np = Σ c_j J_j, M_np = Σ c_j M_j, A = Σ c_j ½J′_j) with the
  reactions of (29) solved from the far end, every mode vector tried for the one consistent
  with the power each pair transmits: the compiled right-hand side agrees with it at random
  states to rounding, and a run integrated by the compiled stepper agrees with it integrated
  by scipy's ``solve_ivp`` (in crank angle, piecewise between the table's corners) to the
  run's tolerance;
* at rest (no inertia power) the chain's efficiency is Π η_forward while the shaft drives and
  Π η_backward while the gas does (docs/theory.md, *The chain's efficiency*);
* the work–energy balance of four-pair runs of every mechanism;
* the links' own inertias (the pistons' m·Σu_k², the swash plate's link 9 by (15)–(17)) from
  the mechanisms' kinematics tables.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from transient.assemble import build_model
from transient.core.model import forcing, inverse, layout, rhs, work
from transient.core.model.chain import UNIQUE
from transient.errors import SceneError
from transient.run import integrate
from transient.scene import Friction, Pair, load_scene
from transient.verify.stress import balance_residual, balance_tolerance

CASES = Path(__file__).resolve().parents[2] / "cases"
RNG = np.random.default_rng(20261207)

# The Gots diesel's geometry and masses (cases/gots_diesel_friction.toml), three cylinders, an
# offset to keep the kinematics general, and a made-up cycle tabulated at a few points with
# linear interpolation, so that the model below can read it exactly.
R, L, E, BORE = 0.047, 0.148, 0.004, 0.088
M_PISTON, M_CRANK, M_ROD, ROD_CG = 1.520, 0.912, 1.752, 0.1073
FIRING_DEG = (360.0, 600.0, 120.0)
J_SHAFT, FAN = 0.17, 9.692e-4
TABLE_DEG = (0, 180, 300, 350, 360, 368, 390, 450, 540, 560, 720)
TABLE_BAR = (1.0, 1.0, 8.0, 40.0, 55.0, 80.0, 60.0, 15.0, 3.0, 1.1, 1.0)
P0 = 1.0e5
LINKS = ("shaft", "crank", "rod", "piston", "cylinder")
ETA = {("shaft", "crank"): (0.985, 0.98), ("crank", "rod"): (0.98, 0.975),
       ("rod", "piston"): (0.99, 0.985), ("piston", "cylinder"): (0.96, 0.95)}


def scene_text(fan: float = FAN, omega_rpm: float = 1000.0, revolutions: float = 4.0,
               rtol: float = 1e-10) -> str:
    pairs = "".join(f'\n[[friction.pairs]]\nbetween = ["{a}", "{b}"]\neta_forward = {f}\n'
                    f"eta_backward = {b_}\n" for (a, b), (f, b_) in ETA.items())
    return f"""
[scene]
name = "four-pairs"

[mechanism]
type = "crank-slider"
crank_radius = {R}
rod_length = {L}
offset = {E}
bore = {BORE}
piston_mass = {M_PISTON}
crank_mass = {M_CRANK}
strokes = 4
cylinders = 3
firing_deg = {list(FIRING_DEG)}

[mechanism.rod]
model = "two-mass"
mass = {M_ROD}
cg_from_pin = {ROD_CG}

[gas]
model = "table"
p0 = {P0}
interpolation = "linear"
phi_deg = {list(TABLE_DEG)}
p_bar = {list(TABLE_BAR)}
corners_deg = {list(TABLE_DEG[1:-1])}

[inertia]
shaft = {J_SHAFT}

[load]
fan = {fan}

[initial]
omega_rpm = {omega_rpm}

[run]
revolutions = {revolutions}

[solver]
rtol = {rtol}
atol = {rtol}

[output]
samples_per_rev = 36

[friction]
{pairs}"""


def four_pairs(**kw):
    return load_scene("four-pairs.toml", text=scene_text(**kw))


# -- the separately written model ------------------------------------------------------------


def links_at(phi: float, omega: float, fan: float = FAN):
    """(J_i, J′_i, M_i) of every link at shaft angle φ, from the Gots relations."""
    a = phi - np.radians(FIRING_DEG)
    sb = (R * np.sin(a) - E) / L
    cb = np.sqrt(1.0 - sb * sb)
    db = R * np.cos(a) / (L * cb)  # β′
    u = R * np.sin(a) + R * np.cos(a) * sb / cb  # ds/dφ toward the crank (Gots §1.2)
    du = R * np.cos(a) - R * np.sin(a) * sb / cb + R * np.cos(a) * db / cb ** 2
    m_pin = M_ROD * (L - ROD_CG) / L  # Gots (20): the rod's masses at the pin and the crankpin
    m_pinc = M_ROD * ROD_CG / L
    x = np.mod(phi - np.radians(FIRING_DEG) + 2.0 * np.pi, 4.0 * np.pi)  # table's 0: exchange TDC
    p = np.interp(np.degrees(x), TABLE_DEG, TABLE_BAR) * 1e5
    J = np.array([J_SHAFT, 3 * M_CRANK * R ** 2, np.sum(m_pinc * R ** 2 + m_pin * u ** 2),
                  M_PISTON * np.sum(u ** 2), 0.0])
    dJ = np.array([0.0, 0.0, 2 * m_pin * np.sum(u * du), 2 * M_PISTON * np.sum(u * du), 0.0])
    M = np.array([-fan * omega * abs(omega), 0.0, 0.0, 0.0,
                  np.sum((p - P0) * math.pi * BORE ** 2 / 4 * u)])
    return J, dJ, M


def chain_27(J, dJ, M, eta_f, eta_b, omega, check_unique=True):
    """φ̈, S_k and η*_k of a serial chain of sub-chains (J, J′, M) by (27)–(28) with c_j =
    Π_{i<j} 1/η*_i, the pair moments by (29) from the far end (the last sub-chain's equation,
    then each one's towards the shaft), for the one mode vector under which every pair's mode
    has the sign of the power it passes on (S_k ω ≥ 0 forward; ``check_unique``: that no other
    vector is consistent too)."""
    n = len(eta_f)
    found = []
    for backward in itertools.product((False, True), repeat=n):
        es = np.where(backward, 1.0 / np.asarray(eta_b), np.asarray(eta_f))
        c = np.concatenate(([1.0], np.cumprod(1.0 / es)))
        I_np, M_np, A = c @ J, c @ M, c @ (0.5 * dJ)
        a = (M_np - A * omega ** 2) / I_np  # (27)
        S = np.zeros(n)
        beyond = 0.0  # S of the pair beyond: η*_k S_k = J_{k+1} a + ½J′_{k+1} ω² − M_{k+1} + S_{k+1}
        for k in range(n - 1, -1, -1):
            S[k] = (J[k + 1] * a + 0.5 * dJ[k + 1] * omega ** 2 - M[k + 1] + beyond) / es[k]
            beyond = S[k]
        if all((s * omega < 0) == b for s, b in zip(S, backward)):
            found.append((a, S, es))
            if not check_unique:
                break
    assert len(found) == 1, found
    return found[0]


def subchains(pairs, J, dJ, M):
    """The links' terms summed into the sub-chains that the pairs cut."""
    cuts = [LINKS.index(a) for a, _ in pairs]
    sub = [sum(c < i for c in cuts) for i in range(len(LINKS))]
    out = np.zeros((3, len(pairs) + 1))
    for i, s in enumerate(sub):
        out[:, s] += J[i], dJ[i], M[i]
    return out


def own_acceleration(phi, omega, pairs=tuple(ETA), check_unique=True):
    Jk, dJk, Mk = subchains(pairs, *links_at(phi, omega))
    return chain_27(Jk, dJk, Mk, [ETA[p][0] for p in pairs], [ETA[p][1] for p in pairs], omega,
                    check_unique)


# -- the compiled model ----------------------------------------------------------------------


def compiled_at(model, phi, omega):
    """φ̈, the sub-chains' J, J′, M and the pairs' S, η* of the compiled model at (φ, ω), with
    the modes it chooses there."""
    wk = work.work_array(model)
    ex = layout.extras_of(model)
    y = np.zeros(layout.n_state(model))
    y[layout.PHI], y[layout.OMEGA] = phi, omega
    sw = np.zeros(layout.N_SWITCHES, dtype=np.int64)
    assert rhs.choose_modes(model, ex, False, y, phi, sw, wk) == UNIQUE
    J, dJ, w, Mg, Ml, Ms = forcing.moments(model, ex, False, y, phi, sw, wk, True)
    a = rhs.acceleration(model, ex, phi, J, dJ, w, Mg, Ml, Ms, sw, wk)
    n = model.n_pairs
    return (a, wk[layout.WK_J, :n + 1].copy(), wk[layout.WK_DJ, :n + 1].copy(),
            wk[layout.WK_M, :n + 1].copy(), wk[layout.WK_S, :n].copy(),
            wk[layout.WK_ETA, :n].copy())


@pytest.mark.parametrize("pairs", [
    tuple(ETA),
    (("shaft", "crank"), ("rod", "piston")),  # a gap: the crankpins ideal
    (("rod", "piston"), ("piston", "cylinder")),
    (("piston", "cylinder"),),
])
def test_rhs_agrees_with_27_to_29_written_apart(pairs):
    """At random states, each sub-chain's J, J′, M, the pairs' moments S_k and modes and φ̈ of
    the compiled model are those of the model above to rounding."""
    base = four_pairs()
    scene = replace(base, friction=Friction("power-flow", tuple(
        Pair(between=p, eta_forward=ETA[p][0], eta_backward=ETA[p][1]) for p in pairs)))
    model, _, _ = build_model(scene)
    for phi, omega in zip(RNG.uniform(0, 4 * math.pi, 40), RNG.uniform(-500, 500, 40)):
        a, Jk, dJk, Mk, S, eta = compiled_at(model, phi, omega)
        J, dJ, M = subchains(pairs, *links_at(phi, omega))
        a_own, S_own, eta_own = own_acceleration(phi, omega, pairs)
        scale_J = np.abs(J).sum()
        np.testing.assert_allclose(Jk, J, rtol=1e-12, atol=1e-13 * scale_J)
        np.testing.assert_allclose(dJk, dJ, rtol=1e-10, atol=1e-12 * scale_J)
        scale_M = np.abs(M).sum() + np.abs(dJ).sum() * omega ** 2
        np.testing.assert_allclose(Mk, M, rtol=1e-10, atol=1e-12 * scale_M)
        assert a == pytest.approx(a_own, rel=1e-10, abs=1e-12 * scale_M / scale_J)
        np.testing.assert_allclose(S, S_own, rtol=1e-9, atol=1e-11 * scale_M)
        np.testing.assert_array_equal(eta, eta_own)
        if pairs[-1] == ("piston", "cylinder"):  # the last pair passes the gas work exactly
            assert S[-1] == -Mk[-1] / eta[-1]


@pytest.mark.slow  # (solve_ivp of the model written apart, a Python right-hand side)
def test_four_pair_run_agrees_with_solve_ivp_of_the_model_written_apart():
    """Four revolutions of the four-pair engine from 1000 rpm (compression and firing, every
    pair switching modes): the compiled run at rtol = 1e-10 against the model above integrated
    in crank angle by ``solve_ivp`` (DOP853, rtol 1e-12) from one table corner to the next.
    At each output sample t and ω agree within E = 50 units of atol + rtol·|y| of the run: each
    path's global error is bounded by the sum of its local errors (one unit per step at most)
    while the errors do not grow, and the run takes more steps than that."""
    scene = four_pairs()
    data = integrate(scene)
    assert data.status == "finished", data.message
    tr = data.trajectory
    rtol = scene.solver.rtol
    w0 = scene.initial.omega
    corners = np.sort(np.mod(np.add.outer(np.radians(FIRING_DEG) - 2 * np.pi,
                                          np.radians(TABLE_DEG[:-1])).ravel(), 4 * np.pi))
    phi_end = tr["phi"][-1]
    cuts = np.concatenate([corners + 4 * np.pi * j for j in range(int(phi_end / (4 * np.pi)) + 2)])
    cuts = np.concatenate(([0.0], cuts[(cuts > 0.0) & (cuts < phi_end)], [phi_end]))

    def rhs_phi(phi, y):
        a = own_acceleration(phi, y[1], check_unique=False)[0]
        return [1.0 / y[1], a / y[1]]

    y, t_own, w_own = np.array([0.0, w0]), [], []
    samples = tr["phi"]
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        sol = solve_ivp(rhs_phi, (lo, hi), y, method="DOP853", rtol=1e-12, atol=1e-14,
                        dense_output=True)
        assert sol.success, sol.message
        y = sol.y[:, -1]
        inside = samples[(samples >= lo) & (samples < hi)]
        if inside.size:
            yy = sol.sol(inside)
            t_own.extend(yy[0])
            w_own.extend(yy[1])
    t_own.append(y[0])
    w_own.append(y[1])
    t_own, w_own = np.array(t_own), np.array(w_own)
    assert t_own.size == samples.size
    E = 50.0
    e_t = (tr["t"] - t_own) / (rtol + rtol * np.abs(t_own))
    e_w = (tr["omega"] - w_own) / (rtol + rtol * np.abs(w_own))
    assert np.max(np.abs(e_t)) <= E, np.max(np.abs(e_t))
    assert np.max(np.abs(e_w)) <= E, np.max(np.abs(e_w))
    assert data.solver["nsteps"] > E
    assert len(data.events.get("pair_mode", ())) >= 8  # the pairs switched on the way


def test_the_chain_passes_on_the_product_of_its_efficiencies_at_rest():
    """With nothing stored in the links (ω = 0, φ̈ = 0) and no load, the drive the shaft needs
    against the gas at every angle of a cycle: where the gas resists the motion the shaft
    drives every pair forward and must put in |M_gas|/Π η_forward; where the gas drives, the
    shaft receives Π η_backward of it. Both directions of the incipient motion."""
    scene = four_pairs(fan=0.0)
    model, _, _ = build_model(scene)
    eta_f = np.prod([f for f, _ in ETA.values()])
    eta_b = np.prod([b for _, b in ETA.values()])
    phi = np.linspace(0.0, 4 * math.pi, 721)
    rows = np.zeros((phi.size, layout.n_outputs(model)))
    drive = np.zeros(phi.size)
    n_ok = np.zeros(phi.size, dtype=np.int64)
    for sigma in (1.0, -1.0):
        eps = np.full(phi.size, 0.0 if sigma > 0 else -1e-300)
        inverse.inverse_dynamics(model, layout.extras_of(model), np.zeros(phi.size), phi,
                                 np.zeros(phi.size), eps, rows, drive, n_ok)
        gas = rows[:, layout.COL_M_GAS]
        moving = np.abs(gas) > 1e-9 * np.abs(gas).max()
        resisting = moving & (gas * sigma < 0)
        driving = moving & (gas * sigma > 0)
        assert resisting.sum() > 100 and driving.sum() > 100
        np.testing.assert_allclose(drive[resisting], -gas[resisting] / eta_f, rtol=1e-13)
        np.testing.assert_allclose(drive[driving], -gas[driving] * eta_b, rtol=1e-13)
        assert np.all(n_ok[moving] == 1)


@pytest.mark.parametrize("case, pairs", [
    ("gots_diesel_friction", (("shaft", "crank"), ("crank", "rod"), ("rod", "piston"),
                              ("piston", "cylinder"))),
    ("radial_5cyl", (("shaft", "crank"), ("crank", "rod"), ("rod", "piston"),
                     ("piston", "cylinder"))),
    ("swash_plate_4cyl", (("shaft", "link"), ("link", "rod"), ("rod", "piston"),
                          ("piston", "cylinder"))),
])
def test_energy_balances_with_four_pairs(case, pairs):
    """Work in = ΔK + Σ losses over a four-pair run of every mechanism, to the solver's
    tolerance; no pair's loss is ever negative (power-flow modes), and each pair loses."""
    base = load_scene(CASES / f"{case}.toml")
    scene = replace(base, run=replace(base.run, revolutions=12.0, t_end=math.inf),
                    friction=Friction("power-flow", tuple(
                        Pair(between=p, eta_forward=0.97 + 0.005 * k,
                             eta_backward=0.96 + 0.005 * k) for k, p in enumerate(pairs))))
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    assert balance_residual(tr, len(pairs)) <= balance_tolerance(scene.solver.rtol)
    for k in range(1, len(pairs) + 1):
        scale = np.abs(tr[f"P_loss_{k}"]).max()
        assert scale > 0.0 and tr[f"W_loss_{k}"][-1] > 0.0
        assert tr[f"P_loss_{k}"].min() >= -1e-12 * scale


@pytest.mark.parametrize("case", ["gots_diesel_friction", "radial_5cyl", "swash_plate_4cyl"])
def test_each_link_has_its_own_inertia(case):
    """Every link a pair of its own: the pistons' sub-chain holds m·Σu_k² and m·2Σu_k u_k′ with
    u_k from the kinematics table (per piston: the swash plate's halves move alike), the swash
    plate's link 9 with the crosses I₉ u₉,₁² + I₁₃ u₁₃² of (13)–(17) (isotropic link 9, the
    case's), the cylinders nothing; the sub-chains add up to J(φ) and J′(φ)."""
    base = load_scene(CASES / f"{case}.toml")
    mech = base.mechanism
    links = mech.links
    pairs = tuple(Pair(between=(a, b), eta_forward=0.98, eta_backward=0.97)
                  for a, b in zip(links, links[1:]))
    model, _, _ = build_model(replace(base, friction=Friction("power-flow", pairs)))
    assert list(model.link_sub) == [0, 1, 2, 3, 4]
    phis = RNG.uniform(0, mech.cycle, 12)
    table = mech.kinematics_table(phis)
    halves = getattr(mech, "halves", 1)
    for j, phi in enumerate(phis):
        _, Jk, dJk, _, _, _ = compiled_at(model, phi, 100.0)
        u = np.array([table[f"u_{k + 1}"][j] for k in range(mech.n_cylinders)])
        du = np.array([table[f"du_{k + 1}"][j] for k in range(mech.n_cylinders)])
        assert Jk[3] == pytest.approx(halves * mech.piston_mass * u @ u, rel=1e-12)
        assert dJk[3] == pytest.approx(2 * halves * mech.piston_mass * u @ du, rel=1e-10,
                                       abs=1e-12 * Jk[3])
        assert Jk[4] == 0.0 and dJk[4] == 0.0
        assert Jk.sum() == pytest.approx(base.inertia.total + table["J"][j], rel=1e-13)
        assert dJk.sum() == pytest.approx(table["dJ_dphi"][j], rel=1e-10,
                                          abs=1e-12 * table["J"][j])
        if mech.name == "swash-plate":
            assert mech.link_polar_inertia == mech.link_diametral_inertia
            def own(phi):
                t = mech.kinematics_table(np.asarray(phi))
                return halves * (mech.link_polar_inertia * t["u9"] ** 2
                                 + mech.cross_inertia * t["u13"] ** 2)

            assert Jk[1] == pytest.approx(own(phi)[0], rel=1e-12)
            h = 1e-5  # central difference: error ~ h² J‴/6, rounding ~ 1e-16 J/h
            assert dJk[1] == pytest.approx((own(phi + h) - own(phi - h))[0] / (2 * h),
                                           abs=1e-8 * Jk[1])
        else:
            assert Jk[1] == pytest.approx(model.link_J[1], rel=1e-15)


@pytest.mark.parametrize("case, between, fragment", [
    ("radial_5cyl", '["rod", "slave rod"]',
     "unknown link 'slave rod'; the links are shaft – crank – rod – piston – cylinder (pairs "
     "with model = \"reaction\" join shaft – crank – master rod – slave rod – piston – "
     "cylinder)"),
    ("swash_plate_4cyl", '["shaft", "plate"]',
     "unknown link 'plate'; the links are shaft – link – rod – piston – cylinder (pairs with "
     "model = \"reaction\" join shaft – plate – link – rod – piston – cylinder)"),
    ("swash_plate_4cyl", '["shaft", "rod"]',
     "'shaft' and 'rod' are not neighbours; a pair joins two adjacent links of the chain "
     "shaft – link – rod – piston – cylinder"),
])
def test_each_mechanism_names_its_links_in_a_refusal(case, between, fragment):
    """A constant-η pair off a mechanism's chain is refused with the key and the links it has
    (and, where they differ, those of the reaction model)."""
    text = (CASES / f"{case}.toml").read_text()  # (no [friction] of its own)
    text += (f"\n[friction]\n\n[[friction.pairs]]\nbetween = {between}\neta_forward = 0.9\n"
             f"eta_backward = 0.9\n")
    with pytest.raises(SceneError) as err:
        load_scene(CASES / f"{case}.toml", text=text)
    assert err.value.key == "friction.pairs[0].between"
    assert fragment in err.value.message
