"""The modal analysis of the elastic shaft line (:mod:`transient.analysis.torsion`,
:mod:`transient.shaft`), each result against something independent: closed forms of two and
three masses, a hand-expanded characteristic polynomial, openTorsion (an independent
torsional-vibration library) on its published Friswell example and on transient's own lines,
the compiled kernel's J(φ) and finite differences for the stations' inertias, and a Lagrangian
written in the driven side's own coordinate for the gear ratio's convention."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scene_texts import SMALL

from transient.analysis.torsion import (
    critical_speeds,
    damped_modes,
    engine_orders,
    frozen_bands,
    modal_analysis,
    natural_modes,
    order_kind,
)
from transient.scene import load_scene
from transient.shaft import ShaftLine, rigid_equivalent

CASES = Path(__file__).resolve().parents[2] / "cases"
INLINE6 = load_scene(CASES / "inline6_damper.toml")
TWO_PI = 2.0 * math.pi


def chain(k) -> np.ndarray:
    """The stiffness matrix of masses in a chain joined by springs ``k``, written out."""
    n = len(k) + 1
    K = np.zeros((n, n))
    for i, ki in enumerate(k):
        K[i:i + 2, i:i + 2] += ki * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return K


def small_line(shaft_toml: str, mechanism: str = "") -> str:
    """SMALL (one cylinder) with its [inertia] taken out and ``shaft_toml`` added."""
    text = SMALL.replace("[inertia]\nshaft = 0.02\n", "")
    if mechanism:
        text = text.replace('type = "crank-slider"\n', f'type = "crank-slider"\n{mechanism}')
    return text + shaft_toml


THREE_STATIONS = small_line("""
[[shaft.stations]]
name = "front"
inertia = 0.01
[[shaft.stations]]
name = "throw"
inertia = 0.005
cylinders = [1]
[[shaft.stations]]
name = "flywheel"
inertia = 0.2
[[shaft.sections]]
stiffness = 2e5
[[shaft.sections]]
stiffness = 3e5
""")


# -- closed forms ----------------------------------------------------------------------------

def test_two_masses_free_free_closed_form_and_mass_normalised_shapes():
    J1, J2, k = 211.4, 8.3, 9.775e6
    omega, shapes = natural_modes(chain([k]), np.array([J1, J2]), rigid=1)
    assert omega[0] == 0.0
    assert omega[1] == pytest.approx(math.sqrt(k * (J1 + J2) / (J1 * J2)), rel=1e-12)
    assert shapes.T @ np.diag([J1, J2]) @ shapes == pytest.approx(np.eye(2), abs=1e-12)
    # the rigid mode turns both alike; the elastic one keeps the angular momentum at 0
    assert shapes[0, 0] == pytest.approx(shapes[1, 0], rel=1e-12)
    assert J1 * shapes[0, 1] + J2 * shapes[1, 1] == pytest.approx(0.0, abs=1e-12)


def test_two_masses_with_a_ground_spring_closed_form():
    J1, J2, k0, k = 0.3, 0.1, 4e4, 1e5
    K = chain([k])
    K[0, 0] += k0  # the first mass held to the frame
    # det(K − λM) = J1J2 λ² − (J1 k + J2 (k0 + k)) λ + k0 k = 0, solved by hand
    b, c, a = J1 * k + J2 * (k0 + k), k0 * k, J1 * J2
    roots = sorted([(b - math.sqrt(b * b - 4 * a * c)) / (2 * a),
                    (b + math.sqrt(b * b - 4 * a * c)) / (2 * a)])
    omega, _ = natural_modes(K, np.array([J1, J2]))
    assert omega ** 2 == pytest.approx(roots, rel=1e-12)


def test_three_masses_against_the_characteristic_polynomial():
    J, k = (0.05, 0.02, 0.4), (3e5, 1.2e5)
    # free chain: λ [J1J2J3 λ² − (k1 J3 (J1 + J2) + k2 J1 (J2 + J3)) λ + k1 k2 (J1 + J2 + J3)]
    quadratic = [J[0] * J[1] * J[2], -(k[0] * J[2] * (J[0] + J[1]) + k[1] * J[0] * (J[1] + J[2])),
                 k[0] * k[1] * sum(J)]
    expected = sorted(np.roots(quadratic).real)
    omega, _ = natural_modes(chain(k), np.array(J), rigid=1)
    assert omega[0] == 0.0
    assert omega[1:] ** 2 == pytest.approx(expected, rel=1e-12)


def test_damped_two_masses_closed_form():
    """Relative damping of a free pair: the twist x obeys μẍ + cẋ + kx = 0, μ = J1J2/(J1 + J2),
    so ω_n = √(k/μ) and ζ = c/(2√(kμ)); the rigid motion is two real (zero) eigenvalues."""
    J1, J2, k, c = 0.2, 0.05, 1e5, 8.0
    mu = J1 * J2 / (J1 + J2)
    C = chain([c])
    modes, real = damped_modes(chain([k]), C, np.array([J1, J2]))
    assert real == 2 and len(modes) == 1
    assert modes[0].omega_n == pytest.approx(math.sqrt(k / mu), rel=1e-10)
    assert modes[0].zeta == pytest.approx(c / (2 * math.sqrt(k * mu)), rel=1e-10)
    assert modes[0].omega_d == pytest.approx(modes[0].omega_n * math.sqrt(1 - modes[0].zeta ** 2),
                                             rel=1e-10)


# -- openTorsion ------------------------------------------------------------------------------

#: Friswell, Penny, Garvey & Lees, Dynamics of Rotating Machines (2010), Example 9.7.1: a free
#: chain of five discs, as openTorsion 0.3.2 gives it in its own test suite
#: (opentorsion/tests/tests.py, ``test_friswell_ex971``, MIT licence): inertias [kg m²],
#: stiffnesses [N m/rad], and the published natural frequencies [Hz] to two decimals.
FRISWELL_971_INERTIA = (3.5e-3, 3.5e-3, 3.5e-3, 0.15, 0.05)
FRISWELL_971_STIFFNESS = (12e3, 12e3, 14e3, 10e3)
FRISWELL_971_HZ = (81.21, 141.21, 378.95, 536.36)


def opentorsion_hz(inertia, stiffness) -> np.ndarray:
    """openTorsion's undamped natural frequencies [Hz] of a free chain, each once."""
    ot = pytest.importorskip("opentorsion")
    shafts = [ot.Shaft(i, i + 1, 0, 0, k=k) for i, k in enumerate(stiffness)]
    disks = [ot.Disk(i, J) for i, J in enumerate(inertia)]
    undamped, _, _ = ot.Assembly(shafts, disk_elements=disks).modal_analysis()
    return np.sort(np.asarray(undamped))[::2] / TWO_PI  # (each appears twice: ±iω)


