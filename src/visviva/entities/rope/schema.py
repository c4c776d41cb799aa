"""The scene table of a rope: particles joined in order by damped springs (``type = "rope"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from ..deformable import DeformableBody, Pins, PositiveEach
from ..fields import Color, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given

__all__ = ["Rope"]


class Rope(DeformableBody):
    """``type = "rope"``: particles at ``points`` joined in order by damped springs (seed 002).

    Each consecutive pair is a stretch spring of ``stiffness`` k [N/m] and ``damping`` c
    [N·s/m] along the spring, at rest at the points' distance; ``bending`` > 0 adds springs
    between particles two apart, which resist bending (and, seed 000 warns, also stretch).
    Particles listed in ``pinned`` stay where they are.
    """

    type: Literal["rope"]
    noun: ClassVar[str] = "rope"
    name: Name | None = None
    points: Annotated[list[Vector], Field(min_length=2)] = Field(
        description="positions of the particles along the rope [m], in order"
    )
    velocities: list[Vector] | None = Field(None, description="initial velocities [m/s]")
    mass: PositiveEach = Field(
        1.0, description="mass of each particle [kg]: one value or one per point"
    )
    stiffness: Positive = Field(description="stiffness k of each stretch spring [N/m]")
    damping: NonNegative = Field(0.0, description="damping c of each spring [N s/m]")
    bending: NonNegative = Field(
        0.0, description="stiffness of the springs between particles two apart [N/m] (0: none)"
    )
    pinned: Pins = Field(default_factory=list, description="indices of the points held fixed")
    radius: Positive = Field(0.02, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int:
        """The rope's particles."""
        return len(self.points)


class RopeMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_rope(
        self: Builds,
        points: Any,
        *,
        stiffness: float,
        mass: float | Sequence[float] | None = None,
        damping: float | None = None,
        bending: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocities: Any = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add a rope: particles at ``points`` [m] ``(n, 3)`` (in this order in the state) of
        ``mass`` [kg] (one value or one per point), joined in order by springs of
        ``stiffness`` [N/m] and ``damping`` [N·s/m] at rest at the points' distances;
        ``bending`` [N/m] > 0 adds springs between points two apart; the points ``pinned``
        (indices) stay where they are, or follow the ``handle``'s motion."""
        return self.add("rope", **given(locals()))
