"""Spring topologies from meshes: cloth from any triangle mesh, soft bodies from any tetrahedral
mesh. A particle sits at each vertex; springs rest at their lengths as built.

* **Cloth from a triangle mesh**: a *stretch* spring on every edge of the mesh, and a *bend*
  spring between the two vertices that face each other across every edge two triangles
  share — the spring stand-in for a bending energy (seed 000 warns that such springs resist
  stretch too). A grid cloth's *shear* springs keep its square cells from shearing; a triangle
  keeps its shape by its three edges alone, so a triangle mesh has no shear family. Each
  vertex weighs the areal density times a third of the area of each triangle around it (Baraff
  & Witkin 1998, section 2.1), so the sheet weighs density × area.
* **Soft body from a tetrahedral mesh** (seed 000: volumetric spring networks "typically
  connected in a mesh of tetrahedra"): a spring on every edge of every tetrahedron. Four points
  and six springs make a rigid frame, so a mesh of tetrahedra holds its shape where a lattice
  needs diagonal springs. Each vertex weighs the density times a quarter of the volume of each
  tetrahedron around it, so the body weighs density × volume.

A cloth mesh is drawn by its triangles as given (each one's front is the side it is
counter-clockwise from); a soft mesh by its boundary, the faces in one tetrahedron only, wound
outward (:func:`.surfaces.boundary_triangles`).

A mesh is refused, at the triangle, tetrahedron or vertex at fault, when an index is past the
vertices, a cell has no area or volume (or, for tetrahedra, is inside out: the standard
orientation is (v1 − v0)·((v2 − v0) × (v3 − v0)) > 0), two cells have the same vertices, a
vertex is in no cell (it would fly free), or — for cloth — an edge is in more than two
triangles (a bend spring across it would be ambiguous).

References:
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from .surfaces import boundary_triangles
from .topology import (
    _BEYOND_A_FLOAT,
    BEND,
    STRETCH,
    DeformableError,
    SpringNetwork,
    _first_repeat,
    _network,
    _overflow_judged_later,
    _springs,
)

__all__ = ["cloth_mesh", "soft_mesh"]

#: A cell is flat when its area (volume) is below this fraction of its longest edge squared
#: (cubed): a height of 1e-10 edge lengths is rounding noise, not geometry.
FLAT = 1e-10
#: The six edges of a tetrahedron, as pairs of its corners.
TETRAHEDRON_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))


@_overflow_judged_later
def cloth_mesh(
    vertices: np.ndarray,
    triangles: np.ndarray,
    areal_density: float,
    stiffness: float,
    bending: float,
) -> SpringNetwork:
    """Cloth on the triangle mesh ``vertices`` ``(n, 3)`` [m], ``triangles`` ``(T, 3)``
    (indices into ``vertices``; their orientation only chooses the front drawn), of
    ``areal_density`` [kg/m²]: :data:`STRETCH` springs of ``stiffness`` [N/m] on every edge,
    then :data:`BEND` springs of ``bending`` [N/m] across every edge two triangles share (none
    if 0);
    drawn by ``triangles``.

    Raises:
        DeformableError: At ``triangles`` (and the triangle) for an index past the vertices,
            a triangle without area, two triangles with the same vertices or an edge in more
            than two triangles; at ``vertices`` for a vertex in no triangle.
    """
    cells = _cells(vertices, triangles, 3, "triangles", "triangle")
    corners = vertices[cells]
    double_area = np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    why = "has no area: its corners coincide or lie on a line"
    _refuse_flat(cells, double_area, _longest_edge(corners) ** 2, "triangles", "triangle", why)
    _refuse_repeats_and_strays(cells, vertices.shape[0], "triangles", "triangle", "cloth")
    # Each half-edge (a corner and the next) with the corner facing it and its triangle.
    half = np.concatenate([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]])
    facing = np.concatenate([cells[:, 2], cells[:, 0], cells[:, 1]])
    owner = np.tile(np.arange(cells.shape[0]), 3)
    edges, which, count = np.unique(
        np.sort(half, axis=1), axis=0, return_inverse=True, return_counts=True
    )
    which = which.reshape(-1)
    # The half-edges of each edge side by side, in the order of their triangles.
    order = np.lexsort((owner, which))
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    crowded = np.flatnonzero(count > 2)
    if crowded.size:
        e = crowded[0]
        shared = owner[order[start[e] : start[e] + count[e]]]
        a, b = edges[e]
        raise DeformableError(
            f"the edge between vertices {a} and {b} is in {count[e]} triangles "
            f"({', '.join(map(str, shared))}): a cloth mesh must be manifold, each edge in one "
            "or two triangles; split the mesh along it or remove a triangle",
            "triangles",
            int(shared[2]),
        )
    families = [_springs(edges[:, 0], edges[:, 1], stiffness, STRETCH)]
    if bending > 0.0:
        inner = start[count == 2]
        families.append(_springs(facing[order[inner]], facing[order[inner + 1]], bending, BEND))
    mass = (
        areal_density
        / 6.0
        * np.bincount(
            cells.reshape(-1), weights=np.repeat(double_area, 3), minlength=vertices.shape[0]
        )
    )
    return _network(vertices, mass, families, faces=cells)


@_overflow_judged_later
def soft_mesh(
    vertices: np.ndarray, tetrahedra: np.ndarray, density: float, stiffness: float
) -> SpringNetwork:
    """A soft body on the tetrahedral mesh ``vertices`` ``(n, 3)`` [m], ``tetrahedra``
    ``(T, 4)`` (indices into ``vertices``, each with (v1 − v0)·((v2 − v0) × (v3 − v0)) > 0), of
    ``density`` [kg/m³]: a :data:`STRETCH` spring of ``stiffness`` [N/m] on every edge; drawn
    by the boundary triangles, wound outward.

    Raises:
        DeformableError: At ``tetrahedra`` (and the tetrahedron) for an index past the
            vertices, a tetrahedron without volume or inside out, or two with the same
            vertices; at ``vertices`` for a vertex in no tetrahedron.
    """
    cells = _cells(vertices, tetrahedra, 4, "tetrahedra", "tetrahedron")
    corners = vertices[cells]
    a, b, c, d = (corners[:, i] for i in range(4))
    six_volume = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))
    why = "has no volume: its corners lie in a plane (or on a line)"
    scale = _longest_edge(corners) ** 3
    _refuse_flat(cells, np.abs(six_volume), scale, "tetrahedra", "tetrahedron", why)
    inverted = np.flatnonzero(six_volume < 0.0)
    if inverted.size:
        t = int(inverted[0])
        v0, v1, v2, v3 = cells[t]
        raise DeformableError(
            f"tetrahedron {t} [{v0}, {v1}, {v2}, {v3}] is inside out: its signed volume "
            f"(v1 − v0)·((v2 − v0) × (v3 − v0))/6 is {six_volume[t] / 6.0:.3g} m³, not positive; "
            f"swap two vertices of tetrahedron {t}, e.g. [{v0}, {v2}, {v1}, {v3}]",
            "tetrahedra",
            t,
        )
    _refuse_repeats_and_strays(cells, vertices.shape[0], "tetrahedra", "tetrahedron", "soft body")
    pairs = np.concatenate([cells[:, [i, j]] for i, j in TETRAHEDRON_EDGES])
    edges = np.unique(np.sort(pairs, axis=1), axis=0)
    mass = (
        density
        / 24.0
        * np.bincount(
            cells.reshape(-1), weights=np.repeat(six_volume, 4), minlength=vertices.shape[0]
        )
    )
    springs = [_springs(edges[:, 0], edges[:, 1], stiffness, STRETCH)]
    return _network(vertices, mass, springs, faces=boundary_triangles(cells))


def _cells(
    vertices: np.ndarray, cells: np.ndarray, corners: int, field: str, noun: str
) -> np.ndarray:
    """``cells`` as an ``(C, corners)`` int64 array whose indices all name a vertex."""
    n = vertices.shape[0]
    cells = np.asarray(cells, dtype=np.int64).reshape(-1, corners)
    outside = np.flatnonzero(((cells < 0) | (cells >= n)).any(axis=1))
    if outside.size:
        c = int(outside[0])
        raise DeformableError(
            f"{noun} {c} {cells[c].tolist()} names a vertex past the {n} `vertices` (0 to "
            f"{n - 1}): each index of `{field}` must name one of them",
            field,
            c,
        )
    return cells


def _longest_edge(corners: np.ndarray) -> np.ndarray:
    """``(C,)`` the longest edge of each cell of ``corners`` ``(C, k, 3)`` [m]."""
    k = corners.shape[1]
    squares = [
        np.sum((corners[:, j] - corners[:, i]) ** 2, axis=1)
        for i in range(k)
        for j in range(i + 1, k)
    ]
    return np.sqrt(np.max(squares, axis=0))


def _refuse_flat(
    cells: np.ndarray, measure: np.ndarray, scale: np.ndarray, field: str, noun: str, why: str
) -> None:
    """Refuse the first cell whose ``measure`` (twice its area, six times its volume) is at
    most :data:`FLAT` times ``scale`` (its longest edge squared, cubed)."""
    if not (np.isfinite(measure).all() and np.isfinite(scale).all()):
        raise ModelError(_BEYOND_A_FLOAT)
    flat = np.flatnonzero(measure <= FLAT * scale)
    if flat.size:
        c = int(flat[0])
        raise DeformableError(
            f"{noun} {c} {cells[c].tolist()} {why}; remove it or move a vertex", field, c
        )


def _refuse_repeats_and_strays(cells: np.ndarray, n: int, field: str, noun: str, body: str) -> None:
    """Refuse two cells with the same vertices, and a vertex of the ``n`` in no cell."""
    repeated = _first_repeat(np.sort(cells, axis=1))
    if repeated is not None:
        first, c = repeated
        raise DeformableError(
            f"{field} {first} and {c} have the same vertices {sorted(cells[c].tolist())}: "
            "remove one",
            field,
            c,
        )
    stray = np.flatnonzero(np.bincount(cells.reshape(-1), minlength=n) == 0)
    if stray.size:
        v = int(stray[0])
        raise DeformableError(
            f"vertex {v} is in no {noun}: it would fly free of the {body}; remove it from "
            f"`vertices` (renumbering the {field}) or add a {noun} with it",
            "vertices",
            v,
        )
