"""Barnes–Hut octree gravity: far groups of bodies act through their multipoles.

J. Barnes & P. Hut, "A hierarchical O(N log N) force-calculation algorithm", Nature 324 (1986)
446; group walks: J. Barnes, J. Comput. Phys. 87 (1990) 161; opening criterion with the cell's
true extent: J. K. Salmon & M. S. Warren, J. Comput. Phys. 111 (1994) 136.

Build: the root cell is the bounding box of all bodies. A cell with more than ``LEAF_SIZE``
bodies is split at the centre of the bounding box of *its own* bodies into up to eight
children (an axis shorter than half the longest is not split, so flat sets such as disks get
flat cells); each child again takes the bounding box of its bodies. Bodies are reordered so
that every cell is a contiguous range (Morton-like order), and cells live in flat arrays.

Moments: each cell keeps its mass, centre of mass and second moment
``I = Σ m d dᵀ`` (``d`` from the centre of mass), combined bottom-up with the parallel-axis
rule, and the radius ``b`` of the sphere about the centre of mass holding its massive bodies.
Far cells act through the Plummer-softened expansion to second order (monopole + quadrupole;
the dipole vanishes about the centre of mass). For ``s = r² + ε²``, ``r`` from the centre of
mass to the body, ``T = tr I``:

    φ = −G [M s^{-1/2} + ½ (3 rᵀIr s^{-5/2} − T s^{-3/2})]
    a = G [−M s^{-3/2} r + 3 s^{-5/2} I r − (15/2) rᵀIr s^{-7/2} r + (3/2) T s^{-5/2} r]

Walk: one walk per leaf serves all its bodies. A cell is used whole if the distance from its
centre of mass to the leaf's bounding box exceeds ``b / theta``; otherwise it is opened, and an
opened leaf's bodies interact directly. The leaf's own bodies interact pairwise. Leaves are
walked in parallel (no shared writes); each walk fills a contiguous interaction list that the
force loop then runs through at SIMD speed.

Accuracy (measured, relative force error ``|a − a_direct| / |a_direct|`` over bodies, Plummer
sphere of 10⁶ bodies in N-body units, ε = 0.01, 20,000 bodies sampled; ``docs/gravitation.md``
has the timings and smaller N):

    theta   median    99th percentile
    0.3     TBD       TBD
    0.5     TBD       TBD
    0.7     TBD       TBD
    1.0     TBD       TBD

Degenerate input: coincident bodies always share a leaf. A leaf whose bodies all sit at one
point (the whole set, at the extreme) is never split and costs no pair loop: its bodies exert
no force on one another (with softening; without it :func:`gravity_accelerations` refuses
them), and their mutual potential is ``−G m_i (M_leaf − m_i) / ε`` in closed form. A cell
whose bodies are too close to split in floating point (within a few units in the last place)
becomes a leaf whatever its size, so the build ends on any input: depth is bounded by the
exponent range of a float64, and each level of the build is one pass over the bodies below it.
``N = 1`` gives a zero acceleration, ``N = 2`` a single leaf (exact). Huge coordinate ranges
cost nothing special: cells shrink to their own bodies, so a distant outlier adds one level.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit, prange

if TYPE_CHECKING:
    from .gravity import PointMasses

__all__ = ["LEAF_SIZE", "Octree", "build_octree", "tree_gravity"]

#: Bodies per leaf (at most, unless they cannot be split). An opened leaf's bodies interact
#: directly. Measured with 10⁶ Plummer bodies: 8–16 within 5% of each other.
LEAF_SIZE = 16

#: Bodies per group (at most, unless a leaf is larger): one walk serves a whole group. Larger
#: groups walk less often but must open more cells (the test is against the whole group's box):
#: 128 was fastest at theta 0.5 and 0.7 (64: +15%, 256: +3%).
GROUP_SIZE = 128

#: An axis is split only if it is at least this fraction of the cell's longest axis.
_SPLIT_FRACTION = 0.5

#: Groups per parallel work item: enough to amortise the interaction-list buffers, few enough
#: to balance the cores.
_GROUPS_PER_BLOCK = 16

#: Initial interaction-list capacity (grows by doubling when a walk needs more).
_LIST_CAPACITY = 2048

# The tree force makes no exact-symmetry promise (it is an approximation), so its sums and
# products may be re-associated; NaN and infinity stay honoured. See gravity.py.
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
    sizes[:] = 0
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


@njit(cache=True)
def _build(x, y, z, leaf_size):  # pragma: no cover - compiled
    n = x.shape[0]
    capacity = 2 * n  # every split makes at least two non-empty children
    # Coordinates and original indices (as floats: exact below 2**53) are reordered together,
    # so that every pass reads memory in order.
    columns = np.empty((4, n))
    columns[0], columns[1], columns[2] = x, y, z
    columns[3] = np.arange(n)
    scratch = np.empty((4, n))
    codes = np.empty(n, np.int64)
    sizes = np.empty(16, np.int64)
    centre = np.empty(3)
    split = np.empty(3, np.bool_)
    start = np.empty(capacity, np.int64)
    count = np.empty(capacity, np.int64)
    first_child = np.full(capacity, -1, np.int64)
    children = np.zeros(capacity, np.int64)
    level = np.zeros(capacity, np.int64)
    lower = np.empty((capacity, 3))
    upper = np.empty((capacity, 3))
    start[0], count[0] = 0, n
    cells = 1
    k = 0
    while k < cells:  # breadth first: children are appended after every existing cell
        _bounds(columns[0], columns[1], columns[2], start[k], count[k], lower[k], upper[k])
        longest = 0.0
        for axis in range(3):
            longest = max(longest, upper[k, axis] - lower[k, axis])
        if count[k] > leaf_size and longest > 0.0:
            for axis in range(3):
                centre[axis] = 0.5 * lower[k, axis] + 0.5 * upper[k, axis]  # no overflow
                split[axis] = upper[k, axis] - lower[k, axis] >= _SPLIT_FRACTION * longest
            _partition(columns, scratch, codes, start[k], count[k], centre, split, sizes)
            if sizes[:8].max() < count[k]:  # else the bodies are too close to separate
                first_child[k] = cells
                offset = start[k]
                for code in range(8):
                    if sizes[code] > 0:
                        start[cells], count[cells] = offset, sizes[code]
                        level[cells] = level[k] + 1
                        offset += sizes[code]
                        cells += 1
                children[k] = cells - first_child[k]
        k += 1
    order = columns[3].astype(np.int64)
    return (
        order,
        columns[0].copy(),
        columns[1].copy(),
        columns[2].copy(),
        start[:cells].copy(),
        count[:cells].copy(),
        first_child[:cells].copy(),
        children[:cells].copy(),
        lower[:cells].copy(),
        upper[:cells].copy(),
        level[:cells].max(),
    )


def build_octree(bodies: PointMasses, leaf_size: int = LEAF_SIZE) -> Octree:
    """Build the octree over checked bodies (see the module docstring)."""
    order, x, y, z, start, size, first_child, children, lower, upper, depth = _build(
        bodies.x, bodies.y, bodies.z, leaf_size
    )
    return Octree(order, x, y, z, start, size, first_child, children, lower, upper, int(depth))


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _leaf_moments(x, y, z, m, first, last):  # pragma: no cover - compiled
    """Mass, centre of mass, second moment and radius² of bodies ``first .. last-1``."""
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
    second = np.zeros(6)
    radius2 = 0.0
    for p in range(first, last):
        dx, dy, dz = x[p] - cx, y[p] - cy, z[p] - cz
        _add_second_moment(second, m[p], dx, dy, dz)
        if m[p] > 0.0:
            radius2 = max(radius2, dx * dx + dy * dy + dz * dz)
    return total, (cx, cy, cz), second, radius2


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _moments(tree, m):  # pragma: no cover - compiled
    """Mass, centre of mass, second moment (xx yy zz xy xz yz) and radius² of every cell.

    ``m`` holds the masses in tree order. Cells are combined bottom-up: children always come
    after their parent.
    """
    x, y, z, start, count, first_child, children, lower, upper = tree
    cells = start.shape[0]
    mass = np.zeros(cells)
    centre = np.empty((cells, 3))
    second = np.zeros((cells, 6))
    radius2 = np.zeros(cells)
    for k in range(cells - 1, -1, -1):
        if first_child[k] < 0:
            total, c, moment, r2 = _leaf_moments(x, y, z, m, start[k], start[k] + count[k])
            mass[k], radius2[k] = total, r2
            centre[k, 0], centre[k, 1], centre[k, 2] = c
            second[k] = moment
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
            second[k] += second[child]  # parallel-axis rule
            _add_second_moment(second[k], mass[child], dx, dy, dz)
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
def _add_second_moment(moment, m, dx, dy, dz):  # pragma: no cover - compiled
    moment[0] += m * dx * dx
    moment[1] += m * dy * dy
    moment[2] += m * dz * dz
    moment[3] += m * dx * dy
    moment[4] += m * dx * dz
    moment[5] += m * dy * dz


# Interaction lists, structure of arrays. Cell rows: centre of mass (3), mass, 1.5 T and
# 0.5 T (T the trace of the second moment), then J = 3 I as xx yy zz xy xz yz: the factors
# of the expansion are folded in once per cell instead of once per interaction.
_CELL_ROWS = 12
# Body rows: position (3), mass.
_BODY_ROWS = 4


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _walk(group, tree, moments, ms, theta2, eps2, cells, bodies, stack):  # pragma: no cover
    """Fill the interaction lists of ``group``; return their lengths.

    Every body of the system ends up exactly once in the lists: inside a cell used whole, or
    as a body (the group's own bodies included). Entries beyond a list's capacity are counted
    but not written: the caller then grows the list and walks again. (Growing inside the loop
    would make the lists loop-carried references, whose reference counting costs more than the
    walk itself.)
    """
    xs, ys, zs, start, count, first_child, children, lower, upper = tree
    mass, centre, second, radius2 = moments
    lo, hi = lower[group], upper[group]
    n_cells = 0
    n_bodies = 0
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        k = stack[top]
        # Distance from the cell's centre of mass to the nearest point of the group's box.
        d2 = 0.0
        for axis in range(3):
            gap = max(lo[axis] - centre[k, axis], 0.0, centre[k, axis] - hi[axis])
            d2 += gap * gap
        # A cell whose mass sits at one point is exact as a monopole at any distance (with
        # softening; without it, only away from the point).
        if d2 * theta2 > radius2[k] or (radius2[k] == 0.0 and eps2 > 0.0):
            if n_cells < cells.shape[1]:
                for axis in range(3):
                    cells[axis, n_cells] = centre[k, axis]
                trace = second[k, 0] + second[k, 1] + second[k, 2]
                cells[3, n_cells] = mass[k]
                cells[4, n_cells] = 1.5 * trace
                cells[5, n_cells] = 0.5 * trace
                for c in range(6):
                    cells[6 + c, n_cells] = 3.0 * second[k, c]
            n_cells += 1
        elif first_child[k] < 0:
            if n_bodies + count[k] <= bodies.shape[1]:
                for p in range(start[k], start[k] + count[k]):
                    bodies[0, n_bodies] = xs[p]
                    bodies[1, n_bodies] = ys[p]
                    bodies[2, n_bodies] = zs[p]
                    bodies[3, n_bodies] = ms[p]
                    n_bodies += 1
            else:
                n_bodies += count[k]
        else:
            for child in range(first_child[k], first_child[k] + children[k]):
                stack[top] = child
                top += 1
    return n_cells, n_bodies


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _far_field(xi, yi, zi, cells, n_cells, eps2, with_potential):  # pragma: no cover
    """Acceleration and ``Σ`` (potential / −G) at a body from the cells of its list."""
    ax = 0.0
    ay = 0.0
    az = 0.0
    pot = 0.0
    for k in range(n_cells):
        rx = xi - cells[0, k]
        ry = yi - cells[1, k]
        rz = zi - cells[2, k]
        inv = 1.0 / np.sqrt(rx * rx + ry * ry + rz * rz + eps2)
        inv2 = inv * inv
        inv3 = inv * inv2
        inv5 = inv3 * inv2
        jx = cells[6, k] * rx + cells[9, k] * ry + cells[10, k] * rz
        jy = cells[9, k] * rx + cells[7, k] * ry + cells[11, k] * rz
        jz = cells[10, k] * rx + cells[11, k] * ry + cells[8, k] * rz
        rjr = rx * jx + ry * jy + rz * jz
        radial = (cells[4, k] - 2.5 * rjr * inv2) * inv5 - cells[3, k] * inv3
        ax += radial * rx + inv5 * jx
        ay += radial * ry + inv5 * jy
        az += radial * rz + inv5 * jz
        if with_potential:  # loop-invariant: the compiler makes two loops
            pot += cells[3, k] * inv + (0.5 * rjr * inv2 - cells[5, k]) * inv3
    return ax, ay, az, pot


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _near_field(xi, yi, zi, bodies, n_bodies, eps2, with_potential):  # pragma: no cover
    """Acceleration and ``Σ m/r`` at a body from the bodies of its list (itself included)."""
    ax = 0.0
    ay = 0.0
    az = 0.0
    pot = 0.0
    for k in range(n_bodies):
        dx = bodies[0, k] - xi
        dy = bodies[1, k] - yi
        dz = bodies[2, k] - zi
        r2 = dx * dx + dy * dy + dz * dz + eps2
        inv = 1.0 / np.sqrt(r2) if r2 > 0.0 else 0.0  # the body itself, without softening
        w = bodies[3, k] * inv
        w3 = w * inv * inv
        ax += w3 * dx
        ay += w3 * dy
        az += w3 * dz
        if with_potential:
            pot += w
    return ax, ay, az, pot


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _group_forces(group, tree, ms, order, lists, eps2, factor, acc, potential):  # pragma: no cover
    """Forces on the bodies of ``group`` from its lists, written at the bodies' own indices."""
    xs, ys, zs, start, count = tree[0], tree[1], tree[2], tree[3], tree[4]
    cells, n_cells, bodies, n_bodies = lists
    with_potential = potential.shape[0] > 0
    # Each body met itself once in the lists: at zero distance it added no force, and with
    # softening it added m/ε to the potential sum, taken off here.
    self_term = 1.0 / np.sqrt(eps2) if eps2 > 0.0 else 0.0
    for p in range(start[group], start[group] + count[group]):
        xi, yi, zi = xs[p], ys[p], zs[p]
        ax, ay, az, far = _far_field(xi, yi, zi, cells, n_cells, eps2, with_potential)
        bx, by, bz, near = _near_field(xi, yi, zi, bodies, n_bodies, eps2, with_potential)
        b = order[p]
        acc[b, 0] = factor * (ax + bx)
        acc[b, 1] = factor * (ay + by)
        acc[b, 2] = factor * (az + bz)
        if with_potential:
            potential[b] = -factor * (far + near - ms[p] * self_term)


@njit(cache=True, parallel=True)
def _tree_forces(
    groups, tree, moments, ms, order, depth, eps2, theta2, factor, acc, potential
):  # pragma: no cover - compiled
    blocks = (groups.shape[0] + _GROUPS_PER_BLOCK - 1) // _GROUPS_PER_BLOCK
    for block in prange(blocks):
        cells = np.empty((_CELL_ROWS, _LIST_CAPACITY))
        bodies = np.empty((_BODY_ROWS, _LIST_CAPACITY))
        stack = np.empty(8 * (depth + 1), np.int64)  # pending siblings: at most 7 per level
        last = min((block + 1) * _GROUPS_PER_BLOCK, groups.shape[0])
        for index in range(block * _GROUPS_PER_BLOCK, last):
            group = groups[index]
            walk = (group, tree, moments, ms, theta2, eps2)
            n_cells, n_bodies = _walk(*walk, cells, bodies, stack)
            if n_cells > cells.shape[1] or n_bodies > bodies.shape[1]:
                cells = np.empty((_CELL_ROWS, 2 * max(n_cells, cells.shape[1])))
                bodies = np.empty((_BODY_ROWS, 2 * max(n_bodies, bodies.shape[1])))
                _walk(*walk, cells, bodies, stack)
            lists = (cells, n_cells, bodies, n_bodies)
            _group_forces(group, tree, ms, order, lists, eps2, factor, acc, potential)


@njit(cache=True)
def _coincident_bodies(tree):  # pragma: no cover - compiled
    """Whether two bodies share a point. They always share a leaf, so leaves are searched."""
    xs, ys, zs, start, count, first_child = tree[0], tree[1], tree[2], tree[3], tree[4], tree[5]
    lower, upper = tree[7], tree[8]
    for k in range(start.shape[0]):
        if first_child[k] >= 0 or count[k] < 2:
            continue
        if (lower[k] == upper[k]).all():
            return True
        for p in range(start[k], start[k] + count[k]):
            for q in range(p + 1, start[k] + count[k]):
                if xs[p] == xs[q] and ys[p] == ys[q] and zs[p] == zs[q]:
                    return True
    return False


def _groups(tree: Octree, size: int) -> np.ndarray:
    """The cells that share one walk: the largest with at most ``size`` bodies (or leaves)."""
    internal = np.flatnonzero(tree.first_child >= 0)
    parent = np.concatenate([[-1], np.repeat(internal, tree.children[internal])])
    eligible = (tree.size <= size) | (tree.first_child < 0)
    groups = np.flatnonzero(eligible & ((parent < 0) | ~eligible[np.maximum(parent, 0)]))
    return groups[np.argsort(tree.start[groups], kind="stable")]  # spatial order


def tree_gravity(
    bodies: PointMasses,
    theta: float,
    factor: float,
    acc: np.ndarray,
    potential: np.ndarray | None,
    *,
    leaf_size: int = LEAF_SIZE,
    group_size: int = GROUP_SIZE,
) -> bool:
    """Barnes–Hut accelerations ``factor · Σ_j m_j (x_j − x_i) / r³`` into ``acc`` ``(N, 3)``.

    ``potential`` (shape ``(N,)``, or ``None``) receives ``−factor Σ_j m_j / r_ij``. Masses are
    those of ``bodies`` (scaled). Returns ``False`` without computing anything if two bodies
    coincide and there is no softening (the caller turns that into an error).
    """
    tree = build_octree(bodies, leaf_size)
    arrays = tuple(tree)[1:-1]
    if bodies.eps2 == 0.0 and _coincident_bodies(arrays):
        return False
    ms = bodies.mass[tree.order]
    moments = _moments(arrays, ms)
    target = np.empty(0) if potential is None else potential  # empty: not wanted
    _tree_forces(
        _groups(tree, group_size),
        arrays,
        moments,
        ms,
        tree.order,
        tree.depth,
        bodies.eps2,
        theta * theta,
        factor,
        acc,
        target,
    )
    return True
