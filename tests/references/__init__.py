"""What the suite compares the model against, in one place for the tests and for the docs.

Each *case* is a function that runs the model (the package itself: kinematics, loads, gas
tables, short runs) and returns its :class:`Comparison` s: a reference value or table column
with where it comes from and the misprints found in it, the model's value, and the tolerance it
is checked to with the reason. The test named by the case calls it and asserts every comparison
(:meth:`Comparison.check`); the Validation page (``docs/_ext/validation_pages.py``) calls the
same cases and renders their comparisons as tables and figures. So a reference number, a
tolerance or a computed value is written once, and the page shows what the tests assert.

A reference value is one of three *kinds*: ``printed`` (a number or table as printed, misprints
named), ``formula`` (a printed formula evaluated here, independently of the package) or
``independent`` (an independent computation: another method, named in ``source``).

The sources: Gots (2006), the worked example of §2.9 and its Appendices (:mod:`.gots`; the
tables in ``tests/data``); Antonyuk, Sakharnov and Koval, the swash-plate engine
(:mod:`.antonyuk`); Semenov (1947), master and articulated rods (:mod:`.semenov`); closed forms
and conservation laws (:mod:`.closed_forms`). Not to be confused with the *reference path*,
:mod:`transient.reference`, the model written a second time.
"""
from __future__ import annotations

import csv
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

#: The published tables as printed (``tests/data/README.md``: provenance, misprints, checksums).
DATA = Path(__file__).resolve().parents[1] / "data"
KINDS = ("printed", "formula", "independent")


def read_table(name: str) -> dict[str, np.ndarray]:
    """A CSV of ``tests/data`` as columns of floats, by header name."""
    with (DATA / name).open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


@dataclass(frozen=True)
class Tolerance:
    """What a comparison must satisfy, and why that much.

    ``abs``/``rel`` bound the largest deviation |computed − reference| (``rel`` relative to the
    reference's magnitude, elementwise); ``low``/``high`` bound the computed value itself (a
    claim such as "at least three times smoother", or a value the source gives as a range).
    """

    why: str
    abs: float | None = None
    rel: float | None = None
    low: float | None = None
    high: float | None = None

    def __post_init__(self):
        if (self.abs is None) + (self.rel is None) + (self.low is None and self.high is None) != 2:
            raise ValueError("a tolerance is one of abs, rel, or bounds (low and/or high)")

    @property
    def on_deviation(self) -> bool:
        return self.abs is not None or self.rel is not None

    @property
    def bound(self) -> float:
        """The largest deviation allowed (abs or rel)."""
        return self.abs if self.abs is not None else self.rel


@dataclass(frozen=True)
class Comparison:
    """One reference value (or table column) against the model.

    ``reference`` and ``computed`` are scalars or arrays over ``at``, named by ``at_name`` (crank
    angles in degrees for a table column). A comparison with bounds may have no reference value
    (``None``).
    """

    quantity: str
    source: str
    kind: str
    reference: float | np.ndarray | None
    computed: float | np.ndarray
    unit: str
    tolerance: Tolerance
    note: str = ""
    at: np.ndarray | None = None
    at_name: str = "φ [°]"
    test: str = ""  # set by :func:`case`

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"kind {self.kind!r} is not one of {KINDS}")

    @property
    def deviation(self) -> np.ndarray:
        """|computed − reference|, relative to |reference| where the tolerance is relative."""
        dev = np.abs(np.asarray(self.computed, float) - np.asarray(self.reference, float))
        if self.tolerance.rel is not None:
            dev = dev / np.abs(np.asarray(self.reference, float))
        return np.atleast_1d(dev)

    @property
    def worst(self) -> int:
        """Index of the element that decides the check (the largest deviation, or the
        computed value nearest a bound)."""
        if self.tolerance.on_deviation:
            return int(np.argmax(self.deviation))
        values = np.atleast_1d(np.asarray(self.computed, float))
        lo, hi = self.tolerance.low, self.tolerance.high
        margin = np.minimum(values - lo if lo is not None else np.inf,
                            hi - values if hi is not None else np.inf)
        return int(np.argmin(margin))

    @property
    def statistic(self) -> float:
        """The number checked: the largest deviation, or the decisive computed value."""
        if self.tolerance.on_deviation:
            return float(self.deviation[self.worst])
        return float(np.atleast_1d(np.asarray(self.computed, float))[self.worst])

    @property
    def holds(self) -> bool:
        t, s = self.tolerance, self.statistic
        if t.on_deviation:
            return s <= t.bound
        return (t.low is None or s >= t.low) and (t.high is None or s <= t.high)

    @property
    def ratio(self) -> float:
        """The deviation as a share of its tolerance (≤ 1 holds); NaN for bounds."""
        t = self.tolerance
        return self.statistic / t.bound if t.on_deviation else math.nan

    @property
    def failure(self) -> str:
        """What failed and where, for an assertion's message."""
        where = (f" at {self.at_name} = {self.at[self.worst]:g}"
                 if self.at is not None and np.size(self.computed) > 1 else "")
        t = self.tolerance
        limit = (f"≤ {t.abs:g} {self.unit}" if t.abs is not None else
                 f"≤ {t.rel:g} relative" if t.rel is not None else
                 f"within [{t.low}, {t.high}] {self.unit}")
        return f"{self.quantity} ({self.source}): {self.statistic:.6g}{where}, allowed {limit}"

    def check(self) -> None:
        assert self.holds, self.failure


#: Every case, by its qualified name ``module.function``: what the page renders.
CASES: dict[str, Callable[[], tuple[Comparison, ...]]] = {}


def case(test: str):
    """Register a case; ``test`` is the test (``folder/file.py::function``, under ``tests/``)
    that calls it and asserts its comparisons. Results are cached: the page and the tests of one
    process build each case once."""

    def register(fn):
        name = f"{fn.__module__.rpartition('.')[2]}.{fn.__name__}"

        @functools.wraps(fn)
        @functools.cache
        def build() -> tuple[Comparison, ...]:
            return tuple(replace(c, test=test) for c in fn())

        build.test = test
        CASES[name] = build
        return build

    return register


def check_all(comparisons) -> None:
    """Assert every comparison; the message names each that fails."""
    failed = [c.failure for c in comparisons if not c.holds]
    assert not failed, "; ".join(failed)


def load_all() -> dict[str, Callable[[], tuple[Comparison, ...]]]:
    """Import every module of cases, so that :data:`CASES` holds them all."""
    from . import antonyuk, closed_forms, gots, semenov  # noqa: F401

    return CASES


__all__ = ["CASES", "Comparison", "DATA", "Tolerance", "case", "check_all", "load_all",
           "read_table"]
