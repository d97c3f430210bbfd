"""Antonyuk, Sakharnov and Koval: the swash-plate engine with spatially swinging links.

Е. Я. Антонюк, Н. А. Сахарнов, А. В. Коваль, a mathematical model of the dynamic system of an
engine with spatially swinging links (Int. Appl. Mech., received 23.12.2009): the kinematics of
§2 (equations (1)–(13)), the equations of motion of §3 and the worked example of §4 — I₁ = 1 kg m²,
m₅ = 6 kg, m₇ = 1 kg, I₉ = I₁₃ = 0.3 kg m², α = 21.4°, R = 0.136 m, trapezoidal gas pulses, a
droop governor, a fan load, one and four cylinders spun up from 10 rad/s (Fig. 5, lost in the
copy at hand). The example's published result is qualitative: "the four-cylinder engine runs
markedly smoother". The scenes ``cases/swash_plate_1cyl.toml`` and ``swash_plate_4cyl.toml``
state what the paper leaves open.

Misprints found: (6) turns the joints B_i against the housing (the consistent argument is
ψ_i + φ₉,₀, of which (7) is then the exact derivative); the printed (1) holds for a cross
hinged along Oz, not along Oy as the text says; u₁₃,₁ of (13) is link 9's rate about Oy, not the
cross's own rate.
"""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from transient.analysis.irregularity import fluctuation
from transient.mechanisms import swash_plate as sp
from transient.run import integrate
from transient.scene import load_scene

from . import Comparison, Tolerance, case

CASES = Path(__file__).resolve().parents[2] / "cases"
SCENES = {1: "swash_plate_1cyl.toml", 4: "swash_plate_4cyl.toml"}
#: The droop governor's band (the scenes' ω_a, ω₁c) [rad/s].
BAND = (45.0, 60.0)
PAPER = "Antonyuk et al."


@functools.cache
def spin_up(cylinders: int):
    """(scene, trajectory) of the example's spin-up with 1 or 4 cylinders."""
    scene = load_scene(CASES / SCENES[cylinders])
    return scene, integrate(scene).trajectory


def last_turn_delta(cylinders: int) -> float:
    """δ = (ω_max − ω_min)/ω_mean over the last whole turn."""
    _, tr = spin_up(cylinders)
    return fluctuation(tr["t"], tr["phi"], tr["omega"], 2 * np.pi, 0.0)


@case("validation/test_swash_runs.py::test_four_cylinders_are_at_least_three_times_smoother")
def four_cylinders_smoother():
    """Governed steady state: the cycle-mean speed inside the droop band, and δ of one cylinder
    against four."""
    delta = {z: last_turn_delta(z) for z in SCENES}
    band = Tolerance(low=BAND[0], high=BAND[1], why="the droop governor's band ω_a … ω₁c")
    out = [Comparison(f"mean speed of the last samples, {z} cylinder{'s' * (z > 1)}",
                      f"{PAPER} §4: the droop governor", "printed", None,
                      float(spin_up(z)[1]["omega"][-200:].mean()), "rad/s", band)
           for z in SCENES]
    out.append(Comparison(
        "speed fluctuation δ, one cylinder over four", f"{PAPER} §4, Fig. 5: four cylinders run "
        "markedly smoother", "printed", None, delta[1] / delta[4], "",
        Tolerance(low=3.0, why="'markedly' read as at least three times"),
        note=f"δ over the last turn: {delta[1]:.3f} (one cylinder), {delta[4]:.4f} (four)"))
    return out


def paper_13(phi, alpha):
    """(13) as printed: u₉,₁ and u₁₃,₁; D = 1 − sin²φ sin²α."""
    s2, sa2 = np.sin(phi) ** 2, np.sin(alpha) ** 2
    d = 1.0 - s2 * sa2
    u9 = np.sqrt(1.0 + (-1.0 + sa2 * (1.0 + 2.0 * s2 * np.cos(alpha) ** 2)) / d**2)
    return u9, -np.cos(alpha) * np.sin(alpha) * np.cos(phi) / d


# Central-difference stencils: 4th order (offsets, weights) and 6th order for the 1e-10 checks.
D4 = (np.array([-2.0, -1.0, 1.0, 2.0]), np.array([1.0, -8.0, 8.0, -1.0]) / 12.0)
D6 = (np.array([-3.0, -2.0, -1.0, 1.0, 2.0, 3.0]),
      np.array([-1.0, 9.0, -45.0, 45.0, -9.0, 1.0]) / 60.0)


def derivative(f, phi, h, stencil=D4):
    """d f/dφ at ``phi`` (n,) by central differences; ``f`` maps angles (m,) to arrays (m, ...)."""
    offsets, weights = stencil
    values = f((phi[:, None] + h * offsets).ravel())
    values = values.reshape(phi.size, offsets.size, *values.shape[1:])
    return np.tensordot(weights, values, axes=([0], [1])) / h


