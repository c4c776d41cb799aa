"""glTF 2.0 export: moving bodies as animated sphere nodes, anything else as morph targets,
rigid bodies as nodes moved by their transforms.

Follows the Khronos glTF 2.0 specification (sections cited as § of version 2.0.1), written
with ``pygltflib``. The recording's points take one of two layouts, chosen by what it shows:

* **Bodies** — points without edges or faces, at most :data:`MAX_BODY_NODES` of them (planets,
  stars of a small cluster, the bobs of a pendulum drawn as points): one node per point
  (§ 3.5) under a root node named after the scene, each showing one shared unit-sphere mesh
  scaled to the point's radius, with a ``LINEAR`` animation of its ``translation`` (§ 3.11).
  They import into Blender as spheres that move, at ``12·N`` bytes per point for ``N`` frames.
* **Mesh** — anything else (cloth, ropes, thousands of particles): one node with one mesh
  (§ 3.7.2) whose base ``POSITION`` is output frame 0 and whose morph target ``k``
  (§ 3.7.2.2) holds the displacement of frame ``k`` from frame 0, played by a ``STEP``
  animation of the node's ``weights`` that shows target ``k`` alone at ``k/fps``. The weights
  are a sparse accessor (§ 3.6.2.3): zeros but for one 1 per keyframe, so they take ``8·N``
  bytes instead of the ``4·N²`` of a dense one. Primitives by topology (§ 3.7.2.1):
  ``TRIANGLES`` for faces (counter-clockwise seen from outside), ``LINES`` for edges,
  ``POINTS`` for points used by neither, with their radii as the application-specific
  attribute ``_RADIUS`` [m] (§ 3.7.2.1: names starting with an underscore), for instancing
  spheres on them (Blender: Geometry Nodes → Instance on Points, radius from the attribute).

Colours (§ 3.9: glTF colours are linear, so the recording's sRGB is converted): bodies get one
material per distinct colour (``baseColorFactor``, not metallic), which every importer applies
to a triangle mesh; the points of the mesh layout carry ``COLOR_0`` (§ 3.7.2.1), as points have
no material worth the name. Neither can change over time: a colour that changes is written as
the point's colour in the first frame it is alive.

Points that are born and die (particles of emitters; :mod:`visviva.simulation.lifetimes`): glTF has
no varying point count. Bodies get a ``STEP`` animation of each node's ``scale``: the point's
radius while it lives (and as it changes), 0 while it is dead, which collapses its sphere to
nothing; a dead node's translation holds where the point was last alive (before its first
life, where it is first born), so it never glides across the scene. In the mesh layout a dead
point is moved onto the live point of the largest radius in the same frame (onto one place,
the first-born point's, in a frame with no live point at all), so it adds no dot of its own
and no extent; its ``_RADIUS`` and ``COLOR_0`` are those of its first life.

Rigid bodies (:mod:`._gltf_rigid`) are added beside either layout, or alone: one node per
body showing its surface, with ``translation`` and ``rotation`` channels and no per-frame
vertex data. The document has one animation, ``simulation``, holding every channel. The static
colliders (spheres, boxes, meshes; not planes) are a root node ``scenery`` of static meshes,
one node per collider, in the world frame, without channels.

All: glTF time starts at 0 (the recording's first frame); every ``POSITION`` accessor and the
animation input have ``min`` and ``max`` (§ 3.6.2.5, § 3.11); buffer views start on 4-byte
boundaries (§ 3.6.2.4); the scene's rate, speed and start time are in ``asset.extras``.
glTF carries no scene frame rate or frame range: importers sample the animation at their own
rate (Blender: the scene's, 24 frames/s by default), so exports default to a whole number of
frames per second and ``docs/export.md`` gives the steps to match it.

Containers (§ 4.4 "GLB File Format Specification"): a ``.glb`` holds the JSON and the binary
buffer in one file; a ``.gltf`` is the JSON, with the buffer in a ``.bin`` file of the same
stem next to it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from ..._version import __version__
from ...errors import ModelError
from ._files import all_or_nothing
from ._frames import ExportFrames
from ._gltf_buffer import GltfBuffer, linear_rgb
from ._gltf_rigid import add_rigid_bodies, add_scenery

__all__ = ["MAX_BODY_NODES", "MAX_GLTF_BYTES", "MAX_MORPH_FRAMES", "gltf_size", "write_gltf"]

#: Largest glTF buffer an export may write [bytes] (1 GiB; a GLB can hold at most 4 GiB and
#: importers hold the whole buffer, and a shape key per frame, in memory).
MAX_GLTF_BYTES = 2**30
#: Most points exported as sphere nodes; more become one mesh (an importer makes an object
#: per node, which thousands of particles would drown in).
MAX_BODY_NODES = 256
#: Most frames of a morph-target export: the sparse weights address N² entries with 32-bit
#: indices (and Blender makes a shape key per frame).
MAX_MORPH_FRAMES = 65_535
#: Segments around and rings of the unit sphere the bodies show.
_SPHERE_SEGMENTS, _SPHERE_RINGS = 24, 12
#: Bytes of one float32 VEC3, and of one float32 or uint32 scalar.
_VEC3_BYTES = 12
_SCALAR_BYTES = 4


def _unit_sphere() -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere of radius 1: vertices (also its normals), float32 ``(V, 3)``, and
    counter-clockwise triangles seen from outside, uint32 ``(T, 3)``."""
    rings, segments = _SPHERE_RINGS, _SPHERE_SEGMENTS
    polar = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    around = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    sin_p, cos_p = np.sin(polar)[:, None], np.cos(polar)[:, None]
    body = np.stack(
        [
            sin_p * np.cos(around),
            np.broadcast_to(cos_p, (rings - 1, segments)),
            -sin_p * np.sin(around),
        ],
        axis=-1,
    ).reshape(-1, 3)
    vertices = np.concatenate([[[0.0, 1.0, 0.0]], body, [[0.0, -1.0, 0.0]]]).astype(np.float32)
    south = len(vertices) - 1

    def ring(r: int, s: int) -> int:
        return 1 + r * segments + s % segments

    triangles = [(0, ring(0, s), ring(0, s + 1)) for s in range(segments)]
    for r in range(rings - 2):
        for s in range(segments):
            a, b = ring(r, s), ring(r, s + 1)
            c, d = ring(r + 1, s), ring(r + 1, s + 1)
            triangles += [(a, c, b), (b, c, d)]
    triangles += [(ring(rings - 2, s), south, ring(rings - 2, s + 1)) for s in range(segments)]
    return vertices, np.asarray(triangles, dtype=np.uint32)


