"""transient — transient dynamics of piston machines with variable shaft speed.

Module map (data flow: scene → mechanism → reduced model → stepper → result → analysis/plots):

- ``scene``          TOML → frozen dataclasses, validation, resolved TOML out
- ``mechanisms``     crank_slider, swash_plate: geometry, validation, kinematics tables
- ``forces``         gas pressure tables and cycles (the Wiebe cycles' file cache: ``wiebe_cache``)
- ``assemble``       scene → compiled model arrays and breakpoints
- ``core``           every numba kernel: kinematics, reduced model (18), DOP853 stepper
- ``simulate``       drives the compiled stepper, streams results; prescribed-speed mode
- ``reference``      the same model in plain numpy through ``scipy.integrate.solve_ivp``
- ``results``        HDF5 writer (streaming) and reader
- ``analysis``       speed fluctuation, steady state
- ``plots``          ax-first plotting helpers
- ``cli``            the ``transient`` command

Public API: :func:`load_scene`, :func:`simulate`, :func:`open_result`.
"""
__version__ = "0.1.0"

from .results import open_result  # noqa: E402
from .scene import load_scene  # noqa: E402
from .simulate import simulate  # noqa: E402

__all__ = ["load_scene", "simulate", "open_result", "__version__"]
