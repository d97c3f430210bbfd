"""The ``[shaft]`` table: read into SI, written back, every mistake refused in one line naming
the key (exit 2), and a scene with it never run rigid or without what it asks in its place:
``transient run`` and the API refuse what the elastic run does not support, and ``transient
modes`` writes its modes."""
from __future__ import annotations

import math
from pathlib import Path

import pytest
from scene_texts import SMALL

from transient.cli import main
from transient.errors import SceneError
from transient.run import simulate
from transient.scene import load_scene
from transient.shaft import rigid_equivalent

CASES = Path(__file__).resolve().parents[2] / "cases"
BASE = SMALL.replace("[inertia]\nshaft = 0.02\n", "")
LINE = """
[[shaft.stations]]
name = "front"
inertia = 0.01
[[shaft.stations]]
name = "throw"
cylinders = [1]
[[shaft.stations]]
name = "flywheel"
inertia = 0.2
[[shaft.sections]]
stiffness = 2e5
[[shaft.sections]]
length_mm = 100
diameter_mm = 60
bore_mm = 20
"""


def scene(text: str = LINE, base: str = BASE):
    return load_scene("s.toml", text=base + text)


def refused(text: str, base: str = BASE) -> SceneError:
    with pytest.raises(SceneError) as info:
        scene(text, base)
    return info.value


def test_a_line_is_read_in_si_with_its_defaults():
    shaft = scene().shaft
    assert [s.name for s in shaft.stations] == ["front", "throw", "flywheel"]
    assert shaft.stations[1].cylinders == (1,) and shaft.stations[1].inertia == 0.0
    # k = G π (d⁴ − d_i⁴) / (32 L), steel by default
    assert shaft.sections[1].stiffness == pytest.approx(
        80e9 * math.pi * (0.06 ** 4 - 0.02 ** 4) / (32 * 0.1), rel=1e-12)
    assert shaft.reference == "flywheel"  # (the largest own inertia)
    assert shaft.load_at == "flywheel"  # (no coupling: the last station)
    assert shaft.coupling is None and shaft.dampers == ()


def test_a_shear_modulus_in_gpa_and_the_load_on_the_driven_side():
    shaft = scene(LINE.replace("bore_mm = 20", "shear_modulus_GPa = 40")
                  + "[shaft.coupling]\nstiffness = 1e4\ndriven_inertia = 0.5\ngear_ratio = 2\n").shaft
    assert shaft.sections[1].stiffness == pytest.approx(40e9 * math.pi * 0.06 ** 4 / 3.2,
                                                        rel=1e-12)
    assert shaft.load_at == "driven" and shaft.coupling.referred_inertia == 2.0


def test_the_resolved_scene_round_trips():
    text = LINE + """[shaft]
reference = "front"
speed_range_rpm = [500, 3000]
[[shaft.dampers]]
station = "front"
model = "tuned"
inertia = 0.003
stiffness = 1e4
damping = 1.0
[shaft.coupling]
stiffness = 1e4
driven_inertia = 0.5
"""
    text = text.replace("stiffness = 2e5\n", "stiffness = 2e5\nloss_factor = 0.03\n", 1)
    original = scene(text)
    again = load_scene("again.toml", text=original.to_toml())
    assert again == original and again.shaft.reference == "front"


