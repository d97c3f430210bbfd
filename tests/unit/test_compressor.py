"""The ideal compressor cycle (:mod:`transient.forces.compressor`) and the piston-force gas keys:
``model = "compressor"`` and a ``"table"`` of forces.

The cycle is checked against the textbook's closed form written out here (work
n/(n − 1)·p_s·V_s·η_v·((p_d/p_s)^((n−1)/n) − 1), η_v = 1 − c((p_d/p_s)^(1/n) − 1)), against a
quadrature of its exact pressure (its own closed forms evaluated here, not the table), and on a
crank-slider volume written here; bad input is refused with the key and what is allowed.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scene_texts import COMPRESSOR_GAS, SMALL, check_text
from scipy.integrate import quad

from transient.errors import SceneError
from transient.forces.compressor import compressor_cycle, ideal_compressor_work
from transient.scene import load_scene
from transient.scene.outputs import output_columns
from transient.scene.queries import cycle_figures, gas_is_force, gas_tables
from transient.scene.read import scene_from_dict
from transient.scene.write import to_toml

# A small single-stage air compressor's crank (our numbers): r = 20 mm, l = 70 mm, bore 50 mm.
R, L, BORE = 0.020, 0.070, 0.050
AREA = math.pi * BORE ** 2 / 4
V_S = AREA * 2 * R


def crank_volume(clearance_ratio: float):
    """V(x) = c·V_s + F_p·(r(1 − cos x) + l(1 − cos β)), sin β = (r/l) sin x (Gots (1))."""
    def volume(x):
        x = np.asarray(x, dtype=float)
        cos_beta = np.sqrt(1 - (R / L * np.sin(x)) ** 2)
        return clearance_ratio * V_S + AREA * (R * (1 - np.cos(x)) + L * (1 - cos_beta))
    return volume


def crank_dvolume(x):
    x = np.asarray(x, dtype=float)
    lam = R / L
    return AREA * R * np.sin(x) * (1 + lam * np.cos(x) / np.sqrt(1 - (lam * np.sin(x)) ** 2))


def textbook(p_s, p_d, n, c):
    """The textbook's ideal compressor with clearance: (work done on the gas per cycle, η_v)."""
    eta_v = 1 - c * ((p_d / p_s) ** (1 / n) - 1)
    return n / (n - 1) * p_s * V_S * eta_v * ((p_d / p_s) ** ((n - 1) / n) - 1), eta_v


def exact_pressure(cyc, volume, x):
    """The cycle's pressure from its closed forms, piece by piece (not the table)."""
    x = np.asarray(x, dtype=float)
    v = volume(x)
    p = np.where(x < cyc.angle_suction, cyc.p_discharge * (cyc.v_c / v) ** cyc.n_reexpansion,
                 cyc.p_suction)
    p = np.where(x >= math.pi, cyc.p_suction * (cyc.v_1 / v) ** cyc.n, p)
    return np.where(x >= cyc.angle_discharge, cyc.p_discharge, p)


def table_loop_work(cyc, dvolume, nodes=8):
    """∮p dV of the table: Gauss–Legendre on every knot interval with that interval's piece."""
    xg, wg = np.polynomial.legendre.leggauss(nodes)
    a, b = cyc.knots[:-1], cyc.knots[1:]
    half = 0.5 * (b - a)
    x = (0.5 * (a + b))[:, None] + half[:, None] * xg[None, :]
    piece = np.searchsorted(cyc.piece_knot, np.arange(a.size), side="right") - 1
    p, _ = cyc.evaluate(x, np.broadcast_to(piece[:, None], x.shape))
    return float(np.sum(half[:, None] * wg[None, :] * p * dvolume(x)))


#: (p_s, p_d, n, c): an air compressor to 8 bar; an R134a compressor 0.3 → 1.5 MPa; a high
#: ratio with the clearance at 90 % of the largest that still delivers.
CYCLES = [(1e5, 8e5, 1.3, 0.05), (0.3e6, 1.5e6, 1.1, 0.04),
          (1e5, 20e5, 1.25, 0.9 / (20 ** (1 / 1.25) - 1))]


