"""One video frame of a recording's geometry: camera projection, lighting and layers.

:class:`FramePainter` turns the geometry of one recorded frame into an 8-bit RGB image with the
kernels of :mod:`visviva.viz.raster`. The camera is fixed for the whole clip, so the sky and
the ground (and each pixel's point on the ground, for shadows) are computed once. Each frame
then takes the steps:

1. project every point into the camera (pinhole model, view depth along the camera axis);
2. each layer casts its shadow onto the ground, along a light from above;
3. the ground is copied with those shadows, then faces, edges and spheres are drawn into the
   colour and depth buffers (spheres far to near, so their anti-aliased rims blend over what
   lies behind; only the points on no face are spheres, the others are the faces' vertices);
4. the time label ``t = 1.234 s`` is stamped in the top-left corner.

A geometry kind is a *layer*: an object with ``cast_shadows`` and ``draw``. Rigid bodies are
one (:class:`~visviva.viz.body_layer.BodyLayer`: each body's surface placed by its transform,
shaded like the faces, in its colour), the static colliders another
(:class:`~visviva.viz.body_layer.SceneryLayer`); the framing and the ground include them.

Points that are born and die (:mod:`visviva.simulation.lifetimes`): each frame draws and shadows
only its live points, at that frame's radius and colour; a trail goes back no further than the start
of its point's current life; the framing and the ground come from live points only. Edges and faces
are drawn between their points in every frame (emitters' particles have none).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..simulation.lifetimes import Appearance, life_starts
from ..simulation.recording import Geometry
from . import ground, raster
from .body_layer import BodyLayer, SceneryLayer
from .shading import LIGHT, MATERIAL, lit_sides
from .timescale import format_time

if TYPE_CHECKING:
    from .video import Camera

__all__ = ["FramePainter", "drawn_bounds"]

#: Colours, RGB in [0, 1]; points, edges and faces match the web viewer's.
SPHERE_COLOUR = (0x2F / 255, 0x6F / 255, 0xB3 / 255)
EDGE_COLOUR = (0x1D / 255, 0x27 / 255, 0x33 / 255)
FACE_COLOUR = (0xD9 / 255, 0x82 / 255, 0x2B / 255)
FACE_BACK_COLOUR = (0.62, 0.56, 0.50)
#: Sky at the zenith, sky at the horizon, the two ground tones.
ENVIRONMENT = ((0.50, 0.66, 0.86), (0.90, 0.92, 0.95), (0.80, 0.79, 0.76), (0.74, 0.73, 0.70))
#: Rays per pixel along each axis for the (once per clip) sky and ground.
BACKGROUND_SAMPLES = 3
#: Ground haze: the ground is fully hazed at a few times this multiple of the camera distance.
HAZE_DISTANCE = 3.0
#: Fraction of the light a shadow removes from the ground.
SHADOW_DARKNESS = 0.45
#: A sphere's shadow is a disc this many times its radius, fading as the sphere rises: it
#: blocks 1 / (1 + SHADOW_FADE · height / scene size) of the light.
SHADOW_SIZE, SHADOW_FADE = 1.1, 2.0
#: Light blocked by a triangle.
FACE_SHADOW_WEIGHT = 1.0
#: Most recorded positions along one trail (longer trails are drawn through a subsample).
TRAIL_SAMPLES = 400
#: Occlusion map: at most this many cells along its longer side, and at least a third of a
#: typical shadow's radius per cell (coarser cells blur the shadows into soft blobs and keep
#: the cost per sphere to a few cells).
SHADOW_MAP_CELLS, SHADOW_CELLS_PER_RADIUS = 512, 3.0
#: Smallest sphere drawn [px]; smaller ones are drawn this size, fainter.
MIN_SPHERE_PIXELS = 0.75
#: Relative depth bias that keeps lines in front of the faces they border.
LINE_DEPTH_BIAS = 2e-3
#: Near plane, as a fraction of the camera's distance to its target.
NEAR_FRACTION = 1e-3
#: A recording of at least this many points, all without a size (gravitating bodies: a
#: galaxy, a star cluster) and nothing else, is drawn as a star field: each point a small
#: spot of light added to a dark sky, so that a disk of stars shows its density and its arms
#: instead of a pancake of opaque spheres hiding each other.
STAR_FIELD_POINTS = 1000
#: A star's colour when the recording gives none.
STAR_COLOUR = (1.0, 0.9, 0.78)
#: A star's brightness: a few overlapping stars saturate, a lone one is clearly seen.
STAR_GAIN = 0.8
#: The star field's night sky, top and bottom of the picture.
NIGHT = ((0.02, 0.03, 0.07), (0.0, 0.0, 0.01))


def drawn_bounds(geometry: Geometry) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners [m] of the box holding everything drawn in every frame: each
    live point padded by its drawn radius in that frame, every rigid body's surface and the
    static colliders' (planes are not drawn). Dead
    points count for nothing; with nothing drawn at all, both corners are the origin."""
    look = Appearance.of(geometry)
    boxes = []
    if geometry.points.shape[1] and (look.alive is None or look.alive.any()):
        boxes.append(look.live_bounds(geometry.points))
    if geometry.bodies is not None and geometry.bodies.vertices.shape[0]:
        boxes.append(geometry.bodies.bounds())
    if geometry.scenery is not None and geometry.scenery.vertices.shape[0]:
        boxes.append(geometry.scenery.bounds())
    if not boxes:
        return np.zeros(3), np.zeros(3)
    return np.min([low for low, _ in boxes], axis=0), np.max([high for _, high in boxes], axis=0)