@pytest.mark.parametrize("text, key, words", [
    (LINE.replace('name = "throw"\ncylinders = [1]', 'name = "front"\ncylinders = [1]'),
     "shaft.stations[1].name", "names station 1 already"),
    (LINE.replace("[[shaft.sections]]\nstiffness = 2e5\n", ""), "shaft.sections",
     "give one [[shaft.sections]] between each two consecutive stations, 2"),
    (LINE.replace("cylinders = [1]", "cylinders = []\ninertia = 0.01"), "shaft.stations",
     "cylinder(s) 1 on no station"),
    (LINE.replace("cylinders = [1]", "cylinders = [2]"), "shaft.stations[1].cylinders",
     "cylinder 2 does not exist; the mechanism has cylinders 1 … 1"),
    (LINE.replace('inertia = 0.2', 'inertia = 0.2\ncylinders = [1]'),
     "shaft.stations[2].cylinders", "cylinder 1 is on station 2 already"),
    (LINE.replace("inertia = 0.01", "inertia = 0"), "shaft.stations[0].inertia",
     "is 0 on a station without cylinders"),
    (LINE.replace("stiffness = 2e5", "stiffness = 0"), "shaft.sections[0].stiffness",
     "must be > 0"),
    (LINE.replace("stiffness = 2e5", "stiffness = 2e5\nlength = 1"), "shaft.sections[0].length",
     "given with 'stiffness'"),
    (LINE.replace("bore_mm = 20", "bore_mm = 60"), "shaft.sections[1].bore_mm",
     "must be < diameter"),
    (LINE.replace("diameter_mm = 60\n", ""), "shaft.sections[1].diameter",
     "is missing (required without stiffness)"),
    (LINE.replace("stiffness = 2e5", "stiffness = 2e5\ndamping = 1\nloss_factor = 0.1"),
     "shaft.sections[0].loss_factor", "given with 'damping'"),
    (LINE + '[[shaft.dampers]]\nstation = "nose"\nmodel = "viscous"\ninertia = 0.01\n'
            'damping = 5\n', "shaft.dampers[0].station", "'nose' is no station"),
    (LINE + '[[shaft.dampers]]\nstation = "front"\nmodel = "viscous"\ninertia = 0.01\n'
            'damping = 5\nstiffness = 1e4\n', "shaft.dampers[0].stiffness", "unknown key"),
    (LINE + '[[shaft.dampers]]\nstation = "front"\nmodel = "tuned"\ninertia = 0.01\n',
     "shaft.dampers[0].stiffness", "is missing"),
    (LINE + '[shaft]\nreference = "gearbox"\n', "shaft.reference", "'gearbox' is no station"),
    (LINE + '[shaft]\nload_at = "driven"\n', "shaft.load_at", "'driven' is no station"),
    (LINE + "[shaft.coupling]\nstiffness = 1e4\n", "shaft.coupling.driven_inertia",
     "is missing"),
    (LINE + "[inertia]\nflywheel = 0.1\n", "inertia", "leave [inertia] out or 0"),
    ("[shaft]\n", "shaft.stations", "needs at least 2 stations"),
])
def test_mistakes_are_refused_naming_the_key(text, key, words):
    exc = refused(text)
    assert exc.key == key and words in exc.message, exc.line()
    assert exc.file == "s.toml"


def test_a_crankpins_cylinders_stay_on_one_station():
    """The cross-plane V8 carries cylinders 2t − 1 and 2t on throw t."""
    v8 = _without_inertia((CASES / "v8_cross_plane.toml").read_text(encoding="utf-8"))
    stations = "".join(f'[[shaft.stations]]\nname = "throw {t + 1}"\ncylinders = {pins}\n'
                       for t, pins in enumerate(([1, 2], [3, 4], [5, 6], [7, 8])))
    line = stations + "[[shaft.sections]]\nstiffness = 1e6\n" * 3
    assert scene(line, v8).shaft.stations[3].cylinders == (7, 8)
    exc = refused(line.replace("[3, 4]", "[3]").replace("[5, 6]", "[4, 5, 6]"), v8)
    assert exc.key == "shaft.stations" and "cylinders 3, 4 share a crankpin" in exc.message


def test_a_mechanism_without_a_split_keeps_its_cylinders_on_one_station():
    swash = (CASES / "swash_plate_4cyl.toml").read_text(encoding="utf-8")
    swash = _without_inertia(swash)
    two = """
[[shaft.stations]]
name = "plate"
cylinders = [1, 2]
[[shaft.stations]]
name = "rest"
cylinders = [3, 4]
[[shaft.sections]]
stiffness = 1e5
"""
    exc = refused(two, swash)
    assert exc.key == "shaft.stations" and "put every cylinder on one station" in exc.message
    one = two.replace("cylinders = [1, 2]", "cylinders = [1, 2, 3, 4]").replace(
        "cylinders = [3, 4]", "inertia = 0.1")
    assert scene(one, swash).shaft.stations[0].cylinders == (1, 2, 3, 4)


