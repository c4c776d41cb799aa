"""How a ``particles`` entity is built: its particles, at the positions it lists."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..checks import check_lengths
from ..context import BuildContext, ParticleRows
from ..kind import HOLDS, KindBuild

__all__ = ["BUILD"]


def _rows(entity: Any, where: str, context: BuildContext) -> ParticleRows:
    x = np.array(entity.positions, dtype=np.float64)
    v = np.zeros_like(x) if entity.velocities is None else np.array(entity.velocities, np.float64)
    return ParticleRows(x, v, entity.mass, entity.radius, entity.color)


BUILD = KindBuild(
    check=lambda entity, where, scene: check_lengths(entity, where, len(entity.positions)),
    count=lambda entity, where, context: len(entity.positions),
    rows=_rows,
    replica=lambda entity: HOLDS,
)
