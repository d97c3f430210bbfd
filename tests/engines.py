"""Mechanisms the tests share (on ``pythonpath``, pyproject): one copy of each."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from transient.mechanisms.crank_slider import CrankSlider


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
