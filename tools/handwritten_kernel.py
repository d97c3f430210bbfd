"""The target "bare scene at the speed of bare (18)", with the difference attributed: the cost of
one right-hand side of transient for the bare single cylinder (``cases/coasting_single.toml``: no
gas, friction, governor or starter) against a kernel written by hand for that equation alone
(``transient.verify.targets.make_hand_rhs``; ``transient bench`` records the two ends in
``targets.md``), and between them the hand-written kernel with, one rung at a time, what
transient's right-hand side does beyond it; then whole runs of the bare scene against the same
scene carrying unused options (a droop governor, a zero-torque starter, never acting; medians of
15 alternating runs). Rerun: ``.venv/bin/python tools/handwritten_kernel.py``.
``tools/bare_gap.py`` looks at the same difference from transient's side.
"""
from transient.scene import load_scene
from transient.verify.targets import BARE_SCENE, bare_kernel, hand_written_cost, unused_options

base = load_scene(BARE_SCENE)
rungs = {"hand-written (18)": {}, "+ offset, masses, cylinder loop": dict(layout=True),
         "+ load terms, starter switch": dict(layout=True, loads=True),
         "+ work integrals, speed range": dict(layout=True, loads=True, records=True)}
t_hand = None
for name, flags in rungs.items():
    t = hand_written_cost(base, **flags)
    t_hand = t_hand or t
    print(f"{name}: {t * 1e9:.1f} ns per call ({t / t_hand:.3f}× hand-written)")
b = bare_kernel()
for kin in ("exact", "tabulated"):
    t = b[f"{kin}_s"]
    print(f"transient {kin}: {t * 1e9:.1f} ns per call ({t / b['hand_written_s']:.3f}× "
          f"hand-written, timed again)")
u = unused_options()
print(f"run, bare scene: {u['bare_s']:.4f} s; with an idle governor and starter: "
      f"{u['unused_s']:.4f} s ({u['change']:+.1%}; the bare runs' IQR {u['bare_iqr']:.1%})")
