"""The scene table of a static shape particles bounce off (``type = "collider"``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Any, Literal, get_args

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..fields import (
    Color,
    Finite,
    Fraction,
    Name,
    Names,
    NonNegative,
    Positive,
    Strict,
    Vector,
)
from ..methods import Builds, Triple, given

__all__ = ["COLLIDER_FIELDS", "COLLIDER_SHAPES", "DEFAULT_SCENERY_COLOR", "Collider"]

#: The colour drawn for a collider without one (in the scene or the recording): a neutral grey,
#: darker than the video's ground, sRGB.
DEFAULT_SCENERY_COLOR = (0.6, 0.6, 0.6)


ColliderShape = Literal["plane", "sphere", "box", "mesh"]


COLLIDER_SHAPES: tuple[str, ...] = get_args(ColliderShape)


#: The fields each collider shape uses (besides the response settings every shape has).
COLLIDER_FIELDS: dict[str, tuple[str, ...]] = {
    "plane": ("point", "normal", "thickness"),
    "sphere": ("center", "radius"),
    "box": ("center", "size", "orientation"),
    "mesh": ("vertices", "triangles"),
}


_REQUIRED_COLLIDER_FIELDS = {
    "sphere": ("radius",),
    "box": ("size",),
    "mesh": COLLIDER_FIELDS["mesh"],
}


class Collider(Strict):
    """``type = "collider"``: a static shape that particles bounce off or are pushed out of.

    Shapes: ``plane`` (``point``, outward ``normal``, optional ``thickness`` [m]: a thin wall;
    without it, a half-space), ``sphere`` (``center``, ``radius``), ``box`` (``center``, ``size``:
    edge lengths, ``orientation`` as a unit quaternion w, x, y, z) and ``mesh`` (a closed
    ``vertices`` / ``triangles`` surface). ``response = "impulse"`` reflects the normal velocity
    with ``restitution`` (seed 002: v' = v − (1 + e)(v·N)N) and applies Coulomb ``friction``;
    ``response = "penalty"`` pushes penetrating particles out with a spring of ``stiffness``
    [N/m] and a damper of ``damping`` [N·s/m] (seeds 000 and 002).
    """

    type: Literal["collider"]
    name: Name | None = None
    shape: ColliderShape = Field(description=", ".join(COLLIDER_SHAPES))
    point: Vector | None = Field(None, description="a point on a plane [m]")
    normal: Vector | None = Field(None, description="a plane's outward normal")
    thickness: Positive | None = Field(None, description="a plane's thickness [m]")
    center: Vector | None = Field(None, description="centre of a sphere or box [m]")
    radius: Positive | None = Field(None, description="a sphere's radius [m]")
    size: tuple[Positive, Positive, Positive] | None = Field(
        None, description="a box's edge lengths [m]"
    )
    orientation: tuple[Finite, Finite, Finite, Finite] | None = Field(
        None, description="a box's orientation, unit quaternion (w, x, y, z)"
    )
    vertices: Annotated[list[Vector], Field(min_length=4)] | None = Field(
        None, description="a mesh's vertices [m]"
    )
    triangles: Annotated[list[tuple[int, int, int]], Field(min_length=4)] | None = Field(
        None, description="a mesh's triangles (vertex indices, counter-clockwise from outside)"
    )
    restitution: Fraction = Field(0.5, description="coefficient of restitution e in [0, 1]")
    friction: NonNegative = Field(0.0, description="Coulomb friction coefficient")
    response: Literal["impulse", "penalty"] = Field("impulse", description="impulse or penalty")
    stiffness: Positive | None = Field(None, description="penalty spring stiffness [N/m]")
    damping: NonNegative | None = Field(None, description="penalty damper [N s/m]")
    time_of_impact: bool = Field(
        True, description="find when, within a step, a particle hits (no tunnelling)"
    )
    resting_speed: NonNegative | None = Field(
        None, description="normal speed below which a contact rests [m/s] (default: 2|g|dt)"
    )
    targets: Names | None = Field(None, description="entity names (default: every particle)")
    color: Color | None = Field(
        None, description="sRGB colour drawn in the outputs, each in [0, 1] (default: grey)"
    )

    @model_validator(mode="after")
    def _fields_of_the_shape(self) -> Collider:
        used = COLLIDER_FIELDS[self.shape]
        for shape, fields in COLLIDER_FIELDS.items():
            for field in fields:
                if field not in used and getattr(self, field) is not None:
                    raise PydanticCustomError(
                        "not_a_parameter",
                        "`{field}` belongs to a {shape} collider, not a {this} (its fields: "
                        "{valid})",
                        {
                            "field": field,
                            "shape": shape,
                            "this": self.shape,
                            "valid": ", ".join(used),
                        },
                    )
        for field in _REQUIRED_COLLIDER_FIELDS.get(self.shape, ()):
            if getattr(self, field) is None:
                raise PydanticCustomError(
                    "missing_parameter",
                    "a {shape} collider needs `{field}`",
                    {"shape": self.shape, "field": field},
                )
        if self.normal is not None and not any(self.normal):
            raise PydanticCustomError("zero_vector", "`normal` must not be the zero vector")
        penalty = self.response == "penalty"
        if not penalty and (self.stiffness is not None or self.damping is not None):
            raise PydanticCustomError(
                "not_a_parameter",
                '`{field}` belongs to response = "penalty"',
                {"field": "stiffness" if self.stiffness is not None else "damping"},
            )
        if penalty and self.stiffness is None:
            raise PydanticCustomError(
                "missing_parameter", 'response = "penalty" needs `stiffness` [N/m]'
            )
        return self


class ColliderMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_collider(
        self: Builds,
        shape: str,
        *,
        point: Triple | None = None,
        normal: Triple | None = None,
        thickness: float | None = None,
        center: Triple | None = None,
        radius: float | None = None,
        size: Triple | None = None,
        orientation: Sequence[float] | None = None,
        vertices: Any = None,
        triangles: Any = None,
        restitution: float | None = None,
        friction: float | None = None,
        response: str | None = None,
        stiffness: float | None = None,
        damping: float | None = None,
        time_of_impact: bool | None = None,
        resting_speed: float | None = None,
        targets: Sequence[str] | None = None,
        color: Sequence[float] | None = None,
        name: str | None = None,
    ) -> int:
        """Add a static collider: ``"plane"`` (``point``, ``normal``, optional ``thickness``),
        ``"sphere"`` (``center``, ``radius``), ``"box"`` (``center``, ``size``,
        ``orientation``) or ``"mesh"`` (``vertices``, ``triangles``), with ``restitution`` e,
        ``friction`` μ, and ``response`` ``"impulse"`` or ``"penalty"`` (``stiffness``,
        ``damping``). The outputs draw a sphere, box or mesh in its sRGB ``color`` (default
        grey); planes are not drawn."""
        return self.add("collider", **given(locals()))
