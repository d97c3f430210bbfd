"""The steady forced response of an elastic shaft line (``[shaft]``) to the engine's excitation,
order by order, over a range of speeds: the frequency-domain torsional analysis a damper is
sized with, at constant (cycle-mean) inertias (docs: Theory, *Forced torsional response*).

**Excitation.** At a constant mean speed Ω every station turns at φ = Ω t, and cylinder c
drives its station with its tangential gas torque T_c(φ) = F_c(φ)·u_c(φ) (F_c the gas force
on its piston at full load, as the rigid model applies it, per-cylinder fuel and pressure
factors and combustion offsets included; u_c = ds_c/dφ), and each station s with the inertia
torque of its cylinders' masses at constant speed, −½ J′_s(φ) Ω² (the term ½ J′ φ̇² of the
reduced equation moved to the right). Their Fourier coefficients over the cycle Θ (4π for a
four-stroke) at the engine orders q = m·2π/Θ [1/rev],

    T̂_q = (2/Θ) ∫₀^Θ T(φ) e^{−i q φ} dφ,   T(φ) = T̄ + Σ_q Re(T̂_q e^{i q φ}),

are integrated piece by piece between the gas tables' corners (Gauss–Legendre on each piece,
exact to rounding for a smooth piece), so that a kink or a jump of the pressure costs nothing
in accuracy. φ is the shaft angle from the mechanism's reference; cylinder c's phase enters
through its own firing angle φ_c: a cylinder whose torque is T₁ shifted, T_c(φ) = T₁(φ − φ_c),
has T̂_c,q = T̂_1,q e^{−i q φ_c}. The mean T̄ twists the line statically and is not vibration;
it is left out.

**Response.** With M the cycle-mean inertias, K and C the line's stiffness and damping
(:class:`~transient.shaft.line.ShaftLine`), each order is a harmonic at ω = qΩ and the steady
angles are ϑ(t) = Σ_q Re(X_q e^{i q Ω t}) with (K − ω² M + i ω C) X_q = F_q, solved banded.
An element joining dofs a and b (a the nearer the front end) of stiffness k and damping c
carries T_e = (k + i ω c)(X_a − X_b) and dissipates ½ ω² c |X_a − X_b|² on average; as the
orders are distinct harmonics, these powers add.

**Synthesis.** The vibratory torque of an element over the cycle is the sum of its orders'
harmonics, T_e(φ) = Σ_q Re(T_e,q e^{i q φ}); its peak-to-peak is max − min of that signal
(located on a grid of 16 points per period of the highest harmonic, then refined by
Newton's method on dT/dφ = 0). The sum of the orders'
amplitudes Σ_q |T_e,q| is the bound the classical tables use: half the peak-to-peak never
exceeds it, and it is reached only if every order peaks at one angle.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..assemble import breakpoints, union_of_angles
from ..errors import SceneError
from ..scene.queries import gas_phases, gas_tables
from ..shaft import ShaftLine
from .loads.common import gas_forces
from .torsion import engine_orders, shaft_elements

Array = NDArray[np.float64]
Complex = NDArray[np.complex128]

#: Longest piece of the cycle one Gauss–Legendre rule integrates [rad] (4°): order 12 turns
#: through 48° over it, which a rule of degree 19 integrates to rounding.
PIECE = math.radians(4.0)
#: Gauss–Legendre points per piece (exact for polynomials of degree 2·GAUSS − 1).
GAUSS = 10
#: Grid points per harmonic of the cycle on which the synthesised signal's extremes are found
#: before Newton's refinement.
GRID_PER_HARMONIC = 16
#: Newton steps refining each extreme of the synthesised signal.
NEWTON_STEPS = 4


@dataclass(frozen=True)
class Excitation:
    """A scene's excitation of its shaft line by engine order: ``orders`` [1/rev]; per
    cylinder the gas torque's complex amplitudes ``gas`` [N m] (n_cyl, n_orders); per station
    the coefficients ``inertia`` [N m s²] (n_stations, n_orders) of −½ J′_s(φ), whose product
    with Ω² is the inertia torque's amplitude; ``cycle`` [rad] the period of the orders."""

    orders: Array
    gas: Complex
    inertia: Complex
    cycle: float

    def at_dofs(self, line: ShaftLine, omega: float) -> Complex:
        """The amplitudes F_q of every dof at the mean speed ``omega`` [rad/s], (n_dofs,
        n_orders): each cylinder's gas torque on its station, each station's inertia torque."""
        F = np.zeros((line.n, self.orders.size), dtype=np.complex128)
        for s, st in enumerate(line.shaft.stations):
            dof = line.station_dof[s]
            F[dof] = omega * omega * self.inertia[s]
            for k in st.cylinders:
                F[dof] += self.gas[k - 1]
        return F


