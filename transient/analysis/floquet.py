"""Parametric stability of an elastic shaft line (``[shaft]``): the Floquet multipliers of the
line linearised about a steady rotation at mean speed Ω, each station's inertia varying with its
own angle (docs: Theory, *Linearised about a steady rotation: Hill's equation*, (T8)–(T10)).

**The linearised line.** Every dof turns at θ = Ω t + x with x small. Lagrange's equation (T2)
of each dof, linearised in x, is Hill's equation (T8) on all of them,

    M(t) ẍ + (C + Ω M′(t)) ẋ + (K + ½ Ω² M″(t)) x = f,

M(t) = diag J_d(Ω t) (a station's own inertia plus its cylinders' at its angle with their
phases; constant on rings and the driven inertia), M′, M″ its derivatives in θ, K and C the
line's (:class:`~transient.shaft.line.ShaftLine`). Its coefficients have the period 2π/(gΩ)
of the inertias, g the greatest common divisor of the orders in which they vary (1 for a
crank-slider, whose rod's obliquity puts odd orders into each cylinder's J; 2 for a Scotch
yoke). The applied moments (gas, load, governor) are the excitation; their dependence on the
twist is left out, as it is in (T8).

**Steady rotation.** The line's rigid-body motion is held: the mean angle Σ m_d x_d = 0 over
the dofs a spring ties (m_d the cycle-mean inertias, the weights of the absolute damping's
ω̄), by a torque f on them in proportion to m_d — a large flywheel or driven inertia turning
at Ω, or a governor. Without it the free line's rigid motion, which (T8) does not conserve
about θ = Ω t, would add multipliers near 1 that say nothing of the twist. The twists are
x = Q z with Q an orthonormal basis of {x : mᵀx = 0}; a viscous damper's ring, tied by no
spring, keeps only its speed (its angle enters no force). Projected on them (Qᵀ f = 0), the
reduced system is w′ = A(τ) w in τ = Ω t, w = (z, ż, ring speeds). For a constant-inertia
line without viscous rings its eigenvalues are the free line's damped ones less the rigid
motion: the elastic motions of the free line keep mᵀx = 0 by themselves (with a viscous ring,
whose speed the free line's mean includes, they differ as far as the ring moves that mean).

**Multipliers.** The monodromy matrix Φ = w(τ₀ + 2π/g) w(τ₀)⁻¹ is the product of the
fourth-order Magnus steps exp(h(A₁ + A₂)/2 + √3 h²[A₂, A₁]/12) at the two Gauss points of each
substep (Blanes, Casas, Oteo & Ros, Phys. Rep. 470 (2009)): the exponential integrates the
line's constant part exactly however stiff, so the substep follows the inertias' variation and
a fraction of the fastest mode's period (:data:`SUBSTEPS_PER_RAD`). Its eigenvalues μ are the
multipliers: a twist grows by |μ|max per period where |μ|max > 1 (parametric instability),
by e^{g ln|μ|max} per revolution.

**Where to look.** A line whose inertias vary in order h per revolution is parametrically
excited at hΩ, and instability regions open near hΩ = (ω_i + ω_j)/k (Mathieu, Hill; for a
multi-dof line the combination resonances, Nayfeh & Mook, *Nonlinear Oscillations*, ch. 5):
the principal regions at hΩ = 2ω_i, the second ones at hΩ = ω_i (O(ε²) wide, on the critical
speed of the inertia torque's own order h) and the sum-type combinations at hΩ = ω_i + ω_j
(:func:`parametric_resonances`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import reduce

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..shaft import ShaftLine

Array = NDArray[np.float64]

#: Samples per revolution of each station's J(θ) for its Fourier series: a crank-slider's
#: harmonics fall geometrically with λ = r/l, below rounding long before the 64th.
SERIES_SAMPLES = 256
#: A harmonic of a station's inertia counts where it exceeds this share of the line's largest
#: mean station inertia (rounding of the samples is some 1e-16 of it).
HARMONIC_FLOOR = 1e-12
#: Magnus substeps per radian of the fastest mode's phase (h ω_max/Ω ≤ 1/this), and at least
#: this many per radian of the highest inertia harmonic's: the method's error falls 16-fold per
#: halving of h, and with 1.5 the multipliers agree with an adaptive integration at rtol 1e-11
#: to 1e-8 (tests/unit/test_floquet.py), far below :data:`UNSTABLE`.
SUBSTEPS_PER_RAD = 1.5
#: ln|μ|max per period above which the line counts as parametrically unstable: far above what
#: the Magnus product's error makes of an undamped line's multipliers on the unit circle.
UNSTABLE = 1e-6
#: Harmonics of the inertias whose resonances :func:`parametric_resonances` lists: those of at
#: least this share of the largest harmonic's amplitude.
MARKED_HARMONIC = 0.1


@dataclass(frozen=True)
class InertiaSeries:
    """Each station's J_s(θ) as a Fourier series, J_s(θ) = Re Σ_h c_{s,h} e^{ihθ}: the orders
    ``orders`` [1/rev] that count (0 first), the coefficients ``coef`` (stations × orders), and
    ``g``, the largest whole number that divides every varying order (the inertias repeat every
    2π/g; 1 for constant ones)."""

    orders: NDArray[np.int64]
    coef: NDArray[np.complex128]
    g: int

    def at(self, theta) -> tuple[Array, Array, Array]:
        """(J, J′, J″) of every station at the angles ``theta`` (shape (n,)): each (n, stations)."""
        e = np.exp(1j * np.outer(np.asarray(theta, dtype=float), self.orders))
        h = self.orders.astype(float)
        return ((e @ self.coef.T).real, (e @ (1j * h * self.coef).T).real,
                (e @ (-h * h * self.coef).T).real)

    def amplitudes(self) -> Array:
        """The largest |c_{s,h}| over the stations of each varying order (orders[1:])."""
        return np.abs(self.coef[:, 1:]).max(axis=0) if self.orders.size > 1 else np.zeros(0)


def inertia_series(line: ShaftLine, samples: int = SERIES_SAMPLES) -> InertiaSeries:
    """The stations' inertias as Fourier series from ``samples`` equally spaced angles per
    revolution (exact to rounding for a smooth periodic J: the discrete transform aliases only
    the harmonics above samples/2, which are below rounding). ValueError if the upper quarter
    of the harmonics is not below :data:`HARMONIC_FLOOR`: the samples do not resolve J."""
    theta = 2.0 * math.pi * np.arange(samples) / samples
    J = np.array([line.station_inertia(t)[0] for t in theta])
    F = np.fft.rfft(J, axis=0) / samples
    F[1:] *= 2.0
    if samples % 2 == 0:
        F[-1] /= 2.0  # (the Nyquist term is its own conjugate)
    floor = HARMONIC_FLOOR * float(np.max(F[0].real))
    size = np.abs(F).max(axis=1)
    if np.any(size[samples // 4:] > floor):
        raise ValueError(f"the stations' J(θ) hold harmonics above order {samples // 4} "
                         f"(up to {size[samples // 4:].max():.3g} kg m²): not resolved by "
                         f"{samples} samples per revolution")
    orders = np.flatnonzero(size > floor)
    orders = np.union1d([0], orders).astype(np.int64)
    varying = [int(h) for h in orders if h > 0]
    g = reduce(math.gcd, varying) if varying else 1
    return InertiaSeries(orders, F[orders].T.copy(), g)


@dataclass(frozen=True)
class Reduced:
    """The line's reduced coordinates (module docs): ``G`` maps the reduced speeds to every
    dof's speed, ``X`` the reduced angles z to every dof's angle; ``nz`` twists, ``nv`` viscous
    rings' speeds; the constant parts of GᵀMG, GᵀCG and GᵀKX, and per station the outer
    products g_s g_sᵀ and g_s x_sᵀ that its varying inertia multiplies."""

    G: Array
    X: Array
    nz: int
    nv: int
    mass: Array
    damping: Array
    stiffness: Array
    gg: Array
    gx: Array


def reduce_line(line: ShaftLine) -> Reduced:
    """The reduced coordinates of ``line`` with its rigid-body motion held (module docs)."""
    tied = np.flatnonzero(np.diag(line.K) > 0.0)
    free = np.setdiff1d(np.arange(line.n), tied)
    Q = scipy.linalg.null_space(line.weights[tied][None, :])
    nz, nv = Q.shape[1], free.size
    G = np.zeros((line.n, nz + nv))
    G[np.ix_(tied, np.arange(nz))] = Q
    G[free, nz + np.arange(nv)] = 1.0
    X = np.zeros((line.n, nz))
    X[tied] = Q
    own = line.own_inertia
    stations = np.asarray(line.station_dof)
    own_varying = own.copy()
    own_varying[stations] = 0.0  # (a station's whole J, its own included, is the series')
    g_s, x_s = G[stations], X[stations]
    return Reduced(G=G, X=X, nz=nz, nv=nv, mass=G.T @ (own_varying[:, None] * G),
                   damping=G.T @ line.C @ G, stiffness=G.T @ line.K @ X,
                   gg=np.einsum("si,sj->sij", g_s, g_s), gx=np.einsum("si,sj->sij", g_s, x_s))


def system_matrices(red: Reduced, series: InertiaSeries, omega: float, tau) -> Array:
    """A(τ) of w′ = A(τ) w in τ = Ω t at the angles ``tau``: shape (len(tau), d, d),
    d = 2 nz + nv."""
    J, dJ, ddJ = series.at(tau)
    M = red.mass + np.einsum("ns,sij->nij", J, red.gg)
    D = red.damping + omega * np.einsum("ns,sij->nij", dJ, red.gg)
    K = red.stiffness + 0.5 * omega ** 2 * np.einsum("ns,sij->nij", ddJ, red.gx)
    nz, ns = red.nz, red.nz + red.nv
    A = np.zeros((len(J), nz + ns, nz + ns))
    A[:, :nz, nz:2 * nz] = np.eye(nz) / omega
    A[:, nz:, :nz] = -np.linalg.solve(M, K) / omega
    A[:, nz:, nz:] = -np.linalg.solve(M, D) / omega
    return A


def fastest_mode(red: Reduced, series: InertiaSeries) -> float:
    """ω_max [rad/s] of the reduced line at its mean inertias, undamped."""
    J0 = series.coef[:, 0].real
    M = red.mass + np.einsum("s,sij->ij", J0, red.gg)
    nz = red.nz
    if nz == 0:
        return 0.0
    values = scipy.linalg.eigvals(red.stiffness[:nz], M[:nz, :nz])
    return float(np.sqrt(np.max(np.abs(values))))


def substeps(red: Reduced, series: InertiaSeries, omega: float) -> int:
    """Magnus substeps over one period (:data:`SUBSTEPS_PER_RAD`)."""
    period = 2.0 * math.pi / series.g
    fastest = max(fastest_mode(red, series) / omega, float(series.orders[-1]), 1.0)
    return max(16, int(math.ceil(SUBSTEPS_PER_RAD * fastest * period)))


def monodromy(red: Reduced, series: InertiaSeries, omega: float, n: int | None = None
              ) -> Array:
    """Φ over one period 2π/g at mean speed ``omega`` [rad/s], by ``n`` Magnus steps (default
    :func:`substeps`)."""
    n = n or substeps(red, series, omega)
    h = 2.0 * math.pi / series.g / n
    start = h * np.arange(n)
    c = math.sqrt(3.0) / 6.0
    A1 = system_matrices(red, series, omega, start + (0.5 - c) * h)
    A2 = system_matrices(red, series, omega, start + (0.5 + c) * h)
    # (speeds in units of the fastest mode's: the blocks of A balanced, so that the
    # exponentials need few squarings; a similarity, which leaves the multipliers as they are)
    d = np.ones(A1.shape[1])
    d[red.nz:] = 1.0 / max(fastest_mode(red, series), omega)
    A1, A2 = (a * d[:, None] / d[None, :] for a in (A1, A2))
    exponents = 0.5 * h * (A1 + A2) + (math.sqrt(3.0) / 12.0) * h * h * (A2 @ A1 - A1 @ A2)
    phi = np.eye(A1.shape[1])
    for step in exponentials(exponents):
        phi = step @ phi
    return phi


#: Degree of the Taylor polynomial of :func:`exponentials`, and the 1-norm its argument is
#: scaled to: the remainder is below 0.5¹⁵/15! ≈ 2e-17 of the norm.
TAYLOR_DEGREE, TAYLOR_NORM = 14, 0.5


def exponentials(X) -> Array:
    """exp of each matrix of the stack ``X`` (n, d, d): the Taylor polynomial of degree
    :data:`TAYLOR_DEGREE` of X/2ˢ, squared s times, s the least for which every ‖X/2ˢ‖₁ is at
    most :data:`TAYLOR_NORM` (scaling and squaring, Moler & Van Loan 2003, method 3), for the
    whole stack at once: the Magnus exponents of one speed have about one norm."""
    norm = float(np.abs(X).sum(axis=1).max()) if X.size else 0.0
    s = max(0, math.ceil(math.log2(norm / TAYLOR_NORM))) if norm > 0.0 else 0
    Y = X / 2.0 ** s
    term = Y
    out = np.eye(X.shape[-1]) + Y
    for k in range(2, TAYLOR_DEGREE + 1):
        term = term @ Y / k
        out += term
    for _ in range(s):
        out = out @ out
    return out


@dataclass(frozen=True)
class Floquet:
    """The multipliers of the linearised line at each mean speed: ``rpm``, ``multipliers``
    (speeds × d, by falling modulus) over one period 2π/g of the inertias, ``g``."""

    line: ShaftLine
    rpm: Array
    multipliers: NDArray[np.complex128]
    g: int

    @property
    def mu_max(self) -> Array:
        """|μ|max per period at each speed."""
        return np.abs(self.multipliers[:, 0])

    @property
    def growth_per_rev(self) -> Array:
        """g·ln|μ|max: the largest twist's growth per revolution in e-folds (< 0: decays)."""
        return self.g * np.log(self.mu_max)

    @property
    def unstable(self) -> NDArray[np.bool_]:
        return np.log(self.mu_max) > UNSTABLE

    def unstable_ranges(self) -> list[tuple[float, float]]:
        """The runs of consecutive unstable speeds, as (first, last) [rpm]."""
        out = []
        flags = self.unstable
        i = 0
        while i < flags.size:
            if flags[i]:
                j = i
                while j + 1 < flags.size and flags[j + 1]:
                    j += 1
                out.append((float(self.rpm[i]), float(self.rpm[j])))
                i = j
            i += 1
        return out


