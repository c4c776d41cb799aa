"""Rigid bodies in a glTF 2.0 export: one node per body, moved by its node's channels.

A rigid body needs no per-frame vertex data (Khronos glTF 2.0, § 3.5.3 "Transformations",
§ 3.11 "Animations"): each body is a node showing a mesh of its surface in its own axes, and
one animation sampler each drives its node's ``translation`` (the body's own origin [m]) and
``rotation`` (a unit quaternion, written in glTF's order (x, y, z, w), not visviva's
(w, x, y, z)), keyframe ``k`` at ``k/fps`` seconds with ``LINEAR`` interpolation, which for
rotations is spherical (§ 3.11.1). Consecutive keyframes are in the same hemisphere
(:meth:`ExportFrames.body_transforms_at`), so that importers that interpolate the components
(Blender's quaternion F-curves) turn the short way too.

The body nodes are children of one root node named ``bodies``. Each mesh has ``POSITION``
(float32, with ``min`` and ``max``), unit ``NORMAL`` (the surface's area-weighted vertex
normals) and ``TRIANGLES`` indices, counter-clockwise seen from outside, and its own material
of the body's colour (``baseColorFactor``, linear as glTF wants, not metallic).

The static colliders (:mod:`visviva.simulation.scenery`) are written the same way but never
move: under a root node named ``scenery``, one node per collider (no transform, no channel)
showing a mesh of its surface in the world frame, in its colour.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...simulation.body_geometry import BodyGeometry
from ...simulation.scenery import Scenery
from ._frames import ExportFrames
from ._gltf_buffer import GltfBuffer, linear_rgb

__all__ = ["add_rigid_bodies", "add_scenery"]

#: The normal given to a vertex on no triangle (glTF asks for unit normals on every vertex).
_SPARE_NORMAL = (0.0, 1.0, 0.0)


def _surface_mesh(bodies: BodyGeometry, b: int, data: GltfBuffer, material: int) -> Any:
    """Body ``b``'s surface as a glTF mesh with ``material``."""
    import pygltflib as gl

    vertices, triangles = bodies.surface(b)
    normals = bodies.normals[bodies.vertex_start[b] : bodies.vertex_start[b + 1]].copy()
    normals[~normals.any(axis=1)] = _SPARE_NORMAL
    attributes = gl.Attributes(
        POSITION=data.floats(vertices, gl.VEC3, bounds=True, target=gl.ARRAY_BUFFER),
        NORMAL=data.floats(normals, gl.VEC3, target=gl.ARRAY_BUFFER),
    )
    primitive = gl.Primitive(
        attributes=attributes,
        indices=data.indices(triangles.ravel()),
        mode=gl.TRIANGLES,
        material=material,
    )
    return gl.Mesh(name=bodies.names[b], primitives=[primitive])


def _material(name: str, color: np.ndarray) -> Any:
    """A material of sRGB ``color`` (``(3,)`` in [0, 1]), not metallic."""
    import pygltflib as gl

    return gl.Material(
        name=name,
        pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=[*linear_rgb(color).tolist(), 1.0],
            metallicFactor=0.0,
            roughnessFactor=0.5,
        ),
    )


def add_scenery(
    scenery: Scenery, data: GltfBuffer, nodes: list[Any], meshes: list[Any], materials: list[Any]
) -> int:
    """Append the static colliders' nodes, meshes and materials (see the module docstring).

    Returns:
        The index of the scenery's root node.
    """
    import pygltflib as gl

    surfaces = scenery.as_bodies()
    root = len(nodes)
    nodes.append(gl.Node(name="scenery", children=list(range(root + 1, root + 1 + scenery.count))))
    for c in range(scenery.count):
        materials.append(_material(scenery.names[c], scenery.color[c]))
        meshes.append(_surface_mesh(surfaces, c, data, len(materials) - 1))
        nodes.append(gl.Node(name=scenery.names[c], mesh=len(meshes) - 1))
    return root


def add_rigid_bodies(
    frames: ExportFrames,
    bodies: BodyGeometry,
    data: GltfBuffer,
    nodes: list[Any],
    meshes: list[Any],
    materials: list[Any],
    animation: tuple[list[Any], list[Any]],
) -> int:
    """Append the bodies' nodes, meshes, materials, samplers and channels (see the module
    docstring) to those of the document.

    Args:
        frames: The resampled recording.
        bodies: Its rigid bodies.
        data: The document's buffer.
        nodes, meshes, materials: The document's lists so far, extended in place.
        animation: The samplers and channels of the document's one animation, extended.

    Returns:
        The index of the bodies' root node.
    """
    import pygltflib as gl

    samplers, channels = animation
    times = data.floats(frames.output_times(), gl.SCALAR, bounds=True)
    transforms = [frames.body_transforms_at(k) for k in range(frames.count)]
    origins = np.stack([x for x, _ in transforms], axis=1)  # (B, N, 3)
    turns = np.stack([q for _, q in transforms], axis=1)[..., [1, 2, 3, 0]]  # (x, y, z, w)
    root = len(nodes)
    nodes.append(gl.Node(name="bodies", children=list(range(root + 1, root + 1 + bodies.count))))
    for b in range(bodies.count):
        materials.append(_material(bodies.names[b], bodies.color[b]))
        meshes.append(_surface_mesh(bodies, b, data, len(materials) - 1))
        node = len(nodes)
        nodes.append(
            gl.Node(
                name=bodies.names[b],
                mesh=len(meshes) - 1,
                translation=origins[b, 0].tolist(),
                rotation=turns[b, 0].tolist(),
            )
        )
        for path, values, kind in (
            (gl.TRANSLATION, origins[b], gl.VEC3),
            (gl.ROTATION, turns[b], gl.VEC4),
        ):
            channels.append(
                gl.AnimationChannel(
                    sampler=len(samplers), target=gl.AnimationChannelTarget(node=node, path=path)
                )
            )
            samplers.append(
                gl.AnimationSampler(
                    input=times, output=data.floats(values, kind), interpolation=gl.ANIM_LINEAR
                )
            )
    return root
