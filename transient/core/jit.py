"""The compile decorator of the hot kernels.

``kernel`` is ``numba.njit(cache=True)`` without numba's reference counting (``_nrt=False``).
With it, every call that passes arrays — the :data:`transient.core.model.Model` tuple holds a
dozen — increfs and decrefs each of them through an indirect call: measured on the single
cylinder, passing the Model to one small function cost 130 ns of a 260 ns right-hand side, and
the whole right-hand side ran 3.6× slower than a hand-written kernel of (18)
(``scripts/handwritten_kernel.py``). Kernels under ``kernel`` must not allocate arrays (they work
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
