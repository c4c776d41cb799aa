"""Finding the contacts of rigid bodies: poses of their pieces, broad phase, narrow phase.

:func:`piece_poses` places every piece (:mod:`~visviva.collision.body_pieces`) in the world
from its body's centre of mass and rotation, with its bounding box grown by its margin;
:func:`~visviva.collision.broad_phase.overlapping_pairs` keeps the pairs whose boxes overlap;
:func:`pair_contacts` finds each one's contacts (:mod:`~visviva.collision.narrow_phase`: the
separating axes for two boxes, GJK/EPA and the clipped manifold for the rest),
:func:`plane_contacts` each piece against each plane and :func:`mesh_contacts` against the
triangles of a static mesh its box overlaps.
Contacts come out in the order of their pairs, then of their planes: the same on every run.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .body_pieces import piece_shape
from .box_box import clip_work
from .broad_phase import shape_bounds
from .bvh import STACK_SIZE
from .convex import HULL, SPHERE
from .manifold import CANDIDATES, MAX_CONTACTS, contact_manifold, plane_manifold
from .narrow_phase import convex_contacts
from .separation import plane_separation, shape_distance

__all__ = [
    "MAX_CONTACTS",
    "contact_arrays",
    "mesh_contacts",
    "pair_contacts",
    "piece_poses",
    "plane_contacts",
]


@njit(cache=True)
def piece_poses(pieces, body, position, rotation, margin, piece_position, piece_rotation, lo, hi):
    """Each piece's world pose and bounding box grown by ``margin[b]`` [m] of its body
    (static pieces keep their pose and grow by nothing).

    Args:
        pieces: :meth:`~visviva.collision.body_pieces.BodyPieces.arrays`.
        body: ``(P,)`` each piece's body (``-1``: static).
        position, rotation: ``(B, 3)`` centres of mass [m] and ``(B, 3, 3)`` rotations.
        margin: ``(B,)`` [m].
        piece_position, piece_rotation: ``(P, 3)``, ``(P, 3, 3)``: the local poses on entry
            (``BodyPieces.local_position``/``local_rotation``), the world poses on return.
        lo, hi: ``(P, 3)`` outputs.
    """
    local = np.empty(3)
    turn = np.empty((3, 3))
    for p in range(body.shape[0]):
        b = body[p]
        grow = 0.0
        if b >= 0:
            local[:] = piece_position[p]
            turn[:] = piece_rotation[p]
            for i in range(3):
                piece_position[p, i] = position[b, i] + (
                    rotation[b, i, 0] * local[0]
                    + rotation[b, i, 1] * local[1]
                    + rotation[b, i, 2] * local[2]
                )
                for j in range(3):
                    piece_rotation[p, i, j] = (
                        rotation[b, i, 0] * turn[0, j]
                        + rotation[b, i, 1] * turn[1, j]
                        + rotation[b, i, 2] * turn[2, j]
                    )
            grow = margin[b]
        shape = piece_shape(p, pieces, piece_position[p], piece_rotation[p])
        shape_bounds(shape[0], shape[1], shape[2], shape[6], shape[7], grow, lo, hi, p)


#: Candidate pairs from which the narrow phase runs on every thread (below, one is faster).
PARALLEL_MIN_PAIRS = 1024
#: Pairs a thread takes at a time (each chunk allocates its own work arrays once).
_CHUNK = 64


def pair_contacts(pieces, body, pairs, piece_position, piece_rotation, margin, out):
    """The contacts of each candidate pair of pieces, written to ``out`` in the pairs' order
    (the same on any number of threads).

    Args:
        pieces: :meth:`~visviva.collision.body_pieces.BodyPieces.arrays`.
        body: ``(P,)`` each piece's body (``-1``: static).
        pairs: ``(K, 2)`` piece pairs from the broad phase.
        piece_position, piece_rotation: ``(P, 3)``, ``(P, 3, 3)`` world poses.
        margin: ``(B,)`` speculative reach of each body [m]: a pair keeps contacts whose gap
            is at most the sum of its bodies'.
        out: ``(piece_a, piece_b, point (C, 3), normal (C, 3), depth (C,))`` of capacity
            ``MAX_CONTACTS · K``.

    Returns:
        How many contacts were written.
    """
    count = pairs.shape[0]
    found = np.empty(count, dtype=np.int64)
    points = np.empty((count, MAX_CONTACTS, 3))
    normals = np.empty((count, 3))
    depths = np.empty((count, MAX_CONTACTS))
    run = _pairs_parallel if count >= PARALLEL_MIN_PAIRS else _pairs_serial
    run(pieces, body, pairs, piece_position, piece_rotation, margin, found, points, normals,
        depths)  # fmt: skip
    return _gathered(pairs, found, points, normals, depths, out)


# A serial and a parallel driver, separate functions so that each has its own entry in
# Numba's cache.
@njit(cache=True)
def _pairs_serial(pieces, body, pairs, piece_position, piece_rotation, margin, found, points,
                  normals, depths):  # fmt: skip
    _pair_chunk(0, pairs.shape[0], pieces, body, pairs, piece_position, piece_rotation, margin,
                found, points, normals, depths)  # fmt: skip


@njit(cache=True, parallel=True)
def _pairs_parallel(pieces, body, pairs, piece_position, piece_rotation, margin, found, points,
                    normals, depths):  # fmt: skip
    count = pairs.shape[0]
    for chunk in prange((count + _CHUNK - 1) // _CHUNK):
        first = chunk * _CHUNK
        _pair_chunk(first, min(first + _CHUNK, count), pieces, body, pairs, piece_position,
                    piece_rotation, margin, found, points, normals, depths)  # fmt: skip


@njit(cache=True)
def _pair_chunk(first, last, pieces, body, pairs, piece_position, piece_rotation, margin,
                found, points, normals, depths):  # fmt: skip
    """Pairs ``first`` to ``last − 1``: each one's contact count ``found[k]``, points, normal
    and depths in its row of the outputs."""
    candidates = np.empty((CANDIDATES, 3))
    candidate_depths = np.empty(CANDIDATES)
    work = clip_work()
    params = pieces[1]
    for k in range(first, last):
        i, j = pairs[k, 0], pairs[k, 1]
        a, b = body[i], body[j]
        found[k] = 0
        if a == b:
            continue
        reach = (margin[a] if a >= 0 else 0.0) + (margin[b] if b >= 0 else 0.0)
        if pieces[0][i] == SPHERE and pieces[0][j] == SPHERE:
            # Two balls: along the line of centres, no iteration needed.
            found[k] = _ball_contact(params[i, 0], params[j, 0], piece_position[i],
                                     piece_position[j], reach, points[k], normals[k],
                                     depths[k])  # fmt: skip
            continue
        shape_a = piece_shape(i, pieces, piece_position[i], piece_rotation[i])
        shape_b = piece_shape(j, pieces, piece_position[j], piece_rotation[j])
        count, nx, ny, nz = convex_contacts(shape_a, shape_b, reach, candidates,
                                            candidate_depths, work)  # fmt: skip
        found[k] = count
        normals[k, 0], normals[k, 1], normals[k, 2] = nx, ny, nz
        for c in range(count):
            points[k, c] = candidates[c]
            depths[k, c] = candidate_depths[c]


@njit(cache=True)
def _gathered(pairs, found, points, normals, depths, out):
    """The pairs' contacts, in order, into ``out``; returns how many."""
    piece_a, piece_b, point, normal, depth = out
    count = 0
    for k in range(pairs.shape[0]):
        for c in range(found[k]):
            piece_a[count], piece_b[count] = pairs[k, 0], pairs[k, 1]
            point[count] = points[k, c]
            normal[count] = normals[k]
            depth[count] = depths[k, c]
            count += 1
    return count


