"""Semenov (1947), master and articulated rods: the worked example of §4 (fig. 19).

M. V. Semenov, *Кинематический анализ механизмов авиационных двигателей* (Kinematic analysis
of aircraft engine mechanisms), LKVVIA, Leningrad, 1947. Its dimensions: r = 95, l = 313,
r_i = 75, l_i = 238 mm (r_i + l_i = l, eq. (5) at δ = 0° and 180°); λ = r/l, printed 0.304.
The text prints λᵢ at δᵢ = 0° and 180° (with an errata slip: "90°" is 0°) and the ratio of
the largest slave to master accelerations; everything else it gives as formulas. Where a test
needs a number the text does not print, it is an *independent* computation from the exact
geometry (an FFT of the positions written in plain numpy, made for the tests), named as such.

Misprints found: the ratio max|W_Bi|/max|W_B| at δᵢ = 180° is printed 1.27, but the text's own
λᵢ gives (1 + 0.686)/(1 + 0.304) = 1.293 and the exact geometry 1.2935; the 3rd-harmonic
coefficients n₃, m₃ of (43) leave out the −⅛ sin⁴β_i term of the same order, so (45)
underestimates Rickert's 3rd harmonic (ψᵢ ≠ δᵢ) by about a factor of three.
"""
from __future__ import annotations

import math

import numpy as np

from transient.analysis.loads.crank_slider import slider_arrays
from transient.analysis.orders import order_spectrum, piston_acceleration
from transient.core.model.articulated import articulated_terms
from transient.mechanisms import articulated as art

from . import Comparison, Tolerance, case

R, L, RI, LI = 0.095, 0.313, 0.075, 0.238
LAM = R / L
BOOK = "Semenov §4, fig. 19"


def radial(banks_deg, psi_deg=None, **changes) -> art.Articulated:
    """Semenov's master and slaves at ``banks_deg`` (link angles ψᵢ = δᵢ unless given), with
    masses for a complete mechanism (the kinematics do not depend on them)."""
    banks = tuple(np.radians(banks_deg))
    psi = banks if psi_deg is None else tuple(np.radians(psi_deg))
    n = len(banks)
    base = dict(crank_radius=R, rod_length=L, bore=0.146, piston_mass=2.18, crank_mass=2.0,
                rod_model="rigid", rod_mass=6.7, rod_cg_from_pin=0.235, rod_inertia_cg=0.06,
                slave_banks=banks, link_angles=psi, link_radii=(RI,) * n, slave_lengths=(LI,) * n,
                slave_rod_model="rigid", slave_rod_mass=1.34, slave_rod_cg_from_pin=0.131,
                slave_rod_inertia_cg=5e-3)
    base.update(changes)
    return art.Articulated(**base)


def kernel_du(mech, phi):
    """u′_k of the compiled kernel at φ."""
    n = mech.n_cylinders
    u, du = np.empty(n), np.empty(n)
    articulated_terms(mech.pack(), phi, u, du)
    return du


#: The five-cylinder radial of the example: slaves at 72°, 144°, 216°, 288°.
FIVE = (72, 144, 216, 288)


