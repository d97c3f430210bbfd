"""The output grid in time (``[output]``; the rule in docs/guide/scenes.md): below the switch
speed and whenever the shaft turns backwards a run is integrated in time, and besides the time
grid (``dt``) it writes a sample wherever the shaft angle crosses a multiple of
360°/samples_per_rev, either way, and one at every speed reversal. So a rocking start shows each
swing and each turning point.

The reproducer of a failed start (issue: ``gots_diesel_spinup.toml`` with no flywheel, a
0.001 kg m² shaft, 30 revolutions asked within 0.5 s): the crank rocks in compression, about
16 reversals. Checked against the rule itself (every multiple of the angle spacing between two
turning points is a sample), against the events (every reversal is a sample with ω = 0), and
against the work–energy balance at every sample (the interpolated rows are the motion's).
"""
from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from transient.run import integrate
from transient.scene import scene_from_dict

CASES = Path(__file__).resolve().parents[2] / "cases"


def rocking_start():
    d = tomllib.loads((CASES / "gots_diesel_spinup.toml").read_text(encoding="utf-8"))
    d["inertia"].update(flywheel=0.0, shaft=0.001)
    d["run"] = {"revolutions": 30, "t_end": 0.5}
    return scene_from_dict(d, file="rocking")


@pytest.fixture(scope="module")
def rocking():
    scene = rocking_start()
    return scene, integrate(scene)


def test_every_reversal_is_a_sample_at_rest(rocking):
    scene, data = rocking
    tr, rev = data.trajectory, data.events["speed_reversal"]
    assert len(rev) >= 10  # (it rocks: the reproducer's run has 16)
    assert np.all(np.diff(tr["t"]) > 0.0)
    for t, phi in rev:
        i = int(np.searchsorted(tr["t"], t))
        assert tr["t"][i] == t and tr["phi"][i] == phi and tr["omega"][i] == 0.0


def test_each_swing_has_a_sample_at_every_multiple_of_the_angle_spacing(rocking):
    """Between two turning points the shaft turns one way: every multiple of Δφ = 5° between
    them is a sample (to rounding), so consecutive samples are never more than Δφ apart, and a
    swing of s radians has at least floor(s/Δφ) samples."""
    scene, data = rocking
    tr, rev = data.trajectory, data.events["speed_reversal"]
    dphi = 2.0 * math.pi / scene.output.samples_per_rev
    for (t0, p0), (t1, p1) in zip(rev[:-1], rev[1:]):
        inside = (tr["t"] > t0) & (tr["t"] < t1)
        phi = tr["phi"][inside]
        lo, hi = min(p0, p1), max(p0, p1)
        levels = dphi * np.arange(math.floor(lo / dphi) + 1, math.ceil(hi / dphi))
        levels = levels[(levels > lo + 1e-9) & (levels < hi - 1e-9)]
        assert levels.size >= 3  # (a swing spans several 5° steps)
        assert phi.size >= levels.size
        gaps = np.abs(np.subtract.outer(levels, phi)).min(axis=1)
        assert gaps.max() <= 1e-9 * max(1.0, hi), (t0, t1)
        swing = np.concatenate([[p0], phi, [p1]])
        assert np.abs(np.diff(swing)).max() <= dphi * (1 + 1e-9)


def test_the_samples_in_time_close_the_energy_balance(rocking):
    """½J(φ)ω² − ½J(φ₀)ω₀² = W_gas + W_load + W_starter at every sample (no pairs), to the
    tolerance the stress suite holds runs to (2000·rtol of the energy throughput): the rows
    interpolated at the angle grid's crossings are the motion's, not something near it."""
    scene, data = rocking
    tr = data.trajectory
    K = 0.5 * tr["J"] * tr["omega"] ** 2
    works = tr["W_gas"] + tr["W_load"] + tr["W_starter"]
    scale = K.max() + np.abs(tr["W_gas"]).max() + np.abs(tr["W_load"]).max()
    assert np.max(np.abs(K - K[0] - works)) / scale <= 2000 * scene.solver.rtol


def test_a_fast_run_in_time_keeps_its_angle_spacing_and_its_buffer():
    """Coasting in the time domain at 3600 samples a turn: a step in time that would span more
    than 256 of the angle grid's intervals is taken again shorter (the samples of one step fit
    the rows the stepper keeps free), and the samples are never more than 0.1° apart."""
    d = tomllib.loads((CASES / "coasting_single.toml").read_text(encoding="utf-8"))
    d = copy.deepcopy(d)
    d["run"] = {"revolutions": 2}
    d.setdefault("solver", {})["domain"] = "time"
    d["output"] = {"samples_per_rev": 3600}
    scene = scene_from_dict(d, file="fast-in-time")
    data = integrate(scene)
    assert data.complete
    phi = data.trajectory["phi"]
    assert np.all(np.diff(data.trajectory["t"]) > 0.0)
    assert np.diff(phi).max() <= 2.0 * math.pi / 3600 * (1 + 1e-9)
    assert phi.size >= 2 * 3600
