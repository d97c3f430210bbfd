"""The dead centres of an offset crank-slider lie off 0 and π (Gots (9) and its folded twin), and
the mixed cycle compresses between them: an offset engine with a consistent compression ratio is
valid, its cycle starts at the true BDC and fires at the true TDC (was a bug: the check compared
V(180°)/V(0°) with the ratio, which no ratio meets once the crank is offset)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scene_texts import MIXED_CYCLE, SMALL

from transient.cli import main
from transient.forces.gas import mixed_cycle
from transient.scene import load_scene
from transient.scene.queries import clearance_volume, gas_table

MIXED = MIXED_CYCLE.format(cr=18)

GEOMETRIES = [  # (r, l, e) [m]: the Gots diesel, offsets both ways, one near the limit l − r
    (0.047, 0.148, 0.0), (0.047, 0.148, 0.010), (0.047, 0.148, -0.030), (0.047, 0.148, 0.100),
    (0.030, 0.100, -0.060),
]


def scene_text(offset_mm: float, strokes: int = 4) -> str:
    mech = f"bore_mm = 88\noffset_mm = {offset_mm}\nstrokes = {strokes}"
    gas = MIXED
    if strokes == 2:  # (a 2-stroke has no gas-exchange strokes: it refuses their pressures)
        gas = gas.replace("p_intake_MPa = 0.165\n", "").replace("p_exhaust_MPa = 0.182\n", "")
    return SMALL.replace("bore_mm = 88", mech) + gas


def mechanism(r: float, l: float, e: float):
    from transient.mechanisms.crank_slider import CrankSlider

    return CrankSlider(crank_radius=r, rod_length=l, offset=e, bore=0.088, piston_mass=1.0,
                       crank_mass=0.0, rod_model="two-mass", rod_mass=1.0, rod_cg_from_pin=0.05,
                       rod_inertia_cg=0.0, strokes=4, firing_angles=(0.0,), bank_angles=(0.0,))


@pytest.mark.parametrize("r, l, e", GEOMETRIES)
def test_the_dead_centres_are_the_extremes_of_the_volume(r, l, e):
    """Brute force over one turn finds the least and greatest volume within a grid step of the
    closed forms; there the slope vanishes (central differences) and the curvature has the
    sign of a minimum (TDC) and of a maximum (BDC)."""
    mech = mechanism(r, l, e)
    tdc, bdc = mech.dead_centre_angles()
    volume = mech.volume_function(1e-5)
    x = np.linspace(-math.pi / 2, 3 * math.pi / 2, 400_001)
    v = volume(x)
    step = x[1] - x[0]
    assert abs(x[np.argmin(v)] - tdc) <= step and abs(x[np.argmax(v)] - bdc) <= step
    h = 1e-5
    for angle, sign in ((tdc, 1.0), (bdc, -1.0)):
        slope = (volume(angle + h) - volume(angle - h)) / (2 * h)
        curvature = (volume(angle + h) - 2 * volume(angle) + volume(angle - h)) / h**2
        scale = mech.piston_area * r
        assert abs(slope) <= 1e-9 * scale
        assert sign * curvature > 0.1 * scale
    stroke = volume(bdc) - volume(tdc)
    assert stroke == pytest.approx(mech.piston_area * mech.stroke(), rel=1e-13)
    if e == 0.0:
        assert (tdc, bdc) == (0.0, math.pi)
    else:
        assert np.sign(tdc) == np.sign(e) and np.sign(bdc - math.pi) == np.sign(e)


@pytest.mark.parametrize("offset_mm", [30, -30, 10])
def test_an_offset_engine_with_a_mixed_cycle_is_valid(tmp_path, capsys, offset_mm):
    path = tmp_path / "offset.toml"
    path.write_text(scene_text(offset_mm), encoding="utf-8")
    assert main(["check", str(path)]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("strokes", [4, 2])
@pytest.mark.parametrize("offset_mm", [30, -30])
def test_the_cycle_compresses_between_the_true_dead_centres(tmp_path, offset_mm, strokes):
    """p = p_a at the true BDC, p_c = p_a·ε^n1 just before the true TDC, p_z at it; the table's
    ∮p dV (Gauss–Legendre per knot interval) is the closed-form work."""
    path = tmp_path / "offset.toml"
    path.write_text(scene_text(offset_mm, strokes), encoding="utf-8")
    scene = load_scene(path)
    mech = scene.mechanism
    mc = gas_table(scene)
    tdc, bdc = mech.dead_centre_angles()
    fire = tdc + (2 * math.pi if strokes == 4 else 0.0)
    volume = mech.volume_function(clearance_volume(scene))
    assert mc.v_a / mc.v_c == pytest.approx(18.0, rel=1e-12)
    assert mc.p_c == pytest.approx(0.1436e6 * 18.0**1.368, rel=1e-12)
    assert mc(bdc % mc.period).item() == pytest.approx(0.1436e6, rel=1e-9)
    assert mc(fire % mc.period).item() == pytest.approx(10.5e6, rel=1e-12)
    before = (fire - 1e-9) % mc.period
    assert mc.evaluate(before, mc.piece_of(mc.wrap(before)))[0].item() == pytest.approx(
        mc.p_c, rel=1e-6)
    xg, wg = np.polynomial.legendre.leggauss(8)
    a, b = mc.knots[:-1], mc.knots[1:]
    half = 0.5 * (b - a)
    x = (0.5 * (a + b))[:, None] + half[:, None] * xg[None, :]
    piece = np.searchsorted(mc.piece_knot, np.arange(a.size), side="right") - 1
    p, _ = mc.evaluate(x, np.broadcast_to(piece[:, None], x.shape))
    h = 1e-6
    dv = (volume(x + h) - volume(x - h)) / (2 * h)
    assert float(np.sum(half[:, None] * wg[None, :] * p * dv)) == pytest.approx(mc.work, rel=1e-7)


def test_no_offset_gives_the_table_it_always_gave():
    mech = mechanism(0.047, 0.148, 0.0)
    volume = mech.volume_function(mech.swept_volume() / 17.0)
    args = dict(compression_ratio=18.0, p_a=0.1436e6, n1=1.368, p_z=10.5e6, rho=1.671, n2=1.228,
                p_intake=0.165e6, p_exhaust=0.182e6)
    before = mixed_cycle(volume, **args)
    after = mixed_cycle(volume, dead_centres=mech.dead_centre_angles(), **args)
    np.testing.assert_array_equal(before.knots, after.knots)
    np.testing.assert_array_equal(before.coef, after.coef)
    np.testing.assert_allclose(after.corners, [0.0, math.pi, 2 * math.pi, after.angle_z,
                                               3 * math.pi, 4 * math.pi], rtol=0, atol=0)


def test_a_volume_that_disagrees_with_the_ratio_says_why():
    mech = mechanism(0.047, 0.148, 0.03)
    volume = mech.volume_function(mech.swept_volume() / 16.0)  # ε = 17 by the volume
    from transient.errors import SceneError

    with pytest.raises(SceneError) as info:
        mixed_cycle(volume, compression_ratio=18.0, p_a=0.1436e6, n1=1.368, p_z=10.5e6,
                    rho=1.671, n2=1.228, p_intake=0.165e6, p_exhaust=0.182e6,
                    dead_centres=mech.dead_centre_angles())
    assert info.value.key == "gas.compression_ratio"
    assert "give V_a/V_c = 17, not the compression_ratio 18" in info.value.message
