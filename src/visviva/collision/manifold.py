"""The contact manifold of two convex shapes: the points where they touch, from one normal.

One closest-point pair holds a box on a table by a single corner: the box rocks and sinks. A
solver needs the whole patch, so here the normal ``n`` from :mod:`~visviva.collision.separation`
picks each shape's **supporting face** along it (a face, an edge or a vertex of the core, grown
by the margin; :func:`~visviva.collision.convex.supporting_face`). The face better aligned with
``n`` is the **reference**; the other, the **incident** face, is clipped against the side
planes of the reference face (Sutherland–Hodgman), and the clipped points within
``max_separation`` of the reference face's plane are the contacts, each with its own depth.
This is the "reference face / incident face" clipping of game physics engines (E. Catto, "Contact
manifolds", GDC 2007; D. Gregorius, "Robust contact creation for physics simulations", GDC
2015). More than :data:`MAX_CONTACTS` points are reduced to the deepest one and those that
span the largest area around it, which hold the shape as well as all of them.

Two edges (a capsule on a capsule) give the overlap of their segments when they are parallel;
a vertex or a round surface gives the one closest-point pair.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .convex import MAX_FACE_POINTS, supporting_face

__all__ = ["CANDIDATES", "MAX_CONTACTS", "clip_polygon", "contact_manifold", "plane_manifold"]

#: The most contacts one pair of convex shapes gets: four span any flat patch.
MAX_CONTACTS = 4
#: Edges whose directions' cosine exceeds this are parallel (the manifold keeps two points).
PARALLEL = 0.995
#: A face is a reference only if its normal is this near the contact normal (cosine, about
#: 11°): a box's nearest face 45° off a normal that comes from one of its edges would push
#: along the wrong direction and measure the wrong depth; the nearest points stand then.
ALIGNED = 0.98
#: A clipped patch whose deepest point is shallower than the shapes' depth by more than this
#: fraction of it has lost its deepest point (see :func:`contact_manifold`).
LOST_DEPTH = 0.1
#: Rows of the work arrays a manifold is built in: every clipped point before the reduction.
CANDIDATES = 2 * MAX_FACE_POINTS + 8


@njit(cache=True)
def _world_face(shape, dx, dy, dz, shift, out):
    """The posed shape's supporting face along the world direction ``d``, in world
    coordinates, moved ``shift`` along ``d`` (the margin); returns the point count."""
    kind, params, vertices, planes, face_start, face_vertices, position, rotation = shape
    lx = rotation[0, 0] * dx + rotation[1, 0] * dy + rotation[2, 0] * dz
    ly = rotation[0, 1] * dx + rotation[1, 1] * dy + rotation[2, 1] * dz
    lz = rotation[0, 2] * dx + rotation[1, 2] * dy + rotation[2, 2] * dz
    local = np.empty((MAX_FACE_POINTS, 3))
    count = supporting_face(kind, params, vertices, planes, face_start, face_vertices,
                            lx, ly, lz, local)  # fmt: skip
    for i in range(count):
        for r in range(3):
            out[i, r] = (
                position[r]
                + rotation[r, 0] * local[i, 0]
                + rotation[r, 1] * local[i, 1]
                + rotation[r, 2] * local[i, 2]
            )
        out[i, 0] += shift * dx
        out[i, 1] += shift * dy
        out[i, 2] += shift * dz
    return count


@njit(cache=True)
def _polygon_normal(points, count):
    """Newell's unit normal of a polygon (counter-clockwise about it)."""
    nx = ny = nz = 0.0
    for i in range(count):
        j = (i + 1) % count
        nx += (points[i, 1] - points[j, 1]) * (points[i, 2] + points[j, 2])
        ny += (points[i, 2] - points[j, 2]) * (points[i, 0] + points[j, 0])
        nz += (points[i, 0] - points[j, 0]) * (points[i, 1] + points[j, 1])
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    if length == 0.0:
        return 0.0, 0.0, 0.0
    return nx / length, ny / length, nz / length


