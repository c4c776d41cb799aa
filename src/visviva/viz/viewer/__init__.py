"""The single-file web viewer: a recording's animation as one self-contained HTML page.

:func:`write_viewer` writes one ``.html`` file holding everything the page needs: a vendored
three.js bundle (``three.min.js``, built by ``tools/three-bundle/build.sh``; MIT licence in
``LICENSE-three.txt``), the viewer script (``viewer.js``) and the animation data (see
``_payload.py``). It opens from ``file://`` in any WebGL browser and makes no network request:
no CDN, no web fonts, no fetch of the data. The page is built from ``template.html`` by
substituting ``{{name}}`` markers in one pass, so inserted text is never re-scanned.

Frames are resampled to the playback rate with :func:`visviva.io.timeline.frames_at_rate`.
The embedded ``<script>`` contents follow the HTML Living Standard's restrictions on script
text (§ 4.12.1.3: no ``</script`` and no ``<!--`` inside an inline script), checked below.
"""

from __future__ import annotations

import html
import math
import os
import re
import warnings
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..._validation import describe, real_number
from ...errors import ModelError
from ...io.files import atomic_path
from ...io.timeline import check_playback, frames_at_rate
from ...simulation.recording import Geometry, Recording
from ..framing import ALL, chosen_camera, following
from ..speed_colors import check_color_mode, colored_by_speed
from ..video import MAX_TRAIL_POINTS, Camera
from ._payload import encode_payload, to_json

__all__ = ["FALLBACK_FPS", "MAX_DEFAULT_FPS", "MAX_POSITION_BYTES", "default_fps", "write_viewer"]

#: Playback rate [frames/s] when a recording's frames are not evenly spaced.
FALLBACK_FPS = 30.0
#: Highest default playback rate [frames/s]: a 1 kHz recording plays every 17th frame (58.8 fps).
MAX_DEFAULT_FPS = 60.0
#: Largest float32 position data [bytes] one page embeds (64 MiB, ~90 MB of base64 in the file):
#: beyond it a browser tab needs several hundred MB to open the page. E.g. 4096 points at
#: 30 frames/s fit 45 s. The default rate is lowered to fit; an explicit ``fps`` must fit.
MAX_POSITION_BYTES = 64 * 2**20
#: Relative tolerance on frame spacing for a recording to count as evenly spaced.
_EVEN_SPACING_RTOL = 1e-6
#: Bytes per point per frame: three float32 coordinates.
_BYTES_PER_POINT_FRAME = 12
#: Bytes per rigid body per frame: a float32 position and quaternion.
_BYTES_PER_BODY_FRAME = 28


#: The fields of a recording's rigid-body contacts (:meth:`visviva.Simulation.record`), drawn
#: by the page when its "contacts" box is ticked.
CONTACT_FIELDS = ("body_contact_point", "body_contact_normal", "body_contact_class")


def _frame_bytes(geometry: Geometry) -> int:
    """Bytes of float32 positions and transforms one frame holds (at least 1)."""
    bodies = 0 if geometry.bodies is None else geometry.bodies.count
    return max(
        1, geometry.points.shape[1] * _BYTES_PER_POINT_FRAME + bodies * _BYTES_PER_BODY_FRAME
    )


def _recorded_rate(time: np.ndarray) -> float | None:
    """Frame rate [1/s] of evenly spaced frames, or ``None``.

    The last interval may be shorter (a run whose end is not a whole number of frames).
    """
    steps = np.diff(time)
    if steps.size == 0 or not steps[0] > 0.0:
        return None
    step = steps[0]
    body, last = steps[:-1], steps[-1]
    tolerance = _EVEN_SPACING_RTOL * step
    if np.all(np.abs(body - step) <= tolerance) and 0.0 < last <= step + tolerance:
        return float(1.0 / step)
    return None


def _frame_count(time: np.ndarray, fps: float, speed: float) -> int:
    return int(frames_at_rate(time[[0, -1]], fps, speed=speed).size)


