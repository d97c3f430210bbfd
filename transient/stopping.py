"""The signals that stop a command, in one place: which they are, how they stop it (as Ctrl-C
does, by KeyboardInterrupt) and how a step that must not be cut in half holds them back.

A KeyboardInterrupt must never be raised inside llvmlite: numba loads a cached kernel through a
ctypes callback from LLVM (its object cache), and an exception there is dropped by ctypes and
leaves LLVM with a buffer it never got, so the process crashes (SIGSEGV) and a run killed while
its kernels load would end with no result at all. :func:`interrupt` therefore sends such a
signal again a moment later, until Python code outside llvmlite takes it.
"""
from __future__ import annotations

import os
import signal
import threading
from contextlib import contextmanager
from pathlib import Path

#: Signals that stop a command as Ctrl-C (SIGINT) does, so that a run stopped by ``timeout``, a
#: batch scheduler's preemption or a closed terminal keeps its partial result marked incomplete
#: (status "interrupted").
INTERRUPTING_SIGNALS = ("SIGTERM", "SIGHUP")
#: Every signal that stops a command: Ctrl-C and :data:`INTERRUPTING_SIGNALS`.
STOPPING = tuple(getattr(signal, name) for name in ("SIGINT", *INTERRUPTING_SIGNALS)
                 if hasattr(signal, name))
#: How long a signal that landed inside llvmlite waits before it is sent again [s].
RESEND_AFTER = 0.02


def _llvmlite_dir() -> str | None:
    try:
        import llvmlite
    except ImportError:  # (then nothing can land there)
        return None
    return str(Path(llvmlite.__file__).resolve().parent) + os.sep


_LLVMLITE = _llvmlite_dir()


def in_llvmlite(frame) -> bool:
    """Whether ``frame`` or a frame it was called from is llvmlite's code."""
    while frame is not None and _LLVMLITE is not None:
        if frame.f_code.co_filename.startswith(_LLVMLITE):
            return True
        frame = frame.f_back
    return False


def interrupt(signum: int, frame) -> None:
    """A stopping signal's handler: KeyboardInterrupt, as Ctrl-C; inside llvmlite the signal is
    sent again after :data:`RESEND_AFTER` instead (see the module's docstring)."""
    if in_llvmlite(frame):
        threading.Timer(RESEND_AFTER, os.kill, (os.getpid(), signum)).start()
        return
    raise KeyboardInterrupt


def _in_main_thread() -> bool:
    """Python handles signals, and installs their handlers, in the main thread only."""
    return threading.current_thread() is threading.main_thread()


def _heeded() -> list[int]:
    """The stopping signals not ignored: one that the process was started ignoring (``nohup``
    ignores SIGHUP, a shell SIGINT for a job in the background) stays ignored."""
    return [sig for sig in STOPPING if signal.getsignal(sig) is not signal.SIG_IGN]


@contextmanager
def _handled_by(handler):
    """While the block runs, every stopping signal not ignored goes to ``handler``; the handlers
    before it come back after (in the main thread only, where Python handles signals)."""
    if not _in_main_thread():
        yield
        return
    kept = {sig: signal.signal(sig, handler) for sig in _heeded()}
    try:
        yield
    finally:
        for sig, kept_handler in kept.items():
            signal.signal(sig, kept_handler)


def interrupting():
    """While the block runs, every stopping signal not ignored raises KeyboardInterrupt
    (:func:`interrupt`)."""
    return _handled_by(interrupt)


@contextmanager
def deferred():
    """The stopping signals wait until the block ends, then act as they would have: a result
    file's last step moves the run into its layout, and stopped halfway it would leave neither
    the finished file nor the interrupted one."""
    caught = []
    try:
        with _handled_by(lambda signum, frame: caught.append(signum)):
            yield
    finally:
        if caught:
            signal.raise_signal(caught[0])
