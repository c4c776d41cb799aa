"""Rigid bodies in scenes: the (x, q, P, L) state in the shared pipeline, tested against physics.

A body's centre of mass moves as a particle of its mass under the same forces
(x(t) = x₀ + v₀t + ½gt² under gravity); a force through the centre of mass turns nothing;
its energy is ½M|v|² + ½ωᵀIω − M g·x; damping rates make the momenta decay as e^(−γt);
and the builder refuses what no body can be, naming the entity and the field.
"""

import warnings
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.forces.body_forces import wrench_at
from visviva.geometry.quaternions import quaternion_matrix

GRAVITY = np.array([0.0, -9.81, 0.0])
#: A tetrahedron with one triangle wound against the others.
INSIDE_OUT = {
    "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    "triangles": [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
}


def _scene(method="symplectic_euler", dt=0.01, gravity=tuple(GRAVITY), **body):
    builder = vv.SceneBuilder(name="bodies")
    builder.set_world(gravity=gravity)
    builder.set_integration(method=method, dt=dt, duration=10.0)
    arguments = {"size": (0.4, 0.2, 0.1), "density": 500.0} | body
    builder.add_body(arguments.pop("shape", "box"), **arguments)
    return builder


def test_a_thrown_body_falls_on_the_parabola_and_gravity_turns_nothing():
    """Velocity Verlet is exact for a constant force: after 1 s the centre of mass is at
    x₀ + v₀t + ½gt² to round-off; the body's spin, about a principal axis, is unchanged
    (gravity acts through the centre of mass: τ = 0, so L stays what it was)."""
    start, velocity = np.array([0.0, 2.0, 0.0]), np.array([1.0, 5.0, -0.5])
    builder = _scene("velocity_verlet", position=start, velocity=velocity,
                     angular_velocity=(0.0, 3.0, 0.0))  # fmt: skip
    simulation = vv.Simulation(builder.build())
    spin = simulation.state["body_angular_momentum"].copy()
    simulation.step(100)
    t = 1.0
    expected = start + velocity * t + 0.5 * GRAVITY * t**2
    np.testing.assert_allclose(simulation.state["body_position"][0], expected, atol=1e-12)
    np.testing.assert_allclose(simulation.state["body_angular_momentum"], spin, atol=0.0)
    mass = 0.4 * 0.2 * 0.1 * 500.0
    np.testing.assert_allclose(
        simulation.state["body_momentum"][0], mass * (velocity + GRAVITY * t), atol=1e-12
    )


def test_the_energy_counts_translation_rotation_and_height():
    """E = ½M|v|² + ½ωᵀIω − M g·x for a box of edges (a, b, c): I = M/12 diag(b²+c², a²+c²,
    a²+b²) in its axes, turned by its orientation into the world's."""
    a, b, c, density = 0.4, 0.2, 0.1, 500.0
    mass = a * b * c * density
    q = np.array([0.9, 0.1, -0.3, 0.3])
    q /= np.linalg.norm(q)
    omega, velocity, position = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.0, 2.0]), (1, 2, 3)
    builder = _scene(position=position, orientation=q, velocity=velocity, angular_velocity=omega)
    simulation = vv.Simulation(builder.build())
    rotation = quaternion_matrix(q)
    inertia = rotation @ np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) @ rotation.T
    inertia *= mass / 12.0
    expected = (
        0.5 * mass * velocity @ velocity + 0.5 * omega @ inertia @ omega
        - mass * GRAVITY @ np.array(position, dtype=float)
    )  # fmt: skip
    assert simulation.energy() == pytest.approx(expected, rel=1e-14)
    np.testing.assert_allclose(simulation.state["body_angular_momentum"][0], inertia @ omega)


