"""Issue 5's "bare scene at the speed of bare (18)": the cost of one right-hand side of transient
for the bare single cylinder (``cases/coasting_single.toml``: no gas, friction, governor or
starter) against a kernel written by hand for that equation alone, and whole runs of the bare
scene against the same scene carrying unused options.

* ``hand``: (18) in crank angle for one rigid-rod crank slider, self-contained (its own
  kinematics: the formulas of Gots (1)–(19) written out once more, on purpose — this is the
  baseline a user would write), plain ``numba.njit``; returns dt/dφ and dK/dφ = −M_load.
* ``transient exact`` / ``transient tabulated``: ``transient.core.model.derivative`` on the
  scene's Model (crank-angle mode), exact kernel or tables.
Each is timed in a compiled loop over 2000 states (median of 7 × 100 loops, ``rhs_timing.py``);
then full runs (1000 revolutions, rtol 1e-8, median of 5) of the bare scene and of the bare
scene with a droop governor, a zero-torque starter and a zero load, none of which ever acts.
Rerun: ``.venv/bin/python scripts/handwritten_kernel.py`` (about 20 s).
"""
import dataclasses as dc
import math
import statistics
from pathlib import Path

import numpy as np
from numba import njit
from rhs_timing import per_call, rhs_loop

from transient.assemble import build_model
from transient.core import model as cm
from transient.scene import Governor, Starter, load_scene
from transient.simulate import integrate

CASES = Path(__file__).resolve().parents[1] / "cases"


@njit(cache=True)
def hand_rhs(p, y, out):
    """(18) in crank angle for one rigid-rod crank slider; p = (r, l, m_slide, m_rot, m_rod,
    cg_from_pin, I_rod, J0, load)."""
    r, l, m_slide, m_rot, m_rod, cg, I_rod, J0, load = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]
    sa, ca = math.sin(y[0]), math.cos(y[0])
    sb = r * sa / l
    cb = math.sqrt(1.0 - sb * sb)
    db = r * ca / (l * cb)
    ds = r * sa + l * sb * db  # piston velocity per unit ω
    f = cg / l
    gx = f * r * ca
    gy = (1.0 - f) * (-ds) - f * r * sa
    J = J0 + m_slide * ds * ds + m_rot * r * r + m_rod * (gx * gx + gy * gy) + I_rod * db * db
    w = math.sqrt(2.0 * y[2] / J)
    out[0] = 1.0
    out[1] = 1.0 / w
    out[2] = -load


@njit(cache=True)
def hand_loop(p, states, out):
    acc = 0.0
    for i in range(states.shape[0]):
        hand_rhs(p, states[i], out)
        acc += out[1]
    return acc


def run_wall(scene):
    integrate(scene, keep=False)
    return statistics.median(integrate(scene, keep=False).solver["wall_s"] for _ in range(5))


base = load_scene(CASES / "coasting_single.toml")
mech = base.mechanism
assert mech.rod_model == "rigid" and mech.offset == 0.0 and mech.n_cylinders == 1
states = np.zeros((2000, 6))
states[:, cm.PHI] = np.linspace(0.0, 40.0, 2000)
states[:, cm.KINETIC] = 170.0
mp = mech.pack()
from transient.core import crank_slider as cs  # noqa: E402  (parameter layout)

p = np.array([mp[cs.R], mp[cs.L], mp[cs.M_PISTON] + mp[cs.M_PIN], mp[cs.M_CRANKPIN] + mp[cs.M_CRANK],
              mp[cs.M_ROD], mp[cs.ROD_CG], mp[cs.I_ROD], base.inertia.total, 0.0])
out = np.empty(6)
# the two kernels agree (same equation, same numbers)
m_exact, _, _ = build_model(base)
o1, o2 = np.empty(6), np.empty(6)
hand_rhs(p, states[7], o1)
sw = np.zeros(cm.N_SWITCHES, dtype=np.int64)
sw[cm.SW_DIRECTION] = 1
rhs_loop(m_exact, states[7:8], o2, sw, cm.work_array(m_exact))
assert abs(o1[1] / o2[1] - 1.0) < 1e-13, (o1, o2)
t_hand = per_call(hand_loop, p, states, out)
print(f"hand-written (18): {t_hand * 1e9:.1f} ns per call")
for kin in ("exact", "tabulated"):
    scene = dc.replace(base, solver=dc.replace(base.solver, kinematics=kin))
    m, _, _ = build_model(scene)
    t = per_call(rhs_loop, m, states, out, sw, cm.work_array(m))
    print(f"transient {kin}: {t * 1e9:.1f} ns per call ({t / t_hand:.3f}× hand-written)")

bare = dc.replace(base, run=dc.replace(base.run, revolutions=1000.0),
                  solver=dc.replace(base.solver, rtol=1e-8, atol=1e-11))
unused = dc.replace(bare, governor=Governor(model="droop", speed_full=1e4, speed_zero=2e4),
                    starter=Starter(torque=0.0))
w_bare, w_unused = run_wall(bare), run_wall(unused)
print(f"run, bare scene: {w_bare:.4f} s; with an idle governor and starter: {w_unused:.4f} s "
      f"({w_unused / w_bare - 1:+.1%})")
