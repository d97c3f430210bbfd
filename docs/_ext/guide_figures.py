"""The guide's pictures, drawn during the build from the model's own code, and the output of a
first run.

* Mechanism sketches (:func:`crank_slider`, :func:`v_engine`, :func:`articulated`,
  :func:`swash_plate`): the bodies at a few angles placed by the mechanism's own kinematics
  (``transient.core.model.crank_slider.slider``, ``transient.mechanisms.articulated.positions``,
  ``transient.mechanisms.swash_plate.positions``) for a shipped case, with the symbols of its
  keys; each sketch checks what it draws (a rod keeps its length), so a sketch that no longer
  matches the model fails the build.
* Friction laws (:func:`eta_law`, :func:`reaction_law`, :func:`eta_map`): each pair model's
  law from the kernels' functions and a shipped case's numbers.
* The figures ``transient plot``, ``orders`` and ``loads`` write (:func:`show`), from one short
  run of a shipped case, made once per build.

The pages show them with the directive ``guide-figure`` (this module as a Sphinx extension),
written to ``_generated/guide`` at twice a screen's resolution, the body its caption::

    ```{guide-figure} show plot speed
    :alt: what it shows

    The caption.
    ```

The directive ``command-output`` runs a ``transient`` command on a copy of the shipped cases in
a scratch folder and shows what it prints.
"""
from __future__ import annotations

import contextlib
import functools
import io
import math
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"

#: Where the figures are written, under the source folder (cleaned by ``make clean``).
OUT = Path("_generated") / "guide"
#: Colours of the sketches: bodies, the part drawn at other angles, dimensions.
BODY, GHOST, DIM = "0.15", "0.75", "C3"


def _case(name, **changes):
    import transient

    scene = transient.load_scene(CASES / name)
    return scene.replace(**changes) if changes else scene