@case("unit/test_articulated.py::test_master_piston_dead_centre_accelerations_and_stroke")
def master_dead_centres():
    """(25) is exact to all orders: the series' λ³, λ⁵ terms cancel at the dead centres."""
    mech = radial(FIVE)
    X, _, ddX = art.axial_positions(mech, np.array([0.0, math.pi]))
    exact = Tolerance(rel=1e-13, why="rounding")
    return [
        Comparison("master piston acceleration at TDC, W/ω²", "Semenov (25): −r(1 + λ)",
                   "formula", -R * (1 + LAM), ddX[0, 0], "m",
                   Tolerance(rel=1e-14, why="rounding")),
        Comparison("master piston acceleration at BDC, W/ω²", "Semenov (25): r(1 − λ)",
                   "formula", R * (1 - LAM), ddX[1, 0], "m", exact),
        Comparison("master stroke X(0) − X(π)", "Semenov (20): 2r", "formula", 2 * R,
                   X[0, 0] - X[1, 0], "m", Tolerance(rel=1e-14, why="rounding")),
        Comparison("master stroke of the dead-centre search", "Semenov (20): 2r", "formula",
                   2 * R, float(art.piston_strokes(mech)[0]), "m",
                   Tolerance(rel=1e-14, why="rounding")),
        Comparison("kernel's u′ of the master at TDC", "Semenov (25): r(1 + λ)", "formula",
                   R * (1 + LAM), float(kernel_du(mech, 0.0)[0]), "m",
                   Tolerance(rel=1e-14, why="rounding")),
    ]


@case("unit/test_articulated.py::test_slave_stroke_is_2r_at_0_and_180_deg_and_longer_elsewhere")
def slave_strokes():
    """With r_i + l_i = l the slaves at δ = 0° and 180° (ψ = δ) have the stroke 2r exactly; at
    72° and 144° it is longer (Semenov's true stroke (58), no number printed)."""
    at_ends = art.piston_strokes(radial([0, 180]))
    excess = art.piston_strokes(radial([72, 144]))[1:] - 2 * R
    return [
        Comparison("strokes of the master and the slaves at δ = 0°, 180°",
                   "Semenov (5), (20): 2r", "formula", np.full(3, 2 * R), at_ends, "m",
                   Tolerance(rel=1e-13, why="rounding")),
        Comparison("slave stroke beyond 2r at δ = 72°, 144°", "exact geometry (the text gives "
                   "the method (55)–(58), no number)", "independent",
                   np.array([0.393651, 1.435197]), excess * 1e3, "mm",
                   Tolerance(rel=1e-5, why="the digits of the independent values"),
                   at=np.array([72.0, 144.0]), at_name="δᵢ [°]"),
    ]


@case("unit/test_articulated.py::test_slave_dead_centres_are_roots_of_the_velocity")
def slave_dead_centres():
    """(55)–(57) solved exactly: the velocity vanishes at both dead centres, and the TDC lies a
    few degrees after δᵢ, symmetric for δ ↦ 360° − δ."""
    mech = radial(FIVE)
    tdc, bdc = art.dead_centres(mech)
    speed = max(float(np.max(np.abs(np.diag(art.axial_positions(mech, a)[1]))))
                for a in (tdc, bdc))
    lag = np.degrees(tdc[1:]) - np.array(FIVE)
    return [
        Comparison("piston velocity at the dead centres, |dX/dφ|", "Semenov (55)–(57): zero",
                   "formula", None, speed, "m", Tolerance(high=1e-12 * R,
                                                          why="rounding (10⁻¹² r)")),
        Comparison("slave TDC after its bank angle δᵢ", "exact geometry (not in the text)",
                   "independent", np.array([2.8102, 3.6714, -3.6714, -2.8102]), lag, "°",
                   Tolerance(abs=1e-4, why="the digits of the independent values"),
                   at=np.array(FIVE, float), at_name="δᵢ [°]"),
    ]


@case("unit/test_articulated.py::test_psi_equal_delta_has_no_odd_harmonics_above_the_first")
def no_third_harmonic():
    """(46)–(47): with ψᵢ = δᵢ, p_i = 0 and "the 3rd-order harmonics are absent"; exactly, no
    odd order ≥ 3 at all, and the first harmonic is r cos(φ − δᵢ)."""
    hs = art.harmonics(radial([40, 72, 144, 200, 288]), orders=9)
    odd = max(float(np.hypot(*h.exact[0][3::2].T).max() / math.hypot(*h.exact[0][1]))
              for h in hs)
    first = np.array([math.hypot(*h.exact[0][1]) for h in hs])
    banks = np.array([40.0, 72.0, 144.0, 200.0, 288.0])
    return [
        Comparison("slave displacement, odd orders 3…9 over the first", "Semenov (46): absent",
                   "formula", None, odd, "", Tolerance(high=1e-12, why="rounding")),
        Comparison("slave displacement, first-order amplitude", "Semenov (47), (59): r",
                   "formula", np.full(5, R), first, "m", Tolerance(rel=1e-13, why="rounding"),
                   at=banks, at_name="δᵢ [°]"),
    ]


