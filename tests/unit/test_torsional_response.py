"""The steady forced response of the shaft line (:mod:`transient.analysis.torsional_response`),
each result against something independent: the two-mass closed form (undamped and damped),
openTorsion's harmonic response and vibratory torque of the same shaft, the orders of each
cylinder's torque by scipy's adaptive quadrature of the Fourier integral on the reference
path's separately written crank-slider (:class:`transient.reference.torsion.CrankSliderCylinders`),
and the synthesised signal against the linear equations integrated in the time domain."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate
from scene_texts import MIXED_CYCLE, SMALL

from transient.analysis.torsion import engine_orders
from transient.analysis.torsional_response import (
    excitation,
    forced_response,
    peak_to_peak,
    synthesise,
)
from transient.errors import SceneError
from transient.reference.torsion import CrankSliderCylinders
from transient.scene import load_scene
from transient.scene.queries import gas_table
from transient.shaft import ShaftLine

CASES = Path(__file__).resolve().parents[2] / "cases"
INLINE6 = load_scene(CASES / "inline6_damper.toml")
RPM = 30.0 / math.pi


def small_line(shaft_toml: str) -> str:
    """SMALL (one cylinder, four-stroke) with the mixed cycle, no [inertia], and
    ``shaft_toml``."""
    text = SMALL.replace("[inertia]\nshaft = 0.02\n", "").replace(
        'type = "crank-slider"\n', 'type = "crank-slider"\nstrokes = 4\n')
    return text + MIXED_CYCLE.format(cr=18) + shaft_toml


def two_masses(damping: float) -> str:
    return small_line(f"""
[[shaft.stations]]
name = "throw"
inertia = 0.01
cylinders = [1]
[[shaft.stations]]
name = "flywheel"
inertia = 0.3
[[shaft.sections]]
stiffness = 2e5
damping = {damping!r}
""")


#: A smooth combustion pulse as a pressure table (spline through samples every 5° of a
#: Gaussian of 6 MPa at 370°, 25° wide): its orders fall off fast, so that the orders up to
#: 60 hold the time signal to far below the time-domain test's tolerance (the mixed cycle's
#: pressure steps where the piston moves, whose orders fall off only as 1/q).
PULSE_DEG = np.arange(0.0, 725.0, 5.0)
PULSE_BAR = 1.0 + 60.0 * np.exp(-0.5 * ((PULSE_DEG - 370.0) / 25.0) ** 2)
PULSE_GAS = f"""
[gas]
model = "table"
interpolation = "spline"
phi_deg = {PULSE_DEG.tolist()}
p_bar = {PULSE_BAR.tolist()}
"""

#: Three stations with strong damping, so that the time-domain run settles in a few cycles.
THREE = SMALL.replace("[inertia]\nshaft = 0.02\n", "").replace(
    'type = "crank-slider"\n', 'type = "crank-slider"\nstrokes = 4\n') + PULSE_GAS + """
