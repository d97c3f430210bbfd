"""Golden values: what ``transient run`` gives for every scene in ``cases/``, kept in
``tests/data/golden/`` so that a change which alters any result shows as a failing test and, once
intended, as a reviewed diff of those files.

Regenerate (after a change meant to alter results, and review ``git diff tests/data/golden``)::

    .venv/bin/python tests/cli/golden.py                  # every scene
    .venv/bin/python tests/cli/golden.py gots_diesel_pi   # the scenes named

What is kept per scene: the end of the run (t, φ, ω), every scalar the run stored under
``/analysis`` with its unit, ω at 17 samples spread over the run, the sample count, the scene's
rtol and atol, and the *error* of each of these values: how far the same scene run at a hundredth
of its rtol and atol puts it (``tests/own_error.py``).

Why the error, and not bit-reproducibility: compiled code and linear algebra round differently on
another CPU, a last-bit difference flips an accepted step into a rejected one or moves an event's
root by an ulp, and from there the steps differ. A value is then off by the difference of two
integration errors of the same size, each what the scene's tolerance admits — which the run at
the tighter tolerance measures, value by value: an end state after hundreds of revolutions has
accumulated far more than one step's error, and a loss through a map's kinks (which rtol does not
control) more still. :func:`compare` holds each value to ``MOVE`` times its error, with a floor
of the scene's rtol times the value's scale (:func:`tolerances`): a value that is zero in exact
arithmetic (an energy-balance residual, the overshoot of a monotone spin-up) is rounding noise
whose error says nothing, and is held to the tolerance of the quantity it is a residual of. Step
counts are not kept: they follow the step sequence.
"""
from __future__ import annotations

import json
import math
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
CASES = REPO / "cases"
GOLDEN = REPO / "tests" / "data" / "golden"
SAMPLES = 17
#: The scale below which a dimensionless value or a percentage is a fraction of a whole: a
#: residual or a share relative to 1, a percentage of 100.
WHOLE = {"1": 1.0, "%": 100.0}

# (what the tests share is on pytest's path, pyproject; as a script this file puts it there)
sys.path.insert(0, str(REPO / "tests"))
from own_error import MOVE, tightened  # noqa: E402


def scenes() -> list[Path]:
    """Every scene of ``cases/`` that runs (the sweeps' folder holds sweep files, not scenes),
    but those with an elastic shaft line, ``[shaft]``: their run-ups are long, and their runs
    are held against the reference line's in ``tests/validation/test_elastic_runs.py``."""
    return sorted(p for p in CASES.glob("*.toml")
                  if tomllib.loads(p.read_text(encoding="utf-8")).get("shaft") is None)


def run(scene: Path, out: Path) -> Path:
    """The scene through the command, as a user runs it; the result file's path."""
    from transient.cli import main

    code = main(["run", str(scene), "-o", str(out), "-q"])
    if code != 0:
        raise RuntimeError(f"transient run {scene.name} exited {code}")
    return out / f"{scene.stem}.h5"


def capture(path: Path) -> dict:
    """The golden values of one result file, with the scene's solver tolerance (not the
    errors, which take a second run: :func:`regenerate`)."""
    from transient.results import open_result

    res = open_result(path)
    traj = res.trajectory
    n = traj["t"].size
    picks = np.unique(np.linspace(0, n - 1, SAMPLES).round().astype(int))
    scalars = {name: (float(value), unit) for name, (value, unit) in sorted(res.analysis.items())
               if np.ndim(value) == 0 and isinstance(value, (int, float, np.number))
               and not isinstance(value, (bool, np.bool_))}
    solver = res.scene().solver
    return {"solver": {"rtol": solver.rtol, "atol": solver.atol},
            "samples": int(n),
            "end": {k: float(traj[k][-1]) for k in ("t", "phi", "omega")},
            "omega": [float(traj["omega"][i]) for i in picks],
            "analysis": {name: value for name, (value, _) in scalars.items()},
            "units": {name: unit for name, (_, unit) in scalars.items()}}


def _values(c: dict) -> dict:
    """Every compared value of a capture (or of its errors), by a name for the diff."""
    values = {"samples": c["samples"]}
    values.update({f"end {k}": v for k, v in c["end"].items()})
    values.update({f"omega sample {i}": v for i, v in enumerate(c["omega"])})
    values.update({f"analysis {k}": v for k, v in c["analysis"].items()})
    return values


def with_errors(values: dict, reference: dict) -> dict:
    """``values`` with the error of each: its distance from ``reference``, the same scene's
    capture at the tighter tolerance. A value that is NaN in one run and not in the other, or
    present in one only, has no error to keep: the scene does not determine it."""
    a, b = _values(values), _values(reference)
    if a.keys() != b.keys():
        raise ValueError(f"values in one run only: {sorted(a.keys() ^ b.keys())}")
    errors = {}
    for name, v in a.items():
        if math.isnan(v) != math.isnan(b[name]):
            raise ValueError(f"{name} is {v!r}, and {b[name]!r} at the tighter tolerance")
        errors[name] = 0.0 if math.isnan(v) else abs(v - b[name])
    return dict(values, error=errors)