@case("unit/test_articulated.py::test_psi_unequal_delta_has_a_third_harmonic_beside_semenov")
def rickert_third_harmonic():
    """Rickert's case ψᵢ ≠ δᵢ (δ = 72°, ψ = 67°): the 3rd harmonic appears. (45)'s n₃, m₃ miss
    the −⅛ sin⁴β_i term of the same order, so the printed series gives a third of it."""
    h = art.harmonics(radial([72], [67]))[0]
    exact, series = h.exact[0][3], h.series[0][3]
    c = math.cos(math.radians(72))
    half = Tolerance(abs=0.5e-4, why="half a unit of the independent values' last digit")
    src = "exact geometry"
    return [
        Comparison("3rd-order cosine coefficient of x_Bᵢ, exact", src, "independent", -0.0249,
                   exact[0] * c * 1e3, "mm", half),
        Comparison("3rd-order cosine coefficient of x_Bᵢ by (45)", "Semenov (45), evaluated "
                   "independently", "formula", -0.0088, series[0] * c * 1e3, "mm", half,
                   note="(43)'s n₃, m₃ are incomplete: a third of the exact value"),
        Comparison("3rd-order coefficients (a₃, b₃) of the slave travel S, exact", src,
                   "independent", np.array([-0.08061, 0.01351]), exact * 1e3, "mm",
                   Tolerance(abs=1e-5, why="the digits of the independent values")),
    ]


@case("unit/test_articulated.py::test_slave_dynamic_parameter")
def slave_dynamic_parameter():
    """λᵢ, the 2nd-harmonic amplitude of the slave's acceleration over rω², by Semenov's (61)
    and exactly; and the largest slave acceleration at δᵢ = 180° over the master's."""
    h0, h180 = art.harmonics(radial([0, 180]))
    W = art.axial_positions(radial([180]), np.linspace(0, 2 * math.pi, 20001))[2]
    ratio = float(np.abs(W[:, 1]).max() / np.abs(W[:, 0]).max())
    return [
        Comparison("λᵢ at δᵢ = 0° by (61)", f"{BOOK}: λᵢ = λ = 0.304 (errata: 0° for '90°')",
                   "formula", LAM, h0.lam_semenov, "", Tolerance(rel=1e-12, why="(61) reduces "
                                                                  "to r/l there: rounding")),
        Comparison("λᵢ at δᵢ = 180° by (61)", BOOK, "printed", 0.686, h180.lam_semenov, "",
                   Tolerance(abs=5e-4, why="printed to three digits")),
        Comparison("λᵢ at δᵢ = 0°, exact 2nd harmonic", "exact geometry",
                   "independent", 0.31082, h0.lam, "", Tolerance(abs=1e-5, why="the digits of the independent values")),
        Comparison("λᵢ at δᵢ = 180°, exact 2nd harmonic", "exact geometry",
                   "independent", 0.73043, h180.lam, "",
                   Tolerance(abs=1e-5, why="the digits of the independent values"),
                   note="(61) truncates at λ²: 6 % low here"),
        Comparison("largest slave acceleration at δᵢ = 180° over the master's",
                   "exact geometry", "independent", 1.2935, ratio, "",
                   Tolerance(abs=1e-4, why="the digits of the independent values"),
                   note=f"{BOOK} prints 1.27, a misprint: its own λᵢ give (1 + 0.686)/(1 + "
                        "0.304) = 1.293"),
    ]


