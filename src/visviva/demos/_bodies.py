"""Recordings of bodies as drawable recordings (shared by the mechanics and gravitation demos)."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import numpy as np

from ..mechanics.lagrangian import LagrangianSystem
from ..simulation.interrupt import Interrupted
from ..simulation.recording import Recording


@contextlib.contextmanager
def drawn_if_interrupted(draw: Callable[[Recording], Recording]) -> Iterator[None]:
    """Inside, a run that Ctrl-C cuts short keeps its frames drawn by ``draw`` as the finished
    run's would have been: its video, viewer and exports show the same points."""
    try:
        yield
    except Interrupted as stop:
        cut = getattr(stop, "recording", None)
        if cut is not None and cut.frames:
            stop.recording = draw(cut)
        raise


def drawn_system(system: LagrangianSystem, recording: Recording) -> Recording:
    """``recording`` of one run of ``system`` (fields ``q`` and ``v``) with the positions of
    its drawn points [m] per frame, ``system_points`` ``(frames, P, 3)``, and its ``edges``, so
    that the video, the viewer and the exporters can show it."""
    points = system.points(recording["q"], recording.time)
    fields = dict(recording.fields) | {"system_points": points}
    units = dict(recording.units) | {"system_points": "m"}
    static = dict(recording.static)
    if system.edges:
        static["edges"] = np.array(system.edges, dtype=np.int64)
    return Recording(recording.time, fields, units=units, attrs=recording.attrs, static=static)


def drawn_bodies(
    recording: Recording,
    *,
    color: np.ndarray | None = None,
    display_radius: np.ndarray | None = None,
) -> Recording:
    """``recording`` of an n-body problem (fields ``q`` and ``v``, the bodies' coordinates
    flattened) with each quantity once: the bodies drawn as ``system_points`` [m] moving at
    ``system_velocity`` [m/s], ``(frames, N, 3)``, plus the recorded energy; optionally each
    body's sRGB ``system_color`` ``(N, 3)`` and ``display_radius`` [m] ``(N,)`` (see
    :mod:`visviva.simulation.recording`)."""
    x, v = body_states(recording)
    fields = {"system_points": x, "system_velocity": v}
    units = {"system_points": "m", "system_velocity": "m/s", "display_radius": "m"}
    if "energy" in recording:
        fields["energy"] = recording["energy"]
        units["energy"] = recording.units.get("energy", "J")
    static = {
        name: np.asarray(value, dtype=np.float64)
        for name, value in (("system_color", color), ("display_radius", display_radius))
        if value is not None
    }
    return Recording(recording.time, fields, units=units, attrs=recording.attrs, static=static)


def body_states(recording: Recording) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities per body, ``(frames, N, 3)`` each."""
    if "system_points" in recording:
        return recording["system_points"], recording["system_velocity"]
    q, v = recording["q"], recording["v"]
    return q.reshape(q.shape[0], -1, 3), v.reshape(v.shape[0], -1, 3)
