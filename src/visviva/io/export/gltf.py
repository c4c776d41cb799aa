"""glTF 2.0 export: one mesh whose morph targets are the frames, played by a STEP animation.

Follows the Khronos glTF 2.0 specification (sections cited as § of version 2.0.1), written
with ``pygltflib``:

* one node with one mesh (§ 3.5, § 3.7.2). Its base ``POSITION`` (float32 VEC3) is output
  frame 0; morph target ``k`` (§ 3.7.2.2) holds the displacement of output frame ``k`` from
  frame 0, so target 0 is all zeros and ``base + target k`` is frame ``k``. The targets'
  names (``frame_0000`` …) are in ``mesh.extras.targetNames``, which Blender uses for shape
  key names;
* primitives by topology (§ 3.7.2.1): ``TRIANGLES`` for faces (counter-clockwise seen from
  outside, as glTF's front faces are), ``LINES`` for edges, ``POINTS`` for the points used by
  neither (all points when there is no topology). Primitives share the position accessors;
* one animation (§ 3.11) with one ``STEP`` sampler on the node's ``weights``: keyframe ``k``
  at ``k/fps`` seconds sets the weight vector to the one-hot vector of target ``k``. glTF time
  starts at 0 (the recording's first frame);
* every ``POSITION`` accessor has ``min`` and ``max`` and the animation input has them too
  (§ 3.6.2.5, § 3.11); every buffer view starts on a 4-byte boundary (§ 3.6.2.4), and the
  positions share one view with ``byteStride = 12`` (required when attribute accessors share a
  view, § 3.6.2.4). Indices are ``UNSIGNED_INT``.

Containers (§ 4.4 "GLB File Format Specification"): a ``.glb`` holds the JSON and the binary
buffer in one file; a ``.gltf`` is the JSON, with the buffer in a ``.bin`` file of the same
stem next to it.

Size. The positions take ``(N + 1) · P · 12`` bytes and the animation's weights ``N² · 4``
(one weight per target per keyframe), for ``N`` output frames and ``P`` points; exports above
:data:`MAX_GLTF_BYTES` are refused before anything is allocated. Blender turns every target
into a shape key: glTF suits hundreds of frames; USD or PC2 suit long animations.
"""

from __future__ import annotations

import math
from pathlib import Path
from urllib.parse import quote

import numpy as np

from ..._version import __version__
from ...errors import ModelError
from ._files import all_or_nothing
from ._frames import ExportFrames

__all__ = ["MAX_GLTF_BYTES", "gltf_size", "write_gltf"]

#: Largest glTF buffer an export may write [bytes] (1 GiB; a GLB can hold at most 4 GiB and
#: importers hold the whole buffer, and a shape key per frame, in memory).
MAX_GLTF_BYTES = 2**30
#: Bytes of one float32 VEC3.
_VEC3_BYTES = 12
#: Bytes of one float32 or uint32 scalar.
_SCALAR_BYTES = 4


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
    """Bytes of the binary buffer of a glTF export.

    Args:
        point_count: Points ``P``.
        frame_count: Output frames ``N``.
        index_count: Indices of all primitives (3 per face, 2 per edge, 1 per loose point).

    Example:
        >>> round(gltf_size(point_count=1000, frame_count=300) / 2**20, 2)   # MiB
        3.79
    """
    positions = (frame_count + 1) * point_count * _VEC3_BYTES
    animation = (frame_count * frame_count + frame_count) * _SCALAR_BYTES
    return positions + animation + index_count * _SCALAR_BYTES


def _round_down(value: float, digits: int = 3) -> float:
    """``value`` > 0 cut to ``digits`` significant digits, never rounded up (advice must fit)."""
    scale = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    return math.floor(value / scale) * scale


def _check_size(frames: ExportFrames, index_count: int) -> None:
    points, count = frames.point_count, frames.count
    size = gltf_size(points, count, index_count)
    if size <= MAX_GLTF_BYTES:
        return
    # Largest N with 4N² + (12P + 4)N + 12P + 4I <= limit.
    b = points * _VEC3_BYTES + _SCALAR_BYTES
    c = points * _VEC3_BYTES + index_count * _SCALAR_BYTES - MAX_GLTF_BYTES
    fits = math.floor((-b + math.sqrt(b * b - 16 * c)) / 8) if c <= 0 else 0
    span = float(frames.time[-1] - frames.time[0]) / frames.speed  # seconds of playback
    if fits >= 2 and span > 0.0:
        advice = f"pass fps ≤ {_round_down((fits - 1) / span):g} frames/s, or export to usd or pc2"
    else:
        advice = "export to usd or pc2, which have no such limit"
    mib = 2**20
    raise ModelError(
        f"a glTF export of {count} frames × {points} points needs {size / mib:.0f} MiB "
        f"({(count + 1) * points * _VEC3_BYTES / mib:.0f} MiB of morph targets, "
        f"{count * count * _SCALAR_BYTES / mib:.0f} MiB of animation weights), more than the "
        f"limit of {MAX_GLTF_BYTES / mib:.0f} MiB (MAX_GLTF_BYTES); {advice}"
    )


