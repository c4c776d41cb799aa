"""The scene entity of a rigid body (``type = "body"``), as plain data validated by pydantic.

A body is a shape — a primitive with its dimensions, or a closed triangle mesh given as arrays
or read from a file — with a density or a total mass, placed at ``position`` with
``orientation``, moving with ``velocity`` and ``angular_velocity``. Its mass properties come
from :mod:`visviva.rigid` when the scene is built; its state is ``(x, q, P, L)``
(:mod:`visviva.rigid.motion`). What each shape needs:

==========  =============================================================================
shape       dimensions [m]
==========  =============================================================================
box         ``size``: the three full edge lengths
sphere      ``radius``
ellipsoid   ``size``: the three semi-axes
cylinder    ``radius``, ``height`` (axis along the body's y)
capsule     ``radius``, ``height``: the distance between its hemispheres' centres (axis y)
cone        ``radius``, ``height``: base in the body's y = 0 plane, apex at y = ``height``
mesh        ``vertices`` and ``triangles`` (counter-clockwise seen from outside), or ``path``
==========  =============================================================================

``position`` is where the body's own origin goes (the shape's centre for the primitives but
the cone, whose origin is its base's centre; a mesh's coordinate origin); the state's
``body_position`` is its centre of mass.

A body's ``motion`` is ``"dynamic"`` (forces and torques move it), ``"kinematic"`` (it moves
at its ``velocity`` and turns at its ``angular_velocity`` forever, whatever acts on it, like
an animated obstacle) or ``"static"`` (it stays where it is put).

A body may be pushed (``[[entities.push]]``: a force [N] in the world frame at a point of the
body, given in its own axes, for a while) and anchored (``[entities.anchor]``: a point of the
body held at a world point by a stiff damped spring, a ball joint by penalty).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Annotated, Any, ClassVar, Literal, Self

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..deformable import FilePath
from ..fields import (
    Color,
    Finite,
    Fraction,
    Index,
    Name,
    NonNegative,
    Positive,
    Strict,
    Vector,
)
from ..methods import Builds, Triple, given, refusing_renamed

__all__ = ["BODY_SHAPES", "Anchor", "Push", "RigidBody"]

BodyShape = Literal["box", "sphere", "ellipsoid", "cylinder", "capsule", "cone", "mesh"]
BODY_SHAPES: tuple[str, ...] = BodyShape.__args__  # type: ignore[attr-defined]

#: The dimensions each shape takes (the others must be left out).
DIMENSIONS: dict[str, tuple[str, ...]] = {
    "box": ("size",),
    "sphere": ("radius",),
    "ellipsoid": ("size",),
    "cylinder": ("radius", "height"),
    "capsule": ("radius", "height"),
    "cone": ("radius", "height"),
    "mesh": (),
}
_ALL_DIMENSIONS = ("size", "radius", "height")
Quaternion = tuple[Finite, Finite, Finite, Finite]

#: Field names this kind gave up, and their replacements (issue 26, one vocabulary).
RENAMED = MappingProxyType(
    {"linear_damping": "linear_damping_rate", "angular_damping": "angular_damping_rate"}
)


class Push(Strict):
    """A force on the body at one of its points for a while (``[[entities.push]]``)."""

    force: Vector = Field(description="the force, world frame [N]")
    point: Vector | None = Field(
        None, description="where it acts, in the body's own axes [m] (default: centre of mass)"
    )
    frame: Literal["body", "world"] = Field(
        "body", description="`point` is a point of the body (turning with it) or of the world"
    )
    start: NonNegative = Field(0.0, description="when it starts [s]")
    duration: Positive | None = Field(None, description="how long it acts [s] (default: ever)")


class Anchor(Strict):
    """A point of the body held at a world point by a damped spring (``[entities.anchor]``)."""

    point: Vector = Field(description="the anchored point, in the body's own axes [m]")
    at: Vector | None = Field(
        None, description="the world point it is held at [m] (default: where it starts)"
    )
    stiffness: Positive = Field(description="k of the spring [N/m]")
    damping: NonNegative = Field(0.0, description="c of its damper [N s/m]")


class RigidBody(Strict):
    """``type = "body"``: a rigid body (see the module docstring)."""

    type: Literal["body"]
    noun: ClassVar[str] = "body"
    name: Name | None = None
    shape: BodyShape = Field(description="box, sphere, ellipsoid, cylinder, capsule, cone, mesh")
    density: Positive | None = Field(None, description="mass per volume [kg/m^3]")
    mass: Positive | None = Field(None, description="total mass [kg] (instead of density)")
    size: tuple[Positive, Positive, Positive] | None = Field(
        None, description="box: full edge lengths; ellipsoid: semi-axes [m]"
    )
    radius: Positive | None = Field(None, description="sphere, cylinder, capsule, cone [m]")
    height: Positive | None = Field(None, description="cylinder, capsule, cone, along y [m]")
    path: FilePath | None = Field(None, description="mesh: a mesh file to read")
    vertices: Annotated[list[Vector], Field(min_length=4)] | None = Field(
        None, description="mesh: vertex positions in the body's axes [m]"
    )
    triangles: Annotated[list[tuple[Index, Index, Index]], Field(min_length=4)] | None = Field(
        None, description="mesh: triangles, counter-clockwise seen from outside"
    )
    position: Vector = Field((0.0, 0.0, 0.0), description="where the body's origin is [m]")
    orientation: Quaternion = Field(
        (1.0, 0.0, 0.0, 0.0), description="unit quaternion (w, x, y, z), body to world"
    )
    velocity: Vector = Field((0.0, 0.0, 0.0), description="of the centre of mass [m/s]")
    angular_velocity: Vector = Field((0.0, 0.0, 0.0), description="world frame [rad/s]")
    motion: Literal["dynamic", "kinematic", "static"] = Field(
        "dynamic", description="dynamic (forces move it), kinematic (moves as given), static"
    )
    linear_damping_rate: NonNegative = Field(0.0, description="P' = F − γ P: γ [1/s]")
    angular_damping_rate: NonNegative = Field(0.0, description="L' = τ − γ L: γ [1/s]")
    push: list[Push] = Field(default_factory=list, description="forces at points, for a while")
    anchor: Anchor | None = Field(None, description="a point held by a spring")
    color: Color = Field((0.8, 0.8, 0.8), description="sRGB colour in [0, 1]")
    restitution: Fraction = Field(
        0.5, description="coefficient of restitution e of its contacts (a pair takes the larger)"
    )
    friction: NonNegative = Field(
        0.5, description="Coulomb friction μ of its contacts (a pair takes √(μ_a μ_b))"
    )
    collision_shape: Literal["shape", "hull", "decomposition", "none"] = Field(
        "shape",
        description="what it collides as: its shape (a mesh must be convex), its mesh's convex "
        "hull, its mesh cut into convex pieces (CoACD), or nothing",
    )
    time_of_impact: Literal["auto", "always", "never"] = Field(
        "auto",
        description="look for its first impact within a step: auto (when it moves more than a "
        "quarter of its size in a step), always, never",
    )
    convex_pieces: (
        Annotated[list[Annotated[list[Vector], Field(min_length=4)]], Field(min_length=1)] | None
    ) = Field(
        None,
        description="the convex pieces it collides as: each the hull of ≥ 4 points in the "
        "body's own axes [m] (instead of its shape)",
    )

    @model_validator(mode="after")
    def _complete(self) -> Self:
        if (self.density is None) == (self.mass is None):
            raise PydanticCustomError(
                "mass_or_density", "give the body a `density` [kg/m^3] or a `mass` [kg], not both"
            )
        needed = DIMENSIONS[self.shape]
        for name in _ALL_DIMENSIONS:
            given = getattr(self, name) is not None
            if name in needed and not given:
                raise PydanticCustomError(
                    "missing_dimension",
                    "a {shape} needs {needs}",
                    {"shape": self.shape, "needs": " and ".join(f"`{n}`" for n in needed)},
                )
            if given and name not in needed:
                raise PydanticCustomError(
                    "extra_dimension",
                    "a {shape} takes no `{field}` (it takes {needs})",
                    {
                        "shape": self.shape,
                        "field": name,
                        "needs": ", ".join(needed) or "vertices and triangles, or path",
                    },
                )
        meshed = self.path is not None or self.vertices is not None or self.triangles is not None
        if self.shape != "mesh" and meshed:
            raise PydanticCustomError(
                "not_a_mesh", 'vertices, triangles and path belong to shape = "mesh"'
            )
        if self.shape == "mesh":
            arrays = self.vertices is not None and self.triangles is not None
            if (self.path is not None) == arrays or (not arrays and self.vertices is not None):
                raise PydanticCustomError(
                    "one_mesh",
                    "give the mesh either as `path` (a mesh file) or as `vertices` and `triangles`",
                )
        if self.motion == "static" and (any(self.velocity) or any(self.angular_velocity)):
            raise PydanticCustomError(
                "static_moving",
                "a static body does not move: leave out `velocity` and `angular_velocity`, or "
                'make it motion = "kinematic" to move it at them',
            )
        if self.motion != "dynamic" and (self.push or self.anchor is not None):
            raise PydanticCustomError(
                "driven_pushed",
                "a {motion} body moves as it is given, not by forces: `push` and `anchor` "
                'belong to motion = "dynamic"',
                {"motion": self.motion},
            )
        if self.convex_pieces is not None and self.collision_shape != "shape":
            raise PydanticCustomError(
                "pieces_and_shape",
                "give `convex_pieces` or `collision_shape`, not both: the pieces are what the "
                "body collides as",
            )
        if self.collision_shape in ("hull", "decomposition") and self.shape != "mesh":
            raise PydanticCustomError(
                "hull_of_primitive",
                'collision_shape = "{kind}" is for a mesh; a {shape} collides as itself '
                "(leave `collision_shape` out)",
                {"shape": self.shape, "kind": self.collision_shape},
            )
        if not any(self.orientation):
            raise PydanticCustomError(
                "zero_quaternion",
                "`orientation` (0, 0, 0, 0) is no rotation: give a unit quaternion (w, x, y, z), "
                "e.g. (1, 0, 0, 0) for none",
            )
        return self

    def dimensions(self) -> dict[str, Any]:
        """The shape's dimensions as keywords of :func:`visviva.rigid.mass_properties`."""
        return {name: getattr(self, name) for name in DIMENSIONS[self.shape]}


class RigidBodyMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    @refusing_renamed("body", RENAMED)
    def add_body(
        self: Builds,
        shape: str,
        *,
        density: float | None = None,
        mass: float | None = None,
        position: Triple | None = None,
        orientation: Sequence[float] | None = None,
        velocity: Triple | None = None,
        angular_velocity: Triple | None = None,
        size: Triple | None = None,
        radius: float | None = None,
        height: float | None = None,
        vertices: Any = None,
        triangles: Any = None,
        path: str | os.PathLike[str] | None = None,
        linear_damping_rate: float | None = None,
        angular_damping_rate: float | None = None,
        push: Sequence[Mapping[str, Any]] | None = None,
        anchor: Mapping[str, Any] | None = None,
        motion: str | None = None,
        color: Triple | None = None,
        restitution: float | None = None,
        friction: float | None = None,
        collision_shape: str | None = None,
        convex_pieces: Sequence[Any] | None = None,
        time_of_impact: str | None = None,
        name: str | None = None,
    ) -> int:
        """Add a rigid body: a ``shape`` (``"box"`` with ``size`` [m] its full edge lengths,
        ``"sphere"`` with ``radius``, ``"ellipsoid"`` with ``size`` its semi-axes,
        ``"cylinder"``, ``"capsule"``, ``"cone"`` with ``radius`` and ``height`` along its y
        axis, ``"mesh"`` with ``vertices`` ``(V, 3)`` and ``triangles`` ``(T, 3)`` or a mesh
        file at ``path``) of uniform ``density`` [kg/m³] or total ``mass`` [kg], its own
        origin at ``position`` [m], turned by ``orientation`` (a unit quaternion (w, x, y, z),
        body to world), its centre of mass moving at ``velocity`` [m/s] and spinning at
        ``angular_velocity`` [rad/s] (world frame); ``linear_damping_rate`` and
        ``angular_damping_rate`` [1/s] damp its momenta; ``push`` is a list of forces at its
        points (``{"force": ..., "point": ..., "start": ..., "duration": ...}``) and
        ``anchor`` holds one of its points at a world point by a spring (``{"point": ...,
        "at": ..., "stiffness": ..., "damping": ...}``). ``motion``: ``"dynamic"`` (the
        default), ``"kinematic"`` (moves at its velocities whatever acts on it) or
        ``"static"`` (see :mod:`visviva.entities.body.schema`). With ``add_body_contacts`` it
        collides with ``restitution`` e in [0, 1] and Coulomb ``friction`` μ (a pair takes the
        larger e and √(μ_a μ_b)) as its shape, or ``collision_shape="hull"`` (a mesh's convex
        hull), ``"decomposition"`` (a mesh cut into convex pieces), ``"none"``, or
        ``convex_pieces``: a list of point sets in its own axes [m], each
        piece their convex hull; its first impact within a step is looked for when it moves
        fast (``time_of_impact="auto"``), ``"always"`` or ``"never"``
        (:mod:`visviva.collision.body_contacts`).
        Its state is ``body_position`` (the centre of mass), ``body_orientation``,
        ``body_momentum`` and ``body_angular_momentum``."""
        fields = given(locals())
        if "path" in fields:
            fields["path"] = os.fspath(fields["path"])
        return self.add("body", **fields)
