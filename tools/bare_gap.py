"""Where the bare scene's right-hand side loses against the hand-written (18), seen from
transient's side (``tools/handwritten_kernel.py`` builds up from the hand-written side).

The bare single cylinder (``cases/coasting_single.toml``) takes none of the branches that
``rhs.derivative`` has for other scenes: gas forces, a generator, pairs, governor states, wall
heat, other mechanisms. This script times a copy of ``derivative``'s crank-angle path with those
branches, then with each of them removed (compiled out: a closure constant), then with all
removed, each checked against transient's own right-hand side first (the same checksum to 1e-9
over the states). It also times transient's ``derivative`` itself in this script's loop and in
``transient bench``'s (``transient.verify.targets.rhs_loop``): the same code in two loops, to show
how far the compiler's layout alone moves a call. Per-call medians as ``transient bench`` times
them. Rerun: ``.venv/bin/python tools/bare_gap.py`` (mostly compiling).
"""
from __future__ import annotations

import numpy as np
from numba import njit

import transient.core.model.forcing as forcing
import transient.core.model.layout as layout
import transient.core.model.rhs as rhs
from transient.core.model import governor as gv
from transient.core.model.crank_slider import crank_slider_terms
from transient.scene import load_scene
from transient.verify.targets import BARE_SCENE, CALLS_PER_STEP, per_call, rhs_arguments, rhs_loop


def derivative_without(kind=True, gas=True, generator=True, others=True):
    """A loop over states calling ``rhs.derivative``'s crank-angle path, without pairs (the
    bare scene's), keeping only the branches whose flag is set: ``kind`` the dispatch on the
    mechanism's kind (else the crank slider's terms directly), ``gas`` the gas forces,
    ``generator`` the generator's term, ``others`` the pairs', governor's and wall heat's."""

    @njit(inline="always", _nrt=False)
    def derivative(m, y, sel, sw, wk, out):
        u = wk[layout.WK_U]
        with_dJ = m.n_pairs > 0
        if kind:
            J, _ = forcing.mechanism_terms(m, y[layout.PHI], u,
                                           wk[layout.WK_DU], with_dJ)
        else:
            J, _ = crank_slider_terms(m.mech, y[layout.PHI], u, wk[layout.WK_DU], with_dJ)
        J += m.J0
        w = np.sqrt(2.0 * y[layout.KINETIC] / J)
        M_gas = 0.0
        if gas and m.has_gas:
            f = forcing.command(m, w, y, sw)
            forcing.select_pieces(m, sel, wk)
            for k in range(m.ncyl):
                M_gas += m.gas_scale[k] * (forcing.gas_value(m, k, y[layout.PHI], sel, wk)
                                           - m.gas_offset) * u[k]
            M_gas *= f
        s = forcing.load_scale(m, y, sw[layout.SW_LOAD])
        M_load = -s * (m.load_const + m.load_linear * w + m.load_fan * w * abs(w))
        if generator and m.gen_power != 0.0:
            M_load -= s * m.gen_power / (m.gen_min if sw[layout.SW_GENERATOR] else w)
        M_starter = 0.0
        if sw[layout.SW_STARTER]:
            M_starter = m.starter_torque * (1.0 - w / m.starter_noload)
        wk[layout.WK_SPEED, 0] = min(wk[layout.WK_SPEED, 0], w)
        wk[layout.WK_SPEED, 1] = max(wk[layout.WK_SPEED, 1], w)
        out[layout.W_GAS] = M_gas
        out[layout.W_LOAD] = M_load
        out[layout.W_STARTER] = M_starter
        if others:
            if m.n_pairs != 0:
                # (the bare scene has none: this copy does not solve them)
                out[layout.W_LOSS0] = np.nan
            if m.gov_dyn != gv.NONE or m.latch:
                forcing.governor_rates(m, w, y, 1.0 / w, sw, wk, out)
            if m.woschni:
                forcing.cylinder_rates(m, True, y, sel, w, forcing.command(m, w, y, sw), wk, out)
        out[layout.PHI] = 1.0
        out[layout.T] = 1.0 / w
        out[layout.KINETIC] = M_gas + M_load + M_starter

    @njit(_nrt=False)
    def loop(m, states, y, out, sw, wk, chained):
        acc = 0.0
        for i in range(states.shape[0]):
            derivative(m, states[i], states[i - i % CALLS_PER_STEP, layout.PHI], sw, wk, out)
            acc += out[layout.KINETIC]
        return acc

    return loop


@njit(_nrt=False)
def transient_in_this_loop(m, states, y, out, sw, wk, chained):
    acc = 0.0
    for i in range(states.shape[0]):
        rhs.derivative(m, True, states[i], states[i - i % CALLS_PER_STEP, layout.PHI], sw, wk, out)
        acc += out[layout.KINETIC]
    return acc


loops = {"transient's derivative, transient bench's loop": rhs_loop,
         "transient's derivative, this script's loop": transient_in_this_loop,
         "the copy, every branch": derivative_without(),
         "  without the mechanism kind's dispatch": derivative_without(kind=False),
         "  without the gas forces": derivative_without(gas=False),
         "  without the generator": derivative_without(generator=False),
         "  without pairs, governor, wall heat": derivative_without(others=False),
         "  without all four": derivative_without(False, False, False, False)}
args = rhs_arguments(load_scene(BARE_SCENE))
sums = {name: loop(*args, False) for name, loop in loops.items()}
reference = sums["transient's derivative, transient bench's loop"]
for name, value in sums.items():
    if abs(value - reference) > 1e-9 * abs(reference):
        raise SystemExit(f"{name.strip()}: checksum {value!r} against transient's {reference!r}")
for rnd in (1, 2):
    print(f"round {rnd}")
    for name, loop in loops.items():
        print(f"  {name:48s} {per_call(loop, *args, False) * 1e9:6.1f} ns per call")
