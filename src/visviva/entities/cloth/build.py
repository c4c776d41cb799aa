"""How a ``cloth`` is built: a grid of points with structural, shear and bending springs
(Choi & Ko 2002), drawn by its triangles."""

from __future__ import annotations

import numpy as np

from ...deformables import SpringNetwork, cloth_grid
from ..deformable_build import deformable_build
from .schema import Cloth

__all__ = ["BUILD"]


def _network(entity: Cloth) -> SpringNetwork:
    return cloth_grid(
        np.asarray(entity.origin, dtype=np.float64),
        np.asarray(entity.along, dtype=np.float64),
        np.asarray(entity.across, dtype=np.float64),
        entity.resolution,
        entity.areal_density,
        entity.stiffness,
        entity.stiffness if entity.shear is None else entity.shear,
        entity.bending,
    )


BUILD = deformable_build("cloth", _network, "resolution")
