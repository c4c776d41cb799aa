"""Exporters (USD, glTF 2.0, OBJ sequences, PC2), each file re-read by an independent reader.

USD is read back with ``pxr``, glTF with ``pygltflib`` (accessors decoded here with NumPy, morph
target k added to the base), OBJ and PC2 with the small parsers below. Positions are compared at
the first, middle and last output frame against the recorded frames that
:func:`visviva.io.timeline.frames_at_rate` selects: exactly for OBJ (float64 text), to float32
precision elsewhere (``FLOAT32_RTOL`` times the scene size).
"""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pygltflib
import pytest
from pxr import Usd, UsdGeom

import visviva as vv
from visviva.errors import ModelError
from visviva.io.export import EXPORT_FORMATS, default_fps, export_recording
from visviva.io.export._frames import ExportFrames
from visviva.io.export.gltf import MAX_BODY_NODES, MAX_GLTF_BYTES, MAX_MORPH_FRAMES, gltf_size
from visviva.io.timeline import frames_at_rate

#: Relative accuracy of float32 storage, with margin: two roundings (glTF base + displacement).
FLOAT32_RTOL = 1e-6
#: Output rate of most tests [frames/s]; the recordings are at 50 Hz, so frames are resampled.
FPS = 24.0
FRAMES = 60
RATE = 50.0


def moving_points(frames: int = FRAMES, *, static: dict[str, Any] | None = None) -> vv.Recording:
    """Four points 1 m apart falling (y = 2 − g t²/2) and swaying in z, each at its own rate."""
    t = np.arange(frames) / RATE
    points = np.zeros((frames, 4, 3))
    points[:, :, 0] = [0.0, 1.0, 2.0, 3.0] + 0.1 * np.cos(3.0 * t[:, None])
    points[:, :, 1] = 2.0 - 4.9 * t[:, None] ** 2
    points[:, :, 2] = np.sin(t[:, None] * np.array([1.0, 2.0, 3.0, 4.0]))
    arrays = {"particle_radius": np.array([0.1, 0.05, 0.2, 0.1])} | (static or {})
    return vv.Recording(
        t,
        {"particle_position": points},
        static=arrays,
        units={"particle_position": "m", "particle_radius": "m"},
    )


def quad() -> vv.Recording:
    """A 1 m square of two triangles (counter-clockwise from +y) that folds and rises."""
    recording = moving_points(static={"faces": np.array([[0, 2, 1], [1, 2, 3]])})
    t = recording.time
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]])
    points = np.repeat(corners[None], t.size, axis=0)
    points[:, 3, 1] = np.sin(2.0 * t)  # the far corner folds up
    points[:, :, 1] += 0.5 * t[:, None]  # the whole quad rises
    recording.fields["particle_position"] = points
    return recording


