"""Reading the ``[shaft]`` table: the elastic shaft line's stations, sections, dampers and
coupling (:class:`~.records.Shaft`), checked against the mechanism's cylinders and crankpins.

Every key is read before the checks across entries, so that the key reference hears them all
(:mod:`.keyref`); each error names the key as written, what is wrong and what is allowed.
"""
from __future__ import annotations

import math
from dataclasses import replace

from ..errors import SceneError, show_value
from ..mechanisms import provides
from ..units import Named
from .reader import MISSING, Section
from .records import (
    DAMPER_MODELS,
    STEEL_SHEAR_MODULUS,
    Coupling,
    Damper,
    Inertia,
    Shaft,
    ShaftSection,
    Station,
)

#: Where the load acts when it acts on the driven inertia (``[shaft] load_at``).
DRIVEN = "driven"
#: A section's length and diameter: required unless its stiffness is given.
GEOMETRY = Named(MISSING, "required without stiffness")
#: The relative damping keys of a section, of which at most one is given.
SECTION_DAMPING = ("damping", "loss_factor", "damping_ratio")


def read_shaft(s: Section, mech, inertia: Inertia) -> Shaft:
    """The ``[shaft]`` table ``s`` (present) of a scene whose mechanism is ``mech`` and whose
    ``[inertia]`` is ``inertia``."""
    stations = [_read_station(st) for st in s.tables("stations")]
    sections = [_read_section(sc) for sc in s.tables("sections")]
    dampers = [_read_damper(sd) for sd in s.tables("dampers")]
    coupling = None
    s.known.append("coupling")
    if s.has("coupling"):
        sc = s.sub("coupling")
        coupling = Coupling(stiffness=sc.number("stiffness", "torsional stiffness", gt=0.0),
                            driven_inertia=sc.number("driven_inertia", "inertia", gt=0.0),
                            damping=sc.number("damping", "rotary damping", 0.0, ge=0.0),
                            gear_ratio=sc.number("gear_ratio", "1", 1.0, gt=0.0))
        sc.finish()
    reference = s.string("reference", Named("", "the station of the largest inertia"))
    load_at = s.string("load_at", Named("", "driven with a coupling, else the last station"))
    speed_range = s.numbers("speed_range", "speed",
                            Named((), "0 to 1.2 × the highest speed the scene names"), ge=0.0)
    shaft = Shaft(tuple(stations), tuple(sections), tuple(dampers), coupling, reference,
                  load_at, speed_range)
    _check_line(s, shaft)
    _check_cylinders(s, shaft, mech)
    _check_names(s, shaft)
    if inertia.total > 0.0:
        raise SceneError("inertia", f"is {inertia.total:g} kg m² with a [shaft]: the stations "
                                    f"hold the shaft line's inertias (station inertia, "
                                    f"[shaft.coupling] driven_inertia); leave [inertia] out or 0")
    if not reference:
        own = [st.inertia for st in stations]
        shaft = replace(shaft, reference=stations[own.index(max(own))].name)
    if not load_at:
        shaft = replace(shaft, load_at=DRIVEN if coupling else stations[-1].name)
    return shaft


def _read_station(s: Section) -> Station:
    station = Station(name=s.string("name"),
                      inertia=s.number("inertia", "inertia", 0.0, ge=0.0),
                      damping=s.number("damping", "rotary damping", 0.0, ge=0.0),
                      cylinders=s.integers("cylinders", ()))
    s.finish()
    return station


def _read_section(s: Section) -> ShaftSection:
    if s.has("stiffness"):
        k = s.number("stiffness", "torsional stiffness", gt=0.0)
        geometry = [n for n in ("length", "diameter", "bore", "shear_modulus")
                    if s.has(n, "length") or s.has(n, "modulus")]
        if geometry:
            raise SceneError(s.key(geometry[0]), "given with 'stiffness'; give the stiffness or "
                                                 "the geometry (length, diameter, bore, "
                                                 "shear_modulus), not both")
    else:
        length = s.number("length", "length", GEOMETRY, gt=0.0)
        d = s.number("diameter", "length", GEOMETRY, gt=0.0)
        bore = s.number("bore", "length", 0.0, ge=0.0, lt=Named(d, "diameter"))
        g = s.number("shear_modulus", "modulus", STEEL_SHEAR_MODULUS, gt=0.0)
        k = g * math.pi * (d ** 4 - bore ** 4) / (32.0 * length)
    values = {"damping": s.number("damping", "rotary damping", 0.0, ge=0.0),
              "loss_factor": s.number("loss_factor", "1", 0.0, ge=0.0),
              "damping_ratio": s.number("damping_ratio", "1", 0.0, ge=0.0, lt=1.0)}
    given = [n for n in SECTION_DAMPING if values[n] > 0.0]
    if len(given) > 1:
        raise SceneError(s.key(given[1]), f"given with {given[0]!r}; a section's relative "
                                          f"damping is one of {', '.join(SECTION_DAMPING)}")
    s.finish()
    return ShaftSection(stiffness=k, **values)


