"""Result files (HDF5, format 1; docs/guide/results.md): the layout, a streaming writer and a
reader (one idea, the result file: what writes it and what reads it back kept together, so that
the format has one definition).

The layout of a run — header attributes, ``scene/toml``, ``trajectory/<column>``,
``events/<name>/{t,phi}``, ``solver`` attributes, ``analysis/<name>`` — is written by the
functions below and nowhere else, so that a result file and each run of a sweep file
(:mod:`transient.sweeps.store`) hold the same thing in the same form and read back alike.

The writer works on a temporary name beside the final one and renames it when the run ends —
``complete = True`` after a finished run, ``False`` after a failure or an interrupt. While the run
goes on the file is in HDF5's single-writer/multiple-reader (SWMR) mode, whose ordered flushes keep
what is on disk a consistent file at every instant: killed by any signal at any instant, a run
leaves a file that opens (read in SWMR mode, :func:`open_file`). After each block the writer
appends a *checkpoint* — the trajectory's and the events' lengths and the stepper's state — once
the block's data are flushed; a reader of an unfinished file takes the trajectory up to the last
checkpoint only (every block completed before it, never a torn tail), and a run resumes from it
bit-identically (:func:`resumable`, and :class:`ResultWriter` with ``resume=True``).
"""
from __future__ import annotations

import datetime as _dt
import functools
import os
from collections.abc import Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from .errors import WriteFailed
from .scene.outputs import describe
from .version import __version__

#: Root attribute ``creator`` of every file written here (result or sweep).
CREATOR = "transient"
#: Root attribute ``format``: the version of the layout below.
FORMAT = 1


@dataclass
class RunData:
    """A run in memory: trajectory columns, events (name → (n, 2) of t, φ), solver statistics;
    ``status`` says what the run did (:data:`transient.outcome.STATUSES`; "" until judged),
    ``warnings`` what a finished run must not be read without and ``summary`` what its judge
    found over the whole run for the end-of-run summary (name → (value, unit))."""

    trajectory: dict[str, np.ndarray]
    events: dict[str, np.ndarray]
    solver: dict[str, float | int | str]
    complete: bool = True
    message: str = ""
    status: str = ""
    warnings: list[str] = field(default_factory=list)
    summary: dict[str, tuple[float, str]] = field(default_factory=dict)


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
        raise ResultExists(f"{partial_path(path)}: the partial result of an interrupted or "
                           f"killed run; continue it with --resume, or replace it with --force")
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
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def write_header(node: h5py.Group, **attrs: Any) -> None:
    """The attributes that open a result (a file's root, or a run's group in a sweep file): who
    wrote it, in which format and when, how (:func:`provenance`), then ``attrs`` (``scene``,
    ``complete``, …)."""
    node.attrs.update(creator=CREATOR, version=__version__, format=FORMAT, created=now(),
                      **provenance(), **attrs)


#: The packages besides the numerical core whose versions a result records: the sweeps' (Dask),
#: the figures' (matplotlib) and the tables' (pandas, optional).
RECORDED_PACKAGES = ("dask", "distributed", "matplotlib", "pandas")


@functools.cache
def provenance() -> dict[str, str]:
    """How a result was made: transient's git commit when it runs from a checkout (``+dirty``
    with uncommitted changes; empty otherwise), the versions of Python, the numerical libraries
    and :data:`RECORDED_PACKAGES` ("not installed" for one that is not), the command or call,
    the CPU."""
    import platform
    import sys

    import numba
    import scipy

    return {"git_commit": _git_commit(), "python": platform.python_version(),
            "numpy": np.__version__, "scipy": scipy.__version__, "numba": numba.__version__,
            "h5py": h5py.__version__, "hdf5": h5py.version.hdf5_version,
            **{name: _installed_version(name) for name in RECORDED_PACKAGES},
            "command": " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]) if sys.argv else "",
            "cpu": _cpu_name(), "platform": platform.platform()}


def _installed_version(package: str) -> str:
    """The installed version of ``package`` from its metadata (not imported: a run need not load
    matplotlib or pandas to say which it would use), or "not installed"."""
    from importlib import metadata

    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


def _git_commit() -> str:
    import subprocess

    src = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "-C", str(src), "describe", "--always", "--dirty=+dirty",
                              "--abbrev=40", "--exclude=*"], capture_output=True, text=True,
                             timeout=10)
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip() if out.returncode == 0 else ""


def _cpu_name() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    import platform

    return platform.processor() or platform.machine()