def default_fps(recording: Recording, speed: float = 1.0) -> float:
    """The playback rate [frames/s] :func:`write_viewer` uses when ``fps`` is not given.

    The recording's own rate if its frames are evenly spaced, divided by the smallest whole
    number that brings it to at most :data:`MAX_DEFAULT_FPS` (so every n-th frame is shown,
    without jitter); :data:`FALLBACK_FPS` for uneven frames. If the frames at that rate would
    exceed :data:`MAX_POSITION_BYTES`, the rate is lowered until they fit, with a warning.
    Played at ``speed`` simulated seconds per second, the recording's own rate is divided by
    ``speed``.

    Example:
        >>> import numpy as np, visviva as vv
        >>> time, points = np.arange(1001) * 1e-3, np.zeros((1001, 1, 3))
        >>> rec = vv.Recording(time, {"particle_position": points})
        >>> round(default_fps(rec), 3)          # 1000 Hz shown every 17th frame
        58.824
    """
    geometry = recording.geometry()
    speed = real_number("speed", speed, positive=True, unit=" simulated s per s")
    if recording.time.size == 0:
        raise ModelError("the recording has no frames: there is nothing to play")
    check_playback(float(recording.time[-1] - recording.time[0]), speed)
    time = recording.time / speed  # playback time [s]
    rate = _recorded_rate(time)
    if rate is None:
        fps = FALLBACK_FPS
    else:
        fps = rate / max(1, math.ceil(rate / MAX_DEFAULT_FPS * (1.0 - _EVEN_SPACING_RTOL)))
    frame_bytes = _frame_bytes(geometry)
    budget_frames = MAX_POSITION_BYTES // frame_bytes
    span = float(time[-1] - time[0])
    if budget_frames < 1:
        raise ModelError(
            f"recording has {geometry.points.shape[1]} points: one frame is {frame_bytes} bytes, "
            f"more than the viewer's limit of {MAX_POSITION_BYTES} bytes of positions; export "
            "to USD or glTF instead"
        )
    if _frame_count(time, fps, 1.0) > budget_frames:
        fps = (budget_frames - 1) / span if budget_frames > 1 else 1.0 / (2.0 * span)
        warnings.warn(
            f"the viewer plays this recording at {fps:.3g} frames/s so that its positions stay "
            f"within {MAX_POSITION_BYTES // 2**20} MiB; for smoother playback, write a shorter "
            "part of the recording",
            stacklevel=2,
        )
    return fps


def _check_fps(recording: Recording, fps: float | None, speed: float) -> float:
    if fps is None:
        return default_fps(recording, speed)
    value = real_number("fps", fps, positive=True, unit=" frames/s")
    size = _frame_count(recording.time, value, speed) * _frame_bytes(recording.geometry())
    if size > MAX_POSITION_BYTES:
        raise ModelError(
            f"`fps` = {value:g} frames/s embeds {size / 2**20:.0f} MiB of positions, more than "
            f"the viewer's limit of {MAX_POSITION_BYTES // 2**20} MiB; lower fps or leave it "
            "unset to let the viewer choose a rate that fits"
        )
    return value


def _check_target(path: str | os.PathLike[str]) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise ModelError(f"`path` must be a file path (got {describe(path)})")
    target = Path(path)
    if target.is_dir():
        raise ModelError(f"`path` {os.fspath(target)!r} is a directory; give a file name")
    if not target.parent.is_dir():
        raise ModelError(
            f"`path` {os.fspath(target)!r}: directory {os.fspath(target.parent)!r} does not "
            "exist; create it first"
        )
    return target


def _check_finite(geometry: Geometry) -> None:
    """Refuse frames with a non-finite live position or body transform (dead points are never
    drawn)."""
    finite = np.isfinite(geometry.points).all(axis=2)
    if geometry.alive is not None:
        finite |= ~geometry.alive
    bad = ~finite.all(axis=1)
    if bad.any():
        frame = int(np.argmax(bad))
        raise ModelError(
            f"`points` of recorded frame {frame} are not finite; the viewer can only show "
            "finite positions (cut the recording before the blow-up)"
        )
    bad_body = None if geometry.bodies is None else geometry.bodies.nonfinite()
    if bad_body is not None:
        raise ModelError(
            f"the transform of body {bad_body[1]} in recorded frame {bad_body[0]} is not "
            "finite; the viewer can only show finite positions (cut the recording before the "
            "blow-up)"
        )


@cache
def _asset(name: str) -> str:
    text = resources.files(__name__).joinpath(name).read_text(encoding="utf-8")
    if name.endswith(".js") and re.search(r"</script|<!--", text, re.IGNORECASE):
        raise RuntimeError(f"{name} contains '</script' or '<!--' and cannot be inlined")
    return text


def _default_title(recording: Recording) -> str:
    # "scene_name" from scene runs ("scene" holds the scene file's text), "problem" from solves.
    for key in ("scene_name", "problem"):
        value = recording.attrs.get(key)
        if isinstance(value, str) and value:
            return f"visviva — {value}"
    return "visviva viewer"


