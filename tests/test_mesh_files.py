"""Cloth from mesh files: ``cloth_mesh`` with ``path =`` (a scene file, relative to its folder)
or ``add_cloth_mesh(path=...)``, read by trimesh; the same cloth from every format; files that
are not one readable triangle mesh refused with the path named, and nothing that blocks."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numba
import numpy as np
import pytest
import trimesh

import visviva as vv
from visviva.io.meshes import MAX_MESH_BYTES, read_triangle_mesh

EXAMPLES = Path(__file__).parents[1] / "examples"
TABLECLOTH = EXAMPLES / "meshes" / "tablecloth.obj"
SCENE = EXAMPLES / "scenes" / "tablecloth.toml"


@pytest.fixture
def one_thread():
    """A small cloth: Numba's parallel kernels cost more to launch than they save (and on a
    busy machine, far more)."""
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(previous)


def area(vertices: np.ndarray, triangles: np.ndarray) -> float:
    corners = vertices[triangles]
    sides = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return 0.5 * float(np.linalg.norm(sides, axis=1).sum())


def test_the_example_scene_reads_its_mesh_relative_to_its_folder(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # nowhere near the mesh
    model = vv.load_model(SCENE)
    vertices, triangles = read_triangle_mesh(TABLECLOTH)
    assert vertices.shape == (217, 3) and triangles.shape == (384, 3)
    assert np.array_equal(model.particle_position, vertices)
    # A disc of 0.5 m, 1 m up, weighing density × area (the 48-gon's area, just under π r²).
    assert np.allclose(vertices[:, 1], 1.0)
    assert model.particle_mass.sum() == pytest.approx(0.1 * area(vertices, triangles), rel=1e-14)
    assert area(vertices, triangles) == pytest.approx(np.pi * 0.25, rel=3e-3)
    # The built scene holds the mesh itself: it builds again without the file.
    mesh = model.scene.entities[0]
    assert mesh.path is None and len(mesh.vertices) == 217
    assert vv.model.build_model(model.scene).particle_count == 217


def test_python_and_the_scene_file_give_the_same_cloth(monkeypatch):
    from_file = vv.load_model(SCENE)
    monkeypatch.chdir(TABLECLOTH.parent)  # from Python a relative path is the working folder's
    builder = vv.SceneBuilder(name="tablecloth", description=from_file.scene.scene.description)
    builder.set_integration(method="projected_newton", dt=1 / 120, duration=2.0)
    builder.add_cloth_mesh(path=Path("tablecloth.obj"), areal_density=0.1, stiffness=1000.0,
                           bending=0.05, damping=0.05, radius=0.01, color=(0.9, 0.9, 0.8),
                           name="tablecloth")  # fmt: skip
    builder.add_force("damping", rate=1.0, name="air")
    builder.add_collider("sphere", center=(0, 0.6, 0), radius=0.3, restitution=0.0,
                         friction=0.5, name="ball")  # fmt: skip
    from_python = builder.build()
    assert builder.scene.entities[0].path is None  # read at once
    for name in ("particle_position", "particle_mass", "particle_radius"):
        assert np.array_equal(getattr(from_python, name), getattr(from_file, name))
    springs = [f for f in from_python.forces if isinstance(f, vv.forces.Springs)]
    again = [f for f in from_file.forces if isinstance(f, vv.forces.Springs)]
    assert np.array_equal(springs[0].pairs, again[0].pairs)
    assert np.array_equal(springs[0].rest_length, again[0].rest_length)


def test_the_tablecloth_drapes_over_the_ball(one_thread):
    model = vv.load_model(SCENE)
    simulation = vv.Simulation(model)
    simulation.run(until=1.0)
    x = simulation.state["particle_position"]
    clearance = np.linalg.norm(x - [0.0, 0.6, 0.0], axis=1) - 0.3 - 0.01
    assert clearance.min() > -1e-6  # never inside the ball
    assert x[0, 1] == pytest.approx(0.91, abs=1e-3)  # the centre rests on top
    assert x[:, 1].min() < 0.75  # the rim hangs down the sides


@pytest.mark.parametrize("kind", ["stl", "stl_ascii", "ply", "off", "glb", "obj"])
def test_every_format_gives_the_same_mesh(tmp_path, kind):
    """An STL repeats each vertex in every triangle, a glTF may order them anew: merged by
    position, every format holds the same 217 vertices and 384 triangles."""
    vertices, triangles = read_triangle_mesh(TABLECLOTH)
    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    suffix = "stl" if kind == "stl_ascii" else kind
    path = tmp_path / f"tablecloth.{suffix}"
    path.write_bytes(_bytes(mesh.export(file_type=kind)))
    read, corners = read_triangle_mesh(path)
    assert read.shape == vertices.shape and corners.shape == triangles.shape
    # STL, PLY and glTF store float32 (trimesh writes them so): a relative 6e-8.
    assert np.abs(_sorted(read) - _sorted(vertices)).max() <= 1e-7
    assert area(read, corners) == pytest.approx(area(vertices, triangles), rel=1e-6)
    # Shared edges stay shared: the cloth is one piece, every vertex in a triangle.
    assert np.array_equal(np.unique(corners), np.arange(read.shape[0]))


def test_pins_index_the_vertices_as_read(tmp_path):
    vertices, _ = read_triangle_mesh(TABLECLOTH)
    rim = np.flatnonzero(np.hypot(vertices[:, 0], vertices[:, 2]) > 0.499)
    builder = vv.SceneBuilder()
    builder.add_cloth_mesh(path=TABLECLOTH, areal_density=0.1, stiffness=100.0, pinned=rim.tolist())
    model = builder.build()
    assert model.particle_pinned.sum() == 48 == rim.shape[0]
    with pytest.raises(vv.SceneError) as error:
        vv.SceneBuilder().add_cloth_mesh(path=TABLECLOTH, areal_density=0.1, stiffness=100.0,
                                         pinned=[3, 217])  # fmt: skip
    assert "entities[0].pinned" in str(error.value)
    assert "pinned index 217 is not a vertex of the mesh" in str(error.value)
    assert str(TABLECLOTH) in str(error.value)


def _bytes(data: str | bytes) -> bytes:
    return data.encode() if isinstance(data, str) else data


def _sorted(points: np.ndarray) -> np.ndarray:
    return points[np.lexsort(np.round(points, 6).T[::-1])]


def _two_meshes() -> bytes:
    scene = trimesh.Scene([trimesh.creation.box(), trimesh.creation.icosphere()])
    return _bytes(scene.export(file_type="glb"))


def _point_cloud() -> bytes:
    points = trimesh.PointCloud(np.random.default_rng(0).random((20, 3)))
    return _bytes(points.export(file_type="ply"))


BAD_FILES = [
    ("empty.obj", b"", "is empty"),
    ("garbage.obj", bytes(range(256)) * 40, "is not UTF-8 text"),
    ("garbage.stl", np.random.default_rng(1).bytes(5000), "is neither a binary STL file"),
    ("garbage.ply", np.random.default_rng(2).bytes(5000), "cannot be read as PLY"),
    ("garbage.glb", np.random.default_rng(3).bytes(5000), "cannot be read as GLB"),
    ("nan.obj", b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "vertex 2 is at [nan  1.  0.]"),
    ("comments.obj", b"# nothing here\n", "holds no mesh"),
    ("lines.obj", b"v 0 0 0\nv 1 0 0\nl 1 2\n", "without triangles"),
    ("two.glb", _two_meshes(), "is a scene of 2 meshes"),
    ("points.ply", _point_cloud(), "a point cloud"),
    ("cloth.fbx", b"anything", "must end in .obj, .stl, .ply, .off, .glb, .gltf"),
    ("latin1.obj", "# é\nv 0 0 0\n".encode("latin-1"), "byte 0xe9 at offset 2"),
]


@pytest.mark.parametrize(("name", "data", "message"), BAD_FILES, ids=[f[0] for f in BAD_FILES])
def test_files_that_are_not_one_triangle_mesh_are_refused_naming_them(tmp_path, name, data,
                                                                     message):  # fmt: skip
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(vv.SceneError) as error:
        vv.SceneBuilder().add_cloth_mesh(path=path, areal_density=0.1, stiffness=10.0)
    text = str(error.value)
    assert "entities[0].path" in text and repr(str(path)) in text
    assert message in text


def test_special_files_and_huge_ones_are_refused_without_reading_them(tmp_path):
    zero = tmp_path / "zero.obj"
    zero.symlink_to("/dev/zero")  # says it is empty, and never ends
    pipe = tmp_path / "pipe.stl"
    os.mkfifo(pipe)  # opening it for reading would wait for a writer
    huge = tmp_path / "huge.stl"
    with huge.open("wb") as sparse:
        sparse.truncate(2 * 2**30)  # 2 GB of nothing, on disk in no time
    folder = tmp_path / "folder.obj"
    folder.mkdir()
    cases = [
        (zero, "is not a regular file"),
        (pipe, "is not a regular file"),
        (huge, f"holds 2147483648 bytes, more than the {MAX_MESH_BYTES}"),
        (folder, "is a directory"),
        (tmp_path / "missing.obj", "cannot be opened: No such file or directory"),
    ]
    for path, message in cases:
        with pytest.raises(vv.SceneError, match=message):
            vv.SceneBuilder().add_cloth_mesh(path=path, areal_density=0.1, stiffness=10.0)


def test_a_mesh_no_cloth_can_be_made_of_is_refused_at_its_path(tmp_path):
    fan = tmp_path / "fan.obj"  # three triangles on one edge: not manifold
    fan.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n")
    with pytest.raises(vv.SceneError) as error:
        vv.SceneBuilder().add_cloth_mesh(path=fan, areal_density=0.1, stiffness=10.0)
    assert "entities[0].path" in str(error.value)
    assert f"the mesh in {str(fan)!r} at triangles[2]" in str(error.value)


def test_path_or_arrays_exactly_one(tmp_path):
    builder = vv.SceneBuilder()
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0]]
    with pytest.raises(vv.SceneError, match="not both"):
        builder.add_cloth_mesh(
            square, [[0, 1, 2]], path=TABLECLOTH, areal_density=0.1, stiffness=1.0
        )
    with pytest.raises(vv.SceneError, match="the mesh is missing: give the mesh as"):
        builder.add_cloth_mesh(areal_density=0.1, stiffness=1.0)
    with pytest.raises(vv.SceneError, match="`triangles` missing"):
        builder.add_cloth_mesh(square, areal_density=0.1, stiffness=1.0)
    assert not builder.scene.entities  # nothing refused was added


def test_a_scene_file_whose_mesh_is_missing_names_the_line_and_the_resolved_path(tmp_path):
    scene = tmp_path / "scenes" / "cloth.toml"
    scene.parent.mkdir()
    scene.write_text(
        '[[entities]]\ntype = "cloth_mesh"\npath = "meshes/cloth.obj"\n'
        "areal_density = 0.1\nstiffness = 10.0\n"
    )
    with pytest.raises(vv.SceneError) as error:
        vv.load_model(scene)
    (problem,) = error.value.problems
    assert problem.path == "entities[0].path" and problem.line == 3
    assert str(tmp_path / "scenes" / "meshes" / "cloth.obj") in problem.message
    # Copied there, it loads, wherever the scene is run from.
    (tmp_path / "scenes" / "meshes").mkdir()
    shutil.copy(TABLECLOTH, tmp_path / "scenes" / "meshes" / "cloth.obj")
    assert vv.load_model(scene).particle_count == 217


def test_a_gltf_scene_of_one_mesh_is_read_where_its_node_places_it(tmp_path):
    vertices, triangles = read_triangle_mesh(TABLECLOTH)
    scene = trimesh.Scene()
    lift = trimesh.transformations.translation_matrix([0.0, 2.0, 0.0])
    scene.add_geometry(trimesh.Trimesh(vertices, triangles, process=False), transform=lift)
    path = tmp_path / "lifted.glb"
    path.write_bytes(_bytes(scene.export(file_type="glb")))
    read, _ = read_triangle_mesh(path)
    assert np.abs(_sorted(read) - _sorted(vertices + [0.0, 2.0, 0.0])).max() <= 2e-7
