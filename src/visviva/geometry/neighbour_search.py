"""Queries of the neighbour grid: every pair within a radius once, and every point's list.

Both start from one search of *half* of each neighbourhood: the point at sorted position
``s`` meets only the points at sorted positions ``t > s`` in its 27 cells' runs
(:func:`~visviva.geometry.neighbour_cells.neighbour_runs`), so each pair is tested once (a
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

The counting sorts give each core a chunk of the pairs and a histogram of its own (see
:mod:`~visviva.geometry.neighbour_cells`): their result is the serial stable sort's, whatever
the number of threads.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .neighbour_cells import _column_offsets, _histogram, _prefix_columns, cell_of, neighbour_runs

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
# Lexicographic order, then lists: stable counting sorts over rows (see neighbour_cells), one
# chunk of the pairs per core, each with its own row of ``hist`` (parts × N).
# ---------------------------------------------------------------------------------------------


@njit(cache=True)
def _scatter_pairs(a, b, hist, p, first, second, begin, end):  # pragma: no cover - compiled
    row = hist[p]
    for q in range(begin, end):
        i = a[q]
        first[row[i]], second[row[i]] = i, b[q]
        row[i] += 1


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
def _order_pairs_serial(a, b, row, first, second, hist):  # pragma: no cover - compiled
    rows = row.shape[0] - 1
    _histogram(a, hist, 0, 0, a.shape[0])
    row[rows] = _column_offsets(hist, row, 0, rows, 0)
    _scatter_pairs(a, b, hist, 0, first, second, 0, a.shape[0])
    _sort_rows(row, second, 0, rows)


@njit(cache=True, parallel=True)
def _order_pairs_parallel(a, b, row, first, second, hist):  # pragma: no cover - compiled
    rows, total, parts = row.shape[0] - 1, a.shape[0], hist.shape[0]
    for p in prange(parts):
        _histogram(a, hist, p, p * total // parts, (p + 1) * total // parts)
    _prefix_columns(hist, row)
    for p in prange(parts):
        begin, end = p * total // parts, (p + 1) * total // parts
        _scatter_pairs(a, b, hist, p, first, second, begin, end)
    tasks = 8 * parts
    for k in prange(tasks):
        _sort_rows(row, second, k * rows // tasks, (k + 1) * rows // tasks)


def order_pairs(a, b, row, first, second, hist, parallel: bool) -> None:
    """Pairs ``(a, b)`` into lexicographic order in ``(first, second)``; ``row`` (``N + 1``)
    gets where each row's pairs begin; ``hist``: scratch of one row of ``N`` per chunk."""
    (_order_pairs_parallel if parallel else _order_pairs_serial)(a, b, row, first, second, hist)


@njit(cache=True)
def _list_histogram(first, second, hist, p, begin, end):  # pragma: no cover - compiled
    row = hist[p]
    for r in range(row.shape[0]):
        row[r] = 0
    for q in range(begin, end):
        row[first[q]] += 1
        row[second[q]] += 1


@njit(cache=True)
def _list_scatter(first, second, hist, p, index, begin, end):  # pragma: no cover - compiled
    """Both ends of pairs ``begin .. end − 1`` into the lists, in order: (i gets j), then
    (j gets i)."""
    row = hist[p]
    for q in range(begin, end):
        i, j = first[q], second[q]
        index[row[i]] = j
        row[i] += 1
        index[row[j]] = i
        row[j] += 1


@njit(cache=True)
def _list_pairs_serial(first, second, start, index, hist):  # pragma: no cover - compiled
    rows = start.shape[0] - 1
    _list_histogram(first, second, hist, 0, 0, first.shape[0])
    start[rows] = _column_offsets(hist, start, 0, rows, 0)
    _list_scatter(first, second, hist, 0, index, 0, first.shape[0])


@njit(cache=True, parallel=True)
def _list_pairs_parallel(first, second, start, index, hist):  # pragma: no cover - compiled
    total, parts = first.shape[0], hist.shape[0]
    for p in prange(parts):
        _list_histogram(first, second, hist, p, p * total // parts, (p + 1) * total // parts)
    _prefix_columns(hist, start)
    for p in prange(parts):
        begin, end = p * total // parts, (p + 1) * total // parts
        _list_scatter(first, second, hist, p, index, begin, end)


def list_pairs(first, second, start, index, hist, parallel: bool) -> None:
    """CSR lists from lexicographically ordered pairs: ``start`` (``N + 1``), ``index``
    (``2P``), each list ascending; ``hist``: scratch of one row of ``N`` per chunk."""
    (_list_pairs_parallel if parallel else _list_pairs_serial)(first, second, start, index, hist)
