"""The cells of the neighbour grid: the spatial hash, the rebuild, and the pieces kernels use.

:mod:`~visviva.particles.neighbour_grid` explains the design; this module holds its compiled
parts: the bucket of a cell (:func:`_bucket`), the rebuild (a counting sort of the points by
bucket, serial or split over the cores), and the Numba functions a kernel calls to visit the
27 cells around a point on :class:`GridArrays`: :func:`cell_of`, :func:`cell_range` and
:func:`neighbour_runs`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .random import _mix

__all__ = [
    "CELL_MARGIN",
    "MAX_CELLS",
    "MAX_COORDINATE",
    "MIN_RADIUS",
    "GridArrays",
    "cell_of",
    "cell_range",
    "neighbour_runs",
]

#: Cell edge over the interaction radius. The excess, 2⁻¹⁰, exceeds the rounding of
#: ``x / h`` (at most 2⁻¹² of a cell within ``MAX_CELLS``) plus that of a distance, so any
#: point within ``r`` lies in one of the 27 cells around a point's own.
CELL_MARGIN = 1.0 + 2.0**-10

#: Largest ``|x| / h`` accepted: cell integers stay exact and ``x / h`` rounds by < 2⁻¹².
MAX_CELLS = 2.0**40

#: Bounds of the radius and of coordinates [m]: squares of distances stay normal floats.
MIN_RADIUS = 1e-150
MAX_COORDINATE = 1e150

# Odd 64-bit multipliers of a block's three integers (the golden ratio's and two of xxHash's).
_HX = np.uint64(0x9E3779B97F4A7C15)
_HY = np.uint64(0xC2B2AE3D27D4EB4F)
_HZ = np.uint64(0x165667B19E3779F9)


class GridArrays(NamedTuple):
    """The grid after an update, for Numba kernels: ``n`` live points in bucket order.

    Attributes:
        start: First sorted position of each bucket, shape ``(T + 1,)``; bucket ``b`` holds
            sorted positions ``start[b] .. start[b + 1] − 1``.
        order: Index (row of ``positions``) of the point at each sorted position, ``(n,)``.
        x, y, z: Coordinates [m] in sorted order, ``(n,)`` each.
        inv_cell: ``1 / h`` [1/m].
        block_mask: The table's count of blocks (a power of two) minus one: it has
            ``T = 27 (block_mask + 1)`` buckets.
    """

    start: np.ndarray
    order: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    inv_cell: float
    block_mask: int


@njit(cache=True, inline="always")
def _bucket(cx, cy, cz, block_mask):  # pragma: no cover - compiled
    """Bucket of cell ``(cx, cy, cz)``: 27 × (hash of its 3×3×3 block) + its slot in the block."""
    bx, by, bz = cx // 3, cy // 3, cz // 3  # floor division, also for negative cells
    slot = (cx - 3 * bx) + 3 * (cy - 3 * by) + 9 * (cz - 3 * bz)
    key = np.uint64(bx) * _HX + np.uint64(by) * _HY + np.uint64(bz) * _HZ
    return 27 * np.int64(_mix(key) & np.uint64(block_mask)) + slot


@njit(cache=True, inline="always")
def cell_of(x, y, z, inv_cell):  # pragma: no cover - compiled
    """The cell integers ``floor(x / h)`` of a point (Numba; ``inv_cell = 1 / h``)."""
    return (
        np.int64(math.floor(x * inv_cell)),
        np.int64(math.floor(y * inv_cell)),
        np.int64(math.floor(z * inv_cell)),
    )


@njit(cache=True, inline="always")
def cell_range(g, cx, cy, cz):  # pragma: no cover - compiled
    """Sorted positions ``(begin, end)`` of the bucket of cell ``(cx, cy, cz)`` (Numba).

    The bucket holds every point of the cell and maybe points of far cells (whose blocks
    share a hash): a distance test keeps the right ones. The 27 cells around any cell have
    27 different buckets, so visiting them never meets a point twice.
    """
    b = _bucket(cx, cy, cz, g.block_mask)
    return g.start[b], g.start[b + 1]


@njit(cache=True, inline="always")
def neighbour_runs(g, cx, cy, cz, runs):  # pragma: no cover - compiled
    """The points of the 27 cells around cell ``(cx, cy, cz)`` as runs of sorted positions.

    Fills ``runs`` (a ``(27, 2)`` int64 scratch array) with ``(begin, end)`` pairs, empty
    buckets left out and adjacent ones joined (cells of one block lie side by side), and
    returns how many (Numba). The runs are disjoint: no point appears twice.
    """
    m = 0
    for dz in range(-1, 2):
        for dy in range(-1, 2):
            for dx in range(-1, 2):
                begin, end = cell_range(g, cx + dx, cy + dy, cz + dz)
                if begin == end:
                    continue
                if m and runs[m - 1, 1] == begin:
                    runs[m - 1, 1] = end
                else:
                    runs[m, 0], runs[m, 1] = begin, end
                    m += 1
    return m


# ---------------------------------------------------------------------------------------------
# Rebuild: keys, counting sort by bucket range, gather
# ---------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _within(x, inv_cell):  # pragma: no cover - compiled
    """Whether a coordinate is in the grid's range (false for NaN and infinities)."""
    return abs(x) <= MAX_COORDINATE and abs(x) * inv_cell < MAX_CELLS


