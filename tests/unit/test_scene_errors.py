"""Invalid scenes reach the user as one line, ``file: key: what is wrong and what is allowed``.

docs/guide/cli.md: exit code 2 for invalid input, one line on stderr, no traceback, and ``run``
creates no
result file. Each case starts from the valid small scene ``VALID`` and breaks one thing; it goes
through ``transient check`` and ``transient run`` in-process. The expected key is the dotted TOML
key that ``transient.scene`` (or the mechanism / gas-table validation it calls) reports.

Cases at the end were bugs once (found by these tests, now fixed): the key or message the user gets
was misleading or the error escaped as a traceback.
"""
from __future__ import annotations

from pathlib import Path

import pytest
from scene_texts import MIXED_CYCLE, SMALL

from transient.cli import main
from transient.run import integrate
from transient.scene import load_scene

CASES_DIR = Path(__file__).resolve().parents[2] / "cases"

VALID = SMALL  # (every case below breaks one thing of it)


def replace(old: str, new: str) -> str:
    """VALID with one exact line (or fragment) replaced; the fragment must be there."""
    assert VALID.count(old) == 1, old
    return VALID.replace(old, new)


def add_after(anchor: str, lines: str) -> str:
    return replace(anchor, f"{anchor}\n{lines}")


def gas_table(phi_deg: str, p_bar: str, extra: str = "") -> str:
    return VALID + f'\n[gas]\nmodel = "table"\nphi_deg = {phi_deg}\np_bar = {p_bar}\n{extra}'


def pair(between: str = '["shaft", "crank"]', fwd: str = "0.98", bwd: str = "0.97",
         policy: str = "power-flow", extra: str = "") -> str:
    """VALID with one friction pair (crank-slider links: shaft – crank – rod)."""
    return VALID + (f'\n[friction]\npolicy = "{policy}"\n\n[[friction.pairs]]\nbetween = {between}\n'
                    f"eta_forward = {fwd}\neta_backward = {bwd}\n{extra}")


def reaction(between: str = '["shaft", "crank"]', keys: str = "mu = 0.003\nradius_mm = 30\n",
             extra: str = "") -> str:
    """VALID with one pair with friction on its reaction."""
    return VALID + (f'\n[friction]\n\n[[friction.pairs]]\nbetween = {between}\n'
                    f'model = "reaction"\n{keys}{extra}')


SLIDER = '["piston", "cylinder"]'
REACTION_CASES = [  # (id, scene text, key, fragment), part of CASES below
    ("reaction-unknown-model", pair(extra='model = "coulomb"\n'), "friction.pairs[0].model",
     "unknown value 'coulomb'; allowed: 'constant-eta', 'reaction'"),
    ("reaction-mu-negative", reaction(keys="mu = -0.01\nradius_mm = 30\n"),
     "friction.pairs[0].mu", "must be ≥ 0, got -0.01"),
    ("reaction-mu-missing", reaction(keys="radius_mm = 30\n"), "friction.pairs[0].mu",
     "is missing"),
    ("reaction-radius-missing", reaction(keys="mu = 0.003\n"), "friction.pairs[0].radius",
     "is missing"),
    ("reaction-radius-zero", reaction(keys="mu = 0.003\nradius_mm = 0\n"),
     "friction.pairs[0].radius_mm", "must be > 0, got 0"),
    ("reaction-eta-given", reaction(extra="eta_forward = 0.98\n"),
     "friction.pairs[0].eta_forward", "unknown key; allowed here: between, model, mu, name, "
                                      "radius, viscous"),
    ("reaction-radius-on-slider", reaction(SLIDER, "mu = 0.03\nradius_mm = 30\n"),
     "friction.pairs[0].radius_mm", "unknown key; allowed here: between, model, mu, name, "
                                    "ring_force, ring_pressure, viscous"),
    ("reaction-ring-share-above-1", reaction(SLIDER, "mu = 0.03\nring_pressure = 2\n"),
     "friction.pairs[0].ring_pressure", "must be ≤ 1, got 2"),
    ("reaction-crankpin-wedges", reaction('["crank", "rod"]', "mu = 1\nradius_mm = 150\n"),
     "friction.pairs[0].mu", "the friction would wedge the mechanism"),
    ("reaction-unknown-link", reaction('["piston", "wall"]', "mu = 0.03\n"),
     "friction.pairs[0].between",
     "unknown link 'wall'; the links are shaft – crank – rod – piston – cylinder"),
    ("constant-eta-into-cylinders-without-gas", pair(between='["piston", "cylinder"]'),
     "friction.pairs[0].between", "['piston', 'cylinder'] passes on the gas forces' work, and "
     "this scene has none (gas.model = \"none\"); give a gas model, or join other links of "
     "shaft – crank – rod – piston – cylinder"),
    ("reaction-mixed-with-constant-eta-off-the-main-bearings",
     reaction(extra='\n[[friction.pairs]]\nbetween = ["crank", "rod"]\neta_forward = 0.9\n'
                    'eta_backward = 0.9\n'),
     "friction.pairs[1].between", "a constant-eta pair among reaction pairs joins ['shaft', "
                                  "'crank'] (the main bearings), not ['crank', 'rod']"),
    ("reaction-mixed-with-table-off-the-main-bearings",
     reaction(extra='\n[[friction.pairs]]\nbetween = ["crank", "rod"]\nmodel = "table"\n'
                    'speed_rpm = [0, 3000]\ntorque = [0, 100]\n'
                    'eta_forward = [[0.97, 0.98], [0.96, 0.97]]\n'
                    'eta_backward = [[0.97, 0.98], [0.96, 0.97]]\n'),
     "friction.pairs[1].between", "a table pair among reaction pairs joins ['shaft', 'crank'] "
                                  "(the main bearings), not ['crank', 'rod']"),
    ("reaction-mixed-under-paper",
     reaction(between='["crank", "rod"]',
              extra='\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\neta_forward = 0.9\n'
                    'eta_backward = 0.9\n').replace("[friction]\n",
                                                      '[friction]\npolicy = "paper"\n'),
     "friction.policy", "'paper' with a constant-eta pair among reaction pairs; their mix "
                        "follows the \"power-flow\" policy"),
    ("reaction-and-constant-eta-on-one-joint",
     reaction(extra='\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\neta_forward = 0.9\n'
                    'eta_backward = 0.9\n'),
     "friction.pairs[1].between", "the same pair as friction.pairs[0]"),
]


