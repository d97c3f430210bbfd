"""Scene files the tests share, as TOML text: one copy of each (on ``pythonpath``, pyproject),
and :func:`check_text`, which runs ``transient check`` on such a text."""

#: A valid small scene: one crank-slider cylinder (the Gots diesel's, two-mass rod), no forces,
#: 2 revolutions from 1000 rpm, coarse output. The scene-error tests break one thing of it; line
#: numbers in their TOML syntax errors count from its first line.
SMALL = """\
[scene]
name = "small"

[mechanism]
type = "crank-slider"
crank_radius_mm = 47
rod_length_mm = 148
bore_mm = 88
piston_mass = 1.520
crank_mass = 0.912

[mechanism.rod]
model = "two-mass"
mass = 1.752
cg_from_pin_mm = 107.3

[inertia]
shaft = 0.02

[initial]
omega_rpm = 1000

[run]
revolutions = 2

[solver]
rtol = 1e-6
atol = 1e-8

[output]
samples_per_rev = 12
"""

#: The Gots diesel's ideal mixed cycle (App. 2) as a [gas] table, its compression ratio left as
#: ``{cr}`` (appended to SMALL or another scene with no [gas] table).
MIXED_CYCLE = """
[gas]
model = "mixed-cycle"
compression_ratio = {cr}
p_a_MPa = 0.1436
n1 = 1.368
p_z_MPa = 10.5
rho = 1.671
n2 = 1.228
p_intake_MPa = 0.165
p_exhaust_MPa = 0.182
"""

#: An air compressor's ideal cycle, 1 → 8 bar (``model = "compressor"``), as a [gas] table for a
#: mechanism whose cycle is one turn (appended to SMALL made a 2-stroke).
COMPRESSOR_GAS = """
[gas]
model = "compressor"
p_suction_bar = 1
p_discharge_bar = 8
n = 1.3
clearance_ratio = 0.05
"""


def check_text(tmp_path, capsys, text: str):
    """``transient check`` on ``text`` written to ``tmp_path/bad.toml``: (path, exit code,
    stdout, stderr)."""
    from transient.cli import main

    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    code = main(["check", str(path)])
    out, err = capsys.readouterr()
    return path, code, out, err
