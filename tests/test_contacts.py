"""Contacts: which particles touch which colliders, where, and Baraff's classification by the
relative normal velocity (colliding v·n < −ε, resting |v·n| ≤ ε, separating v·n > ε)."""

import numpy as np
import pytest

import visviva as vv
from visviva.collision.contact_classes import COLLIDING, RESTING, SEPARATING, Contacts


def _scene(**particles) -> vv.Model:
    builder = vv.SceneBuilder(name="contacts")
    builder.set_integration(method="symplectic_euler", dt=1 / 600, duration=1.0)
    builder.add_collider("plane", name="floor", restitution=0.0, friction=0.5)
    builder.add_collider("sphere", name="ball", center=(3.0, 1.0, 0.0), radius=0.5)
    builder.add_collider(
        "box",
        name="crate",
        center=(-3.0, 0.5, 0.0),
        size=(1.0, 1.0, 1.0),
        response="penalty",
        stiffness=1e4,
        targets=["probes"],
    )
    builder.add_particles(radius=0.1, name="probes", **particles)
    return builder.build()


def test_each_contact_has_its_point_normal_depth_and_class():
    # Falling onto the floor, lying on it, leaving it; touching the ball from above (moving in);
    # inside the crate's top face by 2 cm; one well clear of everything.
    positions = [
        [0.0, 0.09, 0.0],
        [1.0, 0.1, 0.0],
        [1.5, 0.1, 0.0],
        [3.0, 1.6, 0.0],
        [-3.0, 1.08, 0.0],
        [0.0, 5.0, 0.0],
    ]
    velocities = [
        [0.0, -2.0, 0.0],
        [0.3, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
    ]
    simulation = vv.Simulation(_scene(positions=positions, velocities=velocities))
    contacts = simulation.contacts()
    assert contacts.labels == ("floor", "ball", "crate")
    assert contacts.particle.tolist() == [0, 1, 2, 3, 4]
    assert [contacts.labels[k] for k in contacts.collider] == [
        "floor", "floor", "floor", "ball", "crate",
    ]  # fmt: skip
    assert contacts.classes() == ["colliding", "resting", "separating", "colliding", "resting"]
    assert contacts.counts() == {"colliding": 2, "resting": 2, "separating": 1}
    np.testing.assert_allclose(contacts.depth, [0.01, 0.0, 0.0, 0.0, 0.02], atol=1e-12)
    np.testing.assert_allclose(contacts.normal_velocity, [-2.0, 0.0, 1.0, -1.0, 0.0], atol=0)
    up = [0.0, 1.0, 0.0]
    np.testing.assert_allclose(contacts.normal, [up] * 5, atol=1e-12)
    np.testing.assert_allclose(
        contacts.point,
        [[0, 0, 0], [1, 0, 0], [1.5, 0, 0], [3, 1.5, 0], [-3, 1, 0]],
        atol=1e-12,
    )


def test_a_particle_settled_on_the_floor_rests_on_its_surface():
    simulation = vv.Simulation(_scene(positions=[[0.0, 0.6, 0.0]]))
    simulation.run(until=1.0)
    contacts = simulation.contacts()
    assert contacts.classes() == ["resting"]
    # It lies on the floor (depth 0 to round-off) with no normal speed left.
    assert abs(contacts.depth[0]) < 1e-12
    assert contacts.normal_velocity[0] == 0.0


def test_only_live_particles_and_their_colliders_have_contacts():
    builder = vv.SceneBuilder(name="emitted")
    builder.set_integration(method="symplectic_euler", dt=1 / 600, duration=1.0)
    builder.add_collider("plane", name="floor", targets=["jet"])
    builder.add_emitter(
        rate=600,
        position=(0, 0.02, 0),
        speed=0.0,
        lifetime=0.05,
        particle_radius=0.05,
        seed=1,
        name="jet",
    )
    builder.add_particles([[0.0, 0.0, 0.0]], radius=0.1, name="free")  # not a floor target
    simulation = vv.Simulation(builder.build())
    simulation.step(60)  # the first born have died
    alive = simulation.raw_state["particle_alive"]
    contacts = simulation.contacts()
    assert len(contacts) > 0
    assert alive[contacts.particle].all()
    free = simulation.model.particle_count - 1  # the free particle's slot comes last
    assert free not in contacts.particle.tolist()


def test_the_gap_widens_what_counts_as_touching():
    simulation = vv.Simulation(_scene(positions=[[0.0, 0.15, 0.0]]))
    assert len(simulation.contacts()) == 0
    wide = simulation.contacts(gap=0.1)
    assert wide.classes() == ["resting"]
    assert wide.depth[0] == pytest.approx(-0.05)
    with pytest.raises(vv.ModelError, match="gap"):
        simulation.contacts(gap=-1.0)


def test_joined_contacts_number_the_colliders_in_turn():
    one = Contacts.none(["a"])
    other = Contacts(
        np.array([0]),
        np.array([0]),
        np.zeros((1, 3)),
        np.array([[0.0, 1.0, 0.0]]),
        np.array([0.0]),
        np.array([0.0]),
        np.array([RESTING], dtype=np.int8),
        ("b",),
    )
    joined = Contacts.join([one, other])
    assert joined.labels == ("a", "b") and joined.collider.tolist() == [1]
    assert {COLLIDING, RESTING, SEPARATING} == {0, 1, 2}
