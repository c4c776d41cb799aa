"""Static colliders drawn in every output ("scenery"): the recording, the video, the viewer and
the exports.

One scene with a floor plane, a turned box, a sphere and a tetrahedron mesh collider, and a
cloud of particles falling onto them, is recorded once. The recorded surfaces are checked
against closed forms computed here independently (the box's corners by SciPy's rotations, the
sphere's vertices at distance r from its centre, the mesh's own triangles); each output is read
back (imageio, Chromium, pxr, pygltflib) and must draw them where they are.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import visviva as vv
from visviva.cli.main import main
from visviva.errors import SceneError
from visviva.viz.frame import drawn_bounds
from visviva.viz.video import render_video

RED, GREEN, YELLOW = (0.9, 0.1, 0.1), (0.1, 0.7, 0.2), (0.9, 0.8, 0.1)
BOX_CENTER, BOX_SIZE = np.array([-1.0, 0.3, 0.0]), np.array([0.6, 0.4, 0.8])
BOX_TURN = 0.3  # [rad] about an oblique axis, so that every corner coordinate moves
BOX_AXIS = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])
SPHERE_CENTER, SPHERE_RADIUS = np.array([0.2, 0.5, 0.0]), 0.5
#: A tetrahedron, counter-clockwise from outside.
MESH_VERTICES = np.array([[1.0, 0.0, -0.4], [1.8, 0.0, -0.4], [1.0, 0.0, 0.4], [1.4, 0.8, 0.0]])
MESH_TRIANGLES = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])


def box_quaternion() -> tuple[float, float, float, float]:
    half = 0.5 * BOX_TURN
    return (np.cos(half), *(np.sin(half) * BOX_AXIS))


def box_corners() -> np.ndarray:
    """The box's 8 corners c + R (±a/2, ±b/2, ±c/2) [m], R by SciPy from axis and angle."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    return Rotation.from_rotvec(BOX_TURN * BOX_AXIS).apply(0.5 * signs * BOX_SIZE) + BOX_CENTER


def scene(*, colliders: bool = True) -> vv.SceneBuilder:
    builder = vv.SceneBuilder(name="colliders")
    builder.set_integration(method="symplectic_euler", dt=0.005, duration=0.4, record_every=4)
    builder.set_output(fps=10.0)
    builder.add_particle_cloud(
        name="cloud", count=20, center=(0.0, 2.0, 0.0), size=(2.0, 0.3, 1.0), radius=0.04, seed=1
    )
    builder.add_collider("plane", point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0), name="floor")
    if colliders:
        builder.add_collider(
            "box",
            center=BOX_CENTER.tolist(),
            size=BOX_SIZE.tolist(),
            orientation=box_quaternion(),
            color=RED,
            name="crate",
        )
        builder.add_collider(
            "sphere", center=SPHERE_CENTER.tolist(), radius=SPHERE_RADIUS, color=GREEN
        )
        builder.add_collider(
            "mesh",
            vertices=MESH_VERTICES.tolist(),
            triangles=MESH_TRIANGLES.tolist(),
            color=YELLOW,
            name="wedge",
        )
    return builder


@pytest.fixture(scope="module")
def recording() -> vv.Recording:
    return vv.Simulation(scene().build()).record(until=0.4)


def coloured(image: np.ndarray, colour: tuple[float, float, float]) -> np.ndarray:
    """Pixels whose hue is clearly ``colour``'s (red, green or yellow), bool ``(H, W)``."""
    r, g, b = (image[..., i].astype(float) for i in range(3))
    if colour == RED:
        return (r > 90) & (r > 2.5 * g) & (r > 2.5 * b)
    if colour == GREEN:
        return (g > 70) & (g > 1.8 * r) & (g > 1.8 * b)
    return (r > 90) & (g > 80) & (b < 0.4 * g)


# --- the recording ---------------------------------------------------------------------------


