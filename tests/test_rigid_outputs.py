"""Rigid bodies in every output: the recording, USD, glTF, OBJ, PC2, the video and the viewer.

One scene runs once through ``visviva run`` with every output format: a tumbling brick (a box),
a ball (a sphere) thrown sideways, a wedge (a tetrahedron given as a mesh, whose centre of mass
is off its own origin) and a cloud of particles, falling under gravity. Each output is read
back with an independent reader (pxr, pygltflib, plain text and ``struct``, imageio, the page's
own read-back in Chromium) and compared with the recording at every output frame: transforms
exactly where they are float64 (USD), to float32 rounding elsewhere. Surfaces are checked
against :func:`visviva.rigid.surfaces.body_surface`, and bodies placed from what a file holds
are compared with the recording's placed by SciPy's rotations (not visviva's quaternion code).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import imageio.v3 as iio
import numpy as np
import pygltflib
import pytest
from playwright.sync_api import sync_playwright
from pxr import Gf, Usd, UsdGeom
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

import visviva as vv
from test_export import read_obj, read_pc2
from test_viewer import CHROMIUM, CHROMIUM_FLAGS, Opened
from visviva.cli.main import app
from visviva.errors import ModelError
from visviva.io.export import export_recording
from visviva.io.timeline import frames_at_rate
from visviva.rigid.surfaces import body_surface
from visviva.viz.frame import drawn_bounds
from visviva.viz.video import render_video
from visviva.viz.viewer import write_viewer

FPS = 20.0
FORMATS = ("mp4", "html", "usd", "glb", "obj", "pc2")
NAMES = ["brick", "ball", "wedge"]
RED, GREEN, YELLOW = (0.9, 0.1, 0.1), (0.1, 0.8, 0.2), (0.9, 0.8, 0.1)
#: A tetrahedron with its right angle at its own origin: its centre of mass is at (0.075,)·3.
WEDGE_VERTICES = [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3]]
WEDGE_TRIANGLES = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
SHAPES = [
    {"shape": "box", "size": (0.4, 0.2, 0.1)},
    {"shape": "sphere", "radius": 0.15},
    {"shape": "mesh", "vertices": WEDGE_VERTICES, "triangles": WEDGE_TRIANGLES},
]
#: Relative accuracy of a float32 value, with margin for one rounding of a sum.
FLOAT32_RTOL = 1e-6


def scene(*, particles: bool = True) -> vv.SceneBuilder:
    builder = vv.SceneBuilder(name="rigid outputs")
    builder.set_integration(method="symplectic_euler", dt=0.005, duration=0.5, record_every=2)
    builder.set_output(fps=FPS)
    half = 0.3  # the brick starts turned 0.6 rad about y
    builder.add_body(
        "box",
        size=(0.4, 0.2, 0.1),
        density=500.0,
        position=(0.0, 1.0, 0.0),
        orientation=(np.cos(half), 0.0, np.sin(half), 0.0),
        velocity=(0.0, 2.0, 0.0),
        angular_velocity=(0.3, 6.0, 0.2),
        color=RED,
        name="brick",
    )
    builder.add_body(
        "sphere",
        radius=0.15,
        density=800.0,
        position=(0.8, 1.5, 0.0),
        velocity=(0.6, 0.0, 0.0),
        color=GREEN,
        name="ball",
    )
    builder.add_body(
        "mesh",
        vertices=WEDGE_VERTICES,
        triangles=WEDGE_TRIANGLES,
        mass=2.0,
        position=(-0.6, 1.4, 0.3),
        velocity=(0.0, 1.5, 0.0),
        angular_velocity=(4.0, 0.0, 1.0),
        color=YELLOW,
        name="wedge",
    )
    if particles:
        builder.add_particle_cloud(
            name="cloud",
            count=12,
            center=(-0.8, 1.0, -0.4),
            size=(0.3, 0.3, 0.3),
            radius=0.03,
            seed=2,
        )
    return builder


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, vv.Recording]:
    """The scene run for 0.5 s with every output; the folder and the recording."""
    folder = tmp_path_factory.mktemp("rigid")
    path = folder / "scene.toml"
    path.write_text(vv.io.dump_scene(scene().scene, "toml"))
    out = folder / "out"
    arguments = ["run", str(path), "-o", str(out)]
    for format in FORMATS:
        arguments += ["-f", format]
    result = CliRunner().invoke(app, arguments)
    assert result.exit_code == 0, result.output
    return out, vv.io.load_recording(out / "recording.h5")


@pytest.fixture(scope="module")
def browser() -> Any:
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        yield chromium
        chromium.close()


def shown_transforms(recording: vv.Recording) -> tuple[np.ndarray, np.ndarray]:
    """Each body's recorded origin ``(N, B, 3)`` [m] and orientation ``(N, B, 4)`` at the
    output frames."""
    shown = frames_at_rate(recording.time, FPS)
    return recording["body_origin"][shown], recording["body_orientation"][shown]


def placed(origin: np.ndarray, orientation: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """``origin + R(q) v`` by SciPy's rotations (scalar-last quaternions)."""
    w, x, y, z = orientation
    return Rotation.from_quat([x, y, z, w]).apply(vertices) + origin