def tolerances(want: dict) -> dict:
    """How far each value of ``want`` may move: ``MOVE`` times its error, plus the
    scene's rtol times its scale, plus atol for the states (t, φ, ω).

    The scale: |t| and |φ| for the end's; the largest |ω| of the samples for ω (a run that rocks
    through ω = 0 is accurate relative to its swing, not to the ω of one instant); for a
    dimensionless value or a percentage, the whole it is a fraction of (:data:`WHOLE`: a
    residual, a share, an efficiency) or itself where larger (a count); for any other analysis
    value, the largest magnitude among the scene's values of its unit — a loss per cycle is
    integrated along with the work it is part of, a time along the run's span. A sample count
    has none: it is exact, unless the reference's count differs."""
    rtol, atol = want["solver"]["rtol"], want["solver"]["atol"]
    analysis, units = want["analysis"], want["units"]
    largest: dict[str, float] = {}
    for name, unit in units.items():
        if not math.isnan(analysis[name]):
            largest[unit] = max(largest.get(unit, 0.0), abs(analysis[name]))

    def scale(name: str) -> float:
        unit = units[name]
        if unit in WHOLE:
            return max(WHOLE[unit], abs(analysis[name]))
        return largest.get(unit, 0.0)

    omega = max(abs(w) for w in want["omega"])
    floor = {"samples": 0.0,
             "end t": rtol * abs(want["end"]["t"]) + atol,
             "end phi": rtol * abs(want["end"]["phi"]) + atol,
             "end omega": rtol * omega + atol}
    floor.update({f"omega sample {i}": rtol * omega + atol for i in range(len(want["omega"]))})
    floor.update({f"analysis {name}": rtol * scale(name) for name in units})
    return {name: MOVE * err + floor[name] for name, err in want["error"].items()}


def compare(got: dict, want: dict) -> list[str]:
    """What differs between a capture and the golden values, one line each (empty when they
    agree), each value against its tolerance (:func:`tolerances`)."""
    lacking = sorted({"solver", "units", "error"} - want.keys())
    if lacking:
        return [f"the golden values lack {lacking}: regenerate them (tests/cli/golden.py)"]
    diffs = []
    if got["solver"] != want["solver"]:
        diffs.append(f"solver: {got['solver']} against {want['solver']}")
    for name in sorted(got["units"].keys() & want["units"].keys()):
        if got["units"][name] != want["units"][name]:
            diffs.append(f"unit of analysis {name}: {got['units'][name]} against "
                         f"{want['units'][name]}")
    a, b = _values(got), _values(want)
    diffs += [f"{name}: present in only one of them" for name in sorted(a.keys() ^ b.keys())]
    tol = tolerances(want)
    for name in sorted(a.keys() & b.keys()):
        x, v = a[name], b[name]
        if math.isnan(x) or math.isnan(v):
            if math.isnan(x) != math.isnan(v):
                diffs.append(f"{name}: {x!r} against {v!r}")
        elif abs(x - v) > tol[name]:
            diffs.append(f"{name}: {x!r} against {v!r}, off by {abs(x - v):.3g} where "
                         f"{tol[name]:.3g} is allowed")
    return diffs


def reference_scene(scene: Path, folder: Path) -> Path:
    """``scene`` at the tighter tolerance (``tests/own_error.py``), written in ``folder`` under
    the same name (the resolved scene, its tables inline)."""
    from transient.scene import load_scene, to_toml

    path = folder / scene.name
    path.write_text(to_toml(tightened(load_scene(scene))))
    return path


def regenerate(names: list[str]) -> None:
    """Write the golden values of the scenes ``names`` (stems; all when empty)."""
    chosen = [s for s in scenes() if not names or s.stem in names]
    unknown = set(names) - {s.stem for s in chosen}
    if unknown:
        raise SystemExit(f"no scene {sorted(unknown)} in {CASES}")
    GOLDEN.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for scene in chosen:
            out, ref = Path(tmp, scene.stem), Path(tmp, f"{scene.stem}-reference")
            ref.mkdir(parents=True)
            values = capture(run(scene, out))
            reference = capture(run(reference_scene(scene, ref), ref))
            try:
                values = with_errors(values, reference)
            except ValueError as e:
                raise SystemExit(f"{scene.name}: {e}") from None
            (GOLDEN / f"{scene.stem}.json").write_text(json.dumps(values, indent=1) + "\n")
            print(f"{scene.stem}: {values['samples']} samples")


if __name__ == "__main__":
    regenerate(sys.argv[1:])
