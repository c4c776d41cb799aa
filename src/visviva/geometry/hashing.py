"""SplitMix64's finalizer: a 64-bit integer scrambled so every input bit moves every output bit.

Steele, Lea & Flood, "Fast splittable pseudorandom number generators" (OOPSLA 2014). The
counter-based random numbers of :mod:`visviva.particles.random` and the spatial hash of
:mod:`visviva.geometry.neighbour_cells` share it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["mix64"]

_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


@njit(cache=True)
def mix64(z):  # pragma: no cover - compiled
    """The finalizer of SplitMix64 on a ``uint64`` (Numba)."""
    z = (z ^ (z >> np.uint64(30))) * _MIX1
    z = (z ^ (z >> np.uint64(27))) * _MIX2
    return z ^ (z >> np.uint64(31))
