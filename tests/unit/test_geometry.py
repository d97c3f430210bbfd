"""What a mechanism's geometry implies without a run (``scene.geometry()``, ``transient check``)
against independent checks: dead centres found by a dense grid and a root of the piston's rate,
strokes between them, the closed forms of Gots (9)–(10) and §2.3, λ_i from a separately computed
spectrum and the Macalpine series, the long-rod limit of the swash plate; and one vocabulary: the
names and units of the API, the ``check`` output and the user guide's table agree."""
from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from transient.cli import main
from transient.core.model import crank_slider as cs_core
from transient.mechanisms import articulated as art
from transient.mechanisms import swash_plate as sp
from transient.mechanisms.crank_slider import CrankSlider
from transient.scene import load_scene
from transient.scene.queries import cycle_figures

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"


def extremes(f, lo: float, hi: float, h: float, n: int = 20_001) -> tuple[float, float]:
    """Angles of the least and greatest f over [lo, hi): the grid's extremes refined as roots of
    f′ by central differences of step ``h`` (f is only evaluated, never differentiated)."""
    x = np.linspace(lo, hi, n, endpoint=False)
    v = np.array([f(a) for a in x])
    rate = lambda a: (f(a + h) - f(a - h)) / (2.0 * h)
    step = x[1] - x[0]
    return tuple(brentq(rate, x[j] - step, x[j] + step, xtol=1e-14)
                 for j in (int(np.argmin(v)), int(np.argmax(v))))


def wrapped(a: float, b: float) -> float:
    """a − b on the circle, in (−π, π]."""
    return (a - b + math.pi) % (2.0 * math.pi) - math.pi


# ---- crank-slider ---------------------------------------------------------------------------

GEOMETRIES = [  # (r, l, e) [m]: the Gots diesel, offsets both ways, one near the limit l − r
    (0.047, 0.148, 0.0), (0.047, 0.148, 0.010), (0.047, 0.148, -0.030), (0.030, 0.100, -0.060)]


def crank_slider(r: float, l: float, e: float) -> CrankSlider:
    return CrankSlider(crank_radius=r, rod_length=l, offset=e, bore=0.088, piston_mass=1.0,
                       crank_mass=0.0, rod_model="two-mass", rod_mass=1.0, rod_cg_from_pin=0.05,
                       rod_inertia_cg=0.0, strokes=4, firing_angles=(0.0, 4 * math.pi / 3,
                                                                     2 * math.pi / 3),
                       bank_angles=(0.0,) * 3)


@pytest.mark.parametrize("r, l, e", GEOMETRIES)
def test_crank_slider_geometry_against_a_search_of_the_piston_travel(r, l, e):
    """The dead centres are the extremes of the kernel's piston travel s(α), searched on a grid
    and refined as roots of s′; the stroke lies between them; λ and k satisfy Gots (9)–(10) at
    the angles found (with offset) and the acceleration at TDC r(1 + λ) of §2.3 (without)."""
    mech = crank_slider(r, l, e)
    g = mech.geometry()
    travel = lambda a: cs_core.slider(a, r, l, e)[0]
    tdc, bdc = extremes(travel, -math.pi / 2, 3 * math.pi / 2, 1e-5)
    assert g["tdc"] == (pytest.approx(tdc, abs=1e-9), "rad")
    assert g["bdc"] == (pytest.approx(bdc, abs=1e-9), "rad")
    stroke = travel(bdc) - travel(tdc)
    assert g["stroke"] == (pytest.approx(stroke, rel=1e-12), "m")
    volume = mech.volume_function(0.0)  # (a numpy formula of its own)
    assert g["swept_volume"] == (pytest.approx(float(volume(bdc) - volume(tdc)), rel=1e-12),
                                 "m^3")
    assert g["displacement"] == (pytest.approx(3 * mech.piston_area * stroke, rel=1e-12), "m^3")
    lam, k = g["lambda"][0], g["offset_ratio"][0]
    assert g["lambda"][1] == g["offset_ratio"][1] == "1"
    if e:
        s1, s2 = math.sin(tdc), math.sin(bdc - math.pi)  # Gots (9), (10): λk/(1 ± λ)
        assert lam == pytest.approx((s2 - s1) / (s2 + s1), rel=1e-7)
        assert k == pytest.approx(s1 * (1.0 + lam) / lam, rel=1e-7)
    else:
        assert k == 0.0
        assert cs_core.slider(0.0, r, l, e)[2] == pytest.approx(r * (1.0 + lam), rel=1e-14)


# ---- master and articulated rods ------------------------------------------------------------

def articulated_cases():
    radial = load_scene(CASES / "radial_5cyl.toml").mechanism
    vtwin = load_scene(CASES / "v_twin_fork_blade.toml").mechanism
    # link pins off the slave axes (ψ_i ≠ δ_i, Rickert's case of Semenov §3)
    skewed = replace(radial, link_angles=tuple(d - math.radians(5.0) for d in radial.slave_banks))
    return {"radial_5cyl": radial, "v_twin": vtwin, "radial_skewed": skewed}