def _dimension(ax, a, b, text, shift=0.0, offset=(0.0, 0.0)):
    """A dimension line from a to b, moved ``shift`` to its left (seen from a to b) with thin
    extension lines, and its symbol beside its middle (``offset`` more)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    d = b - a
    n = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-300) * shift
    if shift:
        for p in (a, b):
            ax.plot([p[0], p[0] + 1.1 * n[0]], [p[1], p[1] + 1.1 * n[1]], color=DIM, lw=0.5)
    ax.annotate("", xy=tuple(b + n), xytext=tuple(a + n),
                arrowprops={"arrowstyle": "<->", "color": DIM, "lw": 0.9, "shrinkA": 0,
                            "shrinkB": 0})
    ax.update_datalim([a + n, b + n])  # (an annotation does not widen the axes)
    mid = 0.5 * (a + b) + n * (1.0 + (0.6 if shift else 0.0)) + np.asarray(offset)
    ax.text(*mid, text, color=DIM, fontsize=11, ha="center", va="center",
            bbox={"fc": "white", "ec": "none", "pad": 0.3})


def _arc(ax, centre, radius, start, end, text, where=0.5, **kw):
    """An angle from ``start`` to ``end`` (radians, counter-clockwise from +x) with its symbol."""
    t = np.linspace(start, end, 60)
    ax.plot(centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t), color=DIM, lw=0.9)
    m = start + where * (end - start)
    ax.text(centre[0] + 1.25 * radius * np.cos(m), centre[1] + 1.25 * radius * np.sin(m), text,
            color=DIM, fontsize=11, ha="center", va="center", **kw)


def _finish(ax, title):
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title, fontsize=10)


def _cw(v, angle):
    """``v`` (…, 2) turned clockwise by ``angle``."""
    c, s = math.cos(angle), math.sin(angle)
    return np.stack([v[..., 0] * c + v[..., 1] * s, -v[..., 0] * s + v[..., 1] * c], axis=-1)


def _slider_points(mech, alpha):
    """Crankpin A and piston pin B of a crank-slider at local angle ``alpha``, in its cylinder's
    frame (axis up, x = e the axis' offset; the crank turns clockwise), from the kernel's
    ``slider``: B lies one rod length from A (checked)."""
    from transient.core.model.crank_slider import slider

    r, l, e = mech.crank_radius, mech.rod_length, mech.offset
    s, _, _, beta, _, _ = slider.py_func(alpha, r, l, e)
    A = np.array([r * math.sin(alpha), r * math.cos(alpha)])
    B = np.array([e, math.sqrt((l + r) ** 2 - e * e) - s])
    assert abs(np.hypot(*(B - A)) - l) < 1e-12 * l, "the sketch's rod is not the model's"
    assert abs(math.atan2(A[0] - B[0], B[1] - A[1]) - beta) < 1e-9
    return A, B


def _piston(ax, B, axis_angle, bore, height, colour=BODY):
    """A piston (a rectangle across the bore, centred on its pin B) on an axis turned clockwise
    by ``axis_angle`` from the vertical."""
    corners = np.array([[-bore / 2, -0.35 * height], [bore / 2, -0.35 * height],
                        [bore / 2, 0.65 * height], [-bore / 2, 0.65 * height],
                        [-bore / 2, -0.35 * height]])
    pts = _cw(corners, axis_angle) + B
    ax.fill(pts[:, 0], pts[:, 1], color="0.85", ec=colour, lw=1.2, zorder=3)
    ax.plot(*B, "o", color=colour, ms=4, zorder=4)


# ------------------------------------------------------------------------------------------------
# Mechanisms


def crank_slider(ax=None, title=None):
    """The Gots diesel's crank-slider with an offset cylinder axis (e = 12 mm, to show it):
    crank r, rod l, offset e, crank angle φ from the cylinder axis, rod angle β; the piston pin
    at other angles in grey."""
    scene = _case("gots_diesel_4400.toml", mechanism={"offset_mm": 12})
    mech = scene.mechanism
    r, l, e, D = mech.crank_radius, mech.rod_length, mech.offset, mech.bore
    ax = ax or plt.subplots(figsize=(4.6, 6.2), layout="constrained")[1]
    for a in np.radians(np.arange(0, 360, 30)):
        A, B = _slider_points(mech, a)
        ax.plot([A[0], B[0]], [A[1], B[1]], color=GHOST, lw=0.8, zorder=1)
    alpha = math.radians(50.0)
    A, B = _slider_points(mech, alpha)
    t = np.linspace(0, 2 * math.pi, 200)
    ax.plot(r * np.cos(t), r * np.sin(t), color=GHOST, lw=0.8, ls="--")
    ax.plot([0, A[0]], [0, A[1]], color=BODY, lw=3, solid_capstyle="round")
    ax.plot([A[0], B[0]], [A[1], B[1]], color=BODY, lw=2.2, solid_capstyle="round")
    ax.plot(0, 0, "o", color=BODY, ms=6)
    ax.plot(*A, "o", color="white", mec=BODY, ms=6, zorder=4)
    _piston(ax, B, 0.0, D, 0.6 * D)
    top = math.sqrt((l + r) ** 2 - e * e) + 0.5 * D
    for side in (-1, 1):  # the cylinder's walls
        ax.plot([e + side * D / 2] * 2, [top - 1.9 * D, top + 0.1 * D], color=BODY, lw=1.5)
    ax.plot([e, e], [-1.3 * r, top + 0.2 * D], color="0.5", lw=0.6, ls="-.")
    ax.plot([0, 0], [-1.3 * r, 1.5 * r], color="0.5", lw=0.6, ls="-.")
    _dimension(ax, (0, 0), tuple(A), "r", shift=-0.35 * r)
    _dimension(ax, tuple(B), tuple(A), "l", shift=-0.5 * r)
    _dimension(ax, (0, -1.2 * r), (e, -1.2 * r), "e", offset=(0, -0.2 * r))
    _arc(ax, (0, 0), 0.6 * r, math.pi / 2 - alpha, math.pi / 2, "φ", where=0.4)
    beta = math.atan2(A[0] - B[0], B[1] - A[1])
    _arc(ax, tuple(B), 0.55 * l, -math.pi / 2, -math.pi / 2 + beta, "β", where=0.5)
    ax.annotate("", xy=(0.8 * r, 0.95 * r), xytext=(-0.3 * r, 1.25 * r),
                arrowprops={"arrowstyle": "->", "color": "0.4",
                            "connectionstyle": "arc3,rad=-0.3"})
    ax.text(0.5 * r, 1.32 * r, "rotation", color="0.4", fontsize=8)
    _finish(ax, title or f"crank-slider: r = {r * 1e3:g} mm, l = {l * 1e3:g} mm, "
                         f"e = {e * 1e3:g} mm")
    return ax.figure


def v_engine(ax=None):
    """The cross-plane V8 from the front at φ = 0: the banks at ±45° from the reference axis,
    the four throws at their angles, cylinders 1 and 2 on throw 1 with their rods and pistons
    (the rest in grey)."""
    mech = _case("v8_cross_plane.toml").mechanism
    r, l, D = mech.crank_radius, mech.rod_length, mech.bore
    ax = ax or plt.subplots(figsize=(6.2, 5.2), layout="constrained")[1]
    throws, _ = mech.throw_angles()
    for k, bank in enumerate(mech.bank_angles):
        axis = _cw(np.array([[0.0, -0.2 * r], [0.0, l + 2.2 * r]]), bank)
        ax.plot(axis[:, 0], axis[:, 1], color="0.5", lw=0.6, ls="-.")
        A, B = _slider_points(mech, -mech.firing_angles[k] % (2 * math.pi))
        A, B = _cw(A, bank), _cw(B, bank)
        colour = BODY if k < 2 else GHOST
        ax.plot([A[0], B[0]], [A[1], B[1]], color=colour, lw=2.0 if k < 2 else 0.8)
        if k < 2:
            _piston(ax, B, bank, D, 0.5 * D)
            ax.text(*(_cw(np.array([0.0, l + 1.9 * r]), bank)), f"cylinder {k + 1}",
                    ha="center", fontsize=8)
    t = np.linspace(0, 2 * math.pi, 200)
    ax.plot(r * np.cos(t), r * np.sin(t), color=GHOST, lw=0.8, ls="--")
    for j, angle in enumerate(throws):
        p = _cw(np.array([0.0, r]), angle)
        ax.plot([0, p[0]], [0, p[1]], color=BODY if j == 0 else "0.55", lw=2.5 if j == 0 else 1.2)
        ax.plot(*p, "o", color="white", mec=BODY, ms=5, zorder=4)
        q = _cw(np.array([0.0, 1.45 * r]), angle)
        ax.text(*q, f"throw {j + 1}\n{math.degrees(angle):.0f}°", fontsize=7, ha="center",
                va="center", color="0.3")
    ax.plot([0, 0], [0, l + 2.0 * r], color="0.3", lw=0.8, ls=":")
    for k in (0, 1):
        bank = mech.bank_angles[k]
        start, end = sorted((math.pi / 2, math.pi / 2 - bank))
        _arc(ax, (0, 0), 0.75 * l, start, end, f"bank {math.degrees(bank):+.0f}°")
    _finish(ax, "V engine (cases/v8_cross_plane.toml): banks, throws, two rods per crankpin")
    return ax.figure


def articulated(ax=None, title=None):
    """The five-cylinder radial of Semenov from cases/radial_5cyl.toml at α = 30°: the master
    rod l on the crankpin (r), the link pins at radius r_i on it, the slave rods l_i to their
    pistons on the banks δ_i."""
    from transient.mechanisms.articulated import positions

    mech = _case("radial_5cyl.toml").mechanism
    r, l = mech.crank_radius, mech.rod_length
    up = 1j  # the master cylinder drawn upward: z ↦ i z
    ax = ax or plt.subplots(figsize=(5.6, 5.6), layout="constrained")[1]
    t = np.linspace(0, 2 * math.pi, 200)
    ax.plot(r * np.cos(t), r * np.sin(t), color=GHOST, lw=0.8, ls="--")
    p = {k: v[0] for k, v in positions(mech, math.radians(30.0)).items()}
    A, B, Ai, Bi = (up * p["A"], up * p["B"], up * p["Ai"], up * p["Bi"])
    assert abs(abs(p["B"] - p["A"]) - l) < 1e-12 * l
    for i in range(mech.n_slaves):
        assert abs(abs(p["Bi"][i] - p["Ai"][i]) - mech.slave_lengths[i]) < 1e-12 * l
    ax.plot([0, A.real], [0, A.imag], color=BODY, lw=3)
    ax.plot([A.real, B.real], [A.imag, B.imag], color=BODY, lw=2.4)
    for a, b, bank in zip(Ai, Bi, mech.slave_banks):
        ax.fill([A.real, a.real, (A + 0.25 * (B - A)).real],
                [A.imag, a.imag, (A + 0.25 * (B - A)).imag], color="0.8", ec=BODY, lw=0.8)
        ax.plot([a.real, b.real], [a.imag, b.imag], color=BODY, lw=1.4)
        ax.plot(a.real, a.imag, "o", color="white", mec=BODY, ms=4, zorder=4)
        axis = up * np.exp(1j * bank) * np.array([0.2 * r, l + 1.6 * r])
        ax.plot(axis.real, axis.imag, color="0.5", lw=0.5, ls="-.")
        ax.plot(b.real, b.imag, "s", color="0.85", mec=BODY, ms=8)
    ax.plot(B.real, B.imag, "s", color="0.85", mec=BODY, ms=9)
    ax.plot(0, 0, "o", color=BODY, ms=6)
    ax.plot(A.real, A.imag, "o", color="white", mec=BODY, ms=6, zorder=4)
    _dimension(ax, (0, 0), (A.real, A.imag), "r", shift=0.45 * r)
    _dimension(ax, (B.real, B.imag), (A.real, A.imag), "l", shift=0.45 * r)
    a0, b0 = Ai[-1], Bi[-1]  # (the last slave, drawn on the right)
    _dimension(ax, (A.real, A.imag), (a0.real, a0.imag), "r_i", shift=-0.4 * r)
    _dimension(ax, (a0.real, a0.imag), (b0.real, b0.imag), "l_i", shift=-0.45 * r)
    bank0 = mech.slave_banks[0]
    _arc(ax, (0, 0), 1.25 * l, math.pi / 2, math.pi / 2 + bank0, "δ_i")
    _finish(ax, title or f"master and articulated rods: r = {r * 1e3:g} mm, "
                         f"l = {l * 1e3:g} mm, r_i = {mech.link_radii[0] * 1e3:g} mm")
    return ax.figure


def swash_plate(ax=None, title=None):
    """The swash-plate engine of Antonyuk et al. (cases/swash_plate_4cyl.toml) seen across the
    shaft at φ = 0: the plate at the swash angle α, the rod joints B_k on link 9 at radius R,
    the rods ℓ to the piston joints D_k on the cylinders at radius r₁; the joints' paths in
    grey."""
    from transient.mechanisms.swash_plate import positions

    geom = _case("swash_plate_4cyl.toml").mechanism
    R, r1, a = geom.joint_radius, geom.cylinder_radius, geom.swash_angle
    path = positions(geom, np.radians(np.arange(0, 361, 5)))
    now = positions(geom, 0.0)
    B, D = now["B"][0], now["D"][0]  # half 1, (z, 3)
    assert np.allclose(np.linalg.norm(B - D, axis=-1), geom.rod_length, rtol=1e-12)
    ax = ax or plt.subplots(figsize=(6.4, 4.6), layout="constrained")[1]
    for k in range(B.shape[0]):
        ax.plot(path["B"][:, 0, k, 0], path["B"][:, 0, k, 1], color=GHOST, lw=0.8)
        ax.plot(path["D"][:, 0, k, 0], path["D"][:, 0, k, 1], color=GHOST, lw=0.8)
    n = now["normal"][0]
    plate = np.array([-n[1], n[0]]) * 1.15 * R
    ax.plot([-plate[0], plate[0]], [-plate[1], plate[1]], color=BODY, lw=4,
            solid_capstyle="butt")
    ax.plot([0.35 * geom.rod_length, -1.5 * geom.rod_length], [0, 0], color="0.4", lw=1.0,
            ls="-.")
    ax.text(0.36 * geom.rod_length, 0.0, " shaft", fontsize=8, color="0.4", va="center")
    bore, reach = geom.bore, path["D"][:, 0, :, 0]
    for k in range(B.shape[0]):
        if abs(B[k, 2]) > 0.5 * R:  # (the two cylinders seen from the side only)
            continue
        ax.plot([B[k, 0], D[k, 0]], [B[k, 1], D[k, 1]], color=BODY, lw=2)
        ax.plot(B[k, 0], B[k, 1], "o", color="white", mec=BODY, ms=6, zorder=4)
        y0, y1 = D[k, 1] - bore / 2, D[k, 1] + bore / 2
        ax.fill([D[k, 0], D[k, 0] - 0.8 * bore, D[k, 0] - 0.8 * bore, D[k, 0]],
                [y0, y0, y1, y1], color="0.85", ec=BODY, lw=1.0, zorder=3)  # the piston
        ax.plot(D[k, 0], D[k, 1], "o", color=BODY, ms=4, zorder=4)
        head = reach[:, k].min() - 0.8 * bore - 0.15 * bore
        for y in (y0, y1):  # the cylinder, over the piston's stroke, closed at its head
            ax.plot([head, reach[:, k].max() + 0.1 * bore], [y, y], color=BODY, lw=1.2)
        ax.plot([head, head], [y0, y1], color=BODY, lw=1.2)
    top = int(np.argmax(B[:, 1]))
    _dimension(ax, (0.0, 0.0), (B[top, 0], B[top, 1]), "R", shift=-0.25 * R)
    x_r = reach.min() - 1.3 * bore
    _dimension(ax, (x_r, 0.0), (x_r, D[top, 1]), "r₁", offset=(-0.1 * R, 0.0))
    _dimension(ax, (D[top, 0], D[top, 1]), (B[top, 0], B[top, 1]), "ℓ", shift=0.25 * R)
    _arc(ax, (0, 0), 0.7 * R, math.pi / 2, math.pi / 2 + math.atan2(n[1], n[0]), "α",
         where=0.5)
    ax.plot([0, 0], [0, 0.9 * R], color="0.5", lw=0.6, ls=":")
    _finish(ax, title or f"swash plate: α = {math.degrees(a):.1f}°, R = {R * 1e3:g} mm, "
                         f"r₁ = {r1 * 1e3:g} mm, ℓ = {geom.rod_length * 1e3:g} mm")
    return ax.figure


def mechanisms_row():
    """The three mechanisms side by side, for the landing page."""
    fig, axes = plt.subplots(1, 3, figsize=(10, 3.8), layout="constrained",
                             width_ratios=(0.8, 1.0, 1.25))
    for ax, sketch, title in zip(axes, (crank_slider, articulated, swash_plate),
                                 ("crank-slider (in-line, V, offset)",
                                  "master and articulated rods (radial)",
                                  "swash plate (axial)")):
        sketch(ax, title)
    return fig


# ------------------------------------------------------------------------------------------------
# Friction laws


def eta_law():
    """A constant-η pair (the example's main bearings, η_forward 0.985, η_backward 0.98): the
    power it loses and the η* it applies against the power S·ω it takes from its shaft side,
    from the kernels' ``eta_star`` and ``pair_losses``."""
    from transient.core.model.chain import eta_star, pair_losses

    eta_f, eta_b = 0.985, 0.98
    power = np.linspace(-50e3, 50e3, 401)  # S·ω [W] at ω = 100 rad/s
    w = 100.0
    loss, eta = np.empty_like(power), np.empty_like(power)
    out = np.empty(1)
    for i, p in enumerate(power):
        e = eta_star.py_func(eta_f, eta_b, p >= 0.0)
        pair_losses.py_func(np.array([e]), np.array([p / w]), w, out)
        loss[i], eta[i] = out[0], e
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.4), layout="constrained")
    a1.plot(power / 1e3, loss / 1e3, color="C0", lw=1.6)
    a1.axvline(0, color="0.6", lw=0.6)
    a1.set_xlabel("power taken from the shaft side S·ω [kW]")
    a1.set_ylabel("power lost [kW]")
    a1.text(0.97, 0.9, "shaft side drives:\n(1 − η_forward) S·ω", transform=a1.transAxes,
            ha="right", va="top", fontsize=8)
    a1.text(0.03, 0.9, "far side drives:\n(1/η_backward − 1) |S·ω|", transform=a1.transAxes,
            ha="left", va="top", fontsize=8)
    a2.plot(power / 1e3, eta, color="C1", lw=1.6, drawstyle="steps-mid")
    a2.axhline(1.0, color="0.6", lw=0.6)
    a2.set_xlabel("power taken from the shaft side S·ω [kW]")
    a2.set_ylabel("η* applied, output eta_k [1]")
    a2.text(0.97, 0.12, f"η_forward = {eta_f}", transform=a2.transAxes, ha="right", fontsize=8)
    a2.text(0.03, 0.88, f"1/η_backward = {1 / eta_b:.4f}", transform=a2.transAxes, fontsize=8,
            va="top")
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
    fig.suptitle("constant η: the mode follows the direction of the power", fontsize=10)
    return fig