def expected(recording: vv.Recording, fps: float = FPS) -> tuple[np.ndarray, list[int], float]:
    """Recorded positions at each output frame, the output frames checked, and a tolerance [m]."""
    shown = frames_at_rate(recording.time, fps)
    positions = recording["particle_position"][shown]
    checked = [0, shown.size // 2, shown.size - 1]
    return positions, checked, FLOAT32_RTOL * float(np.abs(recording["particle_position"]).max())


# --- independent readers -------------------------------------------------------------------


def usd_points(path: Path, prim: str, frame: int) -> np.ndarray:
    stage = Usd.Stage.Open(str(path))
    return np.array(UsdGeom.PointBased(stage.GetPrimAtPath(prim)).GetPointsAttr().Get(frame))


_DTYPES = {pygltflib.FLOAT: "<f4", pygltflib.UNSIGNED_INT: "<u4"}


def _view_values(
    document: pygltflib.GLTF2, blob: bytes, view_index: int, dtype: str, count: int, width: int
) -> np.ndarray:
    view = document.bufferViews[view_index]
    stride = view.byteStride or 4 * width
    start = view.byteOffset or 0
    rows = [
        np.frombuffer(blob, dtype, count=width, offset=start + i * stride) for i in range(count)
    ]
    return np.array(rows).reshape(count, width)


def gltf_accessor(document: pygltflib.GLTF2, blob: bytes, index: int) -> np.ndarray:
    """Decode one accessor (float32 or uint32, SCALAR or VEC3, dense or sparse, § 3.6.2.3)."""
    accessor = document.accessors[index]
    dtype = _DTYPES[accessor.componentType]
    width = {"SCALAR": 1, "VEC3": 3}[accessor.type]
    if accessor.bufferView is None:
        values = np.zeros((accessor.count, width), dtype=dtype)
    else:
        values = _view_values(document, blob, accessor.bufferView, dtype, accessor.count, width)
        values = (
            values[(accessor.byteOffset or 0) // (4 * width) :] if accessor.byteOffset else values
        )
    sparse = accessor.sparse
    if sparse is not None:
        where = _view_values(
            document,
            blob,
            sparse.indices.bufferView,
            _DTYPES[sparse.indices.componentType],
            sparse.count,
            1,
        ).ravel()
        values = values.copy()
        values[where] = _view_values(
            document, blob, sparse.values.bufferView, dtype, sparse.count, width
        )
    return values.squeeze(axis=1) if width == 1 else values


def gltf_frames(path: Path) -> tuple[pygltflib.GLTF2, bytes, np.ndarray]:
    """The document, its buffer and every frame's positions ``(frames, P, 3)``: base + morph
    target k (mesh layout), or each point node's translation at keyframe k (bodies layout)."""
    document = pygltflib.GLTF2.load(str(path))
    blob = document.binary_blob()
    if blob is None:  # .gltf: the buffer is a file next to the JSON
        blob = (path.parent / document.buffers[0].uri).read_bytes()
    primitive = document.meshes[0].primitives[0]
    if primitive.targets:
        base = gltf_accessor(document, blob, primitive.attributes.POSITION)
        targets = [gltf_accessor(document, blob, t["POSITION"]) for t in primitive.targets]
        return document, blob, np.array([base.astype(np.float64) + d for d in targets])
    (animation,) = document.animations
    tracks = [gltf_accessor(document, blob, s.output) for s in animation.samplers]
    return document, blob, np.stack(tracks, axis=1).astype(np.float64)


def read_obj(path: Path) -> tuple[np.ndarray, list[list[int]], list[list[int]]]:
    vertices, lines, faces = [], [], []
    for line in path.read_text().splitlines():
        kind, *values = line.split()
        if kind == "v":
            vertices.append([float(v) for v in values])
        elif kind == "l":
            lines.append([int(v) for v in values])
        elif kind == "f":
            faces.append([int(v) for v in values])
    return np.array(vertices), lines, faces


def read_pc2(path: Path) -> tuple[tuple[Any, ...], np.ndarray]:
    data = path.read_bytes()
    header = struct.unpack("<12siiffi", data[:32])
    _, _, points, _, _, samples = header
    positions = np.frombuffer(data, "<f4", offset=32).reshape(samples, points, 3)
    assert len(data) == 32 + samples * points * 12
    return header, positions


# --- USD -----------------------------------------------------------------------------------


def test_usd_points_positions_metadata_and_extent(tmp_path: Path) -> None:
    recording = moving_points()
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "fall.usda", fps=FPS)
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == FPS and stage.GetFramesPerSecond() == FPS
    count = math.floor((FRAMES - 1) / RATE * FPS) + 1  # 29 output frames
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, count - 1)
    assert stage.GetDefaultPrim().GetPath() == "/World"
    assert path.read_bytes().startswith(b"#usda")
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/points"))
    np.testing.assert_allclose(np.array(points.GetWidthsAttr().Get()), [0.2, 0.1, 0.4, 0.2])
    assert len(points.GetPointsAttr().GetTimeSamples()) == count
    radius = recording.static["particle_radius"][:, None]
    for k in checked:
        read = np.array(points.GetPointsAttr().Get(k))
        np.testing.assert_allclose(read, positions[k], rtol=0, atol=tolerance)
        extent = np.array(points.GetExtentAttr().Get(k))
        wanted = [(positions[k] - radius).min(axis=0), (positions[k] + radius).max(axis=0)]
        np.testing.assert_allclose(extent, wanted, rtol=0, atol=tolerance)
        # usd-core's own extent computation (widths included) agrees.
        computed = UsdGeom.Boundable.ComputeExtentFromPlugins(points, Usd.TimeCode(k))
        np.testing.assert_allclose(extent, np.array(computed), rtol=0, atol=tolerance)


