"""The contacts of two boxes, analytically: separating axes, then face clipping or two edges.

Two boxes are apart exactly when one of fifteen axes separates them: the three face normals of
each and the nine cross products of an edge direction of one with one of the other (the
separating axis theorem; S. Gottschalk, M. Lin, D. Manocha, "OBBTree", SIGGRAPH 1996). Along a
unit axis ``L`` the boxes' projections are intervals of radii ``Σ e_k |u_k·L|`` about their
centres, so the gap along ``L`` is ``|d·L| − r_A − r_B`` for the centres' offset ``d``. The
axis of largest gap is the contact normal: when they overlap, its gap is minus the depth that
pushes them apart along the shortest way; when they are apart, a lower bound of their
distance.

On a face axis the contacts are the incident box's face most opposed to the normal, clipped to
the reference face's rectangle (as in :mod:`~visviva.collision.manifold`, done here in the
reference face's own 2-D frame), each point with its own depth, at most
:data:`~visviva.collision.manifold.MAX_CONTACTS` of them; on an edge axis, the one pair of
closest points of the two edges. Face axes are preferred over edge axes, and A's faces over B's,
unless the other is deeper by a small tolerance, so that a resting box keeps the same face from
step to step (D. Gregorius, "The separating axis test between convex polyhedra", GDC 2013;
E. Catto, "Contact manifolds", GDC 2007).

This is the same contact :func:`~visviva.collision.manifold.contact_manifold` finds after GJK
and EPA, without their iterations; nothing here allocates (the caller's ``work`` holds the
clipped polygons).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .manifold import LOST_DEPTH, MAX_CONTACTS, clip_polygon

__all__ = ["CLIP_POINTS", "box_box_contacts", "clip_work"]

#: Rows of each clipping buffer: a quadrilateral cut by four lines has at most eight corners.
CLIP_POINTS = 8
#: Gaps within this fraction of the smallest half extent count as equal when choosing the
#: axis (the first kind of axis wins the tie: a face over an edge, A's face over B's).
TIE = 5e-3
#: Edge pairs whose directions' cross product is shorter than this are parallel: a face
#: axis stands for them.
PARALLEL_EDGES = 1e-6


@njit(cache=True)
def clip_work():
    """The work array :func:`box_box_contacts` clips in: ``(2, CLIP_POINTS, 3)``."""
    return np.empty((2, CLIP_POINTS, 3))


@njit(cache=True, inline="always")
def _radius(rotation, extents, lx, ly, lz):
    """Half the length of a posed box's projection on the unit axis ``L``."""
    total = 0.0
    for k in range(3):
        total += extents[k] * abs(rotation[0, k] * lx + rotation[1, k] * ly + rotation[2, k] * lz)
    return total


@njit(cache=True)
def _gap(pa, ra, ea, pb, rb, eb, lx, ly, lz):
    """The gap of the two boxes along the unit axis ``L`` and the sign that turns ``L`` from A
    toward B."""
    along = (pb[0] - pa[0]) * lx + (pb[1] - pa[1]) * ly + (pb[2] - pa[2]) * lz
    sign = 1.0 if along >= 0.0 else -1.0
    return abs(along) - _radius(ra, ea, lx, ly, lz) - _radius(rb, eb, lx, ly, lz), sign


