"""Bounding-volume hierarchy over a closed triangle mesh, and the mesh queries that walk it.

The tree is built once per mesh from axis-aligned boxes, splitting each node's triangles at
the *median* of their box centres along the axis in which those centres spread most, to leaves
of at most :data:`LEAF_SIZE` triangles. A median split rather than the surface-area heuristic
(SAH): it keeps the tree balanced, so its depth is ``⌈log₂(T / LEAF_SIZE)⌉`` and a fixed stack
of :data:`STACK_SIZE` entries is enough for any mesh (the Numba walks cannot grow a list); the
build is ``O(T log² T)`` with no tuning constant; and on the evenly tessellated meshes
colliders use, the SAH's better trees for sparse ray casts buy little for point queries.

The tree is four flat arrays that a Numba kernel passes to :func:`mesh_distance`,
:func:`mesh_first_hit` or :func:`mesh_closest_point` (all ``@njit``, callable from another
kernel):

* ``node_bounds`` ``(M, 6)``: each node's box ``(min x, y, z, max x, y, z)`` [m]; node 0 is
  the root.
* ``node_links`` ``(M, 2)`` int64: a leaf is ``(first slot, count > 0)``; an inner node is
  ``(first child, 0)``, its children being nodes ``first`` and ``first + 1``.
* ``triangle_points`` ``(T, 3, 3)``: the corners a, b, c of the triangle in each slot [m];
  the slots are the triangles sorted so that every leaf owns a contiguous range.
* ``triangle_normals`` ``(T, 7, 3)``: the pseudo-normals of each slot's face, vertices and
  edges (:func:`visviva.geometry.mesh_topology.pseudo_normals`).

``triangle_order[slot]`` maps a slot back to the mesh's own triangle index.

Queries: the closest point (Ericson's closest point on a triangle, best-first descent pruning
every box farther than the best triangle so far); the signed distance, whose sign comes from
the pseudo-normal of the closest feature (Bærentzen & Aanæs 2005); the first entry of a segment
(Möller–Trumbore against the triangles of every box the segment crosses before the best hit).
A point query costs ``O(log T)`` near the surface, where collisions happen; a point nearly
equidistant from much of the surface (the centre of a finely tessellated sphere) cannot prune
and visits most triangles. Non-finite arguments give NaN distances, not an error: the kernels
trust their callers; the vectorized wrappers behind :class:`~visviva.collision.TriangleMesh`
check their input.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from .tables import PARALLEL_MIN_POINTS
from .triangle import closest_point_on_triangle, segment_triangle_hit

__all__ = [
    "LEAF_SIZE",
    "STACK_SIZE",
    "MeshBVH",
    "mesh_closest_point",
    "mesh_closest_points",
    "mesh_distance",
    "mesh_distances",
    "mesh_first_hit",
    "mesh_first_hits",
]

#: Most triangles in a leaf: below this, testing triangles is cheaper than testing two boxes.
LEAF_SIZE = 4

#: Entries of the walks' explicit stack. A depth-first walk of a tree of depth d holds at most
#: d + 1 entries; a balanced tree of 2⁶² leaves has depth 62.
STACK_SIZE = 64

#: Below this many rounding units of the mesh's size, ``p − q`` is noise, not a direction, and
#: the normal of a point on (or within rounding of) the surface is the feature's pseudo-normal.
_NOISE_ULPS = 64.0


@njit(cache=True)
def _build(low, high, leaf_size):  # pragma: no cover - compiled
    """Median-split tree over triangle boxes ``low``/``high`` ``(T, 3)``.

    Returns the node bounds, the node links and the slot order (the triangle in each slot).
    """
    count = low.shape[0]
    centre = 0.5 * (low + high)
    capacity = 2 * count
    bounds = np.empty((capacity, 6))
    links = np.zeros((capacity, 2), dtype=np.int64)
    ranges = np.empty((capacity, 2), dtype=np.int64)
    order = np.arange(count)
    ranges[0, 0] = 0
    ranges[0, 1] = count
    nodes = 1
    stack = [0]
    while len(stack) > 0:
        k = stack.pop()
        start, n = ranges[k, 0], ranges[k, 1]
        members = order[start : start + n]
        for axis in range(3):
            bounds[k, axis] = low[members, axis].min()
            bounds[k, 3 + axis] = high[members, axis].max()
        if n <= leaf_size:
            links[k, 0] = start
            links[k, 1] = n
            continue
        axis = 0
        widest = -1.0
        for a in range(3):
            width = centre[members, a].max() - centre[members, a].min()
            if width > widest:
                widest = width
                axis = a
        # A stable sort makes the tree, and hence tie-breaking in the queries, reproducible.
        members = members[np.argsort(centre[members, axis], kind="mergesort")]
        order[start : start + n] = members
        half = n // 2
        left = nodes
        nodes += 2
        ranges[left, 0] = start
        ranges[left, 1] = half
        ranges[left + 1, 0] = start + half
        ranges[left + 1, 1] = n - half
        links[k, 0] = left
        links[k, 1] = 0
        stack.append(left + 1)
        stack.append(left)
    return bounds[:nodes].copy(), links[:nodes].copy(), order


@dataclass(frozen=True, eq=False)
class MeshBVH:
    """The flat arrays of a mesh's tree (see the module docstring); read-only.

    Attributes:
        node_bounds: ``(M, 6)`` node boxes [m], world frame.
        node_links: ``(M, 2)`` int64 leaf ranges or first children.
        triangle_points: ``(T, 3, 3)`` triangle corners by slot [m].
        triangle_normals: ``(T, 7, 3)`` pseudo-normals by slot.
        triangle_order: ``(T,)`` the mesh's triangle index of each slot.
    """

    node_bounds: np.ndarray
    node_links: np.ndarray
    triangle_points: np.ndarray
    triangle_normals: np.ndarray
    triangle_order: np.ndarray

    @classmethod
    def build(cls, vertices: np.ndarray, triangles: np.ndarray, normals: np.ndarray) -> MeshBVH:
        """Build the tree of a validated mesh.

        Args:
            vertices: ``(V, 3)`` float64 vertices [m].
            triangles: ``(T, 3)`` int64 vertex indices.
            normals: ``(T, 7, 3)`` pseudo-normals per triangle, in the mesh's order.
        """
        corners = vertices[triangles]
        bounds, links, order = _build(corners.min(axis=1), corners.max(axis=1), LEAF_SIZE)
        arrays = (
            bounds,
            links,
            np.ascontiguousarray(corners[order]),
            np.ascontiguousarray(normals[order]),
            order,
        )
        for array in arrays:
            array.setflags(write=False)
        return cls(*arrays)

    @property
    def kernel_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(node_bounds, node_links, triangle_points, triangle_normals)``, the kernels' args."""
        return self.node_bounds, self.node_links, self.triangle_points, self.triangle_normals