def _bounds(values: np.ndarray) -> tuple[list[float], list[float]]:
    """Per-component ``min`` and ``max`` of float32 rows, as exact JSON numbers."""
    return values.min(axis=0).tolist(), values.max(axis=0).tolist()


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
        ModelError: If the buffer would exceed :data:`MAX_GLTF_BYTES`.
    """
    import pygltflib as gl

    primitives = _primitive_indices(frames)
    index_count = sum(0 if indices is None else indices.size for _, indices in primitives)
    _check_size(frames, index_count)
    points, count = frames.point_count, frames.count
    frame_bytes = points * _VEC3_BYTES

    # One allocation for the whole buffer; every part is written straight into its place.
    buffer = np.zeros(gltf_size(points, count, index_count), dtype=np.uint8)
    views: list[gl.BufferView] = []
    accessors: list[gl.Accessor] = []
    offset = 0

    def view(length: int, **options: int) -> tuple[int, np.ndarray]:
        nonlocal offset
        views.append(gl.BufferView(buffer=0, byteOffset=offset, byteLength=length, **options))
        part = buffer[offset : offset + length]
        offset += length  # every part is a whole number of 4-byte values: stays aligned
        return len(views) - 1, part

    position_view, raw = view((count + 1) * frame_bytes, byteStride=12, target=gl.ARRAY_BUFFER)
    positions = raw.view("<f4").reshape(count + 1, points, 3)
    first = frames.points_at(0)
    positions[0] = first
    for k in range(count):
        # Displacements are rounded once, from float64: base + target k is frame k to within
        # float32 rounding of the position and of the displacement.
        positions[k + 1] = frames.points_at(k) - first
    for k in range(count + 1):
        low, high = _bounds(positions[k])
        accessors.append(
            gl.Accessor(
                bufferView=position_view,
                byteOffset=k * frame_bytes,
                componentType=gl.FLOAT,
                count=points,
                type=gl.VEC3,
                min=low,
                max=high,
            )
        )

    index_accessor: list[int | None] = []
    for _, indices in primitives:
        if indices is None:
            index_accessor.append(None)
            continue
        index_view, raw = view(indices.size * _SCALAR_BYTES, target=gl.ELEMENT_ARRAY_BUFFER)
        raw.view("<u4")[:] = indices
        accessors.append(
            gl.Accessor(
                bufferView=index_view,
                componentType=gl.UNSIGNED_INT,
                count=int(indices.size),
                type=gl.SCALAR,
            )
        )
        index_accessor.append(len(accessors) - 1)

    time_view, raw = view(count * _SCALAR_BYTES)
    times = raw.view("<f4")
    times[:] = frames.output_times()
    accessors.append(
        gl.Accessor(
            bufferView=time_view,
            componentType=gl.FLOAT,
            count=count,
            type=gl.SCALAR,
            min=[float(times[0])],
            max=[float(times[-1])],
        )
    )
    weight_view, raw = view(count * count * _SCALAR_BYTES)
    weights = raw.view("<f4").reshape(count, count)
    weights[np.arange(count), np.arange(count)] = 1.0  # keyframe k shows target k only
    accessors.append(
        gl.Accessor(
            bufferView=weight_view, componentType=gl.FLOAT, count=count * count, type=gl.SCALAR
        )
    )
    time_accessor, weight_accessor = len(accessors) - 2, len(accessors) - 1

    targets = [gl.Attributes(POSITION=k + 1) for k in range(count)]
    mesh = gl.Mesh(
        name=frames.name,
        primitives=[
            gl.Primitive(
                attributes=gl.Attributes(POSITION=0), indices=index, mode=mode, targets=targets
            )
            for (mode, _), index in zip(primitives, index_accessor, strict=True)
        ],
        weights=[1.0] + [0.0] * (count - 1),
        extras={"targetNames": [f"frame_{k:04d}" for k in range(count)]},
    )
    animation = gl.Animation(
        name="simulation",
        samplers=[
            gl.AnimationSampler(
                input=time_accessor, output=weight_accessor, interpolation=gl.ANIM_STEP
            )
        ],
        channels=[
            gl.AnimationChannel(
                sampler=0, target=gl.AnimationChannelTarget(node=0, path=gl.WEIGHTS)
            )
        ],
    )
    document = gl.GLTF2(
        asset=gl.Asset(
            generator=f"visviva {__version__}",
            version="2.0",
            extras={
                "fps": frames.fps,
                "speed": frames.speed,
                "start_time_s": float(frames.time[0]),
                "units": "m",
            },
        ),
        scene=0,
        scenes=[gl.Scene(nodes=[0])],
        nodes=[gl.Node(mesh=0, name=frames.name)],
        meshes=[mesh],
        accessors=accessors,
        bufferViews=views,
        animations=[animation],
    )

    if binary:
        document.buffers = [gl.Buffer(byteLength=buffer.size)]
        document.set_binary_blob(buffer.data)
        with all_or_nothing([path]) as (temporary,), temporary.open("wb") as file:
            for chunk in document.save_to_bytes():
                file.write(chunk)
        return [path]
    sidecar = path.with_suffix(".bin")
    document.buffers = [gl.Buffer(byteLength=buffer.size, uri=quote(sidecar.name))]
    with all_or_nothing([path, sidecar]) as (json_file, bin_file):
        json_file.write_text(document.gltf_to_json(), encoding="utf-8")
        buffer.tofile(bin_file)
    return [path, sidecar]
