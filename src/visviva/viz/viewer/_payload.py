"""The animation data the web viewer embeds: drawable geometry as compact, typed layers.

The payload is one JSON object. Large arrays travel as base64 text of little-endian binary
(``float32`` radii, ``uint32`` indices, ``float64`` frame times) that the page decodes straight
into ``Float32Array`` / ``Uint32Array`` / ``Float64Array`` views, which is ~4× smaller than
JSON numbers and needs no parsing per value.

Point positions, most of the page, are quantized: each coordinate becomes a 16-bit integer
``q`` on a grid spanning the points' box, ``x = origin + q·step`` with ``step = extent/65535``
per axis, so a position is off by at most half a step (the galaxy demo, 20 m across: 0.15 mm;
drawn radii are far larger). The integers are stored as differences from the previous frame
(points move little between frames), their low and high bytes in two separate planes, and
compressed with zlib (deflate), which the page inflates with the browser's own
``DecompressionStream``. The galaxy demo's 6002 points × 301 frames take 8.5 MB instead of
29 MB of float32 base64.

Points that are born and die (:mod:`visviva.simulation.lifetimes`) add, only when the recording has
them: ``alive``, which points exist in each frame, as bits (one per point per frame, XOR with
the previous frame, so a frame costs only its births and deaths before zlib); ``births``, with a
trail, the bits of points that start a new life in a frame (a reused slot's trail starts
afresh); ``radii``, radii that change, as 16-bit levels of ``step`` [m] in frame differences
like the positions; ``frame_colors``, colours that change, as 8-bit sRGB in frame differences.
Dead points are stored where they were last alive (before their first life, where they are
born), so they neither stretch the position grid nor cost differences; the page does not draw
them.

Each kind of geometry is one *layer* with its own encoder here and its own builder in
``viewer.js`` (``LAYERS``): ``points`` (moving spheres; absent when the recording has rigid
bodies alone), ``edges`` (lines between points), ``faces`` (triangles between points),
``bodies`` and ``scenery``. With faces, the points layer's ``spheres`` lists the points drawn
as spheres (``uint32``): those on no face (:meth:`Geometry.off_faces`).

The ``bodies`` layer holds each rigid body's surface once, in its own axes (``vertices``
float32 ``(V, 3)`` [m], ``triangles`` uint32 ``(T, 3)`` numbered among each body's own
vertices, ``vertex_start`` and ``triangle_start`` uint32 ``(B + 1,)``, 8-bit sRGB ``colors``,
``names``) and its transform at every shown frame: ``positions`` float32 ``(frames, B, 3)``
[m], the body's own origin, and ``orientations`` float32 ``(frames, B, 4)``, unit quaternions
(w, x, y, z). The page moves each body's mesh by its object transform: 28 bytes per body per
frame, however fine its surface.

The ``scenery`` layer holds the static colliders' surfaces (:mod:`visviva.simulation.scenery`)
in the same form as the bodies' but in the world frame and without transforms: the page draws
them once, as meshes that never move.
"""

from __future__ import annotations

import base64
import json
import zlib
from typing import Any

import numpy as np

from ...simulation.body_geometry import BodyGeometry
from ...simulation.lifetimes import Appearance, held_frames, held_points, life_starts
from ...simulation.recording import Geometry
from ...simulation.scenery import Scenery
from ..frame import drawn_bounds, is_star_field
from ..timescale import time_unit
from ..walls import wall_scenery

__all__ = [
    "PAYLOAD_FORMAT",
    "PAYLOAD_VERSION",
    "decoded_positions",
    "encode_payload",
    "quantized_positions",
    "to_json",
]

PAYLOAD_FORMAT = "visviva.viewer"
PAYLOAD_VERSION = 4
#: Quantization levels of a position coordinate, and of a radius that changes: 16 bits.
POSITION_LEVELS = 65535


#: Recording attributes shown in the viewer's legend, with their labels and units.
_LEGEND_ATTRIBUTES = (("method", "method", ""), ("dt", "dt", " s"), ("substeps", "substeps", ""))


