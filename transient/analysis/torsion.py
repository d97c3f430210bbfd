"""Modal analysis of an elastic shaft line (``[shaft]``): natural frequencies and mode shapes of
the line linearised about its rotation, the band each frequency sweeps as the throws turn, the
damped modes, and the critical speeds at which an engine order meets a natural frequency.

**Linearisation.** About a steady rotation, small twists ϑ obey M ϑ̈ + C ϑ̇ + K ϑ = 0 with the
inertias taken constant at their cycle means (the terms in J′ and in the mean speed's square
vary with the angle and are what the time-domain model keeps; Friswell et al. 2010, §9.7,
for the constant-inertia line). The natural frequencies ω_j and mass-normalised shapes φ_j
solve K φ = ω² M φ, φ_iᵀ M φ_j = δ_ij (scipy's ``eigh``); a free line has a rigid mode at 0,
and each viscous damper ring one more.

**Frozen-angle bands.** Each station's inertia varies with its angle, twice per revolution for a
crank-slider. With every station frozen at the angle φ the line has frequencies ω_j(φ); the
band of mode j is their least to greatest value over one revolution (modes numbered by rising
frequency at each angle). A natural frequency's sidebands and the secondary resonances of
the variable-inertia line lie around it (Guzzomi, Hesterman & Stone 2007).

**Damped modes.** With damping, the eigenvalues λ of the first-order system
[[0, I], [−M⁻¹K, −M⁻¹C]]: each complex pair is a mode of natural frequency |λ|, damping ratio
−Re λ/|λ| and damped frequency |Im λ|; a real λ is a motion that does not oscillate (a viscous
ring's creep).

**Critical speeds.** The gas and inertia torques of an engine of cycle 720° (360°) hold the
orders q = ½, 1, 1½, … (1, 2, …) per revolution; order q meets mode j at n = 60 f_j / q
[rpm]. An order is *major* if every cylinder's excitation adds in phase, |Σ_k e^{iqφ_k}| = n_cyl,
with φ_k each cylinder's firing angle (for an evenly firing in-line four-stroke the multiples of
n_cyl/2, for a two-stroke of n_cyl); the other orders are *integer* or *half* orders. The
*relative excitation* of a critical is the vector sum of the mode's amplitudes at the
cylinders' stations with the order's phases, |Σ_k φ_j(s_k) e^{iqφ_k}| / Σ_k |φ_j(s_k)|, in
[0, 1]: how far the cylinders' excitations add up in that mode (the classical phase-vector
sum). The damped line's criticals are where an order meets a damped mode's natural frequency
|λ|/2π, its excitation summed with the mode's complex amplitudes: a viscous damper's ring then
moves partly with its hub, which the undamped line (the ring left free) does not show.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..shaft import ShaftLine

#: Frozen angles per revolution at which the bands are sampled (every 0.5°).
BAND_SAMPLES = 720
#: Highest engine order listed by default [1/rev].
DEFAULT_MAX_ORDER = 12.0
#: Share of n_cyl at which a phase sum counts as all cylinders in phase (rounding only).
IN_PHASE = 1e-9
#: Order kinds, as the Campbell diagram styles them.
ORDER_KINDS = ("major", "integer", "half")


def natural_modes(K, M_diag, rigid: int = 0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(ω [rad/s], shapes) of K φ = ω² M φ, rising; the shapes are the columns, mass-normalised
    (φᵀ M φ = I). The first ``rigid`` eigenvalues are zero in exact arithmetic (the line's free
    rotations) and are returned as 0."""
    values, shapes = scipy.linalg.eigh(np.asarray(K, dtype=float), np.diag(M_diag))
    values[:rigid] = 0.0
    return np.sqrt(np.clip(values, 0.0, None)), shapes


@dataclass(frozen=True)
class DampedMode:
    """An oscillating mode of the damped line: natural frequency ``omega_n`` = |λ| and damped
    frequency ``omega_d`` = |Im λ| [rad/s], damping ratio ``zeta`` = −Re λ/|λ| [1], and its
    complex ``shape`` over the dofs (the eigenvector's displacements, the largest of modulus 1:
    with non-proportional damping, as a viscous damper's, the dofs do not move in phase)."""

    omega_n: float
    omega_d: float
    zeta: float
    shape: NDArray[np.complex128]


