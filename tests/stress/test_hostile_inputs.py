"""Hostile inputs: scenes, tables, sweep files and command-line options as a careless or hostile
user gives them. Each case states the exact line the user gets on standard error, and every one
ends with exit 2, nothing on standard output and nothing written, before any work (no kernel
runs here: validation comes first).

Grouped by where the input comes from: the scene (TOML), the pressure table (CSV), the sweep file
and the options. Cases of ``test_malformed_scenes.py`` and ``tests/unit/test_scene_errors.py``
are not repeated. Expected lines hold ``{scene}``, ``{dir}``, … for the paths of the case.
"""
from __future__ import annotations

import os

import pytest
from scene_texts import MIXED_CYCLE, SMALL

from transient.cli import main
from transient.scene.files import MAX_INPUT_BYTES

TOO_LARGE = object()  # (a case's content: a sparse file one byte over the limit)


def insert(anchor: str, lines: str, base: str = SMALL) -> str:
    """``base`` with ``lines`` after the line ``anchor`` (there once)."""
    assert base.count("\n" + anchor + "\n") == 1, anchor
    return base.replace("\n" + anchor + "\n", f"\n{anchor}\n{lines}\n")


def write(path, content) -> None:
    if content is TOO_LARGE:
        with open(path, "wb") as fh:
            fh.truncate(MAX_INPUT_BYTES + 1)
    elif isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")


