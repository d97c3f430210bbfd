"""The Gots worked example at constant 4400 rpm (Gots §2.9, App. 1):
tables П4.1 (forces and torque of one cylinder) and П4.2 (three cylinders) reproduced by a
prescribed-speed run (inverse dynamics), and the mean indicated torque of the ideal mixed cycle.

In a prescribed-speed run the result holds M_drive = J ε + ½J′ω² − M, the torque a drive would
have to supply; with ε = 0 and no loads, the torque the cylinders deliver (gas + inertia) is
−M_drive. Scene: ``cases/gots_diesel_4400.toml`` with the gas replaced by the printed indicator
gauge pressures of П4.1 (+ p0 = 0.1 MPa) as a ``table`` with linear interpolation, and the rod
split so that m_j = m_п + m₁ = 1.520 + 0.480 = 2.0 kg (Dinn's VJ1, App. 1), λ = 0.047/0.148.

**Inertia: exact versus the book's 2nd order.** The simulator uses the exact crank-slider
(Gots ch. 1, exact forms), but П4.1's p'_j is −m_j r ω²(cos φ + λ cos 2φ)/F_p, the 2nd-order (6)
(data README, "П4.1"); only the force resolution N, S, K, T is exact. The two differ by up to
m_j ω² |j_exact − j_2nd|/ω²·u ≈ 17 N·m (0.058 MPa in T, at 90°/270°/450°/630°), so the printed
rows cannot be met to 1 N·m by the exact model. The test therefore *adds* the closed-form
difference m_j ω² u (u′_exact − r(cos φ + λ cos 2φ)) to the simulated torque — u, u′ from Gots'
exact §2.2/§2.3 forms, computed here and not by the package — and compares that with the table.
It also checks that the raw difference is of that size, so a model that silently switched to
the 2nd-order inertia would fail.
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model, gas_phases, gas_table
from transient.core import crank_slider as core
from transient.scene import load_scene
from transient.run import integrate

CASES = Path(__file__).resolve().parents[2] / "cases"
N = 4400.0
OMEGA = math.pi * N / 30.0  # 460.77 rad/s, П4.1 uses πn/30 (data README)
R, L = 0.047, 0.148
LAM = R / L  # 0.31757, App. 1 input (Dinn)
M_J = 2.0  # VJ1, App. 1
P0 = 0.1e6
T_TOL = 2e-3  # MPa: П4.1 prints T to 1e-3 MPa; README reproduces it to ≤ 1.2e-3
M_TOL = 1.0  # N·m: П4.1 prints M to 1 N·m; README reproduces it to ≤ 0.84 N·m


def read_csv(path: Path) -> dict[str, np.ndarray]:
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def table_scene(cylinders: int, p41):
    """gots_diesel_4400.toml with the П4.1 gas table; one cylinder (firing TDC at 360° of the
    table, i.e. firing_deg = [360]) or the scene's three (firing_deg = [360, 600, 120])."""
    text = (CASES / "gots_diesel_4400.toml").read_text()
    gas_start = text.index("[gas]")
    gas_end = text.index("[run]")
    cg_mm = L * (1.0 - 0.480 / 1.752) * 1e3  # two-mass rod: m₁ = m(l − l₁)/l = 0.480 kg at the pin
    gas = ("[gas]\nmodel = \"table\"\np0_MPa = 0.1\ninterpolation = \"linear\"\n"
           f"phi_deg = {list(map(float, p41['phi_deg']))}\n"
           f"p_MPa = {list(map(float, p41['pg_gauge_MPa'] + 0.1))}\n\n")
    text = text[:gas_start] + gas + text[gas_end:]
    changes = {"cg_from_pin_mm = 107.3": f"cg_from_pin_mm = {cg_mm!r}",
               "revolutions = 4": "revolutions = 2",
               "samples_per_rev = 1440": "samples_per_rev = 360"}  # a 1° output grid
    if cylinders == 1:
        changes.update({"cylinders = 3": "cylinders = 1", "firing_order = [1, 2, 3]":
                        "firing_order = [1]", "firing_deg = [360, 600, 120]": "firing_deg = [360]"})
    for old, new in changes.items():
        assert text.count(old) == 1, f"gots_diesel_4400.toml no longer has {old!r}"
        text = text.replace(old, new)
    return load_scene(CASES / "gots_p41_table.toml", text=text)