def same_rotation(a: np.ndarray, b: np.ndarray, atol: float) -> bool:
    """True if quaternions ``a`` and ``b`` are equal or opposite (the same rotation)."""
    return bool(np.allclose(a, b, rtol=0, atol=atol) or np.allclose(a, -b, rtol=0, atol=atol))


def surfaces() -> list[tuple[np.ndarray, np.ndarray]]:
    return [body_surface(shape) for shape in SHAPES]


# --- the recording ---------------------------------------------------------------------------


def test_the_run_records_each_surface_once_and_each_transform_per_frame(run):
    _, recording = run
    frames = recording.frames
    assert recording["body_origin"].shape == (frames, 3, 3)
    assert recording["body_orientation"].shape == (frames, 3, 4)
    assert recording.units["body_origin"] == "m" and recording.units["body_vertices"] == "m"
    np.testing.assert_allclose(np.linalg.norm(recording["body_orientation"], axis=2), 1.0, 1e-12)
    # Nothing of a body's surface is recorded per frame: the fields are particles and transforms.
    assert set(recording.fields) == {
        "particle_position",
        "particle_velocity",
        "body_origin",
        "body_orientation",
        "energy",
    }
    static, start = recording.static, 0
    for b, (vertices, triangles) in enumerate(surfaces()):
        first, last = static["body_vertex_start"][b : b + 2]
        assert (first, last) == (start, start + vertices.shape[0])
        np.testing.assert_array_equal(static["body_vertices"][first:last], vertices)
        rows = slice(*static["body_triangle_start"][b : b + 2])
        np.testing.assert_array_equal(static["body_triangles"][rows], triangles + first)
        start = last
    np.testing.assert_array_equal(static["body_color"], [RED, GREEN, YELLOW])
    assert recording.attrs["body_names"] == NAMES
    # body_origin is each body's own origin: where the scene put it at the start.
    starts = [[0.0, 1.0, 0.0], [0.8, 1.5, 0.0], [-0.6, 1.4, 0.3]]
    np.testing.assert_allclose(recording["body_origin"][0], starts, rtol=0, atol=1e-15)
    np.testing.assert_allclose(static["body_center"][2], [0.075] * 3, rtol=1e-12)


def test_the_recorded_origin_and_the_states_centre_of_mass_agree(run):
    """origin + R(q) body_center is the state's body_position at the end of the run."""
    _, recording = run
    simulation = vv.Simulation(scene().build())
    simulation.run(until=0.5)
    state = simulation.state
    for b in range(3):
        origin, orientation = (
            recording["body_origin"][-1, b],
            recording["body_orientation"][-1, b],
        )
        centre = placed(origin, orientation, recording.static["body_center"][b])
        np.testing.assert_allclose(centre, state["body_position"][b], rtol=0, atol=1e-12)
        assert same_rotation(orientation, state["body_orientation"][b], 1e-15)


