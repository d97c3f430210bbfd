"""Crank-slider kinematics and reduced inertia (Gots ch. 1, §2.2, §2.5).

Three independent checks of ``transient.core.model.crank_slider``:

* **finite differences** of the kernel's own outputs: s → ds → dds and β → dβ → ddβ of
  :func:`slider`, J → dJ of :func:`crank_slider_terms` and u = ds/dφ of every cylinder;
* **Gots' exact closed forms**: travel (1) (central) and (12) (offset), velocity v/ω =
  r sin(φ+β)/cos β (§2.2), acceleration j/ω² = r[cos(φ+β)/cos β + λ cos²φ/cos³β] (§2.3), the rod
  angle and its rates (7), (8), (17)–(19), stroke (11) and the TDC angle (9);
* **J(φ) = 2T/φ̇²** from the kinetic energy of the moving parts, with velocities taken as finite
  differences of *positions* (crankpin, piston pin, rod centre of mass, rod angle) written out here
  from the geometry, so the kernel's analytic derivatives are not used.

Finite differences: 4th-order central, h = 1e-5 rad. Truncation ~h⁴ f⁽⁵⁾/30 ≈ 1e-21 (negligible);
round-off ~1.5 ε |f|/h ≈ 3e-11 |f|; so the 1e-7 bound leaves a factor > 1000 for the worst case
(positions ~0.2 m differentiated to velocities ~0.05 m/rad). Errors are measured as
max |fd − analytic| / max |analytic| over a grid covering the cycle, because the derivatives cross
zero (a pointwise relative error is undefined there).
"""
from __future__ import annotations

import types
from dataclasses import replace
from math import asin, pi

import numpy as np
import pytest

from transient.core.model import crank_slider as core
from transient.mechanisms.crank_slider import CrankSlider

H = 1e-5
FD_RTOL = 1e-7  # see module docstring: round-off of the 4th-order stencil is ~3e-11 relative
# Closed forms against the kernel: both are exact, so they differ only by round-off of a few
# dozen operations on numbers of size ~r (≲ 1e-15 relative); 1e-12 leaves room for cancellation
# near the zeros of β′′ and j.
EXACT_RTOL = 1e-12
D4 = (np.array([-2.0, -1.0, 1.0, 2.0]), np.array([1.0, -8.0, 8.0, -1.0]) / 12.0)

# Angles over the whole 4-stroke cycle, with dead centres exactly on the grid and generic points.
ALPHA = np.concatenate([np.linspace(0.0, 4.0 * pi, 145), np.linspace(0.0123, 4.0 * pi, 97)])


def fd(f, x, h=H):
    """d f/dx at each x by the 4th-order central stencil; f maps a float to a float or tuple."""
    offsets, weights = D4
    vals = np.array([[np.atleast_1d(f(xi + h * o)) for o in offsets] for xi in x])
    return np.tensordot(weights, vals, axes=([0], [1])) / h  # (n, m)


def rel_err(approx, exact):
    approx, exact = np.asarray(approx), np.asarray(exact)
    return float(np.max(np.abs(approx - exact)) / np.max(np.abs(exact)))


def gots_mech(**changes) -> CrankSlider:
    """The Gots example cylinder (Gots §2.9, App. 1): r 47, L 148 mm, D 88 mm, two-mass rod
    0.275/0.725."""
    base = CrankSlider(crank_radius=0.047, rod_length=0.148, offset=0.0, bore=0.088,
                       piston_mass=1.520, crank_mass=0.912, rod_model="two-mass", rod_mass=1.752,
                       rod_cg_from_pin=0.725 * 0.148, rod_inertia_cg=0.0, strokes=4,
                       firing_angles=(0.0,), bank_angles=(0.0,))
    mech = replace(base, **changes)
    mech.validate()
    return mech


