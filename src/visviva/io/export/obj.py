"""Wavefront OBJ sequences: one OBJ file per output frame.

Where the files go depends on ``path``:

* ``path`` ending in ``.obj`` (``out/cloth.obj``): ``out/cloth_0000.obj``, ``out/cloth_0001.obj``
  … next to it (``path`` itself is not written);
* any other ``path`` (``out/obj``): a directory, created if missing, holding
  ``frame_0000.obj``, ``frame_0001.obj`` ….

The number is the output frame ``k`` (time ``k/fps`` after the first recorded frame), padded to
four digits (more when there are over 10,000 frames), so Houdini's ``$F4`` and Blender's
sequence importers find them. Files of the same names are replaced; other files in the
directory are left alone.

Each file uses the OBJ subset every reader knows (Wavefront's "Object Files" appendix of the
Advanced Visualizer manual): ``o`` name, one ``v x y z`` line per point in point order, ``l a b``
per edge and ``f a b c`` per triangle, with 1-based indices. Coordinates are written with
Python's ``repr``, the shortest decimal that reads back as the same float64, so the files hold
the recording's positions exactly (``%.9g`` would only keep float32 precision) at the cost of a
few more characters than needed for display. Units are metres, Y up.

Rigid bodies follow the points: their surfaces' vertices, placed where the frame puts each
body (``origin + R(q) v``, float64 like the points), then, after the points' edges and
triangles, one group per body (``g NAME``) with its triangles. Groups, not ``o`` objects:
Blender's OBJ importer splits objects into separate meshes by default but keeps groups in one,
so the first file of a sequence still matches a PC2 cache of the same points and vertices,
in the same order (:mod:`.pc2`).

Static colliders (spheres, boxes, meshes: :mod:`visviva.simulation.scenery`) do not move, so
they are written once, in a file of their own beside the sequence (``out/cloth_scenery.obj``
or ``out/obj/scenery.obj``), one ``o NAME`` object per collider with its vertices (world frame)
and triangles, and returned after the frames' files. Repeating them in every frame would
only make the files larger and break the vertex match with a PC2 cache. Planes have no
finite surface and are left out.

Points that are born and die (particles of emitters): each file holds only the points alive in
its frame, in point order, with a comment saying how many of the recording's slots they are;
edges and triangles are kept where all their points are alive, renumbered to match. Vertex
``n`` of one file and of the next may then be different particles: a mesh cache (PC2) cannot be
laid on such a sequence.
"""

from __future__ import annotations

import contextlib
import re
from pathlib import Path

import numpy as np

from ...simulation.scenery import Scenery
from ._files import all_or_nothing
from ._frames import ExportFrames

__all__ = ["obj_scenery_path", "obj_sequence_paths", "write_obj_sequence"]

#: Digits of the frame number in file names (more are used when the count needs them).
_MIN_DIGITS = 4


def obj_sequence_paths(path: Path, count: int) -> list[Path]:
    """The files an OBJ export of ``count`` frames to ``path`` writes (see the module docstring).

    Example:
        >>> [p.as_posix() for p in obj_sequence_paths(Path("out/cloth.obj"), 2)]
        ['out/cloth_0000.obj', 'out/cloth_0001.obj']
        >>> obj_sequence_paths(Path("out/obj"), 12000)[-1].as_posix()
        'out/obj/frame_11999.obj'
    """
    digits = max(_MIN_DIGITS, len(str(max(count - 1, 0))))
    if path.suffix.lower() == ".obj":
        folder, stem = path.parent, path.stem
    else:
        folder, stem = path, "frame"
    return [folder / f"{stem}_{k:0{digits}d}.obj" for k in range(count)]


def obj_scenery_path(path: Path) -> Path:
    """The file an OBJ export to ``path`` writes the static colliders to (module docstring).

    Example:
        >>> obj_scenery_path(Path("out/cloth.obj")).as_posix()
        'out/cloth_scenery.obj'
    """
    if path.suffix.lower() == ".obj":
        return path.parent / f"{path.stem}_scenery.obj"
    return path / "scenery.obj"


