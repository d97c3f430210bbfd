"""Swash-plate scenes: the [mechanism] reader, its TOML writer, the mechanism interface (firing
angles, volume, stroke) and the example scenes of Antonyuk et al. §4.

The scene loader does not know the swash plate yet, so the reader is driven directly with
``Section`` on the parsed ``[mechanism]`` table, the way ``scene_from_dict`` calls a mechanism
reader (it reads ``type`` and finishes the table itself).
"""
from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from transient.core.model import swash_plate as core
from transient.core.model.swash_plate import terms as swash_kernel
from transient.errors import SceneError
from transient.forces.gas import mixed_cycle
from transient.mechanisms import swash_plate as sp
from transient.scene.reader import Section

CASES = Path(__file__).resolve().parents[2] / "cases"
ALPHA = math.radians(21.4)
R1 = 0.13131  # the scenes' r₁ = R(1 + cos α)/2, rounded to 0.01 mm


def scene_file(name: str) -> dict:
    return tomllib.loads((CASES / name).read_text())


BASE = scene_file("swash_plate_4cyl.toml")["mechanism"]


def read(table: dict) -> sp.SwashPlate:
    """Read a [mechanism] table as scene_from_dict does: type, the reader, then finish."""
    s = Section(copy.deepcopy(table), "mechanism")
    assert s.string("type") == "swash-plate"
    mech = sp.SwashPlate.read(s)
    s.finish()
    return mech


def changed(drop=(), rod=None, **keys) -> dict:
    table = copy.deepcopy(BASE)
    for k in drop:
        table.pop(k)
    table.update(keys)
    if rod is not None:
        table["rod"].update(rod)
    return table


# ------------------------------------------------------------------------------------------------
# The example scenes


@pytest.mark.parametrize("name, z, fan", [("swash_plate_1cyl.toml", 1, 3.1976e-2),
                                          ("swash_plate_4cyl.toml", 4, 1.2867e-1)])
def test_example_scenes(name, z, fan):
    data = scene_file(name)
    mech = read(data["mechanism"])
    expect = sp.antonyuk_example(cylinders=z, cylinder_radius=R1)
    for f in ("joint_radius", "cylinder_radius", "rod_length", "bore", "cylinders", "halves",
              "hinge", "piston_mass", "rod_model", "rod_mass", "rod_cg_from_pin", "rod_inertia_cg",
              "link_polar_inertia", "link_diametral_inertia", "cross_inertia"):
        want = getattr(expect, f)
        assert getattr(mech, f) == (want if isinstance(want, str)
                                    else pytest.approx(want, rel=1e-15)), f
    assert mech.swash_angle == pytest.approx(ALPHA, rel=1e-15)
    # The paper's data and the sections the other readers will take.
    assert data["inertia"] == {"shaft": 1.0}
    assert data["initial"] == {"phi": 0.0, "omega": 10.0}
    assert data["gas"] == {"model": "trapezoid", "amplitude": 8000.0, "ramp_deg": 30,
                           "duration_deg": 180}
    assert data["load"] == {"fan": fan}
    assert data["governor"] == {"model": "droop", "speed_full": 45.0, "speed_zero": 60.0}
    assert data["run"]["t_end"] > 0
    # The paper's pulses of cylinder i start at π(i − 1)/2 (z = 4): exactly the dead centres.
    assert mech.firing_angles == tuple(math.pi / 2 * k for k in range(z))


