"""The reference path: a second implementation of the model in plain numpy, in four parts, each
saying what it shares with the compiled path:

- :mod:`.integrate`: the run, integrated by ``scipy.integrate.solve_ivp`` (``solver.method``
  ``scipy-*``, the implicit rerun of a stiff scene, the benchmark's baseline);
- :mod:`.twins`: the model's parts in numpy (the serial chain, the reaction friction, the
  cylinders' pressures, the governors) that the run assembles;
- :mod:`.joints`: the joint reactions of each mechanism by Newton–Euler, the oracles of the
  compiled reaction-friction solvers and of the analyses' forces;
- :mod:`.torsion`: the elastic shaft line (stations, sections, dampers, a coupling), its
  equations in numpy through ``solve_ivp``, the crank-slider's per-cylinder inertia and the
  rigid limit's run: the oracle of the elastic stepper.
"""
from .integrate import run_reference
from .joints import (
                     articulated_joint_forces,
                     crank_slider_friction,
                     crank_slider_joint_forces,
                     crank_slider_joint_signs,
                     swash_plate_friction,
                     swash_plate_motion,
                     swash_plate_reactions,
)

__all__ = ["run_reference", "articulated_joint_forces", "crank_slider_friction",
           "crank_slider_joint_forces", "crank_slider_joint_signs", "swash_plate_friction",
           "swash_plate_motion", "swash_plate_reactions"]
