"""The stopping signals' handler: KeyboardInterrupt as Ctrl-C, except inside llvmlite, where the
signal comes back a moment later (an exception raised in LLVM's callback into Python crashes
the process)."""
from __future__ import annotations

import os
import signal
import sys
import threading
import time
from pathlib import Path

import llvmlite
import pytest

from transient.stopping import in_llvmlite, interrupt, interrupting

#: A function whose code says it is llvmlite's, as a callback from LLVM is.
_LLVMLITE_FILE = str(Path(llvmlite.__file__).resolve().parent / "binding" / "executionengine.py")
_CALLBACK = """
def callback(signum):
    os.kill(os.getpid(), signum)
    for _ in range(10_000):  # (the handler runs between these bytecodes)
        pass
    return "returned"
"""


def _llvmlite_callback():
    space = {"os": os}
    exec(compile(_CALLBACK, _LLVMLITE_FILE, "exec"), space)
    return space["callback"]


def test_in_llvmlite_looks_along_the_callers():
    """Python code that llvmlite's code called (a callback from LLVM) is inside llvmlite."""
    seen = []

    def inner():
        seen.append(in_llvmlite(sys._getframe()))

    space = {}
    exec(compile("def call(f):\n    return f()\n", _LLVMLITE_FILE, "exec"), space)
    space["call"](inner)
    inner()
    assert seen == [True, False]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_inside_llvmlite_comes_back_outside(signum, ctrl_c):
    # (handlers are installed, and signals handled, in the main thread only)
    assert threading.current_thread() is threading.main_thread()
    callback = _llvmlite_callback()
    with interrupting():
        try:
            returned = callback(signum)
        except KeyboardInterrupt:
            returned = "interrupted inside llvmlite"
        assert returned == "returned"
        with pytest.raises(KeyboardInterrupt):
            time.sleep(10.0)  # the signal, sent again, interrupts here


def test_a_stop_elsewhere_interrupts_at_once(ctrl_c):
    with interrupting(), pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(10.0)


def test_a_signal_the_process_ignores_stays_ignored():
    """``nohup`` starts a command with SIGHUP ignored: closing the terminal must not stop it."""
    kept = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with interrupting():
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGTERM) is interrupt
    finally:
        signal.signal(signal.SIGHUP, kept)