def test_a_recording_round_trips_the_body_fields(tmp_path):
    recording = vv.Simulation(scene().build()).record(until=0.1)
    path = vv.io.save_recording(recording, tmp_path / "bodies.h5")
    again = vv.io.load_recording(path)
    for name in ("body_origin", "body_orientation"):
        assert again[name].dtype == np.float64
        np.testing.assert_array_equal(again[name], recording[name])
    assert set(again.static) == set(recording.static)
    for name, value in recording.static.items():
        assert again.static[name].dtype == value.dtype
        np.testing.assert_array_equal(again.static[name], value)
    assert again.attrs["body_names"] == NAMES
    assert again.units["body_origin"] == "m"
    bodies = again.geometry().bodies
    assert bodies is not None and bodies.names == tuple(NAMES)


# --- USD -------------------------------------------------------------------------------------


def test_usd_has_an_xform_per_body_with_the_recorded_transforms_and_a_static_surface(run):
    out, recording = run
    origins, orientations = shown_transforms(recording)
    stage = Usd.Stage.Open(str(out / "scene.usdc"))
    assert stage.GetPrimAtPath("/World/points").IsValid()  # the particles, as before
    checked = [0, origins.shape[0] // 2, origins.shape[0] - 1]
    for b, ((vertices, triangles), name) in enumerate(zip(surfaces(), NAMES, strict=True)):
        xform = UsdGeom.Xformable(stage.GetPrimAtPath(f"/World/bodies/{name}"))
        translate, orient = xform.GetOrderedXformOps()
        assert translate.GetOpType() == UsdGeom.XformOp.TypeTranslate
        assert orient.GetOpType() == UsdGeom.XformOp.TypeOrient
        assert orient.GetPrecision() == UsdGeom.XformOp.PrecisionDouble
        assert translate.GetNumTimeSamples() == orient.GetNumTimeSamples() == origins.shape[0]
        previous = None
        for k in range(origins.shape[0]):
            assert np.array_equal(np.array(translate.Get(k)), origins[k, b])  # float64, exact
            q = orient.Get(k)
            written = np.array([q.GetReal(), *q.GetImaginary()])
            assert np.array_equal(written, orientations[k, b]) or np.array_equal(
                written, -orientations[k, b]
            )
            if previous is not None:  # interpolation turns the short way
                assert written @ previous >= 0.0
            previous = written
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(f"/World/bodies/{name}/{name}"))
        points = np.array(mesh.GetPointsAttr().Get(), dtype=np.float64)
        assert points.shape == vertices.shape
        assert list(mesh.GetFaceVertexIndicesAttr().Get()) == triangles.ravel().tolist()
        assert set(mesh.GetFaceVertexCountsAttr().Get()) == {3}
        for k in checked:
            matrix = xform.ComputeLocalToWorldTransform(k)
            world = np.array([matrix.Transform(Gf.Vec3d(*p)) for p in points.tolist()])
            expected = placed(origins[k, b], orientations[k, b], vertices)
            np.testing.assert_allclose(world, expected, rtol=0, atol=1e-6)
    # No vertex data per frame: under /World/bodies only the xform ops have time samples.
    for prim in Usd.PrimRange(stage.GetPrimAtPath("/World/bodies")):
        for attribute in prim.GetAttributes():
            if attribute.GetNumTimeSamples():
                assert attribute.GetName() in ("xformOp:translate", "xformOp:orient")


# --- glTF ------------------------------------------------------------------------------------


_WIDTH = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}


def accessor(document: pygltflib.GLTF2, blob: bytes, index: int) -> np.ndarray:
    """A dense float32 or uint32 accessor, ``(count, width)``, by its buffer view."""
    found = document.accessors[index]
    assert found.sparse is None and (found.byteOffset or 0) == 0
    view = document.bufferViews[found.bufferView]
    assert view.byteStride is None
    dtype = "<f4" if found.componentType == pygltflib.FLOAT else "<u4"
    width = _WIDTH[found.type]
    values = np.frombuffer(blob, dtype, count=found.count * width, offset=view.byteOffset or 0)
    return values.reshape(found.count, width)


