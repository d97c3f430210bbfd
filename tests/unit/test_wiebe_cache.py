"""The Wiebe cycles' file cache (:mod:`transient.forces.wiebe_cache`): a cycle read back is the
computed one to the last bit, its dense solution is integrated again on demand, the key follows
every argument, and a bad file or an unwritable folder costs a recomputation, never a run."""
from __future__ import annotations

import copy
import dataclasses
import math
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core import CACHE_DIR_VARIABLE, source_hash
from transient.errors import SceneError
from transient.forces import wiebe_cache
from transient.forces.wiebe import WiebeCycle, wiebe_tables
from transient.mechanisms.crank_slider import CrankSlider
from transient.scene import load_scene
from transient.scene.queries import wiebe_levels

CASES = Path(__file__).resolve().parents[2] / "cases"

# A small engine and cycle (the Gots geometry, coarse knots): cheap to integrate.
MECH = CrankSlider(crank_radius=0.047, rod_length=0.148, offset=0.0, bore=0.088,
                   piston_mass=1.52, crank_mass=0.912, rod_model="two-mass", rod_mass=1.752,
                   rod_cg_from_pin=0.1073, rod_inertia_cg=0.0, strokes=4,
                   firing_angles=(2 * math.pi,), bank_angles=(0.0,))
CYCLE = dict(p_a=0.1436e6, start=358 * math.pi / 180, duration=50 * math.pi / 180,
             p_intake=0.165e6, p_exhaust=0.182e6, gamma=1.368, step=2 * math.pi / 180,
             tolerance=1e-6)
