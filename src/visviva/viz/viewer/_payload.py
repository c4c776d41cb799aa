"""The animation data the web viewer embeds: drawable geometry as compact, typed layers.

The payload is one JSON object. Large arrays travel as base64 text of little-endian binary
(``float32`` positions and radii, ``uint32`` indices, ``float64`` frame times) that the page
decodes straight into ``Float32Array`` / ``Uint32Array`` / ``Float64Array`` views, which is
~4× smaller than JSON numbers and needs no parsing per value.

Each kind of geometry is one *layer* with its own encoder here and its own builder in
``viewer.js`` (``LAYERS``): ``points`` (moving spheres), ``edges`` (lines between points) and
``faces`` (triangles between points). A new kind (rigid bodies: a position and a quaternion per
body per frame) is a new encoder and a new builder, with nothing else changed.
"""

from __future__ import annotations

import base64
import json
from typing import Any

import numpy as np

from ...io.recording import Geometry

__all__ = ["PAYLOAD_FORMAT", "PAYLOAD_VERSION", "encode_payload", "to_json"]

PAYLOAD_FORMAT = "visviva.viewer"
PAYLOAD_VERSION = 1


#: Recording attributes shown in the viewer's legend, with their labels and units.
_LEGEND_ATTRIBUTES = (("method", "method", ""), ("dt", "dt", " s"), ("substeps", "substeps", ""))


def _base64(array: np.ndarray, dtype: str) -> str:
    """``array`` as base64 text of its little-endian ``dtype`` bytes, in C order."""
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def _points_layer(geometry: Geometry, shown: np.ndarray) -> dict[str, Any]:
    count = geometry.points.shape[1]
    if geometry.radius is None:
        radius = np.full(count, geometry.default_radius())
    else:
        radius = geometry.radius
    return {
        "count": count,
        # (frames shown, P, 3) [m], float32: 12 bytes per point per frame.
        "positions": _base64(geometry.points[shown], "<f4"),
        "radius": _base64(radius, "<f4"),
    }


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
    return rows


def encode_payload(
    geometry: Geometry,
    time: np.ndarray,
    shown: np.ndarray,
    *,
    fps: float,
    title: str,
    attrs: dict[str, Any],
) -> dict[str, Any]:
    """The viewer's data object for ``geometry`` resampled to the recorded frames ``shown``.

    Args:
        geometry: Validated drawable geometry of the recording (all recorded frames).
        time: Recorded frame times [s], shape ``(frames,)``.
        shown: Index of the recorded frame shown at each output frame, shape ``(frames out,)``.
        fps: Output frames per second [1/s].
        title: Page title.
        attrs: Recording attributes (only the legend's few are read).

    Returns:
        A JSON-serialisable dict (see the module docstring).
    """
    low, high = geometry.bounds()
    layers: dict[str, Any] = {"points": _points_layer(geometry, shown)}
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
