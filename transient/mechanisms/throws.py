"""How a crank-slider's cylinders sit on its crank: banks, throws, the rods on a shared crankpin
and the firing angles that follow, read from the ``[mechanism]`` table.

Angles (all in the direction of rotation): a cylinder's bank δ_c is its axis from the reference
axis; the shaft angle φ is the angle of the shaft's reference line from the reference axis; a
throw's angle θ_t is its crankpin's angle ahead of that line, so that the crankpin stands at
φ + θ_t and cylinder c, on the pin at θ_c, is at its top dead centre where φ = δ_c − θ_c. A
crank-slider's firing angle f_c is where its local crank angle φ − f_c is 0, so f_c ≡ δ_c − θ_c
(mod 2π): the throws fix every firing angle up to the revolution, which a four-stroke's firing
order picks (:func:`firing_from_order`).

Cylinders on a shared throw: cylinders 2t − 1 and 2t ride on throw t (numbered from the nose),
the first nearer the nose. A V engine numbered bank by bank (one bank 1 … n/2, the other
n/2 + 1 … n) is renumbered to this order.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..errors import SceneError
from ..units import SUFFIXES, Named

if TYPE_CHECKING:
    from ..scene.reader import Section

#: ``rod_arrangement`` of two cylinders on one crankpin: both rods in one plane (one forked
#: around the other) or side by side along the pin.
SHARED = ("fork-and-blade", "side-by-side")
#: ``rod_arrangement`` of a crank-slider whose every cylinder has its own throw.
SINGLE = "single"
#: Two angles closer than this [rad] are one (bank angles of an in-line engine, a firing angle
#: against the crank's top dead centre).
ANGLE_TOL = 1e-9

TWO_PI = 2.0 * math.pi
# What the keys this module reads mean, in a line (the scene-key reference).
KEY_MEANINGS = {
    "bank": "Each cylinder's axis from the reference axis, in the direction of rotation: one "
            "per cylinder, or two (one per bank, odd cylinders on the first) for an even count.",
    "throws": "Each throw's crankpin angle ahead of the shaft's reference line: one per "
              "cylinder, or one per two cylinders (2t − 1 and 2t on throw t).",
    "rod_arrangement": "Two rods on one throw: ``side-by-side`` big ends along the pin, or "
                       "``fork-and-blade`` in one plane; needs ``throws``, one per two "
                       "cylinders.",
    "firing": "Each cylinder's firing angle, at one of its top dead centres (instead of "
              "``firing_order``).",
    "pin_split": "Angle between the two crankpins of a split throw (side-by-side rods).",
    "rod_spacing": "Distance along the pin between two side-by-side big ends' middle planes.",
    "journal_spacing": "Distance between the two main journals beside a throw (side-by-side "
                       "rods).",
}
#: The keys of two cylinders on one throw besides ``rod_arrangement``, with their kinds.
SHARED_KEYS = (("pin_split", "angle"), ("rod_spacing", "length"), ("journal_spacing", "length"))


def read_crank(s: Section, n: int, cycle: float, order: tuple[int, ...]) -> dict:
    """The keys of :class:`~.crank_slider.CrankSlider` that place its cylinders on the crank:
    ``firing_angles``, ``bank_angles``, ``rod_arrangement``, ``rod_spacing``,
    ``journal_spacing``; errors name the keys as written."""
    banks = _read_banks(s, n)
    throws = s.numbers("throws", "angle", Named(None, "a throw per cylinder, from the firing "
                                                      "(in-line engines)"))
    arrangement = s.string("rod_arrangement", Named(None, "a throw per cylinder"),
                           choices=SHARED)
    firing = s.numbers("firing", "angle", Named(None, "from firing_order"))
    if firing is not None:
        _check_count(s, "firing", firing, n)
    if throws is None:
        return _read_without_throws(s, n, cycle, order, banks, arrangement, firing)
    if _cylinders_per_throw(s, n, len(throws), arrangement, banks) == 1:
        _refuse(s, SHARED_KEYS, reason="each cylinder has its own throw here; it applies to two "
                                       "cylinders on one throw (rod_arrangement)")
        pins, keys = list(throws), {"rod_arrangement": SINGLE}
    else:
        pins, keys = _read_shared(s, throws, arrangement)
    tdc = np.mod(np.asarray(banks) - np.asarray(pins), TWO_PI)
    if firing is None:
        firing = firing_from_order(s, tdc, order, cycle)
    else:
        _check_firing(s, firing, tdc, cycle)
    return {"firing_angles": tuple(firing), "bank_angles": banks, **keys}


def _read_banks(s: Section, n: int) -> tuple[float, ...]:
    """``bank``: one angle per cylinder, or (an even count) one per bank, odd cylinders on the
    first, even ones on the second."""
    banks = s.numbers("bank", "angle", Named((0.0,) * n, "0° for every cylinder"))
    if len(banks) == 2 and n % 2 == 0:
        return banks * (n // 2)
    _check_count(s, "bank", banks, n, " (or two for an even count: one per bank, odd cylinders "
                                      "on the first, even ones on the second)")
    return banks


def _read_without_throws(s: Section, n, cycle, order, banks, arrangement, firing) -> dict:
    """An in-line engine declared by its firing (the crank follows from it); a V engine must
    name its throws."""
    if arrangement is not None:
        raise s.rename(SceneError(s.key("rod_arrangement"),
                                  "needs `throws`, one crank angle per throw (two cylinders per "
                                  "throw: cylinders 2t − 1 and 2t ride on throw t)"))
    _refuse(s, SHARED_KEYS, reason="it applies to two cylinders on one throw (`throws` and "
                                   "`rod_arrangement`)")
    if firing is None:
        firing = [0.0] * n
        for j, c in enumerate(order):
            firing[c - 1] = j * cycle / n
    if not equal_angles(banks):
        pins = _degrees(np.mod(np.asarray(banks) - np.asarray(firing), TWO_PI), 6)
        shared = (f"{n // 2} for two cylinders per throw (cylinders 2t − 1 and 2t on throw t) "
                  f"with rod_arrangement = \"side-by-side\" or \"fork-and-blade\" and "
                  f"crank_mass per throw, or " if n % 2 == 0 else "")
        raise s.rename(SceneError(
            s.key("throws"),
            f"is missing: the cylinders sit on different banks (bank = {_degrees(banks)}°), "
            f"so the crank must say where their throws are. Give `throws_deg`, one angle per "
            f"throw: {shared}{n} for one cylinder per throw, as this file was read before: "
            f"throws_deg = {pins} with its firing order or angles"))
    return {"firing_angles": tuple(firing), "bank_angles": banks, "rod_arrangement": SINGLE}


def _cylinders_per_throw(s: Section, n, n_throws, arrangement, banks) -> int:
    """1 or 2 from the count of ``throws``; a rod arrangement only, and always, with 2."""
    if n_throws == n:
        if arrangement is not None:
            raise s.rename(SceneError(
                s.key("rod_arrangement"),
                f"applies to two cylinders on one throw; `throws` has {n} entries, one per "
                f"cylinder, so each rod has a crankpin of its own: leave rod_arrangement out"
                + (f", or give {n // 2} throws" if n % 2 == 0 else "")))
        return 1
    if 2 * n_throws != n:
        raise s.rename(SceneError(
            s.key("throws"), f"has {n_throws} entries; give one per throw: {n} (a throw per "
                             f"cylinder)" + (f" or {n // 2} (two cylinders per throw)"
                                             if n % 2 == 0 else "")))
    if any(equal_angles(banks[k:k + 2]) for k in range(0, n, 2)):
        raise s.rename(SceneError(
            s.key("rod_arrangement" if arrangement is not None else "throws"),
            f"two cylinders on one throw must sit on two banks, but bank = "
            f"{_degrees(banks)}° puts cylinders 2t − 1 and 2t of a throw on one: an in-line "
            f"engine has a throw per cylinder (give {n} throws and no rod_arrangement), a V "
            f"engine gives `bank_deg` one angle per bank or per cylinder"))
    if arrangement is None:
        raise s.rename(SceneError(
            s.key("rod_arrangement"),
            f"is missing: `throws` has {n_throws} entries, so cylinders 2t − 1 and 2t share "
            f"throw t; say how their rods sit on the crankpin: \"side-by-side\" (two big ends "
            f"next to each other along the pin) or \"fork-and-blade\" (one rod forked around "
            f"the other, both in one plane)"))
    return 2


def _read_shared(s: Section, throws, arrangement) -> tuple[list[float], dict]:
    """Each cylinder's crankpin angle and the keys of two cylinders per throw: a split of the
    throw's pins (side by side only) and the rods' and journals' spacing."""
    split = s.number("pin_split", "angle", 0.0, gt=-math.pi, lt=math.pi)
    if arrangement == "fork-and-blade":
        if split != 0.0:
            raise s.rename(SceneError(s.key("pin_split"),
                                      "must be 0 for fork-and-blade rods, which share one pin; "
                                      "a split crankpin carries its rods side by side "
                                      "(rod_arrangement = \"side-by-side\")"))
        _refuse(s, SHARED_KEYS[1:], reason="fork-and-blade rods are both in the throw's middle "
                                           "plane, so their forces share the journals equally; "
                                           "it applies to side-by-side rods")
        keys = {}
    else:
        journals = s.number("journal_spacing", "length", gt=0.0)  # (both big ends between them)
        keys = {"rod_spacing": s.number("rod_spacing", "length", gt=0.0,
                                        lt=Named(journals, "journal_spacing")),
                "journal_spacing": journals}
    pins = [theta + half for theta in throws for half in (-split / 2.0, split / 2.0)]
    return pins, {"rod_arrangement": arrangement, **keys}


