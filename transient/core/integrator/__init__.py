"""The numerics of an ODE y′ = f(x, y), knowing nothing of engines: Runge–Kutta pairs and their
tableaus (:mod:`.tableaus`), the step, its error norm, the step-size control and the dense output
(:mod:`.rk`)."""
