"""An inertia switched in: a load's inertia J_x, at rest, coupled to the shaft
by a clutch at ``load.inertia_time`` — an inelastic engagement that conserves the angular
momentum J(φ)ω.

Closed form on the coasting single cylinder (no forces): before the switch ½J(φ)ω² = E₀; after
it ½(J(φ) + J_x)ω² = E₀·J_s/(J_s + J_x), J_s = J(φ) at the switch; the energy lost,
E₀·J_x/(J_s + J_x), is what ``W_load`` holds at the end. And the compiled path against the
reference path on a governed engine (the Gots PI scene), where the switch also excites the
governor.
"""
from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
from conftest import CASES

from transient.run import integrate
from transient.scene import scene_from_dict


def scene(case: str, **sections):
    data = tomllib.loads((CASES / case).read_text(encoding="utf-8"))
    for name, value in sections.items():
        data.setdefault(name, {}).update(value)
    return scene_from_dict(copy.deepcopy(data), case)


def test_coasting_energy_drops_by_the_inelastic_engagement():
    extra, t_s = 0.05, 0.2
    sc = scene("coasting_single.toml", load={"inertia": extra, "inertia_time": t_s},
               run={"revolutions": 30.0})
    data = integrate(sc)
    assert data.complete, data.message
    tr = data.trajectory
    assert data.events["inertia_switch"].shape == (1, 2)
    assert data.events["inertia_switch"][0, 0] == t_s
    energy = 0.5 * tr["J"] * tr["omega"] ** 2
    before, after = tr["t"] <= t_s, tr["t"] > t_s
    at = np.flatnonzero(tr["t"] == t_s)
    assert at.size == 1  # the run stops on the switch: its row holds the state before it
    e0, j_s = energy[0], tr["J"][at[0]]
    expected = e0 * j_s / (j_s + extra)
    drift_before = np.abs(energy[before] / e0 - 1.0).max()
    drift_after = np.abs(energy[after] / expected - 1.0).max()
    lost = tr["W_load"][-1] / (e0 * extra / (j_s + extra)) + 1.0
    print(f"J_s = {j_s:.6g} kg m², energy after/before {energy[after][-1] / e0:.12f} (closed "
          f"form {j_s / (j_s + extra):.12f}); drift before {drift_before:.2g}, after "
          f"{drift_after:.2g}; W_load against the loss {lost:.2g}")
    assert np.all(tr["J"][after] > extra)  # the extra inertia is on the shaft from then on
    assert drift_before <= 1e-9 and drift_after <= 1e-9
    assert abs(lost) <= 1e-12
    # the balance at the end: ½J(φ)ω² − ½J₀ω₀² = W_load (no other force)
    assert abs(energy[-1] - e0 - tr["W_load"][-1]) <= 1e-9 * e0


def test_switch_agrees_with_the_reference_path():
    sections = dict(load={"inertia": 0.1, "inertia_time": 0.05, "schedule_time": [],
                          "schedule_scale": [], "generator_power": 40e3},
                    run={"t_end": 0.15}, solver={"rtol": 1e-10, "atol": 1e-10})
    fast = integrate(scene("gots_diesel_pi.toml", **sections))
    sections["solver"]["method"] = "scipy-DOP853"
    ref = integrate(scene("gots_diesel_pi.toml", **sections))
    assert fast.complete and ref.complete
    a, b = fast.trajectory, ref.trajectory
    worst = {n: abs(a[n][-1] - b[n][-1]) / max(1.0, abs(b[n][-1]))
             for n in ("omega", "phi", "W_load", "gov_rack", "gov_integral")}
    worst["switch"] = np.abs(fast.events["inertia_switch"] - ref.events["inertia_switch"]).max()
    w_dip = (a["omega"].min() - a["omega"][0]) / a["omega"][0]
    print({k: f"{v:.2g}" for k, v in worst.items()}, f"speed dip {w_dip:.3%}")
    assert w_dip < -0.05  # the engagement is felt
    assert max(worst.values()) <= 1e-6
    assert math.isclose(fast.events["inertia_switch"][0, 0], 0.05, abs_tol=0.0)
