"""The sweep file (HDF5): each run in a result's layout, and the summary table of the sweep.

Only the client writes it (:class:`SweepStore`), run by run as results arrive, so that an
interrupted sweep resumes from what is there. What a run stores — header, ``scene/toml``,
``trajectory``, ``events``, ``solver``, ``analysis`` — is written by :mod:`transient.results`,
so a run of a sweep reads back as a :class:`~transient.results.Result` (:func:`open_run`); what
is the sweep's own — the sweep file, its axes, the runs' index and status, the summary — is
written here.
"""
from __future__ import annotations

import csv
import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .. import results
from ..analysis.summary import nan_reason
from ..errors import SceneError
from ..outcome import FINISHED
from ..units import ALL_SUFFIXES
from .spec import QUANTITIES, RunSpec, Sweep


def group_name(index: int, n_runs: int) -> str:
    """The group of run ``index`` under ``/runs``: zero-padded so that the groups sort in run
    order."""
    return f"run_{index:0{max(4, len(str(n_runs - 1)))}d}"


#: The group of the finished runs a sweep no longer holds.
UNUSED = "unused"


def finished(status: str) -> bool:
    """Whether a stored run's ``status`` (a result's: :data:`transient.outcome.STATUSES`) says
    it did what its scene describes; ``ok`` is how files written before said it."""
    return status in (FINISHED, "ok")


@dataclass(frozen=True)
class Stored:
    """A stored run found in a sweep file: where it is, its resolved scene, whether it ended
    ``finished``, and its axis values (which identify a point of the sweep)."""

    path: str
    toml: str
    ok: bool
    params: dict[str, Any]


def match_runs(stored: list[Stored], runs: tuple[RunSpec, ...], targets: list[str],
               retry_failed: bool = False) -> dict[int, Stored]:
    """The stored run each run of the sweep reuses (by index): one with the same resolved scene,
    a finished one before a failed one and the one already at ``targets[index]`` before another,
    so that nothing moves without need; never a failed one with ``retry_failed``. Each stored
    run serves one run at most (a list sweep may hold one scene twice)."""
    by_scene: dict[str, list[Stored]] = {}
    for s in stored:
        if s.ok or not retry_failed:
            by_scene.setdefault(s.toml, []).append(s)
    out = {}
    for spec in runs:
        pool = by_scene.get(spec.toml)
        if pool:
            best = min(pool, key=lambda s: (not s.ok, s.path != targets[spec.index]))
            pool.remove(best)
            out[spec.index] = best
    return out