def inertia_2nd_order_correction(phi_local):
    """Torque [N·m] to add to the exact model to get the book's: m_j ω² u (u′ − r(cos φ + λ cos 2φ)).

    u = r sin(φ+β)/cos β and u′ = r[cos(φ+β)/cos β + λ cos²φ/cos³β] (Gots §2.2, §2.3 exact).
    """
    beta = np.arcsin(LAM * np.sin(phi_local))
    u = R * np.sin(phi_local + beta) / np.cos(beta)
    du = R * (np.cos(phi_local + beta) / np.cos(beta)
              + LAM * np.cos(phi_local) ** 2 / np.cos(beta) ** 3)
    return M_J * OMEGA**2 * u * (du - R * (np.cos(phi_local) + LAM * np.cos(2 * phi_local)))


@pytest.fixture(scope="module")
def p41(gots_data):
    return read_csv(gots_data / "gots_P4_1_forces.csv")


@pytest.fixture(scope="module")
def p42(gots_data):
    return read_csv(gots_data / "gots_P4_2_torque.csv")


def nodes(data, phi_deg):
    """Row indices of the output at the table's 30° angles (the output grid is 1°)."""
    idx = np.rint(np.asarray(phi_deg)).astype(int)
    np.testing.assert_allclose(np.degrees(data.trajectory["phi"][idx]), phi_deg, atol=1e-9)
    return idx


def test_scene_is_the_books_engine(p41):
    scene = table_scene(3, p41)
    mp = scene.mechanism.pack()
    assert mp[core.M_PISTON] + mp[core.M_PIN] == pytest.approx(M_J, rel=1e-12)
    assert scene.mechanism.lam == pytest.approx(LAM, rel=1e-14)
    assert scene.run.speed == pytest.approx(OMEGA, rel=1e-15)
    # Table convention: 0 = gas-exchange TDC, firing TDC at 360°. firing_deg gives the shaft angle
    # of each crank's local 0, and gas_phases shifts it by 360° (assemble.gas_phases): cylinder
    # tables start at 0/240/480° — the firing offsets of order 1-2-3 (П4.2).
    np.testing.assert_allclose(np.degrees(gas_phases(scene)), [0.0, 240.0, 480.0], atol=1e-12)
    np.testing.assert_allclose(np.degrees(scene.mechanism.firing_angles), [360, 600, 120],
                               atol=1e-12)


def test_P4_1_single_cylinder(p41):
    """T = M_cyl/(r F_p) within 2e-3 MPa (all rows but 660°, scrambled in print: data README)
    and M_cyl within 1 N·m (all 25 rows; at 660° the printed M matches T = +1.046, README)."""
    scene = table_scene(1, p41)
    data = integrate(scene)
    idx = nodes(data, p41["phi_deg"])
    tr = data.trajectory
    # The 30° nodes of the linear table are reproduced exactly.
    np.testing.assert_allclose(tr["p_1"][idx], (p41["pg_gauge_MPa"] + 0.1) * 1e6, rtol=1e-14)
    area = scene.mechanism.piston_area
    m_exact = -tr["M_drive"][idx]
    m_book = m_exact + inertia_2nd_order_correction(np.radians(p41["phi_deg"]))
    t_book = m_book / (R * area) / 1e6
    rows = p41["phi_deg"] != 660.0
    dm = m_book - p41["M_cyl_N_m"]
    dt = (t_book - p41["T_MPa"])[rows]
    raw = np.max(np.abs(m_exact - p41["M_cyl_N_m"]))
    print(f"П4.1: max |ΔM| = {np.max(np.abs(dm)):.3f} N·m, max |ΔT| = {np.max(np.abs(dt)):.2e} "
          f"MPa (2nd-order inertia as printed); exact inertia differs by up to {raw:.2f} N·m")
    assert np.max(np.abs(dm)) <= M_TOL
    assert np.max(np.abs(dt)) <= T_TOL
    # Exact vs 2nd-order inertia is a visible difference (≈17 N·m at 90°): see module docstring.
    assert 10.0 <= raw <= 25.0


