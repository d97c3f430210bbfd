"""Each cylinder's share of the reduced inertia at its own station's angle (``shares_kernel`` of
every mechanism, the elastic shaft line's per-station inertia, theory (T1)): against the whole
mechanism's J(φ), J′(φ), u_k, u′_k where every angle is the same, against finite differences
of itself, against a separately written crank-slider (:class:`transient.reference.torsion.
CrankSliderCylinders`), and local: a group of cylinders that move together (a cylinder, a row of
master and articulated rods, a swash plate's) takes its share from its own angle alone."""
from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest
from engines import inline_six_mech

from transient.assemble import kinematics_table
from transient.core.model import crank_slider, tabulated
from transient.reference.torsion import CrankSliderCylinders
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
#: One case per mechanism and layout: in-line, V with forked and side-by-side rods, radial rows,
#: swash plate, Scotch yoke.
SCENES = ("gots_diesel_4400", "v8_cross_plane", "v_twin_fork_blade", "radial_9cyl",
          "radial_5cyl", "swash_plate_4cyl", "scotch_yoke_compressor")
#: Rounding of sums of a handful of terms of J's size.
RTOL = 1e-13


def _groups(mech) -> list[list[int]]:
    """The cylinders that move together, by what each mechanism is: a crank-slider's or a Scotch
    yoke's cylinders each on their own throw, an articulated mechanism's rows of a master and
    its slaves, a swash plate's cylinders all on the plate."""
    n = mech.n_cylinders
    if mech.name == "swash-plate":
        return [list(range(n))]
    if mech.name == "articulated":
        per_row = n // mech.rows
        return [list(range(j * per_row, (j + 1) * per_row)) for j in range(mech.rows)]
    return [[k] for k in range(n)]


def _shares(kernel, mp, coef, angles, with_dJ=True):
    n = angles.size
    Jc, dJc, u, du = (np.zeros(n) for _ in range(4))
    kernel(mp, coef, angles, Jc, dJc, u, du, with_dJ)
    return Jc, dJc, u, du


def _whole(mech, coef, phi):
    n = mech.n_cylinders
    u, du = np.zeros(n), np.zeros(n)
    J, dJ = mech.kernel(mech.pack(), coef, phi, u, du, True)
    return J, dJ, u, du


@pytest.fixture(params=SCENES)
def mech(request):
    return load_scene(CASES / f"{request.param}.toml").mechanism


NO_TABLE = np.zeros((1, 1, 6))
ANGLES = np.linspace(0.0, 4.0 * np.pi, 23)[:-1] + 0.137


def test_the_shares_at_one_angle_add_up_to_the_whole_mechanism(mech):
    for phi in ANGLES:
        Jc, dJc, u, du = _shares(mech.shares_kernel, mech.pack(), NO_TABLE,
                                 np.full(mech.n_cylinders, phi))
        J, dJ, u_all, du_all = _whole(mech, NO_TABLE, phi)
        scale = abs(J)
        assert abs(Jc.sum() - J) <= RTOL * scale
        assert abs(dJc.sum() - dJ) <= RTOL * scale
        np.testing.assert_allclose(u, u_all, rtol=RTOL, atol=RTOL * np.abs(u_all).max())
        np.testing.assert_allclose(du, du_all, rtol=RTOL, atol=RTOL * np.abs(du_all).max())


def test_the_shares_without_their_derivatives_are_the_same_shares(mech):
    """What the derivative in crank angle asks for (``with_dJ`` False): J_c and u as with the
    derivatives, which the tests around check against the whole mechanism and a separate
    crank-slider."""
    rng = np.random.default_rng(5)
    for _ in range(5):
        angles = rng.uniform(-2 * np.pi, 6 * np.pi, mech.n_cylinders)
        Jc, _, u, _ = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles)
        Jc_only, _, u_only, _ = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles, False)
        np.testing.assert_allclose(Jc_only, Jc, rtol=RTOL, atol=RTOL * np.abs(Jc).max())
        np.testing.assert_allclose(u_only, u, rtol=RTOL, atol=RTOL * np.abs(u).max())


