"""Walls drawn as much of them as the picture needs.

A plane collider other than a floor (a ball pit's four walls, a ceiling, a slope) is
unbounded, so a recording keeps only its point and normal (:class:`~visviva.simulation.scenery.
Walls`). The outputs draw the polygon where the plane cuts the box holding everything drawn,
widened by :data:`MARGIN`: sized to the action, as a wall of a box should look. The video
draws a wall only when the camera is on the side its normal points to — the inside of a box
— so the near walls never hide what they hold and the far ones stand behind it; the web
viewer draws every wall translucent.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from ..simulation.recording import Geometry
from ..simulation.scenery import Scenery, Walls
from .frame import drawn_bounds

__all__ = ["MARGIN", "plane_in_box", "wall_scenery", "with_walls"]

#: How far a wall reaches beyond what is drawn, as a fraction of the box's size.
MARGIN = 0.1


def plane_in_box(
    point: np.ndarray, normal: np.ndarray, low: np.ndarray, high: np.ndarray
) -> np.ndarray:
    """The convex polygon ``(k, 3)`` [m] where the plane through ``point`` with ``normal`` cuts
    the box ``[low, high]``, its corners in order around it (``k`` = 0 if it misses the box)."""
    corners = np.array(list(itertools.product(*zip(low, high, strict=True))), dtype=np.float64)
    side = (corners - point) @ normal  # signed distances of the eight corners
    cuts = []
    for a, b in itertools.combinations(range(8), 2):
        if np.count_nonzero(corners[a] != corners[b]) != 1:
            continue  # not an edge of the box
        if (side[a] < 0.0) != (side[b] < 0.0):
            t = side[a] / (side[a] - side[b])
            cuts.append(corners[a] + t * (corners[b] - corners[a]))
    if len(cuts) < 3:
        return np.empty((0, 3))
    polygon = np.array(cuts)
    centre = polygon.mean(axis=0)
    u = polygon[0] - centre
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    # Counter-clockwise seen from the side the normal points to.
    order = np.argsort(np.arctan2((polygon - centre) @ v, (polygon - centre) @ u))
    return polygon[order]


def wall_scenery(
    walls: Walls, low: np.ndarray, high: np.ndarray, eye: np.ndarray | None = None
) -> Scenery | None:
    """The walls cut by the box ``[low, high]`` widened by :data:`MARGIN` (but not below the
    outputs' ground, ``y = min(0, low_y)``), as scenery (a triangle fan each); with ``eye``,
    only those the camera sees from inside."""
    pad = MARGIN * max(float(np.max(np.subtract(high, low))), 1.0)
    ground = min(0.0, float(low[1]))
    low, high = np.asarray(low, dtype=np.float64) - pad, np.asarray(high, dtype=np.float64) + pad
    low[1] = ground
    polygons, colors = [], []
    for point, normal, color in zip(walls.point, walls.normal, walls.color, strict=True):
        if eye is not None and np.dot(eye - point, normal) <= 0.0:
            continue  # seen from outside: it would hide what it holds
        polygon = plane_in_box(point, normal, low, high)
        if polygon.shape[0]:
            polygons.append(polygon)
            colors.append(color)
    if not polygons:
        return None
    counts = [p.shape[0] for p in polygons]
    vertex_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    fans = [
        [[s, s + k, s + k + 1] for k in range(1, n - 1)]
        for s, n in zip(vertex_start[:-1], counts, strict=True)
    ]
    triangles = np.concatenate(fans).astype(np.int64)
    triangle_start = np.concatenate([[0], np.cumsum([n - 2 for n in counts])]).astype(np.int64)
    return Scenery(
        np.concatenate(polygons),
        triangles,
        vertex_start,
        triangle_start,
        np.array(colors),
        tuple(f"wall {k}" for k in range(len(polygons))),
    )


def with_walls(geometry: Geometry, eye: np.ndarray) -> Geometry:
    """``geometry`` with the walls the camera at ``eye`` sees from inside added to its
    scenery (the video's way of drawing them)."""
    if geometry.walls is None:
        return geometry
    low, high = drawn_bounds(geometry)
    walls = wall_scenery(geometry.walls, low, high, eye)
    if walls is None:
        return geometry
    # Lighter than their colour, as panes: behind what they hold, they should not dominate.
    walls = dataclasses.replace(walls, color=0.55 + 0.45 * walls.color)
    return dataclasses.replace(geometry, scenery=joined(geometry.scenery, walls))


def joined(first: Scenery | None, second: Scenery) -> Scenery:
    """Two sceneries as one, ``first``'s colliders first."""
    if first is None:
        return second
    shift = first.vertices.shape[0]
    return Scenery(
        np.concatenate([first.vertices, second.vertices]),
        np.concatenate([first.triangles, second.triangles + shift]),
        np.concatenate([first.vertex_start, second.vertex_start[1:] + shift]),
        np.concatenate(
            [first.triangle_start, second.triangle_start[1:] + first.triangles.shape[0]]
        ),
        np.concatenate([first.color, second.color]),
        first.names + second.names,
    )
