"""Several triangle surfaces as one set of arrays, one surface after another, as recordings keep
the rigid bodies' and the colliders' surfaces (:mod:`visviva.simulation.frames`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["packed_surfaces"]


def packed_surfaces(
    surfaces: Sequence[tuple[np.ndarray, np.ndarray]], prefix: str
) -> dict[str, np.ndarray]:
    """The surfaces ``(vertices (V_k, 3) [m], triangles (T_k, 3))`` one after another:
    ``<prefix>_vertices`` ``(ΣV, 3)`` float64, ``<prefix>_triangles`` ``(ΣT, 3)`` int64 indexing
    those vertices, and ``<prefix>_vertex_start``, ``<prefix>_triangle_start`` ``(K + 1,)``
    int64, surface ``k``'s rows being ``start[k]:start[k + 1]``.

    >>> square = np.zeros((4, 3)), np.array([[0, 1, 2], [0, 2, 3]])
    >>> packed = packed_surfaces([square, square], "body")
    >>> packed["body_triangles"][2:].tolist(), packed["body_vertex_start"].tolist()
    ([[4, 5, 6], [4, 6, 7]], [0, 4, 8])
    """
    vertex_start = np.cumsum([0] + [v.shape[0] for v, _ in surfaces], dtype=np.int64)
    triangle_start = np.cumsum([0] + [t.shape[0] for _, t in surfaces], dtype=np.int64)
    return {
        f"{prefix}_vertices": np.concatenate([v for v, _ in surfaces]).astype(np.float64),
        # reshape: a surface without triangles (a degenerate one) may come as shape (0,).
        f"{prefix}_triangles": np.concatenate(
            [
                np.reshape(t, (-1, 3)) + first
                for (_, t), first in zip(surfaces, vertex_start, strict=False)
            ]
        ).astype(np.int64),
        f"{prefix}_vertex_start": vertex_start,
        f"{prefix}_triangle_start": triangle_start,
    }
