"""The ``soft_mesh`` entity kind: a volumetric soft body on a tetrahedral mesh."""

from ..kind import EntityKind
from .schema import SoftMesh, SoftMeshMethods

__all__ = ["KIND", "SoftMeshMethods"]

KIND = EntityKind(
    name="soft_mesh",
    schema=SoftMesh,
    summary="a volumetric soft body on a tetrahedral mesh",
    build=f"{__name__}.build",
    holds_particles=True,
)
