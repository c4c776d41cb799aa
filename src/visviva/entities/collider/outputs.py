"""The scene's static colliders as drawable triangles, recorded once ("scenery").

Colliders do not move, so a recording keeps their surfaces once, in the world frame, and no
per-frame field (:mod:`visviva.simulation.scenery` reads them back; the collider kind's build
records them):

    static/scenery_vertices        float64 (V, 3) [m]: the surfaces, collider after collider
    static/scenery_triangles       int64 (T, 3): counter-clockwise seen from outside, indices
                                   into scenery_vertices; a collider's use its own vertices
    static/scenery_vertex_start    int64 (C + 1,): collider c's vertex rows
    static/scenery_triangle_start  int64 (C + 1,): and its triangle rows
    static/scenery_color           float64 (C, 3): sRGB in [0, 1]
    attrs["scenery_names"]         list of C strings

Drawn: boxes (their six faces, four vertices each, so the faces are flat with sharp edges:
the 12 triangles over the box's 8 corners), spheres (the rigid bodies' tessellation,
:func:`visviva.rigid.surfaces.unit_sphere`: 32 segments around, 16 from pole to pole) and
meshes (their own vertices and triangles). Planes have no finite surface: a floor is the
outputs' own ground, and any other plane (a wall) is kept as a point and a normal
(:func:`wall_fields`), drawn as much of it as the picture needs.

Why fields of their own rather than static rigid bodies with a constant transform: every
consumer of ``body_*`` counts the bodies, names them, plots their momenta or animates their
transforms (the USD and glTF exports write a transform per frame); a collider is none of
those. The layout is the bodies' (vertices with start rows) so that the outputs draw scenery
with the same code as a body's surface.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...geometry.packing import packed_surfaces
from .schema import DEFAULT_SCENERY_COLOR, Collider
from .shapes import collider_shape, collider_surface

__all__ = ["scenery_attrs", "scenery_fields", "wall_fields"]

#: A plane whose outward normal is this close to +Y is a floor: the outputs' ground shows it.
FLOOR = 0.999


def _drawn(
    entries: Sequence[tuple[str, Collider]],
) -> list[tuple[str, Collider, tuple[np.ndarray, np.ndarray]]]:
    """The drawable colliders: (where, entity, surface), in the scene's order."""
    drawn = []
    for where, entity in entries:
        if entity.shape == "plane":
            continue
        if entity.shape == "mesh":  # checked when the model was built; no tree needed here
            surface = (
                np.asarray(entity.vertices, dtype=np.float64),
                np.asarray(entity.triangles, dtype=np.int64),
            )
        else:
            surface = collider_surface(collider_shape(entity, where))
        if surface is not None:
            drawn.append((where, entity, surface))
    return drawn


def scenery_fields(entries: Sequence[tuple[str, Collider]]) -> dict[str, np.ndarray]:
    """The static arrays of the drawable colliders among ``entries`` (see the module
    docstring); empty without any (no field is recorded)."""
    drawn = _drawn(entries)
    if not drawn:
        return {}
    surfaces = [surface for _, _, surface in drawn]
    return packed_surfaces(surfaces, "scenery") | {
        "scenery_color": np.array(
            [e.color or DEFAULT_SCENERY_COLOR for _, e, _ in drawn], dtype=np.float64
        ),
    }


def wall_fields(entries: Sequence[tuple[str, Collider]]) -> dict[str, np.ndarray]:
    """The planes that are not floors (a box's walls, a ceiling, a slope) as a point, an
    outward unit normal and a colour each: ``wall_point``, ``wall_normal``, ``wall_color``
    ``(W, 3)``. Unbounded, they are drawn as the part of them within what a video or viewer
    shows (:mod:`visviva.viz.walls`); empty without any."""
    walls = [
        e
        for _, e in entries
        if e.shape == "plane"
        and e.point is not None
        and e.normal is not None
        and np.asarray(e.normal, float)[1] / np.linalg.norm(e.normal) < FLOOR
    ]
    if not walls:
        return {}
    normal = np.array([e.normal for e in walls], dtype=np.float64)
    return {
        "wall_point": np.array([e.point for e in walls], dtype=np.float64),
        "wall_normal": normal / np.linalg.norm(normal, axis=1, keepdims=True),
        "wall_color": np.array([e.color or DEFAULT_SCENERY_COLOR for e in walls], np.float64),
    }


def scenery_attrs(entries: Sequence[tuple[str, Collider]]) -> dict[str, list[str]]:
    """The drawable colliders' names (``collider_<entity index>`` for one without a name)."""
    drawn = _drawn(entries)
    if not drawn:
        return {}
    return {
        "scenery_names": [
            e.name or f"collider_{where.removeprefix('entities[').removesuffix(']')}"
            for where, e, _ in drawn
        ]
    }