def write_layout(node: h5py.Group, scene_toml: str, units: dict[str, str],
                 trajectory: dict[str, np.ndarray] | None = None,
                 scene_source: tuple[str, str] = ("", "")) -> dict[str, h5py.Dataset]:
    """A result's groups under ``node``: ``scene/toml``, with ``scene_source`` (the file the scene
    was read from and its text, comments included) ``scene/source`` and its attribute ``file``,
    one column a unit in ``trajectory`` (empty, or holding ``trajectory[name]``), and ``events``,
    ``solver``, ``analysis``. Returns the columns' datasets.

    The columns are extendable in chunks of :data:`CHUNK_ROWS` whether streamed or written whole,
    so that a stored column is one kind of dataset wherever it was written (and an empty one can
    still be chunked)."""
    scene = node.create_group("scene")
    scene.create_dataset("toml", data=scene_toml)
    file, text = scene_source
    if text:
        scene.create_dataset("source", data=text).attrs["file"] = file
    traj = node.create_group("trajectory")
    columns = {}
    for name, unit in units.items():
        data = np.zeros(0) if trajectory is None else np.asarray(trajectory[name], dtype=float)
        ds = columns[name] = traj.create_dataset(name, data=data, maxshape=(None,), dtype="f8",
                                                 chunks=(CHUNK_ROWS,), compression="gzip",
                                                 compression_opts=1, shuffle=True)
        ds.attrs["unit"] = unit
        ds.attrs["description"] = describe(name)
    for name in ("events", "solver", "analysis"):
        node.create_group(name)
    return columns


def append_events(events_group: h5py.Group, events: dict[str, np.ndarray]) -> None:
    """Append events: ``events[name]`` is an (n, 2) array (or list of pairs) of (t, φ).
    Extendable datasets, so that a long run streams its events too."""
    for name, rows in events.items():
        rows = np.asarray(rows, dtype=float).reshape(-1, 2)
        if not rows.size:
            continue  # (events that occurred only, as a streamed result keeps them)
        g = events_group.require_group(name)
        for j, (col, unit) in enumerate((("t", "s"), ("phi", "rad"))):
            if col not in g:
                g.create_dataset(col, shape=(0,), maxshape=(None,), dtype="f8",
                                 chunks=(1024,)).attrs["unit"] = unit
            _extend(g[col], rows[:, j])


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


#: The group of a multirevolution run's envelope (:mod:`transient.longrun`): per cycle start
#: ``states`` (rows: cycles + 1, columns: its ``names``, the periodic states then t), per cycle
#: ``integrated`` (1: integrated as a direct run would, 0: the envelope's), ``mean_omega`` (Δφ/Δt
#: of the cycle), and where the file holds the cycle's trajectory ``delta`` and ``work`` (NaN
#: elsewhere); the cycles whose trajectory it holds, ``resolved``, each ending at trajectory
#: row ``resolved_end``; ``error``, the envelope's error estimate per state (NaN until known).
ENVELOPE = "envelope"
#: The envelope's per-cycle datasets and their units.
ENVELOPE_CYCLES = {"integrated": "1", "mean_omega": "rad/s", "delta": "1", "work": "J"}


def envelope_datasets(node: h5py.Group, names: list[str], units: list[str], cycles: int
                      ) -> dict[str, h5py.Dataset]:
    """The empty, extendable datasets of ``node``'s :data:`ENVELOPE` group (made before a
    streamed file goes live: SWMR creates no objects)."""
    g = node.create_group(ENVELOPE)
    g.attrs["cycles"] = cycles
    w = len(names)
    ds = {"states": g.create_dataset("states", shape=(0, w), maxshape=(None, w), dtype="f8",
                                     chunks=(256, w))}
    ds["states"].attrs.update(names=names, units=units)
    for name, unit in ENVELOPE_CYCLES.items():
        ds[name] = g.create_dataset(name, shape=(0,), maxshape=(None,), dtype="f8",
                                    chunks=(1024,))
        ds[name].attrs["unit"] = unit
    for name in ("resolved", "resolved_end"):
        ds[name] = g.create_dataset(name, shape=(0,), maxshape=(None,), dtype="i8",
                                    chunks=(256,))
    ds["error"] = g.create_dataset("error", data=np.full(w, np.nan))
    ds["error"].attrs["units"] = units
    return ds


@dataclass
class EnvelopeRecord:
    """A multirevolution run's envelope, as its result holds it (:data:`ENVELOPE`): ``names``
    and ``units`` of the states at every cycle start, ``states`` (cycles + 1 rows), per cycle
    ``integrated`` (bool), ``mean_omega``, ``delta`` and ``work`` (NaN where the result holds
    no trajectory of the cycle), the cycles whose trajectory it holds (``resolved``, each
    ending at trajectory row ``resolved_end``), the error estimate per state (``error``, NaN
    where the run did not get that far) and the cycles the run was to follow."""

    names: list[str]
    units: list[str]
    states: np.ndarray
    integrated: np.ndarray
    mean_omega: np.ndarray
    delta: np.ndarray
    work: np.ndarray
    resolved: np.ndarray
    resolved_end: np.ndarray
    error: np.ndarray
    cycles: int

    def column(self, name: str) -> np.ndarray:
        """One state at every cycle start written."""
        return self.states[:, self.names.index(name)]

    def rows(self, cycle: int) -> slice:
        """The trajectory rows of a resolved ``cycle`` (a KeyError for one the result does not
        hold)."""
        at = np.flatnonzero(self.resolved == cycle)
        if not at.size:
            raise KeyError(f"cycle {cycle} is not resolved in this result (resolved: "
                           f"{', '.join(map(str, self.resolved[:12]))}"
                           f"{' …' if self.resolved.size > 12 else ''})")
        k = int(at[0])
        return slice(int(self.resolved_end[k - 1]) if k else 0, int(self.resolved_end[k]))


