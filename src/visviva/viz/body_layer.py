"""The rigid bodies of a video frame: each body's surface, turned and moved by its transform.

A layer of :class:`visviva.viz.frame.FramePainter`. A body's surface is recorded once, in its
own axes, with a transform per frame (:mod:`visviva.simulation.body_geometry`); each frame
places its vertices (``origin + R(q) v``) and turns its vertex normals (``R(q) n``, computed
once: a rigid surface keeps its normals), then draws its triangles as the faces of cloth are
drawn (Gouraud shading, ambient plus diffuse, :mod:`visviva.viz.shading`), in the body's
colour. Only the triangles that face the light cast a shadow: over a closed surface they
cover its whole shadow once, at half the cost of splatting every triangle.

The static colliders (:mod:`visviva.simulation.scenery`) are drawn the same way, as bodies
that never move (:class:`SceneryLayer`): their vertices are placed once for the whole clip.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..simulation.body_geometry import BodyGeometry
from ..simulation.scenery import Scenery
from . import ground, raster
from .shading import LIGHT, lit_sides

if TYPE_CHECKING:
    from .frame import _Frame, _ShadowMap, _Stage

__all__ = ["BodyLayer", "SceneryLayer"]

#: Light blocked by a body's triangle.
BODY_SHADOW_WEIGHT = 1.0
#: The inside of a body (seen only through a cut of the near plane): its colour, darker.
INSIDE_SHADE = 0.5


class BodyLayer:
    """Draws and shadows the rigid bodies of a geometry.

    Args:
        bodies: The recording's bodies (finite transforms).
    """

    def __init__(self, bodies: BodyGeometry) -> None:
        self.bodies = bodies
        self.front = np.ascontiguousarray(bodies.color, dtype=np.float32)
        self.back = (INSIDE_SHADE * self.front).astype(np.float32)
        self._placed: tuple[int, np.ndarray, np.ndarray] | None = None

    def _place(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """World vertices [m] and unit normals of recorded frame ``index``, each ``(V, 3)``;
        kept for the frame's two passes (shadows, then drawing)."""
        if self._placed is None or self._placed[0] != index:
            bodies = self.bodies
            world = bodies.world_vertices(index)
            still = np.zeros_like(bodies.position[index])
            normal = bodies.transform(still, bodies.orientation[index], bodies.normals)
            self._placed = (index, world, normal)
        return self._placed[1], self._placed[2]

    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        world, _ = self._place(frame.index)
        triangles = self.bodies.triangles
        corner = world[triangles]
        facing = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0]) @ LIGHT > 0.0
        ground.splat_triangles(
            shadows.occlusion,
            shadows.origin,
            shadows.cell,
            stage.on_ground(corner[facing]),
            BODY_SHADOW_WEIGHT,
        )

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        world, normal = self._place(frame.index)
        screen = stage.to_screen(stage.to_view(world))
        front, back = lit_sides(normal)
        bodies = self.bodies
        for b in range(bodies.count):
            rows = slice(bodies.triangle_start[b], bodies.triangle_start[b + 1])
            raster.draw_triangles(
                color,
                depth,
                screen,
                bodies.triangles[rows],
                front,
                back,
                self.front[b],
                self.back[b],
                stage.near,
            )


class SceneryLayer(BodyLayer):
    """Draws and shadows the static colliders: bodies at rest, placed once for every frame.

    Args:
        scenery: The recording's scenery.
    """

    def __init__(self, scenery: Scenery) -> None:
        super().__init__(scenery.as_bodies())

    def _place(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        return super()._place(0)
