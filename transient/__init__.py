"""transient — transient dynamics of piston machines with variable shaft speed.

The package is laid out as its data flow, scene → mechanism → reduced model → chain → stepper →
result → analysis, and each layer imports only those below it (the contracts in
``pyproject.toml``, checked by ``make test``). From the bottom up:

- ``core``           numba only: the integrator (Runge–Kutta pairs, step control, dense
                     output, event location), the model (kinematics per mechanism, the reduced
                     model (18), the serial chain (22), (27) with constant or mapped
                     efficiencies, reaction friction, governor, cylinder) and the stepper that
                     composes them, each array's layout declared once
- ``errors``, ``roots``, ``tomlout``, ``units``, ``version``, ``precompile``
                     what every layer shares: errors, scalar roots, TOML values, unit suffixes,
                     the version, the compile helper process
- ``mechanisms``     crank_slider, swash_plate, articulated: geometry, checks, kinematics
- ``forces``         gas pressure tables and cycles (mixed, Wiebe, Woschni), pulses, their cache
- ``scene``          TOML or dict → frozen records in SI, validated; resolved TOML out; what a
                     scene implies (its gas tables, phases, governor, the trajectory's columns)
- ``tabulate``, ``assemble``
                     scene → compiled model arrays and breakpoints (angle-only terms tabulated)
- ``results``        the in-memory run, the HDF5 writer (streaming) and reader
- ``reference``      the same model in plain numpy through ``scipy.integrate.solve_ivp``
- ``analysis``       irregularity, steady state, efficiency, orders, transient response, loads,
                     load and wear diagrams, the run's thermodynamics (IMEP, BMEP, FMEP), every
                     piston's kinematics, the end-of-run summary
- ``run``            drives the compiled stepper in chunks (or the reference path), prescribed
                     speed, :func:`simulate`, and the cycle map (one engine cycle from a state)
- ``plots``          ax-first plotting helpers
- ``shooting``       the periodic steady state by Newton's method on the cycle map,
                     :func:`steady`
- ``multirev``, ``longrun``
                     long runs on the envelope of the cycle map (multirevolution steps),
                     :func:`run_multirevolution` and its result
- ``study``, ``sweeps``
                     many runs: efficiency and flywheel studies; parameter sweeps on Dask
- ``verify``         the work–precision benchmark, its targets, the stress catalogue
- ``cli``            the ``transient`` command

Public API: :func:`load_scene` and :class:`Scene` (``Scene.from_dict``, ``scene.replace``,
``scene.to_toml``), :func:`simulate` → :class:`Result`, :func:`steady` (the periodic steady
state) → :class:`Result`, :func:`run_multirevolution` (a long run on its envelope) →
:class:`Result`, :func:`open_result`, :func:`sweep`, and the errors
:class:`SceneError` (invalid input) and :class:`SimulationError` (a run that failed).
"""
from . import errors
from .errors import SceneError, SimulationError
from .version import __version__

__all__ = ["load_scene", "Scene", "simulate", "steady", "run_multirevolution", "Result", "open_result", "sweep",
           "SceneError", "SimulationError", "errors", "__version__"]

#: The public names imported when first used (PEP 562), each from its module: importing a part
#: of the package (``transient.core.integrator`` alone, say) does not import the rest, and a
#: tool that needs only the scene reader does not start the stepper's modules.
_LAZY = {"load_scene": "scene", "Scene": "scene", "simulate": "run", "steady": "shooting",
         "run_multirevolution": "longrun",
         "Result": "results", "open_result": "results", "sweep": "sweeps.api"}


def __getattr__(name: str):
    if name in _LAZY:
        from importlib import import_module

        value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'transient' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
