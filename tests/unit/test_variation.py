"""Per-cylinder variation without a run: the misfire draws against a plain-Python SplitMix64,
each cylinder's fuel factor per cycle against a separately written schedule, the model's
breakpoints at the cycle starts, and the scene keys' checks (one-line errors, exit 2)."""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from transient.assemble import build_model
from transient.cli import main
from transient.core.model.variation import FUEL, PRESSURE, SHIFT, START, cycle_fuel, misfire_draw
from transient.errors import SceneError
from transient.reference.twins import misfire_draw as draw
from transient.reference.twins import mix64
from transient.scene import load_scene, scene_from_dict

CASE = Path(__file__).resolve().parents[2] / "cases" / "diesel_4cyl_misfire.toml"


@pytest.fixture(scope="module")
def scene():
    return load_scene(CASE)


def test_splitmix64_first_output_is_the_published_one():
    # The reference implementation's first output for seed 0 (state += golden ratio, then mix):
    # 0xE220A8397B1DCDAF, as printed with Vigna's splitmix64.c.
    assert mix64(0) == 0xE220A8397B1DCDAF


@pytest.mark.parametrize("seed", [0, 1, 12345, 2 ** 63 - 1])
def test_misfire_draw_is_the_python_twin_to_the_bit(seed):
    for k in range(3):
        for n in (1, 2, 10, 99999):
            assert misfire_draw(seed, k, n) == draw(seed, k, n)


def test_misfire_draws_are_uniform():
    u = np.array([misfire_draw(7, 2, n) for n in range(1, 20001)])
    assert u.min() >= 0.0 and u.max() < 1.0
    # mean and the share below 0.1 of 20 000 uniform draws: 5 standard deviations
    assert abs(u.mean() - 0.5) < 5 * math.sqrt(1 / 12 / u.size)
    assert abs(np.mean(u < 0.1) - 0.1) < 5 * math.sqrt(0.09 / u.size)


def schedule(entry: dict, k: int, n: int) -> float:
    """The fuel factor of a [[gas.cylinders]] entry in cycle n, written from the docstring."""
    if entry.get("cut_out"):
        return 0.0
    fuel = entry.get("fuel", 1.0)
    every = entry.get("misfire_every", 0)
    if (every and n % every == 0) or n in entry.get("misfire_cycles", ()):
        return 0.0
    rate = entry.get("misfire_rate", 0.0)
    if rate and draw(entry.get("misfire_seed", 0), k, n) < rate:
        return 0.0
    return fuel


ENTRIES = [{"cylinder": 1, "fuel": 0.8},
           {"cylinder": 2, "misfire_every": 7, "misfire_cycles": [3, 5, 5], "fuel": 0.9},
           {"cylinder": 3, "misfire_rate": 0.25, "misfire_seed": 42},
           {"cylinder": 4, "cut_out": True, "misfire_every": 2}]


@pytest.mark.parametrize("phi0_deg", [0.0, 100.0, -250.0])
def test_fuel_factor_per_cycle_follows_the_schedule(scene, phi0_deg):
    s = scene.replace(gas={"cylinders": ENTRIES}, initial={"phi_deg": phi0_deg})
    model, bp, _ = build_model(s)
    P = model.period
    phi0 = math.radians(phi0_deg)
    for k, entry in enumerate(ENTRIES):
        # cylinder k's cycles begin on its local angle 0 (4-stroke): the gas-exchange TDC
        begin = model.gas_phase[k]
        first = phi0 - ((phi0 - begin) % P)  # start of the cycle in progress at φ0: cycle 1
        assert first <= phi0 < first + P
        for n in range(1, 60):
            mid = first + (n - 1) * P + 0.5 * P
            assert cycle_fuel(model, k, mid) == schedule(entry, k, n), (k, n)
            # the whole cycle, from just after its start to just before its end
            assert cycle_fuel(model, k, first + (n - 1) * P + 1e-6) == schedule(entry, k, n)
            assert cycle_fuel(model, k, first + n * P - 1e-6) == schedule(entry, k, n)
    # a random schedule at rate 0.25 misfires about a quarter of the cycles
    share = np.mean([cycle_fuel(model, 2, model.var_par[2, START] + (n + 0.5) * P) == 0.0
                     for n in range(4000)])
    assert abs(share - 0.25) < 5 * math.sqrt(0.25 * 0.75 / 4000)


