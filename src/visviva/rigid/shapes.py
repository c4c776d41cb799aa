"""Mass properties of a shape named as in a scene: ``mass_properties("box", 1000.0, size=...)``.

The names and dimensions are those of the scene builder's bodies: ``"box"`` (``size``, full edge
lengths), ``"sphere"`` (``radius``), ``"cylinder"``, ``"capsule"`` and ``"cone"`` (``radius``,
``height``), ``"ellipsoid"`` (``size``, the three semi-axes) and ``"mesh"`` (``vertices`` and
``triangles``; a mesh file's are :func:`visviva.io.read_triangle_mesh`'s). Lengths in metres,
density in kg/m³.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .._registry import did_you_mean
from .._validation import describe, with_article
from ..errors import ModelError
from .mass_properties import MassProperties
from .mesh_integrals import mesh_mass_properties
from .primitives import (
    box_mass_properties,
    capsule_mass_properties,
    cone_mass_properties,
    cylinder_mass_properties,
    ellipsoid_mass_properties,
    sphere_mass_properties,
)

__all__ = ["SHAPES", "mass_properties"]

#: Each shape's dimensions, as the keyword arguments of :func:`mass_properties` name them.
SHAPES: dict[str, tuple[str, ...]] = {
    "box": ("size",),
    "sphere": ("radius",),
    "cylinder": ("radius", "height"),
    "capsule": ("radius", "height"),
    "cone": ("radius", "height"),
    "ellipsoid": ("size",),
    "mesh": ("vertices", "triangles"),
}


@dataclass(frozen=True)
class Dimensions:
    """A shape's name and the dimensions given for it (checked for presence, not values)."""

    shape: str
    values: dict[str, Any]


def shape_dimensions(shape: Any, given: dict[str, Any]) -> Dimensions:
    """Check that ``shape`` is known and that exactly its dimensions are among ``given``
    (``None`` values count as not given)."""
    if not isinstance(shape, str) or shape not in SHAPES:
        hint = did_you_mean(shape, SHAPES) if isinstance(shape, str) else ""
        raise ModelError(
            f"`shape` must be one of {', '.join(repr(s) for s in SHAPES)} "
            f"(got {describe(shape)}).{hint}"
        )
    present = {name: value for name, value in given.items() if value is not None}
    wanted: tuple[str, ...] = SHAPES[shape]
    extra = sorted(set(present) - set(wanted))
    if extra:
        raise ModelError(
            f"`{extra[0]}` is not a dimension of {with_article(shape)}; "
            f"{with_article(shape)} takes "
            f"{' and '.join(f'`{name}`' for name in wanted)}"
        )
    missing = [name for name in wanted if name not in present]
    if missing:
        raise ModelError(
            f"{with_article(shape)} needs `{missing[0]}`; its dimensions are "
            f"{' and '.join(f'`{name}`' for name in wanted)}"
        )
    return Dimensions(shape, present)


def mass_properties(
    shape: str,
    density: float,
    *,
    size: Any = None,
    radius: Any = None,
    height: Any = None,
    vertices: Any = None,
    triangles: Any = None,
    check_intersections: bool = True,
) -> MassProperties:
    """Mass properties of a shape of uniform ``density`` [kg/m³], by its name.

    Args:
        shape: ``"box"``, ``"sphere"``, ``"cylinder"``, ``"capsule"``, ``"cone"``,
            ``"ellipsoid"`` or ``"mesh"``.
        density: Uniform density [kg/m³], positive.
        size: A box's full edge lengths, or an ellipsoid's semi-axes, ``(3,)`` [m].
        radius: A sphere's, cylinder's, capsule's or cone's radius [m].
        height: A cylinder's or cone's height, or a capsule's distance between its
            hemispheres' centres [m].
        vertices: A mesh's ``(V, 3)`` vertices [m].
        triangles: A mesh's ``(T, 3)`` triangles, counter-clockwise seen from outside.
        check_intersections: For a mesh, refuse one that crosses itself (see
            :func:`~visviva.rigid.mesh_mass_properties`).

    Returns:
        The shape's :class:`~visviva.rigid.MassProperties`, about its centre of mass in its
        axes (conventions in :mod:`visviva.rigid.primitives`).

    >>> mass_properties("cone", 1000.0, radius=0.5, height=2.0).center_of_mass.tolist()
    [0.0, 0.5, 0.0]
    """
    given = {
        "size": size,
        "radius": radius,
        "height": height,
        "vertices": vertices,
        "triangles": triangles,
    }
    dims = shape_dimensions(shape, given).values
    if shape == "box":
        return box_mass_properties(dims["size"], density)
    if shape == "sphere":
        return sphere_mass_properties(dims["radius"], density)
    if shape == "ellipsoid":
        return ellipsoid_mass_properties(dims["size"], density)
    if shape == "cylinder":
        return cylinder_mass_properties(dims["radius"], dims["height"], density)
    if shape == "capsule":
        return capsule_mass_properties(dims["radius"], dims["height"], density)
    if shape == "cone":
        return cone_mass_properties(dims["radius"], dims["height"], density)
    return mesh_mass_properties(
        dims["vertices"], dims["triangles"], density, check_intersections=check_intersections
    )