def read_envelope(node: h5py.Group, trajectory_rows: int) -> EnvelopeRecord | None:
    """The :data:`ENVELOPE` group under ``node`` (None if there is none), cut to what a kill
    left whole: the cycles every per-cycle dataset holds, the resolved cycles whose rows are
    within the ``trajectory_rows`` read."""
    if ENVELOPE not in node:
        return None
    g = node[ENVELOPE]
    n = min([g[name].shape[0] for name in ENVELOPE_CYCLES] + [max(g["states"].shape[0] - 1, 0)])
    ends = g["resolved_end"][()]
    m = min(g["resolved"].shape[0], int(np.searchsorted(ends, trajectory_rows, side="right")))
    st = g["states"]
    return EnvelopeRecord(
        names=[str(v) for v in st.attrs["names"]], units=[str(v) for v in st.attrs["units"]],
        states=st[:n + 1], integrated=g["integrated"][:n].astype(bool),
        mean_omega=g["mean_omega"][:n], delta=g["delta"][:n], work=g["work"][:n],
        resolved=g["resolved"][:m], resolved_end=ends[:m], error=g["error"][()],
        cycles=int(g.attrs["cycles"]))


def outcome_attrs(status: str, warnings: list[str]) -> dict[str, str]:
    """The root attributes that say what a run did: ``status``, and ``warnings`` if any (one a
    line)."""
    return {"status": status, **({"warnings": "\n".join(warnings)} if warnings else {})}


#: The return code in the checkpoint of a run written whole (the reference path, a stiff rerun):
#: it marks the end of what was written, with no stepper state to resume from.
NOT_RESUMABLE = -1
#: The group of a streamed result's checkpoints (:class:`Checkpoint`), kept in an incomplete
#: result so that its run can be resumed.
CHECKPOINTS = "checkpoint"


@dataclass
class Checkpoint:
    """Where a streamed run stood after one of its blocks: the trajectory's length, the event
    log's length, whether the extra inertia had been switched in, the stepper's return code, and
    its state (its float state ``y`` and ``fst`` laid end to end in ``floats``, its integer state
    ``ist``)."""

    rows: int
    events: int
    switched: bool
    code: int
    floats: np.ndarray
    ints: np.ndarray


def _checkpoint_datasets(node: h5py.Group, event_names) -> dict[str, h5py.Dataset]:
    """The empty, extendable datasets of the checkpoints: ``index`` holds a row per checkpoint
    (rows, switched, the stepper's return code, the float and integer state's lengths, the event
    log's length); ``floats`` and ``ints`` hold the states one after another; ``events``, the
    event log, a row (name, t, φ) per event in time order, the name an index into its
    ``names`` attribute (one dataset, not one per name: a result's objects are made before it
    streams, and each costs its start)."""
    g = node.create_group(CHECKPOINTS)
    g.create_dataset("index", shape=(0, 6), maxshape=(None, 6), dtype="i8", chunks=(64, 6))
    g.create_dataset("floats", shape=(0,), maxshape=(None,), dtype="f8", chunks=(4096,))
    g.create_dataset("ints", shape=(0,), maxshape=(None,), dtype="i8", chunks=(1024,))
    g.create_dataset("events", shape=(0, 3), maxshape=(None, 3), dtype="f8",
                     chunks=(1024, 3)).attrs["names"] = list(event_names)
    return {name: g[name] for name in ("index", "floats", "ints", "events")}


def _last_checkpoint(node: h5py.Group) -> Checkpoint | None:
    """The last checkpoint under ``node`` whose data are all there, or None."""
    if CHECKPOINTS not in node:
        return None
    g = node[CHECKPOINTS]
    index = g["index"]
    k = index.shape[0]
    if k == 0:
        return None
    row = index[k - 1]
    nf, ni = int(row[3]), int(row[4])
    return Checkpoint(rows=int(row[0]), switched=bool(row[1]), code=int(row[2]),
                      events=int(row[5]), floats=g["floats"][(k - 1) * nf:k * nf],
                      ints=g["ints"][(k - 1) * ni:k * ni])


