"""Videos of recordings: mp4 (H.264) and animated GIF, rendered without a display.

:func:`render_video` draws every output frame of a recording with a small software rasterizer
(:mod:`visviva.viz.raster`, Numba kernels) and hands the frames to imageio: the imageio-ffmpeg
plugin for mp4 (its wheel ships a static ffmpeg with libx264; yuv420p, constant quality
CRF 18, ``+faststart`` so browsers can play while downloading) and Pillow for GIF (one global
palette for the whole clip so colours do not flicker from frame to frame).

Why a software rasterizer rather than matplotlib: a scene is thousands of spheres, lines and
triangles seen in perspective with a depth buffer. matplotlib's 3-D axes sort whole artists,
not pixels, draw spheres as flat markers, and took 320 ms per 960×540 frame for a 20,000-point
scatter on our machine; the kernels here draw shaded, depth-tested sphere impostors with
anti-aliased rims and shadows in about 35 ms for the same 20,000 spheres (a few ms for a few
hundred), because the camera never moves (sky and ground are painted once per video) and
every step is a compiled loop over arrays. Encoding runs in the ffmpeg process, on the other
core, while the next frame is drawn.

What a frame shows (:class:`FramePainter` in :mod:`visviva.viz.frame`): a sky gradient, a
checkered ground plane at ``y = min(0, lowest point)``, points as shaded spheres of their
recorded radius and colour (or the viewer's default radius and blue; a recording's display
radii, for bodies too small to see, are drawn instead and the label says "sizes not to
scale"), only the points alive in the frame (particles of emitters are born and die; see
:mod:`visviva.simulation.lifetimes`), optional trails behind the points, edges as lines, faces as
Gouraud-shaded triangles, rigid bodies as their surfaces placed by each frame's transform and
shaded the same way in their colours, shadows from a light above, and the time of the recorded frame
shown in the unit that reads best, ``t = 1.234 s`` or ``t = 182.6 days``. Output frame ``k``
shows the recorded frame nearest ``t0 + k/fps`` (:func:`visviva.io.timeline.frames_at_rate`),
so the video plays in real time whatever the recording's frame spacing.

References: ITU-T H.264 (libx264 via ffmpeg); GIF89a specification (delays in hundredths of a
second, hence the frame delays below alternate so that their sum keeps time).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from .._validation import describe, real_number
from ..errors import ModelError
from ..io.files import atomic_path
from ..io.timeline import frames_at_rate
from ..simulation.recording import Geometry, Recording
from .frame import FramePainter
from .speed_colors import check_color_mode, colored_by_speed

__all__ = [
    "FORMATS",
    "MAX_GIF_FPS",
    "MAX_SIZE",
    "MAX_TRAIL_POINTS",
    "MIN_GIF_FPS",
    "Camera",
    "render_video",
]

#: Most points that get trails: each is a line of up to 400 segments per frame.
MAX_TRAIL_POINTS = 1000

#: Default vertical field of view [degrees] (the web viewer's).
FIELD_OF_VIEW = 45.0
#: Default view direction, as the web viewer's home view: from the target towards the eye,
#: azimuth [rad] from +Z towards +X and elevation [rad] above the horizontal.
VIEW_AZIMUTH, VIEW_ELEVATION = 0.6, math.pi / 2 - 1.15
#: The framed box fills at most this fraction of the picture's half-width and half-height.
FRAMING_FILL = 0.9
#: File suffixes :func:`render_video` writes.
FORMATS = (".mp4", ".gif")
#: GIF delays are whole hundredths of a second and players treat delays below 2 as 10:
#: faster GIFs play slower, not faster, so they are refused.
MAX_GIF_FPS = 50.0
#: The slowest GIF: its frame delay is a 16-bit count of hundredths of a second [frames/s].
MIN_GIF_FPS = 100.0 / 65535
#: Largest width or height [px] (8K UHD width): beyond it a frame buffer alone is > 400 MB.
MAX_SIZE = 7680
#: H.264 constant rate factor: 18 is visually lossless for these flat-shaded pictures.
MP4_QUALITY = 18
#: x264 speed/size trade-off: for these pictures "veryfast" makes files as small as "medium"
#: (within 5 %) in a third of the time.
MP4_PRESET = "veryfast"


@dataclass(frozen=True)
class Camera:
    """A pinhole camera at ``eye`` looking at ``target``, with ``up`` upward in the picture.

    Attributes:
        eye: Camera position [m], world frame.
        target: Point at the centre of the picture [m], world frame.
        up: Direction shown upward (world frame, need not be unit or perpendicular to the view);
            default +Y.
        field_of_view: Vertical field of view [degrees], in (0, 180).

    Example:
        >>> camera = Camera.framing((np.zeros(3), np.ones(3)))
        >>> camera.target
        (0.5, 0.5, 0.5)
    """

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    field_of_view: float = FIELD_OF_VIEW

    def __post_init__(self) -> None:
        for name in ("eye", "target", "up"):
            object.__setattr__(self, name, _vector(name, getattr(self, name)))
        angle = real_number("field_of_view", self.field_of_view, positive=True, unit=" degrees")
        if not angle < 180.0:
            raise ModelError(f"`field_of_view` must be below 180 degrees (got {angle!r})")
        object.__setattr__(self, "field_of_view", angle)
        view = np.subtract(self.target, self.eye)
        if not np.linalg.norm(view) > 0.0:
            raise ModelError(f"`eye` and `target` must differ (both are {self.eye})")
        side = np.linalg.norm(np.cross(view, self.up))
        if not side > 1e-9 * np.linalg.norm(view) * np.linalg.norm(self.up):
            raise ModelError(
                f"`up` {self.up} must be non-zero and not parallel to the view direction "
                f"{tuple(view.tolist())}: nothing would say which way is up; use (0, 1, 0)"
            )

    @classmethod
    def framing(
        cls,
        bounds: tuple[np.ndarray, np.ndarray],
        *,
        aspect: float = 16 / 9,
        field_of_view: float = FIELD_OF_VIEW,
    ) -> Camera:
        """A raised three-quarter view (Y up) that keeps the whole box ``bounds`` in the picture.

        The camera looks at the box's centre from the web viewer's home direction (34° round
        from +Z towards +X, 24° above the horizontal), just far enough that all eight corners
        fall inside the picture with a margin.

        Args:
            bounds: Lower and upper corners of the box [m], e.g. ``geometry.bounds()``; a box of
                no size is treated as 1 m wide.
            aspect: Picture width over height.
            field_of_view: Vertical field of view [degrees].
        """
        low, high = _vector("bounds[0]", bounds[0]), _vector("bounds[1]", bounds[1])
        aspect = real_number("aspect", aspect, positive=True)
        if not all(a <= b for a, b in zip(low, high, strict=True)):
            raise ModelError(f"`bounds` must be (lower, upper) corners (got {low}, {high})")
        centre = 0.5 * (np.array(low) + np.array(high))
        half = 0.5 * (np.array(high) - np.array(low))
        if not half.max() > 0.0:
            half = np.full(3, 0.5)
        back = np.array(
            [
                math.sin(VIEW_AZIMUTH) * math.cos(VIEW_ELEVATION),
                math.sin(VIEW_ELEVATION),
                math.cos(VIEW_AZIMUTH) * math.cos(VIEW_ELEVATION),
            ]
        )
        right = np.cross(-back, [0.0, 1.0, 0.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, -back)
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        corners = signs * half
        tan_v = FRAMING_FILL * math.tan(math.radians(field_of_view) / 2.0)
        tan_h = tan_v * aspect
        # A corner at (x, y) across and h towards the eye is in view from distance d if
        # |x| ≤ tan_h·(d − h) and |y| ≤ tan_v·(d − h).
        towards = corners @ back
        distance = max(
            np.max(towards + np.abs(corners @ right) / tan_h),
            np.max(towards + np.abs(corners @ up) / tan_v),
        )
        eye = centre + distance * back
        return cls(tuple(eye.tolist()), tuple(centre.tolist()), field_of_view=field_of_view)


def _vector(name: str, value: Any) -> tuple[float, float, float]:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        array = np.empty(0)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise ModelError(
            f"`{name}` must be three finite numbers (x, y, z) in metres (got {describe(value)})"
        )
    return (float(array[0]), float(array[1]), float(array[2]))


class _Writer(Protocol):
    def append(self, frame: np.ndarray) -> None: ...


def render_video(
    recording: Recording,
    path: str | os.PathLike[str],
    *,
    fps: float = 30.0,
    size: tuple[int, int] = (960, 540),
    camera: Camera | None = None,
    progress: bool | None = None,
    speed: float = 1.0,
    trail: float = 0.0,
    color_by: str = "scene",
    frame: str = "all",
    labels: bool = False,
    follow: str | None = None,
) -> Path:
    """Render a recording's geometry to an mp4 or GIF file.

    Args:
        recording: A recording with drawable geometry (``points``, optional ``radius``,
            ``color``, ``edges``, ``faces``, and ``alive``, ``radius`` and ``color`` per frame
            for points that are born and die; rigid bodies; see :meth:`Recording.geometry`).
        path: Output file; ``.mp4`` or ``.gif`` chooses the format. Its directory must exist.
            Written atomically: a temporary file renamed when complete.
        fps: Output frames per second [1/s]; at most 50 for GIF.
        size: ``(width, height)`` [px]; both even for mp4 (yuv420p halves the colour planes).
        camera: The view; default :meth:`Camera.framing` of what ``frame`` names, over all
            frames, so that it stays in view for the whole clip.
        progress: Show a progress bar on stderr for long renders; ``None`` (default): only
            when stderr is a terminal.
        speed: Simulated seconds per second of video (1: real time; 86400: a day per
            second). The time label shows simulated time, in the unit that reads best for the
            recording's span (s, min, h, days, years).
        trail: Draw each point's path over the last ``trail`` simulated seconds [s] behind
            it (0: none); for at most :data:`MAX_TRAIL_POINTS` points.
        color_by: ``"scene"``: the recorded colours; ``"speed"``: each point's speed in each
            frame (:mod:`visviva.viz.speed_colors`), the scale in the corner label.
        frame: Without ``camera``, what the view keeps in the picture: ``"all"`` (the live
            points and the bodies) or the name of one rigid body (:mod:`visviva.viz.framing`).
        labels: Write each rigid body's name above it, where the lesson depends on telling
            them apart (the ``dzhanibekov`` demo's three handles).
        follow: The name of a rigid body the camera follows (it moves with the body's centre;
            :func:`~visviva.viz.framing.following`), instead of ``camera`` and ``frame``.

    Returns:
        The path written.

    Raises:
        ModelError: Before anything is written, for an unknown suffix, a recording without
            points or with non-finite ones, ``fps ≤ 0`` (or > 50 for GIF), a bad ``size``,
            a bad camera or a missing directory.

    Example:
        >>> import tempfile, pathlib, numpy as np, visviva as vv
        >>> t = np.arange(10) / 10.0
        >>> points = np.zeros((10, 1, 3)); points[:, 0, 1] = 1.0 - 4.9 * t**2
        >>> radius = {"particle_radius": np.array([0.1])}
        >>> rec = vv.Recording(t, {"particle_position": points}, static=radius)
        >>> out = render_video(rec, pathlib.Path(tempfile.mkdtemp()) / "drop.gif",
        ...                    fps=10, size=(64, 48))
        >>> out.name, out.stat().st_size > 0
        ('drop.gif', True)
    """
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix not in FORMATS:
        raise ModelError(
            f"`path` must end in .mp4 or .gif to choose the video format (got {os.fspath(path)!r})"
        )
    fps = real_number("fps", fps, positive=True, unit=" frames/s")
    if suffix == ".gif" and fps > MAX_GIF_FPS:
        raise ModelError(
            f"`fps` of a GIF must be at most {MAX_GIF_FPS:g} frames/s: players slow faster GIFs "
            f"down (got {fps:g}); use fps={MAX_GIF_FPS:g} or write an .mp4"
        )
    if suffix == ".gif" and fps < MIN_GIF_FPS:
        raise ModelError(
            f"`fps` of a GIF must be at least {MIN_GIF_FPS:.4f} frames/s: a GIF frame lasts at "
            f"most 655.35 s (got {fps:g}); use a higher fps or write an .mp4"
        )
    width, height = _checked_size(size, even=suffix == ".mp4")
    trail = real_number("trail", trail, nonnegative=True, unit=" s")
    color_by = check_color_mode(color_by)
    if follow is not None and camera is not None:
        raise ModelError("`follow` moves the camera with a body; give it or `camera`, not both")
    if camera is not None and not isinstance(camera, Camera):
        raise ModelError(f"`camera` must be a visviva Camera or None (got {describe(camera)})")
    if not isinstance(recording, Recording):
        raise ModelError(f"`recording` must be a visviva Recording (got {describe(recording)})")
    geometry = recording.geometry()
    _check_finite(geometry)
    if trail > 0.0 and geometry.points.shape[1] > MAX_TRAIL_POINTS:
        raise ModelError(
            f"`trail` draws a path behind each point, for at most {MAX_TRAIL_POINTS} points "
            f"(this recording has {geometry.points.shape[1]}); leave it at 0"
        )
    caption = ""
    if color_by == "speed":
        geometry, scale = colored_by_speed(recording, geometry)
        caption = scale.caption()
    if not target.parent.is_dir():
        raise ModelError(
            f"`path` {os.fspath(path)!r}: directory {os.fspath(target.parent)!r} does not "
            "exist; create it first"
        )
    shown = frames_at_rate(recording.time, fps, speed=speed)

    from .framing import chosen_camera, following
    from .walls import with_walls

    moving = None if follow is None else following(geometry, follow, width / height)
    camera = chosen_camera(geometry, camera, frame, width / height) if moving is None else moving(0)
    geometry = with_walls(geometry, np.array(camera.eye))
    painter = FramePainter(
        geometry, (width, height), camera, recording.time, trail, caption, labels=labels,
        follow=moving,
    )  # fmt: skip
    times = recording.time[shown]
    from ..simulation.progress import Progress

    with (
        atomic_path(target) as temporary,
        _open_writer(temporary, suffix, fps, painter, shown, times) as writer,
        Progress(len(shown), f"rendering {target.name}", enabled=progress) as bar,
    ):
        for index, time in zip(shown, times, strict=True):
            writer.append(painter.paint(int(index), float(time)))
            bar.advance(1)
    return target


def _checked_size(size: Any, *, even: bool) -> tuple[int, int]:
    """``size`` as ``(width, height)``, or a :class:`ModelError` saying what is accepted."""
    ok = (
        isinstance(size, Sequence)
        and len(size) == 2
        and all(isinstance(n, (int, np.integer)) and not isinstance(n, bool) for n in size)
    )
    if not ok:
        raise ModelError(
            f"`size` must be two whole numbers (width, height) in pixels, e.g. (960, 540) "
            f"(got {describe(size)})"
        )
    width, height = int(size[0]), int(size[1])
    if not (0 < width <= MAX_SIZE and 0 < height <= MAX_SIZE):
        raise ModelError(
            f"`size` must be positive and at most {MAX_SIZE} pixels each way, e.g. (960, 540) "
            f"(got {(width, height)})"
        )
    if even and (width % 2 or height % 2):
        raise ModelError(
            f"`size` of an mp4 must be even in both directions (yuv420p stores colour at half "
            f"resolution) (got {(width, height)}); use {(width + width % 2, height + height % 2)}"
        )
    return width, height


def _check_finite(geometry: Geometry) -> None:
    """Refuse non-finite live positions, body transforms and bad radii; dead points may hold
    anything."""
    points, radius, alive = geometry.points, geometry.radius, geometry.alive
    bad = ~np.isfinite(points).all(axis=2)
    if alive is not None:
        bad &= alive
    if bad.any():
        frame, point = (int(i) for i in np.argwhere(bad)[0])
        raise ModelError(
            f"`points` must be finite to be drawn: frame {frame}, point {point} is "
            f"{describe(points[frame, point])}; cut the recording before the run diverged"
        )
    bad_body = None if geometry.bodies is None else geometry.bodies.nonfinite()
    if bad_body is not None:
        raise ModelError(
            f"the transforms of the bodies must be finite to be drawn: frame {bad_body[0]}, "
            f"body {bad_body[1]} is not; cut the recording before the run diverged"
        )
    if radius is None:
        return
    wrong = ~(np.isfinite(radius) & (radius >= 0.0))
    if alive is not None and radius.ndim == 2:
        wrong &= alive
    if wrong.any():
        where = tuple(int(i) for i in np.argwhere(wrong)[0])
        place = f"point {where[-1]}" + (f" in frame {where[0]}" if len(where) == 2 else "")
        raise ModelError(
            f"`radius` must be finite and ≥ 0 [m]: {place} has {describe(radius[where])}"
        )


@contextmanager
def _open_writer(
    path: Path,
    suffix: str,
    fps: float,
    painter: FramePainter,
    shown: np.ndarray,
    times: np.ndarray,
) -> Iterator[_Writer]:
    if suffix == ".mp4":
        with _Mp4Writer(path, fps) as mp4:
            yield mp4
    else:
        # One palette for the whole clip, from its first, middle and last frames.
        samples = sorted({0, len(shown) // 2, len(shown) - 1})
        stills = [painter.paint(int(shown[k]), float(times[k])) for k in samples]
        gif = _GifWriter(np.concatenate(stills, axis=0), fps)
        yield gif
        gif.save(path)


class _Mp4Writer:
    """Frames piped to ffmpeg (libx264, yuv420p) through imageio's FFMPEG plugin."""

    def __init__(self, path: Path, fps: float) -> None:
        import imageio.v2 as imageio

        self._writer: Any = imageio.get_writer(
            path,
            format="FFMPEG",
            mode="I",
            fps=fps,
            codec="libx264",
            pixelformat="yuv420p",
            quality=None,  # no imageio quality mapping: the CRF below says it exactly
            macro_block_size=2,  # sizes are even already; never rescale
            ffmpeg_log_level="error",
            output_params=[
                "-crf",
                str(MP4_QUALITY),
                "-preset",
                MP4_PRESET,
                "-movflags",
                "+faststart",
            ],
        )

    def __enter__(self) -> _Mp4Writer:
        return self

    def __exit__(self, *exc: object) -> None:
        self._writer.close()

    def append(self, frame: np.ndarray) -> None:
        self._writer.append_data(frame)


class _GifWriter:
    """Frames mapped to one palette, kept in memory (1 byte per pixel) and saved by Pillow."""

    def __init__(self, samples: np.ndarray, fps: float) -> None:
        from PIL import Image

        # Octree keeps more shades for the small shaded spheres than median cut, which spends
        # the palette on the large ground; no dithering, so regions that do not change stay
        # identical from frame to frame (no shimmer, and Pillow stores only what changed).
        octree = Image.fromarray(samples).quantize(
            colors=256, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE
        )
        # The octree often fills fewer than 256 entries and pads with black. Pillow's GIF
        # writer matches a given palette entry by entry, quadratically slower on repeated
        # entries, so the spare entries become distinct greys (useful for shadows).
        entries = list(dict.fromkeys(map(tuple, np.reshape(octree.getpalette() or [], (-1, 3)))))
        taken = set(entries)
        entries += [(v, v, v) for v in range(256) if (v, v, v) not in taken]
        self._palette = Image.new("P", (1, 1))
        self._palette.putpalette(np.ravel(entries[:256]).astype(np.uint8).tobytes())
        self._fps = fps
        self._frames: list[np.ndarray] = []

    def append(self, frame: np.ndarray) -> None:
        from PIL import Image

        image = Image.fromarray(frame).quantize(palette=self._palette, dither=Image.Dither.NONE)
        self._frames.append(np.asarray(image))

    def save(self, path: Path) -> None:
        import imageio.v3 as iio

        # Delays in hundredths of a second, rounded from integer frame counts so that the
        # sum never drifts: at 30 fps they run 3, 3, 4, 3, 3, 4, ...
        ticks = np.round(np.arange(len(self._frames) + 1) * 100.0 / self._fps)
        delays = [int(10 * d) for d in np.diff(ticks)]  # Pillow takes milliseconds
        palette = self._palette.getpalette() or []
        iio.imwrite(
            path,
            np.stack(self._frames),
            plugin="pillow",
            extension=".gif",
            mode="L",
            is_batch=True,
            palette=bytes(palette[:768]),
            # Pillow's writer takes a list for an animation, a number for a still.
            duration=delays if len(delays) > 1 else delays[0],
            loop=0,
        )