def multipliers(line: ShaftLine, omega: float, series: InertiaSeries | None = None,
                red: Reduced | None = None, n: int | None = None) -> NDArray[np.complex128]:
    """The Floquet multipliers at mean speed ``omega`` [rad/s] > 0, by falling modulus."""
    if not omega > 0.0:
        raise ValueError(f"multipliers: a mean speed > 0 rad/s, got {omega!r}")
    series = series or inertia_series(line)
    red = red or reduce_line(line)
    mu = np.linalg.eigvals(monodromy(red, series, omega, n)).astype(np.complex128)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def floquet_chart(line: ShaftLine, omegas) -> Floquet:
    """The multipliers at each mean speed of ``omegas`` [rad/s] (each > 0)."""
    series, red = inertia_series(line), reduce_line(line)
    mu = np.array([multipliers(line, float(w), series, red) for w in omegas])
    return Floquet(line, np.asarray(omegas, dtype=float) * 30.0 / math.pi, mu, series.g)


def growth_per_period(line: ShaftLine, omega: float, series=None, red=None) -> float:
    """ln|μ|max at ``omega`` [rad/s]: > 0 where the line is parametrically unstable."""
    return float(np.log(np.abs(multipliers(line, omega, series, red)[0])))


def region_edge(line: ShaftLine, inside: float, outside: float, xtol: float = 1e-9) -> float:
    """The mean speed [rad/s] between ``inside`` (unstable) and ``outside`` (stable) where
    |μ|max = 1, by Brent's method."""
    from scipy.optimize import brentq

    series, red = inertia_series(line), reduce_line(line)
    f_in, f_out = (growth_per_period(line, w, series, red) for w in (inside, outside))
    if not (f_in > 0.0 > f_out):
        raise ValueError(f"region_edge: ln|μ|max {f_in:.3g} at {inside:.6g} rad/s and "
                         f"{f_out:.3g} at {outside:.6g}: not an edge between them")
    return float(brentq(lambda w: growth_per_period(line, w, series, red), inside, outside,
                        xtol=xtol * abs(inside)))


