"""Points that are born and die: what each frame of a geometry shows of its points.

Emitters record their particles in a fixed number ``P`` of point slots; ``Geometry.alive``
says which slots hold a live point in each frame, and radii and colours may change from frame
to frame (see :mod:`visviva.simulation.recording`). A dead slot's position means nothing (the
recorder parks it at the origin). Every output (the video, the web viewer, each exporter)
reads the points through this module, so that all of them agree on:

* which points a frame shows, at which radius and in which colour (:class:`Appearance`);
* where each life starts (:func:`life_starts`): a slot reused by a newborn starts a new trail;
* the box the live points fill as drawn (:meth:`Appearance.live_bounds`), which frames the
  video's camera, places its ground and the viewer's grid;
* where a format that must keep every slot in every frame (PC2, glTF tracks, the viewer's
  compressed positions) puts a dead slot (:func:`held_frames`): where its point was last
  alive, or, before its first life, where it is first born. A dead slot then stands still
  instead of streaking to the origin and back, and never widens a bounding box.

Recordings without births and deaths (``alive`` absent) show every point in every frame; their
outputs are those of a recording made before emitters existed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .recording import Geometry

__all__ = ["Appearance", "held_frames", "life_starts"]


@dataclass(frozen=True)
class Appearance:
    """How each point looks in each recorded frame: present or not, its radius, its colour.

    Built once per output (:meth:`of`), since the drawn radius of a recording without radii
    is computed from the bounds of every frame.

    Attributes:
        alive: Which points exist, bool ``(frames, P)``, or ``None`` (all, always).
        radius: Drawn radius [m] (:meth:`Geometry.drawn_radius`), ``(P,)`` or ``(frames, P)``.
        color: sRGB in [0, 1], float32 ``(P, 3)`` or ``(frames, P, 3)``, or ``None`` (the
            output's default colour).
    """

    alive: np.ndarray | None
    radius: np.ndarray
    color: np.ndarray | None

    @classmethod
    def of(cls, geometry: Geometry) -> Appearance:
        """The appearance of ``geometry``'s points (validated by :meth:`Recording.geometry`)."""
        alive = None if geometry.alive is None else np.asarray(geometry.alive, dtype=bool)
        color = None if geometry.color is None else np.asarray(geometry.color, dtype=np.float32)
        return cls(alive, np.asarray(geometry.drawn_radius(), dtype=np.float64), color)

    @property
    def varying_radius(self) -> bool:
        """True if radii change from frame to frame."""
        return self.radius.ndim == 2

    @property
    def varying_color(self) -> bool:
        """True if colours change from frame to frame."""
        return self.color is not None and self.color.ndim == 3

    def alive_at(self, index: int) -> np.ndarray:
        """Which points recorded frame ``index`` shows, bool ``(P,)``."""
        if self.alive is None:
            return np.ones(self.radius.shape[-1], dtype=bool)
        return self.alive[index]

    def radius_at(self, index: int) -> np.ndarray:
        """Drawn radius [m] of every point in recorded frame ``index``, ``(P,)``."""
        return self.radius[index] if self.varying_radius else self.radius

    def color_at(self, index: int) -> np.ndarray | None:
        """Colour of every point in recorded frame ``index``, float32 ``(P, 3)``, or ``None``."""
        if self.color is None:
            return None
        return self.color[index] if self.varying_color else self.color

    def live_bounds(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners [m] of the box holding every live point of every frame as
        drawn, each padded by its radius in that frame; both the origin if none is alive.

        Args:
            points: The positions [m] these points have, ``(frames, P, 3)``.
        """
        if points.shape[0] == 0 or points.shape[1] == 0:
            return np.zeros(3), np.zeros(3)
        if self.alive is None and not self.varying_radius:
            # Each point's extremes over the frames, then its radius: no copy of every frame.
            pad = self.radius[:, None]
            return (points.min(axis=0) - pad).min(axis=0), (points.max(axis=0) + pad).max(axis=0)
        live = np.ones(points.shape[:2], dtype=bool) if self.alive is None else self.alive
        if not live.any():
            return np.zeros(3), np.zeros(3)
        pad = np.broadcast_to(self.radius, live.shape)[..., None]
        where = live[..., None]
        low = np.min(points - pad, axis=(0, 1), where=where, initial=np.inf)
        high = np.max(points + pad, axis=(0, 1), where=where, initial=-np.inf)
        return low, high

    def first_color(self) -> np.ndarray | None:
        """Each point's colour in the first frame it is alive, float32 ``(P, 3)``, or
        ``None``: for formats whose colours cannot change."""
        if self.color is None or not self.varying_color:
            return self.color
        return self._at_first_life(self.color)

    def first_radius(self) -> np.ndarray:
        """Each point's drawn radius [m] in the first frame it is alive, ``(P,)``: for
        formats whose radii cannot change."""
        return self._at_first_life(self.radius) if self.varying_radius else self.radius

    def _at_first_life(self, values: np.ndarray) -> np.ndarray:
        """Per-frame ``values`` ``(frames, P, ...)`` at each point's first live frame (frame 0
        for a point never alive)."""
        first = np.zeros(values.shape[1], dtype=np.intp)
        if self.alive is not None:
            first = np.argmax(self.alive, axis=0)  # 0 where never alive
        return values[first, np.arange(first.size)]


def life_starts(alive: np.ndarray) -> np.ndarray:
    """The frame where each live point's current life began, int ``(frames, P)``.

    Entry ``[k, p]`` is the first frame of the run of live frames of slot ``p`` that holds
    frame ``k``; for a dead slot it is the start of its previous life (or 0), and means
    nothing. A trail of point ``p`` at frame ``k`` goes back no further than this frame.

    Example:
        >>> life_starts(np.array([[1], [1], [0], [1], [1]], dtype=bool)).ravel().tolist()
        [0, 0, 0, 3, 3]
    """
    alive = np.asarray(alive, dtype=bool)
    before = np.zeros_like(alive)
    before[1:] = alive[:-1]
    index = np.arange(alive.shape[0])[:, None]
    return np.maximum.accumulate(np.where(alive & ~before, index, 0), axis=0)


def held_frames(alive: np.ndarray) -> np.ndarray:
    """The recorded frame whose position each slot shows in each frame, int ``(frames, P)``.

    A live slot shows its own frame; a dead one the last frame it was alive, or, before its
    first life, the frame of its first birth; ``-1`` for a slot that is never alive.

    Example:
        >>> held_frames(np.array([[0, 0], [1, 0], [0, 0], [1, 0]], dtype=bool)).tolist()
        [[1, -1], [1, -1], [1, -1], [3, -1]]
    """
    alive = np.asarray(alive, dtype=bool)
    frames = alive.shape[0]
    index = np.arange(frames)[:, None]
    last = np.maximum.accumulate(np.where(alive, index, -1), axis=0)
    upcoming = np.minimum.accumulate(np.where(alive, index, frames)[::-1], axis=0)[::-1]
    held = np.where(last >= 0, last, upcoming)
    return np.where(held < frames, held, -1)


def held_points(
    points: np.ndarray, held: np.ndarray, index: int, fallback: np.ndarray
) -> np.ndarray:
    """Positions [m] of every slot in recorded frame ``index``, dead ones held (float64
    ``(P, 3)``): ``points[held[index, p], p]``, or ``fallback`` for a slot never alive.

    Args:
        points: Recorded positions [m], ``(frames, P, 3)``.
        held: From :func:`held_frames`.
        index: Recorded frame.
        fallback: Position [m] of slots never alive, ``(3,)``: a point among the live ones
            (e.g. the centre of their bounds), so that no box grows to hold it.
    """
    source = held[index]
    slots = np.arange(source.size)
    positions = np.asarray(points[np.maximum(source, 0), slots], dtype=np.float64)
    positions[source < 0] = fallback
    return positions