def test_gltf_has_a_node_per_body_moved_by_translation_and_rotation_channels(run):
    out, recording = run
    origins, orientations = shown_transforms(recording)
    count = origins.shape[0]
    document = pygltflib.GLTF2.load(str(out / "scene.glb"))
    blob = document.binary_blob()
    (animation,) = document.animations
    nodes = {node.name: i for i, node in enumerate(document.nodes)}
    (root,) = [i for i in document.scenes[0].nodes if document.nodes[i].name == "bodies"]
    assert document.nodes[root].children == [nodes[name] for name in NAMES]
    tolerance = FLOAT32_RTOL * float(np.abs(origins).max())
    for b, ((vertices, triangles), name) in enumerate(zip(surfaces(), NAMES, strict=True)):
        node = document.nodes[nodes[name]]
        channels = {c.target.path: c for c in animation.channels if c.target.node == nodes[name]}
        assert set(channels) == {"translation", "rotation"}
        samplers = {path: animation.samplers[c.sampler] for path, c in channels.items()}
        for sampler in samplers.values():
            assert sampler.interpolation == pygltflib.ANIM_LINEAR
            times = accessor(document, blob, sampler.input)[:, 0]
            np.testing.assert_allclose(times, np.arange(count) / FPS, rtol=1e-7)
        translation = accessor(document, blob, samplers["translation"].output)
        np.testing.assert_allclose(translation, origins[:, b], rtol=0, atol=tolerance)
        rotation = accessor(document, blob, samplers["rotation"].output)  # (x, y, z, w)
        assert rotation.shape == (count, 4)
        for k in range(count):
            assert same_rotation(rotation[k, [3, 0, 1, 2]], orientations[k, b], 1e-7)
        assert np.all(np.einsum("ki,ki->k", rotation[1:], rotation[:-1]) >= 0.0)
        (primitive,) = document.meshes[node.mesh].primitives
        assert primitive.mode == pygltflib.TRIANGLES and not primitive.targets
        position = accessor(document, blob, primitive.attributes.POSITION)
        np.testing.assert_array_equal(position, vertices.astype(np.float32))
        indices = accessor(document, blob, primitive.indices)[:, 0]
        np.testing.assert_array_equal(indices, triangles.ravel())
        normals = accessor(document, blob, primitive.attributes.NORMAL)
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=1e-6)
        for k in (0, count - 1):  # what an importer shows: the node's TRS applied to POSITION
            turned = Rotation.from_quat(rotation[k]).apply(position) + translation[k]
            expected = placed(origins[k, b], orientations[k, b], vertices)
            np.testing.assert_allclose(turned, expected, rtol=0, atol=1e-5)
    # No morph targets and no weights anywhere: the particles are sphere nodes, the bodies
    # move by their nodes' transforms.
    assert all(not p.targets for mesh in document.meshes for p in mesh.primitives)
    assert {c.target.path for c in animation.channels} == {"translation", "rotation"}


# --- OBJ and PC2 -----------------------------------------------------------------------------


def test_obj_and_pc2_hold_the_points_then_the_placed_body_vertices(run):
    out, recording = run
    origins, orientations = shown_transforms(recording)
    shown = frames_at_rate(recording.time, FPS)
    points = recording["particle_position"][shown]
    count = points.shape[1]
    files = sorted((out / "obj").glob("*.obj"))
    _, cache = read_pc2(out / "points.pc2")
    total = count + sum(v.shape[0] for v, _ in surfaces())
    assert len(files) == cache.shape[0] == shown.size and cache.shape[1] == total
    for k in (0, shown.size - 1):
        vertices, _, _ = read_obj(files[k])
        np.testing.assert_array_equal(vertices[:count], points[k])
        start = count
        for b, (surface, _) in enumerate(surfaces()):
            body = vertices[start : start + surface.shape[0]]
            expected = placed(origins[k, b], orientations[k, b], surface)
            np.testing.assert_allclose(body, expected, rtol=0, atol=1e-12)
            start += surface.shape[0]
        np.testing.assert_allclose(cache[k], vertices, rtol=0, atol=1e-6)
    # One group per body, holding its triangles numbered after the points (1-based).
    groups: dict[str, list[list[int]]] = {}
    current = None
    for line in files[0].read_text().splitlines():
        if line.startswith("g "):
            current = line[2:]
            groups[current] = []
        elif line.startswith("f ") and current is not None:
            groups[current].append([int(v) for v in line.split()[1:]])
    assert list(groups) == NAMES
    first = count
    for (surface, triangles), name in zip(surfaces(), NAMES, strict=True):
        np.testing.assert_array_equal(np.array(groups[name]) - 1 - first, triangles)
        first += surface.shape[0]


