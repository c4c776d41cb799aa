"""The scene table of a volumetric soft body on a lattice (``type = "soft_lattice"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from ..deformable import DeformableBody, Pins
from ..fields import Color, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given, refusing_renamed

__all__ = ["SoftLattice"]

#: Field names this kind gave up, and their replacements (issue 26, one vocabulary).
RENAMED = MappingProxyType({"stretch": "stiffness"})


class SoftLattice(DeformableBody):
    """``type = "soft_lattice"``: a volumetric soft body (seed 004): ``resolution`` = [nx, ny,
    nz] particles on a lattice filling the box from ``origin`` with edge lengths ``size``,
    joined by structural (``stiffness``), face-diagonal (``shear``) and body-diagonal
    (``diagonal``) springs, each with ``damping`` c [N·s/m]. Point (i, j, k) has index
    (k·ny + j)·nx + i; each weighs ``density`` [kg/m³] times an eighth of each cell around it."""

    type: Literal["soft_lattice"]
    noun: ClassVar[str] = "lattice"
    name: Name | None = None
    origin: Vector = Field((0.0, 0.5, 0.0), description="the box's lowest corner [m]")
    size: tuple[Positive, Positive, Positive] = Field(
        (0.5, 0.5, 0.5), description="edge lengths of the box [m]"
    )
    resolution: tuple[
        Annotated[int, Field(strict=True, ge=2, le=512)],
        Annotated[int, Field(strict=True, ge=2, le=512)],
        Annotated[int, Field(strict=True, ge=2, le=512)],
    ] = Field(description="points along x, y and z [nx, ny, nz]")
    density: Positive = Field(1000.0, description="mass per volume [kg/m³]")
    stiffness: Positive = Field(description="stiffness k of the structural springs [N/m]")
    shear: NonNegative | None = Field(
        None, description="stiffness of the face-diagonal springs [N/m] (default: stiffness)"
    )
    diagonal: NonNegative | None = Field(
        None, description="stiffness of the body-diagonal springs [N/m] (default: stiffness)"
    )
    damping: NonNegative = Field(0.0, description="damping c of every spring [N s/m]")
    pinned: Pins = Field(default_factory=list, description="indices of the points held fixed")
    velocity: Vector = Field((0.0, 0.0, 0.0), description="initial velocity [m/s]")
    radius: Positive = Field(0.01, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int:
        """The lattice's particles, nx·ny·nz."""
        return self.resolution[0] * self.resolution[1] * self.resolution[2]


class SoftLatticeMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    @refusing_renamed("soft_lattice", RENAMED)
    def add_soft_lattice(
        self: Builds,
        resolution: Sequence[int],
        *,
        stiffness: float,
        origin: Triple | None = None,
        size: Triple | None = None,
        density: float | None = None,
        shear: float | None = None,
        diagonal: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Triple | None = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add a soft body: ``resolution`` = (nx, ny, nz) points on a lattice filling the box
        from the corner ``origin`` with edge lengths ``size`` [m], of ``density`` [kg/m³],
        with structural springs of ``stiffness`` [N/m] and face- and body-diagonal springs of
        ``shear`` and ``diagonal`` (default ``stiffness``), each with ``damping`` [N·s/m];
        point (i, j, k) has index (k·ny + j)·nx + i; the points ``pinned`` stay where they
        are, or follow the ``handle``'s motion."""
        fields = given(locals())
        fields["resolution"] = tuple(fields["resolution"])
        return self.add("soft_lattice", **fields)