def damped_modes(K, C, M_diag) -> tuple[list[DampedMode], int]:
    """The oscillating modes of M ϑ̈ + C ϑ̇ + K ϑ = 0 by rising natural frequency, and how many
    of its eigenvalues are real (non-oscillating motions, zero ones included)."""
    n = len(M_diag)
    inv = 1.0 / np.asarray(M_diag, dtype=float)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -inv[:, None] * np.asarray(K)
    A[n:, n:] = -inv[:, None] * np.asarray(C)
    lam, vectors = scipy.linalg.eig(A)
    scale = max(float(np.max(np.abs(lam))), 1.0)
    # (a free line's rigid mode is a double zero eigenvalue without a second eigenvector, which
    # rounding splits by about √ε·|A|: below 1e-6 of the largest it is taken as zero)
    oscillating = np.flatnonzero((lam.imag > 1e-9 * scale) & (np.abs(lam) > 1e-6 * scale))
    modes = sorted((DampedMode(float(abs(lam[i])), float(lam[i].imag),
                               float(-lam[i].real / abs(lam[i])), _unit_shape(vectors[:n, i]))
                    for i in oscillating), key=lambda m: m.omega_n)
    return modes, 2 * n - 2 * len(modes)


def _unit_shape(x) -> NDArray[np.complex128]:
    """``x`` scaled so that its largest component is 1 (modulus and phase)."""
    return np.asarray(x / x[int(np.argmax(np.abs(x)))], dtype=np.complex128)


@dataclass(frozen=True)
class Mode:
    """An elastic mode of the undamped line at cycle-mean inertias: its ``number`` (1 the
    lowest elastic), frequency ``f`` [Hz], mass-normalised ``shape`` over the dofs, its frozen
    band ``band`` (least, greatest) [Hz], the dof of the largest amplitude ``largest_at`` and
    the element (section, damper or coupling) of the largest twist ``twist_at``."""

    number: int
    f: float
    shape: NDArray[np.float64]
    band: tuple[float, float]
    largest_at: str
    twist_at: str


@dataclass(frozen=True)
class Critical:
    """Engine order ``order`` [1/rev] of kind ``kind`` meeting mode ``mode`` at ``rpm``, with
    the mode's relative excitation by that order
    (:mod:`module docs <transient.analysis.torsion>`)."""

    mode: int
    order: float
    kind: str
    rpm: float
    excitation: float


@dataclass(frozen=True)
class Modal:
    """The modal analysis of a shaft line: its ``line``, the elastic ``modes``, the number of
    ``rigid`` modes, the ``damped`` modes (empty without damping) and the count of real
    eigenvalues ``creeping`` among the damped system's."""

    line: ShaftLine
    modes: tuple[Mode, ...]
    rigid: int
    damped: tuple[DampedMode, ...]
    creeping: int


def modal_analysis(line: ShaftLine, band_samples: int = BAND_SAMPLES) -> Modal:
    """Modes, frozen bands and damped modes of ``line``."""
    mean = line.mean_inertia()
    omega, shapes = natural_modes(line.K, mean, line.rigid_modes)
    bands = frozen_bands(line, band_samples)
    elements = shaft_elements(line)
    modes = []
    for j in range(line.rigid_modes, line.n):
        shape = shapes[:, j]
        twist = [abs(shape[a] - shape[b]) for _, a, b in elements]
        modes.append(Mode(number=j - line.rigid_modes + 1, f=float(omega[j] / (2 * math.pi)),
                          shape=shape, band=(float(bands[0, j]), float(bands[1, j])),
                          largest_at=line.names[int(np.argmax(np.abs(shape)))],
                          twist_at=elements[int(np.argmax(twist))][0]))
    damped: list[DampedMode] = []
    creeping = 0
    if np.any(line.C):
        damped, creeping = damped_modes(line.K, line.C, mean)
    return Modal(line, tuple(modes), line.rigid_modes, tuple(damped), creeping)


def frozen_bands(line: ShaftLine, samples: int = BAND_SAMPLES) -> NDArray[np.float64]:
    """(least, greatest) natural frequency [Hz] of each mode (rows 0 and 1, a column per mode
    by rising frequency, rigid ones included) over the angles φ = 2πi/``samples`` at which every
    station is frozen."""
    freqs = np.array([natural_modes(line.K, line.mass_diagonal(2 * math.pi * i / samples),
                                    line.rigid_modes)[0] for i in range(samples)])
    freqs /= 2 * math.pi
    return np.vstack([freqs.min(axis=0), freqs.max(axis=0)]).astype(np.float64)


