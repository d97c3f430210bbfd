"""The reduced model of the machine, compiled: the :data:`~transient.core.model.layout.Model`
tuple and the layout of its state (:mod:`.layout`), the mechanisms' kernels, the forcing, the
serial chain and the friction solvers, the governor, the cylinder, the right-hand side
(:mod:`.rhs`) and the output row (:mod:`~transient.core.model.outputs`). It knows nothing of how
it is integrated."""
