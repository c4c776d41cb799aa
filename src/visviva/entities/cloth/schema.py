"""The scene table of a cloth: a grid of particles joined by structural, shear and bending
springs (``type = "cloth"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..deformable import DeformableBody, Pins
from ..fields import Color, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given, refusing_renamed

__all__ = ["Cloth"]

#: Field names this kind gave up, and their replacements (issue 26, one vocabulary).
RENAMED = MappingProxyType({"stretch": "stiffness", "bend": "bending", "density": "areal_density"})


class Cloth(DeformableBody):
    """``type = "cloth"``: a sheet of ``resolution`` = [nu, nv] particles on a grid spanning
    ``origin + s·along + t·across`` (s, t in [0, 1]), joined by structural (``stiffness``),
    shear (``shear``, cell diagonals) and bending (``bending``, two apart) springs (Choi & Ko
    2002), each with ``damping`` c [N·s/m]. Point (i, j) has index j·nu + i. Each point weighs
    ``areal_density`` [kg/m²] times its share of the cells around it."""

    type: Literal["cloth"]
    noun: ClassVar[str] = "cloth"
    name: Name | None = None
    origin: Vector = Field((0.0, 1.0, 0.0), description="position of point (0, 0) [m]")
    along: Vector = Field((1.0, 0.0, 0.0), description="edge from point (0, 0) to (nu − 1, 0) [m]")
    across: Vector = Field((0.0, 0.0, 1.0), description="edge from point (0, 0) to (0, nv − 1) [m]")
    resolution: tuple[
        Annotated[int, Field(strict=True, ge=2, le=4096)],
        Annotated[int, Field(strict=True, ge=2, le=4096)],
    ] = Field(description="points along and across [nu, nv]")
    areal_density: Positive = Field(0.2, description="mass per area [kg/m²]")
    stiffness: Positive = Field(description="stiffness k of the structural springs [N/m]")
    shear: NonNegative | None = Field(
        None, description="stiffness of the shear springs [N/m] (default: stiffness; 0: none)"
    )
    bending: NonNegative = Field(
        0.0, description="stiffness of the bending springs, two points apart [N/m] (0: none)"
    )
    damping: NonNegative = Field(0.0, description="damping c of every spring [N s/m]")
    pinned: Pins = Field(
        default_factory=list, description="indices (j·nu + i) of the points held fixed"
    )
    velocity: Vector = Field((0.0, 0.0, 0.0), description="initial velocity [m/s]")
    radius: Positive = Field(0.01, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int:
        """The sheet's particles, nu·nv."""
        return self.resolution[0] * self.resolution[1]

    @model_validator(mode="after")
    def _a_sheet(self) -> Cloth:
        a, b = self.along, self.across
        normal = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
        if not any(normal):
            raise PydanticCustomError(
                "no_area",
                "`along` {along} and `across` {across} are parallel or zero: the sheet has no "
                "area; give two edges at an angle",
                {"along": list(a), "across": list(b)},
            )
        return self


class ClothMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    @refusing_renamed("cloth", RENAMED)
    def add_cloth(
        self: Builds,
        resolution: Sequence[int],
        *,
        stiffness: float,
        origin: Triple | None = None,
        along: Triple | None = None,
        across: Triple | None = None,
        areal_density: float | None = None,
        shear: float | None = None,
        bending: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Triple | None = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add a cloth: ``resolution`` = (nu, nv) points on a grid spanning ``origin + s·along
        + t·across`` [m], of ``areal_density`` [kg/m²], with structural springs of
        ``stiffness`` [N/m], shear springs of ``shear`` (default ``stiffness``) and bending
        springs of ``bending`` [N/m] (default none), each with ``damping`` [N·s/m]; point
        (i, j) has index j·nu + i, and the points ``pinned`` stay where they are, or follow the
        ``handle``'s motion."""
        fields = given(locals())
        fields["resolution"] = tuple(fields["resolution"])
        return self.add("cloth", **fields)
