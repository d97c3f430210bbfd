"""Forces along a trajectory φ(t), ω(t), ε(t), one module per mechanism.

* :mod:`~transient.analysis.loads.crank_slider`: pistons, rods, crankpins, big-end bearings, main
  journals and running torques of a crank-slider engine (Gots §2.3–§2.8);
* :mod:`~transient.analysis.loads.articulated`: master-and-articulated-rod engines (radial, V with
  fork-and-blade rods): pistons, rods, link pins and the master crankpins;
* :mod:`~transient.analysis.loads.swash_plate`: pistons, rods, the rods' joints on link 9 and the
  torques on the shaft;
* :mod:`.common`: the records' shared fields, the gas force on the pistons, the two-mass rod and
  the d'Alembert force of a turning mass.

Nothing is imported here, so that reading one mechanism's loads does not import the others'.
"""
