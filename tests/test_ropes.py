"""Ropes: particles joined in order by damped springs, with pins. Tested against statics (a
hanging rope's springs stretch by the weight below them over k), pins that stay bit-identical,
momentum of a free rope, the order of the particles, and bad ropes refused by index."""

import numpy as np
import pytest

import visviva as vv
from visviva.forces import Springs

G = 9.81


def _hanging(method: str, n: int = 11, **rope) -> vv.Model:
    builder = vv.SceneBuilder(name="rope")
    builder.set_integration(method=method, dt=0.05, duration=20.0)
    points = np.stack([np.zeros(n), -0.1 * np.arange(n), np.zeros(n)], axis=1)
    builder.add_rope(points, mass=0.1, stiffness=500.0, pinned=[0], name="rope", **rope)
    return builder.build()


def test_a_hanging_rope_at_rest_stretches_each_spring_by_the_weight_below_over_k():
    # Statics of a chain: spring i carries the weight of the n − 1 − i particles below it,
    # so it stretches by (n − 1 − i) m g / k. Backward Euler with damping settles there.
    n = 11
    simulation = vv.Simulation(_hanging("backward_euler", n, damping=2.0))
    simulation.run(until=20.0)
    x = simulation.state["particle_position"]
    stretch = -np.diff(x[:, 1]) - 0.1
    expected = np.arange(n - 1, 0, -1) * 0.1 * G / 500.0
    np.testing.assert_allclose(stretch, expected, rtol=1e-6)
    np.testing.assert_allclose(x[:, [0, 2]], 0.0, atol=1e-12)  # straight down


@pytest.mark.parametrize("method", ["symplectic_euler", "rk4", "backward_euler"])
def test_pinned_points_stay_bit_identical(method):
    builder = vv.SceneBuilder(name="swing")
    builder.set_integration(method=method, dt=0.002, duration=1.0)
    points = [[0.1 * i, 1.0, 0.0] for i in range(8)]  # horizontal: it swings down
    builder.add_rope(points, stiffness=2000.0, damping=0.5, bending=50.0, pinned=[0, 7])
    simulation = vv.Simulation(builder.build())
    simulation.run(until=0.2)
    x = simulation.state["particle_position"]
    assert x[0].tolist() == points[0] and x[7].tolist() == points[7]
    assert (simulation.state["particle_velocity"][[0, 7]] == 0.0).all()
    assert x[3, 1] < 1.0 - 1e-3  # the middle has sagged


def test_a_free_rope_keeps_its_momentum_and_the_order_of_its_points():
    builder = vv.SceneBuilder(name="free")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.set_integration(method="symplectic_euler", dt=1e-3, duration=1.0)
    rng = np.random.default_rng(3)
    points = np.cumsum(rng.normal(scale=0.2, size=(6, 3)), axis=0)
    velocities = rng.normal(size=(6, 3))
    mass = rng.uniform(0.5, 2.0, 6)
    builder.add_rope(points, velocities=velocities, mass=mass, stiffness=300.0, damping=1.0)
    simulation = vv.Simulation(builder.build())
    np.testing.assert_array_equal(simulation.state["particle_position"], points)
    momentum = mass @ velocities
    simulation.run(until=0.5)
    # Spring forces come in opposite pairs: momentum is conserved to round-off.
    after = mass @ simulation.state["particle_velocity"]
    np.testing.assert_allclose(after, momentum, atol=1e-12 * np.abs(momentum).max() * 500)


def test_bending_adds_the_springs_between_points_two_apart():
    n = 7
    straight, bent = (_hanging("symplectic_euler", n, bending=b) for b in (0.0, 20.0))
    (springs,) = [f for f in straight.forces if isinstance(f, Springs)]
    (with_bending,) = [f for f in bent.forces if isinstance(f, Springs)]
    assert len(springs) == n - 1 and len(with_bending) == 2 * n - 3
    np.testing.assert_allclose(with_bending.rest_length[n - 1 :], 0.2)
    assert with_bending.stiffness[n - 1 :].tolist() == [20.0] * (n - 2)


def test_a_rope_from_a_scene_file(tmp_path):
    path = tmp_path / "rope.toml"
    path.write_text(
        """
        [integration]
        method = "backward_euler"
        dt = 0.01
        duration = 0.1

        [[entities]]
        type = "rope"
        name = "line"
        points = [[0, 0, 0], [0, -0.5, 0], [0, -1, 0]]
        stiffness = 100.0
        damping = 0.1
        pinned = [0]
        """
    )
    simulation = vv.Simulation(vv.load_model(path))
    simulation.run(until=0.1)
    assert simulation.state["particle_position"][0].tolist() == [0.0, 0.0, 0.0]
    assert simulation.state["particle_position"][2, 1] < -1.0  # stretched by its weight


@pytest.mark.parametrize(
    ("rope", "message"),
    [
        ({"pinned": [0, 5]}, "pinned index 5 is not a point of this rope"),
        ({"stiffness": 0.0}, "stiffness"),
        ({"damping": -1.0}, "damping"),
        ({"mass": [1.0, 2.0]}, "has 2 entries for 3 positions"),
        ({"points": [[0, 0, 0], [0, 0, 0], [0, 1, 0]]}, "points 0 and 1 coincide"),
        ({"points": [[0, 0, 0]]}, "points"),
    ],
)
def test_bad_ropes_are_refused_naming_the_field(rope, message):
    arguments = {"points": [[0, 0, 0], [0, -1, 0], [0, -2, 0]], "stiffness": 10.0} | rope
    builder = vv.SceneBuilder(name="bad")
    with pytest.raises(vv.ModelError, match=message):
        builder.add_rope(**arguments)
        builder.build()


def test_recordings_draw_the_stretch_springs_as_edges(tmp_path):
    builder = vv.SceneBuilder(name="drawn")
    builder.set_integration(method="backward_euler", dt=0.01, duration=0.05)
    builder.add_particles([[5.0, 0.0, 0.0]], name="loose")
    builder.add_rope([[0, 0, 0], [0, -1, 0], [0, -2, 0], [0, -3, 0]], stiffness=50.0,
                     bending=5.0, color=(0.9, 0.2, 0.1))  # fmt: skip
    vv.run_scene(builder.build(), tmp_path)
    recording = vv.io.load_recording(tmp_path / "recording.h5")
    # The rope's points follow the loose particle (slots 1–4); bend springs are not drawn.
    np.testing.assert_array_equal(recording.static["edges"], [[1, 2], [2, 3], [3, 4]])
    np.testing.assert_allclose(recording.static["particle_color"][1:], [[0.9, 0.2, 0.1]] * 4)