def test_friswell_971_published_by_opentorsion_and_by_transient():
    ours, _ = natural_modes(chain(FRISWELL_971_STIFFNESS), np.array(FRISWELL_971_INERTIA), 1)
    assert np.round(ours[1:] / TWO_PI, 2).tolist() == list(FRISWELL_971_HZ)
    assert np.round(opentorsion_hz(FRISWELL_971_INERTIA, FRISWELL_971_STIFFNESS)[1:],
                    2).tolist() == list(FRISWELL_971_HZ)


def friswell_scene():
    """Friswell's Ex. 9.7.1 in transient's scene form: the single cylinder of SMALL on the
    fourth disc, whose own inertia is 0.15 kg m² less the cylinder's cycle-mean J."""
    probe = load_scene("probe.toml", text=THREE_STATIONS)
    mean_cylinder = ShaftLine(probe).mean_inertia()[1] - 0.005
    stations = "".join(
        f'[[shaft.stations]]\nname = "disc {i + 1}"\ninertia = {float(J - mean_cylinder * (i == 3))!r}\n'
        + ("cylinders = [1]\n" if i == 3 else "") for i, J in enumerate(FRISWELL_971_INERTIA))
    sections = "".join(f"[[shaft.sections]]\nstiffness = {k!r}\n" for k in FRISWELL_971_STIFFNESS)
    return load_scene("friswell.toml", text=small_line("\n" + stations + sections))


def test_friswell_971_built_as_a_scene():
    modal = modal_analysis(ShaftLine(friswell_scene()), band_samples=8)
    assert [round(m.f, 2) for m in modal.modes] == list(FRISWELL_971_HZ)


@pytest.mark.parametrize("scene", [INLINE6, load_scene("three.toml", text=THREE_STATIONS)],
                         ids=["inline6", "three stations"])
def test_the_scenes_lines_agree_with_opentorsion(scene):
    """The same line (transient's cycle-mean inertias, its section stiffnesses) through
    openTorsion's own assembly and eigensolver: 1e-9 relative. The inline six's damper ring,
    which no spring ties to the line, is left out of both (it is a free disc)."""
    line = ShaftLine(scene)
    keep = [i for i, d in enumerate(line.dofs) if d.kind == "station"]
    inertia = line.mean_inertia()[keep]
    stiffness = [s.stiffness for s in scene.shaft.sections]
    ours, _ = natural_modes(chain(stiffness), inertia, 1)
    theirs = opentorsion_hz(inertia, stiffness)
    assert ours[1:] / TWO_PI == pytest.approx(theirs[1:], rel=1e-9)
    rings = [m.f for m in modal_analysis(line, band_samples=4).modes]
    assert rings == pytest.approx(theirs[1:], rel=1e-9)  # (the free ring changes nothing)


