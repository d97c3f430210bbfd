"""Result files (HDF5, format 1; DESIGN §4): the layout, a streaming writer and a reader.

The layout of a run — header attributes, ``scene/toml``, ``trajectory/<column>``,
``events/<name>/{t,phi}``, ``solver`` attributes, ``analysis/<name>`` — is written by the
functions below and nowhere else, so that a result file and each run of a sweep file
(:mod:`transient.sweep.store`) hold the same thing in the same form and read back alike.

The writer works on a temporary name beside the final one, flushes after every block so that a
killed run leaves a readable file, and renames it when the run ends — ``complete = True`` after a
finished run, ``False`` after a failure or an interrupt.
"""
from __future__ import annotations

import datetime as _dt
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .version import __version__
from .errors import WriteFailed

#: Root attribute ``creator`` of every file written here (result or sweep).
CREATOR = "transient"
#: Root attribute ``format``: the version of the layout below.
FORMAT = 1


@dataclass
class RunData:
    """A run in memory: trajectory columns, events (name → (n, 2) of t, φ), solver statistics;
    ``status`` says what the run did (:data:`transient.outcome.STATUSES`; "" until judged) and
    ``warnings`` what a finished run must not be read without."""

    trajectory: dict[str, np.ndarray]
    events: dict[str, np.ndarray]
    solver: dict[str, float | int | str]
    complete: bool = True
    message: str = ""
    extra: dict = field(default_factory=dict)
    status: str = ""
    warnings: list[str] = field(default_factory=list)


class ResultExists(FileExistsError):
    """The result file is there already and ``force`` was not given."""


class NotWritable(PermissionError):
    """The result cannot be written: its folder cannot be made or written, or the disk is full
    (the CLI prints the one-line message and exits 2 when this happens before integrating)."""


def partial_path(path: Path) -> Path:
    """The temporary name a result is written under until its run ends: hidden, beside it."""
    return path.with_name(f".{path.name}.part")


def check_writable(path: Path, force: bool) -> None:
    """Fail before any work if the result, or the partial result of an interrupted run, exists
    (without force), if the name is a folder, or if its folder is not writable."""
    if path.is_dir():
        raise NotWritable(f"{path}: is a folder, not a result file; remove it or write the "
                          f"result elsewhere (-o)")
    if path.exists() and not force:
        raise ResultExists(f"{path}: exists; use --force to overwrite it")
    if os.path.lexists(partial_path(path)) and not force:
        raise ResultExists(f"{partial_path(path)}: the partial result of an interrupted run; "
                           f"use --force to replace it")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # a file in the way, a read-only or missing file system, …
        raise NotWritable(f"{path.parent}: cannot create the output folder "
                          f"({exc.strerror or exc}); give a writable folder") from None
    if not os.access(path.parent, os.W_OK):
        raise NotWritable(f"{path.parent}: folder is not writable")
    # A probe of PROBE_BYTES with plain file I/O: a full disk (or a read-only file system, which
    # os.access does not see for root) fails here, before any work and before HDF5, whose
    # objects cannot be closed cleanly once its writes fail.
    probe = path.with_name(f".{path.name}.probe")
    try:
        with create_exclusive(probe, replace=True) as fh:
            fh.write(bytes(PROBE_BYTES))
            fh.flush()
            os.fsync(fh.fileno())
    except OSError as exc:
        raise NotWritable(f"{path.parent}: cannot write the result there ({exc.strerror or exc});"
                          f" is the disk full?") from None
    finally:
        probe.unlink(missing_ok=True)


def create_exclusive(path: Path, replace: bool = False):
    """A new file at ``path`` open for binary writing, created by this call and never through a
    link planted at the name (``O_EXCL | O_NOFOLLOW``). ``replace`` first removes what is there
    (a link itself, not its target); otherwise an existing name raises FileExistsError."""
    path = Path(path)
    if path.is_dir() and not path.is_symlink():
        raise NotWritable(f"{path}: is a folder; give a file name")
    if replace:
        path.unlink(missing_ok=True)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o666)
    except FileExistsError:
        raise ResultExists(f"{path}: exists; use --force to replace it") from None
    return os.fdopen(fd, "wb")