LEVELS = [0.0, 0.031e-3]


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """The cache in a fresh folder (numba's stays where it is: its folder was fixed at import),
    found through ``XDG_CACHE_HOME`` whatever the user's ``TRANSIENT_CACHE_DIR``."""
    monkeypatch.delenv(CACHE_DIR_VARIABLE, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path / "transient" / "tables"


def compute(**changes):
    volume = MECH.volume_function(MECH.swept_volume() / 17.0)
    return lambda: wiebe_tables(volume, LEVELS, **{**CYCLE, **changes})


def arguments(**changes):
    return f"{MECH!r} {LEVELS!r} {dict(CYCLE, **changes)!r}"


def must_not_run():
    raise AssertionError("computed again, although the cache holds the cycles")


def assert_same_cycles(read, computed):
    assert len(read) == len(computed)
    for a, b in zip(read, computed):
        assert type(a) is WiebeCycle
        for field in dataclasses.fields(WiebeCycle):
            if field.name == "closed":
                assert (a.closed.start, a.closed.end) == (b.closed.start, b.closed.end)
            elif isinstance(getattr(b, field.name), np.ndarray):
                np.testing.assert_array_equal(getattr(a, field.name), getattr(b, field.name))
                assert getattr(a, field.name).dtype == getattr(b, field.name).dtype
            else:
                assert getattr(a, field.name) == getattr(b, field.name), field.name
                assert type(getattr(a, field.name)) is type(getattr(b, field.name)), field.name


def test_read_back_bit_identical(folder):
    computed = wiebe_cache.cached_cycles(arguments(), compute())
    files = list(folder.iterdir())
    assert [f.suffix for f in files] == [".npz"]  # one file, no temporary left over
    read = wiebe_cache.cached_cycles(arguments(), must_not_run)
    assert_same_cycles(read, computed)
    assert [c.fuel_mass for c in read] == LEVELS and read[1].p_max > read[0].p_max


def test_dense_solution_integrated_again_on_demand(folder):
    computed = wiebe_cache.cached_cycles(arguments(), compute())
    calls = []

    def counted():
        calls.append(1)
        return compute()()

    read = wiebe_cache.cached_cycles(arguments(), counted)
    assert calls == []  # the ends are stored
    assert (read[1].closed.start, read[1].closed.end) == (computed[1].closed.start,
                                                          computed[1].closed.end)
    x = np.linspace(np.pi, 3 * np.pi, 9)
    for i in (1, 0):
        p, w = read[i].closed(x)
        np.testing.assert_array_equal(p, computed[i].closed(x)[0])
        np.testing.assert_array_equal(w, computed[i].closed(x)[1])
        np.testing.assert_array_equal(read[i].closed.breaks, computed[i].closed.breaks)
    assert calls == [1]  # once for both cycles of the file


@pytest.mark.parametrize("change", [dict(gamma=1.37), dict(step=1.9 * math.pi / 180),
                                    dict(p_intake=0.166e6)])
def test_other_arguments_other_file(folder, change):
    wiebe_cache.cached_cycles(arguments(), compute())
    other = wiebe_cache.cached_cycles(arguments(**change), compute(**change))
    assert len(list(folder.iterdir())) == 2
    assert_same_cycles(other, compute(**change)())


def test_source_hash_follows_names_and_contents(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    first = source_hash(tmp_path, "**/*.py")
    assert source_hash(tmp_path, "*.py") != first  # the sub-folder's file counts
    (tmp_path / "sub" / "b.py").write_text("y = 3\n")
    assert source_hash(tmp_path, "**/*.py") != first
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    assert source_hash(tmp_path, "**/*.py") == first
    (tmp_path / "sub" / "b.py").rename(tmp_path / "sub" / "c.py")
    assert source_hash(tmp_path, "**/*.py") != first


def test_code_or_library_version_changes_the_file(folder, monkeypatch):
    first = wiebe_cache.cache_path(arguments())
    monkeypatch.setattr(wiebe_cache, "_code_version", lambda: "another version")
    assert wiebe_cache.cache_path(arguments()) != first
    assert wiebe_cache.cache_path(arguments()).parent == first.parent == folder


@pytest.mark.parametrize("damage", ["garbage", "truncated", "a field missing"])
def test_unreadable_file_computed_again_and_replaced(folder, damage):
    computed = wiebe_cache.cached_cycles(arguments(), compute())
    path = wiebe_cache.cache_path(arguments())
    if damage == "garbage":
        path.write_bytes(b"not a numpy file")
    elif damage == "truncated":
        path.write_bytes(path.read_bytes()[:1000])
    else:
        with np.load(path) as data:
            kept = {k: data[k] for k in data.files if k != "1.p_max"}
        np.savez(path, **kept)
    again = wiebe_cache.cached_cycles(arguments(), compute())
    assert_same_cycles(again, computed)
    assert_same_cycles(wiebe_cache.cached_cycles(arguments(), must_not_run), computed)


def test_unwritable_folder_still_gives_the_cycles(tmp_path, monkeypatch):
    (tmp_path / "transient").write_text("a file where the folder would be")
    monkeypatch.delenv(CACHE_DIR_VARIABLE, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    cycles = wiebe_cache.cached_cycles(arguments(), compute())
    assert_same_cycles(cycles, compute()())


def test_invalid_cycle_raises_and_stores_nothing(folder):
    with pytest.raises(SceneError, match="gas.wiebe.duration_deg"):
        wiebe_cache.cached_cycles(arguments(duration=-1.0), compute(duration=-1.0))
    assert not folder.exists() or list(folder.iterdir()) == []


def test_scene_levels_from_the_file_build_the_same_model(folder):
    """The Woschni case's model (cylinder-pressure states, which need the closed part's ends)
    from cycles read back equals the one from cycles just computed."""
    scene = load_scene(CASES / "gots_diesel_woschni.toml")
    # another (equally valid) tolerance: a cycle set no other test has put in the lru cache
    scene = replace(scene, gas=replace(scene.gas, wiebe=replace(scene.gas.wiebe,
                                                                tolerance=2e-10)))
    wiebe_levels.cache_clear()
    # the case's own cycles, if load_scene built them (not when this process had them already)
    before = set(folder.iterdir()) if folder.exists() else set()
    computed = build_model(scene)[0]
    assert len(set(folder.iterdir()) - before) == 1
    wiebe_levels.cache_clear()
    read = build_model(scene)[0]
    assert isinstance(wiebe_levels(scene.mechanism, scene.gas)[-1].closed,
                      wiebe_cache._ClosedPartOnDemand)
    for name in ("cyl_par", "knots", "coef", "piece_knot", "breakpoints", "bp_jump"):
        np.testing.assert_array_equal(getattr(read, name), getattr(computed, name), name)


def test_folder_keeps_the_last_used(folder, monkeypatch):
    monkeypatch.setattr(wiebe_cache, "MAX_FILES", 2)
    first, second, third = dict(gamma=1.36), dict(gamma=1.37), dict(gamma=1.38)
    for change in (first, second):
        wiebe_cache.cached_cycles(arguments(**change), compute(**change))
    for change, age in ((first, 30.0), (second, 20.0)):  # the first written the earliest
        path = wiebe_cache.cache_path(arguments(**change))
        os.utime(path, (path.stat().st_atime - age, path.stat().st_mtime - age))
    wiebe_cache.cached_cycles(arguments(**first), must_not_run)  # used again: now the latest
    wiebe_cache.cached_cycles(arguments(**third), compute(**third))
    kept = {p.name for p in folder.iterdir()}
    assert kept == {wiebe_cache.cache_path(arguments(**c)).name for c in (first, third)}


def test_failed_write_leaves_nothing_behind(folder, monkeypatch):
    def disk_full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(wiebe_cache.np, "savez", disk_full)
    cycles = wiebe_cache.cached_cycles(arguments(), compute())
    assert_same_cycles(cycles, compute()())
    assert list(folder.iterdir()) == []


def test_stand_in_survives_a_deep_copy(folder):
    """copy probes a new instance that __init__ never saw: the stand-in must not recurse then."""
    computed = wiebe_cache.cached_cycles(arguments(), compute())
    cycle = copy.deepcopy(wiebe_cache.cached_cycles(arguments(), compute())[1])
    assert isinstance(cycle.closed, wiebe_cache._ClosedPartOnDemand)  # read, not computed
    np.testing.assert_array_equal(cycle.coef, computed[1].coef)
    assert cycle.closed.end == computed[1].closed.end
    x = np.linspace(np.pi, 3 * np.pi, 5)
    np.testing.assert_array_equal(cycle.closed(x)[0], computed[1].closed(x)[0])
