"""The numerics of an ODE, knowing nothing of engines: Runge–Kutta pairs and their tableaus
(:mod:`.tableaus`), the step, its error norm, the step-size control and the dense output
(:mod:`.rk`), a Rosenbrock–W method for stiff problems that reuses them, with a model's banded
Jacobian passed as a kernel like the derivative (:mod:`.rosenbrock`), the location of an event
function's zero on the dense output (:mod:`~transient.core.integrator.roots`), the search of
periodic breakpoints (:mod:`~transient.core.integrator.breakpoints`), and a plain adaptive driver
of them all (:mod:`.solve`, what the tests run on closed-form problems).

The contract with a model is three things, passed as arguments, never imported:

- the derivative, a kernel ``rhs(ctx, y, out)`` writing y′ into ``out`` (``ctx``: a tuple of
  what it needs besides the state); an event function is a kernel ``g(ctx, y)`` returning a
  float. Kernels passed so are compile-time constants (:class:`transient.core.jit._KernelArgument`):
  each compiles its own copy of the integrator's functions, with the derivative inlined;
- the error control of each state component, an int array ``control``
  (:data:`transient.core.declare.BY_SIZE` …), which the model declares with its state;
- the component ``ix`` that holds the independent variable, if the state holds it (a
  non-autonomous problem carries it as a state; −1 if not): a step puts it exactly.

The engine's stepper (:mod:`transient.core.stepper`) drives these functions with its model; the
import contracts (``pyproject.toml``) keep this package from importing either.
"""