@pytest.mark.parametrize("method", ["symplectic_euler", "velocity_verlet", "rk4"])
def test_a_free_tumbling_body_in_a_scene_keeps_l_and_its_energy(method):
    """No gravity, 20 s at h = 0.01 s: L exact (no torque), the kinetic energy within 1e-4
    of its start (O(h²) for the splitting, O(h⁴) for RK4 with the projection), orientations
    unit to 1e-12."""
    builder = _scene(method, gravity=(0.0, 0.0, 0.0), angular_velocity=(1.0, 2.0, 3.0))
    simulation = vv.Simulation(builder.build())
    start_l, start_e = simulation.state["body_angular_momentum"].copy(), simulation.energy()
    simulation.step(2000)
    np.testing.assert_allclose(simulation.state["body_angular_momentum"], start_l, atol=1e-12)
    assert simulation.energy() == pytest.approx(start_e, rel=1e-4)
    assert abs(np.linalg.norm(simulation.state["body_orientation"][0]) - 1.0) < 1e-12


def test_damping_rates_make_the_momenta_decay_exponentially():
    """P' = −γP, L' = −γ'L without gravity: P(t) = P₀e^(−γt), L(t) = L₀e^(−γ't); RK4 at
    h = 0.01 s matches to 1e-9 relative after 2 s."""
    builder = _scene(
        "rk4", gravity=(0.0, 0.0, 0.0), velocity=(1.0, 2.0, 0.0),
        angular_velocity=(0.5, 1.0, -2.0), linear_damping_rate=0.7, angular_damping_rate=1.3,
    )  # fmt: skip
    simulation = vv.Simulation(builder.build())
    p0 = simulation.state["body_momentum"].copy()
    l0 = simulation.state["body_angular_momentum"].copy()
    simulation.step(200)
    np.testing.assert_allclose(simulation.state["body_momentum"], p0 * np.exp(-1.4), rtol=1e-9)
    np.testing.assert_allclose(
        simulation.state["body_angular_momentum"], l0 * np.exp(-2.6), rtol=1e-9
    )


def test_rk4_and_explicit_euler_keep_unit_orientations_through_the_projection():
    builder = _scene("explicit_euler", gravity=(0.0, 0.0, 0.0), angular_velocity=(0, 5.0, 0.1))
    simulation = vv.Simulation(builder.build())
    simulation.step(500)
    assert abs(np.linalg.norm(simulation.state["body_orientation"][0]) - 1.0) < 1e-15


def test_torque_of_a_force_at_a_point_is_r_cross_f():
    """By hand: a force (0, 0, 2) N at (1, 0, 0) m from the centre of mass pushes +z at +x,
    turning the body about −y: τ = r × F = (0·2 − 0·0, 0·0 − 1·2, 1·0 − 0·0) = (0, −2, 0) N·m;
    the same force through the centre of mass gives no torque."""
    x = np.array([[0.5, 1.0, -1.0]])
    force, torque = wrench_at(x, x + [1.0, 0.0, 0.0], [[0.0, 0.0, 2.0]])
    np.testing.assert_array_equal(force, [[0.0, 0.0, 2.0]])
    np.testing.assert_array_equal(torque, [[0.0, -2.0, 0.0]])
    assert not wrench_at(x, x, [[3.0, -1.0, 2.0]])[1].any()


def test_the_state_holds_the_centre_of_mass_not_the_bodys_origin():
    """A cone's origin is the centre of its base; its centre of mass is h/4 up its axis: the
    state's body_position is position + R (0, h/4, 0)."""
    q = np.array([np.cos(0.3), np.sin(0.3), 0.0, 0.0])
    builder = _scene(shape="cone", size=None, radius=0.2, height=0.8, position=(1, 1, 1),
                     orientation=q)  # fmt: skip
    state = vv.Simulation(builder.build()).state
    expected = np.array([1.0, 1.0, 1.0]) + quaternion_matrix(q) @ [0.0, 0.2, 0.0]
    np.testing.assert_allclose(state["body_position"][0], expected, atol=1e-15)


def test_a_mass_gives_the_body_the_density_that_weighs_that_much():
    """mass = 3 kg for a sphere of radius 0.1 m: the inertia is ⅖ M r² whatever the volume."""
    builder = _scene(shape="sphere", size=None, density=None, mass=3.0, radius=0.1)
    model = builder.build()
    assert model.bodies.mass[0] == pytest.approx(3.0, rel=1e-15)
    np.testing.assert_allclose(model.bodies.moments[0], 0.4 * 3.0 * 0.01, rtol=1e-14)


