"""The scene entity of particle–particle collisions (``type = "particle_collisions"``).

One such entity makes the particles it targets (the entities it names, or every particle)
collide with each other as spheres of their radii, with a coefficient of restitution and
Coulomb friction; the stage that does it, and its method and sources, are in
:mod:`visviva.collision.particle_contacts`. The scene's impulse colliders take part in the
same solve (a pile resting on a floor). A scene holds at most one.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Literal

from pydantic import Field

from ..fields import Fraction, Name, Names, NonNegative, Strict
from ..methods import Builds, given

__all__ = ["ParticleCollisionSettings"]


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


class ParticleCollisionMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_particle_collisions(
        self: Builds,
        *,
        targets: Sequence[str] | None = None,
        restitution: float | None = None,
        friction: float | None = None,
        iterations: int | None = None,
        resting_speed: float | None = None,
        name: str | None = None,
    ) -> int:
        """Make the particles of ``targets`` (default: every particle) collide with each other
        as spheres of their radii, with restitution ``e`` in [0, 1] and Coulomb ``friction``
        μ, in ``iterations`` sweeps per step; approaches slower than ``resting_speed`` [m/s]
        rest (:mod:`visviva.collision.particle_contacts`)."""
        return self.add("particle_collisions", **given(locals()))
