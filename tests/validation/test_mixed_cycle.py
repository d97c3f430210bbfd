"""The ideal mixed cycle of Gots App. 2 tabulated on the exact crank-slider volume.

Sources: Gots App. 2 (the DIZDN cycle printout and table П2.1), §2.9 and App. 1 (geometry),
§2.9 (mean torque, 149.1 N·m against M_e = 153.05 N·m), and ``tests/data/README.md`` (misprints
in П2.1). Angles follow the Gots tables: 0° is the gas-exchange TDC and 360° the firing TDC.
The comparisons with the printout and the closed forms are cases of ``tests/references/gots.py``
(the Validation page renders them); the tests here assert them and the table's structure.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from references import check_all, closed_forms, gots
from references.gots import CYCLE, EPS, RHO_GEO, V_C, V_H, exact_pressure, left, table_loop_work

from transient.errors import SceneError
from transient.forces.gas import mixed_cycle

DEG = math.pi / 180
volume = gots.volume


@pytest.fixture(scope="module")
def cycles():
    return {rho: gots.cycle(rho) for rho in (1.671, 1.699, RHO_GEO)}


def test_geometry():
    assert volume(math.pi) / V_C == pytest.approx(EPS, rel=1e-14)
    assert round(RHO_GEO, 3) == 1.671  # README: "ρ = V(380°)/V(360°) = 1.671, not 1.699"


def test_characteristic_pressures(cycles):
    """p_c and p_b against App. 2 (the comparisons), the table's limits at the corners, and the
    printed ρ = 1.699, which ends the isobar later and gives a 2 % higher p_b."""
    check_all(gots.cycle_pressures())
    mc = cycles[1.671]
    # The table: p_c just before the firing TDC, the jump to p_z at it.
    assert left(mc, 2 * math.pi) == pytest.approx(mc.p_c, rel=1e-12)
    assert mc(2 * math.pi) == CYCLE["p_z"]
    assert left(mc, 3 * math.pi) == pytest.approx(mc.p_b, rel=1e-12)
    assert mc(3 * math.pi) == CYCLE["p_exhaust"]
    m2 = cycles[1.699]
    assert m2.p_b == pytest.approx(CYCLE["p_z"] * (1.699 / EPS) ** CYCLE["n2"], rel=1e-12)
    assert m2.p_b / 0.5670e6 - 1 > 0.015
    # With the geometric ρ the isobar ends at 380° exactly, as in П2.1.
    assert cycles[RHO_GEO].angle_z == pytest.approx(380 * DEG, abs=1e-12)


def test_indicated_pressure_of_the_printout():
    """App. 2's p_i = 1.42 MPa is φ_i = 0.91 times the ideal cycle's p_i′ with the printed
    ρ = 1.699 and no pumping loop (the standard mixed-cycle formula gives the same 1.563 MPa)."""
    check_all(gots.indicated_pressure())


def test_corners(cycles):
    mc = cycles[1.671]
    np.testing.assert_allclose(mc.corners, [0, math.pi, 2 * math.pi, mc.angle_z, 3 * math.pi,
                                            4 * math.pi], rtol=0, atol=0)
    # Continuous where the isobar meets the expansion (a kink, not a jump).
    assert left(mc, mc.angle_z) == CYCLE["p_z"]
    assert mc(mc.angle_z) == pytest.approx(CYCLE["p_z"], rel=1e-14)
    assert mc(0.0) == CYCLE["p_intake"] and left(mc, 4 * math.pi) == CYCLE["p_exhaust"]


def test_loop_work():
    """The closed form against an adaptive quadrature of the closed forms (checks the formula)
    and against the table's ∮p dV, for ρ = 1.671 and 1.699; the mean torque W/4π."""
    check_all(closed_forms.mixed_cycle_work())


def test_interpolation_error(cycles):
    for rho, mc in cycles.items():
        assert mc.interpolation_error <= 1e-9
        # Independently of the builder's estimate: 8 points per interval, own closed forms.
        err = mc.max_abs_error(lambda x: exact_pressure(mc, x), per_interval=8) / CYCLE["p_z"]
        assert err <= 1e-9
    print(f"\n{mc.knots.size} knots; relative error: estimate {mc.interpolation_error:.2e}, "
          f"8 points per interval {err:.2e}")


def test_p21_indicator_table():
    """П2.1 against the table built with the geometric ρ (its isobar ends at 380°): the volume,
    the temperature and the pressure rows on the model's curves (the comparisons' docstring),
    and the isobar held at p_z exactly."""
    check_all(gots.p21_indicator())
    _, p, _ = gots.p21_model()
    phi = gots.p21()["phi_deg"]
    isobar = (phi > 360) & (phi <= 380)
    np.testing.assert_allclose(p[isobar], CYCLE["p_z"], rtol=1e-14)  # 380° is the corner


def test_two_stroke(cycles):
    mc = gots.cycle(1.671, strokes=2)
    assert mc.period == 2 * math.pi and mc.strokes == 2
    np.testing.assert_allclose(mc.corners, [0, mc.angle_z, math.pi, 2 * math.pi], atol=0)
    assert mc.angle_z == pytest.approx(cycles[1.671].angle_z - 2 * math.pi, abs=1e-13)
    assert mc(0.0) == CYCLE["p_z"]                                     # firing TDC at 0
    assert left(mc, 2 * math.pi) == pytest.approx(mc.p_c, rel=1e-12)   # compression end
    assert left(mc, math.pi) == pytest.approx(mc.p_b, rel=1e-12)       # expansion end
    assert mc(math.pi) == pytest.approx(CYCLE["p_a"], rel=1e-12)       # scavenged at BDC
    w_table = table_loop_work(mc)
    assert abs(w_table / mc.work - 1) <= 1e-8
    # Same polytropes and isobar as the 4-stroke, without its pumping loop.
    pumping = (CYCLE["p_intake"] - CYCLE["p_exhaust"]) * V_H
    assert mc.work == pytest.approx(cycles[1.671].work - pumping, rel=1e-12)
    assert mc.mean_torque == pytest.approx(mc.work / (2 * math.pi), rel=1e-15)


def scene_error(key, **change):
    args = dict(CYCLE, rho=1.671)
    args.update(change)
    with pytest.raises(SceneError) as info:
        mixed_cycle(volume, **args)
    assert info.value.key == key and "\n" not in info.value.message
    return info.value.message


def test_scene_errors():
    msg = scene_error("gas.compression_ratio", compression_ratio=17.0)
    assert "18" in msg and "17" in msg
    assert "7.488" in scene_error("gas.p_z", p_z=5e6)
    scene_error("gas.rho", rho=0.9)
    scene_error("gas.rho", rho=18.0)
    scene_error("gas.n1", n1=1.0)
    scene_error("gas.n2", n2=float("nan"))
    scene_error("gas.p_a", p_a=-1.0)
    scene_error("gas.p_intake", p_intake=None)
    scene_error("gas.strokes", strokes=3)


def test_rho_one_has_no_isobar():
    # ρ = 1: heat added at constant volume only; the expansion starts at p_z on the TDC.
    mc = mixed_cycle(volume, **dict(CYCLE, rho=1.0))
    np.testing.assert_allclose(mc.corners, [0, math.pi, 2 * math.pi, 3 * math.pi, 4 * math.pi],
                               atol=0)
    assert mc(2 * math.pi) == pytest.approx(CYCLE["p_z"], rel=1e-14)
    assert abs(table_loop_work(mc) / mc.work - 1) <= 1e-8