def _read_damper(s: Section) -> Damper:
    station = s.string("station")
    model = s.string("model", choices=DAMPER_MODELS)
    ring = s.number("inertia", "inertia", gt=0.0)
    if model == "viscous":
        damper = Damper(station, model, ring, s.number("damping", "rotary damping", gt=0.0))
    else:
        damper = Damper(station, model, ring, s.number("damping", "rotary damping", 0.0, ge=0.0),
                        s.number("stiffness", "torsional stiffness", gt=0.0))
    s.finish()
    return damper


def _check_line(s: Section, shaft: Shaft) -> None:
    """Two stations at least, one section fewer, and inertia on every degree of freedom that
    has none of its own to lean on."""
    n = len(shaft.stations)
    if n < 2:
        raise SceneError(s.key("stations"), f"has {n} entries; a shaft line needs at least 2 "
                                            f"stations ([[shaft.stations]]), in order from the "
                                            f"front end")
    if len(shaft.sections) != n - 1:
        raise SceneError(s.key("sections"), f"has {len(shaft.sections)} entries for {n} "
                                            f"stations; give one [[shaft.sections]] between "
                                            f"each two consecutive stations, {n - 1}")


def _check_names(s: Section, shaft: Shaft) -> None:
    names = [st.name for st in shaft.stations]
    for i, name in enumerate(names):
        if not name.strip() or not name.isprintable():
            raise SceneError(f"{s.key('stations')}[{i}].name", f"{show_value(name)}: give "
                                                                f"printable, non-empty text")
        if name in names[:i]:
            raise SceneError(f"{s.key('stations')}[{i}].name",
                             f"{show_value(name)} names station {names.index(name) + 1} "
                             f"already; give each station its own name")
        if name == DRIVEN:
            raise SceneError(f"{s.key('stations')}[{i}].name",
                             f"{DRIVEN!r} names the driven inertia; give the station another "
                             f"name")
    listed = ", ".join(map(repr, names))
    for i, d in enumerate(shaft.dampers):
        if d.station not in names:
            raise SceneError(f"{s.key('dampers')}[{i}].station",
                             f"{show_value(d.station)} is no station; one of {listed}")
    if shaft.reference and shaft.reference not in names:
        raise SceneError(s.key("reference"), f"{show_value(shaft.reference)} is no station; "
                                             f"one of {listed}")
    if shaft.load_at:
        allowed = names + [DRIVEN] * (shaft.coupling is not None)
        if shaft.load_at not in allowed:
            more = f" or {DRIVEN!r} (with a [shaft.coupling])"
            raise SceneError(s.key("load_at"), f"{show_value(shaft.load_at)} is no station"
                                               f"{' nor the driven inertia' * (DRIVEN in allowed)}"
                                               f"; one of {listed}{more}")


def _check_cylinders(s: Section, shaft: Shaft, mech) -> None:
    """Every cylinder on exactly one station; the cylinders of a crankpin on one station; a
    mechanism that cannot share its inertia out by cylinder keeps them all on one; a station
    without cylinders has inertia of its own."""
    n = mech.n_cylinders
    where: dict[int, int] = {}
    for i, st in enumerate(shaft.stations):
        key = f"{s.key('stations')}[{i}].cylinders"
        for k in st.cylinders:
            if not 1 <= k <= n:
                raise SceneError(key, f"cylinder {k} does not exist; the mechanism has "
                                      f"cylinders 1 … {n}")
            if k in where:
                raise SceneError(key, f"cylinder {k} is on station {where[k] + 1} already; "
                                      f"each cylinder rides on exactly one station")
            where[k] = i
        if not st.cylinders and st.inertia <= 0.0:
            raise SceneError(f"{s.key('stations')}[{i}].inertia",
                             "is 0 on a station without cylinders; give it its inertia (> 0)")
    missing = [k for k in range(1, n + 1) if k not in where]
    if missing:
        raise SceneError(s.key("stations"), f"cylinder(s) {', '.join(map(str, missing))} on no "
                                            f"station; list each cylinder 1 … {n} in the "
                                            f"'cylinders' of the station carrying its crankpin")
    if not provides(mech, "cylinder-inertia"):
        if len(set(where.values())) > 1:
            raise SceneError(s.key("stations"), f"the cylinders are on several stations, but the "
                                                f"{mech.name} mechanism's inertia is one whole "
                                                f"(all cylinders on one crankpin or plate): put "
                                                f"every cylinder on one station")
        return
    for pin in mech.crankpins:
        on = {where[k + 1] for k in pin}
        if len(on) > 1:
            numbers = ", ".join(str(k + 1) for k in pin)
            raise SceneError(s.key("stations"), f"cylinders {numbers} share a crankpin but sit "
                                                f"on different stations; put them on one")
