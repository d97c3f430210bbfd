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
dvolume = gots.dvolume


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
    for mc in cycles.values():
        assert mc.interpolation_error <= 1e-9
        # Independently of the builder's estimate: 8 points per interval, own closed forms.
        err = mc.max_abs_error(lambda x, mc=mc: exact_pressure(mc, x), per_interval=8) / CYCLE["p_z"]
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


# ------------------------------------------------------------------------------------------------
# The motored cycle and part load (mixed_cycle, *Part load*)

N1 = CYCLE["n1"]


@pytest.mark.parametrize("strokes", [4, 2])
def test_motored_cycle_is_the_compression_polytrope_both_ways(strokes):
    """The motored curve against the closed form p_a·(V_a/V)^n1 over the whole closed part
    (4-stroke: π to 3π; 2-stroke: the whole turn) and the full-load table's gas exchange, on the
    same knots; its loop work is the pumping loop alone, (p_intake − p_exhaust)·V_h (0 for a
    2-stroke), by Gauss–Legendre over the table."""
    args = dict(CYCLE, rho=1.671, strokes=strokes)
    if strokes == 2:
        args.update(p_intake=None, p_exhaust=None)
    mc = mixed_cycle(volume, **args)
    mot = mc.motored
    np.testing.assert_array_equal(mot.corners, mc.corners)
    x = mot.interior_points(4)
    closed = (x > math.pi) & (x < 3 * math.pi) if strokes == 4 else np.ones(x.size, bool)
    polytrope = CYCLE["p_a"] * (V_C * EPS / volume(x)) ** N1
    np.testing.assert_allclose(mot(x)[closed], polytrope[closed], rtol=2e-9)
    np.testing.assert_array_equal(mot(x)[~closed], mc(x)[~closed])
    # at the firing TDC the compression end p_c = p_a·ε^n1, continuous (no heat, no jump)
    tdc = 2 * math.pi if strokes == 4 else 0.0
    assert mot(tdc) == pytest.approx(CYCLE["p_a"] * EPS ** N1, rel=1e-12)
    assert left(mot, tdc + mot.period * (strokes == 2)) == pytest.approx(mot(tdc), rel=1e-12)
    pumping = (CYCLE["p_intake"] - CYCLE["p_exhaust"]) * V_H if strokes == 4 else 0.0
    assert table_loop_work(mot) == pytest.approx(pumping, abs=1e-9 * mc.work)


def first_law_part_load(mc, f, x_out):
    """p at the local angles ``x_out`` (in the closed part, 4-stroke) of the cycle that burns f
    times the full-load heat at every angle, by integrating the first law of one ideal-gas
    zone with k = n1, V dp/dx = (k − 1)·f·dQ/dx − k·p·dV/dx, from p_a at the BDC (solve_ivp).
    The full-load heat release is the cycle's own, from its closed forms: none on the
    compression, V_c(p_z − p_c)/(k − 1) at the firing TDC, k/(k − 1)·p_z dV on the isobar and
    (k − n2)/(k − 1)·p_full dV on the expansion, p_full = p_z(V_z/V)^n2."""
    from scipy.integrate import solve_ivp

    k, n2, p_z = N1, CYCLE["n2"], CYCLE["p_z"]
    v_z = mc.v_z

    def dq(x):  # full-load dQ/dx (compression: 0)
        if x < 2 * math.pi:
            return 0.0
        if x < mc.angle_z:
            return k / (k - 1) * p_z * float(dvolume(x))
        return (k - n2) / (k - 1) * p_z * (v_z / float(volume(x))) ** n2 * float(dvolume(x))

    def rate(x, p):
        return [((k - 1) * f * dq(x) - k * p[0] * float(dvolume(x))) / float(volume(x))]

    out = np.empty(x_out.size)
    p0 = CYCLE["p_a"]
    for a, b, jump in ((math.pi, 2 * math.pi, True), (2 * math.pi, mc.angle_z, False),
                       (mc.angle_z, 3 * math.pi, False)):
        sel = (x_out > a) & (x_out < b)
        sol = solve_ivp(rate, (a, b), [p0], t_eval=np.sort(np.append(x_out[sel], b)),
                        method="DOP853", rtol=1e-12, atol=1e-6)
        out[sel] = sol.y[0][:-1]
        p0 = sol.y[0][-1]
        if jump:  # the isochoric heat f·Q_v at the TDC: Δp = (k − 1)·f·Q_v/V_c
            q_v = V_C * (p_z - p0) / (k - 1)
            p0 = p0 + (k - 1) * f * q_v / V_C
    return out


@pytest.mark.parametrize("f", [0.0, 0.3, 0.8, 1.0])
def test_part_load_is_the_cycle_burning_f_times_the_heat(cycles, f):
    """p_mot + f·(p_full − p_mot) from the two tables against the first law integrated with f
    times the heat at every angle (:func:`first_law_part_load`): to 1e-9 of p_z (the tables'
    interpolation); its peak p_c + f·(p_z − p_c) at the firing TDC; and the pressure along the
    heat addition to V = ρ·V_c falling from it (an isobar at f = 1 only)."""
    mc = cycles[1.671]
    x = np.linspace(math.pi, 3 * math.pi, 721)[1:-1]
    x = x[np.abs(x - 2 * math.pi) > 1e-9]
    table = mc.motored(x) + f * (mc(x) - mc.motored(x))
    ode = first_law_part_load(mc, f, x)
    err = np.max(np.abs(table - ode)) / CYCLE["p_z"]
    print(f"\nf = {f}: interpolated tables against the first law, {err:.1e} of p_z")
    assert err <= 1e-9
    peak = mc.motored(2 * math.pi) + f * (mc(2 * math.pi) - mc.motored(2 * math.pi))
    assert peak == pytest.approx(mc.p_c + f * (CYCLE["p_z"] - mc.p_c), rel=1e-12)
    along = (x > 2 * math.pi) & (x < mc.angle_z)
    assert np.all(table[along] <= peak * (1 + 1e-12))
    if 0.0 < f < 1.0:
        assert np.all(np.diff(table[along]) < 0.0)
