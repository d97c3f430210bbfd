"""The ``transient`` command end to end (docs/guide/cli.md): run, check, info, plot, kinematics.

Every run is small (a few revolutions, coarse output) and goes through ``transient.cli.main``
in-process, so the numba cache is loaded once for the whole file. One test starts
``python -m transient`` in a subprocess.

Some tests here were written against bugs they found (now fixed); they keep those fixed.
"""
from __future__ import annotations

import ctypes
import datetime as dt
import math
import os
import subprocess
import sys
from dataclasses import fields
from pathlib import Path

import h5py
import numpy as np
import pytest
from scene_texts import SMALL
from terminal import terminal_run

import transient
import transient.core.stepper as stepper
import transient.core.stepper.io as sio
import transient.run as sim
from transient.cli import KERNELS_NOTICE, main
from transient.scene import to_toml

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"

# The Gots 3-cylinder diesel (cases/gots_diesel_spinup.toml) for 4 revolutions, coarse output.
SPINUP = """\
[scene]
name = "small-spinup"
description = "Gots diesel, 4 revolutions from 1000 rpm (CLI test)"

[mechanism]
type = "crank-slider"
crank_radius_mm = 47
rod_length_mm = 148
bore_mm = 88
piston_mass = 1.520
crank_mass = 0.912
strokes = 4
cylinders = 3
firing_order = [1, 2, 3]
firing_deg = [360, 600, 120]

[mechanism.rod]
model = "two-mass"
mass = 1.752
cg_from_pin_mm = 107.3

[gas]
model = "mixed-cycle"
p0_MPa = 0.1
compression_ratio = 18
p_a_MPa = 0.1436
n1 = 1.368
p_z_MPa = 10.5
rho = 1.671
n2 = 1.228
p_intake_MPa = 0.165
p_exhaust_MPa = 0.182

[inertia]
shaft = 0.02
flywheel = 0.15

[load]
fan = 9.692e-4

[initial]
omega_rpm = 1000

[run]
revolutions = 4

[solver]
rtol = 1e-6
atol = 1e-8

[output]
samples_per_rev = 24
"""

# One cylinder coasting with no forces (cases/coasting_single.toml, shorter and coarser).
COASTING = """\
[scene]
name = "small-coasting"
description = "single cylinder coasting"

[mechanism]
type = "crank-slider"
crank_radius_mm = 47
rod_length_mm = 148
bore_mm = 88
piston_mass = 1.520
crank_mass = 0.912

[mechanism.rod]
model = "rigid"
mass = 1.752
cg_from_pin_mm = 107.3
inertia_cg = 5e-3

[inertia]
shaft = 0.02

[initial]
omega_rpm = 1000

[run]
revolutions = {revolutions}

[solver]
rtol = 1e-8
atol = 1e-10

[output]
samples_per_rev = {samples}
"""

# A measured-style indicator table with a jump and a kink, an offset V-twin, starter from rest.
TABLE_STARTER = """\
[scene]
name = "table-starter"
description = "V-twin, offset, pressure table with a jump at 360 deg, starter from rest"

[mechanism]
type = "crank-slider"
crank_radius_mm = 40
rod_length_mm = 140
offset_mm = 5
bore_mm = 80
piston_mass = 1.1
strokes = 4
cylinders = 2
firing_deg = [0, 270]
bank_deg = [0, 90]
throws_deg = [0, 180]   # (one throw per cylinder)

[mechanism.rod]
model = "rigid"
mass = 1.3
cg_from_pin_mm = 95
inertia_cg = 4e-3

[gas]
model = "table"
p0_bar = 1
phi_deg = [0, 180, 300, 360, 360, 400, 540, 720]
p_bar = [1, 1, 25, 60, 80, 40, 3, 1]
corners_deg = [360, 540]
interpolation = "linear"

[inertia]
shaft = 0.03

[load]
torque = 2
linear = 0.01

[starter]
torque = 40
noload_speed_rpm = 400
cutout_speed_rpm = 300

[run]
t_end = 0.05
revolutions = 3

[output]
samples_per_rev = 36
dt = 1e-3
"""

PRESCRIBED_TABLE = """\
[scene]
name = "prescribed-ramp"

[mechanism]
type = "crank-slider"
crank_radius_mm = 47
rod_length_mm = 148
bore_mm = 88
piston_mass = 1.520
strokes = 2

[mechanism.rod]
mass = 1.752
cg_from_pin_mm = 107.3

[run]
mode = "prescribed-speed"
time = [0.0, 0.02, 0.05]
speed_table_rpm = [1000, 1500, 1600]
revolutions = 100

[output]
samples_per_rev = 36
"""


def prescribed_4400() -> str:
    """cases/gots_diesel_4400.toml shortened to 2 revolutions (one 4-stroke cycle), coarse."""
    text = (CASES / "gots_diesel_4400.toml").read_text()
    for old, new in (("revolutions = 4\n", "revolutions = 2\n"),
                     ("samples_per_rev = 1440\n", "samples_per_rev = 72\n")):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


#: H5D_chunk_index_t's extensible array (H5Dpublic.h; 0 is the 1.8 format's B-tree)
H5D_CHUNK_IDX_EARRAY = 4


def chunk_index_type(dataset) -> int:
    """HDF5's ``H5Dget_chunk_index_type`` of an h5py dataset (h5py does not wrap it), called in
    the libhdf5 this process has loaded (bundled by h5py or the system's)."""
    with open("/proc/self/maps") as maps:
        path = next(p for p in (line.split()[-1] for line in maps)
                    if os.path.basename(p).startswith("libhdf5") and "_hl" not in p)
    index = ctypes.c_int(-1)
    assert ctypes.CDLL(path).H5Dget_chunk_index_type(ctypes.c_int64(dataset.id.id),
                                                     ctypes.byref(index)) >= 0
    return index.value


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# ----------------------------------------------------------------------------------------------
# run