@dataclass(frozen=True)
class Resonance:
    """Where an instability region may open: order ``order`` of the inertias' variation at
    ``rpm`` with modes ``i`` ≤ ``j`` (numbered as :class:`~.torsion.Mode`), hΩ = (ω_i + ω_j)/k
    (``k``); ``kind`` "principal" (i = j, k = 1), "second" (i = j, k = 2) or "combination"."""

    rpm: float
    order: int
    i: int
    j: int
    k: int
    kind: str

    @property
    def label(self) -> str:
        if self.kind == "principal":
            return f"2f{self.i}/{self.order}"
        if self.kind == "second":
            return f"f{self.i}/{self.order}"
        return f"(f{self.i}+f{self.j})/{self.order}"


def parametric_resonances(line: ShaftLine, mode_freqs, rpm_range) -> list[Resonance]:
    """The speeds within ``rpm_range`` where hΩ = 2ω_i, ω_i or ω_i + ω_j, for the orders h of
    the inertias of at least :data:`MARKED_HARMONIC` of the largest harmonic's amplitude and the
    elastic modes' frequencies ``mode_freqs`` [Hz] (rising, mode 1 first)."""
    series = inertia_series(line)
    amp = series.amplitudes()
    if amp.size == 0 or amp.max() <= 0.0:
        return []
    orders = series.orders[1:][amp >= MARKED_HARMONIC * amp.max()]
    lo, hi = rpm_range
    out = []
    f = list(mode_freqs)
    for h in orders:
        for i in range(len(f)):
            for j in range(i, len(f)):
                for k, kind in ((1, "principal"), (2, "second")) if i == j else ((1,
                                                                                  "combination"),):
                    rpm = 60.0 * (f[i] + f[j]) / (k * h)
                    if lo <= rpm <= hi:
                        out.append(Resonance(rpm, int(h), i + 1, j + 1, k, kind))
    return sorted(out, key=lambda r: r.rpm)
