"""The tools that measure transient rather than run a machine: the work–precision benchmark and
its targets (``transient bench``), the compiled peer's right-hand side, and the stress catalogue
(``transient stress``). Apart from the simulation flow, which never imports them."""
