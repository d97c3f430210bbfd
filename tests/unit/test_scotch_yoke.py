"""The Scotch yoke (``type = "scotch-yoke"``) against its closed forms: the piston's travel is
exactly r(1 − cos φ), so J(φ) = J₀ + m r² sin²φ, J′ = m r² sin 2φ, the piston's acceleration at
constant ω is a pure first order, and the crankpin load is P along the cylinder axis plus the
block's m_b r ω²; a run's kinetic energy changes by the work done on it."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from balances import closure

from transient.analysis.loads.scotch_yoke import scotch_yoke_loads
from transient.analysis.orders import order_spectrum
from transient.analysis.pistons import piston_kinematics
from transient.errors import SceneError
from transient.mechanisms import MECHANISMS
from transient.mechanisms.scotch_yoke import ScotchYoke
from transient.scene import Output, Run, load_scene, to_toml

CASE = Path(__file__).resolve().parents[2] / "cases" / "scotch_yoke_compressor.toml"
YOKE = ScotchYoke(crank_radius=0.02, bore=0.05, yoke_mass=0.8, block_mass=0.1, crank_mass=0.2)
#: Relative rounding of a few operations on doubles.
ROUNDING = 1e-14


def closed_form_J(mech, phi):
    """J(φ) and J′(φ) of (19) for harmonic travel."""
    r, m = mech.crank_radius, mech.yoke_mass
    J0 = (mech.block_mass + mech.crank_mass) * r * r
    return J0 + m * r * r * np.sin(phi) ** 2, m * r * r * np.sin(2.0 * phi)


def test_registered_and_read_from_its_case():
    mech = load_scene(CASE).mechanism
    assert MECHANISMS["scotch-yoke"] is ScotchYoke
    assert mech == YOKE and mech.strokes == 2 and mech.cycle == 2 * math.pi
    assert mech.geometry()["stroke"] == (0.04, "m")


def test_J_and_its_derivative_agree_with_the_closed_form():
    phi = np.linspace(-2 * math.pi, 2 * math.pi, 401)
    table = YOKE.kinematics_table(phi)  # the compiled kernel's
    J, dJ = closed_form_J(YOKE, phi)
    scale = J.max()
    np.testing.assert_allclose(table["J"], J, rtol=ROUNDING, atol=ROUNDING * scale)
    np.testing.assert_allclose(table["dJ_dphi"], dJ, rtol=ROUNDING, atol=ROUNDING * scale)
    np.testing.assert_allclose(table["s_1"], YOKE.crank_radius * (1 - np.cos(phi)),
                               atol=ROUNDING * YOKE.crank_radius)
    np.testing.assert_allclose(table["u_1"], YOKE.crank_radius * np.sin(phi),
                               atol=ROUNDING * YOKE.crank_radius)
    np.testing.assert_allclose(table["du_1"], YOKE.crank_radius * np.cos(phi),
                               atol=ROUNDING * YOKE.crank_radius)


def test_dJ_is_the_derivative_of_J_by_finite_differences():
    """Central differences of the kernel's J, step h: error h²J‴/6 ≈ 1e-13 of J′'s scale."""
    h = 1e-4
    phi = np.linspace(0.0, 2 * math.pi, 97)
    fd = (YOKE.kinematics_table(phi + h)["J"] - YOKE.kinematics_table(phi - h)["J"]) / (2 * h)
    dJ = YOKE.kinematics_table(phi)["dJ_dphi"]
    peak = YOKE.yoke_mass * YOKE.crank_radius ** 2
    np.testing.assert_allclose(fd, dJ, atol=1e-8 * peak)


def test_twin_is_written_apart_and_agrees():
    terms = YOKE.reference_terms()
    phi = np.linspace(0.0, 2 * math.pi, 37)
    table = YOKE.kinematics_table(phi)
    for j, p in enumerate(phi):
        J, dJ, u, du = terms(p)
        assert J == pytest.approx(table["J"][j], rel=ROUNDING)
        assert dJ == pytest.approx(table["dJ_dphi"][j], abs=ROUNDING * table["J"].max())
        assert u[0] == pytest.approx(table["u_1"][j], abs=ROUNDING * YOKE.crank_radius)


@pytest.mark.parametrize("source", ["kernel", "analysis"])
def test_piston_acceleration_is_a_pure_first_order(source):
    """W = ω² s″ at constant ω over one turn: order 1 of amplitude r ω², every other order
    (the mean among them) zero to rounding — a crank-slider's second order λ r ω² is absent."""
    n, w = 256, 150.0
    phi = 2 * math.pi * np.arange(n) / n
    dds = (YOKE.kinematics_table(phi)["du_1"] if source == "kernel"
           else piston_kinematics(YOKE, phi).dds[0])
    spec = order_spectrum(w * w * dds, n, 2 * math.pi)
    amp = np.abs(spec.coef[0])
    r_w2 = YOKE.crank_radius * w * w
    assert spec.orders[1] == pytest.approx(1.0)
    assert amp[1] == pytest.approx(r_w2, rel=1e-13)
    assert np.max(np.delete(amp, 1)) < 1e-13 * r_w2


