"""V engines with two cylinders on a throw (:mod:`transient.mechanisms.throws`,
:class:`~transient.mechanisms.crank_slider.CrankSlider`) and their main journals and running
torques (:mod:`transient.analysis.loads.crank_slider`), against models written here:

* **J(φ)** of a cross-plane V8: the sum over the cylinders of one crank-slider's own J (the numpy
  twin of a single cylinder without crank mass, :class:`~transient.mechanisms.twins.
  CrankSliderNumpy`) at each cylinder's local angle φ + θ_t − δ_c, taken from the crank as
  published (throws, banks), plus m_k r² once per throw; J′ against a finite difference of the
  kernel's J; a 90° V-twin's crank mass counted once; a fork-and-blade V-twin against the
  articulated mechanism with central articulation (``link_radius = 0``), the other model of the
  same engine.
* **Firing** from the throws: the cross-plane V8's order every 90°, the flat-plane's alternating
  banks, a 90° V6 at 90°/150° and with pins split by 30° at 120°, V-twins at 270°/450° and
  315°/405°.
* **Main journals** against Newton–Euler forces of each cylinder (:func:`transient.reference.
  crank_slider_joint_forces` of one cylinder without crank mass, at the local angles above),
  turned into the block's frame by each cylinder's bank, the crank masses' and counterweights'
  d'Alembert forces added by hand, put along the shaft where the rods run and shared between
  the journals by the statics of a span on two supports; the shaft's force and moment balance.
  **Running torques** by the sections' rule written here.
* Refusals of crank declarations that cannot be meant, each naming the key and what is allowed;
  the resolved scene read back to an equal mechanism; the old form of a V engine (banks without
  throws) refused with the throws that keep its meaning, which read to the same J.

Bounds: the kernel and the twin, the loads and Newton–Euler are exact formulas evaluated two
ways, so round-off only (a few dozen operations, an 8×8 solve per sample): 1e-12 of the largest
value. Finite differences: 4th-order central, h = 1e-5 rad: truncation ~h⁴ J⁽⁵⁾/30 ≈ 1e-21,
round-off ~1.5 ε |J|/h ≈ 3e-11 |J|: bound 1e-7 of max |J′|.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scene_texts import SMALL, check_text

from transient.analysis.loads import crank_slider as L
from transient.core.model import crank_slider as core
from transient.mechanisms.crank_slider import CrankSlider
from transient.mechanisms.twins import CrankSliderNumpy
from transient.reference import crank_slider_joint_forces
from transient.scene import load_scene

RTOL = 1e-12
FD_RTOL = 1e-7
H = 1e-5

#: The V8 of ``cases/v8_cross_plane.toml`` (the Chevrolet 305): its crank as published.
V8_BANKS_DEG = (45.0, -45.0)
V8_THROWS_DEG = (0.0, 90.0, 270.0, 180.0)
V8_ORDER = (1, 8, 4, 3, 6, 5, 7, 2)
R, ROD, BORE = 0.044196, 0.14478, 0.094894
M_PISTON, M_CRANK, M_ROD, CG = 0.74, 1.20, 0.60, 0.1013
ROD_SPACING, JOURNAL_SPACING = 0.0239, 0.11176


def mechanism_text(cylinders: int, lines: str) -> str:
    """SMALL with the V8's cylinder and rod and the crank ``lines``."""
    head, tail = SMALL.split("[mechanism]", 1)
    tail = tail.split("[inertia]", 1)[1]
    return (f"{head}[mechanism]\ntype = \"crank-slider\"\ncrank_radius = {R}\n"
            f"rod_length = {ROD}\nbore = {BORE}\npiston_mass = {M_PISTON}\n"
            f"crank_mass = {M_CRANK}\ncylinders = {cylinders}\n{lines}\n\n"
            f"[mechanism.rod]\nmodel = \"two-mass\"\nmass = {M_ROD}\ncg_from_pin = {CG}\n\n"
            f"[inertia]{tail}")


