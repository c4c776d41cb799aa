"""Neighbour search: a hashed uniform grid, rebuilt every step, for every pairwise interaction.

Flocking, crowds, particle–particle contacts and any short-range force need, for each point,
the points within an interaction radius ``r``. :class:`NeighbourGrid` answers that in O(N)
per step for clouds of bounded density; :func:`neighbours` is the one-call form.

**Cells.** Space is cut into cubic cells of edge ``h = r · CELL_MARGIN`` (just over ``r``);
point ``x`` lies in cell ``c = floor(x / h)`` (three integers), so every point within ``r`` of
it lies in one of the 27 cells ``c + {−1, 0, 1}³``.

**The spatial hash.** Cells are never stored densely (the cloud may be 10⁶ m from the origin
or spread over kilometres): they are hashed into a table of buckets, as in Teschner,
Heidelberger, Müller, Pomeranets & Gross, "Optimized spatial hashing for collision detection
of deformable objects" (VMV 2003). Here cells are grouped in blocks of 3 × 3 × 3; a block's
three integers are multiplied by three large odd constants, summed modulo 2⁶⁴ and scrambled
by SplitMix64's finalizer (Steele, Lea & Flood, OOPSLA 2014; the mixer of
:mod:`~visviva.particles.random`), which picks one of ``B`` groups of 27 buckets (``B`` a
power of two, the least with ``T = 27 B ≥ 2N``: a function of ``N`` alone); the cell's place
in its block picks the bucket in the group. Two consequences: the 27 cells around any cell
fall in 27 *different* buckets (two of them differ by at most 2 along every axis, so their
places in their blocks differ), so a search never meets a point twice and needs no check of
which cell a point came from; and the cells of a block lie side by side in memory, so the 27
cells around a point are a few long runs. A bucket may also hold points of a far block with
the same hash: the distance test discards them.

**The rebuild** (:meth:`NeighbourGrid.update`) is a counting sort of the points by bucket
(Cormen, Leiserson, Rivest & Stein, *Introduction to Algorithms*, §8.2): each live point's
bucket, a histogram, a prefix sum giving each bucket's first position, and a stable scatter
(from the last point to the first, each bucket's end counting down); then the coordinates are
gathered in sorted order, so a bucket's points are one contiguous run of structure-of-arrays
memory. On two cores the buckets are split into one range per core: each core counts, sums
and scatters the points of its range (reading every key, writing only its own), with no
atomic operation and no per-core histogram.

**Queries.** A point's neighbours are the points of its 27 cells' buckets within ``r``:
``(xi − xj)² + (yi − yj)² + (zi − zj)² ≤ r²``, evaluated in float64 exactly so (this *is* the
definition: a brute-force search written the same way gives the same sets).
:meth:`NeighbourGrid.neighbours` gives every point's list in CSR form, each list ascending and
without the point itself; :meth:`NeighbourGrid.pairs` every pair ``i < j`` once, in
lexicographic order. Both count, take a prefix sum, then fill; neither branches on the
distance test (its outcome is added), which the processor cannot predict.

**Kernels** that need neighbours every step (forces of boids and crowds, contacts) loop over
the 27 cells themselves, without lists, on :attr:`NeighbourGrid.arrays` (a :class:`GridArrays`
tuple Numba accepts) with :func:`cell_of` and :func:`neighbour_runs` (or :func:`cell_range`
for one cell)::

    @njit(parallel=True)
    def separation(g, radius, force):            # g = grid.arrays, after grid.update(x)
        r2 = radius * radius
        n = g.order.shape[0]                      # live points, in bucket order
        for task in prange((n + 255) // 256):
            runs = np.empty((27, 2), dtype=np.int64)          # scratch, once per task
            for s in range(256 * task, min(n, 256 * task + 256)):
                cx, cy, cz = cell_of(g.x[s], g.y[s], g.z[s], g.inv_cell)
                for k in range(neighbour_runs(g, cx, cy, cz, runs)):
                    for t in range(runs[k, 0], runs[k, 1]):
                        ex, ey, ez = g.x[s] - g.x[t], g.y[s] - g.y[t], g.z[s] - g.z[t]
                        if t != s and ex * ex + ey * ey + ez * ez <= r2:
                            ...  # point g.order[t] is a neighbour of point g.order[s]
                force[g.order[s]] = ...

Visiting points in sorted order keeps a cell's neighbourhood in cache for all of its points
(the search of :meth:`~NeighbourGrid.neighbours` also reuses the runs while the cell stays the
same). ``tests/test_neighbours.py`` runs this pattern against brute force.

**Cost.** Rebuild O(N + T) = O(N); queries O(N · k) for k points in the 27 cells (about 27/4.19
≈ 6.4 times the neighbours within ``r`` in a uniform cloud). Memory: 48 bytes per point
(bucket, order, sorted x, y, z) plus 16–32 bytes of table, plus, for a query's results,
8 bytes per point and 8 per list entry (16 per pair).

**Determinism.** The sort is stable (points of one bucket in ascending index), so its result
is unique: the same positions give the same arrays whatever the number of threads, and the
query results are sets written in ascending order.

**Range.** Cell integers are exact while ``|x| / h < 2⁴⁰`` (about 1.1·10¹² cells: a 1 mm radius
reaches 10⁹ m); beyond, :meth:`NeighbourGrid.update` refuses the point, naming it. The radius
and coordinates must lie within 10⁻¹⁵⁰–10¹⁵⁰ m so that squared distances neither overflow nor
underflow. Within these, the margin of ``h`` over ``r`` (2⁻¹⁰) exceeds every rounding of
``x / h`` (2⁻¹² of a cell per point) and of the distance, so no neighbour is ever missed.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba
import numpy as np
from numba import njit, prange

from .._validation import describe, real_number
from ..errors import ModelError
from .random import _mix

__all__ = [
    "CELL_MARGIN",
    "GridArrays",
    "NeighbourGrid",
    "cell_of",
    "cell_range",
    "neighbour_runs",
    "neighbours",
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

#: Fewest points for which a rebuild or query uses every core (measured in
#: benchmarks/bench_neighbours.py: starting a parallel region costs 10–90 µs).
PARALLEL_MIN_POINTS = 8192

#: Sorted points per parallel task of a query.
CHUNK = 256

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


# ---------------------------------------------------------------------------------------------
# Queries: count, prefix sum, fill
# ---------------------------------------------------------------------------------------------


@njit(cache=True)
def _count_chunk(g, r2, upper, start, runs, begin, end):  # pragma: no cover - compiled
    """Store in ``start[i + 1]`` how many neighbours (``j > i`` only, if ``upper``) each point
    at sorted positions ``begin .. end − 1`` has. Branch-free: the test's outcome is added.
    The runs of the 27 cells are recomputed only when the cell changes from one point to the
    next (a cell's points are neighbours in sorted order)."""
    m = 0
    px = py = pz = np.int64(0)
    for s in range(begin, end):
        xi, yi, zi = g.x[s], g.y[s], g.z[s]
        cx, cy, cz = cell_of(xi, yi, zi, g.inv_cell)
        if s == begin or cx != px or cy != py or cz != pz:
            m = neighbour_runs(g, cx, cy, cz, runs)
            px, py, pz = cx, cy, cz
        i = g.order[s]
        found = 0
        for k in range(m):
            if upper:
                for t in range(runs[k, 0], runs[k, 1]):
                    ex, ey, ez = xi - g.x[t], yi - g.y[t], zi - g.z[t]
                    found += (ex * ex + ey * ey + ez * ez <= r2) & (g.order[t] > i)
            else:
                for t in range(runs[k, 0], runs[k, 1]):
                    ex, ey, ez = xi - g.x[t], yi - g.y[t], zi - g.z[t]
                    found += ex * ex + ey * ey + ez * ez <= r2
        # Without ``upper`` the point itself was counted (its distance is 0).
        start[i + 1] = found if upper else found - 1


@njit(cache=True)
def _fill_chunk(g, r2, upper, start, index, first, runs, begin, end):  # pragma: no cover
    """Write the lists counted by :func:`_count_chunk` from ``start[i]`` on, ascending (and
    ``i`` at the same places of ``first`` unless it is empty). Candidates go to a scratch
    list unconditionally, the test's outcome advancing its end (no branch to mispredict);
    the list is then sorted and copied."""
    scratch = np.empty(64, dtype=np.int64)
    m = 0
    px = py = pz = np.int64(0)
    for s in range(begin, end):
        xi, yi, zi = g.x[s], g.y[s], g.z[s]
        cx, cy, cz = cell_of(xi, yi, zi, g.inv_cell)
        if s == begin or cx != px or cy != py or cz != pz:
            m = neighbour_runs(g, cx, cy, cz, runs)
            px, py, pz = cx, cy, cz
            candidates = 0
            for k in range(m):
                candidates += runs[k, 1] - runs[k, 0]
            if scratch.shape[0] <= candidates:
                scratch = np.empty(2 * candidates, dtype=np.int64)
        i = g.order[s]
        found = 0
        for k in range(m):
            for t in range(runs[k, 0], runs[k, 1]):
                ex, ey, ez = xi - g.x[t], yi - g.y[t], zi - g.z[t]
                j = g.order[t]
                scratch[found] = j
                if upper:
                    found += (ex * ex + ey * ey + ez * ez <= r2) & (j > i)
                else:
                    found += (ex * ex + ey * ey + ez * ez <= r2) & (t != s)
        # Insertion sort: a list is short (tens), and ascends already within each run.
        for a in range(1, found):
            value = scratch[a]
            b = a - 1
            while b >= 0 and scratch[b] > value:
                scratch[b + 1] = scratch[b]
                b -= 1
            scratch[b + 1] = value
        base = start[i]
        for a in range(found):
            index[base + a] = scratch[a]
        if first.shape[0]:
            for a in range(found):
                first[base + a] = i


@njit(cache=True)
def _search_serial(g, r2, upper, start, index, first):  # pragma: no cover - compiled
    runs = np.empty((27, 2), dtype=np.int64)
    n = g.order.shape[0]
    if index.shape[0]:
        _fill_chunk(g, r2, upper, start, index, first, runs, 0, n)
    else:
        _count_chunk(g, r2, upper, start, runs, 0, n)


@njit(cache=True, parallel=True)
def _search_parallel(g, r2, upper, start, index, first):  # pragma: no cover - compiled
    n = g.order.shape[0]
    fill = index.shape[0] > 0
    for k in prange((n + CHUNK - 1) // CHUNK):
        runs = np.empty((27, 2), dtype=np.int64)
        b, e = k * CHUNK, min(n, (k + 1) * CHUNK)
        if fill:
            _fill_chunk(g, r2, upper, start, index, first, runs, b, e)
        else:
            _count_chunk(g, r2, upper, start, runs, b, e)


@njit(cache=True)
def _prefix(start, keys):  # pragma: no cover - compiled
    """Zero the counts of dead rows (key −1), then turn the counts in ``start[1:]`` into
    offsets: ``start[i]`` is where row ``i``'s list begins."""
    start[0] = 0
    for i in range(keys.shape[0]):
        if keys[i] < 0:
            start[i + 1] = 0
        start[i + 1] += start[i]


# ---------------------------------------------------------------------------------------------
# The Python side: validation, buffers, drivers
# ---------------------------------------------------------------------------------------------

_NO_MASK = np.zeros(0, dtype=np.bool_)
_NO_ROWS = np.zeros(0, dtype=np.int64)
#: Rows per parallel task of a rebuild's key and gather passes.
_REBUILD_TASKS = 16


def _check_radius(name: str, value: Any) -> float:
    radius = real_number(name, value, positive=True, unit=" m")
    if not MIN_RADIUS <= radius <= MAX_COORDINATE:
        raise ModelError(
            f"`{name}` must lie between {MIN_RADIUS:g} and {MAX_COORDINATE:g} m, so that "
            f"squared distances stay normal floats (got {radius!r})"
        )
    return radius


def _check_positions(value: Any) -> np.ndarray:
    try:
        points = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ModelError(
            f"`positions` must be an (N, 3) array of points [m] (got {describe(value)})"
        ) from exc
    if points.dtype.kind not in "iuf":
        raise ModelError(
            f"`positions` must be an (N, 3) array of real numbers [m] (got dtype {points.dtype})"
        )
    if points.ndim != 2 or points.shape[1] != 3:
        raise ModelError(f"`positions` must have shape (N, 3) (got shape {points.shape})")
    return np.ascontiguousarray(points, dtype=np.float64)


def _check_alive(value: Any, rows: int) -> np.ndarray:
    if value is None:
        return _NO_MASK
    alive = np.asarray(value)
    if alive.dtype != np.bool_:
        raise ModelError(
            f"`alive` must be a boolean mask, one flag per point (got dtype {alive.dtype})"
        )
    if alive.shape != (rows,):
        raise ModelError(
            f"`alive` must have shape ({rows},), one flag per row of `positions` "
            f"(got shape {alive.shape})"
        )
    return np.ascontiguousarray(alive)


def _blocks(rows: int) -> int:
    """Blocks of 27 buckets for ``rows`` points: the least power of two with
    ``27 · blocks ≥ 2 · rows``."""
    return 1 << max(0, (2 * rows + 26) // 27 - 1).bit_length()


def _grown(buffer: np.ndarray, size: int) -> np.ndarray:
    """``buffer`` if it holds ``size`` entries, else a new one half as large again."""
    if buffer.shape[0] >= size:
        return buffer
    return np.empty(max(size, buffer.shape[0] * 3 // 2), dtype=buffer.dtype)


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.setflags(write=False)
    return view


class NeighbourGrid:
    """A hashed uniform grid over points, rebuilt by :meth:`update` each step.

    Args:
        radius: The interaction radius ``r`` [m]: the largest radius a query may ask for.
            Cells are ``r · CELL_MARGIN`` wide.

    Buffers are kept between updates and grow (by half) only when a larger cloud or result
    arrives, so a steady simulation allocates nothing per step. Query results are read-only
    views of those buffers, valid until the next query of the same kind or the next update:
    copy what you keep.

    >>> import numpy as np
    >>> grid = NeighbourGrid(1.0)
    >>> grid.update(np.array([[0.0, 0, 0], [0.5, 0, 0], [3.0, 0, 0], [0.0, 1.0, 0]]))
    >>> start, index = grid.neighbours()
    >>> [index[start[i] : start[i + 1]].tolist() for i in range(4)]
    [[1, 3], [0], [], [0]]
    >>> first, second = grid.pairs(radius=0.6)
    >>> first.tolist(), second.tolist()
    ([0], [1])
    """

    def __init__(self, radius: float) -> None:
        self.radius = _check_radius("radius", radius)
        #: Cell edge ``h`` [m].
        self.cell_size = self.radius * CELL_MARGIN
        self._inv_cell = 1.0 / self.cell_size
        self._rows = 0
        self._count = 0
        self._keys = _NO_ROWS
        self._order = _NO_ROWS
        self._x = self._y = self._z = np.zeros(0)
        self._table = np.zeros(28, dtype=np.int64)
        self._block_mask = 0
        self._bad = np.empty(_REBUILD_TASKS, dtype=np.int64)
        self._start = np.zeros(1, dtype=np.int64)
        self._index = _NO_ROWS
        self._pair_start = np.zeros(1, dtype=np.int64)
        self._first = self._second = _NO_ROWS
        self.arrays = self._arrays()

    @property
    def count(self) -> int:
        """Live points binned by the last update."""
        return self._count

    def _arrays(self) -> GridArrays:
        n, table = self._count, 27 * (self._block_mask + 1)
        return GridArrays(
            self._table[: table + 1],
            self._order[:n],
            self._x[:n],
            self._y[:n],
            self._z[:n],
            self._inv_cell,
            self._block_mask,
        )

    def update(self, positions: Any, alive: Any = None) -> None:
        """Bin the points: ``positions`` ``(N, 3)`` [m]; ``alive`` an optional ``(N,)`` bool
        mask (dead points are ignored: they have no neighbours and are nobody's)."""
        points = _check_positions(positions)
        rows = points.shape[0]
        mask = _check_alive(alive, rows)
        for name in ("_keys", "_order", "_x", "_y", "_z"):
            setattr(self, name, _grown(getattr(self, name), rows))
        blocks = _blocks(rows)
        self._table = _grown(self._table, 27 * blocks + 1)
        self._block_mask = blocks - 1
        parallel = rows >= PARALLEL_MIN_POINTS
        rebuild = _rebuild_parallel if parallel else _rebuild_serial
        bad = self._bad if parallel else self._bad[:1]
        keys = self._keys[:rows]
        count = rebuild(
            points, mask, self._inv_cell, self._block_mask, keys, self._table, self._order,
            self._x, self._y, self._z, bad, numba.get_num_threads(),
        )  # fmt: skip
        failed = bad[bad >= 0]
        if failed.size:
            self._count, self._rows = 0, 0
            self.arrays = self._arrays()
            self._refuse(points, int(failed[0]))
        self._rows, self._count = rows, int(count)
        self.arrays = self._arrays()

    def _refuse(self, points: np.ndarray, row: int) -> None:
        point = points[row]
        if not np.isfinite(point).all():
            raise ModelError(f"`positions` must be finite; point {row} is {describe(point)}")
        reach = min(MAX_CELLS * self.cell_size, MAX_COORDINATE)
        raise ModelError(
            f"`positions`: point {row} at {describe(point)} m lies beyond the grid's reach of "
            f"{reach:.3g} m from the origin (2^40 cells of {self.cell_size:.3g} m, at most "
            f"{MAX_COORDINATE:g} m): move the cloud nearer the origin or use a larger radius"
        )

    def _radius2(self, radius: Any) -> float:
        if radius is None:
            return self.radius * self.radius
        value = _check_radius("radius", radius)
        if value > self.radius:
            raise ModelError(
                f"`radius` of a query must not exceed the grid's radius {self.radius!r} m "
                f"(got {value!r}): build a NeighbourGrid with the larger radius"
            )
        return value * value

    def _search(self, radius: Any, upper: bool, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Count, prefix sum, fill: ``(index, first)`` of the lists whose offsets go into
        ``start`` (``first`` only for pairs)."""
        r2 = self._radius2(radius)
        search = _search_parallel if self._count >= PARALLEL_MIN_POINTS else _search_serial
        grid = self.arrays
        search(grid, r2, upper, start, _NO_ROWS, _NO_ROWS)
        _prefix(start, self._keys[: self._rows])
        total = int(start[self._rows])
        if upper:
            self._first = _grown(self._first, total)
            self._second = _grown(self._second, total)
            index, first = self._second[:total], self._first[:total]
        else:
            self._index = _grown(self._index, total)
            index, first = self._index[:total], _NO_ROWS
        if total:
            search(grid, r2, upper, start, index, first)
        return _read_only(index), _read_only(first)

    def neighbours(self, radius: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Every point's neighbours within ``radius`` [m] (default: the grid's), as CSR lists.

        Returns:
            ``(start, index)``: the neighbours of point ``i`` are ``index[start[i] :
            start[i + 1]]``, ascending, without ``i``; ``start`` has shape ``(N + 1,)``.
            Read-only views, valid until the next :meth:`neighbours` or :meth:`update`.
        """
        self._start = _grown(self._start, self._rows + 1)
        start = self._start[: self._rows + 1]
        index, _ = self._search(radius, False, start)
        return _read_only(start), index

    def pairs(self, radius: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Every pair of points within ``radius`` [m] (default: the grid's), once.

        Returns:
            ``(first, second)``, shape ``(P,)`` each, with ``first < second``, in
            lexicographic order. Read-only views, valid until the next :meth:`pairs` or
            :meth:`update`.
        """
        self._pair_start = _grown(self._pair_start, self._rows + 1)
        second, first = self._search(radius, True, self._pair_start[: self._rows + 1])
        return first, second


def neighbours(positions: Any, radius: float, alive: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """The neighbours within ``radius`` [m] of every point of ``positions`` ``(N, 3)`` [m].

    Args:
        positions: Point coordinates [m], shape ``(N, 3)``.
        radius: Neighbourhood radius [m]: ``j`` is a neighbour of ``i`` when
            ``|x_i − x_j|² ≤ radius²`` (in float64, as written in the module docstring).
        alive: Optional ``(N,)`` bool mask; dead points have no neighbours and are nobody's.

    Returns:
        ``(start, index)`` in CSR form: the neighbours of point ``i`` are ``index[start[i] :
        start[i + 1]]``, ascending, without ``i`` itself.

    >>> import numpy as np
    >>> import visviva as vv
    >>> start, index = vv.particles.neighbours(np.array([[0.0, 0, 0], [0.1, 0, 0]]), 0.2)
    >>> start.tolist(), index.tolist()
    ([0, 1, 2], [1, 0])
    """
    grid = NeighbourGrid(radius)
    grid.update(positions, alive)
    start, index = grid.neighbours()
    return start.copy(), index.copy()
