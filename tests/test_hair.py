"""Hair strands (Selle, Lentine & Fedkiw 2008): edge, bending and torsion springs between points
one, two and three apart. Tested against statics (a hanging strand settles where the exact
1-D equilibrium of its springs puts it, and its root carries the whole weight), the spring
families' counts, a swinging strand whose root stays bit-identical, and bad strands refused."""

import numpy as np
import pytest

import visviva as vv
from visviva.deformables import hair
from visviva.deformables.topology import BEND, STRETCH, TORSION
from visviva.forces import Springs

G = 9.81


def _hanging_strand(n: int, *, mass: float, stiffness: float, bending: float, torsion: float):
    builder = vv.SceneBuilder(name="strand")
    builder.set_integration(method="backward_euler", dt=0.05, duration=30.0)
    points = np.stack([np.zeros(n), -0.1 * np.arange(n), np.zeros(n)], axis=1)
    builder.add_hair(
        points, mass=mass, stiffness=stiffness, bending=bending, torsion=torsion, damping=2.0
    )  # the root is pinned by default
    return vv.Simulation(builder.build())


def test_a_hanging_strand_settles_at_the_equilibrium_of_its_three_families():
    # A vertical strand's springs all lie along it, so its statics is linear in the heights:
    # K y = K y₀ − m g, with K the 1-D stiffness matrix of the edge, bending and torsion
    # springs (the root held). Solved exactly here and compared with the settled simulation.
    n, m, k, kb, kt = 11, 0.1, 500.0, 100.0, 50.0
    simulation = _hanging_strand(n, mass=m, stiffness=k, bending=kb, torsion=kt)
    simulation.run(until=30.0)
    y = simulation.state["particle_position"][:, 1]
    stiffness = np.zeros((n, n))
    for gap, spring in ((1, k), (2, kb), (3, kt)):
        for i in range(n - gap):
            j = i + gap
            stiffness[[i, j], [i, j]] += spring
            stiffness[i, j] -= spring
            stiffness[j, i] -= spring
    y0 = -0.1 * np.arange(n)
    free = slice(1, n)
    drop = np.linalg.solve(stiffness[free, free], -m * G * np.ones(n - 1))
    np.testing.assert_allclose(y[free] - y0[free], drop, rtol=1e-6)
    assert y[0] == 0.0  # the root has not moved
    # The root's springs carry the weight of the ten particles below it.
    (springs,) = [f for f in simulation.model.forces if isinstance(f, Springs)]
    force = np.zeros((n, 3))
    x = simulation.state["particle_position"]
    springs.accumulate(0.0, x, np.zeros_like(x), force)
    assert force[0, 1] == pytest.approx(-(n - 1) * m * G, rel=1e-6)


def test_without_bending_or_torsion_each_edge_stretches_by_the_weight_below_over_k():
    n = 8
    simulation = _hanging_strand(n, mass=0.05, stiffness=300.0, bending=0.0, torsion=0.0)
    simulation.run(until=30.0)
    stretch = -np.diff(simulation.state["particle_position"][:, 1]) - 0.1
    np.testing.assert_allclose(stretch, np.arange(n - 1, 0, -1) * 0.05 * G / 300.0, rtol=1e-6)


def test_a_strand_has_its_three_families():
    n = 9
    points = np.stack([0.1 * np.arange(n), np.sin(np.arange(n)), np.zeros(n)], axis=1)
    strand = hair(points, np.full(n, 0.01), 100.0, 10.0, 2.0)
    counts = {f: int((strand.family == f).sum()) for f in (STRETCH, BEND, TORSION)}
    assert counts == {STRETCH: n - 1, BEND: n - 2, TORSION: n - 3}
    torsion = strand.pairs[strand.family == TORSION]
    np.testing.assert_array_equal(torsion, np.stack([np.arange(n - 3), np.arange(3, n)], 1))
    assert strand.stiffness[strand.family == TORSION].tolist() == [2.0] * (n - 3)
    np.testing.assert_allclose(
        strand.rest_length()[strand.family == BEND],
        np.linalg.norm(points[2:] - points[:-2], axis=1),
    )
    # A family of stiffness 0 is left out; a strand too short for a family has none.
    assert TORSION not in hair(points, np.full(n, 0.01), 100.0, 10.0, 0.0).family
    short = hair(points[:3], np.full(3, 0.01), 100.0, 10.0, 2.0)
    assert sorted(short.family.tolist()) == [STRETCH, STRETCH, BEND]


@pytest.mark.parametrize("method", ["symplectic_euler", "rk4", "backward_euler"])
def test_a_swinging_strand_keeps_its_root_bit_identical(method):
    builder = vv.SceneBuilder(name="swing")
    builder.set_integration(method=method, dt=0.001, duration=1.0)
    points = [[0.05 * i, 1.0, 0.0] for i in range(10)]  # horizontal: it swings down
    builder.add_hair(points, mass=0.002, stiffness=200.0, bending=20.0, torsion=5.0, damping=0.01)
    simulation = vv.Simulation(builder.build())
    simulation.run(until=0.2)
    x = simulation.state["particle_position"]
    assert x[0].tolist() == points[0]
    assert (simulation.state["particle_velocity"][0] == 0.0).all()
    assert x[-1, 1] < 1.0 - 0.05  # the tip has swung down
    assert np.isfinite(x).all()


def test_a_strand_from_a_scene_file_is_drawn_by_its_edges(tmp_path):
    path = tmp_path / "hair.toml"
    path.write_text(
        """
        [integration]
        method = "backward_euler"
        dt = 0.01
        duration = 0.05

        [[entities]]
        type = "particles"
        positions = [[1.0, 0.0, 0.0]]

        [[entities]]
        type = "hair"
        name = "strand"
        points = [[0, 0, 0], [0, -0.1, 0], [0, -0.2, 0], [0, -0.3, 0], [0, -0.4, 0]]
        mass = 0.001
        stiffness = 50.0
        bending = 5.0
        torsion = 1.0
        """
    )
    model = vv.load_model(path)
    np.testing.assert_array_equal(model.particle_pinned, [False, True] + [False] * 4)
    vv.run_scene(model, tmp_path / "out")
    recording = vv.io.load_recording(tmp_path / "out" / "recording.h5")
    # The strand's points follow the particle (slots 1–5); bending and torsion are not drawn.
    np.testing.assert_array_equal(recording.static["edges"], [[1, 2], [2, 3], [3, 4], [4, 5]])
    assert recording["particle_position"][-1, 1].tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize(
    ("strand", "message"),
    [
        ({"points": [[0, 0, 0]]}, "points"),
        ({"pinned": [0, 3]}, "pinned index 3 is not a point of this hair strand"),
        ({"mass": [1.0, 2.0]}, "has 2 entries for 3 positions"),
        ({"torsion": -1.0}, "torsion"),
        ({"bending": float("nan")}, "bending"),
        ({"points": [[0, 0, 0], [0, -1, 0], [0, 0, 0]]}, "points 0 and 2 coincide"),
        ({"points": [[0, 0, 0], [0, 1e300, 0], [0, -1e300, 0]]}, "beyond what a float holds"),
    ],
)
def test_bad_strands_are_refused_naming_the_field(strand, message):
    arguments = {
        "points": [[0, 0, 0], [0, -1, 0], [0, -2, 0]],
        "mass": 0.01,
        "stiffness": 10.0,
        "bending": 1.0,
    } | strand
    builder = vv.SceneBuilder(name="bad")
    with pytest.raises(vv.ModelError, match=message):
        builder.add_hair(**arguments)
        builder.build()
