"""The ideal reciprocating compressor cycle against the local crank angle: the cylinder pressure
of a compressor or pump whose piston works against its gas, as a periodic pressure table.

The textbook's ideal indicator diagram of a reciprocating compressor with clearance (Rogers &
Mayhew, *Engineering Thermodynamics: Work and Heat Transfer*, the chapter on reciprocating
compressors; derived below piece by piece, so the closed forms stand on their own), with self-acting
valves that open as soon as the pressure reaches the line's
pressure (no valve losses, no leakage) and the constant suction and discharge pressures p_s,
p_d. Over one turn, from the top dead centre t (least volume V_c, the clearance):

====================  ==============================================================
t → x_4               re-expansion of the clearance gas, ``p_d·(V_c/V)^n_e``, to p_s
x_4 → b               suction at p_s (the suction valve open from V_4 to V_1)
b → x_2               polytropic compression ``p_s·(V_1/V)^n`` to p_d
x_2 → t + 2π          discharge at p_d (the discharge valve open from V_2 to V_c)
====================  ==============================================================

with V_1 = V(b) = V_c + V_s, V_4 = V_c·(p_d/p_s)^(1/n_e) and V_2 = V_1·(p_s/p_d)^(1/n). The curve
is continuous; its slope jumps where a valve opens (x_4, x_2: table corners, so breakpoints of the
stepper). The loop work follows piece by piece (a polytrope from 1 to 2 does
(p₁V₁ − p₂V₂)/(n − 1)):

    ∮p dV = (p_d V_c − p_s V_4)/(n_e − 1) + p_s (V_1 − V_4) + (p_s V_1 − p_d V_2)/(n − 1)
            + p_d (V_c − V_2),

negative: the shaft does work on the gas. With n_e = n it is the textbook's closed form
−n/(n − 1)·p_s·(V_1 − V_4)·((p_d/p_s)^((n−1)/n) − 1), V_1 − V_4 = V_s·η_v the volume drawn in
per cycle and η_v = 1 − c((p_d/p_s)^(1/n) − 1) the volumetric efficiency, c = V_c/V_s the
clearance ratio (:func:`ideal_compressor_work`); the tests check the table against both.

The piston force is (p − p0)·F_p as for every pressure model (Gots (33)); p0, the crankcase
pressure, is the caller's (a refrigerant compressor's crankcase holds the suction pressure, an
air compressor's the atmosphere). The cycle is the steady ideal one at every speed: no valve
dynamics, no heat transfer beyond the polytropes, no leakage past the rings, and at rest the
same pressures as when running (a start from rest starts against them).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import SceneError
from ..roots import bisect_root
from .gas import (
    ANGLE_TOL,
    DEFAULT_STEP,
    IndicatedCycle,
    VolumeFunction,
    deg_text,
    table_from_function,
    volume_at,
    wrapped_pieces,
)

__all__ = ["CompressorCycle", "compressor_cycle", "ideal_compressor_work"]


@dataclass(frozen=True, eq=False)
class CompressorCycle(IndicatedCycle):
    """Pressure table of an ideal compressor cycle, with its closed-form quantities.

    A :class:`~transient.forces.gas.PressureTable` (use it wherever one is expected). Volumes
    in m³, pressures in Pa, angles in rad (local: 0 is the cylinder's top dead centre), work in J.

    Attributes
    ----------
    work : float
        ∮p dV per cycle [J], < 0 (the gas takes work); :attr:`indicated_work` is its negative.
    p_suction, p_discharge : float
        p_s and p_d [Pa].
    n, n_reexpansion : float
        Polytropic exponents of the compression and of the clearance gas's re-expansion [1].
    clearance_ratio : float
        c = V_c/V_s [1].
    v_c, v_1, v_2, v_4 : float
        Clearance volume, volume at the bottom dead centre, where the discharge valve opens and
        where the suction valve opens [m³].
    angle_discharge, angle_suction : float
        Local angles [rad] where the discharge valve opens (V = V_2) and where the suction valve
        opens (V = V_4), in [0, period).
    interpolation_error : float
        Relative tabulation error estimate returned by
        :func:`~transient.forces.gas.table_from_function`.
    """

    p_suction: float
    p_discharge: float
    n: float
    n_reexpansion: float
    clearance_ratio: float
    v_c: float
    v_1: float
    v_2: float
    v_4: float
    angle_discharge: float
    angle_suction: float
    interpolation_error: float

    @property
    def v_h(self) -> float:
        """Swept volume V_s = V_1 − V_c [m³]."""
        return self.v_1 - self.v_c

    @property
    def indicated_work(self) -> float:
        """Work the piston does on the gas per cycle, −∮p dV [J] (> 0)."""
        return -self.work

    @property
    def suction_volume(self) -> float:
        """Volume drawn in per cycle at p_s, V_1 − V_4 [m³]."""
        return self.v_1 - self.v_4

    @property
    def volumetric_efficiency(self) -> float:
        """η_v = (V_1 − V_4)/V_s [1]: the share of the swept volume filled with fresh gas."""
        return self.suction_volume / self.v_h


def ideal_compressor_work(p_suction: float, p_discharge: float, n: float, swept: float,
                          clearance_ratio: float) -> tuple[float, float]:
    """The textbook's closed form, for one exponent n of compression and re-expansion:
    ``(W, η_v)`` with W = n/(n − 1)·p_s·V_s·η_v·((p_d/p_s)^((n−1)/n) − 1) the work per cycle
    done on the gas [J] and η_v = 1 − c((p_d/p_s)^(1/n) − 1): with V_4 = c·V_s·(p_d/p_s)^(1/n) the
    two polytropes' works combine into n/(n − 1)·p_s·(V_1 − V_4)·(r^((n−1)/n) − 1), and
    V_1 − V_4 = V_s(1 + c − c·r^(1/n)) = V_s·η_v."""
    r = p_discharge / p_suction
    eta_v = 1.0 - clearance_ratio * (r ** (1.0 / n) - 1.0)
    return n / (n - 1.0) * p_suction * swept * eta_v * (r ** ((n - 1.0) / n) - 1.0), eta_v


def compressor_cycle(volume: VolumeFunction, *, p_suction: float, p_discharge: float, n: float,
                     clearance_ratio: float, n_reexpansion: float | None = None,
                     strokes: int = 2, step: float = DEFAULT_STEP,
                     dead_centres: tuple[float, float] = (0.0, math.pi)) -> CompressorCycle:
    """The ideal compressor cycle of the module docstring, tabulated against the local angle.

    Parameters
    ----------
    volume : callable
        Vectorised ``V(x)`` [m³] of the cylinder at local crank angle x [rad], made with the
        clearance volume c·V_s (``Mechanism.volume_function``): V(t) = V_c, V(b) = V_c + V_s.
    p_suction, p_discharge : float
        p_s > 0 and p_d > p_s [Pa], absolute.
    n : float
        Compression polytropic exponent, > 1 (an adiabatic compression of an ideal gas: its κ;
        air 1.4, R134a vapour about 1.1).
    clearance_ratio : float
        c = V_c/V_s > 0, small enough that the clearance gas re-expands to p_s before the
        bottom dead centre and the compression reaches p_d before the top one.
    n_reexpansion : float, optional
        Re-expansion exponent n_e > 1; default n.
    strokes : int
        The mechanism's cycle, which must be one turn (2): a compressor works once a turn.
    step : float
        Knot spacing of the tabulation [rad] (:func:`~transient.forces.gas.table_from_function`).
    dead_centres : (float, float)
        Local angles [rad] of the top and bottom dead centre (``Mechanism.dead_centre_angles``).

    Raises
    ------
    SceneError
        ``gas.model`` for a mechanism whose cycle is two turns; ``gas.p_suction``,
        ``gas.p_discharge``, ``gas.n``, ``gas.n_reexpansion``, ``gas.clearance_ratio`` for values
        out of range, each with what is allowed.
    """
    if strokes != 2:
        raise SceneError("gas.model", f"\"compressor\" works once a turn, but the mechanism's "
                                      f"cycle is {180 * strokes}° (strokes = {strokes}); give "
                                      f"the mechanism strokes = 2")
    period = 2.0 * math.pi
    if not (math.isfinite(p_suction) and p_suction > 0.0):
        raise SceneError("gas.p_suction", f"{p_suction!r} Pa; an absolute pressure must be "
                                          f"finite and > 0")
    if not (math.isfinite(p_discharge) and p_discharge > p_suction):
        raise SceneError("gas.p_discharge", f"{p_discharge!r} Pa; it must be finite and above "
                                            f"p_suction = {p_suction!r} Pa")
    n_e = n if n_reexpansion is None else n_reexpansion
    for key, value in (("gas.n", n), ("gas.n_reexpansion", n_e)):
        # n = 1 (isothermal) would need the logarithmic work; real compressors have 1.05-1.4.
        if not (math.isfinite(value) and value > 1.0):
            raise SceneError(key, f"polytropic exponent {value!r}; it must be > 1")
    if not (math.isfinite(clearance_ratio) and clearance_ratio > 0.0):
        raise SceneError("gas.clearance_ratio", f"{clearance_ratio!r}; the clearance ratio "
                                                f"V_c/V_s must be > 0")
    r = p_discharge / p_suction
    tdc, bdc = dead_centres
    v_c = volume_at(volume, tdc)
    v_1 = volume_at(volume, bdc)
    v_4 = v_c * r ** (1.0 / n_e)
    v_2 = v_1 / r ** (1.0 / n)
    for key, exponent, fails in (("gas.n_reexpansion" if n_reexpansion is not None else "gas.n",
                                  n_e, v_4 >= v_1),
                                 ("gas.n", n, v_2 <= v_c)):
        if fails:
            top = 1.0 / (r ** (1.0 / exponent) - 1.0)
            what = ("the clearance gas re-expands past the bottom dead centre" if v_4 >= v_1
                    else "the compression reaches p_discharge only below the clearance volume")
            raise SceneError("gas.clearance_ratio",
                             f"c = {clearance_ratio:.6g}: {what}, so the compressor delivers "
                             f"nothing; at p_d/p_s = {r:.6g} and {key.split('.')[1]} = "
                             f"{exponent:.6g} it must be < 1/((p_d/p_s)^(1/n) − 1) = {top:.6g}")
    # V rises monotonically from the top to the bottom dead centre and falls back: bisection
    # finds each valve's opening to the last bit.
    x_4 = bisect_root(lambda x: volume_at(volume, x) - v_4, tdc, bdc)
    x_2 = bisect_root(lambda x: volume_at(volume, x) - v_2, bdc, tdc + period)
    ends = (tdc, x_4, bdc, x_2, tdc + period)
    if min(np.diff(ends)) <= ANGLE_TOL * period:
        raise SceneError("gas.p_discharge", f"p_d/p_s = {r:.10g} leaves a phase of the cycle "
                                            f"shorter than {ANGLE_TOL:g} of a turn (valves "
                                            f"opening at {deg_text(x_4)} and {deg_text(x_2)}); "
                                            f"give pressures further apart")

    def reexpansion(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return p_discharge * (v_c / np.asarray(volume(x), dtype=np.float64)) ** n_e

    def compression(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return p_suction * (v_1 / np.asarray(volume(x), dtype=np.float64)) ** n

    work = ((p_discharge * v_c - p_suction * v_4) / (n_e - 1.0) + p_suction * (v_1 - v_4)
            + (p_suction * v_1 - p_discharge * v_2) / (n - 1.0) + p_discharge * (v_c - v_2))
    funcs, corners = wrapped_pieces([(tdc, reexpansion), (x_4, float(p_suction)),
                                      (bdc, compression), (x_2, float(p_discharge))], period)
    table, err = table_from_function(funcs, period, corners, step)
    return CompressorCycle(knots=table.knots, coef=table.coef, piece_knot=table.piece_knot,
                           period=period, work=work, p_suction=p_suction,
                           p_discharge=p_discharge, n=n, n_reexpansion=n_e,
                           clearance_ratio=clearance_ratio, v_c=v_c, v_1=v_1, v_2=v_2, v_4=v_4,
                           angle_discharge=x_2 % period, angle_suction=x_4 % period,
                           interpolation_error=err)
