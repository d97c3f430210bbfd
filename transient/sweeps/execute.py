"""Running a sweep: the runs on Dask workers (or in this process), their results to the store.

Workers (Dask processes, one thread each) run :func:`run_one` and return arrays; only the client
writes, into one HDF5 file ``DIR/<stem>.h5`` (:class:`~transient.sweeps.store.SweepStore`), run by
run as results arrive, so that an interrupted sweep resumes from what is there. The summary
table goes to ``/analysis/summary`` and ``DIR/<stem>_summary.csv``.
"""
from __future__ import annotations

import contextlib
import math
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Generator
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

from ..errors import SceneError
from ..outcome import FINISHED
from ..version import __version__
from .spec import RunSpec, Sweep
from .store import SweepStore

# ------------------------------------------------------------------------------------------------
# A worker's part: one run, arrays back to the client


def run_one(scene, columns: tuple[str, ...] | None, steady: bool = False) -> dict[str, Any]:
    """Integrate one scene and summarise it (on a worker); never raises: its ``status`` is the
    run's (:data:`transient.outcome.STATUSES`: ``finished``, or what stopped it, with its
    message and the partial trajectory, if any), ``failed`` for an exception. ``steady``: the
    scene's periodic steady state (:func:`steady_run`) in place of the run.

    The imports stay in this process (a Dask worker runs many tasks), so numba loads each kernel
    once per worker, from its on-disk cache; ``compile_s`` shows it (≈ 0 after the first run).
    """
    from ..analysis.summary import summarize
    from ..run import integrate
    from ..scene.outputs import output_columns

    t0 = time.perf_counter()
    out: dict[str, Any] = {"status": "failed", "complete": False, "message": "",
                           "trajectory": {}, "events": {}, "solver": {}, "summary": {},
                           "units": output_columns(scene),
                           "worker": f"{socket.gethostname()}:{os.getpid()}"}
    try:
        data = steady_run(scene) if steady else integrate(scene, keep=True)
        out["solver"] = data.solver
        out["events"] = data.events
        keep = data.trajectory if columns is None else {c: data.trajectory[c] for c in columns}
        out["trajectory"] = keep
        out["complete"] = data.complete
        if data.complete:
            out["summary"] = {**summarize(scene, data.trajectory, data.events), **data.summary}
        out["status"] = data.status
        out["message"] = data.message
    except Exception as exc:
        out["message"] = f"{type(exc).__name__}: {exc}"
    out["wall_s"] = time.perf_counter() - t0
    return out


def steady_run(scene):
    """The steady cycle of ``scene`` (:func:`transient.steady`) as a run's data, its summary
    the result's analysis with η_mech and the friction budget over that cycle (a run's summary
    takes them over steady cycles after a settle, which one cycle has not)."""
    import numpy as np

    from ..analysis.efficiency import mechanical_efficiency
    from ..results import RunData
    from ..shooting import steady

    res = steady(scene)
    traj = dict(res.trajectory)
    events = {k: np.column_stack([e["t"], e["phi"]]) for k, e in res.events.items()}
    phi0 = scene.initial.phi
    window = (phi0, phi0 + scene.mechanism.cycle, 1)
    summary = {**res.analysis, **(mechanical_efficiency(scene, traj, events, window)
                                  if scene.gas.model != "none" else {})}
    return RunData(traj, events, dict(res.solver), complete=True, status=res.status,
                   summary=summary)


def worker_info() -> dict[str, str]:
    """Run on every worker before the sweep: imports the simulator once (and so tells at once
    if a cluster's workers cannot), and reports the version they run."""
    from .. import run  # noqa: F401  (the import is the point)

    return {"version": __version__, "python": sys.version.split()[0]}


def kernel_loads() -> dict[str, int]:
    """How often this process compiled or loaded the stepper from numba's cache (its signatures
    and cache hits + misses): 1 after any number of runs of one kind of scene."""
    from ..core import stepper

    st = stepper.advance.stats
    return {"signatures": len(stepper.advance.signatures),
            "loads": sum(st.cache_hits.values()) + sum(st.cache_misses.values())}


# ------------------------------------------------------------------------------------------------
# The client's part: the runs to do, the cluster, the one writer of the sweep file


@dataclass
class Outcome:
    """What a sweep did: the file, the runs computed now (in the order they arrived), those
    reused from the file, those of the computed that replaced a stored run of the same axis
    values (another scene, or failed and retried), the stored runs the sweep no longer holds
    that the file keeps, and the rows."""

    path: Path
    csv: Path
    computed: list[int]
    reused: list[int]
    recomputed: list[int]
    unused: int
    rows: list[dict[str, Any]]

    @property
    def new(self) -> list[int]:
        """The computed runs that replaced nothing stored: new points, or not reached before."""
        return [i for i in self.computed if i not in self.recomputed]

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [r for r in self.rows if r["status"] != FINISHED]


