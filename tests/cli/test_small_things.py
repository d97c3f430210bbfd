"""Small things a user meets, each as a user meets it: a sweep file given to ``transient check``
(and to ``run``), a two-stroke scene with gas-exchange pressures, the (30) line of a frictionless
engine, the provenance a result keeps (versions, the scene file's own text), a sweep from a script
without the ``__main__`` guard. Runs are small and in-process, as in ``test_cli.py``; the sweep
scripts run in subprocesses, as a user runs them."""
from __future__ import annotations

import subprocess
import sys
import textwrap
from importlib import metadata
from pathlib import Path

import pytest
from scene_texts import MIXED_CYCLE, SMALL

import transient
from transient.cli import main
from transient.errors import SceneError
from transient.results import RECORDED_PACKAGES, open_result
from transient.scene import load_scene, scene_from_dict

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ------------------------------------------------------------------------------------------------
# A sweep file where a scene is expected


@pytest.mark.parametrize("name", ["gots_pi_gains", "gots_eta_speed_load",
                                  "swash_angle_fluctuation"])
def test_check_takes_a_sweep_file_as_a_sweep(capsys, name):
    from transient.sweeps import load_sweep

    path = CASES / "sweeps" / f"{name}.toml"
    sweep = load_sweep(path)  # (what the line must say, read independently)
    code, out, err = cli(capsys, "check", path)
    assert (code, err) == (0, "")
    assert out.startswith(f"{path}: ok (sweep {sweep.name}: {len(sweep.runs)} run(s), method "
                          f"{sweep.method}, axes ")
    for axis in sweep.axes:
        assert f"{axis.key} ({len(axis.values)} values)" in out
    assert out.endswith(f"run it with `transient sweep {path}`\n")


def test_check_of_a_broken_sweep_file_names_the_sweep_key(tmp_path, capsys):
    (tmp_path / "base.toml").write_text(SMALL, encoding="utf-8")
    bad = tmp_path / "bad.toml"
    bad.write_text('[sweep]\nbase = "base.toml"\nmethod = "spiral"\n\n[[axis]]\n'
                   'key = "load.torque"\nvalues = [1.0]\n', encoding="utf-8")
    code, out, err = cli(capsys, "check", bad)
    assert (code, out) == (2, "")
    assert err == f"{bad}: sweep.method: unknown value 'spiral'; allowed: grid, list, random\n"


@pytest.mark.parametrize("command", ["run", "kinematics", "efficiency", "loads"])
def test_other_commands_say_a_sweep_file_is_one(tmp_path, capsys, command):
    path = CASES / "sweeps" / "gots_pi_gains.toml"
    argv = [command, path] + (["-o", tmp_path] if command in ("run", "efficiency") else [])
    code, out, err = cli(capsys, *argv)
    if command == "loads":  # (takes a result file: a TOML file is not one)
        assert code == 2 and err.count("\n") == 1
        return
    assert (code, out) == (2, "")
    assert err == (f"{path}: [sweep]: this is a sweep file, not a scene: run it with `transient "
                   f"sweep`, check it with `transient check`\n")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------------
# A two-stroke's gas-exchange pressures

TWO_STROKE = SMALL.replace("crank_mass = 0.912", "crank_mass = 0.912\nstrokes = 2")


@pytest.mark.parametrize("key", ["p_intake_MPa = 0.165", "p_exhaust_MPa = 0.182",
                                 "p_intake = 165000.0"])
def test_a_two_stroke_mixed_cycle_refuses_gas_exchange_pressures(tmp_path, key):
    gas = MIXED_CYCLE.format(cr=18).replace("p_intake_MPa = 0.165\n", "").replace(
        "p_exhaust_MPa = 0.182\n", "") + key + "\n"
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "two.toml", text=TWO_STROKE + gas)
    assert info.value.key == f"gas.{key.split(' = ')[0]}"
    assert info.value.message == ("a two-stroke cycle (mechanism.strokes = 2) has no intake or "
                                  "exhaust stroke: it is scavenged to p_a at bottom dead centre; "
                                  "leave p_intake and p_exhaust out (they are for strokes = 4)")


