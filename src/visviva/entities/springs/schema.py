"""The scene table of any graph of particles and damped springs (``type = "springs"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from ..deformable import DeformableBody, Pins, PositiveEach
from ..fields import Color, Index, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given

__all__ = ["SpringGraph"]


class SpringGraph(DeformableBody):
    """``type = "springs"``: particles at ``points`` joined by damped springs on any ``pairs``
    of them (indices into ``points``, each unordered pair at most once). Each spring has
    ``stiffness`` k [N/m] and ``rest_length`` L [m] (by default its length as built), one value
    or one per spring, and ``damping`` c [N·s/m] along it."""

    type: Literal["springs"]
    noun: ClassVar[str] = "spring network"
    name: Name | None = None
    points: Annotated[list[Vector], Field(min_length=2)] = Field(
        description="positions of the particles [m]"
    )
    pairs: Annotated[list[tuple[Index, Index]], Field(min_length=1)] = Field(
        description="the springs: [i, j] indices of the two points each one joins"
    )
    velocities: list[Vector] | None = Field(None, description="initial velocities [m/s]")
    mass: PositiveEach = Field(description="mass of each particle [kg]: one value or one per point")
    stiffness: PositiveEach = Field(
        description="stiffness k of the springs [N/m]: one value or one per spring"
    )
    rest_length: PositiveEach | None = Field(
        None,
        description="rest length L of the springs [m]: one value or one per spring (default: "
        "each spring's length as built)",
    )
    damping: NonNegative = Field(0.0, description="damping c of every spring [N s/m]")
    pinned: Pins = Field(default_factory=list, description="indices of the points held fixed")
    radius: Positive = Field(0.02, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int:
        """The network's particles."""
        return len(self.points)


class SpringGraphMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_springs(
        self: Builds,
        points: Any,
        pairs: Any,
        *,
        mass: float | Sequence[float],
        stiffness: float | Sequence[float],
        rest_length: float | Sequence[float] | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocities: Any = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add particles at ``points`` [m] ``(n, 3)`` (in this order in the state) of ``mass``
        [kg] (one value or one per point) joined by a spring on each of ``pairs`` ``(S, 2)``
        (indices into ``points``, each unordered pair once), of ``stiffness`` [N/m] and
        ``rest_length`` [m] (each one value or one per spring; rest lengths by default the
        springs' lengths as built) and ``damping`` [N·s/m]; the points ``pinned`` stay where
        they are, or follow the ``handle``'s motion."""
        return self.add("springs", **given(locals()))
