"""Rigid bodies that touch, through scenes (add_body_contacts): bounces, slides, stacks, the
state a checkpoint keeps, sharing a model between threads, and refusals."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import visviva as vv
from visviva.errors import ModelError

G = 9.81
H = 1.0 / 240.0


def _floor_scene(method="velocity_verlet", *, e=0.5, mu=0.5, duration=3.0):
    builder = vv.SceneBuilder(name="contacts")
    builder.set_integration(method=method, dt=H, duration=duration)
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=e, friction=mu)
    return builder


@pytest.mark.parametrize("e", [0.5, 0.8, 1.0])
def test_a_ball_bounces_to_e_squared_of_its_drop_height(e):
    # Dropped from h = 1 m it meets the floor at √(2gh) and leaves at e√(2gh): it rises to
    # e²h. Velocity Verlet is exact under gravity and the bounce is taken at the moment of
    # impact within the step: within 1 % (issue 27).
    builder = _floor_scene(e=e)
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(0, 1.1, 0), restitution=e)
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    heights = []
    for _ in range(400):
        simulation.step(1)
        heights.append(simulation.state["body_position"][0, 1] - 0.1)
    heights = np.array(heights)
    impact = int(np.argmin(heights[:150]))
    assert heights[impact] < 0.02
    assert heights[impact:].max() == pytest.approx(e * e * 1.0, rel=0.01)


@pytest.mark.parametrize(("mu", "speed"), [(0.3, 2.0), (0.6, 3.0)])
def test_a_sliding_box_stops_after_v_squared_over_two_mu_g(mu, speed):
    # Coulomb friction decelerates it at μg: it slides v²/(2μg) (issue 27: within 2 %), and
    # does not tip (its orientation stays the identity).
    builder = _floor_scene(e=0.0, mu=mu)
    builder.add_body("box", size=(0.4, 0.2, 0.3), density=500.0, position=(0, 0.1, 0),
                     velocity=(speed, 0, 0), friction=mu, restitution=0.0)  # fmt: skip
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    simulation.step(360)
    x = simulation.state["body_position"][0]
    assert x[0] == pytest.approx(speed**2 / (2 * mu * G), rel=0.02)
    assert x[1] == pytest.approx(0.1, abs=1e-6)
    assert simulation.state["body_orientation"][0] == pytest.approx([1, 0, 0, 0], abs=1e-9)


def _stack(count=10, method="symplectic_euler"):
    builder = _floor_scene(method, e=0.0, duration=10.0)
    for i in range(count):
        builder.add_body("box", size=(1, 1, 1), density=1000.0, position=(0, 0.5 + i, 0),
                         restitution=0.0, name=f"box{i}")  # fmt: skip
    builder.add_body_contacts()
    return builder.build()


def test_a_stack_of_ten_boxes_stands_for_ten_seconds():
    # Issue 27: every box within 1 mm of its start for 10 s, residual speed below 1e-3 m/s.
    simulation = vv.Simulation(_stack())
    start = simulation.state["body_position"].copy()
    worst = 0.0
    for _ in range(24):
        simulation.step(100)
        moved = np.linalg.norm(simulation.state["body_position"] - start, axis=1)
        worst = max(worst, float(moved.max()))
    assert worst < 1e-3
    speed = np.linalg.norm(simulation.state["body_momentum"], axis=1) / 1000.0
    assert speed.max() < 1e-3


def test_a_checkpoint_restores_contacts_and_warm_starts_bit_for_bit():
    model = _stack(4)
    simulation = vv.Simulation(model)
    simulation.step(50)
    assert simulation.state["body_contact_normal_impulse"].shape[0] == 16  # 4 corners each
    saved = simulation.checkpoint()
    simulation.step(30)
    expected = simulation.state
    again = vv.Simulation.restore(model, saved)
    again.step(30)
    for name in ("body_position", "body_orientation", "body_momentum",
                 "body_angular_momentum", "body_contact_normal_impulse"):  # fmt: skip
        np.testing.assert_array_equal(again.state[name], expected[name])


def test_one_model_stepped_in_two_threads_gives_the_serial_result():
    model = _stack(3)
    serial = vv.Simulation(model)
    serial.step(120)
    results: dict[int, np.ndarray] = {}

    def run(k):
        simulation = vv.Simulation(model)
        simulation.step(120)
        results[k] = simulation.state["body_position"].copy()

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for k in range(2):
        np.testing.assert_array_equal(results[k], serial.state["body_position"])


def test_two_balls_meet_head_on_and_keep_their_momentum():
    # Equal balls, e = 1, no gravity: they exchange velocities (1-D elastic collision).
    builder = vv.SceneBuilder(name="head-on")
    builder.set_world(gravity=(0, 0, 0))
    builder.set_integration(method="velocity_verlet", dt=H, duration=1.0)
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(-0.5, 0, 0),
                     velocity=(1.0, 0, 0), restitution=1.0)  # fmt: skip
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(0.5, 0, 0),
                     velocity=(-1.0, 0, 0), restitution=1.0)  # fmt: skip
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    momentum = simulation.state["body_momentum"].sum(axis=0)
    simulation.step(240)
    after = simulation.state["body_momentum"]
    np.testing.assert_allclose(after.sum(axis=0), momentum, atol=1e-12)
    mass = 1000.0 * 4.0 / 3.0 * np.pi * 0.1**3
    np.testing.assert_allclose(after[:, 0] / mass, [-1.0, 1.0], atol=1e-9)


CUBE = {
    "vertices": [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)],
}
# An L-shaped prism (not convex): an outline of six corners extruded along z.
L_OUTLINE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]


def _l_prism():
    vertices = [[x, y, z] for z in (0.0, 1.0) for x, y in L_OUTLINE]
    triangles = []
    # Bottom (z = 0, seen from below: clockwise in xy) and top faces, fanned from a corner the
    # whole polygon sees: (1, 1) is the reflex corner, index 3.
    for a, b in ((4, 5), (5, 0), (0, 1), (1, 2)):
        triangles.append([3, b, a])
        triangles.append([9, 6 + a, 6 + b])
    for k in range(6):
        j = (k + 1) % 6
        triangles.append([k, j, 6 + j])
        triangles.append([k, 6 + j, 6 + k])
    return vertices, triangles


def test_a_non_convex_mesh_is_refused_unless_its_pieces_or_hull_are_asked_for():
    vertices, triangles = _l_prism()
    builder = _floor_scene()
    builder.add_body("mesh", vertices=vertices, triangles=triangles, density=1000.0)
    builder.add_body_contacts()
    with pytest.raises(ModelError, match=r"not convex.*convex_pieces"):
        builder.build()
    pieces = [[[x, y, z] for x in (0, 2) for y in (0, 1) for z in (0, 1)],
              [[x, y, z] for x in (0, 1) for y in (1, 2) for z in (0, 1)]]  # fmt: skip
    builder = _floor_scene()
    builder.add_body("mesh", vertices=vertices, triangles=triangles, density=1000.0,
                     convex_pieces=pieces, position=(0, 1, 0))  # fmt: skip
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    simulation.step(480)
    # It lands on a face and comes to rest (3000 kg: P below 3 kg·m/s is v below 1 mm/s).
    assert abs(simulation.state["body_momentum"]).max() < 3.0


def test_bad_contact_input_is_refused_with_the_field_named():
    def scene(**body):
        builder = _floor_scene()
        builder.add_body(body.pop("shape", "box"), **({"size": (1, 1, 1), "density": 1.0} | body))
        builder.add_body_contacts()
        return builder

    with pytest.raises(ModelError, match="restitution"):
        scene(restitution=1.5).build()
    with pytest.raises(ModelError, match="friction"):
        scene(friction=-0.1).build()
    with pytest.raises(ModelError, match=r"convex_pieces.*collision_shape"):
        scene(collision_shape="hull", convex_pieces=[CUBE["vertices"]]).build()
    with pytest.raises(ModelError, match="hull"):
        scene(collision_shape="hull").build()
    with pytest.raises(ModelError, match=r"convex_pieces\[0\].*plane"):
        flat = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
        scene(convex_pieces=[flat]).build()
    builder = scene()
    builder.add_body_contacts()
    with pytest.raises(ModelError, match="at most one body_contacts"):
        builder.build()
    builder = _floor_scene()
    builder.add_body("box", size=(1, 1, 1), density=1.0, name="crate")
    builder.add_body_contacts(targets=["crat"])
    with pytest.raises(ModelError, match=r"no body is called 'crat'.*crate"):
        builder.build()
    builder = _floor_scene()
    builder.add_particles(positions=[(0, 1, 0)], radius=0.1, mass=1.0)
    builder.add_body_contacts()
    with pytest.raises(ModelError, match="need rigid bodies"):
        builder.build()


def test_the_contacts_of_a_moment_are_classified_as_baraff_does():
    # A box resting on the floor touches at four corners, resting; a ball about to hit the
    # box's top at 3 m/s collides; a ball leaving the floor at 3 m/s separates.
    builder = _floor_scene()
    builder.add_body("box", size=(1, 1, 1), density=1000.0, position=(0, 0.5, 0), name="crate")
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(0, 1.1, 0),
                     velocity=(0, -3, 0), name="falling")  # fmt: skip
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(3, 0.1, 0),
                     velocity=(0, 3, 0), name="leaving")  # fmt: skip
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    found = simulation.body_contacts()
    pairs = sorted(zip(found.body_a.tolist(), found.body_b.tolist(), found.classes(),
                       strict=True))  # fmt: skip
    assert pairs == [(-1, 0, "resting")] * 4 + [(-1, 2, "separating"), (0, 1, "colliding")]
    crate = found.body_b == 0
    assert found.depth[crate] == pytest.approx([0.0] * 4, abs=1e-12)
    assert found.normal[crate] == pytest.approx(np.tile([0.0, 1.0, 0.0], (4, 1)))
    hit = found.body_b == 1
    assert found.normal_velocity[hit] == pytest.approx([-3.0])
    assert found.counts() == {"colliding": 1, "resting": 4, "separating": 1}
    plain = _floor_scene()
    plain.add_body("box", size=(1, 1, 1), density=1.0)
    with pytest.raises(ModelError, match="body_contacts"):
        vv.Simulation(plain.build()).body_contacts()


def _row(impacts, count=5, e=1.0, gap=0.0):
    builder = vv.SceneBuilder(name="row")
    builder.set_world(gravity=(0, 0, 0))
    builder.set_integration(method="velocity_verlet", dt=H, duration=1.0)
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(-0.5, 0, 0),
                     velocity=(1.0, 0, 0), restitution=e)  # fmt: skip
    for k in range(count - 1):
        builder.add_body("sphere", radius=0.1, density=1000.0,
                         position=((0.2 + gap) * k, 0, 0), restitution=e)  # fmt: skip
    builder.add_body_contacts(impacts=impacts)
    return vv.Simulation(builder.build())


@pytest.mark.parametrize("gap", [0.0, 1e-5, 1e-3])
def test_simultaneous_impacts_send_the_blow_down_a_row_as_in_newtons_cradle(gap):
    # A ball striking four touching balls at 1 m/s, e = 1: generalized reflections pass the
    # impact along the row, the last ball leaves at 1 m/s and the others stand still (Smith
    # et al. 2012); momentum and kinetic energy are kept, whether the balls touch or stand a
    # little apart (a gap the blow crosses within a step). Sequential impulses instead share
    # the blow at once: the striker bounces back and the row leaves as a lump.
    mass = 1000.0 * 4.0 / 3.0 * np.pi * 0.1**3
    simultaneous = _row("simultaneous", gap=gap)
    simultaneous.step(240)
    v = simultaneous.state["body_momentum"][:, 0] / mass
    np.testing.assert_allclose(v, [0.0, 0.0, 0.0, 0.0, 1.0], atol=1e-9)
    assert 0.5 * mass * (v**2).sum() == pytest.approx(0.5 * mass, rel=1e-12)
    sequential = _row("sequential")
    sequential.step(240)
    lump = sequential.state["body_momentum"][:, 0] / mass
    assert lump[0] < -0.5 and np.all(lump[1:] > 0.3)
    assert lump.sum() == pytest.approx(1.0, abs=1e-12)


def test_generalized_reflections_take_a_round_per_ball_and_keep_symmetry():
    from visviva.collision.simultaneous import reflect_impacts

    # Five unit masses on a line touching, the first moving at 1: four rounds, no failsafe.
    count = 5
    body_a = np.arange(count - 1)
    body_b = body_a + 1
    normal = np.tile([1.0, 0.0, 0.0], (count - 1, 1))
    arm_a = np.tile([0.1, 0.0, 0.0], (count - 1, 1))
    arm_b = -arm_a
    v = np.zeros((count, 3))
    v[0, 0] = 1.0
    w = np.zeros((count, 3))
    ones = np.ones(count - 1)
    _, rounds, ended = reflect_impacts(body_a, body_b, normal, arm_a, arm_b, 0.5 * ones, ones,
                                       np.zeros(count - 1), 1.0, 0.0, np.ones(count),
                                       np.zeros((count, 3, 3)), v, w)  # fmt: skip
    assert (rounds, ended) == (4, False)
    np.testing.assert_allclose(v[:, 0], [0, 0, 0, 0, 1], atol=1e-12)
    # A striker hitting two balls that touch it symmetrically (normals ±30° off its path):
    # they leave at mirror-image velocities, and energy and momentum are kept (e = 1).
    angle = np.radians(30.0)
    normals = np.array([[np.cos(angle), np.sin(angle), 0], [np.cos(angle), -np.sin(angle), 0]])
    v = np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 0]])
    w = np.zeros((3, 3))
    reflect_impacts(np.array([0, 0]), np.array([1, 2]), normals, 0.1 * normals, -0.1 * normals,
                    0.5 * np.ones(2), np.ones(2), np.zeros(2), 1.0, 0.0, np.ones(3),
                    np.zeros((3, 3, 3)), v, w)  # fmt: skip
    assert v[1] == pytest.approx(v[2] * [1, -1, 1], abs=1e-12)
    assert v.sum(axis=0) == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)
    assert (v**2).sum() == pytest.approx(1.0, rel=1e-12)


def _bullet(mode, method="advancement"):
    builder = vv.SceneBuilder(name="bullet")
    builder.set_world(gravity=(0, 0, 0))
    builder.set_integration(method="velocity_verlet", dt=H, duration=1.0)
    builder.add_collider("box", center=(0, 0, 0), size=(2, 2, 0.01), restitution=0.5)
    builder.add_body("sphere", radius=0.05, density=1000.0, position=(0, 0, -1),
                     velocity=(0, 0, 100.0), restitution=0.5, time_of_impact=mode)  # fmt: skip
    builder.add_body_contacts(time_of_impact=method)
    return vv.Simulation(builder.build())


def test_a_fast_ball_does_not_pass_through_a_thin_plate_with_time_of_impact():
    # 100 m/s with dt = 1/240 s is 42 cm a step, against a 1 cm plate: without the time of
    # impact the ball is on the far side at the next step's end and flies on (the test has
    # teeth); conservative advancement finds the impact and the ball bounces back at e v.
    caught = _bullet("auto")
    caught.step(24)
    assert caught.state["body_position"][0, 2] < -1.0
    mass = 1000.0 * 4.0 / 3.0 * np.pi * 0.05**3
    assert caught.state["body_momentum"][0, 2] / mass == pytest.approx(-50.0, rel=1e-9)
    missed = _bullet("never")
    missed.step(24)
    assert missed.state["body_position"][0, 2] > 5.0
    # Seed 003's bisection needs the overlap at the step's end: it misses the thin plate...
    assert _advance(_bullet("auto", "bisection"))[2] > 5.0


def test_both_times_of_impact_match_the_closed_form():
    # A ball of radius 0.1 moving from x = 0 to x = 1 in a step toward a static ball of
    # radius 0.2 at x = 0.8: they touch when the centres are 0.3 apart, at τ = 0.5. Seed 003's
    # bisection needs them overlapping at the end (they do: 0.2 apart); conservative
    # advancement finds it from the start. Both within their tolerance.
    from visviva.collision import Sphere
    from visviva.collision.body_pieces import BodyPieces
    from visviva.collision.impact_time import ADVANCEMENT, BISECTION, impact_fraction

    pieces = BodyPieces.of([Sphere((0, 0, 0), 0.1), Sphere((0.8, 0, 0), 0.2)], [0, -1],
                           [0.5, 0.5], [0.5, 0.5])  # fmt: skip
    x0, x1 = np.zeros((1, 3)), np.array([[1.0, 0.0, 0.0]])
    q = np.array([[1.0, 0.0, 0.0, 0.0]])
    reach = np.linalg.norm(pieces.local_position, axis=1) + pieces.radius
    for method in (ADVANCEMENT, BISECTION):
        tau = impact_fraction(0, 1, method, 1e-6, pieces.arrays(), pieces.body,
                              pieces.local_position, pieces.local_rotation, reach, x0, q, x1,
                              q)  # fmt: skip
        assert tau == pytest.approx(0.5, abs=2e-6)
    # Missing each other (1 m to the side), neither finds an impact.
    far = BodyPieces.of([Sphere((0, 0, 0), 0.1), Sphere((0.8, 1.0, 0), 0.2)], [0, -1],
                        [0.5, 0.5], [0.5, 0.5])  # fmt: skip
    for method in (ADVANCEMENT, BISECTION):
        assert impact_fraction(0, 1, method, 1e-6, far.arrays(), far.body, far.local_position,
                               far.local_rotation, reach, x0, q, x1, q) == 1.0  # fmt: skip


def _advance(simulation):
    simulation.step(24)
    return simulation.state["body_position"][0]


def test_bodies_rest_on_a_mesh_collider_and_roll_off_its_edge():
    # A 1 m × 0.2 m × 1 m step as a triangle mesh on the floor: a cube dropped on it rests on
    # its top (y = 0.2 + 0.1); a ball dropped beside it lands on the floor.
    corners = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 0.2) for z in (-0.5, 0.5)])
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]  # fmt: skip
    builder = _floor_scene(e=0.0)
    builder.add_collider("mesh", vertices=corners.tolist(), triangles=faces, restitution=0.0)
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=1000.0, position=(0.5, 0.6, 0.0),
                     restitution=0.0)  # fmt: skip
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(-0.5, 0.6, 0.0),
                     restitution=0.0)  # fmt: skip
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    simulation.step(480)
    x = simulation.state["body_position"]
    assert x[0] == pytest.approx([0.5, 0.3, 0.0], abs=1e-4)
    assert x[1] == pytest.approx([-0.5, 0.1, 0.0], abs=1e-4)
    found = simulation.body_contacts()
    assert set(found.body_b.tolist()) == {0, 1} and (found.body_a == -1).all()


def test_a_non_convex_mesh_cut_into_convex_pieces_lands_on_its_faces():
    from visviva.collision.decomposition import convex_decomposition

    vertices, triangles = _l_prism()
    pieces = convex_decomposition(np.array(vertices, float), np.array(triangles))
    # The L is two boxes: no piece may fill the notch (x > 1 and y > 1).
    assert len(pieces) >= 2
    for piece in pieces:
        assert not ((piece[:, 0] > 1.0 + 1e-3) & (piece[:, 1] > 1.0 + 1e-3)).any()
    builder = _floor_scene(e=0.0)
    builder.add_body("mesh", vertices=vertices, triangles=triangles, density=1000.0,
                     collision_shape="decomposition", position=(0, 0.5, 0),
                     restitution=0.0)  # fmt: skip
    builder.add_body_contacts()
    simulation = vv.Simulation(builder.build())
    simulation.step(720)
    # It rests on the floor: its lowest corner at y = 0 (to the pieces' approximation, 1 cm).
    from visviva.geometry.quaternions import quaternion_matrix

    model = simulation.model
    centre = model.bodies.center[0]
    rotation = quaternion_matrix(simulation.state["body_orientation"][0])
    world = (np.array(vertices) - centre) @ rotation.T + simulation.state["body_position"][0]
    assert world[:, 1].min() == pytest.approx(0.0, abs=0.01)
    assert np.abs(simulation.state["body_momentum"]).max() < 3.0


def _pour(meet: bool):
    builder = _floor_scene("symplectic_euler", e=0.0)
    builder.add_body("box", size=(1.0, 0.2, 1.0), density=500.0, position=(0, 0.1, 0))
    rng = np.random.default_rng(0)
    positions = np.column_stack([rng.uniform(-0.3, 0.3, 100), rng.uniform(0.4, 1.2, 100),
                                 rng.uniform(-0.3, 0.3, 100)])  # fmt: skip
    builder.add_particles(positions=positions, radius=0.03, mass=0.05, name="balls")
    builder.add_particle_collisions(targets=["balls"])
    builder.add_body_contacts(particles=["balls"] if meet else None)
    simulation = vv.Simulation(builder.build())
    simulation.step(360)
    return simulation


def test_particles_poured_onto_a_body_rest_on_it_and_push_it():
    # Balls poured onto a slab rest on its top (y = 0.2 + r), the slab pressed into the floor
    # by their weight; without `particles` they fall through it (the test has teeth). A ball
    # rolls without resistance: one may roll off the slab's edge, never through it.
    resting = _pour(True)
    x = resting.state["particle_position"]
    on = x[:, 1] > 0.2
    assert on.sum() >= 95
    assert x[on, 1].min() == pytest.approx(0.23, abs=2e-3)
    assert (np.abs(x[~on][:, [0, 2]]).max(axis=1, initial=0.0) > 0.5).all()
    assert resting.state["body_position"][0, 1] == pytest.approx(0.1, abs=2e-4)
    through = _pour(False)
    assert through.state["particle_position"][:, 1].min() < 0.1
    # No gravity: a particle hitting a free box head-on keeps the total momentum.
    builder = vv.SceneBuilder(name="hit")
    builder.set_world(gravity=(0, 0, 0))
    builder.set_integration(method="velocity_verlet", dt=H, duration=1.0)
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=100.0, position=(0.5, 0, 0),
                     restitution=1.0)  # fmt: skip
    builder.add_particles(positions=[(0, 0, 0)], velocities=[(2.0, 0, 0)], radius=0.05,
                          mass=0.4, name="shot")  # fmt: skip
    builder.add_body_contacts(particles=["shot"], particle_restitution=1.0)
    simulation = vv.Simulation(builder.build())
    before = simulation.state["body_momentum"][0] + 0.4 * simulation.state["particle_velocity"][0]
    simulation.step(120)
    after = simulation.state["body_momentum"][0] + 0.4 * simulation.state["particle_velocity"][0]
    np.testing.assert_allclose(after, before, atol=1e-12)
    # Elastic, masses 0.4 and 0.8 kg: v₁' = (m₁ − m₂)/(m₁ + m₂) v = −2/3 m/s.
    assert simulation.state["particle_velocity"][0, 0] == pytest.approx(-2.0 / 3.0, rel=1e-9)
