"""The two mode policies of the non-ideal pairs compared on the Gots diesel and the swash-plate
engine: steady speed, η_mech in both forms, each pair's loss and circulated energy per
cycle, how often the paper's criterion runs a pair against the power it transmits, and the cost.
Rerun: ``.venv/bin/python tools/friction_policy_comparison.py``.
"""
import dataclasses as dc
import math
from pathlib import Path

from transient.analysis.efficiency import mechanical_efficiency
from transient.analysis.irregularity import cycle_means
from transient.run import integrate
from transient.scene import Friction, load_scene

CASES = Path(__file__).resolve().parents[1] / "cases"
print("| engine | policy | steady rpm | η work ratio | η (30) printed | per pair: loss, circulated "
      "[J/cycle], mode against power [% of time, intervals/cycle] | switches/cycle | wall [s] |")
print("|---|---|---|---|---|---|---|---|")
for name in ("gots_diesel_friction", "swash_plate_4cyl_friction"):
    base = load_scene(CASES / f"{name}.toml")
    for policy in ("power-flow", "paper"):
        scene = dc.replace(base, friction=Friction(policy, base.friction.pairs))
        integrate(scene, keep=False)  # compile or load the cache first
        data = integrate(scene)
        e = {k: v for k, (v, _) in mechanical_efficiency(scene, data.trajectory,
                                                         data.events).items()}
        tr = data.trajectory
        means, _ = cycle_means(tr["t"], tr["phi"], scene.mechanism.cycle, scene.initial.phi)
        rpm = means[-1] * 30 / math.pi  # the last whole cycle's mean speed
        pairs = "; ".join(
            f"{p.name}: {e[f'W_loss_{k}_per_cycle']:.4g}, {e[f'W_circulated_{k}_per_cycle']:.4g}, "
            f"{100 * e[f'mode_against_power_share_{k}']:.3g} %, "
            f"{e[f'mode_against_power_per_cycle_{k}']:.3g}"
            for k, p in enumerate(scene.friction.pairs, start=1))
        print(f"| {scene.name} | {policy} | {rpm:.1f} | {e['eta_mech_work']:.5f} | "
              f"{e['eta_mech_printed']:.4g} | {pairs} | {e['pair_mode_switches_per_cycle']:.3g} | "
              f"{data.solver['wall_s']:.3g} |")
