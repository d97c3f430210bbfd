"""The mechanism registry: every registered class provides the :class:`Mechanism` members under
the name the scene reader finds it by, writes that name back, and its reference-path twin agrees
with its kernel; it provides every capability it claims, and a place that branches on the
mechanism never falls through to another mechanism's code."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from transient.analysis.pistons import KINEMATICS, piston_kinematics
from transient.analysis.requested import LOADS
from transient.cli.loads import DRAWERS
from transient.core.model.reactions import NO_REACTIONS
from transient.mechanisms import (
    CAPABILITIES,
    MECHANISMS,
    Mechanism,
    MissingCapability,
    ReactionFriction,
    capability_gaps,
    provider,
    provides,
)
from transient.mechanisms.crank_slider import CrankSlider
from transient.mechanisms.twins import KernelTwin
from transient.reference.integrate import REACTION_TWINS
from transient.scene import load_scene, to_toml

CASES = Path(__file__).resolve().parents[2] / "cases"

#: One scene of each registered mechanism: the first case (by name) of its ``type``.
SCENES = {}
for _path in sorted(CASES.glob("*.toml")):
    _type = re.search(r'^type = "([^"]+)"', _path.read_text(encoding="utf-8"), re.MULTILINE)
    if _type:
        SCENES.setdefault(_type.group(1), _path.name)


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
    # a claimed numpy twin is what the reference path runs, not the kernel's own code
    assert isinstance(terms.__self__, mech.twin if provides(mech, "twin") else KernelTwin)
    for j, p in enumerate(phi):
        J, dJ, u, du = terms(p)
        scale = np.max(np.abs(table["J"]))
        assert J == pytest.approx(table["J"][j], rel=1e-12, abs=1e-12 * scale)
        assert dJ == pytest.approx(table["dJ_dphi"][j], rel=1e-9, abs=1e-9 * scale)
        for k in range(mech.n_cylinders):
            assert u[k] == pytest.approx(table[f"u_{k + 1}"][j], rel=1e-9, abs=1e-12)
            assert du[k] == pytest.approx(table[f"du_{k + 1}"][j], rel=1e-9, abs=1e-12)


#: The capabilities held in tables above the mechanisms, by capability name.
TABLES = {"reaction-twin": REACTION_TWINS, "pistons": KINEMATICS, "loads": LOADS,
          "drawers": DRAWERS}


def test_the_tables_are_the_capabilities_that_name_them():
    """Every table capability of CAPABILITIES is checked here, under the name it gives."""
    named = {cap: where for cap, where in CAPABILITIES.items() if isinstance(where, str)}
    assert set(named) == set(TABLES)
    for cap, where in named.items():
        module, _, attr = where.rpartition(".")
        assert getattr(__import__(module, fromlist=[attr]), attr) is TABLES[cap]


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_every_mechanism_provides_what_it_claims(name):
    cls = MECHANISMS[name]
    assert cls.name == name
    assert capability_gaps(cls, TABLES) == []
    assert "pistons" in cls.capabilities  # (cylinder volumes and torques need it)


def test_tables_list_registered_mechanisms_only():
    for cap, table in TABLES.items():
        assert set(table) <= set(MECHANISMS), cap
        assert set(getattr(table, "own", table)) <= set(MECHANISMS), cap


def test_kernels_are_distinct():
    """Each mechanism compiles its own kernel (``Model.terms``) and, with reaction friction, its
    own solver: none reuses another's, and none the stubs of mechanisms without one."""
    kernels = [cls.kernel for cls in MECHANISMS.values()]
    assert len(set(map(id, kernels))) == len(kernels)
    for cls in MECHANISMS.values():
        if provides(cls, "reaction-friction"):
            assert not set(map(id, cls.reaction_kernels)) & set(map(id, NO_REACTIONS))
            assert len(cls.reaction_kernels) == 3


# -- a deliberately incomplete mechanism: the check must see what it lacks --------------------


#: A crank-slider under another name that never defined ``check_wedging`` yet claims reaction
#: friction, and claims loads and drawers that no table holds for it.
Incomplete = type("Incomplete", (), {
    **{k: v for k, v in vars(CrankSlider).items() if k not in ("check_wedging", "__dict__",
                                                               "__weakref__")},
    "name": "incomplete",
    "capabilities": frozenset({"reaction-friction", "reaction-twin", "pistons", "loads",
                               "drawers", "twin"})})


def test_an_incomplete_mechanism_fails_the_check():
    gaps = capability_gaps(Incomplete, TABLES)
    assert "Incomplete claims 'reaction-friction' but lacks 'check_wedging' of ReactionFriction" \
        in gaps
    for cap in ("reaction-twin", "pistons", "loads", "drawers"):
        assert any(g.startswith(f"Incomplete claims {cap!r} but ") for g in gaps), cap
    assert len(gaps) == 5


def test_unclaimed_table_entries_and_unknown_claims_fail_the_check():
    class Claims(CrankSlider):
        capabilities = frozenset({"pistons", "warp-drive"})

    gaps = capability_gaps(Claims, TABLES)
    assert "Claims claims 'warp-drive', not a capability" in gaps
    assert any("has 'crank-slider', which does not claim 'loads'" in g for g in gaps)


def test_a_mechanism_lacking_a_base_member_fails_the_check():
    class Bare:
        name = "bare"
        capabilities = frozenset()

    gaps = capability_gaps(Bare, {})
    assert "Bare lacks 'kernel' of Mechanism" in gaps
    assert "Bare lacks 'kinematics_table' of Mechanism" in gaps


def test_dispatch_never_falls_through():
    """A claimed capability without a provider is an error, an unclaimed one None, an unknown
    name an error; the piston kinematics of a mechanism without an entry is an error, not the
    crank-slider's."""
    mech = Incomplete.__new__(Incomplete)  # (the dispatch reads no field)
    with pytest.raises(MissingCapability, match="'incomplete' claims 'loads'"):
        provider(mech, "loads", LOADS)
    with pytest.raises(MissingCapability):
        piston_kinematics(mech, [0.0])
    real = CrankSlider.__new__(CrankSlider)
    assert provider(MECHANISMS["swash-plate"], "drawers", DRAWERS) is None
    assert provider(real, "loads", LOADS) is LOADS["crank-slider"]
    with pytest.raises(ValueError, match="unknown capability"):
        provides(real, "warp-drive")


def test_protocols_are_runtime_checkable_on_instances():
    """The registered mechanisms that claim reaction friction are ReactionFriction instances
    (the Protocol's attribute check), and every one is a Mechanism."""
    for stem in ("gots_diesel_reaction_friction", "swash_plate_4cyl"):
        mech = load_scene(CASES / f"{stem}.toml").mechanism
        assert isinstance(mech, Mechanism)
        assert isinstance(mech, ReactionFriction) == provides(mech, "reaction-friction")