def table(keys: str = "", speed: str = "speed_rpm = [0, 3000]", torque: str = "torque = [0, 100]",
          fwd: str = "eta_forward = [[0.97, 0.98], [0.96, 0.97]]",
          bwd: str = "eta_backward = [[0.97, 0.98], [0.96, 0.97]]") -> str:
    """VALID with one pair whose efficiencies are an inline map (rows: speeds)."""
    return VALID + (f'\n[friction]\n\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\n'
                    f'model = "table"\n{speed}\n{torque}\n{fwd}\n{bwd}\n{keys}')


TABLE_CASES = [  # (id, scene text, key, fragment), part of CASES below
    ("table-speed-not-increasing", table(speed="speed_rpm = [3000, 3000]"),
     "friction.pairs[0].speed_rpm", "must increase strictly, got 3000 rpm then 3000 rpm"),
    ("table-torque-negative", table(torque="torque = [-10, 100]"), "friction.pairs[0].torque",
     "starts at -10; a map's axes are magnitudes (|ω|, |S|), ≥ 0"),
    ("table-eta-above-1", table(fwd="eta_forward = [[0.97, 1.01], [0.96, 0.97]]"),
     "friction.pairs[0].eta_forward", "is 1.01 at (0 rpm, 100 N m); allowed: 0 < η ≤ 1"),
    ("table-row-short", table(bwd="eta_backward = [[0.97], [0.96, 0.97]]"),
     "friction.pairs[0].eta_backward", "must have 2 row(s) (one per speed) of 2 value(s)"),
    ("table-not-rows", table(bwd="eta_backward = [0.97, 0.98]"),
     "friction.pairs[0].eta_backward", "must be a list of rows of finite numbers"),
    ("table-breaks-uniqueness", table(torque="torque = [10, 20]",
                                      fwd="eta_forward = [[0.9, 0.4], [0.96, 0.97]]"),
     "friction.pairs[0].eta_forward", "η_fwd + x·∂η_fwd/∂x = -0.6 at 20 N m; the moment a pair "
                                      "passes on must grow with the moment it takes"),
    ("table-file-and-inline", table(keys='file = "map.csv"'), "friction.pairs[0].speed_rpm",
     "is given with 'file'; give the map in the file or inline, not both"),
    ("table-no-such-file", VALID + '\n[friction]\n\n[[friction.pairs]]\nbetween = ["shaft", '
                                   '"crank"]\nmodel = "table"\nfile = "nowhere.csv"\n',
     "friction.pairs[0].file", "no such file 'nowhere.csv'"),
    ("table-on-reference-path", add_after("rtol = 1e-6", 'method = "scipy-RK45"') + table()[
        len(VALID):], "solver.method", "efficiency maps run on the compiled methods"),
]

# Dynamic governors and fuel latching (issue 6): limits, gains, what a prescribed run cannot do.
PI = '\n[governor]\nmodel = "pi"\nspeed_rpm = 1000\ngain_p = 10\ngain_i = 30\n'
FLYWEIGHT = ('\n[governor]\nmodel = "flyweight"\nweight_mass = 0.1\nradius_mm = 30\n'
             'spring_rate = 2e4\nspring_preload = 200\ndamping = 50\ntravel_mm = 8\n')
GOVERNOR_CASES = [  # (id, scene text, key, fragment), part of CASES below
    ("pi-negative-fuel", VALID + PI + "fuel_min = -0.1\n", "governor.fuel_min",
     "must be ≥ 0, got -0.1"),
    ("pi-limits-reversed", VALID + PI + "fuel_min = 0.5\nfuel_max = 0.4\n", "governor.fuel_max",
     "must be > fuel_min = 0.5, got 0.4"),
    ("pi-initial-fuel-outside", VALID + PI + "fuel_initial = 1.5\n", "governor.fuel_initial",
     "must be ≤ fuel_max = 1, got 1.5"),
    ("pi-no-gain", VALID + PI.replace("gain_p = 10", "gain_p = 0").replace("gain_i = 30", "gain_i = 0"),
     "governor.gain_i", "gain_p and gain_i are both 0"),
    ("pi-actuator-lag-zero", VALID + PI + "actuator_time = 0\n", "governor.actuator_time",
     "must be > 0, got 0"),
    ("pi-anti-windup-not-bool", VALID + PI + "anti_windup = 1\n", "governor.anti_windup",
     "must be true or false, got 1"),
    ("pi-speed-missing", VALID + PI.replace("speed_rpm = 1000\n", ""), "governor.speed",
     "is missing"),
    ("pi-prescribed-speed", replace("revolutions = 2", 'mode = "prescribed-speed"\nspeed = 100\n'
                                    'revolutions = 2') + PI,
     "governor.model", "a prescribed-speed run integrates no governor state"),
    ("flyweight-travel-zero", VALID + FLYWEIGHT.replace("travel_mm = 8", "travel_mm = 0"),
     "governor.travel_mm", "must be > 0, got 0"),
    ("flyweight-no-weights", VALID + FLYWEIGHT + "weights = 0\n", "governor.weights",
     "must be ≥ 1, got 0"),
    ("flyweight-pi-key", VALID + FLYWEIGHT + "gain_p = 3\n", "governor.gain_p", "unknown key"),
    ("injection-beyond-cycle", VALID + MIXED_CYCLE.format(cr=18) + "injection_deg = 720\n",
     "gas.injection_deg", "must be < the cycle (mechanism.strokes × 180°) = 720, got 720"),
    ("inertia-switch-without-time", VALID + "\n[load]\ninertia = 0.1\n", "load.inertia_time",
     "is missing"),
    ("inertia-switch-negative", VALID + "\n[load]\ninertia = -0.1\ninertia_time = 1\n",
     "load.inertia", "must be ≥ 0, got -0.1"),
    ("inertia-switch-prescribed", replace("revolutions = 2", 'mode = "prescribed-speed"\n'
                                          'speed = 100\nrevolutions = 2')
     + "\n[load]\ninertia = 0.1\ninertia_time = 1\n",
     "load.inertia", "a prescribed-speed run has no momentum to conserve"),
]


