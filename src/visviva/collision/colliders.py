"""Every static collider of a scene in one flat form the collision kernels can walk.

Planes, spheres, boxes and triangle meshes become one row each of a ``(K, 10)`` parameter
table with a kind code; the meshes' trees are concatenated, each mesh's row holding its index
into an offsets table. :func:`collider_distance` and :func:`collider_first_hit` dispatch on the
kind, so a kernel handles any mix of colliders with one loop (the conventions are those of
:mod:`visviva.collision.queries`: negative distance inside, outward unit normal).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit

from .bvh import mesh_distance, mesh_first_hit
from .queries import (
    box_distance,
    box_first_hit,
    plane_distance,
    plane_first_hit,
    sphere_distance,
    sphere_first_hit,
)
from .shapes import Box, Plane, Sphere, TriangleMesh
from .tables import ColliderKind

__all__ = ["MAX_COLLIDERS", "MESH", "ColliderSet", "collider_distance", "collider_first_hit"]

#: Kind code of a triangle mesh (after the primitives' ColliderKind codes).
MESH = 3
#: Leading planes the kernels handle one by one, without a loop.
UNROLLED_PLANES = 4
#: Most colliders a scene may hold: each particle keeps which colliders it meets as the bits of
#: one 64-bit mask.
MAX_COLLIDERS = 64

Shape = Plane | Sphere | Box | TriangleMesh


class ColliderSet:
    """The colliders of a scene, flattened for the kernels.

    Args:
        shapes: The colliders' shapes; planes first (the kernels handle up to
            :data:`UNROLLED_PLANES` leading planes without a loop, which lets the compiler
            vectorize a particle loop over them).

    Attributes:
        shapes: The shapes.
        planes: How many shapes at the start are planes.
        kinds: ``(K,)`` int64 kind codes (ColliderKind values, or :data:`MESH`).
        rows: ``(K, 10)`` float64 parameters (a primitive's table row, a mesh's index).
        mesh_offsets: ``(M, 4)`` int64: first and end node, first and end triangle of each mesh.
        node_bounds, node_links, triangle_points, triangle_normals: The meshes' trees,
            concatenated (empty arrays without meshes).
    """

    def __init__(self, shapes: Sequence[Shape]) -> None:
        self.shapes = tuple(shapes)
        count = len(self.shapes)
        self.planes = next(
            (k for k, s in enumerate(self.shapes) if not isinstance(s, Plane)), count
        )
        if any(isinstance(s, Plane) for s in self.shapes[self.planes :]):
            raise ValueError("ColliderSet takes its planes first")
        self.kinds = np.zeros(count, dtype=np.int64)
        self.rows = np.zeros((count, 10))
        trees = [s.bvh for s in self.shapes if isinstance(s, TriangleMesh)]
        for k, shape in enumerate(self.shapes):
            if isinstance(shape, TriangleMesh):
                self.kinds[k] = MESH
                self.rows[k, 0] = sum(isinstance(s, TriangleMesh) for s in self.shapes[:k])
            else:
                self.kinds[k] = int(shape.kind)
                row = shape.table_row()
                self.rows[k, : row.shape[0]] = row
        nodes = np.cumsum([0] + [t.node_bounds.shape[0] for t in trees])
        slots = np.cumsum([0] + [t.triangle_points.shape[0] for t in trees])
        self.mesh_offsets = (
            np.stack([nodes[:-1], nodes[1:], slots[:-1], slots[1:]], axis=1).astype(np.int64)
            if trees
            else np.zeros((0, 4), dtype=np.int64)
        )

        def joined(name: str, shape: tuple[int, ...], dtype: type) -> np.ndarray:
            arrays = [getattr(t, name) for t in trees]
            return (
                np.ascontiguousarray(np.concatenate(arrays)) if arrays else np.zeros(shape, dtype)
            )

        self.node_bounds = joined("node_bounds", (0, 6), np.float64)
        self.node_links = joined("node_links", (0, 2), np.int64)
        self.triangle_points = joined("triangle_points", (0, 3, 3), np.float64)
        self.triangle_normals = joined("triangle_normals", (0, 7, 3), np.float64)

    def __len__(self) -> int:
        return len(self.shapes)

    @property
    def kernel_arrays(self) -> tuple[Any, ...]:
        """``(planes, kinds, rows, mesh_offsets, node_bounds, node_links, triangle_points,
        triangle_normals)``: what the collision kernels take (:func:`collider_distance` takes
        what follows ``planes``)."""
        return (
            self.planes,
            self.kinds,
            self.rows,
            self.mesh_offsets,
            self.node_bounds,
            self.node_links,
            self.triangle_points,
            self.triangle_normals,
        )


_PLANE, _SPHERE, _BOX = int(ColliderKind.PLANE), int(ColliderKind.SPHERE), int(ColliderKind.BOX)


@njit(cache=True, error_model="numpy", inline="always")
def collider_distance(k, px, py, pz, kinds, rows, offsets, nb, nl, tp, tn):  # pragma: no cover
    """Signed distance [m] from ``p`` to collider ``k`` and the outward unit normal there.

    Rows are read entry by entry: a row view (``rows[k]``) in a parallel loop costs an atomic
    reference count per particle, ten times the arithmetic.
    """
    kind = kinds[k]
    if kind == _PLANE:
        return plane_distance(
            px, py, pz, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4], rows[k, 5],
            rows[k, 6],
        )  # fmt: skip
    if kind == _SPHERE:
        return sphere_distance(px, py, pz, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3])
    if kind == _BOX:
        return box_distance(
            px, py, pz, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4], rows[k, 5],
            rows[k, 6], rows[k, 7], rows[k, 8], rows[k, 9],
        )  # fmt: skip
    m = int(rows[k, 0])
    a, b, c, d = offsets[m, 0], offsets[m, 1], offsets[m, 2], offsets[m, 3]
    return mesh_distance(px, py, pz, nb[a:b], nl[a:b], tp[c:d], tn[c:d])


@njit(cache=True, error_model="numpy")
def collider_first_hit(
    k, x0, y0, z0, x1, y1, z1, kinds, rows, offsets, nb, nl, tp, tn
):  # pragma: no cover
    """The fraction of the segment ``x0 → x1`` at which it enters collider ``k`` (``inf``:
    never; ``0``: it starts inside)."""
    kind = kinds[k]
    if kind == _PLANE:
        return plane_first_hit(
            x0, y0, z0, x1, y1, z1, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4],
            rows[k, 5], rows[k, 6],
        )  # fmt: skip
    if kind == _SPHERE:
        return sphere_first_hit(
            x0, y0, z0, x1, y1, z1, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3]
        )
    if kind == _BOX:
        return box_first_hit(
            x0, y0, z0, x1, y1, z1, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4],
            rows[k, 5], rows[k, 6], rows[k, 7], rows[k, 8], rows[k, 9],
        )  # fmt: skip
    m = int(rows[k, 0])
    a, b, c, d = offsets[m, 0], offsets[m, 1], offsets[m, 2], offsets[m, 3]
    return mesh_first_hit(x0, y0, z0, x1, y1, z1, nb[a:b], nl[a:b], tp[c:d], tn[c:d])
