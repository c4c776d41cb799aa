"""The scene table of a volumetric soft body from a tetrahedral mesh (``type = "soft_mesh"``)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Annotated, Any, ClassVar, Literal

from pydantic import Field

from ..deformable import DeformableBody, Pins
from ..fields import Color, Index, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given

__all__ = ["SoftMesh"]


class SoftMesh(DeformableBody):
    """``type = "soft_mesh"``: a volumetric soft body from a tetrahedral mesh. A particle at
    each of the ``vertices`` [m], weighing the ``density`` [kg/m³] times a quarter of the
    volume of each tetrahedron around it (so the body weighs density × volume), and a spring
    of ``stiffness`` [N/m] and ``damping`` c [N·s/m] on every edge of every tetrahedron. Each
    tetrahedron [a, b, c, d] must have a positive volume in the standard orientation,
    (b − a)·((c − a) × (d − a)) > 0, and every vertex must be in one."""

    type: Literal["soft_mesh"]
    noun: ClassVar[str] = "soft mesh"
    name: Name | None = None
    vertices: Annotated[list[Vector], Field(min_length=4)] = Field(
        description="positions of the mesh's vertices, one particle each [m]"
    )
    tetrahedra: Annotated[list[tuple[Index, Index, Index, Index]], Field(min_length=1)] = Field(
        description="the tetrahedra: four indices into `vertices` each, positively oriented"
    )
    density: Positive = Field(description="mass per volume [kg/m³]")
    stiffness: Positive = Field(description="stiffness k of the springs on the edges [N/m]")
    damping: NonNegative = Field(0.0, description="damping c of every spring [N s/m]")
    pinned: Pins = Field(default_factory=list, description="indices of the vertices held fixed")
    velocity: Vector = Field((0.0, 0.0, 0.0), description="initial velocity [m/s]")
    radius: Positive = Field(0.01, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int:
        """The mesh's particles, one per vertex."""
        return len(self.vertices)


class SoftMeshMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_soft_mesh(
        self: Builds,
        vertices: Any,
        tetrahedra: Any,
        *,
        density: float,
        stiffness: float,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Triple | None = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add a soft body on a tetrahedral mesh: a particle at each of the ``vertices`` [m]
        ``(n, 3)`` (in this order in the state) weighing the ``density`` [kg/m³] times a
        quarter of the volume of each of its ``tetrahedra`` ``(T, 4)`` (vertex indices
        [a, b, c, d] with (b − a)·((c − a) × (d − a)) > 0), and a spring of ``stiffness``
        [N/m] and ``damping`` [N·s/m] on every edge; the vertices ``pinned`` stay where they
        are, or follow the ``handle``'s motion."""
        return self.add("soft_mesh", **given(locals()))