def test_example_fan_constant_balances_the_governed_gas_torque_at_50_rad_s():
    """The scenes' K_M: the mean of F·u over a turn, summed over cylinders, times the governor's
    fuel at the target speed (2/3 at 50 rad/s between ω_a = 45 and ω₁c = 60), over ω_t²."""
    from transient.forces.trapezoid import trapezoid_table

    table = trapezoid_table(8000.0, math.radians(30.0))
    w_target = 50.0
    fuel = (60.0 - w_target) / (60.0 - 45.0)
    for name, fan in (("swash_plate_1cyl.toml", 3.1976e-2), ("swash_plate_4cyl.toml", 1.2867e-1)):
        mech = read(scene_file(name)["mechanism"])
        mp = mech.pack()
        z = mech.cylinders
        u, du = np.empty(z), np.empty(z)
        x, wq = np.polynomial.legendre.leggauss(40)
        # Every corner of every cylinder's pulse, so that each interval is smooth.
        ends = np.unique(np.concatenate([np.mod(np.add.outer(mech.firing_angles,
                                                             table.corners[:-1]).ravel(),
                                                 2 * math.pi), [0.0, 2 * math.pi]]))
        work = 0.0
        for a, b in zip(ends[:-1], ends[1:]):
            for p, w in zip(0.5 * (a + b) + 0.5 * (b - a) * x, wq):
                core.swash_terms(mp, p, u, du)
                force = table(p - np.asarray(mech.firing_angles))
                work += 0.5 * (b - a) * w * float(force @ u)
        mean_torque = work / (2 * math.pi)
        assert fan == pytest.approx(fuel * mean_torque / w_target**2, rel=5e-4)


# ------------------------------------------------------------------------------------------------
# Reader and writer


ROUND_TRIP = [
    {},
    dict(swash_angle=math.radians(30.0), cylinders=5, halves=2, hinge="normal", bore=0.05,
         rod_model="rigid", rod_inertia_cg=0.012, rod_cg_from_pin=0.1, link_polar_inertia=0.45,
         link_diametral_inertia=0.2, cross_inertia=0.0),
    dict(cylinders=3, rod_length=0.25, cylinder_radius=0.13, piston_mass=0.0),
]


@pytest.mark.parametrize("changes", ROUND_TRIP)
def test_round_trip_through_toml_lines(changes):
    mech = sp.antonyuk_example(**changes)
    lines = mech.toml_lines()
    assert lines[0] == "[mechanism]" and lines[1] == 'type = "swash-plate"'
    assert "[mechanism.rod]" in lines
    assert not any("_deg" in line or "_mm" in line for line in lines)  # SI, no suffixes
    data = tomllib.loads("\n".join(lines) + "\n")
    back = read(data["mechanism"])
    assert back == mech
    assert back.toml_lines() == lines


def test_reader_units_and_defaults():
    table = {"type": "swash-plate", "swash": ALPHA, "joint_radius_mm": 136.0,
             "cylinder_radius": R1, "rod_length_mm": 300, "bore": 0.1, "piston_mass": 6,
             "link_polar_inertia": 0.4, "link_diametral_inertia": 0.25,
             "rod": {"mass": 1.0, "cg_from_pin_mm": 150}}
    mech = read(table)
    assert mech.joint_radius == pytest.approx(0.136, rel=1e-15)
    assert mech.rod_length == pytest.approx(0.3, rel=1e-15)
    assert mech.rod_cg_from_pin == pytest.approx(0.15, rel=1e-15)
    assert (mech.cylinders, mech.halves, mech.hinge, mech.rod_model) == (1, 1, "in-plane",
                                                                        "two-mass")
    assert (mech.cross_inertia, mech.rod_inertia_cg) == (0.0, 0.0)
    assert (mech.link_polar_inertia, mech.link_diametral_inertia) == (0.4, 0.25)
    iso = read(changed())
    assert iso.link_polar_inertia == iso.link_diametral_inertia == 0.3