def _live_radii(look: Appearance) -> np.ndarray:
    """Drawn radii [m] of every live point in any frame, flat (sizes the shadow map)."""
    if look.alive is None:
        return look.radius.ravel()
    if look.varying_radius:
        return look.radius[look.alive]
    return look.radius[look.alive.any(axis=0)]


@dataclass
class _Frame:
    index: int  # recorded frame
    positions: np.ndarray  # (P, 3) world [m]
    view: np.ndarray  # (P, 3) camera coordinates: right, up, forward [m]
    screen: np.ndarray  # (P, 3) pixel x, y (NaN behind the camera) and view depth [m]
    live: np.ndarray | None  # indices of the live points, or None: all of them
    radius: np.ndarray  # (P,) drawn radius [m] in this frame
    colour: np.ndarray  # (P, 3) float32 sRGB in this frame


class _Stage:
    """The fixed camera, light and ground shared by every layer."""

    def __init__(
        self, camera: Camera, width: int, height: int, ground_y: float, scene: float
    ) -> None:
        self.width, self.height = width, height
        self.scene = scene  # size of the scene [m]: its bounding box's diagonal
        self.eye = np.array(camera.eye, dtype=np.float64)
        target = np.array(camera.target, dtype=np.float64)
        forward = (target - self.eye) / np.linalg.norm(target - self.eye)
        right = np.cross(forward, camera.up)
        right /= np.linalg.norm(right)
        self.basis = np.array([right, np.cross(right, forward), forward])
        self.focal = 0.5 * height / math.tan(math.radians(camera.field_of_view) / 2.0)
        self.distance = float(np.linalg.norm(target - self.eye))
        self.near = NEAR_FRACTION * self.distance
        self.ground_y = ground_y
        # Light, world up and Blinn half vector in sphere-kernel coordinates (z to the viewer).
        flip = np.array([1.0, 1.0, -1.0])
        towards_light = (self.basis @ LIGHT) * flip
        half = towards_light + np.array([0.0, 0.0, 1.0])
        self.light = np.array(
            [
                towards_light,
                (self.basis @ np.array([0.0, 1.0, 0.0])) * flip,
                half / np.linalg.norm(half),
            ]
        )

    def to_view(self, points: np.ndarray) -> np.ndarray:
        """Camera coordinates (right, up, forward) [m] of world points, shape ``(..., 3)``."""
        # Three broadcast products: a (P, 3) @ (3, 3) matmul goes through BLAS, whose threads
        # are slower than this on a busy two-core machine.
        relative = points - self.eye
        return (
            relative[..., 0:1] * self.basis[:, 0]
            + relative[..., 1:2] * self.basis[:, 1]
            + relative[..., 2:3] * self.basis[:, 2]
        )

    def to_screen(self, view: np.ndarray) -> np.ndarray:
        """Pixel x, y and view depth of camera coordinates; x, y are NaN behind the near plane."""
        depth = view[..., 2]
        ahead = depth > self.near
        scale = np.where(ahead, self.focal / np.where(ahead, depth, 1.0), np.nan)
        return np.stack(
            [
                0.5 * self.width + view[..., 0] * scale,
                0.5 * self.height - view[..., 1] * scale,
                depth,
            ],
            axis=-1,
        )

    def on_ground(self, points: np.ndarray) -> np.ndarray:
        """Where light through world points ``(..., 3)`` meets the ground: (x, z) [m]."""
        height = points[..., 1:2] - self.ground_y
        return points[..., [0, 2]] - height * (LIGHT[[0, 2]] / LIGHT[1])