def reaction_law():
    """The reaction model with cases/gots_diesel_reaction_friction.toml's numbers: a journal's
    friction moment μ·r·|R| + c·q against its load at a few relative speeds q, and the piston's
    friction force μ·|N| + F_ring + c_p·P⁺ + c·v against the side force at a few gas forces."""
    scene = _case("gots_diesel_reaction_friction.toml")
    pairs = {p.between: p for p in scene.friction.pairs}
    main, piston = pairs[("shaft", "crank")], pairs[("piston", "cylinder")]
    R = np.linspace(0.0, 60e3, 200)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.4), layout="constrained")
    for q, style in ((0.0, "-"), (250.0, "--"), (500.0, ":")):
        a1.plot(R / 1e3, main.mu * main.radius * R + main.viscous * q, ls=style, color="C0",
                label=f"q = {q:g} rad/s")
    a1.set_xlabel("journal load |R| [kN]")
    a1.set_ylabel("friction moment [N m]")
    a1.set_title(f"{main.name}: μ·r·|R| + c·q (μ = {main.mu:g}, r = {main.radius * 1e3:g} mm)",
                 fontsize=9)
    N = np.linspace(0.0, 5e3, 200)
    v = 10.0
    for P, style in ((0.0, "-"), (20e3, "--"), (50e3, ":")):
        a2.plot(N / 1e3, piston.mu * N + piston.ring_force + piston.ring_pressure * max(P, 0.0)
                + piston.viscous * v, ls=style, color="C1", label=f"P = {P / 1e3:g} kN")
    a2.set_xlabel("side force |N| [kN]")
    a2.set_ylabel("friction force [N]")
    a2.set_title(f"{piston.name}: μ·|N| + F_ring + c_p·P⁺ + c·v (v = {v:g} m/s)", fontsize=9)
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    return fig


