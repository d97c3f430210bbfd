"""The elastic shaft line of a scene's ``[shaft]`` table: its degrees of freedom (stations,
damper rings, the driven inertia), its constant stiffness and damping matrices and each
station's reduced inertia J_s(θ), J′_s(θ) at its own angle (:class:`~.line.ShaftLine`), and
the rigid scene equivalent to it (:func:`~.line.rigid_equivalent`).

It sits between the scene and the model's assembly, so that both the modal analysis
(:mod:`transient.analysis.torsion`) and the compiled model can build on it.
"""
from .line import ShaftLine, refuse_elastic_run, rigid_equivalent

__all__ = ["ShaftLine", "refuse_elastic_run", "rigid_equivalent"]