def check_steady(scene) -> None:
    """Raise :class:`~transient.errors.SceneError` where the scene's gas force is not the same
    in every cycle at a steady speed, which a steady response by engine orders needs:
    misfires (every n cycles, listed cycles, random) repeat over many cycles, and a cylinder
    with ``[gas.woschni]`` integrates its closed part at the speed it runs."""
    gas = scene.gas
    if gas.woschni is not None:
        raise SceneError("gas.woschni", "the steady forced response takes the gas force from "
                                        "the cycle tables, which without wall heat do not "
                                        "depend on the speed; Woschni's wall heat does: leave "
                                        "[gas.woschni] out for the response (the adiabatic "
                                        "Wiebe cycle)", file=scene.source_file)
    for i, c in enumerate(gas.cylinders):
        for key in ("misfire_cycles", "misfire_every", "misfire_rate"):
            if key in c.combustion_keys:
                raise SceneError(f"gas.cylinders[{i}].{key}",
                                 "a misfire makes the excitation differ from cycle to cycle; "
                                 "the steady forced response needs the same cycle every cycle: "
                                 "leave the misfires out (a cut-out cylinder, cut_out = true, "
                                 "is steady)", file=scene.source_file)


def cylinder_gas_forces(scene, phi) -> Array:
    """Each piston's gas force [N] at the shaft angles ``phi`` [rad], (n_cyl, n), at full fuel
    with each cylinder's fuel factor φ_k, pressure factor β_k and combustion offset δ_k:
    β_k·(F_mot(φ) + φ_k (F_full(φ − δ_k) − F_mot(φ − δ_k))), as the rigid model applies them
    (:class:`transient.scene.records.Cylinder`)."""
    phi = np.atleast_1d(np.asarray(phi, dtype=np.float64))
    force = gas_forces(scene, phi, 1.0)
    if not scene.gas.cylinders:
        return force
    motored = gas_forces(scene, phi, 0.0)
    for c in scene.gas.cylinders:
        k = c.cylinder - 1
        full, base = force[k], motored[k]
        if c.combustion_offset:
            full = gas_forces(scene, phi - c.combustion_offset, 1.0)[k]
            base = gas_forces(scene, phi - c.combustion_offset, 0.0)[k]
        force[k] = c.pressure * (motored[k] + c.fuel * (full - base))
    return force


def _pieces(scene) -> Array:
    """The shaft angles in [0, cycle] between which every cylinder's gas force is smooth: its
    tables' corners at its phase (the full-load one moved by a combustion offset), subdivided
    to at most :data:`PIECE`."""
    mech = scene.mechanism
    period = mech.cycle
    full, motored = gas_tables(scene)
    phases = gas_phases(scene)
    corners = np.zeros(1)
    if full is not None:
        shift = np.zeros(mech.n_cylinders)
        for c in scene.gas.cylinders:
            shift[c.cylinder - 1] = c.combustion_offset
        corners = union_of_angles(corners, breakpoints(full, phases + shift, period), period)
        if motored is not None:
            corners = union_of_angles(corners, breakpoints(motored, phases, period), period)
    edges = np.append(np.sort(np.mod(corners, period)), period)
    out = [np.linspace(a, b, max(1, math.ceil((b - a) / PIECE)) + 1)[:-1]
           for a, b in zip(edges[:-1], edges[1:]) if b > a]
    return np.append(np.concatenate(out), period)


def _nodes(scene) -> tuple[Array, Array]:
    """(angles, weights) of Gauss–Legendre rules on every piece of :func:`_pieces`."""
    x, w = np.polynomial.legendre.leggauss(GAUSS)
    edges = _pieces(scene)
    a, b = edges[:-1, None], edges[1:, None]
    return (0.5 * (a + b) + 0.5 * (b - a) * x).ravel(), (0.5 * (b - a) * w).ravel()


def check_orders(orders, cycle: float) -> Array:
    """``orders`` [1/rev] as an array, each a positive multiple of 2π/``cycle``; a ValueError
    names one that is not."""
    orders = np.atleast_1d(np.asarray(orders, dtype=np.float64))
    step = 2.0 * math.pi / cycle
    m = orders / step
    bad = (orders <= 0.0) | (np.abs(m - np.round(m)) > 1e-9 * np.maximum(m, 1.0))
    if orders.size == 0 or np.any(bad):
        which = f"order {orders[bad][0]:g}" if np.any(bad) else "no order"
        raise ValueError(f"{which}: give engine orders that are positive multiples of {step:g} "
                         f"per revolution (the cycle of {math.degrees(cycle):g}°)")
    return orders