@njit(cache=True)
def clip_polygon(points, count, ox, oy, oz, sx, sy, sz, out):
    """Sutherland–Hodgman: the part of polygon (or segment, or point) ``points[:count]`` on the
    side ``s·(p − o) ≤ 0`` of a plane, into ``out``; returns its count."""
    kept = 0
    if count == 1:
        if sx * (points[0, 0] - ox) + sy * (points[0, 1] - oy) + sz * (points[0, 2] - oz) <= 0.0:
            out[0, :] = points[0, :]
            kept = 1
        return kept
    edges = count if count > 2 else 1
    for i in range(edges):
        j = (i + 1) % count
        di = sx * (points[i, 0] - ox) + sy * (points[i, 1] - oy) + sz * (points[i, 2] - oz)
        dj = sx * (points[j, 0] - ox) + sy * (points[j, 1] - oy) + sz * (points[j, 2] - oz)
        if di <= 0.0:
            out[kept, :] = points[i, :]
            kept += 1
        if (di < 0.0 < dj) or (dj < 0.0 < di):
            t = di / (di - dj)
            for c in range(3):
                out[kept, c] = points[i, c] + t * (points[j, c] - points[i, c])
            kept += 1
        if count == 2 and dj <= 0.0:
            out[kept, :] = points[j, :]
            kept += 1
    return kept


@njit(cache=True)
def _reduce(points, depths, count):
    """Keep :data:`MAX_CONTACTS` of ``count`` contacts: the deepest, the farthest from it, then
    each point that adds the most area; in place, returns the new count."""
    if count <= MAX_CONTACTS:
        return count
    chosen = np.full(MAX_CONTACTS, -1, dtype=np.int64)
    chosen[0] = int(np.argmax(depths[:count]))
    best = -1.0
    for i in range(count):
        d = np.sum((points[i] - points[chosen[0]]) ** 2)
        if d > best:
            best = d
            chosen[1] = i
    a = points[chosen[0]]
    b = points[chosen[1]]
    # Third: the largest triangle with the first two; fourth: the largest area added outside.
    best = -1.0
    for i in range(count):
        area = np.sum(np.cross(b - a, points[i] - a) ** 2)
        if area > best:
            best = area
            chosen[2] = i
    c = points[chosen[2]]
    normal = np.cross(b - a, c - a)
    best = -math.inf
    for i in range(count):
        p = points[i]
        # The signed areas the point adds beyond each edge of triangle a b c.
        added = min(
            np.dot(np.cross(b - a, p - a), normal),
            np.dot(np.cross(c - b, p - b), normal),
            np.dot(np.cross(a - c, p - c), normal),
        )
        if -added > best and i != chosen[0] and i != chosen[1] and i != chosen[2]:
            best = -added
            chosen[3] = i
    kept_points = np.empty((MAX_CONTACTS, 3))
    kept_depths = np.empty(MAX_CONTACTS)
    n = 0
    for k in range(MAX_CONTACTS):
        if chosen[k] >= 0:
            kept_points[n] = points[chosen[k]]
            kept_depths[n] = depths[chosen[k]]
            n += 1
    points[:n] = kept_points[:n]
    depths[:n] = kept_depths[:n]
    return n


