"""Closed triangle meshes of the primitive shapes, for tests and benchmarks of mass properties.

Each is outward (counter-clockwise seen from outside) and follows the conventions of
:mod:`visviva.rigid.primitives`: centred on the origin, axes along +y, the cone's base in the
plane y = 0. Every shape here is convex, so each triangle is oriented by turning its normal
away from an interior point.
"""

from __future__ import annotations

import numpy as np


def _outward(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    inside = vertices.mean(axis=0)
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    flip = np.einsum("ij,ij->i", normal, (a + b + c) / 3.0 - inside) < 0.0
    triangles = triangles.copy()
    triangles[flip] = triangles[flip][:, ::-1]
    return triangles


def box_mesh(extents=(1.0, 1.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """A box of full edges ``extents``, centred on the origin: 8 vertices, 12 triangles."""
    unit = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    faces = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )  # fmt: skip
    return unit * np.asarray(extents, dtype=float), faces


def cube_sphere(n: int, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A sphere: each face of a cube cut in n × n squares, every vertex pushed out to
    ``radius``; 12 n² triangles, edges about 1.6 r/n long."""
    grid = np.arange(n + 1)
    quads = []
    for axis in range(3):
        for side in (0, n):
            u, v = np.meshgrid(grid, grid, indexing="ij")
            points = np.zeros((n + 1, n + 1, 3), dtype=np.int64)
            points[..., axis] = side
            points[..., (axis + 1) % 3] = u
            points[..., (axis + 2) % 3] = v
            corners = [points[:-1, :-1], points[1:, :-1], points[1:, 1:], points[:-1, 1:]]
            quads.append(np.stack([c.reshape(-1, 3) for c in corners], axis=1))
    lattice = np.concatenate(quads)  # (6 n², 4, 3) integer corners on the cube's surface
    keys, index = np.unique(lattice.reshape(-1, 3), axis=0, return_inverse=True)
    index = index.reshape(-1, 4)
    cube = keys / n * 2.0 - 1.0
    vertices = radius * cube / np.linalg.norm(cube, axis=1, keepdims=True)
    triangles = np.concatenate([index[:, [0, 1, 2]], index[:, [0, 2, 3]]])
    return vertices, _outward(vertices, triangles)


def cylinder_mesh(radius: float, height: float, segments: int) -> tuple[np.ndarray, np.ndarray]:
    """A regular ``segments``-gon prism inscribed in the cylinder (axis y, centred), with a
    centre vertex on each cap."""
    angle = 2.0 * np.pi * np.arange(segments) / segments
    ring = np.stack([radius * np.cos(angle), np.zeros(segments), radius * np.sin(angle)], axis=1)
    top, bottom = ring + [0.0, 0.5 * height, 0.0], ring - [0.0, 0.5 * height, 0.0]
    vertices = np.vstack([bottom, top, [[0.0, -0.5 * height, 0.0], [0.0, 0.5 * height, 0.0]]])
    k = np.arange(segments)
    nxt = (k + 1) % segments
    triangles = np.concatenate(
        [
            np.stack([k, nxt, segments + nxt], axis=1),
            np.stack([k, segments + nxt, segments + k], axis=1),
            np.stack([np.full(segments, 2 * segments), nxt, k], axis=1),
            np.stack([np.full(segments, 2 * segments + 1), segments + k, segments + nxt], axis=1),
        ]
    )
    return vertices, _outward(vertices, triangles)


def cone_mesh(radius: float, height: float, segments: int) -> tuple[np.ndarray, np.ndarray]:
    """A regular ``segments``-gon pyramid inscribed in the cone (base at y = 0, apex at
    y = height)."""
    angle = 2.0 * np.pi * np.arange(segments) / segments
    ring = np.stack([radius * np.cos(angle), np.zeros(segments), radius * np.sin(angle)], axis=1)
    vertices = np.vstack([ring, [[0.0, height, 0.0], [0.0, 0.0, 0.0]]])
    k = np.arange(segments)
    nxt = (k + 1) % segments
    triangles = np.concatenate(
        [
            np.stack([k, np.full(segments, segments), nxt], axis=1),
            np.stack([k, nxt, np.full(segments, segments + 1)], axis=1),
        ]
    )
    return vertices, _outward(vertices, triangles)


def capsule_mesh(radius: float, height: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A capsule: a cube sphere of odd ``n`` (no vertex on its equator) whose upper half is
    lifted by height/2 and lower half lowered by height/2; the band of triangles across the
    equator becomes the cylinder."""
    if n % 2 == 0:
        raise ValueError("capsule_mesh needs an odd n")
    vertices, triangles = cube_sphere(n, radius)
    vertices = vertices.copy()
    vertices[:, 1] += np.where(vertices[:, 1] > 0.0, 0.5 * height, -0.5 * height)
    return vertices, triangles


def transformed(vertices: np.ndarray, rotation: np.ndarray, offset) -> np.ndarray:
    """Vertices turned by ``rotation`` about the origin, then moved by ``offset``."""
    return vertices @ np.asarray(rotation).T + np.asarray(offset, dtype=float)


def rotation_matrix(axis, angle: float) -> np.ndarray:
    """The rotation by ``angle`` [rad] about ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * cross + (1.0 - np.cos(angle)) * cross @ cross