def test_the_recording_holds_each_drawn_colliders_surface_and_no_plane(recording):
    geometry = recording.geometry()
    scenery = geometry.scenery
    assert scenery is not None
    assert scenery.count == 3  # the plane is not drawn
    assert scenery.names == ("crate", "collider_3", "wedge")
    np.testing.assert_array_equal(scenery.color, [RED, GREEN, YELLOW])
    assert recording.units["scenery_vertices"] == "m"
    # Nothing per frame: the fields are the particles' only.
    assert not any(name.startswith("scenery") for name in recording.fields)

    # The box: exactly its 8 corners c + R (±a/2, ±b/2, ±c/2), R by SciPy from axis and angle.
    box, box_triangles = scenery.surface(0)
    corners = box_corners()
    distinct = np.unique(np.round(box, 12), axis=0)
    assert distinct.shape == (8, 3)
    for corner in corners:
        assert np.min(np.linalg.norm(box - corner, axis=1)) < 1e-12
    # 12 triangles, counter-clockwise from outside: the divergence theorem gives the volume
    # V = Σ (a · (b × c)) / 6 over the triangles = a·b·c of the box.
    assert box_triangles.shape == (12, 3)
    assert enclosed_volume(box, box_triangles) == pytest.approx(np.prod(BOX_SIZE), rel=1e-12)

    # The sphere: every vertex on its surface, |v − c| = r to 1e-12 m, round enough.
    ball, ball_triangles = scenery.surface(1)
    np.testing.assert_allclose(
        np.linalg.norm(ball - SPHERE_CENTER, axis=1), SPHERE_RADIUS, rtol=0, atol=1e-12
    )
    assert ball.shape[0] >= 400
    volume = 4.0 / 3.0 * np.pi * SPHERE_RADIUS**3
    assert enclosed_volume(ball, ball_triangles) == pytest.approx(volume, rel=0.03)

    # The mesh: its own vertices and triangles.
    wedge, wedge_triangles = scenery.surface(2)
    np.testing.assert_array_equal(wedge, MESH_VERTICES)
    np.testing.assert_array_equal(wedge_triangles, MESH_TRIANGLES)


def enclosed_volume(vertices: np.ndarray, triangles: np.ndarray) -> float:
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def test_a_recording_without_drawn_colliders_has_no_scenery_field(tmp_path, monkeypatch, capsys):
    # Only a plane: nothing to draw, nothing recorded; the file is what it was before.
    recording = vv.Simulation(scene(colliders=False).build()).record(until=0.1)
    assert not any(name.startswith("scenery") for name in recording.static)
    assert not any(name.startswith("scenery") for name in recording.attrs)
    assert recording.geometry().scenery is None
    path = tmp_path / "plain.h5"
    vv.io.save_recording(recording, path)
    loaded = vv.io.load_recording(path)
    assert sorted(loaded.static) == ["particle_mass", "particle_radius"]
    assert loaded.geometry().scenery is None


def test_the_scenery_round_trips_through_a_file(recording, tmp_path):
    path = tmp_path / "scenery.h5"
    vv.io.save_recording(recording, path)
    loaded = vv.io.load_recording(path).geometry().scenery
    original = recording.geometry().scenery
    assert loaded is not None and original is not None
    np.testing.assert_array_equal(loaded.vertices, original.vertices)
    np.testing.assert_array_equal(loaded.triangles, original.triangles)
    np.testing.assert_array_equal(loaded.color, original.color)
    assert loaded.names == original.names


def test_a_collider_colour_outside_0_1_is_refused_naming_the_entity_and_field(
    tmp_path, monkeypatch, capsys
):
    builder = scene(colliders=False)
    with pytest.raises(SceneError, match=r"entities\[2\]\.color\[0\].*1\.2"):
        builder.add_collider("sphere", radius=0.5, color=(1.2, 0.0, 0.0), name="ball")
    # The same in a scene file: `visviva run` says where and exits with code 2.
    text = vv.io.dump_scene(scene(colliders=False).scene, "toml")
    text += '[[entities]]\ntype = "collider"\nshape = "sphere"\nradius = 0.5\n'
    text += "color = [0.2, -0.1, 0.0]\n"
    path = tmp_path / "bad.toml"
    path.write_text(text)
    monkeypatch.setattr("sys.argv", ["visviva", "validate", str(path)])
    with pytest.raises(SystemExit) as exit_:
        main()
    captured = capsys.readouterr()
    assert exit_.value.code == 2
    assert "entities[2].color[1]" in captured.err and "-0.1" in captured.err
    assert "Traceback" not in captured.err


