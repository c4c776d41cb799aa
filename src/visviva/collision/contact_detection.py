"""Detection for the particle–particle contact stage (:mod:`.particle_contacts`).

The pairs of spheres that touch at the step's end, whose centres' paths crossed within the
step, or that are apart by less than a margin (speculative contacts), found on the shared
neighbour grid each once; each sphere's contacts with the static colliders; and two scans
the stage needs (the largest radius and move; the extents that place the solve's slabs).
Contacts are written in the grid's sorted order, so the result does not depend on the number
of threads.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..geometry.neighbour_cells import cell_of, neighbour_runs
from .colliders import collider_distance

__all__ = ["CHUNK", "collider_contacts", "extents", "pair_contacts", "scan"]

#: Sorted points per parallel task of the detection.
CHUNK = 256


@njit(cache=True, error_model="numpy")
def _pair_test(i, j, px, py, pz, x0, radius, slack):  # pragma: no cover - compiled
    """Whether spheres ``i`` and ``j``, their centres ``p = x_i − x_j`` apart at the step's end,
    are in contact, and the unit normal (from ``j`` towards ``i``).

    In contact: overlapping at the end (``|p| < R = r_i + r_j``; the normal along ``p``, or a
    fixed one, +y, if the centres coincide); or apart at the end but their relative path from
    the step's start ``q = x0_i − x0_j`` to ``p`` (a straight chord) entered the distance
    ``R``: they passed through each other, and the normal is the direction at the first touch,
    ``|q + s(p − q)| = R``, the smaller root of ``|d|² s² + 2 (q·d) s + |q|² − R² = 0`` with
    ``d = p − q``; or apart by less than ``slack`` (a speculative contact, along ``p``).
    """
    big = radius[i] + radius[j]
    d2 = px * px + py * py + pz * pz
    if d2 < big * big:
        d = math.sqrt(d2)
        if d > 0.0:
            return True, px / d, py / d, pz / d
        return True, 0.0, 1.0, 0.0
    qx, qy, qz = x0[i, 0] - x0[j, 0], x0[i, 1] - x0[j, 1], x0[i, 2] - x0[j, 2]
    dx, dy, dz = px - qx, py - qy, pz - qz
    a = dx * dx + dy * dy + dz * dz
    b = qx * dx + qy * dy + qz * dz  # half the linear coefficient
    c = qx * qx + qy * qy + qz * qz - big * big
    if c > 0.0 and b < 0.0 and b * b - a * c >= 0.0:  # apart at the start, approaching
        s = (-b - math.sqrt(b * b - a * c)) / a
        mx, my, mz = qx + s * dx, qy + s * dy, qz + s * dz
        m = math.sqrt(mx * mx + my * my + mz * mz)
        if s <= 1.0 and m > 0.0:
            return True, mx / m, my / m, mz / m
    limit = big + slack
    if d2 < limit * limit:
        d = math.sqrt(d2)
        return True, px / d, py / d, pz / d
    return False, 0.0, 0.0, 0.0


@njit(cache=True, error_model="numpy")
def _pairs_chunk(
    g, x0, radius, reach2, slack, begin, end, offsets, write, first, second, nx, ny, nz
):  # pragma: no cover - compiled
    """Sorted positions ``begin .. end − 1``: count each one's contacts with later sorted
    positions into ``offsets[s + 1]``, or (``write``) write them from ``offsets[s]`` on."""
    runs = np.empty((27, 2), dtype=np.int64)
    x, y, z, order = g.x, g.y, g.z, g.order
    for s in range(begin, end):
        xi, yi, zi = x[s], y[s], z[s]
        cx, cy, cz = cell_of(xi, yi, zi, g.inv_cell)
        m = neighbour_runs(g, cx, cy, cz, runs)
        i = order[s]
        c = offsets[s] if write else 0
        for k in range(m):
            for t in range(max(runs[k, 0], s + 1), runs[k, 1]):
                px, py, pz = xi - x[t], yi - y[t], zi - z[t]
                if px * px + py * py + pz * pz > reach2:
                    continue
                hit, ux, uy, uz = _pair_test(i, order[t], px, py, pz, x0, radius, slack)
                if hit:
                    if write:
                        first[c], second[c] = i, order[t]
                        nx[c], ny[c], nz[c] = ux, uy, uz
                    c += 1
        if not write:
            offsets[s + 1] = c


@njit(cache=True, error_model="numpy")
def _colliders_chunk(
    x,
    radius,
    order,
    masks,
    slack,
    begin,
    end,
    offsets,
    write,
    first,
    which,
    nx,
    ny,
    nz,
    offset,
    colliders,
):  # pragma: no cover - compiled
    """Sorted positions ``begin .. end − 1``: count (or write) each sphere's contacts with the
    colliders of its mask, within ``r + slack`` of its centre."""  # fmt: skip
    kinds, rows, offs, nb, nl, tp, tn = colliders
    for s in range(begin, end):
        i = order[s]
        c = offsets[s] if write else 0
        mask = masks[i]
        if mask != 0:
            r = radius[i]
            for k in range(kinds.shape[0]):
                if not (mask >> np.uint64(k)) & np.uint64(1):
                    continue
                d, ux, uy, uz = collider_distance(
                    k, x[i, 0], x[i, 1], x[i, 2], kinds, rows, offs, nb, nl, tp, tn
                )
                if d < r + slack:
                    if write:
                        first[c], which[c] = i, k
                        nx[c], ny[c], nz[c] = ux, uy, uz
                        # gap(x) = d + n·(x − x_now) − r, linear along the normal.
                        offset[c] = d - r - (ux * x[i, 0] + uy * x[i, 1] + uz * x[i, 2])
                    c += 1
        if not write:
            offsets[s + 1] = c


@njit(cache=True, parallel=True)
def _pairs_parallel(g, x0, radius, reach2, slack, offsets, write, first, second, nx, ny, nz):
    n = g.order.shape[0]  # pragma: no cover - compiled
    for task in prange((n + CHUNK - 1) // CHUNK):
        begin, end = task * CHUNK, min(n, task * CHUNK + CHUNK)
        _pairs_chunk(
            g, x0, radius, reach2, slack, begin, end, offsets, write, first, second, nx, ny, nz
        )


@njit(cache=True)
def _pairs_serial(g, x0, radius, reach2, slack, offsets, write, first, second, nx, ny, nz):
    n = g.order.shape[0]  # pragma: no cover - compiled
    _pairs_chunk(g, x0, radius, reach2, slack, 0, n, offsets, write, first, second, nx, ny, nz)


@njit(cache=True)
def _prefix(offsets):  # pragma: no cover - compiled
    """Counts in ``offsets[1:]`` to offsets, in place; the total."""
    offsets[0] = 0
    for s in range(offsets.shape[0] - 1):
        offsets[s + 1] += offsets[s]
    return offsets[offsets.shape[0] - 1]


def pair_contacts(g, x0, radius, reach: float, slack: float, parallel: bool):
    """The sphere pairs in contact (see :func:`_pair_test`) among the grid's points, each once:
    ``(first, second, nx, ny, nz)``, ordered by the first's sorted position."""
    n = g.order.shape[0]
    offsets = np.zeros(n + 1, dtype=np.int64)
    run = _pairs_parallel if parallel else _pairs_serial
    none = np.zeros(0, dtype=np.int64)
    empty = np.zeros(0)
    reach2 = reach * reach
    run(g, x0, radius, reach2, slack, offsets, False, none, none, empty, empty, empty)
    total = int(_prefix(offsets))
    first, second = np.empty(total, np.int64), np.empty(total, np.int64)
    nx, ny, nz = np.empty(total), np.empty(total), np.empty(total)
    if total:
        run(g, x0, radius, reach2, slack, offsets, True, first, second, nx, ny, nz)
    return first, second, nx, ny, nz