# (id, scene text, key reported, fragment of the message)
# Wall heat transfer (issue 6): [gas.woschni] of a Wiebe cycle; cylinder pressures in the ODE.
WIEBE = """
[gas]
model = "wiebe"
compression_ratio = 18
p_a_MPa = 0.1436
p_intake_MPa = 0.165
p_exhaust_MPa = 0.182

[gas.wiebe]
start_deg = 358
duration_deg = 50
fuel_mass = 0.031e-3
"""
WOSCHNI = "\n[gas.woschni]\n"
WOSCHNI_CASES = [  # (id, scene text, key, fragment), part of CASES below
    ("woschni-negative-c1", VALID + WIEBE + WOSCHNI + "c1 = -1\n", "gas.woschni.c1",
     "must be ≥ 0, got -1"),
    ("woschni-wall-temperature-zero", VALID + WIEBE + WOSCHNI + "wall_temperature = 0\n",
     "gas.woschni.wall_temperature", "must be > 0, got 0"),
    ("woschni-unknown-key", VALID + WIEBE + WOSCHNI + "c3 = 1\n", "gas.woschni.c3",
     "unknown key; allowed here: c1, c2, wall_temperature"),
    ("woschni-wiebe-m-negative", VALID + WIEBE + "m = -0.2\n" + WOSCHNI, "gas.wiebe.m",
     "with wall heat transfer the heat-release rate enters the ODE"),
    ("woschni-prescribed-speed", replace("revolutions = 2", 'mode = "prescribed-speed"\n'
                                         'speed = 100\nrevolutions = 2') + WIEBE + WOSCHNI,
     "gas.woschni", "which a prescribed-speed run does not integrate"),
    ("woschni-tabulated-kinematics", replace("atol = 1e-8", 'atol = 1e-8\nkinematics = "tabulated"')
     + WIEBE + WOSCHNI, "solver.kinematics", "use the exact kinematics"),
    ("woschni-mixed-cycle", VALID + MIXED_CYCLE.format(cr=18) + WOSCHNI, "gas.woschni",
     "unknown key; allowed here:"),
    ("woschni-swash-plate", (CASES_DIR / "swash_plate_1cyl.toml").read_text()
     .replace('model = "trapezoid"\namplitude = 8000.0   # N, force per piston\nramp_deg = 30\n'
              'duration_deg = 180', 'model = "wiebe"\ncompression_ratio = 12\np_a_MPa = 0.1')
     + "\n[gas.wiebe]\nstart_deg = -5\nduration_deg = 40\nfuel_mass = 1e-5\n" + WOSCHNI,
     "gas.woschni", "wall heat transfer is built for crank-slider engines"),
]


