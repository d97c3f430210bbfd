"""``scene.replace`` validates exactly as a scene file is: for each kind of check, the same key
and the same message as the same value written into the TOML file."""
from __future__ import annotations

import pytest
from scene_texts import MIXED_CYCLE, SMALL

from transient import SceneError, load_scene

#: (table, key, value as Python, value as TOML): one of each kind of check.
CHANGES = [
    ("inertia", "flywheel", -0.2, "-0.2"),  # a range
    ("initial", "phi_deg", "x", '"x"'),  # a type
    ("run", "revolutionz", 3, "3"),  # an unknown key
    ("solver", "method", "euler", '"euler"'),  # a choice
    ("mechanism", "rod_length_mm", 40, "40"),  # geometry: the rod shorter than the crank
    ("output", "samples_per_rev", 0, "0"),  # an integer's range
    ("scene", "name", " ", '" "'),  # an empty name
    ("friction", "policy", "magic", '"magic"'),  # a table the scene did not have
    ("load", "torque", float("nan"), "nan"),  # not finite
    ("run", "t_end", -1.0, "-1.0"),  # a time
]


def _toml_with(table: str, key: str, value: str) -> str:
    """SMALL with ``key = value`` in its table ``table`` (the table added if it has none)."""
    lines = SMALL.splitlines()
    header = f"[{table}]"
    if header in lines:
        i = lines.index(header) + 1
        end = next((j for j in range(i, len(lines)) if lines[j].startswith("[")), len(lines))
        lines[i:end] = [f"{key} = {value}"] + [line for line in lines[i:end]
                                               if not line.startswith(f"{key} =")]
    else:
        lines += ["", header, f"{key} = {value}"]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("table, key, value, toml", CHANGES)
def test_replace_raises_what_the_file_raises(table, key, value, toml):
    scene = load_scene("small.toml", text=SMALL)
    with pytest.raises(SceneError) as from_file:
        load_scene("small.toml", text=_toml_with(table, key, toml))
    with pytest.raises(SceneError) as replaced:
        scene.replace(**{table: {key: value}})
    assert (replaced.value.key, replaced.value.message) == \
        (from_file.value.key, from_file.value.message)
    assert str(replaced.value) == f"(replace): {from_file.value.key}: {from_file.value.message}"


def test_a_key_in_another_unit_replaces_the_scene_own():
    scene = load_scene("small.toml", text=SMALL)
    faster = scene.replace(initial={"omega_rpm": 1500})
    assert faster.initial.omega == pytest.approx(1500 * 3.141592653589793 / 30, rel=1e-15)
    assert faster.replace(initial={"omega": 10.0}).initial.omega == 10.0
    assert scene.initial.omega == pytest.approx(1000 * 3.141592653589793 / 30, rel=1e-15)


def test_a_table_must_be_given_as_a_dict():
    with pytest.raises(SceneError, match="give the table's keys as a dict, got float"):
        load_scene("small.toml", text=SMALL).replace(inertia=0.5)


def test_a_key_given_as_none_is_taken_out_in_any_unit():
    """None takes a key out, whatever unit the scene wrote it in, and the default applies again;
    a 4-stroke made a 2-stroke drops the gas-exchange pressures a 2-stroke refuses."""
    scene = load_scene("small.toml", text=SMALL)
    faster = scene.replace(initial={"omega_rpm": 1500})
    with pytest.raises(SceneError, match="at rest with no starter"):  # (the default: at rest)
        faster.replace(initial={"omega": None})
    diesel = load_scene("small.toml", text=SMALL + MIXED_CYCLE.format(cr=18))
    with pytest.raises(SceneError, match="has no intake or exhaust stroke"):
        diesel.replace(mechanism={"strokes": 2})
    two = diesel.replace(mechanism={"strokes": 2}, gas={"p_intake": None, "p_exhaust": None})
    assert (two.mechanism.strokes, two.gas.p_intake, two.gas.p_exhaust) == (2, 0.0, 0.0)
