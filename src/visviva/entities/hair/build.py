"""How a ``hair`` strand is built: edge, bending and torsion springs along its points
(Selle, Lentine & Fedkiw 2008)."""

from __future__ import annotations

import numpy as np

from ...deformables import SpringNetwork, hair
from ..deformable_build import deformable_build
from .schema import Hair

__all__ = ["BUILD"]


def _network(entity: Hair) -> SpringNetwork:
    points = np.array(entity.points, dtype=np.float64)
    mass = np.broadcast_to(np.asarray(entity.mass, dtype=np.float64), (points.shape[0],))
    return hair(points, mass, entity.stiffness, entity.bending, entity.torsion)


BUILD = deformable_build("hair", _network, "points", points_listed=True)
