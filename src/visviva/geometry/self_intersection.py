"""Self-intersections of a triangle mesh: pairs of triangles whose interiors cross.

A closed, outward mesh whose surface passes through itself — two overlapping shells merged in
one mesh, a surface folded through itself — bounds no single solid: its enclosed-volume
integrals count the overlap twice (or cancel a folded part). :func:`check_self_intersections`
refuses it, naming two crossing triangles.

Broad phase: a uniform grid of cubic cells twice the mean longest side of the triangles'
bounding boxes (doubled again until the triangles touch at most :data:`_ENTRIES_PER_TRIANGLE`
cells each on average), stored as a hash table bucketed by a counting sort: O(T) time and
memory for T triangles of similar sizes, with no T² step. Each pair of triangles whose boxes
overlap is tested once, in the one cell holding the lowest corner of the boxes' intersection.
Cost: about 0.25 µs a triangle on 2 cores of a 2020s laptop-class CPU — some ten times the mass
integrals themselves (``benchmarks/bench_mass_properties.py`` measures both).

Narrow phase: two triangles that are not coplanar cross if and only if an edge of one passes
through the other (the segment where they meet ends on such edges). Edge ab passes through
triangle cde when a and b lie strictly on opposite sides of the plane of cde and the line ab
passes strictly inside its three edges: the signs of the orientation determinants
[a, b, c, d], [a, b, d, e], [a, b, e, c] agree, where [p, q, r, s] = (q − p)·((r − p) × (s − p)).
A determinant within :data:`ORIENTATION_TOLERANCE` of the pair's size cubed counts as zero, so
rounding reports nothing. A line through the inside of an edge cd (one determinant zero) is
decided with the neighbouring triangle across cd, as if the line were moved off the edge by an
infinitesimal (simulation of simplicity, H. Edelsbrunner and E. P. Mücke, *ACM Transactions on
Graphics* 9(1), 1990): it then pierces exactly one of the two triangles — the surface is crossed —
when both face the line the same way, and both or neither — a ridge or valley is touched —
otherwise. Overlapping boxes offset along a diagonal cross each other exactly through their
faces' diagonal edges, and are seen.

Not reported, by design: pairs of triangles sharing a vertex (a mesh's neighbours touch there),
touching contacts (a vertex or an edge resting on another triangle), coplanar overlaps, and a
line passing exactly through a vertex. Two shells that really overlap have edges of one
crossing faces of the other, away from such coincidences.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .._validation import describe
from ..errors import ModelError
from .mesh_topology import _paired_edges

__all__ = ["ORIENTATION_TOLERANCE", "check_self_intersections", "find_self_intersection"]

#: An orientation determinant below this fraction of the cube of the pair's extent is zero.
ORIENTATION_TOLERANCE = 1e-12
#: Cell side over the mean longest side of the triangles' boxes: larger cells hold more
#: triangles (more pairs to try), smaller ones more entries (more memory to fill).
_CELL_SCALE = 2.0
#: Average (triangle, cell) entries per triangle allowed before the cells are made larger.
_ENTRIES_PER_TRIANGLE = 8
#: Cells per axis at most, so that a cell's three integer coordinates pack into one int64 key.
_CELL_BITS = 20
#: Odd multiplier of the hash (the 64-bit LCG multiplier of PCG, below 2⁶³).
_MIX = 6364136223846793005


@njit(cache=True)
def _boxes(
    vertices: np.ndarray, triangles: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
    """Each triangle's bounding box (``lo``, ``hi``), the mesh's lowest corner, its largest
    extent and the mean of the boxes' longest sides (in one pass: NumPy's reductions along
    short rows cost more than this whole loop)."""
    count = triangles.shape[0]
    lo = np.empty((count, 3))
    hi = np.empty((count, 3))
    low = np.full(3, np.inf)
    high = np.full(3, -np.inf)
    longest = 0.0
    for t in range(count):
        side = 0.0
        for axis in range(3):
            a = vertices[triangles[t, 0], axis]
            b = vertices[triangles[t, 1], axis]
            c = vertices[triangles[t, 2], axis]
            lo[t, axis] = min(a, b, c)
            hi[t, axis] = max(a, b, c)
            low[axis] = min(low[axis], lo[t, axis])
            high[axis] = max(high[axis], hi[t, axis])
            side = max(side, hi[t, axis] - lo[t, axis])
        longest += side
    return lo, hi, low, float(np.max(high - low)), longest / count


@njit(cache=True, inline="always")
def _cell(x: float, base: float, inverse: float) -> int:
    return int(np.floor((x - base) * inverse))


@njit(cache=True)
def _entry_count(lo: np.ndarray, hi: np.ndarray, base: np.ndarray, inverse: float) -> int:
    total = 0
    for t in range(lo.shape[0]):
        cells = 1
        for axis in range(3):
            first = _cell(lo[t, axis], base[axis], inverse)
            cells *= _cell(hi[t, axis], base[axis], inverse) - first + 1
        total += cells
    return total


@njit(cache=True, inline="always")
def _key(i: int, j: int, k: int) -> int:
    return i | (j << _CELL_BITS) | (k << (2 * _CELL_BITS))


@njit(cache=True, inline="always")
def _bucket(key: int, mask: int) -> int:
    h = key ^ (key >> 29)
    h = h * _MIX
    h = h ^ (h >> 32)
    return h & mask


@njit(cache=True, inline="always")
def _cell_range(
    lo: np.ndarray, hi: np.ndarray, t: int, base: np.ndarray, inverse: float
) -> tuple[int, int, int, int, int, int]:
    return (
        _cell(lo[t, 0], base[0], inverse),
        _cell(hi[t, 0], base[0], inverse),
        _cell(lo[t, 1], base[1], inverse),
        _cell(hi[t, 1], base[1], inverse),
        _cell(lo[t, 2], base[2], inverse),
        _cell(hi[t, 2], base[2], inverse),
    )


@njit(cache=True)
def _grid(
    lo: np.ndarray, hi: np.ndarray, base: np.ndarray, inverse: float, entries: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bucket every (triangle, cell) entry by a hash of its cell (a counting sort).

    Returns ``bounds``, where bucket ``b`` holds entries ``bounds[b + 1]`` to ``bounds[b + 2]``,
    and per entry its triangle, its cell's key and ``lowest``, whose bit ``a`` says that the
    cell is the triangle's first along axis ``a``. Kept small (13 bytes an entry): on a large
    mesh the time goes to touching fresh memory.
    """
    buckets = 1
    while buckets < entries:
        buckets *= 2
    mask = buckets - 1
    bounds = np.zeros(buckets + 2, dtype=np.int64)
    for t in range(lo.shape[0]):
        i0, i1, j0, j1, k0, k1 = _cell_range(lo, hi, t, base, inverse)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                for k in range(k0, k1 + 1):
                    bounds[_bucket(_key(i, j, k), mask) + 1] += 1
    for b in range(buckets):
        bounds[b + 1] += bounds[b]  # the end of bucket b
    bounds[buckets + 1] = entries
    triangle = np.empty(entries, dtype=np.int32)
    key = np.empty(entries, dtype=np.int64)
    lowest = np.empty(entries, dtype=np.int8)
    for t in range(lo.shape[0]):
        i0, i1, j0, j1, k0, k1 = _cell_range(lo, hi, t, base, inverse)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                for k in range(k0, k1 + 1):
                    code = _key(i, j, k)
                    b = _bucket(code, mask)
                    bounds[b + 1] -= 1  # filled from its end: ends at the start of bucket b
                    n = bounds[b + 1]
                    triangle[n] = t
                    key[n] = code
                    lowest[n] = (i == i0) | ((j == j0) << 1) | ((k == k0) << 2)
    return bounds, triangle, key, lowest


