"""Spring graphs (the ``springs`` entity): particles and springs on any pairs of them. Tested
against the two-body oscillator (ω = √(2k/m): the reduced mass is m/2), with the period's error
held to the integrator's order and step, per-spring stiffness and rest lengths, and bad graphs
refused at the spring at fault."""

import math

import numpy as np
import pytest

import visviva as vv
from visviva.forces import Springs


def _crossings(t: np.ndarray, signal: np.ndarray) -> np.ndarray:
    """Times where ``signal`` crosses zero upwards, interpolated linearly between samples."""
    up = np.flatnonzero((signal[:-1] < 0.0) & (signal[1:] >= 0.0))
    fraction = -signal[up] / (signal[up + 1] - signal[up])
    return t[up] + fraction * (t[up + 1] - t[up])


@pytest.mark.parametrize(
    ("method", "order", "coefficient"),
    # The leading relative error of the period on a linear oscillator: velocity Verlet's
    # discrete frequency is arccos(1 − (ωh)²/2)/h, a period short by (ωh)²/24; RK4's phase
    # lags by (ωh)⁵/120 a step, a period long by (ωh)⁴/120.
    [("velocity_verlet", 2, -1 / 24), ("rk4", 4, 1 / 120)],
)
def test_two_particles_on_a_spring_oscillate_with_the_reduced_mass(method, order, coefficient):
    m, k, rest = 0.3, 40.0, 1.0
    omega = math.sqrt(2.0 * k / m)  # relative coordinate: (m/2) r'' = −k (r − L)
    period = 2.0 * math.pi / omega
    h = period / 64
    builder = vv.SceneBuilder(name="dimer")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.set_integration(method=method, dt=h, duration=1.0)
    # 1.2 m apart with a 1 m rest length: it starts stretched by 0.2 m, at rest.
    builder.add_springs(
        [[-0.6, 0.0, 0.0], [0.6, 0.0, 0.0]], [[0, 1]], mass=m, stiffness=k, rest_length=rest
    )
    simulation = vv.Simulation(builder.build())
    times, stretch = [0.0], [0.2]
    for _ in range(20 * 64):
        simulation.step()
        x = simulation.raw_state["particle_position"]
        times.append(simulation.time)
        stretch.append(x[1, 0] - x[0, 0] - rest)
    crossings = _crossings(np.array(times), np.array(stretch))
    assert len(crossings) == 20
    measured = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    # The measured error is the method's leading term (the next terms are (ωh)² smaller).
    assert measured / period - 1.0 == pytest.approx(coefficient * (omega * h) ** order, rel=0.05)
    # The centre of mass stays put: the forces of a spring cancel.
    np.testing.assert_allclose(simulation.state["particle_position"].mean(axis=0), 0.0, atol=1e-12)


def test_stiffness_and_rest_length_one_per_spring_in_the_order_of_the_pairs():
    builder = vv.SceneBuilder(name="triangle")
    builder.set_integration(method="backward_euler", dt=0.01, duration=0.1)
    points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
    pairs = [[0, 1], [1, 2], [2, 0], [3, 1]]
    builder.add_springs(
        points, pairs, mass=[1, 2, 3, 4], stiffness=[10, 20, 30, 40], damping=0.5, pinned=[0]
    )
    builder.add_springs(points, pairs[:2], mass=1.0, stiffness=5.0, rest_length=[0.5, 2.0])
    model = builder.build()
    first, second = (f for f in model.forces if isinstance(f, Springs))
    np.testing.assert_array_equal(first.pairs, pairs)
    assert first.stiffness.tolist() == [10, 20, 30, 40] and first.damping.tolist() == [0.5] * 4
    np.testing.assert_allclose(first.rest_length, [1.0, math.sqrt(2), 1.0, 1.0])
    np.testing.assert_array_equal(second.pairs, [[4, 5], [5, 6]])  # after the first 4 points
    assert second.rest_length.tolist() == [0.5, 2.0] and second.stiffness.tolist() == [5, 5]
    np.testing.assert_array_equal(model.particle_mass[:4], [1, 2, 3, 4])
    assert model.particle_pinned.tolist() == [True] + [False] * 7


def test_a_spring_graph_from_a_scene_file_is_drawn_by_its_springs(tmp_path):
    path = tmp_path / "springs.toml"
    path.write_text(
        """
        [integration]
        method = "backward_euler"
        dt = 0.01
        duration = 0.05

        [[entities]]
        type = "springs"
        name = "frame"
        points = [[0, 0, 0], [1, 0, 0], [0.5, 0.8, 0]]
        pairs = [[0, 1], [1, 2], [2, 0]]
        mass = 0.5
        stiffness = [100.0, 200.0, 300.0]
        pinned = [0, 1]
        """
    )
    vv.run_scene(vv.load_model(path), tmp_path / "out")
    recording = vv.io.load_recording(tmp_path / "out" / "recording.h5")
    np.testing.assert_array_equal(recording.static["edges"], [[0, 1], [1, 2], [2, 0]])
    assert recording["particle_position"][-1, 2, 1] < 0.8  # the free apex sags under its weight


@pytest.mark.parametrize(
    ("graph", "path", "message"),
    [
        ({"pairs": [[0, 1], [1, 5]]}, "pairs[1]", "spring 1 joins points 1 and 5, but there are 3"),
        ({"pairs": [[0, 1], [2, 2]]}, "pairs[1]", "spring 1 joins point 2 to itself"),
        ({"pairs": [[0, 1], [1, 2], [1, 0]]}, "pairs[2]", "springs 0 and 2 both join points 1"),
        ({"points": [[0, 0, 0], [1, 0, 0], [1, 0, 0]]}, "points", "points 1 and 2 coincide"),
        ({"stiffness": [1.0, 2.0, 3.0]}, "stiffness", "has 3 values for 2 springs"),
        ({"rest_length": [1.0]}, "rest_length", "has 1 values for 2 springs"),
        ({"rest_length": 0.0}, "rest_length", "greater than 0"),
        ({"pinned": [3]}, "", "pinned index 3 is not a point of this spring network"),
        ({"pairs": []}, "pairs", "at least 1"),
        ({"pairs": [[0, -1]]}, "pairs[0][1]", "greater than or equal to 0"),
        ({"pairs": [[0, 1, 2]]}, "pairs[0]", "at most 2"),
        ({"mass": [1.0, 1.0]}, "mass", "has 2 entries for 3 positions"),
        ({"points": [[0, 0, 0], [1e300, 0, 0], [-1e300, 0, 0]]}, "points", "beyond what a float"),
    ],
)
def test_bad_graphs_are_refused_at_the_spring_at_fault(graph, path, message):
    arguments = {
        "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
        "pairs": [[0, 1], [1, 2]],
        "mass": 1.0,
        "stiffness": 10.0,
    } | graph
    builder = vv.SceneBuilder(name="bad")
    with pytest.raises(vv.SceneError, match=message) as refusal:
        builder.add_springs(**arguments)
        builder.build()
    (problem,) = refusal.value.problems
    assert problem.path == f"entities[0].{path}".rstrip(".")