def test_usd_default_fps_is_the_recorded_rate_and_usdc_is_binary(tmp_path: Path) -> None:
    recording = moving_points()
    (path,) = export_recording(recording, tmp_path / "fall.usd")
    assert path.read_bytes().startswith(b"PXR-USDC")
    stage = Usd.Stage.Open(str(path))
    assert stage.GetTimeCodesPerSecond() == RATE
    assert stage.GetEndTimeCode() == FRAMES - 1  # every recorded frame
    np.testing.assert_allclose(
        usd_points(path, "/World/points", 37), recording["particle_position"][37], rtol=0, atol=1e-6
    )


def test_usd_edges_are_linear_curves_with_points(tmp_path: Path) -> None:
    edges = np.array([[0, 1], [1, 2], [2, 3]])
    recording = moving_points(static={"edges": edges})
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "rope.usdc", fps=FPS)
    stage = Usd.Stage.Open(str(path))
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/edges"))
    assert curves.GetTypeAttr().Get() == "linear"
    assert list(curves.GetCurveVertexCountsAttr().Get()) == [2, 2, 2]
    np.testing.assert_allclose(np.array(curves.GetWidthsAttr().Get()), [0.05])  # thinnest / 2
    for k in checked:
        read = np.array(curves.GetPointsAttr().Get(k))
        np.testing.assert_allclose(read, positions[k][edges.ravel()], rtol=0, atol=tolerance)
        read = usd_points(path, "/World/points", k)
        np.testing.assert_allclose(read, positions[k], rtol=0, atol=tolerance)


def test_usd_faces_are_a_mesh(tmp_path: Path) -> None:
    recording = quad()
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "quad.usda", fps=FPS)
    stage = Usd.Stage.Open(str(path))
    assert not stage.GetPrimAtPath("/World/points")  # every point is a mesh vertex
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/mesh"))
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == [3, 3]
    assert list(mesh.GetFaceVertexIndicesAttr().Get()) == [0, 2, 1, 1, 2, 3]
    assert mesh.GetOrientationAttr().Get() == "rightHanded"
    assert mesh.GetSubdivisionSchemeAttr().Get() == "none"
    for k in checked:
        np.testing.assert_allclose(
            np.array(mesh.GetPointsAttr().Get(k)), positions[k], rtol=0, atol=tolerance
        )
        extent = np.array(mesh.GetExtentAttr().Get(k))
        wanted = [positions[k].min(axis=0), positions[k].max(axis=0)]
        np.testing.assert_allclose(extent, wanted, rtol=0, atol=tolerance)
    assert np.array(mesh.GetPointsAttr().Get(checked[-1]))[3, 1] != 0.0  # it moved


