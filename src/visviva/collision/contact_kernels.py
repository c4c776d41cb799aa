"""The solve of the particle–particle contact stage (:mod:`.particle_contacts`).

The contacts found by :mod:`.contact_detection` are

* **ordered**: sorted into slabs along a horizontal axis, bottom-up within each slab, by a
  stable counting sort, each with its target normal velocity (:func:`assemble`);
* **warm-started**: given back the impulses they ended the last step with
  (:func:`remember`, :func:`warm_start`);
* **solved**: sweeps of sequential impulses over the contacts (velocities), then sweeps of
  projections (positions), slab by slab: the even slabs, then the odd ones (:func:`solve`).

A contact ``c`` joins sphere ``first[c]`` and sphere ``second[c]``, or a collider when
``second[c] = −1``; its unit normal ``n`` points from the second towards the first (a
collider's outward normal), and its gap is ``n · (x_first − x_second) + offset[c]`` (with
``x_second = 0`` for a collider): ``offset = −(r_first + r_second)`` for two spheres, so the
gap is the distance between the surfaces measured along the normal, fixed for the step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

__all__ = ["ContactArrays", "assemble", "remember", "solve", "warm_start"]


class ContactArrays(NamedTuple):
    """The contacts of one step, in solve order (structure of arrays, ``C`` contacts).

    Attributes:
        first, second: ``(C,)`` int64 particle rows (``second = −1``: a collider).
        nx, ny, nz: ``(C,)`` unit normal, from the second towards the first.
        offset: ``(C,)`` [m]: gap = ``n · (x_first − x_second) + offset``.
        friction: ``(C,)`` Coulomb coefficient μ.
        target: ``(C,)`` [m/s]: the relative normal velocity the impulses aim at
            (``−e v_n`` of a colliding contact, 0 of a resting one).
        normal_impulse: ``(C,)`` [N·s] accumulated normal impulse (≥ 0).
        tangent_impulse: ``(C, 3)`` [N·s] accumulated friction impulse.
        collider: ``(C,)`` int64 collider index (−1 for two spheres).
        start: ``(S · L + 1,)`` first contact of each (slab, layer) key.
        slabs, layers: How many slabs and layers.
    """

    first: np.ndarray
    second: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    nz: np.ndarray
    offset: np.ndarray
    friction: np.ndarray
    target: np.ndarray
    normal_impulse: np.ndarray
    tangent_impulse: np.ndarray
    collider: np.ndarray
    start: np.ndarray
    slabs: int
    layers: int


# ---------------------------------------------------------------------------------------------
# Ordering: slabs along a horizontal axis (the parallel solve's unit), layers bottom-up in each
# ---------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy")
def _cell(x, i, axis, lo, inv_width, slabs, ux, uy, uz, hlo, inv_lw, layers):  # pragma: no cover
    """Slab and layer of particle ``i``."""
    a = x[i, axis]
    f = min(max((a - lo) * inv_width, 0.0), slabs - 1.0)
    h = x[i, 0] * ux + x[i, 1] * uy + x[i, 2] * uz
    e = min(max((h - hlo) * inv_lw, 0.0), layers - 1.0)
    return np.int64(f), np.int64(e)


# fmt: off
@njit(cache=True, error_model="numpy")
def _assemble(
    x, v, radius, cf, ck, cnx, cny, cnz, coff, pf, ps, pnx, pny, pnz,
    e_pair, mu_pair, rest_pair, e_col, mu_col, rest_col,
    axis, lo, inv_width, slabs, ux, uy, uz, hlo, inv_lw, layers, h,
):  # pragma: no cover - compiled
    # fmt: on
    q, p = cf.shape[0], pf.shape[0]
    total = q + p
    keys = np.empty(total, dtype=np.int64)
    for c in range(q):
        a, b = _cell(x, cf[c], axis, lo, inv_width, slabs, ux, uy, uz, hlo, inv_lw, layers)
        keys[c] = a * layers + b
    for c in range(p):
        a, b = _cell(x, pf[c], axis, lo, inv_width, slabs, ux, uy, uz, hlo, inv_lw, layers)
        a2, b2 = _cell(x, ps[c], axis, lo, inv_width, slabs, ux, uy, uz, hlo, inv_lw, layers)
        keys[q + c] = min(a, a2) * layers + min(b, b2)
    # A stable counting sort by key (Cormen et al. §8.2): colliders first, then pairs, each in
    # detection order, within a key.
    count = slabs * layers
    start = np.zeros(count + 1, dtype=np.int64)
    for c in range(total):
        start[keys[c] + 1] += 1
    for k in range(count):
        start[k + 1] += start[k]
    cursor = start[:count].copy()
    first, second = np.empty(total, np.int64), np.empty(total, np.int64)
    collider = np.empty(total, np.int64)
    nx, ny, nz = np.empty(total), np.empty(total), np.empty(total)
    offset, friction, target = np.empty(total), np.empty(total), np.empty(total)
    for c in range(total):
        at = cursor[keys[c]]
        cursor[keys[c]] += 1
        if c < q:
            i, j, k = cf[c], -1, ck[c]
            ax, ay, az, off = cnx[c], cny[c], cnz[c], coff[c]
            e, mu, rest = e_col[k], mu_col[k], rest_col[k]
            vn = ax * v[i, 0] + ay * v[i, 1] + az * v[i, 2]
        else:
            i, j, k = pf[c - q], ps[c - q], -1
            ax, ay, az = pnx[c - q], pny[c - q], pnz[c - q]
            off = -(radius[i] + radius[j])
            e, mu, rest = e_pair, mu_pair, rest_pair
            vn = ax * (v[i, 0] - v[j, 0]) + ay * (v[i, 1] - v[j, 1]) + az * (v[i, 2] - v[j, 2])
        first[at], second[at], collider[at] = i, j, k
        nx[at], ny[at], nz[at], offset[at], friction[at] = ax, ay, az, off, mu
        gap = ax * x[i, 0] + ay * x[i, 1] + az * x[i, 2] + off
        if j >= 0:
            gap -= ax * x[j, 0] + ay * x[j, 1] + az * x[j, 2]
        # Touching, or closing the gap within the next step: a collision now, with a bounce
        # unless slower than the resting speed (Mirtich's threshold). Otherwise a speculative
        # contact: the spheres may approach by the gap in a step, not more.
        if gap <= 0.0 or gap + vn * h < 0.0:
            target[at] = -e * vn if vn < -rest else 0.0
        else:
            target[at] = -gap / h
    return first, second, nx, ny, nz, offset, friction, target, collider, start


def assemble(x, v, radius, colliders_found, pairs_found, pair_law, collider_law, frame, h):
    """The :class:`ContactArrays` of one step, in solve order.

    Args:
        x, v: ``(N, 3)`` positions [m] and velocities [m/s] at the step's end.
        radius: ``(N,)`` radii [m].
        colliders_found: :func:`collider_contacts`' result.
        pairs_found: :func:`pair_contacts`' result.
        pair_law: ``(e, μ, resting speed)`` of sphere pairs.
        collider_law: ``(e, μ, resting speed)`` arrays, one entry per collider.
        frame: ``(axis, low, 1/width, slabs, u, height low, 1/layer height, layers)``.
        h: The step [s] (a speculative contact may close its gap in one).
    """
    axis, lo, inv_width, slabs, (ux, uy, uz), hlo, inv_lw, layers = frame
    arrays = _assemble(
        x, v, radius, *colliders_found, *pairs_found, *pair_law, *collider_law,
        axis, lo, inv_width, slabs, ux, uy, uz, hlo, inv_lw, layers, h,
    )  # fmt: skip
    first, second, nx, ny, nz, offset, friction, target, collider, start = arrays
    total = first.shape[0]
    return ContactArrays(
        first, second, nx, ny, nz, offset, friction, target, np.zeros(total),
        np.zeros((total, 3)), collider, start, slabs, layers,
    )  # fmt: skip


# ---------------------------------------------------------------------------------------------
# The solve: sequential impulses, then projections
# ---------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy")
def _impulses(k, c, v, w):  # pragma: no cover - compiled
    """One sweep of sequential impulses over contacts ``k.start[key]`` of the slab ``c``
    (Catto 2005): the normal impulse accumulated and kept ≥ 0, then the friction impulse
    accumulated and kept within μ times it; each change applied to the two spheres equal and
    opposite (``Δv_i = w_i J``, ``Δv_j = −w_j J``)."""
    begin, end = k.start[c * k.layers], k.start[(c + 1) * k.layers]
    first, second, lt = k.first, k.second, k.tangent_impulse
    for a in range(begin, end):
        i, j = first[a], second[a]
        wi = w[i]
        wj = w[j] if j >= 0 else 0.0
        total = wi + wj
        if total == 0.0:
            continue
        meff = 1.0 / total
        ux, uy, uz = k.nx[a], k.ny[a], k.nz[a]
        rx, ry, rz = v[i, 0], v[i, 1], v[i, 2]
        if j >= 0:
            rx, ry, rz = rx - v[j, 0], ry - v[j, 1], rz - v[j, 2]
        vn = ux * rx + uy * ry + uz * rz
        old = k.normal_impulse[a]
        new = max(old + meff * (k.target[a] - vn), 0.0)
        k.normal_impulse[a] = new
        dn = new - old
        # The relative velocity after the normal change, then its tangential part.
        rx, ry, rz = rx + total * dn * ux, ry + total * dn * uy, rz + total * dn * uz
        vn = ux * rx + uy * ry + uz * rz
        tx, ty, tz = rx - vn * ux, ry - vn * uy, rz - vn * uz
        ox, oy, oz = lt[a, 0], lt[a, 1], lt[a, 2]
        gx, gy, gz = ox - meff * tx, oy - meff * ty, oz - meff * tz
        size = math.sqrt(gx * gx + gy * gy + gz * gz)
        cap = k.friction[a] * new
        if size > cap:
            scale = cap / size
            gx, gy, gz = gx * scale, gy * scale, gz * scale
        lt[a, 0], lt[a, 1], lt[a, 2] = gx, gy, gz
        jx, jy, jz = dn * ux + gx - ox, dn * uy + gy - oy, dn * uz + gz - oz
        v[i, 0] += wi * jx
        v[i, 1] += wi * jy
        v[i, 2] += wi * jz
        if j >= 0:
            v[j, 0] -= wj * jx
            v[j, 1] -= wj * jy
            v[j, 2] -= wj * jz


@njit(cache=True, error_model="numpy")
def _projections(k, c, x, w):  # pragma: no cover - compiled
    """One sweep of projections over the contacts of slab ``c``: an overlap (negative gap) is
    removed by moving the two spheres apart along the normal, ``w_i / (w_i + w_j)`` of it the
    first and the rest the second, so their centre of mass stays where it is; velocities are
    untouched (no kinetic energy is added)."""
    begin, end = k.start[c * k.layers], k.start[(c + 1) * k.layers]
    first, second = k.first, k.second
    for a in range(begin, end):
        i, j = first[a], second[a]
        wi = w[i]
        wj = w[j] if j >= 0 else 0.0
        total = wi + wj
        if total == 0.0:
            continue
        ux, uy, uz = k.nx[a], k.ny[a], k.nz[a]
        gap = ux * x[i, 0] + uy * x[i, 1] + uz * x[i, 2] + k.offset[a]
        if j >= 0:
            gap -= ux * x[j, 0] + uy * x[j, 1] + uz * x[j, 2]
        if gap >= 0.0:
            continue
        push = -gap / total
        x[i, 0] += wi * push * ux
        x[i, 1] += wi * push * uy
        x[i, 2] += wi * push * uz
        if j >= 0:
            x[j, 0] -= wj * push * ux
            x[j, 1] -= wj * push * uy
            x[j, 2] -= wj * push * uz


# Temporal coherence (Catto 2005): a contact that persists from one step to the next starts
# from the impulses it ended the last step with, so a resting pile's impulses converge over
# steps rather than within one. Contacts are remembered by their lower particle (a counting
# sort, O(N + C)) and its partner: the other particle, or N + k for collider k; impulses are
# kept as acting on the lower particle.


@njit(cache=True)
def _partner(i, j, k, count):  # pragma: no cover - compiled
    """The lower particle of a contact, its partner's code, and the sign of the impulses on the
    lower particle (+1 if it is the contact's first)."""
    if j < 0:
        return i, count + k, 1.0
    if i < j:
        return i, j, 1.0
    return j, i, -1.0


@njit(cache=True)
def remember(k, count):  # pragma: no cover - compiled
    """The impulses of the contacts ``k`` by lower particle: ``(start, partner, normal,
    tangent)``, ``start`` of shape ``(count + 1,)``."""
    total = k.first.shape[0]
    start = np.zeros(count + 1, dtype=np.int64)
    for a in range(total):
        low, _, _ = _partner(k.first[a], k.second[a], k.collider[a], count)
        start[low + 1] += 1
    for i in range(count):
        start[i + 1] += start[i]
    cursor = start[:count].copy()
    partner = np.empty(total, dtype=np.int64)
    normal, tangent = np.empty(total), np.empty((total, 3))
    for a in range(total):
        low, code, sign = _partner(k.first[a], k.second[a], k.collider[a], count)
        at = cursor[low]
        cursor[low] += 1
        partner[at], normal[at] = code, k.normal_impulse[a]
        for d in range(3):
            tangent[at, d] = sign * k.tangent_impulse[a, d]
    return start, partner, normal, tangent


@njit(cache=True, error_model="numpy")
def warm_start(k, start, partner, normal, tangent, v, w):  # pragma: no cover - compiled
    """Give each contact found in the last step's memory its impulses back (the friction
    impulse projected on the new tangent plane and kept within μ times the normal one) and
    apply them, equal and opposite; return how many contacts were warm-started."""
    count = start.shape[0] - 1
    warmed = 0
    for a in range(k.first.shape[0]):
        i, j = k.first[a], k.second[a]
        low, code, sign = _partner(i, j, k.collider[a], count)
        found = -1
        for b in range(start[low], start[low + 1]):
            if partner[b] == code:
                found = b
                break
        if found < 0:
            continue
        ux, uy, uz = k.nx[a], k.ny[a], k.nz[a]
        ln = normal[found]
        gx, gy, gz = sign * tangent[found, 0], sign * tangent[found, 1], sign * tangent[found, 2]
        along = gx * ux + gy * uy + gz * uz
        gx, gy, gz = gx - along * ux, gy - along * uy, gz - along * uz
        size = math.sqrt(gx * gx + gy * gy + gz * gz)
        cap = k.friction[a] * ln
        if size > cap:
            gx, gy, gz = gx * (cap / size), gy * (cap / size), gz * (cap / size)
        k.normal_impulse[a] = ln
        k.tangent_impulse[a, 0], k.tangent_impulse[a, 1], k.tangent_impulse[a, 2] = gx, gy, gz
        jx, jy, jz = ln * ux + gx, ln * uy + gy, ln * uz + gz
        wi = w[i]
        v[i, 0] += wi * jx
        v[i, 1] += wi * jy
        v[i, 2] += wi * jz
        if j >= 0:
            wj = w[j]
            v[j, 0] -= wj * jx
            v[j, 1] -= wj * jy
            v[j, 2] -= wj * jz
        warmed += 1
    return warmed


# Slab c holds the contacts whose lower slab is c, so they touch spheres of slabs c and c + 1
# only: slabs c and c + 2 share no sphere, and the even slabs (then the odd ones) can be swept
# at once. The order of the updates is the same whether they are (two cores) or not.


@njit(cache=True, parallel=True)
def _solve_parallel(k, x, v, w, velocity_sweeps, position_sweeps):  # pragma: no cover
    for _ in range(velocity_sweeps):
        for colour in range(2):
            for q in prange((k.slabs - colour + 1) // 2):
                _impulses(k, colour + 2 * q, v, w)
    for _ in range(position_sweeps):
        for colour in range(2):
            for q in prange((k.slabs - colour + 1) // 2):
                _projections(k, colour + 2 * q, x, w)


@njit(cache=True)
def _solve_serial(k, x, v, w, velocity_sweeps, position_sweeps):  # pragma: no cover - compiled
    for _ in range(velocity_sweeps):
        for colour in range(2):
            for q in range((k.slabs - colour + 1) // 2):
                _impulses(k, colour + 2 * q, v, w)
    for _ in range(position_sweeps):
        for colour in range(2):
            for q in range((k.slabs - colour + 1) // 2):
                _projections(k, colour + 2 * q, x, w)


def solve(k: ContactArrays, x, v, w, velocity_sweeps: int, position_sweeps: int, parallel: bool):
    """Sweeps of impulses on ``v`` [m/s], then of projections on ``x`` [m] (in place);
    ``w`` ``(N,)`` inverse masses [1/kg] (0: immovable). The same result either way."""
    (_solve_parallel if parallel else _solve_serial)(k, x, v, w, velocity_sweeps, position_sweeps)