def _logged_events(g: h5py.Group, count: int | None = None, t_from: float = -np.inf
                   ) -> dict[str, np.ndarray]:
    """The event log of the checkpoint group ``g`` (its first ``count`` rows; from the first
    event at t ≥ ``t_from``, found by bisection: the log is in time order), name → (n, 2) of
    (t, φ) in the order they occurred."""
    log = g["events"]
    n = log.shape[0] if count is None else count
    lo, hi = 0, n
    while lo < hi:
        mid = (lo + hi) // 2
        if log[mid, 1] < t_from:
            lo = mid + 1
        else:
            hi = mid
    return _decoded(log[lo:n], log.attrs["names"])


#: Samples :meth:`ResultWriter.written_blocks` reads at a time, at least.
READ_ROWS = 1 << 18


def _decoded(rows: np.ndarray, names) -> dict[str, np.ndarray]:
    """Rows (name index, t, φ) of an event log as name → (n, 2) of (t, φ)."""
    codes = rows[:, 0].astype(np.int64)
    return {str(names[c]): rows[codes == c, 1:] for c in np.unique(codes)}


def _extend(ds: h5py.Dataset, values) -> None:
    """Append ``values`` along the first axis of ``ds``."""
    values = np.asarray(values)
    n = ds.shape[0]
    ds.resize(n + values.shape[0], axis=0)
    ds[n:] = values