def excitation(line: ShaftLine, orders=None) -> Excitation:
    """The excitation of ``line``'s scene by engine order (:class:`Excitation`; default
    orders: :func:`~.torsion.engine_orders` up to 12)."""
    scene = line.scene
    check_steady(scene)
    mech = scene.mechanism
    cycle = mech.cycle
    orders = engine_orders(cycle) if orders is None else check_orders(orders, cycle)
    phi, w = _nodes(scene)
    terms = mech.reference_terms()
    u = np.array([terms(float(p))[2] for p in phi]).T  # (n_cyl, n): ds_c/dφ
    dJ = np.array([line.station_inertia(float(p))[1] for p in phi]).T  # (n_stations, n)
    kernel = ((2.0 / cycle) * w[:, None] * np.exp(-1j * np.outer(phi, orders))).astype(
        np.complex128)
    gas = (cylinder_gas_forces(scene, phi) * u).astype(np.complex128) @ kernel
    return Excitation(orders, gas, (-0.5 * dJ).astype(np.complex128) @ kernel, cycle)


@dataclass(frozen=True)
class ForcedResponse:
    """The steady response of a shaft line at the mean speeds ``omega`` [rad/s] (n_s,) to the
    ``orders`` [1/rev] (n_q,) of its excitation (module docs for the conventions).

    Complex amplitudes, each signal Σ_q Re(A_q e^{i q φ}): ``force`` [N m] (n_s, n_q, n_dofs)
    on the dofs (:attr:`~transient.shaft.line.ShaftLine.names`), ``angle`` [rad] (n_s, n_q, n_dofs) of the dofs,
    ``torque`` [N m] (n_s, n_q, n_elements) of the ``elements`` (labels; dof a − dof b, a the
    nearer the front end). ``power`` [W] (n_s, n_q, n_elements): the mean power each element
    dissipates by order. Over all the orders: ``torque_pp`` [N m] (n_s, n_elements), the
    peak-to-peak of the synthesised torque over the cycle, ``torque_sum`` [N m] the sum of the
    orders' amplitudes, ``angle_pp`` [rad] (n_s, n_dofs) the peak-to-peak of each dof's angle
    about the steady rotation (the line's swing as one body, the speed's irregularity,
    included)."""

    line: ShaftLine
    omega: Array
    orders: Array
    elements: tuple[str, ...]
    element_dofs: tuple[tuple[int, int], ...]
    force: Complex
    angle: Complex
    torque: Complex
    power: Array
    torque_pp: Array
    torque_sum: Array
    angle_pp: Array

    @property
    def rpm(self) -> Array:
        return self.omega * (30.0 / math.pi)

    @property
    def cycle(self) -> float:
        return float(self.line.scene.mechanism.cycle)


def forced_response(line: ShaftLine, omega, orders=None) -> ForcedResponse:
    """The steady forced response of ``line`` at the mean speeds ``omega`` [rad/s] (each > 0)
    to the ``orders`` [1/rev] of its scene's excitation (default: every engine order up to
    12)."""
    omega = np.atleast_1d(np.asarray(omega, dtype=np.float64))
    if omega.size == 0 or not np.all(np.isfinite(omega) & (omega > 0.0)):
        raise ValueError("give mean speeds > 0 [rad/s]: at rest the free line has no steady "
                         "response")
    exc = excitation(line, orders)
    q = exc.orders
    elements = shaft_elements(line, viscous=True)
    a = np.array([e[1] for e in elements])
    b = np.array([e[2] for e in elements])
    rows = line.element_rows()  # (the same elements, in the same order, with their k and c)
    if not np.array_equal(rows[:, :2], np.column_stack([a, b])):
        raise RuntimeError("the shaft line's element table and its labels disagree")
    k, c = rows[:, 2], rows[:, 3]
    band, (Kb, Mb, Cb) = band_of(line.K, np.diag(line.mean_inertia()), line.C)
    n_s, n_q = omega.size, q.size
    F = np.empty((n_s, n_q, line.n), dtype=np.complex128)
    X = np.empty_like(F)
    for i, w0 in enumerate(omega):
        F[i] = exc.at_dofs(line, float(w0)).T
        for j, w in enumerate(q * w0):
            X[i, j] = scipy.linalg.solve_banded(band, Kb - w * w * Mb + 1j * w * Cb,
                                                F[i, j])
    w = (q[None, :] * omega[:, None])[:, :, None]
    twist = X[:, :, a] - X[:, :, b]
    torque = (k + 1j * w * c) * twist
    power = 0.5 * w * w * c * np.abs(twist) ** 2
    harmonics = q * exc.cycle / (2.0 * math.pi)
    return ForcedResponse(line, omega, q, tuple(e[0] for e in elements),
                          tuple(zip(a.tolist(), b.tolist())), F, X, torque, power,
                          peak_to_peak(torque, harmonics), np.abs(torque).sum(axis=1),
                          peak_to_peak(X, harmonics))