#: Size of the write probe of :func:`check_writable` [bytes]: a result's header and first blocks.
PROBE_BYTES = 1 << 16
#: Rows per chunk of a trajectory column (gzip-compressed float64).
CHUNK_ROWS = 4096
#: HDF5's chunk cache per dataset [bytes]: 32 chunks of a column, 1 MiB. A larger cache (HDF5
#: 2.0's default is 8 MiB per dataset) makes a long run's process grow with every column, since
#: the cache holds chunks of each; a smaller one slows the writing, since a block then spans more
#: chunks than the cache holds.
CHUNK_CACHE_BYTES = 32 * CHUNK_ROWS * 8

#: HDF5 format bounds of a result's objects: the 1.10 format, whose chunk index for a dataset
#: extended along one axis (an extensible array, not 1.8's B-tree) keeps the writing process from
#: growing with the run (``tools/hdf5_memory_growth.py`` measures both). The file itself keeps the
#: 1.8 format's superblock (:func:`create_file`).
FILE_FORMAT = ("v110", "v110")


def create_file(path: Path) -> h5py.File:
    """A new, empty HDF5 file at ``path``, open for writing objects in :data:`FILE_FORMAT`.

    Created in h5py's default bounds first, so that its superblock is the 1.8 format's (version 0):
    a 1.10 superblock (version 3) marks the file open for writing until it is closed, and HDF5
    then refuses to open it elsewhere, while the run writes it or for good after the run was
    killed (until ``h5clear --status``), which would lose what a killed run computed. Reopened
    with the 1.10 bounds, the file keeps its superblock."""
    h5py.File(path, "x").close()  # (exclusive: fails on any name there, a planted link too)
    return reopen_file(path)


def reopen_file(path: Path) -> h5py.File:
    """An existing file open for writing more objects in :data:`FILE_FORMAT` (a resumed sweep),
    with the chunk cache of :data:`CHUNK_CACHE_BYTES`."""
    return h5py.File(path, "r+", libver=FILE_FORMAT, rdcc_nbytes=CHUNK_CACHE_BYTES)


def now() -> str:
    """The time of writing as it is stored (``created``): UTC, ISO 8601, whole seconds."""
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def write_header(node: h5py.Group, **attrs: Any) -> None:
    """The attributes that open a result (a file's root, or a run's group in a sweep file): who
    wrote it, in which format and when, then ``attrs`` (``scene``, ``complete``, …)."""
    node.attrs.update(creator=CREATOR, version=__version__, format=FORMAT, created=now(), **attrs)


def write_layout(node: h5py.Group, scene_toml: str, units: dict[str, str],
                 trajectory: dict[str, np.ndarray] | None = None) -> dict[str, h5py.Dataset]:
    """A result's groups under ``node``: ``scene/toml``, one column a unit in ``trajectory``
    (empty, or holding ``trajectory[name]``), and ``events``, ``solver``, ``analysis``. Returns
    the columns' datasets.

    The columns are extendable in chunks of :data:`CHUNK_ROWS` whether streamed or written whole,
    so that a stored column is one kind of dataset wherever it was written (and an empty one can
    still be chunked)."""
    node.create_group("scene").create_dataset("toml", data=scene_toml)
    traj = node.create_group("trajectory")
    columns = {}
    for name, unit in units.items():
        data = np.zeros(0) if trajectory is None else np.asarray(trajectory[name], dtype=float)
        ds = columns[name] = traj.create_dataset(name, data=data, maxshape=(None,), dtype="f8",
                                                 chunks=(CHUNK_ROWS,), compression="gzip",
                                                 compression_opts=1, shuffle=True)
        ds.attrs["unit"] = unit
    for name in ("events", "solver", "analysis"):
        node.create_group(name)
    return columns


def append_events(events_group: h5py.Group, events: dict[str, np.ndarray]) -> None:
    """Append events: ``events[name]`` is an (n, 2) array (or list of pairs) of (t, φ).
    Extendable datasets, so that a long run streams its events too."""
    for name, rows in events.items():
        rows = np.asarray(rows, dtype=float).reshape(-1, 2)
        g = events_group.require_group(name)
        for j, (col, unit) in enumerate((("t", "s"), ("phi", "rad"))):
            if col not in g:
                g.create_dataset(col, shape=(0,), maxshape=(None,), dtype="f8",
                                 chunks=(1024,)).attrs["unit"] = unit
            ds = g[col]
            ds.resize(ds.shape[0] + rows.shape[0], axis=0)
            ds[ds.shape[0] - rows.shape[0]:] = rows[:, j]


def write_solver(solver_group: h5py.Group, attrs: dict[str, Any]) -> None:
    """Solver statistics and settings, as attributes of ``solver``."""
    solver_group.attrs.update(attrs)