def one_line(capsys, argv) -> str:
    """The error line of ``transient argv``: exit 2, nothing on standard output, one line."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert (code, out) == (2, ""), (code, out, err)
    assert err.count("\n") == 1 and err.endswith("\n") and "Traceback" not in err, err
    return err[:-1]


LONG = "x" * 100_000
TOO_DEEP = "[" * 100_000 + "]" * 100_000

# ------------------------------------------------------------------------------------------------
# The scene (TOML): (id, file content, the line after "{scene}: ")

SCENE_CASES = [
    ("nul-in-a-string", SMALL.replace('name = "small"', 'name = "sm\0all"'),
     "(file): holds a NUL byte (line 2, column 11); a scene file is text: save the scene as "
     "UTF-8"),
    ("nul-first", "\0" + SMALL,
     "(file): holds a NUL byte (line 1, column 1); a scene file is text: save the scene as UTF-8"),
    ("nul-in-a-comment", SMALL + "# the end\0\n",
     "(file): holds a NUL byte (line 32, column 10); a scene file is text: save the scene as "
     "UTF-8"),
    ("too-large", TOO_LARGE,
     f"(file): is larger than {MAX_INPUT_BYTES} bytes (16 MiB), the limit for a scene file"),
    ("binary-png", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR",
     "(file): not UTF-8 text (byte 0); save the scene as UTF-8"),
    ("utf-16", SMALL.encode("utf-16"), "(file): not UTF-8 text (byte 0); save the scene as UTF-8"),
    ("nested-arrays", "a = " + TOO_DEEP + "\n",
     "(syntax): arrays or tables nested too deeply to read"),
    ("nested-inline-tables", "a = " + "{b = " * 100_000 + "1" + "}" * 100_000 + "\n",
     "(syntax): arrays or tables nested too deeply to read"),
    ("long-key", insert("shaft = 0.02", LONG + " = 1"),
     "inertia." + "x" * 149 + "...: unknown key; allowed here: flywheel, load, shaft"),
    ("long-table-name", SMALL + f"\n[{LONG}]\n",
     "x" * 157 + "...: unknown key; allowed here: analysis, friction, gas, governor, inertia, "
     "initial, load, mechanism, output, run, scene, shaft, solver, starter"),
    ("newline-in-a-key", insert("shaft = 0.02", '"a\\nb" = 1'),
     "inertia.a\\nb: unknown key; allowed here: flywheel, load, shaft"),
    ("escape-in-a-key", insert("shaft = 0.02", '"\\u001b[2J" = 1'),
     "inertia.\\x1b[2J: unknown key; allowed here: flywheel, load, shaft"),
    ("long-choice", SMALL.replace('model = "two-mass"', f'model = "{LONG}"'),
     "mechanism.rod.model: unknown value '" + "x" * 36 + "...; allowed: 'two-mass', 'rigid'"),
    ("control-in-a-choice", SMALL.replace('model = "two-mass"', 'model = "two-mass\\u0007"'),
     "mechanism.rod.model: unknown value 'two-mass\\x07'; allowed: 'two-mass', 'rigid'"),
    ("newline-in-a-choice", SMALL.replace('model = "two-mass"', 'model = "two-\\nmass"'),
     "mechanism.rod.model: unknown value 'two-\\nmass'; allowed: 'two-mass', 'rigid'"),
    ("long-string-for-a-number", SMALL.replace("bore_mm = 88", f'bore_mm = "{LONG}"'),
     "mechanism.bore_mm: must be a number, got '" + "x" * 36 + "..."),
    ("long-list-for-a-number", SMALL.replace("bore_mm = 88", "bore_mm = [" + "1, " * 10_000 + "]"),
     "mechanism.bore_mm: must be a number, got [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, ..."),
    ("integer-beyond-a-float", SMALL.replace("bore_mm = 88", "bore_mm = 1" + "0" * 400),
     "mechanism.bore_mm: must be finite, got 1" + "0" * 36 + "... (beyond a float's range)"),
    ("float-beyond-a-float", SMALL.replace("bore_mm = 88", "bore_mm = 1e400"),
     "mechanism.bore_mm: must be finite, got inf"),
    ("negative-integer-beyond-a-float", insert("shaft = 0.02", "flywheel = -1" + "0" * 400),
     "inertia.flywheel: must be finite, got -1" + "0" * 35 + "... (beyond a float's range)"),
    ("list-with-a-huge-integer", SMALL + '\n[gas]\nmodel = "table"\nphi_deg = [0, 1' + "0" * 400
     + "]\np_bar = [1, 1]\n",
     "gas.phi_deg: must be a list of finite numbers, got [0, 1" + "0" * 32 + "..."),
    ("whole-number-beyond-any", insert("crank_mass = 0.912", "cylinders = 1" + "0" * 400),
     "mechanism.cylinders: must be ≤ 64, got 1" + "0" * 36 + "..."),
    ("huge-samples", SMALL.replace("samples_per_rev = 12", "samples_per_rev = -1" + "0" * 30),
     "output.samples_per_rev: must be ≥ 4, got -1" + "0" * 30),
    ("pressure-table-name-long", SMALL + f'\n[gas]\nmodel = "table"\nfile = "{LONG}.csv"\n',
     "gas.file: no such file '" + "x" * 36 + "...; give a CSV path relative to the scene"),
    ("pressure-table-name-with-nul", SMALL + '\n[gas]\nmodel = "table"\nfile = "p\\u0000.csv"\n',
     "gas.file: no such file 'p\\x00.csv'; give a CSV path relative to the scene"),
    ("pressure-table-is-the-folder", SMALL + '\n[gas]\nmodel = "table"\nfile = ""\n',
     "gas.file: {dirname}: is a folder, not a CSV file; give a CSV file"),
    ("long-pair-link", SMALL + f'\n[[friction.pairs]]\nbetween = ["shaft", "{LONG}"]\n'
                               "eta_forward = 0.9\neta_backward = 0.9\n",
     "friction.pairs[0].between: unknown link '" + "x" * 36 + "...; the links are shaft – crank – "
     "rod – piston – cylinder"),
    ("long-pair-name", SMALL + f'\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\n'
                               f'name = "{LONG}"\neta_forward = 0.9\neta_backward = 0.9\n'
                               f'\n[[friction.pairs]]\nbetween = ["crank", "rod"]\n'
                               f'name = "{LONG}"\neta_forward = 0.9\neta_backward = 0.9\n',
     "friction.pairs[1].name: '" + "x" * 36 + "... names friction.pairs[0] too; give each pair "
     "its own name (it labels the pair's result columns and reports)"),
    ("long-order-signal", SMALL + f'\n[analysis]\norders = ["{LONG}"]\n',
     "analysis.orders: unknown signal '" + "x" * 36 + "...; allowed: t, phi, omega, epsilon, J, dJ_dphi, "
     "M_gas, M_load, M_starter, "
     "fuel, W_gas, W_load, W_starter, p_1, W_1"),
]


@pytest.mark.parametrize("content, message", [pytest.param(c, m, id=i) for i, c, m in SCENE_CASES])
def test_a_hostile_scene_gives_its_exact_line(tmp_path, capsys, content, message):
    scene = tmp_path / "bad.toml"
    write(scene, content)
    line = one_line(capsys, ["check", scene])
    assert line == f"{scene}: " + message.format(dirname=tmp_path.name)


@pytest.mark.parametrize("content, message", [pytest.param(c, m, id=i) for i, c, m in SCENE_CASES
                                              if i in ("nul-first", "too-large", "long-key")])
def test_run_refuses_them_before_any_work(tmp_path, capsys, content, message):
    scene = tmp_path / "bad.toml"
    write(scene, content)
    out = tmp_path / "out"
    assert one_line(capsys, ["run", scene, "-o", out]) == f"{scene}: {message}"
    assert not out.exists()


# ------------------------------------------------------------------------------------------------
# The pressure table (CSV) of a scene: (id, file content, the line after "{scene}: gas.file: p.csv: ")

FIELD_LIMIT = ("; a table's fields are numbers and column names (at most 200 characters)")

TABLE_CASES = [
    ("nul-in-a-number", b"phi_deg,p_bar\n0,1\0\n720,1\n",
     "holds a NUL byte (line 2, column 4); a CSV file is text: save the table as UTF-8 CSV"),
    ("nul-in-the-header", b"phi_deg\0,p_bar\n0,1\n720,1\n",
     "holds a NUL byte (line 1, column 8); a CSV file is text: save the table as UTF-8 CSV"),
    ("nul-in-a-comment", b"# measured\0\nphi_deg,p_bar\n0,1\n720,1\n",
     "holds a NUL byte (line 1, column 11); a CSV file is text: save the table as UTF-8 CSV"),
    ("too-large", TOO_LARGE,
     f"is larger than {MAX_INPUT_BYTES} bytes (16 MiB), the limit for a CSV file"),
    ("utf-16", "phi_deg,p_bar\n0,1\n720,1\n".encode("utf-16"),
     "not UTF-8 text (byte 0); save the table as UTF-8 CSV"),
    ("binary", bytes(range(128, 256)), "not UTF-8 text (byte 0); save the table as UTF-8 CSV"),
    ("long-field", "phi_deg,p_bar\n0," + "1" * 200_000 + "\n720,1\n",
     "line 2 holds a field of 200000 characters" + FIELD_LIMIT),
    ("field-past-the-csv-limit", "phi_deg,p_bar\n0,1\n" + "9" * 131_073 + ",1\n",
     "line 3 holds a field of 131073 characters" + FIELD_LIMIT),
    ("field-one-past-the-limit", "phi_deg,p_bar\n0," + "0" * 201 + "\n720,1\n",
     "line 2 holds a field of 201 characters" + FIELD_LIMIT),
    ("long-header", "phi_deg," + "p" * 1000 + "\n0,1\n720,1\n",
     "line 1 holds a field of 1000 characters" + FIELD_LIMIT),
    ("long-comment-is-fine-but-not-the-field", "# " + "c" * 100_000 + "\nphi_deg,p_bar\n"
                                                 "0,1," + "z" * 300 + "\n720,1\n",
     "line 3 holds a field of 300 characters" + FIELD_LIMIT),
    ("nan", "phi_deg,p_bar\n0,nan\n720,1\n",
     "line 2, column p_bar: 'nan' is not finite; give finite numbers"),
    ("inf-angle", "phi_deg,p_bar\n0,1\ninf,1\n",
     "line 3, column phi_deg: 'inf' is not finite; give finite numbers"),
    ("overflow", "phi_deg,p_bar\n0,1e999\n720,1\n",
     "line 2, column p_bar: '1e999' is not finite; give finite numbers"),
    ("minus-infinity", "phi_deg,p_MPa\n0,1\n720,-Infinity\n",
     "line 3, column p_MPa: '-Infinity' is not finite; give finite numbers"),
    ("empty-field", "phi_deg,p_bar\n0,\n720,1\n", "line 2, column p_bar: '' is not a number"),
    ("long-text-field", "phi_deg,p_bar\n0," + "ab" * 90 + "\n720,1\n",
     "line 2, column p_bar: '" + "ab" * 18 + "... is not a number"),
    ("text-with-a-quote", "phi_deg,p_bar\n0,\"1 bar\"\n720,1\n",
     "line 2, column p_bar: '1 bar' is not a number"),
    ("decimal-comma", "phi_deg,p_bar\n0,\"1,5\"\n720,1\n",
     "line 2, column p_bar: '1,5' is not a number"),
    ("hex", "phi_deg,p_bar\n0,0x10\n720,1\n", "line 2, column p_bar: '0x10' is not a number"),
    ("short-row", "phi_deg,p_bar\n0,1\n720\n",
     "line 3 has 1 field(s); column p_bar is field 2"),
    ("semicolons", "phi_deg;p_bar\n0;1\n720;1\n",
     "needs an angle column (phi_deg, phi) and a pressure or force column (p, p_bar, p_MPa, p_Pa, "
     "force, force_N, force_kN); header "
     "is ['phi_deg;p_bar']"),
    ("many-unknown-columns", ",".join(f"c{i}" for i in range(60)) + "\n",
     "needs an angle column (phi_deg, phi) and a pressure or force column (p, p_bar, p_MPa, p_Pa, "
     "force, force_N, force_kN); header "
     "is ['c0', 'c1', 'c2', 'c3', 'c4', 'c5', ..."),
    ("pressure-unit-unknown", "phi_deg,p_psi\n0,1\n720,1\n",
     "needs an angle column (phi_deg, phi) and a pressure or force column (p, p_bar, p_MPa, p_Pa, "
     "force, force_N, force_kN); header "
     "is ['phi_deg', 'p_psi']"),
    ("comments-only", "# nothing measured yet\n\n",
     "needs an angle column (phi_deg, phi) and a pressure or force column (p, p_bar, p_MPa, p_Pa, "
     "force, force_N, force_kN); header "
     "is []"),
]


@pytest.mark.parametrize("content, message", [pytest.param(c, m, id=i) for i, c, m in TABLE_CASES])
def test_a_hostile_pressure_table_gives_its_exact_line(tmp_path, capsys, content, message):
    scene = tmp_path / "s.toml"
    scene.write_text(SMALL + '\n[gas]\nmodel = "table"\nfile = "p.csv"\n', encoding="utf-8")
    write(tmp_path / "p.csv", content)
    assert one_line(capsys, ["check", scene]) == f"{scene}: gas.file: p.csv: {message}"


@pytest.mark.parametrize("kind", ["a folder", "a FIFO"])
def test_a_pressure_table_that_is_no_file(tmp_path, capsys, kind):
    scene = tmp_path / "s.toml"
    scene.write_text(SMALL + '\n[gas]\nmodel = "table"\nfile = "p.csv"\n', encoding="utf-8")
    (tmp_path / "p.csv").mkdir() if kind == "a folder" else os.mkfifo(tmp_path / "p.csv")
    assert one_line(capsys, ["check", scene]) == (f"{scene}: gas.file: p.csv: is {kind}, not a "
                                                  f"CSV file; give a CSV file")


# ------------------------------------------------------------------------------------------------
# The sweep file: (id, file content, the line after "{sweep}: "). The base scene is SMALL, in
# base.toml beside it.

BASE = '[sweep]\nbase = "base.toml"\n'
AXIS = '\n[[axis]]\nkey = "load.torque"\nvalues = [1.0, 2.0]\n'
SWEEP = BASE + AXIS

SWEEP_CASES = [
    ("nul", SWEEP.replace("base.toml", "base\0.toml"),
     "(file): holds a NUL byte (line 2, column 13); a sweep file is text: save the sweep as UTF-8"),
    ("too-large", TOO_LARGE,
     f"(file): is larger than {MAX_INPUT_BYTES} bytes (16 MiB), the limit for a sweep file"),
    ("latin-1", ("# Lastschritte für\n" + SWEEP).encode("latin-1"),
     "(file): not UTF-8 text (byte 16); save the sweep as UTF-8"),
    ("nested-too-deeply", SWEEP + "x = " + TOO_DEEP + "\n",
     "(syntax): arrays or tables nested too deeply to read"),
    ("syntax", SWEEP + "[[axis]\n", "(syntax): not valid TOML: Expected ']]' at the end of an "
                                    "array declaration (at line 7, column 7)"),
    ("long-duplicate-table", SWEEP + f"[{LONG}]\n[{LONG}]\n",
     "(syntax): not valid TOML: Cannot declare ('" + "x" * 60 + "... (at line 8, column "
     "100002)"),
    ("sweep-not-a-table", "sweep = 5\n" + AXIS, "sweep: must be a table, got 5"),
    ("base-missing", SWEEP.replace("base.toml", "nope.toml"),
     "sweep.base: the base scene 'nope.toml': cannot read: No such file or directory"),
    ("base-is-a-folder", SWEEP.replace("base.toml", "."),
     "sweep.base: the base scene '.': is a folder, not a scene file; give a TOML file"),
    ("base-with-a-nul", SWEEP.replace("base.toml", "nul.toml"),
     "sweep.base: the base scene 'nul.toml': holds a NUL byte (line 1, column 1); a scene file "
     "is text: save the scene as UTF-8"),
    ("base-nested-too-deeply", SWEEP.replace("base.toml", "deep.toml"),
     "sweep.base: the base scene 'deep.toml': arrays or tables nested too deeply to read"),
    ("base-name-long", SWEEP.replace("base.toml", LONG),
     "sweep.base: the base scene '" + "x" * 36 + "...: cannot read: File name too long"),
    ("long-method", SWEEP.replace("[sweep]\n", f'[sweep]\nmethod = "{LONG}"\n'),
     "sweep.method: unknown value '" + "x" * 36 + "...; allowed: grid, list, random"),
    ("method-a-list", SWEEP.replace("[sweep]\n", '[sweep]\nmethod = ["grid"] \n'),
     "sweep.method: must be a string, got ['grid']"),
    ("collect-long", SWEEP.replace("[sweep]\n", f'[sweep]\ncollect = ["{LONG}-"]\n'),
     "sweep.collect: '" + "x" * 36 + "... is not a quantity name; give names such as "
     "mean_speed_rpm, final_speed_rpm, delta, eta_mech, fmep_kPa, speed_dip_pct, "
     "recovery_time_s, droop_pct, spin_up_t90_s, or any /analysis entry"),
    ("columns-not-strings", SWEEP.replace("[sweep]\n", "[sweep]\ncolumns = [1, 2]\n"),
     "sweep.columns: must be a list of strings, got [1, 2]"),
    ("grid-num-huge", BASE + '[[axis]]\nkey = "load.torque"\nfrom = 0\nto = 1\nnum = '
                             "1000000000000\n",
     "axis[0].num: must be 2 … 100000 (runs of one sweep), got 1000000000000"),
    ("grid-num-one", BASE + '[[axis]]\nkey = "load.torque"\nfrom = 0\nto = 1\nnum = 1\n',
     "axis[0].num: must be 2 … 100000 (runs of one sweep), got 1"),
    ("grid-too-many-points", BASE + '[[axis]]\nkey = "load.torque"\nfrom = 0\nto = 1\n'
                                    'num = 1000\n[[axis]]\nkey = "load.fan"\nfrom = 0\nto = 1\n'
                                    "num = 1000\n",
     "axis: the grid has 1000000 points, more than the 100000 runs of one sweep; split it into "
     "sweeps or give fewer values"),
    ("random-samples-huge", BASE.replace("[sweep]\n", '[sweep]\nmethod = "random"\nseed = 1\n'
                                                      "samples = 1000000000\n")
     + '[[axis]]\nkey = "load.torque"\nlow = 0\nhigh = 1\n',
     "sweep.samples: must be ≤ 100000 (runs of one sweep), got 1000000000"),
    ("from-nan", BASE + '[[axis]]\nkey = "load.torque"\nfrom = nan\nto = 1\nnum = 3\n',
     "axis[0].from: must be finite, got nan"),
    ("to-inf", BASE + '[[axis]]\nkey = "load.torque"\nfrom = 0\nto = inf\nnum = 3\n',
     "axis[0].to: must be finite, got inf"),
    ("low-minus-inf", BASE.replace("[sweep]\n", '[sweep]\nmethod = "random"\nseed = 1\n'
                                                "samples = 3\n")
     + '[[axis]]\nkey = "load.torque"\nlow = -inf\nhigh = 1\n',
     "axis[0].low: must be finite, got -inf"),
    ("values-empty", BASE + '[[axis]]\nkey = "load.torque"\nvalues = []\n',
     "axis[0].values: must be a non-empty list of numbers, strings or booleans, got []"),
    ("values-tables", BASE + '[[axis]]\nkey = "load.torque"\nvalues = [{a = 1}]\n',
     "axis[0].values: must be a non-empty list of numbers, strings or booleans, got [{'a': 1}]"),
    ("values-long-string", BASE + f'[[axis]]\nkey = "load.torque"\nvalues = ["{LONG}"]\n',
     "run 0 (load.torque = '" + "x" * 36 + "...): scene load.torque: must be a number, got '"
     + "x" * 36 + "..."),
    ("key-long-and-unknown", BASE + f'[[axis]]\nkey = "load.{LONG}"\nvalues = [1.0]\n',
     "run 0 (load.xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx... = 1.0): scene load." + "x" * 152
     + "...: unknown key; allowed here: fan, generator_min_speed, generator_power, inertia, "
     "inertia_time, linear, schedule_revolutions, schedule_scale, schedule_time, table, torque"),
    ("key-malformed-long", BASE + f'[[axis]]\nkey = "load..{LONG}"\nvalues = [1.0]\n',
     "axis[0].key: 'load..xxxxxxxxxxxxxxxxxxxxxxxxxxxxxx... is not a scene key; give dotted TOML "
     "keys such as 'load.torque' or 'friction.pairs[0].eta_forward'"),
    ("axis-not-tables", "axis = 5\n" + BASE, "axis: must be an array of tables [[axis]], got 5"),
    ("axis-missing", BASE, "axis: is missing; give at least one [[axis]] with a key and its "
                           "values"),
    ("set-a-huge-integer", SWEEP + '[set]\n"run.revolutions" = 1' + "0" * 400 + "\n",
     "run 0 (load.torque = 1.0): scene run.revolutions: must be finite, got 1" + "0" * 36
     + "... (beyond a float's range)"),
    ("from-a-huge-integer", BASE + '[[axis]]\nkey = "load.torque"\nfrom = 0\nto = 1'
                                   + "0" * 400 + "\nnum = 3\n",
     "axis[0].to: must be finite, got 1" + "0" * 36 + "..."),
    ("unknown-key-long", f"{LONG} = 1\n" + SWEEP,
     "x" * 157 + "...: unknown key; allowed here: sweep, base, set, axis"),
]


@pytest.mark.parametrize("content, message", [pytest.param(c, m, id=i) for i, c, m in SWEEP_CASES])
def test_a_hostile_sweep_file_gives_its_exact_line(tmp_path, capsys, content, message):
    write(tmp_path / "base.toml", SMALL)
    write(tmp_path / "nul.toml", "\0" + SMALL)
    write(tmp_path / "deep.toml", "a = " + TOO_DEEP + "\n")
    sweep = tmp_path / "bad.toml"
    write(sweep, content)
    out = tmp_path / "out"
    assert one_line(capsys, ["sweep", sweep, "-o", out, "--scheduler", "serial"]) == \
        f"{sweep}: {message}"
    assert not out.exists()


# ------------------------------------------------------------------------------------------------
# Command-line options: (id, the arguments after the command, the line). {scene} is a valid
# scene with gas forces, {dir} an empty folder.

POINTS = "--points: must be 2 … 1000000, got"
RPM = "--rpm: values must be finite and lie in (0, 1e+06], got"
FUEL = "--fuel: values must be finite and lie in (0, 1], got"
SPR = "--samples-per-rev: must be 36 … 1000000, got"
SPC = "--samples-per-cycle: must be 16 … 1000000, got"
MAX_ORDER = "--max-order: must be finite and > 0, got"
REVS = "--revolutions: must be finite and > 0 and ≤ 1e+06, got"
BUDGET = "--baseline-budget: must be finite and > 0, got"
COMMANDS = ("'run', 'check', 'info', 'warmup', 'steady', 'plot', 'kinematics', 'modes', 'bench', "
            "'efficiency', 'loads', 'orders', 'stress', 'sweep', 'sweep-plot'")

OPTION_CASES = [
    # kinematics --points: a count of grid points
    ("points-negative", ["kinematics", "{scene}", "--points", "-5"], f"{POINTS} -5"),
    ("points-zero", ["kinematics", "{scene}", "--points", "0"], f"{POINTS} 0"),
    ("points-one", ["kinematics", "{scene}", "--points", "1"], f"{POINTS} 1"),
    ("points-huge", ["kinematics", "{scene}", "--points", "10000000000"], f"{POINTS} 10000000000"),
    ("points-float", ["kinematics", "{scene}", "--points", "36.5"],
     "--points: must be a whole number 2 … 1000000, got '36.5'"),
    ("points-exponent", ["kinematics", "{scene}", "--points", "1e3"],
     "--points: must be a whole number 2 … 1000000, got '1e3'"),
    ("points-nan", ["kinematics", "{scene}", "--points", "nan"],
     "--points: must be a whole number 2 … 1000000, got 'nan'"),
    ("points-empty", ["kinematics", "{scene}", "--points", ""],
     "--points: must be a whole number 2 … 1000000, got ''"),
    ("points-long", ["kinematics", "{scene}", "--points", "9" * 5000],
     "--points: must be a whole number 2 … 1000000, got '" + "9" * 36 + "..."),
    ("points-missing-value", ["kinematics", "{scene}", "--points"],
     "--points: expected one argument"),
    ("kinematics-csv-in-no-folder", ["kinematics", "{scene}", "-o", "{dir}/nope/k.csv"],
     "{dir}/nope/k.csv: cannot create the file (no folder {dir}/nope); give a path in an "
     "existing folder"),
    ("kinematics-plot-in-no-folder", ["kinematics", "{scene}", "--plot", "{dir}/nope/k.png"],
     "{dir}/nope/k.png: cannot create the file (no folder {dir}/nope); give a path in an "
     "existing folder"),
    ("kinematics-csv-exists", ["kinematics", "{scene}", "-o", "{scene}"],
     "{scene}: exists; use --force to replace it"),
    ("kinematics-csv-is-a-folder", ["kinematics", "{scene}", "-o", "{dir}"],
     "{dir}: is a folder; give a file name"),
    # efficiency: speeds, loads, policies, samples
    ("rpm-zero", ["efficiency", "{scene}", "--rpm", "0"], f"{RPM} '0'"),
    ("rpm-negative", ["efficiency", "{scene}", "--rpm", "1000,-1000"], f"{RPM} '1000,-1000'"),
    ("rpm-inf", ["efficiency", "{scene}", "--rpm", "inf"], f"{RPM} 'inf'"),
    ("rpm-nan", ["efficiency", "{scene}", "--rpm", "1000,nan"], f"{RPM} '1000,nan'"),
    ("rpm-beyond-any-engine", ["efficiency", "{scene}", "--rpm", "1e7"], f"{RPM} '1e7'"),
    ("rpm-empty", ["efficiency", "{scene}", "--rpm", ""], f"{RPM} ''"),
    ("rpm-commas-only", ["efficiency", "{scene}", "--rpm", ",,"], f"{RPM} ',,'"),
    ("rpm-text", ["efficiency", "{scene}", "--rpm", "fast"],
     "--rpm: must be comma-separated numbers, got 'fast'"),
    ("rpm-long", ["efficiency", "{scene}", "--rpm", "1," * 10_000 + "x"],
     "--rpm: must be comma-separated numbers, got '" + "1," * 18 + "..."),
    ("fuel-zero", ["efficiency", "{scene}", "--fuel", "0"], f"{FUEL} '0'"),
    ("fuel-above-one", ["efficiency", "{scene}", "--fuel", "1.5"], f"{FUEL} '1.5'"),
    ("fuel-nan", ["efficiency", "{scene}", "--fuel", "nan"], f"{FUEL} 'nan'"),
    ("fuel-negative", ["efficiency", "{scene}", "--fuel", "0.5,-0.5"], f"{FUEL} '0.5,-0.5'"),
    ("policies-unknown", ["efficiency", "{scene}", "--policies", "coulomb"],
     "--policies: unknown policy 'coulomb'; allowed: power-flow, paper"),
    ("policies-long", ["efficiency", "{scene}", "--policies", "power-flow," + LONG],
     "--policies: unknown policy '" + "x" * 36 + "...; allowed: power-flow, paper"),
    ("samples-per-rev-low", ["efficiency", "{scene}", "--samples-per-rev", "10"], f"{SPR} 10"),
    ("samples-per-rev-huge", ["efficiency", "{scene}", "--samples-per-rev", "1000000000"],
     f"{SPR} 1000000000"),
    ("samples-per-rev-text", ["efficiency", "{scene}", "--samples-per-rev", "many"],
     "--samples-per-rev: must be a whole number 36 … 1000000, got 'many'"),
    ("efficiency-output-is-a-file", ["efficiency", "{scene}", "-o", "{scene}"],
     "{scene}: cannot create the output folder (File exists); give a writable folder"),
    # orders and loads: checked before the result is read
    ("samples-per-cycle-low", ["orders", "{dir}/r.h5", "--samples-per-cycle", "8"], f"{SPC} 8"),
    ("samples-per-cycle-huge", ["orders", "{dir}/r.h5", "--samples-per-cycle", "10000000000"],
     f"{SPC} 10000000000"),
    ("samples-per-cycle-negative", ["orders", "{dir}/r.h5", "--samples-per-cycle", "-720"],
     f"{SPC} -720"),
    ("max-order-zero", ["orders", "{dir}/r.h5", "--max-order", "0"], f"{MAX_ORDER} 0"),
    ("max-order-negative", ["orders", "{dir}/r.h5", "--max-order", "-3"], f"{MAX_ORDER} -3"),
    ("max-order-nan", ["orders", "{dir}/r.h5", "--max-order", "nan"], f"{MAX_ORDER} nan"),
    ("max-order-inf", ["orders", "{dir}/r.h5", "--max-order", "inf"], f"{MAX_ORDER} inf"),
    ("max-order-text", ["orders", "{dir}/r.h5", "--max-order", "all"],
     "--max-order: must be a number > 0, got 'all'"),
    ("detrend-unknown", ["orders", "{dir}/r.h5", "--detrend", "spline"],
     "--detrend: invalid choice: 'spline' (choose from 'auto', 'ramp', 'none')"),
    ("detrend-long", ["orders", "{dir}/r.h5", "--detrend", LONG],
     "--detrend: invalid choice: '" + "x" * 36 + "... (choose from 'auto', 'ramp', 'none')"),
    ("cylinder-zero", ["loads", "{dir}/r.h5", "--cylinder", "0"],
     "--cylinder: must be 1 … 64, got 0"),
    ("cylinder-huge", ["loads", "{dir}/r.h5", "--cylinder", "100000"],
     "--cylinder: must be 1 … 64, got 100000"),
    ("cylinder-text", ["loads", "{dir}/r.h5", "--cylinder", "first"],
     "--cylinder: must be a whole number 1 … 64, got 'first'"),
    # result files that are not there or no file
    ("info-missing", ["info", "{dir}/r.h5"], "{dir}/r.h5: no such result file"),
    ("info-a-folder", ["info", "{dir}"],
     "{dir}: (file): is a folder, not a result file; give the .h5 file transient wrote"),
    ("plot-a-folder", ["plot", "{dir}"],
     "{dir}: (file): is a folder, not a result file; give the .h5 file transient wrote"),
    ("orders-a-fifo", ["orders", "{dir}/fifo"],
     "{dir}/fifo: (file): is a FIFO, not a result file; give the .h5 file transient wrote"),
    ("loads-a-device", ["loads", "/dev/null"],
     "/dev/null: (file): is a character device, not a result file; give the .h5 file transient "
     "wrote"),
    ("info-of-a-scene", ["info", "{scene}"],
     "{scene}: (file): not a readable transient result: Unable to synchronously open file (file "
     "signature not found)"),
    # sweep
    ("workers-zero", ["sweep", "{dir}/nope.toml", "--workers", "0"],
     "--workers: must be 1 … 256, got 0"),
    ("workers-huge", ["sweep", "{dir}/nope.toml", "--workers", "100000"],
     "--workers: must be 1 … 256, got 100000"),
    ("workers-text", ["sweep", "{dir}/nope.toml", "--workers", "all"],
     "--workers: must be a whole number 1 … 256, got 'all'"),
    ("sweep-missing", ["sweep", "{dir}/nope.toml"],
     "{dir}/nope.toml: (file): cannot read: No such file or directory"),
    ("sweep-a-folder", ["sweep", "{dir}"],
     "{dir}: (file): is a folder, not a sweep file; give a TOML file"),
    ("sweep-plot-a-folder", ["sweep-plot", "{dir}"],
     "{dir}: (file): is a folder, not a sweep file; give the .h5 file transient wrote"),
    ("sweep-plot-missing", ["sweep-plot", "{dir}/r.h5"], "{dir}/r.h5: no such sweep file"),
    # bench and stress: checked before any work
    ("bench-revolutions-zero", ["bench", "--revolutions", "0"], f"{REVS} 0"),
    ("bench-revolutions-negative", ["bench", "--revolutions", "-10"], f"{REVS} -10"),
    ("bench-revolutions-inf", ["bench", "--revolutions", "inf"], f"{REVS} inf"),
    ("bench-revolutions-nan", ["bench", "--revolutions", "nan"], f"{REVS} nan"),
    ("bench-revolutions-huge", ["bench", "--revolutions", "1e30"], f"{REVS} 1e+30"),
    ("bench-revolutions-text", ["bench", "--revolutions", "many"],
     "--revolutions: must be a number > 0 and ≤ 1e+06, got 'many'"),
    ("bench-repeat-zero", ["bench", "--repeat", "0"], "--repeat: must be 1 … 100, got 0"),
    ("bench-repeat-huge", ["bench", "--repeat", "1000000"],
     "--repeat: must be 1 … 100, got 1000000"),
    ("bench-budget-zero", ["bench", "--baseline-budget", "0"], f"{BUDGET} 0"),
    ("bench-budget-nan", ["bench", "--baseline-budget", "nan"], f"{BUDGET} nan"),
    ("bench-budget-negative", ["bench", "--baseline-budget", "-60"], f"{BUDGET} -60"),
    ("bench-scene-missing", ["bench", "{dir}/nope.toml", "-o", "{dir}/out"],
     "{dir}/nope.toml: (file): cannot read: No such file or directory"),
    # the command line itself
    ("command-unknown", ["frobnicate"],
     f"command: invalid choice: 'frobnicate' (choose from {COMMANDS})"),
    ("command-long", [LONG],
     f"command: invalid choice: '{'x' * 36}... (choose from {COMMANDS})"),
    ("no-command", [], "transient: the following arguments are required: command; see "
                       "'transient --help'"),
    ("scene-missing-argument", ["check"], "transient check: the following arguments are "
                                          "required: scene; see 'transient check --help'"),
    ("option-unknown", ["check", "{scene}", "--frobnicate"],
     "transient: unrecognized arguments: --frobnicate; see 'transient --help'"),
    ("option-unknown-long", ["check", "{scene}", "--" + LONG],
     "transient: unrecognized arguments: --" + "x" * 75 + "...; see 'transient --help'"),
]


@pytest.mark.parametrize("argv, message", [pytest.param(a, m, id=i) for i, a, m in OPTION_CASES])
def test_a_hostile_option_gives_its_exact_line(tmp_path, capsys, argv, message):
    scene = tmp_path / "s.toml"
    scene.write_text(SMALL + '\n[gas]\nmodel = "table"\nphi_deg = [0, 360, 720]\n'
                             'p_bar = [1, 60, 1]\n', encoding="utf-8")
    os.mkfifo(tmp_path / "fifo")
    names = {"scene": scene, "dir": tmp_path}
    argv = [a.format(**names) for a in argv]
    assert one_line(capsys, argv) == message.format(**names)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "s.toml"]


def test_the_suite_is_large_and_distinct():
    groups = (SCENE_CASES, TABLE_CASES, SWEEP_CASES, OPTION_CASES)
    assert sum(map(len, groups)) >= 100
    for group in groups:
        assert len({c[0] for c in group}) == len(group)


# ------------------------------------------------------------------------------------------------
# Absurd magnitudes that passed the checks and failed at the first step, and names a terminal
# would act on: (id, file content, the line after "{scene}: "). The bounds follow from the speed
# no piston machine reaches (RUNAWAY_SPEED): SMALL's least reduced inertia is 0.0248 kg m², so a
# torque may be up to 0.0248·(1e5)²/(4π) = 1.98e7 N m (it would otherwise take the machine from
# rest past 1e5 rad/s within one revolution).

RUNAWAY = ("which would take the machine (least reduced inertia 0.0248 kg m²) from rest past "
           "100000 rad/s, faster than any piston machine turns, within one revolution; allowed "
           "up to J_min·ω²/(4π) = 1.98e+07 N m")
GAS = SMALL + MIXED_CYCLE.format(cr=18)
SPEED = ("rad/s is beyond 100000 rad/s (9.55e+05 rpm), faster than any piston machine turns (a "
         "run reaching it ends as a runaway); give a speed up to that")

MAGNITUDE_CASES = [
    ("initial-speed-beyond-any-machine", SMALL.replace("omega_rpm = 1000", "omega = 1e300"),
     f"initial.omega: 1e+300 {SPEED}"),
    ("initial-speed-in-rpm", SMALL.replace("omega_rpm = 1000", "omega_rpm = -1e7"),
     f"initial.omega_rpm: 1.05e+06 {SPEED}"),
    ("load-torque", insert("shaft = 0.02", "\n[load]\ntorque = 1e300"),
     f"load.torque: gives a torque of 1e+300 N m, {RUNAWAY}"),
    ("load-driving", insert("shaft = 0.02", "\n[load]\ntorque = -1e30"),
     f"load.torque: gives a torque of 1e+30 N m, {RUNAWAY}"),
    ("fan-at-the-initial-speed", insert("shaft = 0.02", "\n[load]\nfan = 1e300"),
     f"load.fan: gives a torque of 1.1e+304 N m at the initial speed, {RUNAWAY}"),
    ("starter", insert("shaft = 0.02", "\n[starter]\ntorque = 1e300"),
     f"starter.torque: gives a torque of 1e+300 N m, {RUNAWAY}"),
    ("crankcase-pressure", GAS.replace("p_a_MPa = 0.1436", "p_a_MPa = 0.1436\np0 = 1e306"),
     "gas.p0: gives a torque of 3e+302 N m (the pressure difference p − p0 up to 1e+306 Pa on "
     "pistons of 0.00608 m², on their lever Σ max|dx/dφ| = 0.0493 m), " + RUNAWAY),
    ("peak-pressure", GAS.replace("p_z_MPa = 10.5", "p_z_MPa = 1e300"),
     "gas.p_z_MPa: gives a torque of 3e+302 N m (the pressure difference p − p0 up to 1e+306 Pa "
     "on pistons of 0.00608 m², on their lever Σ max|dx/dφ| = 0.0493 m), " + RUNAWAY),
    ("intake-pressure", GAS.replace("p_intake_MPa = 0.165", "p_intake_MPa = 1e300"),
     "gas.p_intake_MPa: gives a torque of 3e+302 N m (the pressure difference p − p0 up to "
     "1e+306 Pa on pistons of 0.00608 m², on their lever Σ max|dx/dφ| = 0.0493 m), " + RUNAWAY),
    ("bore-of-a-kilometre", GAS.replace("bore_mm = 88", "bore_mm = 1e6"),
     "gas.p_z_MPa: gives a torque of 4.03e+11 N m (the pressure difference p − p0 up to "
     "1.04e+07 Pa on pistons of 7.85e+05 m², on their lever Σ max|dx/dφ| = 0.0493 m), "
     + RUNAWAY),
    ("compression-exponent", GAS.replace("n1 = 1.368", "n1 = 1e300"),
     "gas.p_z_MPa: must be ≥ p_a · compression_ratio^n1 = inf, got 10.5"),
    ("control-character-in-the-name", SMALL.replace('name = "small"', 'name = "sm\\u001b[2Jall"'),
     "scene.name: holds the control character '\\x1b' (character 3); a name labels terminal "
     "lines, figures and results: give printable text"),
    ("newline-in-the-name", SMALL.replace('name = "small"', 'name = "sm\\nall"'),
     "scene.name: holds the control character '\\n' (character 3); a name labels terminal lines, "
     "figures and results: give printable text"),
    ("control-character-in-a-pair-name",
     SMALL + '\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\nname = "main\\u0007"\n'
             'eta_forward = 0.9\neta_backward = 0.9\n',
     "friction.pairs[0].name: holds the control character '\\x07' (character 5); a name labels "
     "terminal lines, figures and results: give printable text"),
]


@pytest.mark.parametrize("content, message",
                         [pytest.param(c, m, id=i) for i, c, m in MAGNITUDE_CASES])
def test_an_absurd_magnitude_or_a_control_character_gives_its_exact_line(tmp_path, capsys,
                                                                         content, message):
    scene = tmp_path / "bad.toml"
    write(scene, content)
    assert one_line(capsys, ["check", scene]) == f"{scene}: {message}"


def test_a_compressor_beyond_any_machine_is_refused_by_its_discharge(tmp_path, capsys):
    """The magnitude bound covers the compressor cycle, whose largest pressure is the discharge:
    3e19 Pa on the A/C compressor's pistons (a clearance small enough to deliver at that ratio)."""
    from pathlib import Path

    case = (Path(__file__).resolve().parents[2] / "cases" / "ac_compressor_7cyl.toml").read_text(
        encoding="utf-8")
    lines = {"p_discharge_MPa = ": "p_discharge_MPa = 3e13", "clearance_ratio = ":
             "clearance_ratio = 1e-14"}
    scene = tmp_path / "c.toml"
    write(scene, "\n".join(next((v for k, v in lines.items() if line.startswith(k)), line)
                           for line in case.splitlines()) + "\n")
    line = one_line(capsys, ["check", scene])
    assert line.startswith(f"{scene}: gas.p_discharge_MPa: gives a torque of 2.35e+15 N m (the "
                           f"pressure difference p − p0 up to 3e+19 Pa on pistons of ")
    assert line.endswith("faster than any piston machine turns, within one revolution; allowed "
                         "up to J_min·ω²/(4π) = 7.66e+06 N m")


