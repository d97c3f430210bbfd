"""Errors that reach the user, each with what the CLI needs to print it."""
from __future__ import annotations


class SceneError(ValueError):
    """An invalid scene: the CLI prints ``file: key: message`` and exits 2.

    Parameters
    ----------
    key
        Dotted TOML key that is wrong, e.g. ``"mechanism.swash_deg"``.
    message
        What is wrong and what is allowed, in one line.
    file
        The scene file, filled in by the loader if the raiser does not know it.
    """

    def __init__(self, key: str, message: str, file: str = "") -> None:
        self.key = key
        self.message = message
        self.file = file
        super().__init__(self.line())

    def line(self) -> str:
        prefix = f"{self.file}: " if self.file else ""
        return f"{prefix}{self.key}: {self.message}"


class SimulationError(RuntimeError):
    """The integration failed; carries where (time, angle, state), and ``result``, the run up to
    there (a :class:`transient.results.Result`, when there is one)."""

    def __init__(self, message: str, result=None) -> None:
        super().__init__(message)
        self.result = result


class WriteFailed(SimulationError):
    """A write to the result file failed mid-run (a full disk). HDF5 cannot close the handles of
    a file whose writes failed: at interpreter exit its deallocators retry the writes and crash
    (SIGSEGV), so the command line leaves by ``os._exit`` after printing (``cli.entry``)."""