def test_run_writes_result_with_design_layout(tmp_path, capsys):
    scene = write(tmp_path, "spinup", SPINUP)
    out_dir = tmp_path / "res"
    code, out, err = cli(capsys, "run", scene, "-o", out_dir)
    assert (code, err) == (0, "")
    path = out_dir / "spinup.h5"
    assert sorted(p.name for p in out_dir.iterdir()) == ["spinup.h5"]  # no temporary left
    lines = out.splitlines()
    assert lines[0] == f"wrote {path}"
    assert lines[1].startswith("  end: t = ") and "after 4 rev" in lines[1]
    assert lines[2].startswith("  last cycle: mean ω = ")
    assert lines[3].startswith("  steady state: ")
    assert lines[4].startswith("  last cycle: peak |ε| = ") and "½J′ω²" in lines[4]
    assert lines[5].startswith("  solver dop853: ") and "RHS calls" in lines[5]

    with h5py.File(path, "r") as f:
        a = f.attrs
        assert a["creator"] == "transient"
        assert a["version"] == transient.__version__
        assert a["format"] == 1
        assert dt.datetime.fromisoformat(a["created"]).tzinfo is not None
        assert a["scene"] == "small-spinup"
        assert bool(a["complete"]) is True
        # the columns in HDF5's 1.10 format (results.FILE_FORMAT: an extensible array indexes
        # their chunks), the file with the 1.8 superblock, which a killed run leaves readable
        assert f.id.get_create_plist().get_version()[0] == 0
        assert all(chunk_index_type(d) == H5D_CHUNK_IDX_EARRAY for d in f["trajectory"].values())
        assert "toml" in f["scene"]
        toml = f["scene/toml"][()]
        toml = toml.decode() if isinstance(toml, bytes) else toml
        assert toml == to_toml(transient.load_scene(scene))

        traj = f["trajectory"]
        units = {"t": "s", "phi": "rad", "omega": "rad/s", "epsilon": "rad/s^2", "J": "kg m^2",
                 "dJ_dphi": "kg m^2/rad", "M_gas": "N m", "M_load": "N m",
                 "p_1": "Pa", "p_2": "Pa", "p_3": "Pa"}
        for name, unit in units.items():
            assert name in traj, name
            assert traj[name].attrs["unit"] == unit, name
        n = traj["t"].shape[0]
        for name, ds in traj.items():
            assert ds.ndim == 1 and ds.shape[0] == n, name  # one shared sample axis
            assert ds.maxshape == (None,) and ds.chunks is not None, name  # extendable, chunked
            assert ds.compression is not None, name
        t, phi, omega = traj["t"][()], traj["phi"][()], traj["omega"][()]
        # 4 revolutions at 24 samples per revolution, both ends included
        assert n == 4 * 24 + 1
        assert t[0] == 0.0 and np.all(np.diff(t) > 0) and np.all(np.diff(phi) > 0)
        np.testing.assert_allclose(phi[[0, -1]], [0.0, 8 * math.pi], rtol=0, atol=1e-9)
        assert omega[0] == pytest.approx(1000 * math.pi / 30, rel=1e-12)
        assert np.all(np.isfinite(traj["epsilon"][()]))

        s = f["solver"].attrs
        assert {"method", "rtol", "atol", "nfev", "nsteps", "nreject", "wall_s",
                "compile_s"} <= set(s)
        assert s["method"] == "dop853"
        assert (s["rtol"], s["atol"]) == (1e-6, 1e-8)
        assert s["nfev"] > s["nsteps"] > 0 and s["nreject"] >= 0
        assert s["wall_s"] > 0 and s["compile_s"] >= 0
        for name, ds in f["analysis"].items():
            assert "unit" in ds.attrs, name


def test_run_quiet_prints_nothing(tmp_path, capsys):
    scene = write(tmp_path, "spinup", SPINUP)
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path, "-q")
    assert (code, out, err) == (0, "", "")
    assert transient.open_result(tmp_path / "spinup.h5").complete


def test_run_in_a_terminal_says_kernels_load_until_the_first_block(tmp_path):
    """The progress bar names the kernels' loading (on a first run, their compiling, minutes)
    until the run's first block, then only the scene; nothing of it goes to stdout."""
    scene = write(tmp_path, "spinup", SPINUP)
    code, out, terminal = terminal_run(["run", str(scene), "-o", str(tmp_path)])
    assert code == 0, terminal
    assert out.splitlines()[0] == f"wrote {tmp_path / 'spinup.h5'}"
    notice = terminal.find(f"small-spinup ({KERNELS_NOTICE})")
    plain = terminal.find("small-spinup: ", notice)
    assert 0 <= notice < plain, terminal
    assert "‰" in terminal[plain:], terminal


def test_run_never_overwrites_without_force(tmp_path, capsys):
    scene = write(tmp_path, "coast", COASTING.format(revolutions=2, samples=12))
    out_dir = tmp_path / "res"
    path = out_dir / "coast.h5"
    assert cli(capsys, "run", scene, "-o", out_dir)[0] == 0
    before = path.read_bytes()
    mtime = path.stat().st_mtime_ns
    os.utime(path, ns=(mtime - 10**9, mtime - 10**9))  # so that any rewrite shows in the mtime
    mtime = path.stat().st_mtime_ns

    code, out, err = cli(capsys, "run", scene, "-o", out_dir)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and str(path) in err and "--force" in err
    assert "Traceback" not in err
    assert path.read_bytes() == before and path.stat().st_mtime_ns == mtime
    assert sorted(p.name for p in out_dir.iterdir()) == ["coast.h5"]

    code, out, err = cli(capsys, "run", scene, "-o", out_dir, "--force")
    assert (code, err) == (0, "")
    assert out.startswith(f"wrote {path}\n")
    assert path.stat().st_mtime_ns > mtime
    assert transient.open_result(path).complete
    assert sorted(p.name for p in out_dir.iterdir()) == ["coast.h5"]


def test_run_default_output_folder_is_results(tmp_path, capsys, monkeypatch):
    scene = write(tmp_path, "coast", COASTING.format(revolutions=1, samples=8))
    monkeypatch.chdir(tmp_path)
    assert cli(capsys, "run", "coast.toml", "-q")[0] == 0
    assert (tmp_path / "results" / "coast.h5").is_file()
    assert scene.is_file()


# ----------------------------------------------------------------------------------------------
# /scene/toml round trip


def assert_same_scene(a, b):
    """Dataclass equality, with the first differing field named when it fails."""
    if a == b:
        return
    for section in fields(a):
        x, y = getattr(a, section.name), getattr(b, section.name)
        if x != y and hasattr(x, "__dataclass_fields__"):
            for f in fields(x):
                assert getattr(x, f.name) == getattr(y, f.name), f"{section.name}.{f.name}"
        assert x == y, section.name
    raise AssertionError("scenes differ")  # pragma: no cover


@pytest.mark.parametrize("name, text", [
    ("spinup", SPINUP),
    ("coast", COASTING.format(revolutions=1, samples=8)),
    ("table_starter", TABLE_STARTER),
    ("prescribed_4400", prescribed_4400()),
    ("prescribed_ramp", PRESCRIBED_TABLE),
])
def test_scene_toml_round_trips(tmp_path, capsys, name, text):
    """``open_result(path).scene()`` rebuilds exactly the scene that ran.

    The resolved TOML is SI without suffixes and writes floats with ``repr``, so values converted
    from mm, deg, rpm or bar come back bit for bit and plain ``==`` on the dataclasses holds.
    """
    scene_path = write(tmp_path, name, text)
    original = transient.load_scene(scene_path)
    code, out, err = cli(capsys, "run", scene_path, "-o", tmp_path / "res", "-q")
    result = transient.open_result(tmp_path / "res" / f"{name}.h5")
    assert result.complete
    # (the V-twin's starter is weaker than its gas torque at rest: the shaft is driven backwards,
    # which the run says; the scene round-trips all the same)
    assert (code, result.status) == ((1, "reversed") if name == "table_starter" else
                                     (0, "finished"))
    assert len(err.splitlines()) == code
    assert_same_scene(result.scene(), original)


