"""The forces a scene applies, built once per scene on the Python side: cylinder pressure as
periodic piecewise-cubic tables (:mod:`.gas`) and the cycles that fill them (the mixed cycle,
Wiebe cycles :mod:`.wiebe`, the compressor's :mod:`.compressor`, the swash plate's pulse
:mod:`.trapezoid`), the closed cycle with Woschni wall heat that the compiled gas model is
checked against (:mod:`.closed_cycle`, :mod:`.woschni`), and tabulated loads
(:mod:`.load_table`). The compiled model reads the tables (:mod:`transient.core.model.tables`)."""