def _scenery_text(scenery: Scenery) -> str:
    """The static colliders as OBJ text: an ``o`` object per collider (1-based indices)."""
    lines = ["# visviva OBJ export: the static colliders\n", "# units: metres, Y up\n"]
    for c, name in enumerate(scenery.names):
        vertices, triangles = scenery.surface(c)
        lines.append(f"o {_object_name(name)}\n")
        lines.extend(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist())
        start = int(scenery.vertex_start[c]) + 1
        lines.extend(f"f {a} {b} {d}\n" for a, b, d in (triangles + start).tolist())
    return "".join(lines)


def _topology_text(frames: ExportFrames, live: np.ndarray | None = None) -> str:
    """The ``l`` and ``f`` lines (1-based indices): the same in every file, or, given the
    ``live`` mask of a frame, those whose points are all alive, numbered among the live."""
    lines: list[str] = []
    number = None if live is None else np.cumsum(live)  # 1-based vertex number of live points
    for kind, topology in (("l", frames.edges), ("f", frames.faces)):
        if topology is None:
            continue
        if number is not None and live is not None:
            topology = number[topology[live[topology].all(axis=1)]] - 1
        lines.extend(f"{kind} {' '.join(str(i + 1) for i in row)}\n" for row in topology.tolist())
    return "".join(lines)


def _body_text(frames: ExportFrames, first: int) -> str:
    """One ``g`` group per rigid body with its ``f`` lines, its vertices numbered after
    ``first`` vertices (1-based indices)."""
    bodies = frames.bodies
    if bodies is None:
        return ""
    lines: list[str] = []
    for b, name in enumerate(bodies.names):
        lines.append(f"g {_object_name(name)}\n")
        _, triangles = bodies.surface(b)
        start = first + int(bodies.vertex_start[b]) + 1
        lines.extend(f"f {a} {c} {d}\n" for a, c, d in (triangles + start).tolist())
    return "".join(lines)


def _object_name(name: str) -> str:
    """``name`` as one OBJ token (OBJ statements split on white space)."""
    return re.sub(r"\s+", "_", name)


def write_obj_sequence(frames: ExportFrames, path: Path) -> list[Path]:
    """Write one OBJ file per output frame; all files appear, or none does.

    Args:
        frames: The resampled recording (:func:`visviva.io.export._frames.prepare`).
        path: ``something.obj`` (files next to it) or a directory (created if missing; its
            parent must exist).

    Returns:
        The files written, in frame order, then the static colliders' file (if any).
    """
    targets = obj_sequence_paths(path, frames.count)
    if frames.geometry.scenery is not None:
        targets.append(obj_scenery_path(path))
    created = path.suffix.lower() != ".obj" and not path.exists()
    if created:
        path.mkdir()
    topology = _topology_text(frames)
    body_faces = _body_text(frames, frames.point_count)
    vertex_line = "v %r %r %r\n"
    name = _object_name(frames.name)
    try:
        with all_or_nothing(targets) as temporaries:
            if frames.geometry.scenery is not None:
                temporaries[-1].write_text(_scenery_text(frames.geometry.scenery), "utf-8")
            for k, temporary in enumerate(temporaries[: frames.count]):
                shown = int(frames.shown[k])
                header = (
                    f"# visviva OBJ export: frame {k} of {frames.count} at {frames.fps:.9g} "
                    f"frames/s (recorded frame {shown}, t = {float(frames.time[shown])!r} s)\n"
                    "# units: metres, Y up\n"
                    f"o {name}\n"
                )
                positions = frames.points_at(k)
                if frames.lifecycle:
                    live = frames.alive_at(k)
                    positions = positions[live]
                    header += f"# {positions.shape[0]} of {frames.point_count} points alive\n"
                    topology = _topology_text(frames, live)
                    body_faces = _body_text(frames, positions.shape[0])
                if frames.bodies is not None:
                    positions = np.concatenate([positions, frames.body_vertices_at(k)])
                values = tuple(positions.ravel().tolist())
                vertices = (vertex_line * positions.shape[0]) % values
                text = header + vertices + topology + body_faces
                temporary.write_text(text, encoding="utf-8")
    except BaseException:
        if created:
            # Only the directory this call made, and only if nothing else appeared in it.
            with contextlib.suppress(OSError):
                path.rmdir()
        raise
    return targets