def test_inconsistent_scenery_arrays_are_refused(recording):
    static = dict(recording.static)
    static["scenery_triangles"] = static["scenery_triangles"] + 30  # past the box's 24 vertices
    broken = vv.Recording(recording.time, recording.fields, static=static, attrs=recording.attrs)
    with pytest.raises(vv.ModelError, match=r"scenery_triangles.*collider 0"):
        broken.geometry()
    del static["scenery_vertex_start"]
    broken = vv.Recording(recording.time, recording.fields, static=static, attrs=recording.attrs)
    with pytest.raises(vv.ModelError, match="scenery_vertex_start"):
        broken.geometry()


# --- the video -------------------------------------------------------------------------------


def test_the_video_frames_and_draws_the_scenery_in_its_colours(recording, tmp_path):
    import imageio.v3 as iio

    low, high = drawn_bounds(recording.geometry())
    # The framing holds every corner of the box and the sphere's top (1e-12 m of rounding).
    corners = box_corners()
    assert np.all(low <= corners.min(axis=0) + 1e-12) and np.all(
        high >= corners.max(axis=0) - 1e-12
    )
    assert high[1] >= SPHERE_CENTER[1] + SPHERE_RADIUS - 1e-12
    path = tmp_path / "scenery.mp4"
    render_video(recording, path, size=(480, 270))
    frames = iio.imread(path, index=None)
    for k in (0, frames.shape[0] - 1):
        for colour in (RED, GREEN, YELLOW):
            assert coloured(frames[k], colour).sum() > 200, (k, colour)


# --- the viewer ------------------------------------------------------------------------------


def test_the_viewer_draws_each_collider_as_a_static_mesh(recording, tmp_path):
    import json
    import re

    from playwright.sync_api import sync_playwright

    from test_viewer import CHROMIUM, CHROMIUM_FLAGS, Opened
    from visviva.viz.viewer import write_viewer

    path = write_viewer(recording, tmp_path / "scenery.html")
    html = path.read_text()
    data = re.search(r'<script type="application/json" id="visviva-data">(.*?)</script>', html)
    assert data is not None
    layer = json.loads(data.group(1))["layers"]["scenery"]
    assert layer["count"] == 3 and layer["names"] == ["crate", "collider_3", "wedge"]
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        try:
            page = Opened(browser, path)
            shown = page.js("visviva.scenery()")
            triangles = np.diff(recording.static["scenery_triangle_start"]).tolist()
            assert [mesh["triangles"] for mesh in shown] == triangles
            assert [mesh["name"] for mesh in shown] == layer["names"]
            for k in (0, recording.frames - 1):
                image = page.image(k)
                for colour in (RED, GREEN, YELLOW):
                    assert coloured(image, colour).sum() > 100, (k, colour)
            assert page.errors == []
        finally:
            browser.close()


# --- the exports -----------------------------------------------------------------------------


def test_usd_holds_each_collider_as_a_static_mesh_in_its_colour(recording, tmp_path):
    from pxr import Usd, UsdGeom

    from visviva.io.export import export_recording

    (path,) = export_recording(recording, tmp_path / "scenery.usda")
    stage = Usd.Stage.Open(str(path))
    scenery = recording.geometry().scenery
    assert scenery is not None
    assert [p.GetName() for p in stage.GetPrimAtPath("/World/scenery").GetChildren()] == [
        "crate",
        "collider_3",
        "wedge",
    ]
    for c, name in enumerate(scenery.names):
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(f"/World/scenery/{name}"))
        vertices, triangles = scenery.surface(c)
        points = np.array(mesh.GetPointsAttr().Get(), dtype=np.float64)
        np.testing.assert_allclose(points, vertices, rtol=1e-7, atol=1e-7)  # float32
        assert list(mesh.GetFaceVertexIndicesAttr().Get()) == triangles.ravel().tolist()
        assert set(mesh.GetFaceVertexCountsAttr().Get()) == {3}
        colour = mesh.GetDisplayColorPrimvar().Get()
        np.testing.assert_allclose(np.array(colour[0]), scenery.color[c], rtol=1e-6)
        # Static: no attribute of a collider has time samples.
        assert not any(a.GetNumTimeSamples() for a in mesh.GetPrim().GetAttributes())
    assert stage.GetPrimAtPath("/World/points").IsValid()  # the particles, as before