def test_cycle_starts_are_breakpoints(scene):
    model, bp, _ = build_model(scene)
    P = model.period
    for k in range(model.ncyl):
        gap = np.abs(bp - model.gas_phase[k] % P)
        assert np.min(np.minimum(gap, P - gap)) < 1e-12 * P


def test_two_stroke_cycles_begin_at_bdc():
    data = tomllib.loads(CASE.read_text(encoding="utf-8"))
    data["mechanism"].update(strokes=2, firing_deg=[0, 180, 270, 90])
    data["gas"] = {"model": "table", "phi_deg": [0, 90, 180, 270, 360],
                   "p_bar": [60, 10, 1, 10, 60], "motored_p_bar": [30, 5, 1, 10, 30],
                   "cylinders": [{"cylinder": 1, "misfire_every": 2}]}
    model, bp, _ = build_model(scene_from_dict(data))
    assert model.period == pytest.approx(2 * math.pi)
    assert np.min(np.abs(bp - math.pi)) < 1e-12  # cylinder 1's BDC: its cycle start
    assert model.var_par[0, START] == pytest.approx(-math.pi)  # cycle 1 in progress at φ0 = 0
    assert cycle_fuel(model, 0, 0.5) == 1.0  # cycle 1
    assert cycle_fuel(model, 0, math.pi + 0.5) == 0.0  # cycle 2


def test_without_entries_the_model_runs_the_plain_path(scene):
    model, _, _ = build_model(scene.replace(gas={"cylinders": []}))
    assert not model.var_on
    assert np.all(model.var_par[:, [FUEL, PRESSURE]] == 1.0)


def test_resolved_scene_reads_back_equal(scene):
    s = scene.replace(gas={"cylinders": ENTRIES})
    assert s.gas.cylinders[3].cut_out and s.gas.cylinders[3].fuel == 0.0
    assert s.gas.cylinders[1].misfire_cycles == (3, 5)
    again = scene_from_dict(tomllib.loads(s.to_toml()))
    assert again == s


BAD = [
    ({"cylinder": 5}, "gas.cylinders[0].cylinder", "must be ≤ mechanism.cylinders = 4"),
    ({"cylinder": 0}, "gas.cylinders[0].cylinder", "must be ≥ 1"),
    ({"cylinder": 1, "fuel": 2.5}, "gas.cylinders[0].fuel", "must be ≤ 2"),
    ({"cylinder": 1, "fuel": -0.1}, "gas.cylinders[0].fuel", "must be ≥ 0"),
    ({"cylinder": 1, "pressure": 3.0}, "gas.cylinders[0].pressure", "must be ≤ 2"),
    ({"cylinder": 1, "misfire_rate": 1.5}, "gas.cylinders[0].misfire_rate", "must be ≤ 1"),
    ({"cylinder": 1, "misfire_cycles": [2, 0]}, "gas.cylinders[0].misfire_cycles",
     "cycle numbers ≥ 1"),
    ({"cylinder": 1, "misfire_every": -1}, "gas.cylinders[0].misfire_every", "must be ≥ 0"),
    ({"cylinder": 1, "cut_out": True, "fuel": 0.5}, "gas.cylinders[0].cut_out",
     "give one of them"),
    ({"cylinder": 1, "fuel_factor": 0.5}, "gas.cylinders[0].fuel_factor", "unknown key"),
]


@pytest.mark.parametrize("entry, key, words", BAD)
def test_bad_entries_are_one_line_errors(scene, entry, key, words):
    with pytest.raises(SceneError) as err:
        scene.replace(gas={"cylinders": [entry]})
    line = str(err.value)
    assert key in line and words in line and "\n" not in line


def test_one_entry_per_cylinder(scene):
    with pytest.raises(SceneError, match=r"gas.cylinders\[1\].cylinder: cylinder 2 has an entry"):
        scene.replace(gas={"cylinders": [{"cylinder": 2}, {"cylinder": 2, "fuel": 0.5}]})


