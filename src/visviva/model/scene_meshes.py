"""Bodies whose mesh is in a file: the file read, and the entity given its vertices and
triangles in place of the path.

:func:`with_mesh_files` runs first when a scene is built (and :meth:`SceneBuilder.add_cloth_mesh`
runs it at once on a ``path``), so everything after it — the checks across entities, the
particle arrays, the springs, the recordings' surfaces — sees an ordinary mesh entity, and the
built model's scene is whole without the file. A refusal names the entity's ``path`` and the
file (:mod:`visviva.deformables.mesh_files`): an unreadable file, one that is not one triangle
mesh, a mesh a cloth cannot be made of (a degenerate triangle, an edge in three triangles), or
``pinned`` indices past its vertices.
"""

from __future__ import annotations

import numpy as np

from ..deformables import DeformableError, cloth_mesh
from ..deformables.mesh_files import MeshFileError, read_triangle_mesh
from ..errors import SceneError, SceneProblem
from .scene import Scene
from .scene_bodies import ClothMesh
from .scene_rigid import RigidBody

__all__ = ["with_mesh_file", "with_mesh_files"]


def with_mesh_files(scene: Scene) -> Scene:
    """``scene`` with every ``cloth_mesh`` given by ``path`` read (itself if there is none).

    Raises:
        SceneError: Listing every file refused.
    """
    entities, problems, read = list(scene.entities), [], False
    for index, entity in enumerate(entities):
        if isinstance(entity, (ClothMesh, RigidBody)) and entity.path is not None:
            read = True
            try:
                entities[index] = with_mesh_file(entity, f"entities[{index}]")
            except SceneError as error:
                problems += error.problems
    if problems:
        raise SceneError(problems)
    return scene.model_copy(update={"entities": entities}) if read else scene


def with_mesh_file(entity: ClothMesh | RigidBody, where: str) -> ClothMesh | RigidBody:
    """The cloth mesh or rigid body ``entity`` (at ``where`` in its scene) with the vertices
    and triangles of the file at its ``path`` and no path (a body's mesh is checked as a
    solid when the scene is built).

    Raises:
        SceneError: At ``where.path`` for a file refused or a mesh no cloth can be made of, at
            ``where.pinned`` for pins past its vertices.
    """
    path = entity.path
    if path is None:
        return entity
    try:
        vertices, triangles = read_triangle_mesh(path)
        if isinstance(entity, ClothMesh):
            cloth_mesh(vertices, triangles, entity.areal_density, entity.stiffness, entity.bending)
    except MeshFileError as error:
        raise SceneError([SceneProblem(f"{where}.path", str(error))]) from None
    except DeformableError as error:
        item = error.field + ("" if error.index is None else f"[{error.index}]")
        raise SceneError(
            [SceneProblem(f"{where}.path", f"the mesh in {path!r} at {item}: {error}")]
        ) from None
    outside = [i for i in getattr(entity, "pinned", ()) if i >= vertices.shape[0]]
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