def _base64(array: np.ndarray, dtype: str) -> str:
    """``array`` as base64 text of its little-endian ``dtype`` bytes, in C order."""
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def _points_layer(geometry: Geometry, shown: np.ndarray, trail_frames: int) -> dict[str, Any]:
    count = geometry.points.shape[1]
    look = Appearance.of(geometry)
    if look.alive is None:
        held, points = None, geometry.points[shown]
    else:
        held = held_frames(look.alive)
        low, high = look.live_bounds(geometry.points)
        centre = 0.5 * (low + high)
        points = np.stack([held_points(geometry.points, held, k, centre) for k in shown])
    origin, step, data = quantized_positions(points)
    layer: dict[str, Any] = {
        "count": count,
        "origin": [float(v) for v in origin],
        "step": [float(v) for v in step],
        "positions": data,
        "trail": trail_frames,
    }
    if look.varying_radius:
        layer["radii"] = _quantized_radii(_held_values(look.radius, shown, held))
    else:
        layer["radius"] = _base64(look.radius, "<f4")
    if look.color is not None and look.varying_color:
        layer["frame_colors"] = _differences_u8(_held_values(look.color, shown, held))
    elif look.color is not None:
        layer["colors"] = _base64(np.round(255 * look.color), "u1")
    if is_star_field(geometry):  # drawn as spots of light on a night sky, as the video does
        layer["stars"] = True
    spheres = geometry.off_faces()
    if spheres.size < count:  # the points on faces are drawn by the faces
        layer["spheres"] = _base64(spheres, "<u4")
    if look.alive is not None:
        alive = look.alive[shown]
        changed = alive.copy()
        changed[1:] ^= alive[:-1]
        layer["alive"] = _deflated(np.packbits(changed, axis=None, bitorder="little"))
        if trail_frames > 0:
            births = _births(alive, life_starts(look.alive)[shown], shown)
            layer["births"] = _deflated(np.packbits(births, axis=None, bitorder="little"))
    return layer


def _births(alive: np.ndarray, starts: np.ndarray, shown: np.ndarray) -> np.ndarray:
    """Bits of the points that start a life at each output frame: alive, and not alive in the
    previous output frame or born again since (a slot reused between two shown frames)."""
    births = alive.copy()
    births[1:] &= ~alive[:-1] | (starts[1:] > shown[:-1, None])
    return births


def _held_values(values: np.ndarray, shown: np.ndarray, held: np.ndarray | None) -> np.ndarray:
    """Per-frame ``values`` ``(frames, P, ...)`` at the shown frames, each dead point holding
    its value where it was last alive (0 for slots never alive): no difference to store."""
    if held is None:
        return values[shown]
    source = held[shown]
    frames = values[np.maximum(source, 0), np.arange(source.shape[1])]
    frames[source < 0] = 0
    return frames


def _quantized_radii(radii: np.ndarray) -> dict[str, Any]:
    """Radii ``(frames, P)`` [m] as 16-bit levels of ``step`` [m], in frame differences."""
    top = float(radii.max(initial=0.0))
    step = top / POSITION_LEVELS if top > 0.0 else 1.0
    levels = np.rint(radii / step).astype(np.uint16)
    return {"step": step, "data": _difference_planes(levels)}


def _differences_u8(colors: np.ndarray) -> str:
    """sRGB colours ``(frames, P, 3)`` in [0, 1] as 8-bit frame differences (modulo 256)."""
    levels = np.round(255 * colors).astype(np.uint8)
    return _deflated(np.diff(levels, axis=0, prepend=np.zeros_like(levels[:1])))


def _deflated(data: np.ndarray) -> str:
    """Base64 text of the zlib-compressed bytes of ``data``."""
    return base64.b64encode(zlib.compress(np.ascontiguousarray(data).tobytes(), 6)).decode("ascii")


def _difference_planes(levels: np.ndarray) -> str:
    """uint16 ``levels`` ``(frames, ...)`` as compressed frame differences, low and high bytes
    in two planes (see the module docstring)."""
    # Unsigned differences wrap modulo 2¹⁶, and so does the page's running sum: exact.
    differences = np.diff(levels, axis=0, prepend=np.zeros_like(levels[:1]))
    return _deflated(differences.astype("<u2").view(np.uint8).reshape(-1, 2).T)


