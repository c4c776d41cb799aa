"""Drawable surfaces of deformable bodies: the triangles the outputs show between their points.

A body's surface is computed once, when the body is built, in the body's own point indices, as
``(F, 3)`` triangles wound counter-clockwise seen from outside (a closed body) or from the front
(a sheet), the recording convention of :mod:`visviva.simulation.recording`:

* a grid of points (a cloth sheet, a face of a soft lattice) gives two triangles per cell
  (:func:`grid_triangles`), every cell cut along the same diagonal;
* a soft lattice gives the grid triangles of its six faces, wound outward
  (:func:`box_triangles`);
* a tetrahedral mesh gives its boundary: the faces that belong to exactly one tetrahedron,
  wound outward (:func:`boundary_triangles`).

The triangles only draw the body: no force acts on them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["boundary_triangles", "box_triangles", "grid_triangles", "no_triangles"]

#: The faces of a positively oriented tetrahedron [v0, v1, v2, v3] (see
#: :func:`visviva.deformables.soft_mesh`), as its corners counter-clockwise seen from outside:
#: v3 lies on the side of (v1 − v0) × (v2 − v0), so the face opposite it is (v0, v2, v1).
TETRAHEDRON_FACES = ((0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3))


def no_triangles() -> np.ndarray:
    """An empty ``(0, 3)`` int64 array: the surface of a strand or a spring graph."""
    return np.zeros((0, 3), dtype=np.int64)


def grid_triangles(index: np.ndarray) -> np.ndarray:
    """Two triangles per cell of the grid of point indices ``index`` ``(rows, columns)``.

    With ``u`` the step from a point to the next column and ``v`` to the next row, the
    triangles are counter-clockwise seen from the side ``u × v`` points to: cell
    ``[a b; c d]`` (``a`` at row ``r``, column ``s``) gives ``(a, b, d)`` and ``(a, d, c)``.
    Pass ``index.T`` for the other side.

    Example:
        >>> grid_triangles(np.arange(6).reshape(2, 3)).tolist()
        [[0, 1, 4], [1, 2, 5], [0, 4, 3], [1, 5, 4]]
    """
    a = index[:-1, :-1].reshape(-1)
    b = index[:-1, 1:].reshape(-1)
    c = index[1:, :-1].reshape(-1)
    d = index[1:, 1:].reshape(-1)
    return np.concatenate([np.stack([a, b, d], axis=1), np.stack([a, d, c], axis=1)]).astype(
        np.int64
    )


def box_triangles(index: np.ndarray) -> np.ndarray:
    """The six faces of the lattice of point indices ``index`` ``(nz, ny, nx)`` (point
    ``(i, j, k)`` at ``index[k, j, i]``, ``i``, ``j``, ``k`` growing along +x, +y, +z), as grid
    triangles wound outward: ``4[(nx−1)(ny−1) + (ny−1)(nz−1) + (nx−1)(nz−1)]`` of them."""
    # Each face's grid with its columns and rows chosen so that columns × rows points out.
    faces = (
        index[:, :, -1],  # x = max: columns +y, rows +z; y × z = +x
        index[:, :, 0].T,  # x = 0: columns +z, rows +y; z × y = −x
        index[:, -1, :].T,  # y = max: columns +z, rows +x; z × x = +y
        index[:, 0, :],  # y = 0: columns +x, rows +z; x × z = −y
        index[-1, :, :],  # z = max: columns +x, rows +y; x × y = +z
        index[0, :, :].T,  # z = 0: columns +y, rows +x; y × x = −z
    )
    return np.concatenate([grid_triangles(face) for face in faces])


def boundary_triangles(tetrahedra: np.ndarray) -> np.ndarray:
    """The boundary of the mesh of positively oriented ``tetrahedra`` ``(T, 4)``: each face
    that belongs to exactly one tetrahedron, wound outward, in the order of the tetrahedra.

    A face two tetrahedra share is inside the body (a conforming mesh: each of them sees it
    with the opposite winding) and is left out.
    """
    corners = np.asarray(TETRAHEDRON_FACES)
    # Face f of tetrahedron t at row t·4 + f: the boundary keeps the tetrahedra's order.
    faces = tetrahedra[:, corners].reshape(-1, 3)
    _, which, count = np.unique(
        np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True
    )
    return faces[count[which.reshape(-1)] == 1].astype(np.int64)
