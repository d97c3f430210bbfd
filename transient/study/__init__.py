"""Studies that run a scene many times to answer one design question: mechanical efficiency over
speed and load (:mod:`transient.study.efficiency`), the flywheel for a speed fluctuation
(:mod:`transient.study.flywheel`)."""
