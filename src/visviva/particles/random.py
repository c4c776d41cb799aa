"""Counter-based random numbers: each particle's draws are a function of who it is.

A particle's random numbers are ``uniform(seed, stream, serial, draw)``: the emitter's seed,
the emitter's index (its stream), the particle's birth serial number in that emitter, and the
index of the draw (position, direction, speed, ...). Nothing else goes in — not the step, not
the thread, not the order in which particles were made — so a run gives the same particles
whatever its step size, its number of threads, or where it was checkpointed: an emitter's
whole random state is the count of particles it has made.

The mixing function is SplitMix64's finalizer (Steele, Lea & Flood, "Fast splittable
pseudorandom number generators", OOPSLA 2014), applied to the key and counter in turn; the
construction is that of counter-based generators (Salmon, Moraes, Dror & Shaw, "Parallel random
numbers: as easy as 1, 2, 3", SC 2011).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..geometry.hashing import mix64 as _mix

__all__ = ["uniform"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
#: 2⁻⁵³: a 53-bit integer times this is a double in [0, 1) with every bit random.
_UNIT = 1.0 / 9007199254740992.0


@njit(cache=True)
def uniform(seed, stream, serial, draw):  # pragma: no cover - compiled
    """A double in [0, 1) for draw ``draw`` of particle ``serial`` of stream ``stream``."""
    key = _mix(np.uint64(seed) + _GOLDEN * np.uint64(stream + 1))
    key = _mix(key ^ (np.uint64(serial) * _GOLDEN))
    bits = _mix(key + np.uint64(draw + 1) * _GOLDEN)
    return float(bits >> np.uint64(11)) * _UNIT
