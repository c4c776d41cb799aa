"""The scene table of particles placed at random in a box (``type = "particle_cloud"``)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from ..fields import (
    MAX_PARTICLES,
    Color,
    Name,
    NonNegative,
    Positive,
    Strict,
    Vector,
)
from ..methods import Builds, Triple, given

__all__ = ["ParticleCloud"]


class ParticleCloud(Strict):
    """``type = "particle_cloud"``: ``count`` particles placed at random in a box."""

    type: Literal["particle_cloud"]
    name: Name | None = None
    count: Annotated[int, Field(strict=True, ge=1, le=MAX_PARTICLES)] = Field(
        description="number of particles"
    )
    center: Vector = Field((0.0, 1.0, 0.0), description="centre of the box [m]")
    size: tuple[Positive, Positive, Positive] = Field(
        (1.0, 1.0, 1.0), description="edge lengths of the box [m]"
    )
    velocity: Vector = Field((0.0, 0.0, 0.0), description="mean initial velocity [m/s]")
    velocity_jitter: NonNegative = Field(
        0.0, description="standard deviation of each velocity component [m/s]"
    )
    mass: Positive = Field(1.0, description="mass of each particle [kg]")
    radius: Positive = Field(0.02, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")
    seed: Annotated[int, Field(strict=True, ge=0, lt=2**63)] = Field(0, description="random seed")


class ParticleCloudMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_particle_cloud(
        self: Builds,
        count: int,
        *,
        center: Triple | None = None,
        size: Triple | None = None,
        velocity: Triple | None = None,
        velocity_jitter: float | None = None,
        mass: float | None = None,
        radius: float | None = None,
        color: Triple | None = None,
        seed: int | None = None,
        name: str | None = None,
    ) -> int:
        """Add ``count`` particles at random in a box (``center``, edge lengths ``size`` [m]),
        with a mean ``velocity`` and a ``velocity_jitter`` [m/s], ``mass``, ``radius``, ``seed``."""
        return self.add("particle_cloud", **given(locals()))