@pytest.mark.parametrize("p_s, p_d, n, c", CYCLES)
def test_work_and_volumetric_efficiency_are_the_textbook_closed_form(p_s, p_d, n, c):
    cyc = compressor_cycle(crank_volume(c), p_suction=p_s, p_discharge=p_d, n=n,
                           clearance_ratio=c)
    work, eta_v = textbook(p_s, p_d, n, c)
    print(f"W = {work:.6g} J, η_v = {eta_v:.6g}, table error {cyc.interpolation_error:.2g}")
    assert cyc.indicated_work == pytest.approx(work, rel=1e-12)
    assert cyc.work == -cyc.indicated_work
    assert cyc.volumetric_efficiency == pytest.approx(eta_v, rel=1e-12)
    assert ideal_compressor_work(p_s, p_d, n, V_S, c) == pytest.approx((work, eta_v), rel=1e-12)
    # the table's own loop work: its interpolation error (relative to p_d) times the loop's scale
    scale = cyc.interpolation_error * p_d * V_S
    assert abs(table_loop_work(cyc, crank_dvolume) - cyc.work) <= 10 * scale + 1e-12 * work


@pytest.mark.parametrize("p_s, p_d, n, c", CYCLES)
def test_the_table_follows_the_cycle_and_the_valves_open_at_the_line_pressures(p_s, p_d, n, c):
    volume = crank_volume(c)
    cyc = compressor_cycle(volume, p_suction=p_s, p_discharge=p_d, n=n, clearance_ratio=c)
    x = cyc.interior_points(4)
    err = np.max(np.abs(cyc(x) - exact_pressure(cyc, volume, x)))
    assert err <= 2 * cyc.interpolation_error * p_d
    assert volume(cyc.angle_suction) == pytest.approx(c * V_S * (p_d / p_s) ** (1 / n), rel=1e-12)
    assert volume(cyc.angle_discharge) == pytest.approx((1 + c) * V_S * (p_s / p_d) ** (1 / n),
                                                        rel=1e-12)
    for angle, p in ((0.0, p_d), (cyc.angle_suction, p_s), (math.pi, p_s),
                     (cyc.angle_discharge, p_d)):
        assert cyc(angle) == pytest.approx(p, rel=1e-9), math.degrees(angle)


def test_a_reexpansion_exponent_of_its_own_against_a_quadrature_of_the_pressure():
    c, volume = 0.06, crank_volume(0.06)
    cyc = compressor_cycle(volume, p_suction=1e5, p_discharge=7e5, n=1.3, n_reexpansion=1.15,
                           clearance_ratio=c)
    corners = [0.0, cyc.angle_suction, math.pi, cyc.angle_discharge, 2 * math.pi]
    work = sum(quad(lambda x: float(exact_pressure(cyc, volume, x)) * float(crank_dvolume(x)),
                    a, b, epsabs=0, epsrel=1e-13)[0] for a, b in zip(corners, corners[1:]))
    assert cyc.work == pytest.approx(work, rel=1e-11)
    assert cyc.volumetric_efficiency == pytest.approx(1 + c - c * 7 ** (1 / 1.15), rel=1e-12)
    # the clearance gas re-expands along its own polytrope
    x = 0.5 * cyc.angle_suction
    assert cyc(x) == pytest.approx(7e5 * (c * V_S / volume(x)) ** 1.15, rel=1e-8)


@pytest.mark.parametrize("changes, key, fragment", [
    (dict(p_discharge=1e5), "gas.p_discharge", "above p_suction"),
    (dict(n=1.0), "gas.n", "must be > 1"),
    (dict(n_reexpansion=0.9), "gas.n_reexpansion", "must be > 1"),
    (dict(clearance_ratio=0.0), "gas.clearance_ratio", "must be > 0"),
    (dict(clearance_ratio=0.3), "gas.clearance_ratio", "must be < 1/((p_d/p_s)^(1/n) − 1) = "
                                                       f"{1 / (8 ** (1 / 1.3) - 1):.6g}"),
    (dict(strokes=4), "gas.model", "give the mechanism strokes = 2"),
])
def test_the_builder_refuses_a_cycle_that_cannot_work(changes, key, fragment):
    kwargs = dict(p_suction=1e5, p_discharge=8e5, n=1.3, clearance_ratio=0.05)
    c = changes.get("clearance_ratio", 0.05)
    with pytest.raises(SceneError) as info:
        compressor_cycle(crank_volume(max(c, 1e-3)), **{**kwargs, **changes})
    assert info.value.key == key and fragment in info.value.message, info.value