# (r, l, e): λ = 0.31757 (Gots), 1/4 and 1/2; offset e/r = 0.2 (and −0.2) at λ = 0.31757 and 0.5.
GEOMETRIES = {
    "gots": (0.047, 0.148, 0.0),
    "lam0.25": (0.05, 0.2, 0.0),
    "lam0.5": (0.05, 0.1, 0.0),
    "offset0.2": (0.047, 0.148, 0.2 * 0.047),
    "offset-0.2": (0.047, 0.148, -0.2 * 0.047),
    "offset0.2-lam0.5": (0.05, 0.1, 0.2 * 0.05),
}

# Mass and cylinder layouts: single cylinder two-mass / rigid, 3 cylinders (Gots firing 1-2-3,
# cranks 0/240/480° in a 4-stroke cycle), 4 cylinders 1-3-4-2 and a rigid-rod 4-cylinder 2-stroke.
RIGID = dict(rod_model="rigid", rod_inertia_cg=5e-3, rod_cg_from_pin=0.6 * 0.148)
LAYOUTS = {
    "1cyl-two-mass": {},
    "1cyl-rigid": RIGID,
    "1cyl-rigid-noI": dict(RIGID, rod_inertia_cg=0.0),
    "3cyl-two-mass": dict(firing_angles=tuple(np.radians([360.0, 600.0, 120.0])),
                          bank_angles=(0.0,) * 3),
    "4cyl-two-mass": dict(firing_angles=tuple(np.radians([0.0, 540.0, 180.0, 360.0])),
                          bank_angles=(0.0,) * 4),
    "4cyl-rigid-2stroke": dict(RIGID, strokes=2, firing_angles=tuple(np.radians([0, 90, 180, 270])),
                               bank_angles=(0.0,) * 4),
}


def geometry_mech(name, layout="1cyl-two-mass", **extra):
    r, l, e = GEOMETRIES[name]
    changes = dict(LAYOUTS[layout])
    if "rod_cg_from_pin" in changes:
        changes["rod_cg_from_pin"] = 0.6 * l
    else:
        changes["rod_cg_from_pin"] = 0.725 * l
    changes.update(extra)
    return gots_mech(crank_radius=r, rod_length=l, offset=e, **changes)


# ------------------------------------------------------------------------------------------------
# slider(): finite differences


@pytest.mark.parametrize("geom", list(GEOMETRIES))
def test_slider_derivatives_are_the_finite_differences(geom):
    r, l, e = GEOMETRIES[geom]
    out = np.array([core.slider(a, r, l, e) for a in ALPHA])
    s, ds, dds, beta, db, ddb = out.T
    d1 = fd(lambda a: core.slider(a, r, l, e), ALPHA)
    errs = {"s→ds": rel_err(d1[:, 0], ds), "ds→dds": rel_err(d1[:, 1], dds),
            "β→dβ": rel_err(d1[:, 3], db), "dβ→ddβ": rel_err(d1[:, 4], ddb)}
    assert max(errs.values()) <= FD_RTOL, errs


# ------------------------------------------------------------------------------------------------
# slider(): Gots closed forms


def gots_central(phi, r, lam):
    """Gots (1), (2), §2.2 exact v, §2.3 exact j, (7), (8) and ε_ш (§2.4) at ω = 1."""
    beta = np.arcsin(lam * np.sin(phi))
    cb = np.cos(beta)
    s = r * ((1.0 - np.cos(phi)) + (1.0 / lam) * (1.0 - cb))
    v = r * np.sin(phi + beta) / cb
    j = r * (np.cos(phi + beta) / cb + lam * np.cos(phi) ** 2 / cb**3)
    db = lam * np.cos(phi) / np.sqrt(1.0 - lam**2 * np.sin(phi) ** 2)
    ddb = -lam * (1.0 - lam**2) * np.sin(phi) / (1.0 - lam**2 * np.sin(phi) ** 2) ** 1.5
    return s, v, j, beta, db, ddb


