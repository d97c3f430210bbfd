"""Accuracy of the compiled methods (DOP853, DOPRI5; adaptive and fixed-step) against a closed
form: a single cylinder braked by a constant torque c. In crank angle dK/dφ = −c, so
K(φ) = K₀ − cφ exactly and the time to turn Φ is t(Φ) = ∫₀^Φ √(J(φ)/(2K(φ))) dφ, computed with
``scipy.integrate.quad`` (relative error ~1e-14). The phase error t_run/t − 1 measures the stepper.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from transient.core.model.crank_slider import crank_slider_terms
from transient.run import integrate
from transient.scene import Load, Run, load_scene

CASES = Path(__file__).resolve().parents[2] / "cases"
REVS = 10
ORDER = {"dop853": 8, "dopri5": 5}


def braked():
    """cases/coasting_single.toml (J varies ±12 %) from 1000 rpm, braked so that K falls by 90 %
    over REVS revolutions; and the exact time of those revolutions."""
    base = load_scene(CASES / "coasting_single.toml")
    mp = base.mechanism.pack()
    u, du = np.empty(1), np.empty(1)

    def J(p):
        return crank_slider_terms(mp, p, u, du)[0] + base.inertia.total

    K0 = 0.5 * J(base.initial.phi) * base.initial.omega ** 2
    c = 0.9 * K0 / (2 * math.pi * REVS)
    t_exact, err = quad(lambda p: math.sqrt(J(p) / (2.0 * (K0 - c * p))), 0.0,
                        2 * math.pi * REVS, epsabs=0.0, epsrel=1e-13, limit=1000)
    assert base.initial.phi == 0.0 and err < 1e-12 * t_exact
    return replace(base, load=Load(torque=c), run=Run(revolutions=REVS)), t_exact


SCENE, T_EXACT = braked()


def phase_error(method, **solver):
    data = integrate(replace(SCENE, solver=replace(SCENE.solver, method=method, **solver)))
    assert data.complete and data.trajectory["phi"][-1] == pytest.approx(2 * math.pi * REVS,
                                                                         rel=1e-14)
    return data.trajectory["t"][-1] / T_EXACT - 1.0, data


@pytest.mark.parametrize("method,steps", [("dop853", (4, 8)), ("dopri5", (32, 64))])
def test_fixed_step_converges_with_the_method_order(method, steps):
    """Fixed steps of 2π/N: halving the step divides the phase error by 2^p (p = 8, 5).

    Equal steps integrate the periodic part of √(J/2K) spectrally, so at coarser steps the slope
    is steeper and at finer ones round-off (~1e-14) takes over: the pairs are where the error is
    ≥ 50× round-off and the method's own truncation error governs.
    """
    p = ORDER[method]
    errs = []
    for n in steps:
        e, data = phase_error(method, fixed_step=2 * math.pi / n)
        assert data.solver["nsteps"] == n * REVS and data.solver["nreject"] == 0
        errs.append(abs(e))
    slope = math.log2(errs[0] / errs[1])
    print(f"{method}: N = {steps}: phase errors {errs[0]:.3e}, {errs[1]:.3e}, slope {slope:.2f}")
    assert errs[1] >= 5e-13
    assert p - 0.5 <= slope <= p + 1.0


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_adaptive_phase_error_falls_with_rtol(method):
    """Adaptive steps at rtol 1e-6 and 1e-9: phase error ≤ 10·rtol, and 30× smaller at 1e-9."""
    errs = {}
    for rtol in (1e-6, 1e-9):
        e, data = phase_error(method, rtol=rtol, atol=rtol * 1e-3)
        errs[rtol] = abs(e)
        print(f"{method} rtol {rtol:g}: phase error {e:.3e}, {data.solver['nsteps']} steps")
        assert abs(e) <= 10 * rtol
    assert errs[1e-9] <= errs[1e-6] / 30


def test_fixed_step_lands_on_breakpoints():
    """With gas pressure (breakpoints at the pulses' corners) every fixed step ends on each
    breakpoint it meets; the run still matches an adaptive rtol 1e-10 run to 1e-7 in ω."""
    base = load_scene(CASES / "swash_plate_4cyl.toml")
    fine = integrate(replace(base, solver=replace(base.solver, rtol=1e-10, atol=1e-12)))
    step = math.radians(1.0)
    data = integrate(replace(base, solver=replace(base.solver, fixed_step=step)))
    assert data.complete and fine.complete
    bp = data.events["breakpoint"][:, 1]
    assert bp.size > 0
    assert np.array_equal(bp, fine.events["breakpoint"][:, 1][: bp.size])
    w, w_ref = data.trajectory["omega"][-1], fine.trajectory["omega"][-1]
    print(f"fixed 1°: {data.solver['nsteps']} steps, ω_end {w!r} vs {w_ref!r}")
    assert abs(w / w_ref - 1.0) <= 1e-7


def test_where_chunks_end_changes_nothing(monkeypatch):
    """The stepper runs in chunks that end where the output buffer fills, so their ends depend on
    the samples per turn. What a chunk leaves (the derivative carried over, the pairs' margins,
    the step-size control's memory of a rejection) the next takes up as it is: the governed
    diesel with two friction pairs, at one sample per turn in a buffer that never fills and at
    72 in one that fills every ~1.4 turns (700 rows, 600 of them kept free), takes the same steps
    to the same bits. (A chunk that recomputed the derivative with the table piece ahead of the
    shaft angle, or forgot a rejection, would make the steps depend on the output.)
    """
    import transient.run as sim
    base = load_scene(CASES / "gots_diesel_governed.toml")

    def run(samples, rows):
        monkeypatch.setattr(sim, "BUFFER_ROWS", rows)
        scene = replace(base, run=replace(base.run, revolutions=100.0, t_end=math.inf),
                        solver=replace(base.solver, rtol=1e-10, atol=1e-13),
                        output=replace(base.output, samples_per_rev=samples))
        return integrate(scene)

    one, many = run(1, 10_000), run(72, 700)
    assert one.solver["nsteps"] == many.solver["nsteps"]
    assert one.solver["nreject"] == many.solver["nreject"]
    assert one.solver["mode_switches"] == many.solver["mode_switches"] > 1000
    for name in ("phi", "t", "omega", "epsilon", "W_gas", "W_load", "fuel"):  # the end, exactly
        assert one.trajectory[name][-1] == many.trajectory[name][-1], name
    # the once-per-turn samples are among the 72 per turn (their angles k·2π and j·2π/72 can
    # differ in the last bit, so the dense output is read an ulp apart)
    every = {round(p / (2 * math.pi), 9): i for i, p in enumerate(many.trajectory["phi"])}
    rows = [every[round(p / (2 * math.pi), 9)] for p in one.trajectory["phi"]]
    for name in ("t", "omega", "W_load"):
        assert one.trajectory[name] == pytest.approx(many.trajectory[name][rows], rel=1e-14)