# ---------------------------------------------------------------------------------------------
# The scene keys

#: SMALL as a 2-stroke (one cycle a turn) single-cylinder air compressor.
COMPRESSOR = SMALL.replace("bore_mm = 88\n", "bore_mm = 88\nstrokes = 2\n") + COMPRESSOR_GAS

#: The last line of COMPRESSOR, after which tables are appended.
TAIL = "clearance_ratio = 0.05\n"

#: SMALL with a force on its piston tabulated against the angle (a 4-stroke cycle).
FORCE_TABLE = SMALL + """
[gas]
model = "table"
phi_deg = [0, 360, 400, 540, 720]
force_kN = [0, 0, 30, 5, 0]
corners_deg = [360]
interpolation = "linear"
"""


def refused(tmp_path, capsys, text, key, fragment):
    path, code, out, err = check_text(tmp_path, capsys, text)
    assert code == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"{path}: {key}: ") and fragment in err, err


@pytest.mark.parametrize("old, new, key, fragment", [
    ("p_discharge_bar = 8", "p_discharge_bar = 0.5", "gas.p_discharge_bar",
     "must be > p_suction = 1, got 0.5"),
    ("n = 1.3", "n = 1", "gas.n", "must be > 1"),
    ("clearance_ratio = 0.05", "clearance_ratio = 0.4", "gas.clearance_ratio",
     "must be < 1/((p_discharge/p_suction)^(1/min(n, n_reexpansion)) − 1) = "),
    ("clearance_ratio = 0.05", "clearance_ratio = -0.05", "gas.clearance_ratio", "must be > 0"),
    ("strokes = 2\n", "", "gas.model", "the mechanism's cycle is 720° (strokes = 4)"),
    ("n = 1.3", "n = 1.3\ninjection_deg = 10", "gas.injection_deg", "unknown key; allowed here:"),
    (TAIL, TAIL + "\n[governor]\nmodel = \"droop\"\nspeed_full = 50\nspeed_zero = 60\n",
     "governor.model", "a compressor has no fuel for a governor to set; use model = \"none\""),
    (TAIL, TAIL + "\n[[gas.cylinders]]\ncylinder = 1\nfuel = 0.8\n",
     "gas.cylinders[0].fuel", "its [[gas.cylinders]] entries take 'cylinder' and 'pressure' "
                              "only"),
    (TAIL, TAIL + "\n[[gas.cylinders]]\ncylinder = 1\nmisfire_every = 3\n",
     "gas.cylinders[0].misfire_every", "a compressor burns no fuel"),
    ('model = "compressor"', 'model = "compresor"', "gas.model",
     "allowed: 'none', 'table', 'mixed-cycle', 'trapezoid', 'wiebe', 'compressor'"),
])
def test_bad_compressor_keys_are_refused_with_the_key(tmp_path, capsys, old, new, key, fragment):
    assert COMPRESSOR.count(old) == 1, old
    refused(tmp_path, capsys, COMPRESSOR.replace(old, new), key, fragment)


