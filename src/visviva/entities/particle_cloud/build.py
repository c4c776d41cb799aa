"""How a ``particle_cloud`` entity is built: ``count`` particles drawn uniformly in its box,
their velocities its mean plus a Gaussian jitter, from its seed."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..context import BuildContext, ParticleRows
from ..kind import HOLDS, KindBuild

__all__ = ["BUILD"]


def _rows(entity: Any, where: str, context: BuildContext) -> ParticleRows:
    count = entity.count
    rng = np.random.default_rng(entity.seed)
    with np.errstate(over="ignore"):  # an overflow is refused by the start check, located
        offsets = (rng.random((count, 3)) - 0.5) * np.asarray(entity.size)
        x = np.asarray(entity.center) + offsets
        jitter = entity.velocity_jitter * rng.standard_normal((count, 3))
        v = np.asarray(entity.velocity) + jitter
    return ParticleRows(x, v, entity.mass, entity.radius, entity.color)


BUILD = KindBuild(
    count=lambda entity, where, context: entity.count, rows=_rows, replica=lambda entity: HOLDS
)