CASES = [
    ("toml-syntax", replace("bore_mm = 88", "bore_mm = = 88"),
     "(syntax)", "not valid TOML"),
    ("toml-unclosed-table", replace("[inertia]", "[inertia"),
     "(syntax)", "not valid TOML"),
    ("unknown-top-level-key", VALID + "\n[engine]\nspeed = 1\n",
     "engine", "unknown key; allowed here: analysis, friction, gas, governor, inertia, initial, "
               "load, mechanism"),
    ("unknown-top-level-scalar", "format = 2\n" + VALID,
     "format", "unknown key"),
    ("unknown-mechanism-key", add_after("bore_mm = 88", "stroke_mm = 94"),
     "mechanism.stroke_mm", "unknown key; allowed here: bank, bore, crank_mass, crank_radius"),
    ("unknown-rod-key", add_after("mass = 1.752", "length_mm = 148"),
     "mechanism.rod.length_mm", "unknown key"),
    ("unknown-unit-suffix", add_after("bore_mm = 88", "offset_in = 0.1"),
     "mechanism.offset_in", "unknown unit suffix '_in'; give 'offset' or 'offset_mm'"),
    ("suffix-does-not-fit", add_after("bore_mm = 88", "offset_rpm = 1"),
     "mechanism.offset_rpm", "unit suffix '_rpm' does not fit this quantity"),
    ("suffix-on-unitless-quantity", replace("crank_mass = 0.912", "crank_mass_mm = 912"),
     "mechanism.crank_mass_mm", "unit suffix '_mm' does not fit this quantity; give 'crank_mass'"),
    ("suffix-does-not-fit-speed", replace("omega_rpm = 1000", "omega_mm = 1000"),
     "initial.omega_mm", "does not fit this quantity"),
    ("given-twice", add_after("crank_radius_mm = 47", "crank_radius = 0.047"),
     "mechanism.crank_radius_mm", "given twice (also as 'crank_radius'); give one of them"),
    ("given-twice-two-suffixes", VALID + '\n[gas]\np0_bar = 1\np0_MPa = 0.1\n',
     "gas.p0_MPa", "given twice (also as 'p0_bar')"),
    ("missing-bore", replace("bore_mm = 88\n", ""),
     "mechanism.bore", "is missing; give 'bore' or 'bore_mm'"),
    ("missing-rod-table", replace("[mechanism.rod]\nmodel = \"two-mass\"\nmass = 1.752\n"
                                  "cg_from_pin_mm = 107.3\n", ""),
     "mechanism.rod", "is missing (a table)"),
    ("missing-run-table", replace("[run]\nrevolutions = 2\n", ""),
     "run", "is missing (a table)"),
    ("wrong-type-string", replace("bore_mm = 88", 'bore_mm = "88"'),
     "mechanism.bore_mm", "must be a number, got '88'"),
    ("wrong-type-bool", replace("piston_mass = 1.520", "piston_mass = true"),
     "mechanism.piston_mass", "must be a number, got True"),
    ("wrong-type-integer", add_after("crank_mass = 0.912", "cylinders = 2.5"),
     "mechanism.cylinders", "must be a whole number, got 2.5"),
    ("section-not-a-table", "initial = 5\n" + replace("[initial]\nomega_rpm = 1000\n", ""),
     "initial", "must be a table, got int"),
    ("unknown-mechanism-type", replace('type = "crank-slider"', 'type = "wankel"'),
     "mechanism.type", "unknown value 'wankel'; allowed: 'crank-slider'"),
    ("strokes-not-2-or-4", add_after("crank_mass = 0.912", "strokes = 3"),
     "mechanism.strokes", "must be one of 2, 4, got 3"),
    ("lambda-not-below-1", replace("crank_radius_mm = 47", "crank_radius_mm = 150"),
     "mechanism.rod_length_mm", "must be > crank_radius = 150, got 148"),
    ("lambda-equal-1", replace("crank_radius_mm = 47", "crank_radius_mm = 148"),
     "mechanism.rod_length_mm", "must be > crank_radius = 148, got 148"),
    ("offset-too-large", add_after("bore_mm = 88", "offset_mm = 120"),
     "mechanism.offset_mm", "must be < rod_length − crank_radius = 101, got 120"),
    ("offset-too-large-negative", add_after("bore_mm = 88", "offset_mm = -101"),
     "mechanism.offset_mm", "must be > −(rod_length − crank_radius) = -101, got -101"),
    ("zero-piston-mass", replace("piston_mass = 1.520", "piston_mass = 0"),
     "mechanism.piston_mass", "must be > 0, got 0"),
    ("negative-piston-mass", replace("piston_mass = 1.520", "piston_mass = -1.5"),
     "mechanism.piston_mass", "must be > 0, got -1.5"),
    ("negative-rod-mass", replace("mass = 1.752", "mass = -1.752"),
     "mechanism.rod.mass", "must be > 0, got -1.752"),
    ("rod-cg-beyond-rod", replace("cg_from_pin_mm = 107.3", "cg_from_pin_mm = 160"),
     "mechanism.rod.cg_from_pin_mm", "must be ≤ rod_length = 148, got 160"),
    ("rod-cg-negative", replace("cg_from_pin_mm = 107.3", "cg_from_pin_mm = -1"),
     "mechanism.rod.cg_from_pin_mm", "must be ≥ 0, got -1"),
    ("firing-order-repeats", add_after("crank_mass = 0.912", "cylinders = 3\nfiring_order = [1, 1, 3]"),
     "mechanism.firing_order", "must list each cylinder 1 … 3 once, got [1, 1, 3]"),
    ("firing-order-out-of-range", add_after("crank_mass = 0.912",
                                            "cylinders = 3\nfiring_order = [1, 2, 4]"),
     "mechanism.firing_order", "must list each cylinder 1 … 3 once"),
    ("firing-deg-wrong-length", add_after("crank_mass = 0.912", "cylinders = 3\nfiring_deg = [0, 240]"),
     "mechanism.firing_deg", "has 2 entries; must have one per cylinder (3)"),
    ("firing-deg-outside-cycle", add_after("crank_mass = 0.912",
                                           "cylinders = 2\nfiring_deg = [0, 720]"),
     "mechanism.firing_deg", "720° is outside the cycle; allowed 0 ≤ angle < 720°"),
    ("gas-angles-not-increasing", gas_table("[0, 360, 180, 720]", "[1, 60, 5, 1]"),
     "gas.phi_deg", "angles must increase, but 180° follows 360°"),
    ("gas-angle-repeated-off-corner", gas_table("[0, 360, 360, 720]", "[1, 60, 50, 1]"),
     "gas.phi_deg", "360° is repeated but is not in gas.corners_deg"),
    ("gas-table-short-of-cycle", gas_table("[0, 360, 600]", "[1, 60, 1]"),
     "gas.phi_deg", "angles run from 0° to 600°; they must start at 0° and end at 720°"),
    ("gas-table-late-start", gas_table("[10, 360, 720]", "[1, 60, 1]"),
     "gas.phi_deg", "they must start at 0° and end at 720°"),
    ("gas-table-lengths-differ", gas_table("[0, 360, 720]", "[1, 60]"),
     "gas.p_bar", "has 2 values but gas.phi_deg has 3"),
    ("gas-table-negative-pressure", gas_table("[0, 360, 720]", "[1, -60, 1]"),
     "gas.p_bar", "pressures are absolute, finite and ≥ 0"),
    ("gas-corner-outside-cycle", gas_table("[0, 360, 720]", "[1, 60, 1]", "corners_deg = [720]\n"),
     "gas.corners_deg", "corners must lie strictly inside the cycle"),
    ("mixed-cycle-compression-ratio-1", VALID + MIXED_CYCLE.format(cr=1),
     "gas.compression_ratio", "must be > 1, got 1"),
    ("mixed-cycle-compression-ratio-below-1", VALID + MIXED_CYCLE.format(cr=0.5),
     "gas.compression_ratio", "must be > 1, got 0.5"),
    ("mixed-cycle-missing-key", (VALID + MIXED_CYCLE.format(cr=18)).replace("n2 = 1.228\n", ""),
     "gas.n2", "is missing"),
    ("unknown-gas-model", VALID + '\n[gas]\nmodel = "woschni"\n',
     "gas.model", "unknown value 'woschni'; allowed: 'none', 'table', 'mixed-cycle', 'trapezoid', "
                  "'wiebe'"),
    ("run-without-end", replace("revolutions = 2\n", ""),
     "run.t_end", "the run needs an end: give t_end [s] and/or revolutions"),
    ("run-negative-t-end", add_after("revolutions = 2", "t_end = -1"),
     "run.t_end", "must be > 0, got -1"),
    ("unknown-run-mode", add_after("revolutions = 2", 'mode = "steady"'),
     "run.mode", "unknown value 'steady'; allowed: 'dynamic', 'prescribed-speed'"),
    ("starter-cutout-above-noload", VALID + "\n[starter]\ntorque = 50\nnoload_speed_rpm = 300\n"
                                            "cutout_speed_rpm = 400\n",
     "starter.cutout_speed_rpm", "must be ≤ noload_speed = 300, got 400"),
    ("at-rest-without-starter-or-gas", replace("omega_rpm = 1000", "omega_rpm = 0"),
     "initial.omega", "never moves; give omega or a starter"),
    ("unknown-solver-method", add_after("rtol = 1e-6", 'method = "rk4"'),
     "solver.method", "unknown value 'rk4'; allowed: 'dop853'"),
    ("rtol-equal-1", replace("rtol = 1e-6", "rtol = 1"),
     "solver.rtol", "must be < 1, got 1"),
    ("rtol-above-1", replace("rtol = 1e-6", "rtol = 2.5"),
     "solver.rtol", "must be < 1, got 2.5"),
    ("rtol-zero", replace("rtol = 1e-6", "rtol = 0"),
     "solver.rtol", "must be > 0, got 0"),
    ("samples-per-rev-too-few", replace("samples_per_rev = 12", "samples_per_rev = 2"),
     "output.samples_per_rev", "must be ≥ 4, got 2"),
    ("nan-number", replace("piston_mass = 1.520", "piston_mass = nan"),
     "mechanism.piston_mass", "must be finite"),
    # Non-ideal pairs (issue 4): non-physical efficiencies and pairs that are not in the chain.
    ("eta-zero", pair(fwd="0"), "friction.pairs[0].eta_forward", "must be > 0, got 0"),
    ("eta-negative", pair(bwd="-0.5"), "friction.pairs[0].eta_backward", "must be > 0, got -0.5"),
    ("eta-above-1", pair(fwd="1.02"), "friction.pairs[0].eta_forward", "must be ≤ 1, got 1.02"),
    ("eta-missing", pair().replace("eta_backward = 0.97\n", ""),
     "friction.pairs[0].eta_backward", "is missing"),
    ("pair-not-adjacent", pair(between='["shaft", "rod"]'), "friction.pairs[0].between",
     "'shaft' and 'rod' are not neighbours; a pair joins two adjacent links of the chain "
     "shaft – crank – rod – piston – cylinder"),
    ("pair-not-adjacent-deeper", pair(between='["crank", "piston"]'),
     "friction.pairs[0].between", "'crank' and 'piston' are not neighbours; a pair joins two "
     "adjacent links of the chain shaft – crank – rod – piston – cylinder"),
    ("pair-unknown-link", pair(between='["rod", "pin"]'), "friction.pairs[0].between",
     "unknown link 'pin'; the links are shaft – crank – rod – piston – cylinder"),
    ("pair-reversed", pair(between='["crank", "shaft"]'), "friction.pairs[0].between",
     "give the shaft-side link first: ['shaft', 'crank']"),
    ("pair-reversed-deeper", pair(between='["piston", "rod"]'), "friction.pairs[0].between",
     "give the shaft-side link first: ['rod', 'piston']"),
    ("pair-same-link", pair(between='["crank", "crank"]'), "friction.pairs[0].between",
     "are not neighbours"),
    ("pair-one-link", pair(between='["shaft"]'), "friction.pairs[0].between",
     "must be two link names"),
    ("pair-twice", pair(extra='\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\n'
                              'eta_forward = 0.9\neta_backward = 0.9\n'),
     "friction.pairs[1].between", "the same pair as friction.pairs[0]"),
    ("pair-twice-deeper", pair(between='["rod", "piston"]',
                               extra='\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\n'
                                     'eta_forward = 0.9\neta_backward = 0.9\n'
                                     '\n[[friction.pairs]]\nbetween = ["rod", "piston"]\n'
                                     'eta_forward = 0.9\neta_backward = 0.9\n'),
     "friction.pairs[2].between", "the same pair as friction.pairs[0]"),
    ("pair-unknown-key", pair(extra="efficiency = 0.9\n"), "friction.pairs[0].efficiency",
     "unknown key; allowed here: between, eta_backward, eta_forward, model, name"),
    *REACTION_CASES,
    *TABLE_CASES,
    ("pairs-not-array", VALID + '\n[friction]\npairs = 3\n', "friction.pairs",
     "must be an array of tables"),
    ("unknown-policy", pair(policy="coulomb"), "friction.policy",
     "unknown value 'coulomb'; allowed: 'power-flow', 'paper'"),
    ("paper-policy-on-reference-path", add_after("rtol = 1e-6", 'method = "scipy-RK45"')
     + '\n[friction]\npolicy = "paper"\n\n[[friction.pairs]]\n'
                            'between = ["shaft", "crank"]\neta_forward = 0.9\neta_backward = 0.9\n',
     "solver.method", "the reference path (scipy-*) follows the power-flow policy only"),
    # [analysis] (issue 7): what to store under /analysis after the run.
    ("analysis-loads-not-bool", VALID + "\n[analysis]\nloads = 1\n", "analysis.loads",
     "must be true or false, got 1"),
    ("analysis-orders-not-list", VALID + '\n[analysis]\norders = "omega"\n', "analysis.orders",
     "must be a list of strings"),
    ("analysis-unknown-signal", VALID + '\n[analysis]\norders = ["omega", "torque"]\n',
     "analysis.orders", "unknown signal 'torque'; allowed: t, phi, omega, epsilon"),
    ("analysis-piston-of-missing-cylinder", VALID + '\n[analysis]\norders = ["W_2"]\n',
     "analysis.orders", "unknown signal 'W_2'; allowed:"),
    ("analysis-signal-twice", VALID + '\n[analysis]\norders = ["omega", "omega"]\n',
     "analysis.orders", "a signal is named twice"),
    ("analysis-max-order-zero", VALID + "\n[analysis]\norders = [\"omega\"]\nmax_order = 0\n",
     "analysis.max_order", "must be > 0, got 0"),
    ("analysis-max-order-above-nyquist",
     VALID + '\n[analysis]\norders = ["omega"]\nsamples_per_cycle = 16\nmax_order = 9\n',
     "analysis.max_order",
     "must be ≤ 4 (the Nyquist order of samples_per_cycle = 16 over a 720° cycle), got 9"),
    ("analysis-few-samples", VALID + "\n[analysis]\nirregularity = true\nsamples_per_cycle = 8\n",
     "analysis.samples_per_cycle", "must be ≥ 16, got 8"),
    ("analysis-unknown-detrend", VALID + '\n[analysis]\ndetrend = "linear"\n', "analysis.detrend",
     "unknown value 'linear'; allowed: 'auto', 'ramp', 'none'"),
    ("analysis-unknown-key", VALID + "\n[analysis]\nspectra = true\n", "analysis.spectra",
     "unknown key; allowed here: detrend, irregularity, loads, max_order, orders, "
     "samples_per_cycle"),
    *GOVERNOR_CASES,
    *WOSCHNI_CASES,
]


