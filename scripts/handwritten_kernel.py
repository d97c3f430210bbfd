"""Issue 5's "bare scene at the speed of bare (18)": the cost of one right-hand side of transient
for the bare single cylinder (``cases/coasting_single.toml``: no gas, friction, governor or
starter) against a kernel written by hand for that equation alone, and whole runs of the bare
scene against the same scene carrying unused options.

* ``hand-written (18)``: (18) in crank angle for one rigid-rod crank slider, self-contained
  (its own kinematics: the formulas of Gots (1)–(19) written out once more, on purpose — this is
  the baseline a user would write), plain ``numba.njit``; returns dt/dφ and dK/dφ = −M_load.
  Then the same kernel with, one rung at a time, what transient's right-hand side does beyond it
  (``make_hand_rhs``), to say where the difference goes.
* ``transient exact`` / ``transient tabulated``: ``transient.core.model.derivative`` on the
  scene's Model (crank-angle mode), exact kernel or tables.
Each is timed in a compiled loop over 2000 states (median of 7 × 100 loops, ``rhs_timing.py``);
then full runs (1000 revolutions, rtol 1e-8, median of 15, alternating) of the bare scene and of
the bare scene with a droop governor, a zero-torque starter and a zero load, none of which ever
acts.
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


def make_hand_rhs(layout=False, loads=False, records=False):
    """(18) in crank angle for one rigid-rod crank slider; parameters ``p`` in the order of
    ``P_NAMES``. All flags off: the kernel a user would write. Each flag adds one thing transient's
    right-hand side does, to attribute the difference (closure constants: compiled out, not
    branched): ``layout`` the offset, the masses summed per call and the cylinder loop rotating
    sin φ, cos φ by the cylinder's phase; ``loads`` the load's linear and fan terms, the schedule,
    generator and starter switches; ``records`` the three work integrals and the speed range kept
    for the event search (in ``rec``)."""

    @njit(inline="always")  # a closure's dispatcher is not inlined by LLVM: a call costs ~30 ns
    def rhs(p, y, out, rec):
        r, l, m_rod, cg, I_rod = p[0], p[1], p[4], p[5], p[6]
        f = cg / l
        J = p[7]
        if layout:
            sp, cp = math.sin(y[0]), math.cos(y[0])
            m_slide, m_rot = p[10] + p[11], p[12] + p[13]
            for k in range(int(p[16])):
                sa, ca = sp * p[15] - cp * p[14], cp * p[15] + sp * p[14]
                sb = (r * sa - p[9]) / l
                cb = math.sqrt(1.0 - sb * sb)
                db = r * ca / (l * cb)
                ds = r * sa + l * sb * db
                gx = f * r * ca
                gy = (1.0 - f) * (-ds) - f * r * sa
                J += m_slide * ds * ds + m_rot * r * r
                J += m_rod * (gx * gx + gy * gy) + I_rod * db * db
        else:
            sa, ca = math.sin(y[0]), math.cos(y[0])
            sb = r * sa / l
            cb = math.sqrt(1.0 - sb * sb)
            db = r * ca / (l * cb)
            ds = r * sa + l * sb * db  # piston velocity per unit ω
            gx = f * r * ca
            gy = (1.0 - f) * (-ds) - f * r * sa
            J += p[2] * ds * ds + p[3] * r * r + m_rod * (gx * gx + gy * gy) + I_rod * db * db
        w = math.sqrt(2.0 * y[2] / J)
        M = -p[8]
        if loads:  # the bare scene has no schedule (s = 1), fan, generator or starter
            s = 1.0 if p[17] == 0.0 else p[18]
            M = -s * (p[8] + p[19] * w + p[20] * w * abs(w))
            if p[21] != 0.0:
                M -= s * p[21] / w
            if p[22] != 0.0:
                M += p[22] * (1.0 - w / p[23])
        out[0] = 1.0
        out[1] = 1.0 / w
        out[2] = M
        if records:
            out[3] = 0.0
            out[4] = M
            out[5] = 0.0
            rec[0] = min(rec[0], w)
            rec[1] = max(rec[1], w)

    return rhs


def make_hand_loop(rhs):
    @njit
    def loop(p, states, out, rec):
        acc = 0.0
        for i in range(states.shape[0]):
            rhs(p, states[i], out, rec)
            acc += out[1]
        return acc

    return loop


def run_walls(*scenes, repeats=15):
    """Median wall time of each scene's run, the scenes' runs alternating (so that a drift of
    the machine shows in all of them alike), after one warm-up run each."""
    walls = [[] for _ in scenes]
    for i in range(repeats + 1):
        for scene, w in zip(scenes, walls):
            wall = integrate(scene, keep=False).solver["wall_s"]
            if i > 0:
                w.append(wall)
    return [statistics.median(w) for w in walls]


base = load_scene(CASES / "coasting_single.toml")
mech = base.mechanism
assert mech.rod_model == "rigid" and mech.offset == 0.0 and mech.n_cylinders == 1
states = np.zeros((2000, 6))
states[:, cm.PHI] = np.linspace(0.0, 40.0, 2000)
states[:, cm.KINETIC] = 170.0
mp = mech.pack()
from transient.core import crank_slider as cs  # noqa: E402  (parameter layout)

# the bare scene's parameters, by name; the last seven are what ``loads`` reads (all idle)
params = dict(r=mp[cs.R], l=mp[cs.L], m_slide=mp[cs.M_PISTON] + mp[cs.M_PIN],
              m_rot=mp[cs.M_CRANKPIN] + mp[cs.M_CRANK], m_rod=mp[cs.M_ROD],
              cg_from_pin=mp[cs.ROD_CG], I_rod=mp[cs.I_ROD], J0=base.inertia.total, load=0.0,
              e=mp[cs.E], m_piston=mp[cs.M_PISTON], m_pin=mp[cs.M_PIN],
              m_crankpin=mp[cs.M_CRANKPIN], m_crank=mp[cs.M_CRANK], sin_phi0=mp[cs.SIN0],
              cos_phi0=mp[cs.SIN0 + 1], n_cylinders=1.0, n_schedule=0.0, schedule_value=1.0,
              load_linear=0.0, load_fan=0.0, generator=0.0, starter=0.0, starter_noload=1.0)
P_NAMES = tuple(params)  # the order make_hand_rhs indexes
p = np.array(list(params.values()))
rec = np.array([np.inf, -np.inf])  # the speed range
out = np.empty(6)
rungs = {"hand-written (18)": {}, "+ offset, masses, cylinder loop": dict(layout=True),
         "+ load terms, starter switch": dict(layout=True, loads=True),
         "+ work integrals, speed range": dict(layout=True, loads=True, records=True)}
# every rung and transient agree (same equation, same numbers)
m_exact, _, _ = build_model(base)
o2 = np.empty(6)
sw = np.zeros(cm.N_SWITCHES, dtype=np.int64)
sw[cm.SW_DIRECTION] = 1
rhs_loop(m_exact, states[7:8], o2, sw, cm.work_array(m_exact))
t_hand = None
for name, flags in rungs.items():
    rhs = make_hand_rhs(**flags)
    o1 = np.empty(6)
    rhs(p, states[7], o1, rec.copy())
    assert abs(o1[1] / o2[1] - 1.0) < 1e-13, (name, o1, o2)
    t = per_call(make_hand_loop(rhs), p, states, out, rec)
    t_hand = t_hand or t
    print(f"{name}: {t * 1e9:.1f} ns per call ({t / t_hand:.3f}× hand-written)")
for kin in ("exact", "tabulated"):
    scene = dc.replace(base, solver=dc.replace(base.solver, kinematics=kin))
    m, _, _ = build_model(scene)
    t = per_call(rhs_loop, m, states, out, sw, cm.work_array(m))
    print(f"transient {kin}: {t * 1e9:.1f} ns per call ({t / t_hand:.3f}× hand-written)")

bare = dc.replace(base, run=dc.replace(base.run, revolutions=1000.0),
                  solver=dc.replace(base.solver, rtol=1e-8, atol=1e-11))
unused = dc.replace(bare, governor=Governor(model="droop", speed_full=1e4, speed_zero=2e4),
                    starter=Starter(torque=0.0))
w_bare, w_unused = run_walls(bare, unused)
print(f"run, bare scene: {w_bare:.4f} s; with an idle governor and starter: {w_unused:.4f} s "
      f"({w_unused / w_bare - 1:+.1%})")