@njit(cache=True, inline="always")
def _orient(v: np.ndarray, a: int, b: int, c: int, d: int) -> float:
    """[a, b, c, d] = (b − a)·((c − a) × (d − a)) for rows a, b, c, d of ``v``."""
    bx, by, bz = v[b, 0] - v[a, 0], v[b, 1] - v[a, 1], v[b, 2] - v[a, 2]
    cx, cy, cz = v[c, 0] - v[a, 0], v[c, 1] - v[a, 1], v[c, 2] - v[a, 2]
    dx, dy, dz = v[d, 0] - v[a, 0], v[d, 1] - v[a, 1], v[d, 2] - v[a, 2]
    return bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx)


@njit(cache=True, inline="always")
def _side(value: float, tolerance: float) -> int:
    if value > tolerance:
        return 1
    if value < -tolerance:
        return -1
    return 0


@njit(cache=True)
def _pierces(
    v: np.ndarray,
    a: int,
    b: int,
    triangles: np.ndarray,
    far: np.ndarray,
    t: int,
    tolerance: float,
) -> bool:
    """Whether the line ab crosses the surface at triangle t (a, b on either side of its
    plane): strictly inside it, or through the inside of one of its edges where the
    neighbour across that edge faces the line the same way."""
    c, d, e = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    s0 = _side(_orient(v, a, b, c, d), tolerance)  # about edge c → d (slot 0)
    s1 = _side(_orient(v, a, b, d, e), tolerance)  # d → e (slot 1)
    s2 = _side(_orient(v, a, b, e, c), tolerance)  # e → c (slot 2)
    if s0 != 0 and s0 == s1 and s1 == s2:
        return True
    # Through an edge: exactly one side zero, the other two agreeing.
    if s0 == 0 and s1 != 0 and s1 == s2:
        slot, p, sigma = 0, c, s1  # the edge p → q, here c → d
    elif s1 == 0 and s2 != 0 and s2 == s0:
        slot, p, sigma = 1, d, s2
    elif s2 == 0 and s0 != 0 and s0 == s1:
        slot, p, sigma = 2, e, s0
    else:
        return False
    f = far[t, slot]
    if f < 0:
        return False
    # The neighbour (q, p, f): a line moved off the edge pierces exactly one of the two
    # triangles (it crosses the surface) when both face it the same way, both or neither (it
    # touches a ridge or a valley) otherwise.
    return _side(_orient(v, a, b, p, f), tolerance) == sigma


