"""The scene table of a hair strand: a rope with bending and torsion springs (``type = "hair"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from ..deformable import DeformableBody, Pins, PositiveEach
from ..fields import Color, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given

__all__ = ["Hair"]


class Hair(DeformableBody):
    """``type = "hair"``: a strand of hair (Selle, Lentine & Fedkiw 2008): particles at
    ``points``, from the root, joined by damped springs in three families — *edge* springs of
    ``stiffness`` k [N/m] between consecutive points, *bending* springs of ``bending`` [N/m]
    between points two apart and *torsion* springs of ``torsion`` [N/m] between points three
    apart (a family of stiffness 0 is left out) — each with ``damping`` c [N·s/m] along the
    spring and at rest at its length as built. The root (point 0) is pinned unless ``pinned``
    says otherwise. Selle et al.'s altitude springs (which keep a straight stretch of strand
    from folding flat) are left out."""

    type: Literal["hair"]
    noun: ClassVar[str] = "hair strand"
    name: Name | None = None
    points: Annotated[list[Vector], Field(min_length=2)] = Field(
        description="positions of the particles along the strand [m], root first"
    )
    velocities: list[Vector] | None = Field(None, description="initial velocities [m/s]")
    mass: PositiveEach = Field(description="mass of each particle [kg]: one value or one per point")
    stiffness: Positive = Field(description="stiffness k of the edge springs [N/m]")
    bending: NonNegative = Field(
        description="stiffness of the bending springs, between points two apart [N/m] (0: none)"
    )
    torsion: NonNegative = Field(
        0.0, description="stiffness of the torsion springs, between points three apart [N/m]"
    )
    damping: NonNegative = Field(0.0, description="damping c of every spring [N s/m]")
    pinned: Pins = Field(
        default_factory=lambda: [0],
        description="indices of the points held fixed (default: the root, point 0)",
    )
    radius: Positive = Field(0.005, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int:
        """The strand's particles."""
        return len(self.points)


class HairMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_hair(
        self: Builds,
        points: Any,
        *,
        mass: float | Sequence[float],
        stiffness: float,
        bending: float,
        torsion: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocities: Any = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add a hair strand (Selle, Lentine & Fedkiw 2008): particles at ``points`` [m]
        ``(n, 3)``, root first (in this order in the state), of ``mass`` [kg] (one value or
        one per point), joined by edge springs of ``stiffness`` [N/m] between consecutive
        points, bending springs of ``bending`` [N/m] between points two apart and torsion
        springs of ``torsion`` [N/m] (default none) between points three apart, each with
        ``damping`` [N·s/m]; the points ``pinned`` (default: the root, ``[0]``; ``[]`` for a
        free strand) stay where they are, or follow the ``handle``'s motion (a moving head).
        Selle et al.'s altitude springs are left out (see
        :mod:`visviva.deformables.topology`)."""
        return self.add("hair", **given(locals()))