def run_cli(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(err: str, path, key: str, fragment: str) -> None:
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), f"expected exactly one line, got {err!r}"
    line = lines[0]
    assert "Traceback" not in line
    assert line.startswith(f"{path}: {key}: "), line
    message = line[len(f"{path}: {key}: "):]
    assert fragment in message, line


@pytest.mark.parametrize("command", ["check", "run"])
@pytest.mark.parametrize("text, key, fragment",
                         [pytest.param(t, k, f, id=i) for i, t, k, f in CASES])
def test_invalid_scene_is_one_line_exit_2(tmp_path, capsys, command, text, key, fragment):
    scene = tmp_path / "bad.toml"
    scene.write_text(text, encoding="utf-8")
    out_dir = tmp_path / "out"
    argv = ["check", str(scene)] if command == "check" else ["run", str(scene), "-o", str(out_dir)]
    code, out, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, scene, key, fragment)
    assert out == ""
    if command == "run":
        assert not out_dir.exists() or not any(out_dir.iterdir()), list(out_dir.iterdir())


def test_the_cases_are_distinct_and_many():
    ids = [c[0] for c in CASES]
    assert len(set(ids)) == len(ids) >= 15
    assert len({c[1] for c in CASES}) == len(CASES)  # every case is a different scene text


def test_the_base_scene_is_valid(tmp_path, capsys):
    """Every case differs from a scene that passes: the error comes from the one change."""
    scene = tmp_path / "ok.toml"
    scene.write_text(VALID, encoding="utf-8")
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert (code, err) == (0, "")
    assert out.startswith(f"{scene}: ok (small: CrankSlider, 1 cylinder(s)")
    for extra in (MIXED_CYCLE.format(cr=18),
                  '\n[gas]\nmodel = "table"\nphi_deg = [0, 360, 720]\np_bar = [1, 60, 1]\n',
                  "\n[starter]\ntorque = 50\nnoload_speed_rpm = 300\ncutout_speed_rpm = 200\n"):
        scene.write_text(VALID + extra, encoding="utf-8")
        assert run_cli(["check", str(scene)], capsys)[0] == 0


