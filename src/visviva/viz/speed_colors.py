"""Points coloured by their speed: how the video and the viewer show a flock, a crowd or a gas.

With ``color_by="speed"`` each point of each frame takes the colour of its speed ``|v|`` [m/s]
on the perceptually uniform *viridis* map (van der Walt & Smith, matplotlib 1.5, 2015): dark
purple at rest, through blue and green, to yellow at the top of the scale. The scale is one for
the whole clip, so a colour means the same speed in every frame: from 0 to the 99.5th
percentile of the live points' speeds over all frames (a few outliers, a bird that was just
born at full speed, do not wash out the rest), the points above it drawn in the top colour.

The speeds are the recorded velocities of the drawn points (``particle_velocity``, then the
gravitating bodies' ``system_velocity``); points without a recorded velocity (the drawings of
named systems beside them) keep their own colours.
"""

from __future__ import annotations

import dataclasses
from typing import Literal, get_args

import numpy as np

from .._validation import describe
from ..errors import ModelError
from ..simulation.recording import Geometry, Recording

__all__ = ["COLOR_MODES", "ColorMode", "SpeedScale", "check_color_mode", "colored_by_speed"]

#: How outputs colour points: by the recording's colours ("scene") or by speed.
ColorMode = Literal["scene", "speed"]
COLOR_MODES: tuple[str, ...] = get_args(ColorMode)

#: Percentile of the live speeds at the top of the scale.
TOP_PERCENTILE = 99.5
#: Entries of the colour table sampled from the colour map.
_LEVELS = 256
#: Default sRGB colour [0, 1] of points without a colour (that of the video's spheres).
_UNCOLORED = (0.85, 0.85, 0.85)


@dataclasses.dataclass(frozen=True)
class SpeedScale:
    """The speeds the colours span: 0 to :attr:`top` [m/s]."""

    top: float

    def caption(self) -> str:
        """The scale in words, for a legend: ``"speed 0 (purple) to 12.5 m/s (yellow)"``
        (ASCII: the video's label font has no dashes or arrows)."""
        return f"speed 0 (purple) to {self.top:.3g} m/s (yellow)"


def check_color_mode(value: object) -> str:
    """``value`` if it names a colour mode, else a :class:`ModelError` naming the choices."""
    if not isinstance(value, str) or value not in COLOR_MODES:
        raise ModelError(
            f"`color_by` must be one of {', '.join(map(repr, COLOR_MODES))} (got {describe(value)})"
        )
    return value


def colored_by_speed(recording: Recording, geometry: Geometry) -> tuple[Geometry, SpeedScale]:
    """``geometry`` with every point coloured by its speed in each frame, and the scale.

    Args:
        recording: The recording ``geometry`` comes from; its velocities of the drawn points
            (:meth:`Recording.drawn_velocity`: ``particle_velocity``, then
            ``system_velocity``; ``(frames, k, 3)`` [m/s]) give the speeds of the first ``k``
            points, the others keep their colours.
        geometry: :meth:`Recording.geometry` of it.

    Returns:
        The geometry with ``color`` of shape ``(frames, P, 3)`` (float32 sRGB in [0, 1]).

    Raises:
        ModelError: If the recording has no velocities, or non-finite ones.
    """
    velocities = recording.drawn_velocity()
    frames, count = geometry.points.shape[:2]
    if velocities is None or velocities.ndim != 3 or velocities.shape[0] != frames:
        raise ModelError(
            '`color_by = "speed"` needs the velocities of the drawn points (the recording\'s '
            "`particle_velocity`, frames × N × 3): recordings of scenes with particles have "
            'them; use color_by = "scene" for this one'
        )
    moving = min(velocities.shape[1], count)
    speed = np.sqrt(np.einsum("fij,fij->fi", velocities[:, :moving], velocities[:, :moving]))
    alive = None if geometry.alive is None else geometry.alive[:, :moving]
    live = speed if alive is None else speed[alive]
    if not np.isfinite(live).all():
        raise ModelError("the recording's velocities are not all finite: they cannot be coloured")
    top = float(np.percentile(live, TOP_PERCENTILE)) if live.size else 0.0
    scale = SpeedScale(top if top > 0.0 else 1.0)
    table = _viridis()
    level = np.minimum(speed * ((_LEVELS - 1) / scale.top), _LEVELS - 1).astype(np.int64)
    color = np.empty((frames, count, 3), dtype=np.float32)
    color[:, :moving] = table[level]
    if moving < count:
        color[:, moving:] = _own_colors(geometry)[..., moving:, :]
    return dataclasses.replace(geometry, color=color), scale


def _own_colors(geometry: Geometry) -> np.ndarray:
    """The recorded colours, ``(P, 3)`` or ``(frames, P, 3)``, or the default grey."""
    if geometry.color is None:
        return np.broadcast_to(np.array(_UNCOLORED, np.float32), (geometry.points.shape[1], 3))
    return np.asarray(geometry.color, dtype=np.float32)


def _viridis() -> np.ndarray:
    """The viridis colour map sampled at :data:`_LEVELS` levels, float32 ``(L, 3)`` sRGB."""
    from matplotlib import colormaps

    return colormaps["viridis"](np.linspace(0.0, 1.0, _LEVELS))[:, :3].astype(np.float32)
