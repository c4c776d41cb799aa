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

Each kind of geometry is one *layer* with its own encoder here and its own builder in
``viewer.js`` (``LAYERS``): ``points`` (moving spheres), ``edges`` (lines between points) and
``faces`` (triangles between points). A new kind (rigid bodies: a position and a quaternion per
body per frame) is a new encoder and a new builder, with nothing else changed.
"""

from __future__ import annotations

import base64
import json
import zlib
from typing import Any

import numpy as np

from ...simulation.recording import Geometry
from ..timescale import time_unit

__all__ = [
    "PAYLOAD_FORMAT",
    "PAYLOAD_VERSION",
    "decoded_positions",
    "encode_payload",
    "quantized_positions",
    "to_json",
]

PAYLOAD_FORMAT = "visviva.viewer"
PAYLOAD_VERSION = 2
#: Quantization levels of a position coordinate: 16 bits.
POSITION_LEVELS = 65535


#: Recording attributes shown in the viewer's legend, with their labels and units.
_LEGEND_ATTRIBUTES = (("method", "method", ""), ("dt", "dt", " s"), ("substeps", "substeps", ""))


def _base64(array: np.ndarray, dtype: str) -> str:
    """``array`` as base64 text of its little-endian ``dtype`` bytes, in C order."""
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def _points_layer(geometry: Geometry, shown: np.ndarray, trail_frames: int) -> dict[str, Any]:
    count = geometry.points.shape[1]
    origin, step, data = quantized_positions(geometry.points[shown])
    layer = {
        "count": count,
        "origin": [float(v) for v in origin],
        "step": [float(v) for v in step],
        "positions": data,
        "radius": _base64(geometry.drawn_radius(), "<f4"),
        "trail": trail_frames,
    }
    if geometry.color is not None:
        layer["colors"] = _base64(np.round(255 * geometry.color), "u1")
    return layer


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
    # Unsigned differences wrap modulo 2¹⁶, and so does the page's running sum: exact.
    differences = np.diff(levels, axis=0, prepend=np.zeros_like(levels[:1]))
    planes = differences.astype("<u2").view(np.uint8).reshape(-1, 2).T
    data = base64.b64encode(zlib.compress(planes.tobytes(), 6)).decode("ascii")
    return origin, step, data


def _index_layer(indices: np.ndarray) -> dict[str, Any]:
    return {"count": int(indices.shape[0]), "indices": _base64(indices, "<u4")}


def _legend(attrs: dict[str, Any], geometry: Geometry, fps: float) -> list[list[str]]:
    rows = []
    for key, label, unit in _LEGEND_ATTRIBUTES:
        value = attrs.get(key)
        if isinstance(value, (str, int, float, np.integer, np.floating)) and not isinstance(
            value, bool
        ):
            text = f"{value:.6g}" if isinstance(value, (float, np.floating)) else str(value)
            rows.append([label, text + unit])
    parts = [f"{geometry.points.shape[1]} points"]
    for name in ("edges", "faces"):
        value = getattr(geometry, name)
        if value is not None:
            parts.append(f"{value.shape[0]} {name}")
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

    Returns:
        A JSON-serialisable dict (see the module docstring).
    """
    low, high = geometry.bounds()
    layers: dict[str, Any] = {"points": _points_layer(geometry, shown, trail_frames)}
    unit, seconds, decimals = time_unit(float(time[-1] - time[0]))
    if geometry.edges is not None and geometry.edges.shape[0]:
        layers["edges"] = _index_layer(geometry.edges)
    if geometry.faces is not None and geometry.faces.shape[0]:
        layers["faces"] = _index_layer(geometry.faces)
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
        "layers": layers,
    }


def to_json(payload: dict[str, Any]) -> str:
    """``payload`` as compact JSON that is safe inside an HTML ``<script>`` element.

    ``<``, ``>`` and ``&`` are written as JSON ``\\u`` escapes, so no text of the payload (a
    title such as ``</script>``) can end the element or open a comment.
    """
    text = json.dumps(payload, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")