def test_a_turned_sine_and_cosine_are_those_of_the_sum():
    """crank_slider.turned against numpy's sine and cosine of a + d: d up to and past the
    polynomials' bound (NEAR), a up to a thousand turns, where the rounding of a + d itself
    (half an ulp of |a| + |d|) bounds the agreement."""
    rng = np.random.default_rng(13)
    near = crank_slider.NEAR
    d = np.concatenate([rng.uniform(-near, near, 200), [near, -near, np.nextafter(near, 1.0),
                                                        0.0, 1e-300, 0.5, -3.0, 40.0]])
    for a in (0.3, 7.1, 2.0e3, 6.0e3 + 0.77):
        for di in d:
            s, c = crank_slider.turned(np.sin(a), np.cos(a), di)
            tol = 4 * np.finfo(float).eps + np.spacing(abs(a) + abs(di))
            assert abs(s - np.sin(a + di)) <= tol
            assert abs(c - np.cos(a + di)) <= tol


def test_a_group_takes_its_share_from_its_own_angle_alone(mech):
    rng = np.random.default_rng(7)
    groups = _groups(mech)
    own = rng.uniform(0.0, 4.0 * np.pi, len(groups))
    angles = np.empty(mech.n_cylinders)
    for g, cyls in enumerate(groups):
        angles[cyls] = own[g]
    Jc, dJc, u, du = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles)
    for g, cyls in enumerate(groups):
        alone = _shares(mech.shares_kernel, mech.pack(), NO_TABLE,
                        np.full(mech.n_cylinders, own[g]))
        for got, want in zip((Jc, dJc, u, du), alone, strict=True):
            np.testing.assert_allclose(got[cyls], want[cyls], rtol=RTOL,
                                       atol=RTOL * np.abs(alone[0]).max())
        assert np.all(Jc[cyls[1:]] == 0.0)  # (the group's first cylinder takes its share)


def test_each_share_derivative_is_the_finite_difference_of_the_share(mech):
    h = 1e-5
    groups = _groups(mech)
    base = np.linspace(0.3, 11.0, len(groups))
    angles = np.concatenate([np.full(len(c), base[g]) for g, c in enumerate(groups)])
    Jc, dJc, _, _ = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles)
    up, _, _, _ = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles + h)
    down, _, _, _ = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles - h)
    # central difference: error ~ h²·J‴/6, J‴ ~ J·(orders)³ with orders ≲ 4 per radian
    np.testing.assert_allclose(dJc, (up - down) / (2 * h), rtol=0, atol=1e-7 * Jc.max())


def test_crank_slider_shares_against_a_separately_written_crank_slider():
    mech = inline_six_mech()
    other = CrankSliderCylinders(mech)
    rng = np.random.default_rng(11)
    for _ in range(20):
        angles = rng.uniform(-2 * np.pi, 6 * np.pi, mech.n_cylinders)
        Jc, dJc, u, _ = _shares(mech.shares_kernel, mech.pack(), NO_TABLE, angles)
        J_ref, dJ_ref = other.inertia(angles)
        scale = J_ref.max()
        np.testing.assert_allclose(Jc, J_ref, rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(dJc, dJ_ref, rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(u, other.piston_speeds(angles), rtol=0,
                                   atol=1e-13 * mech.crank_radius)


def test_tabulated_shares_are_the_tables_whole_on_one_station():
    scene = load_scene(CASES / "gots_diesel_4400.toml")
    scene = dc.replace(scene, solver=dc.replace(scene.solver, kinematics="tabulated"))
    coef = kinematics_table(scene).coef
    n = scene.mechanism.n_cylinders
    mp = scene.mechanism.pack()
    for phi in ANGLES:
        Jc, dJc, u, du = _shares(tabulated.shares, mp, coef, np.full(n, phi))
        u_all, du_all = np.zeros(n), np.zeros(n)
        J, dJ = tabulated.terms(mp, coef, phi, u_all, du_all, True)
        assert Jc[0] == J and dJc[0] == dJ and not Jc[1:].any() and not dJc[1:].any()
        assert np.array_equal(u, u_all) and np.array_equal(du, du_all)