@njit(cache=True)
def _keys_chunk(points, alive, inv_cell, block_mask, keys, begin, end):  # pragma: no cover
    """Buckets of rows ``begin .. end − 1`` (−1 if dead); return the first bad row or −1."""
    for i in range(begin, end):
        if alive.shape[0] and not alive[i]:
            keys[i] = -1
            continue
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        if not (_within(x, inv_cell) and _within(y, inv_cell) and _within(z, inv_cell)):
            return i
        cx, cy, cz = cell_of(x, y, z, inv_cell)
        keys[i] = _bucket(cx, cy, cz, block_mask)
    return -1


@njit(cache=True)
def _count_part(keys, start, lo, hi):  # pragma: no cover - compiled
    """Inclusive prefix sums of the bucket counts in ``lo .. hi − 1``; return their total."""
    for b in range(lo, hi):
        start[b] = 0
    for i in range(keys.shape[0]):
        k = keys[i]
        if lo <= k < hi:
            start[k] += 1
    total = 0
    for b in range(lo, hi):
        total += start[b]
        start[b] = total
    return total


@njit(cache=True)
def _scatter_part(keys, start, order, lo, hi, offset):  # pragma: no cover - compiled
    """Make ``start[lo:hi]`` global and place this range's points, stably.

    Each bucket's end is decremented as its points arrive from the last to the first, so it
    ends at the bucket's first position and every bucket keeps its points in index order.
    """
    for b in range(lo, hi):
        start[b] += offset
    for i in range(keys.shape[0] - 1, -1, -1):
        k = keys[i]
        if lo <= k < hi:
            start[k] -= 1
            order[start[k]] = i


@njit(cache=True)
def _gather_chunk(points, order, x, y, z, begin, end):  # pragma: no cover - compiled
    for s in range(begin, end):
        i = order[s]
        x[s], y[s], z[s] = points[i, 0], points[i, 1], points[i, 2]


# One serial and one parallel driver per pass: separate functions, each with its own entry in
# Numba's on-disk cache. The parallel one splits the buckets into ``parts`` ranges and the rows
# into ``bad.shape[0]`` tasks; ``bad`` gets each task's first bad row (or −1).


@njit(cache=True)
def _rebuild_serial(points, alive, inv_cell, block_mask, keys, start, order, x, y, z, bad, parts):
    n = points.shape[0]  # pragma: no cover - compiled
    table = 27 * (block_mask + 1)
    bad[0] = _keys_chunk(points, alive, inv_cell, block_mask, keys, 0, n)
    if bad[0] >= 0:
        return 0
    count = _count_part(keys, start, 0, table)
    _scatter_part(keys, start, order, 0, table, 0)
    start[table] = count
    _gather_chunk(points, order, x, y, z, 0, count)
    return count


@njit(cache=True, parallel=True)
def _rebuild_parallel(points, alive, inv_cell, block_mask, keys, start, order, x, y, z, bad, parts):
    n = points.shape[0]  # pragma: no cover - compiled
    table = 27 * (block_mask + 1)
    tasks = bad.shape[0]
    for k in prange(tasks):
        begin, end = k * n // tasks, (k + 1) * n // tasks
        bad[k] = _keys_chunk(points, alive, inv_cell, block_mask, keys, begin, end)
    for k in range(tasks):
        if bad[k] >= 0:
            return 0
    totals = np.empty(parts, dtype=np.int64)
    for p in prange(parts):
        totals[p] = _count_part(keys, start, p * table // parts, (p + 1) * table // parts)
    offsets = np.zeros(parts, dtype=np.int64)
    for p in range(1, parts):
        offsets[p] = offsets[p - 1] + totals[p - 1]
    for p in prange(parts):
        lo, hi = p * table // parts, (p + 1) * table // parts
        _scatter_part(keys, start, order, lo, hi, offsets[p])
    count = offsets[parts - 1] + totals[parts - 1]
    start[table] = count
    for k in prange(tasks):
        _gather_chunk(points, order, x, y, z, k * count // tasks, (k + 1) * count // tasks)
    return count