@njit(cache=True)
def _box_distance2(px, py, pz, bounds, k):  # pragma: no cover - compiled
    """Squared distance [m²] from ``p`` to node ``k``'s box (0 inside)."""
    dx = max(bounds[k, 0] - px, 0.0, px - bounds[k, 3])
    dy = max(bounds[k, 1] - py, 0.0, py - bounds[k, 4])
    dz = max(bounds[k, 2] - pz, 0.0, pz - bounds[k, 5])
    return dx * dx + dy * dy + dz * dz


@njit(cache=True)
def mesh_closest_point(px, py, pz, node_bounds, node_links, triangle_points):  # pragma: no cover
    """Closest point of the mesh to ``p``: ``(qx, qy, qz, squared distance, slot, feature)``.

    Best-first depth-first descent: the nearer child is visited first, and a box is skipped
    when it is no nearer than the best triangle found so far. Among equally near triangles the
    first found is kept.
    """
    stack = np.empty(STACK_SIZE, dtype=np.int64)
    stack_d2 = np.empty(STACK_SIZE)
    best = math.inf
    bx = by = bz = 0.0
    best_slot = -1
    best_feature = -1
    stack[0] = 0
    stack_d2[0] = _box_distance2(px, py, pz, node_bounds, 0)
    top = 1
    while top > 0:
        top -= 1
        if stack_d2[top] >= best:
            continue
        k = stack[top]
        first, count = node_links[k, 0], node_links[k, 1]
        if count > 0:
            for slot in range(first, first + count):
                t = triangle_points[slot]
                qx, qy, qz, feature = closest_point_on_triangle(
                    px, py, pz, t[0, 0], t[0, 1], t[0, 2], t[1, 0], t[1, 1], t[1, 2],
                    t[2, 0], t[2, 1], t[2, 2],
                )  # fmt: skip
                d2 = (px - qx) ** 2 + (py - qy) ** 2 + (pz - qz) ** 2
                if d2 < best:
                    best, bx, by, bz, best_slot, best_feature = d2, qx, qy, qz, slot, feature
            continue
        near_d2 = _box_distance2(px, py, pz, node_bounds, first)
        far_d2 = _box_distance2(px, py, pz, node_bounds, first + 1)
        near, far = first, first + 1
        if far_d2 < near_d2:
            near, far, near_d2, far_d2 = far, near, far_d2, near_d2
        if far_d2 < best:
            stack[top] = far
            stack_d2[top] = far_d2
            top += 1
        if near_d2 < best:
            stack[top] = near
            stack_d2[top] = near_d2
            top += 1
    return bx, by, bz, best, best_slot, best_feature


