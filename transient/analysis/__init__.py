"""What is read from a run once it is computed: the end-of-run summary, the speed fluctuation and
steady state, ISO 8528-5 transient response, mechanical efficiency and where the power goes,
orders, the cylinders' thermodynamics, crank and bearing loads
(:mod:`transient.analysis.loads`) and wear. Each
takes a scene and its trajectory; none runs the stepper. Besides, without a run, the torsional
modes and critical speeds of an elastic shaft line (:mod:`transient.analysis.torsion`)."""
