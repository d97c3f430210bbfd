"""Master and articulated rods (Semenov): the kernel against finite differences and against the
plain-numpy geometry (:func:`positions`, complex numbers), and the Semenov identities and numbers.

Semenov's dimensions (the worked example of §4, fig. 19): r = 95, l = 313, r_i = 75,
l_i = 238 mm (r_i + l_i = l). Numbers that are not in the text were computed independently
(exact geometry, FFT) and are checked where available. The comparisons with Semenov's numbers and
formulas are the cases of ``tests/references/semenov.py``, which the Validation page renders.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from references import check_all, semenov

from transient.cli import main
from transient.core.model.articulated import articulated_terms
from transient.mechanisms import articulated as art
from transient.scene import scene_from_dict

R, L, RI, LI, LAM = semenov.R, semenov.L, semenov.RI, semenov.LI, semenov.LAM
radial = semenov.radial


#: ψ ≠ δ, unequal radii and rods, two rows (crankpins 180° apart, row 2 turned by 20°).
GENERAL = radial([72, 150, 220], [67, 155, 215], link_radii=(0.075, 0.06, 0.0),
                 slave_lengths=(0.238, 0.25, 0.313), row_banks=(0.0, math.radians(20.0)),
                 row_cranks=(0.0, math.pi))
ANGLES = np.linspace(0.0, 2.0 * math.pi, 13)[:-1] + 0.1


def kernel(mech, phi):
    n = mech.n_cylinders
    u, du = np.empty(n), np.empty(n)
    J, dJ = articulated_terms(mech.pack(), phi, u, du)
    return J, dJ, u, du


def test_finite_differences_of_transfer_functions_and_dJ():
    """u′_k and dJ/dφ against central differences of the kernel's own u_k and J (h = 1e-5:
    truncation ~1e-11, rounding ~1e-11 relative)."""
    h = 1e-5
    GENERAL.validate()
    for phi in ANGLES:
        J, dJ, u, du = kernel(GENERAL, phi)
        Jp, _, up, _ = kernel(GENERAL, phi + h)
        Jm, _, um, _ = kernel(GENERAL, phi - h)
        assert dJ == pytest.approx((Jp - Jm) / (2 * h), rel=1e-8, abs=1e-9 * J)
        np.testing.assert_allclose(du, (up - um) / (2 * h), rtol=1e-7, atol=1e-9)


def test_transfer_functions_and_inertia_against_numpy_geometry():
    """u_k = −dX_k/dφ and J = Σ m|G′|² + Σ I (rod angle)′² from the independent numpy positions
    (central differences, h = 1e-5), for row 1 (row 2 is the same at its own phase)."""
    h = 1e-5
    mech = replace(GENERAL, row_banks=(0.0,), row_cranks=(0.0,))
    for phi in ANGLES:
        J, _, u, _ = kernel(mech, phi)
        P = art.positions(mech, np.array([phi - h, phi + h]))
        d = lambda key, P=P: (P[key][1] - P[key][0]) / (2 * h)
        axes = np.exp(1j * np.asarray(mech.slave_banks))
        np.testing.assert_allclose(u[0], -d("B").real, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(u[1:], -(d("Bi") / axes).real, rtol=1e-8, atol=1e-10)
        rods = np.unwrap(np.stack([P["master_angle"], *P["slave_angle"].T]), axis=1)
        rate = (rods[:, 1] - rods[:, 0]) / (2 * h)
        m_slide = mech.piston_mass
        J_np = (mech.crank_mass * R**2 + m_slide * abs(d("B")) ** 2
                + mech.rod_mass * abs(d("G")) ** 2 + mech.rod_inertia_cg * rate[0] ** 2
                + np.sum(m_slide * abs(d("Bi")) ** 2 + mech.slave_rod_mass * abs(d("Gi")) ** 2
                         + mech.slave_rod_inertia_cg * rate[1:] ** 2))
        assert J == pytest.approx(J_np, rel=1e-8)


def test_kernel_equals_its_python_twin():
    for phi in ANGLES[:3]:
        n = GENERAL.n_cylinders
        u, du = np.empty(n), np.empty(n)
        J, dJ = articulated_terms.py_func(GENERAL.pack(), phi, u, du)
        Jc, dJc, uc, duc = kernel(GENERAL, phi)
        assert (J, dJ) == pytest.approx((Jc, dJc), rel=1e-13)
        np.testing.assert_allclose(u, uc, rtol=1e-12, atol=1e-15)


def test_master_piston_dead_centre_accelerations_and_stroke():
    """Semenov (25): W(0) = −rω²(1 + λ), W(π) = rω²(1 − λ) at constant ω (W = ω² d²X/dφ²), exactly
    (the series' λ³, λ⁵ terms cancel there); stroke 2r (1), (20); and u′ of the kernel is
    −d²X/dφ² of the master piston."""
    check_all(semenov.master_dead_centres())


def test_slave_stroke_is_2r_at_0_and_180_deg_and_longer_elsewhere():
    """With r_i + l_i = l the slaves at δ = 0° and 180° (ψ = δ) have stroke 2r exactly; at 72° and
    144° (Semenov's five-cylinder) it is longer. The excess: 0.394 mm at 72°, 1.435 mm at
    144° (0.2 % and 0.76 % of 2r)."""
    check_all(semenov.slave_strokes())


def test_slave_dead_centres_are_roots_of_the_velocity():
    """(55)–(57) solved exactly: dX/dα = 0 at both dead centres, the TDC a few degrees off δ_i
    (2.81° after 72°, 3.67° after 144°), and symmetric for δ ↦ 360° − δ."""
    check_all(semenov.slave_dead_centres())


def test_central_articulation_is_the_master_turned_by_delta():
    """Semenov (39), oracle 11: a slave on the crankpin (r_i = 0) with l_i = l moves as the
    master with φ − δ_i; the same u_k to rounding."""
    mech = radial([45], link_radii=(0.0,), slave_lengths=(L,))
    delta = math.radians(45)
    for phi in ANGLES:
        u = kernel(mech, phi)[2]
        assert u[1] == pytest.approx(kernel(mech, phi - delta)[2][0], rel=1e-12, abs=1e-15)


def test_psi_equal_delta_has_no_odd_harmonics_above_the_first():
    """(46)–(54): with ψ_i = δ_i the slave displacement is r cos(φ − δ_i) plus even harmonics: odd
    orders ≥ 3 below 1e-12 of the first, the first exact to 1e-13·r."""
    check_all(semenov.no_third_harmonic())
    for h in art.harmonics(radial([40, 72, 144, 200, 288]), orders=9):
        np.testing.assert_allclose(h.exact[0][1], [R * math.cos(h.bank), R * math.sin(h.bank)],
                                   atol=1e-13 * R)
        assert h.source == "(47), (50)"
        assert h.series[0][3].tolist() == [0.0, 0.0]


def test_psi_unequal_delta_has_a_third_harmonic_beside_semenov():
    """Rickert's case ψ_i ≠ δ_i: the 3rd harmonic appears. At δ = 72°, ψ = 67° the independently
    computed values (not in the text) for x_Bi = S cos δ: exact A₃ = −0.0249 mm, (45) −0.0088 mm;
    here on S itself: exact (a₃, b₃) = (−0.0806, 0.0135) mm, (45) (−0.0286, 0.0021) mm, and (45)
    with the sin⁴β_i term (:func:`third_harmonic`) (−0.0725, 0.0120) mm."""
    check_all(semenov.rickert_third_harmonic())
    h = art.harmonics(radial([72], [67]))[0]
    assert h.source == "(45)"
    np.testing.assert_allclose(h.third_corrected, [-0.07254e-3, 0.01201e-3], atol=1e-8)
    # found by exact geometry: first-order coefficients of (45) within ~0.4 mm, second within ~4–7 %
    assert np.max(np.abs(h.exact[0][1] - h.series[0][1])) < 0.4e-3
    assert abs(math.hypot(*h.series[0][2]) / math.hypot(*h.exact[0][2]) - 1) < 0.07


def test_series_truncation_errors_are_reported_and_small():
    """The truncation error of (47)/(50) over a turn, for Semenov's five-cylinder radial:
    displacement ≤ 0.22 mm, acceleration ≤ 1.4e-3 rω²·…."""
    for h in art.harmonics(radial([72, 144, 216, 288])):
        print(f"δ = {math.degrees(h.bank):g}°: |ΔS| {h.error[0] * 1e3:.4f} mm, |ΔV/ω| "
              f"{h.error[1] * 1e3:.4f} mm, |ΔW/ω²| {h.error[2] * 1e3:.4f} mm, λ_i {h.lam:.5f} "
              f"(61) {h.lam_semenov:.5f}")
        assert 0 < h.error[0] < 0.25e-3 and 0 < h.error[2] < 1.5e-3
        # V and W coefficients are the derivatives' (53)–(54) of the exact S coefficients
        k = np.arange(h.exact.shape[1])
        np.testing.assert_allclose(h.exact[1][:, 0], k * h.exact[0][:, 1], atol=1e-14)
        np.testing.assert_allclose(h.exact[2][:, 0], -k * k * h.exact[0][:, 0], atol=1e-14)


def test_slave_dynamic_parameter():
    """(61) at δ = 0° equals λ (errata: 0.304) and at 180° gives the text's 0.686; the exact
    2nd-harmonic amplitudes are 0.3108 and 0.7304 (the λ² truncation of (61) is 6 % at 180°).
    max|W| at 180° over the master's: exact 1.2935 (computed; the text prints 1.27)."""
    check_all(semenov.slave_dynamic_parameter())


def test_slave_dimensions_6_and_7():
    for delta in np.radians([0.0, 40.0, 90.0, 144.0, 180.0]):
        ri, li = art.slave_dimensions(R, L, delta, slave_length=LI)
        assert art.slave_dimensions(R, L, delta, link_radius=ri) == pytest.approx((ri, li))
        assert ri * math.sqrt(1 - (LAM * math.sin(delta)) ** 2) + li == pytest.approx(L)
    assert sum(art.slave_dimensions(R, L, 0.0, link_radius=RI)) == pytest.approx(L)


# ------------------------------------------------------------------------------------------------
# Scene reading and errors

SCENE = """\
[mechanism]
type = "articulated"
crank_radius_mm = 95
rod_length_mm = 313
bore_mm = 146
piston_mass = 2.18
bank_deg = [72, 144, 216, 288]
link_radius_mm = 75
slave_rod_length_mm = 238

[mechanism.rod]
model = "rigid"
mass = 6.7
cg_from_pin_mm = 235
inertia_cg = 0.06

[mechanism.slave_rod]
mass = 1.34
cg_from_pin_mm = 131

[inertia]
shaft = 0.2

[initial]
omega_rpm = 1000

[run]
revolutions = 2
"""


def test_scene_round_trip_and_defaults():
    import tomllib

    from transient.scene import to_toml

    scene = scene_from_dict(tomllib.loads(SCENE))
    mech = scene.mechanism
    assert mech.n_cylinders == 5 and mech.link_angles == mech.slave_banks
    again = scene_from_dict(tomllib.loads(to_toml(scene)))
    assert again.mechanism == mech
    # the default firing order 1-3-5-2-4, each at its exact outer dead centre
    order = np.argsort(mech.firing_angles) + 1
    assert order.tolist() == [1, 3, 5, 2, 4]


@pytest.mark.parametrize("old,new,key,message", [
    ("slave_rod_length_mm = 238", "slave_rod_length_mm = [238, 238, 50, 238]",
     "mechanism.slave_rod_length_mm", "slave rod 3 (50 mm) is too short for its cylinder at 216°"),
    ("link_radius_mm = 75", "link_radius_mm = 320",
     "mechanism.link_radius_mm", "must be < rod_length = 313, got 320"),
    ("cg_from_pin_mm = 131", "cg_from_pin_mm = 240",
     "mechanism.slave_rod.cg_from_pin_mm",
     "must be ≤ the shortest slave_rod_length = 238, got 240"),
    ("link_radius_mm = 75\n", "",  # r_i from (7): 316 mm for l_i = 10 mm, beyond the rod
     "mechanism.slave_rod_length_mm", ""),
    ("link_radius_mm = 75\nslave_rod_length_mm = 238\n", "",
     "mechanism.link_radius", "is missing; give link_radius and/or slave_rod_length"),
    ("bank_deg = [72, 144, 216, 288]", "bank_deg = [72, 144, 216, 288]\nlink_angle_deg = [72]",
     "mechanism.link_angle_deg", "has 1 entries; must have one per slave cylinder (4)"),
])
def test_bad_geometry_exits_2_with_one_line(tmp_path, capsys, old, new, key, message):
    # (a slave rod's centre of mass on the shortest slave rod, read before the rods' reach)
    text = SCENE.replace(old, new).replace("cg_from_pin_mm = 131", "cg_from_pin_mm = 5")
    if not message:  # r_i omitted is fine (7): make the r_i it gives impossible
        text = text.replace("slave_rod_length_mm = 238", "slave_rod_length_mm = 10")
        message = "is outside the master rod; allowed 0 ≤ r_i < l = 313 mm (link_radius from"
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    print(err)
    assert "\n" not in err and "Traceback" not in err
    assert f"{path}: {key}: " in err and message in err