@njit(cache=True)
def box_box_contacts(pa, ra, ea, pb, rb, eb, max_separation, points, depths, work):
    """The contacts of box A (centre ``pa`` ``(3,)`` [m], rotation ``ra`` ``(3, 3)`` whose
    columns are its axes, half extents ``ea`` ``(3,)`` [m]) and box B likewise.

    Args:
        max_separation: Keep contacts whose gap is at most this [m].
        points, depths: outputs as for :func:`~visviva.collision.manifold.contact_manifold`
            (at least :data:`CLIP_POINTS` rows): the points midway between the surfaces and
            each one's depth (negative: a gap).
        work: :func:`clip_work`.

    Returns:
        ``(count, nx, ny, nz)``: how many contacts and their unit normal from A toward B;
        ``count`` is ``-1`` when the chosen feature gives no point within ``max_separation``
        though every axis does, or when the boxes' nearest (deepest) features were clipped
        away (a corner beside a face): the caller then asks GJK and EPA.
    """
    size = min(ea[0], ea[1], ea[2], eb[0], eb[1], eb[2])
    tie = TIE * size
    # Faces of A, then faces of B: the deepest (largest gap) of each.
    best_face = -math.inf
    face_owner = 0
    face_axis = 0
    face_sign = 1.0
    for owner in range(2):
        rotation = ra if owner == 0 else rb
        for k in range(3):
            gap, sign = _gap(pa, ra, ea, pb, rb, eb, rotation[0, k], rotation[1, k],
                             rotation[2, k])  # fmt: skip
            if gap > max_separation:
                return 0, 0.0, 0.0, 0.0
            if gap > best_face + (tie if owner == 1 else 0.0):
                best_face, face_owner, face_axis, face_sign = gap, owner, k, sign
    best_edge = -math.inf
    edge_i = edge_j = 0
    ex = ey = ez = 0.0
    for i in range(3):
        for j in range(3):
            # L = a_i × b_j, normalized.
            lx = ra[1, i] * rb[2, j] - ra[2, i] * rb[1, j]
            ly = ra[2, i] * rb[0, j] - ra[0, i] * rb[2, j]
            lz = ra[0, i] * rb[1, j] - ra[1, i] * rb[0, j]
            length = math.sqrt(lx * lx + ly * ly + lz * lz)
            if length < PARALLEL_EDGES:
                continue
            lx, ly, lz = lx / length, ly / length, lz / length
            gap, sign = _gap(pa, ra, ea, pb, rb, eb, lx, ly, lz)
            if gap > max_separation:
                return 0, 0.0, 0.0, 0.0
            if gap > best_edge:
                best_edge, edge_i, edge_j = gap, i, j
                ex, ey, ez = sign * lx, sign * ly, sign * lz
    if best_edge > best_face + tie:
        best = best_edge
        count, nx, ny, nz = _edge_contact(pa, ra, ea, pb, rb, eb, edge_i, edge_j, ex, ey, ez,
                                          max_separation, points, depths)  # fmt: skip
    elif face_owner == 0:
        best = best_face
        count, nx, ny, nz = _face_contacts(pa, ra, ea, face_axis, face_sign, pb, rb, eb,
                                           max_separation, points, depths, work)  # fmt: skip
    else:
        # B's face is the reference: its outward normal points from B toward A.
        best = best_face
        count, nx, ny, nz = _face_contacts(pb, rb, eb, face_axis, -face_sign, pa, ra, ea,
                                           max_separation, points, depths, work)  # fmt: skip
        nx, ny, nz = -nx, -ny, -nz
    if count > 0:
        # The axis's gap is that of the two nearest (deepest) features along it. If they were
        # clipped away (a corner beside the face), the points are farther apart (shallower)
        # than the boxes: let GJK and EPA find the nearest points instead.
        nearest = math.inf
        for i in range(count):
            nearest = min(nearest, -depths[i])
        lost = 1e-9 * size if best > 0.0 else -LOST_DEPTH * best
        if nearest > best + lost:
            return -1, nx, ny, nz
    return count, nx, ny, nz