class ResultWriter:
    """Streams a run into its result file; see the module docstring.

    The run is written to :func:`partial_path` in SWMR mode (:meth:`block` after each block).
    :meth:`finish` copies it into a file of the usual layout beside it — its objects copied
    whole, compressed chunks as they are — adds the solver statistics, the analysis and the
    status, and gives that file the result's name; the partial file is removed only then, so
    that a kill at any instant leaves one of the two whole."""

    def __init__(self, path: Path, scene_name: str, scene_toml: str,
                 columns: dict[str, str], event_names=(), force: bool = False,
                 resume: bool = False, scene_source: tuple[str, str] = ("", ""),
                 envelope: tuple[list[str], list[str], int] | None = None) -> None:
        self.path = Path(path)
        # a multirevolution run's (names, units, cycles): its ENVELOPE group, made with the
        # file (``self.envelope``, its datasets)
        self.envelope_layout = envelope
        self.envelope: dict[str, h5py.Dataset] = {}
        self.force = force
        self.tmp = partial_path(self.path)
        self.done = self.tmp.with_name(f".{self.path.name}.done")
        self.scene_name, self.scene_toml = scene_name, scene_toml
        self.scene_source = scene_source
        self.columns, self.event_names = columns, tuple(event_names)
        self.checkpoint: Checkpoint | None = None
        if resume:
            source = resumable(self.path)
            self.checkpoint = _resume_point(source, scene_toml)
            if source != self.tmp:
                self.force = True  # (the published incomplete result is what this run replaces)
        else:
            check_writable(self.path, force)
        self._create()
        if self.checkpoint is not None:  # (else stopped before its first block: start afresh)
            self._copy_upto(source, self.checkpoint)
        self._go_live()
        self.done.unlink(missing_ok=True)  # (a copy a kill interrupted; the partial file is whole)

    def _create(self) -> None:
        """The partial file, its header and its empty datasets (SWMR creates no objects), made
        under a name of its own until :meth:`_go_live`: until SWMR mode is on, a kill leaves a
        file that HDF5 will not open."""
        self.broken = ""  # why a write failed, if one did
        name = self.tmp.with_name(self.tmp.name + ".new")
        name.unlink(missing_ok=True)  # (one a kill left, or a link planted there)
        try:
            self.f = h5py.File(name, "x", libver=FILE_FORMAT, rdcc_nbytes=CHUNK_CACHE_BYTES)
            write_header(self.f, scene=self.scene_name, complete=False, status="running")
            # The columns' datasets stay open for the file's life: a dataset object freed after
            # a failed write would make HDF5 retry it (and print its failure) on closing.
            self.datasets = write_layout(self.f, self.scene_toml, self.columns,
                                         scene_source=self.scene_source)
            # Opened once: a lookup by path per block would cost more than writing the block.
            self.checkpoints = _checkpoint_datasets(self.f, self.event_names)
            if self.envelope_layout is not None:
                self.envelope = envelope_datasets(self.f, *self.envelope_layout)
            self.f.flush()
        except (OSError, RuntimeError) as exc:  # h5py reports a failed write as either
            self._abandon(name)
            raise NotWritable(f"{name}: cannot write the result file "
                              f"({str(exc).splitlines()[0]}); is the disk full?") from None

    def _go_live(self) -> None:
        """SWMR mode on, then the file takes the partial file's name (replacing what a resumed
        run had there): from now on a kill leaves a file that opens."""
        self.f.swmr_mode = True
        os.replace(self.f.filename, self.tmp)

    def _abandon(self, name: Path) -> None:
        """Close what can be closed of a file whose writes failed, and remove it."""
        try:
            self.f.close()
        except Exception:
            pass
        Path(name).unlink(missing_ok=True)

    def _copy_upto(self, source: Path, cp: Checkpoint) -> None:
        """The trajectory, events and checkpoints of ``source`` up to checkpoint ``cp``."""
        with open_file(source) as src:
            for name, ds in self.datasets.items():
                _extend(ds, src["trajectory"][name][:cp.rows])
            k = src[CHECKPOINTS]["index"].shape[0]
            g = self.checkpoints
            _extend(g["events"], src[CHECKPOINTS]["events"][:cp.events])
            _extend(g["floats"], src[CHECKPOINTS]["floats"][:k * cp.floats.size])
            _extend(g["ints"], src[CHECKPOINTS]["ints"][:k * cp.ints.size])
            _extend(g["index"], src[CHECKPOINTS]["index"][:k])
        self.f.flush()

    def block(self, block: dict[str, np.ndarray], events: dict[str, np.ndarray],
              floats: np.ndarray, ints: np.ndarray, switched: bool, code: int) -> None:
        """A block of the run and its events, flushed; then the checkpoint after it (the
        stepper's state), flushed: a reader sees the checkpoint only once the data it counts are
        on disk (SWMR keeps each dataset consistent in itself, the flushes order them)."""
        with self._writing():
            self._columns(block)
            self._events(events)
            self.f.flush()
            g = self.checkpoints
            _extend(g["floats"], floats)
            _extend(g["ints"], ints)
            _extend(g["index"], [[self.datasets["t"].shape[0], int(switched), code,
                                  floats.size, ints.size, g["events"].shape[0]]])
            self.f.flush()

    @contextmanager
    def _writing(self):
        """Writes whose failure (h5py reports one as OSError or RuntimeError) breaks the file:
        remembered, and raised as :class:`~transient.errors.WriteFailed`."""
        try:
            yield
        except (OSError, RuntimeError) as exc:
            self.broken = (f"writing {self.tmp} failed ({str(exc).splitlines()[0]}); "
                           f"is the disk full?")
            raise WriteFailed(self.broken) from None

    def append(self, block: dict[str, np.ndarray]) -> None:
        """Append equal-length columns (every column of the file), flushed."""
        with self._writing():
            self._columns(block)
            self.f.flush()

    def events(self, events: dict[str, np.ndarray]) -> None:
        """Append events (name → (n, 2) of t, φ) to the event log, flushed."""
        with self._writing():
            self._events(events)
            self.f.flush()

    def extend(self, datasets: list[tuple[h5py.Dataset, np.ndarray]]) -> None:
        """Append each (dataset, values) pair along the dataset's first axis (datasets this
        file made before it went live: a multirevolution run's envelope), flushed."""
        with self._writing():
            for ds, values in datasets:
                _extend(ds, values)
            self.f.flush()

    def _columns(self, block: dict[str, np.ndarray]) -> None:
        if len(next(iter(block.values()))):
            for name, ds in self.datasets.items():
                _extend(ds, block[name])

    def _events(self, events: dict[str, np.ndarray]) -> None:
        """A block's events into the log, in time order (the log is, block after block)."""
        named = [np.column_stack([np.full(len(v), self.event_names.index(name), float),
                                  np.asarray(v, dtype=float).reshape(-1, 2)])
                 for name, v in events.items() if len(v)]
        if named:
            rows = np.concatenate(named)
            _extend(self.checkpoints["events"], rows[np.argsort(rows[:, 1], kind="stable")])

    def restart(self) -> None:
        """Start the file afresh (a run started again from the beginning, e.g. a stiff scene by
        an implicit method)."""
        self.f.close()
        self._create()
        self._go_live()

    def read_trajectory(self, last: int | None = None) -> dict[str, np.ndarray]:
        """The trajectory written so far (its ``last`` samples only, if given), read back."""
        n = self.datasets["t"].shape[0]
        start = 0 if last is None else max(0, n - last)
        return {name: ds[start:] for name, ds in self.datasets.items()}

    def written_blocks(self):
        """The run written so far in the order it streamed, (columns, events) of consecutive
        checkpoints at a time, about :data:`READ_ROWS` samples each: what a resumed run did
        before, in bounded memory."""
        log, index = self.checkpoints["events"], self.checkpoints["index"][()]
        rows = logged = 0
        for k, (end, *_, end_logged) in enumerate(index):
            if end - rows < READ_ROWS and k < len(index) - 1:
                continue
            yield ({name: ds[rows:end] for name, ds in self.datasets.items()},
                   _decoded(log[logged:end_logged], log.attrs["names"]))
            rows, logged = int(end), int(end_logged)

    def read_events(self, t_from: float = -np.inf) -> dict[str, np.ndarray]:
        """Events written so far at t ≥ ``t_from``, name → (n, 2) array of (t, φ); only the
        log's tail is read (a long run has millions of breakpoint events)."""
        return _logged_events(self.f[CHECKPOINTS], t_from=t_from)

    def finish(self, complete: bool, message: str = "", status: str = "",
               solver: dict[str, Any] | None = None,
               analysis: dict[str, tuple[Any, str]] | None = None,
               warnings: list[str] | None = None) -> Path:
        """Write the result under its name: the run so far, ``solver``'s statistics,
        ``analysis`` (name → (value, unit)), ``complete``, ``status`` (with ``warnings``:
        :func:`outcome_attrs`) and ``message``. An
        incomplete result keeps its checkpoints (it can be resumed). After a failed write the
        partial file is left as it is, and :class:`~transient.errors.WriteFailed` (a
        SimulationError) says so."""
        if self.broken:
            # (not closed: HDF5 would retry the failed writes, print and crash; cli.entry exits
            # without freeing it)
            raise WriteFailed(f"{self.broken}; the partial file {self.tmp} holds the run up to "
                              f"its last checkpoint")
        self.f.close()
        status = status or ("finished" if complete else "failed")
        try:
            with h5py.File(self.tmp, "r") as src:
                _copy_result(src, self.done, keep_checkpoints=not complete)
            with reopen_file(self.done) as f:
                f.attrs.update(complete=bool(complete), **outcome_attrs(status, warnings or []))
                if message:
                    f.attrs["message"] = message
                write_solver(f["solver"], solver or {})
                for name, (value, unit) in (analysis or {}).items():
                    write_analysis(f["analysis"], name, value, unit)
        except (OSError, RuntimeError) as exc:
            self.done.unlink(missing_ok=True)
            raise WriteFailed(f"writing {self.done} failed ({str(exc).splitlines()[0]}); is "
                              f"the disk full? The partial file {self.tmp} holds the run") from None
        _publish(self.done, self.path, self.force)
        self.tmp.unlink()
        return self.path