def lambda_curves(banks_deg):
    """(exact λᵢ, Semenov's (61)) of slaves at ``banks_deg`` (ψᵢ = δᵢ), for the figure."""
    hs = art.harmonics(radial(list(banks_deg)))
    return np.array([h.lam for h in hs]), np.array([h.lam_semenov for h in hs])


@case("unit/test_orders.py::test_semenov_printed_fft_numbers")
def master_series():
    """The master's series (Semenov §2): the piston travel x_B (9), (14), its acceleration W
    (19) and the rod angle β (33), against an FFT of the exact geometry (independent digits);
    the package's order spectra of its exact kinematics at λ = 0.304 and r = 95, l = 313 mm.
    The text's truncated series are given alongside."""
    n = 720
    phi = np.arange(n) * (2 * math.pi / n)
    orders = np.array([1.0, 2.0, 4.0, 6.0])
    a = order_spectrum(piston_acceleration(phi, 1.0, 0.0, 0.304, 1.0), n, 2 * math.pi)
    w_amp = a.amplitude[0][orders.astype(int)] / 0.304
    c = order_spectrum(slider_arrays(phi, 0.304, 1.0, 0.0)[3], n, 2 * math.pi).coef[0]
    beta = (1j * c[[1, 3]]).real  # β = b₁ sin φ + b₃ sin 3φ: coef = b·e^{−iπ/2}
    r, l = 95.0, 313.0
    x_b = order_spectrum((l + r) - slider_arrays(phi, r, l, 0.0)[0], n, 2 * math.pi).coef[0].real
    lam = 0.304
    b_series = (lam * (1 + lam**2 / 8), -lam**3 / 24)  # (33)
    fft = "exact geometry, FFT"
    return [
        Comparison("piston acceleration W, amplitudes over rω²", fft, "independent",
                   np.array([1.0, 0.3113, 0.0075, 0.0002]), w_amp, "",
                   Tolerance(abs=0.5e-4, why="half a unit of the fourth decimal"), at=orders,
                   at_name="order", note="λ = 0.304; the 2nd order by the series of (19): "
                                         f"{lam + lam**3 / 4 + 15 * lam**5 / 128:.4f}"),
        Comparison("rod angle β, sin φ coefficient", fft, "independent", 0.30764, beta[0], "rad",
                   Tolerance(abs=0.5e-5, why="half a unit of the fifth decimal"),
                   note=f"Semenov (33): λ(1 + λ²/8) = {b_series[0]:.5f}"),
        Comparison("rod angle β, sin 3φ coefficient", fft, "independent", -0.001235, beta[1],
                   "rad", Tolerance(abs=0.5e-6, why="half a unit of the sixth decimal"),
                   note=f"Semenov (33): −λ³/24 = {b_series[1]:.6f}".replace("-", "−")),
        Comparison("piston position x_B, mean", fft, "independent", 305.662, x_b[0], "mm",
                   Tolerance(abs=0.5e-3, why="half a unit of the third decimal")),
        Comparison("piston position x_B, 1st order", "Semenov (14): r", "formula", 95.0, x_b[1],
                   "mm", Tolerance(abs=1e-9, why="rounding")),
        Comparison("piston position x_B, orders 2, 4, 6", fft, "independent",
                   np.array([7.3821, -0.0446, 0.0005]), x_b[[2, 4, 6]], "mm",
                   Tolerance(abs=0.5e-4, why="half a unit of the fourth decimal"),
                   at=np.array([2.0, 4.0, 6.0]), at_name="order",
                   note="Macalpine's series (9): t_k·l"),
        Comparison("piston position x_B, odd orders ≥ 3", "Semenov (9): even orders only",
                   "formula", None, float(np.abs(x_b[3::2]).max()), "mm",
                   Tolerance(high=1e-12 * r, why="rounding (10⁻¹² r)")),
    ]
