"""Running ``transient`` with its stderr on a terminal, as a user does (the progress bars)."""
from __future__ import annotations

import fcntl
import os
import pty
import select
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def terminal_run(argv, timeout=900.0):
    """``transient`` in a new process whose stderr is a terminal (a pseudo-terminal, read here
    as it is written, so that the process never waits on a full one): (return code, stdout,
    what the terminal received)."""
    master, slave = pty.openpty()
    # 40 rows of 120 columns (a new pseudo-terminal has 0 × 0, in which tqdm draws nothing)
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    proc = subprocess.Popen([sys.executable, "-m", "transient", *argv], cwd=REPO,
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    received = b""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if select.select([master], [], [], 1.0)[0]:
            try:
                chunk = os.read(master, 65536)
            except OSError:  # EIO: the process has closed the terminal
                break
            if not chunk:
                break
            received += chunk
    os.close(master)
    try:
        out = proc.communicate(timeout=60.0)[0]
    except subprocess.TimeoutExpired:
        proc.kill()  # (a hung run: fail, and leave no process behind)
        raise
    return proc.returncode, out.decode(), received.decode(errors="replace")