@njit(cache=True, error_model="numpy")
def mesh_distance(
    px, py, pz, node_bounds, node_links, triangle_points, triangle_normals
):  # pragma: no cover - compiled
    """Signed distance [m] from ``p`` to a closed mesh and the outward unit normal there.

    Returns ``(d, gx, gy, gz)`` with the conventions of :mod:`visviva.collision.queries`:
    ``d < 0`` inside, ``g = ±(p − q)/|p − q|`` pointing out of the solid, ``p − d g = q``.
    The sign is that of ``(p − q)·n`` with ``n`` the pseudo-normal of the feature holding the
    closest point ``q``. A point within rounding of the surface gets that pseudo-normal.
    """
    qx, qy, qz, d2, slot, feature = mesh_closest_point(
        px, py, pz, node_bounds, node_links, triangle_points
    )
    if slot < 0:  # only for a non-finite point: every comparison with NaN failed
        return math.nan, math.nan, math.nan, math.nan
    nx = triangle_normals[slot, feature, 0]
    ny = triangle_normals[slot, feature, 1]
    nz = triangle_normals[slot, feature, 2]
    dx, dy, dz = px - qx, py - qy, pz - qz
    sign = -1.0 if dx * nx + dy * ny + dz * nz < 0.0 else 1.0
    length = math.sqrt(d2)
    scale = 0.0
    for j in range(6):
        scale = max(scale, abs(node_bounds[0, j]))
    if length <= _NOISE_ULPS * 2.220446049250313e-16 * scale:
        return sign * length, nx, ny, nz
    factor = sign / length
    return sign * length, dx * factor, dy * factor, dz * factor


@njit(cache=True, error_model="numpy")
def _segment_crosses_box(x0, y0, z0, ix, iy, iz, bounds, k, limit):  # pragma: no cover
    """Whether ``x0 + t D`` (``i = 1/D`` per axis, ``inf`` for 0) meets node ``k`` for t ≤ limit."""
    enter = 0.0
    leave = limit
    for axis in range(3):
        if axis == 0:
            p, inverse = x0, ix
        elif axis == 1:
            p, inverse = y0, iy
        else:
            p, inverse = z0, iz
        low, high = bounds[k, axis], bounds[k, 3 + axis]
        if math.isinf(inverse):
            if p < low or p > high:
                return False
            continue
        t_low = (low - p) * inverse
        t_high = (high - p) * inverse
        if t_low > t_high:
            t_low, t_high = t_high, t_low
        enter = max(enter, t_low)
        leave = min(leave, t_high)
        if enter > leave:
            return False
    return True


@njit(cache=True, error_model="numpy")
def _first_crossing(
    x0, y0, z0, x1, y1, z1, node_bounds, node_links, triangle_points
):  # pragma: no cover
    """Smallest ``t`` in [0, 1] where the segment crosses a triangle, or ``inf``."""
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    ix = 1.0 / dx if dx != 0.0 else math.inf
    iy = 1.0 / dy if dy != 0.0 else math.inf
    iz = 1.0 / dz if dz != 0.0 else math.inf
    stack = np.empty(STACK_SIZE, dtype=np.int64)
    stack[0] = 0
    top = 1
    best = math.inf
    while top > 0:
        top -= 1
        k = stack[top]
        if not _segment_crosses_box(x0, y0, z0, ix, iy, iz, node_bounds, k, min(best, 1.0)):
            continue
        first, count = node_links[k, 0], node_links[k, 1]
        if count > 0:
            for slot in range(first, first + count):
                t = triangle_points[slot]
                s = segment_triangle_hit(
                    x0, y0, z0, dx, dy, dz, t[0, 0], t[0, 1], t[0, 2], t[1, 0], t[1, 1],
                    t[1, 2], t[2, 0], t[2, 1], t[2, 2],
                )  # fmt: skip
                best = min(best, s)
            continue
        stack[top] = first + 1
        stack[top + 1] = first
        top += 2
    return best


@njit(cache=True, error_model="numpy")
def mesh_first_hit(
    x0, y0, z0, x1, y1, z1, node_bounds, node_links, triangle_points, triangle_normals
):  # pragma: no cover - compiled
    """First fraction ``s`` in [0, 1] at which the segment ``x0 → x1`` enters the closed mesh.

    ``0`` when ``x0`` is inside or on the surface (signed distance ≤ 0), ``inf`` when the
    segment stays outside. From outside, the first crossing of the surface is the entry.
    """
    d, _, _, _ = mesh_distance(
        x0, y0, z0, node_bounds, node_links, triangle_points, triangle_normals
    )
    if d <= 0.0:
        return 0.0
    return _first_crossing(x0, y0, z0, x1, y1, z1, node_bounds, node_links, triangle_points)


