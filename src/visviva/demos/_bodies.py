"""Recordings of gravitating bodies as drawable recordings (shared by the gravitation demos)."""

from __future__ import annotations

import numpy as np

from ..io.recording import Recording


def drawn_bodies(recording: Recording, lift: float) -> Recording:
    """``recording`` of an n-body problem with the bodies as ``points`` [m], lifted by ``lift``
    [m] above the video's ground plane (orbits lie in the horizontal x–z plane)."""
    q = recording["q"]
    points = q.reshape(q.shape[0], -1, 3).copy()
    points[..., 1] += lift
    return Recording(
        recording.time,
        dict(recording.fields) | {"points": points},
        units=dict(recording.units) | {"points": "m"},
        attrs=recording.attrs,
    )


def body_states(recording: Recording) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities per body, ``(frames, N, 3)`` each."""
    q, v = recording["q"], recording["v"]
    return q.reshape(q.shape[0], -1, 3), v.reshape(v.shape[0], -1, 3)