def test_obj_numbers_the_body_triangles_after_the_live_points(tmp_path):
    """Points that are born and die change how many vertices come before the bodies'."""
    recording = vv.Simulation(scene(particles=False).build()).record(until=0.05)
    frames = recording.frames
    alive = np.zeros((frames, 3), dtype=bool)
    for k in range(frames):
        alive[k, : k % 4] = True  # 0, 1, 2, 3, 0, ... live points
    points = np.broadcast_to(np.arange(9.0).reshape(3, 3), (frames, 3, 3))
    mixed = vv.Recording(
        recording.time,
        recording.fields | {"particle_position": points, "particle_alive": alive},
        static=recording.static,
        attrs=recording.attrs,
    )
    files = export_recording(mixed, tmp_path / "mixed.obj", fps=100.0)
    shown = frames_at_rate(recording.time, 100.0)
    for k, path in enumerate(files):
        live = int(alive[shown[k]].sum())
        vertices, _, faces = read_obj(path)
        assert vertices.shape[0] == live + sum(v.shape[0] for v, _ in surfaces())
        np.testing.assert_array_equal(vertices[:live], points[0, :live])
        brick = np.array(faces[: surfaces()[0][1].shape[0]])
        assert brick.min() == live + 1


# --- the video and the viewer ----------------------------------------------------------------


def coloured(image: np.ndarray, colour: tuple[float, float, float]) -> np.ndarray:
    """Pixels whose hue is clearly ``colour``'s (red, green or yellow), bool ``(H, W)``."""
    r, g, b = (image[..., i].astype(float) for i in range(3))
    if colour == RED:
        return (r > 90) & (r > 2.5 * g) & (r > 2.5 * b)
    if colour == GREEN:
        return (g > 80) & (g > 2.0 * r) & (g > 2.0 * b)
    return (r > 90) & (g > 80) & (b < 0.4 * g)


