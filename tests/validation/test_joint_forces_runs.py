"""The Newton–Euler joint forces (:func:`transient.reference.crank_slider_joint_forces`) along
a run of the compiled stepper: the shaft's own equation closes with the throws' torques.

With ideal pairs the shaft (shaft, flywheel, load, starter: inertia J₀ = ``[inertia]``) takes
the throws' torques on it, so J₀ ε = Σ_k T_k + M_load + M_starter at every sample, T_k the
throw torque of Newton–Euler from the sample's φ, ω, ε and gas force (p_k − p0)·F_p. The ε of a
sample is the right-hand side's φ̈ there, and the reduced model's (18) is the Lagrange form of
the same bodies, so the balance holds to rounding (~5e-15 of the largest Σ T_k): bound 1e-12.
J₀ ε is of the order of Σ T_k itself (the flywheel takes the torque's fluctuation), so a wrong
mass, inertia or sign would show at once.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from transient.reference import crank_slider_joint_forces
from transient.run import integrate
from transient.scene import Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_shaft_equation_closes_with_the_newton_euler_throw_torques():
    scene = replace(load_scene(CASES / "gots_diesel_spinup.toml"), run=Run(revolutions=6.0))
    data = integrate(scene)
    assert data.complete, data.message
    tr = data.trajectory
    mech = scene.mechanism
    p = np.array([tr[f"p_{k + 1}"] for k in range(mech.n_cylinders)])
    ne = crank_slider_joint_forces(mech, tr["phi"], tr["omega"], tr["epsilon"],
                                   (p - scene.gas.p0) * mech.piston_area)
    throws = ne.throw_torque.sum(axis=0)
    residual = scene.inertia.total * tr["epsilon"] - (throws + tr["M_load"] + tr["M_starter"])
    scale = np.max(np.abs(throws))
    print(f"{tr['t'].size} samples: max |J₀ε − ΣT − M_load − M_starter| = "
          f"{np.max(np.abs(residual)) / scale:.1e} of max |ΣT| = {scale:.4g} N m; "
          f"max |J₀ε| / max |ΣT| = {np.max(np.abs(scene.inertia.total * tr['epsilon'])) / scale:.1e}")
    assert np.max(np.abs(residual)) <= 1e-12 * scale