def gots_offset(phi, r, lam, k):
    """Offset mechanism, Gots (12), (17), (18), (19); v and j as §2.2/§2.3 with the offset β.

    The exact v/ω = r sin(φ+β)/cos β and j/ω² = r[cos(φ+β)/cos β + λ cos²φ/cos³β] hold for the
    offset mechanism too: differentiating y = r cos φ + l cos β with sin β = λ(sin φ − k) gives
    β′ = λ cos φ/cos β exactly as in the central case, and the derivation of §2.3 uses only that.
    """
    x = np.sin(phi) - k
    beta = np.arcsin(lam * x)
    cb = np.cos(beta)
    s = r * (np.sqrt((1.0 / lam + 1.0) ** 2 - k**2) - (np.cos(phi) + (1.0 / lam) * cb))
    v = r * np.sin(phi + beta) / cb
    j = r * (np.cos(phi + beta) / cb + lam * np.cos(phi) ** 2 / cb**3)
    q = 1.0 - lam**2 * x**2
    db = lam * np.cos(phi) / np.sqrt(q)
    ddb = lam * (lam**2 * np.cos(phi) ** 2 * x - q * np.sin(phi)) / q**1.5
    return s, v, j, beta, db, ddb


@pytest.mark.parametrize("geom", list(GEOMETRIES))
def test_slider_matches_gots_exact_closed_forms(geom):
    r, l, e = GEOMETRIES[geom]
    lam, k = r / l, e / r
    got = np.array([core.slider(a, r, l, e) for a in ALPHA]).T
    want = gots_central(ALPHA, r, lam) if e == 0.0 else gots_offset(ALPHA, r, lam, k)
    names = ("s", "v/ω", "j/ω²", "β", "ω_ш/ω", "ε_ш/ω²")
    errs = {n: rel_err(g, w) for n, g, w in zip(names, got, want)}
    assert max(errs.values()) <= EXACT_RTOL, errs
    if e != 0.0:
        # Gots (12) with k = 0 is (1): the offset form must not be a different curve in disguise.
        central = gots_central(ALPHA, r, lam)[0]
        assert rel_err(got[0], central) > 1e-4


@pytest.mark.parametrize("geom", list(GEOMETRIES))
def test_tdc_bdc_and_stroke(geom):
    """TDC at sin φ₁ = λk/(1 + λ) (9) with s = 0, ds = 0; BDC where crank and rod line up,
    sin α = −e/(l − r) past π, with s = stroke (11); s stays within [0, stroke]."""
    r, l, e = GEOMETRIES[geom]
    lam, k = r / l, e / r
    mech = gots_mech(crank_radius=r, rod_length=l, offset=e, rod_cg_from_pin=0.725 * l)
    phi1 = asin(lam * k / (1.0 + lam))  # (9)
    stroke = r * (np.sqrt((1 / lam + 1) ** 2 - k**2) - np.sqrt((1 / lam - 1) ** 2 - k**2))  # (11)
    assert mech.tdc_angle() == pytest.approx(phi1, rel=1e-14, abs=1e-15)
    assert mech.stroke() == pytest.approx(stroke, rel=1e-14)
    s, ds, *_ = core.slider(phi1, r, l, e)
    assert abs(s) <= 1e-15 and abs(ds) <= 1e-14 * r
    a_bdc = pi + asin(e / (l - r))
    s, ds, *_ = core.slider(a_bdc, r, l, e)
    assert s == pytest.approx(stroke, rel=1e-14) and abs(ds) <= 1e-14 * r
    s_all = np.array([core.slider(a, r, l, e)[0] for a in ALPHA])
    assert s_all.min() >= -1e-15 and s_all.max() <= stroke * (1 + 1e-14)
    if e != 0.0:
        # The offset moves both dead centres off 0 and π (Gots §1.4): φ₁ ≠ 0.
        assert abs(core.slider(0.0, r, l, e)[1]) > 1e-3 * r


