"""Swash-plate kinematics and reduced inertia (Antonyuk et al. §2).

Everything is checked against positions: the kernel's analytic derivatives against finite differences
of the 3-D positions and rotation matrices given by ``positions``, and the paper's closed forms (13)
against the derivatives of link 9's and cross 13's rotations.
"""
from __future__ import annotations

import numpy as np
import pytest
from references import antonyuk, check_all
from references.antonyuk import D6, angular_velocity, derivative, paper_13

from transient.core.model import swash_plate as core
from transient.errors import SceneError
from transient.mechanisms import swash_plate as sp

EX = sp.antonyuk_example()
ALPHA = EX.swash_angle
PHI = np.linspace(0.0, 2.0 * np.pi, 73)
EPS = np.finfo(float).eps


# ------------------------------------------------------------------------------------------------
# Paper formulas (1), (4), (7), (13)


def test_13_normal_hinge_is_the_printed_form():
    """Hinge along Oz: (1), (4) and u₉,₁ of (13) hold exactly; the printed u₁₃,₁ is ω₉·e_y/φ̇, the
    rate about the text's Oy hinge (the comparisons); the cross turns about Oz only, at
    −cos α sin α sin φ / D."""
    check_all(antonyuk.transfer_functions())
    g = sp.antonyuk_example(hinge="normal")
    d = 1.0 - np.sin(PHI) ** 2 * np.sin(ALPHA) ** 2
    u13 = -np.cos(ALPHA) * np.sin(ALPHA) * np.sin(PHI) / d
    w13 = angular_velocity("Q13", g, PHI, 1e-2, D6)[:, 0]
    np.testing.assert_allclose(w13[:, 2], u13, rtol=0, atol=1e-10)
    np.testing.assert_allclose(w13[:, :2], 0.0, atol=1e-10)  # the cross turns about its hinge only
    np.testing.assert_allclose(sp.kinematics_table(g, PHI)["u13"], u13, rtol=0, atol=1e-13)
    # (1) tan φ₉,₀ = tan φ₀,₀ cos α with φ₀,₀ = −φ.
    theta = sp.positions(g, PHI)["theta"]
    np.testing.assert_allclose(np.sin(theta) * np.cos(PHI),
                               -np.cos(ALPHA) * np.sin(PHI) * np.cos(theta), atol=1e-15)


def test_13_in_plane_hinge_is_a_quarter_turn_on():
    """Hinge along Oy (the default): tan φ₉,₀ = tan φ₀,₀ / cos α and (13) shifted by φ → φ + π/2."""
    g = sp.antonyuk_example()
    assert g.hinge == "in-plane"
    u9, _ = paper_13(PHI + np.pi / 2, ALPHA)
    u13 = -np.cos(ALPHA) * np.sin(ALPHA) * np.cos(PHI) / (1.0 - np.cos(PHI) ** 2 * np.sin(ALPHA) ** 2)
    w9 = angular_velocity("Q9", g, PHI, 1e-2, D6)[:, 0]
    w13 = angular_velocity("Q13", g, PHI, 1e-2, D6)[:, 0]
    np.testing.assert_allclose(np.linalg.norm(w9, axis=-1), u9, rtol=0, atol=1e-10)
    np.testing.assert_allclose(w13[:, 1], u13, rtol=0, atol=1e-10)
    np.testing.assert_allclose(w13[:, [0, 2]], 0.0, atol=1e-10)
    table = sp.kinematics_table(g, PHI)
    np.testing.assert_allclose(table["u9"], u9, rtol=0, atol=1e-13)
    np.testing.assert_allclose(table["u13"], u13, rtol=0, atol=1e-13)
    theta = sp.positions(g, PHI)["theta"]
    np.testing.assert_allclose(np.sin(theta) * np.cos(ALPHA) * np.cos(PHI),
                               -np.sin(PHI) * np.cos(theta), atol=1e-15)


# ------------------------------------------------------------------------------------------------
# Constraints along a turn


