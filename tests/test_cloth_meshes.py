"""Cloth from triangle meshes: stretch springs on the edges, bend springs across the edges two
triangles share, a third of each triangle's mass on each corner (Baraff & Witkin 1998).
Tested on a square of two triangles, against a grid cloth of the same points (the same weight,
and a hanging sheet whose pins carry exactly its weight), and bad meshes refused at the
triangle, edge or vertex at fault."""

import numpy as np
import pytest

import visviva as vv
from visviva.deformables import cloth_grid, cloth_mesh
from visviva.deformables.topology import BEND, STRETCH
from visviva.forces import Springs

G = 9.81
SQUARE = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 0.0, 1.0], [0.0, 0.0, 1.0]])


def _triangulated(nu: int, nv: int) -> np.ndarray:
    """The triangles of a grid of ``nu × nv`` points (index ``j·nu + i``): two per cell."""
    i, j = np.meshgrid(np.arange(nu - 1), np.arange(nv - 1))
    a = (j * nu + i).reshape(-1)
    b, c, d = a + 1, a + nu, a + nu + 1
    return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def test_a_square_of_two_triangles_has_five_edges_one_bend_and_weighs_density_times_area():
    sheet = cloth_mesh(SQUARE, np.array([[0, 1, 2], [0, 2, 3]]), 0.3, 100.0, 2.0)
    assert int((sheet.family == STRETCH).sum()) == 5
    np.testing.assert_array_equal(sheet.pairs[sheet.family == BEND], [[1, 3]])
    assert sheet.mass.sum() == pytest.approx(0.3 * 2.0)
    # Vertices 0 and 2 are in both triangles, 1 and 3 in one: a third of 1 m² each.
    np.testing.assert_allclose(sheet.mass, 0.3 * np.array([2, 1, 2, 1]) / 3)
    np.testing.assert_allclose(sheet.rest_length()[sheet.family == BEND], np.sqrt(5.0))
    assert BEND not in cloth_mesh(SQUARE, np.array([[0, 1, 2], [0, 2, 3]]), 0.3, 100.0, 0.0).family


def test_a_triangulated_grid_weighs_what_the_grid_cloth_weighs():
    nu, nv = 7, 5
    grid = cloth_grid(
        np.zeros(3), np.array([1.2, 0, 0]), np.array([0, 0, 0.8]), (nu, nv), 0.2, 100, 50, 1
    )
    mesh = cloth_mesh(grid.points, _triangulated(nu, nv), 0.2, 100.0, 1.0)
    assert mesh.mass.sum() == pytest.approx(grid.mass.sum())
    # A point inside the sheet is in six half cells: the grid's four quarter cells.
    inside = np.arange(nu * nv).reshape(nv, nu)[1:-1, 1:-1].reshape(-1)
    np.testing.assert_allclose(mesh.mass[inside], grid.mass[inside])
    # Edges: the grid's structural springs plus one diagonal per cell; a bend spring across
    # each edge inside the sheet.
    cells = (nu - 1) * (nv - 1)
    structural = (nu - 1) * nv + nu * (nv - 1)
    assert int((mesh.family == STRETCH).sum()) == structural + cells
    assert int((mesh.family == BEND).sum()) == structural + cells - 2 * (nu - 1 + nv - 1)


def _hanging(body: str) -> vv.Simulation:
    """A 0.6 m square sheet of 7 × 7 points hanging in the x-y plane from its top row."""
    builder = vv.SceneBuilder(name="hanging")
    builder.set_integration(method="backward_euler", dt=0.05, duration=20.0)
    along, across = np.array([0.6, 0.0, 0.0]), np.array([0.0, -0.6, 0.0])
    options = {
        "areal_density": 0.1,
        "stiffness": 200.0,
        "bending": 0.5,
        "damping": 0.05,
        "pinned": range(7),
    }
    if body == "grid":
        builder.add_cloth((7, 7), origin=(0, 1, 0), along=along, across=across, **options)
    else:
        points = cloth_grid(np.array([0.0, 1.0, 0.0]), along, across, (7, 7), 1, 1, 1, 1).points
        builder.add_cloth_mesh(points, _triangulated(7, 7), **options)
    return vv.Simulation(builder.build())