def _without_inertia(text: str) -> str:
    """A case's text with its [inertia] table taken out."""
    lines, out, skip = text.splitlines(), [], False
    for line in lines:
        if line.startswith("["):
            skip = line.strip() == "[inertia]"
        if not skip:
            out.append(line)
    return "\n".join(out) + "\n"


# -- what the elastic run does not support is refused, never run without it or rigid -------

#: (the key refused, what the scene adds to BASE + LINE): one of each of
#: transient.shaft.line.UNSUPPORTED
PAIR = '\n[[friction.pairs]]\nbetween = ["crank", "rod"]\neta_forward = 0.9\neta_backward = 0.9\n'
UNSUPPORTED = [
    ("friction.pairs", '\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\neta_forward = 0.95\n'
                       'eta_backward = 0.95\n\n[[friction.pairs]]\nbetween = ["crank", "rod"]\n'
                       'model = "reaction"\nmu = 0.01\nradius_mm = 20\n'),
    ("friction.policy", '\n[friction]\npolicy = "paper"\n' + PAIR),
    ("initial.omega", PAIR + "[starter]\ntorque = 50\nnoload_speed_rpm = 300\n"),
    ("load.table", '[shaft]\nload_at = "front"\n[load.table]\nphi_deg = [0, 360, 720]\n'
                   "torque = [1, -1, 1]\n"),
    ("load.inertia", "\n[load]\ninertia = 0.1\ninertia_time = 0.01\n"),
    ("run.mode", None),
    ("solver.method", None),
]


def _unsupported(key: str, extra: str | None) -> str:
    text = BASE + LINE + (extra or "")
    if key == "run.mode":
        return text.replace("revolutions = 2", 'mode = "prescribed-speed"\nspeed_rpm = 600\n'
                                                "t_end = 0.1")
    if key == "solver.method":
        return text.replace("[solver]\n", '[solver]\nmethod = "scipy-Radau"\n')
    if key == "initial.omega":
        return text.replace("omega_rpm = 1000", "omega_rpm = 0")
    return text


@pytest.mark.parametrize("key, extra", UNSUPPORTED, ids=[k for k, _ in UNSUPPORTED])
def test_the_api_refuses_what_the_elastic_run_does_not_support(key, extra, tmp_path):
    elastic = load_scene("s.toml", text=_unsupported(key, extra))
    with pytest.raises(SceneError, match="is not supported with an elastic \\[shaft\\] line") as info:
        simulate(elastic, tmp_path / "r.h5")
    assert info.value.key == key
    assert list(tmp_path.iterdir()) == []  # (refused before any file is made)


def test_tabulated_kinematics_is_refused_with_cylinders_on_several_stations():
    """Its tables hold the mechanism's J(φ) whole: the six's throws on six stations cannot
    share it out."""
    text = (CASES / "inline6_damper.toml").read_text(encoding="utf-8")
    elastic = load_scene("six.toml", text=text + '\n[solver]\nkinematics = "tabulated"\n')
    with pytest.raises(SceneError, match="put every cylinder on one station") as info:
        simulate(elastic)
    assert info.value.key == "solver.kinematics"


def test_the_command_refuses_what_the_elastic_run_does_not_support(tmp_path, capsys):
    path = tmp_path / "elastic.toml"
    path.write_text(_unsupported("load.inertia", dict(UNSUPPORTED)["load.inertia"]), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "load.inertia: is not supported with an elastic [shaft]" in err[0]
    assert not out.exists() or list(out.iterdir()) == []
    assert main(["check", str(path)]) == 0  # (a valid scene: modes work on it)


def test_the_rigid_equivalent_is_a_scene_that_runs_as_the_rigid_model():
    rigid = rigid_equivalent(scene())
    assert rigid.shaft is None and rigid.inertia.total == pytest.approx(0.21, rel=1e-15)
    res = simulate(rigid.replace(run={"revolutions": 0.05}))
    assert res.status == "finished"