BAD = [
    # The swash angle: 0 < α < 45°, reported under the key as written.
    (dict(swash_deg=0), "mechanism.swash_deg"),
    (dict(swash_deg=-5.0), "mechanism.swash_deg"),
    (dict(swash_deg=45), "mechanism.swash_deg"),
    (dict(drop=["swash_deg"], swash=0.8), "mechanism.swash"),
    (dict(drop=["swash_deg"], swash=0.0), "mechanism.swash"),
    (dict(drop=["swash_deg"]), "mechanism.swash"),  # missing
    # A rod too short for the lateral offset (9.4 mm), and lengths ≤ 0.
    (dict(rod_length_mm=5, rod={"cg_from_pin_mm": 2}), "mechanism.rod_length_mm"),
    (dict(drop=["rod_length_mm"], rod_length=0.005, rod={"cg_from_pin_mm": 2}),
     "mechanism.rod_length"),
    (dict(rod_length_mm=5), "mechanism.rod.cg_from_pin_mm"),  # (≤ rod_length, read first)
    (dict(rod_length_mm=0), "mechanism.rod_length_mm"),
    # r₁ that the rods cannot reach, or a negative one.
    (dict(cylinder_radius_mm=450), "mechanism.cylinder_radius_mm"),
    (dict(drop=["cylinder_radius_mm"], cylinder_radius=0.45), "mechanism.cylinder_radius"),
    (dict(cylinder_radius_mm=-131.31), "mechanism.cylinder_radius_mm"),
    (dict(joint_radius_mm=0), "mechanism.joint_radius_mm"),
    # Cylinders, halves, hinge.
    (dict(cylinders=0), "mechanism.cylinders"),
    (dict(cylinders=-4), "mechanism.cylinders"),
    (dict(cylinders=2.5), "mechanism.cylinders"),
    (dict(halves=3), "mechanism.halves"),
    (dict(hinge="diagonal"), "mechanism.hinge"),
    # Bore: > 0 and no overlap between neighbours (< 185.7 mm for 4 cylinders).
    (dict(bore_mm=200), "mechanism.bore_mm"),
    (dict(drop=["bore_mm"], bore=0.2), "mechanism.bore"),
    # Masses and inertias.
    (dict(piston_mass=-6.0), "mechanism.piston_mass"),
    (dict(link_inertia=-0.3), "mechanism.link_inertia"),
    (dict(link_polar_inertia=0.3), "mechanism.link_inertia"),  # both forms
    (dict(drop=["link_inertia"]), "mechanism.link_inertia"),  # neither
    (dict(drop=["link_inertia"], link_polar_inertia=0.3), "mechanism.link_diametral_inertia"),
    (dict(drop=["link_inertia"], link_diametral_inertia=0.3), "mechanism.link_polar_inertia"),
    (dict(cross_inertia=-1.0), "mechanism.cross_inertia"),
    # The rod table.
    (dict(drop=["rod"]), "mechanism.rod"),
    (dict(rod={"model": "elastic"}), "mechanism.rod.model"),
    (dict(rod={"mass": -1.0}), "mechanism.rod.mass"),
    (dict(rod={"cg_from_pin_mm": 310}), "mechanism.rod.cg_from_pin_mm"),
    (dict(rod={"inertia_cg": 0.01}), "mechanism.rod.inertia_cg"),  # two-mass: no such key
    (dict(rod={"model": "rigid", "inertia_cg": -0.01}), "mechanism.rod.inertia_cg"),
    (dict(rod={"colour": "red"}), "mechanism.rod.colour"),
]


@pytest.mark.parametrize("change, key", BAD, ids=[k + ":" + str(c) for c, k in BAD])
def test_reader_rejects_with_the_key_as_written(change, key):
    with pytest.raises(SceneError) as info:
        read(changed(**change))
    assert info.value.key == key
    assert "\n" not in info.value.message


def test_validate_messages_survive_the_key_mapping():
    with pytest.raises(SceneError, match="must be < 45, got 50") as info:
        read(changed(swash_deg=50))
    assert info.value.key == "mechanism.swash_deg"
    with pytest.raises(SceneError, match="too short") as info:
        read(changed(rod_length_mm=5, rod={"cg_from_pin_mm": 2}))
    assert info.value.key == "mechanism.rod_length_mm"


# ------------------------------------------------------------------------------------------------
# The mechanism interface


def test_interface_attributes():
    g = sp.antonyuk_example()
    assert g.kernel is swash_kernel
    assert g.strokes == 2
    assert g.cycle == 2 * math.pi
    assert g.n_cylinders == 4
    assert g.bank_angles == (0.0, math.pi / 2, math.pi, 3 * math.pi / 2)
    assert g.firing_angles == (0.0, math.pi / 2, math.pi, 3 * math.pi / 2)
    assert isinstance(g.stroke(), float)
    assert g.stroke() == pytest.approx(sp.stroke(g)[0], rel=1e-14)
    assert g.swept_volume() == pytest.approx(g.piston_area * g.stroke(), rel=1e-15)
    assert sp.antonyuk_example(halves=2).swept_volume() == pytest.approx(2 * g.swept_volume())


