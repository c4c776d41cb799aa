"""The ``particles`` entity kind: particles at given positions, moving freely under the forces."""

from ..kind import EntityKind
from .schema import Particles, ParticlesMethods

__all__ = ["KIND", "ParticlesMethods"]

KIND = EntityKind(
    name="particles",
    schema=Particles,
    summary="particles at given positions, moving freely under the forces",
    build=f"{__name__}.build",
    holds_particles=True,
)