def _as_bodies(frames: ExportFrames) -> bool:
    return frames.edges is None and frames.faces is None and frames.point_count <= MAX_BODY_NODES


def _primitive_indices(frames: ExportFrames) -> list[tuple[int, np.ndarray | None]]:
    """(glTF primitive mode, indices or ``None`` for all points in order) per primitive."""
    import pygltflib

    primitives: list[tuple[int, np.ndarray | None]] = []
    if frames.faces is not None:
        primitives.append((pygltflib.TRIANGLES, frames.faces.ravel()))
    if frames.edges is not None:
        primitives.append((pygltflib.LINES, frames.edges.ravel()))
    loose = frames.loose_points(faces=True, edges=True)
    if loose.size == frames.point_count:
        primitives.append((pygltflib.POINTS, None))
    elif loose.size:
        primitives.append((pygltflib.POINTS, loose))
    return primitives


def gltf_size(point_count: int, frame_count: int, index_count: int = 0) -> int:
    """Bytes of the binary buffer of a mesh-layout glTF export (the bodies' is smaller).

    Args:
        point_count: Points ``P``.
        frame_count: Output frames ``N``.
        index_count: Indices of all primitives (3 per face, 2 per edge, 1 per loose point).

    Example:
        >>> round(gltf_size(point_count=1000, frame_count=300) / 2**20, 2)   # MiB
        3.45
    """
    positions = (frame_count + 1) * point_count * _VEC3_BYTES
    radii = point_count * _SCALAR_BYTES
    animation = 3 * frame_count * _SCALAR_BYTES  # times, sparse indices, sparse values
    return positions + radii + animation + index_count * _SCALAR_BYTES


