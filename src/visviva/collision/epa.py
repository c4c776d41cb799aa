"""EPA: how deep two overlapping convex cores are, along which normal, and where.

The expanding polytope algorithm (G. van den Bergen, "Proximity queries and penetration depth
computation on 3D game objects", GDC 2001; *Collision Detection in Interactive 3D
Environments*, 2003, §4.3.7) grows a polytope inside the Minkowski difference ``D = A − B``
around the origin: it takes the face nearest the origin, adds the support point of ``D`` along
that face's outward normal, and re-roofs the faces the new point sees (the horizon). When the
support point lies no farther out than the face, that face is on ``D``'s boundary and its
distance to the origin is the penetration depth: moving ``B`` by ``depth·n`` (``n`` the face's
normal) separates the cores.

It starts from GJK's final simplex (:mod:`~visviva.collision.gjk`), grown to a tetrahedron
when GJK stopped with fewer points. The polytope lives in fixed arrays of
:data:`MAX_VERTICES` points; on a round core EPA stops within :data:`RELATIVE_TOLERANCE` of the
depth, at most :data:`MAX_VERTICES` − 4 iterations.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .convex import world_support

__all__ = ["MAX_VERTICES", "penetration"]

MAX_VERTICES = 96
MAX_FACES = 2 * MAX_VERTICES
#: EPA stops when the support point lies within this fraction of the shapes' size beyond the
#: nearest face: exact for polytopes, a tenth of a micrometre on a metre-sized round core.
RELATIVE_TOLERANCE = 1e-7


@njit(cache=True)
def _add_point(points, points_a, points_b, n, shape_a, shape_b, dx, dy, dz):
    """Append the support point of ``D`` along ``d`` (and its two parts); returns the count."""
    kind_a, params_a, vertices_a, _, _, _, position_a, rotation_a = shape_a
    kind_b, params_b, vertices_b, _, _, _, position_b, rotation_b = shape_b
    ax, ay, az = world_support(kind_a, params_a, vertices_a, position_a, rotation_a, dx, dy, dz)
    bx, by, bz = world_support(kind_b, params_b, vertices_b, position_b, rotation_b,
                               -dx, -dy, -dz)  # fmt: skip
    points[n, 0], points[n, 1], points[n, 2] = ax - bx, ay - by, az - bz
    points_a[n, 0], points_a[n, 1], points_a[n, 2] = ax, ay, az
    points_b[n, 0], points_b[n, 1], points_b[n, 2] = bx, by, bz
    return n + 1


@njit(cache=True)
def _cross_norm2(points, a, b, c):
    abx = points[b, 0] - points[a, 0]
    aby = points[b, 1] - points[a, 1]
    abz = points[b, 2] - points[a, 2]
    acx = points[c, 0] - points[a, 0]
    acy = points[c, 1] - points[a, 1]
    acz = points[c, 2] - points[a, 2]
    nx = aby * acz - abz * acy
    ny = abz * acx - abx * acz
    nz = abx * acy - aby * acx
    return nx, ny, nz


@njit(cache=True)
def _grow_to_tetrahedron(points, points_a, points_b, n, shape_a, shape_b, scale):
    """Add support points until ``points[:4]`` is a tetrahedron of nonzero volume; returns
    the count (4), or 0 when ``D`` is flat in every direction tried."""
    tiny = 1e-12 * scale
    axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0),
            (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0))  # fmt: skip
    if n == 0:
        n = _add_point(points, points_a, points_b, n, shape_a, shape_b, 1.0, 0.0, 0.0)
    if n == 1:
        for d in range(6):
            dx, dy, dz = axes[d]
            n = _add_point(points, points_a, points_b, n, shape_a, shape_b, dx, dy, dz)
            ex = points[1, 0] - points[0, 0]
            ey = points[1, 1] - points[0, 1]
            ez = points[1, 2] - points[0, 2]
            if ex * ex + ey * ey + ez * ez > tiny * tiny:
                break
            n = 1
        if n == 1:
            return 0
    if n == 2:
        ex = points[1, 0] - points[0, 0]
        ey = points[1, 1] - points[0, 1]
        ez = points[1, 2] - points[0, 2]
        for d in range(6):
            # Directions across the segment: e × each axis.
            kx, ky, kz = axes[d]
            dx = ey * kz - ez * ky
            dy = ez * kx - ex * kz
            dz = ex * ky - ey * kx
            if dx * dx + dy * dy + dz * dz == 0.0:
                continue
            n = _add_point(points, points_a, points_b, n, shape_a, shape_b, dx, dy, dz)
            nx, ny, nz = _cross_norm2(points, 0, 1, 2)
            if math.sqrt(nx * nx + ny * ny + nz * nz) > tiny * math.sqrt(
                ex * ex + ey * ey + ez * ez
            ):
                break
            n = 2
        if n == 2:
            return 0
    if n == 3:
        nx, ny, nz = _cross_norm2(points, 0, 1, 2)
        area2 = math.sqrt(nx * nx + ny * ny + nz * nz)
        if area2 == 0.0:
            return 0
        for sign in (1.0, -1.0):
            n = _add_point(points, points_a, points_b, n, shape_a, shape_b,
                           sign * nx, sign * ny, sign * nz)  # fmt: skip
            height = (
                nx * (points[3, 0] - points[0, 0])
                + ny * (points[3, 1] - points[0, 1])
                + nz * (points[3, 2] - points[0, 2])
            ) / area2
            if abs(height) > tiny:
                break
            n = 3
        if n == 3:
            return 0
    return 4


@njit(cache=True)
def _set_face(points, faces, normals, f, a, b, c):
    """Face ``f`` = triangle ``(a, b, c)`` with its outward unit normal and distance
    ``n·p`` from the origin; returns False for a face of no area."""
    nx, ny, nz = _cross_norm2(points, a, b, c)
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    faces[f, 0], faces[f, 1], faces[f, 2] = a, b, c
    if length == 0.0:
        normals[f, :] = 0.0
        normals[f, 3] = math.inf
        return False
    nx, ny, nz = nx / length, ny / length, nz / length
    normals[f, 0], normals[f, 1], normals[f, 2] = nx, ny, nz
    normals[f, 3] = nx * points[a, 0] + ny * points[a, 1] + nz * points[a, 2]
    return True


@njit(cache=True)
def penetration(shape_a, shape_b, simplex, simplex_a, simplex_b, count):
    """Penetration of two overlapping posed cores (posed shapes of
    :mod:`~visviva.collision.convex`), from GJK's final simplex (its first ``count`` rows).

    Returns:
        ``(ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz)``: the depth [m] ≥ 0, the unit
        normal ``n`` along which moving ``B`` by ``depth`` separates the cores (from A toward
        B), and the deepest points of A inside B and of B inside A, ``b − a = −depth·n``.
        ``ok`` is False when ``D`` is flat (the cores only touch); the rest is then zero.
    """
    points = np.empty((MAX_VERTICES, 3))
    points_a = np.empty((MAX_VERTICES, 3))
    points_b = np.empty((MAX_VERTICES, 3))
    for i in range(count):
        points[i, :] = simplex[i, :]
        points_a[i, :] = simplex_a[i, :]
        points_b[i, :] = simplex_b[i, :]
    scale = 0.0
    for i in range(count):
        scale = max(scale, math.sqrt(points[i, 0] ** 2 + points[i, 1] ** 2 + points[i, 2] ** 2))
    kind_a, params_a, vertices_a, _, _, _, position_a, rotation_a = shape_a
    sx, sy, sz = world_support(kind_a, params_a, vertices_a, position_a, rotation_a, 1.0, 1.0, 1.0)
    scale = max(scale, abs(sx - position_a[0]) + abs(sy - position_a[1]) + abs(sz - position_a[2]))
    scale = max(scale, 1e-300)
    n = _grow_to_tetrahedron(points, points_a, points_b, count, shape_a, shape_b, scale)
    if n == 0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # Orient the tetrahedron's faces outward.
    faces = np.empty((MAX_FACES, 3), dtype=np.int64)
    normals = np.empty((MAX_FACES, 4))
    alive = np.zeros(MAX_FACES, dtype=np.bool_)
    nx, ny, nz = _cross_norm2(points, 0, 1, 2)
    volume = (
        nx * (points[3, 0] - points[0, 0])
        + ny * (points[3, 1] - points[0, 1])
        + nz * (points[3, 2] - points[0, 2])
    )
    if volume > 0.0:
        # Point 3 lies on the side (0, 1, 2) faces: swap to make every face outward.
        for array in (points, points_a, points_b):
            for c in range(3):
                array[1, c], array[2, c] = array[2, c], array[1, c]
    tetra = ((0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2))
    face_count = 4
    for f in range(4):
        a, b, c = tetra[f]
        _set_face(points, faces, normals, f, a, b, c)
        alive[f] = True
    edges = np.empty((3 * MAX_FACES, 2), dtype=np.int64)
    tolerance = RELATIVE_TOLERANCE * scale
    # The answer so far: the nearest face's corners, normal and distance. A nearest face
    # never comes nearer as the polytope grows; one that does is rounding having broken the
    # polytope (a new point almost in a face's plane), and the last good face is the answer.
    chosen = np.empty(3, dtype=np.int64)
    chosen_normal = np.empty(4)
    found = False
    for _ in range(MAX_VERTICES):
        best = _nearest_face(alive, normals, face_count)
        if best < 0 or (found and normals[best, 3] < chosen_normal[3] - tolerance):
            break
        chosen[:] = faces[best]
        chosen_normal[:] = normals[best]
        found = True
        best_distance = normals[best, 3]
        fx, fy, fz = normals[best, 0], normals[best, 1], normals[best, 2]
        if n == MAX_VERTICES:
            break
        n = _add_point(points, points_a, points_b, n, shape_a, shape_b, fx, fy, fz)
        new = n - 1
        reach = fx * points[new, 0] + fy * points[new, 1] + fz * points[new, 2]
        if reach - best_distance <= tolerance:
            n -= 1
            break
        # Remove every face the new point sees; the edges left once are the horizon.
        edge_count = 0
        for f in range(face_count):
            if not alive[f]:
                continue
            a = faces[f, 0]
            seen = (
                normals[f, 0] * (points[new, 0] - points[a, 0])
                + normals[f, 1] * (points[new, 1] - points[a, 1])
                + normals[f, 2] * (points[new, 2] - points[a, 2])
            )
            if seen <= 0.0:
                continue
            alive[f] = False
            for e in range(3):
                u = faces[f, e]
                v = faces[f, (e + 1) % 3]
                twin = -1
                for k in range(edge_count):
                    if edges[k, 0] == v and edges[k, 1] == u:
                        twin = k
                        break
                if twin >= 0:
                    edge_count -= 1
                    edges[twin, 0] = edges[edge_count, 0]
                    edges[twin, 1] = edges[edge_count, 1]
                else:
                    edges[edge_count, 0] = u
                    edges[edge_count, 1] = v
                    edge_count += 1
        if face_count + edge_count > MAX_FACES:
            face_count = _compact(faces, normals, alive, face_count)
            if face_count + edge_count > MAX_FACES:
                break
        for k in range(edge_count):
            _set_face(points, faces, normals, face_count, edges[k, 0], edges[k, 1], new)
            alive[face_count] = True
            face_count += 1
    if not found:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    depth = chosen_normal[3]
    fx, fy, fz = chosen_normal[0], chosen_normal[1], chosen_normal[2]
    # The origin's projection on the face, in barycentric weights, gives the deepest points.
    i0, i1, i2 = chosen[0], chosen[1], chosen[2]
    px, py, pz = depth * fx, depth * fy, depth * fz
    u, v, w = _barycentric(points, i0, i1, i2, px, py, pz)
    ax = u * points_a[i0, 0] + v * points_a[i1, 0] + w * points_a[i2, 0]
    ay = u * points_a[i0, 1] + v * points_a[i1, 1] + w * points_a[i2, 1]
    az = u * points_a[i0, 2] + v * points_a[i1, 2] + w * points_a[i2, 2]
    bx = u * points_b[i0, 0] + v * points_b[i1, 0] + w * points_b[i2, 0]
    by = u * points_b[i0, 1] + v * points_b[i1, 1] + w * points_b[i2, 1]
    bz = u * points_b[i0, 2] + v * points_b[i1, 2] + w * points_b[i2, 2]
    return True, max(depth, 0.0), fx, fy, fz, ax, ay, az, bx, by, bz


@njit(cache=True)
def _nearest_face(alive, normals, face_count):
    """The live face nearest the origin (of finite distance: one with area), or -1."""
    best = -1
    best_distance = math.inf
    for f in range(face_count):
        if alive[f] and normals[f, 3] < best_distance:
            best_distance = normals[f, 3]
            best = f
    return best


@njit(cache=True)
def _compact(faces, normals, alive, face_count):
    kept = 0
    for f in range(face_count):
        if alive[f]:
            faces[kept, :] = faces[f, :]
            normals[kept, :] = normals[f, :]
            alive[kept] = True
            kept += 1
    alive[kept:face_count] = False
    return kept


@njit(cache=True)
def _barycentric(points, i0, i1, i2, px, py, pz):
    """Barycentric weights of ``p`` (in the triangle's plane) in triangle ``i0 i1 i2``."""
    v0x = points[i1, 0] - points[i0, 0]
    v0y = points[i1, 1] - points[i0, 1]
    v0z = points[i1, 2] - points[i0, 2]
    v1x = points[i2, 0] - points[i0, 0]
    v1y = points[i2, 1] - points[i0, 1]
    v1z = points[i2, 2] - points[i0, 2]
    v2x = px - points[i0, 0]
    v2y = py - points[i0, 1]
    v2z = pz - points[i0, 2]
    d00 = v0x * v0x + v0y * v0y + v0z * v0z
    d01 = v0x * v1x + v0y * v1y + v0z * v1z
    d11 = v1x * v1x + v1y * v1y + v1z * v1z
    d20 = v2x * v0x + v2y * v0y + v2z * v0z
    d21 = v2x * v1x + v2y * v1y + v2z * v1z
    denominator = d00 * d11 - d01 * d01
    if denominator == 0.0:
        return 1.0, 0.0, 0.0
    v = (d11 * d20 - d01 * d21) / denominator
    w = (d00 * d21 - d01 * d20) / denominator
    return 1.0 - v - w, v, w
