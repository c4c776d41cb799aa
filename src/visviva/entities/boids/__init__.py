"""The ``boids`` entity kind: Reynolds' flocking of the particles it names."""

from ..kind import EntityKind
from .schema import RENAMED, Boids, BoidsMethods

__all__ = ["KIND", "BoidsMethods"]

KIND = EntityKind(
    name="boids",
    schema=Boids,
    summary="Reynolds' flocking of the particles it names",
    build=f"{__name__}.build",
    renamed=RENAMED,
)