def eta_map():
    """The efficiency map of cases/gots_diesel_eta_map.toml: η_forward and η_backward against
    the moment |S| at each of its speeds, bilinear between the grid points as the kernel's
    ``lookup`` reads it (dots: the grid)."""
    from transient.core.model.eta_table import BACKWARD, FORWARD, lookup

    scene = _case("gots_diesel_eta_map.toml")
    pair = next(p for p in scene.friction.pairs if p.model == "table")
    speed, torque = np.asarray(pair.speed), np.asarray(pair.torque)
    maps = np.stack([np.asarray(pair.eta_forward_map), np.asarray(pair.eta_backward_map)])
    size = np.array([[speed.size, torque.size]])
    S = np.linspace(0.0, 1.1 * torque[-1], 300)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), layout="constrained", sharey=True)
    for ax, d, words in ((axes[0], FORWARD, "η_forward (shaft side drives)"),
                         (axes[1], BACKWARD, "η_backward (far side drives)")):
        for j, w in enumerate(speed):
            eta = [lookup.py_func(speed[None], torque[None], size, maps[None], 0, d, w, s)[0]
                   for s in S]
            colour = plt.cm.viridis(j / max(speed.size - 1, 1))
            ax.plot(S, eta, color=colour, lw=1.2, label=f"{w * 30 / math.pi:.0f} rpm")
            ax.plot(torque, maps[d, j], "o", color=colour, ms=3)
        ax.set_xscale("symlog", linthresh=torque[1] if torque.size > 1 else 1.0)
        ax.set_xlabel("moment taken from the shaft side |S| [N m]")
        ax.set_title(words, fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("η [1]")
    axes[1].legend(fontsize=7, loc="lower right", title="|ω|", title_fontsize=7)
    fig.suptitle(f"{pair.name}: efficiency map, held at its edge beyond the grid (|S| "
                 f"logarithmic above {torque[1]:g} N m, linear below)", fontsize=10)
    return fig


# ------------------------------------------------------------------------------------------------
# The figures of a run


@functools.cache
def _run(case: str, revolutions: float):
    """A short run of a shipped case, made once per build, kept in a scratch file."""
    import transient

    folder = Path(tempfile.mkdtemp(prefix="transient-docs-"))
    scene = transient.load_scene(CASES / case).replace(run={"revolutions": revolutions})
    transient.simulate(scene, folder / f"{Path(case).stem}.h5")
    return transient.open_result(folder / f"{Path(case).stem}.h5")


def show(command: str, name: str, case: str = "diesel_4cyl_misfire.toml",
         revolutions: float = 60.0):
    """The figure ``name`` (``speed``, ``indicator``, ``orders_cycles``, ``loads_polar`` …) that
    ``transient <command>`` writes of a short run of ``case``, the others closed."""
    res = _run(case, revolutions)
    scene = res.scene()
    if command == "plot":
        from transient.cli.plot import figures
        made = figures(res)
    elif command == "orders":
        from transient.analysis.orders import run_orders
        from transient.cli.orders import figures
        cuts = res.events.get("breakpoint", {}).get("phi", np.zeros(0))
        made = figures(res, run_orders(scene, res.trajectory, 720, cuts=cuts,
                                       piston_cylinder=1), 12.0, 1)
    elif command == "loads":
        from transient.analysis.loads.diagrams import crank_slider_diagrams
        from transient.cli.loads import crank_slider_figures
        made = crank_slider_figures(scene, crank_slider_diagrams(scene, res.trajectory, 1))
    else:
        raise ValueError(f"no figures of {command!r}")
    found = None
    for figure_name, fig in made:
        if figure_name == name:
            found = fig
        else:
            plt.close(fig)
    if found is None:
        raise ValueError(f"transient {command} draws no {name!r} figure of {case}")
    from transient.cli.common import lay_out

    lay_out(found)  # (as the command does before it saves)
    return found


# ------------------------------------------------------------------------------------------------
# command-output


def _command_output(argv: list[str]) -> str:
    """What ``transient *argv`` prints, run in a scratch folder holding a copy of ``cases/``."""
    from transient.cli import main

    with tempfile.TemporaryDirectory(prefix="transient-docs-") as folder:
        shutil.copytree(CASES, Path(folder) / "cases")
        out, err = io.StringIO(), io.StringIO()
        with contextlib.chdir(folder), contextlib.redirect_stdout(out), \
                contextlib.redirect_stderr(err):
            code = main(argv)
        if code != 0:
            raise RuntimeError(f"transient {' '.join(argv)} exited {code}: {err.getvalue()}")
    return out.getvalue()


def _save(fig, srcdir: Path, name: str) -> tuple[str, int]:
    """``fig`` as ``_generated/guide/<name>.png`` at twice a screen's resolution: its URI and
    its width on the page [px], half its pixels' (so that a figure keeps the size it was drawn
    at, sharp on a high-density screen)."""
    from PIL import Image

    out = srcdir / OUT
    out.mkdir(parents=True, exist_ok=True)
    fig.savefig(out / f"{name}.png", dpi=200, bbox_inches="tight")
    plt.close(fig)
    with Image.open(out / f"{name}.png") as image:
        width = image.size[0] // 2
    return "/" + (OUT / f"{name}.png").as_posix(), width


def setup(app):
    from docutils import nodes
    from docutils.parsers.rst import directives
    from sphinx.util.docutils import SphinxDirective

    class GuideFigure(SphinxDirective):
        """``{guide-figure} NAME [ARG …]``: the figure that this module's function NAME draws
        (called with the ARGs as strings), the body as its caption."""

        required_arguments = 1
        optional_arguments = 4
        has_content = True
        option_spec = {"alt": directives.unchanged}

        def run(self):
            name, *args = self.arguments
            if name.startswith("_") or not callable(globals().get(name)):
                raise self.error(f"guide_figures has no figure {name!r}")
            uri, width = _save(globals()[name](*args), Path(self.env.srcdir),
                               "-".join(self.arguments))
            figure = nodes.figure(classes=["guide-figure"])
            figure += nodes.image(uri=uri, alt=self.options.get("alt", name), width=f"{width}px")
            if self.content:
                parsed = nodes.container()
                self.state.nested_parse(self.content, self.content_offset, parsed)
                figure += nodes.caption("", "", *parsed[0].children)
            return [figure]

    class CommandOutput(SphinxDirective):
        """``transient ARGS`` as typed, and what it prints, as one console block."""

        required_arguments = 1
        final_argument_whitespace = True

        def run(self):
            argv = self.arguments[0].split()
            text = f"$ transient {' '.join(argv)}\n{_command_output(argv)}"
            block = nodes.literal_block(text, text)
            block["language"] = "console"
            return [block]

    app.add_directive("guide-figure", GuideFigure)
    app.add_directive("command-output", CommandOutput)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
