"""Convex shapes as Numba sees them: a core, a margin, a support mapping and supporting faces.

Every convex shape is a **core** grown by a **margin** (a radius): a sphere is a point grown by
its radius, a capsule a segment grown by its radius; a box, cylinder, cone, ellipsoid or convex
hull is its own core with no margin. Distance queries work on the cores (GJK and EPA,
:mod:`~visviva.collision.gjk`, :mod:`~visviva.collision.epa`) and subtract the margins, which
keeps round shapes exact and costs no iterations on them.

A shape's geometry is the tuple ``(kind, params, vertices, planes, face_start, face_vertices)``:

``kind``
    :data:`SPHERE`, :data:`CAPSULE`, :data:`BOX`, :data:`CYLINDER`, :data:`CONE`,
    :data:`ELLIPSOID` or :data:`HULL`.
``params`` ``(4,)`` [m]
    ``[margin, a, b, c]``: a sphere's radius as margin; a capsule's radius as margin and half
    the distance between its hemispheres' centres as ``a``; a box's half extents; a cylinder's
    radius and half height; a cone's base radius and height; an ellipsoid's semi-axes.
``vertices`` ``(V, 3)``, ``planes`` ``(F, 4)``, ``face_start`` ``(F + 1,)``, ``face_vertices``
    A hull's vertices, its faces' planes ``n·x = d`` (outward unit ``n``, then ``d``) and each
    face's vertices, counter-clockwise seen from outside: face ``f`` is
    ``face_vertices[face_start[f]:face_start[f + 1]]``. Empty for the other kinds.

Coordinates are the shape's own (conventions of :mod:`visviva.rigid.primitives`: centred on
the origin, the axis of a capsule, cylinder and cone along +y, a cone's base in y = 0 and apex
at y = h). A **pose** puts a shape in the world: ``x_world = position + rotation @ x_local``,
``position`` ``(3,)`` [m] and ``rotation`` ``(3, 3)``; a **posed shape**, what the kernels
take, is the geometry's tuple followed by ``position, rotation``.

The support mapping ``s(d)`` is the point of the core farthest along ``d`` (G. van den Bergen,
*Collision Detection in Interactive 3D Environments*, 2003, §4.3); the **supporting face** is
the core's feature (face, edge or vertex) whose outward normal is closest to ``d``, the
polygon the contact manifold clips (:mod:`~visviva.collision.manifold`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "BOX",
    "CAPSULE",
    "CONE",
    "CYLINDER",
    "ELLIPSOID",
    "HULL",
    "MAX_FACE_POINTS",
    "ROUND_FACE_POINTS",
    "SPHERE",
    "core_support",
    "supporting_face",
    "world_support",
]

SPHERE = 0
CAPSULE = 1
BOX = 2
CYLINDER = 3
CONE = 4
ELLIPSOID = 5
HULL = 6

#: Points on the rim of a cylinder's cap or a cone's base that stand for the circle in a
#: manifold: eight keep a disc standing on a plane steady and cost little to clip.
ROUND_FACE_POINTS = 8
#: The most points a supporting face may have (a hull's face with more is cut to this many
#: of its vertices, evenly spread around it).
MAX_FACE_POINTS = 32


@njit(cache=True)
def core_support(kind, params, vertices, dx, dy, dz):
    """The point of the core farthest along ``(dx, dy, dz)``, shape coordinates, as 3 floats.

    Ties (a face or edge facing ``d`` exactly) go to one vertex deterministically.
    """
    if kind == SPHERE:
        return 0.0, 0.0, 0.0
    if kind == CAPSULE:
        return 0.0, (params[1] if dy >= 0.0 else -params[1]), 0.0
    if kind == BOX:
        return (
            params[1] if dx >= 0.0 else -params[1],
            params[2] if dy >= 0.0 else -params[2],
            params[3] if dz >= 0.0 else -params[3],
        )
    if kind == CYLINDER:
        radius = params[1]
        y = params[2] if dy >= 0.0 else -params[2]
        across = math.sqrt(dx * dx + dz * dz)
        if across == 0.0:
            return radius, y, 0.0
        return radius * dx / across, y, radius * dz / across
    if kind == CONE:
        # Apex (0, h, 0) or the base rim point toward d, whichever lies farther along d.
        radius = params[1]
        height = params[2]
        across = math.sqrt(dx * dx + dz * dz)
        if height * dy >= radius * across:
            return 0.0, height, 0.0
        if across == 0.0:
            return radius, 0.0, 0.0
        return radius * dx / across, 0.0, radius * dz / across
    if kind == ELLIPSOID:
        # s(d) = A² d / |A d| for the ellipsoid x·A⁻²x = 1, A = diag(a, b, c).
        ax = params[1] * dx
        by = params[2] * dy
        cz = params[3] * dz
        norm = math.sqrt(ax * ax + by * by + cz * cz)
        if norm == 0.0:
            return params[1], 0.0, 0.0
        return params[1] * ax / norm, params[2] * by / norm, params[3] * cz / norm
    best = 0
    best_value = -math.inf
    for i in range(vertices.shape[0]):
        value = vertices[i, 0] * dx + vertices[i, 1] * dy + vertices[i, 2] * dz
        if value > best_value:
            best_value = value
            best = i
    return vertices[best, 0], vertices[best, 1], vertices[best, 2]


@njit(cache=True)
def world_support(kind, params, vertices, position, rotation, dx, dy, dz):
    """The core's support point along the world direction ``d``, in world coordinates:
    ``position + R s(Rᵀ d)``."""
    lx = rotation[0, 0] * dx + rotation[1, 0] * dy + rotation[2, 0] * dz
    ly = rotation[0, 1] * dx + rotation[1, 1] * dy + rotation[2, 1] * dz
    lz = rotation[0, 2] * dx + rotation[1, 2] * dy + rotation[2, 2] * dz
    sx, sy, sz = core_support(kind, params, vertices, lx, ly, lz)
    return (
        position[0] + rotation[0, 0] * sx + rotation[0, 1] * sy + rotation[0, 2] * sz,
        position[1] + rotation[1, 0] * sx + rotation[1, 1] * sy + rotation[1, 2] * sz,
        position[2] + rotation[2, 0] * sx + rotation[2, 1] * sy + rotation[2, 2] * sz,
    )


@njit(cache=True)
def _box_face(params, dx, dy, dz, out):
    """The box face whose outward normal is nearest ``d``: 4 corners, counter-clockwise seen
    from outside, into ``out``; returns 4."""
    ax, ay, az = abs(dx), abs(dy), abs(dz)
    # The face's axis i and the two others (j, k) with (i, j, k) cyclic, so that e_j × e_k = e_i.
    if ax >= ay and ax >= az:
        i, sign = 0, 1.0 if dx >= 0.0 else -1.0
    elif ay >= az:
        i, sign = 1, 1.0 if dy >= 0.0 else -1.0
    else:
        i, sign = 2, 1.0 if dz >= 0.0 else -1.0
    j = (i + 1) % 3
    k = (i + 2) % 3
    hj = params[1 + j]
    hk = params[1 + k]
    # Corners (j, k) in the order that turns counter-clockwise about sign·e_i.
    cj = (1.0, -1.0, -1.0, 1.0)
    ck = (1.0, 1.0, -1.0, -1.0)
    for c in range(4):
        out[c, i] = sign * params[1 + i]
        out[c, j] = cj[c] * hj
        out[c, k] = sign * ck[c] * hk
    return 4


@njit(cache=True)
def _rim(radius, y, outward_sign, dx, dz, out):
    """:data:`ROUND_FACE_POINTS` points of the circle of ``radius`` at height ``y``, one of
    them toward ``(dx, dz)``, counter-clockwise seen from the side ``outward_sign`` of +y."""
    across = math.sqrt(dx * dx + dz * dz)
    start = math.atan2(dz, dx) if across > 0.0 else 0.0
    step = 2.0 * math.pi / ROUND_FACE_POINTS
    for c in range(ROUND_FACE_POINTS):
        # Counter-clockwise about +y runs from +z to +x: the angle decreases in atan2(z, x).
        angle = start - outward_sign * c * step
        out[c, 0] = radius * math.cos(angle)
        out[c, 1] = y
        out[c, 2] = radius * math.sin(angle)
    return ROUND_FACE_POINTS


@njit(cache=True)
def supporting_face(kind, params, vertices, planes, face_start, face_vertices, dx, dy, dz, out):
    """The core's feature whose outward normal is nearest the direction ``d`` (shape
    coordinates): its points into ``out`` (``(MAX_FACE_POINTS, 3)``), counter-clockwise seen
    from outside when they are a polygon; returns how many (1 for a vertex or a round
    surface, 2 for an edge, 3 or more for a face)."""
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    if norm > 0.0:
        dx, dy, dz = dx / norm, dy / norm, dz / norm
    if kind == BOX:
        return _box_face(params, dx, dy, dz, out)
    if kind in (CAPSULE, CYLINDER):
        # The side (an edge along y) or an end: whichever normal lies nearer d.
        half = params[1] if kind == CAPSULE else params[2]
        across = math.sqrt(dx * dx + dz * dz)
        if kind == CYLINDER and abs(dy) > across:
            sign = 1.0 if dy >= 0.0 else -1.0
            return _rim(params[1], sign * half, sign, dx, dz, out)
        if kind == CAPSULE and abs(dy) > 0.05:
            # A capsule's hemispherical ends touch at one point unless d is nearly across it.
            out[0, 0], out[0, 1], out[0, 2] = 0.0, (half if dy >= 0.0 else -half), 0.0
            return 1
        radius = params[1] if kind == CYLINDER else 0.0
        ux, uz = (dx / across, dz / across) if across > 0.0 else (1.0, 0.0)
        out[0, 0], out[0, 1], out[0, 2] = radius * ux, -half, radius * uz
        out[1, 0], out[1, 1], out[1, 2] = radius * ux, half, radius * uz
        return 2
    if kind == CONE:
        radius = params[1]
        height = params[2]
        across = math.sqrt(dx * dx + dz * dz)
        slant = math.sqrt(radius * radius + height * height)
        # The side's outward normal toward d is (h u, r, ...)/slant for u the unit d across.
        side = (height * across + radius * dy) / slant
        if -dy >= side:
            return _rim(radius, 0.0, -1.0, dx, dz, out)
        ux, uz = (dx / across, dz / across) if across > 0.0 else (1.0, 0.0)
        out[0, 0], out[0, 1], out[0, 2] = radius * ux, 0.0, radius * uz
        out[1, 0], out[1, 1], out[1, 2] = 0.0, height, 0.0
        return 2
    if kind == HULL:
        best = 0
        best_value = -math.inf
        for f in range(planes.shape[0]):
            value = planes[f, 0] * dx + planes[f, 1] * dy + planes[f, 2] * dz
            if value > best_value:
                best_value = value
                best = f
        first = face_start[best]
        count = face_start[best + 1] - first
        taken = min(count, MAX_FACE_POINTS)
        for c in range(taken):
            v = face_vertices[first + (c * count) // taken]
            out[c, 0], out[c, 1], out[c, 2] = vertices[v, 0], vertices[v, 1], vertices[v, 2]
        return taken
    out[0, 0], out[0, 1], out[0, 2] = core_support(kind, params, vertices, dx, dy, dz)
    return 1


def empty_hull_arrays() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The ``vertices, planes, face_start, face_vertices`` of a shape that is not a hull."""
    return (
        np.zeros((0, 3)),
        np.zeros((0, 4)),
        np.zeros(1, dtype=np.int64),
        np.zeros(0, dtype=np.int64),
    )