def write_viewer(
    recording: Recording,
    path: str | os.PathLike[str],
    *,
    fps: float | None = None,
    title: str | None = None,
    speed: float = 1.0,
    trail: float = 0.0,
    color_by: str = "scene",
    camera: Camera | None = None,
    frame: str = "all",
    follow: str | None = None,
) -> Path:
    """Write ``recording``'s animation as one self-contained HTML file.

    The page plays the points (spheres of their radii), edges (lines), faces
    (a shaded surface) and rigid bodies (their surfaces, moved by their transforms) of
    :meth:`Recording.geometry` in real time (points that are born and
    die only while alive, at each frame's radius and colour), with an orbit camera, a
    play/pause button (and the space bar), a frame slider, the time ``t`` [s] of the recorded
    frame shown, a speed selector and a legend. See ``docs/viewer.md``.

    Args:
        recording: A recording with ``points`` or rigid bodies.
        path: File to write (conventionally ``.html``); its directory must exist. Written
            atomically: a partial file never appears under this name.
        fps: Playback rate [frames/s]; output frame ``k`` shows the recorded frame nearest
            ``t0 + k/fps``. Default: :func:`default_fps`.
        title: Page title; default ``"visviva — <scene or problem name>"``.
        speed: Simulated seconds per second of playback (1: real time); the page shows
            simulated time, in the unit that reads best (s, min, h, days, years).
        trail: Draw each point's path over the last ``trail`` simulated seconds [s] behind it
            (0: none); for at most :data:`~visviva.viz.video.MAX_TRAIL_POINTS` points.
        color_by: ``"scene"``: the recorded colours; ``"speed"``: each point's speed in each
            frame (:mod:`visviva.viz.speed_colors`), the scale in the legend.
        camera: The page's first view (eye, target and field of view; the page keeps +Y up);
            default: the framing of ``frame``.
        frame: Without ``camera``, what the first view keeps in the picture over the whole
            run: ``"all"`` or the name of one rigid body (:mod:`visviva.viz.framing`).
        follow: The name of a rigid body the page's camera follows as it plays (its target
            moves with the body's centre; orbiting and zooming still work).

    Returns:
        The path written.

    Raises:
        ModelError: Before anything is written, if the recording has no drawable geometry,
            non-finite positions, or too many frames (see :data:`MAX_POSITION_BYTES`), or if
            an argument is invalid.
    """
    if not isinstance(recording, Recording):
        raise ModelError(
            f"`recording` must be a visviva Recording (got {type(recording).__name__}); "
            "load one with visviva.io.load_recording(path)"
        )
    geometry = recording.geometry()
    if recording.frames == 0:
        raise ModelError("the recording has no frames: there is nothing to play")
    if title is not None and not isinstance(title, str):
        raise ModelError(f"`title` must be a string or None (got {describe(title)})")
    target = _check_target(path)
    _check_finite(geometry)
    rate = _check_fps(recording, fps, speed)
    trail = real_number("trail", trail, nonnegative=True, unit=" s")
    if trail > 0.0 and geometry.points.shape[1] > MAX_TRAIL_POINTS:
        raise ModelError(
            f"`trail` draws a path behind each point, for at most {MAX_TRAIL_POINTS} points "
            f"(this recording has {geometry.points.shape[1]}); leave it at 0"
        )
    color_by = check_color_mode(color_by)
    scale = None
    if color_by == "speed":
        geometry, scale = colored_by_speed(recording, geometry)
    shown = frames_at_rate(recording.time, rate, speed=speed)
    page_title = _default_title(recording) if title is None else title
    payload = encode_payload(
        geometry,
        recording.time,
        shown,
        fps=rate,
        title=page_title,
        attrs=recording.attrs,
        trail_frames=round(trail * rate / speed),
        contacts={name: recording[name] for name in CONTACT_FIELDS}
        if all(name in recording for name in CONTACT_FIELDS)
        else None,
    )
    if scale is not None:
        payload["legend"].append(["colour", scale.caption()])
    if follow is not None:
        start = following(geometry, follow, 16 / 9)  # refuses a name that is not a body's
        payload["view"] = _home_view(start(0))
        bodies = geometry.bodies
        assert bodies is not None
        b = bodies.names.index(follow)
        own = bodies.vertices[bodies.vertex_start[b] : bodies.vertex_start[b + 1]]
        # The page moves its target with the body: its index and centre in its own axes.
        payload["follow"] = {"body": b, "centre": own.mean(axis=0).tolist()}
    elif camera is not None or frame != ALL:
        payload["view"] = _home_view(chosen_camera(geometry, camera, frame, 16 / 9))
    parts = {
        "title": html.escape(page_title, quote=False),
        "three": _asset("three.min.js"),
        "viewer": _asset("viewer.js"),
        "data": to_json(payload),
    }
    page = re.sub(r"\{\{(\w+)\}\}", lambda match: parts[match.group(1)], _asset("template.html"))
    with atomic_path(target) as temporary:
        temporary.write_text(page, encoding="utf-8")
    return target


def _home_view(camera: Camera) -> dict[str, Any]:
    """``camera`` as the page's orbit view: its target, distance [m], polar angle from +Y and
    azimuth from +Z towards +X [rad], and vertical field of view [degrees]."""
    offset = np.subtract(camera.eye, camera.target)
    distance = float(np.linalg.norm(offset))
    return {
        "target": list(camera.target),
        "distance": distance,
        "polar": float(np.arccos(np.clip(offset[1] / distance, -1.0, 1.0))),
        "azimuth": float(np.arctan2(offset[0], offset[2])),
        "fov": camera.field_of_view,
    }
