"""The ``particle_cloud`` entity kind: particles placed at random in a box."""

from ..kind import EntityKind
from .schema import ParticleCloud, ParticleCloudMethods

__all__ = ["KIND", "ParticleCloudMethods"]

KIND = EntityKind(
    name="particle_cloud",
    schema=ParticleCloud,
    summary="particles placed at random in a box",
    build=f"{__name__}.build",
    holds_particles=True,
)
