"""The deformable bodies a scene may hold: particles joined by damped springs, each entity a
spring topology of :mod:`visviva.deformables` (built from these fields by
:func:`visviva.model.parts.spring_network`).

Curves: ``rope`` (seed 002) and ``hair`` (Selle, Lentine & Fedkiw 2008). Sheets: ``cloth`` (a
grid, Choi & Ko 2002) and ``cloth_mesh`` (any triangle mesh). Solids: ``soft_lattice`` (a
lattice, seed 004) and ``soft_mesh`` (any tetrahedral mesh). Any graph: ``springs``. Every
body's particles enter the state in the order of its points (or vertices), its ``pinned``
points stay where they are — or, with a ``handle`` (:mod:`.scene_handles`), follow its
prescribed motion — and every spring rests at its length as built (a ``springs`` entity may
give its own rest lengths).

The schema checks each field (types, signs, finite numbers) and the pins; what only the
geometry can tell — points that coincide, a triangle without area, a tetrahedron turned inside
out, an index past the points — is refused when the body is built, at the field and item at
fault (``entities[2].triangles[7]``).

References:
    K.-J. Choi, H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
    A. Selle, M. Lentine, R. Fedkiw, "A mass spring model for hair simulation", SIGGRAPH 2008.
"""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal, Self

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from .scene_fields import Color, Index, Name, NonNegative, Positive, Strict, Vector
from .scene_handles import Handle

__all__ = [
    "BODIES",
    "POINT_BODIES",
    "Body",
    "Cloth",
    "ClothMesh",
    "Hair",
    "Rope",
    "SoftLattice",
    "SoftMesh",
    "SpringGraph",
]

#: Indices of the points held fixed.
Pins = list[Index]
#: A file's path (relative: to the scene file's folder, or the working directory).
FilePath = Annotated[
    str, Field(strict=True, min_length=1, max_length=4096, pattern=r"^[^\x00-\x1f]*$")
]
#: One value, or one per point (or per spring).
PositiveEach = Positive | Annotated[list[Positive], Field(min_length=1)]


def _check_pins(pinned: list[int], count: int, body: str) -> None:
    """Refuse a pinned index past the body's ``count`` points."""
    outside = [i for i in pinned if i >= count]
    if outside:
        raise PydanticCustomError(
            "pin_out_of_range",
            "pinned index {index} is not a point of this {body} (it has {count}: 0 to {last})",
            {"index": outside[0], "body": body, "count": count, "last": count - 1},
        )


class _Body(Strict):
    """What every deformable body's schema shares: its pins must be among its points, and a
    handle moves its pins."""

    #: The body's name in messages.
    noun: ClassVar[str]
    pinned: Pins
    handle: Handle | None = Field(
        None, description="a prescribed rigid motion of the pinned points (default: they stay)"
    )

    @property
    def point_count(self) -> int:
        """The body's particles."""
        raise NotImplementedError

    @model_validator(mode="after")
    def _pins_on_the_body(self) -> Self:
        if self.point_count is not None:  # a mesh file's pins are checked once it is read
            _check_pins(self.pinned, self.point_count, self.noun)
        if self.handle is not None and not self.pinned:
            raise PydanticCustomError(
                "handle_without_pins",
                "a handle moves the pinned points, and this {body} has none: list the points "
                "it should move in `pinned`",
                {"body": self.noun},
            )
        return self


class Rope(_Body):
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


class Hair(_Body):
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


class SpringGraph(_Body):
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


class Cloth(_Body):
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


class ClothMesh(_Body):
    """``type = "cloth_mesh"``: cloth from any triangle mesh, given as ``vertices`` and
    ``triangles`` or read from the mesh file at ``path`` (OBJ, STL, PLY, OFF, glTF: see
    :mod:`visviva.deformables.mesh_files`; in a scene file, a relative path is relative to the
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


class SoftLattice(_Body):
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


class SoftMesh(_Body):
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


#: Every deformable entity: particles joined by springs.
Body = Rope | Hair | SpringGraph | Cloth | ClothMesh | SoftLattice | SoftMesh
BODIES = (Rope, Hair, SpringGraph, Cloth, ClothMesh, SoftLattice, SoftMesh)
#: The bodies whose particles are listed one by one (``points``, ``velocities``, ``mass``).
POINT_BODIES = (Rope, Hair, SpringGraph)