@pytest.mark.parametrize("old, new, key, fragment", [
    ("force_kN = [0, 0, 30, 5, 0]", "force_kN = [0, 0, 30, 5, 0]\np_bar = [1, 1, 60, 5, 1]",
     "gas.force", "a table holds the pressure in the cylinder or the force on its piston"),
    ("interpolation", "p0_bar = 1\ninterpolation", "gas.p0_bar", "unknown key"),
    ("force_kN", "force_MPa", "gas.force_MPa", "unit suffix '_MPa' does not fit this quantity; "
                                               "give 'force' or 'force_kN'"),
    ("force_kN", "forces_kN", "gas.p", "or the forces on the piston 'force' (or 'force_kN')"),
    ('interpolation = "linear"', 'interpolation = "linear"\n\n[analysis]\nthermodynamics = true',
     "analysis.thermodynamics", "applies no cylinder pressure"),
])
def test_bad_force_table_keys_are_refused_with_the_key(tmp_path, capsys, old, new, key,
                                                       fragment):
    assert FORCE_TABLE.count(old) == 1, old
    refused(tmp_path, capsys, FORCE_TABLE.replace(old, new), key, fragment)


def test_a_force_table_from_a_csv_file(tmp_path):
    (tmp_path / "force.csv").write_text("phi_deg,force_kN\n0,0\n360,0\n400,30\n540,5\n720,0\n")
    scene = tmp_path / "scene.toml"
    scene.write_text(FORCE_TABLE.split("[gas]")[0] + '[gas]\nmodel = "table"\nfile = "force.csv"\n'
                     'corners_deg = [360]\ninterpolation = "linear"\n')
    inline = tmp_path / "inline.toml"
    inline.write_text(FORCE_TABLE)
    a, b = load_scene(scene), load_scene(inline)
    assert a.gas == replace(b.gas) and gas_is_force(a)


def _scene(text):
    import tomllib
    return scene_from_dict(tomllib.loads(text), file="test.toml")


@pytest.mark.parametrize("text", [COMPRESSOR, FORCE_TABLE,
                                  COMPRESSOR + "\n[[gas.cylinders]]\ncylinder = 1\npressure = 0.9\n"])
def test_the_resolved_scene_reads_back_equal(text):
    scene = _scene(text)
    assert _scene(to_toml(scene)) == scene


def test_a_force_table_is_applied_as_a_force_as_the_trapezoid_is():
    """The trapezoid's pulse given as a force table (its corners, linear): the same table, a
    force (no area, no p0), columns in newtons."""
    pulse = SMALL.replace("bore_mm = 88\n", "bore_mm = 88\nstrokes = 2\n")
    trapezoid = _scene(pulse + '\n[gas]\nmodel = "trapezoid"\namplitude = 8000\nramp_deg = 30\n')
    table = _scene(pulse + '\n[gas]\nmodel = "table"\nphi_deg = [0, 30, 150, 180, 360]\n'
                           'force = [0, 8000, 8000, 0, 0]\ncorners_deg = [30, 150, 180]\n'
                           'interpolation = "linear"\n')
    a, b = gas_tables(trapezoid)[0], gas_tables(table)[0]
    assert np.array_equal(a.knots, b.knots) and np.allclose(a.coef, b.coef, rtol=1e-15, atol=1e-9)
    assert gas_is_force(table) and table.gas.p0 == 0.0
    assert output_columns(table)["p_1"] == "N"


def test_transient_check_prints_the_cycle_figures():
    """At a prescribed constant speed: the indicated power z·W·ω/2π and the drive moment, from
    the closed form (textbook, above) on the mechanism's clearance c·V_s."""
    scene = _scene(COMPRESSOR.replace("[run]\n", '[run]\nmode = "prescribed-speed"\n'
                                                 'speed_rpm = 1500\n'))
    mech = scene.mechanism
    work, eta_v = textbook(1e5, 8e5, 1.3, 0.05)
    work *= mech.swept_volume() / V_S
    figures = {k: v for k, (v, _) in cycle_figures(scene).items()}
    omega = 1500 * math.pi / 30
    assert figures["indicated_work"] == pytest.approx(work, rel=1e-12)
    assert figures["volumetric_efficiency"] == pytest.approx(eta_v, rel=1e-12)
    assert figures["indicated_power"] == pytest.approx(-work * omega / (2 * math.pi), rel=1e-12)
    assert figures["mean_drive_torque_ideal"] == pytest.approx(work / (2 * math.pi), rel=1e-12)
