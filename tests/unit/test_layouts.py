"""The declared layouts of the compiled arrays (:mod:`transient.core.declare`): offsets derived
from the declarations, the compiled index kernels against the declaration's offsets on every case,
and each checked against something counted another way: the state's and the output row's lengths
against the trajectory's columns that ``transient.scene.outputs`` names from the scene, the
reaction solvers' rows against the rows they share, the event tables against each other."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.core.declare import BY_INCREMENT, BY_SIZE, NOT_CONTROLLED, Block, Layout, Sized
from transient.core.model import articulated_friction as af
from transient.core.model import governor as gv
from transient.core.model import joint_friction as jf
from transient.core.model import layout
from transient.core.model import swash_friction as sf
from transient.core.model.work import N_WK, work_array
from transient.core.stepper import events
from transient.core.stepper import io as sio
from transient.scene import load_scene
from transient.scene.outputs import output_columns

CASES = sorted((Path(__file__).resolve().parents[2] / "cases").glob("*.toml"))


def test_offsets_follow_the_declared_sizes():
    lay = Layout("l", "a", ("b", 3), Block("c", 2, "two"), start=5)
    assert list(lay) == [5, 6, 9]
    assert lay.end == lay.size == 11 and len(lay) == 3
    assert lay.size_of("b") == 3 and lay.index("c") == 2
    assert lay.table() == [("a", "5", ""), ("b", "6…8", ""), ("c", "9…10", "two")]


def test_a_sized_block_is_laid_per_scene():
    lay = Layout("l", "a", ("n", Sized(lambda o: o.k, "k of them")), "z")
    assert lay.fixed_offset("n") == 1
    with pytest.raises(TypeError, match="known per scene"):
        lay.fixed_offset("z")
    with pytest.raises(TypeError):
        list(lay)  # (the unpacking of constants needs every offset known at import)

    class Obj:
        k = 4

    assert lay.offsets_for(Obj) == [0, 1, 5, 6]


def test_bad_declarations_are_refused():
    with pytest.raises(ValueError, match="named twice"):
        Layout("l", "a", "a")
    with pytest.raises(ValueError, match="size -1"):
        Layout("l", ("a", -1))
    with pytest.raises(KeyError, match="no block 'x'"):
        Layout("l", "a").index("x")


@pytest.mark.parametrize("case", CASES, ids=[c.stem for c in CASES])
def test_a_scenes_layouts_match_what_its_columns_and_states_count(case):
    """The compiled offsets (the chain the kernels index by) and the declaration's offsets (what
    the Python side lays out) agree, and both with what the scene counts otherwise (an elastic
    shaft line: two states per dof but the reference's, and its loss)."""
    scene = load_scene(case)
    model, _, _ = build_model(scene)
    at = layout.STATE.offsets_for(model)
    assert layout.state_offsets.python_entry(model) == tuple(at) == layout.state_offsets(model)
    assert [layout.gov_index(model), layout.latch_index(model), layout.cyl_index(model),
            layout.line_index(model), layout.line_loss_index(model),
            layout.n_state(model)] == at[layout.B_GOVERNOR:]
    # the state: its length counted from the scene
    dofs = len(scene.shaft.line_dofs()) if scene.shaft is not None else 0
    assert layout.line_dofs(model) == dofs
    expected = (6 + len(scene.friction.pairs) + len(gv.STATE_NAMES[model.gov_dyn])
                + scene.mechanism.n_cylinders * (int(model.latch) + int(model.woschni))
                + (2 * dofs - 1 if dofs else 0))
    control = layout.state_control(model)
    assert at[-1] == expected == control.size and np.all(np.diff(at) >= 0)
    assert list(control[:3]) == [BY_INCREMENT, BY_INCREMENT, BY_SIZE]
    assert np.all(control[3:layout.W_LOSS0 + model.n_pairs] == NOT_CONTROLLED)
    assert np.all(control[at[layout.B_GOVERNOR]:at[layout.B_GOVERNOR + 1]] == BY_SIZE)
    assert np.all(control[at[layout.B_PRESSURE]:at[layout.B_LINE_LOSS]] == BY_SIZE)
    assert np.all(control[at[layout.B_LINE_LOSS]:] == NOT_CONTROLLED)
    # the states that repeat in a periodic steady state: the speed, the governor's, the latched
    # fuels, the pressures and the line's twists and speeds, counted from the scene
    periodic = layout.periodic_states(model)
    assert periodic.size == expected - 6 - len(scene.friction.pairs) + 1 - (1 if dofs else 0)
    assert periodic[0] == layout.OMEGA and np.all(np.diff(periodic) > 0)
    assert at[layout.B_LOSS + 1] <= periodic[1:].min(initial=at[-1])
    assert periodic.max(initial=0) < at[layout.B_LINE_LOSS]
    # the output row: as long as the trajectory's columns that the scene names
    out = layout.OUTPUT.offsets_for(model)
    assert layout.output_offsets.python_entry(model) == tuple(out) == layout.output_offsets(model)
    assert [layout.pair_col(model), layout.governor_col(model), layout.cylinder_loss_col(model),
            layout.line_col(model), layout.n_outputs(model)] == [
        out[layout.O_PAIRS], out[layout.O_GOVERNOR], out[layout.O_CYL_LOSS], out[layout.O_LINE],
        out[-1]]
    if scene.run.mode != "prescribed-speed":
        names = list(output_columns(scene))
        assert out[-1] == len(names) and names[out[layout.O_GAS]] == "p_1"
        if model.n_pairs:
            assert names[out[layout.O_PAIRS]] == "S_1"
        if dofs:
            assert names[out[layout.O_LINE]] == f"twist_{scene.shaft.stations[0].name}"
            assert names[-1] == "W_line_loss"
    assert work_array(model).shape[0] == N_WK
    assert sio.fst_size(model) == (sio.N_FST + at[-1] + max(model.n_pairs, 1)
                                   + (2 + 2 * dofs if dofs else 0))
    if dofs:  # (the kernels' index of the elastic line's block, as the layout's)
        assert sio.line_fst(model, np.zeros(sio.fst_size(model))) == sio.FLOATS.offsets_for(
            model)[-2]


@pytest.mark.parametrize("solver", [jf, sf, af], ids=["crank-slider", "swash plate", "articulated"])
def test_each_reaction_solver_lays_its_rows_after_the_shared_ones(solver):
    shared = set(jf.SHARED)
    own = set(solver.ROWS)
    assert not shared & own and min(own) == jf.SHARED.end
    assert N_WK >= layout.WK_RX + solver.ROWS.end
    # every row constant of the module is one of its declared rows or a shared one
    prefix = {jf: "R_", sf: "S_", af: "A_"}[solver]
    constants = {getattr(solver, k) for k in dir(solver) if k.startswith(prefix) and k.isupper()
                 and isinstance(getattr(solver, k), int)}
    assert constants <= own | shared


def test_the_switches_lead_the_stepper_integer_state():
    assert sio.I_SWITCHES == 0 and sio.INTS.size_of("switches") == layout.N_SWITCHES
    assert [sio.I_STARTER_ON, sio.I_LOAD_TABLE] == [layout.SW_STARTER, layout.SW_LOAD_TABLE]
    assert sio.N_IST == layout.N_SWITCHES + len(sio.INTS) - 1


def test_events_are_named_once_and_watched_in_slots():
    assert len(set(sio.EVENT_NAMES)) == len(sio.EVENT_NAMES) == len(sio.EVENTS)
    assert sio.EVENT_NAMES[sio.EV_RELEASED] == "released"
    assert sio.EVENT_NAMES[sio.EV_PAIR_MODE] == "pair_mode"
    assert events.N_EVENT_KINDS == events.WATCHED.size
    # the pairs' margins last, as many as a Model has (layout.n_margins), each a bit of the
    # int64 switch of the modes
    assert events.FIRST_PAIR_EVENT + 1 == events.N_EVENT_KINDS
    assert layout.MAX_MARGINS < 63


def _numbas_own_type(model):
    """numba's type of ``model`` as it types any tuple, field by field (without the cache of
    :func:`transient.core.jit.typed_by_fingerprint`)."""
    from numba.core.typing.typeof import Purpose, _TypeofContext, typeof_impl

    return typeof_impl.dispatch(tuple)(model, _TypeofContext(Purpose.argument))


def test_the_models_type_from_its_fingerprint_is_numbas_own_on_every_case():
    from numba import typeof

    seen = {}
    for path in CASES:
        model, _, _ = build_model(load_scene(path))
        assert typeof(model) == _numbas_own_type(model), path.name
        seen.setdefault(typeof(model), path.name)
    assert len(seen) > 3  # (the cases differ in their mechanisms' kernels and fields' types)


def test_a_model_whose_field_changes_type_gets_its_own_type():
    from numba import typeof

    model, _, _ = build_model(load_scene(CASES[0]))
    other = model._replace(mech=model.mech.astype(np.float32))
    assert typeof(other) != typeof(model)
    assert typeof(other) == _numbas_own_type(other)
