"""Errors that reach the user, each with what the CLI needs to print it, and
:func:`~transient.errors.show_value`, the one way a message quotes what the user gave."""
from __future__ import annotations

from typing import Any

#: Longest quotation of a user's value or key in a message: a message names the offending token,
#: never a whole line of a file, and stays one line on a terminal.
QUOTE_LIMIT = 40


def clip(text: str, limit: int = QUOTE_LIMIT) -> str:
    """``text`` with control characters escaped and cut to ``limit`` characters ("..." marks the
    cut), so that a quoted token can neither break the line nor fill the screen."""
    text = escaped(text)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def escaped(text: str) -> str:
    """``text`` with every character a terminal would act on rather than show (a control,
    format or separator character: not ``str.isprintable``) written as its Python escape."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def show_value(value: Any) -> str:
    """``repr(value)`` as a message quotes it (:func:`clip`)."""
    return clip(repr(value))


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

    Examples
    --------
    >>> import transient
    >>> try:
    ...     transient.Scene.from_dict({"mechanism": {}})
    ... except transient.SceneError as exc:
    ...     print(exc.key)
    mechanism.type
    """

    def __init__(self, key: str, message: str, file: str = "") -> None:
        self.key = key
        self.message = message
        self.file = file
        super().__init__(self.line())

    def line(self) -> str:
        """The one line the CLI prints; a key the user wrote is quoted as
        :func:`~transient.errors.clip` does
        (a TOML key may hold any character), and no part may start a second line."""
        prefix = f"{self.file}: " if self.file else ""
        line = f"{prefix}{clip(self.key, 4 * QUOTE_LIMIT)}: {self.message}"
        return line.replace("\n", "\\n").replace("\r", "\\r")


class SimulationError(RuntimeError):
    """The integration failed; carries where (time, angle, state), and ``result``, the run up to
    there (a :class:`transient.Result`, when there is one).

    Examples
    --------
    A load torque brakes the coasting shaft to a stop two revolutions in, long before the
    50 revolutions the run asks for:

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
    >>> stalls = scene.replace(load={"torque": 10.0},
    ...                        run={"revolutions": 50})
    >>> try:
    ...     transient.simulate(stalls)
    ... except transient.SimulationError as exc:
    ...     print(exc.result.status, exc.result.complete)
    stalled False
    """

    def __init__(self, message: str, result=None) -> None:
        super().__init__(message)
        self.result = result


class WriteFailed(SimulationError):
    """A write to the result file failed mid-run (a full disk). HDF5 cannot close the handles of
    a file whose writes failed: at interpreter exit its deallocators retry the writes and crash
    (SIGSEGV), so the command line leaves by ``os._exit`` after printing (``cli.entry``)."""