@pytest.mark.parametrize("hinge", ["in-plane", "normal"])
@pytest.mark.parametrize("halves", [1, 2])
def test_constraints_hold_along_a_turn(hinge, halves):
    g = sp.antonyuk_example(hinge=hinge, halves=halves)
    phi = np.linspace(-np.pi, 3.0 * np.pi, 1441)
    pos = sp.positions(g, phi)
    a, c = pos["hinge_axis"], pos["cross_axis"]
    # Hooke joint: the cross's axes stay perpendicular; the link-9 hinge stays in the plate plane.
    assert np.abs(np.sum(a * c, axis=-1)).max() < 8 * EPS
    assert np.abs(np.sum(pos["normal"] * c, axis=-1)).max() < 8 * EPS
    for Q in (pos["Q9"], pos["Q13"]):
        np.testing.assert_allclose(Q @ np.swapaxes(Q, -1, -2), np.broadcast_to(np.eye(3), Q.shape),
                                   atol=8 * EPS)
    # Rods keep their length; pistons stay on their cylinder axes (the same for both halves).
    ell = np.linalg.norm(pos["B"] - pos["D"], axis=-1)
    assert np.abs(ell / g.rod_length - 1.0).max() < 8 * EPS
    psi = 2.0 * np.pi * np.arange(4) / 4
    axis = g.cylinder_radius * np.stack([np.cos(psi), np.sin(psi)], axis=-1)
    np.testing.assert_array_equal(pos["D"][..., 1:], np.broadcast_to(axis, pos["D"][..., 1:].shape))
    # θ is continuous (no branch jumps) and returns to the same pose every turn.
    assert np.abs(np.diff(pos["theta"])).max() < 2.0 * (phi[1] - phi[0])
    np.testing.assert_allclose(sp.positions(g, phi + 2.0 * np.pi)["theta"], pos["theta"] - 2.0 * np.pi,
                               atol=1e-12)


@pytest.mark.parametrize("hinge", ["in-plane", "normal"])
def test_joints_follow_their_pistons(hinge):
    """B_k follows D_k: the rod tilt is small (≤ 1.8°, the paper: up to 2°), periodic and does
    not drift over many turns."""
    check_all(antonyuk.rod_tilt())
    g = sp.antonyuk_example(hinge=hinge)
    t0 = sp.kinematics_table(g, PHI)
    t9 = sp.kinematics_table(g, PHI + 18.0 * np.pi)
    for k in range(1, 5):
        tilt = t0[f"rod_tilt_{k}_deg"]
        np.testing.assert_allclose(t9[f"rod_tilt_{k}_deg"], tilt, atol=1e-9)
        np.testing.assert_allclose(t9[f"x_{k}"], t0[f"x_{k}"], atol=1e-13)


def test_stroke():
    check_all(antonyuk.stroke())  # 2R sin α for a very long rod
    # A short rod at a steep plate with 3 cylinders: the strokes differ from 2R sin α and each other.
    g = sp.antonyuk_example(swash_angle=np.radians(35.0), rod_length=0.2, cylinders=3, bore=0.05)
    s = sp.stroke(g)
    x = sp.positions(g, np.linspace(0.0, 2.0 * np.pi, 400_001))["D"][:, 0, :, 0]
    np.testing.assert_allclose(s, x.max(axis=0) - x.min(axis=0), rtol=0, atol=1e-10)
    assert np.abs(s - 2.0 * g.joint_radius * np.sin(g.swash_angle)).max() > 5e-6


# ------------------------------------------------------------------------------------------------
# Kernel: transfer functions and reduced inertia

CASES = {
    "two-mass, isotropic, in-plane": {},
    "rigid, polar/diametral, normal": dict(rod_model="rigid", rod_inertia_cg=0.012,
                                           rod_cg_from_pin=0.1, link_polar_inertia=0.5,
                                           link_diametral_inertia=0.2, hinge="normal"),
    "two halves, rigid, in-plane": dict(halves=2, rod_model="rigid", rod_inertia_cg=0.008,
                                        link_polar_inertia=0.4, link_diametral_inertia=0.25),
    "two halves, two-mass, normal, 5 cyl": dict(halves=2, cylinders=5, rod_cg_from_pin=0.2,
                                                hinge="normal", swash_angle=np.radians(30.0)),
}


def kernel(g, phi):
    """J, dJ (n,) and u, du (n, z) from the kernel."""
    mp = g.pack()
    u, du = np.empty((phi.size, g.cylinders)), np.empty((phi.size, g.cylinders))
    JdJ = np.array([core.swash_terms(mp, p, u[j], du[j]) for j, p in enumerate(phi)])
    return JdJ[:, 0], JdJ[:, 1], u, du


@pytest.mark.parametrize("case", CASES)
def test_transfer_functions_and_dJ_against_finite_differences(case):
    g = sp.antonyuk_example(**CASES[case])
    J, dJ, u, du = kernel(g, PHI)
    # u = d x_D/dφ summed over the pistons of a cylinder (the mirror piston moves as far to its plate).
    u_fd = g.halves * derivative(lambda p: sp.positions(g, p)["D"][:, 0, :, 0], PHI, 1e-3)
    du_fd = derivative(lambda p: kernel(g, p)[2], PHI, 1e-3)
    dJ_fd = derivative(lambda p: kernel(g, p)[0], PHI, 1e-3)
    for fd, exact in ((u_fd, u), (du_fd, du), (dJ_fd, dJ)):
        assert np.abs(fd - exact).max() <= 1e-7 * np.abs(exact).max()