def test_points_off_the_mesh_keep_a_primitive_of_their_own(tmp_path: Path) -> None:
    # Points 0-2 form a triangle; point 3 is on no face (USD) and on no face or edge (glTF).
    recording = moving_points(static={"faces": np.array([[0, 1, 2]])})
    positions, checked, tolerance = expected(recording)
    (usd,) = export_recording(recording, tmp_path / "mixed.usda", fps=FPS)
    (glb,) = export_recording(recording, tmp_path / "mixed.glb", fps=FPS)
    stage = Usd.Stage.Open(str(usd))
    loose = UsdGeom.Points(stage.GetPrimAtPath("/World/points"))
    np.testing.assert_allclose(np.array(loose.GetWidthsAttr().Get()), [0.2])  # radius 0.1
    document, blob, frames = gltf_frames(glb)
    triangles, points = document.meshes[0].primitives
    assert (triangles.mode, points.mode) == (pygltflib.TRIANGLES, pygltflib.POINTS)
    np.testing.assert_array_equal(gltf_accessor(document, blob, points.indices), [3])
    for k in checked:
        read = usd_points(usd, "/World/points", k)
        np.testing.assert_allclose(read, positions[k][[3]], rtol=0, atol=tolerance)
        read = usd_points(usd, "/World/mesh", k)  # the mesh holds the points its faces use
        np.testing.assert_allclose(read, positions[k][:3], rtol=0, atol=tolerance)
        np.testing.assert_allclose(frames[k], positions[k], rtol=0, atol=tolerance)


# --- glTF ----------------------------------------------------------------------------------


def test_glb_bodies_are_sphere_nodes_with_translation_tracks(tmp_path: Path) -> None:
    recording = moving_points()
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "fall.glb", fps=FPS)
    data = path.read_bytes()
    magic, version, length = struct.unpack("<4sII", data[:12])
    assert (magic, version, length) == (b"glTF", 2, len(data))
    document, blob, frames = gltf_frames(path)
    count = positions.shape[0]
    assert frames.shape == (count, 4, 3)
    for k in checked:
        np.testing.assert_allclose(frames[k], positions[k], rtol=0, atol=tolerance)
    # A root node named after the scene, one node per point showing the unit sphere at the
    # point's radius, starting where the point starts.
    root, *bodies = document.nodes
    assert root.children == [1, 2, 3, 4] and root.mesh is None
    for node, radius, start in zip(bodies, [0.1, 0.05, 0.2, 0.1], positions[0], strict=True):
        assert node.mesh == 0 and node.scale == [radius] * 3
        np.testing.assert_allclose(node.translation, start, rtol=FLOAT32_RTOL)
    sphere = gltf_accessor(document, blob, document.meshes[0].primitives[0].attributes.POSITION)
    np.testing.assert_allclose(np.linalg.norm(sphere, axis=1), 1.0, rtol=1e-6)
    (animation,) = document.animations
    assert {s.interpolation for s in animation.samplers} == {"LINEAR"}
    assert [(c.target.node, c.target.path) for c in animation.channels] == [
        (i, "translation") for i in (1, 2, 3, 4)
    ]
    times = gltf_accessor(document, blob, animation.samplers[0].input)
    np.testing.assert_array_equal(times, (np.arange(count) / FPS).astype(np.float32))
    assert all(view.byteOffset % 4 == 0 for view in document.bufferViews)


def test_glb_of_many_points_is_a_mesh_with_sparse_step_weights(tmp_path: Path) -> None:
    """Above MAX_BODY_NODES points: one POINTS mesh with morph targets; the weights of the STEP
    animation are a sparse accessor (one 1 per keyframe), not N² floats."""
    t = np.arange(30) / RATE
    rng = np.random.default_rng(3)
    start = rng.standard_normal((MAX_BODY_NODES + 1, 3))
    points = start + t[:, None, None] * np.array([0.0, 1.0, 0.0])
    recording = vv.Recording(
        t, {"particle_position": points}, static={"particle_radius": np.full(len(start), 0.02)}
    )
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "cloud.glb", fps=FPS)
    document, blob, frames = gltf_frames(path)
    count = positions.shape[0]
    for k in checked:
        np.testing.assert_allclose(frames[k], positions[k], rtol=0, atol=tolerance)
    (primitive,) = document.meshes[0].primitives
    assert primitive.mode == pygltflib.POINTS and primitive.indices is None
    radius = gltf_accessor(document, blob, primitive.attributes._RADIUS)
    np.testing.assert_allclose(radius, 0.02, rtol=1e-7)
    # Every POSITION accessor has min/max equal to its data.
    for index in [primitive.attributes.POSITION, *(t["POSITION"] for t in primitive.targets)]:
        values = gltf_accessor(document, blob, index)
        assert document.accessors[index].min == values.min(axis=0).tolist()
        assert document.accessors[index].max == values.max(axis=0).tolist()
    (animation,) = document.animations
    (sampler,) = animation.samplers
    assert sampler.interpolation == "STEP" and animation.channels[0].target.path == "weights"
    weights_accessor = document.accessors[sampler.output]
    assert weights_accessor.bufferView is None and weights_accessor.sparse.count == count
    weights = gltf_accessor(document, blob, sampler.output).reshape(count, count)
    np.testing.assert_array_equal(weights, np.eye(count))
    assert path.stat().st_size < gltf_size(len(start), count) + 20_000