# -- the stations' inertias ---------------------------------------------------------------------

@pytest.mark.parametrize("phi", np.linspace(0.0, 4 * math.pi, 13))
def test_the_stations_inertias_sum_to_the_kernels_J(phi):
    """Σ_s J_s(φ) with every station at φ, less their own inertias, is the compiled kernel's
    J(φ) of the whole mechanism (a separate implementation from the twin the stations use)."""
    line = ShaftLine(INLINE6)
    J, _ = line.station_inertia(phi)
    own = sum(s.inertia for s in INLINE6.shaft.stations)
    kernel = INLINE6.mechanism.kinematics_table(np.array([phi]))["J"][0]
    assert J.sum() - own == pytest.approx(kernel, rel=1e-12)


def test_each_stations_derivative_against_finite_differences():
    line = ShaftLine(INLINE6)
    h = 1e-5
    for phi in (0.3, 1.7, 4.0):
        theta = phi + 0.2 * np.arange(len(INLINE6.shaft.stations))  # (each at its own angle)
        _, dJ = line.station_inertia(theta)
        fd = (line.station_inertia(theta + h)[0] - line.station_inertia(theta - h)[0]) / (2 * h)
        assert dJ == pytest.approx(fd, rel=1e-7, abs=1e-12)
        assert dJ[0] == 0.0 and dJ[-1] == 0.0  # (pulley and flywheel carry no cylinder)


def test_each_station_carries_its_own_cylinder_at_its_phase():
    """The throw of cylinder k has its least inertia at its dead centres: φ = φ_k (mod π)."""
    line = ShaftLine(INLINE6)
    firing = INLINE6.mechanism.firing_angles
    for s, station in enumerate(INLINE6.shaft.stations):
        if not station.cylinders:
            continue
        phi_k = firing[station.cylinders[0] - 1]
        J_dead = line.station_inertia(phi_k)[0][s]
        J_off = [line.station_inertia(phi_k + a)[0][s] for a in (0.3, 1.2, 2.0)]
        assert J_dead < min(J_off)


def test_the_rigid_equivalent_holds_the_lines_inertia():
    rigid = rigid_equivalent(INLINE6)
    assert rigid.shaft is None and rigid_equivalent(rigid) is rigid
    line = ShaftLine(INLINE6)
    for phi in (0.0, 0.7, 2.9):
        kernel = rigid.mechanism.kinematics_table(np.array([phi]))["J"][0]
        assert rigid.inertia.total + kernel == pytest.approx(line.mass_diagonal(phi).sum(),
                                                             rel=1e-12)
    assert rigid.inertia.total == pytest.approx(0.030 + 6 * 0.010 + 0.50 + 0.030, rel=1e-15)
    again = load_scene("rigid.toml", text=rigid.to_toml())  # (a valid scene of its own)
    assert dataclasses.replace(again, name=rigid.name) == rigid


# -- damping, coupling --------------------------------------------------------------------

def test_a_loss_factor_and_a_damping_ratio_are_c_at_the_first_mode():
    def section_c(keys: str) -> tuple[float, float]:
        text = THREE_STATIONS.replace("stiffness = 2e5\n", f"stiffness = 2e5\n{keys}\n")
        line = ShaftLine(load_scene("d.toml", text=text))
        omega, _ = natural_modes(line.K, line.mean_inertia(), 1)
        return -line.C[0, 1], omega[1]
    c, w1 = section_c("loss_factor = 0.04")
    assert c == pytest.approx(0.04 * 2e5 / w1, rel=1e-12)
    c, w1 = section_c("damping_ratio = 0.02")
    assert c == pytest.approx(2 * 0.02 * 2e5 / w1, rel=1e-12)
    c, _ = section_c("damping = 3.5")
    assert c == 3.5


