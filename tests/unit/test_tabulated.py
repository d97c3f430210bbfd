"""The tabulated reduced model (:mod:`transient.tabulate`, :mod:`transient.core.model.tabulated`)
against the exact kernels: values at angles the error estimate never looked at, derivatives by
finite differences of the tables themselves, the refinement rule; runs with the tables are in
``tests/validation/test_tabulated_runs.py``."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from transient.core.model.tabulated import tabulated_terms
from transient.errors import SceneError
from transient.scene import load_scene
from transient.tabulate import MIN_INTERVALS, build_table, exact_terms

CASES = Path(__file__).resolve().parents[2] / "cases"
SCENES = ["coasting_single", "gots_diesel_governed", "swash_plate_4cyl"]


def mechanism(stem):
    scene = load_scene(CASES / f"{stem}.toml")
    mech = scene.mechanism
    return mech.kernel, mech.pack(), mech.n_cylinders


def table_values(coef, ncyl, phi):
    out = np.empty((2 + 2 * ncyl, phi.size))
    u, du = np.empty(ncyl), np.empty(ncyl)
    for j, p in enumerate(phi):
        out[0, j], out[1, j] = tabulated_terms(coef, p, u, du)
        out[2: 2 + ncyl, j] = u
        out[2 + ncyl:, j] = du
    return out


@pytest.mark.parametrize("stem", SCENES)
@pytest.mark.parametrize("target", [1e-6, 1e-10])
def test_error_estimate_holds_at_random_angles(stem, target):
    """At 20 000 random angles (over several revolutions, negative ones too) the tables deviate
    from the exact kernel by ≤ 2× their estimate, which is ≤ the target."""
    kind, mech, ncyl = mechanism(stem)
    tab = build_table(kind, mech, ncyl, target)
    assert tab.coef is not None and tab.error <= target
    phi = np.random.default_rng(1).uniform(-4 * math.pi, 8 * math.pi, 20000)
    exact = exact_terms(kind, mech, ncyl, phi)
    got = table_values(tab.coef, ncyl, phi)
    scale = np.max(np.abs(exact_terms(kind, mech, ncyl, np.linspace(0, 2 * math.pi, 4097))),
                   axis=1)[:, None]
    worst = np.max(np.abs(got - exact) / scale)
    print(f"{stem} target {target:g}: {tab.intervals} intervals, estimate {tab.error:.2e}, "
          f"random angles {worst:.2e}")
    assert worst <= 2.0 * tab.error


@pytest.mark.parametrize("stem", SCENES)
def test_table_derivatives_are_the_derivatives_of_the_tables(stem):
    """dJ and u′ from the tables equal central differences of the tabulated J and u (step 1e-5,
    inside intervals: O(h²) ≈ 1e-10 relative): the tabulated model is a consistent mechanism."""
    kind, mech, ncyl = mechanism(stem)
    coef = build_table(kind, mech, ncyl, 1e-8).coef
    n = coef.shape[1]
    h_grid = 2 * math.pi / n
    phi = (np.arange(0, n, 7) + 0.5) * h_grid
    d = 1e-5
    plus, minus, mid = (table_values(coef, ncyl, phi + s) for s in (d, -d, 0.0))
    fd = (plus - minus) / (2 * d)
    rows_f = [0] + list(range(2, 2 + ncyl))
    rows_d = [1] + list(range(2 + ncyl, 2 + 2 * ncyl))
    scale = np.max(np.abs(mid[rows_d]), axis=1)[:, None]
    assert np.max(np.abs(fd[rows_f] - mid[rows_d]) / scale) <= 1e-8


def test_refinement_doubles_until_the_target():
    """Tighter targets need at least as many intervals; the loosest needs the minimum."""
    kind, mech, ncyl = mechanism("gots_diesel_governed")
    sizes = [build_table(kind, mech, ncyl, t).intervals for t in (1e-3, 1e-8, 1e-11)]
    assert sizes[0] == MIN_INTERVALS
    assert sizes == sorted(sizes) and sizes[2] > sizes[0]


def test_tabulated_is_for_compiled_methods_only(tmp_path):
    text = (CASES / "coasting_single.toml").read_text().replace(
        "[solver]", '[solver]\nmethod = "scipy-DOP853"\nkinematics = "tabulated"')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match="solver.kinematics"):
        load_scene(path)
    path.write_text((CASES / "coasting_single.toml").read_text().replace(
        "[solver]", '[solver]\nkinematics = "fourier"'))
    with pytest.raises(SceneError, match="solver.kinematics"):
        load_scene(path)
