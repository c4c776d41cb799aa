"""Resampling recorded frames to a fixed output rate (video, viewer, USD/glTF time codes).

A recording's frames need not be evenly spaced (adaptive runs, a shortened last step). Output
frame ``k`` shows time ``t0 + k·speed/fps``, computed from the integer ``k`` (never by adding
``1/fps`` repeatedly), and uses the recorded frame nearest that time; on a tie, the earlier one.
``speed`` is simulated seconds per second of playback: 1 plays in real time, 86400 a day per
second (an orbit in SI units).
"""

from __future__ import annotations

import math

import numpy as np

from .._validation import real_number
from ..errors import ModelError

__all__ = ["MAX_OUTPUT_FRAMES", "MIN_PLAYBACK", "check_playback", "frames_at_rate"]

#: Output frames closer than this fraction of a frame to the end still count as inside the run.
_END_SLACK = 1e-9
#: Most frames one output may have: a million frames is ~9 hours at 30 frames/s; more is almost
#: surely a rate in the wrong unit or a long run without a ``speed``.
MAX_OUTPUT_FRAMES = 1_000_000
#: Shortest playback of a whole recording [s]: faster is a ``speed`` in the wrong unit.
MIN_PLAYBACK = 1e-3


def check_playback(span: float, speed: float) -> None:
    """Refuse a ``speed`` [simulated s per s] that plays ``span`` [s] of simulation in less than
    :data:`MIN_PLAYBACK` (``speed = 1e308`` would show a run in 1e-307 s: not a video)."""
    if span > 0.0 and span / speed < MIN_PLAYBACK:
        raise ModelError(
            f"`speed` = {speed:g} plays the {span:g} s recorded in {span / speed:.3g} s of "
            f"playback, less than {MIN_PLAYBACK:g} s; use a speed of at most "
            f"{span / MIN_PLAYBACK:.3g} (simulated seconds per second)"
        )


def frames_at_rate(time: np.ndarray, fps: float, *, speed: float = 1.0) -> np.ndarray:
    """Indices into ``time`` of the recorded frame to show at each output frame.

    Args:
        time: Recorded frame times [s], non-decreasing, shape ``(frames,)``.
        fps: Output frames per second [1/s].
        speed: Simulated seconds per second of playback.

    Returns:
        ``int64`` array of length ``floor((until − t0)·fps/speed) + 1``: for output frame ``k``,
        the index of the recorded frame nearest ``t0 + k·speed/fps``.

    Raises:
        ModelError: If that is more than :data:`MAX_OUTPUT_FRAMES` frames (before allocating).

    Example:
        >>> frames_at_rate(np.array([0.0, 0.1, 0.2, 0.3, 0.4]), fps=5.0)
        array([0, 2, 4])
    """
    fps = real_number("fps", fps, positive=True, unit=" frames/s")
    speed = real_number("speed", speed, positive=True, unit=" simulated s per s")
    time = np.asarray(time, dtype=np.float64)
    if time.ndim != 1 or time.size == 0:
        raise ModelError(f"a recording needs at least one frame to resample (got {time.shape})")
    t0, span = time[0], time[-1] - time[0]
    check_playback(float(span), speed)
    rate = fps / speed  # output frames per simulated second
    if span * rate >= MAX_OUTPUT_FRAMES:
        raise ModelError(
            f"{span:g} s of simulation at {fps:g} frames/s and speed {speed:g} is "
            f"{span * rate:.3g} output frames, more than {MAX_OUTPUT_FRAMES}; "
            f"play it faster (speed = simulated seconds per second, e.g. {span / 60:.3g} for "
            "a one-minute clip) or lower fps"
        )
    count = math.floor(span * rate + _END_SLACK) + 1
    wanted = t0 + np.arange(count) * speed / fps
    after = np.clip(np.searchsorted(time, wanted, side="left"), 1, max(1, time.size - 1))
    before = after - 1
    if time.size == 1:
        return np.zeros(count, dtype=np.int64)
    closer_after = (time[after] - wanted) < (wanted - time[before])
    return np.where(closer_after, after, before).astype(np.int64)
