"""The scene table of particles at given positions, moving freely (``type = "particles"``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Any, Literal

from pydantic import Field

from ..fields import (
    Color,
    Name,
    Positive,
    Strict,
    Vector,
)
from ..methods import Builds, Triple, given

__all__ = ["Particles"]


class Particles(Strict):
    """``type = "particles"``: particles at given positions, moving freely under the forces."""

    type: Literal["particles"]
    name: Name | None = None
    positions: Annotated[list[Vector], Field(min_length=1)] = Field(
        description="initial positions [m], one [x, y, z] per particle"
    )
    velocities: list[Vector] | None = Field(None, description="initial velocities [m/s]")
    mass: Positive | Annotated[list[Positive], Field(min_length=1)] = Field(
        1.0, description="mass [kg]: one value or one per particle"
    )
    radius: Positive | Annotated[list[Positive], Field(min_length=1)] = Field(
        0.05, description="radius [m] (drawing and collisions)"
    )
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")


class ParticlesMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_particles(
        self: Builds,
        positions: Any,
        *,
        velocities: Any = None,
        mass: float | Sequence[float] | None = None,
        radius: float | Sequence[float] | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add particles at ``positions`` [m] ``(n, 3)`` with ``velocities`` [m/s], ``mass`` [kg]
        and ``radius`` [m] (one value or one per particle) and an sRGB ``color``."""
        return self.add("particles", **given(locals()))