def test_absolute_damping_is_relative_to_the_rigid_rotation():
    """C's absolute part takes no torque on a rigid rotation (C·1 = 0: the rigid mode stays
    undamped) and takes ωᵀCω = Σ c δ̇² + Σ a_d (ω_d − ω̄)² of power, ω̄ the cycle-mean-inertia
    weighted mean speed, the elements' part written out from the element table."""
    line = ShaftLine(INLINE6)
    assert np.any(line.absolute > 0.0)
    np.testing.assert_allclose(line.C @ np.ones(line.n), 0.0, atol=1e-12 * np.abs(line.C).max())
    omega = 300.0 + np.random.default_rng(2).normal(0.0, 3.0, line.n)
    mean = line.weights @ omega / line.weights.sum()
    rows = line.element_rows()
    elements = sum(c * (omega[int(a)] - omega[int(b)]) ** 2 for a, b, _, c, _ in rows)
    assert omega @ line.C @ omega == pytest.approx(
        elements + np.sum(line.absolute * (omega - mean) ** 2), rel=1e-9)


@pytest.mark.parametrize("ratio", [0.5, 1.0, 3.0])
def test_the_gear_ratio_refers_the_driven_inertia_by_its_square(ratio):
    """Against the line written in the driven machine's own angle ψ = i·θ_gear: kinetic energy
    ½J_d ψ̇², the coupling's twist θ − ψ/i, so M = diag(J, J_d), K = k [[1, −1/i], [−1/i, 1/i²]]
    (a Lagrangian that refers nothing)."""
    text = THREE_STATIONS + f"""
[shaft.coupling]
stiffness = 5e3
driven_inertia = 0.4
gear_ratio = {ratio}
"""
    line = ShaftLine(load_scene("c.toml", text=text))
    M = line.mean_inertia()
    ours, _ = natural_modes(line.K, M, 1)
    own = np.diag(np.append(M[:-1], 0.4))
    K = np.zeros((4, 4))
    K[:3, :3] = line.K[:3, :3]
    K[2, 2] -= 5e3  # (the coupling's part written again below, in ψ)
    K[2:, 2:] += 5e3 * np.array([[1.0, -1.0 / ratio], [-1.0 / ratio, 1.0 / ratio ** 2]])
    theirs = np.sort(np.linalg.eigvals(np.linalg.solve(own, K)).real)
    assert ours ** 2 == pytest.approx(np.clip(theirs, 0.0, None), rel=1e-9, abs=1e-6)
    assert line.mean_inertia()[-1] == pytest.approx(ratio ** 2 * 0.4, rel=1e-15)


def test_a_tuned_damper_is_a_spring_and_a_ring_on_its_hub():
    text = THREE_STATIONS + """
[[shaft.dampers]]
station = "front"
model = "tuned"
inertia = 0.004
stiffness = 1e4
damping = 2.0
"""
    line = ShaftLine(load_scene("t.toml", text=text))
    assert line.names == ("front", "front damper", "throw", "flywheel")
    assert line.K[0, 1] == -1e4 and line.C[0, 1] == -2.0 and line.rigid_modes == 1


# -- frozen bands, orders, criticals ------------------------------------------------------

def test_the_frozen_band_holds_the_frequencies_at_hand_picked_angles():
    """The three-station line with its one cylinder frozen at φ = 0 (a dead centre, its least
    J) and at φ = π/2: the inertia there from the compiled kernel's table, the eigenvalues by
    numpy in the test. The band's top is the frequency at the dead centre (J least, every mode
    highest there), and the band holds the one at π/2."""
    scene = load_scene("three.toml", text=THREE_STATIONS)
    line = ShaftLine(scene)
    band = frozen_bands(line, samples=720)

    def at(phi: float) -> np.ndarray:
        J = scene.mechanism.kinematics_table(np.array([phi]))["J"][0]
        M = np.diag([0.01, 0.005 + J, 0.2])
        w2 = np.sort(np.linalg.eigvals(np.linalg.solve(M, line.K)).real)
        return np.sqrt(np.clip(w2, 0.0, None)) / TWO_PI
    dead, quarter = at(0.0), at(0.5 * math.pi)
    assert band[1, 1:] == pytest.approx(dead[1:], rel=1e-9)
    assert np.all(band[0, 1:] <= quarter[1:]) and np.all(quarter[1:] <= band[1, 1:])
    assert np.all(quarter[1:] < dead[1:])