def test_book_offset_example():
    """Gots §1.4 example, λ = 1/3, k = 0.2: sin φ₁ = 0.05 (TDC), sin φ₂ = −0.1 (BDC, (10), the
    book prints its magnitude) and S = 2.005 r (11), printed to 3 decimals."""
    r, l = 0.05, 0.15
    e = 0.2 * r
    mech = gots_mech(crank_radius=r, rod_length=l, offset=e, rod_cg_from_pin=0.725 * l)
    assert np.sin(mech.tdc_angle()) == pytest.approx(0.05, rel=1e-12)
    s, ds, *_ = core.slider(np.arcsin(0.05), r, l, e)
    assert abs(s) <= 1e-15 and abs(ds) <= 1e-14 * r
    # BDC: crank and rod in line below the axis, local angle π − φ₂ with sin φ₂ = −0.1.
    s, ds, *_ = core.slider(pi - np.arcsin(-0.1), r, l, e)
    assert abs(ds) <= 1e-14 * r
    assert s / r == pytest.approx(2.005, abs=5e-4)
    assert mech.stroke() == pytest.approx(s, rel=1e-14)


# ------------------------------------------------------------------------------------------------
# crank_slider_terms(): dJ, u, du by finite differences; J from kinetic energy of positions


CASES = [("gots", "1cyl-two-mass"), ("gots", "1cyl-rigid"), ("lam0.5", "1cyl-rigid"),
         ("lam0.5", "1cyl-two-mass"), ("offset0.2", "1cyl-rigid"),
         ("offset0.2-lam0.5", "1cyl-rigid"), ("offset-0.2", "1cyl-rigid-noI"),
         ("gots", "3cyl-two-mass"), ("offset0.2", "3cyl-two-mass"), ("lam0.5", "4cyl-two-mass"),
         ("offset0.2", "4cyl-rigid-2stroke")]


def terms(mp, phi):
    n = int(mp[core.N_CYL])
    u, du = np.empty(n), np.empty(n)
    J, dJ = core.crank_slider_terms(mp, phi, u, du)
    return J, dJ, u.copy(), du.copy()


def kinetic_inertia(mech: CrankSlider, phi: np.ndarray) -> np.ndarray:
    """J(φ) = 2T/φ̇² from finite-difference velocities of positions (φ̇ = 1), per cylinder summed.

    Positions from the geometry (Gots Fig. 1, §1.4): crankpin A = r(sin α, cos α), piston pin
    B = (e, r cos α + l cos β) with sin β = (r sin α − e)/l, rod centre of mass G on AB at l₁ from
    B. Masses from the scene description, not from ``pack()``: piston at B; two-mass rod m₁ =
    m(l − l₁)/l at B and m₂ = m l₁/l at A (Gots (20)); rigid rod m at G with I_G β̇²; crank
    mass at A (reduced to radius r, Gots (28)).
    """
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    l1 = mech.rod_cg_from_pin

    def pos(a):
        beta = np.arcsin((r * np.sin(a) - e) / l)
        A = np.array([r * np.sin(a), r * np.cos(a)])
        B = np.array([e, r * np.cos(a) + l * np.cos(beta)])
        G = B + (l1 / l) * (A - B)
        return np.concatenate([A, B, G, [beta]])

    J = np.zeros_like(phi)
    for phase in mech.firing_angles:
        v = fd(pos, phi - phase)  # (n, 7): dA, dB, dG, dβ over dφ
        vA2 = v[:, 0] ** 2 + v[:, 1] ** 2
        vB2 = v[:, 2] ** 2 + v[:, 3] ** 2
        vG2 = v[:, 4] ** 2 + v[:, 5] ** 2
        J += (mech.piston_mass * vB2 + mech.crank_mass * vA2)
        if mech.rod_model == "two-mass":
            m1 = mech.rod_mass * (l - l1) / l
            m2 = mech.rod_mass * l1 / l
            J += m1 * vB2 + m2 * vA2
        else:
            J += mech.rod_mass * vG2 + mech.rod_inertia_cg * v[:, 6] ** 2
    return J


