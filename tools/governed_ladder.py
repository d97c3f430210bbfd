"""The governed diesel's tolerance ladder, with one ingredient removed at a time: the final phase
error ω_ref·|t − t_ref| after 1000 revolutions against the compiled DOP853 in crank angle at rtol
1e-13 (as ``transient bench``, atol = rtol/1000, one sample per turn), divided by rtol·φ_end (the
scipy-style scaled error of t), with the steps, rejections and pair-mode switches of each run.

Variants: ``base`` (cases/gots_diesel_governed.toml), ``nofric`` (its [friction] removed),
``nogov`` (its governor removed). Domains: ``angle`` (the default path), ``time``.
Rerun: ``.venv/bin/python tools/governed_ladder.py base angle`` (about 20 s per variant and domain).
"""
import dataclasses as dc
import sys
from pathlib import Path

from transient.run import integrate
from transient.scene import Friction, Governor, load_scene
from transient.verify.bench import _scene

SCENE = Path(__file__).resolve().parents[1] / "cases" / "gots_diesel_governed.toml"
RTOLS = tuple(10.0 ** -k for k in range(3, 11))


def variant(name: str):
    scene = load_scene(SCENE)
    if name == "nofric":
        scene = dc.replace(scene, friction=Friction())
    elif name == "nogov":
        scene = dc.replace(scene, governor=Governor())
    return scene


def run(base, rtol: float, domain: str):
    extra = {"domain": "time"} if domain == "time" else {}
    data = integrate(_scene(base, "dop853", rtol, 1000, samples=1, **extra))
    tr = data.trajectory
    return tr["t"][-1], tr["omega"][-1], tr["phi"][-1], data


def main(name: str, domain: str) -> None:
    base = variant(name)
    t_ref, w_ref, phi_ref, _ = run(base, 1e-13, "angle")
    for rtol in RTOLS:
        t, w, _, data = run(base, rtol, domain)
        phase = abs(w_ref * (t - t_ref))
        sv = data.solver
        print(f"{name} {domain} rtol {rtol:.0e}: phase {phase:.2e} rad, "
              f"scaled {phase / (rtol * phi_ref):.2g}, omega {abs(w / w_ref - 1):.2e}, "
              f"{sv['nsteps']} steps, {sv['nreject']} rejected, "
              f"{len(data.events.get('pair_mode', ()))} pair switches", flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:3])