def test_glb_edges_are_lines_and_faces_are_triangles(tmp_path: Path) -> None:
    edges = np.array([[0, 1], [2, 3]])
    recording = moving_points(static={"edges": edges})
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "rope.glb", fps=FPS)
    document, blob, frames = gltf_frames(path)
    (lines,) = document.meshes[0].primitives  # every point is on an edge: no POINTS
    assert lines.mode == pygltflib.LINES
    np.testing.assert_array_equal(gltf_accessor(document, blob, lines.indices), edges.ravel())
    for k in checked:
        np.testing.assert_allclose(frames[k], positions[k], rtol=0, atol=tolerance)

    recording = quad()
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "quad.glb", fps=FPS)
    document, blob, frames = gltf_frames(path)
    (triangles,) = document.meshes[0].primitives
    assert triangles.mode == pygltflib.TRIANGLES
    np.testing.assert_array_equal(
        gltf_accessor(document, blob, triangles.indices), [0, 2, 1, 1, 2, 3]
    )
    for k in checked:
        np.testing.assert_allclose(frames[k], positions[k], rtol=0, atol=tolerance)


def test_gltf_json_writes_a_bin_beside_it(tmp_path: Path) -> None:
    recording = moving_points()
    positions, checked, tolerance = expected(recording)
    written = export_recording(recording, tmp_path / "fall.gltf", fps=FPS)
    assert written == [tmp_path / "fall.gltf", tmp_path / "fall.bin"]
    assert json.loads(written[0].read_text())["buffers"][0]["uri"] == "fall.bin"
    _, _, frames = gltf_frames(written[0])
    for k in checked:
        np.testing.assert_allclose(frames[k], positions[k], rtol=0, atol=tolerance)


# --- OBJ and PC2 ---------------------------------------------------------------------------


def test_obj_sequence_is_exact_float64(tmp_path: Path) -> None:
    edges = np.array([[0, 1], [1, 2]])
    recording = moving_points(static={"edges": edges})
    positions, checked, _ = expected(recording)
    written = export_recording(recording, tmp_path / "rope.obj", fps=FPS)
    assert [p.name for p in written[:2]] == ["rope_0000.obj", "rope_0001.obj"]
    assert len(written) == positions.shape[0]
    assert sorted(tmp_path.iterdir()) == written  # nothing else: no temporary files
    for k in checked:
        vertices, lines, faces = read_obj(written[k])
        np.testing.assert_array_equal(vertices, positions[k])  # bit for bit
        assert lines == [[1, 2], [2, 3]] and faces == []


def test_obj_directory_with_faces(tmp_path: Path) -> None:
    recording = quad()
    positions, checked, _ = expected(recording)
    written = export_recording(recording, tmp_path / "obj", to="obj", fps=FPS)
    assert written[0] == tmp_path / "obj" / "frame_0000.obj"
    for k in checked:
        vertices, lines, faces = read_obj(written[k])
        np.testing.assert_array_equal(vertices, positions[k])
        assert faces == [[1, 3, 2], [2, 3, 4]] and lines == []


