"""Wiebe cycles kept on disk between processes: a warm start does not integrate them again.

A scene with ``model = "wiebe"`` needs its motored and full-load cycles
(:func:`transient.scene.queries.wiebe_levels`). Integrating them with scipy's DOP853, and importing
scipy's integrators for it, is a large part of such a scene's warm start. The cycles depend only
on their arguments and on the code, so they are stored in
``$XDG_CACHE_HOME/transient/tables/`` (default ``~/.cache``), one ``.npz`` per set of cycles,
named by a hash of the arguments' exact text, of every source file of transient and of numpy's
and scipy's versions: an edit anywhere in the package, or another numpy or scipy, starts afresh.

Stored are the tables and the numbers of each :class:`~transient.forces.wiebe.WiebeCycle`, not the
dense ODE solution :attr:`~transient.forces.wiebe.WiebeCycle.closed` (scipy objects, used by
checks): a cycle read from the cache carries a stand-in that knows the closed part's ends and
integrates the cycles again on first use of anything else.

A file that cannot be read is computed again and replaced; a folder that cannot be written is
passed over (the run goes on with the cycles it computed). Files are written to a temporary name
and renamed, so a reader never sees half a file, and the folder keeps the :data:`MAX_FILES` last
used (a sweep over cycle parameters would otherwise fill it without end).
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import os
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from transient.core import cache_root, source_hash
from transient.forces.wiebe import WiebeCycle

if TYPE_CHECKING:
    from transient.forces.closed_cycle import ClosedPart

#: Files the folder keeps: writing one more deletes the least recently used beyond it (a file of
#: the Gots engine's two cycles is 0.26 MB).
MAX_FILES = 200


def cache_folder() -> Path:
    """``tables`` in transient's cache folder (:func:`transient.core.cache_root`), read at every
    call (tests point it elsewhere)."""
    return cache_root() / "tables"


@functools.cache
def _code_version() -> str:
    """Hash of every source file of the package and of numpy's and scipy's versions."""
    import scipy  # the top-level package only (its version); not its integrators

    sources = source_hash(Path(__file__).resolve().parents[1], "**/*.py")
    return hashlib.sha256(f"numpy {np.__version__} scipy {scipy.__version__} "
                          f"{sources}".encode()).hexdigest()


def cache_path(arguments: str) -> Path:
    """The file of the cycles computed from ``arguments`` (the exact text of all of them)."""
    key = hashlib.sha256(f"{_code_version()}\n{arguments}".encode()).hexdigest()[:32]
    return cache_folder() / f"wiebe-{key}.npz"


class _ClosedPartOnDemand:
    """Stands for the :class:`~transient.forces.closed_cycle.ClosedPart` of a cycle read from the
    cache.

    ``start`` and ``end`` (intake closing and exhaust opening, unwrapped, as the assembled Woschni
    model needs them) are stored; any other attribute, or a call, integrates the cycles again
    (once for all the cycles of the file) and answers from the fresh ClosedPart."""

    def __init__(self, start: float, end: float, closed_part: Callable) -> None:
        self.start, self.end, self._closed_part = start, end, closed_part

    def __getattr__(self, name: str):  # only for what __init__ did not set
        if name.startswith("_"):  # (copy and pickle probe an instance that __init__ never saw)
            raise AttributeError(name)
        return getattr(self._closed_part(), name)

    def __call__(self, x):
        return self._closed_part()(x)


def _write(path: Path, cycles: tuple[WiebeCycle, ...]) -> None:
    arrays: dict[str, np.ndarray] = {"n": np.array(len(cycles))}
    for i, cycle in enumerate(cycles):
        for field in dataclasses.fields(WiebeCycle):
            if field.name != "closed":
                arrays[f"{i}.{field.name}"] = np.asarray(getattr(cycle, field.name))
        arrays[f"{i}.closed.start"] = np.asarray(cycle.closed.start)
        arrays[f"{i}.closed.end"] = np.asarray(cycle.closed.end)
    path.parent.mkdir(parents=True, exist_ok=True)
    f = tempfile.NamedTemporaryFile(dir=path.parent, suffix=".tmp", delete=False)
    temporary = Path(f.name)
    try:
        with f:
            np.savez(f, **arrays)  # type: ignore[arg-type]  # (no key is numpy's allow_pickle)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)  # (gone once renamed; a failed write's remains)
    _prune(path.parent)


def _prune(folder: Path) -> None:
    """Delete the least recently used files beyond :data:`MAX_FILES`."""
    files = sorted(folder.glob("wiebe-*.npz"), key=lambda p: p.stat().st_mtime)
    for path in files[:-MAX_FILES]:
        path.unlink(missing_ok=True)


def _read(path: Path, compute: Callable[[], tuple]) -> tuple[WiebeCycle, ...]:
    again = functools.cache(compute)
    cycles = []
    with np.load(path) as data:
        for i in range(int(data["n"])):
            values = {}
            for field in dataclasses.fields(WiebeCycle):
                if field.name != "closed":
                    value = data[f"{i}.{field.name}"]  # a table's array, or a number (0-d)
                    values[field.name] = value.item() if value.ndim == 0 else value
            closed = _ClosedPartOnDemand(data[f"{i}.closed.start"].item(),
                                         data[f"{i}.closed.end"].item(),
                                         lambda i=i: again()[i].closed)
            # (the stand-in answers as the ClosedPart it stands for)
            cycles.append(WiebeCycle(closed=cast("ClosedPart", closed), **values))
    return tuple(cycles)


def cached_cycles(arguments: str, compute: Callable[[], tuple[WiebeCycle, ...]]
                  ) -> tuple[WiebeCycle, ...]:
    """The cycles ``compute()`` returns, read from the cache when a file for ``arguments`` (the
    exact text of everything ``compute`` depends on besides the code) is there, else computed and
    stored. A SceneError from ``compute`` (invalid cycle parameters) passes through; nothing is
    stored then."""
    path = cache_path(arguments)
    try:
        cycles = _read(path, compute)
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        pass  # not there yet, or unreadable: computed again and replaced
    else:
        with contextlib.suppress(OSError):  # (a read-only folder keeps its order)
            os.utime(path)  # used now: the last to be deleted
        return cycles
    cycles = compute()
    try:
        _write(path, cycles)
    except OSError:
        pass  # a folder that cannot be written: the run goes on with what it computed
    return cycles
