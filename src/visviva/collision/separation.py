"""The signed distance between two posed convex shapes: GJK on the cores, EPA when they
overlap, the margins subtracted.

Shapes are posed shapes of :mod:`~visviva.collision.convex`. The result's convention, shared
with the contact manifold and the public queries: ``distance`` is positive when the shapes
are apart and minus the penetration depth when they overlap; ``n`` is the unit normal from A
toward B (moving B by ``−distance·n`` makes them touch); ``a`` and ``b`` are the points of A
and of B nearest the other (deepest inside the other, when they overlap), with
``b − a = distance·n``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .convex import world_support
from .epa import penetration
from .gjk import RELATIVE_TOLERANCE, SEPARATED, core_distance

__all__ = ["plane_separation", "shape_distance"]


@njit(cache=True)
def _fallback_normal(shape_a, shape_b):
    """A normal for cores that touch along a flat Minkowski difference (a point or segment
    core inside another's margin): from A's position toward B's, or +y when they coincide."""
    pa = shape_a[6]
    pb = shape_b[6]
    dx, dy, dz = pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length == 0.0:
        return 0.0, 1.0, 0.0
    return dx / length, dy / length, dz / length


@njit(cache=True)
def shape_distance(shape_a, shape_b, limit=math.inf, tolerance=RELATIVE_TOLERANCE):
    """``(distance, nx, ny, nz, ax, ay, az, bx, by, bz)`` of two posed convex shapes (module
    docstring for the convention), lengths in metres, world frame. Shapes surely farther
    apart than ``limit`` [m] get a lower bound of their distance (above ``limit``) and
    points and normal of no meaning; ``tolerance`` is GJK's
    (:func:`~visviva.collision.gjk.core_distance`)."""
    kind_a, params_a, vertices_a, _, _, _, position_a, rotation_a = shape_a
    kind_b, params_b, vertices_b, _, _, _, position_b, rotation_b = shape_b
    margin_a = params_a[0]
    margin_b = params_b[0]
    simplex = np.empty((4, 3))
    simplex_a = np.empty((4, 3))
    simplex_b = np.empty((4, 3))
    status, core, count, ax, ay, az, bx, by, bz = core_distance(
        kind_a, params_a, vertices_a, position_a, rotation_a,
        kind_b, params_b, vertices_b, position_b, rotation_b,
        simplex, simplex_a, simplex_b, limit + margin_a + margin_b, tolerance,
    )  # fmt: skip
    if status == SEPARATED and core - margin_a - margin_b > limit:
        return core - margin_a - margin_b, 0.0, 0.0, 0.0, ax, ay, az, bx, by, bz
    if status == SEPARATED and core > 0.0:
        nx, ny, nz = (bx - ax) / core, (by - ay) / core, (bz - az) / core
    else:
        ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz = penetration(
            shape_a, shape_b, simplex, simplex_a, simplex_b, count
        )
        core = -depth
        if not ok:
            nx, ny, nz = _fallback_normal(shape_a, shape_b)
            if status != SEPARATED:
                # The flat difference's own point nearest the origin: the cores cross at it.
                ax, ay, az = simplex_a[0, 0], simplex_a[0, 1], simplex_a[0, 2]
                bx, by, bz = ax, ay, az
    return (
        core - margin_a - margin_b,
        nx, ny, nz,
        ax + margin_a * nx, ay + margin_a * ny, az + margin_a * nz,
        bx - margin_b * nx, by - margin_b * ny, bz - margin_b * nz,
    )  # fmt: skip


@njit(cache=True)
def plane_separation(point, normal, thickness, shape):
    """:func:`shape_distance` of a plane slab A (``point`` on its outer face, outward unit
    ``normal``, ``thickness`` [m], ``inf`` for a half-space; see
    :class:`~visviva.collision.shapes.Plane`) and a posed convex shape B.

    The slab is the region ``−thickness ≤ (x − point)·n ≤ 0``; B pushed out of it leaves
    through the nearer face, so the normal is ``n`` or, for B below a thin slab's middle, −n.
    """
    kind, params, vertices, _, _, _, position, rotation = shape
    nx, ny, nz = normal[0], normal[1], normal[2]
    # B's lowest and highest points along n, heights above the outer face.
    lx, ly, lz = world_support(kind, params, vertices, position, rotation, -nx, -ny, -nz)
    hx, hy, hz = world_support(kind, params, vertices, position, rotation, nx, ny, nz)
    margin = params[0]
    low = (lx - point[0]) * nx + (ly - point[1]) * ny + (lz - point[2]) * nz - margin
    high = (hx - point[0]) * nx + (hy - point[1]) * ny + (hz - point[2]) * nz + margin
    # Out through the top costs −low; out through the bottom costs high + thickness.
    if -low <= high + thickness:
        bx, by, bz = lx - margin * nx, ly - margin * ny, lz - margin * nz
        distance = low
        sign = 1.0
    else:
        bx, by, bz = hx + margin * nx, hy + margin * ny, hz + margin * nz
        distance = -(high + thickness)
        sign = -1.0
    # A's point: B's extreme point projected on the face it leaves through.
    ax = bx - sign * distance * nx
    ay = by - sign * distance * ny
    az = bz - sign * distance * nz
    return (
        distance,
        sign * nx, sign * ny, sign * nz,
        ax, ay, az,
        bx, by, bz,
    )  # fmt: skip