def test_gltf_holds_each_collider_as_a_static_node_without_channels(recording, tmp_path):
    import pygltflib

    from test_rigid_outputs import accessor
    from visviva.io.export import export_recording

    (path,) = export_recording(recording, tmp_path / "scenery.glb")
    document = pygltflib.GLTF2.load(str(path))
    blob = document.binary_blob()
    scenery = recording.geometry().scenery
    assert scenery is not None
    nodes = {node.name: i for i, node in enumerate(document.nodes)}
    (root,) = [i for i in document.scenes[0].nodes if document.nodes[i].name == "scenery"]
    assert document.nodes[root].children == [nodes[name] for name in scenery.names]
    animated = {c.target.node for a in document.animations for c in a.channels}
    for c, name in enumerate(scenery.names):
        node = document.nodes[nodes[name]]
        assert nodes[name] not in animated
        assert node.translation is None and node.rotation is None
        (primitive,) = document.meshes[node.mesh].primitives
        vertices, triangles = scenery.surface(c)
        position = accessor(document, blob, primitive.attributes.POSITION)
        np.testing.assert_array_equal(position, vertices.astype(np.float32))
        indices = accessor(document, blob, primitive.indices)[:, 0]
        np.testing.assert_array_equal(indices, triangles.ravel())
        material = document.materials[primitive.material]
        # glTF colours are linear: sRGB 0.9 is ((0.9 + 0.055) / 1.055)^2.4 = 0.7874 (IEC 61966-2-1).
        srgb = scenery.color[c]
        linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
        np.testing.assert_allclose(
            material.pbrMetallicRoughness.baseColorFactor[:3], linear, rtol=1e-6
        )


def test_obj_writes_the_colliders_once_beside_the_sequence(recording, tmp_path):
    from test_export import read_obj
    from visviva.io.export import export_recording
    from visviva.io.timeline import frames_at_rate

    paths = export_recording(recording, tmp_path / "obj", to="obj", fps=10.0)
    assert paths[-1] == tmp_path / "obj" / "scenery.obj"
    frames = paths[:-1]
    assert len(frames) == frames_at_rate(recording.time, 10.0).size
    # The frames hold the particles only, as without colliders.
    vertices, _, _ = read_obj(frames[0])
    assert vertices.shape[0] == recording["particle_position"].shape[1]
    scenery = recording.geometry().scenery
    assert scenery is not None
    text = paths[-1].read_text()
    objects = [line.split()[1] for line in text.splitlines() if line.startswith("o ")]
    assert objects == list(scenery.names)
    vertices, _, faces = read_obj(paths[-1])
    np.testing.assert_array_equal(vertices, scenery.vertices)  # repr: exact float64
    np.testing.assert_array_equal(np.array(faces) - 1, scenery.triangles)


def test_the_colliders_cast_shadows_on_the_ground(recording, tmp_path):
    """The same frame with and without the scenery, from the same camera: ground pixels (no
    collider's colour) darker with it are its shadows."""
    import imageio.v3 as iio

    from visviva.viz.video import Camera

    camera = Camera.framing(drawn_bounds(recording.geometry()), aspect=480 / 270)
    bare_static = {k: v for k, v in recording.static.items() if not k.startswith("scenery")}
    bare = vv.Recording(recording.time, recording.fields, static=bare_static)
    images = []
    for name, shown in (("with", recording), ("bare", bare)):
        path = render_video(shown, tmp_path / f"{name}.mp4", size=(480, 270), camera=camera)
        images.append(iio.imread(path, index=0).astype(float))
    drawn = np.zeros(images[0].shape[:2], dtype=bool)
    for colour in (RED, GREEN, YELLOW):
        drawn |= coloured(images[0].astype(np.uint8), colour)
    darker = images[1].mean(axis=2) - images[0].mean(axis=2) > 20.0  # of 255
    greyish = np.ptp(images[0], axis=2) < 25.0
    assert (darker & greyish & ~drawn).sum() > 300


def test_a_surface_without_triangles_packs_beside_the_others():
    # A degenerate body (sizes near 1e12 m, found by the hostile-number test) tessellated to no
    # triangles, given as shape (0,): it used to stop the recording with a ValueError.
    from visviva.geometry.packing import packed_surfaces

    square = np.zeros((4, 3)), np.array([[0, 1, 2], [0, 2, 3]])
    empty = np.zeros((2, 3)), np.array([], dtype=np.int64)
    packed = packed_surfaces([square, empty, square], "body")
    assert packed["body_triangles"].tolist() == [[0, 1, 2], [0, 2, 3], [6, 7, 8], [6, 8, 9]]
    assert packed["body_triangle_start"].tolist() == [0, 2, 2, 4]
