"""Collider tables: every collider of one kind as one float64 array, and queries over them.

A collision kernel loops over particles and, for each, over every collider of a kind. The
colliders' parameters therefore come as one C-contiguous float64 table per kind, one row per
collider (world frame, metres):

============  =====  ==========================================================================
kind          width  columns
============  =====  ==========================================================================
``PLANE``     7      point (3), unit outward normal (3), thickness (``inf``: half-space)
``SPHERE``    4      centre (3), radius
``BOX``       10     centre (3), half extents (3), unit quaternion (w, x, y, z) box → world
============  =====  ==========================================================================

:func:`collider_table` builds a table from shapes. The Numba functions ``planes_distance``,
``spheres_distance``, ``boxes_distance`` return the smallest signed distance over the table's
rows with its normal and row index; ``planes_first_hit`` etc. the earliest segment entry and
its row. For overlapping colliders the smallest distance is the exact distance to their union
outside it; inside, it is the deepest penetration among the colliders holding the point (a
bound of the union's depth). An empty table gives ``(inf, 0, 0, 0, −1)`` and ``(inf, −1)``.

:func:`collider_distances` and :func:`collider_first_hits` run those over many points, in
parallel from :data:`PARALLEL_MIN_POINTS` points up. Rows are trusted, not checked, by the
kernels: make them with :func:`collider_table` from validated shapes (a plane's normal and a
box's quaternion must be unit length; half extents and radii positive).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np
from numba import njit, prange

from .._validation import describe
from ..errors import ModelError
from .queries import (
    box_distance,
    box_first_hit,
    plane_distance,
    plane_first_hit,
    sphere_distance,
    sphere_first_hit,
)

__all__ = [
    "PARALLEL_MIN_POINTS",
    "ColliderKind",
    "boxes_distance",
    "boxes_first_hit",
    "check_points",
    "collider_distances",
    "collider_first_hits",
    "collider_table",
    "planes_distance",
    "planes_first_hit",
    "spheres_distance",
    "spheres_first_hit",
]

#: Fewest points for which the vectorized queries use every core: starting a parallel region
#: costs 10–90 µs, the time of a few thousand serial point queries.
PARALLEL_MIN_POINTS = 4096


class ColliderKind(enum.IntEnum):
    """The primitive collider kinds; ``width`` is the number of columns of their table."""

    PLANE = 0
    SPHERE = 1
    BOX = 2

    @property
    def width(self) -> int:
        """Columns of this kind's table row."""
        return (7, 4, 10)[self.value]


class Collider(Protocol):
    """What :func:`collider_table` needs of a shape (Plane, Sphere and Box provide it)."""

    kind: ColliderKind

    def table_row(self) -> np.ndarray: ...


def collider_table(shapes: Sequence[Collider]) -> np.ndarray:
    """Stack the table rows of colliders of one kind into a ``(K, width)`` float64 array.

    Args:
        shapes: Planes, spheres or boxes, all of one kind; at least one (the kind of an
            empty table is unknown: make it with ``np.empty((0, kind.width))``).

    Raises:
        ModelError: If there are no shapes, or shapes of different kinds.
    """
    if not shapes:
        raise ModelError("`shapes` must hold at least one collider to make a table (got none)")
    kind = shapes[0].kind
    for index, shape in enumerate(shapes):
        if shape.kind != kind:
            raise ModelError(
                f"`shapes` must all be of one kind to share a table: entry 0 is a "
                f"{kind.name.lower()}, entry {index} a {shape.kind.name.lower()}; make one table "
                "per kind"
            )
    return np.ascontiguousarray(np.stack([shape.table_row() for shape in shapes]))


def check_points(name: str, value: Any) -> np.ndarray:
    """``value`` as a C-contiguous float64 ``(N, 3)`` array of finite points [m].

    A single point of shape ``(3,)`` is taken as ``(1, 3)``.
    """
    try:
        points = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ModelError(f"`{name}` must be an (N, 3) array of points [m]") from exc
    if points.ndim == 1 and points.shape[0] == 3:
        points = points.reshape(1, 3)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ModelError(f"`{name}` must have shape (N, 3) (got shape {points.shape})")
    bad = ~np.isfinite(points)
    if bad.any():
        row = int(np.argwhere(bad)[0, 0])
        raise ModelError(f"`{name}` must be finite; point {row} is {describe(points[row])}")
    return points