@pytest.mark.parametrize("geom,layout", CASES)
def test_reduced_inertia_is_twice_the_kinetic_energy(geom, layout):
    mech = geometry_mech(geom, layout)
    mp = mech.pack()
    J = np.array([terms(mp, p)[0] for p in ALPHA])
    J_kin = kinetic_inertia(mech, ALPHA)
    # J varies by tens of percent over the cycle: a missing or misplaced mass shows at ≥ 1e-3.
    assert rel_err(J, J_kin) <= FD_RTOL
    assert np.ptp(J) > 1e-2 * np.max(J)


@pytest.mark.parametrize("geom,layout", CASES)
def test_dJ_u_du_are_the_finite_differences(geom, layout):
    mech = geometry_mech(geom, layout)
    mp = mech.pack()
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    out = [terms(mp, p) for p in ALPHA]
    J = np.array([o[0] for o in out])
    dJ = np.array([o[1] for o in out])
    u = np.array([o[2] for o in out])
    du = np.array([o[3] for o in out])
    assert rel_err(fd(lambda p: terms(mp, p)[0], ALPHA)[:, 0], dJ) <= FD_RTOL
    assert rel_err(fd(lambda p: terms(mp, p)[2], ALPHA), du) <= FD_RTOL
    for k, phase in enumerate(mech.firing_angles):
        # u_k = ds_k/dφ of cylinder k's own piston travel at local angle φ − phase_k.
        s_k = lambda p, phase=phase: core.slider(p - phase, r, l, e)[0]
        assert rel_err(fd(s_k, ALPHA)[:, 0], u[:, k]) <= FD_RTOL
    assert np.all(J > 0)


def test_multi_cylinder_is_the_sum_of_single_cylinders():
    """J, dJ of 3 cylinders = Σ of one-cylinder kernels shifted by their phases (no cross terms)."""
    mech = geometry_mech("offset0.2", "3cyl-two-mass")
    mp = mech.pack()
    for p in ALPHA:
        J, dJ, u, du = terms(mp, p)
        parts = [terms(replace(mech, firing_angles=(a,), bank_angles=(0.0,)).pack(), p)
                 for a in mech.firing_angles]
        assert J == pytest.approx(sum(q[0] for q in parts), rel=1e-14)
        assert dJ == pytest.approx(sum(q[1] for q in parts), rel=1e-12, abs=1e-14)
        np.testing.assert_allclose(u, [q[2][0] for q in parts], rtol=0, atol=1e-16)


def test_two_mass_rod_equals_rigid_rod_with_the_two_mass_inertia():
    """Gots (20)–(21): a rigid rod of mass m, centre l₁ from the pin, with I_G = m l₁(l − l₁)
    (so that I about G equals that of the two masses) has exactly the two-mass model's J(φ)."""
    l = 0.148
    l1 = 0.725 * l
    two = geometry_mech("offset0.2")
    rigid = replace(two, rod_model="rigid", rod_inertia_cg=two.rod_mass * l1 * (l - l1))
    for p in ALPHA:
        a, b = terms(two.pack(), p), terms(rigid.pack(), p)
        assert a[0] == pytest.approx(b[0], rel=1e-13)
        assert a[1] == pytest.approx(b[1], rel=1e-10, abs=1e-13 * abs(a[0]))


# ------------------------------------------------------------------------------------------------
# Kernels against their pure-Python twins (.py_func)


def pure_python_twins():
    """``slider``, ``cylinder_terms`` and ``crank_slider_terms`` as plain CPython functions.

    ``.py_func`` alone would still call the *compiled* helpers it names, so each twin is rebuilt
    with its globals pointing at the other twins: the whole chain runs without numba.
    """
    glob = dict(core.crank_slider_terms.py_func.__globals__)
    twins = {}
    for name in ("slider", "rod_and_piston", "rod_and_piston_second",
                 "cylinder_terms", "cylinder_terms_sc", "crank_slider_terms"):
        fn = getattr(core, name).py_func
        twins[name] = types.FunctionType(fn.__code__, glob, name, fn.__defaults__, fn.__closure__)
    glob.update(twins)
    return twins