def mech_of(cylinders: int, lines: str) -> CrankSlider:
    return load_scene("v.toml", text=mechanism_text(cylinders, lines)).mechanism


V8_LINES = f"""bank_deg = {list(V8_BANKS_DEG)}
throws_deg = {list(V8_THROWS_DEG)}
rod_arrangement = "side-by-side"
rod_spacing = {ROD_SPACING}
journal_spacing = {JOURNAL_SPACING}
firing_order = {list(V8_ORDER)}"""

V6_SPLIT_LINES = """bank_deg = [45, -45]
throws_deg = [0, 240, 120]
rod_arrangement = "side-by-side"
pin_split_deg = 30
rod_spacing_mm = 22
journal_spacing_mm = 100
firing_order = [1, 6, 5, 4, 3, 2]"""

TWIN_FORK_LINES = """bank_deg = [0, 90]
throws_deg = [0]
rod_arrangement = "fork-and-blade\""""

#: A narrow V with a throw per cylinder (as a VR6 has; the old reading of a V engine), its pins
#: set so that 1-5-3-6-2-4 fires every 120°.
VR6_LINES = """bank_deg = [7.5, -7.5]
throws_deg = [0, 225, 120, 105, 240, 345]
firing_order = [1, 5, 3, 6, 2, 4]"""


def declared(banks_deg, throws_deg, per_throw, split_deg=0.0):
    """Each cylinder's bank δ_c and crankpin angle θ_c [rad] from the crank as declared:
    cylinders 2t − 1 and 2t on throw t (one cylinder per throw: cylinder t), the even one's pin
    ahead by the split."""
    n = per_throw * len(throws_deg)
    banks = np.radians([banks_deg[c % len(banks_deg)] for c in range(n)])
    halves = (-split_deg / 2.0, split_deg / 2.0) if per_throw == 2 else (0.0,)
    pins = np.radians([t + h for t in throws_deg for h in halves])
    return banks, pins


def one_cylinder(mech: CrankSlider, crank_mass: float = 0.0) -> CrankSlider:
    """A single cylinder of ``mech``'s geometry and masses, its crank at the axis at φ = 0."""
    return replace(mech, crank_mass=crank_mass, firing_angles=(0.0,), bank_angles=(0.0,),
                   rod_arrangement="single", rod_spacing=0.0, journal_spacing=0.0)


# ------------------------------------------------------------------------------------------------
# Reduced inertia


def test_v8_inertia_is_the_sum_of_its_crank_sliders_and_its_throws():
    mech = mech_of(8, V8_LINES)
    banks, pins = declared(V8_BANKS_DEG, V8_THROWS_DEG, 2)
    single = CrankSliderNumpy(one_cylinder(mech))
    phi = np.linspace(0.0, 4.0 * math.pi, 181) + 0.0137
    own = np.array([sum(single.terms(p + pins[c] - banks[c])[0] for c in range(8))
                    for p in phi]) + 4 * M_CRANK * R**2
    mp = mech.pack()
    u, du = np.empty(8), np.empty(8)
    kernel = np.array([core.crank_slider_terms(mp, p, u, du)[0] for p in phi])
    err = np.max(np.abs(kernel - own)) / np.max(own)
    print(f"V8: |J_kernel − Σ J_cylinder − 4 m_k r²| / max J = {err:.1e}")
    assert err <= RTOL
    # the crank mass once per throw: 8 m_k r² would be 4 m_k r² more
    assert np.min(np.abs(kernel - (own + 4 * M_CRANK * R**2))) > 0.9 * 4 * M_CRANK * R**2
    assert mech.link_inertias()[1] == pytest.approx(4 * M_CRANK * R**2, rel=1e-15)
    np.testing.assert_allclose(mech.kinematics_table(phi)["J"], kernel, rtol=1e-15, atol=0)