@njit(cache=True)
def _closest_into(points, nb, nl, tp, closest, slots, i):  # pragma: no cover - compiled
    qx, qy, qz, _, slot, _ = mesh_closest_point(
        points[i, 0], points[i, 1], points[i, 2], nb, nl, tp
    )
    closest[i, 0] = qx
    closest[i, 1] = qy
    closest[i, 2] = qz
    slots[i] = slot


@njit(cache=True)
def _distance_into(points, nb, nl, tp, tn, distance, normal, i):  # pragma: no cover
    d, gx, gy, gz = mesh_distance(points[i, 0], points[i, 1], points[i, 2], nb, nl, tp, tn)
    distance[i] = d
    normal[i, 0] = gx
    normal[i, 1] = gy
    normal[i, 2] = gz


@njit(cache=True)
def _hit_into(start, end, nb, nl, tp, tn, fraction, i):  # pragma: no cover - compiled
    fraction[i] = mesh_first_hit(
        start[i, 0], start[i, 1], start[i, 2], end[i, 0], end[i, 1], end[i, 2], nb, nl, tp, tn
    )


# One serial and one parallel driver per query: separate functions, so that each has its own
# entry in Numba's on-disk cache.
@njit(cache=True)
def _closest_serial(points, nb, nl, tp, closest, slots):  # pragma: no cover - compiled
    for i in range(points.shape[0]):
        _closest_into(points, nb, nl, tp, closest, slots, i)


@njit(cache=True, parallel=True)
def _closest_parallel(points, nb, nl, tp, closest, slots):  # pragma: no cover - compiled
    for i in prange(points.shape[0]):
        _closest_into(points, nb, nl, tp, closest, slots, i)


@njit(cache=True)
def _distances_serial(points, nb, nl, tp, tn, distance, normal):  # pragma: no cover
    for i in range(points.shape[0]):
        _distance_into(points, nb, nl, tp, tn, distance, normal, i)


@njit(cache=True, parallel=True)
def _distances_parallel(points, nb, nl, tp, tn, distance, normal):  # pragma: no cover
    for i in prange(points.shape[0]):
        _distance_into(points, nb, nl, tp, tn, distance, normal, i)


@njit(cache=True)
def _hits_serial(start, end, nb, nl, tp, tn, fraction):  # pragma: no cover - compiled
    for i in range(start.shape[0]):
        _hit_into(start, end, nb, nl, tp, tn, fraction, i)


@njit(cache=True, parallel=True)
def _hits_parallel(start, end, nb, nl, tp, tn, fraction):  # pragma: no cover - compiled
    for i in prange(start.shape[0]):
        _hit_into(start, end, nb, nl, tp, tn, fraction, i)


def mesh_closest_points(bvh: MeshBVH, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closest mesh point ``(N, 3)`` [m] to each of ``points`` ``(N, 3)`` (float64,
    C-contiguous, finite), and the mesh's index of the triangle holding it ``(N,)``."""
    n = points.shape[0]
    closest = np.empty((n, 3))
    slots = np.empty(n, dtype=np.int64)
    run = _closest_parallel if n >= PARALLEL_MIN_POINTS else _closest_serial
    run(points, bvh.node_bounds, bvh.node_links, bvh.triangle_points, closest, slots)
    return closest, bvh.triangle_order[slots]


def mesh_distances(bvh: MeshBVH, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance ``(N,)`` [m] and outward unit normal ``(N, 3)`` for each of ``points``
    ``(N, 3)`` (float64, C-contiguous, finite)."""
    n = points.shape[0]
    distance = np.empty(n)
    normal = np.empty((n, 3))
    run = _distances_parallel if n >= PARALLEL_MIN_POINTS else _distances_serial
    run(points, *bvh.kernel_arrays, distance, normal)
    return distance, normal


def mesh_first_hits(bvh: MeshBVH, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """First entry fraction ``(N,)`` of each segment ``start[i] → end[i]`` (``(N, 3)`` each,
    float64, C-contiguous, finite) into the mesh; ``0`` inside, ``inf`` for a miss."""
    n = start.shape[0]
    fraction = np.empty(n)
    run = _hits_parallel if n >= PARALLEL_MIN_POINTS else _hits_serial
    run(start, end, *bvh.kernel_arrays, fraction)
    return fraction