@pytest.mark.parametrize("geom,layout", CASES)
def test_kernels_equal_their_py_func_twins(geom, layout):
    """Same source run by numba and by CPython. numba's sin/cos/sqrt/asin may differ from CPython's
    libm by an ulp, amplified by a few operations: 1e-13 relative to the largest value."""
    mech = geometry_mech(geom, layout)
    mp = mech.pack()
    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    n = mech.n_cylinders
    twin = pure_python_twins()
    for p in ALPHA:
        a = np.array(core.slider(p, r, l, e))
        b = np.array(twin["slider"](p, r, l, e))
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * np.max(np.abs(b)))
        a = np.array(core.cylinder_terms(p, mp))
        b = np.array(twin["cylinder_terms"](p, mp))
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * np.max(np.abs(b)))
        u1, du1, u2, du2 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        J1, dJ1 = core.crank_slider_terms(mp, p, u1, du1)
        J2, dJ2 = twin["crank_slider_terms"](mp, p, u2, du2)
        assert J1 == pytest.approx(J2, rel=1e-13)
        assert dJ1 == pytest.approx(dJ2, rel=0, abs=1e-13 * J2)
        np.testing.assert_allclose(u1, u2, rtol=0, atol=1e-13 * r)
        np.testing.assert_allclose(du1, du2, rtol=0, atol=1e-13 * r)


@pytest.mark.parametrize("geom,layout", CASES)
def test_terms_without_dJ_are_the_same_J_and_u(geom, layout):
    """``with_dJ=False`` (the crank-angle right-hand side without pairs) skips the second
    derivatives: J and u to the last bit of the full evaluation, dJ and du NaN, never stale."""
    mech = geometry_mech(geom, layout)
    mp = mech.pack()
    n = mech.n_cylinders
    for p in ALPHA:
        u1, du1, u2, du2 = np.empty(n), np.empty(n), np.zeros(n), np.zeros(n)
        J1, _ = core.crank_slider_terms(mp, p, u1, du1, True)
        J2, dJ2 = core.crank_slider_terms(mp, p, u2, du2, False)
        assert J2 == J1
        np.testing.assert_array_equal(u2, u1)
        assert np.isnan(dJ2) and np.isnan(du2).all()


@pytest.mark.parametrize("turns", [0, 1000, 100000])
def test_cylinder_angles_by_rotation_are_the_local_angles(turns):
    """crank_slider_terms rotates sin φ, cos φ by each cylinder's phase instead of evaluating
    sin, cos of φ − phase_k: the same J_k, dJ_k, u_k, du_k as :func:`cylinder_terms` at the
    local angle, to 1e-13 of the largest value plus what φ's own rounding (8 ulp of φ, as an
    angle) makes of them; also 10⁵ turns into a run."""
    mech = geometry_mech("offset0.2", "3cyl-two-mass")
    mp = mech.pack()
    r = mech.crank_radius
    for p in ALPHA + 2.0 * np.pi * turns:
        J, dJ, u, du = terms(mp, p)
        parts = np.array([core.cylinder_terms(p - a, mp) for a in mech.firing_angles])
        slack = 1e-13 + 8.0 * np.spacing(p)
        assert J == pytest.approx(parts[:, 0].sum(), rel=0, abs=slack * J)
        assert dJ == pytest.approx(parts[:, 1].sum(), rel=0, abs=slack * J)
        np.testing.assert_allclose(u, parts[:, 2], rtol=0, atol=slack * r)
        np.testing.assert_allclose(du, parts[:, 3], rtol=0, atol=slack * r)