@pytest.mark.parametrize("case", CASES)
def test_J_is_twice_the_kinetic_energy_of_all_bodies(case):
    """J(φ) = 2T/φ̇² with T summed directly from finite-difference velocities of every body."""
    g = sp.antonyuk_example(**CASES[case])
    h = 1e-3
    pos = sp.positions(g, PHI)
    v = {key: derivative(lambda p, key=key: sp.positions(g, p)[key], PHI, h) for key in ("B", "D", "G")}
    e_dot = (v["B"] - v["D"]) / g.rod_length
    sq = lambda x: np.sum(x * x, axis=-1)
    ell, c, m = g.rod_length, g.rod_cg_from_pin, g.rod_mass
    if g.rod_model == "two-mass":
        rods = m * (ell - c) / ell * sq(v["D"]) + m * c / ell * sq(v["B"])
    else:
        rods = m * sq(v["G"]) + g.rod_inertia_cg * sq(e_dot)
    w9 = angular_velocity("Q9", g, PHI, h)
    w9n = np.sum(w9 * pos["normal"], axis=-1)
    link = g.link_polar_inertia * w9n**2 + g.link_diametral_inertia * (sq(w9) - w9n**2)
    cross = g.cross_inertia * sq(angular_velocity("Q13", g, PHI, h))
    twice_T = (g.piston_mass * sq(v["D"]) + rods).sum(axis=(1, 2)) + (link + cross).sum(axis=1)
    J, _, _, _ = kernel(g, PHI)
    np.testing.assert_allclose(J, twice_T, rtol=1e-7)
    # The table reports the same J.
    np.testing.assert_allclose(sp.kinematics_table(g, PHI)["J"], J, rtol=1e-15)


def test_two_mass_rod_is_the_rigid_rod_with_its_inertia():
    m, c, ell = EX.rod_mass, EX.rod_cg_from_pin, EX.rod_length
    rigid = sp.antonyuk_example(rod_model="rigid", rod_inertia_cg=m * c * (ell - c))
    np.testing.assert_allclose(kernel(rigid, PHI)[0], kernel(EX, PHI)[0], rtol=1e-15)


def test_second_half_doubles_everything():
    one, two = kernel(EX, PHI), kernel(sp.antonyuk_example(halves=2), PHI)
    for a, b in zip(one, two):
        np.testing.assert_allclose(b, 2.0 * a, rtol=1e-15, atol=0)


def test_kernel_equals_its_python_twin():
    for case in CASES.values():
        mp = sp.antonyuk_example(**case).pack()
        z = int(mp[core.N_CYL])
        for p in (0.0, 0.7, 2.9, -4.1, 40.0):
            u1, du1, u2, du2 = np.empty(z), np.empty(z), np.empty(z), np.empty(z)
            jit = core.swash_terms(mp, p, u1, du1)
            py = core.swash_terms.py_func(mp, p, u2, du2)
            np.testing.assert_allclose(jit, py, rtol=1e-14)
            np.testing.assert_allclose(u1, u2, rtol=1e-14, atol=1e-17)
            np.testing.assert_allclose(du1, du2, rtol=1e-14, atol=1e-17)


@pytest.mark.parametrize("halves", [1, 2])
def test_the_table_u_is_the_derivative_of_its_x(halves):
    """One vocabulary: ``u_k`` and ``du_k`` of the table are those of the piston ``x_k`` is, for
    one piston per cylinder and for two (whose generalized force the kernel sums)."""
    g = sp.antonyuk_example(halves=halves)
    table = sp.kinematics_table(g, PHI)
    for k in range(1, g.cylinders + 1):
        x = lambda p, k=k: sp.kinematics_table(g, p)[f"x_{k}"]
        u = lambda p, k=k: sp.kinematics_table(g, p)[f"u_{k}"]
        np.testing.assert_allclose(table[f"u_{k}"], derivative(x, PHI, 1e-2, D6), atol=1e-10)
        np.testing.assert_allclose(table[f"du_{k}"], derivative(u, PHI, 1e-2, D6), atol=1e-9)


def test_pack_and_properties():
    mp = EX.pack()
    assert mp.dtype == np.float64 and mp.size == core.CYL0 + core.CYL_STRIDE * EX.cylinders
    assert mp[core.HINGE_PHASE] == pytest.approx(np.pi / 2)
    assert EX.n_cylinders == 4
    assert EX.piston_area == pytest.approx(np.pi * 0.1**2 / 4)
    table = sp.kinematics_table(EX, PHI)
    assert set(table) == {"phi_deg", "u9", "u13", "J", "dJ_dphi"} | {
        f"{name}_{k}" for k in range(1, 5) for name in ("x", "u", "du")} | {
        f"rod_tilt_{k}_deg" for k in range(1, 5)}


# ------------------------------------------------------------------------------------------------
# Validation