@njit(cache=True, parallel=True)
def _colliders_all(x, radius, order, masks, slack, offsets, write, first, which, nx, ny, nz, off,
                   colliders):  # fmt: skip
    n = order.shape[0]  # pragma: no cover - compiled
    for task in prange((n + CHUNK - 1) // CHUNK):
        begin, end = task * CHUNK, min(n, task * CHUNK + CHUNK)
        _colliders_chunk(
            x, radius, order, masks, slack, begin, end, offsets, write, first, which, nx, ny, nz,
            off, colliders,
        )  # fmt: skip


def collider_contacts(x, radius, order, masks, slack: float, colliders):
    """Each sphere's contacts with the colliders: ``(first, which, nx, ny, nz, offset)`` in the
    spheres' ``order``. Every sphere's own work, so the result is the same on any number of
    threads."""
    n = order.shape[0]
    offsets = np.zeros(n + 1, dtype=np.int64)
    none, empty = np.zeros(0, dtype=np.int64), np.zeros(0)
    _colliders_all(
        x, radius, order, masks, slack, offsets, False, none, none, empty, empty, empty, empty,
        colliders,
    )  # fmt: skip
    total = int(_prefix(offsets))
    first, which = np.empty(total, np.int64), np.empty(total, np.int64)
    nx, ny, nz, offset = np.empty(total), np.empty(total), np.empty(total), np.empty(total)
    if total:
        _colliders_all(
            x, radius, order, masks, slack, offsets, True, first, which, nx, ny, nz, offset,
            colliders,
        )  # fmt: skip
    return first, which, nx, ny, nz, offset


@njit(cache=True)
def extents(x, y, z, ux, uy, uz):  # pragma: no cover - compiled
    """``(low, high)`` of each coordinate and of the height ``p · u`` over the points
    ``(x, y, z)``, as a ``(4, 2)`` array (rows: x, y, z, height)."""
    out = np.zeros((4, 2))
    for s in range(x.shape[0]):
        h = x[s] * ux + y[s] * uy + z[s] * uz
        for row, a in ((0, x[s]), (1, y[s]), (2, z[s]), (3, h)):
            if s == 0 or a < out[row, 0]:
                out[row, 0] = a
            if s == 0 or a > out[row, 1]:
                out[row, 1] = a
    return out


@njit(cache=True)
def scan(x0, x, radius, active):  # pragma: no cover - compiled
    """Over the ``active`` spheres: the largest radius [m], the largest move ``|x − x0|`` of
    the step [m], and whether every position is finite."""
    largest = move = 0.0
    for i in range(x.shape[0]):
        if not active[i]:
            continue
        dx, dy, dz = x[i, 0] - x0[i, 0], x[i, 1] - x0[i, 1], x[i, 2] - x0[i, 2]
        d2 = dx * dx + dy * dy + dz * dz
        if not (math.isfinite(d2) and math.isfinite(x[i, 0] + x[i, 1] + x[i, 2])):
            return largest, move, False
        largest = max(largest, radius[i])
        move = max(move, math.sqrt(d2))
    return largest, move, True
