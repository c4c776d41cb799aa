"""What every exporter starts from: a recording's geometry resampled to an output frame rate.

:func:`prepare` checks the recording and the rate once, before any file is touched, and returns
an :class:`ExportFrames`: output frame ``k`` (time ``k/fps`` after the first recorded frame) shows
the recorded frame ``shown[k]`` chosen by :func:`visviva.io.timeline.frames_at_rate`. Each
writer reads positions one output frame at a time (:meth:`ExportFrames.points_at`), so no
format needs a resampled copy of the whole recording unless its layout demands one (glTF).

The drawable parts follow the recording's convention (``points``, ``radius``, ``edges``,
``faces``; see :mod:`visviva.simulation.recording`). Points that are born and die
(``alive``, with radii and colours that may change per frame) are read through
:class:`visviva.simulation.lifetimes.Appearance`, as the video and the viewer read them: each writer
asks which points are alive in an output frame (:meth:`ExportFrames.alive_at`), their radius
and colour there, and, if its format keeps every slot in every frame, where a dead slot is held
(:meth:`ExportFrames.held_points_at`). Rigid bodies (:mod:`visviva.simulation.body_geometry`)
are a surface each and a transform per frame (:meth:`ExportFrames.body_transforms_at`);
formats without transforms place their vertices (:meth:`ExportFrames.body_vertices_at`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from ..._validation import real_number
from ...errors import ModelError
from ...simulation.body_geometry import BodyGeometry, continuous_orientations
from ...simulation.lifetimes import Appearance, held_frames, held_points
from ...simulation.recording import Geometry, Recording
from ..timeline import MAX_OUTPUT_FRAMES, frames_at_rate

__all__ = ["FALLBACK_FPS", "MAX_OUTPUT_FRAMES", "ExportFrames", "default_fps", "prepare"]

#: Output rate [frames/s] when the recorded frames are not evenly spaced (or there is only one).
FALLBACK_FPS = 30.0
#: Highest default output rate [frames/s]: faster recordings show their nearest frame.
MAX_DEFAULT_FPS = 60.0
#: Relative tolerance on frame spacing for a recording to count as evenly spaced, and on its
#: rate for that rate to count as a whole number of frames per second.
_EVEN_SPACING_RTOL = 1e-6


def default_fps(time: np.ndarray) -> float:
    """The output rate [frames/s] used when an export is not given ``fps``: a whole number.

    Importers play animations at their scene's rate, always a whole number of frames per second
    in Blender and Houdini, and sample a file made at another rate at the wrong times (a glTF at
    16.69 frames/s showed 1 frame in 84 right in Blender). So the default is the recording's own
    rate, ``1 / median spacing``, rounded up to a whole number (every recorded frame is shown;
    a few twice), at most :data:`MAX_DEFAULT_FPS`; :data:`FALLBACK_FPS` for uneven frames or a
    single frame.

    Args:
        time: Recorded frame times [s], non-decreasing, shape ``(frames,)``.

    Example:
        >>> default_fps(np.arange(61) / 60), default_fps(np.arange(5) / 16.69)
        (60.0, 17.0)
        >>> default_fps(np.array([0.0, 0.1, 0.3])), default_fps(np.arange(9) / 1000)
        (30.0, 60.0)
    """
    steps = np.diff(np.asarray(time, dtype=np.float64))
    if steps.size == 0:
        return FALLBACK_FPS
    step = float(np.median(steps[:-1])) if steps.size > 1 else float(steps[0])
    if not step > 0.0:
        return FALLBACK_FPS
    tolerance = _EVEN_SPACING_RTOL * step
    body, last = steps[:-1], steps[-1]
    if not (np.all(np.abs(body - step) <= tolerance) and 0.0 < last <= step + tolerance):
        return FALLBACK_FPS
    # 1/(1/60) is 59.999…: a rate within round-off of a whole number is that number.
    rate = 1.0 / step
    return float(min(MAX_DEFAULT_FPS, max(1, math.ceil(rate * (1.0 - _EVEN_SPACING_RTOL)))))


def _topology(value: np.ndarray | None) -> np.ndarray | None:
    """Index pairs or triangles as int64, or ``None`` when there are none."""
    if value is None or value.shape[0] == 0:
        return None
    return np.ascontiguousarray(value, dtype=np.int64)


@dataclass(frozen=True)
class ExportFrames:
    """A recording's drawable geometry, resampled to a fixed output rate.

    Attributes:
        geometry: The validated geometry of every recorded frame.
        time: Recorded frame times [s], shape ``(frames,)``.
        shown: Index of the recorded frame shown at each output frame, int64, shape
            ``(count,)``.
        fps: Output frames per second [1/s]; output frame ``k`` is at
            ``time[0] + k·speed/fps``.
        name: Name for the exported object (the recording's ``scene_name``, else "visviva").
        speed: Simulated seconds per second of playback.
    """

    geometry: Geometry
    time: np.ndarray
    shown: np.ndarray
    fps: float
    name: str
    speed: float = 1.0

    @property
    def count(self) -> int:
        """Number of output frames."""
        return int(self.shown.shape[0])

    @property
    def point_count(self) -> int:
        """Number of points ``P``."""
        return int(self.geometry.points.shape[1])

    @property
    def edges(self) -> np.ndarray | None:
        """Point-index pairs drawn as lines, int64 ``(E, 2)``, or ``None`` if there are none."""
        return _topology(self.geometry.edges)

    @property
    def faces(self) -> np.ndarray | None:
        """Point-index triangles, int64 ``(F, 3)``, or ``None`` if there are none."""
        return _topology(self.geometry.faces)

    @property
    def bodies(self) -> BodyGeometry | None:
        """The rigid bodies, or ``None``."""
        return self.geometry.bodies

    @cached_property
    def _orientations(self) -> np.ndarray:
        bodies = self.geometry.bodies
        if bodies is None:
            return np.zeros((self.count, 0, 4))
        return continuous_orientations(bodies.orientation[self.shown])

    def body_transforms_at(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Each rigid body's own origin [m] ``(B, 3)`` and orientation ``(B, 4)`` (unit
        quaternions (w, x, y, z), body to world) at output frame ``k``, float64. The signs of
        the quaternions are chosen so that each is in the hemisphere of the output frame
        before (the same rotations: see
        :func:`~visviva.simulation.body_geometry.continuous_orientations`)."""
        if self.geometry.bodies is None:
            return np.zeros((0, 3)), np.zeros((0, 4))
        return self.geometry.bodies.position[self.shown[k]], self._orientations[k]

    def body_vertices_at(self, k: int) -> np.ndarray:
        """Every rigid body's surface vertices [m] placed at output frame ``k``, float64
        ``(V, 3)``, world frame (none without bodies)."""
        if self.geometry.bodies is None:
            return np.zeros((0, 3))
        return self.geometry.bodies.world_vertices(int(self.shown[k]))

    def points_at(self, k: int) -> np.ndarray:
        """Positions [m] at output frame ``k``: float64, shape ``(P, 3)``, world frame, Y up."""
        return np.asarray(self.geometry.points[self.shown[k]], dtype=np.float64)

    def output_times(self) -> np.ndarray:
        """Time of each output frame after the first recorded frame [s]: ``k/fps``, ``(count,)``.

        Computed from the integer ``k`` (never by accumulating ``1/fps``).
        """
        return np.arange(self.count) / self.fps

    @cached_property
    def look(self) -> Appearance:
        """Which points are alive in each recorded frame, their drawn radii and colours."""
        return Appearance.of(self.geometry)

    @property
    def lifecycle(self) -> bool:
        """True if points are born and die (the recording has ``alive``)."""
        return self.look.alive is not None

    def alive_at(self, k: int) -> np.ndarray:
        """Which points exist at output frame ``k``: bool, shape ``(P,)``."""
        return self.look.alive_at(int(self.shown[k]))

    def radius_at(self, k: int) -> np.ndarray:
        """Point radii [m] at output frame ``k``, shape ``(P,)``: as drawn everywhere
        (:meth:`Geometry.drawn_radius`), the same in every frame unless radii change."""
        return self.look.radius_at(int(self.shown[k]))

    def color_at(self, k: int) -> np.ndarray | None:
        """sRGB point colours in [0, 1] at output frame ``k``, float32 ``(P, 3)``, or ``None``."""
        return self.look.color_at(int(self.shown[k]))

    @cached_property
    def _held(self) -> tuple[np.ndarray, np.ndarray] | None:
        alive = self.look.alive
        if alive is None:
            return None
        low, high = self.look.live_bounds(self.geometry.points)
        return held_frames(alive), 0.5 * (low + high)

    def held_points_at(self, k: int) -> np.ndarray:
        """Positions [m] of every point at output frame ``k``, float64 ``(P, 3)``, dead ones
        where they were last alive (before their first life, where they are first born; a
        slot never alive at the centre of the live points' bounds): for formats that keep
        every point in every frame."""
        if self._held is None:
            return self.points_at(k)
        held, centre = self._held
        return held_points(self.geometry.points, held, int(self.shown[k]), centre)

    def loose_points(self, *, faces: bool = True, edges: bool = False) -> np.ndarray:
        """Indices of the points used by no face (and, if ``edges``, by no edge), int64.

        A format that draws triangles (or lines) shows their vertices already; the points left
        over still need a primitive of their own.
        """
        used = np.zeros(self.point_count, dtype=bool)
        for wanted, topology in ((faces, self.faces), (edges, self.edges)):
            if wanted and topology is not None:
                used[topology.ravel()] = True
        return np.flatnonzero(~used).astype(np.int64)


def _scene_name(attrs: dict[str, Any]) -> str:
    value = attrs.get("scene_name")
    return value.strip() if isinstance(value, str) and value.strip() else "visviva"


def prepare(recording: Recording, fps: float | None, speed: float = 1.0) -> ExportFrames:
    """Check ``recording`` and ``fps`` and choose the recorded frame of every output frame.

    Args:
        recording: A recording with ``points`` or rigid bodies (see
            :meth:`Recording.geometry`).
        fps: Output frames per second [1/s], or ``None`` for :func:`default_fps` of the
            recording played at ``speed``.
        speed: Simulated seconds per second of playback.

    Raises:
        ModelError: If the recording has no points and no bodies, or no frames, ``fps`` is
            not a positive number or gives more than :data:`MAX_OUTPUT_FRAMES` frames, or a
            shown frame holds a non-finite position of a live point or transform of a body.
    """
    if not isinstance(recording, Recording):
        raise ModelError(
            f"`recording` must be a visviva.Recording (got {type(recording).__name__}); "
            "load one with visviva.io.load_recording(path)"
        )
    geometry = recording.geometry()
    points = geometry.points
    if points.shape[1] == 0 and geometry.bodies is None:
        raise ModelError(
            f"the recording's `points` field holds no points (shape {points.shape}) and it has "
            "no bodies; there is nothing to export"
        )
    time = recording.time
    if time.size == 0:
        raise ModelError("the recording has no frames; there is nothing to export")
    speed = real_number("speed", speed, positive=True, unit=" simulated s per s")
    if fps is None:
        rate = default_fps(time / speed)
    else:
        rate = real_number("fps", fps, positive=True, unit=" frames/s")
    shown = frames_at_rate(time, rate, speed=speed)
    for k in np.unique(shown):
        bad = ~np.isfinite(points[k]).all(axis=1)
        if geometry.alive is not None:
            bad &= geometry.alive[k]  # dead points hold no position worth checking
        if bad.any():
            point = int(np.argwhere(bad)[0][0])
            raise ModelError(
                f"`points` of recorded frame {int(k)} (t = {time[k]:g} s) is not finite at "
                f"point {point} ({points[k, point].tolist()}): the run diverged there; re-run "
                "it with a smaller step, or export a recording that ends before that frame"
            )
    bad_body = None if geometry.bodies is None else geometry.bodies.nonfinite(np.unique(shown))
    if bad_body is not None:
        k, body = bad_body
        raise ModelError(
            f"the transform of body {body} in recorded frame {k} (t = {time[k]:g} s) is not "
            "finite: the run diverged there; re-run it with a smaller step, or export a "
            "recording that ends before that frame"
        )
    return ExportFrames(geometry, time, shown, rate, _scene_name(recording.attrs), speed)
