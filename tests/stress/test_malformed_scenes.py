"""Malformed scenes and hostile files (issue 9, item 3): each kind gives its exact one-line error
and exit 2 through the CLI, before any work; a run killed with SIGKILL leaves a result that opens
and says it is incomplete; an output folder that cannot be written fails before integrating.

The kinds here extend ``tests/unit/test_scene_errors.py`` (which has the first ~70); none of its
cases is repeated. Each case breaks one thing of the valid scene ``VALID`` (or of the swash-plate
case file) and states the whole line the user gets after ``<file>: ``. Cases marked *was a bug*
failed before the stress suite's fixes (a traceback, a hang or an accepted scene).
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest
from scene_texts import SMALL

from transient.cli import main
from transient.results import PROBE_BYTES, open_file

REPO = Path(__file__).resolve().parents[2]

VALID = SMALL

SWASH = (REPO / "cases" / "swash_plate_4cyl.toml").read_text(encoding="utf-8")

PAIRS = """
[friction]

[[friction.pairs]]
name = "{}"
between = ["shaft", "crank"]
eta_forward = 0.9
eta_backward = 0.9

[[friction.pairs]]
name = "{}"
between = ["crank", "rod"]
eta_forward = 0.9
eta_backward = 0.9
"""


def sub(old: str, new: str, base: str = VALID) -> str:
    """``base`` with one line replaced; the line (with its newline before) must be there once."""
    assert base.count("\n" + old) == 1, old
    return base.replace("\n" + old, "\n" + new)


def add(anchor: str, lines: str, base: str = VALID) -> str:
    return sub(anchor, f"{anchor}\n{lines}", base)


def table_gas(extra: str) -> str:
    return VALID + '\n[gas]\nmodel = "table"\n' + extra


SCHEDULE = VALID + "\n[load]\ntorque = 10\n"

# (id, scene text, the exact message after "<file>: ")
CASES = [
    # syntax
    ("syntax-unterminated-string", sub('name = "small"', 'name = "small'),
     "(syntax): not valid TOML: Illegal character '\\n' (at line 2, column 14)"),
    ("syntax-duplicate-key", add("bore_mm = 88", "bore_mm = 90"),
     "(syntax): not valid TOML: Cannot overwrite a value (at line 9, column 13)"),
    ("syntax-duplicate-table", VALID + "\n[inertia]\nflywheel = 0.1\n",
     "(syntax): not valid TOML: Cannot declare ('inertia',) twice (at line 33, column 9)"),
    ("syntax-missing-value", sub("bore_mm = 88", "bore_mm ="),
     "(syntax): not valid TOML: Invalid value (at line 8, column 10)"),
    ("empty-file", "", "mechanism: is missing (a table)"),
    ("comments-only", "# a scene to be written\n", "mechanism: is missing (a table)"),
    # types
    ("type-number-as-string", sub("bore_mm = 88", 'bore_mm = "88"'),
     "mechanism.bore_mm: must be a number, got '88'"),
    ("type-integer-as-float", add("crank_mass = 0.912", "cylinders = 3.0"),
     "mechanism.cylinders: must be a whole number, got 3.0"),
    ("type-string-as-number", sub('model = "two-mass"', "model = 2"),
     "mechanism.rod.model: must be a string, got 2"),
    ("type-list-as-string", add("crank_mass = 0.912", 'cylinders = 3\nfiring_order = "1,2,3"'),
     "mechanism.firing_order: must be a list of whole numbers, got '1,2,3'"),
    ("type-list-with-a-string", table_gas('phi_deg = [0, 360, 720]\np_bar = [1, "60", 1]\n'),
     "gas.p_bar: must be a list of finite numbers, got [1, '60', 1]"),
    ("type-list-with-nan", table_gas("phi_deg = [0, 360, 720]\np_bar = [1, nan, 1]\n"),
     "gas.p_bar: must be a list of finite numbers, got [1, nan, 1]"),
    ("type-array-of-tables", sub("[run]", "[[run]]"), "run: must be a table, got list"),
    ("type-samples-not-whole", sub("samples_per_rev = 12", "samples_per_rev = 12.5"),
     "output.samples_per_rev: must be a whole number, got 12.5"),
    ("type-inline-table", sub("shaft = 0.02", "shaft = {value = 0.02}"),
     "inertia.shaft: must be a number, got {'value': 0.02}"),
    ("type-date", sub("revolutions = 2", "revolutions = 1979-05-27"),
     "run.revolutions: must be a number, got datetime.date(1979, 5, 27)"),
    ("type-corners-not-list", table_gas("phi_deg = [0, 360, 720]\np_bar = [1, 60, 1]\n"
                                        "corners_deg = 360\n"),
     "gas.corners_deg: must be a list of finite numbers, got 360"),
    ("type-pairs-not-tables", VALID + "\n[friction]\npairs = [1, 2]\n",
     "friction.pairs[0]: must be a table, got int"),
    # units
    ("unit-psi", VALID + '\n[gas]\nmodel = "none"\np0_psi = 14.7\n',
     "gas.p0_psi: unknown unit suffix '_psi'; give 'p0' or 'p0_bar' or 'p0_MPa' (SI without a "
     "suffix)"),
    ("unit-ms-on-time", add("revolutions = 2", "t_end_ms = 20"),
     "run.t_end_ms: unknown unit suffix '_ms'; give 't_end' [s]"),
    ("unit-deg-on-speed", sub("omega_rpm = 1000", "omega_deg = 1000"),
     "initial.omega_deg: unit suffix '_deg' does not fit this quantity; give 'omega' or "
     "'omega_rpm' (SI without a suffix)"),
    ("unit-mm-on-mass", sub("piston_mass = 1.520", "piston_mass_mm = 1.520"),
     "mechanism.piston_mass_mm: unit suffix '_mm' does not fit this quantity; give 'piston_mass' "
     "[kg]"),
    ("unit-si-and-rpm", add("omega_rpm = 1000", "omega = 104.7"),
     "initial.omega_rpm: given twice (also as 'omega'); give one of them"),
    # ranges
    ("range-bore-zero", sub("bore_mm = 88", "bore_mm = 0"),
     "mechanism.bore_mm: must be > 0, got 0"),
    ("range-flywheel-negative", add("shaft = 0.02", "flywheel = -1"),
     "inertia.flywheel: must be ≥ 0, got -1"),
    ("range-atol-zero", sub("atol = 1e-8", "atol = 0"), "solver.atol: must be > 0, got 0"),
    ("range-switch-speed-zero", add("atol = 1e-8", "switch_speed = 0"),
     "solver.switch_speed: must be > 0, got 0"),
    ("range-fan-negative", VALID + "\n[load]\nfan = -1e-3\n", "load.fan: must be ≥ 0, got -0.001"),
    ("range-starter-torque-negative", VALID + "\n[starter]\ntorque = -5\n",
     "starter.torque: must be ≥ 0, got -5"),
    ("range-governor-inverted", VALID + '\n[governor]\nmodel = "droop"\nspeed_full_rpm = 3000\n'
                                        'speed_zero_rpm = 2000\n',
     "governor.speed_zero_rpm: must be > speed_full = 3000, got 2000"),
    ("range-output-dt-negative", add("samples_per_rev = 12", "dt = -1e-4"),
     "output.dt: must be 0 or ≥ 1e-08, got -0.0001"),
    ("range-output-dt-tiny", add("samples_per_rev = 12", "dt = 1e-12"),
     "output.dt: must be 0 or ≥ 1e-08, got 1e-12"),
    ("range-max-step-zero", add("atol = 1e-8", "max_step = 0"), "solver.max_step: must be > 0, got 0"),
    ("range-table-tolerance-1", add("atol = 1e-8", "table_tolerance = 1"),
     "solver.table_tolerance: must be < 1, got 1"),
    ("range-t-end-inf", add("revolutions = 2", "t_end = inf"), "run.t_end: must be finite, got inf"),
    ("range-initial-phi-nan", add("omega_rpm = 1000", "phi = nan"),
     "initial.phi: must be finite, got nan"),
    ("range-crank-mass-negative", sub("crank_mass = 0.912", "crank_mass = -0.1"),
     "mechanism.crank_mass: must be ≥ 0, got -0.1"),
    ("range-schedule-infinite", SCHEDULE + "schedule_time = [0.1, inf]\nschedule_scale = [1, 0]\n",
     "load.schedule_time: must be a list of finite numbers, got [0.1, inf]"),
    ("range-schedule-negative-scale", SCHEDULE + "schedule_time = [0.1, 0.2]\n"
                                                 "schedule_scale = [1, -1]\n",
     "load.schedule_scale: must be ≥ 0, got -1 (entry 2)"),
    ("range-schedule-decreasing", SCHEDULE + "schedule_time = [0.2, 0.1]\nschedule_scale = [1, 0]\n",
     "load.schedule_time: must not decrease, but 0.1 follows 0.2 (entry 2); a step is two equal "
     "entries, a ramp two increasing ones"),
    ("range-trapezoid-ramps", VALID + '\n[gas]\nmodel = "trapezoid"\namplitude = 1000\n'
                                      'ramp_deg = 100\nduration_deg = 150\n',
     "gas.ramp_deg: must be ≤ duration/2 = 75, got 100"),
    ("range-prescribed-speed-negative", add("revolutions = 2", 'mode = "prescribed-speed"\n'
                                            "time = [0, 1]\nspeed_table = [10, -5]"),
     "run.speed_table: must be > 0, got -5 (entry 2)"),
    # sizes that would exhaust memory or never finish (was a bug: accepted, then a hang)
    ("too-many-cylinders", add("crank_mass = 0.912", "cylinders = 100000000"),
     "mechanism.cylinders: must be ≤ 64, got 100000000"),
    ("too-many-swash-cylinders", sub("cylinders = 4", "cylinders = 1000000000", SWASH),
     "mechanism.cylinders: must be ≤ 64, got 1000000000"),
    ("too-many-samples", sub("samples_per_rev = 12", "samples_per_rev = 1000000000000"),
     "output.samples_per_rev: must be ≤ 1000000, got 1000000000000"),
    # inconsistent geometry
    ("geometry-swash-bores-overlap", sub("bore_mm = 100", "bore_mm = 190", SWASH),
     "mechanism.bore_mm: must be < 2 · cylinder_radius · sin(180°/cylinders) (cylinders > 1) = "
     "185.7, got 190"),
    ("geometry-swash-three-halves", sub("halves = 1", "halves = 3", SWASH),
     "mechanism.halves: must be one of 1, 2, got 3"),
    ("geometry-swash-rod-cg-off-rod", sub("cg_from_pin_mm = 150", "cg_from_pin_mm = 301", SWASH),
     "mechanism.rod.cg_from_pin_mm: must be ≤ rod_length = 300, got 301"),
    ("geometry-swash-unknown-hinge", sub('hinge = "in-plane"', 'hinge = "diagonal"', SWASH),
     "mechanism.hinge: unknown value 'diagonal'; allowed: 'normal', 'in-plane'"),
    ("geometry-piston-area-overflows", sub("bore_mm = 88", "bore_mm = 1e300"),
     "mechanism.bore: the piston area overflows; check the bore and its unit (mm: 'bore_mm')"),
    # missing tables and keys
    ("missing-mechanism", VALID.replace(VALID[VALID.index("[mechanism]"):VALID.index("[inertia]")],
                                        ""),
     "mechanism: is missing (a table)"),
    ("missing-table-points", table_gas(""),
     "gas.phi: is missing; give 'phi' or 'phi_deg' (SI without a suffix) list"),
    ("missing-wiebe-table", VALID + '\n[gas]\nmodel = "wiebe"\ncompression_ratio = 18\n'
                                    'p_a_MPa = 0.1\np_intake_MPa = 0.1\np_exhaust_MPa = 0.1\n',
     "gas.wiebe: is missing (a table)"),
    ("missing-trapezoid-ramp", VALID + '\n[gas]\nmodel = "trapezoid"\namplitude = 1000\n',
     "gas.ramp: is missing; give 'ramp' or 'ramp_deg' (SI without a suffix)"),
    ("missing-prescribed-speed", add("revolutions = 2", 'mode = "prescribed-speed"'),
     "run.speed: is missing; a prescribed-speed run needs 'speed' (or 'speed_rpm'), or a table "
     "'time' [s] with 'speed_table'"),  # was a bug: reported 'run.time' as the missing key
    ("missing-generator-min-speed", VALID + "\n[load]\ngenerator_power = 1000\n",
     "load.generator_min_speed: is missing (required with a generator_power, else 0); give "
     "'generator_min_speed' or 'generator_min_speed_rpm' (SI without a suffix)"),
    ("missing-csv-columns", table_gas('file = "empty.csv"\n'),
     "gas.file: empty.csv: needs an angle column (phi_deg, phi) and a pressure or force column "
     "(p, p_bar, p_MPa, p_Pa, force, force_N, force_kN); header is []"),
    ("csv-text-row", table_gas('file = "text.csv"\n'),
     "gas.file: text.csv: line 3, column phi_deg: 'abc' is not a number"),
    ("csv-not-utf8", table_gas('file = "latin1.csv"\n'),  # was a bug: a traceback
     "gas.file: latin1.csv: not UTF-8 text (byte 27); save the table as UTF-8 CSV"),
    # empty cylinders, tables and names
    ("no-cylinders", add("crank_mass = 0.912", "cylinders = 0"),
     "mechanism.cylinders: must be ≥ 1, got 0"),
    ("empty-firing-order", add("crank_mass = 0.912", "cylinders = 3\nfiring_order = []"),
     "mechanism.firing_order: must list each cylinder 1 … 3 once, got []"),
    ("empty-firing-angles", add("crank_mass = 0.912", "cylinders = 3\nfiring_deg = []"),
     "mechanism.firing_deg: has 0 entries; must have one per cylinder (3)"),
    ("empty-pressure-table", table_gas("phi_deg = []\np_bar = []\n"),
     "gas.phi_deg: needs at least 2 finite angles from 0° to 720°, got 0"),
    ("empty-pair", VALID + "\n[friction]\n\n[[friction.pairs]]\n",
     "friction.pairs[0].between: must be two link names, got None; the links are shaft – crank "
     "– rod – piston – cylinder"),
    ("empty-scene-name", sub('name = "small"', 'name = ""'),  # was a bug: accepted
     "scene.name: must not be empty; it names the result (leave it out to use the file's name)"),
    # duplicate names and abscissae
    ("duplicate-pair-names", VALID + PAIRS.format("bearing", "bearing"),  # was a bug: accepted
     "friction.pairs[1].name: 'bearing' names friction.pairs[0] too; give each pair its own name "
     "(it labels the pair's result columns and reports)"),
    ("duplicate-schedule-thrice", SCHEDULE + "schedule_time = [0.1, 0.1, 0.1]\n"
                                             "schedule_scale = [1, 0, 1]\n",
     "load.schedule_time: 0.1 appears three times in a row (entries 1 to 3); a step is two equal "
     "entries: the value before and the value after"),
    ("duplicate-schedule-abscissae", SCHEDULE + "schedule_time = [0.1]\nschedule_revolutions = "
                                                "[1]\nschedule_scale = [1]\n",
     "load.schedule_revolutions: given together with 'schedule_time'; a schedule runs against "
     "time or against revolutions: give one of them"),
    # inconsistent settings
    ("fixed-step-in-time-domain", add("atol = 1e-8", 'fixed_step_deg = 5\ndomain = "time"'),
     'solver.fixed_step: fixed steps are crank-angle steps; use domain = "auto" or fixed_step = 0'),
    ("tables-on-reference-path", add("atol = 1e-8", 'kinematics = "tabulated"\n'
                                                    'method = "scipy-DOP853"'),
     "solver.kinematics: tables are for the compiled methods (dop853, dopri5, ros34pw2, auto); the "
     "reference path 'scipy-DOP853' is exact by design"),
    ("unknown-domain", add("atol = 1e-8", 'domain = "angle"'),
     "solver.domain: unknown value 'angle'; allowed: 'auto', 'time'"),
    ("unknown-interpolation", table_gas('phi_deg = [0, 360, 720]\np_bar = [1, 60, 1]\n'
                                        'interpolation = "akima"\n'),
     "gas.interpolation: unknown value 'akima'; allowed: 'pchip', 'spline', 'linear'"),
    ("unknown-rod-model", sub('model = "two-mass"', 'model = "flexible"'),
     "mechanism.rod.model: unknown value 'flexible'; allowed: 'two-mass', 'rigid'"),
]


@pytest.fixture
def scene_dir(tmp_path):
    (tmp_path / "empty.csv").write_text("", encoding="utf-8")
    (tmp_path / "text.csv").write_text("phi_deg,p_bar\n0,1\nabc,5\n720,1\n", encoding="utf-8")
    (tmp_path / "latin1.csv").write_bytes("phi_deg,p_bar\n0,1\n# Druck für\n720,1\n"
                                          .encode("latin-1"))
    return tmp_path


def run_cli(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("command", ["check", "run"])
@pytest.mark.parametrize("text, message", [pytest.param(t, m, id=i) for i, t, m in CASES])
def test_malformed_scene_gives_its_exact_line_and_exit_2(scene_dir, capsys, command, text,
                                                         message):
    scene = scene_dir / "bad.toml"
    scene.write_text(text, encoding="utf-8")
    out_dir = scene_dir / "out"
    argv = [command, str(scene)] + (["-o", str(out_dir)] if command == "run" else [])
    code, out, err = run_cli(argv, capsys)
    assert (code, out, err) == (2, "", f"{scene}: {message}\n")
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_the_catalogue_is_large_and_distinct():
    ids = [c[0] for c in CASES]
    assert len(set(ids)) == len(ids) >= 30
    assert len({c[1] for c in CASES}) == len(CASES)


def test_the_bases_are_valid(tmp_path, capsys):
    for text in (VALID, SWASH, VALID + PAIRS.format("a", "b")):
        scene = tmp_path / "ok.toml"
        scene.write_text(text, encoding="utf-8")
        assert run_cli(["check", str(scene)], capsys)[0] == 0


def test_byte_order_mark_is_accepted(tmp_path, capsys):
    """A scene saved with a UTF-8 byte-order mark (Windows editors) reads as without one (was a
    bug: '(syntax): not valid TOML: Invalid statement (at line 1, column 1)')."""
    scene = tmp_path / "bom.toml"
    scene.write_bytes(b"\xef\xbb\xbf" + VALID.encode("utf-8"))
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert (code, err) == (0, "")


# ------------------------------------------------------------------------------------------------
# Files


LONG = sub("revolutions = 2", "revolutions = 1000000", VALID)  # ~50 s, killed long before


def _holds_a_block(part):
    """Whether the result file being written at ``part`` holds a trajectory block yet."""
    try:
        with open_file(part) as f:
            return f["checkpoint/index"].shape[0] > 0
    except (OSError, KeyError):  # not there yet
        return False


def test_sigkill_during_writing_leaves_an_incomplete_file(tmp_path):
    """docs/guide/results.md: written under a temporary name, flushed after every block; killed with
    SIGKILL the file opens and says complete = false."""
    scene = tmp_path / "long.toml"
    scene.write_text(LONG, encoding="utf-8")
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "transient", "run", str(scene), "-o", str(out),
                             "-q"], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    part = out / ".long.h5.part"
    try:
        # Wait for the file and for the first trajectory block in it. Hang guard: 600 s, as for
        # the warm-up runs below, since a cold numba cache compiles the stepper first (~210–240 s
        # on the slower test machine; a 120 s guard killed such a run before its first block).
        deadline = time.monotonic() + 600.0
        while proc.poll() is None and not _holds_a_block(part):
            assert time.monotonic() < deadline, "no trajectory block written in 600 s"
            time.sleep(0.05)
        assert proc.poll() is None, proc.stderr.read().decode()
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == -signal.SIGKILL
    assert not (out / "long.h5").exists()  # never renamed: the run did not end
    with open_file(part) as f:
        assert f.attrs["creator"] == "transient"
        assert bool(f.attrs["complete"]) is False
        n = f["trajectory/t"].shape[0]
        assert n > 0 and f["trajectory/omega"].shape[0] == n
    # and the CLI reads it and says so
    code = subprocess.run([sys.executable, "-m", "transient", "info", str(part)], cwd=REPO,
                          capture_output=True, text=True, timeout=120)
    assert code.returncode == 0, code.stderr
    assert "complete = False" in code.stdout
    # a rerun without --force refuses, in one line, and leaves the partial result as it was
    before = part.read_bytes()
    again = subprocess.run([sys.executable, "-m", "transient", "run", str(scene), "-o", str(out),
                            "-q"], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert again.returncode == 2 and again.stderr.count("\n") == 1, again.stderr
    assert str(part) in again.stderr and "--force" in again.stderr
    assert part.read_bytes() == before


def _run_until_a_block(scene: Path, out: Path) -> subprocess.Popen:
    """``transient run scene -o out`` in a new process, once its result holds a block."""
    proc = subprocess.Popen([sys.executable, "-m", "transient", "run", str(scene), "-o", str(out),
                             "-q"], cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            preexec_fn=_heeding_signals)
    part = out / f".{scene.stem}.h5.part"
    deadline = time.monotonic() + 600.0  # (a cold cache compiles the stepper first)
    while proc.poll() is None and not _holds_a_block(part):
        assert time.monotonic() < deadline, "no trajectory block written in 600 s"
        time.sleep(0.05)
    assert proc.poll() is None, proc.stderr.read().decode()
    return proc


def _heeding_signals() -> None:
    """preexec_fn: SIGHUP and SIGINT as a terminal's command has them, not ignored as under
    ``nohup`` or in a background job, whose ignored signals a command keeps ignoring."""
    for sig in (signal.SIGHUP, signal.SIGINT):
        signal.signal(sig, signal.SIG_DFL)


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP"])
def test_terminate_and_hangup_end_a_run_as_ctrl_c_does(tmp_path, signame):
    """``timeout``, a scheduler's preemption (SIGTERM) or a closed terminal (SIGHUP): the run
    stops between blocks, the result gets its name and says complete = false, exit 1 with one
    line."""
    scene = tmp_path / "long.toml"
    scene.write_text(LONG, encoding="utf-8")
    out = tmp_path / "out"
    proc = _run_until_a_block(scene, out)
    try:
        os.kill(proc.pid, getattr(signal, signame))
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = err.decode()
    assert proc.returncode == 1 and err.count("\n") == 1 and "interrupted" in err, err
    assert not (out / ".long.h5.part").exists()
    with h5py.File(out / "long.h5", "r") as f:
        assert bool(f.attrs["complete"]) is False
        assert f["trajectory/t"].shape[0] > 0


@pytest.mark.parametrize("where", ["under-a-file", "is-a-file"])
def test_unwritable_output_fails_before_integrating(tmp_path, capsys, where):
    """An output folder that cannot be made (a file in its way) is a one-line error, exit 2,
    before any work (was a bug: a NotADirectoryError traceback)."""
    scene = tmp_path / "ok.toml"
    scene.write_text(LONG, encoding="utf-8")  # would take a minute: it must not start
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a folder")
    out = blocker / "sub" if where == "under-a-file" else blocker
    t0 = time.perf_counter()
    code, stdout, err = run_cli(["run", str(scene), "-o", str(out)], capsys)
    assert code == 2 and stdout == ""
    reason = "Not a directory" if where == "under-a-file" else "File exists"
    assert err == f"{out}: cannot create the output folder ({reason}); give a writable folder\n"
    assert time.perf_counter() - t0 < 30.0  # hang guard only: it must not have integrated


def full_disk(limit):
    """preexec_fn: file-size limit of ``limit`` bytes, writes beyond it fail with EFBIG (as on a
    full disk) instead of killing the process."""
    def apply():
        import resource

        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


def test_full_disk_fails_before_integrating(tmp_path):
    """No room for the result's header: one line, exit 2, no file left (was a bug: an HDF5
    traceback and a crash at exit). Kernels are loaded before the limit applies (numba writes
    its cache)."""
    scene = tmp_path / "ok.toml"
    scene.write_text(VALID, encoding="utf-8")
    warm = subprocess.run([sys.executable, "-m", "transient", "run", str(scene), "-o",
                           str(tmp_path / "warm"), "-q"], cwd=REPO, capture_output=True, timeout=600)
    assert warm.returncode == 0, warm.stderr
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run([sys.executable, "-m", "transient", "run", str(scene), "-o", str(out)],
                       cwd=REPO, capture_output=True, text=True, timeout=300,
                       preexec_fn=full_disk(4096))
    assert r.returncode == 2, r.stderr
    assert r.stderr == f"{out}: cannot write the result there (File too large); is the disk full?\n"
    assert list(out.iterdir()) == []


def test_full_disk_mid_run_fails_with_one_line(tmp_path):
    """The disk fills up while the trajectory streams: one line, exit 1, the partial file left
    under its temporary name (was a bug: HDF5's deallocators retried the failed writes, printed
    their tracebacks and crashed the process with SIGSEGV at exit)."""
    scene = tmp_path / "long.toml"
    scene.write_text(VALID.replace("revolutions = 2", "revolutions = 1000"), encoding="utf-8")
    warm = subprocess.run([sys.executable, "-m", "transient", "run", str(scene), "-o",
                           str(tmp_path / "warm"), "-q"], cwd=REPO, capture_output=True, timeout=600)
    assert warm.returncode == 0, warm.stderr
    size = (tmp_path / "warm" / "long.h5").stat().st_size
    limit = size // 2  # past the probe and the header, short of the whole trajectory
    assert limit > PROBE_BYTES
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run([sys.executable, "-m", "transient", "run", str(scene), "-o", str(out), "-q"],
                       cwd=REPO, capture_output=True, text=True, timeout=300,
                       preexec_fn=full_disk(limit))
    part = out / ".long.h5.part"
    assert r.returncode == 1, r.stderr
    assert r.stderr.count("\n") == 1, r.stderr
    assert r.stderr.startswith(f"transient: writing {part} failed (")
    assert r.stderr.endswith(f"is the disk full?; the partial file {part} holds the run up to "
                             f"its last checkpoint\n")
    assert list(out.iterdir()) == [part]
