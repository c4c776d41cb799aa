"""The extra outputs of a run: video, the web viewer and the exports, by format name.

``visviva run -f``, ``visviva demo -f`` and ``visviva export`` share one table of formats and
file names and one function that writes any of them from a finished recording.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from .._registry import did_you_mean
from ..errors import ModelError
from ..simulation.recording import Recording

if TYPE_CHECKING:
    from .video import Camera

__all__ = ["OUTPUT_FILES", "Playback", "output_names", "playback", "write_output"]

#: Output format → its file (or, for OBJ, folder) name in a run's output directory; `visviva
#: export` uses the same names next to the recording.
OUTPUT_FILES = {
    "mp4": "animation.mp4",
    "gif": "animation.gif",
    "html": "viewer.html",
    "usd": "scene.usdc",
    "glb": "scene.glb",
    "obj": "obj",
    "pc2": "points.pc2",
}


def output_names(formats: Iterable[str]) -> list[str]:
    """The file names of ``formats`` (duplicates dropped), or an error naming an unknown one."""
    chosen = list(dict.fromkeys(formats))
    for name in chosen:
        if name not in OUTPUT_FILES:
            raise ModelError(
                f"unknown output format {name!r}.{did_you_mean(name, OUTPUT_FILES)} "
                f"Valid: {', '.join(OUTPUT_FILES)}"
            )
    return [OUTPUT_FILES[name] for name in chosen]


def write_output(
    recording: Recording,
    path: Path,
    fps: float,
    speed: float = 1.0,
    trail: float = 0.0,
    color_by: str = "scene",
) -> None:
    """Write one output (video, viewer or export, chosen by the suffix of ``path``) at ``fps``
    frames per second, playing ``speed`` simulated seconds per second; the video and the viewer
    draw ``trail`` simulated seconds of each point's path behind it, colour the points by
    ``color_by`` (``"scene"`` or ``"speed"``) and take the view the recording keeps
    (:func:`playback`)."""
    suffix = path.suffix.lower()
    view = playback(recording, speed, trail, color_by)
    if suffix in (".mp4", ".gif"):
        from .video import render_video

        render_video(recording, path, fps=fps, speed=speed, trail=trail, color_by=color_by,
                     camera=view.camera, frame=view.frame, follow=view.follow,
                     labels=view.labels)  # fmt: skip
    elif suffix == ".html":
        from .viewer import write_viewer

        write_viewer(recording, path, fps=fps, speed=speed, trail=trail, color_by=color_by,
                     camera=view.camera, frame=view.frame, follow=view.follow)  # fmt: skip
    else:
        from ..io.export import export_recording

        to = {".usdc": "usd", ".glb": "glb", ".pc2": "pc2", "": "obj"}[suffix]
        export_recording(recording, path, to=to, fps=fps, speed=speed)


class Playback(NamedTuple):
    """How an output plays a recording: simulated seconds per second, the trail behind each
    point [s], what colours the points (``"scene"`` or ``"speed"``), the camera (``None``: a
    framing), what the framing keeps in view (``"all"`` or a body's name), the body the camera
    follows (``None``: it stays put) and whether the video names the bodies."""

    speed: float
    trail: float
    color_by: str
    camera: Camera | None = None
    frame: str = "all"
    follow: str | None = None
    labels: bool = False


def playback(
    recording: Recording,
    speed: float | None,
    trail: float | None,
    color_by: str | None = None,
    camera: str | None = None,
    frame: str | None = None,
    follow: str | None = None,
) -> Playback:
    """The playback ``speed`` [simulated s per s], ``trail`` [s] and ``color_by`` of an output
    made later from ``recording``: the ones given, else those its run was made with
    (``visviva run`` and ``visviva demo`` store them as the attributes ``playback_speed``,
    ``playback_trail`` and ``playback_color_by``), else 1, 0 and ``"scene"``. So
    ``visviva export REC --to mp4`` plays a year of orbits at the week per second
    ``visviva run -f mp4`` chose, not a year of video. The same for the view: ``camera`` (as
    :func:`~visviva.viz.framing.parse_camera` reads it) and ``frame``, else the recording's
    ``playback_camera`` and ``playback_frame``, else the framing of everything; ``follow``
    (a rigid body's name: a camera that moves with it), else ``playback_follow``; whether the
    video names the bodies, ``playback_labels``."""
    attrs = recording.attrs
    if speed is None:
        speed = float(attrs.get("playback_speed", 1.0))
    if trail is None:
        trail = float(attrs.get("playback_trail", 0.0))
    if color_by is None:
        color_by = str(attrs.get("playback_color_by", "scene"))
    if camera is None and frame is None and follow is None:  # a view given now replaces it
        camera = attrs.get("playback_camera")
        follow = attrs.get("playback_follow") or None
    if frame is None:
        frame = str(attrs.get("playback_frame", "all"))
    from .framing import parse_camera

    chosen = None if camera is None else parse_camera(camera)
    labels = bool(attrs.get("playback_labels", False))
    return Playback(speed, trail, color_by, chosen, frame, follow, labels)
