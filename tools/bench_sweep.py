"""Sweep speed-up and scheduler overhead: the 64-run sweep of
``cases/sweeps/gots_eta_speed_load.toml`` serially in one process (``--scheduler serial``, no Dask)
against a 2-worker Dask LocalCluster, and the per-run overhead of the scheduler.

Measured, median of ``--repeat`` rounds (each round: serial, then the cluster):

* serial: ``run_sweep(scheduler="serial")`` after a warm-up run in this process (kernels loaded);
* cluster, end to end: ``run_sweep(workers=2)``, cluster start and stop included, as
  ``transient sweep`` does it;
* cluster, warm: on a running 2-worker cluster whose workers ran one warm-up run each, through
  ``--scheduler`` — the sweep itself, as on a cluster that is up already.

Every run writes the sweep file as the command does (the client writes while workers compute).
Per-run overhead: (a) 1000 no-op tasks through the same client and ``as_completed``, round trip
per task; (b) from the warm sweep, 2·wall/64 minus the mean time a worker spent in a run.

Rerun: ``.venv/bin/python tools/bench_sweep.py [--revolutions N] [--repeat K]`` (the sweep's
300 revolutions by default).
"""
from __future__ import annotations

import argparse
import re
import statistics
import tempfile
import time
from pathlib import Path

from transient.sweeps import load_sweep, run_one, run_sweep, worker_info

SWEEP = Path(__file__).resolve().parents[1] / "cases" / "sweeps" / "gots_eta_speed_load.toml"


def _sweep(tmp: Path, revolutions: int | None):
    text = SWEEP.read_text()
    if revolutions:
        text = re.sub(r'"run\.revolutions" = \d+', f'"run.revolutions" = {revolutions}', text)
    text = text.replace('base = "../', f'base = "{SWEEP.parents[1]}/')
    path = tmp / SWEEP.name
    path.write_text(text)
    return load_sweep(path)


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _noop() -> None:
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--revolutions", type=int, default=None)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    from dask.distributed import Client, LocalCluster, as_completed

    tmp = Path(tempfile.mkdtemp(prefix="bench_sweep_"))
    sweep = _sweep(tmp, args.revolutions)
    n = len(sweep.runs)
    run_one(sweep.runs[0].scene, sweep.columns)  # warm-up: kernels loaded in this process
    serial, cold, warm, noop, busy = [], [], [], [], []
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0") as cluster, Client(cluster) as client:
        client.run(worker_info)
        client.gather([client.submit(run_one, s.scene, sweep.columns, pure=False)
                       for s in sweep.runs[:2]])  # one warm-up run per worker (probably)
        for k in range(args.repeat):
            serial.append(_timed(lambda: run_sweep(sweep, tmp / "serial", "serial", force=True)))
            cold.append(_timed(lambda: run_sweep(sweep, tmp / "cold", workers=2, force=True)))
            t0 = time.perf_counter()
            done = run_sweep(sweep, tmp / "warm", cluster.scheduler_address, force=True)
            warm.append(time.perf_counter() - t0)
            busy.append(statistics.mean(r["wall_s"] for r in done.rows))
            t = _timed(lambda: [f.result() for f in as_completed(
                [client.submit(_noop, pure=False) for _ in range(1000)])])
            noop.append(t / 1000)
            print(f"round {k + 1}: serial {serial[-1]:.2f} s, cluster end to end {cold[-1]:.2f} s, "
                  f"warm {warm[-1]:.2f} s, mean run {busy[-1] * 1e3:.1f} ms, no-op task "
                  f"{noop[-1] * 1e3:.2f} ms", flush=True)
    med = statistics.median
    print(f"\n{n} runs of {sweep.name}, median of {args.repeat} rounds:")
    print(f"  serial (one process, no Dask):      {med(serial):.2f} s "
          f"({med(serial) / n * 1e3:.1f} ms per run)")
    print(f"  2 workers, end to end (cluster up): {med(cold):.2f} s, speed-up "
          f"{med(serial) / med(cold):.2f}x")
    print(f"  2 workers, warm cluster:            {med(warm):.2f} s, speed-up "
          f"{med(serial) / med(warm):.2f}x")
    print(f"  per-run overhead: no-op task round trip {med(noop) * 1e3:.2f} ms; in the warm sweep "
          f"2·wall/{n} − mean run time = {(2 * med(warm) / n - med(busy)) * 1e3:.1f} ms "
          f"(mean run {med(busy) * 1e3:.1f} ms on a worker)")


if __name__ == "__main__":
    main()