def decoded_positions(layer: dict[str, Any], frames: int) -> np.ndarray:
    """The positions [m] a page shows, ``(frames, P, 3)``, decoded from its points layer as
    ``viewer.js`` does (to check a page, or to read one back)."""
    planes = np.frombuffer(zlib.decompress(base64.b64decode(layer["positions"])), np.uint8)
    half = planes.size // 2
    differences = planes[:half].astype(np.uint16) | (planes[half:].astype(np.uint16) << 8)
    levels = np.cumsum(differences.reshape(frames, -1), axis=0, dtype=np.uint16)
    return np.asarray(layer["origin"]) + levels.reshape(frames, -1, 3) * np.asarray(layer["step"])


def quantized_positions(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, str]:
    """Positions ``(frames, P, 3)`` [m] as the viewer stores them (module docstring).

    Returns:
        ``origin`` and ``step`` [m], each ``(3,)``, and the base64 text of the compressed
        frame differences.
    """
    flat = points.reshape(-1, 3)
    origin = flat.min(axis=0)
    step = (flat.max(axis=0) - origin) / POSITION_LEVELS
    inverse = np.divide(1.0, step, out=np.zeros(3), where=step > 0.0)
    levels = np.rint((points - origin) * inverse).astype(np.uint16)
    return origin, step, _difference_planes(levels)


def _bodies_layer(bodies: BodyGeometry, shown: np.ndarray) -> dict[str, Any]:
    """The rigid bodies' surfaces and their transforms at the shown frames (module docstring)."""
    owner = np.repeat(np.arange(bodies.count), np.diff(bodies.triangle_start))
    local = bodies.triangles - bodies.vertex_start[owner][:, None]
    return {
        "count": bodies.count,
        "names": list(bodies.names),
        "vertices": _base64(bodies.vertices, "<f4"),
        "triangles": _base64(local, "<u4"),
        "vertex_start": _base64(bodies.vertex_start, "<u4"),
        "triangle_start": _base64(bodies.triangle_start, "<u4"),
        "colors": _base64(np.round(255 * bodies.color), "u1"),
        "positions": _base64(bodies.position[shown], "<f4"),
        "orientations": _base64(bodies.orientation[shown], "<f4"),
    }


def _scenery_layer(scenery: Scenery) -> dict[str, Any]:
    """The static colliders' surfaces, in the world frame (module docstring)."""
    owner = np.repeat(np.arange(scenery.count), np.diff(scenery.triangle_start))
    local = scenery.triangles - scenery.vertex_start[owner][:, None]
    return {
        "count": scenery.count,
        "names": list(scenery.names),
        "vertices": _base64(scenery.vertices, "<f4"),
        "triangles": _base64(local, "<u4"),
        "vertex_start": _base64(scenery.vertex_start, "<u4"),
        "triangle_start": _base64(scenery.triangle_start, "<u4"),
        "colors": _base64(np.round(255 * scenery.color), "u1"),
    }


def _index_layer(indices: np.ndarray) -> dict[str, Any]:
    return {"count": int(indices.shape[0]), "indices": _base64(indices, "<u4")}


def contacts_layer(fields: dict[str, np.ndarray], shown: np.ndarray, size: float) -> dict[str, Any]:
    """The rigid bodies' contacts of the frames ``shown``, drawn on demand: ``points`` and
    ``normals`` float32 ``(frames, K, 3)``, ``classes`` int8 ``(frames, K)`` (-1: no contact
    in that slot), and ``marker``, the drawn size [m] (a hundredth of the scene's ``size``)."""
    kind = np.asarray(fields["body_contact_class"])[shown]
    points = np.nan_to_num(np.asarray(fields["body_contact_point"])[shown])
    normals = np.nan_to_num(np.asarray(fields["body_contact_normal"])[shown])
    return {
        "count": int(kind.shape[1]),
        "points": _base64(points, "<f4"),
        "normals": _base64(normals, "<f4"),
        "classes": _base64(kind, "i1"),
        "marker": 0.01 * size,
    }


