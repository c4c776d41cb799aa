"""Rigid bodies in a recording: each body's surface in its own axes, and where it is per frame.

A rigid body moves without changing shape, so a recording keeps its surface once and a
transform per frame (:mod:`visviva.simulation.recording` lists every name):

    fields/body_origin          float64 (frames, B, 3) [m]: each body's own origin (where its
                                surface's coordinates start) in the world frame. Not the centre
                                of mass, which is the state's ``body_position``:
                                ``origin + R(q) static/body_center``
    fields/body_orientation     float64 (frames, B, 4): unit quaternions (w, x, y, z), body to
                                world
    static/body_vertices        float64 (V, 3) [m]: every body's drawing surface in its own axes,
                                body after body
    static/body_triangles       int64 (T, 3): triangles, counter-clockwise seen from outside, of
                                indices into body_vertices; a body's triangles use its own
                                vertices only
    static/body_vertex_start    int64 (B + 1,): body b's vertices are rows
                                ``body_vertex_start[b] : body_vertex_start[b + 1]``
    static/body_triangle_start  int64 (B + 1,): and its triangles rows
                                ``body_triangle_start[b] : body_triangle_start[b + 1]``
    static/body_color           float64 (B, 3): sRGB colour in [0, 1] (optional)
    static/body_center          float64 (B, 3) [m]: centre of mass in the body's axes (optional)
    attrs["body_names"]         list of B strings (optional)

Vertex ``v`` of body ``b`` is at ``body_origin[k, b] + R(body_orientation[k, b]) v`` in frame
``k``: exporters write the surface once and the transform per frame, which is all a rigid
animation needs (USD xform ops, glTF node channels, the viewer's object matrices).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ..errors import ModelError
from ..geometry.quaternions import quaternion_matrix

__all__ = ["BODY_FIELDS", "BodyGeometry", "continuous_orientations"]

#: The recording's per-frame body fields and the static arrays every body recording has.
BODY_FIELDS = ("body_origin", "body_orientation")
_BODY_STATIC = ("body_vertices", "body_triangles", "body_vertex_start", "body_triangle_start")
#: Vertices transformed at once when bounding every frame: their gathered rotation matrices
#: take 72 bytes each (19 MB), whatever the number of bodies.
_VERTICES_AT_ONCE = 2**18
#: The colour drawn for a body the recording gives none (the scene entity's default too), sRGB.
DEFAULT_BODY_COLOR = (0.8, 0.8, 0.8)


@dataclass(frozen=True)
class BodyGeometry:
    """``B`` rigid bodies as a recording shows them (see the module docstring).

    Attributes:
        position: Each body's own origin [m], ``(frames, B, 3)``, world frame.
        orientation: Unit quaternions (w, x, y, z), body to world, ``(frames, B, 4)``.
        vertices: The surfaces in the bodies' own axes [m], ``(V, 3)``, body after body.
        triangles: Indices into ``vertices``, ``(T, 3)``, counter-clockwise from outside.
        vertex_start: Body ``b``'s vertex rows start at ``vertex_start[b]``, ``(B + 1,)``.
        triangle_start: Body ``b``'s triangle rows start at ``triangle_start[b]``,
            ``(B + 1,)``.
        color: sRGB colours in [0, 1], ``(B, 3)``.
        names: Each body's name.
    """

    position: np.ndarray
    orientation: np.ndarray
    vertices: np.ndarray
    triangles: np.ndarray
    vertex_start: np.ndarray
    triangle_start: np.ndarray
    color: np.ndarray
    names: tuple[str, ...]

    @property
    def count(self) -> int:
        """Number of bodies ``B``."""
        return int(self.position.shape[1])

    @cached_property
    def owner(self) -> np.ndarray:
        """The body each vertex belongs to, int64 ``(V,)``."""
        return np.repeat(np.arange(self.count), np.diff(self.vertex_start))

    def surface(self, body: int) -> tuple[np.ndarray, np.ndarray]:
        """Body ``body``'s vertices ``(V_b, 3)`` [m] in its own axes and its triangles
        ``(T_b, 3)``, numbered among its own vertices."""
        first, last = self.vertex_start[body], self.vertex_start[body + 1]
        rows = slice(self.triangle_start[body], self.triangle_start[body + 1])
        return self.vertices[first:last], self.triangles[rows] - first

    @cached_property
    def normals(self) -> np.ndarray:
        """Unit vertex normals in the bodies' own axes, ``(V, 3)``: the area-weighted sum of
        the normals of each vertex's triangles (a box's faces have vertices of their own, so
        its normals are its faces'); zero for a vertex on no triangle."""
        return vertex_normals(self.vertices, self.triangles)

    def world_vertices(self, index: int) -> np.ndarray:
        """Every vertex [m] in recorded frame ``index``, float64 ``(V, 3)``, world frame."""
        return self.transform(self.position[index], self.orientation[index], self.vertices)

    def transform(
        self, position: np.ndarray, orientation: np.ndarray, vectors: np.ndarray
    ) -> np.ndarray:
        """``position[b] + R(orientation[b]) v`` for each row ``v`` of ``vectors`` ``(V, 3)``
        (body axes) of body ``b`` = :attr:`owner`; pass zero positions to turn normals."""
        rotation = quaternion_matrix(orientation)[self.owner]  # (V, 3, 3)
        return position[self.owner] + np.einsum("vij,vj->vi", rotation, vectors)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners [m] of the box holding every body's surface in every
        frame (exact: every vertex of every frame, transformed a few frames at a time; computed
        once)."""
        low, high = self._bounds
        return low.copy(), high.copy()

    @cached_property
    def _bounds(self) -> tuple[np.ndarray, np.ndarray]:
        low, high = np.full(3, np.inf), np.full(3, -np.inf)
        if self.vertices.shape[0] == 0:
            return np.zeros(3), np.zeros(3)
        chunk = max(1, _VERTICES_AT_ONCE // self.vertices.shape[0])  # frames at once
        for first in range(0, self.position.shape[0], chunk):
            rows = slice(first, first + chunk)
            rotation = quaternion_matrix(self.orientation[rows])
            turned = np.einsum("fvij,vj->fvi", rotation[:, self.owner], self.vertices)
            world = turned + self.position[rows][:, self.owner]
            low = np.minimum(low, world.min(axis=(0, 1)))
            high = np.maximum(high, world.max(axis=(0, 1)))
        return low, high

    def nonfinite(self, frames: np.ndarray | None = None) -> tuple[int, int] | None:
        """The first (recorded frame, body) whose position or orientation is not finite,
        among ``frames`` (default: all), or ``None``."""
        chosen = np.arange(self.position.shape[0]) if frames is None else np.asarray(frames)
        finite = np.isfinite(self.position[chosen]).all(axis=2)
        finite &= np.isfinite(self.orientation[chosen]).all(axis=2)
        if finite.all():
            return None
        k, b = np.argwhere(~finite)[0]
        return int(chosen[k]), int(b)


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(V, 3)`` of counter-clockwise ``triangles``."""
    corner = vertices[triangles]
    face = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    flat = triangles.ravel()
    count = vertices.shape[0]
    normal = np.stack(
        [np.bincount(flat, np.repeat(face[:, a], 3), count) for a in range(3)], axis=1
    )
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return np.divide(normal, length, out=np.zeros_like(normal), where=length > 0.0)


