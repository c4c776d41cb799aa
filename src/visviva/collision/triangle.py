"""Point and segment queries against one triangle (Numba, scalar arguments).

* :func:`closest_point_on_triangle` is Ericson's Voronoi-region walk (C. Ericson, *Real-Time
  Collision Detection*, Morgan Kaufmann 2005, §5.1.5): the point's projections onto the edges
  decide which of the seven features (three vertices, three edges, the face) holds the closest
  point, with no square root and one division. It also returns that feature, which the mesh's
  signed distance needs to pick the right pseudo-normal.
* :func:`segment_triangle_hit` is the Möller–Trumbore intersection (T. Möller and B. Trumbore,
  "Fast, minimum storage ray-triangle intersection", *Journal of Graphics Tools* 2(1), 1997):
  Cramer's rule on ``x0 + t D = a + u (b − a) + v (c − a)`` with scalar triple products.

Feature codes (the order of the per-triangle pseudo-normals in :mod:`visviva.collision.bvh`):
``FACE = 0``, vertices ``VERTEX_A, VERTEX_B, VERTEX_C = 1, 2, 3``, edges
``EDGE_AB, EDGE_BC, EDGE_CA = 4, 5, 6``.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "BARYCENTRIC_SLACK",
    "EDGE_AB",
    "EDGE_BC",
    "EDGE_CA",
    "FACE",
    "VERTEX_A",
    "VERTEX_B",
    "VERTEX_C",
    "closest_point_on_triangle",
    "segment_triangle_hit",
]

FACE = 0
VERTEX_A = 1
VERTEX_B = 2
VERTEX_C = 3
EDGE_AB = 4
EDGE_BC = 5
EDGE_CA = 6

#: Barycentric margin of the segment test. Möller–Trumbore is not watertight: a segment through
#: a shared edge can round to "outside" of both triangles. Growing each triangle by this
#: fraction of its size makes neighbours overlap slightly, so such a segment hits at least one;
#: the hit fraction moves by about this relative amount at most.
BARYCENTRIC_SLACK = 1e-12


@njit(cache=True, error_model="numpy")
def closest_point_on_triangle(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):  # pragma: no cover
    """Closest point ``(qx, qy, qz)`` of triangle ``abc`` to ``p``, and its feature code.

    Follows Ericson §5.1.5 line by line; ``d1 … d6`` are the dot products of the edge vectors
    ``ab``, ``ac`` with ``p − a``, ``p − b``, ``p − c``, and ``va, vb, vc`` the (unnormalized)
    barycentric coordinates of the projection of ``p`` on the triangle's plane.
    """
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az, VERTEX_A

    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bx, by, bz, VERTEX_B

    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return ax + v * abx, ay + v * aby, az + v * abz, EDGE_AB

    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cx, cy, cz, VERTEX_C

    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return ax + w * acx, ay + w * acy, az + w * acz, EDGE_CA

    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return bx + w * (cx - bx), by + w * (cy - by), bz + w * (cz - bz), EDGE_BC

    denominator = 1.0 / (va + vb + vc)
    v = vb * denominator
    w = vc * denominator
    return (
        ax + abx * v + acx * w,
        ay + aby * v + acy * w,
        az + abz * v + acz * w,
        FACE,
    )


@njit(cache=True, error_model="numpy")
def segment_triangle_hit(
    x0, y0, z0, dx, dy, dz, ax, ay, az, bx, by, bz, cx, cy, cz
):  # pragma: no cover
    """Fraction ``t`` in [0, 1] where ``x0 + t D`` crosses triangle ``abc``, or ``inf``.

    Both sides of the triangle count (a segment starting outside a closed mesh first crosses it
    on the way in, whichever way the triangle faces). A segment in the triangle's plane
    (zero determinant) is reported as a miss: it can only graze the surface there.
    """
    e1x, e1y, e1z = bx - ax, by - ay, bz - az
    e2x, e2y, e2z = cx - ax, cy - ay, cz - az
    # p = D × e2, det = e1 · p
    qx = dy * e2z - dz * e2y
    qy = dz * e2x - dx * e2z
    qz = dx * e2y - dy * e2x
    det = e1x * qx + e1y * qy + e1z * qz
    if det == 0.0:
        return math.inf
    inverse = 1.0 / det
    tx, ty, tz = x0 - ax, y0 - ay, z0 - az
    u = (tx * qx + ty * qy + tz * qz) * inverse
    if u < -BARYCENTRIC_SLACK or u > 1.0 + BARYCENTRIC_SLACK:
        return math.inf
    # r = (x0 − a) × e1
    rx = ty * e1z - tz * e1y
    ry = tz * e1x - tx * e1z
    rz = tx * e1y - ty * e1x
    v = (dx * rx + dy * ry + dz * rz) * inverse
    if v < -BARYCENTRIC_SLACK or u + v > 1.0 + BARYCENTRIC_SLACK:
        return math.inf
    t = (e2x * rx + e2y * ry + e2z * rz) * inverse
    if t < -BARYCENTRIC_SLACK or t > 1.0:
        return math.inf
    return max(t, 0.0)