def test_orders_and_their_kinds():
    """In-line six four-stroke, firing every 120°: the major orders are the multiples of 3
    (n_cyl/2); a two-stroke three, every 120° of one turn: the multiples of 3 (n_cyl)."""
    orders = engine_orders(INLINE6.mechanism.cycle, 12)
    assert orders[0] == 0.5 and orders[-1] == 12 and len(orders) == 24
    firing = INLINE6.mechanism.firing_angles
    kinds = {q: order_kind(q, firing) for q in orders}
    assert [q for q, k in kinds.items() if k == "major"] == [3, 6, 9, 12]
    assert kinds[4.5] == "half" and kinds[5] == "integer"
    two = np.radians([0.0, 120.0, 240.0])
    assert engine_orders(TWO_PI, 6).tolist() == [1, 2, 3, 4, 5, 6]
    assert [q for q in range(1, 7) if order_kind(q, two) == "major"] == [3, 6]
    assert order_kind(0.5, [0.0]) == "major"  # (one cylinder: every order in phase)


def test_critical_speeds_of_the_case():
    modal = modal_analysis(ShaftLine(INLINE6), band_samples=16)
    orders = engine_orders(INLINE6.mechanism.cycle, 12)
    criticals = critical_speeds(modal, orders, (800.0, 4400.0))
    f1 = modal.modes[0].f
    assert 200.0 < f1 < 400.0  # (the case's design: its first mode a few hundred Hz)
    first = {c.order: c for c in criticals if c.mode == 1}
    assert set(np.arange(4.5, 9.5, 0.5)) <= set(first)
    for q, c in first.items():
        assert c.rpm == pytest.approx(60.0 * f1 / q, rel=1e-14)
        assert 0.0 <= c.excitation <= 1.0 + 1e-12
    # the major orders' excitation: every cylinder in phase, so the sum of |amplitudes|
    assert first[6].excitation == pytest.approx(1.0, abs=0.01)
    assert all(800.0 <= c.rpm <= 4400.0 for c in criticals)
    assert [c.rpm for c in criticals] == sorted(c.rpm for c in criticals)


def test_the_case_has_a_damped_first_mode_below_the_undamped_one():
    modal = modal_analysis(ShaftLine(INLINE6), band_samples=4)
    assert modal.rigid == 2  # (the line, and the viscous ring)
    assert modal.damped and 0.0 < modal.damped[0].zeta < 1.0
    assert modal.damped[0].omega_n < TWO_PI * modal.modes[0].f


def test_stiffness_proportional_damping_keeps_the_natural_frequencies_and_real_shapes():
    """With C = αK each undamped mode stays a mode: λ = −αω²/2 ± iω√(1 − α²ω²/4), so |λ| = ω
    exactly, ζ = αω/2, and the complex shape is the real one (up to a common factor)."""
    J, k, alpha = np.array([0.05, 0.02, 0.4]), (3e5, 1.2e5), 2e-5
    K = chain(k)
    omega, shapes = natural_modes(K, J, rigid=1)
    modes, real = damped_modes(K, alpha * K, J)
    assert real == 2 and len(modes) == 2
    for d, w, shape in zip(modes, omega[1:], shapes[:, 1:].T):
        assert d.omega_n == pytest.approx(w, rel=1e-10)
        assert d.zeta == pytest.approx(alpha * w / 2.0, rel=1e-10)
        unit = shape / shape[np.argmax(np.abs(shape))]
        assert np.max(np.abs(d.shape - unit)) < 1e-10


def test_damped_criticals_of_the_case_are_where_its_forced_response_peaks():
    """The damped line's criticals against the steady forced response of the same damped line
    (a banded frequency-domain solve, transient.analysis.torsional_response): each first-mode
    order's section torque peaks within 2 % of its damped critical, nearer to it than to the
    undamped line's (the viscous ring left free), which the damper moves by 3–6 %."""
    from transient.analysis.torsional_response import forced_response

    line = ShaftLine(INLINE6)
    modal = modal_analysis(line, band_samples=4)
    orders = np.array([4.5, 6.0, 7.5, 9.0])
    undamped = {c.order: c.rpm for c in critical_speeds(modal, orders, (800.0, 4400.0))
                if c.mode == 1}
    damped = {c.order: c for c in critical_speeds(modal, orders, (800.0, 4400.0), damped=True)
              if c.mode == 1}
    assert set(damped) == set(undamped) == set(orders)
    for q in orders:
        rpm = np.linspace(0.9, 1.1, 801) * damped[q].rpm
        res = forced_response(line, rpm * math.pi / 30.0, [q])
        torque = np.abs(res.torque[:, 0, :])
        peak = rpm[np.argmax(torque[:, np.argmax(torque.max(axis=0))])]
        assert abs(peak - damped[q].rpm) <= 0.02 * damped[q].rpm
        assert abs(peak - damped[q].rpm) < abs(peak - undamped[q])
        assert damped[q].kind == ("major" if q in (6.0, 9.0) else "half")
        assert 0.0 <= damped[q].excitation <= 1.0 + 1e-12