@pytest.mark.parametrize("command", ["check", "run", "kinematics"])
def test_missing_scene_file(tmp_path, capsys, command):
    scene = tmp_path / "nowhere.toml"
    code, out, err = run_cli([command, str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, "(file)", "cannot read")
    assert not (tmp_path / "results").exists()


# ----------------------------------------------------------------------------------------------
# Bugs: misleading key or message, or an error that escapes as a traceback. See the report.

BUGS = [
    pytest.param(replace("crank_radius_mm = 47", "crank_radius_in = 1.85"),
                 "mechanism.crank_radius_in", "unknown unit suffix '_in'",
                 id="unknown-suffix-on-required-key-reported-as-missing"),
    pytest.param(replace("crank_radius_mm = 47", "crank_radius_rpm = 47"),
                 "mechanism.crank_radius_rpm", "does not fit this quantity",
                 id="misfit-suffix-on-required-key-reported-as-missing"),
    pytest.param(add_after("bore_mm = 88", "offset_rpm = 1"),
                 "mechanism.offset_rpm", "'offset_mm'",
                 id="misfit-suffix-hint-omits-the-allowed-suffix"),
    pytest.param(add_after("crank_mass = 0.912", "cylinders = 3\nfiring = [0.0, 4.0]"),
                 "mechanism.firing", "has 2 entries",
                 id="firing-in-radians-reported-as-firing_deg"),
    pytest.param(VALID + '\n[gas]\nmodel = "table"\nphi = [0.0, 6.0, 3.0, 12.566370614359172]\n'
                         'p_bar = [1, 60, 5, 1]\n',
                 "gas.phi", "angles must increase",
                 id="gas-phi-in-radians-reported-as-phi_deg"),
    pytest.param(add_after("bore_mm = 88", "bore_diameter = 0.088"),
                 "mechanism.bore_diameter", "unknown key",
                 id="unknown-key-reported-as-unknown-unit-suffix"),
    pytest.param("solver_method = 'dop853'\n" + VALID, "solver_method", "unknown key",
                 id="unknown-top-level-key-reported-as-unknown-unit-suffix"),
]


@pytest.mark.parametrize("text, key, fragment", BUGS)
def test_misleading_key_or_message(tmp_path, capsys, text, key, fragment):
    scene = tmp_path / "bad.toml"
    scene.write_text(text, encoding="utf-8")
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, key, fragment)