def angular_velocity(key, geom, phi, h=1e-3, stencil=D4):
    """ω/φ̇ (n, halves, 3) of the body whose rotation matrix is ``positions[key]``: Ω = Q′ Qᵀ."""
    dQ = derivative(lambda p: sp.positions(geom, p)[key], phi, h, stencil)
    Om = dQ @ np.swapaxes(sp.positions(geom, phi)[key], -1, -2)
    return 0.5 * np.stack([Om[..., 2, 1] - Om[..., 1, 2], Om[..., 0, 2] - Om[..., 2, 0],
                           Om[..., 1, 0] - Om[..., 0, 1]], axis=-1)


@case("unit/test_swash_plate.py::test_13_normal_hinge_is_the_printed_form")
def transfer_functions():
    """With the cross hinged along Oz, (4), (7) and u₉,₁ of (13) hold exactly, against finite
    differences of the 3-D rotations (``positions``) and the kernel's kinematics table."""
    g = sp.antonyuk_example(hinge="normal")
    alpha = g.swash_angle
    phi = np.linspace(0.0, 2.0 * np.pi, 73)
    u9, u13_printed = paper_13(phi, alpha)
    d = 1.0 - np.sin(phi) ** 2 * np.sin(alpha) ** 2
    w9 = angular_velocity("Q9", g, phi, 1e-2, D6)[:, 0]
    table = sp.kinematics_table(g, phi)
    theta = sp.positions(g, phi)["theta"]
    dtheta = derivative(lambda p: sp.positions(g, p)["theta"], phi, 1e-2, D6)
    psi = 2.0 * np.pi * np.arange(4) / 4
    dxb = derivative(lambda p: sp.positions(g, p)["B"][:, 0, :, 0], phi, 1e-2, D6)
    dxb_7 = (-g.joint_radius * np.sin(psi + theta[:, None]) * np.sin(alpha) * np.cos(alpha)
             / d[:, None])
    fd = "finite differences of the rotations (6th order, h = 10⁻²): truncation"
    deg = np.degrees(phi)
    return [
        Comparison("link 9's rate |ω₉|/φ̇ (rotations)", f"{PAPER} (13): u₉,₁", "formula", u9,
                   np.linalg.norm(w9, axis=-1), "", Tolerance(abs=1e-10, why=fd), at=deg),
        Comparison("link 9's rate |ω₉|/φ̇ (kernel)", f"{PAPER} (13): u₉,₁", "formula", u9,
                   table["u9"], "", Tolerance(abs=1e-13, why="rounding"), at=deg),
        Comparison("link 9's rate about Oy, ω₉·e_y/φ̇", f"{PAPER} (13): u₁₃,₁ as printed",
                   "formula", u13_printed, w9[:, 1], "", Tolerance(abs=1e-10, why=fd), at=deg,
                   note="the cross itself turns about Oz at −cos α sin α sin φ/D"),
        Comparison("relative rate of link 9, φ̇₉,₀/φ̇", f"{PAPER} (4): −cos α/D", "formula",
                   -np.cos(alpha) / d, dtheta, "", Tolerance(abs=1e-10, why=fd), at=deg),
        Comparison("joint velocity ẋ_B/φ̇, cylinders 1–4", f"{PAPER} (7), argument ψ_i + φ₉,₀",
                   "formula", dxb_7.ravel(), dxb.ravel(), "m",
                   Tolerance(abs=1e-11, why=fd), at=np.repeat(deg, psi.size),
                   note="(6) prints ψ_i − φ₉,₀, which turns B_i against the housing"),
    ]


@case("unit/test_swash_plate.py::test_stroke")
def stroke():
    big = sp.antonyuk_example(rod_length=1e4)
    return [Comparison("stroke with a 10 km rod", f"{PAPER} §2: 2R sin α", "formula",
                       np.full(big.cylinders, 2.0 * big.joint_radius * np.sin(big.swash_angle)),
                       sp.stroke(big), "m",
                       Tolerance(rel=1e-9, why="the rods' swing: (R sin α)²/ℓ relative"))]


@case("unit/test_swash_plate.py::test_joints_follow_their_pistons")
def rod_tilt():
    """The rod's tilt to its cylinder axis in the example (ℓ = 0.30 m chosen for it)."""
    phi = np.linspace(0.0, 2.0 * np.pi, 73)
    tilt = [max(float(sp.kinematics_table(sp.antonyuk_example(hinge=h), phi)
                      [f"rod_tilt_{k}_deg"].max()) for k in range(1, 5))
            for h in ("in-plane", "normal")]
    return [Comparison("largest rod tilt, cross hinged along Oy and Oz", f"{PAPER} §1: ≤ 2°",
                       "printed", None, max(tilt), "°",
                       Tolerance(high=1.8, why="the example's rod length keeps it inside 2°"))]
