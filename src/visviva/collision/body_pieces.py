"""The collision pieces of a scene's rigid bodies and static scenery, as pooled arrays.

A body collides through one or more convex **pieces** (its shape, or the convex pieces of a
non-convex one), each fixed in the body: a piece's pose in the body's axes, measured from the
centre of mass, is ``(local_position, local_rotation)``, so that in the world it is at
``x + R(q) local_position`` turned by ``R(q) local_rotation``. Static convex scenery (a box or
a sphere collider) is a piece of body ``-1`` whose local pose is its world pose.

Hulls' arrays are pooled: piece ``p``'s vertices are ``vertices[vertex_start[p]:
vertex_start[p + 1]]``, and likewise its planes, its ``face_start`` entries (``F + 1``, counting
from 0 within the piece) and its face vertices (:mod:`~visviva.collision.convex`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import convex
from .solids import ConvexShape, posed_shape

__all__ = ["BodyPieces", "piece_shape"]


@dataclass(frozen=True, eq=False)
class BodyPieces:
    """``P`` convex pieces (module docstring); every per-piece array's first axis is the piece.

    Attributes:
        body: ``(P,)`` int64, the body each belongs to (``-1``: static scenery).
        kind: ``(P,)`` int64, the convex kinds.
        params: ``(P, 4)`` [m], ``[margin, a, b, c]``.
        local_position: ``(P, 3)`` [m]; ``local_rotation``: ``(P, 3, 3)``.
        radius: ``(P,)`` [m], the distance from the piece's origin to its farthest point.
        restitution, friction: ``(P,)`` each piece's coefficients.
        vertex_start, plane_start, face_start_start, face_vertex_start: ``(P + 1,)`` offsets
            into ``vertices`` ``(V, 3)``, ``planes`` ``(F, 4)``, ``face_start`` and
            ``face_vertices``.
    """

    body: np.ndarray
    kind: np.ndarray
    params: np.ndarray
    local_position: np.ndarray
    local_rotation: np.ndarray
    radius: np.ndarray
    restitution: np.ndarray
    friction: np.ndarray
    vertex_start: np.ndarray
    plane_start: np.ndarray
    face_start_start: np.ndarray
    face_vertex_start: np.ndarray
    vertices: np.ndarray
    planes: np.ndarray
    face_start: np.ndarray
    face_vertices: np.ndarray

    @classmethod
    def of(
        cls,
        shapes: Sequence[ConvexShape],
        body: Sequence[int],
        restitution: Sequence[float],
        friction: Sequence[float],
    ) -> BodyPieces:
        """Pieces from posed convex shapes (:mod:`~visviva.collision.solids`), each posed in
        its body's axes from the centre of mass (in the world for body ``-1``)."""
        posed = [posed_shape(s) for s in shapes]
        count = len(posed)

        def starts(sizes: list[int]) -> np.ndarray:
            return np.concatenate([[0], np.cumsum(sizes, dtype=np.int64)]).astype(np.int64)

        def pooled(index: int, width: int, dtype: type) -> np.ndarray:
            rows = [np.asarray(p[index], dtype=dtype).reshape(-1, width) for p in posed]
            if not rows:
                return np.zeros((0, width), dtype=dtype)
            return np.ascontiguousarray(np.concatenate(rows))

        radius = []
        for p in posed:
            kind, params, vertices = p[0], p[1], p[2]
            if vertices.shape[0]:
                reach = float(np.linalg.norm(vertices, axis=1).max())
            else:
                # A cone's origin is its base's centre: its apex or rim is farthest.
                cone = kind == convex.CONE
                reach = max(params[1], params[2]) if cone else float(np.linalg.norm(params[1:]))
            radius.append(reach + float(params[0]))
        return cls(
            body=np.array(body, dtype=np.int64).reshape(count),
            kind=np.array([p[0] for p in posed], dtype=np.int64),
            params=np.array([p[1] for p in posed], dtype=np.float64).reshape(count, 4),
            local_position=np.array([p[6] for p in posed], dtype=np.float64).reshape(count, 3),
            local_rotation=np.array([p[7] for p in posed], dtype=np.float64).reshape(count, 3, 3),
            radius=np.array(radius, dtype=np.float64),
            restitution=np.array(restitution, dtype=np.float64).reshape(count),
            friction=np.array(friction, dtype=np.float64).reshape(count),
            vertex_start=starts([p[2].shape[0] for p in posed]),
            plane_start=starts([p[3].shape[0] for p in posed]),
            face_start_start=starts([p[4].shape[0] for p in posed]),
            face_vertex_start=starts([p[5].shape[0] for p in posed]),
            vertices=pooled(2, 3, np.float64),
            planes=pooled(3, 4, np.float64),
            face_start=pooled(4, 1, np.int64).ravel(),
            face_vertices=pooled(5, 1, np.int64).ravel(),
        )

    @property
    def count(self) -> int:
        return int(self.body.shape[0])

    def arrays(self) -> tuple[np.ndarray, ...]:
        """The arrays :func:`piece_shape` takes, in its order."""
        return (
            self.kind, self.params, self.vertex_start, self.plane_start, self.face_start_start,
            self.face_vertex_start, self.vertices, self.planes, self.face_start,
            self.face_vertices,
        )  # fmt: skip


@njit(cache=True)
def piece_shape(p, pieces, position, rotation):
    """Piece ``p`` of the pooled ``pieces`` (:meth:`BodyPieces.arrays`) as a posed shape at the
    world ``position`` ``(3,)`` and ``rotation`` ``(3, 3)``."""
    (kind, params, vertex_start, plane_start, face_start_start, face_vertex_start,
     vertices, planes, face_start, face_vertices) = pieces  # fmt: skip
    return (
        kind[p],
        params[p],
        vertices[vertex_start[p] : vertex_start[p + 1]],
        planes[plane_start[p] : plane_start[p + 1]],
        face_start[face_start_start[p] : face_start_start[p + 1]],
        face_vertices[face_vertex_start[p] : face_vertex_start[p + 1]],
        position,
        rotation,
    )