def test_scene_file_not_utf8(tmp_path, capsys):
    scene = tmp_path / "latin1.toml"
    scene.write_bytes(replace('name = "small"', 'name = "Kolbenmotor für Prüfstand"')
                      .encode("latin-1"))
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, "(file)", "UTF-8")


# ----------------------------------------------------------------------------------------------
# The swash-plate mechanism (issue 3): the default scene with one thing broken.

SWASH = (Path(__file__).resolve().parents[2] / "cases" / "swash_plate_4cyl.toml").read_text()

SWASH_CASES = [
    ("swash_deg = 21.4", "swash_deg = 0", "mechanism.swash_deg", "must be > 0, got 0"),
    ("swash_deg = 21.4", "swash_deg = 45", "mechanism.swash_deg", "must be < 45, got 45"),
    ("rod_length_mm = 300", "rod_length_mm = 5", "mechanism.rod.cg_from_pin_mm",
     "must be ≤ rod_length = 5, got 150"),
    ("cylinder_radius_mm = 131.31", "cylinder_radius_mm = 500", "mechanism.cylinder_radius_mm",
     "must be < the largest r₁ whose pistons turn at their dead centres only = 405.943, got 500"),
    ("cylinders = 4", "cylinders = 0", "mechanism.cylinders", "must be ≥ 1"),
]


@pytest.mark.parametrize("old, new, key, fragment", SWASH_CASES, ids=[c[1] for c in SWASH_CASES])
@pytest.mark.parametrize("command", ["check", "run"])
def test_invalid_swash_plate_is_one_line_exit_2(tmp_path, capsys, command, old, new, key, fragment):
    assert SWASH.count(old) == 1, old
    scene = tmp_path / "bad.toml"
    scene.write_text(SWASH.replace(old, new), encoding="utf-8")
    argv = [command, str(scene)] + (["-o", str(tmp_path / "res")] if command == "run" else [])
    code, out, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, scene, key, fragment)
    assert not (tmp_path / "res").exists()


# The radial with friction on its joints' reactions: one pair broken (the case's first, the main
# bearing, unless said), or a key of the scene.
RADIAL_REACTION = (CASES_DIR / "radial_5cyl_reaction_friction.toml").read_text()
MAIN = 'between = ["shaft", "crank"]'
JOINTS = ("the joints are ['shaft', 'crank'], ['crank', 'master rod'], ['master rod', "
          "'slave rod'], ['master rod', 'piston'], ['slave rod', 'piston'], ['piston', "
          "'cylinder']")
RADIAL_REACTION_CASES = [
    (MAIN, 'between = ["shaft", "rod"]', "friction.pairs[0].between",
     "unknown link 'rod'; the links of 'articulated' are shaft, crank, master rod, slave rod, "
     "piston, cylinder"),
    (MAIN, 'between = ["crank", "shaft"]', "friction.pairs[0].between",
     "give the shaft-side link first: ['shaft', 'crank']"),
    (MAIN, 'between = ["crank", "slave rod"]', "friction.pairs[0].between",
     "'crank' and 'slave rod' are not joined in 'articulated'; " + JOINTS),
    (MAIN, 'between = "shaft"', "friction.pairs[0].between", "must be two link names"),
    (MAIN, 'between = ["crank", "master rod"]', "friction.pairs[1].between",
     "the same pair as friction.pairs[0]"),
    ('radius_mm = 50', 'radius_mm = 0', "friction.pairs[0].radius_mm", "must be > 0"),
    ('ring_force = 50.0', 'ring_force = 50.0\nradius_mm = 20', "friction.pairs[5].radius_mm",
     "unknown key; allowed here: between, model, mu, name, ring_force, ring_pressure, viscous"),
    ('mu = 0.0015\nradius_mm = 44', 'mu = 1\nradius_mm = 300', "friction.pairs[1].mu",
     "the friction would wedge the master rod"),
    ('[solver]', '[solver]\nkinematics = "tabulated"', "solver.kinematics",
     "friction on the reactions of the 'articulated' mechanism takes its exact kinematics"),
]


@pytest.mark.parametrize("old, new, key, fragment", RADIAL_REACTION_CASES,
                         ids=[c[1] for c in RADIAL_REACTION_CASES])
def test_invalid_radial_reaction_pair_is_one_line_exit_2(tmp_path, capsys, old, new, key,
                                                         fragment):
    assert RADIAL_REACTION.count(old) == 1, old
    scene = tmp_path / "bad.toml"
    scene.write_text(RADIAL_REACTION.replace(old, new), encoding="utf-8")
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, key, fragment)


SWASH_REACTION = (Path(__file__).resolve().parents[2] / "cases"
                  / "swash_plate_4cyl_reaction_friction.toml").read_text()