def test_a_wiebe_cycle_no_gas_has_is_refused(tmp_path, capsys):
    """γ above a monatomic gas's 5/3 is refused by its key; a heat release no double holds, by
    the Wiebe table that cannot be integrated (one line, no traceback, no numpy warning)."""
    from pathlib import Path

    wiebe = (Path(__file__).resolve().parents[2] / "cases" / "gots_diesel_wiebe.toml").read_text(
        encoding="utf-8")
    scene = tmp_path / "w.toml"
    write(scene, "\n".join("gamma = 1.7" if line.startswith("gamma = ") else line
                           for line in wiebe.splitlines()) + "\n")
    assert one_line(capsys, ["check", scene]) == (f"{scene}: gas.wiebe.gamma: must be ≤ 5/3 = "
                                                  f"1.66667, got 1.7")
    assert "\ngamma = " in wiebe and "\nfuel_mass = " in wiebe
    write(scene, "\n".join("fuel_mass = 1e300" if line.startswith("fuel_mass = ") else line
                           for line in wiebe.splitlines()) + "\n")
    line = one_line(capsys, ["check", scene])
    assert line.startswith(f"{scene}: gas.wiebe: the cycle's pressure cannot be integrated from ")
    assert line.endswith("its inputs give no physical gas; check fuel_mass, lhv, m, gamma, "
                         "gamma_slope and p_a, and their units")


def test_the_bound_lets_the_shipped_scenes_through():
    """Every scene of cases/ loads: the bounds refuse no machine the project models."""
    from pathlib import Path

    from transient.scene import load_scene

    for path in sorted((Path(__file__).resolve().parents[2] / "cases").glob("*.toml")):
        load_scene(path)


def test_a_sweep_name_with_a_control_character(tmp_path, capsys):
    write(tmp_path / "base.toml", SMALL)
    sweep = tmp_path / "s.toml"
    write(sweep, SWEEP.replace("[sweep]\n", '[sweep]\nname = "a\\u001bb"\n'))
    assert one_line(capsys, ["check", sweep]) == (f"{sweep}: sweep.name: holds a control "
                                                  f"character ('a\\x1bb'); give printable text")