@njit(cache=True)
def contact_manifold(shape_a, shape_b, separation, max_separation, points, depths):
    """Contacts of two posed convex shapes (:mod:`~visviva.collision.convex`) given their
    ``separation`` ``(distance, nx, ny, nz, ax, ay, az, bx, by, bz)`` from
    :func:`~visviva.collision.separation.shape_distance`.

    Args:
        max_separation: Keep contacts whose gap is at most this [m] (0 for touching or
            overlapping only; a small positive value gives speculative contacts).
        points: ``(CANDIDATES, 3)`` output, the contact points [m] (midway between the
            surfaces) in its first ``count`` rows.
        depths: ``(CANDIDATES,)`` output, each point's penetration depth [m] (negative:
            a gap).

    Returns:
        ``(count, nx, ny, nz)``: how many contacts and their common unit normal, from A
        toward B.
    """
    distance, nx, ny, nz, ax, ay, az, bx, by, bz = separation
    if distance > max_separation:
        return 0, nx, ny, nz
    face_a = np.empty((MAX_FACE_POINTS, 3))
    face_b = np.empty((MAX_FACE_POINTS, 3))
    count_a = _world_face(shape_a, nx, ny, nz, shape_a[1][0], face_a)
    count_b = _world_face(shape_b, -nx, -ny, -nz, shape_b[1][0], face_b)
    ra = rb = -1.0
    if count_a >= 3:
        rx, ry, rz = _polygon_normal(face_a, count_a)
        ra = rx * nx + ry * ny + rz * nz
    if count_b >= 3:
        rx, ry, rz = _polygon_normal(face_b, count_b)
        rb = -(rx * nx + ry * ny + rz * nz)
    if max(ra, rb) >= ALIGNED:
        if ra >= rb:
            reference, reference_count, incident, incident_count = face_a, count_a, face_b, count_b
            sign = 1.0
        else:
            reference, reference_count, incident, incident_count = face_b, count_b, face_a, count_a
            sign = -1.0
        rx, ry, rz = _polygon_normal(reference, reference_count)
        if rx * rx + ry * ry + rz * rz > 0.0:
            count = _clip_to_face(reference, reference_count, rx, ry, rz, incident,
                                  incident_count, max_separation, points, depths)  # fmt: skip
            if count > 0:
                nx, ny, nz = sign * rx, sign * ry, sign * rz
                # The deepest point may lie beside the reference face and be clipped away (a
                # corner of one rock in another, off its face's edge): the nearest points'
                # pair is then a contact too, with its depth along this normal.
                deepest = depths[:count].max()
                if deepest < -distance - LOST_DEPTH * abs(distance) and count < CANDIDATES:
                    points[count, 0] = 0.5 * (ax + bx)
                    points[count, 1] = 0.5 * (ay + by)
                    points[count, 2] = 0.5 * (az + bz)
                    depths[count] = (ax - bx) * nx + (ay - by) * ny + (az - bz) * nz
                    count += 1
                return _reduce(points, depths, count), nx, ny, nz
    elif count_a == 2 and count_b == 2:
        count = _parallel_edges(face_a, face_b, nx, ny, nz, points, depths)
        if count > 0:
            return count, nx, ny, nz
    points[0, 0] = 0.5 * (ax + bx)
    points[0, 1] = 0.5 * (ay + by)
    points[0, 2] = 0.5 * (az + bz)
    depths[0] = -distance
    return 1, nx, ny, nz


@njit(cache=True)
def _clip_to_face(reference, reference_count, rx, ry, rz, incident, incident_count,
                  max_separation, points, depths):  # fmt: skip
    """Clip the incident face to the reference face's side planes and keep the points within
    ``max_separation`` of its plane (outward normal ``r``); returns how many."""
    work = np.empty((CANDIDATES, 3))
    other = np.empty((CANDIDATES, 3))
    count = incident_count
    work[:count] = incident[:count]
    for i in range(reference_count):
        j = (i + 1) % reference_count
        ex = reference[j, 0] - reference[i, 0]
        ey = reference[j, 1] - reference[i, 1]
        ez = reference[j, 2] - reference[i, 2]
        # The side plane's outward normal: edge × face normal, for a counter-clockwise face.
        sx = ey * rz - ez * ry
        sy = ez * rx - ex * rz
        sz = ex * ry - ey * rx
        count = clip_polygon(work, count, reference[i, 0], reference[i, 1], reference[i, 2],
                      sx, sy, sz, other)  # fmt: skip
        work, other = other, work
        if count == 0:
            return 0
    kept = 0
    for i in range(count):
        gap = (
            rx * (work[i, 0] - reference[0, 0])
            + ry * (work[i, 1] - reference[0, 1])
            + rz * (work[i, 2] - reference[0, 2])
        )
        if gap <= max_separation:
            points[kept, 0] = work[i, 0] - 0.5 * gap * rx
            points[kept, 1] = work[i, 1] - 0.5 * gap * ry
            points[kept, 2] = work[i, 2] - 0.5 * gap * rz
            depths[kept] = -gap
            kept += 1
    return kept


