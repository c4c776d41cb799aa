"""Cloth and soft bodies drawn as surfaces: each body's triangles, and every output showing them.

The surfaces (:mod:`visviva.deformables.surfaces`) are checked as geometry: the triangle count
of each kind; a sheet's triangles all face one side and tile its area; a soft body's surface is
closed (each edge in two triangles, run once each way) and wound outward, its signed volume
``Σ a·(b × c)/6`` equal to the body's volume. Then a cloth scene recorded by ``vv.Simulation``
keeps its triangles through an HDF5 file into the video, the web viewer (its payload, and the
page drawn in Chromium), USD (read with ``pxr``), glTF (``pygltflib``) and OBJ.
"""

from __future__ import annotations

import base64
import io
import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import imageio.v3 as iio
import numpy as np
import pygltflib
import pytest
from PIL import Image
from playwright.sync_api import Browser, sync_playwright
from pxr import Usd, UsdGeom

import visviva as vv
from visviva.deformables import (
    cloth_grid,
    cloth_mesh,
    hair,
    rope,
    soft_lattice,
    soft_mesh,
    spring_graph,
)
from visviva.io.export import export_recording
from visviva.io.timeline import frames_at_rate
from visviva.viz.video import render_video
from visviva.viz.viewer import write_viewer

#: Cube corner (i, j, k) at index i + 2j + 4k, and its five positively oriented tetrahedra
#: (as in tests/test_soft_meshes.py).
CUBE = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)
FIVE_TETRAHEDRA = np.array([[0, 5, 3, 6], [1, 3, 0, 5], [2, 0, 3, 6], [4, 5, 0, 6], [7, 3, 5, 6]])
CHROMIUM = Path("/usr/bin/chromium")
#: Output rate of the exports [frames/s]: the recorded cloth's own (h = 0.02 s, every step).
FPS = 50.0


