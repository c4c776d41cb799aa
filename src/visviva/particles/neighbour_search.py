"""Queries of the neighbour grid: every pair within a radius once, and every point's list.

Both start from one search of *half* of each neighbourhood: the point at sorted position
``s`` meets only the points at sorted positions ``t > s`` in its 27 cells' runs
(:func:`~visviva.particles.neighbour_cells.neighbour_runs`), so each pair is tested once (a
full search would test it from both ends). The search counts first, then, after a prefix sum
over the sorted positions, writes each pair as ``(min, max)`` of the two rows. Neither pass
branches on the distance test: its outcome is added to a count (a branch on it, taken about
one time in seven in random order, is what the processor mispredicts).

The pairs are then put in lexicographic order by a stable counting sort on the first row and
a short insertion sort of each row's partners (tens at most at a boids-like density). A
point's list is a stable scatter of those sorted pairs both ways: row ``r`` receives its
partners ``a < r`` from the pairs ``(a, r)``, which come first in that order and ascend, then
its partners ``b > r`` from its own pairs, ascending, so every list comes out sorted with no
further sort.

The counting sorts split the rows into one range per core: each core reads every pair and
writes only the rows of its range, so results do not depend on the number of threads.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .neighbour_cells import _count_part, cell_of, neighbour_runs

__all__ = ["CHUNK", "count_pairs", "find_pairs", "list_pairs", "order_pairs", "pair_offsets"]

#: Sorted points per parallel task of the search.
CHUNK = 256


@njit(cache=True)
def _count_chunk(g, r2, count, runs, begin, end):  # pragma: no cover - compiled
    """``count[s + 1]``: the pairs found from sorted position ``s`` in ``begin .. end − 1``,
    meeting ``t > s`` only. The 27 cells' runs are recomputed only when the cell changes
    from one point to the next; the test's outcome is added, not branched on."""
    x, y, z = g.x, g.y, g.z  # locals: faster than the tuple's fields in the loops
    m = 0
    px = py = pz = np.int64(0)
    for s in range(begin, end):
        xi, yi, zi = x[s], y[s], z[s]
        cx, cy, cz = cell_of(xi, yi, zi, g.inv_cell)
        if s == begin or cx != px or cy != py or cz != pz:
            m = neighbour_runs(g, cx, cy, cz, runs)
            px, py, pz = cx, cy, cz
        found = 0
        for k in range(m):
            for t in range(max(runs[k, 0], s + 1), runs[k, 1]):
                ex, ey, ez = xi - x[t], yi - y[t], zi - z[t]
                found += ex * ex + ey * ey + ez * ez <= r2
        count[s + 1] = found


@njit(cache=True)
def _fill_chunk(g, r2, count, a, b, runs, begin, end):  # pragma: no cover - compiled
    """Write the pairs counted by :func:`_count_chunk` from ``count[s]`` on: ``a`` the
    smaller row, ``b`` the larger. Every candidate goes to a scratch list, the test's outcome
    advancing its end (no branch); the pairs are then copied."""
    x, y, z, order = g.x, g.y, g.z, g.order
    scratch = np.empty(256, dtype=np.int64)
    m = 0
    px = py = pz = np.int64(0)
    for s in range(begin, end):
        xi, yi, zi = x[s], y[s], z[s]
        cx, cy, cz = cell_of(xi, yi, zi, g.inv_cell)
        if s == begin or cx != px or cy != py or cz != pz:
            m = neighbour_runs(g, cx, cy, cz, runs)
            px, py, pz = cx, cy, cz
            room = 1
            for k in range(m):
                room += runs[k, 1] - runs[k, 0]
            if scratch.shape[0] < room:
                scratch = np.empty(2 * room, dtype=np.int64)
        found = 0
        for k in range(m):
            for t in range(max(runs[k, 0], s + 1), runs[k, 1]):
                ex, ey, ez = xi - x[t], yi - y[t], zi - z[t]
                scratch[found] = t
                found += ex * ex + ey * ey + ez * ez <= r2
        i, base = order[s], count[s]
        for q in range(found):
            j = order[scratch[q]]
            a[base + q], b[base + q] = min(i, j), max(i, j)


@njit(cache=True)
def _half_serial(g, r2, count, a, b):  # pragma: no cover - compiled
    runs = np.empty((27, 2), dtype=np.int64)
    if a.shape[0]:
        _fill_chunk(g, r2, count, a, b, runs, 0, g.order.shape[0])
    else:
        _count_chunk(g, r2, count, runs, 0, g.order.shape[0])