def test_v8_inertia_derivative_is_the_finite_difference():
    mech = mech_of(8, V8_LINES)
    mp = mech.pack()
    u, du = np.empty(8), np.empty(8)
    phi = np.linspace(0.0, 4.0 * math.pi, 97) + 0.021

    def J(p):
        return core.crank_slider_terms(mp, p, u, du)[0]

    dJ = np.array([core.crank_slider_terms(mp, p, u, du)[1] for p in phi])
    fd = np.array([(J(p - 2 * H) - 8 * J(p - H) + 8 * J(p + H) - J(p + 2 * H)) / (12 * H)
                   for p in phi])
    err = np.max(np.abs(fd - dJ)) / np.max(np.abs(dJ))
    print(f"V8: |J′ − FD| / max |J′| = {err:.1e}")
    assert err <= FD_RTOL


def test_a_v_twin_counts_its_crank_mass_once():
    """A 90° V-twin on one throw: J less the same engine without crank mass is m_k r², not
    2 m_k r², in the kernel, the numpy twin and the crank link's inertia."""
    for lines in (TWIN_FORK_LINES, TWIN_FORK_LINES.replace(
            '"fork-and-blade"', '"side-by-side"\nrod_spacing_mm = 24\njournal_spacing_mm = 90')):
        mech = mech_of(2, lines)
        bare = replace(mech, crank_mass=0.0)
        phi = np.linspace(0.0, 4.0 * math.pi, 73)
        for m in (mech, bare):
            assert m.n_throws == 1
        diff = mech.kinematics_table(phi)["J"] - bare.kinematics_table(phi)["J"]
        np.testing.assert_allclose(diff, M_CRANK * R**2, rtol=1e-12)
        twin = [CrankSliderNumpy(m).terms(p)[0] for p in phi for m in (mech, bare)]
        np.testing.assert_allclose(np.subtract(twin[::2], twin[1::2]), M_CRANK * R**2,
                                   rtol=1e-12)
        assert mech.link_inertias()[1] == pytest.approx(M_CRANK * R**2, rel=1e-15)


def test_fork_and_blade_twin_is_the_centrally_articulated_twin():
    """The same 90° V-twin as a master rod with its slave on the crankpin (Semenov's central
    articulation, ``type = "articulated"``, ``link_radius = 0``): J(φ) and J′(φ) agree."""
    mech = mech_of(2, TWIN_FORK_LINES)
    art = load_scene("a.toml", text=mechanism_text(2, "").replace(
        'type = "crank-slider"', 'type = "articulated"').replace(
        "cylinders = 2\n", "bank_deg = [90]\nlink_radius = 0\n"
        f"slave_rod_length = {ROD}\nstrokes = 4\n").replace(
        "[inertia]", f"[mechanism.slave_rod]\nmodel = \"two-mass\"\nmass = {M_ROD}\n"
                     f"cg_from_pin = {CG}\n\n[inertia]")).mechanism
    phi = np.linspace(0.0, 4.0 * math.pi, 145) + 0.003
    a, b = mech.kinematics_table(phi), art.kinematics_table(phi)
    np.testing.assert_allclose(a["J"], b["J"], rtol=1e-12)
    np.testing.assert_allclose(a["dJ_dphi"], b["dJ_dphi"], rtol=0,
                               atol=1e-12 * np.max(np.abs(b["dJ_dphi"])))


# ------------------------------------------------------------------------------------------------
# Firing from the throws


def intervals(mech, order):
    f = np.degrees([mech.firing_angles[c - 1] for c in order])
    return np.round(np.diff(np.append(f, f[0] + 720.0)), 9)