@njit(cache=True)
def planes_distance(px, py, pz, planes):  # pragma: no cover - compiled
    """Smallest signed distance to the rows of a ``(K, 7)`` plane table: ``(d, gx, gy, gz, k)``."""
    best, bx, by, bz, best_row = math.inf, 0.0, 0.0, 0.0, -1
    for k in range(planes.shape[0]):
        r = planes[k]
        d, gx, gy, gz = plane_distance(px, py, pz, r[0], r[1], r[2], r[3], r[4], r[5], r[6])
        if d < best:
            best, bx, by, bz, best_row = d, gx, gy, gz, k
    return best, bx, by, bz, best_row


@njit(cache=True)
def spheres_distance(px, py, pz, spheres):  # pragma: no cover - compiled
    """Smallest signed distance to the rows of a ``(K, 4)`` sphere table: ``(d, gx, gy, gz, k)``."""
    best, bx, by, bz, best_row = math.inf, 0.0, 0.0, 0.0, -1
    for k in range(spheres.shape[0]):
        r = spheres[k]
        d, gx, gy, gz = sphere_distance(px, py, pz, r[0], r[1], r[2], r[3])
        if d < best:
            best, bx, by, bz, best_row = d, gx, gy, gz, k
    return best, bx, by, bz, best_row


@njit(cache=True)
def boxes_distance(px, py, pz, boxes):  # pragma: no cover - compiled
    """Smallest signed distance to the rows of a ``(K, 10)`` box table: ``(d, gx, gy, gz, k)``."""
    best, bx, by, bz, best_row = math.inf, 0.0, 0.0, 0.0, -1
    for k in range(boxes.shape[0]):
        r = boxes[k]
        d, gx, gy, gz = box_distance(
            px, py, pz, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9]
        )
        if d < best:
            best, bx, by, bz, best_row = d, gx, gy, gz, k
    return best, bx, by, bz, best_row


@njit(cache=True)
def planes_first_hit(x0, y0, z0, x1, y1, z1, planes):  # pragma: no cover - compiled
    """Earliest entry of the segment ``x0 → x1`` into the rows of a plane table: ``(s, k)``."""
    best, best_row = math.inf, -1
    for k in range(planes.shape[0]):
        r = planes[k]
        s = plane_first_hit(x0, y0, z0, x1, y1, z1, r[0], r[1], r[2], r[3], r[4], r[5], r[6])
        if s < best:
            best, best_row = s, k
    return best, best_row


@njit(cache=True)
def spheres_first_hit(x0, y0, z0, x1, y1, z1, spheres):  # pragma: no cover - compiled
    """Earliest entry of the segment ``x0 → x1`` into the rows of a sphere table: ``(s, k)``."""
    best, best_row = math.inf, -1
    for k in range(spheres.shape[0]):
        r = spheres[k]
        s = sphere_first_hit(x0, y0, z0, x1, y1, z1, r[0], r[1], r[2], r[3])
        if s < best:
            best, best_row = s, k
    return best, best_row


@njit(cache=True)
def boxes_first_hit(x0, y0, z0, x1, y1, z1, boxes):  # pragma: no cover - compiled
    """Earliest entry of the segment ``x0 → x1`` into the rows of a box table: ``(s, k)``."""
    best, best_row = math.inf, -1
    for k in range(boxes.shape[0]):
        r = boxes[k]
        s = box_first_hit(
            x0, y0, z0, x1, y1, z1, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9]
        )
        if s < best:
            best, best_row = s, k
    return best, best_row


@njit(cache=True)
def _distance_into(points, kind, table, distance, normal, row, i):  # pragma: no cover
    """Write point ``i``'s query against the table of ``kind`` into the output arrays."""
    px, py, pz = points[i, 0], points[i, 1], points[i, 2]
    if kind == 0:
        d, gx, gy, gz, k = planes_distance(px, py, pz, table)
    elif kind == 1:
        d, gx, gy, gz, k = spheres_distance(px, py, pz, table)
    else:
        d, gx, gy, gz, k = boxes_distance(px, py, pz, table)
    distance[i] = d
    normal[i, 0] = gx
    normal[i, 1] = gy
    normal[i, 2] = gz
    row[i] = k


