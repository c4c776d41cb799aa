"""Scalar Numba queries of the primitive colliders: plane slab, sphere, oriented box.

These are the building blocks a collision kernel calls inside its particle loop. Every
argument is a plain float (SI units, metres, world frame), so a kernel can pass one row of a
collider table (:mod:`visviva.collision.tables`) or constants of its own. Two queries per shape:

* ``<shape>_distance(px, py, pz, params...) -> (d, gx, gy, gz)``: the signed distance ``d``
  [m] from the point to the shape's surface, negative inside the solid, and the outward unit
  normal ``g`` at the closest surface point. For a point outside, ``g`` points from the closest
  surface point to the point; for a point inside, ``g`` is the outward normal of the nearest
  face. In both cases ``g`` is the gradient of ``d`` where that exists, and
  ``x − d·g`` is the closest point on the surface. Every shape, and the triangle mesh of
  :mod:`visviva.collision.bvh`, keeps this convention.
* ``<shape>_first_hit(x0, y0, z0, x1, y1, z1, params...) -> s``: the smallest fraction
  ``s`` in [0, 1] at which the straight segment from ``x0`` to ``x1`` enters the closed solid
  (touching its surface counts), ``0`` if ``x0`` is already inside, ``+inf`` if it never does.
  A segment may jump over a thin solid between two steps; this query still sees it.

Closed forms: a plane slab is two parallel planes; the sphere's segment query solves the
quadratic ``|x0 + s D − c|² = r²`` with the cancellation-free root ``s = c'/(−b' + √Δ')``
(Press et al., *Numerical Recipes*, 3rd ed., §5.6); the box's distance is the usual one in the
box frame (Quílez, "distance functions", and Ericson, *Real-Time Collision Detection*, 2005,
§5.1.3) and its segment query is the slab test (Kay & Kajiya, SIGGRAPH 1986; Ericson
§5.3.3). Box orientations are unit quaternions (w, x, y, z) rotating box axes to world axes.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "box_distance",
    "box_first_hit",
    "plane_distance",
    "plane_first_hit",
    "rotate",
    "sphere_distance",
    "sphere_first_hit",
]


@njit(cache=True)
def rotate(qw, qx, qy, qz, vx, vy, vz):  # pragma: no cover - compiled
    """Rotate ``v`` by the unit quaternion ``q = (w, x, y, z)``: ``q v q*``.

    Uses ``v' = v + w t + u × t`` with ``u = (x, y, z)`` and ``t = 2 u × v`` (15 multiplications
    instead of the 28 of two quaternion products). Pass ``(w, −x, −y, −z)`` to rotate back.
    """
    tx = 2.0 * (qy * vz - qz * vy)
    ty = 2.0 * (qz * vx - qx * vz)
    tz = 2.0 * (qx * vy - qy * vx)
    return (
        vx + qw * tx + (qy * tz - qz * ty),
        vy + qw * ty + (qz * tx - qx * tz),
        vz + qw * tz + (qx * ty - qy * tx),
    )


@njit(cache=True, error_model="numpy", inline="always")
def plane_distance(px, py, pz, ox, oy, oz, nx, ny, nz, thickness):  # pragma: no cover
    """Signed distance [m] and outward normal of a plane slab.

    The solid is the set of points whose height ``s = (x − o)·n`` lies in ``[−thickness, 0]``;
    ``n`` must be a unit vector pointing out of the solid, ``thickness`` may be ``inf`` (a
    half-space). Above the slab's midplane the nearest face is the top one (``d = s``, normal
    ``n``); below it, the bottom one (``d = −thickness − s``, normal ``−n``).
    """
    s = (px - ox) * nx + (py - oy) * ny + (pz - oz) * nz
    if s >= -0.5 * thickness:
        return s, nx, ny, nz
    return -thickness - s, -nx, -ny, -nz


@njit(cache=True, error_model="numpy")
def plane_first_hit(x0, y0, z0, x1, y1, z1, ox, oy, oz, nx, ny, nz, thickness):  # pragma: no cover
    """First fraction of the segment ``x0 → x1`` inside a plane slab, or ``inf``.

    Heights along the segment are linear, ``h(s) = h0 + s (h1 − h0)``, so the segment enters the
    slab where ``h`` first reaches ``0`` from above or ``−thickness`` from below.
    """
    h0 = (x0 - ox) * nx + (y0 - oy) * ny + (z0 - oz) * nz
    h1 = (x1 - ox) * nx + (y1 - oy) * ny + (z1 - oz) * nz
    if -thickness <= h0 <= 0.0:
        return 0.0
    if h0 > 0.0:
        if h1 > 0.0:
            return math.inf
        # h0 ≤ h0 − h1, so the rounded quotient never exceeds 1.
        return h0 / (h0 - h1)
    if h1 < -thickness:
        return math.inf
    return (-thickness - h0) / (h1 - h0)


@njit(cache=True, error_model="numpy")
def sphere_distance(px, py, pz, cx, cy, cz, radius):  # pragma: no cover - compiled
    """Signed distance [m] and outward normal of a solid ball.

    ``d = |x − c| − r`` with normal ``(x − c)/|x − c|``; at the centre itself, where every
    direction is nearest, the normal is +Y (up).
    """
    dx = px - cx
    dy = py - cy
    dz = pz - cz
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length == 0.0:
        return -radius, 0.0, 1.0, 0.0
    return length - radius, dx / length, dy / length, dz / length


@njit(cache=True, error_model="numpy")
def sphere_first_hit(x0, y0, z0, x1, y1, z1, cx, cy, cz, radius):  # pragma: no cover
    """First fraction of the segment ``x0 → x1`` inside a solid ball, or ``inf``.

    With ``m = x0 − c`` and ``D = x1 − x0``: ``a s² + 2 b' s + c' = 0`` with ``a = D·D``,
    ``b' = m·D``, ``c' = m·m − r²``. A start outside has ``c' > 0``; it can only reach the ball
    moving towards it (``b' < 0``), and then the smaller root is ``c'/(−b' + √(b'² − a c'))``,
    a sum of two positive numbers below the fraction bar, free of cancellation.
    """
    mx = x0 - cx
    my = y0 - cy
    mz = z0 - cz
    c = mx * mx + my * my + mz * mz - radius * radius
    if c <= 0.0:
        return 0.0
    dx = x1 - x0
    dy = y1 - y0
    dz = z1 - z0
    b = mx * dx + my * dy + mz * dz
    if b >= 0.0:
        return math.inf
    a = dx * dx + dy * dy + dz * dz
    discriminant = b * b - a * c
    if discriminant < 0.0:
        return math.inf
    s = c / (-b + math.sqrt(discriminant))
    return s if s <= 1.0 else math.inf


@njit(cache=True, error_model="numpy")
def box_distance(px, py, pz, cx, cy, cz, hx, hy, hz, qw, qx, qy, qz):  # pragma: no cover
    """Signed distance [m] and outward normal of a solid oriented box.

    ``c`` is the centre, ``h`` the half extents along the box's own axes [m], ``q`` the unit
    quaternion (w, x, y, z) taking box axes to world axes. In the box frame, with
    ``e = |p| − h`` per axis: outside (some ``e > 0``) the distance is ``|max(e, 0)|`` and the
    normal points from the clamped point to ``p``; inside, the distance is ``max(e)`` (≤ 0) and
    the normal is that face's axis, ``±e_k`` by the sign of ``p_k`` (+ when ``p_k = 0``).
    """
    lx, ly, lz = rotate(qw, -qx, -qy, -qz, px - cx, py - cy, pz - cz)
    ex = abs(lx) - hx
    ey = abs(ly) - hy
    ez = abs(lz) - hz
    ox = max(ex, 0.0)
    oy = max(ey, 0.0)
    oz = max(ez, 0.0)
    outside = math.sqrt(ox * ox + oy * oy + oz * oz)
    if outside > 0.0:
        gx = math.copysign(ox, lx) / outside
        gy = math.copysign(oy, ly) / outside
        gz = math.copysign(oz, lz) / outside
        d = outside
    else:
        # Inside, on the surface, or outside by less than √(smallest normal float): the nearest
        # face decides. Ties (edges, corners, the centre of a cube) go to the first axis.
        gx = 0.0
        gy = 0.0
        gz = 0.0
        if ex >= ey and ex >= ez:
            d = ex
            gx = 1.0 if lx >= 0.0 else -1.0
        elif ey >= ez:
            d = ey
            gy = 1.0 if ly >= 0.0 else -1.0
        else:
            d = ez
            gz = 1.0 if lz >= 0.0 else -1.0
    wx, wy, wz = rotate(qw, qx, qy, qz, gx, gy, gz)
    return d, wx, wy, wz


@njit(cache=True, error_model="numpy")
def box_first_hit(
    x0, y0, z0, x1, y1, z1, cx, cy, cz, hx, hy, hz, qw, qx, qy, qz
):  # pragma: no cover
    """First fraction of the segment ``x0 → x1`` inside a solid oriented box, or ``inf``.

    Slab test in the box frame: the segment is inside slab ``k`` for ``s`` between
    ``(±h_k − p_k)/D_k``; the entry is the latest of the three slab entries, valid if it comes
    before the earliest exit and within ``[0, 1]``. A direction parallel to a slab (``D_k = 0``)
    is inside it for all ``s`` or for none (no ``0 · ∞`` arises).
    """
    p0, p1, p2 = rotate(qw, -qx, -qy, -qz, x0 - cx, y0 - cy, z0 - cz)
    if abs(p0) <= hx and abs(p1) <= hy and abs(p2) <= hz:
        return 0.0
    d0, d1, d2 = rotate(qw, -qx, -qy, -qz, x1 - x0, y1 - y0, z1 - z0)
    enter = 0.0
    leave = 1.0
    for axis in range(3):
        if axis == 0:
            p, d, h = p0, d0, hx
        elif axis == 1:
            p, d, h = p1, d1, hy
        else:
            p, d, h = p2, d2, hz
        if d == 0.0:
            if abs(p) > h:
                return math.inf
            continue
        t_low = (-h - p) / d
        t_high = (h - p) / d
        if t_low > t_high:
            t_low, t_high = t_high, t_low
        enter = max(enter, t_low)
        leave = min(leave, t_high)
        if enter > leave:
            return math.inf
    return enter