@pytest.mark.parametrize("body", ["grid", "mesh"])
def test_a_hanging_sheet_at_rest_hangs_its_weight_on_its_pins(body):
    simulation = _hanging(body)
    simulation.run(until=20.0)
    model = simulation.model
    x = simulation.state["particle_position"]
    (springs,) = [f for f in model.forces if isinstance(f, Springs)]
    force = np.zeros_like(x)
    springs.accumulate(0.0, x, np.zeros_like(x), force)
    weight = model.particle_mass * G
    held = model.particle_pinned
    # Each free point is at rest: its springs hold its weight.
    np.testing.assert_allclose(force[~held, 1], weight[~held], rtol=1e-6)
    np.testing.assert_allclose(force[~held][:, [0, 2]], 0.0, atol=1e-9 * weight.max())
    # So the pinned row carries the weight of the rest, density × area of the sheet in all.
    assert -force[held, 1].sum() == pytest.approx(weight[~held].sum(), rel=1e-6)
    assert weight.sum() == pytest.approx(0.1 * 0.36 * G)
    assert x[:, 1].min() < 0.4 - 1e-4  # it has stretched under its weight


def test_a_cloth_mesh_from_a_scene_file_is_drawn_by_its_triangles(tmp_path):
    path = tmp_path / "mesh.toml"
    path.write_text(
        """
        [integration]
        method = "backward_euler"
        dt = 0.01
        duration = 0.05

        [[entities]]
        type = "cloth_mesh"
        name = "flag"
        vertices = [[0, 1, 0], [1, 1, 0], [1, 0, 0], [0, 0, 0]]
        triangles = [[0, 1, 2], [0, 2, 3]]
        areal_density = 0.2  # kg/m²
        stiffness = 100.0    # N/m
        bending = 1.0        # N/m
        pinned = [0, 1]
        """
    )
    model = vv.load_model(path)
    assert model.particle_mass.sum() == pytest.approx(0.2)
    vv.run_scene(model, tmp_path / "out")
    recording = vv.io.load_recording(tmp_path / "out" / "recording.h5")
    # The triangles as given; the springs are not drawn over them.
    np.testing.assert_array_equal(recording.static["faces"], [[0, 1, 2], [0, 2, 3]])
    assert "edges" not in recording.static


FIVE = [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1], [0.5, 1, 0]]


@pytest.mark.parametrize(
    ("mesh", "path", "message"),
    [
        ({"triangles": [[0, 1, 2], [0, 2, 7]]}, "triangles[1]", "names a vertex past the 4"),
        (
            {"vertices": [[0, 0, 0], [1, 0, 0], [1, 0, 1], [2, 0, 2]]},
            "triangles[1]",
            r"triangle 1 \[0, 2, 3\] has no area",
        ),
        ({"triangles": [[0, 1, 2], [0, 3, 3]]}, "triangles[1]", "has no area"),
        (
            {"triangles": [[0, 1, 2], [2, 1, 0], [0, 2, 3]]},
            "triangles[1]",
            "triangles 0 and 1 have the same vertices",
        ),
        (
            {"vertices": FIVE, "triangles": [[0, 1, 2], [0, 2, 3], [2, 0, 4]]},
            "triangles[2]",
            r"vertices 0 and 2 is in 3 triangles \(0, 1, 2\)",
        ),
        ({"vertices": FIVE}, "vertices[4]", "vertex 4 is in no triangle"),
        ({"pinned": [9]}, "", "pinned index 9 is not a point of this cloth mesh"),
        ({"triangles": []}, "triangles", "at least 1"),
        ({"vertices": [[0, 0, 0], [1, 0, 0]]}, "vertices", "at least 3"),
        ({"stiffness": 0.0}, "stiffness", "greater than 0"),
        ({"vertices": [[0, 0, 0], [1e300, 0, 0], [1e300, 0, 1e300], [0, 0, 1]]}, "", "a float"),
    ],
)
def test_bad_meshes_are_refused_at_the_triangle_at_fault(mesh, path, message):
    arguments = {
        "vertices": SQUARE.tolist(),
        "triangles": [[0, 1, 2], [0, 2, 3]],
        "areal_density": 0.1,
        "stiffness": 10.0,
    } | mesh
    builder = vv.SceneBuilder(name="bad")
    with pytest.raises(vv.SceneError, match=message) as refusal:
        builder.add_cloth_mesh(**arguments)
        builder.build()
    (problem,) = refusal.value.problems
    assert problem.path == f"entities[0].{path}".rstrip(".")