class SweepStore:
    """The sweep file (HDF5), written by the client only.

    Layout: root attributes as a result file (``creator``, ``version``, ``format``, ``created``,
    ``complete``) plus ``kind = "sweep"``, ``sweep`` (its name) and ``n_runs``; ``/sweep/toml``
    the sweep file; ``/sweep`` attributes ``method``, ``axes`` and ``collect`` (JSON);
    ``/runs/run_<i>`` one group per run, laid out as a result file's root
    (:func:`transient.results.write_run`: header attributes with ``scene``, ``complete`` and
    ``message``; ``scene/toml``; ``trajectory/<col>`` with ``unit``; ``events/<name>/{t,phi}``;
    ``solver`` attributes; ``analysis/<name>``, the run's summary, with ``unit``), with the
    sweep's attributes ``index``, ``params`` (JSON), ``scene_toml`` (the resolved scene, by which
    a run is reused), ``worker``, ``wall_s`` and ``status`` (the run's, as a result's:
    ``finished``, ``stalled``, …, ``failed``; written last: a group without it is unfinished);
    ``/unused/scene_<hash>`` finished runs the sweep no longer
    holds, in the same form (kept, so that no computed run is lost, and reused if the sweep
    holds their scene again); ``/analysis/summary`` the table of collected quantities
    (attribute ``units``, JSON).

    While the sweep runs the file is ``.<name>.h5.part``; it is renamed when every run is done.
    An existing file of the same sweep (by name) is mended: a stored run whose resolved scene a
    run of the sweep has is reused, at that run's place; the others are parked in ``/unused``.
    Runs only ever move by renaming a group, and a run is written under a free name with its
    ``status`` last, so that an interrupt at any instant loses no finished run and counts no
    half-written one. A file of another sweep is never overwritten without ``force``.
    """

    def __init__(self, path: Path, sweep: Sweep, force: bool = False,
                 retry_failed: bool = False) -> None:
        self.path, self.sweep = Path(path), sweep
        self.part = results.partial_path(self.path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if not os.access(self.path.parent, os.W_OK):
            raise PermissionError(f"{self.path.parent}: folder is not writable")
        if force:
            for p in (self.path, self.part, self.path.with_name(f"{self.path.stem}_summary.csv")):
                p.unlink(missing_ok=True)
        found = next((p for p in (self.part, self.path) if p.exists()), None)
        if found is None:
            self.f = self._create(self.part)
        else:
            self._check(found)  # raises, changing nothing, if it is another sweep
            os.replace(found, self.part)  # a finished file being mended is a part again
            self.f = results.reopen_file(self.part)
        try:
            self.finished, self.recomputed = self._prepare(retry_failed)
        except BaseException:
            self.f.close()  # (what was done so far is consistent: see the class docstring)
            raise

    def _check(self, path: Path) -> None:
        """An existing file must hold this sweep: a sweep file of the same name."""
        try:
            with h5py.File(path, "r") as f:
                kind, name = f.attrs.get("kind"), f.attrs.get("sweep")
        except OSError as exc:
            raise SceneError("(file)", f"cannot open to resume: {exc}; use --force to start "
                                       f"afresh", file=str(path)) from None
        if kind == "sweep" and name == self.sweep.name:
            return
        what = (f"holds another sweep ({name!r}, not {self.sweep.name!r})" if kind == "sweep"
                else "is not a sweep file")
        raise FileExistsError(f"{path}: exists and {what}; use --force to replace it or -o "
                              f"another folder")

    def _create(self, path: Path) -> h5py.File:
        f = results.create_file(path)
        results.write_header(f, kind="sweep", sweep=self.sweep.name, complete=False,
                             n_runs=len(self.sweep.runs))
        f.create_group("sweep").create_dataset("toml", data=self.sweep.text)
        f.create_group("runs")
        f.create_group(UNUSED)
        f.create_group("analysis")
        return f

    def _prepare(self, retry_failed: bool) -> tuple[set[int], set[int]]:
        """Put every stored run the sweep reuses at its place, park the others in ``/unused``;
        returns the indices of the reused runs and of the runs computed again (a stored run of
        the same axis values had another scene, or failed and ``retry_failed``). The summary of
        an earlier sweep is dropped: it is rewritten when this one ends."""
        self.f.attrs["complete"] = False
        self.f.require_group(UNUSED)
        if "summary" in self.f["analysis"]:
            del self.f["analysis/summary"]
        stored = self._stored()
        targets = [f"runs/{self.group_name(s.index)}" for s in self.sweep.runs]
        reuse = match_runs(stored, self.sweep.runs, targets, retry_failed)
        wanted = {s.path: targets[i] for i, s in reuse.items()}
        for s in stored:  # (out of the way first: a target may hold another run)
            if s.path.startswith("runs/") and wanted.get(s.path) != s.path:
                parked = self._park(s.path)
                if s.path in wanted:
                    wanted[parked] = wanted.pop(s.path)
        for src, dst in wanted.items():
            if src != dst:
                self.f.move(src, dst)
        for i in reuse:
            self.f[targets[i]].attrs.update(index=i, params=json.dumps(self.sweep.runs[i].params))
        self.f.attrs["n_runs"] = len(self.sweep.runs)
        self._write_sweep()
        self.f.flush()
        seen = [s.params for s in stored]
        again = {spec.index for spec in self.sweep.runs
                 if spec.index not in reuse and spec.params in seen}
        return set(reuse), again

    def _stored(self) -> list[Stored]:
        """The finished runs in ``/runs`` and ``/unused``; groups left half-written by an
        interrupt (no ``status``) are removed: they run again."""
        out = []
        for top in ("runs", UNUSED):
            node = self.f[top]
            for name in list(node):
                g = node[name]
                if "status" not in g.attrs:
                    del node[name]
                    continue
                params = json.loads(g.attrs.get("params", "{}"))
                out.append(Stored(f"{top}/{name}", str(g.attrs["scene_toml"]),
                                  finished(str(g.attrs["status"])), params))
        return out

    def _park(self, path: str) -> str:
        """Move a stored run into ``/unused`` under a free name (its scene's hash); returns it."""
        toml = str(self.f[path].attrs["scene_toml"])
        stem = f"{UNUSED}/scene_{hashlib.sha256(toml.encode()).hexdigest()[:16]}"
        name, k = stem, 1
        while name in self.f:
            name, k = f"{stem}_{k}", k + 1
        self.f.move(path, name)
        return name

    def _write_sweep(self) -> None:
        """The sweep's text and axes, (re)written: a mended sweep may differ in both."""
        g = self.f["sweep"]
        g["toml"][()] = self.sweep.text
        g.attrs.update(method=self.sweep.method, collect=json.dumps(self.sweep.collect),
                       axes=json.dumps([{"key": a.key, "group": a.group, "values": list(a.values)}
                                        for a in self.sweep.axes]))

    def group_name(self, index: int) -> str:
        return group_name(index, len(self.sweep.runs))

    def write_run(self, spec: RunSpec, res: dict[str, Any]) -> None:
        """One run's group (``res`` from :func:`~transient.sweeps.execute.run_one`); ``status``
        is written last and flushed, marking it finished."""
        runs = self.f["runs"]
        name = self.group_name(spec.index)
        if name in runs:  # (never a finished run lost: parked)
            self._park(f"runs/{name}")
        g = runs.create_group(name)
        g.attrs.update(index=spec.index, params=json.dumps(spec.params), scene_toml=spec.toml,
                       worker=res["worker"], wall_s=res["wall_s"])
        data = results.RunData(res["trajectory"], res["events"], res["solver"],
                               complete=res["complete"], message=res["message"])
        results.write_run(g, spec.scene.name, spec.toml, data, res["units"], res["summary"])
        g.attrs["status"] = res["status"]
        self.f.flush()
        self.finished.add(spec.index)

    def tidy(self, prune: bool = False) -> int:
        """When every run is done: delete the parked runs whose scene the sweep holds again (a
        failed run retried, a repeated point), and with ``prune`` every parked run; returns how
        many are kept."""
        scenes = {s.toml for s in self.sweep.runs}
        unused = self.f[UNUSED]
        for name in list(unused):
            if prune or unused[name].attrs["scene_toml"] in scenes:
                del unused[name]
        self.f.flush()
        return len(unused)

    def summary(self) -> tuple[list[dict[str, Any]], dict[str, str]]:
        """The summary rows (run order) and the units of their columns, from the stored runs."""
        units = {"run": "", "status": "", **{a.key: _suffix_unit(a.key) for a in self.sweep.axes},
                 **dict.fromkeys(self.sweep.collect, "")}
        rows = []
        for spec in self.sweep.runs:
            g = self.f["runs"].get(self.group_name(spec.index))
            if g is None or "status" not in g.attrs:
                continue
            row = {"run": spec.index, "status": str(g.attrs["status"]), **spec.params}
            for q in self.sweep.collect:
                value, unit = _quantity(g["analysis"], q)
                row[q] = value if finished(row["status"]) else math.nan
                units[q] = units[q] or unit
            row["wall_s"] = float(g.attrs["wall_s"])
            row["compile_s"] = float(g["solver"].attrs.get("compile_s", math.nan))
            row["note"] = _why_nan(row, self.sweep.collect, g["analysis"])
            row["message"] = str(g.attrs["message"])
            rows.append(row)
        units.update(wall_s="s", compile_s="s", note="", message="")
        return rows, units

    def write_summary(self, csv_path: Path) -> list[dict[str, Any]]:
        """``/analysis/summary`` and the CSV beside the file; returns the rows."""
        rows, units = self.summary()
        names = list(units)
        an = self.f["analysis"]
        if "summary" in an:
            del an["summary"]
        table = np.zeros(len(rows), dtype=[(n, _column_dtype(n, rows)) for n in names])
        for n in names:
            table[n] = [r.get(n, math.nan) for r in rows]
        ds = an.create_dataset("summary", data=table)
        ds.attrs["units"] = json.dumps(units)
        self.f.flush()
        with open(csv_path, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(names)
            w.writerows([[_csv(r.get(n, "")) for n in names] for r in rows])
        return rows

    def close(self, complete: bool) -> Path:
        """Close; a complete sweep gets its final name, an incomplete one stays a part."""
        if not self.f.id.valid:
            return self.part
        self.f.attrs["complete"] = bool(complete)
        self.f.close()
        if complete:
            os.replace(self.part, self.path)
            return self.path
        return self.part


def _suffix_unit(key: str) -> str:
    """The unit an axis key names by its suffix (``_rpm``, ``_deg`` …); "" for SI."""
    suffix = key.rpartition("_")[2]
    return suffix if suffix in ALL_SUFFIXES else ""


def _quantity(analysis, name: str) -> tuple[float, str]:
    """A collected quantity from a run's /analysis (a short name of QUANTITIES, or as stored)."""
    entry, factor, unit = QUANTITIES[name][:3] if name in QUANTITIES else (name, 1.0, None)
    if entry not in analysis:
        return math.nan, unit or ""
    return float(analysis[entry][()]) * factor, unit or str(analysis[entry].attrs.get("unit", ""))


def _why_nan(row: dict[str, Any], collect, analysis) -> str:
    """Why each collected quantity of ``row`` that is NaN is so (a run's ``analysis`` group
    holds its summary), "; "-separated; "" if none is."""
    nan = [q for q in collect if isinstance(row[q], float) and math.isnan(row[q])]
    if not nan:
        return ""
    if not finished(row["status"]):
        return f"not collected: the run ended {row['status']} (its message says how)"
    values = {k: float(ds[()]) for k, ds in analysis.items()
              if ds.ndim == 0 and ds.dtype.kind in "fiub"}
    return "; ".join(f"{q}: {nan_reason(QUANTITIES[q][0] if q in QUANTITIES else q, values)}"
                     for q in nan)


def _column_dtype(name: str, rows: list[dict]) -> Any:
    """A summary column's type in the HDF5 table: run indices whole, text as strings (a
    status, a message, a string axis), every other column float (NaN where a run failed)."""
    values = [r.get(name) for r in rows]
    if name == "run":
        return "<i8"
    if any(isinstance(v, str) for v in values):
        return h5py.string_dtype()
    return "<f8"


def _csv(value: Any) -> Any:
    """A CSV cell: floats by ``repr``, so that the CSV holds every digit of the table."""
    return repr(value) if isinstance(value, float) else value


# ------------------------------------------------------------------------------------------------
# Reading a sweep file back (plots, a run's whole result)


@dataclass
class SweepTable:
    """The summary of a sweep file: columns by name, their units, the axes and the method."""

    path: Path
    name: str
    method: str
    axes: list[dict[str, Any]]
    collect: list[str]
    columns: dict[str, np.ndarray]
    units: dict[str, str]


def read_summary(path: str | Path) -> SweepTable:
    """``/analysis/summary`` of a sweep file (complete or a ``.part``)."""
    path = Path(path)
    with _open_sweep(path) as f:
        if "summary" not in f["analysis"]:
            raise ValueError("no summary yet (the sweep did not finish; rerun it to resume)")
        ds = f["analysis/summary"]
        table = ds[()]
        cols = {n: (np.array([v.decode() if isinstance(v, bytes) else v for v in table[n]])
                    if table.dtype[n].kind == "O" else table[n]) for n in table.dtype.names}
        s = f["sweep"].attrs
        return SweepTable(path, str(f.attrs["sweep"]), str(s["method"]), json.loads(s["axes"]),
                          json.loads(s["collect"]), cols, json.loads(ds.attrs["units"]))


def open_run(path: str | Path, index: int) -> results.Result:
    """Run ``index`` of a sweep file (complete or a ``.part``) as a result, read by the result
    files' own reader since a run is stored in their layout. Raises KeyError if the file holds
    no finished run of that index."""
    path = Path(path)
    with _open_sweep(path) as f:
        g = f["runs"].get(group_name(index, int(f.attrs["n_runs"])))
        if g is None or "status" not in g.attrs:
            raise KeyError(f"{path}: no finished run {index}")
        return results.read_run(g, path)


def _open_sweep(path: Path) -> h5py.File:
    """A sweep file open for reading; ValueError if it is another file (a result, say)."""
    f = h5py.File(path, "r")
    if f.attrs.get("kind") != "sweep":
        f.close()
        raise ValueError("not a transient sweep file")
    return f