def test_particles_and_bodies_share_the_state_and_the_step():
    """A particle and a body thrown alike under gravity fall alike (the particle by the
    fused-free generic step, beside the body), each in its own named parts."""
    builder = _scene("velocity_verlet", velocity=(1.0, 4.0, 0.0))
    builder.add_particles(positions=[[0.0, 0.0, 0.0]], velocities=[[1.0, 4.0, 0.0]], name="dot")
    simulation = vv.Simulation(builder.build())
    assert not simulation.compiled
    simulation.step(50)
    moved = simulation.state["body_position"][0] - simulation.model.bodies.position[0]
    np.testing.assert_allclose(simulation.state["particle_position"][0], moved, atol=1e-13)


@pytest.mark.parametrize(
    ("body", "where", "message"),
    [
        ({"shape": "box", "radius": 0.2}, "", "takes no `radius`"),
        ({"shape": "box", "size": None}, "", "a box needs `size`"),
        ({"shape": "cylinder", "size": None, "radius": 0.2}, "", "`radius` and `height`"),
        ({"mass": 2.0}, "", "not both"),
        ({"orientation": (0.0, 0.0, 0.0, 0.0)}, "", "no rotation"),
        ({"density": -1.0}, "density", "greater than 0"),
        ({"shape": "mesh", "size": None, **INSIDE_OUT}, "vertices", "oriented"),
    ],
)
def test_bad_bodies_are_refused_naming_the_entity_and_field(body, where, message):
    with pytest.raises(vv.SceneError, match=message) as error:
        _scene(**body).build()
    assert error.value.problems[0].path.startswith("entities[0]" + (f".{where}" if where else ""))