SWASH_REACTION_CASES = [
    ("ball-joint-on-link", 'between = ["plate", "link"]', 'between = ["link", "rod"]',
     "friction.pairs[1].between", "['link', 'rod'] (the ball joints B_k of the rods on link 9) "
     "cannot have friction on its reactions: the swash-plate keeps them ideal; reaction pairs "
     "join ['shaft', 'plate'], ['plate', 'link'], ['piston', 'cylinder']"),
    ("ball-joint-on-piston", 'between = ["plate", "link"]', 'between = ["rod", "piston"]',
     "friction.pairs[1].between", "(the ball joints D_k of the rods on the pistons)"),
    ("constant-eta-link-name", 'between = ["shaft", "plate"]', 'between = ["shaft", "link"]',
     "friction.pairs[0].between", "'shaft' and 'link' are not neighbours; a pair joins two "
     "adjacent links of the chain shaft – plate – link – rod – piston – cylinder"),
    ("plate-bearing-radius-missing", 'radius_mm = 70', '', "friction.pairs[1].radius",
     "is missing"),
    ("pistons-wedge", 'rod_length_mm = 300\n', 'rod_length_mm = 10\n',
     "friction.pairs[2].mu", "the friction would wedge the pistons: μ·tan γ_max"),
    ("constant-eta-among-reaction-pairs", '[[friction.pairs]]\nname = "pistons"',
     '[[friction.pairs]]\nbetween = ["shaft", "link"]\neta_forward = 0.98\n'
     'eta_backward = 0.98\n\n[[friction.pairs]]\nname = "pistons"',
     "friction.pairs[2].model", "'constant-eta' among reaction pairs: the swash-plate's reaction "
     "pairs do not mix with others; give every pair model = \"reaction\", or none"),
]


@pytest.mark.parametrize("name, old, new, key, fragment", SWASH_REACTION_CASES,
                         ids=[c[0] for c in SWASH_REACTION_CASES])
def test_invalid_swash_reaction_pair_is_one_line_exit_2(tmp_path, capsys, name, old, new, key,
                                                        fragment):
    text = SWASH_REACTION
    assert text.count(old) == 1, old
    text = text.replace(old, new)
    if name == "pistons-wedge":  # (a 10 mm rod swings to 70°; μ = 0.5 wedges it)
        text = text.replace("mu = 0.03\n", "mu = 0.5\n").replace("cg_from_pin_mm = 150",
                                                                "cg_from_pin_mm = 5")
    scene = tmp_path / "bad.toml"
    scene.write_text(text, encoding="utf-8")
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, key, fragment)


def test_swash_reaction_pairs_run_on_the_reference_path(tmp_path, capsys):
    """The reference path has the swash plate's reaction friction
    (:class:`transient.reference.twins.SwashReactionNumpy`): the scene passes the check with a scipy-*
    method and runs there, every pair losing energy (the agreement with the compiled path is
    ``tests/validation/test_reference_path.py``'s)."""
    text = SWASH_REACTION
    for old, new in (('[run]', '[solver]\nmethod = "scipy-RK45"\n\n[run]'),
                     ("t_end = 8.0", "t_end = 0.02")):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = tmp_path / "swash.toml"
    path.write_text(text, encoding="utf-8")
    code, out, err = run_cli(["check", str(path)], capsys)
    assert code == 0 and err == "", err
    data = integrate(load_scene(path))
    assert data.complete and data.solver["method"] == "scipy-RK45", data.message
    assert data.trajectory["t"][-1] == 0.02
    for k in range(1, 4):
        assert data.trajectory[f"W_loss_{k}"][-1] > 0.0


def test_reduced_inertia_reaching_zero_is_rejected(tmp_path, capsys):
    """(18) divides by J(φ): a machine whose J vanishes at a dead centre (no crank mass, the rod's
    mass all at the pin, no shaft inertia) is refused before any work."""
    scene = tmp_path / "bad.toml"
    text = VALID
    for old, new in (("crank_mass = 0.912", "crank_mass = 0.0"), ("shaft = 0.02", "shaft = 0.0"),
                     ("cg_from_pin_mm = 107.3", "cg_from_pin_mm = 0")):
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    scene.write_text(text, encoding="utf-8")
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, "inertia", "the reduced inertia J(φ) falls to")


@pytest.mark.parametrize("csv, fragment", [
    ("speed_rpm,torque,eta_forward,eta_backward\n0,0,0.97,0.97\n0,100,0.98,0.98\n"
     "3000,0,0.96,0.96\n", "the grid is incomplete: no row for (3000 rpm, 100 N m)"),
    ("speed_rpm,torque,eta_forward,eta_backward\n0,0,0.97,0.97\n0,0,0.98,0.98\n",
     "data row 2 repeats the grid point (0 rpm, 0 N m) of data row 1"),
    ("speed_rpm,torque,eta_forward\n0,0,0.97\n", "needs a speed column"),
    ("speed_rpm,torque,eta_forward,eta_backward\n0,0,0.97,0\n0,100,0.98,0.98\n",
     "column eta_backward: is 0 at (0 rpm, 0 N m); allowed: 0 < η ≤ 1"),
])
def test_invalid_efficiency_map_file_is_one_line_exit_2(tmp_path, capsys, csv, fragment):
    """A map from a CSV file (one row per grid point): the error names the scene's key ``file``,
    the CSV file and what is wrong in it."""
    (tmp_path / "map.csv").write_text(csv, encoding="utf-8")
    scene = tmp_path / "bad.toml"
    scene.write_text(VALID + '\n[friction]\n\n[[friction.pairs]]\nbetween = ["shaft", "crank"]\n'
                             'model = "table"\nfile = "map.csv"\n', encoding="utf-8")
    code, out, err = run_cli(["check", str(scene)], capsys)
    assert code == 2
    assert_one_line_error(err, scene, "friction.pairs[0].file", "map.csv: ")
    assert fragment in err, err