def test_P4_2_three_cylinder_sum(p41, p42):
    scene = table_scene(3, p41)
    data = integrate(scene)
    idx = nodes(data, p42["phi_deg"])
    phi = np.radians(p42["phi_deg"])
    correction = sum(inertia_2nd_order_correction(phi - off)
                     for off in np.radians([0.0, 240.0, 480.0]))
    m_sum = -data.trajectory["M_drive"][idx] + correction
    dev = np.max(np.abs(m_sum - p42["M_sum_N_m"]))
    print(f"П4.2: max |ΔM_sum| = {dev:.3f} N·m")
    assert dev <= M_TOL


def test_rod_centrifugal_force():
    """K′_rш = m₂ r ω²/F_p = 2.08 MPa (§2.9), m₂ = 0.725·1.752 kg from the scene's two-mass rod
    (Gots (20): m₂ = m l₁/l with l₁ = 107.3 mm = 0.725 L). Printed to 3 digits: ±0.005 MPa."""
    scene = load_scene(CASES / "gots_diesel_4400.toml")
    m2 = scene.mechanism.pack()[core.M_CRANKPIN]
    assert m2 == pytest.approx(0.725 * 1.752, rel=1e-3)
    k_rod = m2 * R * OMEGA**2 / scene.mechanism.piston_area / 1e6
    print(f"K'_rш = {k_rod:.4f} MPa")
    assert k_rod == pytest.approx(2.08, abs=0.005)


def test_mean_indicated_torque_of_the_ideal_cycle(p42, sample_integral):
    """Mean of −M_drive over a cycle = 3·W/(4π), W the closed-form loop work of the ideal mixed
    cycle (``MixedCycle.work``), to 1e-6: the inertia torque ½J′ω² averages to zero over a turn
    and ∮p0 dV = 0: 205.766 N·m (tables to 1e-9, quadrature ~1e-13).

    Why this is not the book's 149.1 N·m (Gots §2.9): the mean of the printed 30°-sampled
    П4.2 sum is only 104.1 N·m, because a 30° grid misses the combustion peak near 360–390°;
    rebuilding the torque finely from the printed П2.1 pressures gives 151.7 N·m, i.e. a loop
    of 635 J (~p_e, 1.11 MPa, not p_i = 1.42 MPa) — so the book's "dynamic" 149.1 compares with
    M_e = 153.05. The ideal polytropes here (ρ = 1.671, with pumping) give p_i′ ≈ 1.507 MPa and
    205.7 N·m; the book needs M_ср·η_m (59) to get from there to M_e.

    The mean is taken with a local-polynomial rule between the breakpoints (table corners), where
    the torque has kinks: a plain trapezoid on the 0.25° grid is off by 4.5e-6.
    """
    scene = load_scene(CASES / "gots_diesel_4400.toml")
    table = gas_table(scene)
    _, bp, _ = build_model(scene)
    data = integrate(scene)
    tr = data.trajectory
    cycle = 4.0 * math.pi
    assert tr["phi"][-1] >= cycle
    mean = sample_integral(tr["phi"], -tr["M_drive"], np.concatenate([[0.0, cycle], bp])) / cycle
    expected = 3.0 * table.work / cycle
    grid_mean = float(np.mean(p42["M_sum_N_m"][:-1]))  # 0…690°, 720° repeats 0°
    print(f"mean indicated torque: {mean:.4f} N·m (3·W/4π = {expected:.4f}); "
          f"П4.2 30°-grid mean {grid_mean:.2f} N·m")
    assert mean == pytest.approx(expected, rel=1e-6)
    assert mean == pytest.approx(205.77, abs=0.01)
    assert grid_mean == pytest.approx(104.1, abs=0.05)