@njit(cache=True)
def _hit_into(start, end, kind, table, fraction, row, i):  # pragma: no cover - compiled
    """Write segment ``i``'s first hit against the table of ``kind`` into the output arrays."""
    x0, y0, z0 = start[i, 0], start[i, 1], start[i, 2]
    x1, y1, z1 = end[i, 0], end[i, 1], end[i, 2]
    if kind == 0:
        s, k = planes_first_hit(x0, y0, z0, x1, y1, z1, table)
    elif kind == 1:
        s, k = spheres_first_hit(x0, y0, z0, x1, y1, z1, table)
    else:
        s, k = boxes_first_hit(x0, y0, z0, x1, y1, z1, table)
    fraction[i] = s
    row[i] = k


# Serial and parallel drivers are separate functions (not one function compiled twice) so that
# each has its own entry in Numba's on-disk cache.
@njit(cache=True)
def _distances_serial(points, kind, table, distance, normal, row):  # pragma: no cover
    for i in range(points.shape[0]):
        _distance_into(points, kind, table, distance, normal, row, i)


@njit(cache=True, parallel=True)
def _distances_parallel(points, kind, table, distance, normal, row):  # pragma: no cover
    for i in prange(points.shape[0]):
        _distance_into(points, kind, table, distance, normal, row, i)


@njit(cache=True)
def _hits_serial(start, end, kind, table, fraction, row):  # pragma: no cover - compiled
    for i in range(start.shape[0]):
        _hit_into(start, end, kind, table, fraction, row, i)


@njit(cache=True, parallel=True)
def _hits_parallel(start, end, kind, table, fraction, row):  # pragma: no cover - compiled
    for i in prange(start.shape[0]):
        _hit_into(start, end, kind, table, fraction, row, i)


def _check_table(kind: ColliderKind, table: Any) -> np.ndarray:
    if not isinstance(kind, ColliderKind):
        raise ModelError(
            f"`kind` must be a ColliderKind ({', '.join(k.name for k in ColliderKind)}) "
            f"(got {describe(kind)})"
        )
    array = np.ascontiguousarray(table, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != kind.width:
        raise ModelError(
            f"`table` of {kind.name.lower()} colliders must have shape (K, {kind.width}) "
            f"(got shape {array.shape}); build it with collider_table()"
        )
    return array


def collider_distances(
    kind: ColliderKind, table: np.ndarray, points: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance from each point to the nearest collider of a table.

    Args:
        kind: The kind of collider the table holds.
        table: ``(K, kind.width)`` table (see the module docstring).
        points: ``(N, 3)`` points [m], world frame.

    Returns:
        ``distance`` [m] shape ``(N,)``, negative inside; ``normal`` ``(N, 3)`` outward unit
        normals at the closest surface point; ``row`` ``(N,)`` the nearest collider's row.
    """
    table = _check_table(kind, table)
    points = check_points("points", points)
    n = points.shape[0]
    distance = np.empty(n)
    normal = np.empty((n, 3))
    row = np.empty(n, dtype=np.int64)
    run = _distances_parallel if n >= PARALLEL_MIN_POINTS else _distances_serial
    run(points, int(kind), table, distance, normal, row)
    return distance, normal, row


def collider_first_hits(
    kind: ColliderKind, table: np.ndarray, start: Any, end: Any
) -> tuple[np.ndarray, np.ndarray]:
    """First entry of each segment ``start → end`` into any collider of a table.

    Args:
        kind: The kind of collider the table holds.
        table: ``(K, kind.width)`` table (see the module docstring).
        start: ``(N, 3)`` segment starts [m], world frame.
        end: ``(N, 3)`` segment ends [m].

    Returns:
        ``fraction`` ``(N,)``: the smallest ``s`` in [0, 1] with ``start + s (end − start)`` in
        a collider (0 for a start inside, ``inf`` for a miss); ``row`` ``(N,)`` that collider.
    """
    table = _check_table(kind, table)
    start = check_points("start", start)
    end = check_points("end", end)
    if start.shape != end.shape:
        raise ModelError(
            f"`start` and `end` must have the same shape (got {start.shape} and {end.shape})"
        )
    n = start.shape[0]
    fraction = np.empty(n)
    row = np.empty(n, dtype=np.int64)
    run = _hits_parallel if n >= PARALLEL_MIN_POINTS else _hits_serial
    run(start, end, int(kind), table, fraction, row)
    return fraction, row