def test_firing_follows_the_throws():
    v8 = mech_of(8, V8_LINES)
    np.testing.assert_array_equal(intervals(v8, V8_ORDER), [90.0] * 8)
    banks, pins = declared(V8_BANKS_DEG, V8_THROWS_DEG, 2)
    # each cylinder fires at one of its top dead centres, φ = δ − θ (mod 360°)
    tdc = np.degrees(np.mod(banks - pins, 2 * math.pi))
    np.testing.assert_allclose(np.mod(np.degrees(v8.firing_angles) - tdc + 180, 360) - 180, 0,
                               atol=1e-9)
    flat = mech_of(8, V8_LINES.replace("[0.0, 90.0, 270.0, 180.0]", "[0, 180, 180, 0]")
                   .replace(str(list(V8_ORDER)), "[1, 4, 3, 2, 7, 6, 5, 8]"))
    np.testing.assert_array_equal(intervals(flat, (1, 4, 3, 2, 7, 6, 5, 8)), [90.0] * 8)
    v6 = mech_of(6, V6_SPLIT_LINES)
    np.testing.assert_array_equal(intervals(v6, (1, 6, 5, 4, 3, 2)), [120.0] * 6)
    odd = mech_of(6, V6_SPLIT_LINES.replace("pin_split_deg = 30", "pin_split_deg = 0"))
    np.testing.assert_array_equal(intervals(odd, (1, 6, 5, 4, 3, 2)), [150.0, 90.0] * 3)
    twin = mech_of(2, TWIN_FORK_LINES)
    np.testing.assert_array_equal(intervals(twin, (1, 2)), [450.0, 270.0])
    harley = mech_of(2, TWIN_FORK_LINES.replace("[0, 90]", "[0, 45]"))
    np.testing.assert_array_equal(intervals(harley, (1, 2)), [405.0, 315.0])
    # explicit firing angles at the crank's top dead centres are taken as given
    other = mech_of(2, TWIN_FORK_LINES + "\nfiring_deg = [0, 90]")
    np.testing.assert_allclose(np.degrees(other.firing_angles), [0.0, 90.0])


def with_mechanism(table: str) -> str:
    """SMALL with its [mechanism] and [mechanism.rod] tables replaced by ``table``."""
    head, tail = SMALL.split("[mechanism]", 1)
    return f"{head}{table}\n\n[inertia]{tail.split('[inertia]', 1)[1]}"


def test_resolved_crank_reads_back_equal():
    for n, lines in ((8, V8_LINES), (6, V6_SPLIT_LINES), (2, TWIN_FORK_LINES), (6, VR6_LINES)):
        mech = mech_of(n, lines)
        text = "\n".join(mech.toml_lines())
        assert "throws = " in text
        assert load_scene("r.toml", text=with_mechanism(text)).mechanism == mech, lines


# ------------------------------------------------------------------------------------------------
# Main journals and running torques


def motion(t):
    """φ, ω, ε: 400 rad/s ± 25 % at two frequencies, so that ε (to ~1e5 rad/s²) matters."""
    phi = 0.3 + 400.0 * t + 0.25 * np.sin(400.0 * t) + 0.05 * np.sin(1100.0 * t + 1.0)
    omega = 400.0 + 100.0 * np.cos(400.0 * t) + 55.0 * np.cos(1100.0 * t + 1.0)
    eps = -4.0e4 * np.sin(400.0 * t) - 6.05e4 * np.sin(1100.0 * t + 1.0)
    return phi, omega, eps


T = np.linspace(0.0, 0.04, 601)

#: text, cylinders, banks [deg], throws [deg], cylinders per throw, split [deg], journal
#: spacing and rod spacing [m] (their ratio is what counts; 1 and 0 where the rods are centred)
ENGINES = {
    "v8-side-by-side": (V8_LINES, 8, V8_BANKS_DEG, V8_THROWS_DEG, 2, 0.0, JOURNAL_SPACING,
                        ROD_SPACING),
    "v6-split-pins": (V6_SPLIT_LINES, 6, (45.0, -45.0), (0.0, 240.0, 120.0), 2, 30.0, 0.1, 0.022),
    "twin-fork-and-blade": (TWIN_FORK_LINES, 2, (0.0, 90.0), (0.0,), 2, 0.0, 1.0, 0.0),
    "vr6-a-throw-each": (VR6_LINES, 6, (7.5, -7.5), (0, 225, 120, 105, 240, 345), 1, 0.0, 1.0,
                         0.0),
}


