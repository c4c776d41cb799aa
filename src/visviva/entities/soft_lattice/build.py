"""How a ``soft_lattice`` is built: a lattice of points with structural, face-diagonal and
body-diagonal springs (seed 004), drawn by its outer faces."""

from __future__ import annotations

import numpy as np

from ...deformables import SpringNetwork, soft_lattice
from ..deformable_build import deformable_build
from .schema import SoftLattice

__all__ = ["BUILD"]


def _network(entity: SoftLattice) -> SpringNetwork:
    return soft_lattice(
        np.asarray(entity.origin, dtype=np.float64),
        np.asarray(entity.size, dtype=np.float64),
        entity.resolution,
        entity.density,
        entity.stiffness,
        entity.stiffness if entity.shear is None else entity.shear,
        entity.stiffness if entity.diagonal is None else entity.diagonal,
    )


BUILD = deformable_build("soft_lattice", _network, "resolution")
