"""run._WriteBehind: a result's blocks are written in a second thread while the stepper
computes the next, one at a time and in order; a failed write is raised in the caller."""
import threading
import time

import pytest

from transient.core import stepper
from transient.run import _WriteBehind


def test_blocks_are_written_in_order_one_at_a_time():
    log = []
    busy = threading.Lock()

    def write(k):
        assert busy.acquire(blocking=False), "two writes at once"
        log.append(("start", k, threading.current_thread().name))
        time.sleep(0.01)
        log.append(("end", k))
        busy.release()

    writes = _WriteBehind()
    for k in range(5):
        writes.start(write, k)
    writes.wait()
    writes.shutdown()
    assert [e[:2] for e in log] == [(w, k) for k in range(5) for w in ("start", "end")]
    assert all(e[2] != threading.current_thread().name for e in log if e[0] == "start")


def test_the_caller_goes_on_while_a_block_is_written():
    release = threading.Event()
    released = []
    writes = _WriteBehind()
    # the write waits for the caller: had start() waited for the write, it would time out
    writes.start(lambda: released.append(release.wait(5.0)))
    release.set()
    writes.wait()
    writes.shutdown()
    assert released == [True]


def test_a_failed_write_is_raised_by_the_next_wait_and_only_once():
    def write(k):
        if k == 1:
            raise OSError("disk full")

    writes = _WriteBehind()
    writes.start(write, 0)
    writes.start(write, 1)
    with pytest.raises(OSError, match="disk full"):
        writes.start(write, 2)  # waits for write 1 first
    writes.wait()  # nothing in progress: write 2 never started
    writes.start(write, 1)
    writes.settle()  # a failure ignored where another one is being reported
    writes.shutdown()


def test_the_stepper_releases_the_gil():
    """The overlap needs the compiled stepper to run without the GIL."""
    assert stepper.advance.targetoptions.get("nogil") is True


def test_result_files_hold_a_bounded_chunk_cache(tmp_path):
    """The result file is opened with a 1 MiB chunk cache per dataset, not HDF5 2.0's 8 MiB,
    which over every column of a long run holds far more memory than the writer needs; and the
    columns' chunks are the rows it is sized for."""
    from transient.results import CHUNK_CACHE_BYTES, CHUNK_ROWS, ResultWriter

    w = ResultWriter(tmp_path / "r.h5", "s", "", {"t": "s", "omega": "rad/s"})
    try:
        assert CHUNK_CACHE_BYTES == 1 << 20
        assert w.f.id.get_access_plist().get_cache()[2] == CHUNK_CACHE_BYTES
        assert w.datasets["t"].chunks == (CHUNK_ROWS,)
        assert w.datasets["t"].id.get_access_plist().get_chunk_cache()[1] == CHUNK_CACHE_BYTES
    finally:
        w.f.close()


@pytest.mark.parametrize("waits_in", ["wait", "start"])
def test_a_stop_while_waiting_for_a_write_acts_when_the_write_has_ended(waits_in, ctrl_c):
    """A Ctrl-C (or SIGTERM, handled alike) that lands while the caller waits for the write acts after the
    write: raised inside the future's locks it could leave one held, and the writing thread
    then blocks on it for ever (a hung process)."""
    import os
    import signal

    from transient.stopping import interrupting

    ended = []

    def write():
        time.sleep(0.1)  # (the caller waits by then)
        os.kill(os.getpid(), signal.SIGINT)  # (handled in the caller's thread)
        time.sleep(0.2)
        ended.append(True)

    writes = _WriteBehind()
    with interrupting(), pytest.raises(KeyboardInterrupt):
        writes.start(write)
        getattr(writes, waits_in)(*([] if waits_in == "wait" else [lambda: None]))
    assert ended == [True]
    writes.shutdown()