BAD = [
    (dict(swash_angle=0.0), "mechanism.swash_deg"),
    (dict(swash_angle=-0.1), "mechanism.swash_deg"),
    (dict(swash_angle=np.radians(45.0)), "mechanism.swash_deg"),
    (dict(joint_radius=0.0), "mechanism.joint_radius"),
    (dict(rod_length=0.0), "mechanism.rod_length"),
    (dict(rod_length=0.005), "mechanism.rod_length"),  # 5 mm < the 9.4 mm lateral offset
    (dict(cylinder_radius=0.45), "mechanism.cylinder_radius"),  # > R cos α + ℓ
    (dict(cylinder_radius=-0.13), "mechanism.cylinder_radius"),
    (dict(cylinders=0), "mechanism.cylinders"),
    (dict(cylinders=-3), "mechanism.cylinders"),
    (dict(cylinders=2.5), "mechanism.cylinders"),
    (dict(halves=3), "mechanism.halves"),
    (dict(hinge="diagonal"), "mechanism.hinge"),
    (dict(bore=0.0), "mechanism.bore"),
    (dict(bore=0.2), "mechanism.bore"),  # neighbouring cylinders would overlap
    (dict(rod_model="elastic"), "mechanism.rod.model"),
    (dict(rod_cg_from_pin=0.31), "mechanism.rod.cg_from_pin"),
    (dict(piston_mass=-6.0), "mechanism.piston_mass"),
    (dict(rod_mass=-1.0), "mechanism.rod.mass"),
    (dict(rod_model="rigid", rod_inertia_cg=-0.01), "mechanism.rod.inertia_cg"),
    (dict(link_polar_inertia=-0.3), "mechanism.link_polar_inertia"),
    (dict(link_diametral_inertia=-0.3), "mechanism.link_diametral_inertia"),
    (dict(cross_inertia=-0.3), "mechanism.cross_inertia"),
]


@pytest.mark.parametrize("change, key", BAD, ids=[key + ":" + str(c) for c, key in BAD])
def test_validate_rejects(change, key):
    g = sp.antonyuk_example(**change)
    with pytest.raises(SceneError) as info:
        g.validate()
    assert info.value.key == key
    assert "\n" not in info.value.message
    with pytest.raises(SceneError):
        g.pack()


def test_validate_accepts_the_example_and_reports_user_units():
    EX.validate()
    with pytest.raises(SceneError, match="50°"):
        sp.antonyuk_example(swash_angle=np.radians(50.0)).validate()
    with pytest.raises(SceneError, match="mm"):
        sp.antonyuk_example(rod_length=0.005).validate()


def test_cylinder_radius_is_bounded_where_the_pistons_turn_at_their_dead_centres_only():
    """Near a rod's full reach it toggles and the piston turns back between its dead centres:
    the A/C compressor's r₁ = 102.7 mm (inside the reach limit R cos α + ℓ = 103.09 mm) gave
    cylinder 1 a volume below its clearance and the compressor cycle a non-finite table. The
    reader's bound stops short of that; inside it, sampled 20 times finer than the bound's own
    search, every piston turns twice a turn and cylinder 1's volume never falls below V(0);
    beyond it a piston turns back."""
    import dataclasses
    from pathlib import Path

    from transient.scene import load_scene

    case = Path(__file__).resolve().parents[2] / "cases" / "ac_compressor_7cyl.toml"
    mech = load_scene(case).mechanism
    low, high = sp.dead_centre_limits(mech.swash_angle, mech.joint_radius, mech.rod_length,
                                      mech.cylinders, mech.hinge)
    reach = mech.joint_radius * np.cos(mech.swash_angle) + mech.rod_length
    assert low == 0.0 and 0.09 < high < 0.1027 < reach
    phi = np.linspace(0.0, 2.0 * np.pi, 20 * sp.TRAVEL_SAMPLES)

    def turns(r1):
        geom = dataclasses.replace(mech, cylinder_radius=r1)
        return sp.travel_turns(sp._points(geom._pack(), phi)[2][..., 0]), geom

    # (the bound is where the search's grid first sees a piston turn back; the finer grid
    # sees it within about 1e-7 of r₁ of there, a dip of 1e-9 of the stroke)
    inside, geom = turns(high * (1.0 - 1e-6))
    assert np.all(inside == 2)
    volume = geom.volume_function(1e-6)(phi)
    assert volume.min() >= 1e-6 * (1.0 - 1e-9)
    beyond, _ = turns(high + 1e-3 * (reach - high))
    assert np.any(beyond > 2)
    text = case.read_text(encoding="utf-8").replace("cylinder_radius_mm = ",
                                                    "cylinder_radius_mm = 102.7  # ", 1)
    with pytest.raises(SceneError) as refused:
        load_scene("c.toml", text=text)
    assert refused.value.key == "mechanism.cylinder_radius_mm"
    assert refused.value.message.startswith("must be < the largest r₁ whose pistons turn at "
                                            "their dead centres only")
