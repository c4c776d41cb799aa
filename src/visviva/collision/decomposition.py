"""Convex decomposition of a non-convex mesh, for a body that collides as convex pieces.

A rigid body collides as convex pieces (GJK and EPA need convex shapes). A non-convex mesh —
a bunny, a chair — is cut into pieces that are each nearly convex and whose hulls stand in
for it: CoACD (X. Wei, M. Liu, Z. Ling, H. Su, "Approximate convex decomposition for 3D meshes
with collision-aware concavity and tree search", SIGGRAPH 2022) cuts the mesh by planes found
by a Monte Carlo tree search until every piece's *concavity* — how far the piece's surface lies
inside its hull, measured where it matters for collisions — is below a threshold, given as a
fraction of the mesh's size. The pieces are their hulls, at most :data:`MAX_PIECE_VERTICES`
corners each (a support mapping visits each one).

The cut is the same every time for the same mesh and settings (a fixed seed), and a process
keeps the latest decompositions it made (the search takes seconds).
"""

from __future__ import annotations

import hashlib

import numpy as np

from .._memo import Memo
from .._validation import real_number
from ..errors import ModelError

__all__ = ["DEFAULT_CONCAVITY", "MAX_PIECE_VERTICES", "convex_decomposition"]

#: The largest concavity a piece may keep, as a fraction of the mesh's size: 10 % keeps a
#: bunny's ears and head apart from its body in three or four pieces.
DEFAULT_CONCAVITY = 0.1
#: Most corners of a piece's hull.
MAX_PIECE_VERTICES = 48

_DONE: Memo[tuple[np.ndarray, ...]] = Memo(16)


def convex_decomposition(
    vertices: np.ndarray, triangles: np.ndarray, *, concavity: float = DEFAULT_CONCAVITY
) -> tuple[np.ndarray, ...]:
    """The convex pieces of a closed mesh, each as the ``(k, 3)`` corners of its hull [m].

    Args:
        vertices: ``(V, 3)`` vertices [m].
        triangles: ``(T, 3)`` vertex indices, counter-clockwise seen from outside.
        concavity: The largest concavity a piece may keep, a fraction of the mesh's size in
            (0, 1): smaller gives more, tighter pieces (and takes longer).
    """
    concavity = real_number("concavity", concavity, positive=True)
    if concavity >= 1.0:
        raise ModelError(
            f"`concavity` is a fraction of the mesh's size, below 1 (got {concavity!r})"
        )
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    digest = hashlib.sha256()
    for array in (vertices, triangles):
        digest.update(array.tobytes())
    key = (digest.hexdigest(), concavity)
    return _DONE.get(key, lambda: _decompose(vertices, triangles, concavity))


def _decompose(
    vertices: np.ndarray, triangles: np.ndarray, concavity: float
) -> tuple[np.ndarray, ...]:
    import coacd

    coacd.set_log_level("error")
    pieces = coacd.run_coacd(
        coacd.Mesh(vertices, triangles),
        threshold=concavity,
        preprocess_mode="off",  # the mesh is closed and manifold already (checked by the body)
        resolution=1000,
        mcts_iterations=60,
        decimate=True,
        max_ch_vertex=MAX_PIECE_VERTICES,
        seed=0,
    )
    return tuple(np.array(corners, dtype=np.float64) for corners, _ in pieces)