def write_analysis(analysis_group: h5py.Group, name: str, value: Any, unit: str) -> None:
    """One derived quantity with its unit, replacing an earlier one of that name."""
    if name in analysis_group:
        del analysis_group[name]
    analysis_group.create_dataset(name, data=value).attrs["unit"] = unit


def write_run(node: h5py.Group, scene_name: str, scene_toml: str, data: RunData,
              units: dict[str, str], analysis: dict[str, tuple[Any, str]]) -> None:
    """A run held in memory, whole, in a result's layout under ``node`` (a sweep's run): the
    header (``complete`` and ``message`` from ``data``), the columns of ``data.trajectory`` with
    their ``units``, its events and solver statistics, and ``analysis`` (name → (value, unit))."""
    write_header(node, scene=scene_name, complete=bool(data.complete), message=data.message)
    write_layout(node, scene_toml, {c: units.get(c, "") for c in data.trajectory},
                 data.trajectory)
    append_events(node["events"], data.events)
    write_solver(node["solver"], data.solver)
    for name, (value, unit) in analysis.items():
        write_analysis(node["analysis"], name, value, unit)


def outcome_attrs(status: str, warnings: list[str]) -> dict[str, str]:
    """The root attributes that say what a run did: ``status``, and ``warnings`` if any."""
    return {"status": status, **({"warnings": "; ".join(warnings)} if warnings else {})}


class ResultWriter:
    """Streams trajectory blocks into ``/trajectory``; see the module docstring."""

    def __init__(self, path: Path, scene_name: str, scene_toml: str,
                 columns: dict[str, str], force: bool = False) -> None:
        self.path = Path(path)
        check_writable(self.path, force)
        self.force = force
        self.tmp = partial_path(self.path)
        if force:
            self.tmp.unlink(missing_ok=True)  # (a kept partial result, or a link planted there)
        try:
            self.f = create_file(self.tmp)
            self._start(scene_name, scene_toml, columns)
        except (OSError, RuntimeError) as exc:  # h5py reports a failed write as either
            self._abandon()
            raise NotWritable(f"{self.tmp}: cannot write the result file "
                              f"({str(exc).splitlines()[0]}); is the disk full?") from None

    def _abandon(self) -> None:
        """Close what can be closed of a file whose writes failed, and remove it."""
        try:
            self.f.close()
        except Exception:  # noqa: BLE001 — the file is broken already
            pass
        self.tmp.unlink(missing_ok=True)

    def _start(self, scene_name: str, scene_toml: str, columns: dict[str, str]) -> None:
        self.broken = ""  # why a write failed, if one did
        write_header(self.f, scene=scene_name, complete=False)
        self.columns = columns
        # The columns' datasets stay open for the file's life: a dataset object freed after a
        # failed write would make HDF5 retry it (and print its failure) on closing.
        self.datasets = write_layout(self.f, scene_toml, columns)
        self.f.flush()

    def append(self, block: dict[str, np.ndarray]) -> None:
        """Append equal-length columns (every column of the file)."""
        n = len(next(iter(block.values())))
        if n == 0:
            return
        try:
            for name, ds in self.datasets.items():
                ds.resize(ds.shape[0] + n, axis=0)
                ds[-n:] = block[name]
            self.f.flush()
        except (OSError, RuntimeError) as exc:  # h5py reports a failed write as either
            self.broken = f"writing {self.tmp} failed ({str(exc).splitlines()[0]}); is the disk full?"
            raise WriteFailed(self.broken) from None

    def restart(self) -> None:
        """Drop the trajectory and events written so far (a run started again from the
        beginning, e.g. a stiff scene by an implicit method)."""
        for ds in self.f["trajectory"].values():
            ds.resize(0, axis=0)
        del self.f["events"]
        self.f.create_group("events")
        self.f.flush()

    def read_trajectory(self, last: int | None = None) -> dict[str, np.ndarray]:
        """The trajectory written so far (its ``last`` samples only, if given), read back."""
        n = self.f["trajectory"]["t"].shape[0]
        start = 0 if last is None else max(0, n - last)
        return {name: self.f["trajectory"][name][start:] for name in self.columns}

    def events(self, events: dict[str, np.ndarray]) -> None:
        """Append events (:func:`append_events`)."""
        append_events(self.f["events"], events)

    def read_events(self, t_from: float = -np.inf) -> dict[str, np.ndarray]:
        """Events written so far at t ≥ ``t_from``, name → (n, 2) array of (t, φ). Events are
        written in time order, so the first one is found by bisection in the file and only the
        tail is read (a long run has millions of breakpoint events)."""
        out = {}
        for name, g in self.f["events"].items():
            t = g["t"]
            lo, hi = 0, t.shape[0]
            while lo < hi:
                mid = (lo + hi) // 2
                if t[mid] < t_from:
                    lo = mid + 1
                else:
                    hi = mid
            out[name] = np.column_stack([t[lo:], g["phi"][lo:]])
        return out

    def solver(self, attrs: dict[str, Any]) -> None:
        write_solver(self.f["solver"], attrs)

    def outcome(self, status: str, warnings: list[str]) -> None:
        """What the run did (:func:`outcome_attrs`), written before :meth:`close`."""
        if not self.broken:
            self.f.attrs.update(outcome_attrs(status, warnings))

    def analysis(self, name: str, value: Any, unit: str) -> None:
        write_analysis(self.f["analysis"], name, value, unit)

    def close(self, complete: bool, message: str = "") -> Path:
        """Mark the file complete or not, close it and move it to its final name. After a failed
        write the file is left as it is under its temporary name (it says complete = false if
        its header reached the disk) and :class:`~transient.errors.WriteFailed` (a
        SimulationError) says so."""
        if self.broken:
            # (not closed: HDF5 would retry the failed writes, print and crash; cli.entry exits
            # without freeing it)
            raise WriteFailed(f"{self.broken}; the partial file {self.tmp} may be unreadable")
        self.f.attrs["complete"] = bool(complete)
        if message:
            self.f.attrs["message"] = message
        self.f.close()
        _publish(self.tmp, self.path, self.force)
        return self.path


