"""Which points lie inside a closed triangle mesh: ray parity on a grid.

A ray from a point along +x crosses a closed surface an odd number of times when the point is
inside, an even number when outside (Jordan–Brouwer). :class:`InsideTest` counts the triangles
whose projection on the y–z plane contains the point's (y, z) and whose plane the ray meets
beyond the point's x. A ray through a shared edge or vertex must count it once (or, at a
silhouette, twice or not at all): each edge's side test is computed from the edge's two
vertices in a fixed order (lower index first) so that both triangles at an edge see the same
number, and a point exactly on an edge's line is moved by an infinitesimal (ε, ε²) in (y, z)
(simulation of simplicity: H. Edelsbrunner and E. P. Mücke, "Simulation of simplicity", *ACM
Transactions on Graphics* 9(1), 1990), which decides its side from the edge's direction alone.
Rounding can still misplace a point within a few ulps of the surface, or of a vertex in
projection, which random samples meet with probability of order 1e-16.

The triangles are binned once on a uniform y–z grid (cells about as large as the triangles'
projections), so a query reads only the triangles over its cell: about O(1) per point for a
mesh of similar-sized triangles, O(T) to build.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange

__all__ = ["InsideTest"]

#: Average (triangle, cell) entries per triangle allowed before the cells are made larger.
_ENTRIES_PER_TRIANGLE = 8
#: Most cells along each axis of the grid.
_MAX_CELLS = 4096


@njit(cache=True, inline="always")
def _edge_side(v: np.ndarray, a: int, b: int, y: float, z: float) -> int:
    """Side (+1 / −1) of the point (y, z), perturbed by (ε, ε²), of the projected line a → b:
    the sign of (b − a) × (p − a), evaluated with the lower vertex index first."""
    flip = 1
    if a > b:
        a, b = b, a
        flip = -1
    dy = v[b, 1] - v[a, 1]
    dz = v[b, 2] - v[a, 2]
    value = dy * (z - v[a, 2]) - dz * (y - v[a, 1])
    if value == 0.0:
        value = -dz if dz != 0.0 else dy  # the perturbation's first nonzero term
    return flip if value > 0.0 else -flip


@njit(cache=True)
def _bin(
    vertices: np.ndarray, triangles: np.ndarray, base: np.ndarray, inverse: float, cells: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """CSR lists of the triangles over each y–z cell (row-major, ``cells`` = (ny, nz))."""
    ny, nz = cells[0], cells[1]
    start = np.zeros(ny * nz + 1, dtype=np.int64)
    for phase in range(2):
        if phase == 1:
            for c in range(ny * nz):
                start[c + 1] += start[c]
        fill = start[:-1].copy()
        listed = np.empty(start[-1] if phase == 1 else 0, dtype=np.int64)
        for t in range(triangles.shape[0]):
            i, j, k = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            y0 = min(vertices[i, 1], vertices[j, 1], vertices[k, 1])
            y1 = max(vertices[i, 1], vertices[j, 1], vertices[k, 1])
            z0 = min(vertices[i, 2], vertices[j, 2], vertices[k, 2])
            z1 = max(vertices[i, 2], vertices[j, 2], vertices[k, 2])
            a0 = min(int((y0 - base[0]) * inverse), ny - 1)
            a1 = min(int((y1 - base[0]) * inverse), ny - 1)
            b0 = min(int((z0 - base[1]) * inverse), nz - 1)
            b1 = min(int((z1 - base[1]) * inverse), nz - 1)
            for a in range(a0, a1 + 1):
                for b in range(b0, b1 + 1):
                    if phase == 0:
                        start[a * nz + b + 1] += 1
                    else:
                        listed[fill[a * nz + b]] = t
                        fill[a * nz + b] += 1
        if phase == 1:
            return start, listed
    return start, np.empty(0, dtype=np.int64)


@njit(cache=True, parallel=True)
def _inside(
    vertices: np.ndarray,
    triangles: np.ndarray,
    base: np.ndarray,
    inverse: float,
    cells: np.ndarray,
    start: np.ndarray,
    listed: np.ndarray,
    points: np.ndarray,
) -> np.ndarray:
    ny, nz = cells[0], cells[1]
    result = np.zeros(points.shape[0], dtype=np.bool_)
    for n in prange(points.shape[0]):
        x, y, z = points[n, 0], points[n, 1], points[n, 2]
        fy = (y - base[0]) * inverse
        fz = (z - base[1]) * inverse
        if not (0.0 <= fy < ny + 1.0 and 0.0 <= fz < nz + 1.0):
            continue  # outside the mesh's y–z extent
        a = min(int(fy), ny - 1)
        b = min(int(fz), nz - 1)
        crossings = 0
        for m in range(start[a * nz + b], start[a * nz + b + 1]):
            t = listed[m]
            i, j, k = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            s0 = _edge_side(vertices, j, k, y, z)  # opposite vertex i
            s1 = _edge_side(vertices, k, i, y, z)
            s2 = _edge_side(vertices, i, j, y, z)
            if s0 != s1 or s1 != s2:
                continue
            # Barycentric weights are the projected areas opposite each vertex.
            w0 = (vertices[k, 1] - vertices[j, 1]) * (z - vertices[j, 2]) - (
                vertices[k, 2] - vertices[j, 2]
            ) * (y - vertices[j, 1])
            w1 = (vertices[i, 1] - vertices[k, 1]) * (z - vertices[k, 2]) - (
                vertices[i, 2] - vertices[k, 2]
            ) * (y - vertices[k, 1])
            w2 = (vertices[j, 1] - vertices[i, 1]) * (z - vertices[i, 2]) - (
                vertices[j, 2] - vertices[i, 2]
            ) * (y - vertices[i, 1])
            total = w0 + w1 + w2
            if total == 0.0:
                continue  # the triangle is edge-on to the ray
            hit = (w0 * vertices[i, 0] + w1 * vertices[j, 0] + w2 * vertices[k, 0]) / total
            if hit > x:
                crossings += 1
        result[n] = crossings % 2 == 1
    return result


@dataclass(frozen=True, eq=False)
class InsideTest:
    """A closed mesh prepared for inside tests (``vertices`` ``(V, 3)`` float64 and
    ``triangles`` ``(T, 3)`` int64 that passed
    :func:`~visviva.geometry.mesh_topology.check_closed_mesh`).

    >>> import numpy as np
    >>> corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
    ...                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    >>> InsideTest.of(corners, faces).contains([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5]]).tolist()
    [True, False]
    """

    vertices: np.ndarray
    triangles: np.ndarray
    base: np.ndarray
    inverse: float
    cells: np.ndarray
    start: np.ndarray
    listed: np.ndarray

    @classmethod
    def of(cls, vertices: np.ndarray, triangles: np.ndarray) -> InsideTest:
        """Bin the triangles of a checked closed mesh on a y–z grid."""
        vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        corners = vertices[triangles][:, :, 1:]  # (T, 3, 2): projected corners
        low = vertices[:, 1:].min(axis=0)
        span = vertices[:, 1:].max(axis=0) - low
        size = float(np.mean(np.max(np.ptp(corners, axis=1), axis=1)))
        size = max(size, float(span.max()) / _MAX_CELLS, np.finfo(float).tiny)
        while True:
            cells = np.minimum(np.floor(span / size).astype(np.int64) + 1, _MAX_CELLS)
            first = np.minimum(((corners.min(axis=1) - low) / size).astype(np.int64), cells - 1)
            last = np.minimum(((corners.max(axis=1) - low) / size).astype(np.int64), cells - 1)
            entries = int(np.prod(last - first + 1, axis=1).sum())
            if entries <= _ENTRIES_PER_TRIANGLE * triangles.shape[0]:
                break
            size *= 2.0
        start, listed = _bin(vertices, triangles, low, 1.0 / size, cells)
        return cls(vertices, triangles, low, 1.0 / size, cells, start, listed)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether each of ``(N, 3)`` points [m] lies inside the mesh: ``(N,)`` bools."""
        points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        return _inside(
            self.vertices,
            self.triangles,
            self.base,
            self.inverse,
            self.cells,
            self.start,
            self.listed,
            points,
        )