@njit(cache=True)
def _parallel_edges(face_a, face_b, nx, ny, nz, points, depths):
    """Two contacts where parallel edges overlap (a capsule lying along a capsule); 0 when
    they are not parallel or do not overlap."""
    ex, ey, ez = (
        face_a[1, 0] - face_a[0, 0],
        face_a[1, 1] - face_a[0, 1],
        face_a[1, 2] - face_a[0, 2],
    )
    fx, fy, fz = (
        face_b[1, 0] - face_b[0, 0],
        face_b[1, 1] - face_b[0, 1],
        face_b[1, 2] - face_b[0, 2],
    )
    le = math.sqrt(ex * ex + ey * ey + ez * ez)
    lf = math.sqrt(fx * fx + fy * fy + fz * fz)
    if le == 0.0 or lf == 0.0 or abs(ex * fx + ey * fy + ez * fz) < PARALLEL * le * lf:
        return 0
    ux, uy, uz = ex / le, ey / le, ez / le
    # B's endpoints along A's edge, clipped to A's extent [0, le].
    t0 = (
        (face_b[0, 0] - face_a[0, 0]) * ux
        + (face_b[0, 1] - face_a[0, 1]) * uy
        + (face_b[0, 2] - face_a[0, 2]) * uz
    )
    t1 = (
        (face_b[1, 0] - face_a[0, 0]) * ux
        + (face_b[1, 1] - face_a[0, 1]) * uy
        + (face_b[1, 2] - face_a[0, 2]) * uz
    )
    lo = max(min(t0, t1), 0.0)
    hi = min(max(t0, t1), le)
    if lo > hi:
        return 0
    for k in range(2):
        t = lo if k == 0 else hi
        px = face_a[0, 0] + t * ux
        py = face_a[0, 1] + t * uy
        pz = face_a[0, 2] + t * uz
        # B's edge point at the same place along the edges, and the gap between them along n.
        s = (t - t0) / (t1 - t0) if t1 != t0 else 0.0
        qx = face_b[0, 0] + s * fx
        qy = face_b[0, 1] + s * fy
        qz = face_b[0, 2] + s * fz
        gap = (qx - px) * nx + (qy - py) * ny + (qz - pz) * nz
        points[k, 0] = 0.5 * (px + qx)
        points[k, 1] = 0.5 * (py + qy)
        points[k, 2] = 0.5 * (pz + qz)
        depths[k] = -gap
    return 2


@njit(cache=True)
def plane_manifold(separation, shape_b, max_separation, points, depths):
    """Contacts of a plane slab A and a posed convex shape B, given their ``separation`` from
    :func:`~visviva.collision.separation.plane_separation`: the points of B's supporting face
    within ``max_separation`` of the plane. Arguments and result as
    :func:`contact_manifold`."""
    distance, nx, ny, nz, ax, ay, az, bx, by, bz = separation
    if distance > max_separation:
        return 0, nx, ny, nz
    face = np.empty((MAX_FACE_POINTS, 3))
    count = _world_face(shape_b, -nx, -ny, -nz, shape_b[1][0], face)
    kept = 0
    for i in range(count):
        # The gap is measured from the face through a (the plane's point on it).
        gap = (face[i, 0] - ax) * nx + (face[i, 1] - ay) * ny + (face[i, 2] - az) * nz
        if gap <= max_separation:
            points[kept, 0] = face[i, 0] - 0.5 * gap * nx
            points[kept, 1] = face[i, 1] - 0.5 * gap * ny
            points[kept, 2] = face[i, 2] - 0.5 * gap * nz
            depths[kept] = -gap
            kept += 1
    if kept == 0:
        points[0, 0], points[0, 1], points[0, 2] = 0.5 * (ax + bx), 0.5 * (ay + by), 0.5 * (az + bz)
        depths[0] = -distance
        kept = 1
    return _reduce(points, depths, kept), nx, ny, nz