@njit(cache=True, parallel=True)
def _half_parallel(g, r2, count, a, b):  # pragma: no cover - compiled
    n = g.order.shape[0]
    fill = a.shape[0] > 0
    for k in prange((n + CHUNK - 1) // CHUNK):
        runs = np.empty((27, 2), dtype=np.int64)
        begin, end = k * CHUNK, min(n, (k + 1) * CHUNK)
        if fill:
            _fill_chunk(g, r2, count, a, b, runs, begin, end)
        else:
            _count_chunk(g, r2, count, runs, begin, end)


def count_pairs(g, r2: float, count: np.ndarray, parallel: bool) -> None:
    """``count[s + 1]``: pairs found from sorted position ``s`` (``count`` has ``n + 1``)."""
    (_half_parallel if parallel else _half_serial)(g, r2, count, count[:0], count[:0])


@njit(cache=True)
def pair_offsets(count):  # pragma: no cover - compiled
    """Turn the counts in ``count[1:]`` into offsets in place; return the total."""
    count[0] = 0
    for s in range(count.shape[0] - 1):
        count[s + 1] += count[s]
    return count[count.shape[0] - 1]


def find_pairs(g, r2: float, count: np.ndarray, a: np.ndarray, b: np.ndarray, parallel: bool):
    """Write the pairs counted by :func:`count_pairs` (offsets from :func:`pair_offsets`)."""
    (_half_parallel if parallel else _half_serial)(g, r2, count, a, b)


# ---------------------------------------------------------------------------------------------
# Lexicographic order, then lists
# ---------------------------------------------------------------------------------------------


@njit(cache=True)
def _scatter_pairs_part(a, b, row, first, second, lo, hi, offset):  # pragma: no cover
    """Place the pairs whose first row is in ``lo .. hi − 1``, stably (see ``_scatter_part``
    in :mod:`~visviva.particles.neighbour_cells`)."""
    for r in range(lo, hi):
        row[r] += offset
    for p in range(a.shape[0] - 1, -1, -1):
        i = a[p]
        if lo <= i < hi:
            row[i] -= 1
            first[row[i]], second[row[i]] = i, b[p]


@njit(cache=True)
def _sort_rows(row, second, lo, hi):  # pragma: no cover - compiled
    """Insertion-sort the partners of each row ``lo .. hi − 1`` (a few tens at most)."""
    for r in range(lo, hi):
        for q in range(row[r] + 1, row[r + 1]):
            value = second[q]
            p = q - 1
            while p >= row[r] and second[p] > value:
                second[p + 1] = second[p]
                p -= 1
            second[p + 1] = value


@njit(cache=True)
def _order_pairs_serial(a, b, row, first, second, parts):  # pragma: no cover - compiled
    rows = row.shape[0] - 1
    _count_part(a, row, 0, rows)
    _scatter_pairs_part(a, b, row, first, second, 0, rows, 0)
    row[rows] = a.shape[0]
    _sort_rows(row, second, 0, rows)


@njit(cache=True, parallel=True)
def _order_pairs_parallel(a, b, row, first, second, parts):  # pragma: no cover - compiled
    rows = row.shape[0] - 1
    totals = np.empty(parts, dtype=np.int64)
    for p in prange(parts):
        totals[p] = _count_part(a, row, p * rows // parts, (p + 1) * rows // parts)
    offsets = np.zeros(parts, dtype=np.int64)
    for p in range(1, parts):
        offsets[p] = offsets[p - 1] + totals[p - 1]
    for p in prange(parts):
        lo, hi = p * rows // parts, (p + 1) * rows // parts
        _scatter_pairs_part(a, b, row, first, second, lo, hi, offsets[p])
    row[rows] = a.shape[0]
    tasks = 8 * parts
    for k in prange(tasks):
        _sort_rows(row, second, k * rows // tasks, (k + 1) * rows // tasks)


def order_pairs(a, b, row, first, second, parts: int, parallel: bool) -> None:
    """Pairs ``(a, b)`` into lexicographic order in ``(first, second)``; ``row`` (``N + 1``)
    gets where each row's pairs begin. ``parts``: ranges of rows (one per thread)."""
    (_order_pairs_parallel if parallel else _order_pairs_serial)(a, b, row, first, second, parts)


@njit(cache=True)
def _list_count_part(first, second, start, lo, hi):  # pragma: no cover - compiled
    """Inclusive prefix sums of the list lengths of rows ``lo .. hi − 1``; return the total."""
    for r in range(lo, hi):
        start[r] = 0
    for p in range(first.shape[0]):
        i, j = first[p], second[p]
        if lo <= i < hi:
            start[i] += 1
        if lo <= j < hi:
            start[j] += 1
    total = 0
    for r in range(lo, hi):
        total += start[r]
        start[r] = total
    return total


@njit(cache=True)
def _list_scatter_part(first, second, start, index, lo, hi, offset):  # pragma: no cover
    """Place both ends of the pairs into the lists of rows ``lo .. hi − 1``, stably: the
    entries in order are (i gets j), (j gets i) for each pair; taken from the last back."""
    for r in range(lo, hi):
        start[r] += offset
    for p in range(first.shape[0] - 1, -1, -1):
        i, j = first[p], second[p]
        if lo <= j < hi:
            start[j] -= 1
            index[start[j]] = i
        if lo <= i < hi:
            start[i] -= 1
            index[start[i]] = j


@njit(cache=True)
def _list_pairs_serial(first, second, start, index, parts):  # pragma: no cover - compiled
    rows = start.shape[0] - 1
    _list_count_part(first, second, start, 0, rows)
    _list_scatter_part(first, second, start, index, 0, rows, 0)
    start[rows] = 2 * first.shape[0]


@njit(cache=True, parallel=True)
def _list_pairs_parallel(first, second, start, index, parts):  # pragma: no cover - compiled
    rows = start.shape[0] - 1
    totals = np.empty(parts, dtype=np.int64)
    for p in prange(parts):
        lo, hi = p * rows // parts, (p + 1) * rows // parts
        totals[p] = _list_count_part(first, second, start, lo, hi)
    offsets = np.zeros(parts, dtype=np.int64)
    for p in range(1, parts):
        offsets[p] = offsets[p - 1] + totals[p - 1]
    for p in prange(parts):
        lo, hi = p * rows // parts, (p + 1) * rows // parts
        _list_scatter_part(first, second, start, index, lo, hi, offsets[p])
    start[rows] = 2 * first.shape[0]


def list_pairs(first, second, start, index, parts: int, parallel: bool) -> None:
    """CSR lists from lexicographically ordered pairs: ``start`` (``N + 1``), ``index``
    (``2P``), each list ascending. ``parts``: ranges of rows (one per thread)."""
    (_list_pairs_parallel if parallel else _list_pairs_serial)(first, second, start, index, parts)