def test_pc2_header_and_samples(tmp_path: Path) -> None:
    recording = moving_points()
    positions, checked, tolerance = expected(recording)
    (path,) = export_recording(recording, tmp_path / "fall.pc2", fps=FPS)
    header, samples = read_pc2(path)
    assert header == (b"POINTCACHE2\0", 1, 4, 0.0, 1.0, positions.shape[0])
    for k in checked:
        np.testing.assert_allclose(samples[k], positions[k], rtol=0, atol=tolerance)


# --- frame rate ----------------------------------------------------------------------------


def test_default_fps_is_a_whole_number() -> None:
    """Importers play at whole frame rates: the default rounds the recording's rate up (every
    recorded frame shown) and caps it at 60 frames/s."""
    assert default_fps(np.arange(100) / 50.0) == 50.0
    assert default_fps(np.cumsum(np.full(100, 1.0 / 60.0))) == 60.0  # accumulated round-off
    assert default_fps(np.array([0.0, 0.1, 0.2, 0.25])) == 10.0  # a shorter last interval
    assert default_fps(np.arange(84) / 16.69) == 17.0  # the Kepler demo's recording
    assert default_fps(np.arange(10) * 0.003) == 60.0  # 333 Hz
    assert default_fps(np.array([0.0, 0.1, 0.3])) == 30.0  # uneven
    assert default_fps(np.array([0.0])) == 30.0


def test_uneven_recording_exports_at_30_fps(tmp_path: Path) -> None:
    recording = moving_points()
    recording.time = recording.time**1.5  # uneven spacing
    (path,) = export_recording(recording, tmp_path / "uneven.pc2")
    _, samples = read_pc2(path)
    shown = frames_at_rate(recording.time, 30.0)
    assert samples.shape[0] == shown.size
    np.testing.assert_allclose(
        samples[-1], recording["particle_position"][shown[-1]], rtol=0, atol=1e-5
    )


# --- bad input: refused before anything is written -----------------------------------------


def assert_refused(folder: Path, match: str, *args: Any, **kwargs: Any) -> None:
    with pytest.raises(ModelError, match=match):
        export_recording(*args, **kwargs)
    assert list(folder.iterdir()) == []


def test_unknown_or_unfitting_format(tmp_path: Path) -> None:
    recording = moving_points()
    assert_refused(
        tmp_path,
        r"unknown export format `to` = 'glbb'\. Did you mean 'glb'\? Valid: usd, ",
        recording,
        tmp_path / "a.glb",
        to="glbb",
    )
    assert_refused(
        tmp_path, "Valid: " + ", ".join(EXPORT_FORMATS), recording, tmp_path / "a", to="fbx"
    )
    assert_refused(tmp_path, "cannot tell the export format", recording, tmp_path / "anim")
    assert_refused(
        tmp_path,
        r"does not end in \.glb, as a glb file must; use e\.g\. '.*a\.glb'",
        recording,
        tmp_path / "a.usd",
        to="glb",
    )
    assert_refused(
        tmp_path, r"does not end in \.usda or \.usd", recording, tmp_path / "a.usdc", to="usda"
    )
    assert_refused(
        tmp_path,
        r"'.*a\.glb' names a glb file, not an OBJ sequence: use a path ending in \.obj",
        recording,
        tmp_path / "a.glb",
        to="obj",
    )


def test_recording_without_points(tmp_path: Path) -> None:
    abstract = vv.Recording(np.arange(3.0), {"q": np.zeros((3, 2))})
    assert_refused(
        tmp_path, "no `particle_position` or `system_points` field", abstract, tmp_path / "a.usd"
    )
    empty = vv.Recording(np.arange(3.0), {"particle_position": np.zeros((3, 0, 3))})
    assert_refused(tmp_path, "holds no points", empty, tmp_path / "a.glb")