ARTICULATED = articulated_cases()


def axial(mech, alpha, i: int) -> float | np.ndarray:
    """X of piston i (0 the master) along its cylinder axis from O, from the plain-numpy
    positions (not the kernel)."""
    p = art.positions(mech, alpha)
    if i == 0:
        return p["B"].real
    return (p["Bi"][:, i - 1] * np.exp(-1j * mech.slave_banks[i - 1])).real


@pytest.mark.slow  # (the extremes searched in plain Python, one position at a time)
@pytest.mark.parametrize("name", sorted(ARTICULATED))
def test_articulated_geometry_against_a_search_of_the_piston_positions(name):
    """Each piston's dead centres are the extremes of X(α) from the plain-numpy positions, its
    stroke lies between them, and λ_c is the 2nd harmonic of X'' over r from those positions."""
    mech = ARTICULATED[name]
    g = mech.geometry()
    r = mech.crank_radius
    alpha = np.linspace(0.0, 2.0 * math.pi, 1024, endpoint=False)
    total = 0.0
    for i in range(1 + mech.n_slaves):
        c = f"cyl_{i + 1}_"
        X = lambda a, i=i: float(axial(mech, a, i)[0])
        bdc, tdc = extremes(X, -0.5, 2.0 * math.pi - 0.5, 1e-6)
        assert abs(wrapped(g[c + "tdc"][0], tdc)) <= 1e-8, c
        assert abs(wrapped(g[c + "bdc"][0], bdc)) <= 1e-8, c
        assert 0.0 <= g[c + "tdc"][0] < 2.0 * math.pi and 0.0 <= g[c + "bdc"][0] < 2.0 * math.pi
        stroke = X(tdc) - X(bdc)
        total += stroke
        assert g[c + "stroke"] == (pytest.approx(stroke, rel=1e-12), "m")
        F = np.fft.rfft(axial(mech, alpha, i)) / alpha.size
        assert g[c + "lambda"] == (pytest.approx(4.0 * 2.0 * abs(F[2]) / r, rel=1e-10), "1")
        if i:
            assert g[c + "stroke_excess"] == (pytest.approx(stroke - 2.0 * r, abs=1e-13), "m")
            assert abs(g[c + "tdc_after_bank"][0]
                       - wrapped(tdc, mech.slave_banks[i - 1])) <= 1e-8
    lam = g["lambda"][0]
    assert lam == r / mech.rod_length
    # the master is a centred crank-slider: dead centres 0 and π, stroke 2r, and its λ_1 the
    # Macalpine series of the 2nd harmonic, λ + λ³/4 + 15λ⁵/128 + 35λ⁷/512 + 735λ⁹/16384 + …
    assert (g["cyl_1_tdc"][0], g["cyl_1_bdc"][0]) == (0.0, math.pi)
    assert g["cyl_1_stroke"][0] == pytest.approx(2.0 * r, rel=1e-14)
    series = lam + lam**3 / 4 + 15 * lam**5 / 128 + 35 * lam**7 / 512 + 735 * lam**9 / 16384
    assert g["cyl_1_lambda"][0] == pytest.approx(series, rel=1e-6)
    assert g["displacement"] == (pytest.approx(mech.rows * mech.piston_area * total, rel=1e-12),
                                 "m^3")
    assert g["stroke"] == (2.0 * r, "m")


def test_central_articulation_is_a_crank_slider_on_its_bank():
    """A slave rod on the crankpin itself (fork and blade) is a centred crank-slider along its
    bank: TDC at δ, stroke 2r, λ_2 the master's series with r/l_i."""
    mech = ARTICULATED["v_twin"]
    g = mech.geometry()
    assert abs(g["cyl_2_tdc_after_bank"][0]) <= 1e-12
    assert abs(g["cyl_2_stroke_excess"][0]) <= 1e-15
    li = mech.slave_lengths[0]
    lam = mech.crank_radius / li
    series = lam + lam**3 / 4 + 15 * lam**5 / 128 + 35 * lam**7 / 512 + 735 * lam**9 / 16384
    assert g["cyl_2_lambda"][0] == pytest.approx(series, rel=1e-6)


# ---- swash plate ----------------------------------------------------------------------------

SWASH = {"z3": sp.antonyuk_example(cylinders=3),
         "z4_two_halves": sp.antonyuk_example(halves=2),
         "z5_normal_hinge": sp.antonyuk_example(cylinders=5, hinge="normal")}


