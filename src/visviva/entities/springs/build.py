"""How a ``springs`` graph is built: a spring on each of its pairs, resting at its length as
built or at the length given."""

from __future__ import annotations

import numpy as np

from ...deformables import SpringNetwork, spring_graph
from ..deformable_build import deformable_build
from .schema import SpringGraph

__all__ = ["BUILD"]


def _network(entity: SpringGraph) -> SpringNetwork:
    points = np.array(entity.points, dtype=np.float64)
    mass = np.broadcast_to(np.asarray(entity.mass, dtype=np.float64), (points.shape[0],))
    rest = None if entity.rest_length is None else np.asarray(entity.rest_length)
    stiffness = np.asarray(entity.stiffness, dtype=np.float64)
    return spring_graph(points, mass, np.array(entity.pairs), stiffness, rest)


BUILD = deformable_build("springs", _network, "points", points_listed=True)
