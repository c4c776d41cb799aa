"""Closed triangle meshes: the checks that make a mesh a solid, and its pseudo-normals.

A triangle mesh bounds a solid when it is *closed* (every edge shared by exactly two
triangles), *consistently oriented* (the two triangles at an edge list it in opposite
directions) and *outward* (counter-clockwise seen from outside, so the enclosed volume
``Σ a·(b × c)/6`` is positive). :func:`check_closed_mesh` refuses anything else with a message
naming the first offending triangle or edge; signed distances, inside tests and mass properties
are only meaningful on meshes that pass. A mesh of several closed shells passes, and a shell
listed inside-out within a larger one is a cavity (the total volume must still be positive).
Not checked here: shells touching at a single vertex, and self-intersections (see
:func:`visviva.geometry.self_intersection.check_self_intersections`).

:func:`pseudo_normals` gives the angle-weighted pseudo-normals of J. A. Bærentzen and
H. Aanæs, "Signed distance computation using the angle weighted pseudonormal", *IEEE TVCG*
11(3), 2005: at a face, its normal; at an edge, the sum of its two faces' normals; at a vertex,
the sum of its faces' normals weighted by the face's angle at the vertex. The sign of
``(p − q)·n`` with ``q`` the closest point of the mesh and ``n`` the pseudo-normal of the feature
holding ``q`` is then the inside/outside sign of ``p`` (their Theorem 1), for convex and
non-convex meshes alike.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from .._validation import describe
from ..errors import ModelError

__all__ = [
    "DEGENERATE_TOLERANCE",
    "check_closed_mesh",
    "enclosed_volume",
    "mesh_arrays",
    "pseudo_normals",
]

#: A triangle is degenerate when twice its area, |(b − a) × (c − a)|, is below this fraction of
#: its longest edge squared (its height below this fraction of that edge): its normal would be
#: mostly rounding error.
DEGENERATE_TOLERANCE = 1e-10

#: Vertices with more outgoing edges than this sort them with ``np.argsort`` (insertion sort
#: below: a vertex of a typical mesh has about six).
_INSERTION_SORT_MAX = 32

#: The enclosed volume must exceed this fraction of the cube of the mesh's extent.
_FLAT_TOLERANCE = 1e-12


def _vertices(value: Any) -> np.ndarray:
    try:
        vertices = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ModelError(
            f"`vertices` of a triangle mesh must be a (V, 3) array of numbers [m] "
            f"(got {describe(value)})"
        ) from exc
    if vertices.ndim != 2 or vertices.shape[1] != 3 or vertices.shape[0] < 4:
        raise ModelError(
            f"`vertices` of a triangle mesh must have shape (V, 3) with V ≥ 4, the fewest a "
            f"closed mesh has (got shape {vertices.shape})"
        )
    bad = ~np.isfinite(vertices)
    if bad.any():
        row = int(np.argwhere(bad)[0, 0])
        raise ModelError(
            f"`vertices` of a triangle mesh must be finite; vertex {row} is "
            f"{describe(vertices[row])}"
        )
    return vertices


def _triangles(value: Any, vertex_count: int) -> np.ndarray:
    array = np.asarray(value)
    if array.size and not np.issubdtype(array.dtype, np.integer):
        raise ModelError(
            f"`triangles` of a triangle mesh must hold integer vertex indices (got dtype "
            f"{array.dtype}); convert with np.asarray(triangles, dtype=int)"
        )
    if array.ndim != 2 or array.shape[1] != 3 or array.shape[0] < 4:
        raise ModelError(
            f"`triangles` of a triangle mesh must have shape (T, 3) with T ≥ 4, the fewest a "
            f"closed mesh has (got shape {array.shape})"
        )
    triangles = array.astype(np.int64)
    bad = (triangles < 0) | (triangles >= vertex_count)
    if bad.any():
        row, column = (int(k) for k in np.argwhere(bad)[0])
        raise ModelError(
            f"`triangles` entry {row} refers to vertex {int(triangles[row, column])}, but the "
            f"mesh has {vertex_count} vertices (valid indices 0 to {vertex_count - 1})"
        )
    return triangles


@njit(cache=True)
def _first_degenerate(vertices: np.ndarray, triangles: np.ndarray, tolerance: float) -> int:
    """Index of the first triangle whose twice-area is not above ``tolerance`` times its longest
    edge squared (``-1`` if none): the test of :func:`_check_areas`, in one pass."""
    for t in range(triangles.shape[0]):
        i, j, k = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        e1x = vertices[j, 0] - vertices[i, 0]
        e1y = vertices[j, 1] - vertices[i, 1]
        e1z = vertices[j, 2] - vertices[i, 2]
        e2x = vertices[k, 0] - vertices[i, 0]
        e2y = vertices[k, 1] - vertices[i, 1]
        e2z = vertices[k, 2] - vertices[i, 2]
        nx = e1y * e2z - e1z * e2y
        ny = e1z * e2x - e1x * e2z
        nz = e1x * e2y - e1y * e2x
        twice_area = np.sqrt(nx * nx + ny * ny + nz * nz)
        e3x, e3y, e3z = e2x - e1x, e2y - e1y, e2z - e1z
        longest = max(
            e1x * e1x + e1y * e1y + e1z * e1z,
            e2x * e2x + e2y * e2y + e2z * e2z,
            e3x * e3x + e3y * e3y + e3z * e3z,
        )
        if not twice_area > tolerance * longest:
            return t
    return -1


def _check_areas(vertices: np.ndarray, triangles: np.ndarray) -> None:
    row = int(_first_degenerate(vertices, triangles, DEGENERATE_TOLERANCE))
    if row < 0:
        return
    a, b, c = vertices[triangles[row]]
    twice_area = float(np.linalg.norm(np.cross(b - a, c - a)))
    longest = float(max(np.sum((b - a) ** 2), np.sum((c - b) ** 2), np.sum((a - c) ** 2)))
    ratio = twice_area / longest if longest > 0 else 0.0
    raise ModelError(
        f"`triangles` entry {row} (vertices {describe(triangles[row])}) is degenerate: its "
        f"area is {0.5 * twice_area:.3g} m², {ratio:.3g} of its longest edge squared "
        f"(at least {DEGENERATE_TOLERANCE:g} is needed); remove it or move its vertices "
        "apart"
    )


@njit(cache=True)
def _paired_edges(triangles: np.ndarray, vertex_count: int) -> np.ndarray:
    """Each directed edge's undirected index, or an empty array if the mesh is not closed and
    consistently oriented.

    A closed, consistently oriented mesh uses every directed edge a→b once and its reverse b→a
    once. The directed edges are bucketed by tail vertex (a counting sort), each bucket sorted
    by head, and each edge's reverse found by binary search: O(T log d) for vertex degree d,
    where the general table of :func:`_edge_table` sorts all 3T edges. Undirected edges are
    numbered in the order (smaller vertex, larger vertex), as :func:`_edge_table` numbers them.
    """
    count = triangles.shape[0]
    start = np.zeros(vertex_count + 1, dtype=np.int64)
    for t in range(count):
        for j in range(3):
            start[triangles[t, j] + 1] += 1
    for v in range(vertex_count):
        start[v + 1] += start[v]
    head = np.empty(3 * count, dtype=np.int64)
    owner = np.empty(3 * count, dtype=np.int64)  # 3t + j: edge j (vertex j to j + 1) of t
    fill = start[:-1].copy()
    for t in range(count):
        for j in range(3):
            tail = triangles[t, j]
            head[fill[tail]] = triangles[t, (j + 1) % 3]
            owner[fill[tail]] = 3 * t + j
            fill[tail] += 1
    for v in range(vertex_count):
        if start[v + 1] - start[v] > _INSERTION_SORT_MAX:
            order = np.argsort(head[start[v] : start[v + 1]])
            head[start[v] : start[v + 1]] = head[start[v] : start[v + 1]][order]
            owner[start[v] : start[v + 1]] = owner[start[v] : start[v + 1]][order]
            continue
        for k in range(start[v] + 1, start[v + 1]):  # insertion sort: buckets hold ~6 edges
            h, o = head[k], owner[k]
            m = k - 1
            while m >= start[v] and head[m] > h:
                head[m + 1] = head[m]
                owner[m + 1] = owner[m]
                m -= 1
            head[m + 1] = h
            owner[m + 1] = o
    edge = np.full(3 * count, -1, dtype=np.int64)
    failed = np.empty(0, dtype=np.int64)
    numbered = 0
    for a in range(vertex_count):
        for k in range(start[a], start[a + 1]):
            b = head[k]
            if k + 1 < start[a + 1] and head[k + 1] == b:
                return failed  # a→b twice
            lo = start[b] + np.searchsorted(head[start[b] : start[b + 1]], a)
            if lo >= start[b + 1] or head[lo] != a:
                return failed  # no b→a: open, or both triangles run a→b
            if a < b:
                edge[owner[k]] = numbered
                edge[owner[lo]] = numbered
                numbered += 1
    return edge


def _edge_table(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Check closedness and orientation; return the undirected edges and each triangle's.

    Returns:
        ``edges`` ``(E, 2)`` vertex pairs (smaller first) and ``triangle_edges`` ``(T, 3)`` the
        rows of ``edges`` for each triangle's edges ab, bc, ca.
    """
    count = triangles.shape[0]
    directed = np.stack([triangles, np.roll(triangles, -1, axis=1)], axis=2).reshape(
        -1, 2
    )  # row 3t + j is the edge from vertex j to vertex j+1 of triangle t
    undirected = np.sort(directed, axis=1)
    edges, inverse, uses = np.unique(undirected, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    wrong = np.flatnonzero(uses != 2)
    if wrong.size:
        edge = int(wrong[0])
        owners = sorted({int(k) // 3 for k in np.flatnonzero(inverse == edge)})
        pair = (int(edges[edge, 0]), int(edges[edge, 1]))
        if uses[edge] == 1:
            raise ModelError(
                f"`triangles` do not close the mesh: edge {pair} belongs to triangle "
                f"{owners[0]} only; every edge of a closed solid is shared by exactly two "
                "triangles (fill the hole, or merge duplicate vertices at the seam)"
            )
        raise ModelError(
            f"`triangles` are not a manifold: edge {pair} is shared by {int(uses[edge])} "
            f"triangles (entries {owners}); every edge of a closed solid is shared by exactly "
            "two"
        )
    forward = directed[:, 0] < directed[:, 1]
    # Each undirected edge is used twice; consistent orientation uses it once each way.
    forward_uses = np.bincount(inverse, weights=forward, minlength=edges.shape[0])
    clash = np.flatnonzero(forward_uses != 1)
    if clash.size:
        edge = int(clash[0])
        owners = [int(k) // 3 for k in np.flatnonzero(inverse == edge)]
        first = directed[np.flatnonzero(inverse == edge)[0]]
        raise ModelError(
            f"`triangles` are not consistently oriented: triangles {owners[0]} and {owners[1]} "
            f"both run along edge {int(first[0])}→{int(first[1])} in the same direction; "
            f"reverse the vertex order of one of them (neighbours list a shared edge in "
            "opposite directions, all counter-clockwise seen from outside)"
        )
    return edges, inverse.reshape(count, 3)


@njit(cache=True)
def _six_volume(vertices: np.ndarray, triangles: np.ndarray, origin: np.ndarray) -> float:
    total = 0.0
    ox, oy, oz = origin[0], origin[1], origin[2]
    for t in range(triangles.shape[0]):
        i, j, k = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        ax, ay, az = vertices[i, 0] - ox, vertices[i, 1] - oy, vertices[i, 2] - oz
        bx, by, bz = vertices[j, 0] - ox, vertices[j, 1] - oy, vertices[j, 2] - oz
        cx, cy, cz = vertices[k, 0] - ox, vertices[k, 1] - oy, vertices[k, 2] - oz
        total += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
    return total


def enclosed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    """Signed volume [m³] enclosed by a closed mesh: positive when it is counter-clockwise
    seen from outside.

    Sum of the tetrahedra (o, a, b, c) with ``o`` the mean vertex, which keeps the terms small
    for a mesh far from the origin (the sum does not depend on ``o`` for a closed mesh).
    """
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    return float(_six_volume(vertices, triangles, vertices.mean(axis=0)) / 6.0)


def mesh_arrays(vertices: Any, triangles: Any) -> tuple[np.ndarray, np.ndarray]:
    """Check the arrays of a mesh, not its topology: ``vertices`` ``(V, 3)`` finite [m] and
    ``triangles`` ``(T, 3)`` integer indices into them (V, T ≥ 4).

    Returns:
        Fresh C-contiguous copies: float64 vertices and int64 triangles.
    """
    vertices = np.ascontiguousarray(_vertices(vertices))
    return vertices, np.ascontiguousarray(_triangles(triangles, vertices.shape[0]))


def check_closed_mesh(vertices: Any, triangles: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate a mesh as the boundary of a solid.

    Args:
        vertices: ``(V, 3)`` vertex positions [m].
        triangles: ``(T, 3)`` integer vertex indices, counter-clockwise seen from outside.

    Returns:
        ``vertices`` as float64 ``(V, 3)``, ``triangles`` as int64 ``(T, 3)`` (both fresh
        copies), and ``triangle_edges`` ``(T, 3)``: an index per undirected edge, for each
        triangle's edges ab, bc, ca (shared edges share the index).

    Raises:
        ModelError: Non-finite vertices, indices out of range, a degenerate triangle, an open
            or non-manifold mesh, inconsistent orientation, an inside-out or flat mesh.
    """
    vertices, triangles = mesh_arrays(vertices, triangles)
    _check_areas(vertices, triangles)
    paired = _paired_edges(triangles, vertices.shape[0])
    if paired.size:
        triangle_edges = paired.reshape(-1, 3)
    else:  # the general table finds the first offending edge and says what is wrong
        _, triangle_edges = _edge_table(triangles)
    volume = enclosed_volume(vertices, triangles)
    extent = float(np.max(np.ptp(vertices, axis=0)))
    if volume < 0.0:
        raise ModelError(
            f"`triangles` are inside-out: the enclosed volume is {volume:.6g} m³; reverse "
            "every triangle's vertex order (triangles[:, ::-1]) so that they are "
            "counter-clockwise seen from outside"
        )
    if not volume > _FLAT_TOLERANCE * extent**3:
        raise ModelError(
            f"`triangles` enclose no volume ({volume:.3g} m³ within an extent of {extent:.3g} "
            "m): the mesh is flat; a mesh for collisions or mass properties must bound a solid"
        )
    return vertices, triangles, triangle_edges


def _normalized(vectors: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return vectors / np.where(length > 0.0, length, 1.0)


def pseudo_normals(
    vertices: np.ndarray, triangles: np.ndarray, triangle_edges: np.ndarray
) -> np.ndarray:
    """Angle-weighted pseudo-normals of each triangle's seven features (Bærentzen & Aanæs).

    Args:
        vertices: ``(V, 3)`` vertices of a mesh that passed :func:`check_closed_mesh`.
        triangles: ``(T, 3)`` its triangles.
        triangle_edges: ``(T, 3)`` its edge indices, as returned by :func:`check_closed_mesh`.

    Returns:
        ``(T, 7, 3)`` unit vectors: per triangle the face normal, the pseudo-normals of
        vertices a, b, c and of edges ab, bc, ca (the feature codes of
        :mod:`visviva.collision.triangle`).
    """
    corners = vertices[triangles]  # (T, 3 corners, 3 coordinates)
    face = _normalized(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))

    vertex_sum = np.zeros_like(vertices)
    for j in range(3):
        e1 = corners[:, (j + 1) % 3] - corners[:, j]
        e2 = corners[:, (j + 2) % 3] - corners[:, j]
        # atan2 of |e1 × e2| and e1·e2 is accurate for small and obtuse angles alike.
        angle = np.arctan2(np.linalg.norm(np.cross(e1, e2), axis=1), np.einsum("ij,ij->i", e1, e2))
        np.add.at(vertex_sum, triangles[:, j], angle[:, None] * face)

    # Each edge has two faces, each seeing it under the angle π: equal weights.
    edge_sum = np.zeros((int(triangle_edges.max()) + 1, 3))
    for j in range(3):
        np.add.at(edge_sum, triangle_edges[:, j], face)

    result = np.empty((triangles.shape[0], 7, 3))
    result[:, 0] = face
    result[:, 1:4] = _normalized(vertex_sum)[triangles]
    result[:, 4:7] = _normalized(edge_sum)[triangle_edges]
    return result