@pytest.mark.slow  # (the extremes searched in plain Python, one position at a time)
@pytest.mark.parametrize("name", sorted(SWASH))
def test_swash_plate_geometry_against_a_search_of_the_piston_joints(name):
    """Each cylinder's dead centres are the extremes of its piston joint's x_D(φ) (positions),
    its stroke lies between them; every piston counts in the displacement."""
    geom = SWASH[name]
    g = geom.geometry()
    total = 0.0
    for k in range(geom.cylinders):
        c = f"cyl_{k + 1}_"
        x = lambda p, k=k: float(sp.positions(geom, p)["D"][0, k, 0])
        inner, outer = extremes(x, -0.5, 2.0 * math.pi - 0.5, 1e-6, n=4001)
        assert abs(wrapped(g[c + "tdc"][0], inner)) <= 1e-8, c
        assert abs(wrapped(g[c + "bdc"][0], outer)) <= 1e-8, c
        stroke = x(outer) - x(inner)
        total += stroke
        assert g[c + "stroke"] == (pytest.approx(stroke, rel=1e-12), "m")
    assert g["displacement"] == (pytest.approx(geom.halves * geom.piston_area * total,
                                               rel=1e-12), "m^3")
    assert (g["cyl_1_tdc"][0], g["cyl_1_bdc"][0]) == (0.0, math.pi)
    assert g["swept_volume"] == (pytest.approx(geom.halves * geom.piston_area
                                               * g["cyl_1_stroke"][0], rel=1e-12), "m^3")


def test_swash_plate_strokes_tend_to_2R_sin_alpha_for_long_rods():
    """For ℓ → ∞ the rods stay parallel to the shaft and every stroke is 2R sin α (Antonyuk §2);
    a 30 m rod leaves a relative difference of order (lateral swing)²/(ℓ·R sin α)."""
    geom = sp.antonyuk_example(cylinders=3, rod_length=30.0, rod_cg_from_pin=15.0)
    g = geom.geometry()
    closed = 2.0 * geom.joint_radius * math.sin(geom.swash_angle)
    for k in range(3):
        assert g[f"cyl_{k + 1}_stroke"][0] == pytest.approx(closed, rel=1e-5)


# ---- one vocabulary -------------------------------------------------------------------------

def guide_table() -> dict[str, str]:
    """name → unit of the derived-geometry table of the user guide's *Mechanisms* page."""
    text = (ROOT / "docs" / "guide" / "mechanisms.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([^`]+)` \| `([^`]+)` \|", text, flags=re.M)
    assert rows, "the Mechanisms page has the table of derived geometry"
    return dict(rows)


@pytest.mark.parametrize("case", ["gots_diesel_4400", "radial_5cyl", "swash_plate_4cyl"])
def test_check_prints_the_geometry_under_the_api_names_the_guide_lists(case, capsys):
    """``transient check`` prints every figure of ``scene.geometry()`` (and the stored figures
    of ``analysis_summary()``, and the gas cycle's of ``cycle_figures``) as ``name = value
    unit``, with the API's name and unit, and the user guide's table names every geometry figure
    with that unit."""
    path = CASES / f"{case}.toml"
    assert main(["check", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    printed = dict(line.strip().split(" = ") for line in lines[1:])
    scene = load_scene(path)
    geometry = scene.geometry()
    expected = {**geometry, **scene.mechanism.analysis_summary(), **cycle_figures(scene)}
    assert printed == {name: f"{value:.9g} {unit}" for name, (value, unit) in expected.items()}
    assert {"stroke", "swept_volume", "displacement"} <= set(geometry)
    table = guide_table()
    for name, (_, unit) in geometry.items():
        generic = re.sub(r"^cyl_[0-9]+_", "cyl_<c>_", name)
        assert table.get(generic) == unit, name


def test_a_slave_whose_tdc_is_across_0_deg_from_its_bank_lags_it_by_a_small_angle():
    """Slaves at δ = 0.005° and 359.995° whose link pins (ψ = 10°, 350°) put their TDCs about
    0.01° on the other side of 0° (the TDC angle wraps, the bank does not) report the lag in
    (−π, π], the searched TDC's distance from δ on the circle."""
    radial = ARTICULATED["radial_5cyl"]
    for bank, psi in ((0.005, 10.0), (359.995, 350.0)):
        mech = replace(radial, slave_banks=(math.radians(bank),),
                       link_angles=(math.radians(psi),), link_radii=radial.link_radii[:1],
                       slave_lengths=radial.slave_lengths[:1], firing=())
        g = mech.geometry()
        X = lambda a, mech=mech: float(axial(mech, a, 1)[0])
        _, tdc = extremes(X, -0.5, 2.0 * math.pi - 0.5, 1e-6)
        assert abs(g["cyl_2_tdc"][0] - math.radians(bank)) > math.pi  # wrapped across 0°
        lag = g["cyl_2_tdc_after_bank"][0]
        assert abs(lag) < math.radians(0.1) and abs(lag - wrapped(tdc, math.radians(bank))) <= 1e-8
