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
(each bucket's cursor counting up); then the coordinates are gathered in sorted order, so a
bucket's points are one contiguous run of structure-of-arrays memory. It runs on one core:
it is bound by the latency of its scattered reads and writes, and split over two (a chunk of
the points and a histogram per core) it measured no faster, up to 10⁶ points. The queries,
which compute, use both cores from ``PARALLEL_MIN_POINTS`` points on (1.7 times faster).

**Queries.** A point's neighbours are the points of its 27 cells' buckets within ``r``:
``(xi − xj)² + (yi − yj)² + (zi − zj)² ≤ r²``, evaluated in float64 exactly so (this *is* the
definition: a brute-force search written the same way gives the same sets).
:meth:`NeighbourGrid.pairs` gives every pair ``i < j`` once, in lexicographic order;
:meth:`NeighbourGrid.neighbours` every point's list in CSR form, ascending, without the point
itself. Both come from one search that tests each pair once, from its end earlier in sorted
order, then counting sorts (:mod:`~visviva.geometry.neighbour_search`).

**Kernels** that need neighbours every step (forces of boids and crowds, contacts) loop over
the 27 cells themselves, without lists, on :attr:`NeighbourGrid.arrays` (a :class:`GridArrays`
tuple Numba accepts) with :func:`~visviva.geometry.neighbour_cells.cell_of` and
:func:`~visviva.geometry.neighbour_cells.neighbour_runs` (or
:func:`~visviva.geometry.neighbour_cells.cell_range` for one cell), imported from
:mod:`visviva.geometry.neighbour_cells`::

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
(the queries also reuse the runs while the cell stays the same). ``tests/test_neighbours.py``
runs this pattern against brute force.

**Cost.** Rebuild O(N + T) = O(N); queries O(N · k) for k points in the 27 cells (about 27/4.19
≈ 6.4 times the neighbours within ``r`` in a uniform cloud; half of them are tested). Memory:
40 bytes per point (bucket, order, sorted x, y, z) plus 32–64 for the table and its counting
sort's histogram; the queries add 16 bytes per point and 32 per pair (found, then sorted),
and the lists 8 more per point and 16 per pair.

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

from typing import Any

import numba
import numpy as np

from .._validation import describe, real_number
from ..errors import ModelError
from .neighbour_cells import (
    CELL_MARGIN,
    MAX_CELLS,
    MAX_COORDINATE,
    MIN_RADIUS,
    GridArrays,
    _rebuild,
)
from .neighbour_search import count_pairs, find_pairs, list_pairs, order_pairs, pair_offsets

__all__ = ["PARALLEL_MIN_POINTS", "NeighbourGrid", "neighbours"]

#: Fewest live points for which a query uses every core (the rebuild always runs on one: see
#: neighbour_cells). Measured (benchmarks/bench_neighbours.py, part (c)): at 500 points two
#: threads count pairs in 22 µs against 36 µs on one; at 250 they tie (a parallel region
#: costs 10–90 µs to start).
PARALLEL_MIN_POINTS = 512

_NO_MASK = np.zeros(0, dtype=np.bool_)
_NO_ROWS = np.zeros(0, dtype=np.int64)


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
    arrives, so a steady simulation allocates nothing of the cloud's size per step (the
    compiled queries take a few small scratch arrays per task). Query results are read-only
    views of those buffers, valid until the next update or a query with another radius: copy
    what you keep. The pairs found by one query serve the next with the same radius.

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
        self._hist = _NO_ROWS
        # Queries: pairs as found (a, b) and sorted (first, second), offsets per sorted
        # position and per row, lists; ``_found`` says for which update and radius the pairs
        # are ready.
        self._offsets = self._row = self._start = np.zeros(1, dtype=np.int64)
        self._a = self._b = self._first = self._second = self._index = _NO_ROWS
        self._pair_count = 0
        self._generation = 0
        self._found: tuple[int, float] | None = None
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
        count = _rebuild(
            points, mask, self._inv_cell, self._block_mask, self._keys[:rows], self._table,
            self._order, self._x, self._y, self._z, self._histogram(27 * blocks, False),
        )  # fmt: skip
        if count < 0:
            self._count, self._rows = 0, 0
            self._generation += 1
            self.arrays = self._arrays()
            self._refuse(points, -1 - count)
        self._rows, self._count = rows, count
        self._generation += 1
        self.arrays = self._arrays()

    def _histogram(self, buckets: int, parallel: bool) -> np.ndarray:
        """Scratch counts for a counting sort: one row of ``buckets`` per thread (1: serial)."""
        parts = numba.get_num_threads() if parallel else 1
        self._hist = _grown(self._hist, parts * buckets)
        return self._hist[: parts * buckets].reshape(parts, buckets)

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

    def _pairs(self, radius: Any) -> int:
        """Find and sort the pairs within ``radius`` (unless done since the last update)."""
        r2 = self._radius2(radius)
        if self._found == (self._generation, r2):
            return self._pair_count
        grid, n, rows = self.arrays, self._count, self._rows
        parallel = n >= PARALLEL_MIN_POINTS
        self._offsets = _grown(self._offsets, n + 1)
        offsets = self._offsets[: n + 1]
        count_pairs(grid, r2, offsets, parallel)
        total = int(pair_offsets(offsets))
        for name in ("_a", "_b", "_first", "_second"):
            setattr(self, name, _grown(getattr(self, name), total))
        a, b = self._a[:total], self._b[:total]
        if total:
            find_pairs(grid, r2, offsets, a, b, parallel)
        self._row = _grown(self._row, rows + 1)
        first, second = self._first[:total], self._second[:total]
        hist = self._histogram(rows, parallel)
        order_pairs(a, b, self._row[: rows + 1], first, second, hist, parallel)
        self._found, self._pair_count = (self._generation, r2), total
        return total

    def pairs(self, radius: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Every pair of points within ``radius`` [m] (default: the grid's), once.

        Returns:
            ``(first, second)``, shape ``(P,)`` each, with ``first < second``, in
            lexicographic order. Read-only views, valid until the next :meth:`update` or a
            query with another radius.
        """
        total = self._pairs(radius)
        return _read_only(self._first[:total]), _read_only(self._second[:total])

    def neighbours(self, radius: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Every point's neighbours within ``radius`` [m] (default: the grid's), as CSR lists.

        Returns:
            ``(start, index)``: the neighbours of point ``i`` are ``index[start[i] :
            start[i + 1]]``, ascending, without ``i``; ``start`` has shape ``(N + 1,)``.
            Read-only views, valid until the next :meth:`update` or a query with another
            radius.
        """
        total = self._pairs(radius)
        rows = self._rows
        parallel = self._count >= PARALLEL_MIN_POINTS
        self._start = _grown(self._start, rows + 1)
        self._index = _grown(self._index, 2 * total)
        start, index = self._start[: rows + 1], self._index[: 2 * total]
        first, second = self._first[:total], self._second[:total]
        list_pairs(first, second, start, index, self._histogram(rows, parallel), parallel)
        return _read_only(start), _read_only(index)


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