@njit(cache=True)
def _face_contacts(pr, rr, er, axis, sign, pi, ri, ei, max_separation, points, depths, work):
    """Contacts of reference box R's face ``sign · axis`` (its outward normal ``n``, toward
    the incident box I) with I's face most opposed to ``n``; returns ``(count, n)``."""
    nx, ny, nz = sign * rr[0, axis], sign * rr[1, axis], sign * rr[2, axis]
    u = (axis + 1) % 3
    v = (axis + 2) % 3
    # The reference face's centre and half sizes along its two in-plane axes.
    cx = pr[0] + er[axis] * nx
    cy = pr[1] + er[axis] * ny
    cz = pr[2] + er[axis] * nz
    eu, ev = er[u], er[v]
    # The incident face: I's axis most parallel to n, on the side facing R.
    k = 0
    best = -1.0
    for m in range(3):
        along = abs(ri[0, m] * nx + ri[1, m] * ny + ri[2, m] * nz)
        if along > best:
            best, k = along, m
    facing = -1.0 if ri[0, k] * nx + ri[1, k] * ny + ri[2, k] * nz > 0.0 else 1.0
    k1 = (k + 1) % 3
    k2 = (k + 2) % 3
    # Its corners, in order around it, in R's face frame: (along u, along v, height over it).
    polygon = work[0]
    for corner in range(4):
        s1 = 1.0 if corner == 0 or corner == 3 else -1.0
        s2 = 1.0 if corner < 2 else -1.0
        for r in range(3):
            offset = (
                pi[r] + facing * ei[k] * ri[r, k] + s1 * ei[k1] * ri[r, k1]
                + s2 * ei[k2] * ri[r, k2]
            ) - (cx if r == 0 else cy if r == 1 else cz)  # fmt: skip
            polygon[corner, r] = offset
        ox, oy, oz = polygon[corner, 0], polygon[corner, 1], polygon[corner, 2]
        polygon[corner, 0] = ox * rr[0, u] + oy * rr[1, u] + oz * rr[2, u]
        polygon[corner, 1] = ox * rr[0, v] + oy * rr[1, v] + oz * rr[2, v]
        polygon[corner, 2] = ox * nx + oy * ny + oz * nz
    # Clipped to the rectangle |x| ≤ e_u, |y| ≤ e_v, one side at a time.
    count = 4
    source, target = work[0], work[1]
    for side in range(4):
        # The side line direction · (x or y) ≤ e, as a plane of the face's frame.
        limit = eu if side < 2 else ev
        direction = 1.0 if side % 2 == 0 else -1.0
        sx, sy = (direction, 0.0) if side < 2 else (0.0, direction)
        count = clip_polygon(source, count, sx * limit, sy * limit, 0.0, sx, sy, 0.0, target)
        source, target = target, source
        if count == 0:
            return -1, nx, ny, nz
    kept = 0
    for i in range(count):
        gap = source[i, 2]
        if gap <= max_separation:
            source[kept, 0], source[kept, 1], source[kept, 2] = source[i, 0], source[i, 1], gap
            kept += 1
    if kept == 0:
        return -1, nx, ny, nz
    kept, i0, i1, i2, i3 = _keep_spread(source, kept)
    for i in range(kept):
        index = i0 if i == 0 else i1 if i == 1 else i2 if i == 2 else i3
        x, y, gap = source[index, 0], source[index, 1], source[index, 2]
        # Midway between R's face (height 0) and I's point (height gap).
        for r in range(3):
            centre = cx if r == 0 else cy if r == 1 else cz
            normal = nx if r == 0 else ny if r == 1 else nz
            points[i, r] = centre + x * rr[r, u] + y * rr[r, v] + 0.5 * gap * normal
        depths[i] = -gap
    return kept, nx, ny, nz