def _copy_result(src: h5py.File, dest: Path, keep_checkpoints: bool) -> None:
    """A new result file at ``dest`` holding what ``src`` holds: its attributes, its objects
    copied whole (HDF5 copies a compressed chunk as it is), events that occurred only."""
    with create_file(dest) as f:
        f.attrs.update(dict(src.attrs))
        for name in ("scene", "trajectory", "solver", "analysis", ENVELOPE):
            if name in src:  # (the envelope: a multirevolution run's only)
                src.copy(src[name], f, name=name)
        append_events(f.create_group("events"), _logged_events(src[CHECKPOINTS]))
        if keep_checkpoints:
            src.copy(src[CHECKPOINTS], f, name=CHECKPOINTS)


def open_file(path: Path) -> h5py.File:
    """A result file open for reading: finished, or the partial file of a run that was killed
    (or still runs), which HDF5 opens in SWMR mode only."""
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        if "already open for" not in str(exc):
            raise
        return h5py.File(path, "r", swmr=True)


#: The statuses of a run that ``--resume`` continues: killed while running, or interrupted.
RESUMABLE = ("running", "interrupted")


def resumable(path: Path) -> Path:
    """The file a run of ``path`` resumes from: its partial file (a killed run), else the result
    itself if it is incomplete; a one-line error if there is neither."""
    for source in (partial_path(path), path):
        if source.is_file():
            try:
                with open_file(source) as f:
                    status = str(f.attrs.get("status", ""))
                    complete = bool(f.attrs.get("complete", False))
            except OSError as exc:
                raise NotWritable(f"{source}: not a readable result ({str(exc).splitlines()[0]});"
                                  f" use --force to start afresh") from None
            if complete:
                raise ResultExists(f"{source}: the run is complete; nothing to resume")
            if status not in RESUMABLE:
                raise NotWritable(f"{source}: the run ended {status or 'failed'}; resuming would "
                                  f"end the same way (resume continues interrupted or killed runs)")
            return source
    raise NotWritable(f"{path}: no partial or incomplete result to resume; run without --resume")


def _resume_point(source: Path, scene_toml: str) -> Checkpoint | None:
    """The last checkpoint of ``source`` (None if it has none yet), after checking that it is a
    run of the same scene."""
    with open_file(source) as f:
        if _text(f["scene"]["toml"][()]) != scene_toml:
            raise NotWritable(f"{source}: written from another scene (its /scene/toml differs); "
                              f"resume with the same scene, or use --force to start afresh")
        if CHECKPOINTS not in f:
            raise NotWritable(f"{source}: not the result of a streamed run (no checkpoints); "
                              f"use --force to start afresh")
        cp = _last_checkpoint(f)
    if cp is not None and cp.code == NOT_RESUMABLE:
        raise NotWritable(f"{source}: a run written whole (not by the compiled stepper), which "
                          f"cannot be resumed; use --force to start afresh")
    return cp


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