class _ShadowMap:
    """Occlusion on a grid lying on the ground (see :mod:`visviva.viz.ground`)."""

    def __init__(self, stage: _Stage, low: np.ndarray, high: np.ndarray, radius: np.ndarray):
        signs = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
        corners = np.where(signs == 1, high, low)
        footprint = stage.on_ground(corners)
        start, end = footprint.min(axis=0), footprint.max(axis=0)
        extent = max(float((end - start).max()), 1e-9)
        typical = SHADOW_SIZE * float(np.median(radius)) if radius.size else 0.0
        self.cell = max(extent / SHADOW_MAP_CELLS, typical / SHADOW_CELLS_PER_RADIUS)
        # A margin of two cells beyond the largest shadow, so no shadow is cut at the edge.
        margin = SHADOW_SIZE * float(radius.max(initial=0.0)) + 2.0 * self.cell
        self.origin = start - margin
        cells = np.ceil((end - start + 2.0 * margin) / self.cell).astype(int) + 1
        self.occlusion = np.zeros((cells[1], cells[0]), dtype=np.float32)

    def soften(self) -> None:
        """Blur by one [1, 2, 1]/4 pass along each axis: shadow edges a cell or two wide."""
        grid = self.occlusion
        for axis in (0, 1):
            padded = np.pad(grid, [(1, 1) if a == axis else (0, 0) for a in (0, 1)], mode="edge")
            ahead = padded[2:] if axis == 0 else padded[:, 2:]
            behind = padded[:-2] if axis == 0 else padded[:, :-2]
            grid = 0.5 * grid + 0.25 * (ahead + behind)
        self.occlusion[...] = grid


class _Layer(Protocol):
    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        """Add to ``shadows`` what this layer blocks of the light."""

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        """Draw into the colour and depth buffers."""