def test_a_two_stroke_mixed_cycle_without_them_round_trips(tmp_path):
    """Without them the scene loads, its resolved TOML leaves them out and reads back equal;
    the 4-stroke still requires them."""
    gas = MIXED_CYCLE.format(cr=18).replace("p_intake_MPa = 0.165\n", "").replace(
        "p_exhaust_MPa = 0.182\n", "")
    scene = load_scene(tmp_path / "two.toml", text=TWO_STROKE + gas)
    assert scene.mechanism.strokes == 2 and scene.gas.p_intake == scene.gas.p_exhaust == 0.0
    toml = scene.to_toml()
    assert "p_intake" not in toml and "p_exhaust" not in toml
    assert load_scene(tmp_path / "again.toml", text=toml) == scene
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "four.toml", text=SMALL + gas)
    assert info.value.key == "gas.p_intake"


def test_a_two_stroke_wiebe_refuses_them_too(tmp_path):
    text = (CASES / "gots_diesel_wiebe.toml").read_text(encoding="utf-8")
    text = text.replace("strokes = 4", "strokes = 2").replace(
        "firing_deg = [360, 600, 120]", "firing_deg = [0, 120, 240]")
    assert "p_exhaust_MPa" in text
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path / "two.toml", text=text)
    assert info.value.key == "gas.p_intake_MPa"


# ------------------------------------------------------------------------------------------------
# The (30) line


def test_the_30_line_is_left_out_for_a_frictionless_engine(tmp_path, capsys):
    """The Gots engine at a prescribed 4400 rpm, no pairs: η_mech = W_out/W_in is 1 to the
    energy balance (nothing loses power), while the time average of P_out/P_in stored as (30)
    is not — it measures the power the inertia circulates — so the summary does not print it;
    with pairs it does (``test_cli.test_prescribed_run_with_pairs_reports_the_efficiency``)."""
    text = (CASES / "gots_diesel_4400.toml").read_text(encoding="utf-8").replace(
        "revolutions = 4\n", "revolutions = 2\n").replace("samples_per_rev = 1440\n",
                                                          "samples_per_rev = 72\n")
    scene = tmp_path / "frictionless.toml"
    scene.write_text(text, encoding="utf-8")
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert (code, err) == (0, "")
    res = open_result(tmp_path / "frictionless.h5")
    eta, printed = res.analysis["eta_mech_work"][0], res.analysis["eta_mech_printed"][0]
    assert abs(eta - 1.0) <= 1e-9  # (the prescribed path's balance: a quadrature of samples)
    assert abs(printed - 1.0) > 1e-3  # (what the line would have shown under η = 1)
    assert "mechanical efficiency over 1 steady cycle(s): η = W_out/W_in = 1.000000" in out
    assert "(30) as printed" not in out
    code, out, err = cli(capsys, "info", tmp_path / "frictionless.h5")
    assert "(30) as printed" not in out


# ------------------------------------------------------------------------------------------------
# Provenance


def test_a_result_keeps_the_versions_and_the_scene_files_text(tmp_path, capsys):
    text = "# where the numbers come from: the test's own scene\n" + SMALL
    scene = tmp_path / "sourced.toml"
    scene.write_text(text, encoding="utf-8")
    assert cli(capsys, "run", scene, "-o", tmp_path, "-q")[0] == 0
    res = open_result(tmp_path / "sourced.h5")
    assert res.scene_source == (str(scene), text)
    for name in RECORDED_PACKAGES:  # (against the installed metadata, read here)
        assert res.attrs[name] == metadata.version(name), name
    code, out, err = cli(capsys, "info", tmp_path / "sourced.h5")
    assert (code, err) == (0, "")
    lines = out.splitlines()
    versions = next(line for line in lines if line.startswith("  versions: "))
    for name in ("numpy", "numba", *RECORDED_PACKAGES):
        assert f"{name} {res.attrs[name]}" in versions
    assert (f"  scene file: {scene} ({len(text.splitlines())} lines, comments included, stored "
            f"in /scene/source: `transient info --source` prints them)") in lines
    assert any(line.startswith(f"  made by `{res.attrs['command']}` on {res.attrs['cpu']}")
               for line in lines)
    code, out, err = cli(capsys, "info", tmp_path / "sourced.h5", "--source")
    assert (code, out, err) == (0, text, "")
    assert res.scene().source_text == text  # (the rebuilt scene keeps where it came from)


