"""PC2 point caches: every point's position at every output frame, for Blender and 3ds Max.

The PC2 ("Point Cache 2") layout, as read by Blender's Mesh Cache modifier and written by
3ds Max's Point Cache modifier, is a 32-byte little-endian header followed by the samples::

    char[12]  signature      b"POINTCACHE2\\0"
    int32     file version   1
    int32     point count    P (+ V, the rigid bodies' vertices)
    float32   start frame    0.0: sample 0 is output frame 0
    float32   sample rate    1.0: frames between samples (one sample per output frame)
    int32     sample count   N
    float32   positions      N × P × 3, sample-major, then point, then x, y, z

Positions are float32 [m] in visviva's frame (Y up, unconverted): in Blender, apply the cache
to a mesh imported from the first file of an OBJ export, which keeps the point order and puts
the Y-up to Z-up rotation on the object (see ``docs/export.md``). A cache holds no topology and
no time unit: set the scene's frame rate to the export's ``fps``.

Rigid bodies add their surfaces' vertices after the points, placed where each frame puts
their body (``origin + R(q) v``): the order of an OBJ export's vertices (:mod:`.obj`), so the
cache animates the bodies of the mesh imported from its first file as well as the points.

The point count is fixed by the format. Points that are born and die (particles of emitters)
keep their slot in every sample: a dead point is written where it was last alive, or, before
its first life, where it is first born (:meth:`ExportFrames.held_points_at`), so it stands
still instead of streaking to the recorder's parking place and back. A PC2 file cannot say
that a point is dead: an importer shows such a point where it is held.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ._files import all_or_nothing
from ._frames import ExportFrames

__all__ = ["PC2_SIGNATURE", "write_pc2"]

PC2_SIGNATURE = b"POINTCACHE2\0"
#: Signature, version, point count, start frame, sample rate, sample count.
_HEADER = struct.Struct("<12siiffi")
_VERSION = 1


def write_pc2(frames: ExportFrames, path: Path) -> list[Path]:
    """Write a PC2 point cache of every output frame to ``path`` (atomically).

    Args:
        frames: The resampled recording (:func:`visviva.io.export._frames.prepare`).
        path: Target file; its directory must exist. An existing file is replaced.

    Returns:
        ``[path]``.
    """
    vertices = 0 if frames.bodies is None else frames.bodies.vertices.shape[0]
    count = frames.point_count + vertices
    header = _HEADER.pack(PC2_SIGNATURE, _VERSION, count, 0.0, 1.0, frames.count)
    with all_or_nothing([path]) as (temporary,), temporary.open("wb") as file:
        file.write(header)
        for k in range(frames.count):
            file.write(np.ascontiguousarray(frames.held_points_at(k), dtype="<f4").tobytes())
            if vertices:
                file.write(np.ascontiguousarray(frames.body_vertices_at(k), dtype="<f4").tobytes())
    return [path]