@njit(cache=True)
def _ball_contact(radius_a, radius_b, centre_a, centre_b, reach, points, normal, depths):
    """The contact of two balls if their gap is at most ``reach`` (1, its point, normal
    and depth in the outputs), else 0."""
    dx = centre_b[0] - centre_a[0]
    dy = centre_b[1] - centre_a[1]
    dz = centre_b[2] - centre_a[2]
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    gap = distance - radius_a - radius_b
    if gap > reach:
        return 0
    if distance > 0.0:
        nx, ny, nz = dx / distance, dy / distance, dz / distance
    else:
        nx, ny, nz = 0.0, 1.0, 0.0
    # Midway between the two surfaces along the line of centres.
    along = radius_a + 0.5 * gap
    points[0, 0] = centre_a[0] + along * nx
    points[0, 1] = centre_a[1] + along * ny
    points[0, 2] = centre_a[2] + along * nz
    normal[0], normal[1], normal[2] = nx, ny, nz
    depths[0] = -gap
    return 1


@njit(cache=True)
def plane_contacts(pieces, body, meets, piece_position, piece_rotation, lo, hi, margin,
                   plane_point, plane_normal, plane_thickness, out, start):  # fmt: skip
    """The contacts of every moving piece that ``meets`` the scenery with every plane,
    appended to ``out`` from row ``start``; the plane is recorded as piece ``-1 − plane``.
    Returns the new count."""
    piece_a, piece_b, point, normal, depth = out
    points = np.empty((CANDIDATES, 3))
    depths = np.empty(CANDIDATES)
    count = start
    for f in range(plane_point.shape[0]):
        for p in range(body.shape[0]):
            b = body[p]
            if b < 0 or not meets[p]:
                continue
            # The bounding box's lowest corner along the normal tells whether it may touch.
            low = 0.0
            for axis in range(3):
                n = plane_normal[f, axis]
                low += (lo[p, axis] if n >= 0.0 else hi[p, axis]) * n
            low -= (
                plane_point[f, 0] * plane_normal[f, 0]
                + plane_point[f, 1] * plane_normal[f, 1]
                + plane_point[f, 2] * plane_normal[f, 2]
            )
            if low > 0.0:
                continue
            shape = piece_shape(p, pieces, piece_position[p], piece_rotation[p])
            separation = plane_separation(
                plane_point[f], plane_normal[f], plane_thickness[f], shape
            )
            found, nx, ny, nz = plane_manifold(separation, shape, margin[b], points, depths)
            for c in range(found):
                if count == piece_a.shape[0]:
                    return count
                piece_a[count], piece_b[count] = -1 - f, p
                point[count] = points[c]
                normal[count, 0], normal[count, 1], normal[count, 2] = nx, ny, nz
                depth[count] = depths[c]
                count += 1
    return count


