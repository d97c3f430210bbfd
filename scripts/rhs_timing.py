"""What ``stepper_overhead.py`` and ``handwritten_kernel.py`` share: the compiled loops that
evaluate transient's crank-angle right-hand side over a table of states, and the timer of one
call. (Imported by those scripts; run neither this file nor them from elsewhere.)"""
import statistics
import time

from transient.core import model as cm
from transient.core.jit import kernel

#: Right-hand sides per DOP853 step. The stepper picks each cylinder's gas table piece once per
#: step (``model.select_pieces``, keyed by the step's ``sel``): the loops keep ``sel`` for this
#: many calls too, so that a call costs what it costs inside a step.
CALLS_PER_STEP = 12


@kernel
def rhs_loop(m, states, out, sw, wk):
    """Evaluate the crank-angle RHS at every state (rows: φ, t, K, works); return a checksum.
    A kernel with its buffers from outside, as the stepper calls the RHS (core.jit)."""
    acc = 0.0
    for i in range(states.shape[0]):
        sel = states[i - i % CALLS_PER_STEP, cm.PHI]
        cm.derivative(m, True, states[i], sel, sw, wk, out)
        acc += out[cm.KINETIC]
    return acc


@kernel
def rhs_chain(m, states, y, out, sw, wk):
    """The same evaluations, each at a state that depends on the previous result (0·out still
    has to wait for out), as a Runge–Kutta step's stages do: the RHS's latency, where
    ``rhs_loop``, whose calls are independent, measures its throughput."""
    acc = 0.0
    for i in range(states.shape[0]):
        for j in range(y.shape[0]):
            y[j] = states[i, j] + 0.0 * out[j]
        sel = states[i - i % CALLS_PER_STEP, cm.PHI]
        cm.derivative(m, True, y, sel, sw, wk, out)
        acc += out[cm.KINETIC]
    return acc


@kernel
def margins_loop(m, states, out, sw, wk):
    """The mode margins at every state as the stepper evaluates them outside its root finder: a
    call to ``model.margins_at`` (not inlined; it passes the Model by value). ``out`` unused."""
    acc = 0.0
    for i in range(states.shape[0]):
        sel = states[i - i % CALLS_PER_STEP, cm.PHI]
        cm.margins_at(m, True, states[i], sel, sw, wk)
        acc += wk[cm.WK_G, 0]
    return acc


def per_call(loop, *args, rounds=7, loops=100):
    """Time of one call [s] of a loop ``loop(x, states, …)`` over the rows of ``states`` (its
    second argument): median over ``rounds`` of ``loops`` loops, after a warm-up."""
    loop(*args)
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(loops):
            loop(*args)
        times.append((time.perf_counter() - t0) / (loops * args[1].shape[0]))
    return statistics.median(times)
