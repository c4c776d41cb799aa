"""The ``particle_collisions`` entity kind: particles colliding with each other as spheres."""

from ..kind import EntityKind
from .schema import ParticleCollisionMethods, ParticleCollisionSettings

__all__ = ["KIND", "ParticleCollisionMethods"]

KIND = EntityKind(
    name="particle_collisions",
    schema=ParticleCollisionSettings,
    summary="particles colliding with each other as spheres",
    build=f"{__name__}.build",
)