def firing_from_order(s: Section, tdc, order: tuple[int, ...], cycle: float) -> list[float]:
    """Firing angles [rad] in [0, cycle) from each cylinder's top dead centre ``tdc`` (mod 2π)
    and the firing order: the first cylinder fires at its TDC, and the j-th at whichever of its
    TDCs in the cycle (a four-stroke has two, a turn apart) is nearest the even slot
    j·cycle/n after it (on a tie the earlier); the order must then run forward."""
    n = len(tdc)
    first = order[0] - 1
    firing = [0.0] * n
    for j, c in enumerate(order):
        slot = tdc[first] + j * cycle / n
        options = [tdc[c - 1] + k * TWO_PI for k in range(round(cycle / TWO_PI))]
        best = min(options, key=lambda a: abs(wrap_angle(a - slot, cycle)))
        firing[c - 1] = best % cycle
    after = [(firing[c - 1] - firing[first]) % cycle for c in order]
    after = [0.0 if a > cycle - ANGLE_TOL else a for a in after]
    for j in range(1, n):
        if after[j] < after[j - 1] - ANGLE_TOL:
            raise s.rename(SceneError(
                s.key("firing_order"),
                f"{list(order)} does not fit the crank: cylinder {order[j]} cannot fire after "
                f"cylinder {order[j - 1]}; with these throws and banks the cylinders reach top "
                f"dead centre at {_degrees(tdc)}°"
                + (" (and 360° later)" if cycle > TWO_PI + ANGLE_TOL else "")
                + ": give an order that runs forward through them, or explicit `firing` angles"))
    return firing


