"""The mechanism registry: every registered class provides the :class:`Mechanism` members under
the name the scene reader finds it by, writes that name back, and its reference-path twin agrees
with its kernel."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from transient.analysis.requested import LOADS
from transient.mechanisms import MECHANISMS, Mechanism
from transient.scene import load_scene, to_toml

CASES = Path(__file__).resolve().parents[2] / "cases"

#: One scene of each registered mechanism.
SCENES = {"crank-slider": "gots_diesel_4400.toml", "swash-plate": "swash_plate_4cyl.toml",
          "articulated": "radial_5cyl.toml"}


def test_every_mechanism_has_a_scene_here():
    assert set(SCENES) == set(MECHANISMS)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_registered_under_its_name_and_written_back_by_it(name):
    scene = load_scene(CASES / SCENES[name])
    mech = scene.mechanism
    assert type(mech) is MECHANISMS[name] and mech.name == name
    assert isinstance(mech, Mechanism)
    assert f'type = "{name}"' in to_toml(scene).splitlines()
    assert load_scene("resolved.toml", text=to_toml(scene)).mechanism == mech


@pytest.mark.parametrize("name", sorted(SCENES))
def test_reference_twin_agrees_with_the_kernel(name):
    mech = load_scene(CASES / SCENES[name]).mechanism
    phi = np.linspace(0.0, mech.cycle, 37)
    table = mech.kinematics_table(phi)
    terms = mech.reference_terms()
    for j, p in enumerate(phi):
        J, dJ, u, du = terms(p)
        scale = np.max(np.abs(table["J"]))
        assert J == pytest.approx(table["J"][j], rel=1e-12, abs=1e-12 * scale)
        assert dJ == pytest.approx(table["dJ_dphi"][j], rel=1e-9, abs=1e-9 * scale)
        for k in range(mech.n_cylinders):
            assert u[k] == pytest.approx(table[f"u_{k + 1}"][j], rel=1e-9, abs=1e-12)
            assert du[k] == pytest.approx(table[f"du_{k + 1}"][j], rel=1e-9, abs=1e-12)


def test_loads_storers_are_keyed_by_registered_names():
    assert set(LOADS) <= set(MECHANISMS)
