"""The scene entity of particle–particle collisions (``type = "particle_collisions"``).

One such entity makes the particles it targets (the entities it names, or every particle)
collide with each other as spheres of their radii, with a coefficient of restitution and
Coulomb friction; the stage that does it, and its method and sources, are in
:mod:`visviva.collision.particle_contacts`. The scene's impulse colliders take part in the
same solve (a pile resting on a floor). A scene holds at most one.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from .scene_fields import Fraction, Name, NonNegative, Strict

__all__ = ["ParticleCollisionSettings"]

Names = Annotated[list[Name], Field(min_length=1)]


class ParticleCollisionSettings(Strict):
    """``type = "particle_collisions"``: the targeted particles collide with each other as
    spheres (impulses along the line of centres with restitution ``e`` and Coulomb friction
    ``μ``, then their overlaps removed)."""

    type: Literal["particle_collisions"]
    name: Name | None = None
    targets: Names | None = Field(None, description="entity names (default: every particle)")
    restitution: Fraction = Field(0.5, description="coefficient of restitution e in [0, 1]")
    friction: NonNegative = Field(0.3, description="Coulomb friction coefficient between spheres")
    iterations: Annotated[int, Field(strict=True, ge=1, le=10_000)] = Field(
        20, description="sweeps of impulses, then of overlap projections, per step"
    )
    resting_speed: NonNegative | None = Field(
        None, description="approach speed below which a contact rests [m/s] (default: 2|g|dt)"
    )