def _check_firing(s: Section, firing, tdc, cycle: float) -> None:
    """Explicit firing angles with throws: each at one of its cylinder's top dead centres."""
    for c, (f, t) in enumerate(zip(firing, tdc)):
        if abs(wrap_angle(f - t, TWO_PI)) > ANGLE_TOL:
            allowed = " or ".join(f"{math.degrees(t) + 360.0 * k:.6g}°"
                                  for k in range(round(cycle / TWO_PI)))
            raise s.rename(SceneError(
                s.key("firing"), f"cylinder {c + 1} fires at {math.degrees(f):g}°, which is "
                                 f"not a top dead centre of it with these throws and banks: "
                                 f"allowed {allowed}"))


def _check_count(s: Section, key: str, values, n: int, more: str = "") -> None:
    if len(values) != n:
        raise s.rename(SceneError(s.key(key), f"has {len(values)} entries; must have one per "
                                              f"cylinder ({n}){more}"))


def _refuse(s: Section, keys, reason: str) -> None:
    """A key that does not apply to this crank is an error saying why, not an unknown key."""
    for name, kind in keys:
        for written in [name] + [f"{name}_{u}" for u in SUFFIXES.get(kind, {})]:
            if written in s.data:
                raise SceneError(s.key(written), f"does not apply: {reason}")


def equal_angles(angles) -> bool:
    """Whether the angles are one, a whole turn apart or not."""
    return all(abs(wrap_angle(a - angles[0], TWO_PI)) <= ANGLE_TOL for a in angles)


def wrap_angle(x, period: float = TWO_PI):
    """x (a number or an array) into [−period/2, period/2)."""
    return (x + period / 2.0) % period - period / 2.0


def _degrees(angles, digits: int = 4) -> list[float]:
    return [round(math.degrees(a), digits) for a in angles]


def at_phases(local, phases, cycle: float) -> NDArray[np.float64]:
    """Shaft angles [rad] in [0, ``cycle``), sorted and unique, where a row (a cylinder, or a row
    of cylinders) at each of ``phases`` passes the ``local`` angles of its turn, every turn of
    the cycle: where a joint's motion reverses, as a breakpoint."""
    turns = np.arange(0.0, cycle - 1e-9, TWO_PI)
    angles = np.add.outer(np.asarray(phases, dtype=np.float64),
                          np.add.outer(turns, np.asarray(local, dtype=np.float64))).ravel()
    return np.unique(np.mod(angles, cycle))