def test_loads_agree_with_the_closed_forms():
    """At constant ω with a gas force P_g: P_j = −m r ω² cos φ, the slot's force P along the
    axis, K = P cos φ, T = P sin φ, the block's −m_b r ω² toward the axis; the torque P r sin φ
    is the generalized force P u of (19)."""
    phi = np.linspace(0.0, 2 * math.pi, 181)
    w, P_g = 120.0, 4000.0 * np.sin(phi / 2) ** 2
    ld = scotch_yoke_loads(YOKE, phi, w, 0.0, P_g)
    r, m, mb = YOKE.crank_radius, YOKE.yoke_mass, YOKE.block_mass
    P = P_g - m * r * w * w * np.cos(phi)
    scale = 4000.0 + m * r * w * w
    tol = dict(rtol=ROUNDING, atol=ROUNDING * scale)
    np.testing.assert_allclose(ld.P_j[0], -m * r * w * w * np.cos(phi), **tol)
    np.testing.assert_allclose(ld.P[0], P, **tol)
    np.testing.assert_allclose(ld.R_K[0], P * np.cos(phi) - mb * r * w * w, **tol)
    np.testing.assert_allclose(ld.R_T[0], P * np.sin(phi), **tol)
    np.testing.assert_allclose(ld.R[0], np.hypot(P * np.cos(phi) - mb * r * w * w,
                                                 P * np.sin(phi)), **tol)
    np.testing.assert_allclose(ld.torque[0], P * YOKE.kinematics_table(phi)["u_1"],
                               rtol=ROUNDING, atol=ROUNDING * scale * r)
    # no gas: the crankpin's load is the inertia of yoke and block, m r ω² cos φ (cos φ, sin φ)
    bare = scotch_yoke_loads(YOKE, phi, w, 0.0)
    np.testing.assert_allclose(bare.R[0], r * w * w * np.hypot(m * np.cos(phi) ** 2 + mb,
                                                                m * np.cos(phi) * np.sin(phi)),
                               rtol=ROUNDING, atol=ROUNDING * scale)


def test_loads_with_acceleration_balance_the_kinetic_energy():
    """Σ torque = P_g u − J_yoke ε − ½ J′_yoke ω² at any ε: the yoke's inertia forces in the
    torque are the part m r² sin²φ of (18)."""
    phi = np.linspace(0.0, 2 * math.pi, 91)
    w, eps = 80.0 + 10 * np.sin(phi), 300.0 * np.cos(3 * phi)
    P_g = 2500.0 * np.cos(phi / 2) ** 2
    ld = scotch_yoke_loads(YOKE, phi, w, eps, P_g)
    r, m = YOKE.crank_radius, YOKE.yoke_mass
    u = r * np.sin(phi)
    expected = P_g * u - m * u * u * eps - 0.5 * m * r * r * np.sin(2 * phi) * w * w
    np.testing.assert_allclose(ld.engine_torque, expected, atol=1e-12 * 2500.0 * r)


def test_a_run_conserves_energy():
    """The compressor case's run-up: ½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load (no friction pairs)
    at every sample, to the solver's tolerance."""
    from transient.run import integrate

    scene = load_scene(CASE)
    scene = dataclasses.replace(scene, run=Run(revolutions=6.0),
                                output=Output(samples_per_rev=360),
                                solver=dataclasses.replace(scene.solver, rtol=1e-10, atol=1e-10))
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    assert tr["omega"][-1] > 50.0  # (it ran up)
    J, _ = closed_form_J(scene.mechanism, tr["phi"])
    np.testing.assert_allclose(tr["J"], J + scene.inertia.total, rtol=1e-13)
    assert closure(scene, tr) < 1e-8


def test_resolved_scene_reads_back():
    scene = load_scene(CASE)
    assert load_scene("resolved.toml", text=to_toml(scene)).mechanism == scene.mechanism


@pytest.mark.parametrize("key, value, says", [
    ("crank_radius_mm", "0", "must be > 0"),
    ("yoke_mass", "-1", "must be > 0"),
    ("block_mass", "-0.1", "≥ 0"),
    ("strokes", "3", "3"),
])
def test_bad_keys_are_refused(key, value, says):
    text = CASE.read_text(encoding="utf-8")
    lines = [f"{key} = {value}" if line.split(" = ")[0] == key else line
             for line in text.splitlines()]
    with pytest.raises(SceneError) as err:
        load_scene("bad.toml", text="\n".join(lines))
    assert key.removesuffix("_mm") in str(err.value) and says in str(err.value)