class _Spheres:
    """The points on no face (:meth:`Geometry.off_faces`; ``points``, or ``None`` for all)."""

    def __init__(self, points: np.ndarray | None) -> None:
        self.points = points
        self.material = np.array(MATERIAL)

    def _shown(self, frame: _Frame) -> np.ndarray | None:
        """Indices of the spheres this frame draws (its live points of ``points``), or
        ``None``: every point."""
        if self.points is None or frame.live is None:
            return frame.live if self.points is None else self.points
        return np.intersect1d(frame.live, self.points, assume_unique=True)

    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        positions, radius = frame.positions, frame.radius
        shown = self._shown(frame)
        if shown is not None:
            positions, radius = positions[shown], radius[shown]
        height = positions[:, 1] - stage.ground_y
        weight = 1.0 / (1.0 + SHADOW_FADE * np.maximum(height, 0.0) / stage.scene)
        ground.splat_discs(
            shadows.occlusion,
            shadows.origin,
            shadows.cell,
            stage.on_ground(positions),
            SHADOW_SIZE * radius,
            weight,
        )

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        z, radius = frame.screen[:, 2], frame.radius
        with np.errstate(invalid="ignore", divide="ignore"):
            # Apparent radius of a sphere centred on the axis: f·r / sqrt(z² − r²).
            size = stage.focal * radius / np.sqrt(z * z - radius * radius)
        size[~(z - radius > stage.near) | np.isnan(frame.screen[:, 0])] = np.nan
        shown = self._shown(frame)
        if shown is None:
            order = np.argsort(-z, kind="stable")
        else:  # dead points and face vertices are not in the order
            order = shown[np.argsort(-z[shown], kind="stable")]
        raster.draw_spheres(
            color,
            depth,
            frame.screen,
            radius,
            size,
            order,
            frame.colour,
            stage.light,
            self.material,
            MIN_SPHERE_PIXELS,
        )


class _Edges:
    def __init__(self, edges: np.ndarray, height: int) -> None:
        self.edges = np.asarray(edges, dtype=np.int64)
        # At least 1 px wide; 1.5 px at 540 lines, growing with the picture.
        self.half_width = 0.5 * max(1.0, height / 360.0)
        self.colour = np.array(EDGE_COLOUR, dtype=np.float32)

    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        return None  # thin lines cast no visible shadow

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        start, end = frame.view[self.edges[:, 0]], frame.view[self.edges[:, 1]]
        segments = _screen_segments(stage, start, end)
        raster.draw_lines(color, depth, segments, self.half_width, self.colour, LINE_DEPTH_BIAS)


