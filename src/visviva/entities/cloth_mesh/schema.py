"""The scene table of cloth from any triangle mesh (``type = "cloth_mesh"``)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Annotated, Any, ClassVar, Literal, Self

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..deformable import DeformableBody, FilePath, Pins
from ..fields import Color, Index, Name, NonNegative, Positive, Vector
from ..handles import Handle
from ..methods import Builds, Triple, given, refusing_renamed

__all__ = ["ClothMesh"]

#: Field names this kind gave up, and their replacements (issue 26, one vocabulary).
RENAMED = MappingProxyType({"stretch": "stiffness", "bend": "bending", "density": "areal_density"})


class ClothMesh(DeformableBody):
    """``type = "cloth_mesh"``: cloth from any triangle mesh, given as ``vertices`` and
    ``triangles`` or read from the mesh file at ``path`` (OBJ, STL, PLY, OFF, glTF: see
    :mod:`visviva.io.meshes`; in a scene file, a relative path is relative to the
    scene file's folder). A particle at each vertex [m], weighing the ``areal_density``
    [kg/m²] times a third of the area of each triangle around it (so the cloth weighs
    areal_density × area); *stretch* springs of ``stiffness`` [N/m] on every edge of the mesh
    and *bending* springs of ``bending`` [N/m] between the two vertices facing each other
    across every edge two triangles share; every spring with ``damping`` c [N·s/m]. A triangle
    resists shear by itself, so a mesh has no shear family. The mesh must be manifold (no edge
    in three triangles) with every vertex in a triangle. A mesh file is read when the scene is
    built; the built model's scene holds its vertices and triangles instead of the path."""

    type: Literal["cloth_mesh"]
    noun: ClassVar[str] = "cloth mesh"
    name: Name | None = None
    path: FilePath | None = Field(
        None, description="a mesh file to read the vertices and triangles from"
    )
    vertices: Annotated[list[Vector], Field(min_length=3)] | None = Field(
        None, description="positions of the mesh's vertices, one particle each [m]"
    )
    triangles: Annotated[list[tuple[Index, Index, Index]], Field(min_length=1)] | None = Field(
        None, description="the triangles: three indices into `vertices` each"
    )
    areal_density: Positive = Field(description="mass per area [kg/m²]")
    stiffness: Positive = Field(description="stiffness k of the springs on the edges [N/m]")
    bending: NonNegative = Field(
        0.0, description="stiffness of the springs across the edges [N/m] (0: none)"
    )
    damping: NonNegative = Field(0.0, description="damping c of every spring [N s/m]")
    pinned: Pins = Field(default_factory=list, description="indices of the vertices held fixed")
    velocity: Vector = Field((0.0, 0.0, 0.0), description="initial velocity [m/s]")
    radius: Positive = Field(0.01, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")

    @property
    def point_count(self) -> int | None:  # type: ignore[override]
        """The mesh's particles, one per vertex (``None`` until its file is read)."""
        return None if self.vertices is None else len(self.vertices)

    @model_validator(mode="after")
    def _one_mesh(self) -> Self:
        given = self.vertices is not None or self.triangles is not None
        if self.path is not None and given:
            raise PydanticCustomError(
                "path_and_arrays",
                "give the mesh either as `path` (a mesh file) or as `vertices` and "
                "`triangles`, not both",
            )
        if self.path is None and (self.vertices is None or self.triangles is None):
            missing = "`triangles`" if self.vertices is not None else "`vertices`"
            raise PydanticCustomError(
                "no_mesh",
                "{missing} missing: give the mesh as `vertices` and `triangles`, or as `path` "
                "(a mesh file)",
                {"missing": missing if given else "the mesh is"},
            )
        return self


class ClothMeshMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    @refusing_renamed("cloth_mesh", RENAMED)
    def add_cloth_mesh(
        self: Builds,
        vertices: Any = None,
        triangles: Any = None,
        *,
        path: str | os.PathLike[str] | None = None,
        areal_density: float,
        stiffness: float,
        bending: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Triple | None = None,
        radius: float | None = None,
        color: Triple | None = None,
        name: str | None = None,
    ) -> int:
        """Add cloth on a triangle mesh: a particle at each of the ``vertices`` [m] ``(n, 3)``
        (in this order in the state) weighing the ``areal_density`` [kg/m²] times a third of
        the area of each of its ``triangles`` ``(T, 3)`` (vertex indices); stretch springs of
        ``stiffness`` [N/m] on every edge and bending springs of ``bending`` [N/m] (default
        none) between the vertices facing each other across every edge two triangles share,
        each with ``damping`` [N·s/m]. A triangle resists shear by itself: there is no shear
        family. The vertices ``pinned`` stay where they are, or follow the ``handle``'s
        motion.

        Instead of ``vertices`` and ``triangles``, ``path`` names a mesh file (OBJ, STL, PLY,
        OFF, glTF; relative to the working directory), read at once: its vertices are those
        of :func:`visviva.io.meshes.read_triangle_mesh`, which ``pinned`` indexes.
        """
        fields = given(locals())
        if "path" in fields:
            fields["path"] = os.fspath(fields["path"])
        return self.add("cloth_mesh", **fields)