[[shaft.stations]]
name = "front"
inertia = 0.01
damping = 2.0
[[shaft.stations]]
name = "throw"
inertia = 0.005
damping = 2.0
cylinders = [1]
[[shaft.stations]]
name = "flywheel"
inertia = 0.05
damping = 5.0
[[shaft.sections]]
stiffness = 2e4
damping_ratio = 0.05
[[shaft.sections]]
stiffness = 3e4
damping_ratio = 0.05
"""


# -- closed forms ---------------------------------------------------------------------------

@pytest.mark.parametrize("damping", [0.0, 6.0], ids=["undamped", "damped"])
def test_two_masses_against_the_closed_form(damping):
    """A free pair J1, J2 joined by k, c under a torque T on J1 at ω: the section carries
    T·J2 (k + iωc) / ((J1 + J2)(k + iωc) − ω² J1 J2) (eliminating the two equations by hand);
    undamped, T·(J2/(J1 + J2))/(1 − ω²/ω_n²) with ω_n² = k (J1 + J2)/(J1 J2)."""
    line = ShaftLine(load_scene("two.toml", text=two_masses(damping)))
    J1, J2 = line.mean_inertia()
    k = 2e5
    omega = np.array([700.0, 2100.0, 3900.0]) / RPM
    res = forced_response(line, omega)
    w = res.orders[None, :] * omega[:, None]
    T = res.force[:, :, 0]
    assert np.all(res.force[:, :, 1] == 0.0)  # (the flywheel carries no cylinder)
    z = k + 1j * w * damping
    expected = T * J2 * z / ((J1 + J2) * z - w * w * J1 * J2)
    assert res.torque[:, :, 0] == pytest.approx(expected, rel=1e-11)
    if damping == 0.0:
        wn2 = k * (J1 + J2) / (J1 * J2)
        assert res.torque[:, :, 0] == pytest.approx(T * J2 / (J1 + J2) / (1 - w * w / wn2),
                                                    rel=1e-11)
        assert np.all(res.power == 0.0)
    else:  # ½ ω² c |δ|², δ = T_section/(k + iωc)
        assert res.power[:, :, 0] == pytest.approx(0.5 * w * w * damping
                                                   * np.abs(expected / z) ** 2, rel=1e-11)


# -- openTorsion ----------------------------------------------------------------------------

def test_friswell_line_against_opentorsions_vibratory_torque():
    """Friswell's Ex. 9.7.1 chain with the cylinder on its fourth disc and damping in every
    section, through openTorsion's assembly, PeriodicExcitation and vibratory_torque (which
    gives k·twist, the whole torque of undamped sections, the elastic part of damped ones:
    compared with k·twist) with our excitation. (Not absolute damping: openTorsion's acts
    against the frame, transient's against the line's rigid-body motion.)"""
    ot = pytest.importorskip("opentorsion")
    inertia, stiffness = (3.5e-3, 3.5e-3, 3.5e-3, 0.15, 0.05), (12e3, 12e3, 14e3, 10e3)
    stations = "".join(
        f'[[shaft.stations]]\nname = "disc {i + 1}"\ninertia = {J!r}\n'
        + ("cylinders = [1]\n" if i == 3 else "") for i, J in enumerate(inertia))
    sections = "".join(f"[[shaft.sections]]\nstiffness = {k!r}\ndamping = 0.3\n"
                       for k in stiffness)
    line = ShaftLine(load_scene("friswell.toml", text=small_line("\n" + stations + sections)))
    M = line.mean_inertia()
    omega = np.array([600.0, 1400.0, 2500.0, 4000.0]) / RPM
    res = forced_response(line, omega)
    assembly = ot.Assembly([ot.Shaft(i, i + 1, 0, 0, k=k, c=0.3)
                            for i, k in enumerate(stiffness)],
                           disk_elements=[ot.Disk(i, J) for i, J in enumerate(M)])
    assert assembly.C == pytest.approx(line.C, rel=1e-15)
    k = np.array(stiffness)
    for i, w0 in enumerate(omega):
        excite = ot.PeriodicExcitation(line.n, res.orders * w0)
        for dof in range(line.n):
            F = res.force[i, :, dof]
            excite.add_sines(dof, res.orders * w0, np.abs(F), np.angle(F))
        theirs, _ = assembly.vibratory_torque(excite)
        elastic = k * (res.angle[i][:, :-1] - res.angle[i][:, 1:])
        assert elastic.T == pytest.approx(theirs, rel=1e-9)


def test_the_cases_line_against_opentorsions_harmonic_response():
    """The inline six (damper ring, section damping by loss factor and damping ratio)
    through openTorsion's elements and ss_response; the sections' torques (k + iωc)·twist
    from its own S and D matrices. Its chain is numbered ring, pulley, throws, flywheel: a
    ring hanging off a station is a chain there."""
    ot = pytest.importorskip("opentorsion")
    # (without the throws' absolute damping: openTorsion's acts against the frame)
    line = ShaftLine(load_scene("inline6.toml", text=INLINE6.source_text.replace(
        "damping = 0.5\n", "")))
    order = [1, 0, *range(2, line.n)]  # openTorsion's node i is our dof order[i]
    M = line.mean_inertia()[order]
    C = line.C[np.ix_(order, order)]
    shafts = [ot.Shaft(i, i + 1, 0, 0, k=-line.K[order[i], order[i + 1]],
                       c=-line.C[order[i], order[i + 1]]) for i in range(line.n - 1)]
    absolute = C.diagonal() + C.sum(axis=1) - C.diagonal()  # (each row's sum: to the frame)
    disks = [ot.Disk(i, J, c=float(absolute[i])) for i, J in enumerate(M)]
    assembly = ot.Assembly(shafts, disk_elements=disks)
    assert assembly.C == pytest.approx(C, rel=1e-12, abs=1e-12)
    assert assembly.K == pytest.approx(line.K[np.ix_(order, order)], rel=1e-15)
    S, D, _ = assembly.transform_matrices()
    omega = np.array([900.0, 2000.0, 2650.0, 3600.0]) / RPM
    res = forced_response(line, omega)
    for i, w0 in enumerate(omega):
        w = res.orders * w0
        q, _ = assembly.ss_response(res.force[i][:, order].T, w)
        assert res.angle[i][:, order].T == pytest.approx(q, rel=1e-9)
        sections = S @ q + 1j * w * (D @ q)  # (the ring's element has no stiffness: not in S)
        # (at a low order the line turns nearly rigidly, and a twist is a small difference of
        # large angles: each order's torques to 1e-9 of its largest)
        error = np.abs(res.torque[i][:, :7].T - sections)
        assert np.all(error <= 1e-9 * np.max(np.abs(sections), axis=0))


# -- the excitation -------------------------------------------------------------------------

class ReferenceTorques:
    """Each cylinder's gas torque and −½ J′_c (times ω², the inertia torque) at a shaft angle,
    from the reference path's crank-slider, the gas table read at the angle from firing TDC
    (+2π in the four-stroke table, whose 0 is the gas-exchange TDC)."""

    def __init__(self, scene) -> None:
        table, p0 = gas_table(scene), scene.gas.p0
        self.cyl = CrankSliderCylinders(scene.mechanism,
                                        lambda x: table(x + 2.0 * math.pi) - p0)
        self.n = scene.mechanism.n_cylinders

    def __call__(self, phi: float) -> tuple[np.ndarray, np.ndarray]:
        angles = np.full(self.n, phi)
        return self.cyl.moments(angles, angles, 0.0), -0.5 * self.cyl.inertia(angles)[1]


def fourier(f, cycle: float, order: float, corners, epsabs: float) -> complex:
    """(2/Θ) ∫₀^Θ f(φ) e^{−iqφ} dφ by scipy's adaptive quadrature, split at ``corners``, to
    1e-11 relative or ``epsabs`` on each piece."""
    edges = np.unique(np.concatenate([[0.0, cycle], np.mod(corners, cycle)]))
    total = 0.0 + 0.0j
    for a, b in zip(edges[:-1], edges[1:]):
        for part, fn in ((1.0, np.cos), (-1j, np.sin)):
            value, _ = scipy.integrate.quad(lambda x, fn=fn: f(x) * fn(order * x), a, b,
                                            epsabs=epsabs, epsrel=1e-11, limit=200)
            total += part * value
    return 2.0 / cycle * total


def test_each_cylinders_orders_against_quadrature_of_the_fourier_integral():
    """Cylinders 1 and 4 of the six and the inertia torque of throw 1, several orders, against
    scipy's quad on the reference crank-slider (its moments positive in the sense of
    rotation): the amplitudes, their phases and their sign."""
    scene = INLINE6
    mech = scene.mechanism
    orders = np.array([0.5, 1.0, 3.0, 4.5, 6.0, 11.5])
    exc = excitation(ShaftLine(scene), orders)
    corners = np.add.outer(np.asarray(mech.firing_angles) - 2.0 * math.pi,
                           gas_table(scene).corners).ravel()
    torques = ReferenceTorques(scene)
    for c in (0, 3):
        scale = np.max(np.abs(exc.gas[c]))
        for j, q in enumerate(orders):
            theirs = fourier(lambda x, c=c: torques(x)[0][c], mech.cycle, q, corners, 1e-10)
            assert abs(exc.gas[c, j] - theirs) <= 1e-9 * scale
    # the inertia torque of throw 1's station (its one cylinder), even orders of the turn only
    line = ShaftLine(scene)
    s = 1
    for j, q in enumerate(orders):
        theirs = fourier(lambda x: torques(x)[1][0], mech.cycle, q, [], 1e-14)
        assert abs(exc.inertia[s, j] - theirs) <= 1e-10 * np.max(np.abs(exc.inertia[s]))
    assert line.shaft.stations[s].cylinders == (1,)


def test_the_phase_convention_each_cylinder_at_its_firing_angle():
    """Identical cylinders: T_c(φ) = T_1(φ − (φ_c − φ_1)), so T̂_c,q = T̂_1,q e^{−iq(φ_c − φ_1)};
    the major orders of the six add in phase. (The sign, positive in the sense of rotation,
    is the reference path's, which the quadrature test holds the amplitudes to.)"""
    exc = excitation(ShaftLine(INLINE6))
    firing = np.asarray(INLINE6.mechanism.firing_angles)
    for c in range(1, 6):
        shift = np.exp(-1j * exc.orders * (firing[c] - firing[0]))
        assert exc.gas[c] == pytest.approx(exc.gas[0] * shift, rel=1e-9, abs=1e-9)
    # the major orders (3, 6, 9, 12) add in phase: Σ_c T̂_c = 6 T̂_1 e^{−iqφ_1}
    major = [j for j, q in enumerate(exc.orders) if q % 3 == 0]
    total = exc.gas[:, major].sum(axis=0)
    assert total == pytest.approx(6 * exc.gas[0, major], rel=1e-9)


def test_per_cylinder_factors_and_refusals():
    text = (CASES / "inline6_damper.toml").read_text()
    base = excitation(ShaftLine(INLINE6))
    varied = load_scene("v.toml", text=text + "\n[[gas.cylinders]]\ncylinder = 2\n"
                                              "pressure = 0.5\n")
    exc = excitation(ShaftLine(varied))
    assert exc.gas[1] == pytest.approx(0.5 * base.gas[1], rel=1e-12)
    assert exc.gas[0] == pytest.approx(base.gas[0], rel=1e-15)
    misfire = load_scene("m.toml", text=text + "\n[[gas.cylinders]]\ncylinder = 3\n"
                                               "misfire_every = 10\n")
    with pytest.raises(SceneError) as err:
        excitation(ShaftLine(misfire))
    assert err.value.key == "gas.cylinders[0].misfire_every"
    with pytest.raises(ValueError, match="order 0.25"):
        excitation(ShaftLine(INLINE6), [0.25])
    with pytest.raises(ValueError, match="mean speeds > 0"):
        forced_response(ShaftLine(INLINE6), [0.0, 100.0])


# -- synthesis ------------------------------------------------------------------------------

def test_peak_to_peak_of_a_known_signal():
    """cos ψ + ½ cos 2ψ has its maximum 3/2 at 0 and its minimum −3/4 at cos ψ = −½
    (derivative −sin ψ (1 + 2 cos ψ) = 0, cos 2ψ = 2cos²ψ − 1): 9/4; again with a phase that
    moves the extremes off the grid, where Newton's refinement finds them."""
    A = np.array([[[1.0], [0.5]]], dtype=complex)
    assert peak_to_peak(A, [1, 2])[0, 0] == pytest.approx(2.25, rel=1e-13)
    shifted = A * np.exp(-1j * np.array([1, 2]) * 0.123)[None, :, None]
    assert peak_to_peak(shifted, [1, 2])[0, 0] == pytest.approx(2.25, rel=1e-13)


def test_the_synthesised_torque_against_the_time_domain():
    """M ẍ + C ẋ + K x = F(t) integrated by scipy (DOP853) from rest to the steady state at
    one speed, F(t) written again here from the reference crank-slider (the smooth pulse's gas
    torque and −½J′Ω², each dof's mean taken out, which only twists the line statically)
    on a soft, well damped line that settles within a few cycles; each section's torque
    k δ + c δ̇ over the last cycle against the synthesis of its orders (up to 60, beyond which
    what is left is below the tolerance)."""
    scene = load_scene("three.toml", text=THREE)
    line = ShaftLine(scene)
    mech = scene.mechanism
    omega = 2400.0 / RPM
    orders = engine_orders(mech.cycle, 60.0)
    res = forced_response(line, [omega], orders)

    torques = ReferenceTorques(scene)

    def station_force(phi: float) -> np.ndarray:
        gas, inertia = torques(phi)
        out = np.zeros(line.n)
        out[1] = gas[0] + omega ** 2 * inertia[0]
        return out
    corners = gas_table(scene).corners - 2.0 * math.pi
    mean = fourier(lambda x: station_force(x)[1], mech.cycle, 0.0, corners, 1e-10).real / 2.0
    M, K, C = line.mean_inertia(), line.K, line.C

    def rhs(t, y):
        x, v = y[:line.n], y[line.n:]
        F = station_force(omega * t)
        F[1] -= mean
        return np.concatenate([v, (F - C @ v - K @ x) / M])
    period = mech.cycle / omega
    cycles = 8
    t_eval = np.linspace((cycles - 1) * period, cycles * period, 1441)
    sol = scipy.integrate.solve_ivp(rhs, (0.0, cycles * period), np.zeros(2 * line.n),
                                    method="DOP853", rtol=1e-11, atol=1e-14, t_eval=t_eval)
    assert sol.success
    x, v = sol.y[:line.n], sol.y[line.n:]
    harmonics = orders * mech.cycle / (2.0 * math.pi)
    psi = 2.0 * math.pi * np.mod(omega * t_eval, mech.cycle) / mech.cycle
    rows = line.element_rows()
    for e, (a, b) in enumerate(res.element_dofs):
        k, c = rows[e, 2], rows[e, 3]
        direct = k * (x[a] - x[b]) + c * (v[a] - v[b])
        ours = synthesise(res.torque[0, :, e], harmonics, psi)
        scale = np.ptp(direct)
        assert np.max(np.abs(ours - direct)) <= 1e-6 * scale
        # (1441 samples of the cycle miss the extremes by less than that)
        assert res.torque_pp[0, e] == pytest.approx(scale, rel=1e-3)
        assert res.torque_pp[0, e] <= 2.0 * res.torque_sum[0, e]