@pytest.mark.parametrize("hinge", ["in-plane", "normal"])
@pytest.mark.parametrize("z", [1, 2, 3, 5, 6])
def test_firing_angles_are_the_inner_dead_centres(hinge, z):
    g = sp.antonyuk_example(cylinders=z, hinge=hinge, bore=0.05)
    fire = np.array(g.firing_angles)
    assert np.all((0.0 <= fire) & (fire < 2 * math.pi))
    mp = g.pack()
    u, du = np.empty(z), np.empty(z)
    phi = np.linspace(0.0, 2 * math.pi, 200_001)
    x = sp.positions(g, phi)["D"][:, 0, :, 0]
    for k in range(z):
        core.swash_terms(mp, fire[k], u, du)
        assert abs(u[k]) < 1e-14  # a dead centre ...
        assert du[k] > 0  # ... the inner one (x_D smallest)
        xk = sp.positions(g, fire[k])["D"][0, k, 0]
        assert xk <= x[:, k].min() + 1e-15
        even = 2 * math.pi * k / z
        off = (fire[k] - even + math.pi) % (2 * math.pi) - math.pi
        if (4 * k) % z == 0:  # ψ_Dk a multiple of π/2: exactly the even spacing
            assert fire[k] == even
        else:  # off by about the Hooke joint's largest non-uniformity δ_max (2.05° here)
            delta_max = math.atan((1 - math.cos(ALPHA)) / (2 * math.sqrt(math.cos(ALPHA))))
            assert 0.5 * delta_max < abs(off) < 1.1 * delta_max


@pytest.mark.parametrize("halves", [1, 2])
@pytest.mark.parametrize("z", [1, 3, 4])
def test_volume_function(halves, z):
    g = sp.antonyuk_example(cylinders=z, halves=halves, bore=0.08)
    clearance = 5e-5
    V = g.volume_function(clearance)
    area = halves * g.piston_area
    assert V(0.0) == pytest.approx(clearance, rel=1e-15)
    assert np.ndim(V(0.0)) == 0
    # Outer dead centre half a turn on, exactly; V(π) − V(0) = swept volume.
    assert V(math.pi) - V(0.0) == pytest.approx(g.swept_volume(), rel=1e-13)
    x = np.linspace(-math.pi, 3 * math.pi, 4002).reshape(2, -1)
    v = V(x)
    assert v.shape == x.shape
    assert v.min() >= clearance * (1 - 1e-15)
    assert v.max() <= V(math.pi) * (1 + 1e-15)
    np.testing.assert_allclose(V(x + 2 * math.pi), v, rtol=1e-13)
    np.testing.assert_allclose(V(-x), v, rtol=1e-13)  # cylinder 1 is symmetric about φ = 0
    # dV/dx = halves·F_p·u₁, the kernel's transfer function of cylinder 1 (which sums the halves).
    mp = g.pack()
    u, du = np.empty(z), np.empty(z)
    for p in (0.3, 1.2, 2.5, 4.0, 5.5):
        core.swash_terms(mp, p, u, du)
        h = 1e-4
        dv = (V(p + h) - V(p - h)) / (2 * h)
        assert dv == pytest.approx(area / halves * u[0], rel=1e-7)
    # One half: the volume above a piston, V = clearance + F_p·(x_D − x_D(0)).
    if halves == 1:
        xd = sp.positions(g, x.ravel())["D"][:, 0, 0, 0]
        x0 = sp.positions(g, 0.0)["D"][0, 0, 0]
        np.testing.assert_allclose(v.ravel(), clearance + g.piston_area * (xd - x0), rtol=1e-13)


@pytest.mark.parametrize("z, halves", [(4, 1), (3, 1), (3, 2)])
def test_volume_fits_the_mixed_cycle(z, halves):
    """The compression ratio the assembler derives from swept_volume() is the one V gives, to 1e-9,
    even where the cylinders' strokes differ (z = 3)."""
    g = sp.antonyuk_example(cylinders=z, halves=halves, bore=0.08)
    eps = 16.0
    clearance = g.swept_volume() / (eps - 1.0)
    table = mixed_cycle(g.volume_function(clearance), compression_ratio=eps, p_a=1.5e5, n1=1.36,
                        p_z=9e6, rho=1.5, n2=1.25, strokes=2, step=math.radians(1.0))
    assert table.period == g.cycle
    assert table.v_a / table.v_c == pytest.approx(eps, rel=1e-12)