@njit(cache=True)
def _keep_spread(polygon, count):
    """Which :data:`~visviva.collision.manifold.MAX_CONTACTS` of ``count`` points (x, y, gap)
    to keep: the deepest, the farthest from it, the one making the largest triangle with
    those two, and the one adding the most area outside that triangle. Returns how many
    (``count`` itself when few enough) and their four indices."""
    if count <= MAX_CONTACTS:
        return count, 0, 1, 2, 3
    first = 0
    for i in range(count):
        if polygon[i, 2] < polygon[first, 2]:
            first = i
    second = first
    best = -1.0
    for i in range(count):
        d = (polygon[i, 0] - polygon[first, 0]) ** 2 + (polygon[i, 1] - polygon[first, 1]) ** 2
        if d > best:
            best, second = d, i
    third = first
    best = -1.0
    for i in range(count):
        area = abs(_area(polygon, first, second, i))
        if area > best:
            best, third = area, i
    # Orient the triangle counter-clockwise: a point beyond an edge has a negative area.
    if _area(polygon, first, second, third) < 0.0:
        first, second = second, first
    fourth = -1
    best = 0.0
    for i in range(count):
        beyond = -min(_area(polygon, first, second, i), _area(polygon, second, third, i),
                      _area(polygon, third, first, i))  # fmt: skip
        if beyond > best:
            best, fourth = beyond, i
    if fourth < 0:
        return 3, first, second, third, first
    return 4, first, second, third, fourth


@njit(cache=True, inline="always")
def _area(polygon, i, j, k):
    """Twice the signed area of triangle ``i j k`` of the polygon's points (x, y)."""
    return (polygon[j, 0] - polygon[i, 0]) * (polygon[k, 1] - polygon[i, 1]) - (
        polygon[j, 1] - polygon[i, 1]
    ) * (polygon[k, 0] - polygon[i, 0])


@njit(cache=True)
def _edge_contact(pa, ra, ea, pb, rb, eb, i, j, nx, ny, nz, max_separation, points, depths):
    """The contact of A's edge along its axis ``i`` and B's along ``j`` that support the
    normal ``n`` (from A toward B): their nearest points."""
    # Each edge's centre: its box's corner side along n (A's) or −n (B's).
    ax, ay, az = pa[0], pa[1], pa[2]
    bx, by, bz = pb[0], pb[1], pb[2]
    for k in range(3):
        if k != i:
            s = ea[k] if ra[0, k] * nx + ra[1, k] * ny + ra[2, k] * nz > 0.0 else -ea[k]
            ax, ay, az = ax + s * ra[0, k], ay + s * ra[1, k], az + s * ra[2, k]
        if k != j:
            s = -eb[k] if rb[0, k] * nx + rb[1, k] * ny + rb[2, k] * nz > 0.0 else eb[k]
            bx, by, bz = bx + s * rb[0, k], by + s * rb[1, k], bz + s * rb[2, k]
    # Nearest points of the lines a + s a_i and b + t b_j, clamped to the edges.
    c = ra[0, i] * rb[0, j] + ra[1, i] * rb[1, j] + ra[2, i] * rb[2, j]
    dx, dy, dz = bx - ax, by - ay, bz - az
    wa = dx * ra[0, i] + dy * ra[1, i] + dz * ra[2, i]
    wb = dx * rb[0, j] + dy * rb[1, j] + dz * rb[2, j]
    det = 1.0 - c * c  # > 0: parallel edges never get here
    s = min(max((wa - c * wb) / det, -ea[i]), ea[i])
    # Each the nearest to the other, in turn, when an edge's end is reached (C. Ericson,
    # Real-Time Collision Detection, 2005, §5.1.9).
    t = min(max(s * c - wb, -eb[j]), eb[j])
    s = min(max(wa + t * c, -ea[i]), ea[i])
    ax, ay, az = ax + s * ra[0, i], ay + s * ra[1, i], az + s * ra[2, i]
    bx, by, bz = bx + t * rb[0, j], by + t * rb[1, j], bz + t * rb[2, j]
    gap = (bx - ax) * nx + (by - ay) * ny + (bz - az) * nz
    if gap > max_separation:
        return 0, nx, ny, nz
    points[0, 0], points[0, 1], points[0, 2] = 0.5 * (ax + bx), 0.5 * (ay + by), 0.5 * (az + bz)
    depths[0] = -gap
    return 1, nx, ny, nz