def _check_size(frames: ExportFrames, index_count: int) -> None:
    points, count = frames.point_count, frames.count
    size = gltf_size(points, count, index_count)
    if size <= MAX_GLTF_BYTES and count <= MAX_MORPH_FRAMES:
        return
    per_frame = points * _VEC3_BYTES + 3 * _SCALAR_BYTES
    fits = min(MAX_MORPH_FRAMES, (MAX_GLTF_BYTES - index_count * _SCALAR_BYTES) // per_frame - 1)
    span = float(frames.time[-1] - frames.time[0]) / frames.speed  # seconds of playback
    advice = (
        f"pass fps ≤ {(fits - 1) / span:.3g} frames/s, or export to usd or pc2"
        if fits >= 2 and span > 0.0
        else "export to usd or pc2, which have no such limit"
    )
    mib = 2**20
    raise ModelError(
        f"a glTF export of {count} frames × {points} points needs {size / mib:.0f} MiB of "
        f"morph targets; glTF exports hold at most {MAX_GLTF_BYTES / mib:.0f} MiB "
        f"(MAX_GLTF_BYTES) and {MAX_MORPH_FRAMES} frames; {advice}"
    )


class _Layout:
    """What one layout adds to the document: nodes (root first), meshes, materials and the
    animation."""

    def __init__(
        self, nodes: list[Any], meshes: list[Any], animation: Any, materials: list[Any]
    ) -> None:
        self.nodes, self.meshes, self.animation, self.materials = (
            nodes,
            meshes,
            animation,
            materials,
        )


def _sphere_meshes(
    frames: ExportFrames, data: GltfBuffer
) -> tuple[list[Any], list[Any], np.ndarray]:
    """The unit-sphere meshes (one per distinct colour, sharing the sphere's accessors), their
    materials, and the mesh each point shows."""
    import pygltflib as gl

    vertices, triangles = _unit_sphere()
    position = data.floats(vertices, gl.VEC3, bounds=True, target=gl.ARRAY_BUFFER)
    normal = data.floats(vertices, gl.VEC3, target=gl.ARRAY_BUFFER)
    indices = data.indices(triangles.ravel())
    colours = frames.look.first_color()
    if colours is None:
        palette, which = [None], np.zeros(frames.point_count, dtype=np.intp)
    else:
        unique, which = np.unique(colours, axis=0, return_inverse=True)
        palette = list(unique)
    meshes: list[Any] = []
    materials: list[Any] = []
    for j, colour in enumerate(palette):
        material = None
        if colour is not None:
            material = len(materials)
            materials.append(
                gl.Material(
                    name=f"colour_{j:03d}",
                    pbrMetallicRoughness=gl.PbrMetallicRoughness(
                        baseColorFactor=[*linear_rgb(colour).tolist(), 1.0],
                        metallicFactor=0.0,
                        roughnessFactor=0.5,
                    ),
                )
            )
        meshes.append(
            gl.Mesh(
                name="sphere" if colour is None else f"sphere_{j:03d}",
                primitives=[
                    gl.Primitive(
                        attributes=gl.Attributes(POSITION=position, NORMAL=normal),
                        indices=indices,
                        mode=gl.TRIANGLES,
                        material=material,
                    )
                ],
            )
        )
    return meshes, materials, np.ravel(which)


def _bodies(frames: ExportFrames, data: GltfBuffer) -> _Layout:
    """Nodes (root first), sphere meshes, materials and the animation of the bodies layout."""
    import pygltflib as gl

    meshes, materials, which = _sphere_meshes(frames, data)
    times = data.floats(frames.output_times(), gl.SCALAR, bounds=True)
    # Dead points held where they were last alive: translations never streak while hidden.
    tracks = np.stack([frames.held_points_at(k) for k in range(frames.count)], axis=1)  # (P, N, 3)
    animated_size = frames.lifecycle or frames.look.varying_radius
    sizes = np.stack(
        [frames.radius_at(k) * frames.alive_at(k) for k in range(frames.count)], axis=1
    )  # (P, N): 0 while dead
    nodes = [gl.Node(name=frames.name, children=list(range(1, frames.point_count + 1)))]
    samplers, channels = [], []
    for i in range(frames.point_count):
        nodes.append(
            gl.Node(
                name=f"point_{i:04d}",
                mesh=int(which[i]),
                translation=tracks[i, 0].tolist(),
                scale=[float(sizes[i, 0])] * 3,
            )
        )
        samplers.append(
            gl.AnimationSampler(
                input=times, output=data.floats(tracks[i], gl.VEC3), interpolation=gl.ANIM_LINEAR
            )
        )
        channels.append(
            gl.AnimationChannel(
                sampler=i, target=gl.AnimationChannelTarget(node=i + 1, path=gl.TRANSLATION)
            )
        )
    if animated_size:
        # STEP: a point appears and vanishes at its frame, not over the interval before.
        for i in range(frames.point_count):
            scale = np.repeat(sizes[i][:, None], 3, axis=1)
            channels.append(
                gl.AnimationChannel(
                    sampler=len(samplers),
                    target=gl.AnimationChannelTarget(node=i + 1, path=gl.SCALE),
                )
            )
            samplers.append(
                gl.AnimationSampler(
                    input=times, output=data.floats(scale, gl.VEC3), interpolation=gl.ANIM_STEP
                )
            )
    animation = gl.Animation(name="simulation", samplers=samplers, channels=channels)
    return _Layout(nodes, meshes, animation, materials)


def _collapsed_points_at(frames: ExportFrames, k: int, gathering: int) -> np.ndarray:
    """Positions [m] at output frame ``k`` with every dead point moved onto the live point of
    the largest radius (onto slot ``gathering``'s held position if none is alive)."""
    positions = frames.held_points_at(k)
    alive = frames.alive_at(k)
    if alive.all():
        return positions
    if alive.any():
        radius = np.where(alive, frames.radius_at(k), -np.inf)
        positions[~alive] = positions[int(np.argmax(radius))]
    else:
        positions[:] = positions[gathering]
    return positions


def _mesh(frames: ExportFrames, data: GltfBuffer) -> _Layout:
    """Node, mesh with morph targets and the weight animation of the mesh layout."""
    import pygltflib as gl

    primitives = _primitive_indices(frames)
    _check_size(frames, sum(0 if i is None else i.size for _, i in primitives))
    count = frames.count
    if frames.lifecycle:
        alive = frames.look.alive
        gathering = int(np.argmax(alive.any(axis=0))) if alive is not None else 0
        positions = [_collapsed_points_at(frames, k, gathering) for k in range(count)]
        first = positions[0]
    else:
        positions = None
        first = frames.points_at(0)
    # Displacements are rounded once, from float64: base + target k is frame k to within
    # float32 rounding of the position and of the displacement.
    base = data.floats(first, gl.VEC3, bounds=True, target=gl.ARRAY_BUFFER)
    targets = [
        gl.Attributes(
            POSITION=data.floats(
                (frames.points_at(k) if positions is None else positions[k]) - first,
                gl.VEC3,
                bounds=True,
            )
        )
        for k in range(count)
    ]
    radius = data.floats(frames.look.first_radius(), gl.SCALAR, target=gl.ARRAY_BUFFER)
    colours = frames.look.first_color()
    colour = None
    if colours is not None:
        colour = data.floats(linear_rgb(colours), gl.VEC3, target=gl.ARRAY_BUFFER)
    mesh_primitives = []
    for mode, indices in primitives:
        attributes = gl.Attributes(POSITION=base)
        if mode == gl.POINTS:
            attributes._RADIUS = radius
            if colour is not None:
                attributes.COLOR_0 = colour
        mesh_primitives.append(
            gl.Primitive(
                attributes=attributes,
                indices=None if indices is None else data.indices(indices),
                mode=mode,
                targets=targets,
            )
        )
    mesh = gl.Mesh(
        name=frames.name,
        primitives=mesh_primitives,
        weights=[1.0] + [0.0] * (count - 1),
        extras={"targetNames": [f"frame_{k:04d}" for k in range(count)]},
    )
    times = data.floats(frames.output_times(), gl.SCALAR, bounds=True)
    diagonal = np.arange(count, dtype=np.uint64) * (count + 1)  # keyframe k shows target k
    weights = data.accessor(
        componentType=gl.FLOAT,
        count=count * count,
        type=gl.SCALAR,
        sparse=gl.Sparse(
            count=count,
            indices=gl.AccessorSparseIndices(
                bufferView=data.view(diagonal.astype("<u4")), componentType=gl.UNSIGNED_INT
            ),
            values=gl.AccessorSparseValues(bufferView=data.view(np.ones(count, dtype="<f4"))),
        ),
    )
    animation = gl.Animation(
        name="simulation",
        samplers=[gl.AnimationSampler(input=times, output=weights, interpolation=gl.ANIM_STEP)],
        channels=[
            gl.AnimationChannel(
                sampler=0, target=gl.AnimationChannelTarget(node=0, path=gl.WEIGHTS)
            )
        ],
    )
    return _Layout([gl.Node(mesh=0, name=frames.name)], [mesh], animation, [])


def write_gltf(frames: ExportFrames, path: Path, *, binary: bool) -> list[Path]:
    """Write the resampled recording as glTF 2.0 (see the module docstring), atomically.

    Args:
        frames: The resampled recording (:func:`visviva.io.export._frames.prepare`).
        path: Target file (``.glb`` or ``.gltf``); its directory must exist. Existing files
            are replaced.
        binary: ``True`` for one ``.glb`` file, ``False`` for a ``.gltf`` and its ``.bin``.

    Returns:
        The files written: ``[path]``, or ``[path, path.with_suffix(".bin")]``.

    Raises:
        ModelError: If a mesh export would exceed :data:`MAX_GLTF_BYTES` or
            :data:`MAX_MORPH_FRAMES`.
    """
    import pygltflib as gl

    data = GltfBuffer()
    nodes: list[Any] = []
    meshes: list[Any] = []
    materials: list[Any] = []
    samplers: list[Any] = []
    channels: list[Any] = []
    roots = []
    if frames.point_count:
        layout = (_bodies if _as_bodies(frames) else _mesh)(frames, data)
        nodes, meshes, materials = layout.nodes, layout.meshes, layout.materials
        samplers, channels = layout.animation.samplers, layout.animation.channels
        roots.append(0)
    if frames.bodies is not None:
        animation = (samplers, channels)
        roots.append(
            add_rigid_bodies(frames, frames.bodies, data, nodes, meshes, materials, animation)
        )
    if frames.geometry.scenery is not None:
        roots.append(add_scenery(frames.geometry.scenery, data, nodes, meshes, materials))
    document = gl.GLTF2(
        asset=gl.Asset(
            generator=f"visviva {__version__}",
            version="2.0",
            extras={
                "fps": frames.fps,
                "speed": frames.speed,
                "start_time_s": float(frames.time[0]),
                "frames": frames.count,
                "units": "m",
            },
        ),
        scene=0,
        scenes=[gl.Scene(nodes=roots)],
        nodes=nodes,
        meshes=meshes,
        materials=materials,
        accessors=data.accessors,
        bufferViews=data.views,
        animations=[gl.Animation(name="simulation", samplers=samplers, channels=channels)],
    )
    blob = data.blob()
    if binary:
        document.buffers = [gl.Buffer(byteLength=len(blob))]
        document.set_binary_blob(blob)
        with all_or_nothing([path]) as (temporary,), temporary.open("wb") as file:
            for chunk in document.save_to_bytes():
                file.write(chunk)
        return [path]
    sidecar = path.with_suffix(".bin")
    document.buffers = [gl.Buffer(byteLength=len(blob), uri=quote(sidecar.name))]
    with all_or_nothing([path, sidecar]) as (json_file, bin_file):
        json_file.write_text(document.gltf_to_json(), encoding="utf-8")
        bin_file.write_bytes(blob)
    return [path, sidecar]
