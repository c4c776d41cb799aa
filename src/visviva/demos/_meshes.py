"""Closed triangle meshes the rigid-body demos throw: generated here, nothing downloads.

* :func:`t_handle`: Dzhanibekov's wing nut as a T-shaped prism — a T in the x–y plane (a stem
  and a bar across its top) extruded along z. Three different principal moments, one of them
  in the middle: the shape that flips.
* :func:`bunny`: a rabbit-like lump (a sphere pushed out along its directions), for throwing.
* :func:`prism`: any simple polygon (counter-clockwise, triangulated by the caller) extruded
  into a closed, outward mesh.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bunny", "prism", "t_handle"]


def prism(
    outline: np.ndarray, triangles: np.ndarray, thickness: float
) -> tuple[np.ndarray, np.ndarray]:
    """The polygon ``outline`` ``(n, 2)`` [m] (counter-clockwise, in the x–y plane, covered by
    ``triangles`` ``(n − 2, 3)`` counter-clockwise) extruded from z = −t/2 to t/2:
    ``(vertices (2n, 3), triangles (4n − 4, 3))``, counter-clockwise seen from outside."""
    n = outline.shape[0]
    half = 0.5 * thickness
    vertices = np.concatenate(
        [
            np.column_stack([outline, np.full(n, -half)]),
            np.column_stack([outline, np.full(n, half)]),
        ]
    )
    top = triangles + n  # seen from +z: counter-clockwise as given
    bottom = triangles[:, ::-1]  # seen from −z: reversed
    sides = []
    for i in range(n):
        j = (i + 1) % n
        # The edge i → j runs counter-clockwise: the outside is on its right.
        sides += [[i, j, j + n], [i, j + n, i + n]]
    return vertices, np.concatenate([bottom, top, np.array(sides)]).astype(np.int64)


def t_handle(
    stem: float = 0.12, bar: float = 0.3, width: float = 0.03, thickness: float = 0.03
) -> tuple[np.ndarray, np.ndarray]:
    """A T of a ``stem`` [m] long and ``width`` wide along +y under a ``bar`` [m] long and
    ``width`` wide across its top, ``thickness`` thick along z."""
    a, b, w = 0.5 * width, 0.5 * bar, width
    outline = np.array(
        [[-a, 0.0], [a, 0.0], [a, stem], [b, stem], [b, stem + w], [-b, stem + w],
         [-b, stem], [-a, stem]]
    )  # fmt: skip
    # The stem's two triangles, then the bar's four, all on the outline's own corners.
    cover = np.array([[0, 1, 2], [0, 2, 7], [2, 3, 4], [2, 4, 7], [7, 4, 5], [7, 5, 6]])
    return prism(outline, cover, thickness)


def bunny(size: float = 0.2, *, detail: int = 96) -> tuple[np.ndarray, np.ndarray]:
    """A rabbit-like lump about ``size`` [m] long, nose along +x, ears up: a sphere whose
    every vertex is pushed along its direction to ``r(d)`` — an ellipsoidal body, a head, two
    long ears and a tail as bumps of ``r`` (a star-shaped surface, so closed and free of
    crossings whatever the bumps; :func:`visviva.rigid.surfaces.unit_sphere`), ``detail``
    vertices around its equator (a multiple of 4). Generated, not scanned: nothing
    downloads."""
    from ..rigid.surfaces import unit_sphere

    directions, triangles = unit_sphere(around=detail, quarter=detail // 4)
    x, y, z = directions.T
    body = 1.0 / np.sqrt((x / 0.5) ** 2 + (y / 0.36) ** 2 + (z / 0.32) ** 2)
    radius = body.copy()
    for toward, height, width in (
        ((1.0, 0.55, 0.0), 0.22, 0.45),  # head
        ((0.45, 1.0, 0.28), 0.55, 0.11),  # ears
        ((0.45, 1.0, -0.28), 0.55, 0.11),
        ((-1.0, 0.25, 0.0), 0.1, 0.3),  # tail
    ):
        axis = np.asarray(toward) / np.linalg.norm(toward)
        angle = np.arccos(np.clip(directions @ axis, -1.0, 1.0))
        radius += height * np.exp(-((angle / width) ** 2))
    return directions * (size * radius)[:, None], triangles