def _screen_segments(stage: _Stage, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Segments between view-space points ``(E, 3)``, clipped to the near plane, as screen
    ``x0, y0, z0, x1, y1, z1`` rows for :func:`raster.draw_lines`."""
    keep = (start[:, 2] > stage.near) | (end[:, 2] > stage.near)
    start, end = start[keep].copy(), end[keep].copy()
    # Clip to the near plane: move the end behind it to where the segment crosses it.
    for behind, other in ((start, end), (end, start)):
        cut = behind[:, 2] <= stage.near
        if cut.any():
            s = (stage.near * 1.0001 - behind[cut, 2]) / (other[cut, 2] - behind[cut, 2])
            behind[cut] += s[:, None] * (other[cut] - behind[cut])
    return np.concatenate([stage.to_screen(start), stage.to_screen(end)], axis=1)


class _Trails:
    """Each point's path over the last ``trail`` simulated seconds, a line of its colour; a
    point that is born draws from its birth on (a reused slot does not join two lives)."""

    def __init__(
        self, points: np.ndarray, times: np.ndarray, trail: float, look: Appearance, height: int
    ) -> None:
        self.points, self.times, self.trail = points, times, trail
        self.alive = look.alive
        self.starts = None if look.alive is None else life_starts(look.alive)
        self.half_width = 0.5 * max(1.0, height / 540.0)

    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        return None

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        k = frame.index
        first = int(np.searchsorted(self.times, self.times[k] - self.trail, side="left"))
        picks = np.unique(np.linspace(first, k, min(TRAIL_SAMPLES, k - first + 1)).round())
        if picks.size < 2:
            return
        path = self.points[picks.astype(np.int64)]  # (n, P, 3)
        view = stage.to_view(path.reshape(-1, 3)).reshape(path.shape)
        colour = 0.6 * frame.colour + 0.4  # paler than the point
        for p in range(path.shape[1]):
            start = 0
            if self.alive is not None and self.starts is not None:
                if not self.alive[k, p]:
                    continue
                start = int(np.searchsorted(picks, self.starts[k, p]))
                if picks.size - start < 2:
                    continue
            segments = _screen_segments(stage, view[start:-1, p], view[start + 1 :, p])
            raster.draw_lines(color, depth, segments, self.half_width, colour[p], LINE_DEPTH_BIAS)


class _Faces:
    def __init__(self, faces: np.ndarray) -> None:
        self.faces = np.asarray(faces, dtype=np.int64)
        self.front = np.array(FACE_COLOUR, dtype=np.float32)
        self.back = np.array(FACE_BACK_COLOUR, dtype=np.float32)

    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        corners = stage.on_ground(frame.positions[self.faces])  # (F, 3, 2)
        ground.splat_triangles(
            shadows.occlusion, shadows.origin, shadows.cell, corners, FACE_SHADOW_WEIGHT
        )

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        corner = frame.positions[self.faces]
        # Area-weighted vertex normals: the sum of the (unnormalised) normals of a vertex's faces.
        face_normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
        count = frame.positions.shape[0]
        flat = self.faces.ravel()
        normal = np.stack(
            [np.bincount(flat, np.repeat(face_normal[:, a], 3), count) for a in range(3)], axis=1
        )
        length = np.linalg.norm(normal, axis=1, keepdims=True)
        normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0.0)
        sides = lit_sides(normal)
        raster.draw_triangles(
            color,
            depth,
            frame.screen,
            self.faces,
            sides[0],
            sides[1],
            self.front,
            self.back,
            stage.near,
        )


def is_star_field(geometry: Geometry) -> bool:
    """Whether ``geometry`` is drawn as a star field: its style says so (``"night"``,
    ``"day"``), or by default it is many points without a size and nothing else (see
    :data:`STAR_FIELD_POINTS`)."""
    if geometry.style != "auto":
        return geometry.style == "night" and geometry.points.shape[1] > 0
    return (
        geometry.points.shape[1] >= STAR_FIELD_POINTS
        and geometry.radius is None
        and geometry.display_radius is None
        and geometry.bodies is None
        and geometry.scenery is None
        and geometry.walls is None
        and not (geometry.faces is not None and len(geometry.faces))
    )


class _StarField:
    """Every live point as a spot of light (:func:`~visviva.viz.raster.splat_points`)."""

    def __init__(self, height: int, width: int) -> None:
        self.light = np.zeros((height, width, 3), dtype=np.float32)

    def cast_shadows(self, stage: _Stage, frame: _Frame, shadows: _ShadowMap) -> None:
        pass  # light in the dark casts none

    def draw(self, stage: _Stage, frame: _Frame, color: np.ndarray, depth: np.ndarray) -> None:
        self.light.fill(0.0)
        order = np.arange(frame.positions.shape[0]) if frame.live is None else frame.live
        # Fewer points shine brighter (a fireworks shell of a few hundred sparks), up to 4×.
        gain = STAR_GAIN * float(np.clip(np.sqrt(2000 / max(order.size, 1)), 1.0, 4.0))
        raster.splat_points(self.light, frame.screen, order, frame.colour, gain)
        raster.expose(self.light, color)


class FramePainter:
    """Paints frames of one geometry, seen by one camera, at one size.

    Args:
        geometry: The recording's geometry (:meth:`Recording.geometry`), finite.
        size: ``(width, height)`` [px].
        camera: The view, fixed for every frame.
    """

    def __init__(
        self,
        geometry: Geometry,
        size: tuple[int, int],
        camera: Camera,
        times: np.ndarray,
        trail: float = 0.0,
        caption: str = "",
        labels: bool = False,
        follow: Callable[[int], Camera] | None = None,
    ) -> None:
        self.geometry = geometry
        self.labels = labels
        self.follow = follow  # the camera of each recorded frame, for a camera that moves
        self.caption = caption
        self.width, self.height = size
        look = Appearance.of(geometry)
        self.look = look
        self.stars = is_star_field(geometry)
        self.default_colour = np.tile(
            np.array(STAR_COLOUR if self.stars else SPHERE_COLOUR, dtype=np.float32),
            (geometry.points.shape[1], 1),
        )
        low, high = drawn_bounds(geometry)
        scene = max(float(np.linalg.norm(high - low)), 1e-9)
        self.scene, self.ground_y = scene, min(0.0, float(low[1]))
        stage = _Stage(camera, self.width, self.height, self.ground_y, scene)
        self.stage = stage
        self.layers: list[_Layer] = []
        if geometry.bodies is not None:
            self.layers.append(BodyLayer(geometry.bodies))
        if geometry.scenery is not None:
            self.layers.append(SceneryLayer(geometry.scenery))
        if geometry.faces is not None and len(geometry.faces):
            self.layers.append(_Faces(geometry.faces))
        if geometry.edges is not None and len(geometry.edges):
            self.layers.append(_Edges(geometry.edges, self.height))
        if trail > 0.0:
            self.layers.append(_Trails(geometry.points, times, trail, look, self.height))
        spheres = geometry.off_faces()
        if self.stars:
            self.layers.append(_StarField(self.height, self.width))
        elif spheres.size:
            whole = spheres.size == geometry.points.shape[1]
            self.layers.append(_Spheres(None if whole else spheres))
        self.span = float(times[-1] - times[0]) if times.size else 0.0
        shape = (self.height, self.width)
        self.background = np.empty((*shape, 3), dtype=np.float32)
        self.background_depth = np.full(shape, np.inf, dtype=np.float32)
        self.ground_x, self.ground_z = np.empty(shape), np.empty(shape)
        self.color = np.empty_like(self.background)
        self.depth = np.empty_like(self.background_depth)
        self._label = _Label(self.height)
        if self.stars:  # a night sky, no ground and no shadows
            top, bottom = np.array(NIGHT, dtype=np.float32)
            rows = np.linspace(0.0, 1.0, self.height, dtype=np.float32)[:, None, None]
            self.background[:] = top + rows * (bottom - top)
            return
        self._paint_background()
        self.shadows = _ShadowMap(stage, low, high, _live_radii(look))

    def _paint_background(self) -> None:
        """Sky and ground as the stage's camera sees them (once, or every frame it moves)."""
        stage = self.stage
        ground.paint_background(
            self.background,
            self.background_depth,
            self.ground_x,
            self.ground_z,
            stage.eye,
            stage.basis,
            stage.focal,
            stage.ground_y,
            _checker_cell(self.scene),
            HAZE_DISTANCE * (stage.distance + self.scene),
            np.array(ENVIRONMENT),
            BACKGROUND_SAMPLES,
        )

    def label(self, time: float) -> str:
        """The text in the corner: the time in the unit that reads best for the recording's
        span, a warning when points are drawn at display radii, and the caption (a colour
        scale)."""
        text = format_time(time, self.span)
        text = text if self.geometry.to_scale else f"{text}, sizes not to scale"
        return f"{text}, {self.caption}" if self.caption else text

    def paint(self, index: int, time: float) -> np.ndarray:
        """Image of recorded frame ``index`` labelled with ``time`` [s]: uint8, ``(H, W, 3)``."""
        if self.follow is not None:
            camera = self.follow(index)
            self.stage = _Stage(camera, self.width, self.height, self.ground_y, self.scene)
            if not self.stars:
                self._paint_background()
        positions = np.asarray(self.geometry.points[index], dtype=np.float64)
        view = self.stage.to_view(positions)
        look = self.look
        alive = None if look.alive is None else np.flatnonzero(look.alive[index])
        colour = look.color_at(index)
        frame = _Frame(
            index,
            positions,
            view,
            self.stage.to_screen(view),
            alive,
            look.radius_at(index),
            self.default_colour if colour is None else colour,
        )
        if self.stars:
            self.color[:] = self.background
            self.depth[:] = self.background_depth
        else:
            self._ground(frame)
        for layer in self.layers:
            layer.draw(self.stage, frame, self.color, self.depth)
        if self.labels and self.geometry.bodies is not None:
            self._name_bodies(index)
        self._label.stamp(self.color, self.label(time))
        image = np.empty((self.height, self.width, 3), dtype=np.uint8)
        raster.to_bytes(self.color, image)
        return image

    def _name_bodies(self, index: int) -> None:
        """Each rigid body's name just above the top of its surface in recorded frame
        ``index`` (a body behind the camera goes unnamed)."""
        bodies = self.geometry.bodies
        assert bodies is not None
        surface = bodies.world_vertices(index)
        for b, name in enumerate(bodies.names):
            own = surface[bodies.vertex_start[b] : bodies.vertex_start[b + 1]]
            if not own.shape[0]:
                continue
            top = np.array([own[:, 0].mean(), own[:, 1].max(), own[:, 2].mean()])
            x, y, _depth = self.stage.to_screen(self.stage.to_view(top))
            if np.isfinite(x) and np.isfinite(y):
                self._label.stamp(self.color, name, above=(float(x), float(y)))

    def _ground(self, frame: _Frame) -> None:
        """Start the frame from the background: the ground darkened by this frame's shadows."""
        shadows = self.shadows
        shadows.occlusion.fill(0.0)
        for layer in self.layers:
            layer.cast_shadows(self.stage, frame, shadows)
        shadows.soften()
        ground.compose_ground(
            self.color,
            self.depth,
            self.background,
            self.background_depth,
            self.ground_x,
            self.ground_z,
            shadows.occlusion,
            shadows.origin,
            shadows.cell,
            SHADOW_DARKNESS,
        )


def _checker_cell(scene: float) -> float:
    """Checker square [m]: the 1-2-5 step just below a quarter of the scene's size."""
    step = 10.0 ** math.floor(math.log10(scene / 4.0))
    for factor in (5.0, 2.0):
        if factor * step <= scene / 4.0:
            return factor * step
    return step


class _Label:
    """White text on a translucent dark box in the top-left corner (Pillow's built-in font)."""

    def __init__(self, height: int) -> None:
        from PIL import ImageFont

        self.pixels = max(8, round(height / 24))
        self.margin = max(2, round(height / 60))
        self.font: Any = ImageFont.load_default(size=self.pixels)

    def stamp(self, color: np.ndarray, text: str, above: tuple[float, float] | None = None) -> None:
        """Write ``text`` in the top-left corner, or centred just above the pixel ``above``
        (x, y), kept inside the picture."""
        from PIL import Image, ImageDraw

        _left, top, right, bottom = self.font.getbbox(text)
        pad = max(1, self.pixels // 4)
        mask = Image.new("L", (right + 2 * pad, bottom - top + 2 * pad), 0)
        ImageDraw.Draw(mask).text((pad, pad - top), text, fill=255, font=self.font)
        alpha = np.asarray(mask, dtype=np.float32)[..., None] / 255.0
        x, y = self.margin, self.margin
        if above is not None:
            high, wide = color.shape[0] - alpha.shape[0], color.shape[1] - alpha.shape[1]
            x = int(min(max(above[0] - alpha.shape[1] / 2, 0), max(wide, 0)))
            y = int(min(max(above[1] - alpha.shape[0] - self.margin, 0), max(high, 0)))
        region = color[y : y + alpha.shape[0], x : x + alpha.shape[1]]
        alpha = alpha[: region.shape[0], : region.shape[1]]
        region *= 0.45
        region += 0.55 * np.array([0.10, 0.12, 0.15], dtype=np.float32)
        region += alpha * (1.0 - region)