def test_no_gas_no_variation(scene):
    with pytest.raises(SceneError, match=r"gas.cylinders: varies the gas force"):
        scene.replace(gas={"model": "none", "cylinders": [{"cylinder": 1, "fuel": 0.5}]})


def test_cli_check_exits_2_with_file_and_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.read_text(encoding="utf-8").replace("misfire_every = 10",
                                                            "misfire_rate = 2"),
                   encoding="utf-8")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err
    assert "bad.toml" in err and "gas.cylinders[1].misfire_rate" in err and "≤ 1" in err


def test_combustion_offset_corners_are_breakpoints(scene):
    base_model, base_bp, table = build_model(scene.replace(gas={"cylinders": []}))
    s = scene.replace(gas={"cylinders": [{"cylinder": 2, "combustion_offset_deg": 3.0}]})
    model, bp, _ = build_model(s)
    assert model.var_shifted and model.var_par[1, SHIFT] == pytest.approx(math.radians(3.0))
    P = model.period
    moved = np.mod(model.gas_phase[1] + math.radians(3.0) + table.corners[:-1], P)
    gap = np.abs(np.subtract.outer(moved, bp))
    assert np.all(np.min(np.minimum(gap, P - gap), axis=1) < 1e-12 * P)
    assert set(np.round(base_bp, 12)) <= set(np.round(bp, 12))


def test_combustion_offset_range(scene):
    with pytest.raises(SceneError,
                       match=r"gas.cylinders\[0\].combustion_offset_deg: must be ≤ 30"):
        scene.replace(gas={"cylinders": [{"cylinder": 1, "combustion_offset_deg": 31}]})


def test_woschni_offset_must_keep_the_combustion_in_the_closed_part():
    # combustion 358° to 408° (local), exhaust opening moved to 420°: 12° of room after it
    woschni = load_scene(CASE.parent / "gots_diesel_woschni.toml").replace(
        gas={"wiebe": {"exhaust_opening_deg": 420}})
    woschni.replace(gas={"cylinders": [{"cylinder": 1, "combustion_offset_deg": 11.9}]})
    with pytest.raises(SceneError, match=r"gas.cylinders\[0\].combustion_offset: 12.1° moves the "
                                         r"combustion out of the closed part .* allowed -178° to "
                                         r"12°$"):
        woschni.replace(gas={"cylinders": [{"cylinder": 1, "combustion_offset_deg": 12.1}]})


# ------------------------------------------------------------------------------------------------
# A pressure table burns less than full-load fuel only with its motored curve


def table_data(motored: bool = False, cylinders=(), governor: bool = False) -> dict:
    """The misfire case on a 4-stroke pressure table (and its motored curve)."""
    data = tomllib.loads(CASE.read_text(encoding="utf-8"))
    data["gas"] = {"model": "table", "phi_deg": [0, 180, 360, 540, 720],
                   "p_bar": [1.6, 1.4, 90, 5, 1.6], "cylinders": list(cylinders)}
    if motored:
        data["gas"]["motored_p_bar"] = [1.6, 1.4, 70, 1.4, 1.6]
    if governor:
        data["governor"] = {"model": "droop", "speed_full_rpm": 4000, "speed_zero_rpm": 4600}
    return data


@pytest.mark.parametrize("entry, key", [
    ({"fuel": 0.8}, "fuel"), ({"cut_out": True}, "cut_out"),
    ({"misfire_every": 3}, "misfire_every"), ({"misfire_cycles": [2]}, "misfire_cycles"),
    ({"misfire_rate": 0.1}, "misfire_rate"),
    ({"combustion_offset_deg": 2}, "combustion_offset")])
def test_table_without_motored_curve_refuses_what_burns_less(entry, key):
    with pytest.raises(SceneError) as err:
        scene_from_dict(table_data(cylinders=[{"cylinder": 2, **entry}]))
    line = str(err.value)
    assert f"gas.cylinders[0].{key}:" in line and "gas.motored_p" in line and "\n" not in line
    scene = scene_from_dict(table_data(motored=True, cylinders=[{"cylinder": 2, **entry}]))
    assert build_model(scene)[0].has_motored