def test_missing_directory_and_directory_as_file(tmp_path: Path) -> None:
    recording = moving_points()
    missing = tmp_path / "nowhere"
    with pytest.raises(ModelError, match=r"directory '.*nowhere' does not exist; create it"):
        export_recording(recording, missing / "a.pc2")
    with pytest.raises(ModelError, match="does not exist"):
        export_recording(recording, missing / "obj", to="obj")
    assert not missing.exists()
    (tmp_path / "a.usd").mkdir()
    with pytest.raises(ModelError, match="is a directory; give a file name"):
        export_recording(recording, tmp_path / "a.usd")


def test_bad_fps_and_non_finite_positions(tmp_path: Path) -> None:
    recording = moving_points()
    assert_refused(tmp_path, r"`fps` must be positive", recording, tmp_path / "a.pc2", fps=0.0)
    assert_refused(
        tmp_path, r"`fps` must be a real number", recording, tmp_path / "a.pc2", fps="24"
    )
    assert_refused(tmp_path, "more than 1000000", recording, tmp_path / "a.pc2", fps=1e9)
    recording["particle_position"][40, 2, 1] = np.nan
    assert_refused(
        tmp_path,
        r"recorded frame 40 \(t = 0\.8 s\) is not finite at point 2",
        recording,
        tmp_path / "a.obj",
        fps=RATE,
    )


def test_glb_over_the_size_limit(tmp_path: Path) -> None:
    # 2 recorded frames 1 s apart at 90,000 frames/s: 90,001 output frames of 1000 points.
    t = np.array([0.0, 1.0])
    recording = vv.Recording(t, {"particle_position": np.zeros((2, 1000, 3))})
    with pytest.raises(ModelError) as error:
        export_recording(recording, tmp_path / "big.glb", fps=90_000.0)
    message = str(error.value)
    # (90001 + 1)·1000·12 B of positions + 1000·4 B of radii + 90001·12 B of animation.
    assert "90001 frames × 1000 points needs 1031 MiB" in message
    assert f"at most {MAX_GLTF_BYTES // 2**20} MiB (MAX_GLTF_BYTES)" in message
    assert list(tmp_path.iterdir()) == []
    advice = float(message.split("pass fps ≤ ")[1].split(" frames/s")[0])
    fits = math.floor(advice) + 1  # frames over 1 s at that rate
    assert gltf_size(1000, fits) <= MAX_GLTF_BYTES and fits <= MAX_MORPH_FRAMES


def test_existing_files_are_replaced(tmp_path: Path) -> None:
    recording = moving_points()
    target = tmp_path / "fall.pc2"
    target.write_bytes(b"old")
    export_recording(recording, target, fps=FPS)
    export_recording(recording, target, fps=10.0)
    header, _ = read_pc2(target)
    assert header[-1] == math.floor((FRAMES - 1) / RATE * 10.0) + 1
    assert list(tmp_path.iterdir()) == [target]  # no temporary file left


def test_a_failing_obj_sequence_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    recording = moving_points()
    folder = tmp_path / "obj"
    folder.mkdir()
    (folder / "frame_0000.obj").write_text("old")
    original = ExportFrames.points_at

    def failing(self: ExportFrames, k: int) -> np.ndarray:
        if k == 2:
            raise OSError("disk full")
        return original(self, k)

    monkeypatch.setattr(ExportFrames, "points_at", failing)
    with pytest.raises(OSError, match="disk full"):
        export_recording(recording, folder, to="obj", fps=FPS)
    assert [p.name for p in folder.iterdir()] == ["frame_0000.obj"]
    assert (folder / "frame_0000.obj").read_text() == "old"  # untouched
    with pytest.raises(OSError, match="disk full"):
        export_recording(recording, tmp_path / "new", to="obj", fps=FPS)
    assert not (tmp_path / "new").exists()  # the directory this call made is gone too