class _Columns(Mapping):
    """A result file's trajectory columns (its first ``rows`` samples), each read from the file
    when first used: a long run's result opens without reading gigabytes. The file stays open
    (read-only) while the columns are in use, so that they can be read after it was replaced or
    deleted (a temporary folder gone)."""

    def __init__(self, path: Path, node: str, names: list[str], rows: slice) -> None:
        self._file, self._node, self._names, self._rows = open_file(path), node, names, rows
        self._read: dict[str, np.ndarray] = {}

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._read:
            if name not in self._names:
                raise KeyError(name)
            self._read[name] = self._file[self._node]["trajectory"][name][self._rows]
        return self._read[name]

    def __iter__(self):
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)


@dataclass
class Result:
    """A run's result, from its file (:func:`~transient.open_result`, or :func:`transient.simulate`
    with a path) or in memory (:func:`transient.simulate` without one); the same either way.

    Attributes
    ----------
    path
        The result file, or None for a run held in memory.
    attrs
        The header: ``scene`` (name), ``complete``, ``status``, ``message``, ``version``, …
    trajectory
        Column name → samples (a file's columns are read when first used); units in ``units``.
    units
        Column name → unit (SI).
    events
        Event name → ``{"t": [s], "phi": [rad]}`` of its occurrences.
    solver
        The solver's settings and statistics (``method``, ``rtol``, ``nfev``, ``nsteps``,
        ``wall_s``, …).
    analysis
        Name → (value, unit) of the end-of-run summary and the analyses the scene asked for.
    scene_toml
        The resolved scene (every default filled in); :meth:`scene` rebuilds it.
    scene_source
        The file the scene was read from and its text, comments included (``("", "")`` for a
        scene built in code).
    envelope
        A multirevolution run's per-cycle envelope
        (:class:`~transient.results.EnvelopeRecord`: which cycles were integrated, which
        interpolated, the error estimate); None for any other run.

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> res = transient.simulate(scene)
    >>> res.complete, res.path is None  # held in memory
    (True, True)
    >>> [name for name in res.trajectory][:4]
    ['t', 'phi', 'omega', 'epsilon']
    >>> res.scene() == scene
    True
    """

    path: Path | None
    attrs: dict[str, Any]
    trajectory: Mapping[str, np.ndarray]
    units: dict[str, str]
    events: dict[str, dict[str, np.ndarray]]
    solver: dict[str, Any]
    analysis: dict[str, tuple[Any, str]]
    scene_toml: str
    scene_source: tuple[str, str] = ("", "")
    envelope: EnvelopeRecord | None = None

    @property
    def complete(self) -> bool:
        """Whether the run ended as its scene describes."""
        return bool(self.attrs.get("complete", False))

    @property
    def status(self) -> str:
        """``finished``, ``interrupted``, the failure's first word (``stalled``, ``locked``, …),
        or ``running`` for the partial file of a run killed (or still running)."""
        return str(self.attrs.get("status", "finished" if self.complete else "failed"))

    @property
    def message(self) -> str:
        """What happened, with time, angle and speed, if the run did not finish."""
        return str(self.attrs.get("message", ""))

    @property
    def warnings(self) -> list[str]:
        """What a finished run must not be read without (negative losses, …), one per item."""
        return [w for w in str(self.attrs.get("warnings", "")).splitlines() if w]

    def scene(self):
        """Rebuild the scene from ``/scene/toml`` (with the source it was read from)."""
        from dataclasses import replace

        from .scene import load_scene

        scene = load_scene(f"{self.path or '(in memory)'}:/scene/toml", text=self.scene_toml)
        file, text = self.scene_source
        return replace(scene, source_file=file, source_text=text) if text else scene

    def summary(self) -> dict[str, Any]:
        """The end-of-run summary's values by name (units in ``analysis``): final and mean speed,
        δ, steady state, spin-up and ISO 8528-5 measures, η_mech where the scene has pairs."""
        return {name: value for name, (value, _) in self.analysis.items() if np.ndim(value) == 0}

    def to_dataframe(self):
        """The trajectory as a pandas DataFrame, one column per name, units in ``df.attrs``
        (pandas is the optional extra ``transient[pandas]``)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: pip install 'transient[pandas]'") \
                from None
        df = pd.DataFrame({name: self.trajectory[name] for name in self.trajectory})
        df.attrs["units"] = dict(self.units)
        return df


def result_in_memory(scene_name: str, scene_toml: str, data: RunData, units: dict[str, str],
                     analysis: dict[str, tuple[Any, str]],
                     scene_source: tuple[str, str] = ("", "")) -> Result:
    """The :class:`Result` of a run held in memory (judged: ``data.status``), as its file would
    read back."""
    attrs = {"creator": CREATOR, "version": __version__, "format": FORMAT, "created": now(),
             **provenance(), "scene": scene_name, "complete": bool(data.complete),
             **outcome_attrs(data.status, data.warnings)}
    if data.message:
        attrs["message"] = data.message
    events = {name: {"t": rows[:, 0], "phi": rows[:, 1]}
              for name, rows in data.events.items() if rows.size}
    return Result(path=None, attrs=attrs, trajectory=dict(data.trajectory),
                  units={c: units.get(c, "") for c in data.trajectory}, events=events,
                  solver=dict(data.solver), analysis=dict(analysis), scene_toml=scene_toml,
                  scene_source=scene_source)


def open_result(path: str | Path) -> Result:
    """Read a result file into a :class:`~transient.Result`: complete, incomplete, or the partial
    file (``.NAME.h5.part``) of a run that was killed, read up to its last checkpoint.

    Parameters
    ----------
    path : str or Path
        The result file (HDF5) that :func:`transient.simulate` or ``transient run`` wrote.

    Returns
    -------
    Result
        The run; its trajectory's columns are read from the file when first used.

    Raises
    ------
    ValueError
        The file is HDF5 but not a result of transient.

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "single.h5"
    ...     written = transient.simulate(scene, path)
    ...     res = transient.open_result(path)
    ...     print(res.status, res.path.name, res.scene() == scene)
    finished single.h5 True
    """
    path = Path(path)
    with open_file(path) as f:
        if f.attrs.get("creator") != CREATOR:
            raise ValueError(f"{path}: not a transient result file")
        return read_run(f, path)


def read_run(node: h5py.Group, path: Path) -> Result:
    """The result laid out under ``node`` (a file's root or a sweep's run), read into memory;
    ``path`` names the file it came from. An incomplete streamed run is read up to its last
    checkpoint: the blocks completed before it, never what a kill left half-written after it."""
    attrs = dict(node.attrs)
    complete = attrs.get("complete", True)
    cp = None if complete else _last_checkpoint(node)
    if cp is not None:
        rows = slice(cp.rows)
    elif not complete and CHECKPOINTS in node:  # a partial file killed before its first block
        rows = slice(0)
    else:  # complete, or a run written whole
        rows = slice(None)
    traj = _Columns(Path(path), node.name, list(node["trajectory"]), rows)
    units = {k: str(node["trajectory"][k].attrs.get("unit", "")) for k in node["trajectory"]}
    if len(node["events"]) or CHECKPOINTS not in node:  # (a finished file, a sweep's run)
        logged = {k: np.column_stack([g["t"][()], g["phi"][()]]) for k, g in node["events"].items()}
    else:  # a partial file: its event log, up to the last checkpoint
        logged = _logged_events(node[CHECKPOINTS], cp.events if cp else 0)
    events = {k: {"t": v[:, 0], "phi": v[:, 1]} for k, v in logged.items() if len(v)}
    analysis = {}
    for k, ds in node["analysis"].items():
        value = ds[()]
        analysis[k] = (value.decode() if isinstance(value, bytes) else value,
                       str(ds.attrs.get("unit", "")))
    toml = node["scene"]["toml"][()]
    source = node["scene"].get("source")
    if attrs.get("status") == "running":
        attrs["message"] = _stopped_message(node["trajectory"], rows, ENVELOPE in node)
    return Result(path=path, attrs=attrs, trajectory=traj, units=units, events=events,
                  solver=dict(node["solver"].attrs), analysis=analysis, scene_toml=_text(toml),
                  scene_source=("", "") if source is None else (str(source.attrs.get("file", "")),
                                                                _text(source[()])),
                  envelope=read_envelope(node, len(range(*rows.indices(
                      node["trajectory"]["t"].shape[0])))))


def _text(value) -> str:
    """A string dataset's value as str (h5py gives bytes)."""
    return value.decode() if isinstance(value, bytes) else str(value)


def _stopped_message(columns: h5py.Group, rows: slice, envelope: bool = False) -> str:
    """What a partial file says of its run: it stopped (killed) or still runs, and where its
    last checkpoint is; how to go on (a multirevolution run's, ``envelope``, starts afresh)."""
    n = len(range(*rows.indices(columns["t"].shape[0])))
    again = ("a multirevolution run is not resumed: `transient run SCENE --force` runs it again"
             if envelope else "`transient run SCENE --resume` continues it")
    if not n:
        return f"stopped (killed?) or still running, before its first block was written; {again}"
    t, phi, w = (float(columns[c][n - 1]) for c in ("t", "phi", "omega"))
    return (f"stopped (killed?) or still running; holds the run up to its last checkpoint, "
            f"t = {t:.9g} s, φ = {phi:.9g} rad, ω = {w:.9g} rad/s; {again}")