def run_sweep(sweep: Sweep, out_dir: str | Path = "results", scheduler: str | None = None,
              workers: int | None = None, force: bool = False, retry_failed: bool = False,
              on_result: Callable[[RunSpec, dict, int, int], None] | None = None,
              prune: bool = False) -> Outcome:
    """Run the runs of the sweep the file does not hold and write the file and the summary
    (module docstring).

    An existing file of the sweep is mended (:class:`~transient.sweeps.store.SweepStore`): a
    stored run whose resolved scene is unchanged is reused, failed ones too unless
    ``retry_failed``; stored runs the sweep no longer holds are kept apart, or deleted at the end
    with ``prune``. ``scheduler``: None for a LocalCluster of ``workers`` processes (default one
    per core), a ``tcp://host:port`` address of a running Dask scheduler, or ``"serial"`` (this
    process, no Dask: debugging and the benchmark's baseline). ``on_result(spec, result, done,
    total)`` is called after each run is written (the progress bar). On KeyboardInterrupt the
    file keeps the finished runs (``complete = false``) and the interrupt goes on.
    """
    if scheduler is None:
        check_main_guarded()  # (before the sweep file is touched)
    out_dir = Path(out_dir)
    stem = sweep.path.stem
    store = SweepStore(out_dir / f"{stem}.h5", sweep, force, retry_failed)
    reused = sorted(store.finished)
    todo = [s for s in sweep.runs if s.index not in store.finished]
    computed: list[int] = []
    try:
        # closing(): an interrupt here shuts the cluster down at once, not when the generator
        # is collected
        with contextlib.closing(_execute(todo, sweep.columns, scheduler, workers, sweep.steady)) as arriving:
            for spec, res in arriving:
                store.write_run(spec, res)
                computed.append(spec.index)
                if on_result:
                    on_result(spec, res, len(store.finished), len(sweep.runs))
        unused = store.tidy(prune)
    except BaseException:
        store.close(False)
        raise
    csv_path = out_dir / f"{stem}_summary.csv"
    rows = store.write_summary(csv_path)
    path = store.close(True)
    return Outcome(path, csv_path, computed, reused, sorted(store.recomputed), unused, rows)


def _execute(todo: list[RunSpec], columns, scheduler: str | None, workers: int | None,
             steady: bool = False) -> Generator[tuple[RunSpec, dict], None, None]:
    """(spec, result) of each run as it finishes."""
    for i, res in map_tasks(run_one, [(s.scene, columns, steady) for s in todo], scheduler,
                            workers, _lost):
        yield todo[i], res


def map_tasks(fn: Callable, tasks: list[tuple], scheduler: str | None = None,
              workers: int | None = None,
              lost: Callable[[BaseException], Any] | None = None
              ) -> Generator[tuple[int, Any], None, None]:
    """(i, fn(*tasks[i])) as each task finishes: on the workers of a new local cluster
    (``scheduler`` None, ``workers`` processes), of a running scheduler (``tcp://host:port``)
    or, with ``"serial"``, in this process in order. ``lost(exc)`` stands for the result of a
    task whose worker was lost (None: the exception goes on)."""
    if not tasks:
        return
    if scheduler == "serial":
        for i, task in enumerate(tasks):
            yield i, fn(*task)
        return
    from dask.distributed import as_completed

    with _client(scheduler, workers) as client:
        futures = {client.submit(fn, *task, pure=False,
                                 key=f"transient-{fn.__name__}-{i}-{os.urandom(4).hex()}"): i
                   for i, task in enumerate(tasks)}
        try:
            for fut in as_completed(futures):
                i = futures.pop(fut)
                try:
                    res = fut.result()
                except Exception as exc:
                    if lost is None:
                        raise
                    res = lost(exc)
                fut.release()
                yield i, res
        finally:
            client.cancel(list(futures))


def _lost(exc: BaseException) -> dict[str, Any]:
    """A run whose task or worker was lost, as a failed run of :func:`run_one` (nothing computed
    comes back), so that the sweep records it and goes on."""
    return {"status": "failed", "complete": False,
            "message": f"{type(exc).__name__} (on the cluster): {exc}",
            "trajectory": {}, "events": {}, "solver": {}, "summary": {}, "units": {},
            "worker": "?", "wall_s": math.nan}


