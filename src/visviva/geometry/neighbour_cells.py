"""The cells of the neighbour grid: the spatial hash, the rebuild, and the pieces kernels use.

:mod:`~visviva.geometry.neighbour_grid` explains the design; this module holds its compiled
parts: the bucket of a cell (:func:`_bucket`), the stable counting sort that rebuilds the
grid (and, split over the cores, orders the queries' results), and the Numba functions a
kernel calls to visit the 27 cells around a point on :class:`GridArrays`: :func:`cell_of`,
:func:`cell_range` and :func:`neighbour_runs`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .hashing import mix64 as _mix

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
# Rebuild: keys, counting sort by bucket, gather
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


# A stable counting sort that may be split over ``parts`` chunks of the input (one per core):
# each chunk counts its keys into its own row of ``hist`` (parts × K), an exclusive prefix sum
# over the buckets, chunk after chunk within each bucket, turns every row into the chunk's
# first position in each bucket, and each chunk places its own items in order. The result is
# the serial stable sort's, whatever ``parts``: items of a bucket stay in input order.


@njit(cache=True)
def _histogram(keys, hist, p, begin, end):  # pragma: no cover - compiled
    """Counts of the keys ``keys[begin:end]`` (negative keys: none) into ``hist[p]``."""
    row = hist[p]
    for b in range(row.shape[0]):
        row[b] = 0
    for i in range(begin, end):
        key = keys[i]
        if key >= 0:
            row[key] += 1


@njit(cache=True)
def _column_sums(hist, lo, hi):  # pragma: no cover - compiled
    total = 0
    for b in range(lo, hi):
        for p in range(hist.shape[0]):
            total += hist[p, b]
    return total


@njit(cache=True)
def _column_offsets(hist, start, lo, hi, running):  # pragma: no cover - compiled
    """Buckets ``lo .. hi − 1``: ``start[b]`` their first position, ``hist[p, b]`` chunk
    ``p``'s, counting from ``running``; return the count after them."""
    for b in range(lo, hi):
        start[b] = running
        for p in range(hist.shape[0]):
            count = hist[p, b]
            hist[p, b] = running
            running += count
    return running


@njit(cache=True, parallel=True)
def _prefix_columns(hist, start):  # pragma: no cover - compiled
    """The exclusive prefix sum of ``hist`` by bucket, then chunk, into ``hist`` and
    ``start`` (``start[K]``: the total), the buckets split over ``hist.shape[0]`` threads."""
    parts, buckets = hist.shape[0], hist.shape[1]
    totals = np.empty(parts, dtype=np.int64)
    for q in prange(parts):
        totals[q] = _column_sums(hist, q * buckets // parts, (q + 1) * buckets // parts)
    offsets = np.zeros(parts + 1, dtype=np.int64)
    for q in range(parts):
        offsets[q + 1] = offsets[q] + totals[q]
    for q in prange(parts):
        lo, hi = q * buckets // parts, (q + 1) * buckets // parts
        _column_offsets(hist, start, lo, hi, offsets[q])
    start[buckets] = offsets[parts]


@njit(cache=True)
def _scatter(keys, hist, p, order, begin, end):  # pragma: no cover - compiled
    """Chunk ``p`` places its items ``begin .. end − 1`` at its cursors ``hist[p]``."""
    row = hist[p]
    for i in range(begin, end):
        key = keys[i]
        if key >= 0:
            order[row[key]] = i
            row[key] += 1


@njit(cache=True)
def _gather_chunk(points, order, x, y, z, begin, end):  # pragma: no cover - compiled
    """Coordinates of sorted positions ``begin .. end − 1`` from their rows."""
    for s in range(begin, end):
        i = order[s]
        x[s], y[s], z[s] = points[i, 0], points[i, 1], points[i, 2]


# The rebuild runs on one thread: it is bound by the latency of its scattered reads and writes.
# A two-core version (the keys and the gather in parallel, a chunk of the points and its own
# histogram per core, the prefix sum split by buckets) measured no faster on 2 cores of a
# Zen 5 EPYC in November 2026: 0.98 against 0.90 ms at 10⁵ points, 4.6 against 3.9 ms at
# 3·10⁵, 20.3 against 18.9 ms at 10⁶ (rows in random order), so it was not kept.


@njit(cache=True)
def _rebuild(points, alive, inv_cell, block_mask, keys, start, order, x, y, z, hist):
    """Bin the points; return the number of live ones, or ``−1 − row`` for the first row out
    of range (``hist``: scratch of shape ``(1, T)``)."""
    n = points.shape[0]  # pragma: no cover - compiled
    bad = _keys_chunk(points, alive, inv_cell, block_mask, keys, 0, n)
    if bad >= 0:
        return -1 - bad
    _histogram(keys, hist, 0, 0, n)
    count = _column_offsets(hist, start, 0, hist.shape[1], 0)
    start[hist.shape[1]] = count
    _scatter(keys, hist, 0, order, 0, n)
    _gather_chunk(points, order, x, y, z, 0, count)
    return count