def _publish(tmp: Path, path: Path, force: bool) -> None:
    """Give the finished file its name: replacing what is there only with ``force``; without it,
    a file that appeared at the name during the run is kept, and so is ours, under ``tmp``."""
    if force:
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)  # (fails if the name exists, even as a link)
    except FileExistsError:
        raise ResultExists(f"{path}: appeared during the run; the result is kept as {tmp}") \
            from None
    except OSError:  # a file system without hard links: as close as it allows
        if os.path.lexists(path):
            raise ResultExists(f"{path}: appeared during the run; the result is kept as "
                               f"{tmp}") from None
        os.replace(tmp, path)
        return
    tmp.unlink()


@dataclass
class Result:
    """A result file read back into memory."""

    path: Path
    attrs: dict[str, Any]
    trajectory: dict[str, np.ndarray]
    units: dict[str, str]
    events: dict[str, dict[str, np.ndarray]]
    solver: dict[str, Any]
    analysis: dict[str, tuple[Any, str]]  # name -> (value, unit)
    scene_toml: str

    @property
    def complete(self) -> bool:
        return bool(self.attrs.get("complete", False))

    @property
    def status(self) -> str:
        """What the run did (:data:`transient.outcome.STATUSES`); a file written before
        statuses were stored says ``finished`` if complete, else ``failed``."""
        default = "finished" if self.complete else "failed"
        return str(self.attrs.get("status", default))

    def scene(self):
        """Rebuild the scene from ``/scene/toml``."""
        from .scene import load_scene

        return load_scene(f"{self.path}:/scene/toml", text=self.scene_toml)


def open_result(path: str | Path) -> Result:
    """Read a result file (complete or not) into a :class:`Result`."""
    path = Path(path)
    with h5py.File(path, "r") as f:
        if f.attrs.get("creator") != CREATOR:
            raise ValueError(f"{path}: not a transient result file")
        return read_run(f, path)


def read_run(node: h5py.Group, path: Path) -> Result:
    """The result laid out under ``node`` (a file's root or a sweep's run), read into memory;
    ``path`` names the file it came from."""
    traj = {k: node["trajectory"][k][()] for k in node["trajectory"]}
    units = {k: str(node["trajectory"][k].attrs.get("unit", "")) for k in node["trajectory"]}
    events = {k: {c: g[c][()] for c in g} for k, g in node["events"].items()}
    analysis = {}
    for k, ds in node["analysis"].items():
        value = ds[()]
        analysis[k] = (value.decode() if isinstance(value, bytes) else value,
                       str(ds.attrs.get("unit", "")))
    toml = node["scene"]["toml"][()]
    return Result(path=path, attrs=dict(node.attrs), trajectory=traj, units=units, events=events,
                  solver=dict(node["solver"].attrs), analysis=analysis,
                  scene_toml=toml.decode() if isinstance(toml, bytes) else str(toml))