def signed_volume(points: np.ndarray, faces: np.ndarray) -> float:
    """Σ a·(b × c)/6 over the triangles (a, b, c): the enclosed volume [m³] of a closed
    surface wound outward (the divergence theorem), negative if wound inward."""
    a, b, c = (points[faces[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def assert_closed_and_consistent(faces: np.ndarray) -> None:
    """Each edge is in exactly two triangles, which run along it in opposite directions."""
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    undirected, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert (count == 2).all(), undirected[count != 2]
    assert np.unique(directed, axis=0).shape[0] == directed.shape[0]  # no edge run twice


def kuhn_mesh(cells: list[tuple[int, int, int]], spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Lattice points ``(n, 3)`` [m] ``spacing`` apart and six positively oriented tetrahedra
    in each of the unit ``cells`` (given by their lowest corner): the Kuhn split along the
    paths from a cell's lowest corner to its highest, one axis at a time, which conforms across
    cells (a shared face is cut along the same diagonal on both sides). Only the corners of the
    cells are points."""
    axes = np.eye(3, dtype=int)
    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    corners = []
    for cell in cells:
        for path in paths:
            chain = [np.array(cell)]
            for axis in path:
                chain.append(chain[-1] + axes[axis])
            if np.linalg.det(np.diff(np.array(chain, dtype=float), axis=0)) < 0.0:
                chain[1], chain[2] = chain[2], chain[1]
            corners.append(chain)
    lattice, tetrahedra = np.unique(np.reshape(corners, (-1, 3)), axis=0, return_inverse=True)
    return spacing * lattice.astype(float), tetrahedra.reshape(-1, 4)


# --- the triangles of each kind ------------------------------------------------------------


@pytest.mark.parametrize("resolution", [(2, 2), (3, 7), (8, 5), (64, 64)])
def test_a_cloth_grid_has_two_triangles_per_cell_all_facing_across_times_along(resolution):
    nu, nv = resolution
    along, across = np.array([1.2, 0.3, 0.0]), np.array([0.1, -0.2, 0.9])
    sheet = cloth_grid(np.array([0.5, 1.0, -2.0]), along, across, resolution, 0.1, 100, 10, 1)
    faces = sheet.faces
    assert faces.shape == (2 * (nu - 1) * (nv - 1), 3) and faces.dtype == np.int64
    corner = sheet.points[faces]
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    front = np.cross(across, along)
    # Every triangle faces the front, and together they tile the parallelogram once.
    assert (normal @ front > 0.0).all()
    area = 0.5 * np.linalg.norm(normal, axis=1).sum()
    assert area == pytest.approx(np.linalg.norm(front), rel=1e-12)
    # Inside the sheet each edge is run once each way; the border once, by one triangle.
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    assert np.unique(directed, axis=0).shape[0] == directed.shape[0]
    _, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert (count == 1).sum() == 2 * (nu - 1) + 2 * (nv - 1)


def test_the_default_sheet_faces_up():
    sheet = cloth_grid(np.array([0, 1.0, 0]), np.eye(3)[0], np.eye(3)[2], (4, 4), 0.1, 1, 1, 1)
    a, b, c = (sheet.points[sheet.faces[:, i]] for i in range(3))
    assert (np.cross(b - a, c - a)[:, 1] > 0.0).all()


def test_a_cloth_mesh_is_drawn_by_its_triangles_as_given():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1], [2, 0, 0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2]])
    np.testing.assert_array_equal(cloth_mesh(vertices, triangles, 0.2, 10.0, 1.0).faces, triangles)


@pytest.mark.parametrize("resolution", [(2, 2, 2), (3, 4, 5), (6, 2, 3)])
def test_a_soft_lattice_is_drawn_by_its_six_faces_closed_and_wound_outward(resolution):
    a, b, c = resolution
    origin, size = np.array([0.3, -1.2, 2.0]), np.array([0.3, 0.5, 0.7])
    body = soft_lattice(origin, size, resolution, 100.0, 10.0, 10.0, 10.0)
    faces = body.faces
    assert faces.shape == (4 * ((a - 1) * (b - 1) + (b - 1) * (c - 1) + (a - 1) * (c - 1)), 3)
    assert_closed_and_consistent(faces)
    assert signed_volume(body.points, faces) == pytest.approx(np.prod(size), rel=1e-12)
    # Only the points on the box's faces are used, and each of them.
    index = np.arange(a * b * c).reshape(c, b, a)
    inside = index[1:-1, 1:-1, 1:-1].ravel()
    assert set(np.unique(faces)) == set(range(a * b * c)) - set(inside)


def test_a_tetrahedron_is_drawn_by_its_four_faces_wound_outward():
    corners = np.array([[0.0, 1, 0], [1, 1, 0], [0, 2, 0], [0, 1, 1]])
    body = soft_mesh(corners, np.array([[0, 1, 2, 3]]), 600.0, 500.0)
    assert body.faces.shape == (4, 3)
    assert_closed_and_consistent(body.faces)
    assert signed_volume(body.points, body.faces) == pytest.approx(1 / 6, rel=1e-14)


@pytest.mark.parametrize(
    ("vertices", "tetrahedra", "volume"),
    [
        (0.3 * CUBE + [1.0, 2.0, -3.0], FIVE_TETRAHEDRA, 0.3**3),
        # Three of the four cells of a 2 × 2 × 1 block: an L, not convex; six per cell.
        (*kuhn_mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0)], 0.2), 3 * 0.2**3),
    ],
    ids=["five-tetrahedra-cube", "kuhn-L"],
)
def test_a_soft_mesh_is_drawn_by_its_boundary_closed_and_wound_outward(
    vertices, tetrahedra, volume
):
    body = soft_mesh(np.asarray(vertices, dtype=float), tetrahedra, 100.0, 10.0)
    faces = body.faces
    # Four faces per tetrahedron; each inner face is in two of them, each boundary face in one.
    corners = np.sort(tetrahedra[:, [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]], axis=2)
    _, count = np.unique(corners.reshape(-1, 3), axis=0, return_counts=True)
    assert faces.shape == (int((count == 1).sum()), 3) and set(count.tolist()) == {1, 2}
    assert_closed_and_consistent(faces)
    assert signed_volume(body.points, faces) == pytest.approx(volume, rel=1e-12)


def test_the_l_shaped_mesh_is_drawn_by_two_triangles_per_outer_square():
    points, tetrahedra = kuhn_mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0)], 1.0)
    faces = soft_mesh(points, tetrahedra, 100.0, 10.0).faces
    # Unit squares on the L's outside: 3 below, 3 above, 8 around its sides.
    assert faces.shape[0] == 2 * (3 + 3 + 8)


def test_strands_and_spring_graphs_have_no_surface():
    points = np.array([[0.0, 0, 0], [0, -0.1, 0], [0, -0.2, 0], [0.1, -0.2, 0]])
    mass = np.full(4, 0.1)
    for body in (
        rope(points, mass, 100.0, 1.0),
        hair(points, mass, 100.0, 1.0, 0.5),
        spring_graph(points, mass, np.array([[0, 1], [1, 2], [2, 3], [3, 0]]), 10.0),
    ):
        assert body.faces.shape == (0, 3) and body.faces.dtype == np.int64


# --- a recorded scene ----------------------------------------------------------------------


def test_a_recording_holds_each_surface_shifted_to_its_points_and_edges_only_for_strands():
    builder = vv.SceneBuilder(name="bodies")
    builder.set_integration(method="symplectic_euler", dt=1e-4, duration=0.002, record_every=5)
    builder.add_particles([[3.0, 1.0, 0.0], [3.0, 2.0, 0.0]], mass=1.0)
    rope_points = [[2.0, 1.0 - 0.1 * i, 0.0] for i in range(4)]
    builder.add_rope(rope_points, mass=0.01, stiffness=50.0)
    builder.add_cloth((4, 3), stiffness=50.0, areal_density=0.1)
    builder.add_soft_lattice((2, 3, 2), stiffness=50.0, origin=(0, 2, 0), size=(0.2, 0.3, 0.2))
    tetrahedron = [[0, 1, 2], [0.2, 1, 2], [0, 1.2, 2], [0, 1, 2.2]]
    builder.add_soft_mesh(tetrahedron, [[0, 1, 2, 3]], density=100.0, stiffness=50.0)
    recording = vv.Simulation(builder.build()).record(until=0.002)
    static = recording.static
    # Points: 2 particles, 4 rope, 12 cloth, 12 lattice, 4 tetrahedron.
    cloth = cloth_grid(np.array([0, 1.0, 0]), np.eye(3)[0], np.eye(3)[2], (4, 3), 0.1, 1, 1, 0)
    lattice = soft_lattice(np.zeros(3), np.ones(3), (2, 3, 2), 1.0, 1.0, 1.0, 1.0)
    outward = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])  # the tetrahedron's
    expected = np.concatenate([cloth.faces + 6, lattice.faces + 18, outward + 30])
    np.testing.assert_array_equal(static["faces"], expected)
    np.testing.assert_array_equal(static["edges"], [[2, 3], [3, 4], [4, 5]])  # the rope's
    geometry = recording.geometry()
    np.testing.assert_array_equal(geometry.off_faces(), [0, 1, 2, 3, 4, 5])
    assert geometry.points.shape == (recording.frames, 34, 3)


# --- every output draws the surface of a recorded cloth -------------------------------------


@pytest.fixture(scope="module")
def cloth(tmp_path_factory: pytest.TempPathFactory) -> vv.Recording:
    """A 1 m sheet of 6 × 5 points held at two corners, falling for 0.4 s (21 frames), read
    back from a recording file."""
    builder = vv.SceneBuilder(name="sheet")
    builder.set_integration(method="backward_euler", dt=0.02, duration=0.4, record_every=1)
    builder.add_cloth(
        (6, 5),
        stiffness=200.0,
        bending=0.1,
        areal_density=0.1,
        damping=0.02,
        pinned=[0, 5],
        name="sheet",
    )
    recorded = vv.Simulation(builder.build()).record(until=0.4)
    path = tmp_path_factory.mktemp("sheet") / "recording.h5"
    vv.io.save_recording(recorded, path)
    recording = vv.io.load_recording(path)
    assert recording.static["faces"].shape == (2 * 5 * 4, 3) and "edges" not in recording.static
    points = recording["particle_position"]
    assert np.abs(points[-1] - points[0]).max() > 0.1  # it fell and swung
    return recording


def test_usd_holds_the_sheet_as_one_mesh_of_its_triangles(cloth, tmp_path):
    (path,) = export_recording(cloth, tmp_path / "sheet.usda", fps=FPS)
    stage = Usd.Stage.Open(str(path))
    assert not stage.GetPrimAtPath("/World/points") and not stage.GetPrimAtPath("/World/edges")
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/mesh"))
    faces = cloth.static["faces"]
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == [3] * faces.shape[0]
    assert list(mesh.GetFaceVertexIndicesAttr().Get()) == faces.ravel().tolist()
    shown = frames_at_rate(cloth.time, FPS)
    last = shown.size - 1
    read = np.array(mesh.GetPointsAttr().Get(last))
    np.testing.assert_allclose(read, cloth["particle_position"][shown[last]], rtol=0, atol=1e-6)


def test_gltf_holds_the_sheet_as_one_primitive_of_its_triangles(cloth, tmp_path):
    (path,) = export_recording(cloth, tmp_path / "sheet.glb", fps=FPS)
    document = pygltflib.GLTF2.load(str(path))
    (primitive,) = document.meshes[0].primitives  # every point is a vertex: no POINTS
    assert primitive.mode == pygltflib.TRIANGLES
    accessor = document.accessors[primitive.indices]
    assert (accessor.componentType, accessor.type) == (pygltflib.UNSIGNED_INT, "SCALAR")
    view = document.bufferViews[accessor.bufferView]
    start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
    indices = np.frombuffer(document.binary_blob(), "<u4", count=accessor.count, offset=start)
    np.testing.assert_array_equal(indices, cloth.static["faces"].ravel())


def test_obj_writes_the_triangles_as_f_lines(cloth, tmp_path):
    written = export_recording(cloth, tmp_path / "obj", to="obj", fps=FPS)
    lines = written[-1].read_text().splitlines()
    faces = [[int(v) for v in line.split()[1:]] for line in lines if line.startswith("f ")]
    np.testing.assert_array_equal(faces, cloth.static["faces"] + 1)  # OBJ counts from 1
    assert sum(line.startswith("v ") for line in lines) == 30
    assert not any(line.startswith("l ") for line in lines)


def orange(image: np.ndarray) -> np.ndarray:
    """Pixels of the faces' front colour #d9822b, lit or in shade."""
    r, g, b = (image[..., i].astype(float) for i in range(3))
    return (r - b > 60.0) & (r > g) & (g > b)


def blue(image: np.ndarray) -> np.ndarray:
    """Pixels of the default spheres' colour #2f6fb3, darker than the sky."""
    r, b = image[..., 0].astype(float), image[..., 2].astype(float)
    return (b - r > 0.45 * b) & (b > 25.0) & (r < 110.0)


def test_the_video_draws_the_sheet_as_a_surface_not_as_spheres(cloth, tmp_path):
    path = render_video(cloth, tmp_path / "sheet.gif", fps=FPS, size=(320, 180))
    first = iio.imread(path, plugin="pillow", mode="RGB", index=None)[0]
    assert orange(first).sum() > 0.03 * first.shape[0] * first.shape[1]  # seen from above
    assert blue(first).sum() == 0  # its points are the surface's vertices, not spheres
    # The same points without their surface are drawn as spheres.
    static = {k: v for k, v in cloth.static.items() if k != "faces"}
    bare = vv.Recording(cloth.time, cloth.fields, units=cloth.units, static=static)
    path = render_video(bare, tmp_path / "bare.gif", fps=FPS, size=(320, 180))
    first = iio.imread(path, plugin="pillow", mode="RGB", index=None)[0]
    assert orange(first).sum() == 0 and blue(first).sum() > 30


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    if not CHROMIUM.is_file():
        pytest.fail(f"the page checks need Debian's Chromium at {CHROMIUM}", pytrace=False)
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(
            executable_path=str(CHROMIUM), args=["--headless", "--no-sandbox", "--disable-gpu"]
        )
        yield chromium
        chromium.close()


def shown(browser: Browser, path: Path, frame: int) -> tuple[np.ndarray, dict[str, Any]]:
    """The page's picture of ``frame`` (RGB, 640 × 480) and the spheres it draws there."""
    page = browser.new_page(viewport={"width": 640, "height": 480})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto(path.as_uri())
        page.wait_for_function("window.visviva && window.visviva.ready === true")
        url = page.evaluate(
            f"visviva.pause(), visviva.setFrame({frame}), "
            "document.getElementById('view').toDataURL('image/png')"
        )
        drawn = page.evaluate("visviva.drawn()")
    finally:
        page.close()
    assert errors == []
    png = base64.b64decode(url.split(",", 1)[1])
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")), drawn


def test_the_viewer_embeds_the_triangles_and_draws_them_without_spheres(cloth, browser, tmp_path):
    path = write_viewer(cloth, tmp_path / "sheet.html")
    text = path.read_text()
    match = re.search(r'<script type="application/json" id="visviva-data">(.*?)</script>', text)
    assert match is not None
    layers = json.loads(match.group(1))["layers"]
    faces = np.frombuffer(base64.b64decode(layers["faces"]["indices"]), "<u4").reshape(-1, 3)
    np.testing.assert_array_equal(faces, cloth.static["faces"])
    assert layers["points"]["spheres"] == ""  # no point is drawn as a sphere
    image, drawn = shown(browser, path, 0)
    assert drawn["count"] == 0
    assert orange(image).sum() > 0.03 * image.shape[0] * image.shape[1]


def test_points_off_the_surface_keep_their_spheres_radii_and_colours(browser, tmp_path):
    # A square of two triangles (points 0-3) rising beside a green and a blue ball.
    t = np.arange(10) / 10.0
    points = np.zeros((10, 6, 3))
    points[:] = [[0, 1, 0], [1, 1, 0], [0, 1, 1], [1, 1, 1], [2, 1, 0], [-1, 0.5, 0.5]]
    points[:, :, 1] += t[:, None]
    static = {
        "faces": np.array([[0, 2, 1], [1, 2, 3]]),
        "particle_radius": np.array([0.08, 0.08, 0.08, 0.08, 0.2, 0.1]),
        "particle_color": np.array([[1.0, 0.0, 0.0]] * 4 + [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    }
    fields, units = {"particle_position": points}, {"particle_position": "m"}
    recording = vv.Recording(t, fields, static=static, units=units)
    _, drawn = shown(browser, write_viewer(recording, tmp_path / "mixed.html"), 5)
    assert drawn["count"] == 2 and drawn["colours"] == [[0, 255, 0], [0, 0, 255]]
    np.testing.assert_allclose(drawn["radii"], [0.2, 0.1], rtol=1e-6)
    np.testing.assert_allclose(drawn["centres"], points[5, 4:], atol=1e-4)
    path = render_video(recording, tmp_path / "mixed.gif", fps=10.0, size=(320, 180))
    image = iio.imread(path, plugin="pillow", mode="RGB", index=None)[5].astype(float)
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    assert ((g - r > 80.0) & (g - b > 80.0)).sum() > 30  # the green ball
    red = (r > 60.0) & (g < 0.25 * r) & (b < 0.25 * r)  # not the faces' orange, g ≈ 0.6 r
    assert red.sum() == 0  # no red sphere on the square
