"""Broad phase: which pairs of shapes may touch, by sweep and prune on their bounding boxes.

Each shape is bounded by an axis-aligned box ``[lo, hi]`` (from its support mapping along the
six world axes, widened by a margin: the distance it may travel in a step, plus the speculative
gap). Two shapes can only touch if their boxes overlap on all three axes. Sweep and prune
(D. Baraff, *Dynamic simulation of non-penetrating rigid bodies*, PhD thesis, Cornell 1992,
§6.2; J. D. Cohen, M. C. Lin, D. Manocha, M. Ponamgi, "I-COLLIDE", I3D 1995) sorts the boxes
by their lower bound on one axis and sweeps: each box is checked only against the boxes that
start before it ends, which is the boxes it overlaps on that axis. The axis is the one along
which the boxes' centres spread most, so that few overlap on it.

The pairs come out sorted by ``(i, j)``, ``i < j``, whatever the order of the sort, so a
simulation's contacts, and what is solved from them, are the same from run to run and on any
number of threads.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .convex import world_support

__all__ = ["overlapping_pairs", "shape_bounds"]


@njit(cache=True)
def shape_bounds(kind, params, vertices, position, rotation, margin, lo, hi, row):
    """Write the world bounding box of a posed convex shape grown by its own margin and
    ``margin`` [m] into ``lo[row]`` and ``hi[row]``."""
    grow = params[0] + margin
    for axis in range(3):
        dx, dy, dz = (
            (1.0, 0.0, 0.0) if axis == 0 else (0.0, 1.0, 0.0) if axis == 1 else (0.0, 0.0, 1.0)
        )
        high = world_support(kind, params, vertices, position, rotation, dx, dy, dz)
        low = world_support(kind, params, vertices, position, rotation, -dx, -dy, -dz)
        hi[row, axis] = high[axis] + grow
        lo[row, axis] = low[axis] - grow


@njit(cache=True)
def overlapping_pairs(lo, hi, active):
    """Every pair ``(i, j)``, ``i < j``, of active boxes that overlap, sorted.

    Args:
        lo, hi: ``(N, 3)`` each box's lower and upper corner [m].
        active: ``(N,)`` which boxes take part.

    Returns:
        ``(P, 2)`` int64 pairs in lexicographic order.
    """
    n = lo.shape[0]
    # The sweep axis: the largest spread of the active boxes' centres.
    mean = np.zeros(3)
    square = np.zeros(3)
    count = 0
    for i in range(n):
        if active[i]:
            for a in range(3):
                c = 0.5 * (lo[i, a] + hi[i, a])
                mean[a] += c
                square[a] += c * c
            count += 1
    if count < 2:
        return np.zeros((0, 2), dtype=np.int64)
    axis = int(np.argmax(square / count - (mean / count) ** 2))
    order = np.argsort(lo[:, axis], kind="mergesort")
    # The active boxes in sweep order, copied so that the sweep reads memory in sequence.
    m = 0
    for s in range(n):
        if active[order[s]]:
            order[m] = order[s]
            m += 1
    order = order[:m]
    box = np.empty((m, 6))
    for s in range(m):
        i = order[s]
        for a in range(3):
            box[s, a] = lo[i, a]
            box[s, 3 + a] = hi[i, a]
    pairs = np.empty((max(16, 4 * m), 2), dtype=np.int64)
    found = 0
    for s in range(m):
        end = box[s, 3 + axis]
        for t in range(s + 1, m):
            if box[t, axis] > end:
                break
            if (
                box[s, 0] <= box[t, 3] and box[t, 0] <= box[s, 3]
                and box[s, 1] <= box[t, 4] and box[t, 1] <= box[s, 4]
                and box[s, 2] <= box[t, 5] and box[t, 2] <= box[s, 5]
            ):  # fmt: skip
                if found == pairs.shape[0]:
                    grown = np.empty((2 * found, 2), dtype=np.int64)
                    grown[:found] = pairs
                    pairs = grown
                i, j = order[s], order[t]
                pairs[found, 0] = min(i, j)
                pairs[found, 1] = max(i, j)
                found += 1
    pairs = pairs[:found]
    keys = pairs[:, 0] * n + pairs[:, 1]
    return pairs[np.argsort(keys)].copy()  # keys are distinct: any sort gives one order
