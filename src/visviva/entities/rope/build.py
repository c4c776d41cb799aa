"""How a ``rope`` is built: a chain of stretch springs, and bending springs two apart."""

from __future__ import annotations

import numpy as np

from ...deformables import SpringNetwork, rope
from ..deformable_build import deformable_build
from .schema import Rope

__all__ = ["BUILD"]


def _network(entity: Rope) -> SpringNetwork:
    points = np.array(entity.points, dtype=np.float64)
    mass = np.broadcast_to(np.asarray(entity.mass, dtype=np.float64), (points.shape[0],))
    return rope(points, mass, entity.stiffness, entity.bending)


BUILD = deformable_build("rope", _network, "points", points_listed=True)