def continuous_orientations(orientation: np.ndarray) -> np.ndarray:
    """``orientation`` ``(frames, B, 4)`` with signs chosen so that each quaternion lies in
    the hemisphere of the frame before (``q`` and ``−q`` are the same rotation): keyframes an
    importer interpolates then turn the short way, including those that interpolate the
    components (Blender's F-curves) rather than along the sphere."""
    q = np.asarray(orientation, dtype=np.float64)
    if q.shape[0] < 2:
        return q.copy()
    turn = np.where(np.einsum("fbi,fbi->fb", q[1:], q[:-1]) < 0.0, -1.0, 1.0)
    signs = np.concatenate([np.ones((1, q.shape[1])), np.cumprod(turn, axis=0)])
    return q * signs[..., None]


def read_bodies(
    fields: Mapping[str, np.ndarray], static: Mapping[str, np.ndarray], attrs: Mapping[str, Any]
) -> BodyGeometry | None:
    """The bodies of a recording's arrays, checked (``None`` if it has none).

    Raises:
        ModelError: If some body arrays are missing or do not fit together.
    """
    present = [n for n in (*BODY_FIELDS, *_BODY_STATIC) if n in fields or n in static]
    if not present:
        return None
    missing = [n for n in BODY_FIELDS if n not in fields] + [
        n for n in _BODY_STATIC if n not in static
    ]
    if missing:
        raise ModelError(
            f"the recording has rigid bodies ({', '.join(present)}) but not "
            f"{', '.join(missing)}; a body needs a surface and a transform per frame"
        )
    position, orientation = fields["body_origin"], fields["body_orientation"]
    frames = position.shape[0] if position.ndim == 3 else -1
    count = position.shape[1] if position.ndim == 3 else -1
    _shape("body_origin", position, (frames, count, 3))
    _shape("body_orientation", orientation, (frames, count, 4))
    vertices, triangles = static["body_vertices"], static["body_triangles"]
    _shape("body_vertices", vertices, (vertices.shape[0] if vertices.ndim else -1, 3))
    _shape("body_triangles", triangles, (triangles.shape[0] if triangles.ndim else -1, 3))
    starts = {}
    for name, rows in (("body_vertex_start", vertices), ("body_triangle_start", triangles)):
        start = np.asarray(static[name])
        _shape(name, start, (count + 1,))
        if start[0] != 0 or start[-1] != rows.shape[0] or np.any(np.diff(start) < 0):
            raise ModelError(
                f"`{name}` must rise from 0 to {rows.shape[0]} (got {start.tolist()[:8]}...)"
            )
        starts[name] = start.astype(np.int64)
    triangles = np.asarray(triangles, dtype=np.int64)
    owner = np.repeat(np.arange(count), np.diff(starts["body_triangle_start"]))
    first, last = starts["body_vertex_start"][owner], starts["body_vertex_start"][owner + 1]
    outside = (triangles < first[:, None]) | (triangles >= last[:, None])
    if outside.any():
        t = int(np.argwhere(outside)[0][0])
        raise ModelError(
            f"`body_triangles` row {t} (body {int(owner[t])}) uses vertices outside its body's "
            f"rows {int(first[t])}..{int(last[t]) - 1}"
        )
    color = static.get("body_color")
    if color is None:
        color = np.tile(DEFAULT_BODY_COLOR, (count, 1))
    _shape("body_color", color, (count, 3))
    if not (np.all(color >= 0.0) and np.all(color <= 1.0)):
        raise ModelError("`body_color` must hold sRGB values between 0 and 1")
    names = attrs.get("body_names")
    if not (isinstance(names, list) and len(names) == count):
        names = [f"body_{b:04d}" for b in range(count)]
    return BodyGeometry(
        np.asarray(position, dtype=np.float64),
        np.asarray(orientation, dtype=np.float64),
        np.asarray(vertices, dtype=np.float64),
        triangles,
        starts["body_vertex_start"],
        starts["body_triangle_start"],
        np.asarray(color, dtype=np.float64),
        tuple(str(n) for n in names),
    )


def _shape(name: str, value: np.ndarray, shape: tuple[int, ...]) -> None:
    if value.shape != shape or -1 in shape:
        wanted = "(" + ", ".join("n" if n < 0 else str(n) for n in shape) + ")"
        raise ModelError(f"`{name}` must have shape {wanted} (got {value.shape})")