def test_a_quaternion_not_of_unit_length_is_normalized_with_a_warning():
    with pytest.warns(UserWarning, match="normalized"):
        model = _scene(orientation=(2.0, 0.0, 0.0, 0.0)).build()
    np.testing.assert_array_equal(model.bodies.orientation[0], [1.0, 0.0, 0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _scene(orientation=(1.0, 0.0, 0.0, 1e-9)).build()  # rounding is no mistake


def test_implicit_methods_refuse_rigid_bodies_and_name_those_that_step_them():
    model = _scene().build()
    with pytest.raises(vv.ModelError, match="cannot step rigid bodies"):
        vv.Simulation(model, method="projected_newton")


@pytest.mark.parametrize(
    "shape",
    [
        {"shape": "box", "size": (1.0, 2.0, 3.0)},
        {"shape": "sphere", "radius": 0.5},
        {"shape": "ellipsoid", "size": (1.0, 2.0, 3.0)},
        {"shape": "cylinder", "radius": 0.5, "height": 2.0},
        {"shape": "cone", "radius": 0.5, "height": 2.0},
        {"shape": "capsule", "radius": 0.5, "height": 1.0},
    ],
)
def test_drawn_surfaces_face_outward_and_enclose_the_shapes_volume(shape):
    """Every triangle has area and faces outward (the signed volume Σ a·(b × c)/6 is
    positive); a cylinder or cone drawn with N segments encloses exactly the inscribed prism's
    or pyramid's share N sin(2π/N)/2π of the volume, round shapes within 2 %."""
    from visviva.rigid import mass_properties
    from visviva.rigid.surfaces import AROUND, body_surface

    vertices, triangles = body_surface(shape)
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    assert np.linalg.norm(np.cross(b - a, c - a), axis=1).min() > 0.0
    volume = np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0
    dimensions = {k: v for k, v in shape.items() if k != "shape"}
    exact = mass_properties(shape["shape"], 1.0, **dimensions).volume
    if shape["shape"] == "box":
        assert volume == pytest.approx(exact, rel=1e-14)
    elif shape["shape"] in ("cylinder", "cone"):
        share = AROUND * np.sin(2 * np.pi / AROUND) / (2 * np.pi)
        assert volume == pytest.approx(share * exact, rel=1e-12)
    else:
        assert 0.98 * exact < volume < exact


def test_a_push_through_the_centre_of_mass_changes_p_by_its_impulse_and_turns_nothing():
    """F = (3, 0, −2) N for 0.1 s (10 steps of 0.01 s) at the centre of mass: ΔP = F Δt
    exactly, L unchanged."""
    push = {"force": (3.0, 0.0, -2.0), "start": 0.05, "duration": 0.1}
    builder = _scene(gravity=(0.0, 0.0, 0.0), angular_velocity=(0.0, 1.0, 0.0), push=[push])
    simulation = vv.Simulation(builder.build())
    spin = simulation.state["body_angular_momentum"].copy()
    simulation.step(30)
    np.testing.assert_allclose(simulation.state["body_momentum"][0], [0.3, 0.0, -0.2], atol=1e-14)
    np.testing.assert_allclose(simulation.state["body_angular_momentum"], spin, atol=1e-15)


def test_a_push_off_the_centre_of_mass_turns_the_body_by_r_cross_f():
    """One step of h = 0.01 s with F = (0, 0, 5) N at the body point (0.2, 0, 0), the body at
    rest and turned by q: ΔL = h (R(q) r) × F, ΔP = h F (Baraff & Witkin: τ = (p − x) × F)."""
    q = np.array([np.cos(0.4), 0.0, np.sin(0.4), 0.0])
    push = {"force": (0.0, 0.0, 5.0), "point": (0.2, 0.0, 0.0), "duration": 0.01}
    builder = _scene(gravity=(0.0, 0.0, 0.0), orientation=q, push=[push])
    simulation = vv.Simulation(builder.build())
    simulation.step(1)
    arm = quaternion_matrix(q) @ [0.2, 0.0, 0.0]
    expected = 0.01 * np.cross(arm, [0.0, 0.0, 5.0])
    np.testing.assert_allclose(simulation.state["body_angular_momentum"][0], expected, atol=1e-15)
    np.testing.assert_allclose(simulation.state["body_momentum"][0], [0.0, 0.0, 0.05], atol=1e-15)


def test_a_spinning_top_on_an_anchor_precesses_at_m_g_d_over_i3_omega():
    """A cone spinning at ω₃ = 150 rad/s about its axis, tilted 0.3 rad, its base centre held
    at the origin by a stiff spring, its centre of mass d = h/4 above: gravity's torque turns
    L about +y at the gyroscopic rate Ω = M g d / (I₃ ω₃) (I₃ = 3/10 M r²; the steady rate
    with the pivot's inertia is 4 % faster, and a released top nutates between them): the
    measured mean rate over 1 s is within 3 % of Ω, and the pivot stays within 3 M g / k of
    the origin (M g / k is the spring's static sag)."""
    tilt, spin, radius, height = 0.3, 150.0, 0.1, 0.3
    q = np.array([np.cos(tilt / 2), np.sin(tilt / 2), 0.0, 0.0])
    anchor = {"point": (0.0, 0.0, 0.0), "stiffness": 2e5, "damping": 50.0}
    builder = _scene(
        dt=2e-4, shape="cone", size=None, radius=radius, height=height, density=700.0,
        orientation=q, angular_velocity=quaternion_matrix(q) @ [0.0, spin, 0.0], anchor=anchor,
    )  # fmt: skip
    simulation = vv.Simulation(builder.build())
    mass = simulation.model.bodies.mass[0]
    azimuth, pivot = [], []
    for _ in range(100):
        simulation.step(50)
        x = simulation.state["body_position"][0]
        q_now = simulation.state["body_orientation"][0]
        azimuth.append(np.arctan2(-x[2], x[0]))  # about +y, counter-clockwise from above
        pivot.append(np.linalg.norm(x - quaternion_matrix(q_now) @ [0.0, height / 4, 0.0]))
    rate = (np.unwrap(azimuth)[-1] - azimuth[0]) / (99 * 50 * 2e-4)
    theory = 9.81 * mass * (height / 4) / (0.3 * mass * radius**2 * spin)
    assert rate == pytest.approx(theory, rel=0.03)
    assert max(pivot) < 3 * mass * 9.81 / anchor["stiffness"]


def test_the_example_scene_of_bodies_validates_and_names_its_bodies():
    from typer.testing import CliRunner

    from visviva.cli.main import app

    scene = Path(__file__).parents[1] / "examples" / "scenes" / "spinning_bodies.toml"
    result = CliRunner().invoke(app, ["validate", str(scene)])
    assert result.exit_code == 0 and "3 rigid bodies" in result.stdout


def test_the_fused_step_of_free_bodies_is_the_generic_pipelines():
    """Bodies alone under gravity and damping take one compiled pass per step (kick, drift,
    watch): after 300 steps the same state as the generic pipeline to round-off (the order of
    the same operations differs), and scenes with pushes, anchors or particles do not take
    it."""
    rng = np.random.default_rng(5)
    builder = _scene(linear_damping_rate=0.3, angular_damping_rate=0.2, angular_velocity=(1, 2, 3))
    for _ in range(5):
        builder.add_body(
            "capsule", radius=0.05, height=0.2, density=800.0, position=rng.normal(size=3),
            orientation=rng.normal(size=4) / 2.0 + [1, 0, 0, 0], velocity=rng.normal(size=3),
            angular_velocity=5 * rng.normal(size=3), linear_damping_rate=0.1,
        )  # fmt: skip
    # One spinning fast enough (40 rad/s: ½ h |L|/I_min > 0.05) to leave the short series:
    # the fused step's general path takes it.
    builder.add_body("box", size=(0.1, 0.2, 0.3), density=500.0, angular_velocity=(40, 5, 1))
    # And an isotropic one, which turns about L in one exact turn (the general path too).
    builder.add_body("sphere", radius=0.1, density=500.0, angular_velocity=(1, -2, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the random quaternions are normalized
        model = builder.build()
    fused, generic = vv.Simulation(model), vv.Simulation(model, compiled=False)
    assert fused.compiled and not generic.compiled
    fused.step(300)
    generic.step(300)
    for name in ("body_position", "body_orientation", "body_momentum", "body_angular_momentum"):
        np.testing.assert_allclose(fused.state[name], generic.state[name], rtol=1e-12, atol=1e-13)
    assert fused.energy() == pytest.approx(generic.energy(), rel=1e-12)
    pushed = _scene(push=[{"force": (1.0, 0.0, 0.0), "duration": 0.1}]).build()
    assert not vv.Simulation(pushed).compiled
    assert not vv.Simulation(_scene("velocity_verlet").build()).compiled


def test_a_fused_blow_up_stops_with_the_last_good_state():
    """Damping γ = 500/s at h = 0.01 s makes the explicit kick multiply P by 1 − hγ = −4 a
    step: the run stops with SimulationDiverged naming the body part, and the simulation
    holds the finite state of the last good step."""
    model = _scene(linear_damping_rate=500.0, velocity=(1.0, 0.0, 0.0)).build()
    simulation = vv.Simulation(model)
    assert simulation.compiled
    with pytest.raises(vv.SimulationDiverged, match="body_"):
        simulation.step(1000)
    state = simulation.state
    assert np.isfinite(state["body_momentum"]).all() and np.abs(state["body_momentum"]).max() > 1


def test_the_derived_views_are_p_over_m_r_of_q_and_omega_from_l():
    """sim.bodies(): v = P/M, R = R(q), I⁻¹ = R I_body⁻¹ Rᵀ and ω = I⁻¹ L, against the
    box's closed-form inertia; ω agrees with the kinematics' own, and changes while L stays."""
    q = np.array([0.8, 0.2, -0.4, 0.4])
    q /= np.linalg.norm(q)
    omega = np.array([0.5, -1.0, 2.0])
    simulation = vv.Simulation(
        _scene(gravity=(0, 0, 0), orientation=q, velocity=(1, 2, 3), angular_velocity=omega).build()
    )
    views = simulation.bodies()
    np.testing.assert_allclose(views.velocity[0], [1, 2, 3], rtol=1e-15)
    np.testing.assert_allclose(views.rotation[0], quaternion_matrix(q), atol=1e-15)
    mass = 0.4 * 0.2 * 0.1 * 500.0
    body = mass / 12.0 * np.diag([0.2**2 + 0.1**2, 0.4**2 + 0.1**2, 0.4**2 + 0.2**2])
    rotation = quaternion_matrix(q)
    np.testing.assert_allclose(
        views.inverse_inertia[0], rotation @ np.linalg.inv(body) @ rotation.T, rtol=1e-12
    )
    np.testing.assert_allclose(views.angular_velocity[0], omega, rtol=1e-12)
    simulation.step(100)
    later = simulation.bodies().angular_velocity[0]
    q_, v_ = simulation.raw_state.parts
    np.testing.assert_allclose(later, simulation.system.kinematics.angular_velocity(q_, v_)[0])
    assert np.abs(later - omega).max() > 0.1  # ω wanders; L does not
    with pytest.raises(vv.ModelError, match="no rigid bodies"):
        particles = vv.SceneBuilder(name="p")
        particles.add_particles(positions=[[0.0, 0.0, 0.0]])
        vv.Simulation(particles.build()).bodies()


def test_kinematic_and_static_bodies_move_as_given_whatever_acts():
    """Under gravity and damping, a kinematic box moves at its velocity and turns at its
    angular velocity (about a fixed axis, even though a box spun off its principal axes would
    tumble), and a static one stays put; a dynamic sphere falls. The energy counts neither
    driven body's height (gravity does not pull them)."""
    omega = np.array([0.3, 1.0, -0.5])
    builder = _scene(
        motion="kinematic", velocity=(1.0, 0.0, 0.0), angular_velocity=omega,
        linear_damping_rate=2.0, angular_damping_rate=2.0,
    )  # fmt: skip
    builder.add_body("sphere", radius=0.1, density=100.0, motion="static", position=(0, 5, 0))
    builder.add_body("sphere", radius=0.1, density=100.0, position=(0, 5, 1))
    simulation = vv.Simulation(builder.build())
    start = simulation.state["body_position"].copy()
    energy = simulation.energy()
    simulation.step(100)  # 1 s
    x, q = simulation.state["body_position"], simulation.state["body_orientation"]
    np.testing.assert_allclose(x[0], start[0] + [1.0, 0.0, 0.0], atol=1e-12)
    angle = np.linalg.norm(omega)  # turned by |ω| t about ω/|ω|
    expected = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * omega / angle])
    np.testing.assert_allclose(q[0], expected, atol=1e-12)
    np.testing.assert_array_equal(x[1], start[1])
    assert x[2, 1] < start[2, 1] - 4.0  # the dynamic sphere fell about ½ g t² = 4.9 m
    # The energy changes by the falling sphere's alone: symplectic Euler's exact offset under a
    # constant force, ΔE = −½ M g² h t (v_n = n h g, x_n − x_0 = h² g n (n + 1)/2).
    sphere = 100.0 * 4.0 / 3.0 * np.pi * 0.1**3
    assert simulation.energy() - energy == pytest.approx(-0.5 * sphere * 9.81**2 * 0.01, rel=1e-9)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ({"motion": "static", "velocity": (1.0, 0.0, 0.0)}, "static body does not move"),
        ({"motion": "kinematic", "push": [{"force": (1.0, 0.0, 0.0)}]}, "not by forces"),
    ],
)
def test_driven_bodies_refuse_what_would_move_them_otherwise(body, message):
    with pytest.raises(vv.SceneError, match=message):
        _scene(**body).build()


def test_a_push_at_a_world_point_turns_by_its_lever_arm_from_the_centre():
    """A force (0, 0, 5) N at the world point 0.2 m beside a body's centre of mass for one step
    of 0.01 s: ΔL = h (p − x) × F = 0.01 (0.2, 0, 0) × (0, 0, 5), whatever its orientation (the
    point is fixed in space, not in the body)."""
    q = np.array([np.cos(0.4), 0.0, np.sin(0.4), 0.0])
    centre = np.array([1.0, 2.0, 3.0])
    push = {"force": (0.0, 0.0, 5.0), "point": tuple(centre + [0.2, 0, 0]), "frame": "world",
            "duration": 0.01}  # fmt: skip
    builder = _scene(gravity=(0.0, 0.0, 0.0), orientation=q, position=centre, push=[push])
    simulation = vv.Simulation(builder.build())
    simulation.step(1)
    expected = 0.01 * np.cross([0.2, 0.0, 0.0], [0.0, 0.0, 5.0])
    np.testing.assert_allclose(simulation.state["body_angular_momentum"][0], expected, atol=1e-15)