@njit(cache=True)
def _cross(
    v: np.ndarray, triangles: np.ndarray, far: np.ndarray, s: int, t: int, tolerance: float
) -> bool:
    """Whether triangles s and t cross, by the edge test above."""
    p0, p1, p2 = triangles[s, 0], triangles[s, 1], triangles[s, 2]
    q0, q1, q2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    a0 = _side(_orient(v, q0, q1, q2, p0), tolerance)  # sides of s's vertices about t's plane
    a1 = _side(_orient(v, q0, q1, q2, p1), tolerance)
    a2 = _side(_orient(v, q0, q1, q2, p2), tolerance)
    if abs(a0 + a1 + a2) == 3:
        return False  # s wholly on one side of t's plane
    b0 = _side(_orient(v, p0, p1, p2, q0), tolerance)
    b1 = _side(_orient(v, p0, p1, p2, q1), tolerance)
    b2 = _side(_orient(v, p0, p1, p2, q2), tolerance)
    if abs(b0 + b1 + b2) == 3:
        return False
    return (
        (a0 * a1 < 0 and _pierces(v, p0, p1, triangles, far, t, tolerance))
        or (a1 * a2 < 0 and _pierces(v, p1, p2, triangles, far, t, tolerance))
        or (a2 * a0 < 0 and _pierces(v, p2, p0, triangles, far, t, tolerance))
        or (b0 * b1 < 0 and _pierces(v, q0, q1, triangles, far, s, tolerance))
        or (b1 * b2 < 0 and _pierces(v, q1, q2, triangles, far, s, tolerance))
        or (b2 * b0 < 0 and _pierces(v, q2, q0, triangles, far, s, tolerance))
    )


@njit(cache=True)
def _far_vertices(triangles: np.ndarray, triangle_edges: np.ndarray) -> np.ndarray:
    """Per triangle and edge slot (a → b, b → c, c → a), the vertex of the neighbour across
    that edge not on it; −1 without ``triangle_edges`` (an empty array)."""
    count = triangles.shape[0]
    far = np.full((count, 3), -1, dtype=np.int64)
    if triangle_edges.shape[0] != count:
        return far
    first = np.full(3 * count, -1, dtype=np.int64)  # the first directed edge seen per edge
    for t in range(count):
        for slot in range(3):
            edge = triangle_edges[t, slot]
            other = first[edge]
            if other < 0:
                first[edge] = 3 * t + slot
                continue
            u, k = other // 3, other % 3
            far[t, slot] = triangles[u, (k + 2) % 3]
            far[u, k] = triangles[t, (slot + 2) % 3]
    return far


#: Buckets are walked in this many chunks (one lowest pair kept per chunk).
_CHUNKS = 256


