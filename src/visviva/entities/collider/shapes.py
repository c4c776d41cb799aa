"""A collider's table as its shape (:mod:`visviva.collision.shapes`), and its drawn surface.

Boids avoid colliders and crowds walk between them too, so the shape of a ``collider`` entity
is made here, for every kind that meets one.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...collision import Box, Plane, Sphere, TriangleMesh
from ...errors import ModelError
from ...geometry.quaternions import quaternion_matrix
from ...rigid.surfaces import body_surface, unit_sphere
from ..context import Located
from .schema import Collider

__all__ = ["collider_shape", "collider_surface"]


def collider_shape(e: Collider, where: str) -> Any:
    """The collider's shape.

    Raises:
        Located: For a shape its class refuses (a mesh that is not closed, a quaternion that
            is not a rotation).
    """
    zero = (0.0, 0.0, 0.0)
    try:
        if e.shape == "plane":
            thickness = math.inf if e.thickness is None else e.thickness
            return Plane(e.point or zero, e.normal or (0.0, 1.0, 0.0), thickness)
        if e.shape == "sphere":
            return Sphere(e.center or zero, e.radius)
        if e.shape == "box":
            return Box(e.center or zero, e.size, e.orientation or (1.0, 0.0, 0.0, 0.0))
        return TriangleMesh(np.asarray(e.vertices), np.asarray(e.triangles))
    except ModelError as error:
        raise Located(where, str(error)) from None


def collider_surface(shape: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """``(vertices (V, 3) [m], triangles (T, 3))`` of a collider shape in the world frame,
    counter-clockwise seen from outside, or ``None`` for a plane (not drawn)."""
    if isinstance(shape, Sphere):
        vertices, triangles = unit_sphere()
        return vertices * shape.radius + np.asarray(shape.center), triangles
    if isinstance(shape, Box):
        vertices, triangles = body_surface({"shape": "box", "size": shape.size})
        q = np.asarray(shape.orientation, dtype=np.float64)
        rotation = quaternion_matrix(q / np.linalg.norm(q))
        return vertices @ rotation.T + np.asarray(shape.center), triangles
    if isinstance(shape, TriangleMesh):
        return np.array(shape.vertices), np.array(shape.triangles, dtype=np.int64)
    return None
