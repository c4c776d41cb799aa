"""What the camera of a video or the web viewer shows.

Either a camera given outright — eye, target, up and vertical field of view, as a scene's
``[output] camera = {eye = [4, 2, 6], target = [0, 0.5, 0], fov = 40}`` or on the command line
as ``--camera "eye=4,2,6 target=0,0.5,0 fov=40"`` — or a framing: the raised three-quarter
view (:meth:`~visviva.viz.video.Camera.framing`) that keeps a box in the picture for the whole
run, the box holding everything drawn (``--frame all``, the default; for a star field, where
98 % of the stars are) or one named rigid body over every frame (``--frame NAME``), so that a
brick falling far away no longer shrinks the bodies the scene is about to specks.

Both are stored with a recording (attributes ``playback_camera`` and ``playback_frame``) so that
a later ``visviva export`` or ``visviva view`` shows what the run showed.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._registry import did_you_mean
from ..errors import ModelError
from ..geometry.quaternions import quaternion_matrix
from ..simulation.recording import Geometry
from .frame import drawn_bounds, is_star_field
from .video import FIELD_OF_VIEW, Camera

__all__ = ["ALL", "FOLLOW_ROOM", "chosen_camera", "following", "framed_bounds", "parse_camera"]

#: A followed body's view shows a box this many times the body's size around it.
FOLLOW_ROOM = 4.0

#: The framing that keeps everything drawn in view.
ALL = "all"

_KEYS = {"eye": 3, "target": 3, "up": 3, "fov": 1}

#: The percentiles of a star field's points, per axis, that its framing keeps in view.
STAR_SHARE = (1.0, 99.0)


def parse_camera(text: str) -> Camera:
    """The camera written ``"eye=x,y,z target=x,y,z [up=x,y,z] [fov=degrees]"`` [m, degrees].

    Raises:
        ModelError: Naming the part that is missing, unknown or not numbers.
    """
    given: dict[str, list[float]] = {}
    for part in str(text).split():
        key, sep, value = part.partition("=")
        if not sep or key not in _KEYS:
            known = did_you_mean(key, _KEYS) if sep else ""
            raise ModelError(
                f"camera: {part!r} is not key=value with a key of eye, target, up, fov.{known} "
                'Write for example "eye=4,2,6 target=0,0.5,0 fov=40"'
            )
        try:
            numbers = [float(v) for v in value.split(",")]
        except ValueError:
            raise ModelError(
                f"camera: {key} must be numbers separated by commas (got {value!r})"
            ) from None
        if len(numbers) != _KEYS[key]:
            raise ModelError(f"camera: {key} takes {_KEYS[key]} number(s) (got {value!r})")
        given[key] = numbers
    missing = [key for key in ("eye", "target") if key not in given]
    if missing:
        raise ModelError(
            f"camera: give {' and '.join(missing)} (got {text!r}); for example "
            '"eye=4,2,6 target=0,0.5,0 fov=40"'
        )
    return Camera(
        tuple(given["eye"]),
        tuple(given["target"]),
        tuple(given.get("up", (0.0, 1.0, 0.0))),
        given.get("fov", [FIELD_OF_VIEW])[0],
    )


def framed_bounds(geometry: Geometry, frame: str = ALL) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners [m] of what ``frame`` keeps in view over the whole run:
    everything drawn (``"all"``) or the rigid body of that name.

    Raises:
        ModelError: For a name that is not a body's, listing the bodies' names.
    """
    if frame == ALL and is_star_field(geometry):
        # A few stars flung far out would shrink the galaxies to a dot: frame where nearly
        # all of them are, over the whole run, and let the stragglers leave the picture.
        points = geometry.points.reshape(-1, 3)
        if geometry.alive is not None:
            points = points[geometry.alive.reshape(-1)]
        low, high = np.percentile(points, [STAR_SHARE[0], STAR_SHARE[1]], axis=0)
        return low, high
    if frame == ALL:
        return drawn_bounds(geometry)
    names = () if geometry.bodies is None else geometry.bodies.names
    if frame not in names:
        valid = ", ".join(repr(n) for n in names[:20]) or "none: this recording has no bodies"
        close = did_you_mean(frame, names)
        raise ModelError(
            f"frame: {frame!r} is neither 'all' nor a body of the recording.{close} Bodies: {valid}"
        )
    bodies = geometry.bodies
    assert bodies is not None
    b = names.index(frame)
    own = bodies.vertices[bodies.vertex_start[b] : bodies.vertex_start[b + 1]]  # body axes
    rotation = quaternion_matrix(bodies.orientation[:, b])  # (frames, 3, 3)
    surface = bodies.position[:, b, None] + np.einsum("fij,vj->fvi", rotation, own)
    return surface.min(axis=(0, 1)), surface.max(axis=(0, 1))


def following(geometry: Geometry, name: str, aspect: float) -> Callable[[int], Camera]:
    """The camera of each recorded frame that follows rigid body ``name``: it looks at the
    body's centre from a fixed offset, the raised three-quarter view of a box
    :data:`FOLLOW_ROOM` times the body's size (so the body and what is around it show).

    Raises:
        ModelError: For a name that is not a body's, listing the bodies' names.
    """
    framed_bounds(geometry, name)  # refuses a name that is not a body's
    bodies = geometry.bodies
    assert bodies is not None
    b = bodies.names.index(name)
    own = bodies.vertices[bodies.vertex_start[b] : bodies.vertex_start[b + 1]]
    rotation = quaternion_matrix(bodies.orientation[:, b])
    centres = (bodies.position[:, b, None] + np.einsum("fij,vj->fvi", rotation, own)).mean(axis=1)
    size = max(float(np.max(own.max(axis=0) - own.min(axis=0))), 1e-3)
    half = np.full(3, 0.5 * FOLLOW_ROOM * size)
    home = Camera.framing((-half, half), aspect=aspect)
    offset = np.subtract(home.eye, home.target)

    def camera(index: int) -> Camera:
        centre = centres[index]
        return Camera(tuple(centre + offset), tuple(centre), home.up, home.field_of_view)

    return camera


def chosen_camera(geometry: Geometry, camera: Camera | None, frame: str, aspect: float) -> Camera:
    """``camera`` if given, else the framing of ``frame`` for a picture of ``aspect``."""
    if camera is not None:
        return camera
    return Camera.framing(framed_bounds(geometry, frame), aspect=aspect)
