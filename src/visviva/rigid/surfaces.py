"""The triangles that draw a rigid body: its shape's surface in the body's own axes.

Drawing only (video, viewer, exports): the physics uses the closed forms and the mesh
integrals of :mod:`.primitives` and :mod:`.mesh_integrals`. Conventions are theirs: centred on
the origin, cylinder, capsule and cone along +y, the cone's base in the plane y = 0. Round
shapes are surfaces of revolution of a profile ``(r, y)``; a corner in the profile (a
cylinder's rim, a cone's base) is given twice, so the faces on either side get vertices of
their own and draw with a sharp edge. Triangles are counter-clockwise seen from outside.
"""

from __future__ import annotations

from collections.abc import Mapping
from itertools import pairwise
from typing import Any

import numpy as np

__all__ = ["body_surface", "unit_sphere"]

#: Segments around the axis of a round shape, and along a quarter circle of its profile.
AROUND = 32
QUARTER = 8


def body_surface(shape: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3) [m], triangles (T, 3))`` of a body's shape (a dict with ``"shape"``
    and its dimensions, or a mesh's ``"vertices"`` and ``"triangles"``)."""
    kind = shape["shape"]
    if kind == "mesh":
        return (
            np.asarray(shape["vertices"], dtype=np.float64),
            np.asarray(shape["triangles"], dtype=np.int64),
        )
    if kind == "box":
        return _box(np.asarray(shape["size"], dtype=np.float64))
    arc = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * QUARTER + 1)
    if kind in ("sphere", "ellipsoid"):
        vertices, triangles = unit_sphere()
        scale = np.full(3, shape["radius"]) if kind == "sphere" else np.asarray(shape["size"])
        return vertices * scale, triangles
    r, h = float(shape["radius"]), float(shape["height"])
    if kind == "cylinder":
        profile = [(0.0, -h / 2), (r, -h / 2), (r, -h / 2), (r, h / 2), (r, h / 2), (0.0, h / 2)]
        return _revolved(*np.array(profile).T)
    if kind == "cone":
        return _revolved(*np.array([(0.0, 0.0), (r, 0.0), (r, 0.0), (0.0, h)]).T)
    if kind == "capsule":
        lower, upper = arc[: QUARTER + 1], arc[QUARTER:]
        radii = r * np.cos(np.concatenate([lower, upper]))
        heights = r * np.sin(np.concatenate([lower, upper]))
        heights[: QUARTER + 1] -= h / 2
        heights[QUARTER + 1 :] += h / 2
        return _revolved(radii, heights)
    raise ValueError(f"no surface for shape {kind!r}")


def unit_sphere(around: int = AROUND, quarter: int = QUARTER) -> tuple[np.ndarray, np.ndarray]:
    """A sphere of radius 1 m: ``around`` segments about y, ``quarter`` along each quarter
    circle from the equator to a pole. Pushing its vertices along their directions by any
    positive amount keeps it closed and free of crossings (a star-shaped surface: each
    triangle stays inside the cone of its three directions)."""
    arc = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * quarter + 1)
    return _revolved(np.cos(arc), np.sin(arc), around)


def _box(size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Six faces of four vertices each (flat faces, sharp edges)."""
    vertices, triangles = [], []
    for axis in range(3):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        for side in (-1.0, 1.0):
            corners = []
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                corner = np.zeros(3)
                corner[axis], corner[u], corner[w] = side, a * side, b
                corners.append(corner)
            first = len(vertices)
            vertices += corners
            triangles += [[first, first + 1, first + 2], [first, first + 2, first + 3]]
    return 0.5 * np.array(vertices) * size, np.array(triangles, dtype=np.int64)


def _revolved(
    radii: np.ndarray, heights: np.ndarray, around: int = AROUND
) -> tuple[np.ndarray, np.ndarray]:
    """The surface of revolution about +y of the profile ``(radii, heights)``, bottom to top;
    a point on the axis (r = 0) is one vertex, where the neighbouring ring closes as a fan."""
    angle = np.linspace(0.0, 2.0 * np.pi, around, endpoint=False)
    rows: list[np.ndarray] = []  # each profile point's vertex indices
    vertices: list[np.ndarray] = []
    count = 0
    scale = max(float(np.max(np.abs(radii))), float(np.ptp(heights)))
    radii = np.where(np.abs(radii) <= 1e-12 * scale, 0.0, radii)  # cos(±π/2) is 6e-17, not 0
    for r, y in zip(radii, heights, strict=True):
        if r == 0.0:
            vertices.append(np.array([[0.0, y, 0.0]]))
            rows.append(np.array([count]))
            count += 1
        else:
            ring = np.stack([r * np.cos(angle), np.full(around, y), -r * np.sin(angle)], axis=1)
            vertices.append(ring)
            rows.append(np.arange(count, count + around))
            count += around
    triangles = []
    points = list(zip(radii, heights, strict=True))
    for i, (below, above) in enumerate(pairwise(rows)):
        if points[i] == points[i + 1] or (below.shape[0] == 1 and above.shape[0] == 1):
            continue  # a corner given twice: the faces on either side share no vertex
        if below.shape[0] == 1:  # a fan up from a pole
            triangles += [[below[0], above[(k + 1) % around], above[k]] for k in range(around)]
        elif above.shape[0] == 1:  # a fan closing at a pole
            triangles += [[below[k], below[(k + 1) % around], above[0]] for k in range(around)]
        else:
            for k in range(around):
                n = (k + 1) % around
                triangles += [[below[k], above[n], above[k]], [below[k], below[n], above[n]]]
    return np.concatenate(vertices), np.array(triangles, dtype=np.int64)
