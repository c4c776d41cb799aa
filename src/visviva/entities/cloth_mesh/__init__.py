"""The ``cloth_mesh`` entity kind: cloth on any triangle mesh."""

from ..kind import EntityKind
from .schema import RENAMED, ClothMesh, ClothMeshMethods

__all__ = ["KIND", "ClothMeshMethods"]

KIND = EntityKind(
    name="cloth_mesh",
    schema=ClothMesh,
    summary="cloth on any triangle mesh",
    build=f"{__name__}.build",
    holds_particles=True,
    renamed=RENAMED,
)
