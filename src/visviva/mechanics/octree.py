"""The octree of Barnes & Hut (1986): build, and the moments of every cell.

Build: the root cell is the bounding box of all bodies. A cell with more than ``leaf_size``
bodies is split at the centre of the bounding box of *its own* bodies into up to eight
children (an axis shorter than half the longest is not split, so flat sets such as disks get
flat cells); each child again takes the bounding box of its bodies. Bodies are reordered so
that every cell is a contiguous range (a Morton-like order), and cells live in flat arrays in
breadth-first order, children after their parent and contiguous.

Moments: each cell keeps its mass, centre of mass, second moment ``I = Σ m d dᵀ`` (``d`` from
the centre of mass) and the radius ``b`` about the centre of mass of the sphere holding its
massive bodies, combined bottom-up (parallel-axis rule for ``I``; ``b`` from the children's
spheres, or the farthest corner of the cell's box if nearer).

Degenerate input: a cell whose bodies all sit at one point, or are too close to separate in
floating point (within a few units in the last place), becomes a leaf whatever its size, so the
build ends on any input; coincident bodies therefore always share a leaf. Cells shrink to their
own bodies, so a huge coordinate range costs no extra levels beyond those its bodies need.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit, prange

if TYPE_CHECKING:
    from .gravity import PointMasses

__all__ = ["LEAF_SIZE", "Octree", "build_octree", "cell_moments"]

#: Bodies per leaf (at most, unless they cannot be split). An opened leaf's bodies interact
#: directly. Measured with 10⁶ Plummer bodies: 8–16 within 5% of each other.
LEAF_SIZE = 16

#: An axis is split only if it is at least this fraction of the cell's longest axis.
_SPLIT_FRACTION = 0.5

# Moments make no exact-symmetry promise; NaN and infinity stay honoured (see gravity.py).
_FAST = {"contract", "arcp", "nsz", "afn", "reassoc"}


class Octree(NamedTuple):
    """The tree over ``N`` bodies with ``K`` cells; cell 0 is the root.

    Attributes:
        order: Body index at each tree position, shape ``(N,)``.
        x, y, z: Body coordinates in tree order [m], shape ``(N,)`` each.
        start, size: Each cell's range of tree positions, shape ``(K,)`` each.
        first_child: Index of a cell's first child (children are contiguous), −1 for a leaf.
        children: Number of children, shape ``(K,)``.
        lower, upper: Bounding box of each cell's bodies [m], shape ``(K, 3)`` each.
        depth: Largest depth below the root.
    """

    order: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    start: np.ndarray
    size: np.ndarray
    first_child: np.ndarray
    children: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    depth: int


@njit(cache=True)
def _bounds(x, y, z, start, count, lower, upper):  # pragma: no cover - compiled
    """Store the bounding box of bodies ``start .. start+count-1`` into ``lower`` and ``upper``."""
    lx, ly, lz = x[start], y[start], z[start]
    hx, hy, hz = lx, ly, lz
    for p in range(start + 1, start + count):
        lx, hx = min(lx, x[p]), max(hx, x[p])
        ly, hy = min(ly, y[p]), max(hy, y[p])
        lz, hz = min(lz, z[p]), max(hz, z[p])
    lower[0], lower[1], lower[2] = lx, ly, lz
    upper[0], upper[1], upper[2] = hx, hy, hz


@njit(cache=True)
def _partition(columns, scratch, codes, start, count, centre, split, sizes):  # pragma: no cover
    """Reorder the range of every column by octant about ``centre``; fill ``sizes`` (8,)."""
    x, y, z = columns[0], columns[1], columns[2]
    for code in range(16):
        sizes[code] = 0
    for p in range(start, start + count):
        code = 0
        if split[0] and x[p] > centre[0]:
            code |= 1
        if split[1] and y[p] > centre[1]:
            code |= 2
        if split[2] and z[p] > centre[2]:
            code |= 4
        codes[p] = code
        sizes[code] += 1
    # sizes[8:16] serve as the running write positions.
    sizes[8] = start
    for c in range(1, 8):
        sizes[8 + c] = sizes[8 + c - 1] + sizes[c - 1]
    for p in range(start, start + count):
        target = sizes[8 + codes[p]]
        sizes[8 + codes[p]] += 1
        for column in range(columns.shape[0]):
            scratch[column, target] = columns[column, p]
    for column in range(columns.shape[0]):
        for p in range(start, start + count):
            columns[column, p] = scratch[column, p]


@njit(cache=True, parallel=True)
def _build(columns, leaf_size):  # pragma: no cover - compiled
    """Split cells level by level, reordering ``columns`` (x, y, z, index) in place.

    The cells of one level own disjoint ranges of bodies, so they are split in parallel; their
    children are then numbered in order, after every existing cell (breadth first). Returns
    the cell arrays at full capacity, the number of cells used and the depth.
    """
    n = columns.shape[1]
    capacity = 2 * n  # every split makes at least two non-empty children
    scratch = np.empty((columns.shape[0], n))
    codes = np.empty(n, np.int64)
    start = np.empty(capacity, np.int64)
    count = np.empty(capacity, np.int64)
    first_child = np.full(capacity, -1, np.int64)
    children = np.zeros(capacity, np.int64)
    lower = np.empty((capacity, 3))
    upper = np.empty((capacity, 3))
    start[0], count[0] = 0, n
    cells = 1
    depth = 0
    level_start, level_end = 0, 1
    while level_start < level_end:
        width = level_end - level_start
        sizes = np.zeros((width, 16), np.int64)  # per cell: bodies per octant, write positions
        centre = np.empty((width, 3))
        split = np.empty((width, 3), np.bool_)
        divided = np.zeros(width, np.bool_)
        for w in prange(width):
            k = level_start + w
            _bounds(columns[0], columns[1], columns[2], start[k], count[k], lower[k], upper[k])
            longest = 0.0
            for axis in range(3):
                longest = max(longest, upper[k, axis] - lower[k, axis])
            if count[k] > leaf_size and longest > 0.0:
                for axis in range(3):
                    centre[w, axis] = 0.5 * lower[k, axis] + 0.5 * upper[k, axis]  # no overflow
                    split[w, axis] = upper[k, axis] - lower[k, axis] >= _SPLIT_FRACTION * longest
                _partition(
                    columns, scratch, codes, start[k], count[k], centre[w], split[w], sizes[w]
                )
                largest = 0
                for code in range(8):
                    largest = max(largest, sizes[w, code])
                divided[w] = largest < count[k]  # else the bodies are too close to separate
        for w in range(width):
            if divided[w]:
                k = level_start + w
                first_child[k] = cells
                offset = start[k]
                for code in range(8):
                    if sizes[w, code] > 0:
                        start[cells], count[cells] = offset, sizes[w, code]
                        offset += sizes[w, code]
                        cells += 1
                children[k] = cells - first_child[k]
        if cells > level_end:
            depth += 1
        level_start, level_end = level_end, cells
    return start, count, first_child, children, lower, upper, cells, depth


def build_octree(bodies: PointMasses, leaf_size: int = LEAF_SIZE) -> Octree:
    """Build the octree over checked bodies (see the module docstring)."""
    # Coordinates and original indices (as floats: exact below 2**53) are reordered together,
    # so that every pass of the build reads memory in order.
    columns = np.stack([bodies.x, bodies.y, bodies.z, np.arange(bodies.count, dtype=np.float64)])
    *arrays, cells, depth = _build(columns, leaf_size)
    start, size, first_child, children, lower, upper = (array[:cells] for array in arrays)
    x, y, z, index = columns
    return Octree(
        index.astype(np.int64), x, y, z, start, size, first_child, children, lower, upper, depth
    )


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _leaf_moments(x, y, z, m, first, last, k, mass, centre, second, radius2):  # pragma: no cover
    """Moments of the leaf ``k`` holding bodies ``first .. last-1``, stored in row ``k``."""
    total = 0.0
    cx = 0.0
    cy = 0.0
    cz = 0.0
    for p in range(first, last):
        total += m[p]
        cx += m[p] * x[p]
        cy += m[p] * y[p]
        cz += m[p] * z[p]
    if total > 0.0:
        cx, cy, cz = cx / total, cy / total, cz / total
    else:  # a massless cell acts on nothing; its centre is only a place to measure from
        cx, cy, cz = x[first], y[first], z[first]
    mass[k] = total
    centre[k, 0], centre[k, 1], centre[k, 2] = cx, cy, cz
    for p in range(first, last):
        dx, dy, dz = x[p] - cx, y[p] - cy, z[p] - cz
        _add_second_moment(second, k, m[p], dx, dy, dz)
        if m[p] > 0.0:
            radius2[k] = max(radius2[k], dx * dx + dy * dy + dz * dz)


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def cell_moments(tree, m):  # pragma: no cover - compiled
    """Mass, centre of mass, second moment (xx yy zz xy xz yz) and radius² of every cell.

    ``tree`` is the tuple of an :class:`Octree`'s arrays from ``x`` to ``upper``; ``m`` holds
    the masses in tree order. Cells are combined bottom-up: children always come after their
    parent.
    """
    x, y, z, start, count, first_child, children, lower, upper = tree
    cells = start.shape[0]
    mass = np.zeros(cells)
    centre = np.empty((cells, 3))
    second = np.zeros((cells, 6))
    radius2 = np.zeros(cells)
    for k in range(cells - 1, -1, -1):
        if first_child[k] < 0:
            last = start[k] + count[k]
            _leaf_moments(x, y, z, m, start[k], last, k, mass, centre, second, radius2)
            continue
        children_of = range(first_child[k], first_child[k] + children[k])
        total = 0.0
        for child in children_of:
            total += mass[child]
        for axis in range(3):
            weighted = 0.0
            for child in children_of:
                weighted += mass[child] * centre[child, axis]
            middle = 0.5 * lower[k, axis] + 0.5 * upper[k, axis]
            centre[k, axis] = weighted / total if total > 0.0 else middle
        radius = 0.0
        for child in children_of:
            dx = centre[child, 0] - centre[k, 0]
            dy = centre[child, 1] - centre[k, 1]
            dz = centre[child, 2] - centre[k, 2]
            for c in range(6):
                second[k, c] += second[child, c]  # parallel-axis rule: own moment + M d dᵀ
            _add_second_moment(second, k, mass[child], dx, dy, dz)
            if mass[child] > 0.0:
                reach = np.sqrt(dx * dx + dy * dy + dz * dz) + np.sqrt(radius2[child])
                radius = max(radius, reach)
        mass[k] = total
        # The farthest corner of the cell's box bounds it too; keep the tighter bound.
        corner = 0.0
        for axis in range(3):
            far = max(centre[k, axis] - lower[k, axis], upper[k, axis] - centre[k, axis])
            corner += far * far
        radius2[k] = min(radius * radius, corner)
    return mass, centre, second, radius2


@njit(cache=True, fastmath=_FAST)
def _add_second_moment(second, k, m, dx, dy, dz):  # pragma: no cover - compiled
    second[k, 0] += m * dx * dx
    second[k, 1] += m * dy * dy
    second[k, 2] += m * dz * dz
    second[k, 3] += m * dx * dy
    second[k, 4] += m * dx * dz
    second[k, 5] += m * dy * dz