def test_a_scene_from_code_stores_no_source(tmp_path, capsys):
    import tomllib

    scene = scene_from_dict(tomllib.loads(SMALL))
    assert scene.source_text == ""
    transient.simulate(scene, tmp_path / "coded.h5")
    assert open_result(tmp_path / "coded.h5").scene_source == ("", "")
    code, out, err = cli(capsys, "info", tmp_path / "coded.h5", "--source")
    assert (code, out) == (2, "")
    assert err.startswith(f"{tmp_path / 'coded.h5'}: --source: the result stores no scene file")


def test_the_source_is_not_part_of_what_a_scene_is(tmp_path):
    a = load_scene(tmp_path / "a.toml", text=SMALL)
    b = load_scene(tmp_path / "b.toml", text="# another comment\n" + SMALL)
    assert a == b and a.source_text != b.source_text


def test_a_missing_package_is_recorded_as_such():
    from transient.results import _installed_version

    assert _installed_version("no-such-package-transient-test") == "not installed"


# ------------------------------------------------------------------------------------------------
# A sweep from a script

SWEEP_SCRIPT = """\
import transient

base = transient.load_scene({scene!r})
{call}
"""
CALL = ('done = transient.sweep(base, {{"load.torque": [0.0, 1.0]}}, output={out!r}, '
        'workers=1)')


def run_script(tmp_path, body: str) -> subprocess.CompletedProcess:
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL, encoding="utf-8")
    script = tmp_path / "study.py"
    script.write_text(SWEEP_SCRIPT.format(scene=str(scene), call=body), encoding="utf-8")
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300)


def test_a_sweep_script_without_the_guard_fails_in_one_line(tmp_path):
    """The guide's sweep from code as a plain script: no worker is started (no Dask frame in
    the traceback, no sweep file), and the last line says what to add, naming the line."""
    proc = run_script(tmp_path, CALL.format(out=str(tmp_path / "res")))
    assert proc.returncode == 1
    last = proc.stderr.strip().splitlines()[-1]
    assert last == (f"transient.sweeps.execute.UnguardedMain: a sweep on a local Dask cluster "
                    f"starts its workers by running the main script again, so the script must "
                    f"start it under `if __name__ == \"__main__\":` ({tmp_path / 'study.py'}, "
                    f"line 4); or give scheduler=\"serial\" or a client")
    assert "distributed" not in proc.stderr and "nanny" not in proc.stderr.lower()
    assert not (tmp_path / "res" / "small.sweep.h5").exists()


@pytest.mark.parametrize("body, guarded", [
    ('if __name__ == "__main__":\n    check()', True),
    ('if "__main__" == __name__:\n    def go():\n        check()\n    go()', True),
    ("check()", False),
    ("def go():\n    check()\ngo()", False),
    ('if __name__ != "__main__":\n    pass\nelse:\n    check()', False),
])
def test_the_guard_is_read_from_the_statement_that_runs_the_call(tmp_path, body, guarded):
    """The check alone (no cluster): guarded where the main module's top-level statement that
    is running is ``if __name__ == "__main__":``. (An ``else`` of another test is refused: the
    check reads the statement, not what it evaluates to.)"""
    text = "from transient.sweeps.execute import check_main_guarded as check\n" + body + "\n"
    script = tmp_path / "probe.py"
    script.write_text(text, encoding="utf-8")
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=120)
    assert (proc.returncode == 0) == guarded, proc.stderr
    if not guarded:
        assert "UnguardedMain" in proc.stderr.splitlines()[-1]


def test_a_sweep_script_with_scheduler_serial_needs_no_guard(tmp_path):
    body = textwrap.dedent(f"""\
        done = transient.sweep(base, {{"load.torque": [0.0, 1.0]}}, output={str(tmp_path)!r},
                               scheduler="serial")
        print(*done.table.columns["status"])""")
    proc = run_script(tmp_path, body)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["finished", "finished"]