@pytest.mark.parametrize("case", sorted(CASES.glob("*.toml")), ids=lambda p: p.stem)
def test_resolved_toml_of_every_case_round_trips(case):
    """Every committed scene survives ``to_toml`` → ``load_scene`` (no run needed)."""
    scene = transient.load_scene(case)
    again = transient.load_scene(case.with_name("resolved.toml"), text=to_toml(scene))
    assert_same_scene(again, scene)
    assert to_toml(again) == to_toml(scene)


def test_scene_toml_round_trips_with_a_multiline_description(tmp_path, capsys):
    text = COASTING.format(revolutions=1, samples=8).replace(
        'description = "single cylinder coasting"',
        'description = """single cylinder\ncoasting\twith a tab"""')
    scene_path = write(tmp_path, "multiline", text)
    original = transient.load_scene(scene_path)
    assert "\n" in original.description
    assert cli(capsys, "run", scene_path, "-o", tmp_path, "-q")[0] == 0
    assert_same_scene(transient.open_result(tmp_path / "multiline.h5").scene(), original)


# ----------------------------------------------------------------------------------------------
# info, plot, kinematics


def test_info_prints_the_summary(tmp_path, capsys):
    scene = write(tmp_path, "spinup", SPINUP)
    assert cli(capsys, "run", scene, "-o", tmp_path, "-q")[0] == 0
    path = tmp_path / "spinup.h5"
    code, out, err = cli(capsys, "info", path)
    assert (code, err) == (0, "")
    lines = out.splitlines()
    assert lines[0].startswith(f"{path}: scene 'small-spinup', transient {transient.__version__}, "
                               f"format 1, created ")
    assert lines[0].endswith("complete = True, status = finished")
    assert lines[1].startswith(f"  trajectory: {4 * 24 + 1} samples; ")
    for column in ("t [s]", "phi [rad]", "omega [rad/s]", "epsilon [rad/s^2]", "p_3 [Pa]"):
        assert column in lines[1]
    assert any(line.startswith("  solver dop853: rtol 1e-06, atol 1e-08, ") for line in lines)
    for key in ("final_omega", "final_t", "revolutions", "mean_omega_last_cycle",
                "delta_last_cycle", "steady_state_t"):
        assert any(line.startswith(f"  {key} = ") for line in lines), key
    assert "  revolutions = 4 1" in lines


def test_info_rejects_a_file_that_is_not_a_result(tmp_path, capsys):
    bogus = tmp_path / "bogus.h5"
    bogus.write_text("not hdf5\n")
    code, out, err = cli(capsys, "info", bogus)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith(f"{bogus}: ")
    code, out, err = cli(capsys, "info", tmp_path / "missing.h5")
    assert code == 2 and len(err.splitlines()) == 1 and "missing.h5" in err


def test_plot_writes_png_figures(tmp_path, capsys):
    scene = write(tmp_path, "spinup", SPINUP)
    assert cli(capsys, "run", scene, "-o", tmp_path, "-q")[0] == 0
    figures = tmp_path / "figures"
    code, out, err = cli(capsys, "plot", tmp_path / "spinup.h5", "-o", figures)
    assert (code, err) == (0, "")
    names = ["spinup_speed.png", "spinup_torques.png", "spinup_speed_cycle.png",
             "spinup_inertia.png", "spinup_cylinder_torques.png", "spinup_indicator.png"]
    assert out.splitlines() == [f"wrote {figures / n}" for n in names]
    for n in names:
        data = (figures / n).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000, n


def test_plot_defaults_to_the_result_folder_and_skips_gas_figures_without_gas(tmp_path, capsys):
    scene = write(tmp_path, "coast", COASTING.format(revolutions=2, samples=12))
    assert cli(capsys, "run", scene, "-o", tmp_path / "res", "-q")[0] == 0
    code, out, err = cli(capsys, "plot", tmp_path / "res" / "coast.h5")
    assert (code, err) == (0, "")
    assert sorted(p.name for p in (tmp_path / "res").glob("*.png")) == [
        "coast_inertia.png", "coast_speed.png", "coast_speed_cycle.png", "coast_torques.png"]


def test_kinematics_writes_csv(tmp_path, capsys):
    scene = write(tmp_path, "spinup", SPINUP)
    csv = tmp_path / "x.csv"
    code, out, err = cli(capsys, "kinematics", scene, "-o", csv, "--points", 49)
    assert (code, err) == (0, "")
    assert out == f"wrote {csv}\n"
    header, *rows = csv.read_text().splitlines()
    names = header.split(",")
    for column in ("phi_deg", "J", "dJ_dphi", "s_1", "u_1", "du_1", "s_3", "u_3"):
        assert column in names, column
    assert len(rows) == 49
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert data.shape == (49, len(names))
    col = {n: data[:, j] for j, n in enumerate(names)}
    np.testing.assert_allclose(col["phi_deg"], np.linspace(0.0, 720.0, 49), atol=1e-9)
    assert np.all(col["J"] > 0)
    # Periodic over the cycle: the last row repeats the first.
    np.testing.assert_allclose(data[-1, 1:], data[0, 1:], rtol=1e-9, atol=1e-12)


def test_kinematics_to_stdout(tmp_path, capsys):
    scene = write(tmp_path, "coast", COASTING.format(revolutions=1, samples=8))
    code, out, err = cli(capsys, "kinematics", scene, "--points", 7)
    assert (code, err) == (0, "")
    lines = out.splitlines()
    assert lines[0].split(",")[:6] == ["phi_deg", "J", "J_mechanism", "dJ_dphi", "s_1", "u_1"]
    assert len(lines) == 1 + 7


def test_kinematics_J_is_the_result_J(tmp_path, capsys):
    """One vocabulary: the J of ``kinematics`` is the J a run writes (the constant inertias
    included), at the same angles."""
    scene = write(tmp_path, "coast", COASTING.format(revolutions=1, samples=8))
    code, _, err = cli(capsys, "kinematics", scene, "-o", tmp_path / "k.csv", "--points", 9)
    assert code == 0, err
    k = np.genfromtxt(tmp_path / "k.csv", delimiter=",", names=True)
    assert cli(capsys, "run", scene, "-o", tmp_path, "-q")[0] == 0
    res = transient.open_result(tmp_path / "coast.h5")
    J = np.interp(np.radians(k["phi_deg"]), res.trajectory["phi"], res.trajectory["J"])
    inside = np.radians(k["phi_deg"]) <= res.trajectory["phi"][-1]
    at = np.isin(np.round(np.radians(k["phi_deg"]), 12), np.round(res.trajectory["phi"], 12))
    assert np.count_nonzero(inside & at) >= 3
    # (the CSV holds 12 significant digits)
    np.testing.assert_allclose(J[inside & at], k["J"][inside & at], rtol=1e-11)
    total = transient.load_scene(scene).inertia.total
    assert total > 0 and np.allclose(k["J"] - k["J_mechanism"], total, rtol=1e-9)


