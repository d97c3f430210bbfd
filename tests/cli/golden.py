"""Golden values: what ``transient run`` gives for every scene in ``cases/``, kept in
``tests/data/golden/`` so that a change which alters any result shows as a failing test and, once
intended, as a reviewed diff of those files.

Regenerate (after a change meant to alter results, and review ``git diff tests/data/golden``)::

    .venv/bin/python tests/cli/golden.py

What is kept per scene: the end of the run (t, φ, ω), every scalar the run stored under
``/analysis``, ω at 17 samples spread over the run, and the sample count. Step counts are not kept:
they may differ between processors whose compiled code rounds differently, while the values agree
to far below the tolerance that :func:`compare` allows.
"""
from __future__ import annotations

import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"
GOLDEN = REPO / "tests" / "data" / "golden"
#: Relative agreement asked of every value: far below any scene's rtol (1e-8 and looser), far
#: above the last-bit differences between processors.
RTOL = 1e-9
SAMPLES = 17


def scenes() -> list[Path]:
    """Every scene of ``cases/`` (the sweeps' folder holds sweep files, not scenes)."""
    return sorted(CASES.glob("*.toml"))


def run(scene: Path, out: Path) -> Path:
    """The scene through the command, as a user runs it; the result file's path."""
    from transient.cli import main

    code = main(["run", str(scene), "-o", str(out), "-q"])
    if code != 0:
        raise RuntimeError(f"transient run {scene.name} exited {code}")
    return out / f"{scene.stem}.h5"


def capture(path: Path) -> dict:
    """The golden values of one result file."""
    from transient.results import open_result

    res = open_result(path)
    traj = res.trajectory
    n = traj["t"].size
    picks = np.unique(np.linspace(0, n - 1, SAMPLES).round().astype(int))
    analysis = {name: float(value) for name, (value, _unit) in sorted(res.analysis.items())
                if np.ndim(value) == 0 and isinstance(value, (int, float, np.number))
                and not isinstance(value, (bool, np.bool_))}
    return {"samples": int(n),
            "end": {k: float(traj[k][-1]) for k in ("t", "phi", "omega")},
            "omega": [float(traj["omega"][i]) for i in picks],
            "analysis": analysis}


def _close(a: float, b: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= RTOL * max(abs(a), abs(b)) or a == b


def compare(got: dict, want: dict) -> list[str]:
    """What differs between two captures, one line each (empty when they agree)."""
    diffs = []
    if got["samples"] != want["samples"]:
        diffs.append(f"samples: {got['samples']} against {want['samples']}")
    for k, v in want["end"].items():
        if not _close(got["end"][k], v):
            diffs.append(f"end {k}: {got['end'][k]!r} against {v!r}")
    if len(got["omega"]) != len(want["omega"]) or not all(
            _close(a, b) for a, b in zip(got["omega"], want["omega"])):
        diffs.append(f"omega samples: {got['omega']} against {want['omega']}")
    for k in sorted(set(got["analysis"]) | set(want["analysis"])):
        if k not in got["analysis"] or k not in want["analysis"]:
            diffs.append(f"analysis {k}: present in only one of them")
        elif not _close(got["analysis"][k], want["analysis"][k]):
            diffs.append(f"analysis {k}: {got['analysis'][k]!r} against {want['analysis'][k]!r}")
    return diffs


def regenerate() -> None:
    GOLDEN.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes():
            values = capture(run(scene, Path(tmp)))
            (GOLDEN / f"{scene.stem}.json").write_text(json.dumps(values, indent=1) + "\n")
            print(f"{scene.stem}: {values['samples']} samples")


if __name__ == "__main__":
    sys.exit(regenerate())
