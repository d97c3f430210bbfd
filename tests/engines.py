"""Mechanisms and shaft lines the tests share (on ``pythonpath``, pyproject): one copy of each."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from transient.mechanisms.crank_slider import CrankSlider
from transient.reference.torsion import Coupling, Ring, ShaftLine


def gots_mech(**changes) -> CrankSlider:
    """The Gots example engine (Gots §2.9, App. 1): 3 cylinders, firing 1-2-3, two-mass rod."""
    base = CrankSlider(crank_radius=0.047, rod_length=0.148, offset=0.0, bore=0.088,
                       piston_mass=1.520, crank_mass=0.912, rod_model="two-mass", rod_mass=1.752,
                       rod_cg_from_pin=0.725 * 0.148, rod_inertia_cg=0.0, strokes=4,
                       firing_angles=tuple(np.radians([360.0, 600.0, 120.0])),
                       bank_angles=(0.0, 0.0, 0.0))
    return replace(base, **changes)


#: Offset, rigid rod with an inertia far from the two-mass one, large λ: every term is visible.
OFFSET_RIGID = {"offset": 0.012, "rod_length": 0.11, "rod_model": "rigid",
                "rod_cg_from_pin": 0.07, "rod_inertia_cg": 2.5e-3}

#: The Gots engine, with an offset and a shorter rod, and with a rigid rod besides.
MECHS = {"two-mass": gots_mech(), "offset-two-mass": gots_mech(offset=0.012, rod_length=0.11),
         "offset-rigid": gots_mech(**OFFSET_RIGID)}


def inline_six_mech(**changes) -> CrankSlider:
    """An in-line six of a truck diesel's size (bore 102 mm, stroke 120 mm, rod 190 mm, two-mass
    rod), firing 1-5-3-6-2-4 every 120°: the engine of the elastic shaft line's tests."""
    firing = {1: 0.0, 5: 120.0, 3: 240.0, 6: 360.0, 2: 480.0, 4: 600.0}
    base = CrankSlider(crank_radius=0.06, rod_length=0.19, offset=0.0, bore=0.102,
                       piston_mass=1.6, crank_mass=1.2, rod_model="two-mass", rod_mass=2.2,
                       rod_cg_from_pin=0.7 * 0.19, rod_inertia_cg=0.0, strokes=4,
                       firing_angles=tuple(np.radians([firing[c] for c in range(1, 7)])),
                       bank_angles=(0.0,) * 6)
    return replace(base, **changes)


#: The six's shaft line's own inertias: damper hub, six throws, flywheel [kg m²].
SIX_OWN = np.array([0.03] + [0.05] * 6 + [1.2])


def inline_six_line(**changes) -> ShaftLine:
    """The in-line six's shaft line in the reference path's form: damper hub, six throws (one
    cylinder each), flywheel; sections of 0.6–1.5 MN m/rad with some damping, a little absolute
    damping at the throws, a viscous ring on the hub and a tuned one on the flywheel, and a
    coupling through a 2:1 gear to a driven inertia."""
    base = ShaftLine(inertia=SIX_OWN, stiffness=np.array([6e5] + [1.2e6] * 5 + [1.5e6]),
                     damping=np.array([5.0] + [10.0] * 6),
                     absolute=np.array([0.0] + [0.005] * 6 + [0.0]),
                     station_of_cylinder=np.arange(1, 7),
                     rings=(Ring(0, 0.04, 30.0), Ring(7, 0.02, 2.0, 2e4)),
                     coupling=Coupling(7, 3e4, 20.0, 2.0, 0.5))
    return replace(base, **changes)
