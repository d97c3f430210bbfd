"""Steps per engine cycle an explicit pair takes on the elastic shaft line, against the rigid
model of the same engine: does stability or accuracy limit the step?

The line: an in-line six (``tests/engines.py``: bore 102 mm, stroke 120 mm) with 9 inertias —
damper hub 0.03 kg m² with a viscous damper's ring (0.04 kg m², 30 N m s/rad), six throws of
0.05 kg m² plus each cylinder's J_c(θ) (mean 0.014), the flywheel 1.2 kg m², and through an
elastic coupling (3e4 N m/rad, 20 N m s/rad, referred to the engine) and a 2:1 gear a driven
inertia of 0.5 kg m² with a fan load; sections 6e5 (hub), 1.2e6 (between throws), 1.5e6
(to the flywheel) N m/rad, each damped with 5–10 N m s/rad. The rigid model: one station
carrying the six cylinders with Σ J_own + J_d/i² and the fan reduced through the gear. Both by
``solve_ivp`` in time (numpy right-hand side, :mod:`transient.reference.torsion`) from
200 rad/s, the steps counted over the second and third cycle.

Prints the line's natural frequencies at the mean inertias (ring left free), f_max/f_1, and per
method and rtol the steps per cycle, elastic and rigid, and h·ω_max at the elastic run's median
step. Rerun: ``.venv/bin/python tools/shaft_steps.py [HUB_STIFFNESS]`` (the hub's section, 6e5 N m/rad
by default: a stiff front end, e.g. 1e7, raises f_max alone).
"""
import math
import sys
from pathlib import Path

import numpy as np
from scipy.linalg import eigh

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from engines import SIX_OWN as OWN
from engines import inline_six_line, inline_six_mech

from transient.reference.torsion import (
    Coupling,
    CrankSliderCylinders,
    PressurePulse,
    ShaftLine,
    TorsionModel,
    integrate,
)

SPEED, MEAN_TORQUE, RATIO, JD = 200.0, 356.0, 2.0, 0.5
K = np.array([6e5] + [1.2e6] * 5 + [1.5e6])
KC, CC = 3e4, 20.0
CYCLE = 4 * math.pi


def fan(th, w, t):
    return -MEAN_TORQUE * RATIO * (w * RATIO / SPEED) ** 2


def frequencies():
    """Natural frequencies [Hz] of the undamped line at mean inertias, the driven inertia
    referred to the engine (J_d/i²), the rigid mode left out."""
    J = np.append(OWN + np.r_[0.0, [0.014] * 6, 0.0], JD / RATIO ** 2)
    k = np.append(K, KC)
    n = J.size
    S = np.zeros((n, n))
    for i, ki in enumerate(k):
        S[i:i + 2, i:i + 2] += ki * np.array([[1, -1], [-1, 1]])
    w2 = eigh(S, np.diag(J), eigvals_only=True)
    return np.sqrt(np.abs(w2[1:])) / (2 * math.pi)


def main():
    if len(sys.argv) > 1:
        K[0] = float(sys.argv[1])
    mech = inline_six_mech()
    cyl = CrankSliderCylinders(mech, PressurePulse(9e6, math.radians(12), math.radians(15)))
    line = inline_six_line(stiffness=K, rings=inline_six_line().rings[:1],
                           coupling=Coupling(7, KC, CC, RATIO, JD))
    rigid = ShaftLine(inertia=np.array([OWN.sum() + JD / RATIO ** 2]), stiffness=np.zeros(0),
                      damping=np.zeros(0), absolute=np.array([0.03]),
                      station_of_cylinder=np.zeros(6, dtype=np.intp))
    f = frequencies()
    w_max = 2 * math.pi * f[-1]
    print("natural frequencies [Hz]:", np.array2string(f, precision=1))
    print(f"f_max/f_1 = {f[-1] / f[0]:.1f}")
    t_end = 3 * CYCLE / SPEED
    window = (CYCLE / SPEED, t_end)
    print("method  rtol   elastic/cycle  rigid/cycle  h*w_max(median)  nfev elastic")
    for method in ("DOP853", "RK45"):
        for rtol in (1e-6, 1e-7, 1e-8, 1e-9):
            counts = []
            for shaft in (line, rigid):
                model = TorsionModel(shaft, cyl, driven_load=fan,
                                     external=(None if shaft is line else
                                               lambda th, w, t: fan(th / RATIO, w / RATIO, t)
                                               / RATIO * np.ones(1)))
                sol = integrate(model, model.initial_state(0.0, SPEED), t_end, method=method,
                                rtol=rtol, atol=rtol)
                inside = (sol.t > window[0]) & (sol.t <= window[1])
                h = np.diff(sol.t)[inside[1:]]
                counts.append((inside.sum() / 2.0, np.median(h), model.nfev))
            (e, h, nfev), (r, _, _) = counts
            print(f"{method:7s} {rtol:.0e} {e:10.0f} {r:12.0f} {h * w_max:14.2f} {nfev:12d}")


if __name__ == "__main__":
    main()
