"""The weighted sum of a Runge–Kutta step's stages, entry by entry, in a fixed order.

``h Σ_j w_j k_j`` is summed for each entry over the stages in order, zero weights skipped, with
no reassociation: every entry of every system gets the same operations whatever the array's
length, alignment or thread count. A BLAS matrix–vector product orders its sums by length and
alignment, so one system would step differently alone and in a batch (a chaotic pendulum then
parts from itself within seconds). NumPy's entry-wise updates keep the order too, but make a
temporary per stage; this kernel adds each stage into the sum in place.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["weighted_sum"]


@njit(cache=True)
def weighted_sum(rows: np.ndarray, scaled: np.ndarray, out: np.ndarray) -> None:
    """``out[k] = Σ_j scaled[j] rows[j, k]`` over ``j < len(scaled)`` in order, for
    ``rows`` of shape ``(stages, size)``; terms of zero weight are left out."""
    size = rows.shape[1]
    for k in range(size):
        out[k] = 0.0
    for j in range(scaled.shape[0]):
        weight = scaled[j]
        if weight != 0.0:
            for k in range(size):  # stage by stage: each entry still sums in stage order
                out[k] += weight * rows[j, k]