def _legend(attrs: dict[str, Any], geometry: Geometry, fps: float) -> list[list[str]]:
    rows = []
    for key, label, unit in _LEGEND_ATTRIBUTES:
        value = attrs.get(key)
        if isinstance(value, (str, int, float, np.integer, np.floating)) and not isinstance(
            value, bool
        ):
            text = f"{value:.6g}" if isinstance(value, (float, np.floating)) else str(value)
            rows.append([label, text + unit])
    parts = [f"{geometry.points.shape[1]} points"] if geometry.points.shape[1] else []
    if geometry.alive is not None and parts:
        most = int(geometry.alive.sum(axis=1).max(initial=0))
        parts[0] = f"up to {most} of {parts[0]} at once"
    for name in ("edges", "faces"):
        value = getattr(geometry, name)
        if value is not None:
            parts.append(f"{value.shape[0]} {name}")
    if geometry.bodies is not None:
        count = geometry.bodies.count
        parts.append(f"{count} rigid bod{'y' if count == 1 else 'ies'}")
    if geometry.scenery is not None:
        count = geometry.scenery.count
        parts.append(f"{count} collider{'' if count == 1 else 's'}")
    rows.append(["shows", ", ".join(parts)])
    rows.append(["playback", f"{fps:.6g} frames/s"])
    if not geometry.to_scale:
        rows.append(["sizes", "not to scale (display radii)"])
    return rows


def encode_payload(
    geometry: Geometry,
    time: np.ndarray,
    shown: np.ndarray,
    *,
    fps: float,
    title: str,
    attrs: dict[str, Any],
    trail_frames: int = 0,
    contacts: dict[str, np.ndarray] | None = None,
) -> dict[str, Any]:
    """The viewer's data object for ``geometry`` resampled to the recorded frames ``shown``.

    Args:
        geometry: Validated drawable geometry of the recording (all recorded frames).
        time: Recorded frame times [s], shape ``(frames,)``.
        shown: Index of the recorded frame shown at each output frame, shape ``(frames out,)``.
        fps: Output frames per second [1/s].
        title: Page title.
        attrs: Recording attributes (only the legend's few are read).
        trail_frames: Output frames of each point's path drawn behind it (0: none).
        contacts: The recording's contact fields (``body_contact_point``, ...), if any.

    Returns:
        A JSON-serialisable dict (see the module docstring).
    """
    # Everything as drawn: the page's camera, grid and light are placed from this box.
    low, high = drawn_bounds(geometry)
    layers: dict[str, Any] = {}
    if geometry.points.shape[1]:
        layers["points"] = _points_layer(geometry, shown, trail_frames)
    unit, seconds, decimals = time_unit(float(time[-1] - time[0]))
    if geometry.edges is not None and geometry.edges.shape[0]:
        layers["edges"] = _index_layer(geometry.edges)
    if geometry.faces is not None and geometry.faces.shape[0]:
        layers["faces"] = _index_layer(geometry.faces)
    if geometry.bodies is not None:
        layers["bodies"] = _bodies_layer(geometry.bodies, shown)
    if geometry.scenery is not None:
        layers["scenery"] = _scenery_layer(geometry.scenery)
    walls = None if geometry.walls is None else wall_scenery(geometry.walls, low, high)
    if walls is not None:  # translucent, every one: the page's camera goes all round them
        layers["walls"] = _scenery_layer(walls)
    if contacts:
        layers["contacts"] = contacts_layer(contacts, shown, float(np.linalg.norm(high - low)))
    return {
        "format": PAYLOAD_FORMAT,
        "version": PAYLOAD_VERSION,
        "title": title,
        "fps": fps,
        "frames": int(shown.size),
        "times": _base64(time[shown], "<f8"),
        "time_unit": [unit, seconds, decimals],
        "to_scale": geometry.to_scale,
        "bounds": [[float(v) for v in low], [float(v) for v in high]],
        "legend": _legend(attrs, geometry, fps),
        "labels": bool(attrs.get("playback_labels", False)) and geometry.bodies is not None,
        "layers": layers,
    }


def to_json(payload: dict[str, Any]) -> str:
    """``payload`` as compact JSON that is safe inside an HTML ``<script>`` element.

    ``<``, ``>`` and ``&`` are written as JSON ``\\u`` escapes, so no text of the payload (a
    title such as ``</script>``) can end the element or open a comment.
    """
    text = json.dumps(payload, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