# ----------------------------------------------------------------------------------------------
# prescribed speed


def test_prescribed_speed_run_writes_drive_torque(tmp_path, capsys):
    scene = write(tmp_path, "gots_4400", prescribed_4400())
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert (code, err) == (0, "")
    assert "mean drive torque required over the last cycle: " in out
    res = transient.open_result(tmp_path / "gots_4400.h5")
    assert res.complete
    assert res.units["M_drive"] == "N m"
    tr = res.trajectory
    n = 2 * 72 + 1
    assert all(v.size == n for v in tr.values())
    assert np.all(np.isfinite(tr["M_drive"]))
    np.testing.assert_allclose(tr["omega"], 4400 * math.pi / 30, rtol=1e-12)
    assert res.solver["method"] == "prescribed"
    # At constant speed the inertia moment −½J′ω² has zero cycle mean, so the drive torque
    # cancels the gas torque on average; the engine makes power, so the drive needed is < 0.
    cycle = 4 * math.pi
    mean_drive = np.trapezoid(tr["M_drive"], tr["phi"]) / cycle
    mean_gas = np.trapezoid(tr["M_gas"], tr["phi"]) / cycle
    assert mean_drive < 0
    assert mean_drive == pytest.approx(-mean_gas, rel=1e-9)
    # the summary's mean is the drive's work over the cycle (the work columns are integrated to
    # the solver's tolerance: tests/validation/test_prescribed_work.py), which the trapezoid
    # over the 5° samples misses by the pressure's corners between them
    W_drive = tr["W_drive"][-1] - tr["W_drive"][0]
    assert res.analysis["mean_drive_torque_last_cycle"][0] == pytest.approx(W_drive / cycle,
                                                                           rel=1e-12)
    assert W_drive / cycle == pytest.approx(mean_drive, rel=1e-2)
    kinetic = 0.5 * tr["J"] * tr["omega"] ** 2
    balance = tr["W_drive"] + tr["W_gas"] + tr["W_load"] - (kinetic - kinetic[0])
    assert np.abs(balance).max() <= 1e-9 * np.abs(tr["W_gas"]).max()


# ----------------------------------------------------------------------------------------------
# interrupted run


def interrupt_advance(monkeypatch, on_chunk: int):
    """Make ``advance`` raise KeyboardInterrupt on the run's ``on_chunk``-th chunk.

    ``run._compile`` calls ``advance`` once first to warm the JIT up (with a small output
    buffer of its own); only calls with the run's buffer of ``BUFFER_ROWS`` rows are counted.
    Returns the list of output rows each completed chunk produced.
    """
    real = stepper.advance
    rows: list[int] = []
    calls = [0]

    def advance(m, extras, tab, cfg, bp, y, fst, ist, outbuf, evbuf, work):
        if outbuf.shape[0] == sim.BUFFER_ROWS:
            calls[0] += 1
            if calls[0] == on_chunk:
                raise KeyboardInterrupt
        status = real(m, extras, tab, cfg, bp, y, fst, ist, outbuf, evbuf, work)
        if outbuf.shape[0] == sim.BUFFER_ROWS:
            rows.append(int(ist[sio.I_NOUT]))
        return status

    monkeypatch.setattr(stepper, "advance", advance)
    return rows


def test_interrupted_run_keeps_the_partial_result(tmp_path, capsys, monkeypatch):
    # 20 revolutions at 1000 samples each: 20001 rows, three chunks of at most BUFFER_ROWS.
    scene = write(tmp_path, "long", COASTING.format(revolutions=20, samples=1000))
    rows = interrupt_advance(monkeypatch, on_chunk=2)
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert code == 1
    path = tmp_path / "long.h5"
    assert len(err.splitlines()) == 1 and "interrupted" in err and str(path) in err
    assert "Traceback" not in err
    assert len(rows) == 1 and 0 < rows[0] < 20001

    assert sorted(p.name for p in tmp_path.glob("*.h5*")) == ["long.h5"]
    res = transient.open_result(path)
    assert res.complete is False and res.status == "interrupted"
    assert "interrupted" in res.attrs["message"]
    tr = res.trajectory
    assert tr["t"].size == rows[0]
    assert all(v.size == rows[0] for v in tr.values())
    assert np.all(np.diff(tr["phi"]) > 0)
    step = 2 * math.pi / 1000
    np.testing.assert_allclose(tr["phi"], step * np.arange(rows[0]), rtol=0, atol=1e-9)
    assert tr["phi"][-1] < 20 * 2 * math.pi
    # what was computed is the same as in an uninterrupted run
    monkeypatch.undo()
    assert cli(capsys, "run", scene, "-o", tmp_path / "full", "-q")[0] == 0
    full = transient.open_result(tmp_path / "full" / "long.h5").trajectory
    for name in ("t", "phi", "omega", "epsilon"):
        np.testing.assert_array_equal(tr[name], full[name][: rows[0]], err_msg=name)
    # info still works on the partial result
    code, out, err = cli(capsys, "info", path)
    assert code == 0 and "complete = False" in out and "message: interrupted" in out


def test_interrupt_during_the_first_chunk(tmp_path, capsys, monkeypatch):
    scene = write(tmp_path, "coast", COASTING.format(revolutions=2, samples=12))
    interrupt_advance(monkeypatch, on_chunk=1)
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert code == 1 and "interrupted" in err
    assert transient.open_result(tmp_path / "coast.h5").complete is False


# ----------------------------------------------------------------------------------------------
# python -m transient


