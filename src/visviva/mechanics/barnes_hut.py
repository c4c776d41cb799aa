"""Barnes–Hut gravity: far groups of bodies act through their multipoles, in O(N log N).

J. Barnes & P. Hut, "A hierarchical O(N log N) force-calculation algorithm", Nature 324 (1986)
446; group walks: J. Barnes, J. Comput. Phys. 87 (1990) 161; opening test with the cell's true
extent: J. K. Salmon & M. S. Warren, J. Comput. Phys. 111 (1994) 136. The tree itself is
built in :mod:`visviva.mechanics.octree`.

Far cells act through the Plummer-softened expansion to second order (monopole + quadrupole;
the dipole vanishes about the centre of mass). For ``s = r² + ε²``, ``r`` from the cell's
centre of mass to the body, ``M`` its mass, ``I`` its second moment and ``T = tr I``:

    φ = −G [M s^{-1/2} + ½ (3 rᵀIr s^{-5/2} − T s^{-3/2})]
    a = G [−M s^{-3/2} r + 3 s^{-5/2} I r − (15/2) rᵀIr s^{-7/2} r + (3/2) T s^{-5/2} r]

The quadrupole costs about 2× a monopole per cell but cuts the error 3–6× at a given
``theta``: for the same accuracy a monopole code needs ``theta`` about 0.6× as large, and so
about 4× as many cells.

Walk: one walk serves a *group* (the largest cell with at most :data:`GROUP_SIZE` bodies). A
cell is used whole if the distance from its centre of mass to the group's bounding box exceeds
``b / theta``, ``b`` the radius of the cell's massive bodies about their centre of mass; a cell
whose mass sits at one point is exact at any distance (with softening). Otherwise it is opened,
and an opened leaf's bodies interact directly, the group's own bodies included. Every body of
the system thus appears exactly once in a group's lists. Groups are walked in parallel (each
writes only its own bodies), and each walk fills contiguous interaction lists that the force
loops then run through at SIMD speed.

Precision: bodies interact in double precision; far cells in single precision, relative to the
group's centre and in units of a power of two near the system's size, which adds ~1e-7 to the
relative error of each term (the expansion's own error is ≥ 3e-5 at any theta) and makes the
far field 2.5× faster. Cells too near the group for that, or with masses or distances near the
limits of float32, stay in double precision.

Accuracy: relative force error ``|a − a_direct| / |a_direct|`` over bodies, Plummer spheres in
N-body units with ε = 0.01 (10⁵ bodies, all compared; 10⁶ bodies in ``docs/gravitation.md``).
:data:`ERROR_BOUNDS` are the documented bounds (tested):

    theta   median    99th percentile    bound (median, 99th)
    0.3     4.0e-5    3.2e-4             1e-4, 1e-3
    0.5     2.1e-4    1.5e-3             5e-4, 5e-3
    0.7     6.8e-4    4.9e-3             1.5e-3, 1.5e-2
    1.0     3.0e-3    2.5e-2             6e-3, 8e-2

Degenerate input (see also :mod:`~visviva.mechanics.octree`): ``N = 1`` gives a zero
acceleration; up to :data:`GROUP_SIZE` bodies form one group, so the result is direct
summation. Bodies at one point exert no force on one another (with softening; without it
:func:`~visviva.mechanics.gravity_accelerations` refuses them, found from the leaves before any
force is computed) and their mutual potential is exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit, prange

from .._validation import whole_number
from ..errors import ModelError
from .gravity import (
    GRAVITATIONAL_CONSTANT,
    PointMasses,
    accelerations_into,
    direct_accelerations_of,
    prepare,
)
from .octree import Octree, build_octree, cell_moments

__all__ = ["ERROR_BOUNDS", "GROUP_SIZE", "TreeError", "tree_force_error", "tree_gravity"]

#: Documented accuracy per opening angle: bounds on the median and the 99th percentile of the
#: relative force error against direct summation, for Plummer spheres of 10⁴–10⁶ bodies
#: (measured values in the module docstring and docs/gravitation.md, about 1.5× below these).
ERROR_BOUNDS = {0.3: (1e-4, 1e-3), 0.5: (5e-4, 5e-3), 0.7: (1.5e-3, 1.5e-2), 1.0: (6e-3, 8e-2)}

#: Bodies per group (at most, unless a leaf is larger): one walk serves a whole group. Larger
#: groups walk less often but must open more cells (the test is against the whole group's box):
#: with 10⁶ Plummer bodies 128 was fastest at theta 0.5 and 1 (64: +10%, 192: within 5%).
GROUP_SIZE = 128

#: Groups per parallel work item: enough to amortise the interaction-list buffers, few enough
#: to balance the cores.
_GROUPS_PER_BLOCK = 16

#: Initial capacity of the far-cell list (θ = 0.5 with 10⁶ bodies needs ~2200 entries); the
#: lists grow to twice what a walk needed when it needs more.
_LIST_CAPACITY = 4096

#: Extra entries per list row. A walk writes one column of 12 rows at a time; with a row
#: length a multiple of 4 KiB all 12 would map to one set of the 8-way L1 cache and evict
#: each other on every write (the walk ran 3× slower).
_ROW_PADDING = 16

# The tree force makes no exact-symmetry promise (it is an approximation), so its sums and
# products may be re-associated; NaN and infinity stay honoured. See gravity.py.
_FAST = {"contract", "arcp", "nsz", "afn", "reassoc"}


# Interaction lists, structure of arrays. Cell rows: centre of mass (3), mass, 1.5 T and
# 0.5 T (T the trace of the second moment), then J = 3 I as xx yy zz xy xz yz: the factors
# of the expansion are folded in once per cell instead of once per interaction.
_CELL_ROWS = 12

# Far cells are evaluated in single precision (8 SIMD lanes instead of 4, and a faster square
# root and division: 2.5× the interactions per second), lengths in units of a power of two
# `L` near the size of the system and centres relative to the group's centre. Rounding a
# body's and a cell's offsets costs ~6e-8 of each relative to their distance, so a term's error
# is ~1e-7 for most cells and at most ~1e-5 for a cell 1/64 of the group's half-diagonal away,
# below the expansion's own error (≥ 3e-5 at any theta). A cell enters the single-precision
# list if its distance d from the group's box satisfies d ≥ (group half-diagonal) / _NEAR_RATIO
# and d ≥ _SMALLEST_DISTANCE L (so r⁻⁵ stays within float32's range), and its mass in units of
# the largest body's is at least _SMALLEST_MASS; other cells go to a double-precision list.
_NEAR_RATIO = 64.0
_SMALLEST_DISTANCE = 2.0**-20
_SMALLEST_MASS = 2.0**-100

# Body rows: position (3), mass.
_BODY_ROWS = 4


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _cell_records(moments, scale):  # pragma: no cover - compiled
    """What a walk reads of each cell, packed: ``nodes`` ``(K, 5)`` (centre of mass, radius²,
    mass) for the opening test, and ``records`` ``(K, 9)`` float32, the single-precision list's
    rows 3–11 in units of ``scale`` (copied whole when the cell is used)."""
    mass, centre, second, radius2 = moments
    cells = mass.shape[0]
    nodes = np.empty((cells, 5))
    records = np.empty((cells, _CELL_ROWS - 3), np.float32)
    unit2 = 1.0 / (scale * scale)
    for k in range(cells):
        for axis in range(3):
            nodes[k, axis] = centre[k, axis]
        nodes[k, 3] = radius2[k]
        nodes[k, 4] = mass[k]
        trace = (second[k, 0] + second[k, 1] + second[k, 2]) * unit2
        records[k, 0] = mass[k]
        records[k, 1] = 1.5 * trace
        records[k, 2] = 0.5 * trace
        for c in range(6):
            records[k, 3 + c] = 3.0 * second[k, c] * unit2
    return nodes, records, second


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _walk(group, tree, cells, ms, theta2, eps2, scale, lists, stack):  # pragma: no cover
    """Fill the interaction lists of ``group``; return their lengths.

    ``cells`` is :func:`_cell_records`' output; ``lists`` holds the single- and double-precision
    cell lists and the body list; ``scale`` is the length unit ``L`` of the single-precision
    list. Every body of the system ends up exactly once in the lists: inside a cell used whole,
    or as a body (the group's own bodies included).
    Entries beyond a list's capacity are counted but not written: the caller then grows the
    list and walks again. (Growing inside the loop would make the lists loop-carried
    references, whose reference counting costs more than the walk itself.)
    """
    xs, ys, zs, start, count, first_child, children, lower, upper = tree
    nodes, records, second = cells
    single, double, bodies = lists
    lo, hi = lower[group], upper[group]
    reference = np.empty(3)
    half_diagonal2 = 0.0
    for axis in range(3):
        reference[axis] = 0.5 * lo[axis] + 0.5 * hi[axis]
        half_diagonal2 += (0.5 * hi[axis] - 0.5 * lo[axis]) ** 2
    single_floor2 = max(half_diagonal2 / _NEAR_RATIO**2, (_SMALLEST_DISTANCE * scale) ** 2)
    unit = 1.0 / scale
    n_single = 0
    n_double = 0
    n_bodies = 0
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        k = stack[top]
        # Distance from the cell's centre of mass to the nearest point of the group's box.
        d2 = 0.0
        for axis in range(3):
            gap = max(lo[axis] - nodes[k, axis], 0.0, nodes[k, axis] - hi[axis])
            d2 += gap * gap
        radius2, mass = nodes[k, 3], nodes[k, 4]
        # A cell whose mass sits at one point is exact as a monopole at any distance (with
        # softening; without it, only away from the point).
        if d2 * theta2 > radius2 or (radius2 == 0.0 and eps2 > 0.0):
            if mass == 0.0:  # test particles only: nothing to pull with
                pass
            elif d2 >= single_floor2 and mass >= _SMALLEST_MASS:
                if n_single < single.shape[1]:
                    for axis in range(3):
                        single[axis, n_single] = (nodes[k, axis] - reference[axis]) * unit
                    for row in range(_CELL_ROWS - 3):
                        single[3 + row, n_single] = records[k, row]
                n_single += 1
            else:
                if n_double < double.shape[1]:
                    trace = second[k, 0] + second[k, 1] + second[k, 2]
                    for axis in range(3):
                        double[axis, n_double] = nodes[k, axis]
                    double[3, n_double] = mass
                    double[4, n_double] = 1.5 * trace
                    double[5, n_double] = 0.5 * trace
                    for c in range(6):
                        double[6 + c, n_double] = 3.0 * second[k, c]
                n_double += 1
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
    return n_single, n_double, n_bodies


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _far_field(xi, yi, zi, cells, n_cells, eps2, with_potential, one):  # pragma: no cover
    """Acceleration and ``Σ`` (potential / −G) at a body from the cells of its list.

    Computed in the precision of ``cells`` (float32 or float64): every scalar argument comes in
    that precision and ``one`` is 1 in it, so no constant widens the arithmetic.
    """
    ax = one - one
    ay = ax
    az = ax
    pot = ax
    half = one / (one + one)  # (a float literal would be float64 and widen everything)
    two_and_half = one + one + half
    for k in range(n_cells):
        rx = xi - cells[0, k]
        ry = yi - cells[1, k]
        rz = zi - cells[2, k]
        inv = one / np.sqrt(rx * rx + ry * ry + rz * rz + eps2)
        inv2 = inv * inv
        inv3 = inv * inv2
        inv5 = inv3 * inv2
        jx = cells[6, k] * rx + cells[9, k] * ry + cells[10, k] * rz
        jy = cells[9, k] * rx + cells[7, k] * ry + cells[11, k] * rz
        jz = cells[10, k] * rx + cells[11, k] * ry + cells[8, k] * rz
        rjr = rx * jx + ry * jy + rz * jz
        radial = (cells[4, k] - two_and_half * rjr * inv2) * inv5 - cells[3, k] * inv3
        ax += radial * rx + inv5 * jx
        ay += radial * ry + inv5 * jy
        az += radial * rz + inv5 * jz
        if with_potential:  # loop-invariant: the compiler makes two loops
            pot += cells[3, k] * inv + (half * rjr * inv2 - cells[5, k]) * inv3
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
def _group_forces(
    group, tree, ms, order, lists, counts, eps2, scale, factor, acc, potential
):  # pragma: no cover
    """Forces on the bodies of ``group`` from its lists, written at the bodies' own indices."""
    xs, ys, zs, start, count, lower, upper = (
        tree[0],
        tree[1],
        tree[2],
        tree[3],
        tree[4],
        tree[7],
        tree[8],
    )
    single, double, bodies = lists
    n_single, n_double, n_bodies = counts
    with_potential = potential.shape[0] > 0
    # Each body met itself once in the lists: at zero distance it added no force, and with
    # softening it added m/ε to the potential sum, taken off here.
    self_term = 1.0 / np.sqrt(eps2) if eps2 > 0.0 else 0.0
    # The single-precision list's frame: centre of the group's box, lengths in units of `scale`.
    unit = 1.0 / scale
    one = np.float32(1.0)
    eps2_single = np.float32(eps2 * unit * unit)
    reference = 0.5 * lower[group] + 0.5 * upper[group]
    for p in range(start[group], start[group] + count[group]):
        xi, yi, zi = xs[p], ys[p], zs[p]
        fx, fy, fz, far = _far_field(
            np.float32((xi - reference[0]) * unit),
            np.float32((yi - reference[1]) * unit),
            np.float32((zi - reference[2]) * unit),
            single,
            n_single,
            eps2_single,
            with_potential,
            one,
        )
        ax, ay, az, close = _far_field(xi, yi, zi, double, n_double, eps2, with_potential, 1.0)
        bx, by, bz, near = _near_field(xi, yi, zi, bodies, n_bodies, eps2, with_potential)
        b = order[p]
        acc[b, 0] = factor * (unit * unit * fx + ax + bx)
        acc[b, 1] = factor * (unit * unit * fy + ay + by)
        acc[b, 2] = factor * (unit * unit * fz + az + bz)
        if with_potential:
            potential[b] = -factor * (unit * far + close + near - ms[p] * self_term)


@njit(cache=True, parallel=True)
def _tree_forces(
    groups, tree, cells, ms, order, depth, eps2, theta2, scale, factor, acc, potential
):  # pragma: no cover - compiled
    blocks = (groups.shape[0] + _GROUPS_PER_BLOCK - 1) // _GROUPS_PER_BLOCK
    for block in prange(blocks):
        single = np.empty((_CELL_ROWS, _LIST_CAPACITY + _ROW_PADDING), np.float32)
        double = np.empty((_CELL_ROWS, _LIST_CAPACITY // 8 + _ROW_PADDING))
        bodies = np.empty((_BODY_ROWS, _LIST_CAPACITY // 4 + _ROW_PADDING))
        stack = np.empty(8 * (depth + 1), np.int64)  # pending siblings: at most 7 per level
        last = min((block + 1) * _GROUPS_PER_BLOCK, groups.shape[0])
        for index in range(block * _GROUPS_PER_BLOCK, last):
            group = groups[index]
            walk = (group, tree, cells, ms, theta2, eps2, scale)
            counts = _walk(*walk, (single, double, bodies), stack)
            n_single, n_double, n_bodies = counts
            if (
                n_single > single.shape[1]
                or n_double > double.shape[1]
                or n_bodies > bodies.shape[1]
            ):
                single = np.empty((_CELL_ROWS, _row(n_single, single)), np.float32)
                double = np.empty((_CELL_ROWS, _row(n_double, double)))
                bodies = np.empty((_BODY_ROWS, _row(n_bodies, bodies)))
                _walk(*walk, (single, double, bodies), stack)
            lists = (single, double, bodies)
            _group_forces(
                group, tree, ms, order, lists, counts, eps2, scale, factor, acc, potential
            )


@njit(cache=True)
def _row(needed, current):  # pragma: no cover - compiled
    """Row length of a list that must hold ``needed`` entries: twice that, never less than the
    ``current`` list's, padded so that rows do not alias."""
    return max(2 * needed, current.shape[1]) + _ROW_PADDING


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
    leaf_size: int | None = None,
    group_size: int = GROUP_SIZE,
) -> bool:
    """Barnes–Hut accelerations ``factor · Σ_j m_j (x_j − x_i) / r³`` into ``acc`` ``(N, 3)``.

    ``potential`` (shape ``(N,)``, or ``None``) receives ``−factor Σ_j m_j / r_ij``. Masses are
    those of ``bodies`` (scaled). Returns ``False`` without computing anything if two bodies
    coincide and there is no softening (the caller turns that into an error).
    """
    tree = build_octree(bodies) if leaf_size is None else build_octree(bodies, leaf_size)
    arrays = tuple(tree)[1:-1]
    if bodies.eps2 == 0.0 and _coincident_bodies(arrays):
        return False
    ms = bodies.mass[tree.order]
    target = np.empty(0) if potential is None else potential  # empty: not wanted
    # The single-precision length unit: a power of two (exact scaling) near the system's size.
    extent = float((tree.upper[0] - tree.lower[0]).max())
    scale = math.ldexp(1.0, math.frexp(extent)[1]) if extent > 0.0 else 1.0
    _tree_forces(
        _groups(tree, group_size),
        arrays,
        _cell_records(cell_moments(arrays, ms), scale),
        ms,
        tree.order,
        tree.depth,
        bodies.eps2,
        theta * theta,
        scale,
        factor,
        acc,
        target,
    )
    return True


@dataclass(frozen=True)
class TreeError:
    """Relative force error ``|a_tree − a_direct| / |a_direct|`` of Barnes–Hut over bodies.

    Attributes:
        theta: The opening angle measured.
        median, p99, largest: Median, 99th percentile and largest error over the bodies compared.
        compared: How many bodies were compared (a random sample, or all).
    """

    theta: float
    median: float
    p99: float
    largest: float
    compared: int


def tree_force_error(
    positions: Any,
    masses: Any,
    *,
    G: float = GRAVITATIONAL_CONSTANT,
    softening: float = 0.0,
    theta: float = 0.5,
    sample: int = 2000,
    seed: int = 0,
) -> TreeError:
    """How far Barnes–Hut forces are from direct summation, for these very bodies.

    The tree forces every body; direct summation only a random ``sample`` of them (all if
    ``sample ≥ N``), so a million bodies cost about as much as one direct sum over 2000 rows.
    Bodies whose exact acceleration is zero (a lone body, a perfectly balanced one) have no
    relative error and are left out.

    Args:
        positions, masses, G, softening, theta: As for
            :func:`~visviva.mechanics.gravity_accelerations`.
        sample: Number of bodies compared, at least 1.
        seed: Seed of the sample.

    Example:
        >>> import visviva as vv
        >>> cluster = vv.mechanics.plummer_sphere(5000, total_mass=1, scale_radius=1, G=1, seed=1)
        >>> error = vv.mechanics.tree_force_error(
        ...     cluster.positions, cluster.masses, G=1.0, softening=0.01, theta=0.5)
        >>> error.median < ERROR_BOUNDS[0.5][0] and error.p99 < ERROR_BOUNDS[0.5][1]
        True
    """
    bodies, gravity, _, angle = prepare(positions, masses, G, softening, "barnes_hut", theta)
    count = whole_number("sample", sample, minimum=1)
    rng = np.random.default_rng(seed)
    if count >= bodies.count:
        targets = np.arange(bodies.count)
    else:
        targets = np.sort(rng.choice(bodies.count, size=count, replace=False))
    tree = accelerations_into(bodies, gravity, "barnes_hut", angle, np.empty((bodies.count, 3)))
    exact = np.empty((targets.size, 3))
    direct_accelerations_of(targets, bodies, gravity * bodies.mass_scale, exact)
    size = np.linalg.norm(exact, axis=1)
    kept = size > 0.0
    if not kept.any():
        raise ModelError("no compared body feels any force, so there is no relative error")
    error = np.linalg.norm(tree[targets] - exact, axis=1)[kept] / size[kept]
    return TreeError(
        angle,
        float(np.median(error)),
        float(np.percentile(error, 99)),
        float(error.max()),
        int(kept.sum()),
    )