def test_the_video_draws_each_body_in_its_colour(run):
    out, recording = run
    frames = iio.imread(out / "animation.mp4", index=None)
    assert frames.shape[0] == frames_at_rate(recording.time, FPS).size
    for k in (0, frames.shape[0] // 2, frames.shape[0] - 1):  # framed for the whole clip
        for colour in (RED, GREEN, YELLOW):
            assert coloured(frames[k], colour).sum() > 100, (k, colour)
    # The ball falls: its pixels move down the picture.
    rows = [np.argwhere(coloured(frames[k], GREEN))[:, 0].mean() for k in (0, -1)]
    assert rows[1] > rows[0] + 20


def test_the_viewer_moves_each_body_by_its_transform(run, browser):
    out, recording = run
    origins, orientations = shown_transforms(recording)
    html = (out / "viewer.html").read_text()
    data = re.search(r'<script type="application/json" id="visviva-data">(.*?)</script>', html)
    assert data is not None
    layer = json.loads(data.group(1))["layers"]["bodies"]
    assert layer["count"] == 3 and layer["names"] == NAMES
    page = Opened(browser, out / "viewer.html")
    try:
        for k in (0, origins.shape[0] // 2, origins.shape[0] - 1):
            shown = page.js(f"visviva.pause(), visviva.setFrame({k}), visviva.bodies()")
            assert [body["name"] for body in shown] == NAMES
            for b, body in enumerate(shown):
                np.testing.assert_allclose(body["position"], origins[k, b], rtol=FLOAT32_RTOL)
                np.testing.assert_allclose(body["orientation"], orientations[k, b], atol=1e-7)
            image = page.image(k)
            for colour in (RED, GREEN, YELLOW):
                assert coloured(image, colour).sum() > 100, (k, colour)
        assert page.errors == []
    finally:
        page.page.close()


# --- bodies alone, and bad input -------------------------------------------------------------


def test_bodies_alone_go_to_every_output(tmp_path, browser):
    recording = vv.Simulation(scene(particles=False).build()).record(until=0.2)
    geometry = recording.geometry()
    assert geometry.points.shape == (recording.frames, 0, 3)
    # The framing holds every vertex of every frame, and no more.
    everything = np.concatenate(
        [
            placed(x, q, surface)
            for k in range(recording.frames)
            for x, q, (surface, _) in zip(
                recording["body_origin"][k],
                recording["body_orientation"][k],
                surfaces(),
                strict=True,
            )
        ]
    )
    low, high = drawn_bounds(geometry)
    np.testing.assert_allclose(low, everything.min(axis=0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(high, everything.max(axis=0), rtol=0, atol=1e-12)

    (usd,) = export_recording(recording, tmp_path / "alone.usda", fps=FPS)
    stage = Usd.Stage.Open(str(usd))
    assert [str(p.GetPath()) for p in stage.GetPrimAtPath("/World").GetChildren()] == [
        "/World/bodies"
    ]
    (glb,) = export_recording(recording, tmp_path / "alone.glb", fps=FPS)
    document = pygltflib.GLTF2.load(str(glb))
    assert [document.nodes[i].name for i in document.scenes[0].nodes] == ["bodies"]
    (pc2,) = export_recording(recording, tmp_path / "alone.pc2", fps=FPS)
    assert read_pc2(pc2)[1].shape[1] == sum(v.shape[0] for v, _ in surfaces())
    gif = render_video(recording, tmp_path / "alone.gif", fps=FPS, size=(240, 136))
    assert coloured(iio.imread(gif, index=0), RED).sum() > 10

    page = Opened(browser, write_viewer(recording, tmp_path / "alone.html", fps=FPS))
    try:
        assert page.js("visviva.drawn().count") == 0 and len(page.js("visviva.bodies()")) == 3
        assert coloured(page.image(0), RED).sum() > 100
        assert page.errors == []
    finally:
        page.page.close()


def test_bad_body_arrays_are_refused_before_anything_is_written(tmp_path):
    recording = vv.Simulation(scene(particles=False).build()).record(until=0.05)
    fields, static = dict(recording.fields), dict(recording.static)

    def geometry_of(**changes: Any) -> None:
        static_changes = {k: v for k, v in changes.items() if k in static}
        field_changes = {k: v for k, v in changes.items() if k in fields}
        vv.Recording(
            recording.time,
            {k: v for k, v in (fields | field_changes).items() if v is not None},
            static={k: v for k, v in (static | static_changes).items() if v is not None},
        ).geometry()

    with pytest.raises(ModelError, match="body_triangle_start"):
        geometry_of(body_triangle_start=None)
    crossing = static["body_triangles"].copy()
    crossing[0, 0] = static["body_vertex_start"][1]  # the brick's first triangle uses the ball
    with pytest.raises(ModelError, match=r"row 0 \(body 0\) uses vertices outside"):
        geometry_of(body_triangles=crossing)
    with pytest.raises(ModelError, match="body_orientation"):
        geometry_of(body_orientation=fields["body_orientation"][:, :2])

    diverged = fields["body_orientation"].copy()
    diverged[-1, 1, 0] = np.nan
    broken = vv.Recording(recording.time, fields | {"body_orientation": diverged}, static=static)
    with pytest.raises(ModelError, match="body 1"):
        export_recording(broken, tmp_path / "broken.usda")
    with pytest.raises(ModelError, match="body 1"):
        render_video(broken, tmp_path / "broken.gif", size=(64, 48))
    with pytest.raises(ModelError, match="body 1"):
        write_viewer(broken, tmp_path / "broken.html")
    assert list(tmp_path.iterdir()) == []