def contact_arrays(capacity: int) -> tuple[np.ndarray, ...]:
    """Empty output arrays for :func:`pair_contacts` and :func:`plane_contacts`."""
    return (
        np.empty(capacity, dtype=np.int64),
        np.empty(capacity, dtype=np.int64),
        np.empty((capacity, 3)),
        np.empty((capacity, 3)),
        np.empty(capacity),
    )


@njit(cache=True)
def _triangle_shape(corners):
    """A triangle ``(3, 3)`` as a flat posed hull of two faces, its front counter-clockwise
    (the mesh's outside) first, in the world frame."""
    ex = corners[1] - corners[0]
    ey = corners[2] - corners[0]
    n = np.cross(ex, ey)
    n /= math.sqrt(np.dot(n, n))
    planes = np.empty((2, 4))
    planes[0, :3] = n
    planes[0, 3] = np.dot(n, corners[0])
    planes[1, :3] = -n
    planes[1, 3] = -planes[0, 3]
    face_start = np.array([0, 3, 6], dtype=np.int64)
    face_vertices = np.array([0, 1, 2, 0, 2, 1], dtype=np.int64)
    params = np.zeros(4)
    return (HULL, params, corners, planes, face_start, face_vertices, np.zeros(3), np.eye(3)), n


@njit(cache=True)
def mesh_contacts(node_bounds, node_links, triangle_points, first_id, pieces, body, meets,
                  piece_position, piece_rotation, lo, hi, margin, out, start):  # fmt: skip
    """The contacts of every moving piece that ``meets`` the scenery with the triangles of a
    static mesh (its tree's
    arrays, :class:`~visviva.collision.bvh.MeshBVH`) whose boxes its bounding box overlaps,
    appended to ``out`` from row ``start``; triangle slot ``s`` is recorded as piece
    ``-1 − (first_id + s)``. A triangle meets a piece only from the mesh's outside (the piece's
    origin in front of the triangle's plane), so the contacts push it out, never through.
    Returns the new count."""
    piece_a, piece_b, point, normal, depth = out
    points = np.empty((CANDIDATES, 3))
    depths = np.empty(CANDIDATES)
    stack = np.empty(STACK_SIZE, dtype=np.int64)
    count = start
    for p in range(body.shape[0]):
        b = body[p]
        if b < 0 or not meets[p]:
            continue
        stack[0] = 0
        top = 1
        while top > 0:
            top -= 1
            k = stack[top]
            overlaps = True
            for axis in range(3):
                if node_bounds[k, axis] > hi[p, axis] or node_bounds[k, 3 + axis] < lo[p, axis]:
                    overlaps = False
            if not overlaps:
                continue
            first, size = node_links[k, 0], node_links[k, 1]
            if size == 0:
                stack[top] = first
                stack[top + 1] = first + 1
                top += 2
                continue
            for slot in range(first, first + size):
                corners = triangle_points[slot]
                triangle, n = _triangle_shape(corners)
                if np.dot(n, piece_position[p] - corners[0]) < 0.0:
                    continue  # behind the triangle: inside the mesh, or beyond it
                shape = piece_shape(p, pieces, piece_position[p], piece_rotation[p])
                separation = shape_distance(triangle, shape)
                found, nx, ny, nz = contact_manifold(triangle, shape, separation, margin[b],
                                                     points, depths)  # fmt: skip
                for c in range(found):
                    if count == piece_a.shape[0]:
                        return count
                    piece_a[count], piece_b[count] = -1 - (first_id + slot), p
                    point[count] = points[c]
                    normal[count, 0], normal[count, 1], normal[count, 2] = nx, ny, nz
                    depth[count] = depths[c]
                    count += 1
    return count