class UnguardedMain(RuntimeError):
    """A sweep on a local cluster started from a script's top level, outside
    ``if __name__ == "__main__":`` (:func:`check_main_guarded`)."""


def check_main_guarded() -> None:
    """Refuse, in one line, to start a local cluster from the top-level code of the main script
    outside ``if __name__ == "__main__":``.

    The cluster's workers are processes that multiprocessing starts by "spawn" (Dask's default),
    and spawn runs the main module again in each of them, as ``multiprocessing.spawn``
    prepares it: by its name where it was run as ``python -m pkg.mod`` (not a package's
    ``__main__``), else by its file. There the call would start a cluster again while the worker
    is still starting, and Dask fails with a traceback from deep inside its nanny. The call is
    guarded when the main module's top-level statement that is running it (the frame of the
    module on the stack) is that ``if``; a main module with no source to read (an interactive
    session) is not run again."""
    import ast
    import linecache

    import dask

    main = sys.modules.get("__main__")
    name = getattr(getattr(main, "__spec__", None), "name", None)
    rerun = (not (name == "__main__" or name.endswith(".__main__")) if name is not None
             else getattr(main, "__file__", None) is not None)
    if main is None or not rerun or dask.config.get(
            "distributed.worker.multiprocessing-method", "spawn") == "fork":
        return
    frame: FrameType | None = sys._getframe()
    while frame is not None and not (frame.f_globals is vars(main)
                                     and frame.f_code.co_name == "<module>"):
        frame = frame.f_back
    if frame is None:
        return  # (called after the main module ran: it does not run its calls again)
    file, line = frame.f_code.co_filename, frame.f_lineno
    try:
        tree = ast.parse("".join(linecache.getlines(file)) or "\n")
    except SyntaxError:
        return
    top = next((node for node in tree.body
                if node.lineno <= line <= (node.end_lineno or node.lineno)), None)
    if top is None or _is_main_guard(top):
        return
    raise UnguardedMain(f"a sweep on a local Dask cluster starts its workers by running the main "
                        f"script again, so the script must start it under `if __name__ == "
                        f"\"__main__\":` ({file}, line {line}); or give scheduler=\"serial\" "
                        f"or a client")


def _is_main_guard(node) -> bool:
    """Whether ``node`` is ``if __name__ == "__main__":`` (either way round)."""
    import ast

    test = getattr(node, "test", None)
    if not (isinstance(node, ast.If) and isinstance(test, ast.Compare) and len(test.ops) == 1
            and isinstance(test.ops[0], ast.Eq)):
        return False
    sides = [test.left, test.comparators[0]]
    return (any(isinstance(x, ast.Name) and x.id == "__name__" for x in sides)
            and any(isinstance(x, ast.Constant) and x.value == "__main__" for x in sides))


@contextlib.contextmanager
def _sigint_ignored():
    """SIGINT ignored while processes are started (they keep ignoring it: Python installs no
    KeyboardInterrupt handler where SIGINT is ignored at start), so that a Ctrl-C reaches the
    client alone, which stops the cluster in order; the main thread only (signals need it)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class _client:
    """A Dask client: on a new LocalCluster (one single-threaded process per core, loopback
    only) or connected to ``address``; checks that the workers can import transient."""

    def __init__(self, address: str | None, workers: int | None) -> None:
        self.address, self.workers = address, workers
        self.cluster = self.client = None

    def __enter__(self):
        import logging

        from dask.distributed import Client, LocalCluster

        if self.address is None:
            # Processes, not threads: the runs hold the GIL in Python between compiled chunks.
            # Loopback only; the scheduler's HTTP server (always started) on a free port.
            with _sigint_ignored():  # Ctrl-C is the client's to handle: the workers inherit this
                self.cluster = LocalCluster(n_workers=self.workers or os.cpu_count() or 1,
                                            threads_per_worker=1, processes=True,
                                            host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                            silence_logs=logging.ERROR)
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(self.address, timeout="10s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise SceneError("--scheduler", f"cannot connect to {self.address!r}: {exc}; "
                                                f"give tcp://host:port of a running Dask "
                                                f"scheduler") from None
        try:
            info = self.client.run(worker_info)
        except Exception as exc:
            self.__exit__(None, None, None)
            raise SceneError("--scheduler", f"the workers cannot import transient ({exc}); "
                                            f"install it in the workers' environment") from None
        other = {w: i["version"] for w, i in info.items() if i["version"] != __version__}
        if other:
            print(f"transient sweep: warning: workers run other versions of transient: {other}",
                  file=sys.stderr)
        return self.client

    def __exit__(self, *exc) -> None:
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
