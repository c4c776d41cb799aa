"""A recording's scenery: the static colliders' surfaces, drawn by every output, never moved.

Recorded once, in the world frame (:mod:`visviva.entities.collider.outputs` writes them and
says why they are not static rigid bodies):

    static/scenery_vertices        float64 (V, 3) [m], world frame, collider after collider
    static/scenery_triangles       int64 (T, 3): counter-clockwise seen from outside
    static/scenery_vertex_start    int64 (C + 1,): collider c's vertex rows
    static/scenery_triangle_start  int64 (C + 1,): collider c's triangle rows
    static/scenery_color           float64 (C, 3): sRGB in [0, 1] (optional: grey)
    attrs["scenery_names"]         list of C strings (optional)

Planes have no finite surface. Floors are the outputs' own ground; any other plane (a wall, a
ceiling, a slope) is recorded as a point and an outward normal, and the outputs draw the part
of it within their picture (:class:`Walls`, :mod:`visviva.viz.walls`):

    static/wall_point              float64 (W, 3) [m]
    static/wall_normal             float64 (W, 3): unit, towards the side things stay on
    static/wall_color              float64 (W, 3): sRGB in [0, 1]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ..entities.collider.schema import DEFAULT_SCENERY_COLOR
from ..errors import ModelError
from .body_geometry import BodyGeometry, vertex_normals

__all__ = ["SCENERY_STATIC", "Scenery", "Walls", "read_scenery", "read_walls"]

#: The static arrays a recording with scenery has (``scenery_color`` is optional).
SCENERY_STATIC = (
    "scenery_vertices",
    "scenery_triangles",
    "scenery_vertex_start",
    "scenery_triangle_start",
)


#: The static arrays of a recording's walls.
WALL_STATIC = ("wall_point", "wall_normal", "wall_color")


@dataclass(frozen=True)
class Scenery:
    """``C`` static colliders' surfaces (see the module docstring).

    Attributes:
        vertices: Every surface's vertices [m], ``(V, 3)``, world frame.
        triangles: Indices into ``vertices``, ``(T, 3)``, counter-clockwise from outside.
        vertex_start: Collider ``c``'s vertex rows start at ``vertex_start[c]``, ``(C + 1,)``.
        triangle_start: Its triangle rows start at ``triangle_start[c]``, ``(C + 1,)``.
        color: sRGB colours in [0, 1], ``(C, 3)``.
        names: Each collider's name.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    vertex_start: np.ndarray
    triangle_start: np.ndarray
    color: np.ndarray
    names: tuple[str, ...]

    @property
    def count(self) -> int:
        """Number of colliders ``C``."""
        return int(self.vertex_start.shape[0] - 1)

    def surface(self, collider: int) -> tuple[np.ndarray, np.ndarray]:
        """Collider ``collider``'s vertices ``(V_c, 3)`` [m] and its triangles ``(T_c, 3)``,
        numbered among its own vertices."""
        first, last = self.vertex_start[collider], self.vertex_start[collider + 1]
        rows = slice(self.triangle_start[collider], self.triangle_start[collider + 1])
        return self.vertices[first:last], self.triangles[rows] - first

    @cached_property
    def normals(self) -> np.ndarray:
        """Unit vertex normals, ``(V, 3)`` (area-weighted; a box's faces have vertices of
        their own, so its normals are its faces')."""
        return vertex_normals(self.vertices, self.triangles)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners [m] of the box holding every surface."""
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    def as_bodies(self) -> BodyGeometry:
        """The scenery as one frame of bodies at rest at the origin (identity transforms), for
        code that draws a body's surface (the video's body layer)."""
        count = self.count
        orientation = np.zeros((1, count, 4))
        orientation[..., 0] = 1.0
        return BodyGeometry(
            np.zeros((1, count, 3)),
            orientation,
            self.vertices,
            self.triangles,
            self.vertex_start,
            self.triangle_start,
            self.color,
            self.names,
        )


@dataclass(frozen=True)
class Walls:
    """``W`` planes other than floors: a point [m], an outward unit normal and an sRGB colour
    each, ``(W, 3)``."""

    point: np.ndarray
    normal: np.ndarray
    color: np.ndarray


def read_walls(static: Mapping[str, np.ndarray]) -> Walls | None:
    """The walls of a recording's static arrays (``None`` without any).

    Raises:
        ModelError: If they are not three finite ``(W, 3)`` arrays of one ``W``.
    """
    if "wall_point" not in static:
        return None
    arrays = [np.asarray(static.get(name, np.empty(0))) for name in WALL_STATIC]
    shape = arrays[0].shape
    if len(shape) != 2 or shape[1] != 3 or any(a.shape != shape for a in arrays):
        raise ModelError(f"`{'`, `'.join(WALL_STATIC)}` must all have one shape (W, 3)")
    if not all(np.isfinite(a).all() for a in arrays):
        raise ModelError("walls must be finite numbers")
    return Walls(*arrays)


def read_scenery(static: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> Scenery | None:
    """The scenery of a recording's static arrays, checked (``None`` if it has none).

    Raises:
        ModelError: If some scenery arrays are missing, do not fit together or are not finite.
    """
    present = [n for n in (*SCENERY_STATIC, "scenery_color") if n in static]
    if not present:
        return None
    missing = [n for n in SCENERY_STATIC if n not in static]
    if missing:
        raise ModelError(
            f"the recording has scenery ({', '.join(present)}) but not {', '.join(missing)}; "
            "record the scene again to get all of them"
        )
    vertices = np.asarray(static["scenery_vertices"])
    triangles = np.asarray(static["scenery_triangles"])
    _shape("scenery_vertices", vertices, 3)
    _shape("scenery_triangles", triangles, 3)
    if not np.isfinite(vertices).all():
        raise ModelError("`scenery_vertices` must be finite numbers [m]")
    starts = []
    for name, rows in (("scenery_vertex_start", vertices), ("scenery_triangle_start", triangles)):
        start = np.asarray(static[name])
        if (
            start.ndim != 1
            or start.shape[0] < 2
            or start[0] != 0
            or start[-1] != rows.shape[0]
            or np.any(np.diff(start) < 0)
        ):
            raise ModelError(
                f"`{name}` must rise from 0 to {rows.shape[0]} (got {start.tolist()[:8]}...)"
            )
        starts.append(start.astype(np.int64))
    vertex_start, triangle_start = starts
    count = vertex_start.shape[0] - 1
    if triangle_start.shape[0] != count + 1:
        raise ModelError(
            f"`scenery_triangle_start` must have {count + 1} entries like "
            f"`scenery_vertex_start` (got {triangle_start.shape[0]})"
        )
    triangles = triangles.astype(np.int64)
    owner = np.repeat(np.arange(count), np.diff(triangle_start))
    first, last = vertex_start[owner], vertex_start[owner + 1]
    outside = (triangles < first[:, None]) | (triangles >= last[:, None])
    if outside.any():
        t = int(np.argwhere(outside)[0][0])
        raise ModelError(
            f"`scenery_triangles` row {t} (collider {int(owner[t])}) uses vertices outside its "
            f"collider's rows {int(first[t])}..{int(last[t]) - 1}"
        )
    color = np.asarray(static.get("scenery_color", np.tile(DEFAULT_SCENERY_COLOR, (count, 1))))
    if color.shape != (count, 3) or not (np.all(color >= 0.0) and np.all(color <= 1.0)):
        raise ModelError(
            f"`scenery_color` must have shape ({count}, 3) and hold sRGB values between 0 and 1 "
            f"(got shape {color.shape})"
        )
    names = attrs.get("scenery_names")
    if not (isinstance(names, list) and len(names) == count):
        names = [f"collider_{c}" for c in range(count)]
    return Scenery(
        vertices.astype(np.float64),
        triangles,
        vertex_start,
        triangle_start,
        color.astype(np.float64),
        tuple(str(n) for n in names),
    )


def _shape(name: str, value: np.ndarray, width: int) -> None:
    if value.ndim != 2 or value.shape[1] != width:
        raise ModelError(f"`{name}` must have shape (n, {width}) (got {value.shape})")
