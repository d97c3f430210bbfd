"""What the friction models cost scenes that do not use them, scene by scene: ``tools/ab_wall.py``
on this checkout against a copy of its package without those models' code
(:func:`transient.verify.models_out.left_out_copy`), in alternating rounds. ``transient bench
--targets`` records the same comparison; this prints every round, with the time inside the
compiled stepper.

    .venv/bin/python tools/ab_models.py            # 3 rounds; the copy compiles cold once
    .venv/bin/python tools/ab_models.py --rounds 5
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from transient.verify.models_out import left_out_copy

REPO = Path(__file__).resolve().parents[1]


def ab_wall(path: Path) -> list[str]:
    """The lines of ``tools/ab_wall.py`` importing transient from ``path``."""
    env = {**os.environ, "PYTHONPATH": str(path)}
    run = subprocess.run([sys.executable, str(REPO / "tools" / "ab_wall.py")], env=env,
                         capture_output=True, text=True, check=True)
    return run.stdout.splitlines()[1:]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    rounds = parser.parse_args().rounds
    with tempfile.TemporaryDirectory(prefix="transient-models-out-") as tmp:
        trees = {"this checkout": REPO, "models left out": left_out_copy(Path(tmp))}
        for tree in trees.values():  # (the copy's kernels compile here, once)
            ab_wall(tree)
        for r in range(1, rounds + 1):
            for label, tree in trees.items():
                print(f"round {r}, {label}:", *(f"  {line}" for line in ab_wall(tree)), sep="\n")


if __name__ == "__main__":
    main()
