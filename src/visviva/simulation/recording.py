"""Recordings in memory: the frames a run keeps, with units and the run's attributes.

A :class:`Recording` holds the times of the recorded frames and one array per recorded field
(``y``, or ``q`` and ``v``, a scene's ``particle_position``, plus derived series such as
``energy``), each with its unit, the arrays that do not change over the run (``static``), and
the attributes that make the run reproducible (method, step, substeps, library version, work).
A field that is a part of the state has the part's name (``particle_position``,
``particle_velocity``, ``particle_alive``, ``generalized_position``, ``body_orientation``; see
:mod:`.frames`). Files hold the same content (:mod:`visviva.io.recording`:
``vv.io.save_recording`` and ``vv.io.load_recording``, which reads files written with the
names of format 1 too).

Drawable geometry (what the video, the web viewer and the exporters show) follows one
convention, read back by :meth:`Recording.geometry`. The drawn points are the ``N`` particles,
then the ``S`` points of named systems' pictures (a pendulum's pivot and bob), ``P = N + S``:

    fields/particle_position float64 (frames, N, 3) [m]: particle positions, world frame, Y up
    fields/system_points    float64 (frames, S, 3) [m]: the systems' drawn points
    static/particle_radius  float64 (N,) [m]: particle radii (optional), with
                            static/system_radius (S,) when there are both
    static/particle_color   float64 (N, 3): sRGB colour of each particle, in [0, 1]
                            (optional), with static/system_color (S, 3) when there are both
    static/edges            int64 (E, 2): pairs of point indices (of the P drawn points) drawn
                            as lines (optional)
    static/faces            int64 (F, 3): triangles of point indices, counter-clockwise seen
                            from outside (optional); their points are drawn as the surface's
                            vertices, not as spheres (:meth:`Geometry.off_faces`)
    static/display_radius   float64 (P,) [m]: the radius to draw instead of the physical one,
                            where true sizes would be invisible (planets at the scale of their
                            orbits); outputs then say "sizes not to scale" (optional)

Particles that are born and die (those of emitters) are recorded with a fixed capacity ``N``
and, per frame:

    fields/particle_alive   bool (frames, N): which particles exist in each frame; the others
                            are not drawn (optional: all exist; systems' points always do)
    fields/particle_radius  float64 (frames, N) [m]: radii that change over time (instead of
                            static/particle_radius)
    fields/particle_color   float32 (frames, N, 3): colours that change over time, sRGB in
                            [0, 1] (instead of static/particle_color)

The velocities of the drawn points, where recorded, colour them by speed
(:meth:`Recording.drawn_velocity`): ``fields/particle_velocity`` (frames, N, 3) [m/s], then
``fields/system_velocity`` (frames, S, 3) [m/s].

Rigid bodies keep their surfaces once and a transform per frame (the full list is in
:mod:`visviva.simulation.body_geometry`; a recording may hold bodies without points):

    fields/body_origin      float64 (frames, B, 3) [m]: each body's own origin, world frame
    fields/body_orientation float64 (frames, B, 4): unit quaternions (w, x, y, z), body to world
    static/body_vertices    float64 (V, 3) [m]: the bodies' surfaces in their own axes, with
                            body_triangles (T, 3), body_vertex_start and body_triangle_start
                            (B + 1,), body_color (B, 3), body_center (B, 3) [m]

Static colliders (spheres, boxes, meshes; not planes) keep their surfaces once, in the world
frame (:mod:`visviva.simulation.scenery`; a recording without them has none of these names):

    static/scenery_vertices float64 (V, 3) [m], with scenery_triangles (T, 3),
                            scenery_vertex_start and scenery_triangle_start (C + 1,),
                            scenery_color (C, 3)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ModelError
from .body_geometry import BodyGeometry, read_bodies
from .scenery import Scenery, Walls, read_scenery, read_walls

__all__ = ["Geometry", "Recording"]

#: The fields of the drawn points, in drawing order: particles, then the systems' points.
_DRAWN = ("particle_position", "system_points")

#: Default point radius, as a fraction of the scene's bounding-box diagonal.
_RADIUS_FRACTION = 0.01
#: With edges or faces, at most this fraction of the median edge length.
_RADIUS_FRACTION_OF_EDGE = 0.1
#: Radius [m] for a scene with no extent (one point that never moves).
_RADIUS_OF_A_POINT_SCENE = 0.05


@dataclass(frozen=True)
class Geometry:
    """What a recording shows: moving points, optionally with radii, colours, edges, triangles,
    and points that are born and die.

    Attributes:
        points: Positions [m], shape ``(frames, P, 3)``, world frame, Y up.
        radius: Radii [m], shape ``(P,)``, or ``(frames, P)`` when they change over time, or
            ``None`` (draw as small dots).
        edges: Point-index pairs drawn as lines, shape ``(E, 2)``, or ``None``.
        faces: Point-index triangles, shape ``(F, 3)``, or ``None``.
        color: sRGB colour of each point in [0, 1], shape ``(P, 3)``, or ``(frames, P, 3)``
            when it changes over time, or ``None`` (the outputs' default colour).
        display_radius: Radii [m] drawn instead of ``radius`` where true sizes would be
            invisible, shape ``(P,)``, or ``None`` (drawn to scale).
        alive: Which points exist in each frame, shape ``(frames, P)`` bool, or ``None`` (all
            of them, always). Outputs draw only the live points of each frame.
        bodies: The rigid bodies' surfaces and transforms, or ``None``.
        scenery: The static colliders' surfaces, or ``None``.
        walls: The planes other than floors, or ``None``.
        style: How outputs draw the points: ``"auto"`` (by what they are), ``"day"`` (shaded
            spheres on a ground) or ``"night"`` (spots of light on a night sky: fireworks, a
            galaxy); a recording's attribute ``playback_style``.
    """

    points: np.ndarray
    radius: np.ndarray | None = None
    edges: np.ndarray | None = None
    faces: np.ndarray | None = None
    color: np.ndarray | None = None
    display_radius: np.ndarray | None = None
    alive: np.ndarray | None = None
    bodies: BodyGeometry | None = None
    scenery: Scenery | None = None
    walls: Walls | None = None
    style: str = "auto"

    @property
    def to_scale(self) -> bool:
        """False if the points are drawn larger (or smaller) than they are."""
        return self.display_radius is None

    @property
    def frames(self) -> int:
        """Number of frames."""
        return self.points.shape[0]

    def default_radius(self) -> float:
        """Radius [m] drawn for points when the recording gives none.

        1 % of the diagonal of :meth:`bounds`; with edges or faces, where points are only the
        vertices of the shape, at most a tenth of the median edge length in the first frame (so
        neighbouring dots never touch); 0.05 m for a scene with no extent.
        """
        low, high = self.bounds()
        diagonal = float(np.linalg.norm(high - low))
        if not diagonal > 0.0:
            return _RADIUS_OF_A_POINT_SCENE
        radius = _RADIUS_FRACTION * diagonal
        pairs = [] if self.edges is None else [self.edges]
        if self.faces is not None:
            pairs.extend(self.faces[:, [i, (i + 1) % 3]] for i in range(3))
        if pairs and self.frames:
            ends = self.points[0][np.concatenate(pairs)]
            lengths = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
            lengths = lengths[lengths > 0.0]
            if lengths.size:
                radius = min(radius, _RADIUS_FRACTION_OF_EDGE * float(np.median(lengths)))
        return radius

    def drawn_radius(self) -> np.ndarray:
        """Radius [m] of each point as drawn, shape ``(P,)`` (``(frames, P)`` for radii that
        change over time): the display radius, else the recorded one, else
        :meth:`default_radius` (the same in the video, the viewer and every export)."""
        if self.display_radius is not None:
            return np.asarray(self.display_radius, dtype=np.float64)
        if self.radius is not None:
            return np.asarray(self.radius, dtype=np.float64)
        return np.full(self.points.shape[1], self.default_radius())

    def off_faces(self) -> np.ndarray:
        """Indices of the points on no face, int64 ``(n,)``: the points every output draws as
        spheres (or a point cloud). A point on a face is a vertex of the surface, drawn by it:
        a cloth of 64 × 64 points 1.6 cm apart would otherwise hide under spheres of its 1 cm
        particle radius."""
        count = self.points.shape[1]
        if self.faces is None:
            return np.arange(count, dtype=np.int64)
        on_face = np.zeros(count, dtype=bool)
        on_face[np.asarray(self.faces, dtype=np.int64).ravel()] = True
        return np.flatnonzero(~on_face).astype(np.int64)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners [m] of the box holding every live point of every frame
        (radii included)."""
        pad = 0.0 if self.radius is None or self.radius.size == 0 else float(self.radius.max())
        flat = self.points.reshape(-1, 3)
        if self.alive is not None:
            flat = flat[self.alive.reshape(-1)]
        if flat.size == 0:
            return np.zeros(3), np.zeros(3)
        return flat.min(axis=0) - pad, flat.max(axis=0) + pad


class Recording:
    """Frames of one run: times, named state arrays with units, and attributes.

    Args:
        time: Frame times [s], shape ``(frames,)``.
        fields: Arrays with a leading frame axis, e.g. ``{"q": (frames, n), "v": ...}``.
        units: Unit of each field or static array (``""`` for dimensionless or unknown).
        attrs: Run attributes: strings, numbers, booleans, or JSON-serialisable values.
        static: Arrays that do not change over the run (radii, edges, faces).

    Example:
        >>> import numpy as np
        >>> rec = Recording(np.array([0.0, 0.5]), {"q": np.zeros((2, 3))}, units={"q": "m"})
        >>> rec.frames, rec["q"].shape, rec.units["q"]
        (2, (2, 3), 'm')
    """

    def __init__(
        self,
        time: np.ndarray,
        fields: Mapping[str, np.ndarray],
        *,
        units: Mapping[str, str] | None = None,
        attrs: Mapping[str, Any] | None = None,
        static: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        self.time = np.asarray(time, dtype=np.float64)
        self.fields = {name: np.asarray(value) for name, value in fields.items()}
        for name, value in self.fields.items():
            if value.shape[:1] != self.time.shape:
                raise ModelError(
                    f"field {name!r} has {value.shape[:1]} frames but time has {self.time.shape}"
                )
        self.static = {name: np.asarray(value) for name, value in (static or {}).items()}
        self.units = {name: "" for name in (*self.fields, *self.static)} | dict(units or {})
        self.attrs: dict[str, Any] = dict(attrs or {})

    @property
    def frames(self) -> int:
        """Number of recorded frames."""
        return self.time.shape[0]

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.fields[name]
        except KeyError:
            raise KeyError(
                f"recording has no field {name!r}; fields: {', '.join(self.fields)}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self.fields

    def geometry(self) -> Geometry:
        """The drawable geometry (see the module docstring), checked for consistent shapes:
        the particles, then the systems' points, with their radii, colours and liveness.

        A recording of rigid bodies alone has ``points`` of shape ``(frames, 0, 3)``.

        Raises:
            ModelError: If the recording has neither drawn points (``particle_position``,
                ``system_points``) nor rigid bodies, or its arrays do not fit them.
        """
        bodies = read_bodies(self.fields, self.static, self.attrs)
        if not any(name in self.fields for name in _DRAWN) and bodies is None:
            raise ModelError(
                "this recording has no geometry to show (no `particle_position` or "
                "`system_points` field, no bodies): it comes from a run of an abstract "
                "system; record a scene with particles or bodies instead"
            )
        groups = []
        for name, size in zip(_DRAWN, ("N", "S"), strict=True):
            group = self.fields.get(name, np.zeros((self.frames, 0, 3)))
            if group.ndim != 3 or group.shape[2] != 3:
                raise ModelError(
                    f"`{name}` must have shape (frames, {size}, 3) (got {group.shape})"
                )
            groups.append(group)
        particles, systems = groups
        n, extra = particles.shape[1], systems.shape[1]
        points = np.concatenate(groups, axis=1) if n and extra else particles if n else systems
        frames, count = points.shape[:2]
        radius = self._per_point("radius", n, extra, ())
        color = self._per_point("color", n, extra, (3,))
        if color is not None and not (np.all(color >= 0.0) and np.all(color <= 1.0)):
            raise ModelError("`particle_color` and `system_color` must hold sRGB values in [0, 1]")
        display_radius = self.static.get("display_radius")
        if display_radius is not None and display_radius.shape != (count,):
            raise ModelError(
                f"`display_radius` must have shape {(count,)} (got {display_radius.shape})"
            )
        alive = self.fields.get("particle_alive")
        if alive is not None:
            if alive.shape != (frames, n) or alive.dtype != np.bool_:
                raise ModelError(
                    f"`particle_alive` must be a boolean array of shape {(frames, n)} (got "
                    f"{alive.dtype} {alive.shape})"
                )
            if extra:  # the systems' points always exist
                alive = np.concatenate([alive, np.ones((frames, extra), dtype=bool)], axis=1)
        topology: dict[str, np.ndarray | None] = {}
        for name, width in (("edges", 2), ("faces", 3)):
            value = self.static.get(name)
            if value is not None:
                if value.ndim != 2 or value.shape[1] != width:
                    raise ModelError(f"`{name}` must have shape (n, {width}) (got {value.shape})")
                if value.size and (value.min() < 0 or value.max() >= count):
                    raise ModelError(f"`{name}` refers to points outside 0..{count - 1}")
            topology[name] = value
        scenery = read_scenery(self.static, self.attrs)
        return Geometry(
            points,
            walls=read_walls(self.static),
            style=_style(self.attrs),
            radius=radius,
            color=color,
            display_radius=display_radius,
            alive=alive,
            bodies=bodies,
            scenery=scenery,
            **topology,
        )

    def _per_point(self, quantity: str, n: int, extra: int, tail: tuple[int, ...]) -> Any:
        """The drawn points' ``quantity`` (``radius`` or ``color``): the particles'
        (``particle_<quantity>``, static ``(N, *tail)`` or per frame ``(frames, N, *tail)``),
        then the systems' points' (static ``system_<quantity>``, ``(S, *tail)``); ``None`` if
        neither is recorded."""
        own, theirs = f"particle_{quantity}", f"system_{quantity}"
        particles = self.fields.get(own) if own in self.fields else self.static.get(own)
        systems = self.static.get(theirs)
        varying = own in self.fields
        for name, value, shapes in (
            (own, particles, [(self.frames, n, *tail)] if varying else [(n, *tail)]),
            (theirs, systems, [(extra, *tail)]),
        ):
            if value is not None and value.shape not in shapes:
                raise ModelError(f"`{name}` must have shape {shapes[0]} (got {value.shape})")
        parts = [(particles, own, n), (systems, theirs, extra)]
        given = [name for value, name, size in parts if size and value is not None]
        if not given:
            return None
        missing = [name for value, name, size in parts if size and value is None]
        if missing:
            raise ModelError(
                f"`{given[0]}` needs `{missing[0]}` beside it: every drawn point has a "
                f"{quantity} or none does"
            )
        if particles is None or systems is None:  # one group: the other holds no point
            return particles if n else systems
        if varying:
            systems = np.broadcast_to(systems, (self.frames, *systems.shape)).astype(
                particles.dtype
            )
        return np.concatenate([particles, systems], axis=1 if varying else 0)

    def drawn_velocity(self) -> np.ndarray | None:
        """Velocities [m/s] of the first ``k`` drawn points, ``(frames, k, 3)``: the
        particles' (``particle_velocity``), then the systems' points' (``system_velocity``)
        where recorded; ``None`` if the first drawn points have none."""
        parts = []
        if "particle_position" in self.fields and self.fields["particle_position"].shape[1]:
            if "particle_velocity" not in self.fields:
                return None
            parts.append(self.fields["particle_velocity"])
        if "system_velocity" in self.fields:
            parts.append(self.fields["system_velocity"])
        if not parts:
            return None
        return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1)

    def __repr__(self) -> str:
        shapes = ", ".join(f"{k}{tuple(v.shape)}" for k, v in self.fields.items())
        return f"Recording({self.frames} frames: {shapes})"


#: How outputs may draw a recording's points (:attr:`Geometry.style`).
STYLES = ("auto", "day", "night")


def _style(attrs: Mapping[str, Any]) -> str:
    style = str(attrs.get("playback_style", "auto"))
    if style not in STYLES:
        raise ModelError(
            f"the recording's playback_style {style!r} is not one of {', '.join(STYLES)}"
        )
    return style
