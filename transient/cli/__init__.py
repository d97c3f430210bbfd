"""The ``transient`` command: simulate a scene, then read, plot and analyse its result
(docs/guide/cli.md).

Exit codes: 0 success; 2 invalid input (one line, no traceback); 1 the simulation failed (the
partial result is kept and marked incomplete).

Each command group is a module that registers its subparsers and parses, calls the library,
draws and prints: ``run`` (run, check, info), ``steady``, ``plot``, ``kinematics``, ``modes``,
``verify`` (bench, stress), ``efficiency``, ``loads``, ``orders``, ``sweep`` (sweep,
sweep-plot); ``common`` holds what they share. Errors become exit codes here only, in :func:`main`.
"""
from __future__ import annotations

import argparse
import gc
import os
import sys

from ..errors import SceneError, SimulationError, WriteFailed
from ..stopping import interrupting
from . import efficiency, kinematics, loads, modes, orders, plot, run, steady, sweep, verify
from .common import EXIT_FAILED, EXIT_INVALID, EXIT_OK, KERNELS_NOTICE, OptionParser

__all__ = ["EXIT_FAILED", "EXIT_INVALID", "EXIT_OK", "KERNELS_NOTICE", "entry", "main"]

# The error of a result file whose writes failed: HDF5's deallocators must never run on it.
_BROKEN_WRITE: WriteFailed | None = None

#: The subcommands' registrations, in the order ``transient --help`` lists them.
_COMMANDS = (run.register, steady.register, plot.register, kinematics.register, modes.register,
             verify.register_bench,
             efficiency.register, loads.register, orders.register, verify.register_stress,
             sweep.register)

#: The exit code of a command whose reader closed its standard output: 128 + SIGPIPE, as a
#: shell reports ``cat`` ended by the signal.
EXIT_BROKEN_PIPE = 128 + 13

#: One example of each command, in the order ``transient --help`` lists them: the end of
#: ``transient --help`` lists them all, and each command's own help ends with its own.
EXAMPLES = {
    "run": "transient run cases/swash_plate_4cyl.toml -o results",
    "check": "transient check cases/gots_diesel_4400.toml",
    "info": "transient info results/swash_plate_4cyl.h5",
    "warmup": "transient warmup cases/radial_9cyl.toml",
    "steady": "transient steady cases/gots_diesel_friction.toml --cycles 2",
    "plot": "transient plot results/swash_plate_4cyl.h5 -o results",
    "kinematics": "transient kinematics cases/radial_5cyl.toml --points 721 -o results",
    "modes": "transient modes cases/inline6_damper.toml -o results",
    "bench": "transient bench --quick -o results/benchmarks",
    "efficiency": "transient efficiency cases/gots_diesel_friction.toml --rpm 1000,2000",
    "loads": "transient loads results/gots_diesel_4400.h5 --cylinder 2 -o results",
    "orders": "transient orders results/diesel_4cyl_misfire.h5 --max-order 6",
    "stress": "transient stress --quick -o results",
    "sweep": "transient sweep cases/sweeps/gots_pi_gains.toml -o results",
    "sweep-plot": "transient sweep-plot results/gots_pi_gains.h5 -o results",
}


def entry() -> None:
    """The ``transient`` command: :func:`main`, then exit with its code. After a failed write
    (:class:`~transient.errors.WriteFailed`) the process leaves by ``os._exit``, skipping the
    interpreter's teardown, in which HDF5 would retry the writes of the broken file and crash.

    Before exiting, every live object is frozen out of the garbage collector: the interpreter's
    final collections would otherwise walk numba's type system, a large part of a short run.
    Files are closed by then; reference counting still tears the modules down.

    A reader that stops reading (``transient info … | head``) ends the command as it ends
    ``cat``: exit 128 + SIGPIPE, no traceback; standard output goes to the null device, so that
    the interpreter's final flush does not raise again."""
    try:
        code = main()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = EXIT_BROKEN_PIPE
    gc.freeze()
    if _BROKEN_WRITE is not None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` (default: the process's arguments), run the command and return its exit
    code. Every command's errors are turned into exit codes here, so that each prints as one
    line: invalid input (a :class:`~transient.errors.SceneError`, a file that is missing, exists
    or may not be written) → 2; a failed simulation (:class:`~transient.errors.SimulationError`)
    or an interrupt → 1. Options are checked as scene keys are, each error one line."""
    try:
        args = _parser().parse_args(argv)
        with interrupting():
            return args.func(args)
    except SceneError as exc:
        print(exc.line(), file=sys.stderr)
        return EXIT_INVALID
    except (FileExistsError, PermissionError, FileNotFoundError) as exc:
        print(str(exc), file=sys.stderr)
        return EXIT_INVALID
    except SimulationError as exc:
        print(f"transient: {exc}", file=sys.stderr)
        if isinstance(exc, WriteFailed):
            # (its traceback holds the broken file's objects: keep them from being freed)
            global _BROKEN_WRITE
            _BROKEN_WRITE = exc
        return EXIT_FAILED
    except KeyboardInterrupt:
        print("transient: interrupted", file=sys.stderr)
        return EXIT_FAILED




def _parser() -> argparse.ArgumentParser:
    width = max(map(len, EXAMPLES))
    examples = "\n".join(f"  {name:<{width}}  {line}" for name, line in EXAMPLES.items())
    p = OptionParser(prog="transient",
                     description="Transient dynamics of piston machines: simulate a scene, then "
                                 "read, plot and analyse its result.",
                     epilog=f"examples, one per command:\n{examples}",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, metavar="command")
    for register in _COMMANDS:
        register(sub)
    for name, command in sub.choices.items():
        command.epilog = f"example: {EXAMPLES[name]}"
    return p
