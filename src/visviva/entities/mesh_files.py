"""Entities whose mesh is in a file: the file read, and the entity given its vertices and
triangles in place of the path.

The ``prepare`` hook of the kinds that take a ``path`` (``cloth_mesh``, ``body``) runs
:func:`with_mesh_file` when the entity is added to a builder and before a scene is built, so
everything after it — the checks across entities, the particles, the springs, the recordings'
surfaces — sees an ordinary mesh entity, and the built model's scene is whole without the
file. A refusal names the entity's ``path`` and the file
(:mod:`visviva.io.meshes`): an unreadable file, one that is not one triangle mesh,
a mesh the kind refuses (``check``: a degenerate triangle in a cloth), or ``pinned`` indices
past its vertices.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..deformables import DeformableError
from ..errors import SceneError, SceneProblem
from ..io.meshes import MeshFileError, read_triangle_mesh

__all__ = ["with_mesh_file"]


def with_mesh_file(
    entity: Any,
    where: str,
    check: Callable[[np.ndarray, np.ndarray], object] | None = None,
    pinned: tuple[int, ...] = (),
) -> Any:
    """``entity`` (at ``where`` in its scene) with the vertices and triangles of the file at
    its ``path`` and no path; ``check(vertices, triangles)`` raises what the kind refuses of
    the mesh, and ``pinned`` are the entity's pinned vertices (checked against the mesh's).

    Raises:
        SceneError: At ``where.path`` for a file refused or a mesh the kind refuses, at
            ``where.pinned`` for pins past its vertices.
    """
    path = entity.path
    if path is None:
        return entity
    try:
        vertices, triangles = read_triangle_mesh(path)
        if check is not None:
            check(vertices, triangles)
    except MeshFileError as error:
        raise SceneError([SceneProblem(f"{where}.path", str(error))]) from None
    except DeformableError as error:
        item = error.field + ("" if error.index is None else f"[{error.index}]")
        raise SceneError(
            [SceneProblem(f"{where}.path", f"the mesh in {path!r} at {item}: {error}")]
        ) from None
    outside = [i for i in pinned if i >= vertices.shape[0]]
    if outside:
        raise SceneError(
            [
                SceneProblem(
                    f"{where}.pinned",
                    f"pinned index {outside[0]} is not a vertex of the mesh in {path!r} (it has "
                    f"{vertices.shape[0]}: 0 to {vertices.shape[0] - 1})",
                )
            ]
        )
    # The arrays come from the reader (finite floats, indices in range): no second validation.
    return entity.model_copy(
        update={
            "path": None,
            "vertices": [tuple(v) for v in vertices.tolist()],
            "triangles": [tuple(t) for t in np.asarray(triangles).tolist()],
        }
    )