def band_of(*matrices) -> tuple[tuple[int, int], list[Array]]:
    """((lower, upper), each of ``matrices`` in scipy's banded storage) over the band that
    holds every one's nonzero entries (the line's: tridiagonal, a damper's ring one place off
    it), for :func:`scipy.linalg.solve_banded`."""
    rows, cols = np.nonzero(np.any([np.asarray(A) != 0.0 for A in matrices], axis=0))
    lower = int(max(0, np.max(rows - cols, initial=0)))
    upper = int(max(0, np.max(cols - rows, initial=0)))
    out = []
    for A in matrices:
        n = A.shape[0]
        ab = np.zeros((lower + upper + 1, n))
        for d in range(-lower, upper + 1):
            ab[upper - d, max(d, 0):n + min(d, 0)] = np.diagonal(A, d)
        out.append(ab)
    return (lower, upper), out


def synthesise(amplitudes, harmonics, psi) -> Array:
    """Σ_m Re(A_m e^{i m ψ}) at the angles ``psi`` [rad of the cycle, 2π a whole cycle]:
    ``amplitudes`` (..., n_m) complex, ``harmonics`` m (n_m,) per cycle. Returns (..., n_psi)."""
    A = np.asarray(amplitudes, dtype=np.complex128)
    phase = np.exp(1j * np.outer(np.asarray(harmonics, dtype=float), np.atleast_1d(psi)))
    return (A @ phase).real


def peak_to_peak(amplitudes: Complex, harmonics) -> Array:
    """max − min over the cycle of Σ_m Re(A_m e^{i m ψ}) for ``amplitudes`` (n_s, n_m, n) by
    harmonic ``harmonics`` m; (n_s, n). Each extreme is found on a grid of 16 points per
    period of the highest harmonic and refined by Newton's method on the signal's
    derivative."""
    A = np.moveaxis(np.asarray(amplitudes, dtype=np.complex128), 1, -1)  # (n_s, n, n_m)
    m = np.asarray(harmonics, dtype=float)
    size = int(GRID_PER_HARMONIC * max(1.0, float(np.max(m))))
    spectrum = np.zeros(A.shape[:-1] + (size // 2 + 1,), dtype=np.complex128)
    spectrum[..., np.round(m).astype(int)] = 0.5 * size * A
    signal = np.fft.irfft(spectrum, n=size, axis=-1)  # Σ_m Re(A_m e^{i m ψ}) on the grid
    grid = 2.0 * math.pi * np.arange(size) / size
    top = _refine(A, m, grid[np.argmax(signal, axis=-1)], np.max(signal, axis=-1), +1.0)
    low = _refine(A, m, grid[np.argmin(signal, axis=-1)], np.min(signal, axis=-1), -1.0)
    return top - low


def _refine(A: Complex, m: Array, psi: Array, value: Array, sign: float) -> Array:
    """The extreme near ``psi`` of Σ_m Re(A_m e^{i m ψ}) by Newton's method on its derivative,
    kept only where it is beyond the grid's ``value`` (the larger for ``sign`` +1)."""
    for _ in range(NEWTON_STEPS):
        e = A * np.exp(1j * m * psi[..., None])
        d1 = np.sum((1j * m * e).real, axis=-1)
        d2 = np.sum((-m * m * e).real, axis=-1)
        ok = sign * d2 < 0.0
        step = np.where(ok, -d1 / np.where(ok, d2, 1.0), 0.0)
        psi = psi + np.clip(step, -math.pi / m.max(), math.pi / m.max())
    refined = np.sum((A * np.exp(1j * m * psi[..., None])).real, axis=-1)
    return np.where(sign * refined > sign * value, refined, value)


def speed_grid(rpm_range: tuple[float, float], points: int, criticals=()) -> Array:
    """Mean speeds [rad/s] for a response: ``points`` evenly from ``rpm_range`` (a lower end of
    0 moved up one step: at rest there is no steady response) and every critical speed
    (:class:`~.torsion.Critical`) within it, where a peak lies."""
    lo, hi = rpm_range
    step = (hi - lo) / max(points - 1, 1)
    rpm = np.linspace(lo if lo > 0.0 else step, hi, points)
    rpm = np.union1d(rpm, [c.rpm for c in criticals if rpm[0] <= c.rpm <= hi])
    return rpm * (math.pi / 30.0)


def leading_orders(res: ForcedResponse, element: int, count: int) -> NDArray[np.intp]:
    """Indices of the ``count`` orders whose largest amplitude over the speeds in ``element``
    is greatest, the greatest first."""
    peaks = np.abs(res.torque[:, :, element]).max(axis=0)
    return np.argsort(peaks)[::-1][:count]
