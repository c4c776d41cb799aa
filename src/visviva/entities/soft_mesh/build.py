"""How a ``soft_mesh`` is built: a particle at each vertex, a spring on every edge of every
tetrahedron, drawn by its outer triangles."""

from __future__ import annotations

import numpy as np

from ...deformables import SpringNetwork, soft_mesh
from ..deformable_build import deformable_build
from .schema import SoftMesh

__all__ = ["BUILD"]


def _network(entity: SoftMesh) -> SpringNetwork:
    return soft_mesh(
        np.array(entity.vertices, dtype=np.float64),
        np.array(entity.tetrahedra, dtype=np.int64).reshape(-1, 4),
        entity.density,
        entity.stiffness,
    )


BUILD = deformable_build("soft_mesh", _network, "vertices")
