"""Soft bodies from tetrahedral meshes: a spring on every edge, a quarter of each tetrahedron's
mass on each corner. Tested on a single tetrahedron and a cube of five (springs, weight), a
cube that falls on a floor and rests on it, keeping its shape, and bad meshes — an inside-out
tetrahedron among them — refused at the tetrahedron or vertex at fault."""

import numpy as np
import pytest

import visviva as vv
from visviva.deformables import soft_mesh
from visviva.deformables.topology import STRETCH

CORNER = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
#: The unit cube's corners (index i + 2j + 4k for the corner (i, j, k), as in a soft lattice)
#: and its split into five positively oriented tetrahedra: the four corners (i + j + k odd)
#: cut off, and the regular tetrahedron of the even corners between them.
CUBE = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)
FIVE_TETRAHEDRA = [[0, 5, 3, 6], [1, 3, 0, 5], [2, 0, 3, 6], [4, 5, 0, 6], [7, 3, 5, 6]]


def test_a_tetrahedron_has_six_springs_and_weighs_density_times_volume():
    body = soft_mesh(CORNER, np.array([[0, 1, 2, 3]]), 600.0, 50.0)
    assert len(body.pairs) == 6 and (body.family == STRETCH).all()
    assert body.stiffness.tolist() == [50.0] * 6
    np.testing.assert_allclose(body.mass, 600.0 / 6 / 4)  # a quarter of 1/6 m³ each
    assert sorted(body.rest_length().round(12).tolist()) == [1, 1, 1] + [np.sqrt(2).round(12)] * 3


def test_a_cube_of_five_tetrahedra_has_eighteen_edges_and_weighs_density_times_volume():
    body = soft_mesh(0.3 * CUBE, np.array(FIVE_TETRAHEDRA), 200.0, 1.0)
    # The cube's 12 edges and one diagonal on each of its 6 faces (the middle tetrahedron's).
    assert len(body.pairs) == 18
    assert body.mass.sum() == pytest.approx(200.0 * 0.3**3)
    # An odd corner is in one tetrahedron (1/6 of the cube); an even one in four (1/3 + 3/6).
    cube = 200.0 * 0.3**3
    np.testing.assert_allclose(body.mass[[1, 2, 4, 7]], cube / 6 / 4)
    np.testing.assert_allclose(body.mass[[0, 3, 5, 6]], cube * (1 / 3 + 3 / 6) / 4)


@pytest.mark.parametrize(
    ("method", "dt"), [("symplectic_euler", 2e-3), ("linearly_implicit_euler", 1e-2)]
)
def test_a_soft_cube_falls_on_the_floor_and_rests_above_it(method, dt):
    builder = vv.SceneBuilder(name="soft cube")
    builder.set_integration(method=method, dt=dt, duration=2.0)
    vertices = 0.3 * CUBE + [-0.15, 0.5, -0.15]
    builder.add_soft_mesh(
        vertices,
        FIVE_TETRAHEDRA,
        density=200.0,
        stiffness=3000.0,
        damping=1.0,
        radius=0.01,
        name="cube",
    )
    builder.add_collider("plane", name="floor", point=(0, 0, 0), normal=(0, 1, 0), friction=0.6)
    simulation = vv.Simulation(builder.build())
    lowest = np.inf
    for _ in range(round(2.0 / dt)):
        simulation.step()
        lowest = min(lowest, simulation.raw_state["particle_position"][:, 1].min())
    x = simulation.state["particle_position"]
    # Never below the floor after any step (a particle rests at its radius), on it at the end.
    assert lowest >= 0.01 - 1e-9
    assert x[:, 1].min() == pytest.approx(0.01, abs=1e-6)
    assert simulation.contacts().counts()["resting"] == 4  # its bottom face
    # Its shape held: 5.4 kg on four corners sag it by millimetres, not centimetres.
    extent = x.max(axis=0) - x.min(axis=0)
    np.testing.assert_allclose(extent, 0.3, atol=0.01)


def test_a_soft_mesh_from_a_scene_file_is_drawn_by_its_boundary(tmp_path):
    path = tmp_path / "tetrahedron.toml"
    path.write_text(
        """
        [integration]
        method = "linearly_implicit_euler"
        dt = 0.01
        duration = 0.05

        [[entities]]
        type = "soft_mesh"
        name = "tetrahedron"
        vertices = [[0, 1, 0], [1, 1, 0], [0, 2, 0], [0, 1, 1]]
        tetrahedra = [[0, 1, 2, 3]]
        density = 600.0    # kg/m³
        stiffness = 500.0  # N/m
        """
    )
    model = vv.load_model(path)
    assert model.particle_mass.sum() == pytest.approx(100.0)
    vv.run_scene(model, tmp_path / "out")
    recording = vv.io.load_recording(tmp_path / "out" / "recording.h5")
    # The tetrahedron's four faces, wound outward; its six springs are not drawn over them.
    np.testing.assert_array_equal(
        recording.static["faces"], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    )
    assert "edges" not in recording.static


@pytest.mark.parametrize(
    ("mesh", "path", "message"),
    [
        (
            {"tetrahedra": [[0, 2, 1, 3]]},
            "tetrahedra[0]",
            r"tetrahedron 0 \[0, 2, 1, 3\] is inside out.*swap two vertices of tetrahedron 0",
        ),
        (
            {"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]},
            "tetrahedra[0]",
            "has no volume",
        ),
        ({"tetrahedra": [[0, 1, 2, 4]]}, "tetrahedra[0]", "names a vertex past the 4"),
        ({"tetrahedra": [[0, 1, 2, 3], [1, 0, 3, 2]]}, "tetrahedra[1]", "the same vertices"),
        ({"vertices": [*CORNER.tolist(), [5, 5, 5]]}, "vertices[4]", "vertex 4 is in no tetra"),
        ({"pinned": [4]}, "", "pinned index 4 is not a point of this soft mesh"),
        ({"tetrahedra": []}, "tetrahedra", "at least 1"),
        ({"tetrahedra": [[0, 1, 2]]}, "tetrahedra[0][3]", "Field required"),
        ({"vertices": CORNER.tolist()[:3]}, "vertices", "at least 4"),
        ({"density": -1.0}, "density", "greater than 0"),
        ({"vertices": (1e300 * CORNER).tolist()}, "", "beyond what a float holds"),
    ],
)
def test_bad_meshes_are_refused_at_the_tetrahedron_at_fault(mesh, path, message):
    arguments = {
        "vertices": CORNER.tolist(),
        "tetrahedra": [[0, 1, 2, 3]],
        "density": 100.0,
        "stiffness": 10.0,
    } | mesh
    builder = vv.SceneBuilder(name="bad")
    with pytest.raises(vv.SceneError, match=message) as refusal:
        builder.add_soft_mesh(**arguments)
        builder.build()
    (problem,) = refusal.value.problems
    assert problem.path == f"entities[0].{path}".rstrip(".")