def test_python_m_transient_check():
    proc = subprocess.run([sys.executable, "-m", "transient", "check",
                           "cases/coasting_single.toml"],
                          cwd=REPO, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    assert proc.stdout.startswith("cases/coasting_single.toml: ok (coasting-single: CrankSlider, "
                                  "1 cylinder(s), gas none, run dynamic)")


# The probe run in a fresh interpreter: the command's exit code, whether numba's compiler
# registries (numba.np.arraymath, which imports scipy.linalg) and scipy's integrators (which the
# Wiebe cycles need unless read from their file cache) were loaded, and then a function compiled
# in the same process afterwards (numba's compiler loads the registries itself).
_WARM_PROBE = """
import sys
from transient.cli import main
code = main(sys.argv[1:])
print(code, 'numba.np.arraymath' in sys.modules, 'scipy.linalg' in sys.modules,
      'scipy.integrate' in sys.modules)
import numba, numpy as np
print(numba.njit(lambda n: np.sum(np.arange(n) ** 2))(4))
"""


@pytest.mark.parametrize("case", ["gots_diesel_governed", "swash_plate_4cyl", "gots_diesel_wiebe"])
def test_warm_run_loads_no_compiler_registries(tmp_path, capsys, case):
    """With numba's cache warm, a new process runs a scene without loading numba's compiler
    registries or scipy.linalg (``core.jit._RegistryFreeCache``, README *Start-up*), nor, for
    the Wiebe case, scipy's integrators (its cycles read from ``forces.wiebe_cache``, which this
    process's run filled if they were not there yet), and its result is bit-identical to this
    process's run, in which they are loaded; a function compiled after it in that process works.
    The diesel's stepper allocates (numba's runtime), its pairs and governor take every event
    path."""
    scene = str(CASES / f"{case}.toml")
    # this process: every function the run needs is compiled or loaded, hence in the cache
    assert cli(capsys, "run", scene, "-q", "-o", str(tmp_path / "here"))[0] == 0
    proc = subprocess.run([sys.executable, "-c", _WARM_PROBE, "run", scene, "-q", "-o",
                           str(tmp_path / "fresh")], cwd=REPO, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["0", "False", "False", "False", "14"], proc.stdout + proc.stderr
    with (h5py.File(tmp_path / "here" / f"{case}.h5") as a,
          h5py.File(tmp_path / "fresh" / f"{case}.h5") as b):
        names = list(a["trajectory"])
        assert names == list(b["trajectory"]) and len(names) > 10
        for name in names:
            np.testing.assert_array_equal(a["trajectory"][name][()], b["trajectory"][name][()],
                                          err_msg=name)


# ----------------------------------------------------------------------------------------------
# non-ideal pairs (issue 4)

PAIRS = """
[friction]
policy = "power-flow"

[[friction.pairs]]
name = "main bearings"
between = ["shaft", "crank"]
eta_forward = 0.985
eta_backward = 0.98

[[friction.pairs]]
name = "crankpins"
between = ["crank", "rod"]
eta_forward = 0.98
eta_backward = 0.975
"""


def test_run_with_pairs_writes_pair_columns_and_mode_events(tmp_path, capsys):
    scene = write(tmp_path, "pairs", SPINUP + PAIRS)
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert (code, err) == (0, "")
    res = transient.open_result(tmp_path / "pairs.h5")
    assert res.complete
    for k in (1, 2):
        assert {f"S_{k}": "N m", f"eta_{k}": "1", f"P_loss_{k}": "W",
                f"W_loss_{k}": "J"}.items() <= res.units.items()
    assert {"W_gas": "J", "W_load": "J", "W_starter": "J"}.items() <= res.units.items()
    tr = res.trajectory
    assert set(np.unique(tr["eta_1"])) <= {0.985, 1 / 0.98}
    assert res.events["pair_mode"]["t"].size > 0
    assert res.solver["mode_switches"] == res.events["pair_mode"]["t"].size
    assert res.scene().friction.pairs[1].name == "crankpins"


def test_prescribed_run_with_pairs_reports_the_efficiency(tmp_path, capsys):
    """At a prescribed constant speed every cycle is steady: run and info print η_mech in both
    forms and each pair's budget; the values are stored under /analysis with units."""
    scene = write(tmp_path, "gots_4400_pairs", prescribed_4400() + PAIRS)
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert (code, err) == (0, "")
    assert "mechanical efficiency over 1 steady cycle(s): η = W_out/W_in = " in out
    assert "(30) as printed, time average of P_out/P_in" in out
    assert "pair 2 (crankpins): loss " in out and "circulated" in out
    assert "mean effective pressures (V_d = 1.71516 L): imep " in out
    assert "pair 2 (crankpins) loses most" in out  # (its efficiencies are the lower ones)
    res = transient.open_result(tmp_path / "gots_4400_pairs.h5")
    eta, unit = res.analysis["eta_mech_work"]
    assert unit == "1" and 0.85 < eta < 0.98
    losses = res.analysis["W_loss_1_per_cycle"][0] + res.analysis["W_loss_2_per_cycle"][0]
    assert eta == pytest.approx(1 - losses / res.analysis["W_in_per_cycle"][0], rel=1e-9)
    for name in ("imep", "bmep", "fmep", "fmep_1", "fmep_2"):
        assert res.analysis[name][1] == "Pa"
    assert res.analysis["displacement"][1] == "m^3"
    assert eta == pytest.approx(res.analysis["bmep"][0] / res.analysis["imep"][0], rel=1e-12)
    code, out, err = cli(capsys, "info", tmp_path / "gots_4400_pairs.h5")
    assert code == 0 and "mechanical efficiency over 1 steady cycle(s)" in out
    assert "pair 1 (main bearings): loss " in out
    code, out, err = cli(capsys, "plot", tmp_path / "gots_4400_pairs.h5", "-o", tmp_path)
    assert code == 0 and (tmp_path / "gots_4400_pairs_budget.png").stat().st_size > 10_000


def test_efficiency_study_writes_table_and_plot(tmp_path, capsys):
    scene = CASES / "gots_diesel_friction.toml"
    code, out, err = cli(capsys, "efficiency", scene, "--rpm", "1000,5000", "--fuel", "1,0.5",
                         "--policies", "power-flow,paper", "--samples-per-rev", "360",
                         "-o", tmp_path)
    assert (code, err) == (0, "")
    csv = (tmp_path / "gots_diesel_friction_efficiency.csv").read_text().splitlines()
    header = csv[0].split(",")
    assert header[:4] == ["policy", "fuel", "rpm", "eta_mech_work"]
    rows = [dict(zip(header, line.split(","))) for line in csv[1:]]
    assert len(rows) == 8
    eta = {(r["policy"], float(r["fuel"]), float(r["rpm"])): float(r["eta_mech_work"])
           for r in rows}
    # The inertia power circulating through the pairs lowers η_mech at high speed.
    assert eta[("power-flow", 1.0, 5000.0)] < eta[("power-flow", 1.0, 1000.0)] - 0.01
    assert (tmp_path / "gots_diesel_friction_efficiency.png").stat().st_size > 10_000
    assert "wrote" in out and "power-flow" in out
    # the friction budget per pair over speed, and η_mech over speed × load
    for figure in ("friction_budget", "efficiency_map"):
        assert (tmp_path / f"gots_diesel_friction_{figure}.png").stat().st_size > 10_000
    fmep = {(r["policy"], float(r["fuel"]), float(r["rpm"])): float(r["fmep"]) for r in rows}
    assert all(float(r["fmep"]) == pytest.approx(float(r["fmep_1"]) + float(r["fmep_2"]),
                                                 rel=1e-9) for r in rows)
    assert fmep[("power-flow", 1.0, 5000.0)] > fmep[("power-flow", 1.0, 1000.0)]


def test_efficiency_study_and_budget_with_reaction_friction(tmp_path, capsys):
    """The budget reads reaction pairs as constant-η ones: `transient efficiency` writes every
    point's per-pair FMEP (summing to the total), the budget chart and the η map; η_mech falls
    with speed and load; `transient run` at a prescribed speed names the pistons as the pair
    that loses most, stores the budget under /analysis with each cylinder's share, and `transient
    plot` draws it."""
    scene = CASES / "gots_diesel_reaction_friction.toml"
    code, out, err = cli(capsys, "efficiency", scene, "--rpm", "1000,4400", "--fuel", "1,0.5",
                         "--samples-per-rev", "360", "-o", tmp_path)
    assert (code, err) == (0, "")
    csv = (tmp_path / "gots_diesel_reaction_friction_efficiency.csv").read_text().splitlines()
    header = csv[0].split(",")
    rows = {(float(r["fuel"]), float(r["rpm"])): r for r in
            (dict(zip(header, line.split(","))) for line in csv[1:])}
    assert len(rows) == 4
    for r in rows.values():
        assert float(r["fmep"]) == pytest.approx(sum(float(r[f"fmep_{k}"]) for k in range(1, 5)),
                                                 rel=1e-9)
    eta = {key: float(r["eta_mech_work"]) for key, r in rows.items()}
    assert eta[(1.0, 4400.0)] < eta[(1.0, 1000.0)] and eta[(0.5, 4400.0)] < eta[(1.0, 4400.0)]
    for figure in ("efficiency", "friction_budget", "efficiency_map"):
        assert (tmp_path / f"gots_diesel_reaction_friction_{figure}.png").stat().st_size > 10_000
    text = scene.read_text().replace('[run]\nrevolutions = 600',
                                     '[run]\nmode = "prescribed-speed"\nspeed_rpm = 4400\n'
                                     'revolutions = 2')
    assert text != scene.read_text()
    path = write(tmp_path, "reaction_4400", text)
    code, out, err = cli(capsys, "run", path, "-o", tmp_path)
    assert (code, err) == (0, "")
    assert "pair 4 (pistons) loses most" in out
    assert "fmep per cylinder, on its own swept volume: 1 " in out
    res = transient.open_result(tmp_path / "reaction_4400.h5")
    assert res.analysis["fmep_4"][1] == "Pa" and res.analysis["fmep_4"][0] > 0.0
    # cylinders that work alike at a constant speed: each one's FMEP is the engine's
    for c in (1, 2, 3):
        assert res.analysis[f"fmep_cyl{c}"][0] == pytest.approx(res.analysis["fmep"][0], rel=2e-3)
    code, out, err = cli(capsys, "plot", tmp_path / "reaction_4400.h5", "-o", tmp_path)
    assert (code, err) == (0, "")
    assert (tmp_path / "reaction_4400_budget.png").stat().st_size > 10_000


def study_rows(path) -> dict:
    """An efficiency study's CSV, its rows by speed [rpm]."""
    import csv

    with open(path, newline="", encoding="utf-8") as fh:
        return {float(r["rpm"]): r for r in csv.DictReader(fh)}


def test_efficiency_study_holds_the_fuel_without_the_scenes_governor(tmp_path, capsys):
    """The swash-plate engine's droop governor cuts the fuel to 0 at 60 rad/s (573 rpm); at
    --fuel 1 the study leaves it out and says so: every speed gets the full pulse, whose work per
    cycle does not depend on the speed (the force is a function of angle), and the rows are
    those of the same scene with its [governor] table deleted."""
    scene = CASES / "swash_plate_4cyl_reaction_friction.toml"
    code, out, err = cli(capsys, "efficiency", scene, "--rpm", "300,600", "--fuel", "1",
                         "-o", tmp_path / "governed")
    assert (code, err) == (0, "")
    assert out.startswith("the scene's droop governor is left out: each point holds its speed "
                          "and its fuel (--fuel)\n")
    rows = study_rows(tmp_path / "governed" / "swash_plate_4cyl_reaction_friction_efficiency.csv")
    assert float(rows[300.0]["W_in_per_cycle"]) > 0.0
    assert float(rows[600.0]["W_in_per_cycle"]) == pytest.approx(
        float(rows[300.0]["W_in_per_cycle"]), rel=1e-9)
    assert all(0.9 < float(r["eta_mech_work"]) < 1.0 and r["note"] == "" for r in rows.values())
    text = scene.read_text()
    ungoverned = write(tmp_path, "ungoverned", text[:text.index("[governor]")]
                       + text[text.index("[initial]"):])
    code, out, err = cli(capsys, "efficiency", ungoverned, "--rpm", "300,600", "--fuel", "1",
                         "-o", tmp_path)
    assert (code, err) == (0, "") and "governor" not in out
    assert study_rows(tmp_path / "ungoverned_efficiency.csv") == rows


def test_a_nan_in_the_efficiency_study_comes_with_its_reason(tmp_path, capsys):
    """A cylinder with no force on its piston (a trapezoid pulse of amplitude 0: a compressor
    unloaded, its suction valve held open): no work comes in, neither from the gas nor from the
    drive, η_mech = W_out/W_in and (30) as printed are not numbers, and the note says why, in
    the CSV (quoted: it holds commas) and under the table."""
    text = SMALL.replace("crank_mass = 0.912", "crank_mass = 0.912\nstrokes = 2") + (
        '\n[gas]\nmodel = "trapezoid"\namplitude = 0.0\nramp_deg = 30\nduration_deg = 180\n')
    code, out, err = cli(capsys, "efficiency", write(tmp_path, "unloaded", text), "--rpm", "1000",
                         "--fuel", "1", "-o", tmp_path)
    assert (code, err) == (0, "")
    [row] = study_rows(tmp_path / "unloaded_efficiency.csv").values()
    assert float(row["W_in_per_cycle"]) == 0.0 and math.isnan(float(row["eta_mech_work"]))
    no_work = "no work in over the steady cycles (W_in = 0 J per cycle)"
    assert row["note"] == f"eta_mech_work: {no_work}; eta_mech_printed: {no_work}"
    assert f"  NaN at 1000 rpm, fuel 1 (power-flow): {row['note']}\n" in out


def test_efficiency_study_refuses_a_figure_before_the_study(tmp_path, capsys, monkeypatch):
    """A figure that exists is refused (exit 2) before any point is run, not after the study."""
    import transient.study.efficiency as study

    (tmp_path / "gots_diesel_friction_efficiency_map.png").write_bytes(b"keep")
    monkeypatch.setattr(study, "prescribed", lambda *a, **k: pytest.fail("the study ran"))
    code, out, err = cli(capsys, "efficiency", CASES / "gots_diesel_friction.toml", "--rpm",
                         "1000,5000", "--fuel", "1,0.5", "-o", tmp_path)
    assert code == 2 and "efficiency_map.png: exists; use --force" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gots_diesel_friction_efficiency_map.png"]


@pytest.mark.parametrize("argv, key", [
    (("--rpm", "-100"), "--rpm"), (("--rpm", "abc"), "--rpm"), (("--fuel", "1.5"), "--fuel"),
    (("--fuel", "0"), "--fuel"), (("--policies", "coulomb"), "--policies"),
    (("--samples-per-rev", "10"), "--samples-per-rev")])
def test_efficiency_study_rejects_bad_options(tmp_path, capsys, argv, key):
    code, out, err = cli(capsys, "efficiency", CASES / "gots_diesel_friction.toml", *argv,
                         "-o", tmp_path)
    assert code == 2 and out == "" and key in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


# ----------------------------------------------------------------------------------------------
# bounded memory and the benchmark harness (issue 5)


def test_long_runs_stream_events_and_summarise_the_tail(tmp_path, capsys, monkeypatch):
    """Events go to the file block by block (not gathered in memory), and the end-of-run summary
    reads back only the last ``SUMMARY_SAMPLES`` samples: here 30 of the 97, and the summary of
    the end of the run is the same."""
    scene = write(tmp_path, "pairs", SPINUP + PAIRS)
    full = sim.integrate(transient.load_scene(scene))
    monkeypatch.setattr(sim, "SUMMARY_SAMPLES", 30)
    code, out, err = cli(capsys, "run", scene, "-o", tmp_path)
    assert (code, err) == (0, "")
    res = transient.open_result(tmp_path / "pairs.h5")
    assert res.trajectory["t"].size == 97
    for name, rows in full.events.items():
        np.testing.assert_array_equal(res.events[name]["t"], rows[:, 0])
        np.testing.assert_array_equal(res.events[name]["phi"], rows[:, 1])
    assert res.analysis["final_omega"][0] == full.trajectory["omega"][-1]
    assert res.analysis["revolutions"][0] == pytest.approx(4.0, rel=1e-12)


@pytest.mark.slow  # (the benchmark's runs, its reference included)
def test_bench_quick_writes_a_consistent_record(tmp_path):
    """The harness end to end on 3 revolutions (CI's smoke test: outputs and error measures,
    never timings): every scene and method has rows, errors are finite, the compiled paths'
    phase error falls as the tolerance tightens, and the record's files are written."""
    from transient.verify.bench import ADAPTIVE, BENCH_SCENES, COLUMNS, FIXED, run_bench

    # (the baseline's budget far above what 3 revolutions take, so that a loaded machine does
    # not drop its rows: the test checks outputs, not timings)
    rows = run_bench(BENCH_SCENES, revolutions=3.0, tolerances=(1e-4, 1e-8), repeat=1,
                     out=tmp_path, baseline_budget=600.0, baseline_tolerances=(1e-4,),
                     progress=lambda line: None, steps_per_rev=(16, 256))
    for scene in BENCH_SCENES:
        methods = {r["method"] for r in rows if r["scene"] == scene}
        assert {*ADAPTIVE, *FIXED, "solve_ivp RK45 (numpy RHS)",
                "solve_ivp DOP853 (numpy RHS)"} <= methods
        for m in ADAPTIVE:
            err = {r["rtol"]: r["phase_err_rad"] for r in rows
                   if r["scene"] == scene and r["method"] == m}
            # (over 3 revolutions a smooth scene may be resolved to ~1e-9 rad at both)
            assert err[1e-8] < err[1e-4] or max(err.values()) < 1e-7, (scene, m, err)
        for m in FIXED:
            err = {r["step_rad"]: r["phase_err_rad"] for r in rows
                   if r["scene"] == scene and r["method"] == m}
            assert sorted(err) == pytest.approx([2 * np.pi / 256, 2 * np.pi / 16])
            assert min(err, key=err.get) == min(err) or max(err.values()) < 1e-7, (scene, err)
    for r in rows:
        assert set(r) == set(COLUMNS)
        assert all(np.isfinite(r[k]) and r[k] >= 0 for k in ("phase_err_rad", "omega_rel_err",
                                                             "omega_l2_rel_err", "wall_s"))
    names = {p.name for p in tmp_path.iterdir()}
    assert {"work_precision.csv", "work_precision.md"} <= names
    assert {f"work_precision_{s}.png" for s in BENCH_SCENES} <= names
    text = (tmp_path / "work_precision.md").read_text()
    assert all(f"## {s}" in text for s in BENCH_SCENES)

    # the other targets, measured against that record (issue 5): every one has a verdict
    from transient.verify.bench import cyrk_available
    from transient.verify.targets import run_targets, verdicts

    res = run_targets(tmp_path, quick=True, progress=lambda line: None)
    targets = (tmp_path / "targets.md").read_text()
    n_speed = (1 + cyrk_available()) * len(BENCH_SCENES)  # RK45 (and CyRK) on each
    assert len(res["speed"]) == n_speed
    assert {o["scene"] for o in res["overhead"]} == set(BENCH_SCENES)
    for o in res["overhead"]:
        assert o["nfev"] > 0 and o["wall_s"] > 0 and o["call_chained_s"] > 0
    assert [s["revolutions"] for s in res["scale"]] == [10.0, 100.0]
    assert all(s["peak_mb"] > 10 and s["wall_per_1000_s"] > 0 for s in res["scale"])
    assert 0 < res["warm_start"]["python_alone_s"] < res["warm_start"]["median_s"]
    cold = res["cold_start"]  # (quick: on warm caches, the harness only)
    assert not cold["cold"] and cold["compile_s"] >= 0 and cold["run_wall_s"] > 0
    assert "(quick: caches warm)" in targets and "## Cold compile profile" in targets
    lines = verdicts(res)
    assert len(lines) == n_speed + len(BENCH_SCENES) + 2 + 1 + 1 + 1 + 1 + 2 \
        + len(BENCH_SCENES) * len(ADAPTIVE) + 2 + 4 + 1 + 5  # (the elastic line's four, steady, multirevolution's five)
    tors = res["torsion"]  # (quick: 4 revolutions, lines of 3 and 4 stations, RK45 only)
    assert tors["rigid"]["elastic_s"] > 0 and tors["rigid"]["rigid_s"] > 0
    assert tors["scaling"]["stations"] == [3, 4] and all(
        w > 0 for w in tors["scaling"]["wall_per_cycle_s"])
    assert {r["method"] for r in tors["rows"]} == {"transient DOP853 (crank angle)",
                                                     "solve_ivp RK45 (numpy RHS)"}
    assert all(np.isfinite(r["phase_err_rad"]) for r in tors["rows"])
    assert "## Elastic shaft line" in targets
    (steady,) = res["steady"]  # (quick: the first case only)
    assert steady["shooting_cycles"] >= 2 and steady["direct_cycles"] > 0
    assert steady["speed_difference"] <= 1e-9  # (the settled run's speed, by either way)
    assert "## Steady state against a settling direct run" in targets
    mr = res["multirevolution"]  # (quick: a short run, the harness only)
    assert mr["cycles"] == 400 and mr["cycles_integrated"] > 0 and mr["direct_s"] > 0
    assert "## Multirevolution" in targets
    assert res["reaction"]["constant_s"] > 0 and res["reaction"]["reaction_s"] > 0
    (models,) = res["models"]  # (quick: the plain scene only)
    assert models["this_s"] > 0 and models["left_out_s"] > 0
    assert models["nfev"] == models["nfev_left_out"]  # (unused, the models change no step)
    assert "## Friction models left out" in targets
    for target, case, measured, verdict in lines:
        assert verdict in ("met", "met at the baseline's best error", "**missed**",
                           "**not measured**", "covered by the rigid targets")
        assert f"| {target} | {case} | {measured} | {verdict} |" in targets
        assert "|" not in target + case + measured  # (a cell's pipe would split the table)
    # --report rewrites both reports from the stored measurements, unchanged; only with --force
    (tmp_path / "targets.md").write_text("stale")
    assert main(["bench", "--report", "-o", str(tmp_path)]) == 2
    assert (tmp_path / "targets.md").read_text() == "stale"
    assert main(["bench", "--report", "-o", str(tmp_path), "--force"]) == 0
    assert (tmp_path / "targets.md").read_text() == targets


def test_bench_targets_needs_a_record(tmp_path, capsys):
    assert main(["bench", "--targets", "-o", str(tmp_path)]) == 2
    assert "bench --targets: no work_precision.csv" in capsys.readouterr().err


# ----------------------------------------------------------------------------------------------
# load steps: ISO 8528-5 measures in the summary, a response plot (issue 6)


def test_load_steps_are_measured_printed_and_plotted(tmp_path, capsys):
    """cases/gots_diesel_load_steps.toml: the summary finds the schedule's two steps (at 1 s and
    2 s, from the load_schedule events), the acceptance dips and the rejection rises, the speed
    returns to where it started (static droop: the two steady changes cancel), both recover into
    ±1 %, ``run`` prints them and ``plot`` writes the response figure."""
    scene = CASES / "gots_diesel_load_steps.toml"
    code = main(["run", str(scene), "-o", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0
    assert "load step 1 at t = 1 s" in out and "load step 2 at t = 2 s" in out
    with h5py.File(tmp_path / "gots_diesel_load_steps.h5") as f:
        a = {k: f["analysis"][k][()] for k in f["analysis"]}
        assert f["analysis"]["load_change_1_recovery_s"].attrs["unit"] == "s"
    assert (a["load_change_1_t_s"], a["load_change_2_t_s"]) == (1.0, 2.0)
    assert a["load_change_1_dev_max_pct"] < -1.0 < 1.0 < a["load_change_2_dev_max_pct"]
    assert a["load_change_1_recovered"] == a["load_change_2_recovered"] == 1.0
    assert 0.0 < a["load_change_1_recovery_s"] < 1.0 and 0.0 < a["load_change_2_recovery_s"] < 1.0
    w0, w1 = a["load_change_1_omega_before_rad_s"], a["load_change_2_omega_after_rad_s"]
    assert w1 == pytest.approx(w0, rel=1e-5)
    assert a["load_change_1_omega_after_rad_s"] == pytest.approx(
        a["load_change_2_omega_before_rad_s"], rel=1e-5)  # (different windows)
    assert main(["info", str(tmp_path / "gots_diesel_load_steps.h5")]) == 0
    assert "load step 2 at t = 2 s" in capsys.readouterr().out
    assert main(["plot", str(tmp_path / "gots_diesel_load_steps.h5"), "-o", str(tmp_path)]) == 0
    assert (tmp_path / "gots_diesel_load_steps_response.png").stat().st_size > 10_000


def test_spin_up_is_measured(tmp_path, capsys):
    """cases/swash_plate_4cyl.toml starts at 10 rad/s and ends near 50 rad/s: the summary gives
    the spin-up's t90, which must be where the cycle-mean speed of the stored trajectory first
    reaches 90 % of the final speed (recomputed here by linear interpolation between the two
    cycle means around it: within 1e-4 s)."""
    from transient.analysis.transient_response import cycle_mean_speed
    from transient.results import open_result

    code = main(["run", str(CASES / "swash_plate_4cyl.toml"), "-o", str(tmp_path)])
    assert code == 0 and "spin-up: 90 % of the final" in capsys.readouterr().out
    res = open_result(tmp_path / "swash_plate_4cyl.h5")
    a = {k: v[0] for k, v in res.analysis.items()}
    tr = res.trajectory
    tm, wm = cycle_mean_speed(tr["t"], tr["phi"], res.scene().mechanism.cycle, tr["omega"])
    target = 0.9 * a["spin_up_omega_rated_rad_s"]
    k = int(np.argmax(wm >= target))
    t90 = tm[k - 1] + (target - wm[k - 1]) * (tm[k] - tm[k - 1]) / (wm[k] - wm[k - 1])
    assert a["spin_up_t90_s"] - tr["t"][0] == pytest.approx(t90 - tr["t"][0], abs=1e-4)
    assert 0 < a["spin_up_t90_s"] < a["spin_up_settling_s"] < tr["t"][-1]


def test_efficiency_study_with_an_efficiency_map(tmp_path, capsys):
    """`transient efficiency` on the map case (its CSV next to the scene): every point's pair
    FMEPs sum to the total, the charts are written, η_mech falls with speed at both loads (the
    map's drag grows with speed) and with load at high speed."""
    scene = CASES / "gots_diesel_eta_map.toml"
    code, out, err = cli(capsys, "efficiency", scene, "--rpm", "1000,5000", "--fuel", "1,0.5",
                         "--samples-per-rev", "360", "-o", tmp_path)
    assert (code, err) == (0, "")
    csv = (tmp_path / "gots_diesel_eta_map_efficiency.csv").read_text().splitlines()
    header = csv[0].split(",")
    rows = {(float(r["fuel"]), float(r["rpm"])): r for r in
            (dict(zip(header, line.split(","))) for line in csv[1:])}
    assert len(rows) == 4
    for r in rows.values():
        assert float(r["fmep"]) == pytest.approx(float(r["fmep_1"]) + float(r["fmep_2"]),
                                                 rel=1e-9)
        assert float(r["fmep_1"]) > 0.0 and float(r["inconsistent_samples"]) == 0
    eta = {key: float(r["eta_mech_work"]) for key, r in rows.items()}
    assert eta[(1.0, 5000.0)] < eta[(1.0, 1000.0)] and eta[(0.5, 5000.0)] < eta[(0.5, 1000.0)]
    assert eta[(0.5, 5000.0)] < eta[(1.0, 5000.0)]
    for figure in ("efficiency", "friction_budget", "efficiency_map"):
        assert (tmp_path / f"gots_diesel_eta_map_{figure}.png").stat().st_size > 10_000
