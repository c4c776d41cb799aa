"""GJK: the distance between two convex cores and their closest points.

The Gilbert–Johnson–Keerthi algorithm (E. G. Gilbert, D. W. Johnson, S. S. Keerthi, "A fast
procedure for computing the distance between complex objects in three-dimensional space",
IEEE J. Robotics and Automation 4(2), 1988) finds the point ``v`` of the Minkowski difference
``D = A − B`` nearest the origin: ``|v|`` is the distance between the cores, and ``v = p_A − p_B``
for the closest points. It keeps a simplex of at most four points of ``D``, each the
difference of two support points, moves to the point of the simplex nearest the origin, drops
the simplex's points it no longer needs and adds the support point of ``D`` along ``−v``.

Here the nearest point of a simplex comes from its Voronoi regions (C. Ericson, *Real-Time
Collision Detection*, 2005, §5.1.5 and §5.1.6), and the loop stops by van den Bergen's test
(*Collision Detection in Interactive 3D Environments*, 2003, §4.3.4): ``v`` is within a relative
tolerance of the distance once ``|v|² − v·w ≤ ε |v|²`` for the new support point ``w``. On two
polytopes GJK ends exactly in finitely many steps; on a round core it converges linearly.

A result with the cores overlapping (the origin inside ``D``) keeps its simplex for EPA
(:mod:`~visviva.collision.epa`), which measures how deep.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .convex import world_support

__all__ = ["OVERLAPPING", "SEPARATED", "core_distance"]

SEPARATED = 0
OVERLAPPING = 1

#: Relative tolerance of van den Bergen's stopping test: the distance is exact to about
#: ``RELATIVE_TOLERANCE/2`` of itself (polytopes end sooner, exactly).
RELATIVE_TOLERANCE = 1e-13
#: Below this squared distance [m²] (relative to the shapes' size squared) the cores touch.
TOUCHING = 1e-24
MAX_ITERATIONS = 200


@njit(cache=True)
def _dot(a, i, b, j):
    return a[i, 0] * b[j, 0] + a[i, 1] * b[j, 1] + a[i, 2] * b[j, 2]


@njit(cache=True)
def _closest_on_segment(w, lam):
    """Weights ``lam[0:2]`` of the point of segment ``w[0] w[1]`` nearest the origin."""
    ex = w[1, 0] - w[0, 0]
    ey = w[1, 1] - w[0, 1]
    ez = w[1, 2] - w[0, 2]
    length2 = ex * ex + ey * ey + ez * ez
    t = 0.0
    if length2 > 0.0:
        t = -(w[0, 0] * ex + w[0, 1] * ey + w[0, 2] * ez) / length2
        t = min(max(t, 0.0), 1.0)
    lam[0] = 1.0 - t
    lam[1] = t


@njit(cache=True)
def _closest_on_triangle(w, i0, i1, i2):
    """Barycentric weights of the point of triangle ``w[i0] w[i1] w[i2]`` nearest the origin,
    by its Voronoi regions (Ericson, §5.1.5, with the query point at the origin)."""
    abx = w[i1, 0] - w[i0, 0]
    aby = w[i1, 1] - w[i0, 1]
    abz = w[i1, 2] - w[i0, 2]
    acx = w[i2, 0] - w[i0, 0]
    acy = w[i2, 1] - w[i0, 1]
    acz = w[i2, 2] - w[i0, 2]
    # ap = origin − a = −a
    apx, apy, apz = -w[i0, 0], -w[i0, 1], -w[i0, 2]
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0
    bpx, bpy, bpz = -w[i1, 0], -w[i1, 1], -w[i1, 2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return 1.0 - t, t, 0.0
    cpx, cpy, cpz = -w[i2, 0], -w[i2, 1], -w[i2, 2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return 1.0 - t, 0.0, t
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - t, t
    denominator = va + vb + vc
    if denominator == 0.0:
        # A degenerate (flat) triangle: its nearest point lies on an edge.
        return _closest_on_degenerate_triangle(w, i0, i1, i2)
    v = vb / denominator
    u = vc / denominator
    return 1.0 - v - u, v, u


@njit(cache=True)
def _closest_on_degenerate_triangle(w, i0, i1, i2):
    best = math.inf
    weights = (1.0, 0.0, 0.0)
    edges = ((i0, i1), (i1, i2), (i2, i0))
    pair = np.empty((2, 3))
    lam = np.empty(2)
    for e in range(3):
        a, b = edges[e]
        for c in range(3):
            pair[0, c] = w[a, c]
            pair[1, c] = w[b, c]
        _closest_on_segment(pair, lam)
        px = lam[0] * pair[0, 0] + lam[1] * pair[1, 0]
        py = lam[0] * pair[0, 1] + lam[1] * pair[1, 1]
        pz = lam[0] * pair[0, 2] + lam[1] * pair[1, 2]
        d = px * px + py * py + pz * pz
        if d < best:
            best = d
            if e == 0:
                weights = (lam[0], lam[1], 0.0)
            elif e == 1:
                weights = (0.0, lam[0], lam[1])
            else:
                weights = (lam[1], 0.0, lam[0])
    return weights


@njit(cache=True)
def _outside_face(w, i0, i1, i2, i3):
    """Whether the origin and ``w[i3]`` lie on opposite sides of the plane of face
    ``w[i0] w[i1] w[i2]`` (the origin outside the tetrahedron through that face)."""
    abx = w[i1, 0] - w[i0, 0]
    aby = w[i1, 1] - w[i0, 1]
    abz = w[i1, 2] - w[i0, 2]
    acx = w[i2, 0] - w[i0, 0]
    acy = w[i2, 1] - w[i0, 1]
    acz = w[i2, 2] - w[i0, 2]
    nx = aby * acz - abz * acy
    ny = abz * acx - abx * acz
    nz = abx * acy - aby * acx
    origin_side = -(nx * w[i0, 0] + ny * w[i0, 1] + nz * w[i0, 2])
    vertex_side = (
        nx * (w[i3, 0] - w[i0, 0]) + ny * (w[i3, 1] - w[i0, 1]) + nz * (w[i3, 2] - w[i0, 2])
    )
    return origin_side * vertex_side < 0.0


@njit(cache=True)
def _closest_on_simplex(w, count, lam):
    """Weights ``lam[:count]`` of the point of the simplex ``w[:count]`` nearest the origin;
    for a tetrahedron holding the origin every weight may be nonzero (returns True)."""
    if count == 1:
        lam[0] = 1.0
        return False
    if count == 2:
        _closest_on_segment(w, lam)
        return False
    if count == 3:
        lam[0], lam[1], lam[2] = _closest_on_triangle(w, 0, 1, 2)
        return False
    faces = ((0, 1, 2, 3), (0, 3, 1, 2), (0, 2, 3, 1), (1, 3, 2, 0))
    best = math.inf
    inside = True
    for f in range(4):
        i0, i1, i2, i3 = faces[f]
        if not _outside_face(w, i0, i1, i2, i3):
            continue
        inside = False
        a, b, c = _closest_on_triangle(w, i0, i1, i2)
        px = a * w[i0, 0] + b * w[i1, 0] + c * w[i2, 0]
        py = a * w[i0, 1] + b * w[i1, 1] + c * w[i2, 1]
        pz = a * w[i0, 2] + b * w[i1, 2] + c * w[i2, 2]
        d = px * px + py * py + pz * pz
        if d < best:
            best = d
            lam[:] = 0.0
            lam[i0] = a
            lam[i1] = b
            lam[i2] = c
    if inside:
        # The origin is inside: any convex weights will do, the caller hands over to EPA.
        lam[:] = 0.25
    return inside


@njit(cache=True)
def core_distance(
    kind_a, params_a, vertices_a, position_a, rotation_a,
    kind_b, params_b, vertices_b, position_b, rotation_b,
    simplex, simplex_a, simplex_b, limit=math.inf, tolerance=RELATIVE_TOLERANCE,
):  # fmt: skip
    """GJK on two posed cores (see :mod:`~visviva.collision.convex` for the arguments).

    ``simplex``, ``simplex_a`` and ``simplex_b`` are ``(4, 3)`` work arrays; on return their
    first ``count`` rows hold the final simplex of ``D = A − B`` and the support points of
    ``A`` and ``B`` that made it (EPA starts from them). ``tolerance`` is the stopping test's
    relative tolerance; once the cores are surely farther apart than ``limit`` [m] (a support
    plane of ``D`` lies beyond it) the search stops with that lower bound as the distance.

    Returns:
        ``(status, distance, count, ax, ay, az, bx, by, bz)``: :data:`SEPARATED` with the
        distance [m] between the cores and their closest points, or :data:`OVERLAPPING`
        (distance 0) when the cores overlap or touch.
    """
    lam = np.empty(4)
    vx = position_a[0] - position_b[0]
    vy = position_a[1] - position_b[1]
    vz = position_a[2] - position_b[2]
    if vx == 0.0 and vy == 0.0 and vz == 0.0:
        vx = 1.0
    scale = 0.0
    count = 0
    previous = math.inf
    for _ in range(MAX_ITERATIONS):
        pax, pay, paz = world_support(kind_a, params_a, vertices_a, position_a, rotation_a,
                                      -vx, -vy, -vz)  # fmt: skip
        pbx, pby, pbz = world_support(kind_b, params_b, vertices_b, position_b, rotation_b,
                                      vx, vy, vz)  # fmt: skip
        wx, wy, wz = pax - pbx, pay - pby, paz - pbz
        scale = max(scale, wx * wx + wy * wy + wz * wz)
        vv = vx * vx + vy * vy + vz * vz
        vw = vx * wx + vy * wy + vz * wz
        if vw > 0.0 and vw * vw > limit * limit * vv:
            # Every point of D lies beyond the plane v·x = v·w: the cores are farther apart
            # than v·w/|v| > limit.
            return SEPARATED, vw / math.sqrt(vv), count, pax, pay, paz, pbx, pby, pbz
        if count > 0 and vv - vw <= tolerance * vv:
            break
        repeated = False
        for i in range(count):
            if simplex[i, 0] == wx and simplex[i, 1] == wy and simplex[i, 2] == wz:
                repeated = True
        if repeated:
            break
        simplex[count, 0], simplex[count, 1], simplex[count, 2] = wx, wy, wz
        simplex_a[count, 0], simplex_a[count, 1], simplex_a[count, 2] = pax, pay, paz
        simplex_b[count, 0], simplex_b[count, 1], simplex_b[count, 2] = pbx, pby, pbz
        count += 1
        inside = _closest_on_simplex(simplex, count, lam)
        if inside:
            return OVERLAPPING, 0.0, count, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        # Keep the points with weight; v is their weighted sum.
        kept = 0
        vx = vy = vz = 0.0
        for i in range(count):
            if lam[i] > 0.0:
                for c in range(3):
                    simplex[kept, c] = simplex[i, c]
                    simplex_a[kept, c] = simplex_a[i, c]
                    simplex_b[kept, c] = simplex_b[i, c]
                lam[kept] = lam[i]
                vx += lam[i] * simplex[i, 0]
                vy += lam[i] * simplex[i, 1]
                vz += lam[i] * simplex[i, 2]
                kept += 1
        count = kept
        vv_new = vx * vx + vy * vy + vz * vz
        if vv_new <= TOUCHING * max(scale, 1e-300):
            return OVERLAPPING, 0.0, count, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        if vv_new >= previous:
            # No progress: rounding has taken over and v is as near as it gets.
            break
        previous = vv_new
    ax = ay = az = bx = by = bz = 0.0
    vx = vy = vz = 0.0
    for i in range(count):
        ax += lam[i] * simplex_a[i, 0]
        ay += lam[i] * simplex_a[i, 1]
        az += lam[i] * simplex_a[i, 2]
        bx += lam[i] * simplex_b[i, 0]
        by += lam[i] * simplex_b[i, 1]
        bz += lam[i] * simplex_b[i, 2]
    dx, dy, dz = ax - bx, ay - by, az - bz
    return SEPARATED, math.sqrt(dx * dx + dy * dy + dz * dz), count, ax, ay, az, bx, by, bz
