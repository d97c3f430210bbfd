"""The run's loop (:func:`~transient.core.stepper.loop.advance`), composing the integrator
(:mod:`transient.core.integrator`) with the model (:mod:`transient.core.model`): steps in crank
angle or in time between breakpoints (:mod:`~transient.core.stepper.breakpoints`), the
engine's events (:mod:`.events`) and what they switch, the output grid, and what the loop and its Python caller
exchange between chunks (:mod:`.io`)."""
from .loop import advance, buffers

__all__ = ["advance", "buffers"]