def by_hand(name, cw_mass, cw_angle):
    """What the shaft carries, written out: each cylinder's rod force on its crankpin by
    Newton–Euler in the block frame (x perpendicular to the reference axis, toward where the
    crankpins pass at the top, y along it toward the heads), each throw's unbalanced mass and
    counterweight by their d'Alembert force −m a (a share at each pin), each at its place z
    along the shaft from the nose; the torque each passes to the shaft. Returns the mechanism,
    the motion and gas force, the journals' loads (n_journals, 2, n) by the lever rule of a span
    on two supports, the (z, force) and (z, torque) of every load, and the span."""
    text, n, banks_deg, throws_deg, per, split, span, spacing = ENGINES[name]
    mech = mech_of(n, text)
    banks, pins = declared(banks_deg, throws_deg, per, split)
    phi, omega, eps = motion(T)
    gas = 2.0e4 * np.exp(np.cos((phi[None, :] - np.asarray(mech.firing_angles)[:, None]) / 2.0)
                         * 3.0 - 3.0) - 3.0e3
    one = one_cylinder(mech)
    forces, torques = [], []
    for c in range(n):
        z_mid = (c // per + 0.5) * span
        z_rod = z_mid + (0.5 if c % 2 else -0.5) * spacing if per == 2 else z_mid
        ne = crank_slider_joint_forces(one, phi + pins[c] - banks[c], omega, eps, gas[c:c + 1])
        x_hat = np.array([[math.cos(banks[c])], [-math.sin(banks[c])]])
        y_hat = np.array([[math.sin(banks[c])], [math.cos(banks[c])]])
        forces.append((z_rod, ne.crankpin[0, 0] * x_hat + ne.crankpin[1, 0] * y_hat))
        torques.append((z_rod, ne.throw_torque[0]))
        for mass, ahead in ((M_CRANK / per, 0.0), (cw_mass / per, cw_angle)):
            psi = phi + pins[c] + ahead
            c_hat, t_hat = np.array([np.sin(psi), np.cos(psi)]), np.array([np.cos(psi),
                                                                            -np.sin(psi)])
            forces.append((z_mid, -mass * (-omega**2 * R * c_hat + eps * R * t_hat)))
        torques.append((z_mid, -M_CRANK / per * R * R * eps))  # the crank's own (no cw here)
    journals = np.zeros((n // per + 1, 2, T.size))
    for z, f in forces:
        j = int(z // span)
        journals[j] += f * ((j + 1) * span - z) / span
        journals[j + 1] += f * (z - j * span) / span
    return mech, (phi, omega, eps, gas), journals, forces, torques, span


@pytest.mark.parametrize("name", list(ENGINES))
def test_main_journals_against_newton_euler_and_the_lever_rule(name):
    cw_mass, cw_angle = 0.9, math.radians(200.0)
    mech, (phi, omega, eps, gas), journals, forces, _, span = by_hand(name, cw_mass, cw_angle)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas)
    mj = L.main_journal_loads(mech, ld, omega, eps, cw_mass, cw_angle)
    assert mj.x.shape == (mech.n_throws + 1, T.size)
    scale = np.max(np.abs(journals))
    err = max(np.max(np.abs(mj.side - journals[:, 0])), np.max(np.abs(mj.down + journals[:, 1])))
    print(f"{name}: |journal − Newton–Euler by the lever rule| / max = {err / scale:.1e}")
    assert err <= RTOL * scale
    # the shaft's balance: the journals carry every force, and its moment about the nose
    total = sum(f for _, f in forces)
    moment = sum(z * f for z, f in forces)
    z_j = np.arange(mj.x.shape[0])[:, None] * span
    assert np.max(np.abs(mj.side.sum(axis=0) - total[0])) <= RTOL * scale * len(z_j)
    assert np.max(np.abs((z_j * mj.down).sum(axis=0) + moment[1])) <= (
        RTOL * scale * span * len(z_j) ** 2)
    # the frame of crank 1 is the block frame turned by crank 1's angle
    assert np.max(np.abs(mj.magnitude - np.hypot(mj.side, mj.down))) <= RTOL * scale
    if ENGINES[name][7]:  # side by side: the rods' offset moves load from journal to journal
        centred = L.main_journal_loads(replace(mech, rod_spacing=1e-12), ld, omega, eps,
                                       cw_mass, cw_angle)
        assert np.max(np.abs(centred.magnitude - mj.magnitude)) > 0.01 * scale


@pytest.mark.parametrize("name", list(ENGINES))
def test_running_torques_by_the_sections(name):
    """The torque through a section of the shaft is that of every load ahead of it, a load in
    the section counted half: at journal j the throws ahead of it, in a throw's middle also
    its side-by-side rod ahead (whole), a centred rod and the crank's own term (half)."""
    mech, (phi, omega, eps, gas), _, _, torques, span = by_hand(name, 0.0, 0.0)
    ld = L.crank_slider_loads(mech, phi, omega, eps, gas)
    journals, pins = L.running_torques(mech, ld)

    def through(z):
        return sum(np.where(abs(zl - z) <= 1e-12 * span, 0.5, float(zl < z)) * m
                   for zl, m in torques)

    scale = np.max(np.abs(journals))
    for j in range(mech.n_throws + 1):
        assert np.max(np.abs(journals[j] - through(j * span))) <= RTOL * scale, j
    for t in range(mech.n_throws):
        assert np.max(np.abs(pins[t] - through((t + 0.5) * span))) <= RTOL * scale, t
    np.testing.assert_allclose(journals[-1], ld.throw_torque.sum(axis=0), rtol=0,
                               atol=RTOL * scale)


# ------------------------------------------------------------------------------------------------
# Refusals and the old form


FORK = 'rod_arrangement = "fork-and-blade"'
SIDE = 'rod_arrangement = "side-by-side"'
V4 = "bank_deg = [45, -45]\nthrows_deg = [0, 180]\nfiring_order = [1, 3, 2, 4]\n"

REFUSED = [  # cylinders, crank lines, the key as written, what the message says
    (8, V8_LINES.replace("[0.0, 90.0, 270.0, 180.0]", "[0, 90, 270, 180, 0]"),
     "mechanism.throws_deg", "has 5 entries; give one per throw: 8 (a throw per cylinder) or 4 "
                             "(two cylinders per throw)"),
    (5, "bank_deg = [0, 90, 0, 90, 0]\nthrows_deg = [0, 90]\n" + SIDE, "mechanism.throws_deg",
     "has 2 entries; give one per throw: 5 (a throw per cylinder)"),
    (4, "throws_deg = [0, 180, 180, 0]\n" + SIDE, "mechanism.rod_arrangement",
     "applies to two cylinders on one throw; `throws` has 4 entries"),
    (4, "throws_deg = [0, 180]\n" + FORK, "mechanism.rod_arrangement",
     "two cylinders on one throw must sit on two banks"),
    (4, "firing_order = [1, 3, 4, 2]\n" + SIDE, "mechanism.rod_arrangement", "needs `throws`"),
    (4, "firing_order = [1, 3, 4, 2]\npin_split_deg = 30", "mechanism.pin_split_deg",
     "does not apply: it applies to two cylinders on one throw"),
    (4, V4, "mechanism.rod_arrangement",
     'is missing: `throws` has 2 entries, so cylinders 2t − 1 and 2t share throw t'),
    (4, V4 + FORK + "\npin_split_deg = 30", "mechanism.pin_split_deg",
     "must be 0 for fork-and-blade rods"),
    (4, V4 + FORK + "\nrod_spacing_mm = 20", "mechanism.rod_spacing_mm",
     "does not apply: fork-and-blade rods are both in the throw's middle plane"),
    (4, V4 + SIDE + "\nrod_spacing_mm = 20", "mechanism.journal_spacing", "is missing"),
    (4, V4 + SIDE + "\nrod_spacing_mm = 120\njournal_spacing_mm = 110", "mechanism.rod_spacing_mm",
     "must be < journal_spacing = 110, got 120"),
    (8, V8_LINES.replace(str(list(V8_ORDER)), "[1, 2, 3, 4, 5, 6, 7, 8]"),
     "mechanism.firing_order", "does not fit the crank: cylinder 4 cannot fire after cylinder 3"),
    (2, TWIN_FORK_LINES + "\nfiring_deg = [0, 100]", "mechanism.firing_deg",
     "cylinder 2 fires at 100°, which is not a top dead centre of it with these throws and "
     "banks: allowed 90° or 450°"),
    (8, V8_LINES.replace("[45.0, -45.0]", "[45, -45, 45]"), "mechanism.bank_deg",
     "has 3 entries; must have one per cylinder (8) (or two for an even count"),
]


@pytest.mark.parametrize("n, lines, key, message", REFUSED,
                         ids=[f"{r[2]}-{i}" for i, r in enumerate(REFUSED)])
def test_refusals_name_the_key_and_what_is_allowed(tmp_path, capsys, n, lines, key, message):
    path, code, out, err = check_text(tmp_path, capsys, mechanism_text(n, lines))
    assert code == 2 and "Traceback" not in err, err
    assert f"{path}: {key}: " in err and message in err, err
    assert err.count("\n") == 1


def test_reaction_friction_on_a_fork_and_blade_crankpin_is_refused(tmp_path, capsys):
    text = mechanism_text(2, TWIN_FORK_LINES) + """
[[friction.pairs]]
between = ["crank", "rod"]
model = "reaction"
mu = 0.001
radius_mm = 25
"""
    path, code, _, err = check_text(tmp_path, capsys, text)
    assert code == 2 and "Traceback" not in err
    assert (f"{path}: friction.pairs[0].between: ['crank', 'rod'] (the crankpin of "
            f"fork-and-blade rods") in err
    side = text.replace('"fork-and-blade"', '"side-by-side"\nrod_spacing_mm = 24\n'
                                            'journal_spacing_mm = 90')
    assert check_text(tmp_path, capsys, side)[1] == 0


def test_the_old_form_of_a_v_engine_is_refused_with_the_throws_that_keep_its_meaning(
        tmp_path, capsys):
    """A V8 written as before (a bank per cylinder, no throws: a throw per cylinder, its crank
    mass per cylinder): refused, and the ``throws_deg`` the message gives, added to the file,
    read to the J it had: Σ over the cylinders of a single cylinder with its crank mass."""
    firing = [45, 675, 315, 225, 495, 405, 585, 135]
    banks = [45, -45] * 4
    old = mechanism_text(8, f"bank_deg = {banks}\nfiring_deg = {firing}")
    path, code, _, err = check_text(tmp_path, capsys, old)
    assert code == 2 and f"{path}: mechanism.throws: is missing: the cylinders sit on " in err
    assert 'rod_arrangement = "side-by-side" or "fork-and-blade"' in err
    throws = err.split("as this file was read before: throws_deg = ")[1].split(" with its")[0]
    mech = load_scene("o.toml", text=old.replace("firing_deg", f"throws_deg = {throws}\n"
                                                               f"firing_deg")).mechanism
    assert mech.n_throws == 8
    single = CrankSliderNumpy(one_cylinder(mech, crank_mass=M_CRANK))
    phi = np.linspace(0.0, 4.0 * math.pi, 61)
    before = [sum(single.terms(p - math.radians(f))[0] for f in firing) for p in phi]
    np.testing.assert_allclose(mech.kinematics_table(phi)["J"], before, rtol=1e-12)
    # an in-line engine is read as before: no throws needed
    inline = load_scene("i.toml", text=mechanism_text(4, "firing_order = [1, 3, 4, 2]"))
    assert inline.mechanism.n_throws == 4 and inline.mechanism.rod_arrangement == "single"
    np.testing.assert_allclose(np.degrees(inline.mechanism.firing_angles), [0, 540, 180, 360])
