"""The compile decorator of the hot kernels.

``kernel`` is ``numba.njit(cache=True)`` without numba's reference counting (``_nrt=False``).
With it, every call that passes arrays — the :data:`transient.core.model.Model` tuple holds a
dozen — increfs and decrefs each of them through an indirect call: measured on the single
cylinder (a throwaway loop timing one small kernel), passing the Model to it cost 130 ns of
260 ns; without reference counting the same call took 72 ns. The whole right-hand side went from
0.512 µs per call (the previous record of ``scripts/stepper_overhead.py``) to 0.036 µs. Kernels under ``kernel`` must not allocate arrays (they work
in buffers their caller allocated); the few that allocate (the stepper's ``advance``, work
arrays) stay under plain ``njit(cache=True)``.
"""
from __future__ import annotations

from numba import njit


def kernel(fn=None, **options):
    """``@kernel`` or ``@kernel(inline="always")``: njit, cached, no reference counting."""
    if fn is None:
        return lambda f: njit(f, cache=True, _nrt=False, **options)
    return njit(fn, cache=True, _nrt=False, **options)