@njit(cache=True, parallel=True)
def _crossing_pairs(
    vertices: np.ndarray,
    triangles: np.ndarray,
    far: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    bounds: np.ndarray,
    entry_triangle: np.ndarray,
    entry_key: np.ndarray,
    entry_lowest: np.ndarray,
) -> np.ndarray:
    """Per chunk of buckets, the lowest crossing pair (s < t) found in it, or (-1, -1)."""
    buckets = bounds.shape[0] - 2
    per_chunk = (buckets + _CHUNKS - 1) // _CHUNKS
    found = np.full((_CHUNKS, 2), -1, dtype=np.int64)
    for chunk in prange(_CHUNKS):
        for b in range(chunk * per_chunk, min(buckets, (chunk + 1) * per_chunk)):
            for x in range(bounds[b + 1], bounds[b + 2]):
                for y in range(x + 1, bounds[b + 2]):
                    # Same cell, and the cell holds the lowest corner of the boxes'
                    # intersection (along each axis, the first cell of one of the two): each
                    # pair is tested once.
                    if (entry_lowest[x] | entry_lowest[y]) != 7 or entry_key[x] != entry_key[y]:
                        continue
                    s = min(entry_triangle[x], entry_triangle[y])
                    t = max(entry_triangle[x], entry_triangle[y])
                    overlap = True
                    extent = 0.0
                    for axis in range(3):
                        low = max(lo[s, axis], lo[t, axis])
                        overlap = overlap and low <= min(hi[s, axis], hi[t, axis])
                        width = max(hi[s, axis], hi[t, axis]) - min(lo[s, axis], lo[t, axis])
                        extent = max(extent, width)
                    if not overlap:
                        continue
                    shared = False
                    for m in range(3):
                        for n in range(3):
                            shared = shared or triangles[s, m] == triangles[t, n]
                    if shared:
                        continue
                    tolerance = ORIENTATION_TOLERANCE * extent * extent * extent
                    if _cross(vertices, triangles, far, s, t, tolerance) and (
                        found[chunk, 0] < 0
                        or s < found[chunk, 0]
                        or (s == found[chunk, 0] and t < found[chunk, 1])
                    ):
                        found[chunk, 0] = s
                        found[chunk, 1] = t
    return found


def find_self_intersection(
    vertices: np.ndarray, triangles: np.ndarray, triangle_edges: np.ndarray | None = None
) -> tuple[int, int] | None:
    """The crossing pair of triangles (s, t), s < t, lowest in s then t, or ``None``.

    Args:
        vertices: ``(V, 3)`` float64 vertex positions [m], C-contiguous, finite.
        triangles: ``(T, 3)`` int64 vertex indices, valid (as from
            :func:`visviva.geometry.mesh_topology.mesh_arrays`).
        triangle_edges: ``(T, 3)`` edge indices as returned by
            :func:`~visviva.geometry.mesh_topology.check_closed_mesh` (found again if not
            given; for a mesh that is not closed, crossings through an edge are not seen).
    """
    if triangles.shape[0] < 2:
        return None
    lo, hi, base, span, mean_side = _boxes(vertices, triangles)
    # Cells no smaller than the span over 2^20, so that their coordinates pack in the key.
    size = max(_CELL_SCALE * mean_side, span / float((1 << _CELL_BITS) - 2), np.finfo(float).tiny)
    while True:
        entries = _entry_count(lo, hi, base, 1.0 / size)
        if entries <= _ENTRIES_PER_TRIANGLE * triangles.shape[0]:
            break
        size *= 2.0
    inverse = 1.0 / size
    if triangle_edges is None:
        paired = _paired_edges(triangles, vertices.shape[0])
        triangle_edges = paired.reshape(-1, 3) if paired.size else np.empty((0, 3), np.int64)
    far = _far_vertices(triangles, np.ascontiguousarray(triangle_edges, dtype=np.int64))
    grid = _grid(lo, hi, base, inverse, entries)
    found = _crossing_pairs(vertices, triangles, far, lo, hi, *grid)
    hits = found[found[:, 0] >= 0]
    if not hits.size:
        return None
    s, t = hits[np.lexsort((hits[:, 1], hits[:, 0]))[0]]
    return int(s), int(t)


def check_self_intersections(
    vertices: np.ndarray, triangles: np.ndarray, triangle_edges: np.ndarray | None = None
) -> None:
    """Raise a ModelError naming two crossing triangles, if the mesh crosses itself.

    Arguments as for :func:`find_self_intersection`.
    """
    pair = find_self_intersection(vertices, triangles, triangle_edges)
    if pair is None:
        return
    s, t = pair
    near = 0.5 * (vertices[triangles[s]].mean(axis=0) + vertices[triangles[t]].mean(axis=0))
    raise ModelError(
        f"`triangles` cross each other: entries {s} (vertices {describe(triangles[s])}) and "
        f"{t} (vertices {describe(triangles[t])}) intersect, near {describe(near.round(6))} m, "
        "so the mesh bounds no single solid (an overlap would count twice in its volume and "
        "mass); merge the overlapping parts into one surface (a boolean union) or separate them"
    )