def test_table_without_motored_curve_takes_a_pressure_factor():
    scene = scene_from_dict(table_data(cylinders=[{"cylinder": 2, "pressure": 0.9}]))
    model = build_model(scene)[0]
    assert model.var_on and not model.has_motored  # full fuel: the one-table path


def test_table_without_motored_curve_refuses_a_governor():
    with pytest.raises(SceneError, match=r"^governor.model: the governor's fuel command: a fuel "
                                         r"below 1 scales the combustion only"):
        scene_from_dict(table_data(governor=True))
    scene = scene_from_dict(table_data(motored=True, governor=True))
    model = build_model(scene)[0]
    assert model.has_motored
    # the motored curve on the table's knots: columns 4–7, its value at the firing TDC 70 bar
    assert model.coef[np.searchsorted(model.knots, 2 * math.pi), 4] == pytest.approx(70e5)


def test_motored_points_are_checked_under_their_key():
    data = table_data(motored=True)
    data["gas"]["motored_p_bar"] = [1.6, 1.4, 70, 1.4]
    with pytest.raises(SceneError, match=r"^gas.motored_p_bar: has 4 values but gas.phi_deg "
                                         r"has 5"):
        scene_from_dict(data)
    data["gas"]["motored_p_bar"] = [1.6, 1.4, -70, 1.4, 1.6]
    with pytest.raises(SceneError, match=r"^gas.motored_p_bar: pressure -7e\+06 Pa at 360°"):
        scene_from_dict(data)


def test_motored_column_of_a_table_file(tmp_path):
    (tmp_path / "diagram.csv").write_text("phi_deg,p_bar,motored_p_bar\n0,1.6,1.6\n180,1.4,1.4\n"
                                          "360,90,70\n540,5,1.4\n720,1.6,1.6\n", encoding="utf-8")
    data = table_data(cylinders=[{"cylinder": 3, "misfire_every": 2}])
    data["gas"] = {"model": "table", "file": "diagram.csv", "cylinders": data["gas"]["cylinders"]}
    scene = scene_from_dict(data, file=str(tmp_path / "s.toml"), base_dir=tmp_path)
    inline = scene_from_dict(table_data(motored=True,
                                        cylinders=[{"cylinder": 3, "misfire_every": 2}]))
    assert scene.gas.motored_p == pytest.approx(inline.gas.motored_p, rel=1e-15)
    assert scene_from_dict(tomllib.loads(inline.to_toml())) == inline  # written back


def test_part_load_study_on_a_table_without_motored_curve(tmp_path, capsys):
    from transient.run import prescribed

    scene = scene_from_dict(table_data())
    with pytest.raises(SceneError, match=r"^fuel: 0.5: a fuel below 1"):
        prescribed(scene.replace(run={"mode": "prescribed-speed", "speed_rpm": 2000,
                                      "revolutions": 2}), 0.5)
    path = tmp_path / "table.toml"
    path.write_text(scene.to_toml(), encoding="utf-8")
    assert main(["efficiency", str(path), "--rpm", "2000", "--fuel", "1,0.5", "-o",
                 str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--fuel: a fuel below 1" in err and "\n" not in err and "table.toml" in err


def test_force_table_refuses_what_burns_less():
    data = table_data(governor=True)
    data["gas"] = {"model": "table", "phi_deg": [0, 180, 360, 540, 720],
                   "force_kN": [0, 0, 30, 5, 0]}
    with pytest.raises(SceneError, match=r"^governor.model: .* a force table holds no account of "
                                         r"which part of it is compression"):
        scene_from_dict(data)
    del data["governor"]
    data["gas"]["cylinders"] = [{"cylinder": 1, "misfire_every": 2}]
    with pytest.raises(SceneError, match=r"^gas.cylinders\[0\].misfire_every: "):
        scene_from_dict(data)
    data["gas"]["motored_p_bar"] = [1, 1, 60, 1, 1]
    with pytest.raises(SceneError, match=r"^gas.motored_p_bar: gives motored pressures with "
                                         r"forces on the piston"):
        scene_from_dict(data)
