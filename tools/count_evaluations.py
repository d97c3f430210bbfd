"""Where a run's model evaluations go: right-hand sides against mode-margin evaluations, the
latter by the stepper's function that asked for them, and the root finder's calls and
iterations by event component.

The kernels run as Python (``NUMBA_DISABLE_JIT=1``, set here before numba is imported), so that
the margins and the root finder can be wrapped and counted; the run takes the compiled run's
steps (the same right-hand sides and steps on the diesel's 100 revolutions). Run::

    .venv/bin/python tools/count_evaluations.py gots_diesel_governed 100
"""
import collections
import dataclasses as dc
import os
import sys
from pathlib import Path

os.environ["NUMBA_DISABLE_JIT"] = "1"

import transient.core.model.rhs as rhs
import transient.core.stepper.events as events
from transient.run import integrate
from transient.scene import load_scene

CASES = Path(__file__).resolve().parents[1] / "cases"
margins = collections.Counter()  # caller → margin evaluations
roots = collections.Counter()  # event component → root finder calls
iterations = collections.Counter()  # event component → its iterations


def counted(function, record):
    def wrapper(*args):
        result = function(*args)
        record(sys._getframe(1).f_code.co_name, args, result)
        return result
    return wrapper


def margin_call(caller, args, result):
    margins[caller] += 1


def root_call(caller, args, result):
    comp = args[4]
    name = f"pair {comp - events.PAIR_COMP}" if comp >= events.PAIR_COMP else f"component {comp}"
    roots[name] += 1
    iterations[name] += result[1]


# (the kernels look these names up in the module at each call when run as Python)
rhs.margins_at = counted(rhs.margins_at, margin_call)
rhs.margins_inline = counted(rhs.margins_inline, margin_call)
events._root = counted(events._root, root_call)

name, revolutions = sys.argv[1], float(sys.argv[2])
scene = load_scene(CASES / f"{name}.toml")
scene = dc.replace(scene, output=dc.replace(scene.output, samples_per_rev=1),
                   solver=dc.replace(scene.solver, rtol=1e-8, atol=1e-11),
                   run=dc.replace(scene.run, revolutions=revolutions))
solver = integrate(scene, keep=False).solver
print(f"{name}, {revolutions:g} revolutions: {solver['nfev']} right-hand sides counted by the "
      f"stepper, {solver['nsteps']} steps; margin evaluations {sum(margins.values())}: "
      + ", ".join(f"{n} from {caller}" for caller, n in margins.most_common()))
for comp, n in roots.most_common():
    print(f"  root finding on {comp}: {n} calls, {iterations[comp] / n:.1f} iterations a call")