def shaft_elements(line: ShaftLine, viscous: bool = False) -> list[tuple[str, int, int]]:
    """(label, dof a, dof b) of each elastic element: the sections, the tuned dampers' springs
    and the coupling; with ``viscous`` the viscous dampers' silicone too (an element of
    damping only). dof a is the one nearer the front end (a damper's: its hub)."""
    names, at = line.names, line.station_dof
    out = [(f"section {i + 1} ({names[at[i]]}–{names[at[i + 1]]})", at[i], at[i + 1])
           for i in range(len(at) - 1)]
    out += [(f"damper {'spring' if d.model == 'tuned' else 'silicone'} at {names[hub]}", hub,
             ring) for d, ring, hub in line.rings() if viscous or d.model == "tuned"]
    if line.shaft.coupling is not None:
        out.append(("coupling", at[-1], line.n - 1))
    return out


def engine_orders(cycle: float, max_order: float = DEFAULT_MAX_ORDER) -> NDArray[np.float64]:
    """The orders [1/rev] an engine of cycle ``cycle`` [rad] excites, up to ``max_order``:
    multiples of 2π/cycle (½ for a four-stroke, 1 for a two-stroke)."""
    step = 2.0 * math.pi / cycle
    return step * np.arange(1, int(math.floor(max_order / step + 1e-9)) + 1, dtype=np.float64)


def order_kind(order: float, firing_angles) -> str:
    """``"major"`` if the cylinders' excitations of ``order`` add in phase, else
    ``"integer"`` or ``"half"``."""
    phases = np.exp(1j * order * np.asarray(firing_angles, dtype=float))
    n = len(phases)
    if abs(abs(np.sum(phases)) - n) <= IN_PHASE * n:
        return "major"
    return "integer" if abs(order - round(order)) < 1e-9 else "half"


def critical_speeds(modal: Modal, orders, speed_range: tuple[float, float],
                    damped: bool = False) -> list[Critical]:
    """The criticals of every elastic mode and order within ``speed_range`` [rpm] (inclusive),
    by rising speed; with ``damped`` those of the damped line's modes (``modal.damped``,
    numbered from 1 by rising f_n), where the order meets the natural frequency f_n = |λ|/2π
    and the excitation sums the complex shape's amplitudes (for real shapes the same sum)."""
    scene = modal.line.scene
    firing = np.asarray(scene.mechanism.firing_angles, dtype=float)
    line = modal.line
    dof_of = np.zeros(len(firing), dtype=int)
    for s, st in enumerate(line.shaft.stations):
        for k in st.cylinders:
            dof_of[k - 1] = line.station_dof[s]
    modes = ([(i + 1, d.omega_n / (2 * math.pi), d.shape) for i, d in enumerate(modal.damped)]
             if damped else [(m.number, m.f, m.shape) for m in modal.modes])
    lo, hi = speed_range
    out = []
    for number, f, shape in modes:
        amp = shape[dof_of]
        for q in orders:
            rpm = 60.0 * f / q
            if lo <= rpm <= hi:
                vector = abs(np.sum(amp * np.exp(1j * q * firing)))
                out.append(Critical(number, float(q), order_kind(q, firing), float(rpm),
                                    float(vector / np.sum(np.abs(amp)))))
    return sorted(out, key=lambda c: c.rpm)


def speed_range(scene) -> tuple[float, float]:
    """The speeds [rpm] whose criticals are listed: ``[shaft] speed_range``, else 0 to 1.2 times
    the highest speed the scene names (initial, governed, prescribed, starter no-load)."""
    given = scene.shaft.speed_range if scene.shaft is not None else ()
    rpm = 30.0 / math.pi
    if given:
        return given[0] * rpm, given[-1] * rpm
    gv, run = scene.governor, scene.run
    named = [scene.initial.omega, gv.speed, gv.speed_zero, run.speed, *run.speed_table]
    if scene.starter.torque > 0:
        named.append(scene.starter.noload_speed)
    return 0.0, 1.2 * max(abs(v) for v in named) * rpm
